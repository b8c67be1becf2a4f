//! The 13-cam code word: 12 number cams and one parity cam, even parity.

use core::fmt;
use core::num::NonZeroU16;

/// Number of number cams (bits 0–11 of the code word, bit 0 least significant).
pub const NUMBER_BITS: u32 = 12;
/// Bit position of the parity cam.
pub const PARITY_BIT: u32 = 12;
/// Mask of the number cams.
pub const NUMBER_MASK: u16 = 0x0FFF;
/// Mask of all 13 cams (number and parity).
pub const CODE_MASK: u16 = 0x1FFF;

/// A trolley number, 1 to 4095: what the 12 number cams of a trolley carry.
///
/// 0 is not a trolley (a reader that sees no cams sees no trolley), so the type cannot hold it,
/// and `Option<TrolleyId>` is as small as `TrolleyId`.
///
/// ```
/// use regler_trolley_id::TrolleyId;
/// let id = TrolleyId::try_from(1977)?;
/// assert_eq!(id.get(), 1977);
/// assert!(TrolleyId::new(0).is_none());
/// assert!(TrolleyId::new(4096).is_none());
/// # Ok::<(), regler_trolley_id::InvalidTrolleyNumber>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "u16", into = "u16"))]
pub struct TrolleyId(NonZeroU16);

impl TrolleyId {
    /// The lowest trolley number.
    pub const MIN: TrolleyId = TrolleyId(NonZeroU16::MIN);
    /// The highest trolley number the 12 number cams can carry (4095).
    pub const MAX: TrolleyId = match NonZeroU16::new(NUMBER_MASK) {
        Some(n) => TrolleyId(n),
        None => TrolleyId(NonZeroU16::MIN), // ok: NUMBER_MASK is not zero; never taken
    };

    /// The trolley with number `n`: `Some` for 1..=4095, `None` otherwise.
    #[must_use]
    pub const fn new(n: u16) -> Option<TrolleyId> {
        if n > NUMBER_MASK {
            return None;
        }
        match NonZeroU16::new(n) {
            Some(n) => Some(TrolleyId(n)),
            None => None,
        }
    }

    /// The trolley number, 1..=4095.
    #[must_use]
    pub const fn get(self) -> u16 {
        self.0.get()
    }

    /// Every trolley number in ascending order, 1 to 4095.
    pub fn all() -> impl DoubleEndedIterator<Item = TrolleyId> + Clone {
        (1..=NUMBER_MASK).filter_map(TrolleyId::new)
    }
}

impl fmt::Display for TrolleyId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "trolley {}", self.get())
    }
}

impl From<TrolleyId> for u16 {
    fn from(id: TrolleyId) -> u16 {
        id.get()
    }
}

impl TryFrom<u16> for TrolleyId {
    type Error = InvalidTrolleyNumber;
    fn try_from(n: u16) -> Result<TrolleyId, InvalidTrolleyNumber> {
        TrolleyId::new(n).ok_or(InvalidTrolleyNumber(n))
    }
}

/// A number that is not a trolley number (0 or above 4095).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct InvalidTrolleyNumber(pub u16);

impl fmt::Display for InvalidTrolleyNumber {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "trolley numbers run from 1 to 4095, got {}", self.0)
    }
}

impl core::error::Error for InvalidTrolleyNumber {}

/// Why a code word read at a reader does not name a trolley.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum ReadError {
    /// No cam was seen: there is no trolley at the reader.
    NoCams,
    /// The 13 cams hold an odd number of ones: at least one cam was misread.
    Parity {
        /// The word as read.
        raw: u16,
    },
    /// Bits above the 13 cam positions are set: the reader or its wiring is faulty.
    BitsAboveCode {
        /// The word as read.
        raw: u16,
    },
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ReadError::NoCams => f.write_str("no cams seen: no trolley at the reader"),
            ReadError::Parity { raw } => {
                write!(
                    f,
                    "parity error in code word {raw:#06x}: odd number of cams seen"
                )
            }
            ReadError::BitsAboveCode { raw } => write!(
                f,
                "code word {raw:#06x} has bits set above the 13 cam positions (mask {CODE_MASK:#06x})"
            ),
        }
    }
}

impl core::error::Error for ReadError {}

/// Decodes one reading of the 13 cams into a trolley number.
///
/// Checks, in this order: no bit above bit 12 ([`ReadError::BitsAboveCode`]), at least one cam
/// ([`ReadError::NoCams`]), even parity over all 13 bits ([`ReadError::Parity`]). A word that
/// passes all three always names a trolley: the only 13-bit word with number 0 and a cam is
/// the lone parity cam, which has odd parity.
///
/// Parity detects every odd number of misread cams; an even number (two cams missed, say)
/// decodes to another trolley, which is why [`Voter`](crate::Voter) exists.
///
/// ```
/// use regler_trolley_id::{decode, encode, ReadError, TrolleyId};
/// let id = TrolleyId::try_from(0b1011)?; // three ones: parity cam set
/// assert_eq!(encode(id), 0b1_0000_0000_1011);
/// assert_eq!(decode(0b1_0000_0000_1011), Ok(id));
/// assert_eq!(decode(0b0_0000_0000_1011), Err(ReadError::Parity { raw: 0b1011 }));
/// assert_eq!(decode(0), Err(ReadError::NoCams));
/// # Ok::<(), regler_trolley_id::InvalidTrolleyNumber>(())
/// ```
pub const fn decode(raw: u16) -> Result<TrolleyId, ReadError> {
    if raw & !CODE_MASK != 0 {
        return Err(ReadError::BitsAboveCode { raw });
    }
    if raw == 0 {
        return Err(ReadError::NoCams);
    }
    if !raw.count_ones().is_multiple_of(2) {
        return Err(ReadError::Parity { raw });
    }
    match TrolleyId::new(raw & NUMBER_MASK) {
        Some(id) => Ok(id),
        // ok: unreachable in fact (0x1000 has odd parity), reported as the parity error it is.
        None => Err(ReadError::Parity { raw }),
    }
}

/// The 13-bit code word carried by a trolley's cams: the number in bits 0–11 and the parity
/// cam in bit 12, set when the number has an odd count of ones.
#[must_use]
pub const fn encode(id: TrolleyId) -> u16 {
    let number = id.get();
    let parity = (number.count_ones() % 2) as u16;
    number | (parity << PARITY_BIT)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every 13-bit word, and a sample of wider ones, against a straightforward model.
    #[test]
    fn decode_all_8192_code_words() {
        let mut trolleys = 0;
        // Under Miri every 61st word (both parities, 135 words).
        let step = if cfg!(miri) { 61 } else { 1 };
        for raw in (0u16..=CODE_MASK).step_by(step) {
            let ones = (0..13).filter(|b| raw >> b & 1 == 1).count();
            let got = decode(raw);
            if raw == 0 {
                assert_eq!(got, Err(ReadError::NoCams));
            } else if ones % 2 == 1 {
                assert_eq!(got, Err(ReadError::Parity { raw }), "{raw:#x}");
            } else {
                let id = got.unwrap();
                assert_eq!(id.get(), raw & 0xFFF);
                assert_eq!(encode(id), raw);
                trolleys += 1;
            }
        }
        assert!(trolleys == 4095 || (cfg!(miri) && trolleys > 0));
    }

    #[test]
    fn bits_above_code_are_rejected_for_every_high_pattern() {
        for high in 1u16..=7 {
            for low in [0u16, 1, 0x1001, 0x1FFF, 0x0003] {
                let raw = high << 13 | low;
                assert_eq!(decode(raw), Err(ReadError::BitsAboveCode { raw }));
            }
        }
    }

    #[test]
    fn encode_round_trips_every_trolley() {
        assert_eq!(TrolleyId::all().count(), 4095);
        for id in TrolleyId::all() {
            let raw = encode(id);
            assert_eq!(raw.count_ones() % 2, 0);
            assert_eq!(raw & !CODE_MASK, 0);
            assert_eq!(decode(raw), Ok(id));
        }
    }

    #[test]
    #[cfg_attr(
        miri,
        ignore = "exhaustive: every trolley × every cam, 53 000 decodes: hours under Miri; safe code, run natively in every CI run"
    )]
    fn single_cam_errors_are_always_detected() {
        for id in TrolleyId::all() {
            for bit in 0..13 {
                let raw = encode(id) ^ (1 << bit);
                assert!(decode(raw).is_err(), "{id} bit {bit}");
            }
        }
    }

    #[test]
    fn new_bounds_and_conversions() {
        assert_eq!(TrolleyId::MIN.get(), 1);
        assert_eq!(TrolleyId::MAX.get(), 4095);
        assert_eq!(TrolleyId::try_from(0), Err(InvalidTrolleyNumber(0)));
        assert_eq!(u16::from(TrolleyId::try_from(12).unwrap()), 12);
        assert_eq!(core::mem::size_of::<Option<TrolleyId>>(), 2);
    }

    #[test]
    fn errors_say_what_was_wrong() {
        assert!(
            ReadError::Parity { raw: 0x0001 }
                .to_string()
                .contains("0x0001")
        );
        assert!(
            ReadError::BitsAboveCode { raw: 0x2000 }
                .to_string()
                .contains("0x2000")
        );
        assert!(InvalidTrolleyNumber(4096).to_string().contains("4096"));
    }
}
