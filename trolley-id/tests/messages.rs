//! Every error's message, read as a user reads it: it names what was wrong (the value read, the
//! limit it broke). Written out in full, so a message that loses its value or its limit fails.
#![allow(clippy::unwrap_used, reason = "a test may panic: that is how it fails")]

use regler_trolley_id::{
    AlarmLimits, AlarmLimitsError, HealthStats, InvalidTrolleyNumber, NoRead, ReadError,
    ReaderHealth, RejectReason, Strategy, StrategyError, TrolleyId, Voter,
};

fn id(n: u16) -> TrolleyId {
    TrolleyId::new(n).unwrap()
}

#[test]
fn every_error_message_names_what_was_wrong() {
    // A trolley is shown by its number.
    assert_eq!(id(1977).to_string(), "trolley 1977");
    // A number that is no trolley: the range and the number given.
    assert_eq!(
        TrolleyId::try_from(4096).unwrap_err().to_string(),
        "trolley numbers run from 1 to 4095, got 4096"
    );
    assert_eq!(
        InvalidTrolleyNumber(0).to_string(),
        "trolley numbers run from 1 to 4095, got 0"
    );

    // Reading errors: the word as read, and for a reader fault the mask it broke.
    let cases: [(ReadError, &str); 3] = [
        (ReadError::NoCams, "no cams seen: no trolley at the reader"),
        (
            ReadError::Parity { raw: 0x0b01 },
            "parity error in code word 0x0b01: odd number of cams seen",
        ),
        (
            ReadError::BitsAboveCode { raw: 0xa003 },
            "code word 0xa003 has bits set above the 13 cam positions (mask 0x1fff)",
        ),
    ];
    for (e, text) in cases {
        assert_eq!(e.to_string(), text, "{e:?}");
    }

    // Strategies that cannot work: the parameter, its least value and the value given; the
    // errors are the ones `Voter::new` returns.
    let consecutive = Voter::new(Strategy::Consecutive { k: 0 }).unwrap_err();
    assert_eq!(consecutive, StrategyError::ZeroConsecutive);
    assert_eq!(
        consecutive.to_string(),
        "Consecutive k must be at least 1, got 0"
    );
    let majority = Voter::new(Strategy::Majority { min_samples: 0 }).unwrap_err();
    assert_eq!(majority, StrategyError::ZeroMinSamples);
    assert_eq!(
        majority.to_string(),
        "Majority min_samples must be at least 1, got 0"
    );

    // Every no-read: the counts, trolleys, cam or word it is about.
    let no_reads: [(NoRead, &str); 8] = [
        (NoRead::NoCams, "no reading saw any cam"),
        (
            NoRead::TooFewSamples { got: 2, needed: 7 },
            "2 readings with cams, 7 needed",
        ),
        (
            NoRead::NoAgreement,
            "no trolley number was read consistently enough",
        ),
        (
            NoRead::Conflict {
                first: id(51),
                second: id(60),
            },
            "conflicting reads: trolley 51 and trolley 60",
        ),
        (
            NoRead::AmbiguousBit { bit: 11 },
            "cam 11 tied between set and clear",
        ),
        (
            NoRead::Undecodable(ReadError::Parity { raw: 0x0001 }),
            "majority word does not decode: parity error in code word 0x0001: odd number of cams seen",
        ),
        (
            NoRead::Unsupported { majority: id(63) },
            "majority word names trolley 63, which the readings do not support",
        ),
        (
            NoRead::TooManySamples,
            "more than 65535 readings in one passage: reader or trolley stuck",
        ),
    ];
    for (e, text) in no_reads {
        assert_eq!(e.to_string(), text, "{e:?}");
    }

    // Limits `ReaderHealth::new` refuses: both values, from the error it returns.
    let limits = AlarmLimits {
        min_passages: 100,
        ..AlarmLimits::default()
    };
    let e = ReaderHealth::<64>::new(limits).unwrap_err();
    assert_eq!(
        e,
        AlarmLimitsError::MinPassagesAboveWindow {
            min_passages: 100,
            window: 64
        }
    );
    assert_eq!(
        e.to_string(),
        "min_passages is 100 but the window holds only 64 passages: the alarm could never be raised"
    );

    // Why a trolley goes to the reject path: the no-read's own message, the trolley, and the
    // destination it is bound for.
    let rejects: [(RejectReason<u8>, &str); 3] = [
        (
            RejectReason::NoRead(NoRead::TooFewSamples { got: 1, needed: 3 }),
            "no-read: 1 readings with cams, 3 needed",
        ),
        (
            RejectReason::NoDestination(id(43)),
            "trolley 43 has no destination",
        ),
        (
            RejectReason::Implausible {
                trolley: id(42),
                destination: 17,
            },
            "trolley 42 is bound for 17, which this reader cannot reach",
        ),
    ];
    for (e, text) in rejects {
        assert_eq!(e.to_string(), text, "{e:?}");
    }
}

/// A reader's statistics as an operator's display shows them: every count, each named.
#[test]
fn health_stats_show_every_count_by_name() {
    let stats = HealthStats {
        passages: 170,
        parity_errors: 4,
        no_reads: 3,
        disagreements: 2,
        faulty_words: 1,
    };
    assert_eq!(
        stats.to_string(),
        "170 passages, 4 with parity errors, 3 no-reads, 2 disagreements, 1 faulty"
    );
}
