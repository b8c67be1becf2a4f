#![doc = include_str!("../README.md")]
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![doc(test(attr(deny(warnings))))]
#![cfg_attr(
    test,
    allow(
        clippy::arithmetic_side_effects,
        clippy::cast_possible_truncation,
        clippy::indexing_slicing,
        clippy::unwrap_used,
        reason = "tests compute expected values freely; a panic is a failure"
    )
)]

pub mod highway;
#[cfg(feature = "embedded-io")]
pub mod io;
pub mod line;
pub mod panel;
