//! Any 16-bit word: decode never panics and gives exactly the README's verdict — bits above the
//! 13 cams, no cams, a parity error (an odd count of ones: every single cam error), or the
//! trolley the 12 number cams carry, whose code is the word; and every trolley decoded by its
//! code differs from the one a single flipped cam would give (the flip is always caught).
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_trolley_id::{ReadError, decode, encode};

fuzz_target!(|data: &[u8]| {
    for pair in data.chunks_exact(2) {
        let raw = u16::from_le_bytes([pair[0], pair[1]]);
        let want = if raw >> 13 != 0 {
            Err(ReadError::BitsAboveCode { raw })
        } else if raw == 0 {
            Err(ReadError::NoCams)
        } else if raw.count_ones() % 2 == 1 {
            Err(ReadError::Parity { raw })
        } else {
            Ok(raw & 0x0FFF)
        };
        let got = decode(raw);
        assert_eq!(got.map(|id| id.get()), want, "{raw:#06x}");
        if let Ok(id) = got {
            assert_eq!(encode(id), raw);
            for cam in 0..13 {
                assert!(
                    decode(raw ^ 1 << cam).is_err(),
                    "one cam of {raw:#06x} flipped decodes"
                );
            }
        }
    }
});
