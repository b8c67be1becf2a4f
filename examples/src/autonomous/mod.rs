//! The 1985 autonomous PID controller (source 002) on a simulated process, run in simulated
//! time on `regler-pid`'s [`Station`](regler_pid::Station), operated through the source's terminal dialogue or its
//! keypad and LCD.
//!
//! # Processes
//! - **room**: a room heated by a 0–10 V heater through a first-order lag (time constant
//!   30 min) with a dead time of 2 min; 10 V holds the room 40 °C above the outdoor temperature,
//!   which follows a daily sine (mean `outdoor_mean`, ±5 °C) plus seeded weather noise.
//!   Scale 0–40 °C.
//! - **tank**: a tank level fed by a 0–10 V pump, first-order, time constant 30 s, no dead time;
//!   10 V would hold 150 % with the outflow valve shut (the pump sized for the largest outflow
//!   with margin); the valve moves every five minutes (a seeded random walk, 0–30 % of the
//!   inflow range).
//!   Scale 0–100 %.
//!
//! The measurement goes through the source's 12-bit A/D and the output through its 8-bit D/A.
//!
//! # Scripts
//! One command a line, `TIME KIND ARGUMENTS`; `#` starts a comment. TIME is seconds, or with a
//! unit `90s`, `15m`, `2h`, or a clock time `hh:mm`. KIND is
//! - `term TEXT`: a line typed at the terminal (start-up answers, `Y` for the change mode, `C`);
//!   `term` alone is an empty line (CR);
//! - `keys KEYS`: keys pressed on the keypad, e.g. `keys * 21 * A 22 A D` (set-point 22 on the room's 0–40 °C scale; the source's own example keyed 150 on its scale);
//! - `night on|off`: the night input (set-back);
//! - `outdoor DELTA`: a step in the outdoor temperature (room) or outflow (tank), in scale units.
//!
//! # Timing
//! Everything runs in simulated time: the plant integrates in fixed steps (1 s for the room,
//! 0.1 s for the tank), the controller samples every S seconds (its sampling period, set at
//! start-up or in the change mode), a script's inputs act at the first step at or after their
//! time. With `--interactive` the plant runs at `--speed` times real time while the operator
//! types.
//!
//! # Source
//! TFRT-5323 (Lund, 1985): an autonomous PID controller on an 8052AH-BASIC, its program listing
//! (the terminal dialogue, the keypad codes and the LCD) in the appendix. The control law is
//! `regler_pid::Station`; this module is only the plant around it and the operator in front.
//!
//! # Files, as the data flows
//! - [`plant`]: the room, the tank and the three-point motor;
//! - [`script`]: the timed operator input and the built-in demonstrations;
//! - [`startup`], [`terminal`], [`keypad`]: the operator interfaces of the source (the start-up
//!   dialogue, each answer checked when typed; the terminal after it; the keypad and LCD);
//! - [`controller`]: `Station` on the plant, and the script's run;
//! - [`report`]: what a run gives, and the loop's measures;
//! - [`interactive`]: the controller at a live terminal;
//! - [`autotune`](mod@autotune), [`benchmark`]: relay auto-tuning on the room or tank, and the tuning rules
//!   judged on Åström and Hägglund's benchmark processes;
//! - [`summary`], [`json`], [`picture`]: the presentation — the text summary, the streamed
//!   JSON, the SVG.

pub mod autotune;
pub mod benchmark;
pub mod controller;
pub mod interactive;
pub mod json;
pub mod keypad;
pub mod picture;
pub mod plant;
pub mod report;
pub mod script;
pub mod startup;
pub mod summary;
pub mod terminal;

use serde::Serialize;

pub use self::autotune::{AutotunePoint, AutotuneReport, autotune};
pub use self::controller::{Sim, keypad_startup, run, validate};
pub use self::report::{Refusal, Shown, SimConfig, SimReport, TracePoint};
pub use self::script::{Event, Input, demo_script, parse_script};

/// The simulated process.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ProcessKind {
    /// A heated room (slow, dead time, outdoor disturbance).
    Room,
    /// A tank level (fast).
    Tank,
}

impl ProcessKind {
    /// The measurement scale.
    #[must_use]
    pub fn scale(self) -> (f64, f64) {
        match self {
            ProcessKind::Room => (0.0, 40.0),
            ProcessKind::Tank => (0.0, 100.0),
        }
    }

    /// Its name on the command line and in the summary: `room`, `tank`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            ProcessKind::Room => "room",
            ProcessKind::Tank => "tank",
        }
    }

    /// The measurement's unit: `°C`, `%`.
    #[must_use]
    pub fn unit(self) -> &'static str {
        match self {
            ProcessKind::Room => "°C",
            ProcessKind::Tank => "%",
        }
    }

    /// Integration step, seconds.
    fn dt(self) -> f64 {
        match self {
            ProcessKind::Room => 1.0,
            ProcessKind::Tank => 0.1,
        }
    }
}

/// Which operator interface starts the controller.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Interface {
    /// The terminal: the script's first `term` lines answer the start-up questions.
    Terminal,
    /// The keypad only: the source's keypad start-up values (PID, S = 1 s, KP = 10, TI = 8,
    /// 0–10 V, WIN = SCALEMIN).
    Keypad,
}
