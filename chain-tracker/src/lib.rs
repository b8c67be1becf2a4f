#![doc = include_str!("../README.md")]
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![doc(test(attr(deny(warnings))))]
#![cfg_attr(
    test,
    allow(
        clippy::arithmetic_side_effects,
        clippy::cast_possible_truncation,
        reason = "tests compute expected values freely; a panic is a failure"
    )
)]

mod startup;
mod stretch;
mod table;
mod tracker;

pub use startup::{StartUp, start_up};
pub use stretch::{Measurement, StretchConfig, StretchConfigError, StretchMeter};
pub use table::{CorrectionError, DistanceTable, TableError, correct};
pub use tracker::{
    EnterError, HeldTipper, InFlight, RESTORE_SLACK, SOURCE_HOLD_PULSES, Snapshot, TipperEvent,
    Tracker, TrackerError,
};
