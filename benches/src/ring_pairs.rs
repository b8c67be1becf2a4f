//! One `receive` + `next` pair on a half-full byte ring, for each contestant, in two shapes.
//!
//! Contestants: the crate's `Ring<u8, 256>` (statistics on, holds 256) and its split halves
//! (`SharedRing<u8, 256>` → `Filler` + `Drainer`, holds 256); the anchor
//! `heapless::spsc::Queue<u8, 256>` (a power of two, as heapless's docs ask; holds 255) used
//! directly and through its own `Producer` + `Consumer`; `Queue<u8, 257>` (holds 256, the same
//! number of items as `Ring<u8, 256>`, but its index arithmetic becomes a modulo); and a plain
//! array ring (the naive algorithm).
//!
//! Shapes ([`Shape`]):
//! - **firmware**: each operation is one out-of-line call (`#[inline(never)]`) on a `&mut` the
//!   compiler cannot see through (`black_box`), so the ring's state lives in memory between
//!   operations — as an interrupt handler fills a ring and a main loop drains it;
//! - **inlined**: a tight loop that owns the ring, both operations inlined, every contestant
//!   equally visible to the optimizer (which may keep a plain ring's indices in registers; it
//!   cannot do that through heapless's atomics).
//!
//! Every contestant runs the same generic loop (`pairs`): the same item sequence, the same
//! harness work (item counter, `black_box` on the item, an order-sensitive checksum of what came
//! out), so the difference between two rows is the rings' own work.

use std::hint::black_box;

use heapless::spsc::{Consumer, Producer, Queue};
use regler_ring_transfer::{Drainer, Filler, Ring, SharedRing};

/// Slots in every contestant (`Queue<u8, 257>` aside).
pub const SLOTS: usize = 256;

/// A plain array ring: the naive algorithm (power-of-two size, wrapping indices).
#[derive(Debug)]
pub struct ArrayRing {
    items: [u8; SLOTS],
    read: usize,
    write: usize,
}

impl Default for ArrayRing {
    fn default() -> Self {
        Self {
            items: [0; SLOTS],
            read: 0,
            write: 0,
        }
    }
}

impl ArrayRing {
    /// Stores at the write index; `Err` when full.
    pub fn push(&mut self, item: u8) -> Result<(), u8> {
        if self.write.wrapping_sub(self.read) == SLOTS {
            return Err(item);
        }
        if let Some(slot) = self.items.get_mut(self.write % SLOTS) {
            *slot = item;
        }
        self.write = self.write.wrapping_add(1);
        Ok(())
    }

    /// Takes at the read index.
    pub fn pop(&mut self) -> Option<u8> {
        if self.read == self.write {
            return None;
        }
        let item = self.items.get(self.read % SLOTS).copied();
        self.read = self.read.wrapping_add(1);
        item
    }
}

/// A ring on the shared loop: `push` is `receive`/`enqueue`, `pop` is `next`/`dequeue`.
pub trait Fifo {
    /// Stores an item; `Err` hands it back when full.
    fn push(&mut self, item: u8) -> Result<(), u8>;
    /// Takes the oldest item; `None` when empty.
    fn pop(&mut self) -> Option<u8>;
}

impl Fifo for Ring<u8, SLOTS> {
    #[inline(always)]
    fn push(&mut self, item: u8) -> Result<(), u8> {
        self.receive(item)
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<u8> {
        self.next()
    }
}

impl<const S: usize> Fifo for Queue<u8, S> {
    #[inline(always)]
    fn push(&mut self, item: u8) -> Result<(), u8> {
        self.enqueue(item)
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<u8> {
        self.dequeue()
    }
}

impl Fifo for ArrayRing {
    #[inline(always)]
    fn push(&mut self, item: u8) -> Result<(), u8> {
        ArrayRing::push(self, item)
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<u8> {
        ArrayRing::pop(self)
    }
}

/// regler's split halves, side by side (the firmware shape calls each half out of line).
pub struct Halves<'a>(pub Filler<'a, u8, SLOTS>, pub Drainer<'a, u8, SLOTS>);

impl Fifo for Halves<'_> {
    #[inline(always)]
    fn push(&mut self, item: u8) -> Result<(), u8> {
        self.0.receive(item)
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<u8> {
        self.1.next()
    }
}

/// heapless's split halves, side by side.
pub struct SpscHalves<'a>(pub Producer<'a, u8>, pub Consumer<'a, u8>);

impl Fifo for SpscHalves<'_> {
    #[inline(always)]
    fn push(&mut self, item: u8) -> Result<(), u8> {
        self.0.enqueue(item)
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<u8> {
        self.1.dequeue()
    }
}

/// No ring: `pop` hands back the last item pushed. The loop's own cost in each shape (the item,
/// the checksum, in the firmware shape the two calls), subtracted to get a ring's net cost per
/// pair. Not a contestant: what comes out is not what a ring gives.
#[derive(Default)]
pub struct Null(u8);

impl Fifo for Null {
    #[inline(always)]
    fn push(&mut self, item: u8) -> Result<(), u8> {
        self.0 = item;
        Ok(())
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<u8> {
        Some(self.0)
    }
}

/// How the ring meets the loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Each operation one out-of-line call on a `&mut` the compiler cannot see through.
    Firmware,
    /// Both operations inlined into a loop that owns the ring.
    Inlined,
}

impl Shape {
    /// By name: `firmware`, `inlined`.
    #[must_use]
    pub fn parse(name: &str) -> Option<Shape> {
        match name {
            "firmware" => Some(Shape::Firmware),
            "inlined" => Some(Shape::Inlined),
            _ => None,
        }
    }
}

/// One `receive`, out of line (the firmware shape's interrupt handler). The `black_box` on the
/// reference keeps the state in memory on both sides of the call: without it LLVM may promote a
/// small contestant's fields to arguments, loaded in the caller (it did so for heapless's halves
/// and not for regler's, so the loops differed).
#[inline(never)]
fn push_call<F: Fifo>(f: &mut F, item: u8) -> Result<(), u8> {
    black_box(f).push(item)
}

/// One `next`, out of line (the firmware shape's main loop), as [`push_call`].
#[inline(never)]
fn pop_call<F: Fifo>(f: &mut F) -> Option<u8> {
    black_box(f).pop()
}

/// The checksum step: order-sensitive, an underrun (`None`) counts as 256, so two rings give
/// the same checksum only if the same items came out in the same order.
#[inline(always)]
fn mix(sum: u64, item: Option<u8>) -> u64 {
    sum.wrapping_mul(31)
        .wrapping_add(item.map_or(256, u64::from))
}

/// The shared loop: fills `f` half (`SLOTS / 2` zeros), then runs `pairs` pairs, items 1, 2, 3, …
/// (wrapping at 256); returns the checksum of what came out. `FIRMWARE` picks the shape at
/// compile time, so neither shape pays a test per operation.
#[inline(always)]
fn pairs<F: Fifo, const FIRMWARE: bool>(f: &mut F, pairs: u64) -> u64 {
    for _ in 0..SLOTS / 2 {
        let _ = f.push(0);
    }
    let mut sum = 0u64;
    let mut x = 0u8;
    for _ in 0..pairs {
        x = x.wrapping_add(1);
        let item = black_box(x);
        let out = if FIRMWARE {
            let _ = push_call(black_box(&mut *f), item);
            pop_call(black_box(&mut *f))
        } else {
            let _ = f.push(item);
            f.pop()
        };
        sum = mix(sum, out);
    }
    sum
}

/// Runs `n` pairs on `f` in `shape`.
#[inline(never)]
fn run_on<F: Fifo>(f: &mut F, shape: Shape, n: u64) -> u64 {
    match shape {
        Shape::Firmware => pairs::<F, true>(f, n),
        Shape::Inlined => pairs::<F, false>(f, n),
    }
}

/// The contestants' names, as [`run`] takes them.
pub const CONTESTANTS: [&str; 6] = ["ring", "spsc", "spsc-257", "split", "spsc-split", "array"];

/// Runs `n` pairs on the named contestant in `shape` and returns the checksum of what came out
/// (the same for every contestant: the test `every_contestant_carries_the_same_items` holds
/// them to it). Names: [`CONTESTANTS`], and `none` for the baseline ([`Null`]). The shape and
/// the contestant are chosen once, outside the loop.
#[must_use]
pub fn run(which: &str, shape: Shape, n: u64) -> Option<u64> {
    Some(match which {
        "ring" => run_on(&mut *Box::<Ring<u8, SLOTS>>::default(), shape, n),
        "spsc" => run_on(&mut *Box::<Queue<u8, SLOTS>>::default(), shape, n),
        "spsc-257" => run_on(&mut *Box::<Queue<u8, { SLOTS + 1 }>>::default(), shape, n),
        "split" => {
            let mut shared: Box<SharedRing<u8, SLOTS>> = Box::default();
            let (filler, drainer) = shared.split();
            run_on(&mut Halves(filler, drainer), shape, n)
        }
        "spsc-split" => {
            let mut queue: Box<Queue<u8, SLOTS>> = Box::default();
            let (producer, consumer) = queue.split();
            run_on(&mut SpscHalves(producer, consumer), shape, n)
        }
        "array" => run_on(&mut *Box::<ArrayRing>::default(), shape, n),
        "none" => run_on(&mut *Box::<Null>::default(), shape, n),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, reason = "a test may panic: that is how it fails")]
    use super::*;
    use std::collections::VecDeque;

    /// What an unbounded FIFO gives for the same workload: the checksum every contestant must
    /// reproduce.
    fn model(n: u64) -> u64 {
        let mut q: VecDeque<u8> = std::iter::repeat_n(0, SLOTS / 2).collect();
        let (mut sum, mut x) = (0u64, 0u8);
        for _ in 0..n {
            x = x.wrapping_add(1);
            q.push_back(x);
            sum = mix(sum, q.pop_front());
        }
        sum
    }

    /// The harness compares like with like: every contestant, in both shapes, carries the same
    /// item sequence (nothing refused as full, nothing missing) and gives back the same items in
    /// the same order as an unbounded FIFO.
    #[test]
    fn every_contestant_carries_the_same_items() {
        for n in [0, 1, 127, 128, 129, 1000, 10_000] {
            let want = model(n);
            for shape in [Shape::Firmware, Shape::Inlined] {
                for which in CONTESTANTS {
                    assert_eq!(
                        run(which, shape, n),
                        Some(want),
                        "{which} {shape:?} {n} pairs"
                    );
                }
            }
        }
        // The checksum sees order and underruns: a swapped pair or a lost item changes it.
        assert_ne!(mix(mix(0, Some(1)), Some(2)), mix(mix(0, Some(2)), Some(1)));
        assert_ne!(mix(0, None), mix(0, Some(0)));
        assert_eq!(run("nothing", Shape::Inlined, 1), None);
    }
}
