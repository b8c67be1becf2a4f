//! The plant: a simulated conveyor section (parts arrive, ride the belt while the motor runs,
//! pass the quality sensor and the gate, now and then one sticks at the eye and stalls the belt)
//! and the operator who starts the belt and clears jams. It is the executive's `Io`: the input
//! words it reads (the points and the belt encoder's counter), the output word it writes, and the
//! clock.
//!
//! The belt runs at 1 m/s (1 mm a millisecond) while the motor is on and nothing stalls it; a
//! part's position is the belt travel since it was put on at the quality sensor (mm), the gate's
//! photo eye covers 2 000–2 150 mm and a part leaves the section at 2 150 mm, into the reject bin
//! if the gate is open then. A part stuck at the eye, or a stall scheduled with
//! [`Plant::stall`], stops the belt with every part on it: no part moves and the encoder gives no
//! pulses, whether or not the motor output is on.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use regler_scan_cycle::Io;
use serde::Serialize;

use super::{IW, MM_PER_PULSE, OW, input, output};

/// A part on the belt (its position in mm of belt travel from the quality sensor).
#[derive(Clone, Copy, Debug)]
struct Part {
    position_mm: u32,
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
    /// Belt travel, mm: the encoder counts one pulse per [`MM_PER_PULSE`] of it since
    /// `encoder_from_mm`, where the power last came on.
    belt_mm: u64,
    encoder_from_mm: u64,
    /// Scheduled stalls: from `at_ms` for `for_ms`.
    stalls: Vec<(u32, u32)>,
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
    /// Parts put on the belt.
    pub arrived: u32,
}

const GATE_AT_MM: u32 = 2_000;
const EYE_WIDTH_MM: u32 = 150;

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
            belt_mm: 0,
            encoder_from_mm: 0,
            stalls: Vec::new(),
        }
    }

    /// Stalls the belt at `at_ms` for `for_ms` (something wedged in it, wherever the parts are):
    /// nothing on it moves and the encoder gives no pulses, whatever the motor output. A stall
    /// with a part at the eye lasting 3 s is a jam to the program like a stuck part.
    pub fn stall(&mut self, at_ms: u32, for_ms: u32) {
        self.stalls.push((at_ms, for_ms));
    }

    /// Parts on the belt now.
    #[must_use]
    pub fn on_belt(&self) -> usize {
        self.parts.len()
    }

    /// The belt encoder's counter card: one pulse per [`MM_PER_PULSE`] mm, 16 bits, wrapping.
    #[must_use]
    pub fn encoder(&self) -> u16 {
        (((self.belt_mm - self.encoder_from_mm) / u64::from(MM_PER_PULSE)) & 0xffff) as u16
    }

    /// The power is off for `ms` (the outputs are the safe ones the executive wrote: the motor
    /// is off, the belt stands): time passes; when the power comes back the encoder's counter
    /// card starts again from 0, and the operator presses START 1 s later.
    pub fn power_cut(&mut self, ms: u32) {
        self.advance(ms);
        self.encoder_from_mm = self.belt_mm;
        self.inputs[input::ENCODER_WORD] = self.encoder();
        let now = self.now_ms();
        self.press(now + 1_000, input::START, 200);
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
                    && self.parts.last().is_none_or(|p| p.position_mm > 400)
                {
                    let bad = self.rng.random_bool(0.1);
                    let stuck_for_ms = if self.rng.random_bool(0.02) { 4_000 } else { 0 };
                    self.tally.arrived += 1;
                    self.parts.push(Part {
                        position_mm: 0,
                        bad,
                        stuck_for_ms,
                    });
                    self.next_arrival_ms = now + self.rng.random_range(300..1500);
                }
                // The part at the eye may stick: it stalls the belt, and every part on it
                // stands (none can be ahead of it: they are 400 mm apart and leave at 2 150).
                let mut stuck = false;
                for p in &mut self.parts {
                    let at_eye =
                        p.position_mm >= GATE_AT_MM && p.position_mm < GATE_AT_MM + EYE_WIDTH_MM;
                    if at_eye && p.stuck_for_ms > 0 {
                        if p.stuck_for_ms == 4_000 {
                            self.tally.jams += 1;
                        }
                        p.stuck_for_ms -= 1;
                        stuck = true;
                    }
                }
                let stalled = self
                    .stalls
                    .iter()
                    .any(|&(at, dur)| now > at && now - at <= dur);
                if !stuck && !stalled {
                    self.belt_mm += 1;
                    for p in &mut self.parts {
                        p.position_mm += 1;
                    }
                }
            }
            // Parts leave at the gate: into the reject bin if it is open, on otherwise.
            let mut kept = Vec::with_capacity(self.parts.len());
            for p in self.parts.drain(..) {
                if p.position_mm >= GATE_AT_MM + EYE_WIDTH_MM {
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
            .any(|p| p.position_mm >= GATE_AT_MM && p.position_mm < GATE_AT_MM + EYE_WIDTH_MM)
        {
            word |= 1 << input::PART;
        }
        if self.parts.iter().any(|p| p.bad && p.position_mm < 100) {
            word |= 1 << input::BAD;
        }
        for &(at, point, dur) in &self.press {
            if now >= at && now < at + dur {
                word |= 1 << point;
            }
        }
        self.inputs = [word, self.encoder()];
        // Two seconds after the jam lamp comes on, the operator takes the stuck part off the
        // belt, presses RESET, then START.
        if self.outputs[0] & (1 << output::JAM) == 0 {
            self.jam_since_ms = None;
        } else if now.saturating_sub(*self.jam_since_ms.get_or_insert(now)) >= 2_000 {
            let before = self.parts.len();
            self.parts.retain(|p| {
                !(p.position_mm >= GATE_AT_MM && p.position_mm < GATE_AT_MM + EYE_WIDTH_MM)
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
