//! The FSW-81 two-level jacquard system (source 001, Tsinghua 1981) on `regler-ring-transfer`:
//! one master (the TRS-80) feeding pattern bytes to knitting-machine boards (the Z-80
//! single-board computers) over one link.
//!
//! **Model.** A sock machine has `needles` needles per round (default 200) and turns at 120–140
//! rpm; every needle takes **one pattern byte** (the yarn feed it selects: a colour 0–3), so a
//! machine at 130 rpm consumes a byte every 60 s / (130 · 200) ≈ 2.31 ms — the source's "about
//! 2 ms". One round is one row of fabric. Each board has a 256-byte ring (`Slave<256>`). A job
//! is a jacquard pattern of `job_rows` rows; `C` queues the next job for a machine, which starts
//! after the current one.
//!
//! **Timing.** The master's link is shared: a refill frame of `k` items occupies it for
//! `(9 + k)` byte times (`byte_ns`, default 3 µs); reports travel on each board's own request
//! line (the source's interrupt) after 20 µs. Both directions lose and duplicate frames at the
//! rates given, from a seeded generator. The link's busy figure is the time the refill frames
//! hold it, over the time run ([`summary::Link`]): in memory that is the simulated link; over
//! UDP the same frames' time at `byte_ns`, as the sockets' own time is not measured.
//!
//! **Files, as the data flows:**
//! - [`plant`]: the machines' speeds, the jobs' jacquard designs, the ROM's stripes;
//! - [`boards`]: each machine's board, its ring (`Slave`) and the fabric it knits;
//! - [`master`]: the jobs and the scheduler (`Master`) that grants refills by deadline;
//! - [`keys`]: the operator's keys at level 2, from a script, and the keyboard's answers;
//! - [`memory`]: boards, master and link as one discrete-event simulation (deterministic);
//! - [`terminal`]: the keys live, typed at a terminal or one a line from a pipe;
//! - [`udp`]: the same over real datagrams on 127.0.0.1;
//! - [`summary`]: the run's figures as a table and as JSON;
//! - [`picture`]: the knitted fabric as a PNG with title, machine labels and legend.

// The modules in the order the data flows (kept apart so that rustfmt keeps that order).
pub mod plant;

pub mod boards;

pub mod master;

pub mod keys;

pub mod memory;

pub mod terminal;

pub mod udp;

pub mod summary;

pub mod picture;

use std::fmt::Display;

pub use boards::{Board, Row, RowSource, boot_number};
pub use keys::{Key, Keyboard, Timed, parse_script};
pub use master::{Host, Jobs};
pub use memory::Sim;
pub use picture::write_png;
pub use plant::{pattern, rom_pattern, speeds};
pub use summary::{MachineSummary, Summary, summarise};
pub use udp::run_udp;

use regler_ring_transfer::capacity::{self, LinkSpec, Load, Verdict};
use regler_ring_transfer::{MAX_DRIFT, link};
use serde::Serialize;

use crate::cli::number;

/// Ring slots per board.
pub const RING: usize = 256;

/// The most machines one run simulates.
pub const MAX_MACHINES: usize = 100;

/// When the machines start (plus a phase of up to one needle each): after the master's first
/// fill of eight rings on the default link (8 × 256 frames of 10 bytes at 3 µs: 61 ms). A board
/// whose ring does not cover a row at its first needle knits that row from its local pattern.
pub const START_NS: u64 = 100_000_000;

/// The longest run, seconds (a day).
pub const MAX_SECONDS: f64 = 86_400.0;
/// The jobs in the master's memory: 0 to `JOBS − 1` (machine `m` starts on job `m − 1`; the
/// patterns repeat every eight jobs).
pub const JOBS: u32 = 100;
/// The longest job, rows.
pub const MAX_JOB_ROWS: u32 = 1_000_000;
/// Bytes a refill frame adds to its items (tag, address, first index, flags, boot, count, CRC).
pub const FRAME_OVERHEAD: u64 = (link::MAX_FRAME - link::MAX_REFILL) as u64;

/// How a run is set up.
#[derive(Clone, Debug, Serialize)]
pub struct Config {
    /// Machines (1..=100).
    pub machines: usize,
    /// Needles per row (8..=1000).
    pub needles: u16,
    /// Simulated seconds.
    pub seconds: f64,
    /// Seed of the machines' speeds and the link's faults.
    pub seed: u64,
    /// Link time per byte, in nanoseconds.
    pub byte_ns: u64,
    /// Items per refill frame at most.
    pub batch: u32,
    /// Probability that a frame is lost (each direction).
    pub loss: f64,
    /// Probability that a frame arrives twice.
    pub duplicate: f64,
    /// Report latency (request line), nanoseconds.
    pub report_ns: u64,
    /// The master is silent from `.0` for `.1` seconds.
    pub master_fault: Option<(f64, f64)>,
    /// Needles without a frame after which a board counts its master as silent.
    pub silence_needles: u32,
    /// Rows per job.
    pub job_rows: u32,
    /// The machines' start count, as a board keeps it in flash and increments at every start:
    /// each start's boot number differs from the one before (see [`boot_number`]).
    pub start: u32,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            machines: 8,
            needles: 200,
            seconds: 60.0,
            seed: 1981,
            byte_ns: 3_000,
            batch: 1,
            loss: 0.0,
            duplicate: 0.0,
            report_ns: 20_000,
            master_fault: None,
            silence_needles: 100,
            job_rows: 40,
            start: 0,
        }
    }
}

impl Config {
    /// Checks every field; the error names the field and its range.
    ///
    /// # Errors
    /// A message naming the bad field.
    pub fn validate(&self) -> Result<(), String> {
        let range =
            |option: &str, ok: bool, lo: &dyn Display, hi: &dyn Display, got: &dyn Display| {
                if ok {
                    Ok(())
                } else {
                    Err(format!("{option}: must be from {lo} to {hi}, got {got}"))
                }
            };
        range(
            "--machines",
            (1..=MAX_MACHINES).contains(&self.machines),
            &1,
            &MAX_MACHINES,
            &self.machines,
        )?;
        range(
            "--needles",
            (8..=1000).contains(&self.needles),
            &8,
            &1000,
            &self.needles,
        )?;
        if !(self.seconds.is_finite() && self.seconds > 0.0 && self.seconds <= MAX_SECONDS) {
            return Err(format!(
                "--seconds: must be more than 0 and at most {MAX_SECONDS}, got {}",
                number(self.seconds)
            ));
        }
        range(
            "--byte-ns",
            (1..=1_000_000).contains(&self.byte_ns),
            &1,
            &1_000_000,
            &self.byte_ns,
        )?;
        range(
            "--batch",
            (1..=link::MAX_REFILL as u32).contains(&self.batch),
            &1,
            &link::MAX_REFILL,
            &self.batch,
        )?;
        for (option, p) in [("--loss", self.loss), ("--duplicate", self.duplicate)] {
            range(option, (0.0..=0.5).contains(&p), &0, &0.5, &number(p))?;
        }
        if let Some((from, len)) = self.master_fault {
            if !(from.is_finite() && len.is_finite() && from >= 0.0 && len > 0.0) {
                return Err(format!(
                    "--master-fault: START:SECONDS must be 0 or more and more than 0, got {}:{}",
                    number(from),
                    number(len)
                ));
            }
            if from >= self.seconds {
                return Err(format!(
                    "--master-fault: the master would fall silent at {} s, but the run ends at \
                     {} s (--seconds): the fault never happens",
                    number(from),
                    number(self.seconds)
                ));
            }
        }
        // The slave refuses silence_limit + row_len + ring > MAX_DRIFT (an outage could move
        // its 16-bit counters half their range past the master's).
        let max_silence = MAX_DRIFT
            .saturating_sub(u64::from(self.needles))
            .saturating_sub(RING as u64);
        if self.silence_needles == 0 || u64::from(self.silence_needles) > max_silence {
            return Err(format!(
                "--silence: must be from 1 to {max_silence} needles (with {} needles and a \
                 {RING}-byte ring), got {}",
                self.needles, self.silence_needles
            ));
        }
        range(
            "--job-rows",
            (1..=MAX_JOB_ROWS).contains(&self.job_rows),
            &1,
            &MAX_JOB_ROWS,
            &self.job_rows,
        )?;
        Ok(())
    }

    /// Link time of a refill frame of `items` items.
    #[must_use]
    pub fn frame_ns(&self, items: u64) -> u64 {
        (FRAME_OVERHEAD + items) * self.byte_ns
    }

    /// The capacity check for machines at these speeds: each item may need a frame of its own
    /// and a full batch may hold the link (both safe).
    #[must_use]
    pub fn capacity(&self, t0s: &[u64]) -> Capacity {
        let link = LinkSpec {
            item_time: self.frame_ns(u64::from(self.batch)),
            latency: self.report_ns,
        };
        let loads: Vec<Load> = t0s
            .iter()
            .map(|&t0| Load {
                t0,
                ring: RING as u32,
            })
            .collect();
        let verdict = capacity::check(&loads, link);
        let slowest = t0s.iter().copied().min().unwrap_or(1);
        let max = capacity::max_slaves(
            Load {
                t0: slowest,
                ring: RING as u32,
            },
            link,
            10_000,
        );
        Capacity {
            verdict: match verdict {
                Ok(Verdict::Schedulable { .. }) => "schedulable".into(),
                Ok(Verdict::Overloaded { .. }) => "overloaded".into(),
                Ok(_) => "not checked".into(),
                Err(e) => format!("not checked: {e}"),
            },
            schedulable: matches!(verdict, Ok(v) if v.is_schedulable()),
            utilisation_percent: match verdict {
                Ok(
                    Verdict::Schedulable { utilisation_ppm }
                    | Verdict::Overloaded { utilisation_ppm },
                ) => Some(utilisation_ppm as f64 / 10_000.0),
                _ => None,
            },
            max_machines_at_fastest: max.unwrap_or(0),
        }
    }
}

/// What the capacity check says of the run's machines.
#[derive(Clone, Debug, Serialize)]
pub struct Capacity {
    /// The verdict: `schedulable`, `overloaded`, or `not checked: ` and why.
    pub verdict: String,
    /// Schedulable?
    pub schedulable: bool,
    /// Link utilisation (worst case: a frame per item); absent when the check could not run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub utilisation_percent: Option<f64>,
    /// How many machines at the fastest machine's speed this link could serve.
    pub max_machines_at_fastest: usize,
}

impl Capacity {
    /// The worst-case utilisation as text: `10.5 %`, or `unknown` when the check could not run.
    #[must_use]
    pub fn utilisation(&self) -> String {
        self.utilisation_percent
            .map_or_else(|| "unknown".into(), |u| format!("{u:.1} %"))
    }
}
