//! One dock, pulse by pulse: the chain stretching, trolleys entering past the reader and routed
//! by the registry, the tracker setting tippers, sacks falling into whichever bin they pass, the
//! stretch meter recalibrating the tracker (with correction).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use regler_chain_tracker::{
    DistanceTable, Measurement, SOURCE_HOLD_PULSES, StretchConfig, StretchMeter, TipperEvent,
    Tracker,
};
use regler_trolley_id::{
    AlarmLimits, Passage, ReaderHealth, Registry, Route, TrolleyId, Voter, encode,
};

use super::readers::{scan, single_read};
use super::report::{CURVE_POINTS, TipError, YearReport};
use super::scenarios::Scenario;
use super::{
    Config, DISTURBED_SHARE, Destination, LEAD_PULSES, MAX_BINS, MAX_ON_CHAIN, MIN_GAP_PULSES,
    PULSES_PER_M,
};

type Tag = (TrolleyId, u64);
type DockTracker = Tracker<Tag, MAX_ON_CHAIN, MAX_BINS>;

pub(super) struct DockResult {
    pub(super) years: Vec<YearReport>,
    pub(super) curve: Vec<TipError>,
    pub(super) recalibrations: u64,
    pub(super) health: ReaderHealth<1000>,
    pub(super) meter: StretchMeter,
}

/// A trolley physically on the chain.
#[derive(Clone, Copy)]
struct Carried {
    truth: Destination,
    entered: u64,
    has_sack: bool,
    routed: bool,
}

pub(super) fn run_dock(
    config: &Config,
    scenario: Scenario,
    dock: u8,
    progress: &mut impl FnMut(u64),
) -> Result<DockResult, String> {
    // The same seed for every scenario: the same trolleys, destinations and misreads.
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed ^ (u64::from(dock) << 56));
    let p0 = 1.0 / PULSES_PER_M;
    let sia = (config.initiator_span_m * PULSES_PER_M).round() as u32;
    let bins: Vec<f64> = (0..config.bins).map(|b| config.bin_position_m(b)).collect();
    let sa: Vec<u32> = bins
        .iter()
        .map(|x| ((x / p0).round() as u32).saturating_sub(LEAD_PULSES))
        .collect();
    let table: DistanceTable<MAX_BINS> = DistanceTable::new(sia, &sa).map_err(|e| e.to_string())?;
    let mut tracker: Box<DockTracker> =
        Box::new(Tracker::new(table, SOURCE_HOLD_PULSES).map_err(|e| e.to_string())?);
    let mut meter = StretchMeter::new(StretchConfig::new(sia)).map_err(|e| e.to_string())?;
    let mut voter = Voter::new(config.strategy).map_err(|e| e.to_string())?;
    let mut health: ReaderHealth<1000> = ReaderHealth::new(AlarmLimits {
        disagreement_per_mille: config.alarm_disagreement_per_mille,
        ..AlarmLimits::default()
    })
    .map_err(|e| e.to_string())?;

    // Every trolley in the plant has a destination somewhere: the registry the readers share.
    let mut registry: Registry<Destination> = Registry::new();
    for id in TrolleyId::all() {
        let d = Destination {
            dock: rng.random_range(0..config.docks),
            bin: rng.random_range(0..config.bins),
        };
        registry.assign(id, d);
    }

    let rate = config.reader_rate(dock);
    let disturbed = (rate / DISTURBED_SHARE).min(1.0);
    let pulses_total = config.pulses_per_dock();
    let pulses_per_year = f64::from(config.trolleys_per_year) * f64::from(config.mean_gap_pulses);
    let measure_every =
        ((pulses_per_year / f64::from(config.measurements_per_year)).round() as u64).max(1);
    let chain_pulses = (config.chain_m * PULSES_PER_M) as u64;

    // Trolleys on the chain by entry pulse; at most one enters per pulse.
    let ring_len = (chain_pulses as usize * 2).next_power_of_two();
    let mut on_chain: Vec<Option<Carried>> = vec![None; ring_len];
    let mut set = vec![false; usize::from(config.bins)];
    let mut years: Vec<YearReport> = Vec::new();
    let mut curve = vec![TipError::default(); CURVE_POINTS];
    let mut recalibrations = 0;
    let mut next_entry = 0u64;
    let mut events: Vec<TipperEvent<Tag>> = Vec::new();

    for pulse in 1..=pulses_total {
        let t_years = pulse as f64 / pulses_per_year;
        let year = ((pulse - 1) as f64 / pulses_per_year).floor() as usize;
        while years.len() <= year {
            years.push(YearReport {
                year: years.len() as u32 + 1,
                ..YearReport::default()
            });
        }
        let epsilon = config.stretch_m_per_year * t_years / config.chain_m;
        let pitch = p0 * (1.0 + epsilon);

        // The chain moves one pulse: the tracker hears it.
        events.clear();
        tracker.pulse(|e| events.push(e));
        for e in &events {
            match *e {
                TipperEvent::Set {
                    tipper,
                    trolley: (_, entered),
                } => {
                    set[tipper] = true;
                    // Where was the trolley the tracker meant, against where it should be?
                    let travelled_m = (pulse - entered) as f64 * pitch;
                    let meant_m = bins[tipper] - f64::from(LEAD_PULSES) * p0;
                    years[year].tip_error.record(travelled_m - meant_m);
                    let bin = (pulse.saturating_sub(1) as usize * CURVE_POINTS)
                        / pulses_total.max(1) as usize;
                    if let Some(e) = curve.get_mut(bin) {
                        e.record(travelled_m - meant_m);
                    }
                }
                TipperEvent::Reset { tipper } => set[tipper] = false,
            }
        }

        // Sacks fall wherever a trolley passes a set tipper in the coming pulse: trolley `e` is
        // at (pulse − e)·pitch, so it passes bin x when that crosses x. The pitch grows a
        // little every pulse, so one or two trolleys can cross in one pulse.
        let pitch_next = p0
            * (1.0
                + config.stretch_m_per_year * (pulse + 1) as f64
                    / pulses_per_year
                    / config.chain_m);
        for (bin, _) in set.iter().enumerate().filter(|(_, s)| **s) {
            let first = (pulse as f64 - bins[bin] / pitch).floor() + 1.0;
            let last = ((pulse + 1) as f64 - bins[bin] / pitch_next).floor();
            if last < 0.0 {
                continue;
            }
            for entered in (first.max(0.0) as u64)..=(last as u64) {
                let slot = &mut on_chain[entered as usize % ring_len];
                if let Some(c) = slot.as_mut().filter(|c| c.entered == entered && c.has_sack) {
                    c.has_sack = false;
                    let o = &mut years[year].outcomes;
                    if c.truth.bin == bin as u16 {
                        o.delivered += 1;
                    } else {
                        o.misdelivered += 1;
                    }
                }
            }
        }

        // A trolley leaves the chain end.
        if let Some(left) = pulse.checked_sub(chain_pulses) {
            let slot = &mut on_chain[left as usize % ring_len];
            if let Some(c) = slot.take_if(|c| c.entered == left) {
                if c.has_sack && c.routed {
                    years[year].outcomes.not_tipped += 1;
                }
            }
        }

        // The reference mark passes the second initiator.
        if pulse % measure_every == 0 {
            let true_dia = (config.initiator_span_m / pitch).round() as u32;
            let dia = if rng.random_bool(config.glitch_rate) {
                if rng.random_bool(0.5) {
                    true_dia + 1
                } else {
                    true_dia - 1
                }
            } else {
                true_dia
            };
            if let Measurement::Accepted { dia } = meter.measure(dia) {
                if scenario.correction && tracker.recalibrate(dia).map_err(|e| e.to_string())? {
                    recalibrations += 1;
                }
            }
        }

        // A trolley reaches the reader.
        if pulse >= next_entry {
            let gap = MIN_GAP_PULSES
                + rng.random_range(0..=2 * (config.mean_gap_pulses - MIN_GAP_PULSES));
            next_entry = pulse + u64::from(gap);
            let id = TrolleyId::new(rng.random_range(1..=4095)).ok_or("trolley number")?;
            let truth = Destination {
                dock,
                bin: rng.random_range(0..config.bins),
            };
            registry.assign(id, truth); // keyed at the loading desk
            let scans = scan(&mut rng, encode(id), config.readings, disturbed);
            let passage: Passage = if scenario.voting {
                voter.vote(&scans)
            } else {
                single_read(scans[0])
            };
            health.record(&passage);
            let route = registry.route(&passage.verdict, |d| d.dock == dock);
            let mut carried = Carried {
                truth,
                entered: pulse,
                has_sack: true,
                routed: false,
            };
            years[year].outcomes.sacks += 1;
            match route {
                Route::Deliver {
                    trolley,
                    destination,
                } => match tracker.enter((trolley, pulse), usize::from(destination.bin)) {
                    Ok(()) => carried.routed = true,
                    Err(_) => years[year].outcomes.rejected += 1,
                },
                Route::Reject(_) => years[year].outcomes.rejected += 1,
            }
            // A rejected sack goes to the manual station at the reader: no tipper can drop it.
            carried.has_sack = carried.routed;
            on_chain[pulse as usize % ring_len] = Some(carried);
        }

        if pulse % 65_536 == 0 {
            progress(65_536);
        }
    }
    progress(pulses_total % 65_536);
    // Sacks still riding to their bins when the run ends.
    let still = on_chain
        .iter()
        .flatten()
        .filter(|c| c.has_sack && c.routed)
        .count() as u64;
    if let Some(last) = years.last_mut() {
        last.outcomes.on_chain += still;
    }
    Ok(DockResult {
        years,
        curve,
        recalibrations,
        health,
        meter,
    })
}
