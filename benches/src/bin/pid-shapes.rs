//! Runs `samples` samples of one loop shape for instruction counting:
//! `pid-shapes <regler|pid-crate|none>[-call] <constant|steps|noise|saturation> <samples>`; with
//! `scripts/instructions-per-op 1000000 target/release/pid-shapes regler steps {N}` what is left
//! is instructions per sample (controller + plant step + the shape's own work, the same for both).
//! A `-call` suffix calls the controller out of line once per sample, as firmware does.

use std::process::ExitCode;

use regler_benches::pid_shapes::{Call, Null, Shape, anchor, regler, run_with};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: pid-shapes <regler|pid-crate|none>[-call] <constant|steps|noise|saturation> <samples>";
    let [which, shape, samples] = args.as_slice() else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let (Some(shape), Ok(samples)) = (Shape::parse(shape), samples.parse::<u64>()) else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let (who, call) = match which.strip_suffix("-call") {
        Some(who) => (who, Call::PerSample),
        None => (which.as_str(), Call::Inlined),
    };
    let y = match who {
        "regler" => run_with(&mut regler(), call, shape, samples),
        "pid-crate" => run_with(&mut anchor(), call, shape, samples),
        "none" => run_with(&mut Null, call, shape, samples),
        _ => {
            eprintln!("{usage}");
            return ExitCode::from(2);
        }
    };
    println!("{y}");
    ExitCode::SUCCESS
}
