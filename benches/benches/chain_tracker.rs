//! One chain pulse with 16, 256, 4 096 and 10 000 trolleys on the chain: the tracker beside the
//! source's count-down shift register, fed the same steady stream of entering trolleys.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use regler_benches::count_down::CountDown;
use regler_benches::dock::{Feed, TIPPERS, distances};
use regler_chain_tracker::{DistanceTable, Tracker};

const HOLD: u32 = 6;

fn warmed_tracker<const N: usize>(trolleys: u32) -> (Tracker<u32, N, TIPPERS>, Feed) {
    let d = distances(trolleys);
    let table = DistanceTable::new(1000, &d).expect("bench table");
    let mut tracker = Tracker::new(table, HOLD).expect("bench tracker");
    let mut feed = Feed::new();
    for _ in 0..2 * d.iter().max().copied().unwrap_or(1) {
        step_tracker(&mut tracker, &mut feed);
    }
    (tracker, feed)
}

fn step_tracker<const N: usize>(tracker: &mut Tracker<u32, N, TIPPERS>, feed: &mut Feed) -> u32 {
    if let Some((trolley, tipper)) = feed.step() {
        tracker
            .enter(trolley, tipper)
            .expect("capacity is twice the mean load");
    }
    let mut events = 0;
    tracker.pulse(|_| events += 1);
    events
}

fn warmed_count_down(trolleys: u32) -> (CountDown, Feed) {
    let d = distances(trolleys);
    let mut feed = Feed::new();
    let warm = 2 * u64::from(d.iter().max().copied().unwrap_or(1));
    let register = CountDown::warmed(&d, HOLD, 2 * trolleys as usize, &mut feed, warm);
    (register, feed)
}

fn step_count_down(register: &mut CountDown, feed: &mut Feed) -> u32 {
    if let Some((trolley, tipper)) = feed.step() {
        register.enter(trolley, tipper);
    }
    let mut events = 0;
    register.pulse(|_| events += 1);
    events
}

fn bench_size<const N: usize>(c: &mut Criterion, trolleys: u32) {
    let mut group = c.benchmark_group("chain_pulse");
    group.throughput(Throughput::Elements(1));
    let (mut tracker, mut feed) = warmed_tracker::<N>(trolleys);
    assert!(tracker.len().abs_diff(trolleys as usize) <= trolleys as usize / 5 + 5);
    group.bench_function(BenchmarkId::new("regler_tracker", trolleys), |b| {
        b.iter(|| black_box(step_tracker(&mut tracker, &mut feed)));
    });
    let (mut register, mut feed) = warmed_count_down(trolleys);
    group.bench_function(BenchmarkId::new("count_down_register", trolleys), |b| {
        b.iter(|| black_box(step_count_down(&mut register, &mut feed)));
    });
    group.finish();
}

fn chain_pulse(c: &mut Criterion) {
    bench_size::<32>(c, 16);
    bench_size::<512>(c, 256);
    bench_size::<8192>(c, 4_096);
    bench_size::<20_480>(c, 10_000);
}

criterion_group!(benches, chain_pulse);
criterion_main!(benches);
