//! Arbitrary bytes into `highway::decode`: no panic; a reply or demand decodes only from a crate
//! 1–62, a demand only with a non-zero SGL; whatever decodes encodes back to a byte
//! sequence that decodes to the same message, and equals the input when the input carried exactly
//! the reply room `encode` gives.
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_panel_link::highway::{MAX_MESSAGE, Message, decode};

fuzz_target!(|data: &[u8]| {
    if let Ok(message) = decode(data) {
        match message {
            Message::Reply { crate_address, .. } => {
                assert!((1..=62).contains(&crate_address), "{message:?}");
            }
            Message::Demand { crate_address, sgl } => {
                assert!((1..=62).contains(&crate_address) && sgl != 0, "{message:?}");
            }
            Message::Command { .. } => {}
        }
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
