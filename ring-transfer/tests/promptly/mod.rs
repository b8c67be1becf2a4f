//! `promptly`: run a call that the README says returns promptly (a capacity check is capped at
//! `MAX_POINTS` demand terms, `min_ring` costs O(log r) checks) and fail, rather than hang, when
//! it does not return within a few seconds.
#![allow(clippy::panic, reason = "a test may panic: that is how it fails")]

use std::sync::mpsc;
use std::time::Duration;

/// What "promptly" means here: far above what any capped call takes in a debug build, far
/// below the time a test runner gives a test.
pub(crate) const BUDGET: Duration = Duration::from_secs(5);

/// `f()`, run on its own thread; panics if it has not returned within [`BUDGET`] (the thread
/// is left behind: the test fails and its process ends). Under Miri, whose clock is virtual,
/// `f` simply runs.
pub(crate) fn promptly<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    if cfg!(miri) {
        return f();
    }
    let (done, result) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = done.send(f());
    });
    match result.recv_timeout(BUDGET) {
        Ok(value) => value,
        Err(mpsc::RecvTimeoutError::Timeout) => panic!("did not return within {BUDGET:?}"),
        Err(mpsc::RecvTimeoutError::Disconnected) => panic!("panicked (see above)"),
    }
}
