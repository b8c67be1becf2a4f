//! `decode` beside a bit-by-bit decoder, and one passage through each voting strategy.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use regler_benches::naive_decode;
use regler_trolley_id::{Strategy, TrolleyId, Voter, decode, encode};

fn decode_all(c: &mut Criterion) {
    let mut group = c.benchmark_group("decode_8192_words");
    group.throughput(Throughput::Elements(8192));
    group.bench_function("regler_decode", |b| {
        b.iter(|| {
            (0u16..8192)
                .filter(|&w| decode(black_box(w)).is_ok())
                .count()
        });
    });
    group.bench_function("naive_bitwise_decode", |b| {
        b.iter(|| {
            (0u16..8192)
                .filter(|&w| naive_decode::decode(black_box(w)).is_some())
                .count()
        });
    });
    group.finish();
}

fn passages(c: &mut Criterion) {
    let word = encode(TrolleyId::new(1234).expect("valid number"));
    // Five scans of a passing trolley: one empty edge, one double misread.
    let readings = [0, word, word ^ 0b11, word, word];
    let mut group = c.benchmark_group("voter_passage_5_readings");
    group.throughput(Throughput::Elements(1));
    for (name, strategy) in [
        ("consecutive_k2", Strategy::Consecutive { k: 2 }),
        ("majority_min3", Strategy::Majority { min_samples: 3 }),
    ] {
        let mut voter = Voter::new(strategy).expect("valid strategy");
        group.bench_function(name, |b| b.iter(|| voter.vote(black_box(&readings))));
    }
    group.bench_function("single_read_decode", |b| {
        b.iter(|| decode(black_box(readings[1])))
    });
    group.finish();
}

criterion_group!(benches, decode_all, passages);
criterion_main!(benches);
