//! Arbitrary bytes as a passage: the first byte picks the strategy and its parameter, the rest
//! are 16-bit readings. The voter must never panic, and what it reports must add up.
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_trolley_id::{Strategy, Verdict, Voter, decode};

fuzz_target!(|data: &[u8]| {
    let Some((&head, rest)) = data.split_first() else { return };
    let k = (head & 0x7F).max(1);
    let strategy = if head & 0x80 == 0 {
        Strategy::Consecutive { k }
    } else {
        Strategy::Majority { min_samples: k }
    };
    let readings: Vec<u16> =
        rest.chunks_exact(2).map(|c| u16::from_le_bytes([c[0], c[1]])).collect();
    let mut voter = Voter::new(strategy).unwrap();
    let passage = voter.vote(&readings);
    assert_eq!(usize::from(passage.samples), readings.len().min(usize::from(u16::MAX)));
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
});
