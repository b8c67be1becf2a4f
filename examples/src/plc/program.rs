//! The PLC program: the conveyor section's control logic as IEC 61131-3 function blocks (SR, TON,
//! CTU, R_TRIG) and the timer register, scanned by the executive on its input and output images.

use regler_scan_cycle::{Ctu, RTrig, Scan, Spool, Sr, TimerQueue, Ton};

use super::{IW, OW, input, output};

/// A one-shot job for the reserve: a printout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Report {
    /// Every tenth part: the batch count.
    Batch(u32),
    /// A shift change from the minute table: the hour.
    Shift(u8),
}

impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Report::Batch(n) => write!(f, "batch of 10 parts, {n} parts in all"),
            Report::Shift(h) => write!(f, "shift report at {h:02}:00"),
        }
    }
}

/// Actions in the timer register.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum GateAction {
    Open,
    Close,
}

/// The application program and its function blocks.
pub struct Conveyor {
    motor: Sr,
    jam_timer: Ton,
    jammed: Sr,
    parts: Ctu,
    part_edge: RTrig,
    bad_edge: RTrig,
    timers: TimerQueue<GateAction, 64>,
    gate: bool,
    /// Reports waiting for the reserve.
    pub spool: Spool<Report, 8>,
    /// Reports refused by a full spool.
    pub spool_refused: u32,
}

/// Cycles of running belt a bad part takes from the quality sensor to the gate (2 s at 50 ms).
pub const TRAVEL_CYCLES: u32 = 40;
/// Gate open time, cycles.
const GATE_OPEN_CYCLES: u32 = 12;

impl Default for Conveyor {
    fn default() -> Self {
        Conveyor::new()
    }
}

impl Conveyor {
    /// The program at power-on.
    #[must_use]
    pub fn new() -> Conveyor {
        Conveyor {
            motor: Sr::new(),
            jam_timer: Ton::new(3_000),
            jammed: Sr::new(),
            parts: Ctu::new(i32::MAX),
            part_edge: RTrig::new(),
            bad_edge: RTrig::new(),
            timers: TimerQueue::new(),
            gate: false,
            spool: Spool::new(),
            spool_refused: 0,
        }
    }

    /// Parts counted (CTU's CV).
    #[must_use]
    pub fn parts(&self) -> i32 {
        self.parts.cv()
    }

    /// The jam timer's elapsed time, ms.
    #[must_use]
    pub fn jam_et(&self) -> u32 {
        self.jam_timer.et()
    }

    /// Timers waiting in the register.
    #[must_use]
    pub fn timers_waiting(&self) -> usize {
        self.timers.len()
    }

    /// One scan of the program.
    pub fn scan(&mut self, s: &mut Scan<'_, IW, OW>) {
        let i = s.inputs;
        let part = i.get(input::PART);
        let jam = self
            .jam_timer
            .call(part && s.previous.get(output::MOTOR), s.now_ms);
        let jammed = self.jammed.call(jam, i.get(input::RESET) && !part);
        let motor = self
            .motor
            .call(i.get(input::START) && !jammed, i.get(input::STOP) || jammed);
        if self.part_edge.call(part) {
            self.parts.call(true, false);
            if self.parts.cv() % 10 == 0
                && self
                    .spool
                    .push(Report::Batch(self.parts.cv().unsigned_abs()))
                    .is_err()
            {
                self.spool_refused += 1;
            }
        } else {
            self.parts.call(false, false);
        }
        if self.bad_edge.call(i.get(input::BAD)) && motor {
            // Lost only if 64 bad parts were on the belt at once: then the part goes through.
            let _ = self.timers.insert(TRAVEL_CYCLES, GateAction::Open);
        }
        let mut opened = 0;
        let mut gate = self.gate;
        // The register counts belt time: a stopped belt (a jam) holds every part where it is.
        if s.previous.get(output::MOTOR) {
            self.timers.tick(|action| match action {
                GateAction::Open => {
                    gate = true;
                    opened += 1;
                }
                GateAction::Close => gate = false,
            });
        }
        for _ in 0..opened {
            let _ = self.timers.insert(GATE_OPEN_CYCLES, GateAction::Close);
        }
        self.gate = gate;
        let _ = s.outputs.set(output::MOTOR, motor);
        let _ = s.outputs.set(output::JAM, jammed);
        let _ = s.outputs.set(output::GATE, gate);
        let _ = s.outputs.set(output::RUN, motor && !jammed);
    }
}
