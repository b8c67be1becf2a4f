//! Arbitrary bytes into `highway::decode`: no panic; whatever decodes encodes back to a byte
//! sequence that decodes to the same message, and equals the input when the input carried exactly
//! the reply room `encode` gives.
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_panel_link::highway::{MAX_MESSAGE, decode};

fuzz_target!(|data: &[u8]| {
    if let Ok(message) = decode(data) {
        let mut buf = [0u8; MAX_MESSAGE];
        let len = message.encode(&mut buf).expect("a decoded message encodes");
        assert_eq!(decode(&buf[..len]), Ok(message));
        if len == data.len() {
            assert_eq!(
                &buf[..len],
                data,
                "canonical length re-encodes byte for byte"
            );
        }
    }
});
