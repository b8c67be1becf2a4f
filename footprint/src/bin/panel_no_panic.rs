//! A probe, not a measurement: firmware whose panic handler calls a function that is declared
//! but defined nowhere, so it links only if no panic path is left in what it calls — all of
//! `regler-panel-link`: `line`
//! (`Framing` of every parity, `encode`/`decode` of run-time bytes and frames, `BitReceiver` fed
//! run-time bits, `Noise` with run-time rates, NaN and ±∞ among them), `panel` (`Host` and
//! `Panel` of 1, 2 and 46 registers: `set` at run-time indices and values, `next_byte`,
//! `poll_mot`, `receive` of run-time bytes and line errors, `press`, `set_san`, `tick_20ms`, the
//! read-outs) and `highway` (`Message` built from run-time fields, `validate`, `encode` into
//! buffers of run-time length, `decode` of run-time bytes, the sums and byte helpers, `Status`,
//! `Controller::new`/`clock` over a dataway, `Driver::new`/`submit`/`clock`), the `io` adapters
//! (`read_byte`, `write_byte`, `clock_controller`, `clock_driver`, `host_transmit`,
//! `panel_receive`) over a port whose answers are read at run time (bytes, 0 = closed, short
//! writes, interrupted, timed-out and other errors, a failing flush), every error's
//! `Display` but `NoiseError`'s, which prints an `f64` through core's float formatting: that keeps
//! panic paths of core's own, so no probe can link with it). The measuring build (feature `measure`) runs the calls under QEMU with an
//! ordinary panic handler.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, at, finish, keep, shown};
use regler_panel_link::highway::{
    self, Controller, ControllerConfig, Cycle, Dataway, Driver, DriverConfig, DriverEvent,
    MAX_DECODE, MAX_MESSAGE, Message, Status,
};
use regler_panel_link::io::{self, ControllerLink, DriverLink, Transmit};
use regler_panel_link::line::{BitReceiver, Framing, LineError, Noise, Parity};
use regler_panel_link::panel::{Host, HostConfig, HostEvent, Panel};

/// Bytes as a line would deliver them (any `u8`).
static BYTES: [u8; 16] = [
    0x00, 0x01, 0x7F, 0x80, 0xFF, 0xBF, 0xE0, 0x40, 0x3F, 0xC1, 0x55, 0xAA, 0x02, 0x10, 0x20, 0xFE,
];
/// Words as a program would give them (counts, addresses, limits; 0 and `u32::MAX` among them).
static WORDS: [u32; 8] = [0, 1, 2, 15, 63, 1000, 0x00FF_FFFF, u32::MAX];
/// Noise rates as a test harness would set them.
static RATES: [f64; 5] = [0.0, 1e-3, 1.0, f64::NAN, f64::INFINITY];

fn byte(i: usize) -> u8 {
    at(&BYTES, i)
}

fn word(i: usize) -> u32 {
    at(&WORDS, i)
}

/// A crate whose modules answer from a table indexed by the station.
struct Modules([u32; 32]);

impl Dataway for Modules {
    fn cycle(&mut self, station: u8, _a: u8, function: u8, write: Option<u32>) -> Cycle {
        let reg = &mut self.0[usize::from(station & 31)];
        if let Some(w) = write {
            *reg = w;
        }
        Cycle {
            read: *reg,
            x: function != 31,
            q: function < 8,
        }
    }

    fn graded_lam(&mut self) -> u8 {
        byte(self.0[0] as usize) & 31
    }
}

fn line() -> u32 {
    let mut answer = 0u32;
    for parity in [Parity::None, Parity::Even, Parity::Odd] {
        let framing = Framing::new(parity);
        answer ^= framing.bits();
        let mut receiver = BitReceiver::new(framing);
        for i in 0..64usize {
            let frame = framing.encode(byte(i));
            let noisy = frame ^ (u16::from(byte(i / 3)) << (i % 16));
            match framing.decode(noisy) {
                Ok(b) => answer ^= u32::from(b),
                Err(e) => answer ^= shown(&e),
            }
            for k in 0..12 {
                if let Some(got) = receiver.bit(byte(i + k) & 1 != 0) {
                    answer ^= got.map_or_else(|e| shown(&e), u32::from);
                }
            }
            answer ^= u32::from(receiver.busy());
        }
    }
    for (i, _) in RATES.iter().enumerate() {
        match Noise::new(at(&RATES, i), u64::from(word(i))) {
            // Not its `Display`: it prints the rate, an `f64`, and core's float formatting keeps
            // panic paths of its own (`core::num::flt2dec`'s assertions), whatever the crate does.
            Err(_) => answer ^= 1,
            Ok(mut noise) => {
                for k in 0..16usize {
                    answer ^= noise.next_u64() as u32;
                    answer ^= u32::from(noise.corrupt(u16::from(byte(k)), word(k)));
                    answer ^= u32::from(noise.corrupt_byte(byte(k)));
                }
                answer ^= noise.flips() as u32;
            }
        }
    }
    answer
}

fn received(i: usize) -> Result<u8, LineError> {
    match byte(i) {
        0x3F => Err(LineError::Framing),
        0x55 => Err(LineError::Parity),
        b => Ok(b),
    }
}

fn host_and_panel<const R: usize>(seed: usize) -> u32 {
    let mut answer = 0u32;
    let config = HostConfig {
        key_timeout_polls: word(seed) as u16,
        mot_stuck_polls: word(seed + 3) as u16,
    };
    let mut host = match Host::<R>::new(config) {
        Ok(host) => host,
        Err(e) => {
            answer ^= shown(&e);
            match Host::<R>::new(HostConfig::default()) {
                Ok(host) => host,
                Err(e) => return answer ^ shown(&e),
            }
        }
    };
    let mut panel = Panel::<R>::new();
    for i in 0..400usize {
        if let Err(e) = host.set(word(i) as usize ^ i, byte(i + seed)) {
            answer ^= shown(&e);
        }
        if let Some(b) = host.next_byte() {
            let b = if byte(i) == 0x10 { b ^ 1 } else { b };
            panel.receive(if byte(i) == 0x3F {
                Err(LineError::Framing)
            } else {
                Ok(b)
            });
        }
        panel.receive(received(i * 7 + seed));
        if let Err(e) = panel.press(byte(i * 5)) {
            answer ^= shown(&e);
        }
        answer ^= panel.keys_waiting() as u32;
        if let Some(b) = panel.set_san(byte(i) & 2 != 0) {
            answer ^= u32::from(b);
        }
        if let Some(b) = panel.tick_20ms()
            && let Some(event) = host.receive(Ok(b))
        {
            answer ^= match event {
                HostEvent::Key(k) => u32::from(k),
                _ => 1,
            };
        }
        if let Some(event) = host.poll_mot(panel.mot() ^ (byte(i) == 0x20)) {
            answer ^= u32::from(matches!(event, HostEvent::Key(_)));
        }
        if let Some(event) = host.receive(received(i)) {
            answer ^= u32::from(matches!(event, HostEvent::Key(_)));
        }
        answer ^= u32::from(host.san());
    }
    answer ^= host.registers().iter().map(|&r| u32::from(r)).sum::<u32>();
    answer ^= panel.registers().iter().map(|&r| u32::from(r)).sum::<u32>();
    let host_stats = *host.stats();
    let panel_stats = *panel.stats();
    keep(core::hint::black_box(&host_stats as *const _ as u32));
    keep(core::hint::black_box(&panel_stats as *const _ as u32));
    answer
}

fn message(i: usize) -> Message {
    let f = byte(i) & 31;
    match byte(i + 1) % 4 {
        0 => Message::Command {
            crate_address: byte(i + 2),
            station: byte(i + 3),
            subaddress: byte(i + 4),
            function: f,
            data: if byte(i + 5) & 1 != 0 {
                Some(word(i))
            } else {
                None
            },
        },
        1 => Message::Reply {
            crate_address: byte(i + 2),
            status: Status::from_bits(byte(i + 3)),
            data: if byte(i + 5) & 1 != 0 {
                Some(word(i))
            } else {
                None
            },
        },
        _ => Message::Demand {
            crate_address: byte(i + 2),
            sgl: byte(i + 3),
        },
    }
}

fn highway_messages() -> u32 {
    let mut answer = 0u32;
    let mut out = [0u8; MAX_DECODE];
    let mut input = [0u8; MAX_DECODE];
    for i in 0..200usize {
        let m = message(i);
        answer ^= u32::from(m.crate_address()) ^ m.encoded_len() as u32;
        if let Err(e) = m.validate() {
            answer ^= shown(&e);
        }
        let len = (word(i) as usize).min(out.len()) ^ (i % 3);
        let len = len.min(out.len());
        match m.encode(&mut out[..len]) {
            Ok(n) => {
                answer ^= n as u32;
                match highway::decode(&out[..n.min(len)]) {
                    Ok(back) => answer ^= u32::from(back == m),
                    Err(e) => answer ^= shown(&e),
                }
            }
            Err(e) => answer ^= shown(&e),
        }
        for (k, b) in input.iter_mut().enumerate() {
            *b = byte(i.wrapping_mul(k + 1) ^ k);
        }
        let n = (word(i / 7) as usize ^ i) % (input.len() + 1);
        match highway::decode(&input[..n]) {
            Ok(back) => answer ^= u32::from(back.crate_address()),
            Err(e) => answer ^= shown(&e),
        }
        answer ^= u32::from(highway::column_sum(&input[..n]))
            ^ u32::from(highway::sum_byte(&input[..n]))
            ^ u32::from(highway::endsum_byte(&input[..n]));
        let b = byte(i);
        answer ^= u32::from(highway::with_parity(b))
            ^ u32::from(highway::row_parity_ok(b))
            ^ u32::from(highway::is_delimiter(b))
            ^ u32::from(highway::is_clean_delimiter(b))
            ^ u32::from(highway::is_write(b))
            ^ u32::from(highway::is_read(b))
            ^ highway::reply_len(b) as u32
            ^ highway::guard_len(b) as u32
            ^ highway::min_spaces(b) as u32
            ^ u32::from(Status::from_bits(b).bits());
        answer ^= u32::from_le_bytes(highway::data_bytes(word(i)));
    }
    answer
}

fn highway_machines<const W: usize>(seed: usize) -> u32 {
    let mut answer = 0u32;
    let mut modules = Modules([0; 32]);
    let controller = Controller::new(ControllerConfig {
        address: byte(seed),
        demand_repeat: word(seed),
    });
    let mut controller = match controller {
        Ok(c) => c,
        Err(e) => {
            answer ^= shown(&e);
            match Controller::new(ControllerConfig::default()) {
                Ok(c) => c,
                Err(e) => return answer ^ shown(&e),
            }
        }
    };
    let config = DriverConfig {
        timeout: word(seed + 1),
        retries: byte(seed + 2),
        gap: byte(seed + 3),
    };
    answer ^= config.least_timeout() ^ DriverConfig::for_loop(byte(seed)).timeout;
    let mut driver = match Driver::<W>::new(config) {
        Ok(d) => d,
        Err(e) => {
            answer ^= shown(&e);
            match Driver::<W>::new(DriverConfig::for_loop(1)) {
                Ok(d) => d,
                Err(e) => return answer ^ shown(&e),
            }
        }
    };
    let mut back = highway::WAIT;
    let mut buf = [0u8; MAX_MESSAGE];
    for i in 0..600usize {
        if i.is_multiple_of(40) {
            match driver.submit(message(i + seed)) {
                Ok(tag) => answer ^= tag,
                Err(e) => answer ^= shown(&e),
            }
        }
        let step = driver.clock(back ^ u8::from(byte(i) == 0x02));
        answer ^= u32::from(step.transmit);
        if let Some(event) = step.event {
            answer ^= match event {
                DriverEvent::Completed(c) => c.tag ^ c.data.unwrap_or(0),
                DriverEvent::Failed { tag, .. } => tag,
                DriverEvent::Demand { sgl, .. } => u32::from(sgl),
            };
        }
        back = controller.clock(step.transmit, &mut modules);
        // A byte from outside now and then: a message of its own or garbage.
        if byte(i) == 0xC1 {
            let n = message(i).encode(&mut buf).unwrap_or(0);
            for &b in buf.iter().take(n) {
                answer ^= u32::from(controller.clock(b, &mut modules));
            }
        }
        answer ^= driver.outstanding() as u32 ^ u32::from(driver.busy(byte(i)));
    }
    answer ^= controller.held() as u32 ^ controller.config().demand_repeat;
    let cs = *controller.stats();
    let ds = *driver.stats();
    keep(core::hint::black_box(&cs as *const _ as u32));
    keep(core::hint::black_box(&ds as *const _ as u32));
    answer
}

/// A serial port whose every answer is read at run time: a byte, end of stream (0 bytes), or an
/// error of any kind (interrupted ones are retried by the adapters, so the table has others).
struct Port(usize);

impl embedded_io::ErrorType for Port {
    type Error = embedded_io::ErrorKind;
}

impl Port {
    fn answer(&mut self) -> Result<usize, embedded_io::ErrorKind> {
        self.0 = self.0.wrapping_add(1);
        match byte(self.0.wrapping_mul(7)) {
            0x00 => Ok(0),
            0x7F => Err(embedded_io::ErrorKind::Interrupted),
            0x80 => Err(embedded_io::ErrorKind::TimedOut),
            0xFE => Err(embedded_io::ErrorKind::Other),
            b => Ok(usize::from(b)),
        }
    }
}

impl embedded_io::Read for Port {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, embedded_io::ErrorKind> {
        let n = self.answer()?.min(buf.len());
        for (k, b) in buf.iter_mut().take(n).enumerate() {
            *b = byte(self.0 ^ k);
        }
        Ok(n)
    }
}

impl embedded_io::Write for Port {
    fn write(&mut self, buf: &[u8]) -> Result<usize, embedded_io::ErrorKind> {
        let n = self.answer()?.min(buf.len());
        keep(buf.iter().take(n).map(|&b| u32::from(b)).sum());
        Ok(n)
    }
    fn flush(&mut self) -> Result<(), embedded_io::ErrorKind> {
        self.answer().map(|_| ())
    }
}

/// The `io` adapters over a port of run-time answers.
fn adapters<const R: usize, const W: usize>(seed: usize) -> u32 {
    let mut answer = 0u32;
    let mut port = Port(seed);
    let mut modules = Modules([0; 32]);
    let (Ok(mut controller), Ok(mut driver), Ok(mut host)) = (
        Controller::new(ControllerConfig::default()),
        Driver::<W>::new(DriverConfig::for_loop(1)),
        Host::<R>::new(HostConfig::default()),
    ) else {
        return 0;
    };
    let mut panel = Panel::<R>::new();
    let mut controller_link = ControllerLink::default();
    let mut driver_link = DriverLink::default();
    for i in 0..200usize {
        match io::read_byte(&mut port) {
            Ok(b) => answer ^= u32::from(b),
            Err(e) => answer ^= shown(&e),
        }
        if let Err(e) = io::write_byte(&mut port, byte(i)) {
            answer ^= shown(&e);
        }
        if let Err(e) = io::clock_controller(
            &mut port,
            &mut controller,
            &mut modules,
            &mut controller_link,
        ) {
            answer ^= shown(&e);
        }
        answer ^= controller_link.unsent().map_or(0, u32::from);
        if i.is_multiple_of(30) {
            let _ = driver.submit(message(i + seed));
        }
        match io::clock_driver(&mut port, &mut driver, &mut driver_link) {
            Ok(event) => answer ^= u32::from(event.is_some()),
            Err(e) => answer ^= shown(&e) ^ u32::from(e.event.is_some()),
        }
        answer ^= u32::from(driver_link.interrupted());
        match io::host_transmit(&mut port, &mut host) {
            Ok(Transmit::Sent) => answer ^= 1,
            Ok(_) => answer ^= 2,
            Err(e) => answer ^= shown(&e),
        }
        if let Err(e) = io::panel_receive(&mut port, &mut panel) {
            answer ^= shown(&e);
        }
    }
    answer
}

#[entry]
fn main() -> ! {
    let mut answer = line();
    answer ^= host_and_panel::<1>(0);
    answer ^= host_and_panel::<2>(1);
    answer ^= host_and_panel::<46>(2);
    answer ^= highway_messages();
    answer ^= highway_machines::<1>(0);
    answer ^= highway_machines::<4>(5);
    answer ^= adapters::<1, 1>(0);
    answer ^= adapters::<46, 4>(3);
    keep(answer);
    if MEASURING {
        finish();
    }
    loop {
        cortex_m::asm::nop();
    }
}

regler_footprint::no_panic_probe!();
