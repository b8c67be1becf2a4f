//! regler-panel-link on the core: the serial highway's codec, controller and driver, and the
//! 1977 panel link, as a firmware would run them.

use regler_panel_link::highway::{
    Controller, ControllerConfig, Cycle, Dataway, DecodeError, Driver, DriverConfig, DriverEvent,
    MAX_MESSAGE, Message, Status, WAIT, decode,
};
use regler_panel_link::line::{Framing, LineError, Noise};
use regler_panel_link::panel::{Host, HostConfig, HostEvent, Panel, RESET, RegisterError};

use crate::{Outcome, check};

/// One message of each shape.
fn shapes() -> [Message; 5] {
    [
        Message::Command {
            crate_address: 21,
            station: 5,
            subaddress: 9,
            function: 17,
            data: Some(0xA5_5A3C),
        },
        Message::Command {
            crate_address: 42,
            station: 30,
            subaddress: 3,
            function: 2,
            data: None,
        },
        Message::Reply {
            crate_address: 7,
            status: Status {
                err: false,
                x: true,
                q: true,
                derr: false,
            },
            data: Some(0x12_3456),
        },
        Message::Reply {
            crate_address: 8,
            status: Status::default(),
            data: None,
        },
        Message::Demand {
            crate_address: 9,
            sgl: 21,
        },
    ]
}

/// Every 1- and 2-bit error of every shape is rejected (the same check as on the host, on the
/// target's 32-bit `usize` and without a hardware popcount on the M0).
pub fn highway_rejects_every_one_and_two_bit_error() -> Outcome {
    for m in shapes() {
        let mut buf = [0u8; MAX_MESSAGE];
        let len = m.encode(&mut buf).map_err(|_| "encode")?;
        let bytes = buf.get(..len).ok_or("len")?;
        check!(decode(bytes) == Ok(m));
        let bits = len * 8;
        for i in 0..bits {
            for j in i..bits {
                let mut bad = [0u8; MAX_MESSAGE];
                bad[..len].copy_from_slice(bytes);
                bad[i / 8] ^= 1 << (i % 8);
                if j != i {
                    bad[j / 8] ^= 1 << (j % 8);
                }
                check!(decode(&bad[..len]).is_err());
            }
        }
    }
    check!(decode(&[0x04, 0xE0]) == Err(DecodeError::Truncated { crate_address: 4 }));
    Ok(())
}

struct Registers([u32; 32]);

impl Dataway for Registers {
    fn cycle(&mut self, n: u8, _a: u8, f: u8, write: Option<u32>) -> Cycle {
        let reg = &mut self.0[usize::from(n & 31)];
        if let Some(w) = write {
            *reg = w;
        }
        Cycle {
            read: *reg,
            x: true,
            q: f < 8,
        }
    }
}

/// A driver and three crates on a noisy loop: every write lands, every read returns it.
pub fn highway_loop_with_noise() -> Outcome {
    let mut crates = [
        (
            Controller::new(ControllerConfig {
                address: 1,
                demand_repeat: 0,
            })
            .map_err(|_| "c1")?,
            Registers([0; 32]),
        ),
        (
            Controller::new(ControllerConfig {
                address: 2,
                demand_repeat: 0,
            })
            .map_err(|_| "c2")?,
            Registers([0; 32]),
        ),
        (
            Controller::new(ControllerConfig {
                address: 3,
                demand_repeat: 0,
            })
            .map_err(|_| "c3")?,
            Registers([0; 32]),
        ),
    ];
    let mut noise = Noise::new(1e-3, 1977).map_err(|_| "noise")?;
    let mut driver: Driver<3> = Driver::new(DriverConfig {
        timeout: 48,
        retries: 8,
        gap: 1,
    })
    .map_err(|_| "driver")?;
    let mut line = WAIT;
    let mut completed = 0u32;
    for round in 0..60u32 {
        let crate_address = 1 + (round % 3) as u8;
        let (function, data) = if round % 2 == 0 {
            (16, Some(round * 1000))
        } else {
            (0, None)
        };
        driver
            .submit(Message::Command {
                crate_address,
                station: 4,
                subaddress: 0,
                function,
                data,
            })
            .map_err(|_| "submit")?;
        let mut clocks = 0u32;
        loop {
            let step = driver.clock(line);
            let mut byte = step.transmit;
            for (controller, dataway) in crates.iter_mut() {
                byte = controller.clock(noise.corrupt_byte(byte), dataway);
            }
            line = noise.corrupt_byte(byte);
            clocks += 1;
            check!(clocks < 2_000);
            match step.event {
                Some(DriverEvent::Completed(done)) => {
                    if function == 0 {
                        // Written two rounds ago to this crate... or, in the first rounds, 0.
                        let reg = crates[usize::from(crate_address - 1)].1.0[4];
                        check!(done.data == Some(reg));
                    }
                    completed += 1;
                    break;
                }
                Some(DriverEvent::Failed { .. }) => return Err("a command failed"),
                _ => {}
            }
        }
    }
    check!(completed == 60);
    check!(driver.stats().sent >= 60);
    Ok(())
}

/// The panel link: sequence, a damaged byte, the key handshake.
pub fn panel_sequence_and_key() -> Outcome {
    let mut host: Host<29> = Host::new(HostConfig::default()).map_err(|_| "host")?;
    let mut panel: Panel<29> = Panel::new();
    check!(host.set(3, 200) == Err(RegisterError::Value(200)));
    for i in 0..29u8 {
        host.set(usize::from(i), i + 10).map_err(|_| "set")?;
    }
    let framing = Framing::PANEL;
    // One sequence with a byte damaged on the line, then a clean one; a sequence is shown when
    // the reset byte after it arrives, and only if all its bytes were clean. Byte times: the
    // reset byte, an idle byte time (`None`), 29 registers.
    let mut sent = 0u32;
    for _ in 0..62u32 {
        let Some(byte) = host.next_byte() else {
            continue; // the idle byte time after a reset byte
        };
        let mut frame = framing.encode(byte);
        if sent == 5 {
            frame ^= 1 << 4;
        }
        sent += 1;
        panel.receive(framing.decode(frame));
        if sent == 31 {
            check!(panel.registers()[4] == 0); // the damaged sequence is not shown
            check!(panel.stats().discarded == 1);
        }
    }
    check!(sent == 60);
    check!(panel.registers()[4] == 0); // the second sequence is shown when its reset arrives
    panel.receive(framing.decode(framing.encode(host.next_byte().ok_or("host stopped")?)));
    check!(panel.registers() == host.registers());
    check!(framing.decode(framing.encode(RESET) ^ 1) == Err(LineError::Framing));
    // Key: MOT, taken between sequences (right after a reset byte), SÄN, two equal bytes.
    panel.press(0x2A).map_err(|_| "press")?;
    check!(host.poll_mot(panel.mot()).is_none());
    check!(host.next_byte().is_none()); // right after a reset byte: the key's turn
    check!(host.san());
    let first = panel.set_san(host.san()).ok_or("no key sent")?;
    check!(host.receive(Ok(first)).is_none());
    let again = panel.tick_20ms().ok_or("no repeat")?;
    check!(host.receive(Ok(again)) == Some(HostEvent::Key(0x2A)));
    check!(panel.set_san(host.san()).is_none());
    check!(!panel.mot());
    // SÄN stays low for three polls (over 20 ms) with MOT seen low, so a panel that samples
    // SÄN every 20 ms always sees the key taken; then the registers go on.
    for _ in 0..3 {
        check!(host.next_byte().is_none());
        check!(host.poll_mot(panel.mot()).is_none());
    }
    check!(host.next_byte().is_none()); // the idle byte time after the reset byte
    check!(host.next_byte() == Some(10)); // the registers go on: the reset went before
    Ok(())
}
