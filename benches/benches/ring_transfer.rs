//! The ring beside its anchors, in one run: `receive` + `next` pairs on a half-full byte ring —
//! the crate's `Ring<u8, 256>` (statistics on) and split halves, `heapless::spsc::Queue<u8, 256>`
//! (and `<u8, 257>`, which holds 256 like `Ring<u8, 256>`) used directly and through its own
//! halves, a plain array ring — in the firmware and the inlined shape; two threads moving 1 million items
//! through the split halves and through heapless's; and the master's scheduling decision with 8,
//! 80 and 500 slaves.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use heapless::spsc::Queue;
use regler_benches::master::Scheduler;
use regler_benches::ring_pairs::{SLOTS, Shape, run};
use regler_ring_transfer::SharedRing;

/// 10 000 pairs per iteration (the ring's set-up, a box and 128 items, is about 1 % of that) through the shared loop (`regler_benches::ring_pairs`), each
/// contestant in both shapes: `firmware` (each operation an out-of-line call on state in memory)
/// and `inlined` (a tight loop owning the ring).
fn pairs(c: &mut Criterion) {
    for (shape_name, shape) in [("firmware", Shape::Firmware), ("inlined", Shape::Inlined)] {
        let mut group = c.benchmark_group(format!("ring/pair/{shape_name}/10000"));
        group.throughput(Throughput::Elements(10_000));
        for (name, which) in [
            ("regler Ring 256", "ring"),
            ("heapless spsc Queue 256", "spsc"),
            ("heapless spsc Queue 257", "spsc-257"),
            ("regler Filler+Drainer 256", "split"),
            ("heapless Producer+Consumer 256", "spsc-split"),
            ("plain array ring 256", "array"),
            ("none (the loop alone)", "none"),
        ] {
            group.bench_function(name, |b| {
                b.iter(|| run(black_box(which), black_box(shape), 10_000))
            });
        }
        group.finish();
    }
}

const TRANSFER: u32 = 1_000_000;

/// Moves `TRANSFER` items from a producer thread (`push`, spinning while full) to this thread
/// (`pop`); returns their sum.
fn transfer(
    mut push: impl FnMut(u32) -> Result<(), u32> + Send,
    mut pop: impl FnMut() -> Option<u32>,
) -> u64 {
    std::thread::scope(|s| {
        s.spawn(move || {
            for i in 0..TRANSFER {
                let mut item = i;
                while let Err(back) = push(item) {
                    item = back;
                    std::hint::spin_loop();
                }
            }
        });
        let (mut sum, mut got) = (0u64, 0);
        while got < TRANSFER {
            if let Some(item) = pop() {
                sum = sum.wrapping_add(u64::from(item));
                got += 1;
            }
        }
        sum
    })
}

fn two_threads(c: &mut Criterion) {
    let mut group = c.benchmark_group("ring/two-thread transfer");
    group.sample_size(10);
    group.throughput(Throughput::Elements(u64::from(TRANSFER)));
    group.bench_function("regler Filler+Drainer", |b| {
        b.iter(|| {
            let mut shared: Box<SharedRing<u32, SLOTS>> = Box::default();
            let (mut filler, mut drainer) = shared.split();
            black_box(transfer(|x| filler.receive(x), || drainer.next()))
        })
    });
    group.bench_function("heapless Producer+Consumer", |b| {
        b.iter(|| {
            let mut queue: Box<Queue<u32, SLOTS>> = Box::default();
            let (mut producer, mut consumer) = queue.split();
            black_box(transfer(|x| producer.enqueue(x), || consumer.dequeue()))
        })
    });
    group.finish();
}

/// A master with `n` slaves of mixed rates and rings in steady state
/// (`regler_benches::master`): each iteration is one decision (`next_refill`) and the served
/// slave's next report (one heap update each).
fn scheduler(c: &mut Criterion) {
    let mut group = c.benchmark_group("ring/scheduler decision");
    for n in [8usize, 80, 500] {
        let mut scheduler = Scheduler::new(n).expect("slaves in range");
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| black_box(scheduler.step()))
        });
    }
    group.finish();
}

criterion_group!(benches, pairs, two_threads, scheduler);
criterion_main!(benches);
