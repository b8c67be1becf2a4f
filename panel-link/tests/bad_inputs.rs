//! Bad inputs (issue 22 §5): every public constructor and operation of `regler-panel-link` fed
//! the extremes — every UART frame (exhaustive), a line stuck at 0 or 1, noise rates NaN, −0,
//! 0.5 and just above, inf; panels and hosts of 1 and 2 registers, register indices at `R` and
//! `usize::MAX`, values 127 and 128, a full key queue, time-outs at and one below their least;
//! highway messages with every field one past its range, buffers one byte short, byte sequences
//! of 0, 1, the longest and one longer, drivers with windows of 1 and 2, crate addresses 0, 62,
//! 63 and 255 — with the exact error or documented result. A refused call changes nothing.
#![allow(
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    clippy::type_complexity,
    reason = "a test may panic: that is how it fails"
)]

use regler_panel_link::highway::{
    self, ConfigError as ControllerConfigError, Controller, ControllerConfig, DecodeError, Driver,
    DriverConfig, DriverError, EncodeError, MAX_DECODE, MAX_MESSAGE, Message, Status,
};
use regler_panel_link::line::{BitReceiver, Framing, LineError, Noise, NoiseError, Parity};
use regler_panel_link::panel::{
    ConfigError, Host, HostConfig, KEY_QUEUE, MIN_KEY_TIMEOUT_POLLS, MIN_MOT_STUCK_POLLS, Panel,
    PanelError, RESET, RegisterError,
};

/// `Framing::decode` over every `u16` for the three parities, against the obvious model, and
/// `encode` round trips every byte.
#[test]
fn every_frame_for_every_framing() {
    let step = if cfg!(miri) { 97 } else { 1 };
    for framing in [
        Framing::BIT_SERIAL,
        Framing::PANEL,
        Framing::new(Parity::Odd),
    ] {
        let stop = framing.bits() - 1;
        for frame in (0..=u16::MAX).step_by(step) {
            let byte = ((frame >> 1) & 0xFF) as u8;
            let ones = byte.count_ones() + u32::from((frame >> 9) & 1);
            let parity_ok = match framing.parity {
                Parity::None => true,
                Parity::Even => ones & 1 == 0,
                Parity::Odd => ones & 1 == 1,
            };
            let want = if frame & 1 != 0 || (frame >> stop) & 1 != 1 {
                Err(LineError::Framing)
            } else if !parity_ok {
                Err(LineError::Parity)
            } else {
                Ok(byte)
            };
            assert_eq!(framing.decode(frame), want, "{framing:?} {frame:#06x}");
        }
        for byte in 0..=u8::MAX {
            assert_eq!(framing.decode(framing.encode(byte)), Ok(byte));
        }
    }
}

/// A receiver fed a line stuck at 0 (a break) reports a framing error per frame time and goes
/// on; one stuck at 1 (idle) reports nothing.
#[test]
fn a_stuck_line() {
    for framing in [Framing::BIT_SERIAL, Framing::PANEL] {
        let mut rx = BitReceiver::new(framing);
        let got: Vec<_> = (0..framing.bits() * 3)
            .filter_map(|_| rx.bit(false))
            .collect();
        assert_eq!(
            got,
            vec![Err(LineError::Framing); 3],
            "{framing:?} stuck at 0"
        );
        let mut rx = BitReceiver::new(framing);
        assert!(
            (0..1000).all(|_| rx.bit(true).is_none()),
            "{framing:?} stuck at 1"
        );
        assert!(!rx.busy());
    }
}

/// `Noise::new` with rates NaN, ±inf, −0, subnormal, 0.5 and just above; `corrupt` with 0, 16,
/// 17 and `u32::MAX` bits.
#[test]
#[rustfmt::skip]
fn noise_at_the_extremes() {
    let rows: [(f64, bool); 9] = [
        (f64::NAN, false),
        (f64::INFINITY, false),
        (f64::NEG_INFINITY, false),
        (-f64::from_bits(1), false),
        (-0.0, true),
        (f64::from_bits(1), true),
        (0.5, true),
        (0.5 + f64::EPSILON / 2.0, false),
        (1.0, false),
    ];
    for (rate, ok) in rows {
        let got = Noise::new(rate, 1).map(|_| ());
        if ok {
            assert_eq!(got, Ok(()), "rate {rate:e}");
        } else {
            assert!(matches!(got, Err(NoiseError::Rate(r)) if r.to_bits() == rate.to_bits()), "rate {rate:e}: {got:?}");
        }
    }
    // Rate 0 (and −0) never flips; rate 0.5 flips only within the bits asked for.
    for rate in [0.0, -0.0] {
        let mut n = Noise::new(rate, 7).unwrap();
        assert!((0..1000).all(|k| n.corrupt(k as u16, 16) == k as u16));
        assert_eq!(n.flips(), 0);
    }
    let mut n = Noise::new(0.5, 7).unwrap();
    for (bits, mask) in [(0u32, 0u16), (1, 1), (8, 0xFF), (16, 0xFFFF), (17, 0xFFFF), (u32::MAX, 0xFFFF)] {
        for _ in 0..200 {
            let w = n.corrupt(0, bits);
            assert_eq!(w & !mask, 0, "{bits} bits: flipped {w:#06x}");
        }
    }
}

/// Hosts of 1 and 2 registers: time-outs at and one below their least, 0 and MAX; register
/// indices at `R` and `usize::MAX`; values 127 and 128. A refused set changes nothing.
#[test]
#[rustfmt::skip]
fn hosts_at_the_extremes() {
    let c = HostConfig::default();
    // (config, result)
    let rows: [(HostConfig, Result<(), ConfigError>); 6] = [
        (HostConfig { key_timeout_polls: MIN_KEY_TIMEOUT_POLLS, mot_stuck_polls: MIN_MOT_STUCK_POLLS }, Ok(())),
        (HostConfig { key_timeout_polls: MIN_KEY_TIMEOUT_POLLS - 1, ..c }, Err(ConfigError::KeyTimeout(MIN_KEY_TIMEOUT_POLLS - 1))),
        (HostConfig { key_timeout_polls: 0, ..c }, Err(ConfigError::KeyTimeout(0))),
        (HostConfig { mot_stuck_polls: MIN_MOT_STUCK_POLLS - 1, ..c }, Err(ConfigError::MotStuck(MIN_MOT_STUCK_POLLS - 1))),
        (HostConfig { mot_stuck_polls: 0, key_timeout_polls: 0 }, Err(ConfigError::KeyTimeout(0))),
        (HostConfig { key_timeout_polls: u16::MAX, mot_stuck_polls: u16::MAX }, Ok(())),
    ];
    for (config, want) in rows {
        assert_eq!(Host::<1>::new(config).map(|_| ()), want, "{config:?}");
    }
    fn sets<const R: usize>() {
        let mut host: Host<R> = Host::new(HostConfig::default()).unwrap();
        // (index, value, result)
        let rows: [(usize, u8, Result<(), RegisterError>); 6] = [
            (0, 127, Ok(())),
            (R - 1, 0, Ok(())),
            (0, 128, Err(RegisterError::Value(128))),
            (0, RESET, Err(RegisterError::Value(RESET))),
            (R, 1, Err(RegisterError::Index { index: R, registers: R })),
            (usize::MAX, 1, Err(RegisterError::Index { index: usize::MAX, registers: R })),
        ];
        for (index, value, want) in rows {
            let before = *host.registers();
            let r = host.set(index, value);
            assert_eq!(r, want, "Host<{R}>::set({index}, {value})");
            if r.is_err() {
                assert_eq!(*host.registers(), before, "a refused set changed the registers");
            }
        }
    }
    sets::<1>();
    sets::<2>();
}

/// Panels of 1 and 2 registers: a sequence of exactly `R` bytes is shown, `R − 1`, `R + 1`, a
/// damaged byte or a byte with bit 7 set is not; the key queue full hands the key back.
#[test]
#[rustfmt::skip]
fn panels_at_the_extremes() {
    fn sequences<const R: usize>() {
        let ok = |b: u8| Ok::<u8, LineError>(b);
        // (what, bytes after a first reset, registers shown after, shown, discarded)
        let full: Vec<Result<u8, LineError>> = (0..R).map(|k| ok(127 - k as u8)).collect();
        let shown: [u8; R] = core::array::from_fn(|k| 127 - k as u8);
        let rows: Vec<(&str, Vec<Result<u8, LineError>>, [u8; R], u64, u64)> = vec![
            ("R bytes", full.clone(), shown, 1, 0),
            // Two reset bytes in a row (R = 1) are neither shown nor discarded: 1 to R − 1 bytes are.
            ("R - 1 bytes", full[..R - 1].to_vec(), [0; R], 0, u64::from(R > 1)),
            ("R + 1 bytes", [full.clone(), vec![ok(5)]].concat(), [0; R], 0, 1),
            ("a framing error", [vec![Err(LineError::Framing)], full[1..].to_vec()].concat(), [0; R], 0, 1),
            ("a byte with bit 7 set", [vec![ok(0x80)], full[1..].to_vec()].concat(), [0; R], 0, 1),
        ];
        for (what, bytes, registers, n_shown, n_discarded) in rows {
            let mut panel: Panel<R> = Panel::new();
            panel.receive(ok(RESET));
            for b in bytes {
                panel.receive(b);
            }
            panel.receive(ok(RESET));
            assert_eq!(*panel.registers(), registers, "Panel<{R}> {what}");
            assert_eq!((panel.stats().shown, panel.stats().discarded), (n_shown, n_discarded), "Panel<{R}> {what}");
        }
        // Bytes before the first reset byte are ignored.
        let mut panel: Panel<R> = Panel::new();
        panel.receive(ok(5));
        assert_eq!((*panel.registers(), panel.stats().overruns), ([0; R], 1));
    }
    sequences::<1>();
    sequences::<2>();
    // The key queue: KEY_QUEUE keys, then the next is handed back; any byte is a key.
    let mut panel: Panel<1> = Panel::new();
    for k in 0..KEY_QUEUE {
        assert_eq!(panel.press([0, 0x7F, 0x80, 0xFF][k % 4]), Ok(()));
    }
    assert_eq!(panel.press(0x41), Err(PanelError::QueueFull(0x41)));
    assert_eq!(panel.keys_waiting(), KEY_QUEUE);
    assert_eq!(panel.set_san(true), Some(0));
}

fn command(
    crate_address: u8,
    station: u8,
    subaddress: u8,
    function: u8,
    data: Option<u32>,
) -> Message {
    Message::Command {
        crate_address,
        station,
        subaddress,
        function,
        data,
    }
}

/// `Message::validate` and `encode` with every field at its limit and one past; buffers of 0
/// and one byte short.
#[test]
#[rustfmt::skip]
fn messages_at_the_extremes() {
    let reply = |crate_address, data| Message::Reply { crate_address, status: Status::default(), data };
    let demand = |crate_address, sgl| Message::Demand { crate_address, sgl };
    let rows: Vec<(&str, Message, Result<(), EncodeError>)> = vec![
        ("command, every field at its top", command(63, 31, 15, 23, Some(0xFF_FFFF)), Ok(())),
        ("command, every field 0", command(0, 0, 0, 0, None), Ok(())),
        ("crate 64", command(64, 0, 0, 0, None), Err(EncodeError::CrateAddress(64))),
        ("crate 255", command(255, 0, 0, 0, None), Err(EncodeError::CrateAddress(255))),
        ("station 32", command(1, 32, 0, 0, None), Err(EncodeError::Station(32))),
        ("subaddress 16", command(1, 0, 16, 0, None), Err(EncodeError::Subaddress(16))),
        ("function 32", command(1, 0, 0, 32, None), Err(EncodeError::Function(32))),
        ("function 255", command(1, 0, 0, 255, None), Err(EncodeError::Function(255))),
        ("data 2^24", command(1, 0, 0, 16, Some(1 << 24)), Err(EncodeError::Data(1 << 24))),
        ("data u32::MAX", command(1, 0, 0, 16, Some(u32::MAX)), Err(EncodeError::Data(u32::MAX))),
        ("write without data", command(1, 0, 0, 16, None), Err(EncodeError::DataPresence { function: 16, has_data: false })),
        ("read with data", command(1, 0, 0, 0, Some(0)), Err(EncodeError::DataPresence { function: 0, has_data: true })),
        ("F24 with data", command(1, 0, 0, 24, Some(0)), Err(EncodeError::DataPresence { function: 24, has_data: true })),
        ("reply from crate 0", reply(0, None), Err(EncodeError::NotACrate(0))),
        ("reply from crate 63", reply(63, None), Err(EncodeError::NotACrate(63))),
        ("reply from crate 62, data 2^24 - 1", reply(62, Some(0xFF_FFFF)), Ok(())),
        ("reply data 2^24", reply(1, Some(1 << 24)), Err(EncodeError::Data(1 << 24))),
        ("demand SGL 0", demand(1, 0), Err(EncodeError::SglZero)),
        ("demand SGL 31", demand(62, 31), Ok(())),
        ("demand SGL 32", demand(1, 32), Err(EncodeError::Sgl(32))),
        ("demand from crate 63", demand(63, 1), Err(EncodeError::NotACrate(63))),
    ];
    for (what, message, want) in rows {
        assert_eq!(message.validate(), want, "validate {what}");
        let mut buf = [0x77u8; 16];
        let r = message.encode(&mut buf);
        assert_eq!(r.map(|_| ()), want, "encode {what}");
        if want.is_err() {
            assert!(buf.iter().all(|&b| b == 0x77), "a refused encode wrote: {what}");
        } else {
            let n = message.encoded_len();
            assert_eq!(r, Ok(n));
            assert!(n <= MAX_MESSAGE, "{what}: {n} bytes");
            // The buffer one byte short is refused and left alone; exactly long enough works.
            let mut short = vec![0x77u8; n - 1];
            assert_eq!(message.encode(&mut short), Err(EncodeError::BufferTooShort { needed: n }), "{what}");
            assert!(short.iter().all(|&b| b == 0x77));
            let mut exact = vec![0u8; n];
            assert_eq!(message.encode(&mut exact), Ok(n));
        }
    }
    assert_eq!(command(1, 0, 0, 0, None).encode(&mut []), Err(EncodeError::BufferTooShort { needed: command(1, 0, 0, 0, None).encoded_len() }));
}

/// `decode` of byte sequences of 0, 1, the longest, one longer, and with each byte of a good
/// message damaged to 0x00 and 0xFF: an error naming the rule, never a message.
#[test]
#[rustfmt::skip]
fn decode_at_the_extremes() {
    let rows: Vec<(&str, Vec<u8>, Result<Message, DecodeError>)> = vec![
        ("empty", vec![], Err(DecodeError::TooShort { len: 0 })),
        ("one byte", vec![highway::END], Err(DecodeError::TooShort { len: 1 })),
        ("one byte longer than the longest", vec![highway::SPACE; MAX_DECODE + 1], Err(DecodeError::TooLong { len: MAX_DECODE + 1 })),
    ];
    for (what, bytes, want) in rows {
        assert_eq!(highway::decode(&bytes), want, "{what}");
    }
    assert!(highway::decode(&[0xFF; MAX_DECODE]).is_err());
    for message in [command(63, 31, 15, 23, Some(0xFF_FFFF)), command(1, 2, 3, 0, None), Message::Reply { crate_address: 62, status: Status::default(), data: Some(0xABCDEF) }, Message::Demand { crate_address: 1, sgl: 31 }] {
        let mut buf = [0u8; MAX_MESSAGE];
        let n = message.encode(&mut buf).unwrap();
        assert_eq!(highway::decode(&buf[..n]), Ok(message));
        for k in 0..n {
            for bad in [0x00, 0xFF, buf[k] ^ 1, buf[k] ^ 0x80] {
                if bad == buf[k] {
                    continue;
                }
                let mut damaged = buf;
                damaged[k] = bad;
                assert!(highway::decode(&damaged[..n]).is_err(), "{message:?}: byte {k} as {bad:#04x} decoded");
            }
            assert!(highway::decode(&buf[..k]).is_err(), "{message:?}: cut at {k}");
        }
    }
}

/// Drivers with windows of 1 and 2: time-outs at and one below the least; submits of a reply,
/// of bad fields, to crates 0 and 63, to a busy crate and to a full window. A refused submit
/// queues nothing.
#[test]
#[rustfmt::skip]
fn drivers_at_the_extremes() {
    let config = DriverConfig::for_loop(1);
    let least = config.least_timeout();
    assert_eq!(Driver::<1>::new(DriverConfig { timeout: least, ..config }).map(|_| ()), Ok(()));
    assert_eq!(Driver::<1>::new(DriverConfig { timeout: least - 1, ..config }).map(|_| ()), Err(DriverError::TimeoutTooShort { timeout: least - 1, least }));
    assert_eq!(Driver::<1>::new(DriverConfig { timeout: 0, ..config }).map(|_| ()), Err(DriverError::TimeoutTooShort { timeout: 0, least }));
    assert_eq!(Driver::<1>::new(DriverConfig { timeout: u32::MAX, retries: u8::MAX, gap: u8::MAX }).map(|_| ()), Ok(()));
    let big_gap = DriverConfig { gap: u8::MAX, ..config };
    assert_eq!(Driver::<1>::new(DriverConfig { timeout: big_gap.least_timeout(), ..big_gap }).map(|_| ()), Ok(()));
    // for_loop at 0, 1, 62, 63 and 255 controllers: none counts as 1, more than 62 as 62.
    assert_eq!(DriverConfig::for_loop(0), DriverConfig::for_loop(1));
    assert_eq!(DriverConfig::for_loop(255), DriverConfig::for_loop(62));
    fn window<const W: usize>() {
        let mut d: Driver<W> = Driver::new(DriverConfig::for_loop(62)).unwrap();
        // (what, message, result)
        let rows: Vec<(&str, Message, Result<(), DriverError>)> = vec![
            ("a reply", Message::Reply { crate_address: 1, status: Status::default(), data: None }, Err(DriverError::NotACommand)),
            ("a demand", Message::Demand { crate_address: 1, sgl: 1 }, Err(DriverError::NotACommand)),
            ("crate 0", command(0, 0, 0, 0, None), Err(DriverError::NoReplyPossible(0))),
            ("crate 63", command(63, 0, 0, 0, None), Err(DriverError::NoReplyPossible(63))),
            ("crate 64", command(64, 0, 0, 0, None), Err(DriverError::Encode(EncodeError::CrateAddress(64)))),
            ("write without data", command(1, 0, 0, 16, None), Err(DriverError::Encode(EncodeError::DataPresence { function: 16, has_data: false }))),
            ("crate 1", command(1, 0, 0, 0, None), Ok(())),
            ("crate 1 again: busy", command(1, 0, 0, 0, None), Err(DriverError::CrateBusy(1))),
            ("crate 62", command(62, 0, 0, 0, None), if W >= 2 { Ok(()) } else { Err(DriverError::WindowFull) }),
            ("crate 2: window full", command(2, 0, 0, 0, None), Err(DriverError::WindowFull)),
        ];
        for (what, message, want) in rows {
            let before = d.outstanding();
            let r = d.submit(message).map(|_| ());
            assert_eq!(r, want, "Driver<{W}> {what}");
            assert_eq!(d.outstanding(), before + usize::from(r.is_ok()), "Driver<{W}> {what}");
        }
        assert!(d.busy(1) && !d.busy(0) && !d.busy(63) && !d.busy(255));
    }
    window::<1>();
    window::<2>();
}

struct Crate;

impl highway::Dataway for Crate {
    fn cycle(
        &mut self,
        _station: u8,
        _subaddress: u8,
        _function: u8,
        _write: Option<u32>,
    ) -> highway::Cycle {
        highway::Cycle {
            x: true,
            q: true,
            read: 0,
        }
    }
}

/// Crate controllers: addresses 0, 1, 62, 63, 255; demand repeats 0 and MAX; every input byte
/// clocked into a fresh controller passes through or is answered, never lost silently: a
/// controller with nothing to say passes its input on.
#[test]
#[rustfmt::skip]
fn controllers_at_the_extremes() {
    let c = |address, demand_repeat| ControllerConfig { address, demand_repeat };
    let rows: [(ControllerConfig, Result<(), ControllerConfigError>); 6] = [
        (c(0, 0), Err(ControllerConfigError::Address(0))),
        (c(1, 0), Ok(())),
        (c(62, u32::MAX), Ok(())),
        (c(63, 0), Err(ControllerConfigError::Address(63))),
        (c(64, 0), Err(ControllerConfigError::Address(64))),
        (c(255, 0), Err(ControllerConfigError::Address(255))),
    ];
    for (config, want) in rows {
        assert_eq!(Controller::new(config).map(|_| ()), want, "{config:?}");
    }
    // Every byte into an idle controller: a WAIT, a SPACE or the byte itself comes out, and no
    // command runs from one byte.
    for byte in 0..=u8::MAX {
        let mut ctl = Controller::new(c(1, 0)).unwrap();
        let out = ctl.clock(byte, &mut Crate);
        assert!(out == byte || out == highway::WAIT || out == highway::SPACE, "{byte:#04x} -> {out:#04x}");
        assert_eq!(ctl.stats().executed, 0, "{byte:#04x}");
    }
}

/// A slice port that takes one write: a second (`write_byte` retrying a port error that is not
/// `Interrupted`) fails the test instead of looping for ever.
#[cfg(feature = "embedded-io")]
struct Once<'a> {
    port: &'a mut [u8],
    writes: u32,
}

#[cfg(feature = "embedded-io")]
impl embedded_io::ErrorType for Once<'_> {
    type Error = embedded_io::SliceWriteError;
}

#[cfg(feature = "embedded-io")]
impl embedded_io::Write for Once<'_> {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.writes += 1;
        assert!(self.writes <= 1, "write_byte retried a port error");
        embedded_io::Write::write(&mut self.port, buf)
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// The byte-stream adapters at the ends of a stream: a read from an ended stream is `Closed`, a
/// write into a full one is the port's error, tried once; nothing is read or written past them.
#[cfg(feature = "embedded-io")]
#[test]
fn io_at_the_ends_of_a_stream() {
    use regler_panel_link::io::{IoError, read_byte, write_byte};
    let mut empty: &[u8] = &[];
    assert_eq!(read_byte(&mut empty), Err(IoError::Closed));
    let mut one: &[u8] = &[0xFF];
    assert_eq!(read_byte(&mut one), Ok(0xFF));
    assert_eq!(read_byte(&mut one), Err(IoError::Closed));
    let mut none: [u8; 0] = [];
    let mut port = Once {
        port: &mut none,
        writes: 0,
    };
    assert_eq!(
        write_byte(&mut port, 1),
        Err(IoError::Port(embedded_io::SliceWriteError::Full))
    );
    assert_eq!(port.writes, 1);
    let mut room = [0u8; 1];
    let mut port: &mut [u8] = &mut room;
    assert_eq!(write_byte(&mut port, 0xFF), Ok(()));
    assert_eq!(room, [0xFF]);
}
