//! The request/refill messages between a slave and its master, carrying cumulative counters.
//!
//! The source's level-1 board asks for "one more byte" every time it sends one to the machine.
//! Over a link that loses, repeats or reorders messages such edges drift: a lost request is a
//! byte never sent, a repeated one a byte sent twice. Here every message says where it stands
//! instead:
//!
//! * a [`Report`] (slave → master) carries the slave's **consumed** and **received** totals
//!   (wrapping `u16`); the master owes `consumed + capacity − sent` items, whatever happened to
//!   the reports before it, and ignores a report older than one it has seen;
//! * a [`Refill`] (master → slave) carries the stream index of its first item; the slave takes
//!   an item only if its index is the next one it expects, so an item that arrives twice is not
//!   consumed twice and one that arrives early (after a loss) is not taken out of order.
//!
//! **Sessions.** Every report carries the board's **boot number** (its firmware adds 1 at every
//! start; [`newer_boot`] orders them, wrapping). A board that has just started has no place in
//! the stream: its reports carry the **hello** flag, and the master answers with refills flagged
//! **sync** that carry the same boot number and start where the previous board stopped; the
//! board takes its counters from the first such refill that has items. A report whose boot
//! number is not the current session's is ignored, and so is a hello of an earlier start, so a
//! late or repeated frame of the board before a reboot never moves the new board's session; a
//! sync refill for another boot number is never taken by the new board. The master answers a
//! report it ignored for its boot number with a **session offer** — a sync refill of no items
//! carrying the session's boot number — and a placed board that gets one for another start says
//! hello again (taking the number after the offered one if that is a later start than its own),
//! so a board is never ignored for good.
//!
//! Frames (all integers little-endian, CRC-16/CCITT-FALSE over everything before it):
//!
//! | frame | bytes |
//! |---|---|
//! | report | `0xA5`, slave, consumed (2), received (2), flags, boot, CRC (2) — 10 bytes; flags bit 0 = stand-alone, bit 1 = retry, bit 2 = hello, others 0 |
//! | refill | `0x5A`, slave, first index (2), flags, boot, count n (0..=[`MAX_REFILL`]), n items, CRC (2) — 9 + n bytes; flags bit 0 = sync, others 0; n = 0 is a keep-alive, or with sync a session offer |
//!
//! The CRC detects every error of up to 3 bits in a frame of this size and every burst of up to
//! 16 bits.

use core::fmt;

/// Bytes in a report frame.
pub const REPORT_LEN: usize = 10;
/// The most items one refill frame carries.
pub const MAX_REFILL: usize = 64;
/// Bytes in the longest frame (a full refill).
pub const MAX_FRAME: usize = REFILL_OVERHEAD + MAX_REFILL;

const REPORT_TAG: u8 = 0xA5;
const REFILL_TAG: u8 = 0x5A;
const REFILL_HEADER: usize = 7;
const REFILL_OVERHEAD: usize = REFILL_HEADER + 2;
const FLAG_STANDALONE: u8 = 0x01;
const FLAG_RETRY: u8 = 0x02;
const FLAG_HELLO: u8 = 0x04;
const FLAG_SYNC: u8 = 0x01;

/// A slave's request: where it stands, as cumulative wrapping counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Report {
    /// The slave's address.
    pub slave: u8,
    /// Stream items used up (consumed, or skipped after an underrun), wrapping.
    pub consumed: u16,
    /// Stream items taken into the ring: the index of the next item the slave will accept.
    pub received: u16,
    /// The slave is running from its local pattern (the master was silent too long).
    pub standalone: bool,
    /// The slave has waited for a refill longer than its retry time, or saw a gap: the master
    /// should send again from `received`.
    pub retry: bool,
    /// The board's boot number ([`SlaveConfig::boot`](crate::SlaveConfig::boot)): reports of
    /// another boot than the master's current session are ignored.
    pub boot: u8,
    /// The board has just started and has no place in the stream yet (its counters mean
    /// nothing): the master starts a new session and answers with sync refills.
    pub hello: bool,
}

/// The master's refill: items of the stream, starting at index `first`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Refill<'a> {
    /// The slave's address.
    pub slave: u8,
    /// Stream index (wrapping) of `items[0]`.
    pub first: u16,
    /// Up to [`MAX_REFILL`] items; none is a keep-alive ("the master is here").
    pub items: &'a [u8],
    /// The boot number of the session this refill belongs to (for a sync refill: the board
    /// that said hello).
    pub boot: u8,
    /// A refill of a new session: `first` is where the board with boot number `boot` starts.
    pub sync: bool,
}

impl Refill<'static> {
    /// An empty refill ("the master is here"), the answer to a report when nothing is owed.
    #[must_use]
    pub const fn keep_alive(slave: u8) -> Self {
        Self {
            slave,
            first: 0,
            items: &[],
            boot: 0,
            sync: false,
        }
    }
}

/// A decoded frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Message<'a> {
    /// Slave → master.
    Report(Report),
    /// Master → slave.
    Refill(Refill<'a>),
}

/// Why a frame was refused by [`decode`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DecodeError {
    /// No bytes at all.
    Empty,
    /// The first byte is neither a report (`0xA5`) nor a refill (`0x5A`) tag.
    UnknownTag(u8),
    /// The frame is not as long as its tag and count say.
    Length {
        /// Bytes the frame should have.
        expected: usize,
        /// Bytes it has.
        got: usize,
    },
    /// A refill's count is above [`MAX_REFILL`].
    TooManyItems(u8),
    /// The CRC does not match: the frame was damaged.
    Checksum {
        /// The CRC carried in the frame.
        carried: u16,
        /// The CRC of the bytes received.
        computed: u16,
    },
    /// A flag byte has bits set that mean nothing.
    ReservedFlags(u8),
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Empty => write!(f, "empty frame"),
            Self::UnknownTag(tag) => {
                write!(f, "unknown frame tag {tag:#04x} (0xa5 report, 0x5a refill)")
            }
            Self::Length { expected, got } => {
                write!(f, "frame length: expected {expected} bytes, got {got}")
            }
            Self::TooManyItems(n) => write!(f, "refill of {n} items (at most {MAX_REFILL})"),
            Self::Checksum { carried, computed } => {
                write!(
                    f,
                    "CRC mismatch: frame carries {carried:#06x}, bytes give {computed:#06x}"
                )
            }
            Self::ReservedFlags(flags) => write!(f, "frame flags {flags:#04x} use reserved bits"),
        }
    }
}

impl core::error::Error for DecodeError {}

/// Why a frame could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EncodeError {
    /// The output buffer is too short.
    BufferTooSmall {
        /// Bytes the frame needs.
        needed: usize,
        /// Bytes the buffer has.
        got: usize,
    },
    /// A refill of more than [`MAX_REFILL`] items.
    TooManyItems(usize),
}

impl fmt::Display for EncodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::BufferTooSmall { needed, got } => {
                write!(f, "buffer of {got} bytes, the frame needs {needed}")
            }
            Self::TooManyItems(n) => write!(f, "refill of {n} items (at most {MAX_REFILL})"),
        }
    }
}

impl core::error::Error for EncodeError {}

/// `true` when boot number `candidate` is a **later start** than `than`: it lies 1 to 127
/// ahead of it, wrapping (so 0 is later than 255). A board's boot number increases by one at
/// every start, so a start is later than the 127 before it; `than` itself and the 128 numbers
/// behind it are not later.
///
/// ```
/// use regler_ring_transfer::link::newer_boot;
/// assert!(newer_boot(6, 5) && newer_boot(0, 255) && newer_boot(132, 5));
/// assert!(!newer_boot(5, 5) && !newer_boot(4, 5) && !newer_boot(133, 5));
/// ```
#[must_use]
pub const fn newer_boot(candidate: u8, than: u8) -> bool {
    let ahead = candidate.wrapping_sub(than);
    ahead != 0 && ahead < 0x80
}

/// CRC-16/CCITT-FALSE (polynomial 0x1021, initial value 0xFFFF, no reflection).
#[must_use]
pub fn crc16(bytes: &[u8]) -> u16 {
    let mut crc: u16 = 0xFFFF;
    for &byte in bytes {
        crc ^= u16::from(byte) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 == 0 {
                crc << 1
            } else {
                (crc << 1) ^ 0x1021
            };
        }
    }
    crc
}

fn seal(frame: &mut [u8]) -> Option<()> {
    let (body, tail) = frame.split_at_mut_checked(frame.len().checked_sub(2)?)?;
    tail.copy_from_slice(&crc16(body).to_le_bytes());
    Some(())
}

impl Report {
    /// Writes the 10-byte frame into `out`; returns its length.
    ///
    /// # Errors
    /// [`EncodeError::BufferTooSmall`] when `out` is shorter than [`REPORT_LEN`].
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        let got = out.len();
        let frame = out
            .get_mut(..REPORT_LEN)
            .ok_or(EncodeError::BufferTooSmall {
                needed: REPORT_LEN,
                got,
            })?;
        let [c0, c1] = self.consumed.to_le_bytes();
        let [r0, r1] = self.received.to_le_bytes();
        let mut flags = 0;
        if self.standalone {
            flags |= FLAG_STANDALONE;
        }
        if self.retry {
            flags |= FLAG_RETRY;
        }
        if self.hello {
            flags |= FLAG_HELLO;
        }
        frame.copy_from_slice(&[
            REPORT_TAG, self.slave, c0, c1, r0, r1, flags, self.boot, 0, 0,
        ]);
        seal(frame).map_or(
            Err(EncodeError::BufferTooSmall {
                needed: REPORT_LEN,
                got: 0,
            }),
            |()| Ok(REPORT_LEN),
        )
    }
}

impl Refill<'_> {
    /// Writes the frame (9 + items bytes) into `out`; returns its length.
    ///
    /// # Errors
    /// [`EncodeError::TooManyItems`] for more than [`MAX_REFILL`] items,
    /// [`EncodeError::BufferTooSmall`] when `out` cannot hold the frame.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        let count = u8::try_from(self.items.len())
            .ok()
            .filter(|&n| usize::from(n) <= MAX_REFILL)
            .ok_or(EncodeError::TooManyItems(self.items.len()))?;
        let needed = REFILL_OVERHEAD.saturating_add(self.items.len());
        let got = out.len();
        let frame = out
            .get_mut(..needed)
            .ok_or(EncodeError::BufferTooSmall { needed, got })?;
        let [f0, f1] = self.first.to_le_bytes();
        let (header, rest) = frame.split_at_mut(REFILL_HEADER);
        let flags = if self.sync { FLAG_SYNC } else { 0 };
        header.copy_from_slice(&[REFILL_TAG, self.slave, f0, f1, flags, self.boot, count]);
        let (items, _crc) = rest.split_at_mut(self.items.len());
        items.copy_from_slice(self.items);
        seal(frame).map_or(Err(EncodeError::BufferTooSmall { needed, got }), |()| {
            Ok(needed)
        })
    }
}

/// Checks and decodes one frame: tag, length, count, CRC and flags, in that order; the first
/// rule broken is the error. Never panics, never reads past `bytes`.
///
/// # Errors
/// The [`DecodeError`] naming the rule that failed.
pub fn decode(bytes: &[u8]) -> Result<Message<'_>, DecodeError> {
    let (&tag, _) = bytes.split_first().ok_or(DecodeError::Empty)?;
    let expected = match tag {
        REPORT_TAG => REPORT_LEN,
        REFILL_TAG => {
            let &count = bytes
                .get(REFILL_HEADER.saturating_sub(1))
                .ok_or(DecodeError::Length {
                    expected: REFILL_OVERHEAD,
                    got: bytes.len(),
                })?;
            if usize::from(count) > MAX_REFILL {
                return Err(DecodeError::TooManyItems(count));
            }
            REFILL_OVERHEAD.saturating_add(usize::from(count))
        }
        other => return Err(DecodeError::UnknownTag(other)),
    };
    if bytes.len() != expected {
        return Err(DecodeError::Length {
            expected,
            got: bytes.len(),
        });
    }
    let (body, crc) =
        bytes
            .split_at_checked(expected.saturating_sub(2))
            .ok_or(DecodeError::Length {
                expected,
                got: bytes.len(),
            })?;
    let carried = match *crc {
        [a, b] => u16::from_le_bytes([a, b]),
        _ => {
            return Err(DecodeError::Length {
                expected,
                got: bytes.len(),
            });
        }
    };
    let computed = crc16(body);
    if carried != computed {
        return Err(DecodeError::Checksum { carried, computed });
    }
    match *body {
        [REPORT_TAG, slave, c0, c1, r0, r1, flags, boot] => {
            if flags & !(FLAG_STANDALONE | FLAG_RETRY | FLAG_HELLO) != 0 {
                return Err(DecodeError::ReservedFlags(flags));
            }
            Ok(Message::Report(Report {
                slave,
                consumed: u16::from_le_bytes([c0, c1]),
                received: u16::from_le_bytes([r0, r1]),
                standalone: flags & FLAG_STANDALONE != 0,
                retry: flags & FLAG_RETRY != 0,
                boot,
                hello: flags & FLAG_HELLO != 0,
            }))
        }
        [
            REFILL_TAG,
            slave,
            f0,
            f1,
            flags,
            boot,
            _count,
            ref items @ ..,
        ] => {
            if flags & !FLAG_SYNC != 0 {
                return Err(DecodeError::ReservedFlags(flags));
            }
            Ok(Message::Refill(Refill {
                slave,
                first: u16::from_le_bytes([f0, f1]),
                items,
                boot,
                sync: flags & FLAG_SYNC != 0,
            }))
        }
        _ => Err(DecodeError::Length {
            expected,
            got: bytes.len(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_check_value() {
        // The catalogue's check value for CRC-16/CCITT-FALSE ("123456789").
        assert_eq!(crc16(b"123456789"), 0x29B1);
    }

    #[test]
    fn round_trips() {
        let report = Report {
            slave: 7,
            consumed: 65_535,
            received: 3,
            standalone: true,
            retry: false,
            boot: 200,
            hello: true,
        };
        let mut buf = [0; MAX_FRAME];
        let n = report.encode(&mut buf).unwrap();
        assert_eq!(decode(&buf[..n]), Ok(Message::Report(report)));
        let items = [1, 2, 3, 255];
        let refill = Refill {
            slave: 2,
            first: 40_000,
            items: &items,
            boot: 17,
            sync: true,
        };
        let n = refill.encode(&mut buf).unwrap();
        assert_eq!(n, 13);
        assert_eq!(decode(&buf[..n]), Ok(Message::Refill(refill)));
        let keep_alive = Refill::keep_alive(2);
        let n = keep_alive.encode(&mut buf).unwrap();
        assert_eq!(decode(&buf[..n]), Ok(Message::Refill(keep_alive)));
    }

    #[test]
    fn error_messages_name_the_problem() {
        let mut buf = [0; MAX_FRAME];
        let crc = {
            let n = Refill::keep_alive(1).encode(&mut buf).unwrap();
            buf[2] ^= 0x01;
            decode(&buf[..n]).unwrap_err()
        };
        let DecodeError::Checksum { carried, computed } = crc else {
            panic!("{crc:?}");
        };
        let decode_cases = [
            (decode(&[]).unwrap_err(), "empty frame".to_string()),
            (
                decode(&[0x00]).unwrap_err(),
                "unknown frame tag 0x00 (0xa5 report, 0x5a refill)".to_string(),
            ),
            (
                decode(&[REPORT_TAG, 1]).unwrap_err(),
                "frame length: expected 10 bytes, got 2".to_string(),
            ),
            (
                decode(&[REFILL_TAG, 1, 0, 0, 0, 0, 65]).unwrap_err(),
                "refill of 65 items (at most 64)".to_string(),
            ),
            (
                crc,
                format!("CRC mismatch: frame carries {carried:#06x}, bytes give {computed:#06x}"),
            ),
            (
                DecodeError::ReservedFlags(0x80),
                "frame flags 0x80 use reserved bits".to_string(),
            ),
        ];
        for (error, message) in decode_cases {
            assert_eq!(error.to_string(), message, "{error:?}");
        }
        let encode_cases = [
            (
                Refill {
                    items: &[0; 4],
                    ..Refill::keep_alive(0)
                }
                .encode(&mut buf[..12])
                .unwrap_err(),
                "buffer of 12 bytes, the frame needs 13",
            ),
            (
                Refill {
                    items: &[0; 65],
                    ..Refill::keep_alive(0)
                }
                .encode(&mut buf)
                .unwrap_err(),
                "refill of 65 items (at most 64)",
            ),
        ];
        for (error, message) in encode_cases {
            assert_eq!(error.to_string(), message, "{error:?}");
        }
    }

    #[test]
    fn every_rule_has_its_error() {
        let mut buf = [0; MAX_FRAME];
        assert_eq!(decode(&[]), Err(DecodeError::Empty));
        assert_eq!(decode(&[0x00]), Err(DecodeError::UnknownTag(0)));
        assert_eq!(
            decode(&[REPORT_TAG, 1]),
            Err(DecodeError::Length {
                expected: 10,
                got: 2
            })
        );
        assert_eq!(
            decode(&[REFILL_TAG, 1, 0]),
            Err(DecodeError::Length {
                expected: 9,
                got: 3
            })
        );
        assert_eq!(
            decode(&[REFILL_TAG, 1, 0, 0, 0, 0, 65]),
            Err(DecodeError::TooManyItems(65))
        );
        let n = Report {
            slave: 1,
            consumed: 2,
            received: 3,
            standalone: false,
            retry: true,
            boot: 0,
            hello: false,
        }
        .encode(&mut buf)
        .unwrap();
        buf[2] ^= 0x10;
        assert!(matches!(
            decode(&buf[..n]),
            Err(DecodeError::Checksum { .. })
        ));
        buf[2] ^= 0x10;
        buf[6] = 0x80;
        let crc = crc16(&buf[..8]).to_le_bytes();
        buf[8..10].copy_from_slice(&crc);
        assert_eq!(decode(&buf[..n]), Err(DecodeError::ReservedFlags(0x80)));
        let n = Refill::keep_alive(1).encode(&mut buf).unwrap();
        buf[4] = 0x02;
        let crc = crc16(&buf[..n - 2]).to_le_bytes();
        buf[n - 2..n].copy_from_slice(&crc);
        assert_eq!(decode(&buf[..n]), Err(DecodeError::ReservedFlags(0x02)));
        assert_eq!(
            Refill {
                items: &[0; 65],
                ..Refill::keep_alive(0)
            }
            .encode(&mut buf),
            Err(EncodeError::TooManyItems(65))
        );
        assert_eq!(
            Refill {
                items: &[0; 4],
                ..Refill::keep_alive(0)
            }
            .encode(&mut buf[..12]),
            Err(EncodeError::BufferTooSmall {
                needed: 13,
                got: 12
            })
        );
    }

    #[test]
    #[cfg_attr(
        miri,
        ignore = "exhaustive sweep of every 1- and 2-bit error: hours under Miri; safe code, run natively"
    )]
    fn every_error_of_one_and_two_bits_is_caught() {
        // Exhaustive over every position of a report and of a 4-item refill.
        let mut frames: [([u8; MAX_FRAME], usize); 2] = [([0; MAX_FRAME], 0); 2];
        frames[0].1 = Report {
            slave: 9,
            consumed: 513,
            received: 770,
            standalone: false,
            retry: false,
            boot: 3,
            hello: false,
        }
        .encode(&mut frames[0].0)
        .unwrap();
        frames[1].1 = Refill {
            slave: 9,
            first: 1234,
            items: &[0xAA, 0x55, 0, 0xFF],
            boot: 3,
            sync: true,
        }
        .encode(&mut frames[1].0)
        .unwrap();
        for (frame, n) in frames {
            let original = decode(&frame[..n]).unwrap();
            let bits = n * 8;
            for i in 0..bits {
                for j in i..bits {
                    let mut damaged = frame;
                    damaged[i / 8] ^= 1 << (i % 8);
                    if j != i {
                        damaged[j / 8] ^= 1 << (j % 8);
                    }
                    let decoded = decode(&damaged[..n]);
                    assert!(
                        decoded.is_err(),
                        "bits {i},{j}: {decoded:?} (was {original:?})"
                    );
                }
            }
        }
    }
}
