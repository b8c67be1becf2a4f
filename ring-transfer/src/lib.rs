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

pub mod capacity;
mod edf;
pub mod link;
mod master;
mod ring;
mod slave;
mod split;

pub use link::{Message, Refill, Report, decode};
pub use master::{Grant, Master, MasterError, ReportOutcome, SlaveParams, SlaveStatus};
pub use ring::{Counters, Item, Ring, Stats};
pub use slave::{
    FrameError, MAX_DRIFT, Mode, Output, Slave, SlaveConfig, SlaveConfigError, SlaveStats, Source,
};
pub use split::{Drainer, Filler, SharedItem, SharedRing};
