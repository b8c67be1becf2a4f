//! The 1989 industrial microcomputer controller (Maribor / Metalna, source 003) rebuilt as a
//! soft-PLC on `regler_scan_cycle::Executive`, running a conveyor section against a simulated
//! plant, driven like the source's simulator: run N cycles, one cycle, continuous with
//! breakpoints, show and force I/O, spool and statistics — from a script, typed at a monitor, or
//! over Modbus/TCP.
//!
//! # The conveyor section
//! Inputs: 0 START, 1 STOP, 2 PART (photo eye at the reject gate), 3 BAD (a quality sensor
//! 2 m up the belt flags a bad part), 4 RESET (jam reset); input word 1 is the belt encoder's
//! counter card (one pulse per [`MM_PER_PULSE`] mm of belt travel, a 16-bit count that wraps).
//! Outputs: 0 MOTOR, 1 JAM lamp, 2 GATE (reject gate), 3 RUN lamp.
//!
//! The program: the motor is latched by START and dropped by STOP or a jam (an SR block); a part
//! covering the photo eye for more than 3 s is a jam (TON) until RESET; every part passing the
//! eye is counted (CTU) and every tenth part queues a batch report on the spool; a bad part at the
//! quality sensor is entered into a `regler_chain_tracker::Tracker`, which counts the belt's
//! encoder pulses down ([`program::GATE_PULSES`], 2 m) and opens the gate when the part reaches
//! it, closing it [`program::HOLD_PULSES`] pulses (0.3 m) later — as source 000's dock chains
//! track trolleys to their tippers by chain pulses.
//!
//! The parts are tracked by the belt's movement, not by time: a part stuck at the eye stalls the
//! belt (the parts behind it stand, the drive slips) while the motor still runs, for up to the
//! jam detector's 3 s, and a stalled belt gives no encoder pulses. Until issue 21 the gate was run
//! by the timer register (source 000's timed sequences), which ticked every cycle the motor
//! output was on: during a stall it went on counting, opened the gate early for the bad parts
//! held behind the stuck one, and they went on — 40 of 602 bad parts in ten seeded ten-minute
//! runs with 119 jams (`tests/plc_conveyor_tracking.rs`). Counted by the encoder, none pass.
//!
//! # Power failure
//! [`Simulator::power_failure`] (the monitor's `powerfail MS`): the executive writes the safe
//! outputs and freezes, the program's battery-backed memory keeps a [`program::Retained`] — the
//! tracker's snapshot (the bad parts on their way, the gate's hold), the edges, the counts and
//! the spool —, the program starts again from power-on with it, and the executive resumes with
//! `Restart::Inhibit` (the motor stays off until START). The encoder's counter card restarts from
//! 0 with the power; the first scan takes it as the new reference (the belt cannot move
//! unpowered). No tracked part is lost: every bad part in flight reaches the gate.
//!
//! # The timing model
//! One cycle every [`PERIOD_MS`] = 50 ms (the 1977 plant's period). In a simulated run the
//! executive reads the plant's clock twice a cycle and each read costs the simulated CPU 1 ms, so
//! a cycle is busy 1 ms; the plant then moves for the rest of the period, and latched pulses
//! shorter than a cycle are captured in between. With `--modbus` the clock is this machine's wall
//! clock and the cycles are paced in real time, so busy time, jitter and load are measured ones.
//! The calendar (shift reports from the minute table at 06:00, 14:00 and 22:00) goes by the
//! plant's time, starting 2026-11-23 13:58:30.
//!
//! # Reading order, as the data flows
//! [`plant`] (the conveyor and its operator) → [`program`] (the PLC program's function blocks)
//! → [`simulator`] (the executive cycling program and plant, the reserve, the trace) →
//! [`monitor`] (the operator's commands) and [`modbus`] (the images served over Modbus/TCP) →
//! [`summary`] (text and JSON) and [`picture`] (the timing diagram).

pub mod modbus;
pub mod monitor;
pub mod picture;
pub mod plant;
pub mod program;
pub mod simulator;
pub mod summary;

pub use monitor::{CONT_MAX, DEMO_SCRIPT, RUN_MAX};
pub use plant::{Plant, Tally};
pub use program::{Conveyor, Report};
pub use simulator::{REPORTS_KEPT, Sample, Simulator, TRACE_CAP};

/// Input words: the points (word 0) and the belt encoder's counter (word 1).
pub const IW: usize = 2;
/// Millimetres of belt travel per encoder pulse.
pub const MM_PER_PULSE: u32 = 10;
/// Output words.
pub const OW: usize = 1;
/// Cycle period, ms (the 1977 plant's 50 ms).
pub const PERIOD_MS: u32 = 50;

/// Input points.
pub mod input {
    /// Start push-button.
    pub const START: usize = 0;
    /// Stop push-button.
    pub const STOP: usize = 1;
    /// Photo eye at the reject gate.
    pub const PART: usize = 2;
    /// Quality sensor: the part under it is bad.
    pub const BAD: usize = 3;
    /// Jam reset push-button.
    pub const RESET: usize = 4;
    /// The input word that holds the belt encoder's pulse count (a counter card: 16 bits,
    /// wrapping), not points.
    pub const ENCODER_WORD: usize = 1;
}

/// Output points.
pub mod output {
    /// Belt motor.
    pub const MOTOR: usize = 0;
    /// Jam lamp.
    pub const JAM: usize = 1;
    /// Reject gate.
    pub const GATE: usize = 2;
    /// Running lamp.
    pub const RUN: usize = 3;
}

/// Signal names for the timing diagram and commands.
pub const SIGNALS: [(&str, bool, usize); 9] = [
    ("start", true, input::START),
    ("stop", true, input::STOP),
    ("part", true, input::PART),
    ("bad", true, input::BAD),
    ("reset", true, input::RESET),
    ("motor", false, output::MOTOR),
    ("jam", false, output::JAM),
    ("gate", false, output::GATE),
    ("run", false, output::RUN),
];
