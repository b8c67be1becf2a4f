//! The tracker: trolleys on the chain, counted to their tippers by the chain pulses.

use core::fmt;

use heapless::Vec;

use crate::table::{DistanceTable, TableError, correct};

/// The hold of the source: a tipper is reset 6 pulses after it was set.
pub const SOURCE_HOLD_PULSES: u32 = 6;

const NIL: u32 = u32::MAX;

/// Something the tipper outputs must do now.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum TipperEvent<K> {
    /// `trolley` is over `tipper`: set the tipper output. It may already be set by a trolley
    /// that arrived within the hold; it then stays set for the hold after this arrival.
    Set {
        /// The tipper.
        tipper: usize,
        /// The trolley that arrived.
        trolley: K,
    },
    /// The hold after the last arrival at `tipper` has passed: reset the tipper output.
    Reset {
        /// The tipper.
        tipper: usize,
    },
}

/// Why [`Tracker::enter`] refused a trolley. The trolley is handed back; nothing changed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EnterError<K> {
    /// All `N` places are taken.
    Full(K),
    /// The distance table has no such tipper.
    UnknownTipper {
        /// The trolley, handed back.
        trolley: K,
        /// The tipper asked for.
        tipper: usize,
    },
}

impl<K> EnterError<K> {
    /// The trolley that was refused.
    pub fn into_trolley(self) -> K {
        match self {
            EnterError::Full(k) | EnterError::UnknownTipper { trolley: k, .. } => k,
        }
    }
}

impl<K> fmt::Display for EnterError<K> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EnterError::Full(_) => f.write_str("tracker full: no room for another trolley"),
            EnterError::UnknownTipper { tipper, .. } => {
                write!(f, "no tipper {tipper} in the distance table")
            }
        }
    }
}

impl<K: fmt::Debug> core::error::Error for EnterError<K> {}

/// Why a tracker could not be built, recalibrated or restored. Nothing changed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum TrackerError {
    /// A hold of 0 pulses would never let a tipper act.
    ZeroHold,
    /// The distance table refused.
    Table(TableError),
    /// Rescaling the remaining distances of the trolleys on the chain overflowed.
    RescaleOverflow,
    /// A snapshot names a tipper the table does not have.
    UnknownTipper {
        /// The tipper named.
        tipper: usize,
    },
    /// A snapshot holds a trolley with 0 pulses to go (it would have arrived already).
    ZeroRemaining,
    /// A snapshot holds a tipper set for longer than this tracker's hold (a snapshot from a
    /// firmware with another hold, or a corrupt block).
    HeldTooLong {
        /// The tipper.
        tipper: usize,
        /// Pulses the snapshot says it stays set.
        remaining: u32,
        /// This tracker's hold.
        hold: u32,
    },
    /// A snapshot names the same tipper as set twice.
    DuplicateHeld {
        /// The tipper.
        tipper: usize,
    },
    /// A snapshot holds a trolley further from its tipper than the tipper is from the reader
    /// (plus [`RESTORE_SLACK`] pulses of rescaling rounding).
    TooFar {
        /// Its tipper.
        tipper: usize,
        /// Pulses the snapshot says it has to go.
        remaining: u32,
        /// The tipper's distance at the snapshot's DIA.
        distance: u32,
    },
    /// A snapshot lists a tipper's trolleys out of order: one would overtake the one that
    /// entered before it, which a chain cannot do.
    OutOfOrder {
        /// The tipper.
        tipper: usize,
    },
}

/// Pulses by which a trolley's remaining distance may exceed its tipper's distance in a
/// snapshot. A tracker never holds a trolley further from its tipper than the tipper's distance
/// (at least 1): [`Tracker::recalibrate`] caps the rescaled distances there, so its own
/// snapshots need no slack. The slack accepts snapshots stored by firmware built before that
/// cap, whose rounding could leave a trolley a pulse or two further.
pub const RESTORE_SLACK: u32 = 2;

impl fmt::Display for TrackerError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TrackerError::ZeroHold => f.write_str("the tipper hold must be at least 1 pulse"),
            TrackerError::Table(e) => write!(f, "distance table: {e}"),
            TrackerError::RescaleOverflow => {
                f.write_str("rescaled distance of a trolley on the chain does not fit in 32 bits")
            }
            TrackerError::UnknownTipper { tipper } => {
                write!(
                    f,
                    "snapshot names tipper {tipper}, which the table does not have"
                )
            }
            TrackerError::ZeroRemaining => {
                f.write_str("snapshot holds a trolley with 0 pulses to go")
            }
            TrackerError::HeldTooLong {
                tipper,
                remaining,
                hold,
            } => write!(
                f,
                "snapshot holds tipper {tipper} set for {remaining} more pulses, but the hold is {hold}"
            ),
            TrackerError::DuplicateHeld { tipper } => {
                write!(f, "snapshot names tipper {tipper} as set twice")
            }
            TrackerError::TooFar {
                tipper,
                remaining,
                distance,
            } => write!(
                f,
                "snapshot holds a trolley {remaining} pulses from tipper {tipper}, which is only {distance} from the reader"
            ),
            TrackerError::OutOfOrder { tipper } => write!(
                f,
                "snapshot lists the trolleys for tipper {tipper} out of order (one would overtake another)"
            ),
        }
    }
}

impl core::error::Error for TrackerError {}

impl From<TableError> for TrackerError {
    fn from(e: TableError) -> TrackerError {
        TrackerError::Table(e)
    }
}

/// One trolley on the chain, as listed by [`Tracker::in_flight`] and stored in a [`Snapshot`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct InFlight<K> {
    /// The trolley.
    pub trolley: K,
    /// Its destination tipper.
    pub tipper: usize,
    /// Pulses until it is over its tipper (at least 1).
    pub remaining: u32,
}

/// A tipper that is set, as stored in a [`Snapshot`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct HeldTipper {
    /// The tipper.
    pub tipper: usize,
    /// Pulses until it is reset (at least 1).
    pub remaining: u32,
}

/// Everything a [`Tracker`] needs to continue after a power failure, apart from its
/// configuration (the static list, SIA and the hold, which live in program memory).
///
/// Write it to non-volatile memory (feature `serde`) when power fails; after the restart build
/// the tracker from its configuration again and [`restore`](Tracker::restore) it.
#[derive(Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Snapshot<K, const N: usize, const T: usize> {
    /// The pulse counter.
    pub now: u32,
    /// The DIA the distances were computed for.
    pub dia: u32,
    /// The trolleys on the chain, each tipper's in the order they entered.
    pub in_flight: Vec<InFlight<K>, N>,
    /// The tippers that are set.
    pub held: Vec<HeldTipper, T>,
}

impl<K, const N: usize, const T: usize> Snapshot<K, N, T> {
    /// An empty snapshot (a `const fn`, so one can live in a `static`), to fill with
    /// [`Tracker::snapshot_into`].
    #[must_use]
    pub const fn new() -> Snapshot<K, N, T> {
        Snapshot {
            now: 0,
            dia: 0,
            in_flight: Vec::new(),
            held: Vec::new(),
        }
    }
}

impl<K, const N: usize, const T: usize> Default for Snapshot<K, N, T> {
    fn default() -> Snapshot<K, N, T> {
        Snapshot::new()
    }
}

/// A place for one trolley. A used slot is linked into its tipper's queue, a free one into
/// the free list, both through `next`.
#[derive(Clone, Copy, Debug)]
struct Slot<K> {
    trolley: Option<K>,
    /// Pulse count at which the trolley is over its tipper.
    arrival: u32,
    next: u32,
}

/// Per tipper: the queue of trolleys bound for it, and its output. The arrivals of the head
/// and tail are kept here too, so that a pulse reads the slots only of trolleys that arrive.
#[derive(Clone, Copy, Debug)]
struct Tipper {
    head: u32,
    tail: u32,
    head_arrival: u32,
    tail_arrival: u32,
    /// Pulse count at which the output is reset; `None` while it is not set.
    reset_at: Option<u32>,
}

const IDLE_TIPPER: Tipper = Tipper {
    head: NIL,
    tail: NIL,
    head_arrival: 0,
    tail_arrival: 0,
    reset_at: None,
};

/// Trolleys on a dock chain, each counted by the chain pulses to its destination tipper.
///
/// A trolley [`enter`](Tracker::enter)s at the code reader with its destination tipper; its
/// distance comes from the [`DistanceTable`]. Every [`pulse`](Tracker::pulse) moves all
/// trolleys one pulse; when one is over its tipper the tracker emits [`TipperEvent::Set`], and
/// [`TipperEvent::Reset`] `hold` pulses after the last arrival at that tipper. `K` is the
/// caller's trolley tag (a trolley number, say); `N` trolleys fit on the chain, `T` tippers
/// in the table.
///
/// **Cost.** The source kept one shift register and counted every entry down on every pulse:
/// O(trolleys) per pulse. Here trolleys bound for one tipper arrive in the order they entered
/// (they ride the same chain and cannot overtake), so each tipper keeps a FIFO queue, and a
/// pulse only compares the pulse counter with the earliest pending arrival and reset: O(1) per
/// pulse, plus O(T) when something arrives or resets. `enter` is O(1); `recalibrate` O(N + T).
/// Nothing is allocated; the tracker's size is fixed by `N` and `T`:
/// `N·size_of::<(Option<K>, u32, u32)>() + T·24 + size_of::<DistanceTable<T>>() + 32` bytes on
/// a 32-bit target, padded to the alignment — 7 468 bytes for `Tracker<u16, 512, 40>` (a slot of
/// a `u16` trolley is 12 bytes, a tipper 24; a unit test checks the formula). [`Tracker::new`] is a `const fn`, so a big tracker
/// can be a `static` instead of being built on the stack.
///
/// **Recalibration.** When the chain has stretched, [`recalibrate`](Tracker::recalibrate)
/// recomputes the distance table and rescales the remaining distance of every trolley already
/// on the chain: the physical distance still to go is unchanged while each pulse now stands for
/// a longer piece of chain, so `remaining' = remaining × DIA_new / DIA_old`, rounded half up,
/// at most the tipper's new distance (no trolley is further from its tipper than the tipper is
/// from the reader, however many recalibrations have rounded its distance), at least 1, and
/// never ahead of the trolley before it. So every [`Snapshot`] a tracker takes restores.
///
/// **Wrapping.** The pulse counter wraps at `u32::MAX`; arrivals are compared by wrapping
/// difference, so tracking carries on across the wrap.
///
/// ```
/// use regler_chain_tracker::{DistanceTable, TipperEvent, Tracker};
/// let table: DistanceTable<3> = DistanceTable::new(3000, &[10, 20, 30])?;
/// let mut tracker: Tracker<u16, 64, 3> = Tracker::new(table, 6)?;
/// tracker.enter(1977, 1)?; // trolley 1977 to tipper 1, 20 pulses on
/// let mut events = Vec::new();
/// for _ in 0..30 {
///     tracker.pulse(|e| events.push(e));
/// }
/// assert_eq!(events, [
///     TipperEvent::Set { tipper: 1, trolley: 1977 }, // after pulse 20
///     TipperEvent::Reset { tipper: 1 },              // after pulse 26
/// ]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct Tracker<K, const N: usize, const T: usize> {
    table: DistanceTable<T>,
    hold: u32,
    now: u32,
    slots: [Slot<K>; N],
    free: u32,
    len: usize,
    tippers: [Tipper; T],
    next_arrival: Option<u32>,
    next_reset: Option<u32>,
}

impl<K: Copy, const N: usize, const T: usize> Tracker<K, N, T> {
    /// A tracker with an empty chain, distances from `table`, tippers held `hold` pulses
    /// ([`SOURCE_HOLD_PULSES`] in the source), pulse counter at 0.
    pub const fn new(table: DistanceTable<T>, hold: u32) -> Result<Tracker<K, N, T>, TrackerError> {
        const {
            assert!(N > 0, "a tracker holds at least one trolley");
            assert!(N < NIL as usize, "at most u32::MAX - 1 trolleys");
        }
        if hold == 0 {
            return Err(TrackerError::ZeroHold);
        }
        Ok(Tracker {
            table,
            hold,
            now: 0,
            slots: Self::free_slots(),
            free: 0,
            len: 0,
            tippers: [IDLE_TIPPER; T],
            next_arrival: None,
            next_reset: None,
        })
    }

    /// Every slot free, linked in order (slot i → i + 1; N < u32::MAX was checked).
    const fn free_slots() -> [Slot<K>; N] {
        let mut slots = [const {
            Slot {
                trolley: None,
                arrival: 0,
                next: NIL,
            }
        }; N];
        let mut i = 0usize;
        while i < N {
            let next = i.saturating_add(1);
            #[allow(
                clippy::indexing_slicing,
                clippy::cast_possible_truncation,
                reason = "i < N < u32::MAX"
            )]
            {
                slots[i].next = if next < N { next as u32 } else { NIL };
            }
            i = next;
        }
        slots
    }

    /// Takes every trolley off the chain and resets every tipper (without events).
    pub fn clear(&mut self) {
        self.slots = Self::free_slots();
        self.free = 0;
        self.len = 0;
        self.tippers = [IDLE_TIPPER; T];
        self.next_arrival = None;
        self.next_reset = None;
    }

    /// Puts `trolley` on the chain at the reader, bound for `tipper`: it arrives after
    /// [`distance`](DistanceTable::distance)`(tipper)` pulses (a distance of 0 counts as 1).
    /// It never arrives before a trolley that entered earlier for the same tipper.
    pub fn enter(&mut self, trolley: K, tipper: usize) -> Result<(), EnterError<K>> {
        let Some(distance) = self.table.distance(tipper) else {
            return Err(EnterError::UnknownTipper { trolley, tipper });
        };
        self.push(trolley, tipper, distance.max(1))
            .map_err(|()| EnterError::Full(trolley))
    }

    /// Appends a trolley to `tipper`'s queue, `distance` (≥ 1) pulses from now, or later if the
    /// trolley ahead arrives later. `Err` when full or no such tipper.
    fn push(&mut self, trolley: K, tipper: usize, distance: u32) -> Result<(), ()> {
        let now = self.now;
        let Some(queue) = self.tippers.get(tipper).copied() else {
            return Err(());
        };
        let ahead = if queue.tail == NIL {
            0
        } else {
            queue.tail_arrival.wrapping_sub(now)
        };
        let arrival = now.wrapping_add(distance.max(ahead));
        let index = self.free;
        let slot = self.slots.get_mut(index_usize(index)).ok_or(())?;
        self.free = slot.next;
        *slot = Slot {
            trolley: Some(trolley),
            arrival,
            next: NIL,
        };
        if let Some(tail) = self.slots.get_mut(index_usize(queue.tail)) {
            tail.next = index;
        }
        if let Some(q) = self.tippers.get_mut(tipper) {
            if q.head == NIL {
                q.head = index;
                q.head_arrival = arrival;
            }
            q.tail = index;
            q.tail_arrival = arrival;
        }
        self.len = self.len.saturating_add(1);
        self.next_arrival = Some(earliest(self.next_arrival, arrival, now));
        Ok(())
    }

    /// The used slot at `index` with its trolley; `None` for `NIL`.
    fn slot(&self, index: u32) -> Option<(K, &Slot<K>)> {
        let slot = self.slots.get(index_usize(index))?;
        Some((slot.trolley?, slot))
    }

    /// Advances the chain one pulse and reports what the tippers must do: sets first (in tipper
    /// order), then resets. A tipper with an arrival in this pulse is not reset in it.
    pub fn pulse(&mut self, mut on_event: impl FnMut(TipperEvent<K>)) {
        self.now = self.now.wrapping_add(1);
        if self.next_arrival == Some(self.now) {
            self.arrive(&mut on_event);
        }
        if self.next_reset == Some(self.now) {
            self.reset_due(&mut on_event);
        }
    }

    /// Advances the chain `pulses` pulses, with the same events as that many calls to
    /// [`pulse`](Tracker::pulse), but at the cost of the pulses on which something happens:
    /// the quiet pulses between them are skipped in one step. So a delta read from a hardware
    /// counter costs O(T) per arrival or reset in it, and O(1) besides, whatever its size — a
    /// wrapped counter's `u32::MAX` does not hang the loop.
    pub fn advance(&mut self, pulses: u32, mut on_event: impl FnMut(TipperEvent<K>)) {
        let mut left = pulses;
        while left > 0 {
            let now = self.now;
            // Pulses until the next arrival or reset (0 would be 2³² pulses away).
            let until = [self.next_arrival, self.next_reset]
                .into_iter()
                .flatten()
                .map(|at| at.wrapping_sub(now))
                .filter(|&d| d != 0)
                .min();
            match until {
                Some(d) if d <= left => {
                    self.now = now.wrapping_add(d.saturating_sub(1));
                    left = left.saturating_sub(d);
                    self.pulse(&mut on_event);
                }
                _ => {
                    self.now = now.wrapping_add(left);
                    left = 0;
                }
            }
        }
    }

    fn arrive(&mut self, on_event: &mut impl FnMut(TipperEvent<K>)) {
        let now = self.now;
        let reset_at = now.wrapping_add(self.hold);
        let mut next: Option<u32> = None;
        for tipper in 0..T {
            let Some(&q) = self.tippers.get(tipper) else {
                break;
            };
            let (mut head, mut head_arrival) = (q.head, q.head_arrival);
            let mut arrived = false;
            while head != NIL && head_arrival == now {
                let Some(slot) = self.slots.get_mut(index_usize(head)) else {
                    break;
                };
                let trolley = slot.trolley.take();
                let following = slot.next;
                slot.next = self.free;
                self.free = head;
                self.len = self.len.saturating_sub(1);
                head = following;
                head_arrival = self.slots.get(index_usize(head)).map_or(0, |s| s.arrival);
                arrived = true;
                if let Some(trolley) = trolley {
                    on_event(TipperEvent::Set { tipper, trolley });
                }
            }
            if let Some(q) = self.tippers.get_mut(tipper) {
                if arrived {
                    q.head = head;
                    q.head_arrival = head_arrival;
                    if head == NIL {
                        q.tail = NIL;
                    }
                    q.reset_at = Some(reset_at);
                    // Resets are all `hold` after their set, so an earlier one stays earliest.
                    if self.next_reset.is_none() {
                        self.next_reset = Some(reset_at);
                    }
                }
                if head != NIL {
                    next = Some(earliest(next, head_arrival, now));
                }
            }
        }
        self.next_arrival = next;
    }

    fn reset_due(&mut self, on_event: &mut impl FnMut(TipperEvent<K>)) {
        let now = self.now;
        let mut next: Option<u32> = None;
        for (tipper, q) in self.tippers.iter_mut().enumerate() {
            match q.reset_at {
                Some(at) if at == now => {
                    q.reset_at = None;
                    on_event(TipperEvent::Reset { tipper });
                }
                Some(at) => next = Some(earliest(next, at, now)),
                None => {}
            }
        }
        self.next_reset = next;
    }

    /// Takes a new DIA (from a [`StretchMeter`](crate::StretchMeter)): recomputes the distance
    /// table and rescales the trolleys on the chain (see the type's docs). Returns whether
    /// anything changed; on an error nothing did.
    pub fn recalibrate(&mut self, dia: u32) -> Result<bool, TrackerError> {
        let old = self.table.dia();
        if dia == old {
            return Ok(false);
        }
        let da = self.table.corrected(dia)?;
        let now = self.now;
        // Remaining distances grow or shrink monotonically with the rescale, so if the longest
        // fits, all do: check it before changing anything.
        let longest = self
            .tippers
            .iter()
            .filter(|q| q.tail != NIL)
            .map(|q| q.tail_arrival.wrapping_sub(now))
            .max()
            .unwrap_or(0);
        correct(longest, dia, old).map_err(|_| TrackerError::RescaleOverflow)?;
        self.table.commit(dia, da);
        let mut next: Option<u32> = None;
        for (q, &distance) in self.tippers.iter_mut().zip(da.iter()) {
            // No trolley is further from its tipper than the tipper is from the reader: rounding
            // a small remaining distance half up at every recalibration must not add up (it
            // made the tracker's own snapshots fail `restore`).
            let cap = distance.max(1);
            let mut index = q.head;
            let mut ahead = 1u32;
            while let Some(slot) = self.slots.get_mut(index_usize(index)) {
                let remaining = slot.arrival.wrapping_sub(now);
                let scaled = correct(remaining, dia, old)
                    .unwrap_or(remaining)
                    .min(cap)
                    .max(ahead);
                slot.arrival = now.wrapping_add(scaled);
                if index == q.head {
                    q.head_arrival = slot.arrival;
                    next = Some(earliest(next, slot.arrival, now));
                }
                if index == q.tail {
                    q.tail_arrival = slot.arrival;
                }
                ahead = scaled;
                index = slot.next;
            }
        }
        self.next_arrival = next;
        Ok(true)
    }

    /// The trolleys on the chain: tipper by tipper, each tipper's in the order they entered.
    pub fn in_flight(&self) -> impl Iterator<Item = InFlight<K>> + '_ {
        let now = self.now;
        self.tippers
            .iter()
            .enumerate()
            .flat_map(move |(tipper, q)| {
                let mut index = q.head;
                core::iter::from_fn(move || {
                    let (trolley, slot) = self.slot(index)?;
                    index = slot.next;
                    Some(InFlight {
                        trolley,
                        tipper,
                        remaining: slot.arrival.wrapping_sub(now),
                    })
                })
            })
    }

    /// Whether `tipper`'s output is set (`false` for an unknown tipper).
    #[must_use]
    pub fn is_set(&self, tipper: usize) -> bool {
        self.tippers
            .get(tipper)
            .is_some_and(|q| q.reset_at.is_some())
    }

    /// Trolleys on the chain.
    #[must_use]
    pub const fn len(&self) -> usize {
        self.len
    }

    /// Whether the chain carries no tracked trolley.
    #[must_use]
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Trolleys the tracker has room for (`N`).
    #[must_use]
    pub const fn capacity(&self) -> usize {
        N
    }

    /// The pulse counter (wrapping).
    #[must_use]
    pub const fn now(&self) -> u32 {
        self.now
    }

    /// Sets the pulse counter (to line it up with a hardware counter); distances to go are kept.
    pub fn set_now(&mut self, now: u32) {
        let delta = now.wrapping_sub(self.now);
        for slot in &mut self.slots {
            slot.arrival = slot.arrival.wrapping_add(delta);
        }
        for q in &mut self.tippers {
            q.reset_at = q.reset_at.map(|r| r.wrapping_add(delta));
            q.head_arrival = q.head_arrival.wrapping_add(delta);
            q.tail_arrival = q.tail_arrival.wrapping_add(delta);
        }
        self.next_arrival = self.next_arrival.map(|a| a.wrapping_add(delta));
        self.next_reset = self.next_reset.map(|r| r.wrapping_add(delta));
        self.now = now;
    }

    /// The hold in pulses.
    #[must_use]
    pub const fn hold(&self) -> u32 {
        self.hold
    }

    /// The distance table in use.
    #[must_use]
    pub const fn table(&self) -> &DistanceTable<T> {
        &self.table
    }

    /// The tracker's state, for non-volatile memory. A `Snapshot<K, N, T>` is as big as `N`
    /// trolleys and `T` tippers make it (6.5 KB for `Tracker<u16, 512, 40>`): on a small stack,
    /// write it into one that lives elsewhere with [`snapshot_into`](Tracker::snapshot_into).
    #[must_use]
    pub fn snapshot(&self) -> Snapshot<K, N, T> {
        let mut snapshot = Snapshot::new();
        self.snapshot_into(&mut snapshot);
        snapshot
    }

    /// The tracker's state, written into `snapshot` (a `static` or a buffer next to the flash
    /// driver) without building one on the stack. Whatever `snapshot` held is replaced.
    pub fn snapshot_into(&self, snapshot: &mut Snapshot<K, N, T>) {
        let now = self.now;
        snapshot.now = now;
        snapshot.dia = self.table.dia();
        snapshot.in_flight.clear();
        snapshot.held.clear();
        for trolley in self.in_flight() {
            // ok to ignore: in_flight yields at most N items, the capacity.
            let _ = snapshot.in_flight.push(trolley);
        }
        for (tipper, q) in self.tippers.iter().enumerate() {
            if let Some(at) = q.reset_at {
                let _ = snapshot.held.push(HeldTipper {
                    tipper,
                    remaining: at.wrapping_sub(now),
                });
            }
        }
    }

    /// Replaces the state with `snapshot` (taken from a tracker with the same configuration).
    /// Every field is checked against this tracker first, so a snapshot from a firmware with
    /// another configuration or a corrupt block is an error, never a tracker that misbehaves:
    /// the DIA must give a valid table; every tipper must exist; a set tipper must reset within
    /// this tracker's hold and be listed once; a trolley must have 1..=distance +
    /// [`RESTORE_SLACK`] pulses to go, and a tipper's trolleys must be in the order they can
    /// arrive. On an error nothing changes.
    pub fn restore(&mut self, snapshot: &Snapshot<K, N, T>) -> Result<(), TrackerError> {
        let da = self.table.corrected(snapshot.dia)?;
        let tippers = self.table.tippers();
        // The table's tippers only (the arrays run to the capacity T).
        let distances = da.get(..tippers).unwrap_or(&[]);
        let mut last = [0u32; T];
        for t in &snapshot.in_flight {
            let (Some(&distance), Some(previous)) =
                (distances.get(t.tipper), last.get_mut(t.tipper))
            else {
                return Err(TrackerError::UnknownTipper { tipper: t.tipper });
            };
            if t.remaining == 0 {
                return Err(TrackerError::ZeroRemaining);
            }
            let distance = distance.max(1);
            if t.remaining > distance.saturating_add(RESTORE_SLACK) {
                return Err(TrackerError::TooFar {
                    tipper: t.tipper,
                    remaining: t.remaining,
                    distance,
                });
            }
            if t.remaining < *previous {
                return Err(TrackerError::OutOfOrder { tipper: t.tipper });
            }
            *previous = t.remaining;
        }
        let mut held = [false; T];
        for h in &snapshot.held {
            let Some(seen) = held.get_mut(h.tipper).filter(|_| h.tipper < tippers) else {
                return Err(TrackerError::UnknownTipper { tipper: h.tipper });
            };
            if *seen {
                return Err(TrackerError::DuplicateHeld { tipper: h.tipper });
            }
            *seen = true;
            if h.remaining == 0 {
                return Err(TrackerError::ZeroRemaining);
            }
            if h.remaining > self.hold {
                return Err(TrackerError::HeldTooLong {
                    tipper: h.tipper,
                    remaining: h.remaining,
                    hold: self.hold,
                });
            }
        }
        let da = self.table.corrected(snapshot.dia)?;
        self.table.commit(snapshot.dia, da);
        self.clear();
        self.now = snapshot.now;
        for t in &snapshot.in_flight {
            // Capacity N and tipper range were checked: push cannot fail.
            let _ = self.push(t.trolley, t.tipper, t.remaining);
        }
        for h in &snapshot.held {
            let at = snapshot.now.wrapping_add(h.remaining);
            if let Some(q) = self.tippers.get_mut(h.tipper) {
                q.reset_at = Some(at);
            }
            self.next_reset = Some(earliest(self.next_reset, at, snapshot.now));
        }
        Ok(())
    }
}

/// Whichever of `next` and `at` comes first counting from `now` on the wrapping clock (`next`
/// on a tie; `at` when there is no `next`): the one deadline the tracker keeps per kind of event.
fn earliest(next: Option<u32>, at: u32, now: u32) -> u32 {
    match next {
        Some(n) if n.wrapping_sub(now) <= at.wrapping_sub(now) => n,
        _ => at,
    }
}

fn index_usize(index: u32) -> usize {
    usize::try_from(index).unwrap_or(usize::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The deadline kept is the one nearer in time from `now` on the wrapping clock, the one
    /// already kept on a tie, the new one when none was kept: over clocks about to wrap.
    #[test]
    fn earliest_is_the_nearer_deadline_across_the_wrap() {
        for now in [0u32, 1, 1 << 31, u32::MAX - 1, u32::MAX] {
            for a in [0u32, 1, 2, 1000, (1 << 31) - 1, 1 << 31, u32::MAX] {
                let at = now.wrapping_add(a);
                assert_eq!(earliest(None, at, now), at);
                for b in [0u32, 1, 2, 999, 1000, 1001, 1 << 31, u32::MAX] {
                    let n = now.wrapping_add(b);
                    let want = if b <= a { n } else { at };
                    assert_eq!(earliest(Some(n), at, now), want, "now {now}, +{b} and +{a}");
                }
            }
        }
    }
    use crate::table::{CorrectionError, TableError};
    use std::vec::Vec;
    type Events = Vec<(u32, TipperEvent<u16>)>;

    fn tracker<const N: usize>(sa: &[u32], hold: u32) -> Tracker<u16, N, 8> {
        Tracker::new(DistanceTable::new(1000, sa).unwrap(), hold).unwrap()
    }

    fn run<const N: usize>(t: &mut Tracker<u16, N, 8>, pulses: u32) -> Events {
        let mut events = Vec::new();
        for _ in 0..pulses {
            let now = t.now();
            t.pulse(|e| events.push((now.wrapping_add(1), e)));
        }
        events
    }

    #[test]
    fn arrives_after_distance_and_resets_after_hold() {
        let mut t = tracker::<4>(&[3, 5], SOURCE_HOLD_PULSES);
        t.enter(7, 1).unwrap();
        assert!(!t.is_empty());
        let events = run(&mut t, 20);
        assert_eq!(
            events,
            [
                (
                    5,
                    TipperEvent::Set {
                        tipper: 1,
                        trolley: 7
                    }
                ),
                (11, TipperEvent::Reset { tipper: 1 })
            ]
        );
        assert!(t.is_empty());
    }

    #[test]
    fn two_arrivals_within_the_hold_keep_the_tipper_set() {
        let mut t = tracker::<4>(&[4], 6);
        t.enter(1, 0).unwrap();
        run(&mut t, 3);
        t.enter(2, 0).unwrap(); // arrives at pulse 7, within the hold of the first (4..10)
        let events = run(&mut t, 20);
        assert_eq!(
            events,
            [
                (
                    4,
                    TipperEvent::Set {
                        tipper: 0,
                        trolley: 1
                    }
                ),
                (
                    7,
                    TipperEvent::Set {
                        tipper: 0,
                        trolley: 2
                    }
                ),
                (13, TipperEvent::Reset { tipper: 0 }),
            ]
        );
    }

    #[test]
    fn arrival_on_the_reset_pulse_keeps_the_tipper_set() {
        let mut t = tracker::<4>(&[4], 2);
        t.enter(1, 0).unwrap();
        run(&mut t, 2);
        t.enter(2, 0).unwrap(); // arrives at 6 = reset pulse of the first
        let events = run(&mut t, 10);
        assert_eq!(
            events,
            [
                (
                    4,
                    TipperEvent::Set {
                        tipper: 0,
                        trolley: 1
                    }
                ),
                (
                    6,
                    TipperEvent::Set {
                        tipper: 0,
                        trolley: 2
                    }
                ),
                (8, TipperEvent::Reset { tipper: 0 }),
            ]
        );
    }

    #[test]
    fn full_and_unknown_tipper_change_nothing() {
        let mut t = tracker::<2>(&[10, 20], 6);
        t.enter(1, 0).unwrap();
        t.enter(2, 1).unwrap();
        assert_eq!(t.enter(3, 0), Err(EnterError::Full(3)));
        assert_eq!(
            t.enter(4, 2),
            Err(EnterError::UnknownTipper {
                trolley: 4,
                tipper: 2
            })
        );
        assert_eq!(t.enter(4, 2).unwrap_err().into_trolley(), 4);
        assert_eq!(t.len(), 2);
        let events = run(&mut t, 30);
        assert_eq!(
            events
                .iter()
                .filter(|(_, e)| matches!(e, TipperEvent::Set { .. }))
                .count(),
            2
        );
        // The places are free again.
        t.enter(5, 0).unwrap();
        t.enter(6, 0).unwrap();
    }

    /// `capacity` is `N`, the trolleys `enter` takes before it says `Full`; `hold` is the hold
    /// the tracker was built with.
    #[test]
    fn capacity_and_hold_are_what_it_was_built_with() {
        let mut t = tracker::<3>(&[10], 6);
        assert_eq!((t.capacity(), t.hold()), (3, 6));
        assert_eq!(tracker::<3>(&[10], 250).hold(), 250);
        for k in 0..3 {
            t.enter(k, 0).unwrap();
        }
        assert_eq!(t.enter(9, 0), Err(EnterError::Full(9)));
        assert_eq!(t.len(), t.capacity());
        assert_eq!(tracker::<512>(&[10], 6).capacity(), 512);
    }

    #[test]
    fn zero_distance_counts_as_one_and_zero_hold_is_refused() {
        let mut t = tracker::<2>(&[0], 1);
        t.enter(1, 0).unwrap();
        assert_eq!(
            run(&mut t, 1),
            [(
                1,
                TipperEvent::Set {
                    tipper: 0,
                    trolley: 1
                }
            )]
        );
        assert_eq!(run(&mut t, 1), [(2, TipperEvent::Reset { tipper: 0 })]);
        let table = DistanceTable::<8>::new(1, &[1]).unwrap();
        assert_eq!(
            Tracker::<u16, 2, 8>::new(table, 0).unwrap_err(),
            TrackerError::ZeroHold
        );
    }

    #[test]
    fn wraps_across_u32_max() {
        let mut t = tracker::<8>(&[5, 10], 6);
        t.set_now(u32::MAX - 3);
        t.enter(1, 0).unwrap();
        t.enter(2, 1).unwrap();
        let events = run(&mut t, 20);
        assert_eq!(
            events,
            [
                (
                    1,
                    TipperEvent::Set {
                        tipper: 0,
                        trolley: 1
                    }
                ),
                (
                    6,
                    TipperEvent::Set {
                        tipper: 1,
                        trolley: 2
                    }
                ),
                (7, TipperEvent::Reset { tipper: 0 }),
                (12, TipperEvent::Reset { tipper: 1 }),
            ]
        );
    }

    #[test]
    fn cannot_overtake_the_trolley_ahead() {
        let mut t = tracker::<8>(&[100], 6);
        t.enter(1, 0).unwrap();
        t.recalibrate(900).unwrap(); // stretched: new entries need 90 pulses
        // The trolley ahead was rescaled to 90 too; the one behind arrives no earlier.
        t.enter(2, 0).unwrap();
        let sets: Vec<_> = run(&mut t, 100)
            .into_iter()
            .filter(|(_, e)| matches!(e, TipperEvent::Set { .. }))
            .collect();
        assert_eq!(
            sets,
            [
                (
                    90,
                    TipperEvent::Set {
                        tipper: 0,
                        trolley: 1
                    }
                ),
                (
                    90,
                    TipperEvent::Set {
                        tipper: 0,
                        trolley: 2
                    }
                ),
            ]
        );
    }

    #[test]
    fn recalibration_rescales_trolleys_on_the_chain() {
        let mut t = tracker::<8>(&[1000, 2000], 6);
        t.enter(1, 1).unwrap();
        run(&mut t, 1000); // half way: 1000 to go
        assert!(t.recalibrate(990).unwrap()); // 1 % more pulses' worth of chain per pulse
        assert_eq!(t.table().distance(1), Some(1980));
        assert_eq!(
            t.in_flight().next(),
            Some(InFlight {
                trolley: 1,
                tipper: 1,
                remaining: 990
            })
        );
        assert!(!t.recalibrate(990).unwrap());
        let events = run(&mut t, 990);
        assert_eq!(
            events,
            [(
                1990,
                TipperEvent::Set {
                    tipper: 1,
                    trolley: 1
                }
            )]
        );
    }

    #[test]
    fn failed_recalibration_changes_nothing() {
        let mut t: Tracker<u16, 4, 8> =
            Tracker::new(DistanceTable::new(1, &[1, 1 << 30]).unwrap(), 6).unwrap();
        t.enter(1, 1).unwrap();
        let before = t.snapshot();
        assert_eq!(
            t.recalibrate(8),
            Err(TrackerError::Table(TableError::Overflow { tipper: 1 }))
        );
        assert_eq!(
            t.recalibrate(0),
            Err(TrackerError::Table(TableError::ZeroMeasurement))
        );
        assert_eq!(t.snapshot(), before);
        assert_eq!(t.table().dia(), 1);
    }

    #[test]
    fn snapshot_and_restore_lose_nothing() {
        let mut a = tracker::<16>(&[10, 20, 30], 6);
        for (i, tipper) in [0, 1, 2, 1, 0, 2, 2].into_iter().enumerate() {
            a.enter(i as u16, tipper).unwrap();
            run(&mut a, 2);
        }
        a.recalibrate(1010).unwrap();
        let snapshot = a.snapshot();
        assert!(!snapshot.held.is_empty());
        let mut b = tracker::<16>(&[10, 20, 30], 6);
        b.restore(&snapshot).unwrap();
        assert_eq!(b.snapshot(), snapshot);
        assert_eq!(run(&mut a, 50), run(&mut b, 50));
    }

    /// The issue's case: SA 50, SIA 1000, six small recalibrations with a trolley just entered
    /// rounded its remaining distance up each time (50) while the tipper's distance fell to 47:
    /// the tracker's own snapshot was refused as `TooFar`.
    #[test]
    fn own_snapshot_restores_after_many_small_recalibrations() {
        let mut t: Tracker<u16, 4, 8> =
            Tracker::new(DistanceTable::new(1000, &[50]).unwrap(), 6).unwrap();
        t.enter(1, 0).unwrap();
        for dia in [990, 981, 972, 963, 954, 945] {
            t.recalibrate(dia).unwrap();
            let remaining = t.in_flight().next().unwrap().remaining;
            assert!(remaining <= t.table().distance(0).unwrap(), "DIA {dia}");
            let snapshot = t.snapshot();
            let mut fresh: Tracker<u16, 4, 8> =
                Tracker::new(DistanceTable::new(1000, &[50]).unwrap(), 6).unwrap();
            fresh.restore(&snapshot).unwrap();
            assert_eq!(run(&mut fresh, 60), run(&mut t.clone(), 60));
        }
        assert_eq!(t.table().distance(0), Some(47));
    }

    /// A tracker whose table has fewer tippers than its capacity `T` refuses a snapshot that
    /// names a tipper past the table's last, set or with a trolley bound for it, exactly from
    /// the first such tipper on.
    #[test]
    fn a_snapshot_naming_a_tipper_past_the_tables_last_is_refused() {
        let mut t = tracker::<4>(&[10, 20], 6); // two tippers in a table of capacity 8
        let good = t.snapshot();
        for tipper in [2, 3, 7] {
            let mut bad = good.clone();
            bad.held
                .push(HeldTipper {
                    tipper,
                    remaining: 3,
                })
                .unwrap();
            assert_eq!(t.restore(&bad), Err(TrackerError::UnknownTipper { tipper }));
            let mut bad = good.clone();
            bad.in_flight
                .push(InFlight {
                    trolley: 1,
                    tipper,
                    remaining: 5,
                })
                .unwrap();
            assert_eq!(t.restore(&bad), Err(TrackerError::UnknownTipper { tipper }));
        }
        let mut last = good.clone();
        last.held
            .push(HeldTipper {
                tipper: 1,
                remaining: 3,
            })
            .unwrap();
        assert_eq!(t.restore(&last), Ok(()));
        assert!(t.is_set(1) && !t.is_set(2));
    }

    #[test]
    fn restore_refuses_bad_snapshots() {
        let mut t = tracker::<4>(&[10], 6);
        t.enter(9, 0).unwrap();
        let good = t.snapshot();
        let mut bad = good.clone();
        bad.in_flight[0].tipper = 5;
        assert_eq!(
            t.restore(&bad),
            Err(TrackerError::UnknownTipper { tipper: 5 })
        );
        let mut bad = good.clone();
        bad.in_flight[0].remaining = 0;
        assert_eq!(t.restore(&bad), Err(TrackerError::ZeroRemaining));
        let mut bad = good.clone();
        bad.dia = 0;
        assert_eq!(
            t.restore(&bad),
            Err(TrackerError::Table(TableError::ZeroMeasurement))
        );
        let mut bad = good.clone();
        bad.in_flight[0].remaining = 13; // tipper 0 is 10 pulses from the reader
        assert_eq!(
            t.restore(&bad),
            Err(TrackerError::TooFar {
                tipper: 0,
                remaining: 13,
                distance: 10
            })
        );
        let mut bad = good.clone();
        bad.in_flight
            .push(InFlight {
                trolley: 8,
                tipper: 0,
                remaining: 1,
            })
            .unwrap();
        assert_eq!(t.restore(&bad), Err(TrackerError::OutOfOrder { tipper: 0 }));
        assert_eq!(t.snapshot(), good, "refused snapshots changed nothing");
    }

    #[test]
    fn size_is_the_documented_formula() {
        use core::mem::size_of;
        fn formula<K, const N: usize, const T: usize>() -> usize {
            let other = 4 + 4 + 4 + size_of::<usize>() + 8 + 8; // hold, now, free, len, next_*
            let raw = N * size_of::<Slot<K>>() + T * 24 + size_of::<DistanceTable<T>>() + other;
            raw.next_multiple_of(core::mem::align_of::<Tracker<K, N, T>>())
        }
        assert_eq!(size_of::<Slot<u16>>(), 12);
        assert_eq!(size_of::<Tipper>(), 24);
        assert_eq!(
            size_of::<DistanceTable<40>>(),
            8 * 40 + 8 + size_of::<usize>()
        );
        assert_eq!(
            size_of::<Tracker<u16, 512, 40>>(),
            formula::<u16, 512, 40>()
        );
        assert_eq!(size_of::<Tracker<u32, 64, 3>>(), formula::<u32, 64, 3>());
        // On a 32-bit target: 512·12 + 40·24 + 332 + 32 = 7 468 bytes.
        assert_eq!(512 * 12 + 40 * 24 + (8 * 40 + 8 + 4) + 32, 7468);
    }

    #[test]
    fn trackers_and_snapshots_live_in_statics() {
        static TABLE: DistanceTable<3> = match DistanceTable::new(1000, &[10, 20, 30]) {
            Ok(t) => t,
            Err(_) => panic!("a valid table"),
        };
        static TRACKER: Tracker<u16, 512, 3> = match Tracker::new(TABLE, 6) {
            Ok(t) => t,
            Err(_) => panic!("a valid hold"),
        };
        static EMPTY: Snapshot<u16, 512, 3> = Snapshot::new();
        let mut t = TRACKER.clone();
        t.enter(5, 2).unwrap();
        let mut stored = EMPTY.clone();
        t.snapshot_into(&mut stored);
        assert_eq!(stored, t.snapshot());
        assert_eq!(stored.in_flight.len(), 1);
    }

    #[test]
    fn a_held_tipper_beyond_the_hold_is_refused() {
        // A snapshot from a firmware whose hold was 20: restored into a hold of 6, the tipper
        // reset would come 14 pulses late, and every later reset of it never.
        let mut t = tracker::<4>(&[10], 6);
        let mut snapshot = t.snapshot();
        snapshot
            .held
            .push(HeldTipper {
                tipper: 0,
                remaining: 20,
            })
            .unwrap();
        assert_eq!(
            t.restore(&snapshot),
            Err(TrackerError::HeldTooLong {
                tipper: 0,
                remaining: 20,
                hold: 6
            })
        );
        snapshot.held[0].remaining = 6;
        snapshot
            .held
            .push(HeldTipper {
                tipper: 0,
                remaining: 2,
            })
            .unwrap();
        assert_eq!(
            t.restore(&snapshot),
            Err(TrackerError::DuplicateHeld { tipper: 0 })
        );
        snapshot.held.pop();
        t.restore(&snapshot).unwrap();
        let events = run(&mut t, 7);
        assert_eq!(events, [(6, TipperEvent::Reset { tipper: 0 })]);
    }

    #[test]
    fn error_messages_name_the_problem() {
        assert!(
            EnterError::UnknownTipper {
                trolley: 1u16,
                tipper: 9
            }
            .to_string()
            .contains('9')
        );
        assert!(TrackerError::ZeroHold.to_string().contains("hold"));
        assert!(
            CorrectionError::Overflow {
                sa: 1,
                dia: 2,
                sia: 3
            }
            .to_string()
            .contains("1·2/3")
        );
    }
}
