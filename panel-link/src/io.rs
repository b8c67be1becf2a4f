//! Driving the machines from a real byte stream (feature `embedded-io`).
//!
//! The machines stay sans-IO; these functions are the few lines a firmware writes around them
//! for a UART that implements [`embedded_io::Read`] and [`embedded_io::Write`] (every HAL's
//! blocking UART does; on a PC, `embedded-io-adapters` wraps any `std::io` port such as the
//! `serialport` crate's). Each call is one byte clock.
//!
//! ```
//! use regler_panel_link::highway::{Controller, ControllerConfig, Cycle, Dataway};
//! use regler_panel_link::io::clock_controller;
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
//! clock_controller(&mut port, &mut controller, &mut Empty)?;
//! clock_controller(&mut port, &mut controller, &mut Empty)?;
//! assert_eq!(port.tx, [0xE0, 0x02]); // a header for crate 2, passed on one byte late
//! assert!(clock_controller(&mut port, &mut controller, &mut Empty).is_err()); // stream closed
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```

use core::fmt;

use embedded_io::{Read, Write};

use crate::highway::{Controller, Dataway, Driver, DriverEvent};
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

/// One byte clock of a crate controller: read the byte from upstream, write the byte for
/// downstream.
///
/// # Errors
/// See [`read_byte`] and [`write_byte`].
pub fn clock_controller<P: Read + Write, D: Dataway + ?Sized>(
    port: &mut P,
    controller: &mut Controller,
    dataway: &mut D,
) -> Result<(), IoError<P::Error>> {
    let input = read_byte(port)?;
    write_byte(port, controller.clock(input, dataway))
}

/// One byte clock of the driver in lock-step with the loop: `input` is the byte that came back
/// last clock; the driver's byte is written, and the byte that comes back replaces `input`.
///
/// # Errors
/// See [`read_byte`] and [`write_byte`].
pub fn clock_driver<P: Read + Write, const W: usize>(
    port: &mut P,
    driver: &mut Driver<W>,
    input: &mut u8,
) -> Result<Option<DriverEvent>, IoError<P::Error>> {
    let step = driver.clock(*input);
    write_byte(port, step.transmit)?;
    port.flush().map_err(IoError::Port)?;
    *input = read_byte(port)?;
    Ok(step.event)
}

/// The host's transmitter is ready: writes the next sequence byte, if the host is sending.
/// Returns whether a byte was written.
///
/// # Errors
/// See [`write_byte`].
pub fn host_transmit<P: Write, const R: usize>(
    port: &mut P,
    host: &mut Host<R>,
) -> Result<bool, IoError<P::Error>> {
    match host.next_byte() {
        Some(byte) => write_byte(port, byte).map(|()| true),
        None => Ok(false),
    }
}

/// Reads one byte into the panel.
///
/// # Errors
/// See [`read_byte`].
pub fn panel_receive<P: Read, const R: usize>(
    port: &mut P,
    panel: &mut Panel<R>,
) -> Result<(), IoError<P::Error>> {
    let byte = read_byte(port)?;
    panel.receive(Ok(byte));
    Ok(())
}
