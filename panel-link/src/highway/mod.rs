//! The CAMAC serial highway (source 004): bytes, messages, the driver and the L-type crate
//! controller.
//!
//! # Bytes
//! Bits are numbered 1 to 8 as in the source; bit *k* is `1 << (k − 1)`.
//! - **Bit 8 is row parity**: every byte on the highway has an **odd** number of ones.
//! - **Bit 7 is the delimiter**: 0 in the header and every text byte (and SPACE), 1 in END,
//!   ENDSUM and WAIT.
//! - Bits 1–6 are the columns: the crate address in the header, the fields of the text bytes,
//!   six bits of data per data byte (most significant first: SW24–19, SW18–13, SW12–7, SW6–1),
//!   the column sums in SUM and ENDSUM.
//!
//! | byte | bits 1–6 | bit 7 | value |
//! |---|---|---|---|
//! | header | crate address 0–63 (SC0 is the driver, SC63 addresses no crate) | 0 | |
//! | SA (command) | A in bits 1–4, M1 = bit 5 = 0, M2 = bit 6 = 0 | 0 | |
//! | SF | F in bits 1–5, bit 6 = 0 | 0 | |
//! | SN | N in bits 1–5, bit 6 = 1 | 0 | |
//! | data | 6 bits of the 24-bit word | 0 | |
//! | status (reply) | ERR, SX, SQ, DERR in bits 1–4, M1 = 1, M2 = 0 | 0 | |
//! | SGL (demand) | graded LAM in bits 1–5, M2 = bit 6 = 1 | 0 | |
//! | SUM | even column parity | 0 | |
//! | SPACE | all six 1 | 0 | [`SPACE`] = `0xBF` |
//! | END, WAIT | bits 1–5 = 0, bits 6–8 = 1 | 1 | [`END`] = [`WAIT`] = `0xE0` |
//! | ENDSUM | even column parity | 1 | |
//!
//! The message type sits in bits 5–6 of the second byte: M2 M1 = 00 command, 01 reply, 1x demand
//! (in a demand, bit 5 is the fifth SGL bit).
//!
//! # Messages
//! - Command: header, SA, SF, SN, \[4 write-data bytes for F16–F23\], SUM, SPACE × n, END. For
//!   a write n is at least 3, the reply's length; for every other function n is at least 2 + the
//!   reply's length (5, or 9 for the reads F0–F7): two **guard** SPACE, then the reply room (see
//!   below). The crate controller writes its reply over the room. [`Message::encode`] sends
//!   exactly that many ([`min_spaces`]).
//! - Reply: header, status, \[4 data bytes for F0–F7\], ENDSUM (3 or 7 bytes).
//! - Demand: header, SGL, ENDSUM (3 bytes).
//! - Replies and demands come only from crates 1–62, and a demand's SGL is never 0 (a controller
//!   sends none then): [`decode`] refuses a reply or demand from crate 0 or 63 and a demand with
//!   SGL 0 ([`DecodeError::NotACrate`], [`DecodeError::SglZero`]), [`Message::encode`] makes none.
//!   A 2-bit error in a WAIT before a short reply of crate 32 (`E0 ^ 0x60`, `20`, `E0`) reads as
//!   exactly such a demand from crate 0.
//! - A truncated command or short reply, header + END, is not a message: [`decode`] names it
//!   ([`DecodeError::Truncated`]).
//!
//! # Which bytes the column sums cover (our reading of the source)
//! The source says the SUM byte's first six bits give even column parity "over the message text"
//! and that ENDSUM ends replies "with the column sums". We read it as: the column sum covers
//! **every byte from the header to the byte before SUM/ENDSUM**, header included, SPACE and END
//! excluded (they are filler the controller overwrites, not text); the SUM/ENDSUM byte's bits
//! 1–6 make the XOR of bits 1–6 over header … SUM zero. Covering the header matters: a header
//! whose two column bits flip would otherwise send a command to another crate unnoticed.
//!
//! # What the checks catch in one message
//! Every odd number of flipped bits breaks some byte's row parity. Two flips in one byte change
//! two columns (caught by the sum), a column and the delimiter, or the delimiter and the parity
//! (caught by the layout rules: delimiter where text belongs, SPACE or END not exact); two flips
//! in two bytes break two rows. So [`decode`] rejects every 1-, 2- and 3-bit error in a whole
//! message. The smallest error it misses is four flips on a rectangle (two bytes, the same two
//! columns).
//!
//! # Message boundaries on the loop (our reading of the source)
//! The machines do not see whole messages: they read byte by byte, and a delimiter and a parity
//! bit flipped together (`^ 0xC0`, or the delimiter with any other bit) turn a text byte into a
//! clean delimiter. Were every clean delimiter an end, the tail of a damaged message would be
//! read as a new one (a write to crate 47 with its SF hit made crate 35 run N5 A2 F9). The source
//! does not say how a controller finds where a message ends; we make every reader — each crate
//! controller, passing or addressed, and the driver — hold each message to its layout:
//! - A message ends only with a clean delimiter where its layout allows an end: header + END (the
//!   short reply); a reply's ENDSUM at byte 2 or 6; a demand's at byte 2; a command's END once
//!   all its SPACE (at least [`min_spaces`]) went by, with nothing but SPACE after SUM.
//! - Any other delimiter in a message, clean or not, or a byte the layout forbids (text after a
//!   reply's byte 6, a non-SPACE after a command's SUM) is a **break**; between messages, every
//!   delimiter other than WAIT is one. After a break the stream is junk up to the **next** clean
//!   delimiter: passed on unread by the controllers, taken off the loop (replaced by WAIT) by the
//!   controller the command was for, counted as garbled by the driver. Only then is a header
//!   looked for again.
//! - The driver completes a command only with a reply that [`decode`]s cleanly, whose header
//!   names that command's crate, and whose length is the one the command's function asks for.
//! - A new controller or driver (power-up, reset) starts as after a break: junk up to the first
//!   clean delimiter (an idle line's WAIT). It may start in the middle of a message, and a
//!   message's tail can be a clean message of its own (a write's SN and data read as a command to
//!   crate 32–62, a read reply's d2 d3 ENDSUM as a short reply). The driver sends one WAIT before
//!   its first command, so controllers that start with it are in step at once.
//!
//! # Bytes lost or repeated (a limit)
//! The checks are made for bit errors. A byte lost or duplicated on the line itself (a UART
//! overrun, a receiver that missed a start bit) is a fault they do not always catch: when a write's
//! data byte `0x3F` is lost, the SPACE after SUM slides into SUM's place, the column sum passes,
//! and the crate runs the write with shifted data. No controller can wait for END to show the
//! length: its reply goes out over the SPACE before END. The `io` functions (feature
//! `embedded-io`) never lose or repeat a byte themselves.
//!
//! # The two guard SPACE (beyond the source)
//! A damaged SF decides the layout: a write read as a non-write would have its SUM checked at d1,
//! and data can be chosen (d1 = the sum of header, SA, SF′, SN; d2 = d3 = 0x3F, exactly SPACE)
//! that passes every check the layout SF′ declares. So a non-write carries two guard SPACE before
//! its reply room, and the controller decides the reply's status — runs the dataway cycle — only
//! after checking that the four bytes after SUM (positions 5–8, where a write's d2, d3, d4 and SUM
//! stand) are exactly SPACE. For the true write that needs d2 = d3 = d4 = SUM = SPACE; and if the
//! column sum at d1 passed, SUM's columns are those of SF ⊕ SF′ ⊕ 0x3F — SPACE only if SF and SF′
//! had the same columns, yet they differ in F: impossible, whatever the data. The other way round (a non-write read as a write) the column
//! sum over positions 0–8 comes out as the columns of SF ⊕ SF′, never zero. The cost: reads are 15
//! bytes instead of 13, other non-writes 11 instead of 9.
//!
//! # What the tests show at the level of the machines
//! - No 1- or 2-bit error anywhere in a command, in the gap after it or across into the next
//!   command's first bytes makes any crate controller (every address 1–62, each fed the damaged
//!   bytes as if the error were on the link right before it) run a cycle other than the one sent,
//!   and each resynchronises by itself: exhaustive over ten command shapes; 3-bit errors sampled
//!   (6 000 cases, random commands of every shape).
//! - No 1- or 2-bit error in what a crate sends back (short reply, WAIT, reply of every shape,
//!   END, gap) or in a demand makes the driver — waiting on every crate — complete a command with
//!   anything but that crate's true reply, nor any controller run a cycle: exhaustive over twelve
//!   segments; 3-bit errors sampled (20 000 cases).
//! - An error after the addressed controller has checked the command (past its status byte) may
//!   still let it run the command sent — never another.
//! - A fresh controller (every address 1–62) started at any byte of 42 command shapes — 31 of
//!   them writes whose tail from SN on is a clean command — runs nothing, then runs the next clean
//!   command; a fresh driver started at any byte of replies whose tail is a clean reply of every
//!   crate completes nothing.
//! - No 1- or 2-bit error with a bit in a gap byte (WAIT between replies, short replies and
//!   demands), the other within three bytes of it, makes the driver report a demand no crate
//!   sent. A 2-bit error inside a short reply's END (then WAIT) reads as a demand for crates 1, 2,
//!   4, 8 and 16 (SGL = the address): tested, every crate and bit pair.

mod controller;
mod driver;

pub use controller::{ConfigError, Controller, ControllerConfig, ControllerStats, Cycle, Dataway};
pub use driver::{
    Completion, Driver, DriverConfig, DriverError, DriverEvent, DriverStats, Failure, Step,
};

use core::fmt;

/// SPACE: the filler a command carries for the reply (bits 1–6 and 8 set).
pub const SPACE: u8 = 0xBF;
/// END: the last byte of a command (bits 6–8 set).
pub const END: u8 = 0xE0;
/// WAIT: the byte a controller puts where it removed one, and the driver between messages; the
/// same bit pattern as [`END`] — its meaning comes from where it stands.
pub const WAIT: u8 = END;
/// Delimiter bit (bit 7).
pub const DELIMITER: u8 = 0x40;
/// Row-parity bit (bit 8).
pub const PARITY: u8 = 0x80;
/// The six column bits (bits 1–6).
pub const COLUMNS: u8 = 0x3F;
/// The non-addressed header SC63: no crate controller answers it.
pub const NON_ADDRESSED: u8 = 63;
/// The longest encoded message: a read (4 text bytes, SUM, 2 guard SPACE, 7 SPACE for the
/// reply, END), 15 bytes; a write is 13 (8 text bytes, SUM, 3 SPACE, END).
pub const MAX_MESSAGE: usize = 15;

const M1: u8 = 0x10;
const M2: u8 = 0x20;
const STATION_MARK: u8 = 0x20;

/// `bits` (bits 1–7) with bit 8 set so that the byte has an odd number of ones.
#[must_use]
pub const fn with_parity(bits: u8) -> u8 {
    let bits = bits & 0x7F;
    if bits.count_ones() & 1 == 0 {
        bits | PARITY
    } else {
        bits
    }
}

/// True when `byte` has odd row parity.
#[must_use]
pub const fn row_parity_ok(byte: u8) -> bool {
    byte.count_ones() & 1 == 1
}

/// True when `byte` is a delimiter (END, ENDSUM or WAIT: bit 7 set).
#[must_use]
pub const fn is_delimiter(byte: u8) -> bool {
    byte & DELIMITER != 0
}

/// True when `byte` is a delimiter with good row parity. Only such a byte ends a message or
/// makes a gap, in the crate controller and the driver alike: a byte whose delimiter bit was
/// flipped in fails its parity, so the tail of a damaged message can never be taken for a new
/// message.
#[must_use]
pub const fn is_clean_delimiter(byte: u8) -> bool {
    is_delimiter(byte) && row_parity_ok(byte)
}

/// True for the CAMAC functions that carry write data in the command (F16–F23).
#[must_use]
pub const fn is_write(function: u8) -> bool {
    matches!(function, 16..=23)
}

/// True for the CAMAC functions whose reply carries read data (F0–F7).
#[must_use]
pub const fn is_read(function: u8) -> bool {
    function <= 7
}

/// The length of the reply a command with `function` asks for: 7 for reads, 3 otherwise.
#[must_use]
pub const fn reply_len(function: u8) -> usize {
    if is_read(function) { 7 } else { 3 }
}

/// The guard SPACE bytes a command with `function` carries between SUM and its reply room: 2 for
/// every function that is not a write, 0 for writes (F16–F23).
///
/// They let the crate controller check that the four bytes after a non-write's SUM — where a
/// write's d2, d3, d4 and SUM stand — are SPACE before it must decide the reply's status, so a
/// write whose function byte was damaged into a non-write is always refused (see the module docs).
#[must_use]
pub const fn guard_len(function: u8) -> usize {
    if is_write(function) { 0 } else { 2 }
}

/// The least number of SPACE bytes between a command's SUM and its END: the guard
/// ([`guard_len`]) and the reply room ([`reply_len`]). 3 for writes, 9 for reads, 5 otherwise.
#[must_use]
pub const fn min_spaces(function: u8) -> usize {
    guard_len(function).saturating_add(reply_len(function))
}

/// The status byte of a reply.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Status {
    /// ERR: the controller found an error in this command and did not run it.
    pub err: bool,
    /// SX: the X (command accepted) response of the crate's dataway cycle.
    pub x: bool,
    /// SQ: the Q response of the dataway cycle.
    pub q: bool,
    /// DERR: the controller found an error in the command before this one.
    pub derr: bool,
}

impl Status {
    /// Bits 1–4 of the status byte.
    #[must_use]
    pub const fn bits(self) -> u8 {
        (self.err as u8) | (self.x as u8) << 1 | (self.q as u8) << 2 | (self.derr as u8) << 3
    }

    /// The status in bits 1–4 of `bits`.
    #[must_use]
    pub const fn from_bits(bits: u8) -> Self {
        Self {
            err: bits & 1 != 0,
            x: bits & 2 != 0,
            q: bits & 4 != 0,
            derr: bits & 8 != 0,
        }
    }
}

/// A serial-highway message.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Message {
    /// Driver → crate: run CAMAC function F at station N, subaddress A.
    Command {
        /// Crate address, 0–63 (1–62 address a crate).
        crate_address: u8,
        /// Station number N, 0–31.
        station: u8,
        /// Subaddress A, 0–15.
        subaddress: u8,
        /// Function F, 0–31.
        function: u8,
        /// The 24-bit write data: present exactly for F16–F23.
        data: Option<u32>,
    },
    /// Crate → driver: the answer to a command.
    Reply {
        /// The answering crate.
        crate_address: u8,
        /// ERR, SX, SQ, DERR.
        status: Status,
        /// The 24-bit read data (replies to F0–F7).
        data: Option<u32>,
    },
    /// Crate → driver, unasked: graded LAM requests.
    Demand {
        /// The demanding crate.
        crate_address: u8,
        /// The graded LAM (SGL), 5 bits.
        sgl: u8,
    },
}

/// Why a message could not be encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum EncodeError {
    /// The crate address does not fit six bits (0–63).
    CrateAddress(u8),
    /// The station number does not fit five bits (0–31).
    Station(u8),
    /// The subaddress does not fit four bits (0–15).
    Subaddress(u8),
    /// The function does not fit five bits (0–31).
    Function(u8),
    /// The SGL does not fit five bits (0–31).
    Sgl(u8),
    /// Data does not fit 24 bits.
    Data(u32),
    /// A reply or demand from crate 0 (the driver) or 63 (no crate): only crates 1–62 send them.
    NotACrate(u8),
    /// A demand with SGL 0 asks for nothing: it is not a message.
    SglZero,
    /// A write function (F16–F23) without data, or data with any other function.
    DataPresence {
        /// The function.
        function: u8,
        /// Whether data was given.
        has_data: bool,
    },
    /// The output buffer is shorter than the encoded message.
    BufferTooShort {
        /// Bytes needed.
        needed: usize,
    },
}

impl fmt::Display for EncodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::CrateAddress(v) => write!(f, "crate address must be 0..=63, got {v}"),
            Self::Station(v) => write!(f, "station number must be 0..=31, got {v}"),
            Self::Subaddress(v) => write!(f, "subaddress must be 0..=15, got {v}"),
            Self::Function(v) => write!(f, "function must be 0..=31, got {v}"),
            Self::Sgl(v) => write!(f, "SGL must be 0..=31, got {v}"),
            Self::Data(v) => write!(f, "data must fit 24 bits, got {v:#x}"),
            Self::NotACrate(v) => write!(
                f,
                "replies and demands come from crates 1..=62, got crate {v}"
            ),
            Self::SglZero => f.write_str("a demand needs a non-zero SGL (1..=31)"),
            Self::DataPresence {
                function,
                has_data: true,
            } => {
                write!(f, "F{function} carries no write data, but data was given")
            }
            Self::DataPresence {
                function,
                has_data: false,
            } => {
                write!(f, "F{function} is a write (F16-F23) and needs data")
            }
            Self::BufferTooShort { needed } => {
                write!(f, "output buffer too short: {needed} bytes needed")
            }
        }
    }
}

impl core::error::Error for EncodeError {}

/// Which rule a received byte sequence broke.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum DecodeError {
    /// Fewer than two bytes: not even a header and a delimiter.
    TooShort {
        /// Bytes given.
        len: usize,
    },
    /// More bytes than [`MAX_DECODE`] (75), the longest message `decode` takes.
    TooLong {
        /// Bytes given.
        len: usize,
    },
    /// The byte at `index` has even row parity.
    RowParity {
        /// Position from the header (0).
        index: usize,
    },
    /// A delimiter bit in the wrong place: set in a header or text byte, or clear in the last.
    Delimiter {
        /// Position from the header (0).
        index: usize,
    },
    /// Header + END: a truncated command or a short reply.
    Truncated {
        /// The header's crate address.
        crate_address: u8,
    },
    /// A bit the layout fixes has the wrong value (SN bit 6 must be 1, SF bit 6 must be 0).
    ReservedBit {
        /// Position from the header (0).
        index: usize,
    },
    /// The message is not as long as its type and function say.
    Length {
        /// Bytes expected (for a command: the least).
        expected: usize,
        /// Bytes given.
        got: usize,
    },
    /// The column sums do not cancel: SUM or ENDSUM at `index` is wrong for the bytes before it.
    ColumnParity {
        /// Position of the SUM or ENDSUM byte.
        index: usize,
    },
    /// A command byte between SUM and END is not SPACE.
    NotSpace {
        /// Position from the header (0).
        index: usize,
    },
    /// A command's last byte is a delimiter but not END.
    NotEnd {
        /// The byte.
        byte: u8,
    },
    /// A reply or demand whose header names crate 0 (the driver) or 63 (no crate): only crates
    /// 1–62 send them.
    NotACrate {
        /// The header's crate address.
        crate_address: u8,
    },
    /// A demand with SGL 0: it asks for nothing (a controller sends none).
    SglZero {
        /// The header's crate address.
        crate_address: u8,
    },
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::TooShort { len } => write!(
                f,
                "{len} bytes: a message has at least a header and a delimiter"
            ),
            Self::TooLong { len } => write!(f, "{len} bytes: longer than any message"),
            Self::RowParity { index } => {
                write!(f, "row parity: byte {index} has an even number of ones")
            }
            Self::Delimiter { index } => write!(f, "delimiter bit (bit 7) wrong in byte {index}"),
            Self::Truncated { crate_address } => {
                write!(
                    f,
                    "header + END only (truncated command or short reply) from crate {crate_address}"
                )
            }
            Self::ReservedBit { index } => {
                write!(f, "byte {index} has a fixed bit with the wrong value")
            }
            Self::Length { expected, got } => {
                write!(f, "length {got}, the message type needs {expected}")
            }
            Self::ColumnParity { index } => write!(
                f,
                "column parity: the sum byte {index} does not cancel the columns"
            ),
            Self::NotSpace { index } => {
                write!(f, "byte {index} of a command's reply room is not SPACE")
            }
            Self::NotEnd { byte } => write!(f, "a command must end with END, got {byte:#04x}"),
            Self::NotACrate { crate_address } => write!(
                f,
                "a reply or demand from crate {crate_address}: only crates 1..=62 send them"
            ),
            Self::SglZero { crate_address } => {
                write!(
                    f,
                    "a demand with SGL 0 from crate {crate_address} asks for nothing"
                )
            }
        }
    }
}

impl core::error::Error for DecodeError {}

/// Column sum (XOR of bits 1–6) of `bytes`.
#[must_use]
pub fn column_sum(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0, |acc, b| acc ^ (b & COLUMNS))
}

/// The SUM byte closing the text `bytes`.
#[must_use]
pub fn sum_byte(bytes: &[u8]) -> u8 {
    with_parity(column_sum(bytes))
}

/// The ENDSUM byte closing the text `bytes`.
#[must_use]
pub fn endsum_byte(bytes: &[u8]) -> u8 {
    with_parity(DELIMITER | column_sum(bytes))
}

/// The four data bytes of a 24-bit word, most significant six bits first.
#[must_use]
pub const fn data_bytes(word: u32) -> [u8; 4] {
    [
        with_parity(((word >> 18) & 0x3F) as u8),
        with_parity(((word >> 12) & 0x3F) as u8),
        with_parity(((word >> 6) & 0x3F) as u8),
        with_parity((word & 0x3F) as u8),
    ]
}

fn data_word(bytes: &[u8]) -> u32 {
    bytes
        .iter()
        .fold(0, |acc, b| (acc << 6) | u32::from(b & COLUMNS))
}

/// A cursor writing into the caller's buffer.
struct Out<'a> {
    buf: &'a mut [u8],
    len: usize,
}

impl Out<'_> {
    fn push(&mut self, byte: u8) {
        if let Some(slot) = self.buf.get_mut(self.len) {
            *slot = byte;
        }
        self.len = self.len.saturating_add(1);
    }

    fn text(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }
}

impl Message {
    /// The crate address in the header.
    #[must_use]
    pub const fn crate_address(&self) -> u8 {
        match *self {
            Self::Command { crate_address, .. }
            | Self::Reply { crate_address, .. }
            | Self::Demand { crate_address, .. } => crate_address,
        }
    }

    /// The length of the encoded message.
    #[must_use]
    pub const fn encoded_len(&self) -> usize {
        match *self {
            Self::Command { function, data, .. } => {
                let data: usize = if data.is_some() { 4 } else { 0 };
                // header, SA, SF, SN, data, SUM, SPACE × (guard + reply length), END
                data.saturating_add(min_spaces(function)).saturating_add(6)
            }
            Self::Reply { data: Some(_), .. } => 7,
            Self::Reply { data: None, .. } | Self::Demand { .. } => 3,
        }
    }

    /// Checks every field against its width and the data-presence rule.
    ///
    /// # Errors
    /// The first field that does not fit, as [`EncodeError`].
    pub const fn validate(&self) -> Result<(), EncodeError> {
        let crate_address = self.crate_address();
        if crate_address > 63 {
            return Err(EncodeError::CrateAddress(crate_address));
        }
        let data = match *self {
            Self::Command {
                station,
                subaddress,
                function,
                data,
                ..
            } => {
                if station > 31 {
                    return Err(EncodeError::Station(station));
                }
                if subaddress > 15 {
                    return Err(EncodeError::Subaddress(subaddress));
                }
                if function > 31 {
                    return Err(EncodeError::Function(function));
                }
                if is_write(function) != data.is_some() {
                    return Err(EncodeError::DataPresence {
                        function,
                        has_data: data.is_some(),
                    });
                }
                data
            }
            Self::Reply { data, .. } => {
                if crate_address == 0 || crate_address == NON_ADDRESSED {
                    return Err(EncodeError::NotACrate(crate_address));
                }
                data
            }
            Self::Demand { sgl, .. } => {
                if crate_address == 0 || crate_address == NON_ADDRESSED {
                    return Err(EncodeError::NotACrate(crate_address));
                }
                if sgl > 31 {
                    return Err(EncodeError::Sgl(sgl));
                }
                if sgl == 0 {
                    return Err(EncodeError::SglZero);
                }
                None
            }
        };
        if let Some(word) = data {
            if word >= 1 << 24 {
                return Err(EncodeError::Data(word));
            }
        }
        Ok(())
    }

    /// Writes the message into `out` and returns its length.
    ///
    /// ```
    /// use regler_panel_link::highway::{decode, Message, MAX_MESSAGE};
    ///
    /// let read = Message::Command { crate_address: 5, station: 3, subaddress: 0, function: 0, data: None };
    /// let mut buf = [0u8; MAX_MESSAGE];
    /// let len = read.encode(&mut buf)?;
    /// assert_eq!(len, 15); // 4 text bytes + SUM, 2 guard SPACE, 7 SPACE for the 7-byte reply, END
    /// assert_eq!(decode(&buf[..len]), Ok(read));
    /// # Ok::<(), Box<dyn core::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// A field that does not fit ([`validate`](Self::validate)) or a buffer too short; `out` is
    /// left untouched then.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        self.validate()?;
        let needed = self.encoded_len();
        if out.len() < needed {
            return Err(EncodeError::BufferTooShort { needed });
        }
        let mut w = Out { buf: out, len: 0 };
        w.push(with_parity(self.crate_address()));
        match *self {
            Self::Command {
                station,
                subaddress,
                function,
                data,
                ..
            } => {
                w.push(with_parity(subaddress));
                w.push(with_parity(function));
                w.push(with_parity(STATION_MARK | station));
                if let Some(word) = data {
                    for byte in data_bytes(word) {
                        w.push(byte);
                    }
                }
                w.push(sum_byte(w.text()));
                for _ in 0..min_spaces(function) {
                    w.push(SPACE);
                }
                w.push(END);
            }
            Self::Reply { status, data, .. } => {
                w.push(with_parity(M1 | status.bits()));
                if let Some(word) = data {
                    for byte in data_bytes(word) {
                        w.push(byte);
                    }
                }
                w.push(endsum_byte(w.text()));
            }
            Self::Demand { sgl, .. } => {
                w.push(with_parity(M2 | sgl));
                w.push(endsum_byte(w.text()));
            }
        }
        Ok(w.len)
    }
}

/// The shortest command: 4 text bytes, SUM, 2 guard SPACE, 3 SPACE for the reply, END (a
/// function that neither reads nor writes).
const SHORTEST_COMMAND: usize = 11;

/// The longest byte sequence [`decode`] considers, 75 bytes: a write (8 text bytes and SUM) with
/// 65 SPACE bytes and its END, a read or any other command with more SPACE.
pub const MAX_DECODE: usize = 9 + 1 + 64 + 1;

/// Decodes one message, from its header to its END or ENDSUM byte inclusive, checking every rule:
/// length, row parity of every byte, the delimiter bit of every byte, the fixed bits, the layout
/// of the message type, the column sum, the sender (a reply or demand comes from a crate 1–62, a
/// demand has a non-zero SGL), the SPACE run and the END byte.
///
/// ```
/// use regler_panel_link::highway::{decode, DecodeError, Message, Status};
///
/// let reply = Message::Reply { crate_address: 5, status: Status { x: true, q: true, ..Status::default() }, data: Some(0xABCDE) };
/// let mut buf = [0u8; 7];
/// reply.encode(&mut buf)?;
/// assert_eq!(decode(&buf), Ok(reply));
/// buf[3] ^= 0b0000_0011; // two flips in one byte: row parity holds, two columns do not
/// assert_eq!(decode(&buf), Err(DecodeError::ColumnParity { index: 6 }));
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
///
/// # Errors
/// The first broken rule, as [`DecodeError`], in the order listed above.
pub fn decode(bytes: &[u8]) -> Result<Message, DecodeError> {
    let len = bytes.len();
    if len < 2 {
        return Err(DecodeError::TooShort { len });
    }
    if len > MAX_DECODE {
        return Err(DecodeError::TooLong { len });
    }
    if let Some(index) = bytes.iter().position(|&b| !row_parity_ok(b)) {
        return Err(DecodeError::RowParity { index });
    }
    let last = len.saturating_sub(1);
    // Text bytes: delimiter bit clear. Where the text ends depends on the type, so first find the
    // first delimiter: it must be the last byte.
    if let Some(index) = bytes.iter().position(|&b| is_delimiter(b)) {
        if index != last {
            return Err(DecodeError::Delimiter { index });
        }
    } else {
        return Err(DecodeError::Delimiter { index: last });
    }
    let field = |index: usize| bytes.get(index).map_or(0, |b| b & COLUMNS);
    let crate_address = field(0);
    if len == 2 {
        return Err(DecodeError::Truncated { crate_address });
    }
    let second = field(1);
    if second & M2 != 0 {
        if len != 3 {
            return Err(DecodeError::Length {
                expected: 3,
                got: len,
            });
        }
        check_sum(bytes, 2)?;
        sender(crate_address)?;
        let sgl = second & 0x1F;
        if sgl == 0 {
            return Err(DecodeError::SglZero { crate_address });
        }
        return Ok(Message::Demand { crate_address, sgl });
    }
    if second & M1 != 0 {
        let data = match len {
            3 => None,
            7 => Some(data_word(bytes.get(2..6).unwrap_or(&[]))),
            _ => {
                return Err(DecodeError::Length {
                    expected: if len < 7 { 3 } else { 7 },
                    got: len,
                });
            }
        };
        check_sum(bytes, last)?;
        sender(crate_address)?;
        return Ok(Message::Reply {
            crate_address,
            status: Status::from_bits(second),
            data,
        });
    }
    // A command: header, SA, SF, SN, [data], SUM, SPACE…, END. Without SF and SN its function
    // is unknown: the least of any command is what it needs.
    if len < 5 {
        return Err(DecodeError::Length {
            expected: SHORTEST_COMMAND,
            got: len,
        });
    }
    let subaddress = second & 0x0F;
    let sf = field(2);
    let sn = field(3);
    if sf & 0x20 != 0 {
        return Err(DecodeError::ReservedBit { index: 2 });
    }
    if sn & STATION_MARK == 0 {
        return Err(DecodeError::ReservedBit { index: 3 });
    }
    let function = sf & 0x1F;
    let data_len = if is_write(function) { 4 } else { 0 };
    let sum_at = 4usize.saturating_add(data_len);
    let expected = sum_at
        .saturating_add(1)
        .saturating_add(min_spaces(function))
        .saturating_add(1);
    if len < expected {
        return Err(DecodeError::Length { expected, got: len });
    }
    check_sum(bytes, sum_at)?;
    let room = bytes.get(sum_at.saturating_add(1)..last).unwrap_or(&[]);
    if let Some(k) = room.iter().position(|&b| b != SPACE) {
        return Err(DecodeError::NotSpace {
            index: sum_at.saturating_add(1).saturating_add(k),
        });
    }
    let end = bytes.get(last).copied().unwrap_or(0);
    if end != END {
        return Err(DecodeError::NotEnd { byte: end });
    }
    let data = if data_len == 4 {
        Some(data_word(bytes.get(4..8).unwrap_or(&[])))
    } else {
        None
    };
    Ok(Message::Command {
        crate_address,
        station: sn & 0x1F,
        subaddress,
        function,
        data,
    })
}

/// What one byte is to a reader that follows message boundaries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Seen {
    /// WAIT between messages.
    Gap,
    /// The first byte of a message.
    Header,
    /// A byte inside a message whose layout still holds.
    Text,
    /// A clean delimiter where the message's layout allows it to end.
    End,
    /// Junk: a delimiter where no message may end or a byte the layout does not allow (a
    /// *break*), and everything after it up to and including the next clean delimiter.
    Junk,
}

/// The layout a [`Framer`] holds a message to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
enum Layout {
    /// Only the header so far: header + END (a short reply) may end here.
    Header,
    /// A command before its SF.
    CommandStart,
    /// A command: text up to `sum_at`, then only SPACE; END from `end_from` on.
    Command { sum_at: u8, end_from: u8 },
    /// A reply: ENDSUM at index 2 or 6.
    Reply,
    /// A demand: ENDSUM at index 2.
    Demand,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
enum FrameState {
    Between,
    Message { layout: Layout, index: u8 },
    Junk,
}

/// Follows message boundaries in a byte stream, the same way in every crate controller and the
/// driver: a message ends only with a clean delimiter where its layout allows an end; a
/// delimiter anywhere else (clean or not), a byte the layout forbids, or any delimiter other than
/// WAIT between messages is a break, and the stream is junk up to the next clean delimiter — a
/// damaged message's tail is never read as a message of its own.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) struct Framer {
    state: FrameState,
}

impl Framer {
    /// A reader that starts as after a break: junk up to the first clean delimiter. A machine
    /// that (re)starts may be in the middle of a message, and a message's tail can be a clean
    /// message of its own (a write's SN and data read as a command to crate 32–62); an idle
    /// line's first WAIT ends the junk at once.
    pub(crate) const fn new() -> Self {
        Self {
            state: FrameState::Junk,
        }
    }

    /// True between messages (a demand may go out).
    pub(crate) const fn between(&self) -> bool {
        matches!(self.state, FrameState::Between)
    }

    /// Back to between messages (after a message this reader took apart itself).
    pub(crate) fn reset(&mut self) {
        self.state = FrameState::Between;
    }

    pub(crate) fn push(&mut self, byte: u8) -> Seen {
        let (state, seen) = match self.state {
            FrameState::Between if byte == WAIT => (FrameState::Between, Seen::Gap),
            FrameState::Between if is_delimiter(byte) => (FrameState::Junk, Seen::Junk),
            FrameState::Between => (
                FrameState::Message {
                    layout: Layout::Header,
                    index: 1,
                },
                Seen::Header,
            ),
            FrameState::Junk if is_clean_delimiter(byte) => (FrameState::Between, Seen::Junk),
            FrameState::Junk => (FrameState::Junk, Seen::Junk),
            FrameState::Message { layout, index } => {
                if is_delimiter(byte) {
                    if is_clean_delimiter(byte) && layout.may_end(index, byte) {
                        (FrameState::Between, Seen::End)
                    } else {
                        (FrameState::Junk, Seen::Junk)
                    }
                } else {
                    match layout.after_text(index, byte) {
                        Some(layout) if usize::from(index) < MAX_DECODE => (
                            FrameState::Message {
                                layout,
                                index: index.saturating_add(1),
                            },
                            Seen::Text,
                        ),
                        _ => (FrameState::Junk, Seen::Junk),
                    }
                }
            }
        };
        self.state = state;
        seen
    }
}

impl Layout {
    /// May a clean delimiter `byte` at `index` end the message?
    const fn may_end(self, index: u8, byte: u8) -> bool {
        match self {
            Self::Header => byte == END,
            Self::CommandStart => false,
            Self::Command { end_from, .. } => byte == END && index >= end_from,
            Self::Reply => index == 2 || index == 6,
            Self::Demand => index == 2,
        }
    }

    /// The layout after text byte `byte` at `index`; `None` where the layout allows no text.
    fn after_text(self, index: u8, byte: u8) -> Option<Self> {
        match self {
            Self::Header if byte & M2 != 0 => Some(Self::Demand),
            Self::Header if byte & M1 != 0 => Some(Self::Reply),
            Self::Header => Some(Self::CommandStart),
            Self::CommandStart => {
                let function = byte & 0x1F;
                let sum_at: u8 = if is_write(function) { 8 } else { 4 };
                let spaces = u8::try_from(min_spaces(function)).unwrap_or(u8::MAX);
                let end_from = sum_at.saturating_add(1).saturating_add(spaces);
                Some(Self::Command { sum_at, end_from })
            }
            Self::Command { sum_at, .. } if index > sum_at && byte != SPACE => None,
            Self::Command { .. } => Some(self),
            Self::Reply if index < 6 => Some(self),
            Self::Reply | Self::Demand => None,
        }
    }
}

/// Replies and demands come only from crates 1–62.
const fn sender(crate_address: u8) -> Result<(), DecodeError> {
    if crate_address == 0 || crate_address == NON_ADDRESSED {
        Err(DecodeError::NotACrate { crate_address })
    } else {
        Ok(())
    }
}

/// Checks that the XOR of bits 1–6 over `bytes[..=at]` is zero.
fn check_sum(bytes: &[u8], at: usize) -> Result<(), DecodeError> {
    let covered = bytes.get(..=at).unwrap_or(&[]);
    if column_sum(covered) == 0 {
        Ok(())
    } else {
        Err(DecodeError::ColumnParity { index: at })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn byte_constants_have_the_sources_bits() {
        // SPACE: first six bits 1, delimiter 0, odd parity.
        assert_eq!(SPACE & COLUMNS, 0x3F);
        assert!(!is_delimiter(SPACE) && row_parity_ok(SPACE));
        // END and WAIT: first five bits 0, last three 1.
        assert_eq!(END, 0b1110_0000);
        assert!(is_delimiter(END) && row_parity_ok(END));
    }

    #[test]
    fn every_byte_of_every_message_has_odd_parity_and_one_delimiter_at_the_end() {
        let messages = [
            Message::Command {
                crate_address: 62,
                station: 31,
                subaddress: 15,
                function: 16,
                data: Some(0xFF_FFFF),
            },
            Message::Command {
                crate_address: 1,
                station: 0,
                subaddress: 0,
                function: 0,
                data: None,
            },
            Message::Command {
                crate_address: 1,
                station: 1,
                subaddress: 2,
                function: 9,
                data: None,
            },
            Message::Reply {
                crate_address: 7,
                status: Status::from_bits(0xF),
                data: Some(0),
            },
            Message::Reply {
                crate_address: 7,
                status: Status::default(),
                data: None,
            },
            Message::Demand {
                crate_address: 9,
                sgl: 31,
            },
        ];
        for m in messages {
            let mut buf = [0u8; MAX_MESSAGE];
            let len = m.encode(&mut buf).unwrap();
            assert_eq!(len, m.encoded_len());
            let bytes = &buf[..len];
            assert!(bytes.iter().all(|&b| row_parity_ok(b)));
            assert_eq!(bytes.iter().filter(|&&b| is_delimiter(b)).count(), 1);
            assert!(is_delimiter(bytes[len - 1]));
            assert_eq!(decode(bytes), Ok(m));
        }
    }

    #[test]
    fn encode_refuses_fields_that_do_not_fit_and_leaves_the_buffer_alone() {
        let cmd = |crate_address, station, subaddress, function, data| Message::Command {
            crate_address,
            station,
            subaddress,
            function,
            data,
        };
        let mut buf = [0x55u8; MAX_MESSAGE];
        assert_eq!(
            cmd(64, 0, 0, 0, None).encode(&mut buf),
            Err(EncodeError::CrateAddress(64))
        );
        assert_eq!(
            cmd(1, 32, 0, 0, None).encode(&mut buf),
            Err(EncodeError::Station(32))
        );
        assert_eq!(
            cmd(1, 0, 16, 0, None).encode(&mut buf),
            Err(EncodeError::Subaddress(16))
        );
        assert_eq!(
            cmd(1, 0, 0, 32, None).encode(&mut buf),
            Err(EncodeError::Function(32))
        );
        assert_eq!(
            cmd(1, 0, 0, 16, None).encode(&mut buf),
            Err(EncodeError::DataPresence {
                function: 16,
                has_data: false
            })
        );
        assert_eq!(
            cmd(1, 0, 0, 0, Some(1)).encode(&mut buf),
            Err(EncodeError::DataPresence {
                function: 0,
                has_data: true
            })
        );
        assert_eq!(
            cmd(1, 0, 0, 16, Some(1 << 24)).encode(&mut buf),
            Err(EncodeError::Data(1 << 24))
        );
        assert_eq!(
            Message::Demand {
                crate_address: 1,
                sgl: 32
            }
            .encode(&mut buf),
            Err(EncodeError::Sgl(32))
        );
        assert_eq!(
            cmd(1, 0, 0, 16, Some(1)).encode(&mut buf[..12]),
            Err(EncodeError::BufferTooShort { needed: 13 })
        );
        assert!(buf.iter().all(|&b| b == 0x55));
        for text in [
            EncodeError::Station(32).to_string(),
            DecodeError::RowParity { index: 3 }.to_string(),
        ] {
            assert!(text.contains("32") || text.contains('3'), "{text}");
        }
    }

    #[test]
    fn decode_names_the_rule() {
        let mut buf = [0u8; MAX_MESSAGE];
        let cmd = Message::Command {
            crate_address: 4,
            station: 2,
            subaddress: 1,
            function: 9,
            data: None,
        };
        let len = cmd.encode(&mut buf).unwrap();
        assert_eq!(len, 11); // 5 text bytes with SUM, 2 guard SPACE, 3 SPACE for the reply, END
        assert_eq!(decode(&[]), Err(DecodeError::TooShort { len: 0 }));
        assert_eq!(
            decode(&[with_parity(4), END]),
            Err(DecodeError::Truncated { crate_address: 4 })
        );
        // One SPACE short of the guard and the reply.
        let short = [&buf[..5], &[SPACE; 4], &[END]].concat();
        assert_eq!(
            decode(&short),
            Err(DecodeError::Length {
                expected: 11,
                got: 10
            })
        );
        // Extra SPACE is fine (the driver may give more room than needed).
        let long = [&buf[..5], &[SPACE; 8], &[END]].concat();
        assert_eq!(decode(&long), Ok(cmd));
        // A delimiter in the text.
        let mut bad = buf;
        bad[2] = with_parity(DELIMITER | 9);
        assert_eq!(
            decode(&bad[..len]),
            Err(DecodeError::Delimiter { index: 2 })
        );
        // SN without its bit 6.
        let mut bad = buf;
        bad[3] = with_parity(2);
        assert_eq!(
            decode(&bad[..len]),
            Err(DecodeError::ReservedBit { index: 3 })
        );
        // ENDSUM where END belongs.
        let mut bad = buf;
        bad[10] = with_parity(DELIMITER | 1);
        assert_eq!(
            decode(&bad[..len]),
            Err(DecodeError::NotEnd { byte: bad[10] })
        );
        // A reply of the wrong length.
        assert_eq!(
            decode(&[
                with_parity(4),
                with_parity(M1),
                with_parity(1),
                endsum_byte(&[4, M1, 1])
            ]),
            Err(DecodeError::Length {
                expected: 3,
                got: 4
            })
        );
    }

    /// A command cut short (its first bytes, then END) is refused with the length its function
    /// needs, and, where SF and SN are missing, the least of any command — never a length no
    /// command has. Every function, every cut.
    #[test]
    fn a_cut_command_names_the_length_its_function_needs() {
        let shortest = (0..=31)
            .map(|function| command(function).encoded_len())
            .min();
        assert_eq!(shortest, Some(SHORTEST_COMMAND));
        assert_eq!(SHORTEST_COMMAND, 11);
        // Under Miri every fifth function (0, 5, 10, …, 30): reads, writes and the others.
        for function in (0..=31).step_by(if cfg!(miri) { 5 } else { 1 }) {
            let cmd = command(function);
            let mut buf = [0u8; MAX_MESSAGE];
            let n = cmd.encode(&mut buf).unwrap();
            for k in 1..n {
                let cut = [&buf[..k], &[END]].concat();
                let want = match k + 1 {
                    2 => Err(DecodeError::Truncated { crate_address: 4 }),
                    got @ 3..=4 => Err(DecodeError::Length { expected: 11, got }),
                    got if got < n => Err(DecodeError::Length { expected: n, got }),
                    _ => Ok(cmd),
                };
                assert_eq!(decode(&cut), want, "F{function} cut after {k} bytes");
            }
        }
    }

    /// `decode` takes up to `MAX_DECODE` = 75 bytes: a write padded with SPACE to 75 bytes is a
    /// message, one byte more is too long.
    #[test]
    fn decode_takes_a_command_of_75_bytes_and_no_longer() {
        let write = Message::Command {
            crate_address: 4,
            station: 2,
            subaddress: 1,
            function: 16,
            data: Some(0x12_3456),
        };
        let mut buf = [0u8; MAX_MESSAGE];
        let n = write.encode(&mut buf).unwrap();
        let text = &buf[..9]; // 8 text bytes and SUM
        for len in [n, 74, 75] {
            let padded = [text, &vec![SPACE; len - 10][..], &[END]].concat();
            assert_eq!(decode(&padded), Ok(write), "{len} bytes");
        }
        let too_long = [text, &[SPACE; 66][..], &[END]].concat();
        assert_eq!(decode(&too_long), Err(DecodeError::TooLong { len: 76 }));
        assert_eq!(MAX_DECODE, 75);
    }

    fn command(function: u8) -> Message {
        Message::Command {
            crate_address: 4,
            station: 2,
            subaddress: 1,
            function,
            data: is_write(function).then_some(0x0ABC),
        }
    }
}
