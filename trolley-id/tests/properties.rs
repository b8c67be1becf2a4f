//! Voter, registry and reader health against the obvious slow implementations.
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "a test may panic: that is how it fails"
)]

use std::collections::BTreeMap;

use proptest::prelude::{Just, any, prop, prop_assert, prop_assert_eq, prop_oneof, proptest};
use proptest::strategy::Strategy as _;
use regler_trolley_id::{
    AlarmChange, AlarmLimits, HealthStats, NoRead, Passage, ReaderHealth, Registry, RejectReason,
    Route, Strategy, TrolleyId, Verdict, Voter, decode, encode,
};

/// Readings biased toward what a reader really sees: a true code, misreads of it, empty scans,
/// other trolleys, and arbitrary words.
fn reading(true_word: u16) -> impl proptest::strategy::Strategy<Value = u16> {
    prop_oneof![
        4 => Just(true_word),
        2 => (0u32..13).prop_map(move |b| true_word ^ (1 << b)),
        2 => (0u32..13, 0u32..13).prop_map(move |(a, b)| true_word ^ (1 << a) ^ (1 << b)),
        1 => Just(0u16),
        1 => any::<u16>(),
    ]
}

/// The longest sequence a property draws: `native`, and at most 40 under Miri, which interprets
/// every step.
const fn long(native: usize) -> usize {
    if cfg!(miri) && native > 40 {
        40
    } else {
        native
    }
}

fn passage_readings() -> impl proptest::strategy::Strategy<Value = Vec<u16>> {
    (1u16..=4095).prop_flat_map(|n| {
        let word = encode(TrolleyId::new(n).unwrap());
        prop::collection::vec(reading(word), 0..12)
    })
}

fn model_consecutive(readings: &[u16], k: usize) -> Verdict {
    let decoded: Vec<Option<TrolleyId>> = readings.iter().map(|&r| decode(r).ok()).collect();
    let mut confirmed: Vec<TrolleyId> = Vec::new();
    for i in 0..decoded.len() {
        // A run of exactly k ending at i (counting the k-th element of each run once).
        if i + 1 >= k {
            let window = &decoded[i + 1 - k..=i];
            let first = window[0];
            let starts_run = i + 1 == k || decoded[i - k] != first;
            if let Some(id) = first.filter(|_| starts_run && window.iter().all(|d| *d == first)) {
                confirmed.push(id);
            }
        }
    }
    confirmed.dedup();
    let distinct: Vec<TrolleyId> = confirmed.iter().fold(Vec::new(), |mut v, id| {
        if !v.contains(id) {
            v.push(*id);
        }
        v
    });
    match distinct.as_slice() {
        [] if readings.iter().all(|&r| r == 0) => Verdict::NoRead(NoRead::NoCams),
        [] => Verdict::NoRead(NoRead::NoAgreement),
        [one] => Verdict::Identified(*one),
        [first, second, ..] => Verdict::NoRead(NoRead::Conflict {
            first: *first,
            second: *second,
        }),
    }
}

fn model_majority(readings: &[u16], min: u16) -> Verdict {
    let votes: Vec<u16> = readings
        .iter()
        .copied()
        .filter(|&r| r != 0 && r < 0x2000)
        .collect();
    let got = votes.len() as u16;
    // No cams only when no reading had any: faulty words (bits above the cams) have cams.
    if readings.iter().all(|&r| r == 0) {
        return Verdict::NoRead(NoRead::NoCams);
    }
    if got < min {
        return Verdict::NoRead(NoRead::TooFewSamples { got, needed: min });
    }
    let mut word = 0;
    for bit in 0..13u8 {
        let ones = votes.iter().filter(|&&r| r >> bit & 1 == 1).count();
        let zeros = votes.len() - ones;
        if ones == zeros {
            return Verdict::NoRead(NoRead::AmbiguousBit { bit });
        }
        if ones > zeros {
            word |= 1 << bit;
        }
    }
    let majority = match decode(word) {
        Ok(id) => id,
        Err(e) => return Verdict::NoRead(NoRead::Undecodable(e)),
    };
    // Support: readings decoded to the majority trolley, and to no other more often; more than
    // eight different trolleys in one passage is beyond what the voter tracks.
    let mut counts = std::collections::BTreeMap::new();
    for id in readings.iter().filter_map(|&r| decode(r).ok()) {
        *counts.entry(id).or_insert(0usize) += 1;
    }
    let support = counts.get(&majority).copied().unwrap_or(0);
    if support > 0 && counts.len() <= 8 && counts.values().all(|&n| n <= support) {
        Verdict::Identified(majority)
    } else {
        Verdict::NoRead(NoRead::Unsupported { majority })
    }
}

/// Passages in which several different trolleys read validly: where a bitwise majority can
/// invent a trolley no reading showed.
fn mixed_valid_readings() -> impl proptest::strategy::Strategy<Value = Vec<u16>> {
    prop::collection::vec(1u16..=4095, 1..5).prop_flat_map(|ids| {
        let words: Vec<u16> = ids
            .iter()
            .map(|&n| encode(TrolleyId::new(n).unwrap()))
            .collect();
        prop::collection::vec(prop::sample::select(words), 1..12)
    })
}

proptest! {
    #[test]
    fn consecutive_matches_model(readings in passage_readings(), k in 1u8..5) {
        let mut voter = Voter::new(Strategy::Consecutive { k }).unwrap();
        let passage = voter.vote(&readings);
        prop_assert_eq!(passage.verdict, model_consecutive(&readings, k.into()));
        prop_assert_eq!(usize::from(passage.samples), readings.len());
        prop_assert_eq!(
            usize::from(passage.parity_errors),
            readings.iter().filter(|&&r| matches!(decode(r), Err(regler_trolley_id::ReadError::Parity { .. }))).count()
        );
    }

    #[test]
    fn majority_matches_model(readings in passage_readings(), min in 1u8..6) {
        let mut voter = Voter::new(Strategy::Majority { min_samples: min }).unwrap();
        prop_assert_eq!(voter.vote(&readings).verdict, model_majority(&readings, min.into()));
    }

    #[test]
    fn majority_matches_model_when_several_trolleys_read_validly(readings in mixed_valid_readings(), min in 1u8..4) {
        let mut voter = Voter::new(Strategy::Majority { min_samples: min }).unwrap();
        prop_assert_eq!(voter.vote(&readings).verdict, model_majority(&readings, min.into()));
    }

    /// Safety: whatever the strategy, an identified trolley was decoded from some reading, and
    /// feeding readings one by one or as a slice gives the same passage.
    #[test]
    fn identified_only_from_real_decodes(
        readings in prop_oneof![passage_readings(), mixed_valid_readings()],
        k in 1u8..4,
    ) {
        for strategy in [Strategy::Consecutive { k }, Strategy::Majority { min_samples: k }] {
            let mut a = Voter::new(strategy).unwrap();
            let mut b = Voter::new(strategy).unwrap();
            for &r in &readings { a.sample(r); }
            let (pa, pb) = (a.finish(), b.vote(&readings));
            prop_assert_eq!(pa, pb);
            if let Verdict::Identified(id) = pa.verdict {
                prop_assert!(readings.iter().any(|&r| decode(r) == Ok(id)), "{strategy:?} named {id}");
            }
            let distinct: std::collections::BTreeSet<_> =
                readings.iter().filter_map(|&r| decode(r).ok()).collect();
            prop_assert_eq!(pa.disagreement, distinct.len() > 1);
        }
    }

    #[test]
    fn registry_matches_a_map(ops in prop::collection::vec((0u8..3, 1u16..=4095, any::<u8>()), 0..long(200))) {
        let mut registry: Registry<u8> = Registry::new();
        let mut model: BTreeMap<u16, u8> = BTreeMap::new();
        for (op, n, dest) in ops {
            let id = TrolleyId::new(n).unwrap();
            match op {
                0 => prop_assert_eq!(registry.assign(id, dest), model.insert(n, dest)),
                1 => prop_assert_eq!(registry.release(id), model.remove(&n)),
                _ => {
                    let want = match model.get(&n) {
                        None => Route::Reject(RejectReason::NoDestination(id)),
                        Some(&d) if d % 2 == 0 => Route::Deliver { trolley: id, destination: d },
                        Some(&d) => Route::Reject(RejectReason::Implausible { trolley: id, destination: d }),
                    };
                    prop_assert_eq!(registry.route(&Verdict::Identified(id), |d| d % 2 == 0), want);
                }
            }
            prop_assert_eq!(registry.len(), model.len());
        }
        let listed: Vec<(u16, u8)> = registry.iter().map(|(t, &d)| (t.get(), d)).collect();
        prop_assert_eq!(listed, model.into_iter().collect::<Vec<_>>());
    }

    #[test]
    fn health_window_matches_recount(flags in prop::collection::vec((any::<bool>(), any::<bool>(), any::<bool>()), 0..long(300))) {
        const W: usize = 16;
        let limits = AlarmLimits { min_passages: 16, ..AlarmLimits::default() };
        let mut health: ReaderHealth<W> = ReaderHealth::new(limits).unwrap();
        let passages: Vec<Passage> = flags.iter().map(|&(no_read, parity, disagreement)| Passage {
            verdict: if no_read { Verdict::NoRead(NoRead::NoAgreement) } else { Verdict::Identified(TrolleyId::MIN) },
            samples: 1,
            no_cams: 0,
            parity_errors: u16::from(parity),
            faulty_words: 0,
            disagreement,
        }).collect();
        for (i, p) in passages.iter().enumerate() {
            health.record(p);
            let recent = &passages[i.saturating_sub(W - 1)..=i];
            let want = HealthStats {
                passages: recent.len() as u32,
                parity_errors: recent.iter().filter(|p| p.parity_errors > 0).count() as u32,
                no_reads: recent.iter().filter(|p| p.verdict.trolley().is_none()).count() as u32,
                disagreements: recent.iter().filter(|p| p.disagreement).count() as u32,
                faulty_words: 0,
            };
            prop_assert_eq!(health.window(), want);
            prop_assert_eq!(health.totals().passages as usize, i + 1);
        }
    }
}

/// The alarm rule in the docs' words, over shares computed as real numbers: raised when the
/// window holds at least `min_passages` and a share exceeds its limit, cleared when both shares
/// are at or below half their limits; a limit of 1000 ‰ or more switches its symptom off (no part
/// in raising or clearing).
fn alarm_model<const W: usize>(
    limits: AlarmLimits,
    stream: &[(bool, bool)],
) -> Result<(), proptest::test_runner::TestCaseError> {
    let mut health: ReaderHealth<W> = ReaderHealth::new(limits).unwrap();
    let mut alarm = false;
    for (i, &(no_read, disagreement)) in stream.iter().enumerate() {
        let change = health.record(&Passage {
            verdict: if no_read {
                Verdict::NoRead(NoRead::NoAgreement)
            } else {
                Verdict::Identified(TrolleyId::MIN)
            },
            samples: 1,
            no_cams: 0,
            parity_errors: 0,
            faulty_words: 0,
            disagreement,
        });
        let recent = &stream[(i + 1).saturating_sub(W)..=i];
        let n = recent.len() as f64;
        let share = |k: usize| k as f64 / n;
        let no_reads = share(recent.iter().filter(|p| p.0).count());
        let disagreements = share(recent.iter().filter(|p| p.1).count());
        let (nl, dl) = (
            f64::from(limits.no_read_per_mille) / 1000.0,
            f64::from(limits.disagreement_per_mille) / 1000.0,
        );
        let want = if !alarm
            && recent.len() >= limits.min_passages as usize
            && (no_reads > nl || disagreements > dl)
        {
            alarm = true;
            Some(AlarmChange::Raised)
        } else if alarm
            && (nl >= 1.0 || no_reads <= nl / 2.0)
            && (dl >= 1.0 || disagreements <= dl / 2.0)
        {
            alarm = false;
            Some(AlarmChange::Cleared)
        } else {
            None
        };
        prop_assert_eq!(change, want, "passage {}", i);
        prop_assert_eq!(health.alarm(), alarm);
    }
    Ok(())
}

fn limits_for(window: u32) -> impl proptest::strategy::Strategy<Value = AlarmLimits> {
    (0u32..2100, 0u32..2100, 0..=window).prop_map(
        |(no_read_per_mille, disagreement_per_mille, min_passages)| AlarmLimits {
            no_read_per_mille,
            disagreement_per_mille,
            min_passages,
        },
    )
}

fn stream() -> impl proptest::strategy::Strategy<Value = Vec<(bool, bool)>> {
    // Runs of good passages with bursts of symptoms, so shares cross their limits both ways.
    prop::collection::vec(
        (prop::bool::weighted(0.1), prop::bool::weighted(0.05)),
        0..long(600),
    )
}

proptest! {
    #[test]
    fn alarm_follows_the_documented_rule_exactly(
        small in limits_for(1), two in limits_for(2), five in limits_for(5), big in limits_for(170),
        passages in stream(),
    ) {
        alarm_model::<1>(small, &passages)?;
        alarm_model::<2>(two, &passages)?;
        alarm_model::<5>(five, &passages)?;
        alarm_model::<170>(big, &passages)?;
    }
}
