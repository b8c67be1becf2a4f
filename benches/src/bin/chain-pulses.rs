//! Runs `pulses` chain pulses of the bench dock for instruction counting:
//! `chain-pulses <regler|count-down> <trolleys: 10|16|256|1000|4096|10000> <pulses>`. With
//! `scripts/instructions-per-op 20000 target/release/chain-pulses regler 10000 {N}` the
//! warm-up cancels out and what is left is instructions per pulse.

use std::process::ExitCode;

use regler_benches::count_down::CountDown;
use regler_benches::dock::{Feed, TIPPERS, distances};
use regler_chain_tracker::{DistanceTable, Tracker};

fn run_tracker<const N: usize>(trolleys: u32, pulses: u64) -> Result<u64, String> {
    let d = distances(trolleys);
    let table = DistanceTable::new(1000, &d).map_err(|e| e.to_string())?;
    let mut tracker: Box<Tracker<u32, N, TIPPERS>> =
        Box::new(Tracker::new(table, 6).map_err(|e| e.to_string())?);
    let mut feed = Feed::new();
    let warm = 2 * u64::from(d.iter().max().copied().unwrap_or(1));
    let mut events = 0u64;
    for _ in 0..warm + pulses {
        if let Some((trolley, tipper)) = feed.step() {
            tracker.enter(trolley, tipper).map_err(|e| e.to_string())?;
        }
        tracker.pulse(|_| events += 1);
    }
    Ok(events)
}

fn run_count_down(trolleys: u32, pulses: u64) -> u64 {
    let d = distances(trolleys);
    let mut feed = Feed::new();
    let warm = 2 * u64::from(d.iter().max().copied().unwrap_or(1));
    // The same state as `warm` pulses leave, without counting down every entry on each of them.
    let mut register = CountDown::warmed(&d, 6, 2 * trolleys as usize, &mut feed, warm);
    let mut events = 0u64;
    for _ in 0..pulses {
        if let Some((trolley, tipper)) = feed.step() {
            register.enter(trolley, tipper);
        }
        register.pulse(|_| events += 1);
    }
    events
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: chain-pulses <regler|count-down> <10|16|256|1000|4096|10000> <pulses>";
    let [which, trolleys, pulses] = args.as_slice() else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let (Ok(trolleys), Ok(pulses)) = (trolleys.parse::<u32>(), pulses.parse::<u64>()) else {
        eprintln!("{usage}");
        return ExitCode::from(2);
    };
    let events = match (which.as_str(), trolleys) {
        // Room for twice the mean load, as in the criterion bench.
        ("regler", 10 | 16) => run_tracker::<32>(trolleys, pulses),
        ("regler", 256) => run_tracker::<512>(trolleys, pulses),
        ("regler", 1000) => run_tracker::<2048>(trolleys, pulses),
        ("regler", 4096) => run_tracker::<8192>(trolleys, pulses),
        ("regler", 10000) => run_tracker::<20_480>(trolleys, pulses),
        ("count-down", 10 | 16 | 256 | 1000 | 4096 | 10000) => Ok(run_count_down(trolleys, pulses)),
        _ => Err(usage.to_string()),
    };
    match events {
        Ok(events) => {
            println!("{events} tipper events");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("{e}");
            ExitCode::from(2)
        }
    }
}
