//! Driving the machines from a real byte stream (feature `embedded-io`).
//!
//! The machines stay sans-IO; these functions are the few lines a firmware writes around them
//! for a UART that implements [`embedded_io::Read`] and [`embedded_io::Write`] (every HAL's
//! blocking UART does; on a PC, `embedded-io-adapters` wraps any `std::io` port such as the
//! `serialport` crate's). Each call is one byte clock.
//!
//! These functions never lose or repeat a byte themselves: a byte the port did not take is kept
//! ([`ControllerLink`], [`DriverLink`]) and written by the next call before the machine is
//! clocked again. A byte lost or duplicated on the line itself (a UART overrun, a receiver that
//! missed a start bit) is a fault the highway's checks do not always catch: a write whose data
//! byte `0x3F` is lost has the SPACE that follows slide into its SUM's place, the column sum
//! passes, and the crate runs the write with shifted data (see the [`highway`](crate::highway)
//! module docs).
//!
//! ```
//! use regler_panel_link::highway::{Controller, ControllerConfig, Cycle, Dataway};
//! use regler_panel_link::io::{clock_controller, ControllerLink};
//!
//! struct Loopback { rx: Vec<u8>, tx: Vec<u8> }
//! impl embedded_io::ErrorType for Loopback { type Error = core::convert::Infallible; }
//! impl embedded_io::Read for Loopback {
//!     fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
//!         let n = buf.len().min(self.rx.len());
//!         buf[..n].copy_from_slice(&self.rx[..n]);
//!         self.rx.drain(..n);
//!         Ok(n)
//!     }
//! }
//! impl embedded_io::Write for Loopback {
//!     fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> { self.tx.extend_from_slice(buf); Ok(buf.len()) }
//!     fn flush(&mut self) -> Result<(), Self::Error> { Ok(()) }
//! }
//! struct Empty;
//! impl Dataway for Empty {
//!     fn cycle(&mut self, _: u8, _: u8, _: u8, _: Option<u32>) -> Cycle { Cycle::default() }
//! }
//!
//! let mut port = Loopback { rx: vec![0x02, 0xE0], tx: Vec::new() };
//! let mut controller = Controller::new(ControllerConfig { address: 2, ..Default::default() })?;
//! let mut link = ControllerLink::default();
//! clock_controller(&mut port, &mut controller, &mut Empty, &mut link)?;
//! clock_controller(&mut port, &mut controller, &mut Empty, &mut link)?;
//! assert_eq!(port.tx, [0xE0, 0x02]); // a header for crate 2, passed on one byte late
//! assert!(clock_controller(&mut port, &mut controller, &mut Empty, &mut link).is_err()); // stream closed
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```

use core::fmt;

use embedded_io::{Read, Write};

use crate::highway::{Controller, Dataway, Driver, DriverEvent, WAIT};
use crate::line::LineError;
use crate::panel::{Host, Panel};

/// What went wrong on the port.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum IoError<E> {
    /// The port reported an error.
    Port(E),
    /// The stream ended (a read returned 0 bytes, or a write took none).
    Closed,
}

impl<E: fmt::Debug> fmt::Display for IoError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Port(e) => write!(f, "serial port error: {e:?}"),
            Self::Closed => f.write_str("serial stream closed"),
        }
    }
}

impl<E: fmt::Debug> core::error::Error for IoError<E> {}

/// Reads exactly one byte (blocking as the port does).
///
/// # Errors
/// The port's error, or [`IoError::Closed`] at the end of the stream.
pub fn read_byte<P: Read>(port: &mut P) -> Result<u8, IoError<P::Error>> {
    let mut byte = [0u8; 1];
    loop {
        match port.read(&mut byte) {
            Ok(0) => return Err(IoError::Closed),
            Ok(_) => return Ok(byte[0]),
            Err(e) => {
                use embedded_io::{Error as _, ErrorKind};
                if e.kind() != ErrorKind::Interrupted {
                    return Err(IoError::Port(e));
                }
            }
        }
    }
}

/// Writes one byte.
///
/// # Errors
/// The port's error, or [`IoError::Closed`] when the port takes nothing.
pub fn write_byte<P: Write>(port: &mut P, byte: u8) -> Result<(), IoError<P::Error>> {
    loop {
        match port.write(&[byte]) {
            Ok(0) => return Err(IoError::Closed),
            Ok(_) => return Ok(()),
            Err(e) => {
                use embedded_io::{Error as _, ErrorKind};
                if e.kind() != ErrorKind::Interrupted {
                    return Err(IoError::Port(e));
                }
            }
        }
    }
}

/// What a controller's port still owes the loop between calls of [`clock_controller`]: the byte
/// the controller gave at its last clock, when the port did not take it.
///
/// Start with [`ControllerLink::default`] and pass the same value to every call.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ControllerLink {
    unsent: Option<u8>,
}

impl ControllerLink {
    /// The byte the controller gave that has not gone out yet (after a failed write).
    #[must_use]
    pub const fn unsent(&self) -> Option<u8> {
        self.unsent
    }
}

/// One byte clock of a crate controller: read the byte from upstream, write the byte for
/// downstream.
///
/// **It never loses or repeats a byte.** When the write fails, the byte stays in `link` and the
/// next call writes it first; the controller is not clocked again, nor a byte read, before it went
/// out. When the read fails, nothing was taken and the controller was not clocked. So a port that
/// fails now and then only delays the stream; the application carries on calling.
///
/// # Errors
/// See [`read_byte`] and [`write_byte`].
pub fn clock_controller<P: Read + Write, D: Dataway + ?Sized>(
    port: &mut P,
    controller: &mut Controller,
    dataway: &mut D,
    link: &mut ControllerLink,
) -> Result<(), IoError<P::Error>> {
    if let Some(byte) = link.unsent {
        write_byte(port, byte)?;
        link.unsent = None;
    }
    let input = read_byte(port)?;
    let out = controller.clock(input, dataway);
    link.unsent = Some(out);
    write_byte(port, out)?;
    link.unsent = None;
    Ok(())
}

/// A port error in [`clock_driver`], with the event the driver gave at that clock.
///
/// The driver has already taken its byte clock when the port fails — a command may have
/// completed, its dataway cycle run — so the event is handed back here, never lost. The byte it
/// meant to send, or the one it waits for, is not lost either: [`DriverLink`] keeps where the
/// clock stopped, and the next call finishes it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct DriverClockError<E> {
    /// What went wrong on the port.
    pub error: IoError<E>,
    /// The event of this clock, if it produced one.
    pub event: Option<DriverEvent>,
}

impl<E: fmt::Debug> fmt::Display for DriverClockError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.error, f)?;
        if self.event.is_some() {
            f.write_str(" (the driver's event of that clock is handed back with the error)")?;
        }
        Ok(())
    }
}

impl<E: fmt::Debug> core::error::Error for DriverClockError<E> {}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum DriverPhase {
    /// The input of the next clock is here.
    Clock(u8),
    /// The clock is taken; its byte is still to be written.
    Write(u8),
    /// Written; the port is still to be flushed.
    Flush,
    /// Flushed; the byte coming back is still to be read.
    Read,
}

/// Where [`clock_driver`] stands between calls: the byte that came back last clock, or the part
/// of the last clock a port error interrupted.
///
/// Start with [`DriverLink::default`] (an idle line: WAIT) and pass the same value to every call.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DriverLink {
    phase: DriverPhase,
}

impl Default for DriverLink {
    fn default() -> Self {
        Self {
            phase: DriverPhase::Clock(WAIT),
        }
    }
}

impl DriverLink {
    /// True when a port error interrupted the last clock and the next call finishes it.
    #[must_use]
    pub const fn interrupted(&self) -> bool {
        !matches!(self.phase, DriverPhase::Clock(_))
    }
}

/// One byte clock of the driver in lock-step with the loop: the driver takes the byte that came
/// back last clock, its byte is written and flushed, and the byte that comes back is read.
///
/// **It never loses or repeats a byte.** When the port fails, `link` keeps where the clock
/// stopped, and the next call finishes that clock — writes the byte not written, flushes, reads
/// the byte not read — and returns `Ok(None)` without clocking the driver; the call after it
/// clocks it again. The driver is never clocked before the byte it gave went out and the byte
/// that came back was read, and never given a received byte twice. So a port that fails now and
/// then only delays the stream; the application carries on calling.
///
/// # Errors
/// See [`read_byte`] and [`write_byte`]; the error carries the event the driver gave at this
/// clock ([`DriverClockError::event`]), so nothing the driver accepted is lost.
pub fn clock_driver<P: Read + Write, const W: usize>(
    port: &mut P,
    driver: &mut Driver<W>,
    link: &mut DriverLink,
) -> Result<Option<DriverEvent>, DriverClockError<P::Error>> {
    let mut event = None;
    if let DriverPhase::Clock(input) = link.phase {
        let step = driver.clock(input);
        event = step.event;
        link.phase = DriverPhase::Write(step.transmit);
    } else {
        // Finish the interrupted clock only.
    }
    let with_event = |error| DriverClockError { error, event };
    if let DriverPhase::Write(byte) = link.phase {
        write_byte(port, byte).map_err(with_event)?;
        link.phase = DriverPhase::Flush;
    }
    if link.phase == DriverPhase::Flush {
        port.flush().map_err(|e| with_event(IoError::Port(e)))?;
        link.phase = DriverPhase::Read;
    }
    if link.phase == DriverPhase::Read {
        link.phase = DriverPhase::Clock(read_byte(port).map_err(with_event)?);
    }
    Ok(event)
}

/// What [`host_transmit`] did with this byte time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[must_use = "on `LeaveIdle` the line must stay idle for one byte time before the next call"]
pub enum Transmit {
    /// A byte was written: it takes the line for one byte time.
    Sent,
    /// Nothing was written (the idle byte time after a reset byte, or no sequence under way):
    /// **the caller must leave the line idle for one byte time** (11 bit times: 2.3 ms at 4 800
    /// baud) before it calls [`host_transmit`] again. Without that wait the idle byte time that
    /// lets a receiver that lost character sync find the start bits again does not exist.
    LeaveIdle,
}

/// One byte time of the host's transmitter: writes the next sequence byte, if the host is
/// sending.
///
/// Call it **once per byte time**, whatever it returns (a timer at the byte rate, or the UART's
/// transmit-ready with a one-byte-time wait after [`Transmit::LeaveIdle`]). A blocking UART
/// write returns as soon as the byte is in the transmitter, so a loop that calls this again at
/// once after `LeaveIdle` sends the next byte with no idle line in between. This function cannot
/// wait itself: `embedded-io` has no clock; the wait is the caller's (a HAL delay, a timer).
///
/// # Errors
/// See [`write_byte`].
pub fn host_transmit<P: Write, const R: usize>(
    port: &mut P,
    host: &mut Host<R>,
) -> Result<Transmit, IoError<P::Error>> {
    match host.next_byte() {
        Some(byte) => write_byte(port, byte).map(|()| Transmit::Sent),
        None => Ok(Transmit::LeaveIdle),
    }
}

/// Reads one byte into the panel.
///
/// A port error other than a time-out (a UART's framing, parity or overrun error, a broken
/// port) means the byte slot was damaged: the panel is told so, as
/// [`LineError::Framing`] (it drops the sequence the slot falls in, as for a damaged byte on
/// the line), and the error is returned too. A time-out
/// ([`embedded_io::ErrorKind::TimedOut`]) means no byte arrived (a quiet line, the idle byte
/// time): the panel is not told. [`IoError::Closed`] leaves the panel alone as well.
///
/// # Errors
/// See [`read_byte`].
pub fn panel_receive<P: Read, const R: usize>(
    port: &mut P,
    panel: &mut Panel<R>,
) -> Result<(), IoError<P::Error>> {
    match read_byte(port) {
        Ok(byte) => {
            panel.receive(Ok(byte));
            Ok(())
        }
        Err(IoError::Port(e)) => {
            use embedded_io::{Error as _, ErrorKind};
            if e.kind() != ErrorKind::TimedOut {
                panel.receive(Err(LineError::Framing));
            }
            Err(IoError::Port(e))
        }
        Err(e) => Err(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::highway::{
        Controller, ControllerConfig, Cycle, Dataway, DriverConfig, Message, Status,
    };

    /// A port in a loop with one crate controller: what the driver writes goes through the
    /// controller and comes back on the next read. Its writes fail from clock `fail_from` on.
    struct LoopPort {
        controller: Controller,
        back: u8,
        writes: u32,
        fail_from: u32,
    }

    struct Register;
    impl Dataway for Register {
        fn cycle(&mut self, _: u8, _: u8, _: u8, _: Option<u32>) -> Cycle {
            Cycle {
                read: 0x12_3456,
                x: true,
                q: true,
            }
        }
    }

    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    struct Broken;
    impl fmt::Display for Broken {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str("broken")
        }
    }
    impl core::error::Error for Broken {}
    impl embedded_io::Error for Broken {
        fn kind(&self) -> embedded_io::ErrorKind {
            embedded_io::ErrorKind::Other
        }
    }
    impl embedded_io::ErrorType for LoopPort {
        type Error = Broken;
    }
    impl Read for LoopPort {
        fn read(&mut self, buf: &mut [u8]) -> Result<usize, Broken> {
            match buf.first_mut() {
                Some(b) => {
                    *b = self.back;
                    Ok(1)
                }
                None => Ok(0),
            }
        }
    }
    impl Write for LoopPort {
        fn write(&mut self, buf: &[u8]) -> Result<usize, Broken> {
            self.writes = self.writes.saturating_add(1);
            if self.writes > self.fail_from {
                // The application stops at the first error: a second failing write is a port
                // error retried (a test that fails rather than hangs).
                assert!(
                    self.writes <= self.fail_from.saturating_add(1),
                    "write_byte retried a port error"
                );
                return Err(Broken);
            }
            if let Some(&b) = buf.first() {
                self.back = self.controller.clock(b, &mut Register);
            }
            Ok(buf.len())
        }
        fn flush(&mut self) -> Result<(), Broken> {
            Ok(())
        }
    }

    /// Item 3 of issue 19: for every clock at which the port's write can fail — in particular
    /// the one that produces `Completed` — the event the driver gave is returned, with the error
    /// or without it: over the whole run, the command completes exactly once.
    #[test]
    fn no_driver_event_is_lost_when_the_port_fails() {
        let read = Message::Command {
            crate_address: 4,
            station: 1,
            subaddress: 0,
            function: 0,
            data: None,
        };
        let run = |fail_from: u32| {
            let mut port = LoopPort {
                controller: Controller::new(ControllerConfig {
                    address: 4,
                    demand_repeat: 0,
                })
                .unwrap(),
                back: crate::highway::WAIT,
                writes: 0,
                fail_from,
            };
            let mut driver: Driver<1> = Driver::new(DriverConfig::default()).unwrap();
            driver.submit(read).unwrap();
            let mut link = DriverLink::default();
            let mut completed = std::vec::Vec::new();
            for clock in 0..100u32 {
                let event = match clock_driver(&mut port, &mut driver, &mut link) {
                    Ok(event) => event,
                    Err(e) => {
                        assert_eq!(e.error, IoError::Port(Broken));
                        assert!(e.to_string().contains("serial port error"));
                        e.event
                    }
                };
                if let Some(DriverEvent::Completed(done)) = event {
                    completed.push((clock, done));
                }
                if clock >= fail_from {
                    break; // the application stops at the error
                }
            }
            completed
        };
        let clean = run(u32::MAX);
        assert_eq!(clean.len(), 1);
        let (done_at, done) = clean[0];
        assert_eq!(done.data, Some(0x12_3456));
        assert_eq!(
            done.status,
            Status {
                x: true,
                q: true,
                ..Status::default()
            }
        );
        for fail_from in 0..done_at + 5 {
            let completed = run(fail_from);
            let expected = if fail_from >= done_at { 1 } else { 0 };
            assert_eq!(
                completed.len(),
                expected,
                "write failing at clock {fail_from}, completion at {done_at}"
            );
        }
    }

    /// A port that hands out a fixed script of reads: a byte, an error of some kind, or the end.
    struct Script(std::vec::Vec<Result<u8, embedded_io::ErrorKind>>);
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    struct Kind(embedded_io::ErrorKind);
    impl embedded_io::Error for Kind {
        fn kind(&self) -> embedded_io::ErrorKind {
            self.0
        }
    }
    impl fmt::Display for Kind {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            write!(f, "{:?}", self.0)
        }
    }
    impl core::error::Error for Kind {}
    impl embedded_io::ErrorType for Script {
        type Error = Kind;
    }
    impl Read for Script {
        fn read(&mut self, buf: &mut [u8]) -> Result<usize, Kind> {
            if self.0.is_empty() {
                return Ok(0);
            }
            match (self.0.remove(0), buf.first_mut()) {
                (Ok(b), Some(slot)) => {
                    *slot = b;
                    Ok(1)
                }
                (Ok(_), None) => Ok(0),
                (Err(kind), _) => Err(Kind(kind)),
            }
        }
    }
    impl Write for Script {
        fn write(&mut self, buf: &[u8]) -> Result<usize, Kind> {
            Ok(buf.len())
        }
        fn flush(&mut self) -> Result<(), Kind> {
            Ok(())
        }
    }

    /// Attack item 3: a read error (a UART's framing, parity or overrun error) in a sequence
    /// drops that sequence, as a damaged byte on the line does; a time-out is a quiet line and
    /// drops nothing. Both are returned to the caller.
    #[test]
    fn a_port_read_error_is_a_damaged_byte_for_the_panel() {
        use crate::panel::RESET;
        use embedded_io::ErrorKind;
        for (kind, dropped) in [
            (ErrorKind::Other, true),
            (ErrorKind::InvalidData, true),
            (ErrorKind::TimedOut, false),
        ] {
            // Reset, 1, 2, <error where 3 was>, ... the slot of register 3 went bad: with the
            // error read as damage the sequence 1 2 x 4 is dropped. A time-out takes no slot:
            // 1 2 4 5 is shown.
            let mut port = Script(std::vec![
                Ok(RESET),
                Ok(1),
                Ok(2),
                Err(kind),
                Ok(4),
                Ok(5),
                Ok(RESET),
            ]);
            let mut panel: Panel<4> = Panel::new();
            let mut errors = 0;
            for _ in 0..7 {
                if let Err(e) = panel_receive(&mut port, &mut panel) {
                    assert_eq!(e, IoError::Port(Kind(kind)));
                    errors += 1;
                }
            }
            assert_eq!(errors, 1);
            if dropped {
                assert_eq!(panel.registers(), &[0; 4], "{kind:?}");
                assert_eq!(panel.stats().bad_bytes, 1);
            } else {
                assert_eq!(panel.registers(), &[1, 2, 4, 5], "{kind:?}");
            }
            assert_eq!(panel_receive(&mut port, &mut panel), Err(IoError::Closed));
        }
    }

    /// Attack item 4: `host_transmit` says `LeaveIdle` exactly where the host leaves the line
    /// idle (once per sequence, after the reset byte) and writes nothing then.
    #[test]
    fn host_transmit_says_when_to_leave_the_line_idle() {
        use crate::panel::{HostConfig, RESET};
        let mut host: Host<3> = Host::new(HostConfig::default()).unwrap();
        let mut written = std::vec::Vec::new();
        struct Tx<'a>(&'a mut std::vec::Vec<Option<u8>>);
        impl embedded_io::ErrorType for Tx<'_> {
            type Error = core::convert::Infallible;
        }
        impl Write for Tx<'_> {
            fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
                self.0.extend(buf.iter().map(|&b| Some(b)));
                Ok(buf.len())
            }
            fn flush(&mut self) -> Result<(), Self::Error> {
                Ok(())
            }
        }
        for _ in 0..10 {
            match host_transmit(&mut Tx(&mut written), &mut host) {
                Ok(Transmit::Sent) => {}
                Ok(Transmit::LeaveIdle) => written.push(None),
                Err(e) => panic!("{e:?}"),
            }
        }
        assert_eq!(
            written,
            [
                Some(RESET),
                None,
                Some(0),
                Some(0),
                Some(0),
                Some(RESET),
                None,
                Some(0),
                Some(0),
                Some(0)
            ]
        );
    }

    /// The adapters' error messages in full: the port's own error, a closed stream, and the note
    /// that the driver's event of that clock comes back with the error.
    #[test]
    fn error_messages_name_what_was_wrong() {
        assert_eq!(
            IoError::Port("overrun").to_string(),
            "serial port error: \"overrun\""
        );
        assert_eq!(IoError::<()>::Closed.to_string(), "serial stream closed");
        let without = DriverClockError::<()> {
            error: IoError::Closed,
            event: None,
        };
        assert_eq!(without.to_string(), "serial stream closed");
        let with = DriverClockError::<()> {
            error: IoError::Closed,
            event: Some(DriverEvent::Demand {
                crate_address: 3,
                sgl: 1,
            }),
        };
        assert_eq!(
            with.to_string(),
            "serial stream closed (the driver's event of that clock is handed back with the error)"
        );
    }
}
