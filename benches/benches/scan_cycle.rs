//! `TimerQueue::tick` beside the count-down register at 16, 256, 4 096 and 10 000 timers (one expiry per
//! tick), and one full cycle at the 1977 plant's sizes.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use regler_benches::scan::{CountDownTimers, Plant1977, WheelTimers, cycle_1977, executive_1977};

fn timers(c: &mut Criterion) {
    let mut group = c.benchmark_group("timer_tick");
    group.throughput(Throughput::Elements(1));
    macro_rules! size {
        ($n:literal) => {
            let mut wheel = WheelTimers::<$n>::steady($n);
            group.bench_function(BenchmarkId::new("regler_timer_queue", $n), |b| {
                b.iter(|| black_box(wheel.tick()))
            });
            let mut naive = CountDownTimers::steady($n);
            group.bench_function(BenchmarkId::new("count_down_register", $n), |b| {
                b.iter(|| black_box(naive.tick()))
            });
        };
    }
    size!(16);
    size!(256);
    size!(4096);
    size!(10000);
    group.finish();
}

fn full_cycle(c: &mut Criterion) {
    let mut group = c.benchmark_group("full_cycle_544_in_240_out");
    group.throughput(Throughput::Elements(1));
    let mut plc = executive_1977();
    let mut plant = Plant1977::default();
    group.bench_function("regler_executive", |b| {
        b.iter(|| cycle_1977(&mut plc, &mut plant))
    });
    group.finish();
}

criterion_group!(benches, timers, full_cycle);
criterion_main!(benches);
