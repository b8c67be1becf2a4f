//! The integration suites of `regler-pid`, one module per file beside this one, built as a
//! single test binary (`autotests = false` in Cargo.toml): one crate to compile and link
//! instead of one per file. `cargo test -p regler-pid --test suites reach::` runs one suite.

mod actuator;
mod actuator_exact;
mod attack2_fixes;
mod attack3_fixes;
mod attack_regressions;
mod bad_inputs;
mod custom_scalar;
mod load_step;
mod modes;
mod operator;
mod properties;
mod reach;
mod reach_model;
mod scaling;
mod serde;
mod set_config;
mod tuning;
