//! Runs `samples` samples of one workload for instruction counting:
//! `pid-shapes <regler|pid-crate|none> <firmware|inlined> <constant|steps|noise|saturation> <samples>`;
//! with `scripts/instructions-per-op 1000000 target/release/pid-shapes regler firmware steps {N}`
//! what is left is instructions per sample (controller + plant step + the workload's own work;
//! subtract the `none` row for the controller's net cost). `firmware`: run-time configuration,
//! one out-of-line call per sample; `inlined`: constant configuration, update inlined.

use std::process::ExitCode;

use regler_benches::pid_shapes::{Anchor, Call, Null, Shape, run};
use regler_pid::Pid;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: pid-shapes <regler|pid-crate|none> <firmware|inlined> <constant|steps|noise|saturation> <samples>";
    let [who, call, shape, samples] = args.as_slice() else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let (Some(call), Some(shape), Ok(samples)) = (
        Call::parse(call),
        Shape::parse(shape),
        samples.parse::<u64>(),
    ) else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let end = match who.as_str() {
        "regler" => run::<Pid<f32>>(call, shape, samples),
        "pid-crate" => run::<Anchor>(call, shape, samples),
        "none" => run::<Null>(call, shape, samples),
        _ => {
            eprintln!("{usage}");
            return ExitCode::from(2);
        }
    };
    println!("{}", end.y);
    ExitCode::SUCCESS
}
