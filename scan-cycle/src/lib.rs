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

mod blocks;
mod calendar;
mod executive;
mod image;
mod signals;
mod timer_queue;

pub use blocks::{Ctd, Ctu, Ctud, FTrig, RTrig, Rs, Sr, StoredTimerError, Tof, Ton, Tp};
pub use calendar::{
    AddError, Checked, DateTime, Due, InvalidDateTime, MinuteTable, Start, Weekdays,
};
pub use executive::{
    Breakpoint, BreakpointError, BreakpointWatch, Condition, CycleConfig, CycleStats, Executive,
    Halt, Io, Restart, Routine, Scan, Spool, StepChain,
};
pub use image::{
    Conditioning, DebounceError, Forcing, Image, POINTS_PER_WORD, PointError, WordError,
};
pub use signals::Signals;
pub use timer_queue::{QueueFull, TimerId, TimerQueue, UnknownTimer};
