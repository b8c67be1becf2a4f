//! Trolley → destination: the cell per trolley of the 1977 plant, with plausibility checks.

use core::fmt;

use crate::code::{NUMBER_MASK, TrolleyId};
use crate::voter::{NoRead, Verdict};

/// Number of cells in a [`Registry`]: one per 12-bit number (cell 0 is never used).
pub const REGISTRY_CELLS: usize = NUMBER_MASK as usize + 1;

/// The destination of every trolley in the plant, one cell per trolley number.
///
/// As in the source, the destination is stored in a cell unique to the trolley, so a look-up is
/// one array access whatever the number of trolleys. The registry takes
/// `4096 × size_of::<Option<D>>()` bytes (8 KiB for a `u8` destination), inline and fixed.
///
/// [`route`](Registry::route) is the decision a reader makes: deliver an identified trolley that
/// has a plausible destination, send everything else to the reject path.
///
/// ```
/// use regler_trolley_id::{Registry, Route, RejectReason, TrolleyId, Verdict};
/// let mut registry: Registry<u8> = Registry::new();
/// let t = TrolleyId::try_from(42)?;
/// registry.assign(t, 17); // the operator keyed bin 17 at the loading desk
/// assert_eq!(
///     registry.route(&Verdict::Identified(t), |_| true),
///     Route::Deliver { trolley: t, destination: 17 }
/// );
/// let stranger = TrolleyId::try_from(43)?;
/// assert_eq!(
///     registry.route(&Verdict::Identified(stranger), |_| true),
///     Route::Reject(RejectReason::NoDestination(stranger))
/// );
/// # Ok::<(), regler_trolley_id::InvalidTrolleyNumber>(())
/// ```
#[derive(Clone, Debug)]
pub struct Registry<D> {
    cells: [Option<D>; REGISTRY_CELLS],
    len: usize,
}

/// Where a reader sends a trolley.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Route<D> {
    /// Toward `destination`.
    Deliver {
        /// The identified trolley.
        trolley: TrolleyId,
        /// Its registered destination.
        destination: D,
    },
    /// To the reject path, for a person to look at.
    Reject(RejectReason<D>),
}

/// Why a trolley goes to the reject path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum RejectReason<D> {
    /// The reading gave no trolley number.
    NoRead(NoRead),
    /// The number read has no destination: most likely a misread of another trolley.
    NoDestination(TrolleyId),
    /// The number read has a destination this reader cannot lead to: a misread, or a trolley
    /// on the wrong path.
    Implausible {
        /// The number read.
        trolley: TrolleyId,
        /// Its registered destination.
        destination: D,
    },
}

impl<D: fmt::Debug> fmt::Display for RejectReason<D> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RejectReason::NoRead(e) => write!(f, "no-read: {e}"),
            RejectReason::NoDestination(t) => write!(f, "{t} has no destination"),
            RejectReason::Implausible {
                trolley,
                destination,
            } => {
                write!(
                    f,
                    "{trolley} is bound for {destination:?}, which this reader cannot reach"
                )
            }
        }
    }
}

impl<D> Default for Registry<D> {
    fn default() -> Registry<D> {
        Registry::new()
    }
}

impl<D> Registry<D> {
    /// An empty registry: no trolley has a destination.
    #[must_use]
    pub const fn new() -> Registry<D> {
        Registry {
            cells: [const { None }; REGISTRY_CELLS],
            len: 0,
        }
    }

    /// Gives `trolley` a destination; returns the one it had.
    pub fn assign(&mut self, trolley: TrolleyId, destination: D) -> Option<D> {
        let previous = self.cell_mut(trolley).and_then(|c| c.replace(destination));
        if previous.is_none() {
            self.len = self.len.saturating_add(1);
        }
        previous
    }

    /// Takes the destination away from `trolley` (its sack was delivered); returns it.
    pub fn release(&mut self, trolley: TrolleyId) -> Option<D> {
        let previous = self.cell_mut(trolley).and_then(Option::take);
        if previous.is_some() {
            self.len = self.len.saturating_sub(1);
        }
        previous
    }

    /// The destination of `trolley`, if it has one.
    #[must_use]
    pub fn destination(&self, trolley: TrolleyId) -> Option<&D> {
        self.cells
            .get(usize::from(trolley.get()))
            .and_then(Option::as_ref)
    }

    /// Number of trolleys with a destination.
    #[must_use]
    pub const fn len(&self) -> usize {
        self.len
    }

    /// Whether no trolley has a destination.
    #[must_use]
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Every trolley with its destination, in trolley-number order.
    pub fn iter(&self) -> impl Iterator<Item = (TrolleyId, &D)> {
        (0u16..)
            .zip(self.cells.iter())
            .filter_map(|(n, d)| Some((TrolleyId::new(n)?, d.as_ref()?)))
    }

    /// Removes every destination.
    pub fn clear(&mut self) {
        for cell in &mut self.cells {
            *cell = None;
        }
        self.len = 0;
    }

    fn cell_mut(&mut self, trolley: TrolleyId) -> Option<&mut Option<D>> {
        self.cells.get_mut(usize::from(trolley.get()))
    }
}

impl<D: Copy> Registry<D> {
    /// Decides where a trolley goes after a reader's verdict.
    ///
    /// An identified trolley is delivered only if it has a destination and `plausible` accepts
    /// it (e.g. "this reader's dock has that bin", or "the destination is in the active sorting
    /// schedule"); anything else is rejected with the reason.
    pub fn route(&self, verdict: &Verdict, plausible: impl FnOnce(&D) -> bool) -> Route<D> {
        let trolley = match *verdict {
            Verdict::Identified(t) => t,
            Verdict::NoRead(e) => return Route::Reject(RejectReason::NoRead(e)),
        };
        match self.destination(trolley) {
            None => Route::Reject(RejectReason::NoDestination(trolley)),
            Some(&destination) if plausible(&destination) => Route::Deliver {
                trolley,
                destination,
            },
            Some(&destination) => Route::Reject(RejectReason::Implausible {
                trolley,
                destination,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn id(n: u16) -> TrolleyId {
        TrolleyId::new(n).unwrap()
    }

    #[test]
    fn assign_release_and_len() {
        let mut r: Registry<u16> = Registry::new();
        assert!(r.is_empty());
        assert_eq!(r.assign(id(1), 10), None);
        assert_eq!(r.assign(id(4095), 20), None);
        assert!(!r.is_empty());
        assert_eq!(r.assign(id(1), 11), Some(10));
        assert_eq!(r.len(), 2);
        assert_eq!(r.destination(id(1)), Some(&11));
        assert_eq!(r.release(id(1)), Some(11));
        assert_eq!(r.release(id(1)), None);
        assert_eq!(r.len(), 1);
        assert!(!r.is_empty());
        assert_eq!(r.iter().collect::<Vec<_>>(), [(id(4095), &20)]);
        r.clear();
        assert!(r.is_empty());
        assert_eq!(r.destination(id(4095)), None);
    }

    #[test]
    fn route_rejects_no_reads_unknowns_and_implausible_destinations() {
        let mut r: Registry<u8> = Registry::new();
        r.assign(id(3), 2);
        let no_read = Verdict::NoRead(NoRead::NoAgreement);
        assert_eq!(
            r.route(&no_read, |_| true),
            Route::Reject(RejectReason::NoRead(NoRead::NoAgreement))
        );
        assert_eq!(
            r.route(&Verdict::Identified(id(4)), |_| true),
            Route::Reject(RejectReason::NoDestination(id(4)))
        );
        assert_eq!(
            r.route(&Verdict::Identified(id(3)), |&d| d > 5),
            Route::Reject(RejectReason::Implausible {
                trolley: id(3),
                destination: 2
            })
        );
        assert_eq!(
            r.route(&Verdict::Identified(id(3)), |&d| d == 2),
            Route::Deliver {
                trolley: id(3),
                destination: 2
            }
        );
    }
}
