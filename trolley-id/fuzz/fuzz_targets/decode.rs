//! Any 16-bit word: decode never panics, and a word it accepts is exactly the trolley's code.
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_trolley_id::{decode, encode};

fuzz_target!(|data: &[u8]| {
    for pair in data.chunks_exact(2) {
        let raw = u16::from_le_bytes([pair[0], pair[1]]);
        if let Ok(id) = decode(raw) {
            assert_eq!(encode(id), raw);
        }
    }
});
