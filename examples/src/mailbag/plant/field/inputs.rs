//! The field as the executive sees it: the input words it reads (cams with their misreads,
//! sensors, photocells, latched pulses, then the faulty inputs), the outputs it writes.

use regler_scan_cycle::Io;

use super::super::layout::{READERS, capacity, io};
use super::super::operator::BUFFER_LANES;
use super::Field;

impl Io<{ io::IN_WORDS }, { io::OUT_WORDS }> for Field {
    fn read_inputs(&mut self, raw: &mut [u16; io::IN_WORDS]) {
        *raw = [0; io::IN_WORDS];
        for r in 0..READERS {
            if let Some((t, swinging)) = self.occupant[r] {
                raw[r] = self.cams(r, t, swinging) | 1 << io::PRESENT_BIT;
            }
        }
        let (lanes, stations) = self.fills();
        for l in 0..usize::from(BUFFER_LANES) {
            raw[io::LANE_FULL_WORD] |= u16::from(lanes[l] >= capacity::LANE) << l;
            raw[io::LANE_WAITING_WORD] |= u16::from(lanes[l] > 0) << l;
        }
        for (s, &n) in stations.iter().enumerate() {
            raw[io::STATION_FULL_WORD] |= u16::from(n >= capacity::STATION) << s;
        }
        for (w, l) in raw.iter_mut().zip(self.latched.iter_mut()) {
            *w |= *l;
            *l = 0;
        }
        self.chatter_phase = !self.chatter_phase;
        for &point in &self.faults.chatter {
            let bit = 1 << (point % 16);
            if self.chatter_phase {
                raw[point / 16] |= bit;
            } else {
                raw[point / 16] &= !bit;
            }
        }
        for &(point, on) in &self.faults.stuck {
            let bit = 1 << (point % 16);
            if on {
                raw[point / 16] |= bit;
            } else {
                raw[point / 16] &= !bit;
            }
        }
    }

    fn write_outputs(&mut self, outputs: &[u16; io::OUT_WORDS]) {
        self.outputs = *outputs;
        self.lane_gates();
    }

    fn now_us(&mut self) -> u32 {
        self.clock_us.wrapping_add(self.cost.get()) as u32
    }

    fn kick_watchdog(&mut self) {
        self.kicks += 1;
    }
}
