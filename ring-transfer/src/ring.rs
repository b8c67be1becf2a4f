//! The slave's ring: `receive` at RP, `next` at SP, one refill owed per free slot.

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

/// What a [`Ring`] slot holds: a `Copy` item with a value for a slot that holds nothing yet.
///
/// The ring stores its items in a plain array (no `unsafe`, no per-slot flag, so a byte ring of
/// `N` slots is `N` bytes); [`BLANK`](Self::BLANK) fills the array when the ring is made and is
/// never handed out by [`Ring::next`]. Implemented for the integers, `bool`, `char`, the floats,
/// `()`, arrays of items and `Option` of any `Copy` type; for a type of your own give any value:
///
/// ```
/// use regler_ring_transfer::{Item, Ring};
///
/// #[derive(Clone, Copy, Debug, PartialEq)]
/// struct Stitch { colour: u8, needle: u16 }
/// impl Item for Stitch {
///     const BLANK: Self = Stitch { colour: 0, needle: 0 };
/// }
/// let mut ring: Ring<Stitch, 4> = Ring::new();
/// ring.receive(Stitch { colour: 2, needle: 7 }).map_err(|_| "full")?;
/// assert_eq!(ring.next(), Some(Stitch { colour: 2, needle: 7 }));
/// assert_eq!(ring.next(), None); // an underrun, never the blank
/// # Ok::<(), &str>(())
/// ```
pub trait Item: Copy {
    /// The value of a slot that holds nothing yet.
    const BLANK: Self;
}

macro_rules! blank_items {
    ($($t:ty = $v:expr),* $(,)?) => {
        $(impl Item for $t {
            const BLANK: Self = $v;
        })*
    };
}

blank_items!(
    u8 = 0,
    u16 = 0,
    u32 = 0,
    u64 = 0,
    u128 = 0,
    usize = 0,
    i8 = 0,
    i16 = 0,
    i32 = 0,
    i64 = 0,
    i128 = 0,
    isize = 0,
    bool = false,
    char = '\0',
    f32 = 0.0,
    f64 = 0.0,
    () = (),
);

impl<T: Item, const K: usize> Item for [T; K] {
    const BLANK: Self = [T::BLANK; K];
}

impl<T: Copy> Item for Option<T> {
    const BLANK: Self = None;
}

/// The source's ring of 2N bytes, here `N` slots of any [`Item`] (a `Copy` type).
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
/// RP and SP are kept as wrapping 32-bit counts of the items stored and taken, so full and empty
/// are one comparison each; with `N` a power of two the slot is the count's low bits (the fast
/// case), otherwise an index wraps beside it. `N` must be at least 1 and below 2³² (both checked
/// when the program is compiled).
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
#[derive(Clone)]
pub struct Ring<T, const N: usize> {
    items: [T; N],
    /// RP as a count: items stored, wrapping at 2³² (the received counter).
    received: u32,
    /// SP as a count: items taken by `next` or dropped by `clear`, wrapping at 2³².
    taken: u32,
    /// Items dropped by `clear`, wrapping: `consumed = taken − dropped`.
    dropped: u32,
    /// Slot of SP and of RP when `N` is not a power of two (unused otherwise).
    read: usize,
    write: usize,
    underruns: u32,
    /// The least slack as a count (below 2³²: at most `N`).
    least_slack: u32,
}

impl<T, const N: usize> core::fmt::Debug for Ring<T, N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Ring")
            .field("capacity", &N)
            .field("held", &self.received.wrapping_sub(self.taken))
            .field("received", &self.received)
            .field("consumed", &self.taken.wrapping_sub(self.dropped))
            .field("underruns", &self.underruns)
            .field("least_slack", &self.least_slack)
            .finish_non_exhaustive()
    }
}

impl<T: Item, const N: usize> Default for Ring<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Item, const N: usize> Ring<T, N> {
    /// `N` as a count (`N < 2³²`, checked in [`new`](Self::new)).
    #[allow(
        clippy::cast_possible_truncation,
        reason = "N < 2^32 is asserted when the program is compiled"
    )]
    const SLOTS: u32 = N as u32;
    /// A power of two divides 2³², so the slot of a wrapping count is its low bits.
    const POW2: bool = N.is_power_of_two();

    /// An empty ring (the master's first fill follows). `const`, so it can live in a `static`.
    /// `N` must be at least 1 and below 2³² (checked when the program is compiled).
    #[must_use]
    pub const fn new() -> Self {
        const {
            assert!(N >= 1, "a Ring needs N >= 1");
            assert!(
                N as u64 <= u32::MAX as u64,
                "a Ring holds fewer than 2^32 items (its counts are 32-bit)"
            );
        };
        Self {
            items: [T::BLANK; N],
            received: 0,
            taken: 0,
            dropped: 0,
            read: 0,
            write: 0,
            underruns: 0,
            least_slack: Self::SLOTS,
        }
    }

    /// The slot of a count (`N` a power of two) or the index kept beside it.
    #[inline(always)]
    #[allow(
        clippy::cast_possible_truncation,
        reason = "only the low bits are used: N divides 2^32 and fits usize"
    )]
    fn slot(count: u32, index: usize) -> usize {
        if Self::POW2 {
            (count as usize) & N.wrapping_sub(1)
        } else {
            index
        }
    }

    /// The index after `index`, for `N` not a power of two.
    #[inline(always)]
    fn after(index: usize) -> usize {
        let next = index.wrapping_add(1);
        if next == N { 0 } else { next }
    }

    /// Items held, as a count.
    #[inline(always)]
    fn held(&self) -> u32 {
        self.received.wrapping_sub(self.taken)
    }

    /// Stores `item` at RP. A full ring hands the item back and changes nothing.
    ///
    /// # Errors
    /// `Err(item)` when all `N` slots hold items.
    #[inline]
    pub fn receive(&mut self, item: T) -> Result<(), T> {
        // Held is at most N; `>=` rather than `==` spares an inlined caller a constant it would
        // otherwise keep for the full case (one instruction a pair, measured).
        if self.held() >= Self::SLOTS {
            return Err(item);
        }
        if let Some(slot) = self.items.get_mut(Self::slot(self.received, self.write)) {
            *slot = item;
        }
        if !Self::POW2 {
            self.write = Self::after(self.write);
        }
        self.received = self.received.wrapping_add(1);
        Ok(())
    }

    /// Takes the item at SP. `None` is an underrun and is counted.
    #[inline]
    #[allow(
        clippy::should_implement_trait,
        reason = "the contract's name for SP+1→SP; a Ring is not an iterator (None does not end it)"
    )]
    pub fn next(&mut self) -> Option<T> {
        let held = self.held();
        if held == 0 {
            self.underruns = self.underruns.saturating_add(1);
            self.least_slack = 0;
            return None;
        }
        // Always `Some`: the slot index is below N (low bits of the count, or `read`).
        let item = self.items.get(Self::slot(self.taken, self.read)).copied();
        if !Self::POW2 {
            self.read = Self::after(self.read);
        }
        self.taken = self.taken.wrapping_add(1);
        // `held − 1` items are left; a branch, not a store, in the usual case (no new low).
        if held <= self.least_slack {
            self.least_slack = held.wrapping_sub(1);
        }
        item
    }

    /// Refills owed to this ring: one per free slot (the source's "RP ≠ SP").
    #[must_use]
    pub fn requests(&self) -> usize {
        N.saturating_sub(self.len())
    }

    /// Items left before an underrun.
    #[must_use]
    pub fn slack(&self) -> usize {
        self.len()
    }

    /// The time within which the master must answer a request made now: `slack · t0`, where `t0`
    /// is the time per item consumed in any unit (saturating). 0 means the next `next` underruns
    /// unless an item arrives first.
    #[must_use]
    pub fn deadline(&self, t0: u32) -> u64 {
        u64::from(self.held()).saturating_mul(u64::from(t0))
    }

    /// The number of slots, `N`.
    #[must_use]
    pub const fn capacity(&self) -> usize {
        N
    }

    /// Items held (the same as [`slack`](Self::slack)).
    #[must_use]
    #[inline]
    pub fn len(&self) -> usize {
        // At most N, which fits usize.
        usize::try_from(self.held()).unwrap_or(N)
    }

    /// `true` when the next `next` would underrun.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.taken == self.received
    }

    /// `true` when no refill is owed.
    #[must_use]
    pub fn is_full(&self) -> bool {
        self.held() == Self::SLOTS
    }

    /// Underruns, least slack and most requests outstanding.
    #[must_use]
    pub fn stats(&self) -> Stats {
        Stats {
            underruns: self.underruns,
            least_slack: self.least(),
            most_requests: N.saturating_sub(self.least()),
        }
    }

    /// Starts the statistics afresh, as for a new ring: no underruns, and the least slack back
    /// to the capacity until the next consumption (how full the ring is at the reset is not a
    /// sample: an empty ring reset after a `clear` does not read as one that ran dry). The
    /// counters keep counting.
    pub fn reset_stats(&mut self) {
        self.underruns = 0;
        self.least_slack = Self::SLOTS;
    }

    /// The least slack as a `usize` (it is at most `N`).
    fn least(&self) -> usize {
        usize::try_from(self.least_slack).unwrap_or(N)
    }

    /// The cumulative received and consumed counts.
    #[must_use]
    pub fn counters(&self) -> Counters {
        Counters {
            received: self.received,
            consumed: self.taken.wrapping_sub(self.dropped),
        }
    }

    /// Drops every item held (a re-initialised interface); counters and statistics stay.
    pub fn clear(&mut self) {
        self.dropped = self.dropped.wrapping_add(self.held());
        self.taken = self.received;
        self.read = self.write;
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

    /// `capacity` is the number of items a ring takes before it hands one back.
    #[test]
    fn capacity_is_what_a_full_ring_takes() {
        fn taken<const N: usize>() -> (usize, usize) {
            let mut ring: Ring<u8, N> = Ring::new();
            let taken = (0..=N).take_while(|_| ring.receive(7).is_ok()).count();
            (taken, ring.capacity())
        }
        assert_eq!(taken::<1>(), (1, 1));
        assert_eq!(taken::<3>(), (3, 3));
        assert_eq!(taken::<5>(), (5, 5));
    }

    /// The least slack keeps its meaning: the fewest items left right after a consumption, the
    /// capacity before any and again after a reset, 0 after an underrun — and `clear` (no
    /// consumption) does not move it.
    #[test]
    fn least_slack_is_the_fewest_left_after_a_consumption() {
        let mut ring: Ring<u8, 4> = Ring::new();
        assert_eq!(ring.stats().least_slack, 4);
        for b in 0..4 {
            ring.receive(b).unwrap();
        }
        // Filling and emptying without consuming leaves it alone.
        ring.clear();
        assert_eq!(
            (ring.stats().least_slack, ring.stats().most_requests),
            (4, 0)
        );
        for b in 0..4 {
            ring.receive(b).unwrap();
        }
        assert_eq!(ring.next(), Some(0));
        assert_eq!(ring.stats().least_slack, 3);
        assert_eq!(ring.next(), Some(1));
        assert_eq!(ring.stats().least_slack, 2);
        // A refill does not raise it; a consumption that leaves more does not either.
        ring.receive(9).unwrap();
        ring.receive(9).unwrap();
        assert_eq!(ring.next(), Some(2));
        assert_eq!(
            (ring.stats().least_slack, ring.stats().most_requests),
            (2, 2)
        );
        // A reset starts afresh, as a new ring: the capacity until the next consumption.
        ring.reset_stats();
        assert_eq!(ring.stats().least_slack, 4);
        assert_eq!(ring.next(), Some(3));
        assert_eq!(ring.stats().least_slack, 2);
        for _ in 0..2 {
            ring.next().unwrap();
        }
        assert_eq!(ring.stats().least_slack, 0);
        assert_eq!(ring.next(), None);
        assert_eq!(
            ring.stats(),
            Stats {
                underruns: 1,
                least_slack: 0,
                most_requests: 4
            }
        );
    }

    /// The cumulative counters wrap at 2³² as before, and the ring stays a FIFO across the wrap,
    /// for a power of two (slot = the count's low bits) and for other sizes (an index beside it);
    /// `clear` drops items without counting them as consumed.
    #[test]
    fn counters_wrap_at_2_32_and_the_ring_keeps_its_order() {
        fn across_the_wrap<const N: usize>() {
            let mut ring: Ring<u32, N> = Ring::new();
            let start = u32::MAX - 2;
            ring.received = start;
            ring.taken = start;
            ring.dropped = 0;
            let mut next_in = 0u32;
            let mut next_out = 0u32;
            for round in 0..40u32 {
                while ring.receive(next_in).is_ok() {
                    next_in += 1;
                }
                assert!(ring.is_full());
                for _ in 0..=(round % 3) {
                    if let Some(item) = ring.next() {
                        assert_eq!(item, next_out, "N = {N}");
                        next_out += 1;
                    }
                }
                assert_eq!(ring.len(), N - (round as usize % 3 + 1).min(N));
            }
            let c = ring.counters();
            assert_eq!(c.received, start.wrapping_add(next_in), "N = {N}");
            assert_eq!(c.consumed, start.wrapping_add(next_out), "N = {N}");
            // Clearing drops the items held: not consumed, and the next item comes out next.
            let held = ring.len();
            ring.clear();
            assert_eq!((ring.len(), ring.counters()), (0, c));
            assert_eq!(ring.receive(7), Ok(()));
            assert_eq!(ring.next(), Some(7));
            assert_eq!(
                ring.counters(),
                Counters {
                    received: c.received.wrapping_add(1),
                    consumed: c.consumed.wrapping_add(1)
                }
            );
            assert!(held > 0 || N == 1);
        }
        across_the_wrap::<4>();
        across_the_wrap::<8>();
        across_the_wrap::<5>();
        across_the_wrap::<7>();
        across_the_wrap::<1>();
    }

    #[test]
    fn debug_shows_the_counts_not_the_slots() {
        let mut ring: Ring<u8, 3> = Ring::new();
        ring.receive(1).unwrap();
        let text = format!("{ring:?}");
        assert!(
            text.contains("capacity: 3") && text.contains("held: 1"),
            "{text}"
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
