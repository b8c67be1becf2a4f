//! Runs `samples` samples of the bench loop for instruction counting:
//! `pid-loop <f32|f64|i16f16|i32f32> <samples>`; with
//! `scripts/instructions-per-op 1000000 target/release/pid-loop f32 {N}` what is left is
//! instructions per sample (controller + plant step; the plant step is the same for all). The
//! comparison with the `pid` crate is `pid-shapes`.

use std::hint::black_box;
use std::process::ExitCode;

use fixed::types::{I16F16, I32F32};
use regler_benches::pid_loop::ReglerLoop;
use regler_pid::Scalar;

fn run<T: Scalar>(samples: u64) -> f64 {
    let mut l = ReglerLoop::<T>::new();
    let mut y = T::ZERO;
    for _ in 0..samples {
        y = black_box(l.step());
    }
    y.to_f64()
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: pid-loop <f32|f64|i16f16|i32f32> <samples>";
    let [which, samples] = args.as_slice() else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let Ok(samples) = samples.parse::<u64>() else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let y = match which.as_str() {
        "f32" => run::<f32>(samples),
        "f64" => run::<f64>(samples),
        "i16f16" => run::<I16F16>(samples),
        "i32f32" => run::<I32F32>(samples),
        _ => {
            eprintln!("{usage}");
            return ExitCode::from(2);
        }
    };
    println!("y = {y}");
    ExitCode::SUCCESS
}
