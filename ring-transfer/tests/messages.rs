//! Every error a user of the master and the slave can be handed reads as what was wrong: the
//! whole message of every variant (the link's and the capacity check's are tested beside their
//! code).
#![allow(clippy::unwrap_used, reason = "a test may panic: that is how it fails")]

use regler_ring_transfer::link::DecodeError;
use regler_ring_transfer::{FrameError, Master, SlaveConfigError, SlaveParams};

#[test]
fn every_error_message_names_what_was_wrong() {
    let mut master: Master<2> = Master::new();
    let p = |capacity, t0| SlaveParams { capacity, t0 };
    let master_errors = [
        (
            master.attach(2, p(8, 10)).unwrap_err(),
            "slave 2 is beyond the master's capacity",
        ),
        (master.reinit(1).unwrap_err(), "slave 1 is not attached"),
        (
            master.attach(0, p(0, 10)).unwrap_err(),
            "ring capacity must be 1..=32767 slots, got 0",
        ),
        (
            master.attach(0, p(8, 0)).unwrap_err(),
            "t0 must be at least 1 time unit per item",
        ),
    ];
    for (error, message) in master_errors {
        assert_eq!(error.to_string(), message, "{error:?}");
    }
    let config_errors = [
        (SlaveConfigError::ZeroRow, "row_len must be at least 1 item"),
        (
            SlaveConfigError::ZeroSilenceLimit,
            "silence_limit must be at least 1 step",
        ),
        (
            SlaveConfigError::ZeroRetry,
            "retry_after must be at least 1 step",
        ),
        (
            SlaveConfigError::Capacity(40_000),
            "ring must have 1..=32767 slots, got 40000",
        ),
        (
            SlaveConfigError::Drift {
                silence_limit: 50_000,
                row_len: 4,
                capacity: 8,
            },
            "silence_limit + row_len + ring slots must be at most 32767, got 50000 + 4 + 8",
        ),
    ];
    for (error, message) in config_errors {
        assert_eq!(error.to_string(), message, "{error:?}");
    }
    let frame_errors = [
        (
            FrameError::Decode(DecodeError::Empty),
            "bad frame: empty frame",
        ),
        (FrameError::NotForMe(3), "refill addressed to slave 3"),
        (FrameError::NotARefill, "a report, not a refill"),
    ];
    for (error, message) in frame_errors {
        assert_eq!(error.to_string(), message, "{error:?}");
    }
}
