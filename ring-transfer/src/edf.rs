//! An indexed binary min-heap of deadlines: the master's earliest-deadline-first choice in
//! O(1), a deadline change in O(log n).

/// Keys of `S` members (indices `0..S`); `None` means "nothing owed" and sorts after every
/// deadline, `u64::MAX` included (a deadline that saturated at the clock's end is still owed).
/// Ties go to the lower index, so decisions are deterministic.
#[derive(Debug, Clone)]
pub(crate) struct Edf<const S: usize> {
    keys: [Option<u64>; S],
    /// heap[k] = member at heap position k.
    heap: [u16; S],
    /// pos[m] = heap position of member m.
    pos: [u16; S],
}

/// A key's place in the order: every deadline before "nothing owed".
fn order(key: Option<u64>) -> (bool, u64) {
    key.map_or((true, 0), |k| (false, k))
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
            keys: [None; S],
            heap,
            pos: heap,
        }
    }

    /// The member with the earliest key, and the key; `None` if no member has a key.
    pub(crate) fn earliest(&self) -> Option<(usize, u64)> {
        let member = usize::from(*self.heap.first()?);
        let key = (*self.keys.get(member)?)?;
        Some((member, key))
    }

    /// Sets a member's key and restores the heap order. Unknown members are ignored.
    pub(crate) fn set(&mut self, member: usize, key: Option<u64>) {
        let Some(old) = self.keys.get_mut(member) else {
            return;
        };
        let previous = core::mem::replace(old, key);
        let Some(&at) = self.pos.get(member) else {
            return;
        };
        let at = usize::from(at);
        if order(key) < order(previous) {
            self.sift_up(at);
        } else if order(key) > order(previous) {
            self.sift_down(at);
        }
    }

    fn before(&self, a: usize, b: usize) -> bool {
        // Heap positions → members → (key, member) order.
        let (Some(&ma), Some(&mb)) = (self.heap.get(a), self.heap.get(b)) else {
            return false;
        };
        let ka = order(self.keys.get(usize::from(ma)).copied().flatten());
        let kb = order(self.keys.get(usize::from(mb)).copied().flatten());
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
        /// After any sequence of key changes the heap names the member a linear scan names
        /// (up to 200 changes; 10 under Miri).
        #[test]
        fn earliest_matches_a_linear_scan(
            changes in proptest::collection::vec(
                (0usize..12, prop_oneof![Just(None), Just(Some(u64::MAX)), Just(Some(u64::MAX - 1)), (0u64..50).prop_map(Some)]),
                0..if cfg!(miri) { 10 } else { 200 },
            )
        ) {
            let mut edf: Edf<12> = Edf::new();
            let mut model: [Option<u64>; 12] = [None; 12];
            for (member, key) in changes {
                edf.set(member, key);
                model[member] = key;
                let expected = (0..12)
                    .filter_map(|m| model[m].map(|k| (k, m)))
                    .min()
                    .map(|(k, m)| (m, k));
                prop_assert_eq!(edf.earliest(), expected);
            }
        }
    }

    #[test]
    fn empty_and_unknown_members() {
        let mut edf: Edf<3> = Edf::new();
        assert_eq!(edf.earliest(), None);
        edf.set(7, Some(1));
        assert_eq!(edf.earliest(), None);
        let mut none: Edf<0> = Edf::new();
        none.set(0, Some(1));
        assert_eq!(none.earliest(), None);
    }
}
