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

/// The end of every example's `main`: success (also when the reader closed the pipe), or the
/// error on stderr (prefixed with the program's name) and exit code 2, never a panic. See
/// [`cli::finish`].
#[must_use]
pub fn finish<E: Into<cli::Stop>>(program: &str, result: Result<(), E>) -> std::process::ExitCode {
    cli::finish(program, result.map_err(Into::into))
}
