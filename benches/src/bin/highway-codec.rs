//! Runs `rounds` passes over the 1 024-message serial-highway workload for instruction counting:
//! `highway-codec <encode|decode|decode-shortest|decode-longest|copy|controller|delay> <rounds>`; with
//! `scripts/instructions-per-op 200 target/release/highway-codec decode {N}` what is left is
//! instructions per pass (1 024 messages, 9 084 bytes; `decode-shortest` / `decode-longest`: the
//! workload's messages of its shortest / longest encoded length only).

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: highway-codec <encode|decode|decode-shortest|decode-longest|copy|controller|delay> <rounds>";
    let [which, rounds] = args.as_slice() else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let Ok(rounds) = rounds.parse::<u64>() else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    match regler_benches::highway::run(which, rounds) {
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
