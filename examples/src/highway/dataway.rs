//! The crates' dataways: register modules at stations 1–4 and a counter at station 20 whose LAM
//! makes its crate controller send a demand. Every cycle is logged so that the harness can check
//! it against the command the driver issued.

use regler_panel_link::highway::{Cycle, Dataway, is_read};

use super::{COUNTER_STATION, REGISTER_STATIONS};

/// One dataway cycle as the crate ran it: (N, A, F, write data, read data, X, Q).
pub type CycleRecord = (u8, u8, u8, Option<u32>, u32, bool, bool);

/// A cycle a module took (X and Q set), nothing to read.
const ACCEPTED: Cycle = Cycle {
    read: 0,
    x: true,
    q: true,
};
/// No module answers this N·F: X and Q clear.
const NO_MODULE: Cycle = Cycle {
    read: 0,
    x: false,
    q: false,
};

/// The modules of one simulated crate.
#[derive(Clone, Debug)]
pub struct SimCrate {
    /// Register modules: 16 registers of 24 bits each.
    pub registers: [[u32; 16]; REGISTER_STATIONS as usize],
    /// The counter's count.
    pub count: u32,
    /// The counter's LAM is enabled.
    pub lam_enabled: bool,
    /// The LAM preset.
    pub preset: u32,
    /// Cycles run since the harness last cleared the log: (N, A, F, write, read, X, Q).
    pub log: Vec<CycleRecord>,
}

impl SimCrate {
    pub(crate) fn new(preset: u32) -> Self {
        Self {
            registers: [[0; 16]; REGISTER_STATIONS as usize],
            count: 0,
            lam_enabled: true,
            preset,
            log: Vec::new(),
        }
    }

    /// The counter's LAM.
    #[must_use]
    pub fn lam(&self) -> bool {
        self.lam_enabled && self.count >= self.preset
    }
}

impl Dataway for SimCrate {
    fn cycle(&mut self, n: u8, a: u8, f: u8, write: Option<u32>) -> Cycle {
        let result = match (n, f) {
            (1..=REGISTER_STATIONS, _) => {
                let reg = &mut self.registers[usize::from(n - 1)][usize::from(a & 15)];
                match f {
                    0 => Cycle {
                        read: *reg,
                        ..ACCEPTED
                    },
                    9 => {
                        *reg = 0;
                        ACCEPTED
                    }
                    16 => {
                        *reg = write.unwrap_or(0) & 0xFF_FFFF;
                        ACCEPTED
                    }
                    _ => NO_MODULE,
                }
            }
            (COUNTER_STATION, 0) => Cycle {
                read: self.count,
                ..ACCEPTED
            },
            (COUNTER_STATION, 2) => Cycle {
                read: core::mem::take(&mut self.count),
                ..ACCEPTED
            },
            (COUNTER_STATION, 8) => Cycle {
                q: self.lam(),
                ..ACCEPTED
            },
            (COUNTER_STATION, 24) => {
                self.lam_enabled = false;
                ACCEPTED
            }
            (COUNTER_STATION, 26) => {
                self.lam_enabled = true;
                ACCEPTED
            }
            _ => NO_MODULE,
        };
        let read = if is_read(f) {
            result.read & 0xFF_FFFF
        } else {
            0
        };
        self.log.push((n, a, f, write, read, result.x, result.q));
        result
    }

    fn graded_lam(&mut self) -> u8 {
        u8::from(self.lam())
    }
}
