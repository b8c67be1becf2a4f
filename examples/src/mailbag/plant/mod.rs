//! The whole 1977 Malmö Ban mailbag-sorting plant (source 000): loading desks, rails with
//! switches at code readers, buffer lanes, emptying stations, dock chains, six panels and the
//! control program on the regler crates.
//!
//! # Topology
//! - **Loading stations P1–P3**, each with a code reader (R1–R3) that reads the trolley standing
//!   at the desk, so the computer knows which trolley's registry cell takes the keyed
//!   destination. Unsorted post: a post type 0–13 (ten letter types, four parcel types). Sorted
//!   post (P1 and P2 only): a postcode with a bin in the active sorting schedule. An entry that
//!   is not plausible is refused and the sack goes back: it was never loaded.
//! - **Rails and switches**: R4 at the main junction (buffer area or docks), R5 (D or E lanes),
//!   R6 (a switch bank into D1–D4), R7 (into E1–E11), R8 (dock 1, 2 or 3), R9 on the emptying
//!   rail (a switch bank into A1–A3, B1–B2, C1–C2), R10–R12 at the start of the dock chains
//!   (see [`layout::READER_NAMES`]). Every reader R4–R12 has a reject gate to the **manual
//!   station**. A reader's switch with no exit set (the safe outputs) also leads there.
//! - **Buffer lanes** D1–D4 and E1–E11 (letters D and E as the source names them), 60 trolleys
//!   each; emptied one lane at a time in portions of 5 trolleys onto the emptying rail; at R9
//!   each lane's trolleys go to the lane's emptying stations in turn, a portion each, so they
//!   fill evenly. The central desk assigns post types to lanes; panels A (letters) and B
//!   (parcels) choose each lane's emptying stations.
//! - **Emptying stations** A1–A3 (letters), B1–B2 and C1–C2 (parcels).
//! - **Dock chains** 1–3, 50 bins each (150 in all): a chain pulse per decimetre, a reader at
//!   the chain start entering the trolley into a [`Tracker`](regler_chain_tracker::Tracker)
//!   with its bin's tipper, set at zero and reset after 6 pulses; the chains have stretched
//!   (0.5 ‰ by default) and a [`StretchMeter`](regler_chain_tracker::StretchMeter) between two
//!   reference initiators (SIA 3000 pulses) keeps the distances corrected.
//! - **The return rail** takes every emptied trolley back to the desk with the fewest waiting.
//! - **Trolleys**: up to 4095 (the 12 number cams); the default run uses 3000.
//! - **173 destinations**: 150 bins, 15 buffer lanes, 7 emptying stations and the manual
//!   station. The computer knows where each trolley is *going* (a
//!   [`Registry`](regler_trolley_id::Registry) cell per trolley: a lane or a bin), not where it
//!   is, except on the dock chains (the trackers).
//!
//! # Timing
//! A 10 ms clock. Every tick: the six panel links ([`operator::Desks::tick_10ms`]), the field
//! (trolleys move between places with travel times, event-driven: no work per trolley and tick
//! except at a reader), the input flip-flops (chain pulses, initiators, lane exits latched by
//! the executive's conditioning), the watchdog check (it trips at the first check more than
//! 90 ms after the last cycle's end, so the outputs are safe within 100 ms of a hang's start;
//! a hang that begins during a power failure counts from the power's return). Every 5th tick
//! (50 ms) the [`Executive`](regler_scan_cycle::Executive) cycle reads all 544 inputs (34 words), debounces
//! the presence sensors (2 scans) and photocells (3 scans), runs the program (level B, a
//! [`StepChain`](regler_scan_cycle::StepChain)), writes all 240 outputs (15 words); then the
//! reserve hands the teletype its next printout when it is free (10 characters a second).
//! Nothing skips the cycle. Travel times: [`layout::timing`]. The I/O map: [`layout::io`].
//!
//! # Readers and misreads
//! A trolley is in front of a reader's cams for 250 ms: about 5 scans. Each passage is
//! *disturbed* (the trolley swings) with probability `rate / 0.5`, and in a disturbed passage
//! each scan is wrong with probability 0.5 (1, 2 or 3 cams flipped): a single scan is wrong at
//! `rate`, the source's 1 in 1000, uneven over the readers (`reader_spread`). Parity-only takes
//! the first scan, as the source did; voting takes the majority of all scans
//! ([`Voter`](regler_trolley_id::Voter)). A trolley passes 3 or 4 readers on its way (the desk's,
//! R4 and at least two more), so misreads compound. Each run is made twice on the same seed and
//! traffic, parity-only and voting, in two threads.
//!
//! How a misread ends: a wrong number that names no loaded trolley (most of them) sends the
//! trolley to the manual station at once; one that names another loaded trolley throws the
//! switch toward *that* trolley's destination, and the next reader, reading right, finds the
//! trolley off its way and rejects it. A trolley that a misread at R6 or R7 puts into another
//! trolley's lane is rejected at R9: R9 empties only a trolley that R6 or R7 itself switched into
//! its lane (the program notes the lane per trolley). Only a misread at a last switch — R9
//! (stations), R10–R12 (bins) — or at a desk (the wrong trolley's cell written) can misdeliver.
//! Parity-only misdelivers about 100 sacks per million in the 48 h test (more with more
//! trolleys loaded at a time), voting none in the runs measured.
//!
//! # Switches and supervision
//! A reader's switch (or reject gate) is set at the end of a passage, for that passage only:
//! 1.5 s later (the trolley reaches the switch 1 s after its passage; the next passage ends 2 s
//! after at the earliest) a timer on the timer queue puts it back to its safe position, no exit
//! set, which leads to the manual station. A trolley for which no passage was judged (a reader
//! that does not see it) therefore goes to the manual station, never where the switch stood
//! for the trolley before. The program supervises the inputs that make passages:
//! - a reader's presence input on for more than 1 s (a passage lasts 250 ms), or a desk's on
//!   without a trolley's code for 1 s, is a fault: a teletype report, the reader's alarm on
//!   (the panels' alarm lamps and the summary), the passage dropped unjudged and the switch safe
//!   until the input goes off again;
//! - a trolley routed toward a reader must be read *there* within 2 minutes, or the teletype
//!   reports it (a reader that has stopped seeing trolleys); being read at another reader does
//!   not end its supervision;
//! - each trolley a buffer lane lets go must give R9 a passage within 2 minutes, or the
//!   teletype reports it;
//! - a desk's entry that finds no trolley at the desk is refused and reported (once, until a
//!   trolley is seen there again).
//!
//! All of these count as time-supervision reports in the summary.
//!
//! # Faults and tallies
//! `--fault` ([`faults::FAULT_SYNTAX`]); every sack loaded is delivered, misdelivered, rejected
//! or still in the plant, counted place by place and checked every simulated minute — through
//! power failures and hangs too — and at the end of a partial last minute.
//!
//! # CPU load
//! The executive measures each cycle's busy time on a clock that the program's routines advance
//! by a cost model ([`control::cost`]): the source's idle-counter measurement, ≈ 30 %.
//!
//! # Files, as the data flows
//! `layout.rs` (readers, exits, destinations, timing, the I/O map); `traffic.rs` (the seeded
//! sacks and operators, `--script`); `faults.rs` (`--fault`); `field/` (the plant: trolleys and events,
//! `dock_chain.rs` pulse by pulse, `inputs.rs` the executive's I/O); `control/` (the program:
//! desks and commands, `readers.rs`, `conveyors.rs` for chains and lanes, `calendar.rs`);
//! `run.rs` (the 10 ms loop, faults, teletype, tallies); `report.rs` (JSON, map, summary).

pub mod control;
pub mod faults;
pub mod field;
pub mod layout;
pub mod map;
pub mod map_data;
pub mod operator;
pub mod panels;
pub mod report;
pub mod run;
pub mod traffic;

use regler_scan_cycle::DateTime;

pub use self::control::Reading;
use self::faults::Fault;
pub use self::report::{Report, summary_text};
pub use self::run::RunResult;
use self::traffic::{Keyed, SackArrival, Script};

/// A whole-plant run's parameters.
#[derive(Clone, Debug)]
pub struct Config {
    /// Seed of the traffic and the misreads.
    pub seed: u64,
    /// Simulated hours.
    pub hours: f64,
    /// Trolleys in the plant (1–4095).
    pub trolleys: u16,
    /// Mean single-scan misread rate.
    pub misread_rate: f64,
    /// How uneven the readers are (0–1).
    pub reader_spread: f64,
    /// The chains' stretch since commissioning, per mille.
    pub stretch_per_mille: f64,
    /// Traffic, times the usual.
    pub traffic: f64,
    /// The calendar at the start.
    pub start: DateTime,
    /// The faults.
    pub faults: Vec<Fault>,
    /// A script.
    pub script: Option<Script>,
}

impl Default for Config {
    fn default() -> Config {
        Config {
            seed: 1977,
            hours: 24.0,
            trolleys: 3000,
            misread_rate: 0.001,
            reader_spread: 0.8,
            stretch_per_mille: 0.5,
            traffic: 1.0,
            start: run::default_start(),
            faults: Vec::new(),
            script: None,
        }
    }
}

impl Config {
    /// The sacks and the operators' commands of the run (seeded, and the script's).
    #[must_use]
    pub fn traffic(&self) -> (Vec<SackArrival>, Vec<Keyed>) {
        let start = self.start;
        let mut keyed = traffic::start_up_settings();
        let (mut sacks, changes) = match &self.script {
            Some(s) if s.replace => (Vec::new(), Vec::new()),
            _ => traffic::workload(self.seed, self.hours, self.traffic, |ms| {
                run::schedule_at(start, ms)
            }),
        };
        keyed.extend(changes);
        if let Some(s) = &self.script {
            sacks.extend(s.sacks.iter().copied());
            keyed.extend(s.keyed.iter().copied());
        }
        sacks.sort_by_key(|s| s.at_ms);
        keyed.sort_by_key(|k| k.at_ms);
        (sacks, keyed)
    }

    /// Simulated minutes of the run, a partial last one counted (the tally is checked at each,
    /// and the progress bar counts them, for both runs).
    #[must_use]
    pub fn minutes(&self) -> u64 {
        ((self.hours * 3_600_000.0).round() as u64).div_ceil(60_000)
    }
}

/// Runs the plant twice on the same seed and traffic, parity-only and voting, in two threads,
/// each with its own operator subsystem from `desks`. `progress` gets simulated minutes.
///
/// # Errors
/// A broken tally, naming the minute.
pub fn run<D: operator::Desks>(
    config: &Config,
    desks: impl Fn() -> D + Sync,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Report, String> {
    let (sacks, keyed) = config.traffic();
    let mut faults = config.faults.clone();
    faults.sort_by_key(|f| f.at_ms);
    let started = std::time::Instant::now();
    let one = |reading| {
        let mut d = desks();
        run::run_one(config, reading, &mut d, &sacks, &keyed, &faults, progress)
    };
    let (parity, voting) = std::thread::scope(|s| {
        let parity = s.spawn(|| one(Reading::ParityOnly));
        let voting = one(Reading::Voting);
        (parity.join(), voting)
    });
    let parity = parity.map_err(|_| "the parity-only run stopped unexpectedly".to_string())??;
    let voting = voting?;
    Ok(Report::new(
        config,
        parity,
        voting,
        started.elapsed().as_secs_f64(),
    ))
}
