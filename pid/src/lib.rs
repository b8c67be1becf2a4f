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

pub mod actuator;
mod alarm;
mod config;
mod controller;
mod operator;
mod real;
mod scalar;
mod scaling;
pub mod tuning;

pub use alarm::{Alarm, AlarmState};
pub use config::{Action, Config, ConfigError, Kind, Parameter};
pub use controller::{Faults, Inputs, Mode, Pid, STATE_BOUND, TOLERANCE, ValueError};
pub use operator::{Code, EditError, OperatorLimits, Parameters, Requirement, Staged, Station};
pub use real::Real;
pub use scalar::Scalar;
pub use scaling::{ADC_FULL_SCALE, DAC_FULL_SCALE, SPAN_VOLTS, Scaling, ScalingError};
