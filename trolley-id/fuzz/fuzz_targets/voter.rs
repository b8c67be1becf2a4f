//! Arbitrary bytes as a passage: the first byte picks the strategy and its parameter, the rest
//! are 16-bit readings. The voter must never panic, what it reports must add up, and its
//! verdict is the README's rule, computed by the obvious slow models (the property tests'
//! models, `tests/properties.rs`): `Consecutive { k }` — k identical decodes in a row, a second
//! trolley reaching k is a conflict; `Majority` — a strict majority on every cam, decoded,
//! supported by the readings (no other trolley read more often, at most eight trolleys seen).
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_trolley_id::{NoRead, Strategy, TrolleyId, Verdict, Voter, decode};

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
    let mut distinct: Vec<TrolleyId> = Vec::new();
    for id in confirmed {
        if !distinct.contains(&id) {
            distinct.push(id);
        }
    }
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
    if got == 0 {
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

fuzz_target!(|data: &[u8]| {
    let Some((&head, rest)) = data.split_first() else {
        return;
    };
    let k = (head & 0x7F).max(1);
    let strategy = if head & 0x80 == 0 {
        Strategy::Consecutive { k }
    } else {
        Strategy::Majority { min_samples: k }
    };
    let readings: Vec<u16> = rest
        .chunks_exact(2)
        .map(|c| u16::from_le_bytes([c[0], c[1]]))
        .collect();
    let mut voter = Voter::new(strategy).unwrap();
    let passage = voter.vote(&readings);
    assert_eq!(
        usize::from(passage.samples),
        readings.len().min(usize::from(u16::MAX))
    );
    if readings.len() > usize::from(u16::MAX) {
        assert!(matches!(passage.verdict, Verdict::NoRead(_)));
    }
    let errors = usize::from(passage.no_cams)
        + usize::from(passage.parity_errors)
        + usize::from(passage.faulty_words);
    assert!(errors <= readings.len());
    // Whatever the strategy: only a trolley that some reading decoded to.
    if let Verdict::Identified(id) = passage.verdict {
        assert!(readings.iter().any(|&r| decode(r) == Ok(id)));
    }
    assert_eq!(voter.samples(), 0);
    if readings.len() <= usize::from(u16::MAX) {
        let want = match strategy {
            Strategy::Consecutive { k } => model_consecutive(&readings, usize::from(k)),
            Strategy::Majority { min_samples } => model_majority(&readings, u16::from(min_samples)),
            _ => return,
        };
        assert_eq!(passage.verdict, want, "{strategy:?}");
    }
});
