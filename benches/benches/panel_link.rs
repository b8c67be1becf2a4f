//! Serial-highway `encode` and `decode`, and a crate controller passing the loop's traffic on,
//! each beside a plain byte copy of the same bytes — the practical limit of any codec.
//! Throughput is in bytes of encoded messages, so the figure to read is the ratio to the copy.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use regler_benches::highway::{Registers, copy_all, decode_all, encode_all, encoded, workload};
use regler_panel_link::highway::{Controller, ControllerConfig};

fn codec(c: &mut Criterion) {
    let messages = workload();
    let (bytes, lens) = encoded(&messages);
    let mut out = vec![0u8; bytes.len()];

    let mut group = c.benchmark_group("highway_encode_1024_messages");
    group.throughput(Throughput::Bytes(bytes.len() as u64));
    group.bench_function("regler_encode", |b| {
        b.iter(|| encode_all(black_box(&messages), &mut out))
    });
    group.bench_function("plain_copy", |b| {
        b.iter(|| copy_all(black_box(&bytes), &lens, &mut out))
    });
    group.finish();

    let mut group = c.benchmark_group("highway_decode_1024_messages");
    group.throughput(Throughput::Bytes(bytes.len() as u64));
    group.bench_function("regler_decode", |b| {
        b.iter(|| decode_all(black_box(&bytes), &lens))
    });
    group.bench_function("plain_copy", |b| {
        b.iter(|| copy_all(black_box(&bytes), &lens, &mut out))
    });
    group.finish();
}

fn controller(c: &mut Criterion) {
    let (bytes, _) = encoded(&workload());
    let mut out = vec![0u8; bytes.len()];
    let mut group = c.benchmark_group("controller_stream");
    group.throughput(Throughput::Bytes(bytes.len() as u64));
    let mut crate_ = Registers([0; 32]);
    let mut ctl = Controller::new(ControllerConfig {
        address: 7,
        demand_repeat: 0,
    })
    .expect("valid address");
    group.bench_function("regler_controller_clock", |b| {
        b.iter(|| {
            for (o, &i) in out.iter_mut().zip(black_box(&bytes)) {
                *o = ctl.clock(i, &mut crate_);
            }
        });
    });
    group.bench_function("plain_copy_with_one_byte_delay", |b| {
        b.iter(|| {
            let mut held = 0xE0u8;
            for (o, &i) in out.iter_mut().zip(black_box(&bytes)) {
                *o = held;
                held = i;
            }
        });
    });
    group.finish();
}

criterion_group!(benches, codec, controller);
criterion_main!(benches);
