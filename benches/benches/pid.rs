//! regler's `Pid` in f32, f64, I16F16 and I32F32 with every feature on, one closed-loop sample
//! (controller + first-order plant) each; and the fair comparison with the `pid` crate's P+I+D
//! update: one generic loop function for both, four workloads, the update inlined into the loop
//! or called once per sample.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use fixed::types::{I16F16, I32F32};
use regler_benches::pid_loop::ReglerLoop;

fn closed_loop(c: &mut Criterion) {
    let mut group = c.benchmark_group("pid_closed_loop_sample");
    group.throughput(Throughput::Elements(1));
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

/// The fair loop: one generic loop function for both controllers, 1 000 samples of each shape
/// per iteration (`regler_benches::pid_shapes`); subtract the `none` row (the loop's own work)
/// to get a controller's time per update.
fn shapes(c: &mut Criterion) {
    use regler_benches::pid_shapes::{Call, Null, Shape, anchor, regler, run_with};
    for (name, shape) in [
        ("constant", Shape::Constant),
        ("steps", Shape::Steps),
        ("noise", Shape::Noise),
        ("saturation", Shape::Saturation),
    ] {
        for (how, call) in [("", Call::Inlined), ("_call", Call::PerSample)] {
            let mut group = c.benchmark_group(format!("pid_shape_{name}{how}_1000_samples"));
            group.throughput(Throughput::Elements(1000));
            let mut r = regler();
            group.bench_function("regler_f32", |b| {
                b.iter(|| run_with(&mut r, call, black_box(shape), 1000))
            });
            let mut p = anchor();
            group.bench_function("pid_crate_f32", |b| {
                b.iter(|| run_with(&mut p, call, black_box(shape), 1000))
            });
            group.bench_function("none", |b| {
                b.iter(|| run_with(&mut Null, call, black_box(shape), 1000))
            });
            group.finish();
        }
    }
}

criterion_group!(benches, closed_loop, shapes);
criterion_main!(benches);
