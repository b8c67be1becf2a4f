//! A closed loop (controller + first-order plant) per sample: regler's `Pid` in f32, f64,
//! I16F16 and I32F32 with every feature on, beside the `pid` crate's P+I+D update.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use fixed::types::{I16F16, I32F32};
use regler_benches::pid_loop::{AnchorLoop, ReglerLoop};

fn closed_loop(c: &mut Criterion) {
    let mut group = c.benchmark_group("pid_closed_loop_sample");
    group.throughput(Throughput::Elements(1));
    let mut anchor = AnchorLoop::new();
    group.bench_function("pid_crate_f32", |b| b.iter(|| black_box(anchor.step())));
    let mut f32_loop = ReglerLoop::<f32>::new();
    group.bench_function("regler_f32", |b| b.iter(|| black_box(f32_loop.step())));
    let mut f64_loop = ReglerLoop::<f64>::new();
    group.bench_function("regler_f64", |b| b.iter(|| black_box(f64_loop.step())));
    let mut i16f16 = ReglerLoop::<I16F16>::new();
    group.bench_function("regler_i16f16", |b| b.iter(|| black_box(i16f16.step())));
    let mut i32f32 = ReglerLoop::<I32F32>::new();
    group.bench_function("regler_i32f32", |b| b.iter(|| black_box(i32f32.step())));
    group.finish();
}

criterion_group!(benches, closed_loop);
criterion_main!(benches);
