//! The dock chains' and the buffer lanes' routines: chain pulses through the tracker and the
//! stretch meter, tippers; the lanes emptied in portions, one lane at a time.

use regler_chain_tracker::{Measurement, TipperEvent};
use regler_scan_cycle::Scan;

use super::super::layout::{BINS_PER_DOCK, DOCKS, io};
use super::super::operator::BUFFER_LANES;
use super::{Control, IW, OW, PORTION, SUPERVISE_TICKS, Timer, cost};

impl Control {
    /// Dock chains: pulses through the tracker and the stretch meter, tippers set and reset.
    pub(super) fn chains(scan: &mut Scan<'_, IW, OW>, c: &mut Control) {
        for d in 0..DOCKS {
            if scan.inputs.get(io::chain_pulse(d)) {
                c.spend(cost::PULSE_US);
                c.meters[d].pulse();
                let mut events = Vec::new();
                c.trackers[d].pulse(|e| events.push(e));
                for e in events {
                    c.spend(cost::TIPPER_US);
                    let (tipper, on) = match e {
                        TipperEvent::Set { tipper, .. } => (tipper, true),
                        TipperEvent::Reset { tipper } => (tipper, false),
                    };
                    let _ = scan.outputs.set(io::tipper(d * BINS_PER_DOCK + tipper), on);
                }
            }
            if scan.inputs.get(io::reference_start(d)) {
                c.meters[d].start();
            }
            if scan.inputs.get(io::reference_end(d)) {
                match c.meters[d].end() {
                    Some(Measurement::Accepted { dia })
                        if c.trackers[d].recalibrate(dia).is_ok() =>
                    {
                        c.recalibrations += 1;
                    }
                    Some(Measurement::Implausible { dia }) => {
                        let text = format!(
                            "{} dock {} chain measured {dia} pulses: implausible",
                            c.stamp(),
                            d + 1
                        );
                        c.print(text);
                    }
                    _ => {}
                }
            }
        }
    }

    pub(super) fn lane_exits(scan: &mut Scan<'_, IW, OW>, c: &mut Control) {
        let exits = scan.inputs.word(io::LANE_EXIT_WORD).unwrap_or(0);
        // Each trolley a lane lets go must be read at R9 in time.
        for l in 0..BUFFER_LANES {
            if exits >> l & 1 == 1 {
                if let Ok(timer) = c
                    .timers
                    .insert(SUPERVISE_TICKS, Timer::ExpectAtR9 { lane: l })
                {
                    c.to_r9.push_back(timer);
                }
            }
        }
        if let Some((lane, left, timer)) = c.portion {
            if exits >> lane & 1 == 1 {
                let left = left.saturating_sub(1);
                c.portion = Some((lane, left, timer));
            }
        }
    }

    /// Buffer lanes: one lane at a time lets a portion of [`PORTION`] trolleys go toward its
    /// emptying stations; lanes are taken in turn.
    pub(super) fn lanes(scan: &mut Scan<'_, IW, OW>, c: &mut Control) {
        c.spend(cost::LANES_US);
        let waiting = scan.inputs.word(io::LANE_WAITING_WORD).unwrap_or(0);
        let full_stations = scan.inputs.word(io::STATION_FULL_WORD).unwrap_or(0);
        if let Some((lane, left, timer)) = c.portion {
            if left > 0 && waiting >> lane & 1 == 1 {
                return;
            }
            c.timers.remove(timer);
            let _ = scan.outputs.set(io::lane_gate(lane), false);
            c.portion = None;
        }
        for k in 0..usize::from(BUFFER_LANES) {
            let l = (c.next_lane + k) % usize::from(BUFFER_LANES);
            let stations = c.emptying[l];
            if waiting >> l & 1 == 1 && stations != 0 && stations & !full_stations as u8 != 0 {
                if let Ok(timer) = c.timers.insert(40 * 20, Timer::PortionTimeout) {
                    c.portion = Some((l, PORTION, timer));
                    let _ = scan.outputs.set(io::lane_gate(l), true);
                }
                c.next_lane = l + 1;
                break;
            }
        }
    }
}
