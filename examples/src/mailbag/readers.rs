//! The code reader at the chain start: the scans it takes of a passing trolley (a swinging
//! trolley gives wrong scans), and the source's reading of one scan with parity alone.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use regler_trolley_id::{NoRead, Passage, Verdict, decode};

use super::DISTURBED_SHARE;

/// The scans a reader takes of one passing trolley.
pub(super) fn scan(rng: &mut ChaCha8Rng, word: u16, readings: u8, disturbed: f64) -> Vec<u16> {
    let swinging = rng.random_bool(disturbed);
    (0..readings)
        .map(|_| {
            if swinging && rng.random_bool(DISTURBED_SHARE) {
                misread(rng, word)
            } else {
                word
            }
        })
        .collect()
}

/// One wrong scan of `word`: 1, 2 or 3 distinct cams flipped (50 %, 35 %, 15 %). Parity catches
/// the odd counts; two flipped cams read as another trolley's number. The dock chains' readers
/// and the whole plant's (`plant::field`) draw their wrong scans here.
pub(crate) fn misread(rng: &mut impl Rng, word: u16) -> u16 {
    let flips = match rng.random_range(0..100) {
        0..50 => 1,
        50..85 => 2,
        _ => 3,
    };
    let mut w = word;
    let mut flipped = 0;
    while flipped < flips {
        let bit = 1u16 << rng.random_range(0..13);
        if (w ^ word) & bit == 0 {
            w ^= bit;
            flipped += 1;
        }
    }
    w
}

/// The source's reading: one scan, parity checked, nothing else.
pub(super) fn single_read(raw: u16) -> Passage {
    let verdict = match decode(raw) {
        Ok(id) => Verdict::Identified(id),
        Err(e) => Verdict::NoRead(NoRead::Undecodable(e)),
    };
    Passage {
        verdict,
        samples: 1,
        no_cams: u16::from(raw == 0),
        parity_errors: u16::from(decode(raw).is_err() && raw != 0),
        faulty_words: 0,
        disagreement: false,
    }
}
