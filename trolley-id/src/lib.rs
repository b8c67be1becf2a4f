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

mod code;
mod health;
mod registry;
mod voter;

pub use code::{
    CODE_MASK, InvalidTrolleyNumber, NUMBER_BITS, NUMBER_MASK, PARITY_BIT, ReadError, TrolleyId,
    decode, encode,
};
pub use health::{AlarmChange, AlarmLimits, AlarmLimitsError, HealthStats, ReaderHealth};
pub use registry::{REGISTRY_CELLS, Registry, RejectReason, Route};
pub use voter::{NoRead, Passage, Strategy, StrategyError, Verdict, Voter};
