//! Plant simulators and shared helpers of the regler example programs. Each binary in
//! `src/bin/` rebuilds one source system on the regler crates; the simulation of its plant
//! lives here so the integration tests can drive it directly.

pub mod autonomous;
pub mod cli;
pub mod highway;
pub mod knitter;
pub mod mailbag;
pub mod plc;
pub mod svg;
