//! Two parts, chosen by the first input byte.
//!
//! Even: arbitrary events into a panel and a host: bytes (clean or with a line error), MOT polls,
//! SÄN changes, key presses and ticks. No panic; the registers only ever hold 7-bit values; once
//! MOT is released and a clean full sequence is through, the panel shows the host's registers
//! (it always recovers, whatever came before).
//!
//! Odd: the host's stream of two register sets `a` then `b` (from the input), framed, with the
//! idle byte time after every reset byte as eleven 1 bits, up to two bits flipped anywhere
//! (positions from the input), read frame by frame or through a bit receiver. Frames read in sync
//! (what a UART gives while it keeps sync), 1 or 2 flips, and a bit receiver with 1 flip: after
//! every byte every register shows a value the host sent for it, or — at frame level, for the
//! register whose own frame took both flips — some 7-bit value (the parity cannot see two
//! flips). A bit receiver with 2 flips may show wrong 7-bit values (a receiver thrown out of
//! character sync can read a fake reset byte) until it recovers. In every case the display is `b`
//! once the flips are two sequences behind.
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_panel_link::line::{BitReceiver, Framing, LineError};
use regler_panel_link::panel::{Host, HostConfig, MAX_VALUE, Panel, RESET};

const R: usize = 7;
/// Byte times per sequence: the reset byte, the idle byte time, the registers.
const SEQ: usize = R + 2;

fn events(data: &[u8]) {
    let mut host: Host<R> = Host::new(HostConfig {
        key_timeout_polls: 6,
        mot_stuck_polls: 5,
    })
    .unwrap();
    let mut panel: Panel<R> = Panel::new();
    for pair in data.chunks_exact(2) {
        let (op, arg) = (pair[0], pair[1]);
        match op % 8 {
            0 => panel.receive(Ok(arg)),
            1 => panel.receive(Err(if arg & 1 == 0 {
                LineError::Parity
            } else {
                LineError::Framing
            })),
            2 => {
                let _ = panel.press(arg);
            }
            3 => {
                let _ = panel.set_san(arg & 1 == 1);
            }
            4 => {
                let _ = panel.tick_20ms();
            }
            5 => {
                let _ = host.poll_mot(arg & 1 == 1);
            }
            6 => {
                let _ = host.receive(if arg == 0 {
                    Err(LineError::Parity)
                } else {
                    Ok(arg)
                });
            }
            _ => {
                let _ = host.set(usize::from(arg % 8), arg >> 1);
                if let Some(byte) = host.next_byte() {
                    panel.receive(Ok(byte));
                }
            }
        }
        assert!(panel.registers().iter().all(|&v| v <= MAX_VALUE));
        assert!(host.registers().iter().all(|&v| v <= MAX_VALUE));
    }
    // Liveness: release MOT (a key exchange in progress times out and ends), then the rest of
    // the sequence under way, a whole one and the reset byte closing it: at most 2 (R + 2) byte
    // times (the host leaves one idle byte time after each reset byte).
    for _ in 0..20 {
        let _ = host.poll_mot(false);
    }
    for _ in 0..2 * SEQ {
        if let Some(byte) = host.next_byte() {
            panel.receive(Ok(byte));
        }
    }
    assert_eq!(panel.registers(), host.registers());
}

fn bit_errors(data: &[u8]) {
    if data.len() < 2 * R + 5 {
        return;
    }
    let a: [u8; R] = core::array::from_fn(|i| data[i] & 0x7F);
    let b: [u8; R] = core::array::from_fn(|i| data[R + i] & 0x7F);
    let flips = usize::from(data[2 * R] % 3);
    let total = 6 * SEQ;
    let bits_total = 3 + 11 * total;
    let pos = |k: usize| {
        usize::from(u16::from_le_bytes([data[2 * R + 1 + 2 * k], data[2 * R + 2 + 2 * k]]))
            % (11 * 3 * SEQ)
    };
    let flipped: Vec<usize> = (0..flips).map(|k| 3 + pos(k)).collect();
    let bit_level = data.get(2 * R + 5).is_some_and(|m| m & 1 == 1);

    let mut host: Host<R> = Host::new(HostConfig::default()).unwrap();
    for (i, &v) in a.iter().enumerate() {
        host.set(i, v).unwrap();
    }
    // Byte time by byte time: Some(byte), or None for the idle byte time.
    let mut slots = Vec::new();
    while slots.len() < total {
        slots.push(host.next_byte());
        if host.stats().sequences == 1 {
            for (i, &v) in b.iter().enumerate() {
                host.set(i, v).unwrap();
            }
        }
    }
    let framing = Framing::PANEL;
    let mut line = vec![true; 3];
    for slot in &slots {
        let frame = slot.map_or(0x7FF, |byte| framing.encode(byte));
        line.extend((0..11).map(|k| frame >> k & 1 == 1));
    }
    assert_eq!(line.len(), bits_total);
    for &f in &flipped {
        line[f] = !line[f];
    }
    let mut allow: [u128; R] = core::array::from_fn(|i| 1 | 1 << a[i] | 1 << b[i]);
    if bit_level && flipped.len() == 2 {
        allow = [u128::MAX; R]; // recovery only (checked at the end)
    }
    for n in 0..total {
        let place = n % SEQ;
        if place >= 2 {
            let start = 3 + 11 * n;
            if flipped.len() == 2 && flipped.iter().all(|f| (start..start + 11).contains(f)) {
                allow[place - 2] = u128::MAX;
            }
        }
    }
    let mut panel: Panel<R> = Panel::new();
    let mut rx = BitReceiver::new(framing);
    let check = |panel: &Panel<R>| {
        for (i, &v) in panel.registers().iter().enumerate() {
            assert!(
                v <= MAX_VALUE && allow[i] >> v & 1 == 1,
                "register {i} shows {v}: a {a:?}, b {b:?}, flipped {flipped:?}"
            );
        }
    };
    for (n, slot) in slots.iter().enumerate() {
        let from = 3 + 11 * n;
        if bit_level {
            for k in from..from + 11 {
                if let Some(got) = rx.bit(line[k]) {
                    panel.receive(got);
                    check(&panel);
                }
            }
        } else if slot.is_some() {
            // Frames read in sync: the idle byte time carries no frame.
            let frame = (0..11).fold(0u16, |f, k| f | u16::from(line[from + k]) << k);
            panel.receive(framing.decode(frame));
            check(&panel);
        }
    }
    // The flips lie in the first three sequences: the display is `b` by the end of the sixth.
    assert_eq!(slots[5 * SEQ], Some(RESET));
    assert_eq!(panel.registers(), &b, "flipped {flipped:?}, bit level {bit_level}");
}

fuzz_target!(|data: &[u8]| {
    match data.split_first() {
        Some((mode, rest)) if mode & 1 == 1 => bit_errors(rest),
        Some((_, rest)) => events(rest),
        None => {}
    }
});
