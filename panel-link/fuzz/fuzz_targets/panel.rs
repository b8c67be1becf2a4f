//! Arbitrary events into a panel and a host: bytes (clean or with a line error), MOT polls, SÄN
//! changes, key presses and ticks. No panic; the registers only ever hold 7-bit values; once MOT
//! is released and a clean full sequence is through, the panel shows the host's registers (it
//! always recovers, whatever came before).
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_panel_link::line::LineError;
use regler_panel_link::panel::{Host, HostConfig, MAX_VALUE, Panel};

fuzz_target!(|data: &[u8]| {
    let mut host: Host<7> = Host::new(HostConfig {
        key_timeout_polls: 3,
        mot_stuck_polls: 5,
    })
    .unwrap();
    let mut panel: Panel<7> = Panel::new();
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
    // Liveness: release MOT, let the host refresh twice, and the panel agrees.
    for _ in 0..20 {
        let _ = host.poll_mot(false);
    }
    // Two sequences' worth of bytes hold one whole sequence, reset byte first.
    for _ in 0..16 {
        if let Some(byte) = host.next_byte() {
            panel.receive(Ok(byte));
        }
    }
    assert_eq!(panel.registers(), host.registers());
});
