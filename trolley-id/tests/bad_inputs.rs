//! Bad inputs (issue 22 §5): every public constructor and operation of `regler-trolley-id` fed
//! the extremes — every `u16` as a trolley number and as a reading (exhaustive), passages of 0,
//! 1, 65 535 and 65 536 readings, strategies with 0, 1 and `u8::MAX`, the registry's first and
//! last cells, reader-health windows of 1 and 2 with limits of 0, 1000 and `u32::MAX` and
//! passages whose counts are at `u16::MAX` — with the exact error or documented result.
#![allow(
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    clippy::type_complexity,
    reason = "a test may panic: that is how it fails"
)]

use regler_trolley_id::{
    AlarmChange, AlarmLimits, AlarmLimitsError, HealthStats, InvalidTrolleyNumber, NoRead, Passage,
    ReadError, ReaderHealth, Registry, RejectReason, Route, Strategy, StrategyError, TrolleyId,
    Verdict, Voter, decode, encode,
};

/// Every `u16` (every 257th under Miri).
fn every_u16() -> impl Iterator<Item = u16> {
    let step = if cfg!(miri) { 257 } else { 1 };
    (0..=u16::MAX).step_by(step).chain([u16::MAX])
}

/// `TrolleyId::new`, `try_from`, `decode` over every `u16`, against the obvious model; `encode`
/// round trips for every trolley.
#[test]
fn numbers_and_readings_over_every_u16() {
    for n in every_u16() {
        let valid = (1..=4095).contains(&n);
        assert_eq!(
            TrolleyId::new(n).map(TrolleyId::get),
            valid.then_some(n),
            "new({n})"
        );
        assert_eq!(
            TrolleyId::try_from(n).map(TrolleyId::get),
            if valid {
                Ok(n)
            } else {
                Err(InvalidTrolleyNumber(n))
            }
        );
        let want = if n > 0x1FFF {
            Err(ReadError::BitsAboveCode { raw: n })
        } else if n == 0 {
            Err(ReadError::NoCams)
        } else if n.count_ones() % 2 == 1 {
            Err(ReadError::Parity { raw: n })
        } else {
            Ok(TrolleyId::new(n & 0x0FFF).unwrap())
        };
        assert_eq!(decode(n), want, "decode({n:#06x})");
    }
    for id in TrolleyId::all() {
        assert_eq!(decode(encode(id)), Ok(id));
    }
    assert_eq!(
        (
            TrolleyId::MIN.get(),
            TrolleyId::MAX.get(),
            TrolleyId::all().count()
        ),
        (1, 4095, 4095)
    );
}

fn word(n: u16) -> u16 {
    encode(TrolleyId::new(n).unwrap())
}

/// Voters at their extremes: strategies with 0, 1 and `u8::MAX`; passages of 0 and 1 readings,
/// of faulty words only, of an even split; the verdict and the counts.
#[test]
#[rustfmt::skip]
fn voters_at_the_extremes() {
    assert_eq!(Voter::new(Strategy::Consecutive { k: 0 }).map(|_| ()), Err(StrategyError::ZeroConsecutive));
    assert_eq!(Voter::new(Strategy::Majority { min_samples: 0 }).map(|_| ()), Err(StrategyError::ZeroMinSamples));
    let c = |k| Strategy::Consecutive { k };
    let m = |min_samples| Strategy::Majority { min_samples };
    let (a, b) = (word(1), word(4095));
    let id = |n| Verdict::Identified(TrolleyId::new(n).unwrap());
    // (what, strategy, readings, verdict, (samples, no_cams, parity, faulty, disagreement))
    let rows: Vec<(&str, Strategy, Vec<u16>, Verdict, (u16, u16, u16, u16, bool))> = vec![
        ("no readings, k 1", c(1), vec![], Verdict::NoRead(NoRead::NoCams), (0, 0, 0, 0, false)),
        ("no readings, majority 1", m(1), vec![], Verdict::NoRead(NoRead::NoCams), (0, 0, 0, 0, false)),
        ("one reading, k 1", c(1), vec![b], id(4095), (1, 0, 0, 0, false)),
        ("one reading, majority 1", m(1), vec![b], id(4095), (1, 0, 0, 0, false)),
        ("one reading, k MAX", c(u8::MAX), vec![b], Verdict::NoRead(NoRead::NoAgreement), (1, 0, 0, 0, false)),
        ("one reading, majority MAX", m(u8::MAX), vec![b], Verdict::NoRead(NoRead::TooFewSamples { got: 1, needed: 255 }), (1, 0, 0, 0, false)),
        ("only zeros", c(1), vec![0; 3], Verdict::NoRead(NoRead::NoCams), (3, 3, 0, 0, false)),
        ("only u16::MAX (faulty)", c(1), vec![u16::MAX; 3], Verdict::NoRead(NoRead::NoAgreement), (3, 0, 0, 3, false)),
        ("only u16::MAX, majority", m(1), vec![u16::MAX; 3], Verdict::NoRead(NoRead::TooFewSamples { got: 0, needed: 1 }), (3, 0, 0, 3, false)),
        ("only parity errors", c(1), vec![0x1FFF; 2], Verdict::NoRead(NoRead::NoAgreement), (2, 0, 2, 0, false)),
        ("two trolleys, k 1", c(1), vec![a, b], Verdict::NoRead(NoRead::Conflict { first: TrolleyId::new(1).unwrap(), second: TrolleyId::new(4095).unwrap() }), (2, 0, 0, 0, true)),
        ("even split, majority", m(1), vec![a, b], Verdict::NoRead(NoRead::AmbiguousBit { bit: 1 }), (2, 0, 0, 0, true)),
        ("k MAX reached", c(u8::MAX), vec![a; 255], id(1), (255, 0, 0, 0, false)),
    ];
    for (what, strategy, readings, verdict, (samples, no_cams, parity, faulty, disagreement)) in rows {
        let mut v = Voter::new(strategy).unwrap();
        let p = v.vote(&readings);
        assert_eq!(p.verdict, verdict, "{what}");
        assert_eq!((p.samples, p.no_cams, p.parity_errors, p.faulty_words, p.disagreement), (samples, no_cams, parity, faulty, disagreement), "{what}: counts");
        // The voter is cleared for the next passage.
        assert_eq!(v.samples(), 0);
        assert_eq!(v.vote(&[b]), Voter::new(strategy).unwrap().vote(&[b]), "{what}: the next passage is judged as by a new voter");
    }
}

/// A passage of 65 535 readings is decided; one of 65 536 is `TooManySamples`, its counts
/// saturated at `u16::MAX`, and the voter is cleared after it.
#[test]
#[cfg_attr(miri, ignore = "65 536 samples: minutes under Miri")]
fn a_passage_of_65_536_readings() {
    for strategy in [
        Strategy::Consecutive { k: 2 },
        Strategy::Majority { min_samples: 1 },
    ] {
        let mut v = Voter::new(strategy).unwrap();
        let p = v.vote(&vec![word(7); 65_535]);
        assert_eq!(
            (p.verdict, p.samples),
            (Verdict::Identified(TrolleyId::new(7).unwrap()), u16::MAX),
            "{strategy:?}"
        );
        let p = v.vote(&vec![word(7); 65_536]);
        assert_eq!(
            (p.verdict, p.samples),
            (Verdict::NoRead(NoRead::TooManySamples), u16::MAX),
            "{strategy:?}"
        );
        let p = v.vote(&vec![0; 65_536]);
        assert_eq!(
            (p.verdict, p.no_cams),
            (Verdict::NoRead(NoRead::TooManySamples), u16::MAX),
            "{strategy:?}: no cams"
        );
        assert_eq!(
            v.vote(&[word(7), word(7)]).verdict,
            Verdict::Identified(TrolleyId::new(7).unwrap())
        );
    }
}

/// The registry at its first and last cells; release of an unassigned trolley; routes of every
/// verdict kind.
#[test]
#[rustfmt::skip]
fn registry_at_the_extremes() {
    let (min, max) = (TrolleyId::MIN, TrolleyId::MAX);
    let mut r: Registry<u8> = Registry::new();
    assert!(r.is_empty());
    // (operation result, expected)
    assert_eq!(r.release(max), None, "release of a trolley never assigned");
    assert_eq!(r.assign(min, 1), None);
    assert_eq!(r.assign(max, 2), None);
    assert_eq!(r.assign(max, u8::MAX), Some(2), "re-assign hands back the old destination");
    assert_eq!((r.len(), r.destination(min), r.destination(max)), (2, Some(&1), Some(&u8::MAX)));
    assert_eq!(r.iter().map(|(t, d)| (t.get(), *d)).collect::<Vec<_>>(), [(1, 1), (4095, 255)]);
    // route: (what, verdict, plausible, route)
    let rows: Vec<(&str, Verdict, bool, Route<u8>)> = vec![
        ("MAX identified", Verdict::Identified(max), true, Route::Deliver { trolley: max, destination: u8::MAX }),
        ("MAX implausible", Verdict::Identified(max), false, Route::Reject(RejectReason::Implausible { trolley: max, destination: u8::MAX })),
        ("no destination", Verdict::Identified(TrolleyId::new(2).unwrap()), true, Route::Reject(RejectReason::NoDestination(TrolleyId::new(2).unwrap()))),
        ("no-read", Verdict::NoRead(NoRead::TooManySamples), true, Route::Reject(RejectReason::NoRead(NoRead::TooManySamples))),
    ];
    for (what, verdict, plausible, want) in rows {
        assert_eq!(r.route(&verdict, |_| plausible), want, "{what}");
    }
    assert_eq!(r.release(min), Some(1));
    assert_eq!(r.release(min), None, "released twice");
    r.clear();
    assert!(r.is_empty() && r.destination(max).is_none());
}

fn passage(verdict: Verdict, parity: u16, faulty: u16, disagreement: bool) -> Passage {
    Passage {
        verdict,
        samples: u16::MAX,
        no_cams: u16::MAX,
        parity_errors: parity,
        faulty_words: faulty,
        disagreement,
    }
}

/// Reader health: windows of 1 and 2, limits 0, 1000 and `u32::MAX`, `min_passages` 0 and one
/// past the window; passages whose counts are all `u16::MAX`; `per_mille` with no passages.
#[test]
#[rustfmt::skip]
fn reader_health_at_the_extremes() {
    let l = |no_read_per_mille, disagreement_per_mille, min_passages| AlarmLimits { no_read_per_mille, disagreement_per_mille, min_passages };
    assert_eq!(ReaderHealth::<1>::new(l(5, 10, 2)).map(|_| ()), Err(AlarmLimitsError::MinPassagesAboveWindow { min_passages: 2, window: 1 }));
    assert_eq!(ReaderHealth::<2>::new(l(5, 10, u32::MAX)).map(|_| ()), Err(AlarmLimitsError::MinPassagesAboveWindow { min_passages: u32::MAX, window: 2 }));
    assert!(ReaderHealth::<1>::new(l(0, 0, 0)).is_ok());
    let no_read = || passage(Verdict::NoRead(NoRead::NoCams), u16::MAX, u16::MAX, true);
    let good = || passage(Verdict::Identified(TrolleyId::MAX), 0, 0, false);
    // (what, window-1 limits, passages, alarm changes)
    let rows: Vec<(&str, AlarmLimits, Vec<Passage>, Vec<Option<AlarmChange>>)> = vec![
        ("limits 0: the first no-read raises", l(0, 0, 0), vec![no_read(), good()], vec![Some(AlarmChange::Raised), Some(AlarmChange::Cleared)]),
        ("limits 0, a good passage never raises", l(0, 0, 1), vec![good(), good()], vec![None, None]),
        ("limits 1000: switched off", l(1000, 1000, 0), vec![no_read(), no_read()], vec![None, None]),
        ("limits MAX: switched off", l(u32::MAX, u32::MAX, 1), vec![no_read(), no_read()], vec![None, None]),
        ("no-reads only counted", l(0, 1000, 1), vec![no_read(), good()], vec![Some(AlarmChange::Raised), Some(AlarmChange::Cleared)]),
    ];
    for (what, limits, passages, changes) in rows {
        let mut h = ReaderHealth::<1>::new(limits).unwrap();
        let got: Vec<_> = passages.iter().map(|p| h.record(p)).collect();
        assert_eq!(got, changes, "{what}");
        assert_eq!(h.totals().passages, passages.len() as u32, "{what}");
        assert_eq!(h.window().passages, 1, "{what}: a window of 1");
    }
    // A passage with every count at u16::MAX counts once per symptom.
    let mut h = ReaderHealth::<2>::new(l(5, 10, 1)).unwrap();
    h.record(&no_read());
    assert_eq!(h.window(), HealthStats { passages: 1, parity_errors: 1, no_reads: 1, disagreements: 1, faulty_words: 1 });
    h.reset();
    assert_eq!((h.window(), h.totals(), h.alarm()), (HealthStats::ZERO, HealthStats::ZERO, false));
    // per_mille: (stats, count, per mille)
    let s = |passages| HealthStats { passages, ..HealthStats::ZERO };
    for (stats, count, want) in [(s(0), 5, 0), (s(0), u32::MAX, 0), (s(1), 1, 1000), (s(1), u32::MAX, u32::MAX), (s(u32::MAX), u32::MAX, 1000), (s(u32::MAX), 1, 0), (s(3), 1, 333)] {
        assert_eq!(stats.per_mille(count), want, "{stats:?}: per_mille({count})");
    }
}

proptest::proptest! {
    /// `NoCams` means what it says under both strategies: the verdict is `NoCams` exactly when
    /// no reading had any cam (every reading 0, or none at all). Before the fix a `Majority`
    /// passage of faulty words only (bits above the cams: a reader fault) was `NoCams`, as if
    /// the hook were empty; it is now `TooFewSamples { got: 0, .. }`.
    #[test]
    fn no_cams_exactly_when_no_reading_had_a_cam(
        readings in proptest::collection::vec(
            proptest::prop_oneof![
                proptest::strategy::Just(0u16),
                0x2000u16..=u16::MAX,
                1u16..0x2000,
            ],
            0..12,
        ),
        k in 1u8..4,
    ) {
        let empty = readings.iter().all(|&r| r == 0);
        for strategy in [Strategy::Consecutive { k }, Strategy::Majority { min_samples: k }] {
            let p = Voter::new(strategy).unwrap().vote(&readings);
            proptest::prop_assert_eq!(p.verdict == Verdict::NoRead(NoRead::NoCams), empty, "{:?} {:?}: {:?}", strategy, readings, p.verdict);
        }
    }
}
