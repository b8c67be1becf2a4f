//! Runs `pairs` receive + next pairs for instruction counting:
//! `ring-pairs <ring|split|spsc|spsc-split|array> <pairs>`; with
//! `scripts/instructions-per-op N target/release/ring-pairs ring {N}` what is left is
//! instructions per pair.

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: ring-pairs <ring|split|spsc|spsc-split|array> <pairs>";
    let [which, pairs] = args.as_slice() else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let Ok(pairs) = pairs.parse::<u64>() else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    match regler_benches::ring_pairs::run(which, pairs) {
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
