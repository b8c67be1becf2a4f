//! One `receive` + `next` pair on a half-full 256-slot ring of bytes, for each contestant: the
//! crate's `Ring` (statistics on) and split halves, `heapless::spsc::Queue` used directly and
//! through its own split halves, and a plain array ring (the naive algorithm). The same loop
//! shape for all, so criterion and callgrind compare like with like.

use std::hint::black_box;

use heapless::spsc::Queue;
use regler_ring_transfer::{Ring, SharedRing};

/// Slots in every contestant.
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

/// Runs `pairs` pairs on the named contestant and returns a checksum of what came out.
/// Names: `ring`, `split`, `spsc`, `spsc-split`, `array`.
pub fn run(which: &str, pairs: u64) -> Option<u64> {
    let mut sum = 0u64;
    let mut x = 0u8;
    macro_rules! pairs {
        (|$v:ident| $push:expr, $pop:expr) => {{
            for _ in 0..SLOTS / 2 {
                let $v = 0;
                let _ = $push;
            }
            for _ in 0..pairs {
                x = x.wrapping_add(1);
                let $v = black_box(x);
                let _ = $push;
                sum = sum.wrapping_add(u64::from($pop.unwrap_or(0)));
            }
        }};
    }
    match which {
        "ring" => {
            let mut ring: Box<Ring<u8, SLOTS>> = Box::default();
            pairs!(|v| ring.receive(v), ring.next());
            sum = sum.wrapping_add(u64::from(ring.stats().least_slack as u8));
        }
        "split" => {
            let mut shared: Box<SharedRing<u8, { SLOTS + 1 }>> = Box::default();
            let (mut filler, mut drainer) = shared.split();
            pairs!(|v| filler.receive(v), drainer.next());
        }
        "spsc" => {
            let mut queue: Box<Queue<u8, { SLOTS + 1 }>> = Box::default();
            pairs!(|v| queue.enqueue(v), queue.dequeue());
        }
        "spsc-split" => {
            let mut queue: Box<Queue<u8, { SLOTS + 1 }>> = Box::default();
            let (mut producer, mut consumer) = queue.split();
            pairs!(|v| producer.enqueue(v), consumer.dequeue());
        }
        "array" => {
            let mut ring = Box::<ArrayRing>::default();
            pairs!(|v| ring.push(v), ring.pop());
        }
        _ => return None,
    }
    Some(sum)
}
