//! Runs `pairs` receive + next pairs for instruction counting:
//! `ring-pairs <ring|spsc|spsc-257|split|spsc-split|array|none> <firmware|inlined> <pairs>`; with
//! `scripts/instructions-per-op 1000000 target/release/ring-pairs ring firmware {N}` what is left
//! is instructions per pair (the loop's own work included, the same for every contestant;
//! `none` is that work alone, to subtract).

use std::process::ExitCode;

use regler_benches::ring_pairs::{Shape, run};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: ring-pairs <ring|spsc|spsc-257|split|spsc-split|array|none> <firmware|inlined> <pairs>";
    let [which, shape, pairs] = args.as_slice() else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let (Some(shape), Ok(pairs)) = (Shape::parse(shape), pairs.parse::<u64>()) else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    match run(which, shape, pairs) {
        Some(sum) => {
            println!("{sum}");
            ExitCode::SUCCESS
        }
        None => {
            eprintln!("{usage}");
            ExitCode::from(2)
        }
    }
}
