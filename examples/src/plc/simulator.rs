//! The soft-PLC with its plant: the executive runs the program each 50 ms cycle, the calendar
//! and the minute table start the shift reports, the reserve runs the spool, and the timing
//! diagram records every cycle's images.

use regler_scan_cycle::{
    Breakpoint, CycleConfig, DateTime, Executive, Halt, MinuteTable, Restart, Start, Weekdays,
};
use serde::Serialize;

use super::plant::Plant;
use super::program::{Conveyor, Report};
use super::{IW, OW, PERIOD_MS, input};

/// Samples of the timing diagram kept (the last ones): memory stays flat however long it runs.
pub const TRACE_CAP: usize = 100_000;
/// Reports kept for `spool` and the summary (the total is counted apart).
pub const REPORTS_KEPT: usize = 1_000;

/// One sample of the timing diagram.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Sample {
    /// Cycle number.
    pub cycle: u64,
    /// Input word (the points).
    pub inputs: u16,
    /// The belt encoder's count (input word 1).
    pub encoder: u16,
    /// Output word.
    pub outputs: u16,
}

/// The soft-PLC with its plant, as the simulator drives it.
pub struct Simulator {
    /// The executive.
    pub plc: Executive<IW, OW>,
    /// The program.
    pub program: Conveyor,
    /// The plant.
    pub plant: Plant,
    /// Active breakpoints; each stops a run on the cycle it comes to hold.
    pub breakpoints: Vec<Breakpoint>,
    /// The timing diagram.
    pub trace: std::collections::VecDeque<Sample>,
    /// Reports run in the reserve.
    pub reports: std::collections::VecDeque<Report>,
    /// Reports run in all.
    pub reports_run: u64,
    /// The calendar clock, advanced by the plant's wall clock.
    pub clock: DateTime,
    /// Shift changes: programs started at given minutes.
    pub table: MinuteTable<Report, 4>,
    /// Power failures survived.
    pub power_failures: u32,
}

impl Simulator {
    /// A simulator with the plant seeded by `seed`.
    #[must_use]
    pub fn new(seed: u64) -> Simulator {
        let config = CycleConfig {
            period_us: PERIOD_MS * 1000,
            ..CycleConfig::source()
        };
        let mut plc = Executive::new(config);
        // The photo eye chatters at edges: two equal readings needed.
        let _ = plc.conditioning_mut().set_debounce(input::PART, 2);
        // The quality sensor's pulse can be shorter than a cycle: latch it.
        let _ = plc.conditioning_mut().set_latched(input::BAD, true);
        // Shift reports at the shift changes, as the 1977 plant printed statistics at 24:00.
        let mut table = MinuteTable::new();
        for hour in [6, 14, 22] {
            let _ = table.add(Start {
                hour,
                minute: 0,
                days: Weekdays::ALL,
                program: Report::Shift(hour),
            });
        }
        Simulator {
            plc,
            program: Conveyor::new(),
            plant: Plant::new(seed),
            breakpoints: Vec::new(),
            trace: std::collections::VecDeque::new(),
            reports: std::collections::VecDeque::new(),
            reports_run: 0,
            clock: DateTime::new(2026, 11, 23, 13, 58, 30).unwrap_or_else(|_| unreachable!()),
            table,
            power_failures: 0,
        }
    }

    /// A power failure of `ms` between two cycles: the executive writes the safe outputs (motor
    /// off, gate closed) and freezes; the program's battery-backed memory keeps what
    /// [`Conveyor::retain`] takes (the tracker's snapshot among it); the plant stands for `ms`;
    /// then the program starts from power-on with what was kept ([`Conveyor::power_on`]) and
    /// the executive resumes with [`Restart::Inhibit`] (the motor stays off until the operator
    /// presses START, 1 s after the power is back). The calendar goes on by the plant's clock.
    ///
    /// # Errors
    /// The tracker refused the kept snapshot: the program runs on without the outage.
    pub fn power_failure(&mut self, ms: u32) -> Result<(), regler_chain_tracker::TrackerError> {
        let kept = self.program.retain();
        let program = Conveyor::power_on(&kept)?;
        self.plc.power_fail(&mut self.plant);
        self.plant.power_cut(ms);
        self.plc.capture(&self.plant.inputs);
        self.clock.advance(ms);
        self.program = program;
        self.plc.resume(Restart::Inhibit);
        self.power_failures += 1;
        Ok(())
    }

    /// Runs up to `cycles` cycles, stopping at a breakpoint; returns the cycles run and why it
    /// stopped early.
    pub fn run(&mut self, cycles: u64) -> (u64, Option<Halt>) {
        let mut done = 0u64;
        while done < cycles {
            let watch = self.plc.watch();
            let cycle_from_us = self.plant.clock_us;
            let program = &mut self.program;
            if let Err(halt) = self.plc.cycle(&mut self.plant, |scan| program.scan(scan)) {
                return (done, Some(halt));
            }
            done += 1;
            // The calendar goes by the plant's wall clock (here the simulated period), never by
            // the executive's program time, which leaves power outages out. The minute table
            // hands out each start once, late if the clock jumped over its minute.
            self.clock.advance(PERIOD_MS);
            let (spool, refused) = (&mut self.program.spool, &mut self.program.spool_refused);
            self.table.check(&self.clock, |due| {
                if spool.push(*due.program).is_err() {
                    *refused += 1;
                }
            });
            // Level C: the reserve runs the spool.
            let (reports, run) = (&mut self.reports, &mut self.reports_run);
            self.plc
                .reserve(&mut self.plant, &mut self.program.spool, 5_000, |batch| {
                    if reports.len() == REPORTS_KEPT {
                        reports.pop_front();
                    }
                    reports.push_back(batch);
                    *run += 1;
                });
            if self.trace.len() == TRACE_CAP {
                self.trace.pop_front();
            }
            self.trace.push_back(Sample {
                cycle: self.plc.cycle_count(),
                inputs: self.plc.inputs().word(0).unwrap_or(0),
                encoder: self.plc.inputs().word(input::ENCODER_WORD).unwrap_or(0),
                outputs: self.plc.outputs().word(0).unwrap_or(0),
            });
            // The rest of the period passes; the plant moves; latched pulses are caught. The
            // rest is counted on the plant's clock from before the cycle's first read, so the
            // reserve's clock reads (1 ms each) come out of the period too and the next cycle
            // starts exactly one period after this one (no jitter unless a cycle overruns).
            let spent_ms = (self.plant.clock_us - cycle_from_us) / 1000;
            let rest_ms = u64::from(PERIOD_MS).saturating_sub(spent_ms).max(1);
            self.plant
                .advance(u32::try_from(rest_ms).unwrap_or(PERIOD_MS));
            self.plc.capture(&self.plant.inputs);
            // A breakpoint stops the run on the cycle it comes to hold, not while it holds.
            if let Some(b) = watch.fired(&self.plc, &self.breakpoints) {
                return (done, Some(Halt::Breakpoint(b)));
            }
        }
        (done, None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_program_runs_the_section() {
        let mut sim = Simulator::new(7);
        sim.run(6_000); // five minutes
        let t = sim.plant.tally;
        assert!(sim.program.parts() > 100, "{}", sim.program.parts());
        // Tracked by the belt's travel, every bad part is rejected and no good one, jams or not.
        assert!(t.jams > 0 && t.bad_rejected > 5, "{t:?}");
        assert_eq!((t.bad_passed, t.good_rejected), (0, 0), "{t:?}");
        assert_eq!(t.cleared_by_hand, t.jams);
        assert!(sim.reports.iter().any(|r| matches!(r, Report::Batch(_))));
        assert!(
            sim.reports.contains(&Report::Shift(14)),
            "the 14:00 shift report ran"
        );
        assert!(sim.plc.stats().overruns == 0);
    }
}
