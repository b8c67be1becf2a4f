//! Runs `samples` samples of one loop shape for instruction counting:
//! `pid-shapes <regler|pid-crate|none> <constant|steps|noise|saturation> <samples>`; with
//! `scripts/instructions-per-op 1000000 target/release/pid-shapes regler steps {N}` what is left
//! is instructions per sample (controller + plant step + the shape's own work, the same for both).

use std::process::ExitCode;

use regler_benches::pid_shapes::{Null, Shape, anchor, regler, run};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage =
        "usage: pid-shapes <regler|pid-crate|none> <constant|steps|noise|saturation> <samples>";
    let [which, shape, samples] = args.as_slice() else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let (Some(shape), Ok(samples)) = (Shape::parse(shape), samples.parse::<u64>()) else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let y = match which.as_str() {
        "regler" => run(&mut regler(), shape, samples),
        "pid-crate" => run(&mut anchor(), shape, samples),
        "none" => run(&mut Null, shape, samples),
        _ => {
            eprintln!("{usage}");
            return ExitCode::from(2);
        }
    };
    println!("{y}");
    ExitCode::SUCCESS
}
