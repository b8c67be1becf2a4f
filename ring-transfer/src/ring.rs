//! The slave's ring: `receive` at RP, `next` at SP, one refill owed per free slot.

use heapless::Deque;

/// What a ring has seen since it was made or its statistics were reset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Stats {
    /// `next` calls that found the ring empty (saturating).
    pub underruns: u32,
    /// The fewest items left in the ring right after a consumption (0 after an underrun); the
    /// ring's capacity while nothing has been consumed.
    pub least_slack: usize,
    /// The most refills owed at once, seen at the same moments (`capacity − least_slack`).
    pub most_requests: usize,
}

/// Cumulative, wrapping item counts: what a slave reports so that its master can work out what
/// is owed after any lost, repeated or late message (see [`crate::link::Report`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Counters {
    /// Items accepted by `receive` (RP advanced), wrapping at 2³².
    pub received: u32,
    /// Items handed out by `next` (SP advanced), wrapping at 2³².
    pub consumed: u32,
}

/// The source's ring of 2N bytes, here `N` slots of any `T`.
///
/// `receive` stores at RP, `next` takes at SP. Whenever RP ≠ SP — whenever a slot is free — a
/// refill is owed: [`requests`](Self::requests) is the number owed, [`slack`](Self::slack) the
/// number of items left before an underrun, and [`deadline`](Self::deadline) the source's
/// `[2N − (SP − RP)]·t0` bound within which the master must deliver. The longest permitted wait
/// is `(N − 1)·t0`, reached right after the first consumption from a full ring.
///
/// The bound leaves one consumption period of margin: with `slack` items left, the item
/// requested now is taken at the `(slack + 1)`-th consumption from now. The master's scheduler
/// and the capacity check use the source's bound, so a set they call schedulable never comes
/// within one item of an underrun.
///
/// For a ring filled in an interrupt and drained in the main loop use [`crate::SharedRing`].
///
/// ```
/// use regler_ring_transfer::Ring;
///
/// let mut ring: Ring<u8, 4> = Ring::new();
/// for byte in [1, 2, 3, 4] {
///     ring.receive(byte).map_err(|_| "full")?;
/// }
/// assert_eq!(ring.receive(5), Err(5)); // full: the item is handed back
/// assert_eq!(ring.next(), Some(1));
/// assert_eq!((ring.requests(), ring.slack()), (1, 3));
/// assert_eq!(ring.deadline(2_300), 6_900); // 3 items of 2.3 ms each, in µs
/// # Ok::<(), &str>(())
/// ```
#[derive(Debug, Clone)]
pub struct Ring<T, const N: usize> {
    items: Deque<T, N>,
    counters: Counters,
    underruns: u32,
    least_slack: usize,
}

impl<T, const N: usize> Default for Ring<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T, const N: usize> Ring<T, N> {
    /// An empty ring (the master's first fill follows). `const`, so it can live in a `static`.
    /// `N` must be at least 1 (checked when the program is compiled).
    #[must_use]
    pub const fn new() -> Self {
        Self {
            items: Deque::new(),
            counters: Counters {
                received: 0,
                consumed: 0,
            },
            underruns: 0,
            least_slack: N,
        }
    }

    /// Stores `item` at RP. A full ring hands the item back and changes nothing.
    ///
    /// # Errors
    /// `Err(item)` when all `N` slots hold items.
    pub fn receive(&mut self, item: T) -> Result<(), T> {
        self.items.push_back(item)?;
        self.counters.received = self.counters.received.wrapping_add(1);
        Ok(())
    }

    /// Takes the item at SP. `None` is an underrun and is counted.
    #[allow(
        clippy::should_implement_trait,
        reason = "the contract's name for SP+1→SP; a Ring is not an iterator (None does not end it)"
    )]
    pub fn next(&mut self) -> Option<T> {
        if let Some(item) = self.items.pop_front() {
            self.counters.consumed = self.counters.consumed.wrapping_add(1);
            self.least_slack = self.least_slack.min(self.items.len());
            Some(item)
        } else {
            self.underruns = self.underruns.saturating_add(1);
            self.least_slack = 0;
            None
        }
    }

    /// Refills owed to this ring: one per free slot (the source's "RP ≠ SP").
    #[must_use]
    pub fn requests(&self) -> usize {
        N.saturating_sub(self.items.len())
    }

    /// Items left before an underrun.
    #[must_use]
    pub fn slack(&self) -> usize {
        self.items.len()
    }

    /// The time within which the master must answer a request made now: `slack · t0`, where `t0`
    /// is the time per item consumed in any unit (saturating). 0 means the next `next` underruns
    /// unless an item arrives first.
    #[must_use]
    pub fn deadline(&self, t0: u32) -> u64 {
        u64::try_from(self.items.len())
            .map_or(u64::MAX, |slack| slack.saturating_mul(u64::from(t0)))
    }

    /// The number of slots, `N`.
    #[must_use]
    pub const fn capacity(&self) -> usize {
        N
    }

    /// Items held (the same as [`slack`](Self::slack)).
    #[must_use]
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// `true` when the next `next` would underrun.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// `true` when no refill is owed.
    #[must_use]
    pub fn is_full(&self) -> bool {
        self.items.is_full()
    }

    /// Underruns, least slack and most requests outstanding.
    #[must_use]
    pub fn stats(&self) -> Stats {
        Stats {
            underruns: self.underruns,
            least_slack: self.least_slack,
            most_requests: N.saturating_sub(self.least_slack),
        }
    }

    /// Starts the statistics afresh (the counters keep counting).
    pub fn reset_stats(&mut self) {
        self.underruns = 0;
        self.least_slack = self.items.len();
    }

    /// The cumulative received and consumed counts.
    #[must_use]
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// Drops every item held (a re-initialised interface); counters and statistics stay.
    pub fn clear(&mut self) {
        self.items.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sources_pointer_rule() {
        // After the first fill RP = SP; each consumption makes one request, each refill clears one.
        let mut ring: Ring<u8, 8> = Ring::new();
        assert_eq!(ring.requests(), 8);
        for b in 0..8 {
            ring.receive(b).unwrap();
        }
        assert_eq!((ring.requests(), ring.slack()), (0, 8));
        assert_eq!(ring.next(), Some(0));
        // The longest permitted wait: (2N − 1)·t0 in the source's terms, (N − 1)·t0 here.
        assert_eq!(ring.deadline(10), 70);
        assert_eq!(ring.stats().most_requests, 1);
        for _ in 0..7 {
            ring.next().unwrap();
        }
        assert_eq!(ring.deadline(10), 0);
        assert_eq!(ring.next(), None);
        assert_eq!(
            ring.stats(),
            Stats {
                underruns: 1,
                least_slack: 0,
                most_requests: 8
            }
        );
        assert_eq!(
            ring.counters(),
            Counters {
                received: 8,
                consumed: 8
            }
        );
    }

    #[test]
    fn a_full_ring_hands_the_item_back_and_keeps_its_own() {
        let mut ring: Ring<u16, 2> = Ring::new();
        ring.receive(1).unwrap();
        ring.receive(2).unwrap();
        assert_eq!(ring.receive(3), Err(3));
        assert_eq!(ring.counters().received, 2);
        assert_eq!(
            (ring.next(), ring.next(), ring.next()),
            (Some(1), Some(2), None)
        );
    }

    #[test]
    fn deadline_saturates() {
        let mut ring: Ring<u8, 3> = Ring::new();
        ring.receive(0).unwrap();
        ring.receive(0).unwrap();
        assert_eq!(ring.deadline(u32::MAX), 2 * u64::from(u32::MAX));
    }
}
