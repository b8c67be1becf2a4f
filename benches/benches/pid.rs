//! regler's `Pid` in f32, f64, I16F16 and I32F32 with every feature on, one closed-loop sample
//! (controller + first-order plant) each; and the fair comparison with the `pid` crate's P+I+D
//! update: the same loop for both, four workloads compiled into it, in the firmware shape (one
//! out-of-line call per sample) and the inlined shape.

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

/// The fair comparison with the `pid` crate (`regler_benches::pid_shapes`): the same loop,
/// plant and workload for both, 1 000 samples per iteration, in two shapes — `firmware`
/// (run-time configuration, the controller kept in memory across iterations, one out-of-line call
/// per sample) and `inlined` (the loop builds and owns a controller from the constant
/// configuration). Subtract the `none` row (the loop's own work, same shape) for a controller's
/// time per update.
fn shapes(c: &mut Criterion) {
    use regler_benches::pid_shapes::{Anchor, Build, Call, Null, Shape, run, run_firmware};
    use regler_pid::Pid;
    for (name, shape) in [
        ("constant", Shape::Constant),
        ("steps", Shape::Steps),
        ("noise", Shape::Noise),
        ("saturation", Shape::Saturation),
    ] {
        let mut group = c.benchmark_group(format!("pid_shape_{name}_firmware_1000_samples"));
        group.throughput(Throughput::Elements(1000));
        let mut r = <Pid<f32> as Build>::runtime();
        group.bench_function("regler_f32", |b| {
            b.iter(|| run_firmware(&mut r, black_box(shape), 1000))
        });
        let mut p = Anchor::runtime();
        group.bench_function("pid_crate_f32", |b| {
            b.iter(|| run_firmware(&mut p, black_box(shape), 1000))
        });
        group.bench_function("none", |b| {
            b.iter(|| run_firmware(&mut Null, black_box(shape), 1000))
        });
        group.finish();
        let mut group = c.benchmark_group(format!("pid_shape_{name}_inlined_1000_samples"));
        group.throughput(Throughput::Elements(1000));
        group.bench_function("regler_f32", |b| {
            b.iter(|| run::<Pid<f32>>(Call::Inlined, black_box(shape), 1000))
        });
        group.bench_function("pid_crate_f32", |b| {
            b.iter(|| run::<Anchor>(Call::Inlined, black_box(shape), 1000))
        });
        group.bench_function("none", |b| {
            b.iter(|| run::<Null>(Call::Inlined, black_box(shape), 1000))
        });
        group.finish();
    }
}

criterion_group!(benches, closed_loop, shapes);
criterion_main!(benches);
