//! Runs `decisions` steps of the master's workload for instruction counting:
//! `master-decisions <slaves: 1..=512> <decisions>`; with
//! `scripts/instructions-per-op 100000 target/release/master-decisions 500 {N}` what is left is
//! instructions per EDF decision and the served slave's report.

use std::hint::black_box;
use std::process::ExitCode;

use regler_benches::master::Scheduler;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: master-decisions <slaves: 1..=512> <decisions>";
    let [slaves, decisions] = args.as_slice() else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let (Ok(slaves), Ok(decisions)) = (slaves.parse::<usize>(), decisions.parse::<u64>()) else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let Some(mut scheduler) = Scheduler::new(slaves) else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let mut sum = 0u64;
    for _ in 0..decisions {
        sum = sum.wrapping_add(black_box(scheduler.step()) as u64);
    }
    println!("{sum}");
    ExitCode::SUCCESS
}
