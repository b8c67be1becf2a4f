//! The timer shift register of the 1977 plant, with O(1) ticks: a hierarchical timing wheel.

use core::fmt;

/// The bits of a deadline each level's slots stand for, lowest first: level 0 the lowest 8 (one
/// slot per tick of a 256-tick block), level 1 the next 8, then three levels of 6. 34 bits: more
/// than any `u32` delay needs. Two wide levels at the bottom: a timer under 65 536 ticks moves
/// down once (twice when its deadline lies in a later 65 536-tick block than now), where six
/// levels of 64 moved a 4 096-tick timer twice or three times; with heads only (no tails) the
/// table (2 816 bytes) is still smaller than six levels' heads and tails were (3 072).
const WIDTHS: [u32; LEVELS] = [8, 8, 6, 6, 6];
const LEVELS: usize = 5;
/// Slot heads in all: 256 + 256 + 3 × 64.
const SLOTS: usize = 704;
/// Ticks of a level-0 block: entering one may bring entries down from the levels above.
const BLOCK_MASK: u64 = (1 << 8) - 1;
const NIL: u32 = u32::MAX;

/// Where a deadline goes at one level: its slots start at `base`, and the slot is the deadline's
/// bits from `shift` on, masked by `mask`.
#[derive(Clone, Copy)]
struct Level {
    base: u16,
    shift: u8,
    mask: u8,
}

impl Level {
    /// The slot for `ticks` at this level.
    #[inline]
    fn slot(self, ticks: u64) -> usize {
        let within = low_usize(ticks.wrapping_shr(u32::from(self.shift))) & usize::from(self.mask);
        usize::from(self.base).wrapping_add(within)
    }
}

/// The levels, lowest first, from [`WIDTHS`].
const LEVEL: [Level; LEVELS] = levels();

/// The level for each highest bit in which a deadline differs from now (0 to 63): the level
/// whose bits hold it, the top level for any bit above (never reached: a deadline is less than
/// 2³² ticks ahead, so it differs from now in bit 32 at the highest).
const LEVEL_OF_TOP: [Level; 64] = level_of_top();

#[allow(
    clippy::arithmetic_side_effects,
    clippy::indexing_slicing,
    clippy::cast_possible_truncation,
    reason = "compile-time tables over small constants: an overflow or a bad index fails the build"
)]
const fn levels() -> [Level; LEVELS] {
    let mut out = [Level {
        base: 0,
        shift: 0,
        mask: 0,
    }; LEVELS];
    let (mut base, mut shift, mut k) = (0usize, 0u32, 0);
    while k < LEVELS {
        out[k] = Level {
            base: base as u16,
            shift: shift as u8,
            mask: ((1u32 << WIDTHS[k]) - 1) as u8,
        };
        base += 1 << WIDTHS[k];
        shift += WIDTHS[k];
        k += 1;
    }
    assert!(base == SLOTS, "SLOTS is the sum of the levels' slots");
    assert!(shift > 32, "the levels cover every u32 delay and its carry");
    out
}

#[allow(
    clippy::arithmetic_side_effects,
    clippy::indexing_slicing,
    reason = "compile-time tables over small constants: an overflow or a bad index fails the build"
)]
const fn level_of_top() -> [Level; 64] {
    let mut out = [LEVEL[LEVELS - 1]; 64];
    let mut top = 0;
    while top < 64 {
        let mut k = 0;
        while k + 1 < LEVELS && top >= LEVEL[k + 1].shift as usize {
            k += 1;
        }
        out[top] = LEVEL[k];
        top += 1;
    }
    out
}

/// A handle on an inserted timer. It stays valid until the timer expires or is removed; after
/// that it is stale forever and can never touch a newer timer in the same place: each place
/// counts its uses in a 64-bit generation, so no two timers in one place share a handle. The
/// count cannot run out in a plant's life: 2⁶⁴ timers in one place take 584 years at one a
/// nanosecond (a 32-bit count ran out after 2³² timers: 2.2 years of 16 timers re-armed at
/// 1 kHz). Should it ever be used up, the place is retired rather than reused, and the queue has
/// room for one timer fewer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TimerId {
    index: u32,
    generation: u64,
}

/// [`TimerQueue::insert`] on a full queue: the action is handed back.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct QueueFull<A>(pub A);

impl<A> fmt::Display for QueueFull<A> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("timer queue full: no room for another timer")
    }
}

impl<A: fmt::Debug> core::error::Error for QueueFull<A> {}

/// A handle that names no waiting timer (it expired, was removed, or never existed here).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct UnknownTimer(pub TimerId);

impl fmt::Display for UnknownTimer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "no waiting timer has the handle of place {}, use {}: it expired, was removed or \
             never existed in this queue",
            self.0.index, self.0.generation
        )
    }
}

impl core::error::Error for UnknownTimer {}

/// One place of the queue. A waiting timer is in exactly one slot's list; a free place is on the
/// free list (through `next`) or retired.
#[derive(Clone, Debug)]
struct Entry<A> {
    action: Option<A>,
    /// The low 32 bits of the deadline tick: a waiting timer's deadline is less than 2³² ticks
    /// ahead, so these bits and the clock give it back (see [`TimerQueue::deadline_of`]).
    deadline: u32,
    generation: u64,
    /// The previous entry in the slot's list; the first entry's `prev` names the last, so a
    /// slot needs only its head to append in order.
    prev: u32,
    next: u32,
    slot: u16,
}

/// The source's timer shift register: one register for all delays, counted by the cycle tick.
/// [`insert`](TimerQueue::insert) a delay with its action, [`replace`](TimerQueue::replace) its
/// time, [`remove`](TimerQueue::remove) it; [`tick`](TimerQueue::tick) hands out the actions
/// whose time has come.
///
/// **Order.** An entry inserted (or replaced) with `ticks` = k ≥ 1 expires during the k-th
/// following `tick`; 0 counts as 1. Entries expiring in the same tick come out in the order they
/// were inserted or last replaced.
///
/// **Cost.** The source counted every entry down on every tick. This is a hierarchical timing
/// wheel: 256 slots, one per tick of the current 256-tick block; 256 slots of 256 ticks; three
/// levels of 64 slots above. `insert`, `replace` and `remove` are O(1); a tick looks at one slot,
/// and every 256 ticks moves the timers due in the block it enters down to their ticks' slots
/// (every 2¹⁶, 2²² and 2²⁸ ticks those of the higher levels a level or more down first), so a
/// timer moves at most four times in its life — at most once for a delay under 256 ticks, at
/// most twice under 65 536: O(1) amortised per tick, whatever the number of timers (the tick
/// that enters a block moves all of its timers at once). `N` entries fit; nothing is allocated.
/// Memory: the slot table takes 2 816 bytes (704 slot heads, each a `u32`: a list's first entry
/// names its last) whatever `N`, 16 bytes of counters (20 on a 64-bit host), and per entry
/// `size_of::<Option<A>>() + 22` bytes rounded up to the entry's alignment (8 for an action
/// aligned to 8 or less: 24 bytes for `u8`, 32 for `u16` or `u32` actions).
/// `TimerQueue<u32, 4096>` is 134 KB, so [`new`](TimerQueue::new) is a `const fn` and such a
/// queue belongs in a `static`. A unit test checks the formula.
///
/// ```
/// use regler_scan_cycle::TimerQueue;
/// let mut timers: TimerQueue<&str, 8> = TimerQueue::new();
/// let gate = timers.insert(3, "close reject gate")?;
/// timers.insert(1, "lamp off")?;
/// let mut fired = Vec::new();
/// timers.tick(|a| fired.push(a));
/// assert_eq!(fired, ["lamp off"]);
/// timers.replace(gate, 1)?; // sooner
/// timers.tick(|a| fired.push(a));
/// assert_eq!(fired, ["lamp off", "close reject gate"]);
/// assert!(timers.remove(gate).is_none()); // expired: the handle is stale
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct TimerQueue<A, const N: usize> {
    entries: [Entry<A>; N],
    /// The first entry of each slot's list, `NIL` when empty; level k's slots follow level k - 1's.
    heads: [u32; SLOTS],
    free: u32,
    len: usize,
    now: u64,
}

impl<A, const N: usize> Default for TimerQueue<A, N> {
    fn default() -> Self {
        TimerQueue::new()
    }
}

impl<A, const N: usize> TimerQueue<A, N> {
    /// An empty queue with room for `N` timers. A `const fn`, so a big queue can live in a
    /// `static` instead of being built on the stack.
    #[must_use]
    #[allow(
        clippy::arithmetic_side_effects,
        reason = "i < N < u32::MAX: the loop counter cannot overflow"
    )]
    pub const fn new() -> TimerQueue<A, N> {
        const {
            assert!(N > 0, "a timer queue holds at least one timer");
            assert!(N < NIL as usize, "at most u32::MAX - 1 timers");
        }
        let mut entries = [const {
            Entry {
                action: None,
                deadline: 0,
                generation: 0,
                prev: NIL,
                next: NIL,
                slot: 0,
            }
        }; N];
        // The free list runs through every entry in order; N < u32::MAX was checked above.
        let mut i = 0;
        while i + 1 < N {
            #[allow(clippy::indexing_slicing, reason = "i + 1 < N")]
            #[allow(clippy::cast_possible_truncation, reason = "N < u32::MAX")]
            {
                entries[i].next = (i + 1) as u32;
            }
            i += 1;
        }
        TimerQueue {
            entries,
            heads: [NIL; SLOTS],
            free: 0,
            len: 0,
            now: 0,
        }
    }

    /// Inserts a timer that expires after `ticks` ticks (0 counts as 1) with `action`.
    pub fn insert(&mut self, ticks: u32, action: A) -> Result<TimerId, QueueFull<A>> {
        let index = self.free;
        let now32 = low32(self.now);
        let Some(entry) = self.entries.get_mut(idx(index)) else {
            return Err(QueueFull(action));
        };
        self.free = entry.next;
        entry.action = Some(action);
        entry.deadline = now32.wrapping_add(ticks.max(1));
        let generation = entry.generation;
        self.link(index, self.now.wrapping_add(u64::from(ticks.max(1))));
        // At most N < u32::MAX entries wait: `len` cannot wrap.
        self.len = self.len.wrapping_add(1);
        Ok(TimerId { index, generation })
    }

    /// Gives a waiting timer a new time: it expires after `ticks` ticks from now (0 counts as 1)
    /// and, among timers expiring in the same tick, after those inserted or replaced before.
    pub fn replace(&mut self, id: TimerId, ticks: u32) -> Result<(), UnknownTimer> {
        if !self.is_waiting(id) {
            return Err(UnknownTimer(id));
        }
        self.unlink(id.index);
        let now32 = low32(self.now);
        if let Some(e) = self.entries.get_mut(idx(id.index)) {
            e.deadline = now32.wrapping_add(ticks.max(1));
        }
        self.link(id.index, self.now.wrapping_add(u64::from(ticks.max(1))));
        Ok(())
    }

    /// Removes a waiting timer and returns its action; `None` for a stale handle.
    pub fn remove(&mut self, id: TimerId) -> Option<A> {
        if !self.is_waiting(id) {
            return None;
        }
        self.unlink(id.index);
        self.release(id.index)
    }

    /// Ticks pending before `id` expires (≥ 1; 0 for one left due by a panic in `on_expire`,
    /// see [`tick`](Self::tick)), or `None` for a stale handle.
    #[must_use]
    pub fn remaining(&self, id: TimerId) -> Option<u32> {
        let e = self
            .entries
            .get(idx(id.index))
            .filter(|_| self.is_waiting(id))?;
        Some(e.deadline.wrapping_sub(low32(self.now)))
    }

    /// One tick: every action whose time has come goes to `on_expire`, in order.
    ///
    /// Should `on_expire` panic and the panic be caught (on a host), that one action is gone
    /// (its timer expired) and nothing else is lost: the queue is whole again as the panic
    /// leaves `tick`, and the actions due on the same tick after it stay waiting
    /// ([`remaining`](Self::remaining) 0) and come out first, in order, on the next `tick`.
    pub fn tick(&mut self, mut on_expire: impl FnMut(A)) {
        self.now = self.now.wrapping_add(1);
        // Entering a new block of 256 ticks: the higher levels may have entries for it. Most
        // ticks enter no block at all.
        if self.now & BLOCK_MASK == 0 {
            self.cascade_into_block();
        }
        let Some(head) = self.heads.get_mut(level_slot(0, self.now)) else {
            return;
        };
        let rest = core::mem::replace(head, NIL);
        let free = self.free;
        // The free list and the length are written back once, when `run` is dropped: after the
        // loop, or as a panic in `on_expire` unwinds (see `Expiry`).
        let mut run = Expiry {
            queue: self,
            rest,
            free,
            expired: 0,
        };
        // The list ends at NIL, which is no entry's index (N < u32::MAX).
        while let Some(e) = run.queue.entries.get_mut(idx(run.rest)) {
            let index = run.rest;
            run.rest = e.next;
            if let Some(action) = e.action.take() {
                run.expired = run.expired.wrapping_add(1);
                match e.generation.checked_add(1) {
                    Some(generation) => {
                        e.generation = generation;
                        e.next = run.free;
                        run.free = index;
                    }
                    // See `release`: the place is retired.
                    None => e.next = NIL,
                }
                on_expire(action);
            }
        }
    }

    /// Puts the list starting at `first` (the entries a panic in `on_expire` left unhanded; their
    /// links as in their slot, the last one's `next` NIL) in front of the next tick's level-0
    /// slot, keeping the order of both.
    #[cold]
    fn put_first_in_next_slot(&mut self, first: u32) {
        let slot = level_slot(0, self.now.wrapping_add(1));
        let Ok(slot_index) = u16::try_from(slot) else {
            return;
        };
        // Walk the list to its last entry, renaming each entry's slot.
        let mut last = first;
        let mut index = first;
        while let Some(e) = self.entries.get_mut(idx(index)) {
            e.slot = slot_index;
            last = index;
            index = e.next;
        }
        let Some(head) = self.heads.get_mut(slot) else {
            return;
        };
        let old_first = core::mem::replace(head, first);
        // The new first names the last of the whole list: the old list's last, or its own.
        let whole_last = match self.entries.get_mut(idx(old_first)) {
            Some(o) => core::mem::replace(&mut o.prev, last),
            None => last,
        };
        if let Some(l) = self.entries.get_mut(idx(last)) {
            l.next = old_first;
        }
        if let Some(f) = self.entries.get_mut(idx(first)) {
            f.prev = whole_last;
        }
    }

    /// Number of waiting timers.
    #[must_use]
    pub const fn len(&self) -> usize {
        self.len
    }

    /// Whether no timer waits.
    #[must_use]
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Timers the queue has room for (`N`).
    #[must_use]
    pub const fn capacity(&self) -> usize {
        N
    }

    /// Ticks since creation.
    #[must_use]
    pub const fn now(&self) -> u64 {
        self.now
    }

    /// The full deadline of a waiting timer from its low 32 bits: it lies 0 to 2³² − 1 ticks
    /// ahead of now (0 while its own tick cascades it down).
    #[inline]
    fn deadline_of(&self, deadline: u32) -> u64 {
        self.now
            .wrapping_add(u64::from(deadline.wrapping_sub(low32(self.now))))
    }

    fn is_waiting(&self, id: TimerId) -> bool {
        self.entries
            .get(idx(id.index))
            .is_some_and(|e| e.generation == id.generation && e.action.is_some())
    }

    /// The slot for a deadline: the level is the one whose bits hold the highest bit in which it
    /// differs from now. Until now enters the deadline's block at that level, that bit stays the
    /// highest that differs: a waiting entry's slot is where it was put.
    #[inline]
    fn slot_for(&self, deadline: u64) -> usize {
        // `| 1` makes "no difference" level 0.
        let top = 63u32.wrapping_sub((deadline ^ self.now | 1).leading_zeros());
        let level = LEVEL_OF_TOP
            .get(idx(top & 63))
            .copied()
            .unwrap_or(LEVEL[LEVELS - 1]);
        level.slot(deadline)
    }

    /// Appends entry `index` to the list of the slot for `deadline`.
    #[inline]
    fn link(&mut self, index: u32, deadline: u64) {
        self.append(index, self.slot_for(deadline));
    }

    /// Appends entry `index` to the list of `slot`.
    #[inline]
    fn append(&mut self, index: u32, slot: usize) {
        let Some(head) = self.heads.get_mut(slot) else {
            return;
        };
        let last = match self.entries.get_mut(idx(*head)) {
            Some(first) => {
                // The first entry's `prev` is the last: the new entry becomes the last.
                let last = core::mem::replace(&mut first.prev, index);
                if let Some(l) = self.entries.get_mut(idx(last)) {
                    l.next = index;
                }
                last
            }
            None => {
                *head = index;
                index
            }
        };
        if let Some(e) = self.entries.get_mut(idx(index)) {
            e.prev = last;
            e.next = NIL;
            e.slot = u16::try_from(slot).unwrap_or(0);
        }
    }

    /// Takes entry `index` out of its slot's list, keeping the others' order.
    fn unlink(&mut self, index: u32) {
        let Some((prev, next, slot)) = self
            .entries
            .get(idx(index))
            .map(|e| (e.prev, e.next, usize::from(e.slot)))
        else {
            return;
        };
        let Some(head) = self.heads.get_mut(slot) else {
            return;
        };
        let first = *head;
        if first == index {
            // The next becomes the first and inherits the name of the last.
            *head = next;
        } else if let Some(p) = self.entries.get_mut(idx(prev)) {
            p.next = next;
        }
        let successor = if next == NIL { first } else { next };
        if let Some(s) = self.entries.get_mut(idx(successor)) {
            // The entry after it (or, for the last entry, the first, which names the last).
            if successor != index {
                s.prev = prev;
            }
        }
    }

    /// Frees an entry (already out of its list) and returns its action; the handle goes stale.
    #[inline]
    fn release(&mut self, index: u32) -> Option<A> {
        let e = self.entries.get_mut(idx(index))?;
        let action = e.action.take()?;
        self.len = self.len.saturating_sub(1);
        match e.generation.checked_add(1) {
            Some(generation) => {
                e.generation = generation;
                e.next = self.free;
                self.free = index;
            }
            // Every generation of this place has been handed out: a new timer here could get
            // the generation of a stale handle, so the place is retired.
            None => e.next = NIL,
        }
        Some(action)
    }

    /// Now has entered a new block of 256 ticks: for each level whose block it has entered too
    /// (now's bits below the level's are zero), highest first, moves that level's slot for the
    /// block down to where its entries belong now.
    #[inline(never)]
    fn cascade_into_block(&mut self) {
        let zeros = self.now.trailing_zeros();
        for level in (2..LEVELS).rev() {
            let Some(&Level { shift, .. }) = LEVEL.get(level) else {
                continue;
            };
            if zeros >= u32::from(shift) {
                self.cascade(level_slot(level, self.now));
            }
        }
        self.cascade_to_level_0(level_slot(1, self.now));
    }

    /// Moves every entry of `slot` to where it belongs now (a lower level), keeping its order.
    fn cascade(&mut self, slot: usize) {
        let Some(head) = self.heads.get_mut(slot) else {
            return;
        };
        let mut index = core::mem::replace(head, NIL);
        while let Some(e) = self.entries.get(idx(index)) {
            let (next, deadline) = (e.next, self.deadline_of(e.deadline));
            self.link(index, deadline);
            index = next;
        }
    }

    /// [`cascade`](Self::cascade) for a level-1 slot as now enters its block: its entries'
    /// deadlines agree with now above the lowest 8 bits, so they all go to level 0, each to the
    /// slot of its lowest 8 bits — no need to find the level.
    fn cascade_to_level_0(&mut self, slot: usize) {
        let Some(head) = self.heads.get_mut(slot) else {
            return;
        };
        let mut index = core::mem::replace(head, NIL);
        while let Some(e) = self.entries.get(idx(index)) {
            let (next, slot) = (e.next, usize::from(e.deadline.to_le_bytes()[0]));
            self.append(index, slot);
            index = next;
        }
    }
}

/// The slot for `ticks` at `level`.
#[inline]
fn level_slot(level: usize, ticks: u64) -> usize {
    LEVEL
        .get(level)
        .copied()
        .unwrap_or(LEVEL[LEVELS - 1])
        .slot(ticks)
}

/// The low bits of `ticks` that fit a `usize` (all of them on a 64-bit host, 32 on a 32-bit one):
/// enough for any mask of 8 bits.
#[inline]
#[allow(
    clippy::cast_possible_truncation,
    reason = "only the low 8 bits are used, after a mask"
)]
fn low_usize(ticks: u64) -> usize {
    ticks as usize
}

#[inline]
#[allow(
    clippy::cast_possible_truncation,
    reason = "the low 32 bits are wanted: deadlines are kept modulo 2³²"
)]
fn low32(ticks: u64) -> u32 {
    ticks as u32
}

#[inline]
fn idx(index: u32) -> usize {
    usize::try_from(index).unwrap_or(usize::MAX)
}

/// A tick's expiry in progress: the entries of the tick's slot not yet handed out (`rest`), the
/// free list with the handed-out entries' places on it, and their count. Dropped after the loop
/// it writes the free list and the length back; dropped by a panic in `on_expire` it also puts
/// the entries not yet handed out at the front of the next tick's slot, so they stay waiting and
/// come out first on the next tick.
struct Expiry<'q, A, const N: usize> {
    queue: &'q mut TimerQueue<A, N>,
    rest: u32,
    free: u32,
    expired: usize,
}

impl<A, const N: usize> Drop for Expiry<'_, A, N> {
    fn drop(&mut self) {
        let q = &mut *self.queue;
        q.free = self.free;
        // Each expired entry was counted in `len` when it was inserted.
        q.len = q.len.wrapping_sub(self.expired);
        if self.rest != NIL {
            q.put_first_in_next_slot(self.rest);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drain<const N: usize>(q: &mut TimerQueue<u32, N>, ticks: u32) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        for t in 1..=ticks {
            q.tick(|a| out.push((t, a)));
        }
        out
    }

    #[test]
    fn a_full_queue_says_so_and_is_empty_follows_the_timers() {
        let mut q: TimerQueue<u32, 2> = TimerQueue::new();
        assert!(q.is_empty());
        q.insert(5, 1).unwrap();
        assert!(!q.is_empty());
        q.insert(5, 2).unwrap();
        let full = q.insert(5, 3).unwrap_err();
        assert_eq!(full, QueueFull(3));
        assert_eq!(
            full.to_string(),
            "timer queue full: no room for another timer"
        );
        assert_eq!(drain(&mut q, 5), [(5, 1), (5, 2)]);
        assert!(q.is_empty());
    }

    #[test]
    fn expires_on_the_kth_tick_zero_as_one() {
        let mut q: TimerQueue<u32, 8> = TimerQueue::new();
        q.insert(3, 3).unwrap();
        q.insert(0, 0).unwrap();
        q.insert(1, 1).unwrap();
        assert_eq!(drain(&mut q, 5), [(1, 0), (1, 1), (3, 3)]);
        assert!(q.is_empty());
    }

    #[test]
    fn far_deadlines_cascade_down_and_keep_insertion_order() {
        let mut q: TimerQueue<u32, 16> = TimerQueue::new();
        for (i, ticks) in [5000u32, 70, 5000, 64, 4096, 5000].into_iter().enumerate() {
            q.insert(ticks, i as u32).unwrap();
        }
        let out = drain(&mut q, 6000);
        assert_eq!(
            out,
            [(64, 3), (70, 1), (4096, 4), (5000, 0), (5000, 2), (5000, 5)]
        );
    }

    #[test]
    fn replace_moves_to_the_end_of_its_tick() {
        let mut q: TimerQueue<u32, 8> = TimerQueue::new();
        let a = q.insert(10, 0).unwrap();
        q.insert(10, 1).unwrap();
        q.replace(a, 10).unwrap();
        assert_eq!(q.remaining(a), Some(10));
        assert_eq!(drain(&mut q, 10), [(10, 1), (10, 0)]);
    }

    #[test]
    fn a_place_whose_generations_are_used_up_is_retired() {
        let mut q: TimerQueue<u8, 2> = TimerQueue::new();
        // Place 0 has handed out every generation but the last.
        if let Some(e) = q.entries.get_mut(0) {
            e.generation = u64::MAX;
        }
        let last = q.insert(5, 1).unwrap();
        assert_eq!(
            last,
            TimerId {
                index: 0,
                generation: u64::MAX
            }
        );
        assert_eq!(q.remove(last), Some(1));
        // A wrapped generation would be 0 again; the place is retired instead (unreachable in
        // practice: 2⁶⁴ timers in one place).
        let other = q.insert(5, 2).unwrap();
        assert_eq!(other.index, 1);
        assert!(
            matches!(q.insert(5, 3), Err(QueueFull(3))),
            "room for one timer fewer"
        );
        assert_eq!(
            q.remove(TimerId {
                index: 0,
                generation: 0
            }),
            None
        );
        assert_eq!(q.remove(last), None);
        assert_eq!(q.len(), 1);
    }

    /// A place re-armed 2³² times (16 timers at 1 kHz for 2.2 years) still takes timers, and no
    /// stale handle from before or after the 32-bit boundary acts on the newer timer there.
    #[test]
    fn a_place_keeps_working_past_2_pow_32_timers_and_stale_handles_stay_stale() {
        let mut q: TimerQueue<u8, 1> = TimerQueue::new();
        let mut stale = Vec::new();
        if let Some(e) = q.entries.get_mut(0) {
            e.generation = (u32::MAX - 2).into();
        }
        // Six timers in the one place across the boundary: each gets its own handle.
        for action in 0..6u8 {
            let id = q.insert(5, action).expect("the place is not retired");
            for old in &stale {
                assert_eq!(q.remaining(*old), None);
                assert_eq!(q.replace(*old, 1), Err(UnknownTimer(*old)));
                assert_eq!(q.remove(*old), None);
            }
            // A handle whose generation is the new one's modulo 2³² names another timer.
            let mut alias = id;
            alias.generation = id.generation % (1 << 32);
            if alias != id {
                assert_eq!(q.remove(alias), None);
            }
            assert_eq!(q.remaining(id), Some(5));
            assert_eq!(q.remove(id), Some(action));
            stale.push(id);
        }
        assert_eq!(q.len(), 0);
    }

    #[test]
    fn size_is_the_documented_formula() {
        use core::mem::size_of;
        // 2.75 KiB of slot heads, 20 bytes of counters and the clock on a 64-bit host, and per
        // entry the action, a u32 deadline, a u64 generation and 2 u32 + a u16 of links (padded
        // to the entry's alignment).
        let entry = |action: usize| (action + 4 + 8 + 2 * 4 + 2).next_multiple_of(8);
        assert_eq!(size_of::<Entry<u8>>(), entry(2)); // Option<u8> is 2 bytes
        assert_eq!(size_of::<Entry<u16>>(), entry(4));
        let table = (256 + 256 + 3 * 64) * 4;
        let counters = 4 + size_of::<usize>() + 8;
        let size = |entries: usize| (table + counters + entries).next_multiple_of(8);
        assert_eq!(size_of::<TimerQueue<u8, 4096>>(), size(4096 * entry(2)));
        assert_eq!(size_of::<TimerQueue<u32, 16>>(), size(16 * entry(8)));
        assert_eq!(size_of::<TimerQueue<u32, 4096>>(), 133_912, "134 KB");
        assert_eq!(entry(2), 24);
        assert_eq!(entry(4), 32);
        assert_eq!(entry(8), 32);
    }

    #[test]
    fn big_queues_live_in_statics() {
        static QUEUE: TimerQueue<u16, 4096> = TimerQueue::new();
        assert_eq!(QUEUE.len(), 0);
    }

    #[test]
    fn stale_handles_never_touch_newer_timers() {
        let mut q: TimerQueue<u32, 1> = TimerQueue::new();
        let old = q.insert(5, 1).unwrap();
        assert_eq!(q.remove(old), Some(1));
        let new = q.insert(5, 2).unwrap(); // same place, new generation
        assert_eq!(q.remove(old), None);
        assert_eq!(q.replace(old, 1), Err(UnknownTimer(old)));
        assert_eq!(q.remaining(old), None);
        assert_eq!(q.remaining(new), Some(5));
        assert_eq!(q.insert(1, 3), Err(QueueFull(3)));
        assert_eq!(drain(&mut q, 5), [(5, 2)]);
        assert_eq!(q.remove(new), None, "expired handles are stale too");
    }

    #[test]
    fn longest_delay_works() {
        let mut q: TimerQueue<u32, 2> = TimerQueue::new();
        let id = q.insert(u32::MAX, 7).unwrap();
        assert_eq!(q.remaining(id), Some(u32::MAX));
        q.replace(id, 2).unwrap();
        assert_eq!(drain(&mut q, 2), [(2, 7)]);
    }
}

/// The wheel against a naive list from any starting tick: the clock near every level's block
/// boundary and across 2³², where the entries' low 32 bits of deadline wrap, so that entries
/// move down every level within a few thousand ticks. (`tests/properties.rs` drives the public
/// API from tick 0; the starting tick is not public.)
#[cfg(test)]
mod model {
    use super::*;
    use proptest::prelude::*;

    #[derive(Clone, Debug)]
    enum Op {
        Insert(u32),
        Replace(usize, u32),
        Remove(usize),
        Tick(u32),
    }

    /// Delays: short, around every level's width (2⁸, 2¹⁶, 2²², 2²⁸) and up to `u32::MAX`.
    fn delay() -> impl Strategy<Value = u32> {
        prop_oneof![
            0u32..300,
            (0usize..5, -40i64..40).prop_map(|(k, d)| {
                let edge = [256i64, 65_536, 1 << 22, 1 << 28, 1 << 32][k];
                u32::try_from((edge + d).clamp(0, i64::from(u32::MAX))).unwrap()
            }),
            any::<u32>(),
            Just(u32::MAX),
        ]
    }

    /// A starting tick a little before a block boundary of some level (a multiple of 2^s), or
    /// anywhere.
    fn start() -> impl Strategy<Value = u64> {
        prop_oneof![
            Just(0u64),
            (
                prop::sample::select(vec![8u32, 16, 22, 28, 32, 34, 40]),
                1u64..1 << 20,
                0u64..3000
            )
                .prop_map(|(s, m, back)| (m << s).saturating_sub(back)),
            0u64..1 << 62,
        ]
    }

    fn op() -> impl Strategy<Value = Op> {
        prop_oneof![
            3 => delay().prop_map(Op::Insert),
            1 => (any::<usize>(), delay()).prop_map(|(i, t)| Op::Replace(i, t)),
            1 => any::<usize>().prop_map(Op::Remove),
            3 => prop_oneof![1u32..3, 1u32..300, 200u32..3000].prop_map(Op::Tick),
        ]
    }

    proptest! {
        #[test]
        #[cfg_attr(miri, ignore = "thousands of ticks per case: too slow under Miri")]
        fn wheel_matches_a_naive_list_from_any_start(
            start in start(),
            ops in prop::collection::vec(op(), 1..60),
        ) {
            const N: usize = 12;
            let mut queue: TimerQueue<u32, N> = TimerQueue::new();
            queue.now = start;
            // (deadline, order, action): the obvious register.
            let mut naive: Vec<(u64, u64, u32)> = Vec::new();
            let (mut now, mut order, mut next_action) = (start, 0u64, 0u32);
            let mut handles: Vec<(TimerId, u32)> = Vec::new();
            for op in ops {
                match op {
                    Op::Insert(t) => {
                        next_action += 1;
                        match queue.insert(t, next_action) {
                            Ok(id) => {
                                prop_assert!(naive.len() < N);
                                handles.push((id, next_action));
                                order += 1;
                                naive.push((now + u64::from(t.max(1)), order, next_action));
                            }
                            Err(QueueFull(a)) => {
                                prop_assert_eq!(naive.len(), N);
                                prop_assert_eq!(a, next_action);
                            }
                        }
                    }
                    Op::Replace(i, t) if !handles.is_empty() => {
                        let (id, action) = handles[i % handles.len()];
                        let waiting = naive.iter().position(|e| e.2 == action);
                        prop_assert_eq!(queue.replace(id, t).is_ok(), waiting.is_some());
                        if let Some(p) = waiting {
                            order += 1;
                            naive[p] = (now + u64::from(t.max(1)), order, action);
                        }
                    }
                    Op::Remove(i) if !handles.is_empty() => {
                        let (id, action) = handles[i % handles.len()];
                        let waiting = naive.iter().position(|e| e.2 == action);
                        prop_assert_eq!(queue.remove(id), waiting.map(|_| action));
                        if let Some(p) = waiting {
                            naive.remove(p);
                        }
                    }
                    Op::Tick(k) => {
                        for _ in 0..k {
                            now += 1;
                            let mut due: Vec<_> =
                                naive.iter().copied().filter(|e| e.0 == now).collect();
                            due.sort_by_key(|e| e.1);
                            naive.retain(|e| e.0 != now);
                            let mut got = Vec::new();
                            queue.tick(|a| got.push(a));
                            prop_assert_eq!(got, due.iter().map(|e| e.2).collect::<Vec<_>>());
                        }
                    }
                    _ => {}
                }
                prop_assert_eq!(queue.now(), now);
                prop_assert_eq!(queue.len(), naive.len());
                for &(id, action) in &handles {
                    let want = naive
                        .iter()
                        .find(|e| e.2 == action)
                        .map(|e| u32::try_from(e.0 - now).unwrap());
                    prop_assert_eq!(queue.remaining(id), want);
                }
            }
        }
    }

    /// Every entry a cascade moves keeps its order among the entries of its deadline, on every
    /// level: 12 timers with the same deadline, inserted from far away to near, one per level
    /// and tick, come out in insertion order, also across 2³².
    #[test]
    #[cfg_attr(miri, ignore = "280 000 ticks: too slow under Miri")]
    fn same_deadline_from_every_level_keeps_insertion_order() {
        for start in [0u64, (1 << 32) - 70_000, (1 << 34) - 70_000, 12_345_678_901] {
            let mut q: TimerQueue<u32, 12> = TimerQueue::new();
            q.now = start;
            let deadline = start + 70_000;
            let mut want = Vec::new();
            for action in 0..12u32 {
                let ticks = u32::try_from(deadline - q.now).unwrap();
                q.insert(ticks, action).unwrap();
                want.push(action);
                // 70 000 → level 2, then down through level 1 to level 0 as the clock moves.
                for _ in 0..[1u64, 60_000, 5_000, 4_000, 700, 200, 30, 5, 3, 1, 1, 0]
                    [usize::try_from(action).unwrap()]
                {
                    q.tick(|_| panic!("nothing is due yet"));
                }
            }
            let mut got = Vec::new();
            while q.now < deadline {
                let tick = q.now + 1;
                q.tick(|a| got.push((tick, a)));
            }
            assert!(got.iter().all(|&(tick, _)| tick == deadline), "{got:?}");
            assert_eq!(got.iter().map(|g| g.1).collect::<Vec<_>>(), want);
        }
    }
}
