//! An indexed binary min-heap of deadlines: the master's earliest-deadline-first choice in
//! O(1), a deadline change in O(log n).

/// Keys of `S` members (indices `0..S`); `u64::MAX` means "nothing owed" and sorts last.
/// Ties go to the lower index, so decisions are deterministic.
#[derive(Debug, Clone)]
pub(crate) struct Edf<const S: usize> {
    keys: [u64; S],
    /// heap[k] = member at heap position k.
    heap: [u16; S],
    /// pos[m] = heap position of member m.
    pos: [u16; S],
}

impl<const S: usize> Edf<S> {
    pub(crate) const fn new() -> Self {
        const { assert!(S <= 1 << 16, "at most 65 536 slaves") };
        let mut heap = [0u16; S];
        let mut i = 0;
        #[allow(
            clippy::cast_possible_truncation,
            clippy::indexing_slicing,
            clippy::arithmetic_side_effects,
            reason = "i < S <= 65 536: in bounds, fits in u16, cannot overflow"
        )]
        while i < S {
            heap[i] = i as u16;
            i += 1;
        }
        Self {
            keys: [u64::MAX; S],
            heap,
            pos: heap,
        }
    }

    /// The member with the earliest key, and the key; `None` if every key is `u64::MAX`.
    pub(crate) fn earliest(&self) -> Option<(usize, u64)> {
        let member = usize::from(*self.heap.first()?);
        let key = *self.keys.get(member)?;
        (key != u64::MAX).then_some((member, key))
    }

    /// Sets a member's key and restores the heap order. Unknown members are ignored.
    pub(crate) fn set(&mut self, member: usize, key: u64) {
        let Some(old) = self.keys.get_mut(member) else {
            return;
        };
        let previous = core::mem::replace(old, key);
        let Some(&at) = self.pos.get(member) else {
            return;
        };
        let at = usize::from(at);
        if key < previous {
            self.sift_up(at);
        } else if key > previous {
            self.sift_down(at);
        }
    }

    fn before(&self, a: usize, b: usize) -> bool {
        // Heap positions → members → (key, member) order.
        let (Some(&ma), Some(&mb)) = (self.heap.get(a), self.heap.get(b)) else {
            return false;
        };
        let ka = self.keys.get(usize::from(ma)).copied().unwrap_or(u64::MAX);
        let kb = self.keys.get(usize::from(mb)).copied().unwrap_or(u64::MAX);
        (ka, ma) < (kb, mb)
    }

    fn swap(&mut self, a: usize, b: usize) {
        if a >= S || b >= S {
            return;
        }
        self.heap.swap(a, b);
        for at in [a, b] {
            if let Some(&member) = self.heap.get(at) {
                if let (Some(slot), Ok(at)) =
                    (self.pos.get_mut(usize::from(member)), u16::try_from(at))
                {
                    *slot = at;
                }
            }
        }
    }

    fn sift_up(&mut self, mut at: usize) {
        while at > 0 {
            let parent = at.saturating_sub(1) / 2;
            if !self.before(at, parent) {
                break;
            }
            self.swap(at, parent);
            at = parent;
        }
    }

    fn sift_down(&mut self, mut at: usize) {
        loop {
            let left = at.saturating_mul(2).saturating_add(1);
            if left >= S {
                break;
            }
            let right = left.saturating_add(1);
            let child = if right < S && self.before(right, left) {
                right
            } else {
                left
            };
            if !self.before(child, at) {
                break;
            }
            self.swap(at, child);
            at = child;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// After any sequence of key changes the heap names the member a linear scan names.
        #[test]
        fn earliest_matches_a_linear_scan(
            changes in proptest::collection::vec((0usize..12, prop_oneof![Just(u64::MAX), 0u64..50]), 0..200)
        ) {
            let mut edf: Edf<12> = Edf::new();
            let mut model = [u64::MAX; 12];
            for (member, key) in changes {
                edf.set(member, key);
                model[member] = key;
                let expected = (0..12)
                    .filter(|&m| model[m] != u64::MAX)
                    .min_by_key(|&m| (model[m], m))
                    .map(|m| (m, model[m]));
                prop_assert_eq!(edf.earliest(), expected);
            }
        }
    }

    #[test]
    fn empty_and_unknown_members() {
        let mut edf: Edf<3> = Edf::new();
        assert_eq!(edf.earliest(), None);
        edf.set(7, 1);
        assert_eq!(edf.earliest(), None);
        let mut none: Edf<0> = Edf::new();
        none.set(0, 1);
        assert_eq!(none.earliest(), None);
    }
}
