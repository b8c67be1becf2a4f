//! Instruction counts for the scan-cycle hot paths:
//! `scan-loop <wheel|count-down> <16|256|4096|10000> <ticks>` or `scan-loop cycle 0 <cycles>`;
//! use with `scripts/instructions-per-op 131072 target/release/scan-loop wheel 4096 {N}` (a
//! multiple of 256 ticks: the queue moves a 256-tick block's timers down once per block).

use std::hint::black_box;
use std::process::ExitCode;

use regler_benches::scan::{CountDownTimers, Plant1977, WheelTimers, cycle_1977, executive_1977};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: scan-loop <wheel|count-down|cycle> <16|256|4096|10000> <count>";
    let [which, size, count] = args.as_slice() else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let Ok(count) = count.parse::<u64>() else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let mut sum = 0u64;
    match (which.as_str(), size.as_str()) {
        ("wheel", "16") => {
            let mut w = WheelTimers::<16>::steady(16);
            for _ in 0..count {
                sum += u64::from(black_box(w.tick()));
            }
        }
        ("wheel", "256") => {
            let mut w = WheelTimers::<256>::steady(256);
            for _ in 0..count {
                sum += u64::from(black_box(w.tick()));
            }
        }
        ("wheel", "4096") => {
            let mut w = WheelTimers::<4096>::steady(4096);
            for _ in 0..count {
                sum += u64::from(black_box(w.tick()));
            }
        }
        ("wheel", "10000") => {
            let mut w = WheelTimers::<10_000>::steady(10_000);
            for _ in 0..count {
                sum += u64::from(black_box(w.tick()));
            }
        }
        ("count-down", n) => {
            let Ok(n) = n.parse::<u32>() else {
                eprintln!("{usage}");
                return ExitCode::from(2);
            };
            let mut c = CountDownTimers::steady(n);
            for _ in 0..count {
                sum += u64::from(black_box(c.tick()));
            }
        }
        ("cycle", _) => {
            let (mut plc, mut plant) = (executive_1977(), Plant1977::default());
            for _ in 0..count {
                cycle_1977(&mut plc, &mut plant);
            }
            sum = u64::from(plant.outputs[0]);
        }
        _ => {
            eprintln!("{usage}");
            return ExitCode::from(2);
        }
    }
    println!("{sum}");
    ExitCode::SUCCESS
}
