//! The ring split into a filling half (the link interrupt) and a draining half (the machine loop).
//!
//! A single-producer single-consumer ring on per-slot atomics, in safe code: each slot is an
//! atomic cell ([`SharedItem::Cell`]), RP and SP are free-running 32-bit counts — the filler's
//! `received` and the drainer's `consumed` — published through two `AtomicU32`s. Only atomic
//! loads and stores are used (no compare-and-swap, no read-modify-write), so it runs on a
//! Cortex-M0, which has none.
//!
//! # Why the orderings are enough
//! The filler writes the slot of count `c` (relaxed), then publishes `received = c + 1`
//! (`Release`). The drainer reads the slot of count `c` only after it has read (`Acquire`) a
//! `received` above `c`: that write happens-before its read. The filler writes that slot again
//! (for count `c + S`) only after it has read (`Acquire`) a `consumed` above `c`, which the drainer
//! published (`Release`) after reading it: the drainer's read happens-before the overwrite, so it
//! sees exactly the item stored for `c`, never a later one. Each half caches the other's count
//! and reads it again only when the ring looks full (filler) or empty (drainer): the counts only
//! grow (modulo 2³², and the two are never more than `S ≤ 2³¹` apart, so the wrapping difference
//! is exact), so a cached value is at most behind — the ring looks fuller or emptier than it is,
//! which costs a read, never an item. The slots are atomics, so even a mistake in this argument
//! could not be undefined behaviour, only a wrong item. The orderings rest on this argument, not
//! on a test: `tests/properties.rs` runs the halves on two threads natively and under Miri
//! (which emulates weak memory), but on x86-64 every load acquires and every store releases, and
//! under Miri a copy with the `received` pair made `Relaxed` ran ten minutes without a wrong item.

use core::sync::atomic::{
    AtomicBool, AtomicI8, AtomicI16, AtomicI32, AtomicIsize, AtomicU8, AtomicU16, AtomicU32,
    AtomicUsize, Ordering,
};

use crate::ring::{Counters, Stats};

/// What a [`SharedRing`] slot holds: a `Copy` item kept in an atomic cell, so that the filling
/// and the draining half can touch the same slots from different contexts without `unsafe`.
///
/// Implemented for `u8`, `u16`, `u32`, `usize`, `i8`, `i16`, `i32`, `isize` and `bool` (their
/// `core::sync::atomic` cells, on every target with atomic loads and stores, the Cortex-M0 too),
/// and `u64`, `i64` where the target has 64-bit atomics. A type of your own maps onto one of them:
///
/// ```
/// use regler_ring_transfer::{SharedItem, SharedRing};
///
/// /// A needle's colour and number, packed into one 32-bit cell.
/// #[derive(Clone, Copy, Debug, PartialEq)]
/// struct Stitch { colour: u8, needle: u16 }
///
/// impl SharedItem for Stitch {
///     type Cell = <u32 as SharedItem>::Cell;
///     const BLANK: Self::Cell = <u32 as SharedItem>::BLANK;
///     fn load(cell: &Self::Cell) -> Self {
///         let bits = u32::load(cell);
///         Stitch { colour: bits.to_le_bytes()[0], needle: (bits >> 8) as u16 }
///     }
///     fn store(cell: &Self::Cell, item: Self) {
///         u32::store(cell, u32::from(item.colour) | u32::from(item.needle) << 8);
///     }
/// }
///
/// let mut ring: SharedRing<Stitch, 4> = SharedRing::new();
/// let (mut filler, mut drainer) = ring.split();
/// filler.receive(Stitch { colour: 2, needle: 700 }).map_err(|_| "full")?;
/// assert_eq!(drainer.next(), Some(Stitch { colour: 2, needle: 700 }));
/// assert_eq!(drainer.next(), None); // an underrun, never the blank
/// # Ok::<(), &str>(())
/// ```
///
/// `load` and `store` must be single atomic loads and stores of the cell (relaxed is enough: the
/// ring orders them with its counts); a cell that is not `Sync` keeps the halves on one thread.
pub trait SharedItem: Copy {
    /// The atomic cell one slot is made of (`AtomicU8` for `u8`, …).
    type Cell;
    /// A cell holding nothing yet: fills the slots when the ring is made; never handed out by
    /// [`Drainer::next`].
    const BLANK: Self::Cell;
    /// Reads the item in `cell` (a relaxed atomic load).
    fn load(cell: &Self::Cell) -> Self;
    /// Writes `item` into `cell` (a relaxed atomic store).
    fn store(cell: &Self::Cell, item: Self);
}

macro_rules! shared_items {
    ($($(#[$cfg:meta])* $t:ty => $cell:ty = $blank:expr),* $(,)?) => {
        $(
            $(#[$cfg])*
            impl SharedItem for $t {
                type Cell = $cell;
                #[allow(
                    clippy::declare_interior_mutable_const,
                    reason = "each use is a fresh, empty cell: what the slot array is built from"
                )]
                const BLANK: $cell = <$cell>::new($blank);
                #[inline(always)]
                fn load(cell: &$cell) -> Self {
                    cell.load(Ordering::Relaxed)
                }
                #[inline(always)]
                fn store(cell: &$cell, item: Self) {
                    cell.store(item, Ordering::Relaxed);
                }
            }
        )*
    };
}

shared_items!(
    u8 => AtomicU8 = 0,
    u16 => AtomicU16 = 0,
    u32 => AtomicU32 = 0,
    usize => AtomicUsize = 0,
    i8 => AtomicI8 = 0,
    i16 => AtomicI16 = 0,
    i32 => AtomicI32 = 0,
    isize => AtomicIsize = 0,
    bool => AtomicBool = false,
    #[cfg(target_has_atomic = "64")]
    u64 => core::sync::atomic::AtomicU64 = 0,
    #[cfg(target_has_atomic = "64")]
    i64 => core::sync::atomic::AtomicI64 = 0,
);

/// A ring whose filling and draining halves live in different execution contexts — interrupt
/// priorities or threads — lock-free, on atomic loads and stores only (no `unsafe`, no
/// compare-and-swap: a Cortex-M0 runs it).
///
/// It holds **`S` items** of a [`SharedItem`] type; `S` must be a power of two from 1 to 2³¹
/// (checked when the program is built — `cargo build`, not `cargo check`, which does not evaluate
/// the assertion): `SharedRing<u8, 256>` holds 256 bytes. On a 32-bit target the cells must also
/// fit its address space: there rustc refuses 2³¹ one-byte cells as too big for the target
/// before the crate's check is reached. (While it sat on `heapless::spsc::Queue` it held
/// `S − 1`.)
///
/// [`split`](Self::split) hands out a [`Filler`] (`receive`, the request count and the
/// cumulative counters a report needs) and a [`Drainer`] (`next`, underruns). The halves borrow
/// the ring; once both are dropped, `split` may be called again and the new halves carry on
/// where the old ones stopped: the items held and the counters stay (the statistics start
/// afresh). For `'static` halves in firmware put the ring in a `static` through a once-cell such
/// as `static_cell` or an RTIC resource; in a thread program use `std::thread::scope`:
///
/// ```
/// use regler_ring_transfer::SharedRing;
///
/// let mut ring: SharedRing<u32, 16> = SharedRing::new();
/// let (mut filler, mut drainer) = ring.split();
/// std::thread::scope(|s| {
///     s.spawn(move || {
///         for i in 0..10_000 {
///             let mut item = i;
///             while let Err(back) = filler.receive(item) {
///                 item = back; // full: wait for the machine to consume
///                 std::hint::spin_loop();
///             }
///         }
///     });
///     let mut expect = 0;
///     while expect < 10_000 {
///         if let Some(item) = drainer.next() {
///             assert_eq!(item, expect);
///             expect += 1;
///         }
///     }
/// });
/// assert_eq!(ring.split().0.counters().received, 10_000); // a second split carries on
/// ```
pub struct SharedRing<T: SharedItem, const S: usize> {
    slots: [T::Cell; S],
    /// RP as a count: items stored, wrapping at 2³² (written by the filler only).
    received: AtomicU32,
    /// SP as a count: items taken, wrapping at 2³² (written by the drainer only).
    consumed: AtomicU32,
}

impl<T: SharedItem, const S: usize> core::fmt::Debug for SharedRing<T, S> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SharedRing")
            .field("capacity", &S)
            .field("received", &self.received.load(Ordering::Acquire))
            .field("consumed", &self.consumed.load(Ordering::Acquire))
            .finish_non_exhaustive()
    }
}

impl<T: SharedItem, const S: usize> Default for SharedRing<T, S> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: SharedItem, const S: usize> SharedRing<T, S> {
    /// `S` as a count (`S ≤ 2³¹`, checked in [`new`](Self::new)).
    #[allow(
        clippy::cast_possible_truncation,
        reason = "S <= 2^31 is asserted when the program is compiled"
    )]
    const SLOTS: u32 = S as u32;

    /// An empty ring of `S` slots; `const`, so it can live in a `static`. `S` must be a power of
    /// two from 1 to 2³¹ (checked when the program is built; see [`SharedRing`] for 32-bit
    /// targets):
    ///
    /// ```
    /// use regler_ring_transfer::SharedRing;
    ///
    /// static RING: SharedRing<u8, 256> = SharedRing::new();
    /// assert_eq!(RING.capacity(), 256);
    /// ```
    ///
    /// ```compile_fail
    /// // 3 is not a power of two.
    /// let ring: regler_ring_transfer::SharedRing<u8, 3> = regler_ring_transfer::SharedRing::new();
    /// ```
    ///
    /// ```compile_fail
    /// // 2^32 slots: more than the 32-bit counts can tell apart from empty.
    /// let ring: regler_ring_transfer::SharedRing<u8, { 1 << 32 }> =
    ///     regler_ring_transfer::SharedRing::new();
    /// ```
    #[must_use]
    pub const fn new() -> Self {
        Self::starting_at(0)
    }

    /// An empty ring whose counters start at `count` (the tests' way to the 2³² wrap).
    const fn starting_at(count: u32) -> Self {
        const {
            assert!(
                S.is_power_of_two(),
                "a SharedRing needs S a power of two (the slot is the count's low bits)"
            );
            assert!(
                S as u64 <= 1 << 31,
                "a SharedRing holds at most 2^31 items (its counts are 32-bit)"
            );
        };
        Self {
            slots: [const { T::BLANK }; S],
            received: AtomicU32::new(count),
            consumed: AtomicU32::new(count),
        }
    }

    /// The number of slots, `S`.
    #[must_use]
    pub const fn capacity(&self) -> usize {
        S
    }

    /// The two halves. They borrow the ring; each may move to its own context. After both are
    /// dropped a new `split` carries on: the items held and the counters are the ring's, the
    /// statistics (least slack, underruns) the halves'.
    pub fn split(&mut self) -> (Filler<'_, T, S>, Drainer<'_, T, S>) {
        let received = *self.received.get_mut();
        let consumed = *self.consumed.get_mut();
        let ring = &*self;
        (
            Filler {
                ring,
                received,
                consumed,
                least_slack: S,
            },
            Drainer {
                ring,
                consumed,
                received,
                underruns: 0,
            },
        )
    }

    /// The slot of a count: its low bits (`S` is a power of two, so it divides 2³²).
    #[inline(always)]
    fn slot(&self, count: u32) -> Option<&T::Cell> {
        self.slots.get((count as usize) & S.wrapping_sub(1))
    }
}

/// The filling half: the link side. It stores refills at RP and answers what a request report
/// needs — the refills owed and the cumulative counters.
pub struct Filler<'a, T: SharedItem, const S: usize> {
    ring: &'a SharedRing<T, S>,
    /// RP: this half's own count (the ring's `received` is a copy for the drainer).
    received: u32,
    /// The drainer's count as last read: at most the real one.
    consumed: u32,
    least_slack: usize,
}

impl<T: SharedItem, const S: usize> core::fmt::Debug for Filler<'_, T, S> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Filler")
            .field("capacity", &S)
            .field("held", &self.slack())
            .field("received", &self.received)
            .field("least_slack", &self.least_slack)
            .finish()
    }
}

impl<T: SharedItem, const S: usize> Filler<'_, T, S> {
    /// Stores `item` at RP.
    ///
    /// # Errors
    /// `Err(item)` when all `S` slots hold items (nothing stored, nothing counted).
    #[inline]
    pub fn receive(&mut self, item: T) -> Result<(), T> {
        let received = self.received;
        // Full as far as this half knows: look again at what the drainer has taken.
        if received.wrapping_sub(self.consumed) >= SharedRing::<T, S>::SLOTS {
            self.consumed = self.ring.consumed.load(Ordering::Acquire);
            if received.wrapping_sub(self.consumed) >= SharedRing::<T, S>::SLOTS {
                return Err(item);
            }
        }
        // Always `Some`: the low bits of a count are below S.
        if let Some(cell) = self.ring.slot(received) {
            T::store(cell, item);
        }
        let received = received.wrapping_add(1);
        self.received = received;
        self.ring.received.store(received, Ordering::Release);
        Ok(())
    }

    /// Items held, as of now (the drainer may take more at any moment).
    fn held(&self) -> u32 {
        self.received
            .wrapping_sub(self.ring.consumed.load(Ordering::Acquire))
    }

    /// Refills owed now (free slots). Also samples the slack for [`stats`](Self::stats): the
    /// least slack is the least seen at these moments, which is when the link side looks.
    pub fn requests(&mut self) -> usize {
        self.consumed = self.ring.consumed.load(Ordering::Acquire);
        let slack = self.slack_of(self.received.wrapping_sub(self.consumed));
        self.least_slack = self.least_slack.min(slack);
        S.saturating_sub(slack)
    }

    /// `held` as a count of items (at most `S`, which fits `usize`).
    fn slack_of(&self, held: u32) -> usize {
        usize::try_from(held).unwrap_or(S).min(S)
    }

    /// Items left before an underrun, as of now (the drainer may take more at any moment).
    #[must_use]
    pub fn slack(&self) -> usize {
        self.slack_of(self.held())
    }

    /// Cumulative counts for a report: `received` is this half's, `consumed` the drainer's as
    /// published — a consumption racing with this call is reported next time, never one that
    /// did not happen. Both carry on across [`SharedRing::split`].
    #[must_use]
    pub fn counters(&self) -> Counters {
        Counters {
            received: self.received,
            consumed: self.ring.consumed.load(Ordering::Acquire),
        }
    }

    /// Least slack and most requests seen by [`requests`](Self::requests) since this half was
    /// split off; underruns are counted by the [`Drainer`] (this half reports 0 for them).
    #[must_use]
    pub fn stats(&self) -> Stats {
        Stats {
            underruns: 0,
            least_slack: self.least_slack,
            most_requests: S.saturating_sub(self.least_slack),
        }
    }
}

/// The draining half: the machine side, taking items at SP.
pub struct Drainer<'a, T: SharedItem, const S: usize> {
    ring: &'a SharedRing<T, S>,
    /// SP: this half's own count (the ring's `consumed` is a copy for the filler).
    consumed: u32,
    /// The filler's count as last read: at most the real one.
    received: u32,
    underruns: u32,
}

impl<T: SharedItem, const S: usize> core::fmt::Debug for Drainer<'_, T, S> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Drainer")
            .field("consumed", &self.consumed)
            .field("underruns", &self.underruns)
            .finish()
    }
}

impl<T: SharedItem, const S: usize> Drainer<'_, T, S> {
    /// Takes the item at SP; `None` is an underrun and is counted.
    #[inline]
    #[allow(
        clippy::should_implement_trait,
        reason = "SP+1→SP as on `Ring`; None is an underrun, not the end"
    )]
    pub fn next(&mut self) -> Option<T> {
        let consumed = self.consumed;
        // Empty as far as this half knows: look again at what the filler has stored.
        if consumed == self.received {
            self.received = self.ring.received.load(Ordering::Acquire);
            if consumed == self.received {
                self.underruns = self.underruns.saturating_add(1);
                return None;
            }
        }
        // Always `Some`: the low bits of a count are below S.
        let item = T::load(self.ring.slot(consumed)?);
        let consumed = consumed.wrapping_add(1);
        self.consumed = consumed;
        self.ring.consumed.store(consumed, Ordering::Release);
        Some(item)
    }

    /// Underruns counted by this half (saturating).
    #[must_use]
    pub fn underruns(&self) -> u32 {
        self.underruns
    }

    /// Items taken so far, wrapping at 2³²; carries on across [`SharedRing::split`].
    #[must_use]
    pub fn consumed(&self) -> u32 {
        self.consumed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::VecDeque;

    /// What the halves may be asked to do, one call at a time.
    #[derive(Debug, Clone, Copy)]
    enum Op {
        Receive(u8),
        Next,
        Requests,
        /// Drop both halves and split again.
        Split,
    }

    fn ops() -> impl Strategy<Value = Vec<Op>> {
        proptest::collection::vec(
            prop_oneof![
                4 => any::<u8>().prop_map(Op::Receive),
                4 => Just(Op::Next),
                1 => Just(Op::Requests),
                1 => Just(Op::Split),
            ],
            0..400,
        )
    }

    /// Where the counters start: 0, just below the 2³² wrap (so that the run crosses it), around
    /// the half range, or anywhere.
    fn start() -> impl Strategy<Value = u32> {
        prop_oneof![
            Just(0),
            (0u32..300).prop_map(|k| u32::MAX - k),
            (0u32..300).prop_map(|k| (1u32 << 31) - 150 + k),
            any::<u32>(),
        ]
    }

    /// The halves of a `SharedRing<u8, S>` whose counters start at `start`, against a `VecDeque`
    /// holding at most `S`, wrapping counters and the statistics as documented, after every call.
    fn halves_match_the_model<const S: usize>(start: u32, ops: &[Op]) -> Result<(), TestCaseError> {
        let mut ring: SharedRing<u8, S> = SharedRing::starting_at(start);
        let mut model: VecDeque<u8> = VecDeque::new();
        let (mut received, mut consumed, mut underruns, mut least) = (start, start, 0u32, S);
        let (mut filler, mut drainer) = ring.split();
        for &op in ops {
            match op {
                Op::Receive(x) => {
                    let expected = if model.len() < S {
                        model.push_back(x);
                        received = received.wrapping_add(1);
                        Ok(())
                    } else {
                        Err(x)
                    };
                    prop_assert_eq!(filler.receive(x), expected, "S = {}", S);
                }
                Op::Next => {
                    let expected = model.pop_front();
                    match expected {
                        Some(_) => consumed = consumed.wrapping_add(1),
                        None => underruns += 1,
                    }
                    prop_assert_eq!(drainer.next(), expected, "S = {}", S);
                }
                Op::Requests => {
                    least = least.min(model.len());
                    prop_assert_eq!(filler.requests(), S - model.len());
                }
                Op::Split => {
                    (filler, drainer) = ring.split();
                    (underruns, least) = (0, S);
                }
            }
            prop_assert_eq!(filler.counters(), Counters { received, consumed });
            prop_assert_eq!(drainer.consumed(), consumed);
            prop_assert_eq!(drainer.underruns(), underruns);
            prop_assert_eq!(filler.slack(), model.len());
            prop_assert_eq!(
                filler.stats(),
                Stats {
                    underruns: 0,
                    least_slack: least,
                    most_requests: S - least
                }
            );
        }
        Ok(())
    }

    proptest! {
        /// Every power-of-two size up to 64, the counters starting anywhere — across the 2³²
        /// wrap too — and the halves split again at any point: the same bounded FIFO of `S`
        /// items as the model, the same counters.
        #[test]
        #[cfg_attr(
            miri,
            ignore = "7 sizes x 400 operations, one thread: 8 minutes interpreted; safe code, run natively in CI"
        )]
        fn halves_of_every_size_match_the_model_across_the_wrap(start in start(), ops in ops()) {
            halves_match_the_model::<1>(start, &ops)?;
            halves_match_the_model::<2>(start, &ops)?;
            halves_match_the_model::<4>(start, &ops)?;
            halves_match_the_model::<8>(start, &ops)?;
            halves_match_the_model::<16>(start, &ops)?;
            halves_match_the_model::<32>(start, &ops)?;
            halves_match_the_model::<64>(start, &ops)?;
        }
    }

    /// A full ring just below the wrap: the filler's and the drainer's counts on either side of
    /// it, the slot still the count's low bits.
    #[test]
    fn the_counts_wrap_at_2_pow_32() {
        let mut ring: SharedRing<u16, 8> = SharedRing::starting_at(u32::MAX - 3);
        let (mut fill, mut drain) = ring.split();
        for k in 0..8 {
            fill.receive(k).unwrap();
        }
        assert_eq!(fill.receive(8), Err(8));
        assert_eq!(
            fill.counters(),
            Counters {
                received: 4,
                consumed: u32::MAX - 3
            }
        );
        for k in 0..5 {
            assert_eq!(drain.next(), Some(k));
        }
        assert_eq!(drain.consumed(), 1);
        assert_eq!(fill.requests(), 5);
        for k in 8..13 {
            fill.receive(k).unwrap();
        }
        assert_eq!(fill.receive(99), Err(99));
        let out: Vec<u16> = core::iter::from_fn(|| drain.next()).collect();
        assert_eq!(out, (5..13).collect::<Vec<_>>());
        assert_eq!((drain.consumed(), drain.underruns()), (9, 1));
    }

    /// The size check accepts 2³¹ slots: `new` for it is compiled (its assertion evaluated) but
    /// not called (no 2 GiB array is built). 3 and 2³² are refused: the `compile_fail` examples
    /// on [`SharedRing::new`].
    #[test]
    fn a_ring_of_2_pow_31_slots_is_accepted() {
        let make: fn() -> SharedRing<u8, { 1 << 31 }> = SharedRing::new;
        core::hint::black_box(make);
        assert_eq!(SharedRing::<u8, { 1 << 31 }>::SLOTS, 1 << 31);
    }

    /// The `Debug` text a firmware's log shows: the counts as they are, by name.
    #[test]
    fn debug_text_shows_the_counts() {
        let mut ring: SharedRing<u8, 4> = SharedRing::new();
        {
            let (mut fill, mut drain) = ring.split();
            for b in 0..3 {
                fill.receive(b).unwrap();
            }
            assert_eq!(drain.next(), Some(0));
            assert_eq!(fill.requests(), 2);
            assert_eq!(
                format!("{fill:?}"),
                "Filler { capacity: 4, held: 2, received: 3, least_slack: 2 }"
            );
            assert_eq!(
                (drain.next(), drain.next(), drain.next()),
                (Some(1), Some(2), None)
            );
            assert_eq!(
                format!("{drain:?}"),
                "Drainer { consumed: 3, underruns: 1 }"
            );
        }
        assert_eq!(
            format!("{ring:?}"),
            "SharedRing { capacity: 4, received: 3, consumed: 3, .. }"
        );
    }

    #[test]
    fn a_ring_of_s_holds_s() {
        let mut ring: SharedRing<u8, 4> = SharedRing::new();
        assert_eq!(ring.capacity(), 4);
        let (mut fill, mut drain) = ring.split();
        assert_eq!(fill.requests(), 4);
        for b in 0..4 {
            fill.receive(b).unwrap();
        }
        assert_eq!(fill.receive(9), Err(9));
        assert_eq!(fill.requests(), 0);
        assert_eq!(drain.next(), Some(0));
        assert_eq!(
            fill.counters(),
            Counters {
                received: 4,
                consumed: 1
            }
        );
        assert_eq!(fill.requests(), 1);
        assert_eq!(
            (drain.next(), drain.next(), drain.next(), drain.next()),
            (Some(1), Some(2), Some(3), None)
        );
        assert_eq!((drain.underruns(), drain.consumed()), (1, 4));
        assert_eq!(fill.requests(), 4);
        assert_eq!(fill.stats().least_slack, 0);
        assert_eq!(fill.stats().most_requests, 4);
    }

    #[test]
    fn the_smallest_ring_has_one_slot() {
        let mut ring: SharedRing<u8, 1> = SharedRing::new();
        let (mut fill, mut drain) = ring.split();
        fill.receive(1).unwrap();
        assert_eq!(fill.receive(2), Err(2));
        assert_eq!((drain.next(), drain.next()), (Some(1), None));
        assert_eq!(fill.requests(), 1);
    }
}
