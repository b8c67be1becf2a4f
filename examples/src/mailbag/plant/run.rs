//! One run of the plant: the 10 ms loop that drives the panels, the field and, every 5th
//! tick, the executive's cycle with the control program; faults on demand; the teletype; the
//! tallies checked every simulated minute (through power failures and hangs) and at the end.

use std::cell::Cell;
use std::collections::VecDeque;
use std::rc::Rc;
use std::time::Instant;

use regler_chain_tracker::{DistanceTable, SOURCE_HOLD_PULSES, StretchConfig, start_up};
use regler_scan_cycle::{CycleConfig, DateTime, Executive, Restart};

use super::Config;
use super::control::{Control, DockTracker, IW, OW, Reading, schedule_for};
use super::faults::{Fault, FaultKind};
use super::field::{Field, FieldCounts};
use super::layout::{BINS_PER_DOCK, DESKS, DOCKS, chain, io};
use super::operator::{Desks, PanelId, PanelTotals};
use super::traffic::{Keyed, SackArrival};

/// What one run (one way of reading) found.
#[derive(Clone, Debug)]
pub struct RunResult {
    /// How the readers' scans were judged.
    pub reading: Reading,
    /// The field's counts.
    pub counts: FieldCounts,
    /// Sacks still in the plant at the end.
    pub in_plant: u64,
    /// Entries the computer refused (the sack went back, never loaded).
    pub refused: u64,
    /// Trolleys each reader sent to the manual station.
    pub rejected_by: [u64; super::layout::READERS],
    /// Reader passages judged.
    pub passages: u64,
    /// Per reader: passages, no-reads, disagreements, alarm on at the end, alarms raised.
    pub readers: Vec<ReaderFigures>,
    /// Time-supervision faults reported.
    pub supervision_faults: u64,
    /// Stretch recalibrations.
    pub recalibrations: u64,
    /// Executive cycles run.
    pub cycles: u64,
    /// Mean and largest busy time of a cycle, µs (the cost model).
    pub busy_mean_us: u32,
    /// Largest: the busiest cycle's busy time.
    pub busy_max_us: u32,
    /// Watchdog trips.
    pub watchdog_trips: u32,
    /// Longest time from a hang's start (or from the power's return, for a hang that began
    /// during a power failure) to the safe outputs, ms: at most [`WATCHDOG_SAFE_MS`].
    pub watchdog_safe_ms: u64,
    /// Times the tally was checked (every simulated minute, and at the end of a partial last
    /// minute).
    pub tally_checks: u64,
    /// Power failures survived (resumed).
    pub power_failures: u32,
    /// Teletype lines printed, and the spool's overflow.
    pub printed: Vec<String>,
    /// Printouts the spool refused.
    pub spool_overflow: u64,
    /// The panels' totals.
    pub panels: PanelTotals,
    /// Real seconds the run took.
    pub real_seconds: f64,
    /// Simulated hours.
    pub hours: f64,
}

/// One reader's figures.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct ReaderFigures {
    /// Passages.
    pub passages: u32,
    /// Passages with no verdict.
    pub no_reads: u32,
    /// Passages with two different numbers decoded.
    pub disagreements: u32,
    /// Alarm on at the end (the reader's health, or its presence input found faulty).
    pub alarm: bool,
    /// Alarms raised.
    pub alarms_raised: u32,
}

#[derive(Clone, Copy, Debug)]
enum Operator {
    Idle,
    Typed { at_ms: u64 },
}

/// The bound the plant keeps from a hang's start to the safe outputs, ms.
pub const WATCHDOG_SAFE_MS: u64 = 100;

/// The executive's watchdog limit for the plant, µs. The check runs every 10 ms and trips at the
/// first check *more* than this after the last cycle's end, so at most 10 ms later: within
/// [`WATCHDOG_SAFE_MS`] of the last cycle's end, and so of the hang's start.
const WATCHDOG_LIMIT_US: u32 = 90_000;

/// The teletype: 10 characters a second.
const TELETYPE_MS_PER_CHAR: u64 = 100;

/// Runs the plant for `config.hours`, reading the scans as `reading`, with `desks` as the
/// operator subsystem. `progress` is called every simulated minute with the minutes done.
///
/// # Errors
/// A broken tally (naming the minute).
pub fn run_one(
    config: &Config,
    reading: Reading,
    desks: &mut dyn Desks,
    sacks: &[SackArrival],
    keyed: &[Keyed],
    faults: &[Fault],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RunResult, String> {
    let started = Instant::now();
    let cost = Rc::new(Cell::new(0u64));
    let mut field = Field::new(
        config.seed,
        config.trolleys,
        config.stretch_per_mille,
        config.misread_rate,
        config.reader_spread,
    );
    field.cost = Rc::clone(&cost);
    let calendar = config.start;
    let dia = std::array::from_fn(|d| field.chain_dia(d));
    let mut control = Control::new(reading, Rc::clone(&cost), calendar, dia);
    let steps = Control::chain();
    let mut exec: Executive<IW, OW> = Executive::new(CycleConfig {
        watchdog_us: WATCHDOG_LIMIT_US,
        ..CycleConfig::source()
    });
    let debounce = |exec: &mut Executive<IW, OW>, point: usize, k: u8| {
        let _ = exec.conditioning_mut().set_debounce(point, k);
    };
    for r in 0..super::layout::READERS {
        debounce(&mut exec, io::present(r), 2);
    }
    for l in 0..15 {
        debounce(&mut exec, 16 * io::LANE_FULL_WORD + l, 3);
        debounce(&mut exec, 16 * io::LANE_WAITING_WORD + l, 3);
        let _ = exec
            .conditioning_mut()
            .set_latched(16 * io::LANE_EXIT_WORD + l, true);
    }
    for s in 0..7 {
        debounce(&mut exec, 16 * io::STATION_FULL_WORD + s, 3);
    }
    for d in 0..DOCKS {
        for p in [
            io::chain_pulse(d),
            io::reference_start(d),
            io::reference_end(d),
        ] {
            let _ = exec.conditioning_mut().set_latched(p, true);
        }
    }

    let mut desk_sacks: [VecDeque<SackArrival>; DESKS] = Default::default();
    let mut next_sack = 0usize;
    let mut next_key = 0usize;
    let mut next_fault = 0usize;
    let mut operators = [Operator::Idle; DESKS];
    let mut teletype_free_ms = 0u64;
    let mut printed = Vec::new();
    let mut power_until: Option<u64> = None;
    let mut stored = None;
    let mut hang: Option<(u64, u64, bool)> = None;
    let mut watchdog_safe_ms = 0u64;
    let mut power_failures = 0u32;
    let mut ends: Vec<(u64, Ending)> = Vec::new();
    let mut power_back_ms = 0u64;
    let mut tally_checks = 0u64;

    let total_ms = (config.hours * 3_600_000.0).round() as u64;
    let mut wall_ms = 0u64;
    while wall_ms < total_ms {
        wall_ms += 10;
        field.clock_us = wall_ms * 1000;
        cost.set(0);
        control.calendar.advance(10);

        while let Some(f) = faults.get(next_fault).filter(|f| f.at_ms <= wall_ms) {
            next_fault += 1;
            match f.kind {
                FaultKind::Misread { reader, rate } => field.faults.misread[reader] = rate,
                FaultKind::ReaderFails { reader } => field.faults.dead[reader] = true,
                FaultKind::Noise { panel, rate } => desks.set_noise(panel, rate),
                FaultKind::Stuck { point, on, secs } => {
                    field.faults.stuck.push((point, on));
                    if secs > 0 {
                        ends.push((after(wall_ms, secs), Ending::Stuck(point)));
                    }
                }
                FaultKind::Chatter { point, secs } => {
                    field.faults.chatter.push(point);
                    ends.push((after(wall_ms, secs), Ending::Chatter(point)));
                }
                FaultKind::Power { secs } => {
                    if power_until.is_none() {
                        exec.power_fail(&mut field);
                        stored = Some((
                            control
                                .trackers
                                .iter()
                                .map(DockTracker::snapshot)
                                .collect::<Vec<_>>(),
                            control.meters.clone(),
                        ));
                        power_until = Some(after(wall_ms, secs));
                        control.print(format!("{} power failure", stamp(wall_ms)));
                    }
                }
                FaultKind::Hang { secs } => {
                    if hang.is_none() {
                        hang = Some((wall_ms, after(wall_ms, secs), false));
                    }
                }
                FaultKind::MissedPulses { dock, rate, secs } => {
                    field.faults.missed_pulse[dock] = rate;
                    if secs > 0 {
                        ends.push((after(wall_ms, secs), Ending::Pulses(dock)));
                    }
                }
            }
        }
        ends.retain(|&(at, ending)| {
            if at > wall_ms {
                return true;
            }
            match ending {
                Ending::Stuck(p) => field.faults.stuck.retain(|&(q, _)| q != p),
                Ending::Chatter(p) => field.faults.chatter.retain(|&q| q != p),
                Ending::Pulses(d) => field.faults.missed_pulse[d] = 0.0,
            }
            false
        });

        // The tick's work; a power failure or a hang ends it early (`break 'tick`), the
        // tally is checked after it all the same.
        'tick: {
            if let Some(until) = power_until {
                if wall_ms < until {
                    break 'tick; // everything stands; the calendar runs on its battery clock
                }
                power_until = None;
                if let Some((snapshots, meters)) = stored.take() {
                    for (d, (snapshot, meter)) in snapshots.iter().zip(meters).enumerate() {
                        let sa: [u32; BINS_PER_DOCK] =
                            std::array::from_fn(|j| chain::bin_sa(j) - chain::LEAD_PULSES);
                        let table =
                            DistanceTable::new(chain::SIA, &sa).map_err(|e| e.to_string())?;
                        let mut tracker = DockTracker::new(table, SOURCE_HOLD_PULSES)
                            .map_err(|e| e.to_string())?;
                        let (meter, _) = start_up(
                            &mut tracker,
                            Some(snapshot),
                            Some(meter),
                            StretchConfig::new(chain::SIA),
                        )
                        .map_err(|e| e.to_string())?;
                        control.trackers[d] = tracker;
                        control.meters[d] = meter;
                    }
                }
                exec.resume(Restart::WhereStopped);
                power_back_ms = wall_ms;
                power_failures += 1;
                control.print(format!(
                    "{} power back, resumed where stopped",
                    stamp(wall_ms)
                ));
            }

            // Level A, every 10 ms: the panel links, the field, the input flip-flops.
            desks.tick_10ms(wall_ms, &mut |panel, command| {
                control.commands.push_back((panel, command))
            });
            let mut capture = [0u16; IW];
            field.advance(&mut capture);
            if capture.iter().any(|&w| w != 0) {
                exec.capture(&capture);
            }
            while let Some(k) = keyed.get(next_key).filter(|k| k.at_ms <= wall_ms) {
                next_key += 1;
                desks.type_in(k.panel, k.command);
            }
            while let Some(s) = sacks.get(next_sack).filter(|s| s.at_ms <= wall_ms) {
                next_sack += 1;
                desk_sacks[usize::from(s.desk.min(2))].push_back(*s);
            }
            for p in 0..DESKS {
                match operators[p] {
                    Operator::Idle => {
                        if field.desk_ready(p) && !field.release_open(p) {
                            if let Some(sack) = desk_sacks[p].pop_front() {
                                desks.type_in(PanelId::Desk(p as u8), sack.entry);
                                operators[p] = Operator::Typed {
                                    at_ms: field.now_ms,
                                };
                            }
                        }
                    }
                    Operator::Typed { at_ms } => {
                        if field.release_open(p) {
                            if let Some(dest) = control.accepted[p].take() {
                                field.load(p, dest);
                                operators[p] = Operator::Idle;
                            }
                        } else if field.now_ms > at_ms + 6_000 {
                            operators[p] = Operator::Idle; // refused: the sack goes back
                        }
                    }
                }
            }

            // The watchdog, checked every 10 ms; a hung program runs no cycle.
            if let Some((from, until, tripped)) = hang {
                if wall_ms >= until {
                    if tripped {
                        exec.reset_watchdog();
                        control.print(format!(
                            "{} watchdog reset, program restarted",
                            stamp(wall_ms)
                        ));
                    }
                    hang = None;
                } else {
                    if !tripped && exec.check_watchdog(&mut field) {
                        // A hang that began during a power failure counts from the power's return.
                        let since = from.max(power_back_ms);
                        watchdog_safe_ms = watchdog_safe_ms.max(wall_ms.saturating_sub(since));
                        hang = Some((from, until, true));
                    }
                    break 'tick;
                }
            }
            exec.check_watchdog(&mut field);

            if wall_ms.is_multiple_of(50) {
                let (lanes, stations) = field.fills();
                let ready = std::array::from_fn(|p| field.desk_ready(p));
                control.show_field(ready, &lanes, &stations);
                let _ = exec.cycle(&mut field, |scan| steps.run(scan, &mut control));
                field.emptying = control.emptying;
                desks.refresh(&control.live);
                if teletype_free_ms <= wall_ms {
                    let reserve_cost = Rc::clone(&cost);
                    let mut started_job = None;
                    exec.reserve(&mut field, &mut control.spool, 0, |job| {
                        started_job = Some(job.0);
                        reserve_cost.set(1_000_000); // the reserve now waits on the teletype
                    });
                    if let Some(line) = started_job {
                        teletype_free_ms = wall_ms + (line.len() as u64 + 2) * TELETYPE_MS_PER_CHAR;
                        printed.push(line);
                    }
                }
            }
        }

        if wall_ms.is_multiple_of(60_000) || wall_ms >= total_ms {
            check_tally(&field, wall_ms)?;
            tally_checks += 1;
            progress(1);
        }
    }
    let stats = exec.stats();
    let readers = control
        .health
        .iter()
        .enumerate()
        .map(|(r, h)| {
            let t = h.totals();
            ReaderFigures {
                passages: t.passages,
                no_reads: t.no_reads,
                disagreements: t.disagreements,
                alarm: h.alarm() || control.presence_fault(r),
                alarms_raised: h.alarms_raised(),
            }
        })
        .collect();
    Ok(RunResult {
        reading,
        in_plant: field.sacks_in_plant(),
        counts: field.counts.clone(),
        refused: control.refused,
        rejected_by: control.rejected_by,
        passages: control.passages,
        readers,
        supervision_faults: control.supervision_faults,
        recalibrations: control.recalibrations,
        cycles: exec.cycle_count(),
        busy_mean_us: stats.mean_us(),
        busy_max_us: stats.max_us,
        tally_checks,
        watchdog_trips: exec.watchdog_trips(),
        watchdog_safe_ms,
        power_failures,
        printed,
        spool_overflow: control.spool_overflow,
        panels: desks.totals(),
        real_seconds: started.elapsed().as_secs_f64(),
        hours: config.hours,
    })
}

/// delivered + misdelivered + rejected + in the plant = loaded, or the error naming the minute.
fn check_tally(field: &Field, wall_ms: u64) -> Result<(), String> {
    let loaded: u64 = field.counts.loaded.iter().sum();
    let in_plant = field.sacks_in_plant();
    let c = &field.counts;
    if c.delivered + c.misdelivered + c.rejected + in_plant != loaded {
        return Err(format!(
            "tally broken at minute {} ({}): delivered {} + misdelivered {} + rejected {} + in the plant {} != loaded {loaded}",
            wall_ms / 60_000,
            stamp(wall_ms),
            c.delivered,
            c.misdelivered,
            c.rejected,
            in_plant
        ));
    }
    Ok(())
}

#[derive(Clone, Copy, Debug)]
enum Ending {
    Stuck(usize),
    Chatter(usize),
    Pulses(usize),
}

fn stamp(ms: u64) -> String {
    let s = ms / 1000;
    format!("{:02}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

/// The calendar the default run starts on: Monday 1977-03-07 00:00.
#[must_use]
pub fn default_start() -> DateTime {
    DateTime::new(1977, 3, 7, 0, 0, 0).expect("a valid date")
}

/// The schedule the calendar has in force `ms` after `start` (for the seeded sorted post).
#[must_use]
pub fn schedule_at(start: DateTime, ms: u64) -> u8 {
    let mut t = start;
    let mut left = ms;
    while left > 0 {
        let step = left.min(u64::from(u32::MAX));
        t.advance(step as u32);
        left -= step;
    }
    schedule_for(&t)
}

/// `secs` seconds after `wall_ms`, saturating (a fault's end never wraps; `--fault` bounds the
/// seconds anyway: [`super::faults::MAX_FAULT_SECONDS`]).
fn after(wall_ms: u64, secs: u64) -> u64 {
    wall_ms.saturating_add(secs.saturating_mul(1000))
}
