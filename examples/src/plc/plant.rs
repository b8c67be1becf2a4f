//! The plant: a simulated conveyor section (parts arrive, travel while the motor runs, pass the
//! quality sensor and the gate, now and then one sticks at the eye) and the operator who starts
//! the belt and clears jams. It is the executive's `Io`: the input word it reads, the output word
//! it writes, and the clock.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use regler_scan_cycle::Io;
use serde::Serialize;

use super::{IW, OW, input, output};

/// A part on the belt.
#[derive(Clone, Copy, Debug)]
struct Part {
    position_ms: u32,
    bad: bool,
    stuck_for_ms: u32,
}

/// The simulated conveyor section: parts arrive, travel while the motor runs, pass the quality
/// sensor and the gate; now and then one sticks at the eye. An operator presses START at 0.5 s.
pub struct Plant {
    rng: ChaCha8Rng,
    /// Raw inputs.
    pub inputs: [u16; IW],
    /// Outputs as last written.
    pub outputs: [u16; OW],
    /// Simulated time, µs.
    pub clock_us: u64,
    /// In real-time mode (the Modbus server) the clock is the wall clock, so the executive's
    /// busy time, jitter and load are the real ones.
    real_clock: Option<std::time::Instant>,
    parts: Vec<Part>,
    next_arrival_ms: u32,
    /// Outcomes.
    pub tally: Tally,
    press: Vec<(u32, usize, u32)>,
    jam_since_ms: Option<u32>,
}

/// What happened to the parts.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Tally {
    /// Good parts that went on.
    pub good_passed: u32,
    /// Bad parts the gate took out.
    pub bad_rejected: u32,
    /// Bad parts that went on.
    pub bad_passed: u32,
    /// Good parts the gate took out.
    pub good_rejected: u32,
    /// Jams.
    pub jams: u32,
    /// Stuck parts the operator took off the belt.
    pub cleared_by_hand: u32,
}

const GATE_AT_MS: u32 = 2_000;
const EYE_WIDTH_MS: u32 = 150;

impl Plant {
    /// A plant with the given seed; the operator presses START at 0.5 s (for 200 ms).
    #[must_use]
    pub fn new(seed: u64) -> Plant {
        Plant {
            rng: ChaCha8Rng::seed_from_u64(seed),
            inputs: [0; IW],
            outputs: [0; OW],
            clock_us: 0,
            real_clock: None,
            parts: Vec::new(),
            next_arrival_ms: 1_000,
            tally: Tally::default(),
            press: vec![(500, input::START, 200)],
            jam_since_ms: None,
        }
    }

    /// Presses a push-button at `at_ms` for `for_ms`.
    pub fn press(&mut self, at_ms: u32, point: usize, for_ms: u32) {
        self.press.push((at_ms, point, for_ms));
    }

    fn now_ms(&self) -> u32 {
        u32::try_from(self.clock_us / 1000).unwrap_or(u32::MAX)
    }

    /// Advances the plant by `ms` (between cycles).
    pub fn advance(&mut self, ms: u32) {
        let motor = self.outputs[0] & (1 << output::MOTOR) != 0;
        let gate = self.outputs[0] & (1 << output::GATE) != 0;
        for _ in 0..ms {
            self.clock_us += 1000;
            let now = self.now_ms();
            if motor {
                if now >= self.next_arrival_ms
                    && self.parts.last().is_none_or(|p| p.position_ms > 400)
                {
                    let bad = self.rng.random_bool(0.1);
                    let stuck_for_ms = if self.rng.random_bool(0.02) { 4_000 } else { 0 };
                    self.parts.push(Part {
                        position_ms: 0,
                        bad,
                        stuck_for_ms,
                    });
                    self.next_arrival_ms = now + self.rng.random_range(300..1500);
                }
                // The part at the eye may stick; the ones behind it wait.
                let mut blocked = false;
                for p in &mut self.parts {
                    let at_eye =
                        p.position_ms >= GATE_AT_MS && p.position_ms < GATE_AT_MS + EYE_WIDTH_MS;
                    if at_eye && p.stuck_for_ms > 0 {
                        if p.stuck_for_ms == 4_000 {
                            self.tally.jams += 1;
                        }
                        p.stuck_for_ms -= 1;
                        blocked = true;
                    } else if !blocked {
                        p.position_ms += 1;
                    }
                }
            }
            // Parts leave at the gate: into the reject bin if it is open, on otherwise.
            let mut kept = Vec::with_capacity(self.parts.len());
            for p in self.parts.drain(..) {
                if p.position_ms >= GATE_AT_MS + EYE_WIDTH_MS {
                    match (p.bad, gate) {
                        (true, true) => self.tally.bad_rejected += 1,
                        (true, false) => self.tally.bad_passed += 1,
                        (false, true) => self.tally.good_rejected += 1,
                        (false, false) => self.tally.good_passed += 1,
                    }
                } else {
                    kept.push(p);
                }
            }
            self.parts = kept;
        }
        let now = self.now_ms();
        let mut word = 0u16;
        if self
            .parts
            .iter()
            .any(|p| p.position_ms >= GATE_AT_MS && p.position_ms < GATE_AT_MS + EYE_WIDTH_MS)
        {
            word |= 1 << input::PART;
        }
        if self.parts.iter().any(|p| p.bad && p.position_ms < 100) {
            word |= 1 << input::BAD;
        }
        for &(at, point, dur) in &self.press {
            if now >= at && now < at + dur {
                word |= 1 << point;
            }
        }
        self.inputs = [word];
        // Two seconds after the jam lamp comes on, the operator takes the stuck part off the
        // belt, presses RESET, then START.
        if self.outputs[0] & (1 << output::JAM) == 0 {
            self.jam_since_ms = None;
        } else if now.saturating_sub(*self.jam_since_ms.get_or_insert(now)) >= 2_000 {
            let before = self.parts.len();
            self.parts.retain(|p| {
                !(p.position_ms >= GATE_AT_MS && p.position_ms < GATE_AT_MS + EYE_WIDTH_MS)
            });
            self.tally.cleared_by_hand += u32::try_from(before - self.parts.len()).unwrap_or(0);
            self.press.push((now + 100, input::RESET, 200));
            self.press.push((now + 500, input::START, 200));
            self.jam_since_ms = Some(u32::MAX / 2); // handled: wait for the lamp to go out
        }
    }
}

impl Plant {
    /// From now on the clock is the wall clock (real-time mode): the cycle statistics measure
    /// this machine, not the simulated CPU.
    pub fn use_real_clock(&mut self) {
        self.real_clock = Some(std::time::Instant::now());
    }
}

impl Io<IW, OW> for Plant {
    fn read_inputs(&mut self, raw: &mut [u16; IW]) {
        *raw = self.inputs;
    }
    fn write_outputs(&mut self, outputs: &[u16; OW]) {
        self.outputs = *outputs;
    }
    fn now_us(&mut self) -> u32 {
        if let Some(start) = self.real_clock {
            // The wall clock, wrapping at 2^32 µs as a hardware timer would.
            return (start.elapsed().as_micros() & u128::from(u32::MAX)) as u32;
        }
        // Each clock read costs the simulated CPU 1 ms, so a cycle (two reads) is busy 1 ms.
        self.clock_us += 1_000;
        (self.clock_us & u64::from(u32::MAX)) as u32
    }
}
