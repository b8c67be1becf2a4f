//! The ring split into a filling half (the link interrupt) and a draining half (the machine loop).

use heapless::spsc::{Consumer, Producer, Queue};

use crate::ring::{Counters, Stats};

/// A ring whose filling and draining halves live in different execution contexts — interrupt
/// priorities or threads — built on [`heapless::spsc::Queue`] (no atomics or `unsafe` here).
///
/// `S` is the queue's storage size; it holds **`S − 1` items**, because heapless's lock-free
/// queue keeps one slot empty to tell full from empty. `SharedRing<u8, 257>` is a 256-byte ring.
///
/// [`split`](Self::split) hands out a [`Filler`] (`receive`, the request count and the
/// cumulative counters a report needs) and a [`Drainer`] (`next`, underruns). For `'static`
/// halves in firmware put the ring in a `static` through a once-cell such as `static_cell` or an
/// RTIC resource; in a thread program use `std::thread::scope`:
///
/// ```
/// use regler_ring_transfer::SharedRing;
///
/// let mut ring: SharedRing<u32, 17> = SharedRing::new();
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
/// ```
#[derive(Debug)]
pub struct SharedRing<T, const S: usize> {
    queue: Queue<T, S>,
}

impl<T, const S: usize> Default for SharedRing<T, S> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T, const S: usize> SharedRing<T, S> {
    /// An empty ring of `S − 1` slots; `const`, so it can live in a `static`. `S` must be at
    /// least 2 (checked when the program is compiled).
    #[must_use]
    pub const fn new() -> Self {
        const { assert!(S >= 2, "a SharedRing needs S >= 2 (it holds S - 1 items)") };
        Self {
            queue: Queue::new(),
        }
    }

    /// The number of slots, `S − 1`.
    #[must_use]
    pub const fn capacity(&self) -> usize {
        S.saturating_sub(1)
    }

    /// The two halves. They borrow the ring; each may move to its own context.
    pub fn split(&mut self) -> (Filler<'_, T>, Drainer<'_, T>) {
        let capacity = self.capacity();
        let (producer, consumer) = self.queue.split();
        (
            Filler {
                producer,
                received: 0,
                least_slack: capacity,
                capacity,
            },
            Drainer {
                consumer,
                consumed: 0,
                underruns: 0,
            },
        )
    }
}

/// The filling half: the link side. It stores refills at RP and answers what a request report
/// needs — the refills owed and the cumulative counters.
pub struct Filler<'a, T> {
    producer: Producer<'a, T>,
    received: u32,
    least_slack: usize,
    capacity: usize,
}

impl<T> core::fmt::Debug for Filler<'_, T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Filler")
            .field("capacity", &self.capacity)
            .field("held", &self.producer.len())
            .field("received", &self.received)
            .field("least_slack", &self.least_slack)
            .finish()
    }
}

impl<T> Filler<'_, T> {
    /// Stores `item` at RP.
    ///
    /// # Errors
    /// `Err(item)` when the ring is full (nothing stored, nothing counted).
    #[inline]
    pub fn receive(&mut self, item: T) -> Result<(), T> {
        self.producer.enqueue(item)?;
        self.received = self.received.wrapping_add(1);
        Ok(())
    }

    /// Refills owed now (free slots). Also samples the slack for [`stats`](Self::stats): the
    /// least slack is the least seen at these moments, which is when the link side looks.
    pub fn requests(&mut self) -> usize {
        let slack = self.producer.len();
        self.least_slack = self.least_slack.min(slack);
        self.capacity.saturating_sub(slack)
    }

    /// Items left before an underrun, as of now (the drainer may take more at any moment).
    #[must_use]
    pub fn slack(&self) -> usize {
        self.producer.len()
    }

    /// Cumulative counts for a report. `consumed` is derived as `received − held`, so a
    /// consumption racing with this call is reported next time — never one that did not happen.
    #[must_use]
    pub fn counters(&self) -> Counters {
        let held = u32::try_from(self.producer.len()).unwrap_or(u32::MAX);
        Counters {
            received: self.received,
            consumed: self.received.wrapping_sub(held),
        }
    }

    /// Least slack and most requests seen by [`requests`](Self::requests); underruns are
    /// counted by the [`Drainer`] (this half reports 0 for them).
    #[must_use]
    pub fn stats(&self) -> Stats {
        Stats {
            underruns: 0,
            least_slack: self.least_slack,
            most_requests: self.capacity.saturating_sub(self.least_slack),
        }
    }
}

/// The draining half: the machine side, taking items at SP.
pub struct Drainer<'a, T> {
    consumer: Consumer<'a, T>,
    consumed: u32,
    underruns: u32,
}

impl<T> core::fmt::Debug for Drainer<'_, T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Drainer")
            .field("consumed", &self.consumed)
            .field("underruns", &self.underruns)
            .finish()
    }
}

impl<T> Drainer<'_, T> {
    /// Takes the item at SP; `None` is an underrun and is counted.
    #[inline]
    #[allow(
        clippy::should_implement_trait,
        reason = "SP+1→SP as on `Ring`; None is an underrun, not the end"
    )]
    pub fn next(&mut self) -> Option<T> {
        let item = self.consumer.dequeue();
        if item.is_some() {
            self.consumed = self.consumed.wrapping_add(1);
        } else {
            self.underruns = self.underruns.saturating_add(1);
        }
        item
    }

    /// Underruns counted so far (saturating).
    #[must_use]
    pub fn underruns(&self) -> u32 {
        self.underruns
    }

    /// Items taken so far, wrapping at 2³².
    #[must_use]
    pub fn consumed(&self) -> u32 {
        self.consumed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn storage_of_s_holds_s_minus_one() {
        let mut ring: SharedRing<u8, 4> = SharedRing::new();
        assert_eq!(ring.capacity(), 3);
        let (mut fill, mut drain) = ring.split();
        assert_eq!(fill.requests(), 3);
        for b in 0..3 {
            fill.receive(b).unwrap();
        }
        assert_eq!(fill.receive(9), Err(9));
        assert_eq!(fill.requests(), 0);
        assert_eq!(drain.next(), Some(0));
        assert_eq!(
            fill.counters(),
            Counters {
                received: 3,
                consumed: 1
            }
        );
        assert_eq!(fill.requests(), 1);
        assert_eq!(
            (drain.next(), drain.next(), drain.next()),
            (Some(1), Some(2), None)
        );
        assert_eq!((drain.underruns(), drain.consumed()), (1, 3));
        assert_eq!(fill.requests(), 3);
        assert_eq!(fill.stats().least_slack, 0);
        assert_eq!(fill.stats().most_requests, 3);
    }

    #[test]
    fn the_smallest_ring_has_one_slot() {
        let mut ring: SharedRing<u8, 2> = SharedRing::new();
        let (mut fill, mut drain) = ring.split();
        fill.receive(1).unwrap();
        assert_eq!(fill.receive(2), Err(2));
        assert_eq!((drain.next(), drain.next()), (Some(1), None));
        assert_eq!(fill.requests(), 1);
    }
}
