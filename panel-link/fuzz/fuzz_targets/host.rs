//! The host side of the 1977 panel link against a panel that does anything: the input chooses,
//! byte time by byte time, what comes back from the panel (a byte, a line error or nothing),
//! the MOT line at each poll (one poll every 1–4 byte times), register changes (values above
//! 127 among them) and the host's time-outs. The host's transmitter is asked for a byte once
//! per byte time, as the documentation asks.
//!
//! Checked, from `panel`'s documentation:
//! - the stream is `RESET · r1 … rR RESET · …`: register bytes 0–127, the registers as they
//!   were when the sequence's first register went out, never a gap inside a sequence; SÄN rises
//!   only between sequences (right after a reset byte);
//! - a key is delivered only from two consecutive identical clean bytes received while SÄN is
//!   up (since it rose), and SÄN drops with it; nothing received while SÄN is down does
//!   anything;
//! - `set` refuses a value above 127 and then changes nothing;
//! - whatever the MOT line and the panel's bytes do, a new sequence is completed at least every
//!   `R + 3` byte times plus `key_timeout_polls + mot_stuck_polls` polls.
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_panel_link::line::LineError;
use regler_panel_link::panel::{Host, HostConfig, HostEvent, MAX_VALUE, RESET};

fn run<const R: usize>(head: &[u8], data: &[u8]) {
    let config = HostConfig {
        key_timeout_polls: 6 + u16::from(head[0] % 16),
        mot_stuck_polls: 3 + u16::from(head[1] % 16),
    };
    let poll_every = 1 + usize::from(head[2] % 4);
    let mut host: Host<R> = Host::new(config).unwrap();
    // Where the stream stands: `None` before the first reset byte; Some(k): k register bytes
    // of the open sequence sent (`R + 1`: between sequences, after the idle byte time).
    let mut place: Option<usize> = None;
    let mut snapshot = [0u8; R];
    let mut last_clean: Option<u8> = None;
    let bound = R + 3 + usize::from(config.key_timeout_polls + config.mot_stuck_polls) * poll_every;
    let (mut since_sequence, mut sequences) = (0usize, 0u64);
    for (t, &b) in data.iter().enumerate() {
        // The transmitter, once per byte time.
        let san_before = host.san();
        let byte = host.next_byte();
        match (byte, place) {
            (Some(RESET), Some(k)) => {
                assert!(k == 0 || k == R, "a reset byte after {k} of {R} registers");
                place = Some(0);
            }
            (Some(RESET), None) => place = Some(0),
            (Some(v), Some(k)) if k < R => {
                assert!(v <= MAX_VALUE, "register byte {v:#04x}");
                if k == 0 {
                    snapshot = *host.registers();
                }
                assert_eq!(v, snapshot[k], "register {k} of the sequence");
                place = Some(k + 1);
            }
            (Some(v), p) => panic!("byte {v:#04x} where the stream stands at {p:?}"),
            (None, Some(k)) => assert_eq!(k, 0, "a gap after {k} of {R} registers"),
            (None, None) => panic!("a gap before the first reset byte"),
        }
        if host.san() && !san_before {
            assert_eq!(byte, None);
            assert_eq!(place, Some(0), "SÄN rose inside a sequence");
            last_clean = None;
        }
        // The end of a complete sequence (its closing reset byte) resets the clock.
        since_sequence += 1;
        if host.stats().sequences > sequences {
            sequences = host.stats().sequences;
            since_sequence = 0;
        }
        assert!(
            since_sequence <= bound,
            "no sequence for {since_sequence} byte times (bound {bound}), at byte time {t}"
        );
        // The panel's side of this byte time.
        let listening = host.san();
        let event = match b >> 5 {
            0..=2 => None,
            3 => host.receive(Err(if b & 1 == 0 {
                LineError::Parity
            } else {
                LineError::Framing
            })),
            4 | 5 => host.receive(Ok(b & 0x3F)),
            6 => host.receive(Ok(0x40 | b & 0x03)),
            _ => {
                let before = *host.registers();
                let (index, value) = (usize::from(b & 0x07), b.wrapping_mul(37));
                match host.set(index, value) {
                    Ok(()) => assert!(value <= MAX_VALUE && index < R),
                    Err(_) => assert_eq!(
                        *host.registers(),
                        before,
                        "a refused set changed a register"
                    ),
                }
                None
            }
        };
        if matches!(b >> 5, 3..=6) {
            if !listening {
                assert_eq!(
                    event, None,
                    "something received with SÄN down did something"
                );
            } else {
                let received = if b >> 5 == 3 {
                    None
                } else if b >> 5 == 6 {
                    Some(0x40 | b & 0x03)
                } else {
                    Some(b & 0x3F)
                };
                if let Some(HostEvent::Key(k)) = event {
                    assert_eq!(
                        (received, last_clean),
                        (Some(k), Some(k)),
                        "a key from one byte"
                    );
                    assert!(!host.san(), "SÄN still up after the key");
                }
                last_clean = received;
            }
        }
        // The MOT poll, every `poll_every` byte times; the MOT line from the input's bits.
        if t % poll_every == 0 {
            let mot = b & 0x10 != 0 || b & 0x0F == 0x0F;
            let event = host.poll_mot(mot);
            assert!(!matches!(event, Some(HostEvent::Key(_))), "a key at a poll");
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((head, rest)) = data.split_at_checked(3) else {
        return;
    };
    if head[0] & 0x80 == 0 {
        run::<7>(head, rest);
    } else {
        run::<1>(head, rest);
    }
});
