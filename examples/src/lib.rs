//! Plant simulators and shared helpers of the regler example programs. Each binary in
//! `src/bin/` rebuilds one source system on the regler crates; the simulation of its plant
//! lives here so the integration tests can drive it directly.

pub mod autonomous;
pub mod highway;
pub mod knitter;
pub mod mailbag;
pub mod plc;
pub mod svg;

/// The end of every example's `main`: success, or the error on stderr (prefixed with the
/// program's name) and exit code 2, never a panic.
#[must_use]
pub fn finish(program: &str, result: Result<(), String>) -> std::process::ExitCode {
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{program}: {e}");
            std::process::ExitCode::from(2)
        }
    }
}
