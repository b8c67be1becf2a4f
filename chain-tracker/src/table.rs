//! The stretch correction DA = SA·DIA/SIA and the distance table it keeps current.

use core::fmt;

/// Why [`correct`] could not give a distance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum CorrectionError {
    /// SIA, the original pulse count between the initiators, is 0.
    ZeroReference,
    /// SA·DIA/SIA does not fit a `u32`.
    Overflow {
        /// Static distance.
        sa: u32,
        /// Measured pulses between the initiators.
        dia: u32,
        /// Original pulses between the initiators.
        sia: u32,
    },
}

impl fmt::Display for CorrectionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            CorrectionError::ZeroReference => {
                f.write_str("SIA (original pulses between the initiators) must not be 0")
            }
            CorrectionError::Overflow { sa, dia, sia } => {
                write!(f, "SA·DIA/SIA = {sa}·{dia}/{sia} does not fit in 32 bits")
            }
        }
    }
}

impl core::error::Error for CorrectionError {}

/// The source's chain-length correction: `DA = SA × DIA / SIA`, rounded half up.
///
/// `sa` is a static (original) distance in pulses, `sia` the original pulse count between the
/// two reference initiators, `dia` the count measured now. The product is formed in 64 bits, so
/// the result is exact for every `u32` input; it is an error when `sia` is 0 or the result
/// exceeds `u32::MAX`.
///
/// ```
/// use regler_chain_tracker::{correct, CorrectionError};
/// // 4 000 pulses to the far tipper; the chain stretched 0.5 %: 3 000 → 2 985 pulses between the initiators.
/// assert_eq!(correct(4000, 2985, 3000), Ok(3980));
/// assert_eq!(correct(1, 1, 2), Ok(1)); // one half rounds up
/// assert_eq!(correct(5, 1, 0), Err(CorrectionError::ZeroReference));
/// ```
pub const fn correct(sa: u32, dia: u32, sia: u32) -> Result<u32, CorrectionError> {
    if sia == 0 {
        return Err(CorrectionError::ZeroReference);
    }
    // (2^32 - 1)^2 < 2^64: the product cannot overflow; quotient and remainder are exact.
    let product = (sa as u64).wrapping_mul(dia as u64);
    let divisor = sia as u64;
    let (quotient, remainder) = match (product.checked_div(divisor), product.checked_rem(divisor)) {
        (Some(q), Some(r)) => (q, r),
        _ => return Err(CorrectionError::ZeroReference), // ok: sia != 0 was checked above
    };
    // Half up: the remainder is at least half the divisor. remainder < 2^32, so 2·remainder fits.
    let rounded = if remainder.wrapping_mul(2) >= divisor {
        quotient.saturating_add(1)
    } else {
        quotient
    };
    if rounded > u32::MAX as u64 {
        return Err(CorrectionError::Overflow { sa, dia, sia });
    }
    #[allow(
        clippy::cast_possible_truncation,
        reason = "checked against u32::MAX just above"
    )]
    Ok(rounded as u32)
}

/// Why a [`DistanceTable`] could not be built or recalibrated. The table is unchanged.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum TableError {
    /// More static distances than the table has room for.
    TooManyTippers {
        /// Distances given.
        given: usize,
        /// The table's capacity `T`.
        capacity: usize,
    },
    /// SIA is 0.
    ZeroReference,
    /// A measured DIA of 0: no chain between the initiators is not a measurement.
    ZeroMeasurement,
    /// The corrected distance of `tipper` does not fit a `u32`.
    Overflow {
        /// The tipper whose distance overflowed.
        tipper: usize,
    },
}

impl fmt::Display for TableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            TableError::TooManyTippers { given, capacity } => {
                write!(
                    f,
                    "{given} tipper distances given, the table holds {capacity}"
                )
            }
            TableError::ZeroReference => {
                f.write_str("SIA (original pulses between the initiators) must not be 0")
            }
            TableError::ZeroMeasurement => {
                f.write_str("DIA (measured pulses between the initiators) must not be 0")
            }
            TableError::Overflow { tipper } => {
                write!(
                    f,
                    "corrected distance of tipper {tipper} does not fit in 32 bits"
                )
            }
        }
    }
}

impl core::error::Error for TableError {}

/// Distances from the code reader to each tipper: the static list SA measured when the chain was
/// new, and the dynamic list DA = SA·DIA/SIA recomputed whenever the measured DIA changes.
///
/// Tracking reads the dynamic list, as in the source. `T` is the number of tippers it can hold.
///
/// ```
/// use regler_chain_tracker::DistanceTable;
/// let mut table: DistanceTable<4> = DistanceTable::new(3000, &[100, 2000, 4000])?;
/// assert_eq!(table.distance(2), Some(4000));
/// assert!(table.recalibrate(2985)?); // the chain stretched
/// assert_eq!(table.distance(2), Some(3980));
/// assert_eq!(table.static_distance(2), Some(4000));
/// assert_eq!(table.stretch_per_mille(), 5);
/// # Ok::<(), regler_chain_tracker::TableError>(())
/// ```
///
/// A `DistanceTable<T>` is `8·T + 8` bytes plus a `usize` (two lists of `T` distances, SIA,
/// DIA and the number of tippers), and [`new`](DistanceTable::new) is a `const fn`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DistanceTable<const T: usize> {
    sia: u32,
    dia: u32,
    len: usize,
    /// Entries beyond `len` are 0, so the derived equality compares only the lists.
    sa: [u32; T],
    da: [u32; T],
}

impl<const T: usize> DistanceTable<T> {
    /// A table for a new chain: `sia` pulses between the initiators and `sa[i]` pulses from the
    /// reader to tipper `i`. DIA starts equal to SIA, so DA equals SA.
    pub const fn new(sia: u32, sa: &[u32]) -> Result<DistanceTable<T>, TableError> {
        if sia == 0 {
            return Err(TableError::ZeroReference);
        }
        if sa.len() > T {
            return Err(TableError::TooManyTippers {
                given: sa.len(),
                capacity: T,
            });
        }
        let mut list = [0u32; T];
        let (mut rest, mut i) = (sa, 0usize);
        while let [first, tail @ ..] = rest {
            if i < T {
                #[allow(clippy::indexing_slicing, reason = "i < T just checked")]
                {
                    list[i] = *first;
                }
            }
            rest = tail;
            i = i.saturating_add(1);
        }
        Ok(DistanceTable {
            sia,
            dia: sia,
            len: sa.len(),
            sa: list,
            da: list,
        })
    }

    /// Takes a new DIA. Returns `Ok(true)` when the dynamic list was recomputed, `Ok(false)` when
    /// DIA did not change; on an error nothing changes.
    pub fn recalibrate(&mut self, dia: u32) -> Result<bool, TableError> {
        if dia == self.dia {
            return Ok(false);
        }
        self.da = self.corrected(dia)?;
        self.dia = dia;
        Ok(true)
    }

    /// The dynamic list DIA would give, without changing the table.
    pub(crate) fn corrected(&self, dia: u32) -> Result<[u32; T], TableError> {
        if dia == 0 {
            return Err(TableError::ZeroMeasurement);
        }
        let mut da = [0u32; T];
        for (tipper, (d, &sa)) in da.iter_mut().zip(self.static_list()).enumerate() {
            // SIA is never 0 (`new` refuses it, nothing else sets it, a table is not
            // deserialized): the only error left is the overflow.
            *d = correct(sa, dia, self.sia).map_err(|_| TableError::Overflow { tipper })?;
        }
        Ok(da)
    }

    fn static_list(&self) -> &[u32] {
        self.sa.get(..self.len).unwrap_or(&[])
    }

    pub(crate) fn commit(&mut self, dia: u32, da: [u32; T]) {
        self.dia = dia;
        self.da = da;
    }

    /// Current (dynamic) distance from the reader to `tipper`, in pulses.
    #[must_use]
    pub fn distance(&self, tipper: usize) -> Option<u32> {
        self.distances().get(tipper).copied()
    }

    /// Original (static) distance from the reader to `tipper`, in pulses.
    #[must_use]
    pub fn static_distance(&self, tipper: usize) -> Option<u32> {
        self.static_list().get(tipper).copied()
    }

    /// The dynamic list.
    #[must_use]
    pub fn distances(&self) -> &[u32] {
        self.da.get(..self.len).unwrap_or(&[])
    }

    /// Number of tippers.
    #[must_use]
    pub const fn tippers(&self) -> usize {
        self.len
    }

    /// SIA: original pulses between the initiators.
    #[must_use]
    pub const fn sia(&self) -> u32 {
        self.sia
    }

    /// DIA: the pulses between the initiators the dynamic list was computed for.
    #[must_use]
    pub const fn dia(&self) -> u32 {
        self.dia
    }

    /// Chain elongation since the static list was taken, per mille, rounded half away from
    /// zero: (SIA − DIA)/DIA. A stretched chain has longer links, so fewer pulses between the
    /// initiators and a positive figure.
    #[must_use]
    pub const fn stretch_per_mille(&self) -> i32 {
        stretch_per_mille(self.sia, self.dia)
    }
}

/// (SIA − DIA)·1000/DIA, rounded half away from zero, saturating; 0 when DIA is 0.
pub(crate) const fn stretch_per_mille(sia: u32, dia: u32) -> i32 {
    let (sia, dia) = (sia as i64, dia as i64);
    // |sia - dia| < 2^32 and 1000·2^32 < 2^63: nothing below can overflow.
    let scaled = sia.wrapping_sub(dia).wrapping_mul(1000);
    let half = dia.wrapping_div(2);
    let rounded = if scaled >= 0 {
        scaled.wrapping_add(half)
    } else {
        scaled.wrapping_sub(half)
    };
    let Some(q) = rounded.checked_div(dia) else {
        return 0;
    };
    // q ≥ −1 001: SIA ≥ 0 makes (SIA − DIA)/DIA ≥ −1, so only the top can leave an `i32`
    // (`stretch_per_mille(0, u32::MAX)` is −1 000).
    if q > i32::MAX as i64 {
        i32::MAX
    } else {
        #[allow(
            clippy::cast_possible_truncation,
            reason = "−1 001 ≤ q ≤ i32::MAX, checked just above"
        )]
        let q = q as i32;
        q
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Half up against exact 128-bit arithmetic.
    fn reference(sa: u32, dia: u32, sia: u32) -> Option<u32> {
        let (sa, dia, sia) = (u128::from(sa), u128::from(dia), u128::from(sia));
        let r = (2 * sa * dia + sia) / (2 * sia);
        u32::try_from(r).ok()
    }

    #[test]
    fn correct_matches_reference_at_the_edges() {
        let edges = [
            0,
            1,
            2,
            3,
            999,
            1000,
            4000,
            65_535,
            65_536,
            u32::MAX / 2,
            u32::MAX - 1,
            u32::MAX,
        ];
        for &sa in &edges {
            for &dia in &edges {
                for &sia in &edges[1..] {
                    match reference(sa, dia, sia) {
                        Some(want) => {
                            assert_eq!(correct(sa, dia, sia), Ok(want), "{sa} {dia} {sia}")
                        }
                        None => assert_eq!(
                            correct(sa, dia, sia),
                            Err(CorrectionError::Overflow { sa, dia, sia })
                        ),
                    }
                }
                assert_eq!(correct(sa, dia, 0), Err(CorrectionError::ZeroReference));
            }
        }
    }

    #[test]
    fn rounding_is_half_up() {
        assert_eq!(correct(3, 1, 2), Ok(2)); // 1.5
        assert_eq!(correct(5, 1, 4), Ok(1)); // 1.25
        assert_eq!(correct(7, 1, 4), Ok(2)); // 1.75
        assert_eq!(correct(u32::MAX, u32::MAX, u32::MAX), Ok(u32::MAX));
        assert_eq!(correct(u32::MAX, 1, 2), Ok(1 << 31)); // 2147483647.5
    }

    #[test]
    fn table_rejects_bad_input_and_keeps_state() {
        assert_eq!(
            DistanceTable::<2>::new(0, &[1]),
            Err(TableError::ZeroReference)
        );
        assert_eq!(
            DistanceTable::<2>::new(10, &[1, 2, 3]),
            Err(TableError::TooManyTippers {
                given: 3,
                capacity: 2
            })
        );
        let mut t = DistanceTable::<2>::new(1, &[5, u32::MAX]).unwrap();
        let before = t;
        assert_eq!(t.recalibrate(2), Err(TableError::Overflow { tipper: 1 }));
        assert_eq!(t.recalibrate(0), Err(TableError::ZeroMeasurement));
        assert_eq!(t, before);
        assert_eq!(t.recalibrate(1), Ok(false));
    }

    /// What a table reports: SIA, DIA, the number of tippers, each static and dynamic
    /// distance (none past the last tipper) and the stretch, before and after recalibrations.
    #[test]
    fn the_table_reports_what_it_holds() {
        let mut t = DistanceTable::<4>::new(3000, &[100, 2000, 4000]).unwrap();
        assert_eq!((t.sia(), t.dia(), t.tippers()), (3000, 3000, 3));
        assert_eq!(t.stretch_per_mille(), 0);
        assert_eq!(t.recalibrate(2985), Ok(true));
        assert_eq!((t.sia(), t.dia(), t.tippers()), (3000, 2985, 3));
        // 100·2985/3000 = 99.5 rounds half up to 100.
        assert_eq!(t.distances(), [100, 1990, 3980]);
        assert_eq!(
            (0..4).map(|i| t.static_distance(i)).collect::<Vec<_>>(),
            [Some(100), Some(2000), Some(4000), None]
        );
        assert_eq!(
            (0..4).map(|i| t.distance(i)).collect::<Vec<_>>(),
            [Some(100), Some(1990), Some(3980), None]
        );
        assert_eq!(t.stretch_per_mille(), 5);
        assert_eq!(t.recalibrate(3015), Ok(true));
        assert_eq!(t.stretch_per_mille(), -5);
        assert_eq!(t.static_distance(2), Some(4000));
    }

    #[test]
    fn stretch_is_signed_and_rounded() {
        assert_eq!(stretch_per_mille(3000, 2985), 5);
        assert_eq!(stretch_per_mille(3000, 3015), -5);
        assert_eq!(stretch_per_mille(3000, 3000), 0);
        assert_eq!(stretch_per_mille(1, 0), 0);
        assert_eq!(stretch_per_mille(u32::MAX, 1), i32::MAX);
        assert_eq!(stretch_per_mille(0, u32::MAX), -1000);
        assert_eq!(stretch_per_mille(0, 1), -1000);
    }

    /// Against the formula in `i128`, rounded half away from zero and saturated, at the ends of
    /// both counts and around them: the lowest value is −1 000 (SIA 0), never near `i32::MIN`.
    #[test]
    fn stretch_matches_the_formula_at_the_ends() {
        let values = [
            0u32,
            1,
            2,
            3,
            999,
            1000,
            2985,
            3000,
            4_294_967,
            1 << 31,
            u32::MAX - 1,
            u32::MAX,
        ];
        for &sia in &values {
            for &dia in &values {
                let want = if dia == 0 {
                    0
                } else {
                    let (s, d) = (i128::from(sia), i128::from(dia));
                    let scaled = (s - d) * 1000;
                    let rounded = if scaled >= 0 {
                        scaled + d / 2
                    } else {
                        scaled - d / 2
                    };
                    let q = rounded / d;
                    i32::try_from(q.clamp(i128::from(i32::MIN), i128::from(i32::MAX))).unwrap()
                };
                assert_eq!(stretch_per_mille(sia, dia), want, "SIA {sia}, DIA {dia}");
                assert!(want >= -1000);
            }
        }
    }
}
