//! The timer shift register of the 1977 plant, with O(1) ticks: a hierarchical timing wheel.

use core::fmt;

const BITS: u32 = 6;
const SLOTS: usize = 1 << BITS;
/// Six levels of 64 slots cover deadlines up to 2³⁶ ticks ahead: more than any `u32` delay.
const LEVELS: usize = 6;
const LEVELS_U32: u32 = 6;
const NIL: u32 = u32::MAX;

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
            "no waiting timer has handle {:?}: it expired or was removed",
            self.0
        )
    }
}

impl core::error::Error for UnknownTimer {}

#[derive(Clone, Debug)]
struct Entry<A> {
    action: Option<A>,
    deadline: u64,
    generation: u64,
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
/// wheel (six levels of 64 slots): `insert`, `replace` and `remove` are O(1); a tick looks at one
/// slot, and every 64ᵏ ticks moves one slot's entries a level down, so each entry is touched a
/// bounded number of times (at most six) in its life: O(1) amortised per tick, whatever the
/// number of timers. `N` entries fit; nothing is allocated. Memory: the slot table takes 3 KiB
/// (384 slots, head and tail each a `u32`) whatever `N`, 16 bytes of counters, and per entry
/// `size_of::<Option<A>>() + 26` bytes rounded up to a multiple of 8 (32 for `u8`, 40 for `u32`
/// actions): `TimerQueue<u32, 4096>` is 167 KB, so [`new`](TimerQueue::new) is a `const fn` and
/// such a queue belongs in a `static`. A unit test checks the formula.
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
    heads: [u32; LEVELS * SLOTS],
    tails: [u32; LEVELS * SLOTS],
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
            heads: [NIL; LEVELS * SLOTS],
            tails: [NIL; LEVELS * SLOTS],
            free: 0,
            len: 0,
            now: 0,
        }
    }

    /// Inserts a timer that expires after `ticks` ticks (0 counts as 1) with `action`.
    pub fn insert(&mut self, ticks: u32, action: A) -> Result<TimerId, QueueFull<A>> {
        let index = self.free;
        let deadline = self.deadline(ticks);
        let Some(entry) = self.entries.get_mut(idx(index)) else {
            return Err(QueueFull(action));
        };
        self.free = entry.next;
        entry.action = Some(action);
        entry.deadline = deadline;
        let generation = entry.generation;
        self.link(index);
        self.len = self.len.saturating_add(1);
        Ok(TimerId { index, generation })
    }

    /// Gives a waiting timer a new time: it expires after `ticks` ticks from now (0 counts as 1)
    /// and, among timers expiring in the same tick, after those inserted or replaced before.
    pub fn replace(&mut self, id: TimerId, ticks: u32) -> Result<(), UnknownTimer> {
        if !self.is_waiting(id) {
            return Err(UnknownTimer(id));
        }
        self.unlink(id.index);
        let deadline = self.deadline(ticks);
        if let Some(e) = self.entries.get_mut(idx(id.index)) {
            e.deadline = deadline;
        }
        self.link(id.index);
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

    /// Ticks pending before `id` expires (≥ 1), or `None` for a stale handle.
    #[must_use]
    pub fn remaining(&self, id: TimerId) -> Option<u32> {
        let e = self
            .entries
            .get(idx(id.index))
            .filter(|_| self.is_waiting(id))?;
        u32::try_from(e.deadline.saturating_sub(self.now)).ok()
    }

    /// One tick: every action whose time has come goes to `on_expire`, in order.
    pub fn tick(&mut self, mut on_expire: impl FnMut(A)) {
        self.now = self.now.wrapping_add(1);
        // Entering a new block at level k (the low 6k bits of now are zero): move that level's
        // slot for the block down. Most ticks enter no block at all.
        if self.now.trailing_zeros() >= BITS {
            let zeros = self.now.trailing_zeros();
            for level in (1..LEVELS_U32).rev() {
                let shift = BITS.wrapping_mul(level);
                if zeros >= shift {
                    self.cascade(level_slot(level as usize, self.now.wrapping_shr(shift)));
                }
            }
        }
        let slot = level_slot(0, self.now);
        let mut index = self.heads.get(slot).copied().unwrap_or(NIL);
        if let Some(h) = self.heads.get_mut(slot) {
            *h = NIL;
        }
        if let Some(t) = self.tails.get_mut(slot) {
            *t = NIL;
        }
        while index != NIL {
            let next = self.entries.get(idx(index)).map_or(NIL, |e| e.next);
            if let Some(action) = self.release(index) {
                on_expire(action);
            }
            index = next;
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

    fn deadline(&self, ticks: u32) -> u64 {
        self.now.saturating_add(u64::from(ticks.max(1)))
    }

    fn is_waiting(&self, id: TimerId) -> bool {
        self.entries
            .get(idx(id.index))
            .is_some_and(|e| e.generation == id.generation && e.action.is_some())
    }

    /// The slot for a deadline: the level is the highest 6-bit group in which it differs from now.
    #[inline]
    fn slot_for(&self, deadline: u64) -> usize {
        // `| 1` makes "no difference" level 0; the level is at most 63 / 6 = 10, capped at 5,
        // so the slot is below LEVELS * SLOTS and the lookups below need no bounds failure path.
        let top = 63u32.wrapping_sub((deadline ^ self.now | 1).leading_zeros());
        let level = (top / BITS).min(LEVELS_U32.wrapping_sub(1));
        level_slot(
            level as usize,
            deadline.wrapping_shr(level.wrapping_mul(BITS)),
        )
    }

    #[inline]
    fn link(&mut self, index: u32) {
        let Some(entry) = self.entries.get(idx(index)) else {
            return;
        };
        let slot = self.slot_for(entry.deadline);
        let (Some(&tail), Some(head)) = (self.tails.get(slot), self.heads.get_mut(slot)) else {
            return;
        };
        if tail == NIL {
            *head = index;
        } else if let Some(t) = self.entries.get_mut(idx(tail)) {
            t.next = index;
        }
        if let Some(t) = self.tails.get_mut(slot) {
            *t = index;
        }
        if let Some(e) = self.entries.get_mut(idx(index)) {
            e.prev = tail;
            e.next = NIL;
            e.slot = u16::try_from(slot).unwrap_or(0);
        }
    }

    fn unlink(&mut self, index: u32) {
        let Some((prev, next, slot)) = self
            .entries
            .get(idx(index))
            .map(|e| (e.prev, e.next, usize::from(e.slot)))
        else {
            return;
        };
        match self.entries.get_mut(idx(prev)) {
            Some(p) => p.next = next,
            None => {
                if let Some(h) = self.heads.get_mut(slot) {
                    *h = next;
                }
            }
        }
        match self.entries.get_mut(idx(next)) {
            Some(n) => n.prev = prev,
            None => {
                if let Some(t) = self.tails.get_mut(slot) {
                    *t = prev;
                }
            }
        }
    }

    /// Frees an entry (already unlinked) and returns its action; the handle goes stale.
    fn release(&mut self, index: u32) -> Option<A> {
        let e = self.entries.get_mut(idx(index))?;
        let action = e.action.take()?;
        e.prev = NIL;
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

    /// Moves every entry of `slot` to where it belongs now (a lower level), keeping its order.
    fn cascade(&mut self, slot: usize) {
        let mut index = self.heads.get(slot).copied().unwrap_or(NIL);
        if let Some(h) = self.heads.get_mut(slot) {
            *h = NIL;
        }
        if let Some(t) = self.tails.get_mut(slot) {
            *t = NIL;
        }
        while index != NIL {
            let next = self.entries.get(idx(index)).map_or(NIL, |e| e.next);
            self.link(index);
            index = next;
        }
    }
}

#[inline]
#[allow(
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "level < LEVELS and the masked value < SLOTS: the slot is below LEVELS * SLOTS"
)]
fn level_slot(level: usize, value: u64) -> usize {
    const MASK: u64 = (1 << BITS) - 1;
    level.min(LEVELS - 1) * SLOTS + (value & MASK) as usize
}

fn idx(index: u32) -> usize {
    usize::try_from(index).unwrap_or(usize::MAX)
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
        // 3 KiB of slot heads and tails, 16 bytes of counters and the clock, and per entry the
        // action, a u64 deadline, a u64 generation and 2 u32 + a u16 of links (padded to the
        // entry's alignment).
        let entry = |action: usize| (action + 8 + 8 + 2 * 4 + 2).next_multiple_of(8);
        assert_eq!(size_of::<Entry<u8>>(), entry(2)); // Option<u8> is 2 bytes
        let table = 2 * 6 * 64 * 4;
        let counters = 4 + size_of::<usize>() + 8;
        let size = |entries: usize| (table + counters + entries).next_multiple_of(8);
        assert_eq!(size_of::<TimerQueue<u8, 4096>>(), size(4096 * entry(2)));
        assert_eq!(size_of::<TimerQueue<u32, 16>>(), size(16 * entry(8)));
        assert_eq!(size_of::<TimerQueue<u32, 4096>>(), 166_936, "167 KB");
        assert_eq!(entry(2), 32);
        assert_eq!(entry(8), 40);
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
