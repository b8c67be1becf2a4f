//! The FSW-81 two-level jacquard system (source 001) on `regler-ring-transfer`: one master (the
//! TRS-80) feeding pattern bytes to knitting-machine boards (the Z-80 single-board computers)
//! over one link.
//!
//! **Model.** A sock machine has `needles` needles per round (default 200) and turns at 120–140
//! rpm; every needle takes **one pattern byte** (the yarn feed it selects: a colour 0–3), so a
//! machine at 130 rpm consumes a byte every 60 s / (130 · 200) ≈ 2.31 ms — the source's "about
//! 2 ms". One round is one row of fabric. Each board has a 256-byte ring (`Slave<256>`). The
//! master's link is shared: a refill frame of `k` items occupies it for `(9 + k)` byte times;
//! reports travel on each board's own request line (the source's interrupt) after a short
//! latency. Both directions lose and duplicate frames at the rates given, from a seeded
//! generator. A job is a jacquard pattern of `job_rows` rows; `C` queues the next job for a
//! machine, which starts after the current one.

use std::cmp::Reverse;
use std::collections::{BTreeMap, BinaryHeap};
use std::fmt::Write as _;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use regler_ring_transfer::capacity::{self, LinkSpec, Load, Verdict};
use regler_ring_transfer::{
    MAX_DRIFT, Master, Mode, Refill, Report, ReportOutcome, Slave, SlaveConfig, SlaveParams,
    Source, link,
};
use serde::Serialize;

/// Ring slots per board.
pub const RING: usize = 256;
/// The most machines one run simulates.
pub const MAX_MACHINES: usize = 100;
/// When the machines start (plus a phase of up to one needle each): after the master's first
/// fill of eight rings on the default link (8 × 256 frames of 10 bytes at 3 µs: 61 ms). A board
/// whose ring does not cover a row at its first needle knits that row from its local pattern.
pub const START_NS: u64 = 100_000_000;
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
        if !(1..=MAX_MACHINES).contains(&self.machines) {
            return Err(format!(
                "machines must be between 1 and {MAX_MACHINES}, got {}",
                self.machines
            ));
        }
        if !(8..=1000).contains(&self.needles) {
            return Err(format!(
                "needles must be between 8 and 1000, got {}",
                self.needles
            ));
        }
        if !(self.seconds.is_finite() && self.seconds > 0.0 && self.seconds <= 86_400.0) {
            return Err(format!(
                "seconds must be between 0 and 86400, got {}",
                self.seconds
            ));
        }
        if !(1..=1_000_000).contains(&self.byte_ns) {
            return Err(format!(
                "byte time must be 1..=1000000 ns, got {}",
                self.byte_ns
            ));
        }
        if !(1..=link::MAX_REFILL as u32).contains(&self.batch) {
            return Err(format!(
                "batch must be between 1 and {}, got {}",
                link::MAX_REFILL,
                self.batch
            ));
        }
        for (name, p) in [("loss", self.loss), ("duplicate", self.duplicate)] {
            if !(0.0..=0.5).contains(&p) {
                return Err(format!(
                    "{name} must be a probability between 0 and 0.5, got {p}"
                ));
            }
        }
        if let Some((from, len)) = self.master_fault {
            if !(from.is_finite() && len.is_finite() && from >= 0.0 && len > 0.0) {
                return Err(format!(
                    "master fault must be START:SECONDS with both positive, got {from}:{len}"
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
                "silence must be 1..={max_silence} needles (with {} needles and a {RING}-byte \
                 ring), got {}",
                self.needles, self.silence_needles
            ));
        }
        if self.job_rows == 0 {
            return Err("job rows must be at least 1".into());
        }
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
                Ok(v) => format!("{v:?}"),
                Err(e) => format!("not checked: {e}"),
            },
            schedulable: matches!(verdict, Ok(v) if v.is_schedulable()),
            utilisation_percent: match verdict {
                Ok(
                    Verdict::Schedulable { utilisation_ppm }
                    | Verdict::Overloaded { utilisation_ppm },
                ) => utilisation_ppm as f64 / 10_000.0,
                _ => f64::NAN,
            },
            max_machines_at_fastest: max.unwrap_or(0),
        }
    }
}

/// What the capacity check says of the run's machines.
#[derive(Clone, Debug, Serialize)]
pub struct Capacity {
    /// The verdict, as the crate states it.
    pub verdict: String,
    /// Schedulable?
    pub schedulable: bool,
    /// Link utilisation (worst case: a frame per item).
    pub utilisation_percent: f64,
    /// How many machines at the fastest machine's speed this link could serve.
    pub max_machines_at_fastest: usize,
}

/// The boot number of machine `machine` at its start number `start` in the run seeded `seed`:
/// a hash of seed and machine plus the start count, so two consecutive starts of a machine
/// always differ (a board must never start with the previous start's number: a late sync of
/// that start could place it behind the master's stream, ignored for good).
#[must_use]
pub fn boot_number(seed: u64, machine: usize, start: u32) -> u8 {
    let mut x = seed ^ (machine as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^= x >> 31;
    x.to_le_bytes()[0].wrapping_add(start.to_le_bytes()[0])
}

/// Colour (0–3) of needle `col` in row `row` of job `job`: four jacquard designs, so a shifted,
/// lost or repeated row shows as a break in the pattern.
#[must_use]
pub fn pattern(job: u32, row: u64, col: u16) -> u8 {
    let (r, c) = (row as i64, i64::from(col));
    match job % 4 {
        // Argyle diamonds with a diagonal over-check.
        0 => {
            let (dr, dc) = ((r % 32) - 16, (c % 32) - 16);
            if (r + c) % 16 == 0 || (r - c).rem_euclid(16) == 0 {
                3
            } else if dr.abs() + dc.abs() < 14 {
                1
            } else {
                0
            }
        }
        // Zig-zag bands.
        1 => (((r + (c % 20 - 10).abs()) / 5) % 3) as u8,
        // Checks with a dot.
        2 => {
            let check = ((r / 8) + (c / 8)) % 2;
            if r % 8 == 4 && c % 8 == 4 {
                3
            } else {
                check as u8
            }
        }
        // Hearts-ish: concentric rings.
        _ => {
            let (dr, dc) = ((r % 24) - 12, (c % 24) - 12);
            (((dr * dr + dc * dc) / 30) % 3) as u8 + u8::from(job % 8 >= 4)
        }
    }
}

/// The board's ROM pattern (stand-alone): plain stripes, recognisably not a jacquard.
#[must_use]
pub fn rom_pattern(row: u32, _col: u16) -> u8 {
    if row % 4 < 2 { 2 } else { 0 }
}

/// The master's job plan for one machine: which job each stream row belongs to.
#[derive(Clone, Debug)]
pub struct Jobs {
    rows: u64,
    starts: BTreeMap<u64, u32>,
    next: Option<u32>,
}

impl Jobs {
    /// Starting with `job`, `rows` rows each.
    #[must_use]
    pub fn new(job: u32, rows: u32) -> Self {
        Self {
            rows: u64::from(rows),
            starts: BTreeMap::from([(0, job)]),
            next: None,
        }
    }

    /// The job and its row for stream row `row`, planning boundaries as they are reached.
    pub fn at(&mut self, row: u64) -> (u32, u64) {
        loop {
            let (&start, &job) = self.starts.last_key_value().unwrap_or((&0, &0));
            if row < start + self.rows {
                break;
            }
            let job = self.next.take().unwrap_or(job);
            self.starts.insert(start + self.rows, job);
        }
        let (&start, &job) = self.starts.range(..=row).next_back().unwrap_or((&0, &0));
        (job, row - start)
    }

    /// The source's C: this job after the current one.
    pub fn change_after_current(&mut self, job: u32) {
        self.next = Some(job);
    }

    /// (current job, queued job) as of stream row `row`.
    #[must_use]
    pub fn shown(&self, row: u64) -> (u32, Option<u32>) {
        let job = self.starts.range(..=row).next_back().map_or(0, |(_, &j)| j);
        (job, self.next)
    }
}

/// What a knitted row was made from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum RowSource {
    /// Stream row `n` from the master, whole.
    Master(u64),
    /// The board's ROM pattern (stand-alone).
    Local,
    /// A row with items that were not the master's (an underrun or a fallback).
    Patched,
}

/// One knitted row.
#[derive(Clone, Debug)]
pub struct Row {
    /// Source of the row.
    pub source: RowSource,
    /// Colours, with bit 7 set for a needle that did not get the master's item.
    pub needles: Vec<u8>,
}

/// The machine side: a board with its slave and the fabric it knitted.
#[derive(Debug)]
pub struct Board {
    /// Index (0-based; the operator's keys number them from 1).
    pub index: usize,
    /// Revolutions per minute.
    pub rpm: u32,
    /// Nanoseconds per needle.
    pub t0_ns: u64,
    slave: Slave<RING>,
    needles: u16,
    stream_index: u64,
    /// Rows knitted.
    pub rows: Vec<Row>,
    current: Vec<u8>,
    current_stream_row: Option<u64>,
    current_patched: bool,
    current_local: bool,
    /// Master items that were not the right byte for their stream position (must stay 0).
    pub wrong_items: u64,
    /// Master rows that were not the next stream row (must stay 0).
    pub rows_out_of_order: u64,
    next_stream_row: u64,
    /// Needles knitted in stand-alone mode.
    pub standalone_needles: u64,
}

impl Board {
    /// A board at `rpm` with `needles` needles.
    ///
    /// # Errors
    /// The slave's configuration error, as text.
    pub fn new(index: usize, rpm: u32, config: &Config) -> Result<Self, String> {
        let slave = Slave::new(SlaveConfig {
            address: u8::try_from(index).map_err(|_| "too many machines")?,
            row_len: config.needles,
            silence_limit: config.silence_needles,
            retry_after: 16,
            boot: boot_number(config.seed, index, config.start),
        })
        .map_err(|e| e.to_string())?;
        Ok(Self {
            index,
            rpm,
            t0_ns: 60_000_000_000 / (u64::from(rpm) * u64::from(config.needles)),
            slave,
            needles: config.needles,
            stream_index: 0,
            rows: Vec::new(),
            current: Vec::new(),
            current_stream_row: None,
            current_patched: false,
            current_local: false,
            wrong_items: 0,
            rows_out_of_order: 0,
            next_stream_row: 0,
            standalone_needles: 0,
        })
    }

    /// A frame from the link.
    pub fn frame(&mut self, bytes: &[u8]) {
        let _ = self.slave.on_frame(bytes);
    }

    /// One needle; `expected(stream_index)` is the master's byte there (for the check).
    /// Returns a report to send, if one is due.
    pub fn needle(&mut self, expected: impl FnOnce(u64) -> u8) -> Option<Report> {
        let out = self.slave.step(rom_pattern);
        if out.col == 0 {
            self.current.clear();
            self.current_stream_row = None;
            self.current_patched = false;
            self.current_local = false;
        }
        let mut colour = out.item & 0x03;
        match out.source {
            Source::Master => {
                if out.item != expected(self.stream_index) {
                    self.wrong_items += 1;
                }
                if out.col == 0 {
                    self.current_stream_row = Some(self.stream_index / u64::from(self.needles));
                }
                self.stream_index += 1;
            }
            Source::Underrun | Source::Fallback => {
                colour |= 0x80;
                self.current_patched = true;
                self.stream_index += 1;
            }
            Source::Local => {
                self.current_local = true;
                self.standalone_needles += 1;
            }
        }
        self.current.push(colour);
        if usize::from(out.col) + 1 == usize::from(self.needles) {
            let source = if self.current_local {
                RowSource::Local
            } else if self.current_patched {
                RowSource::Patched
            } else {
                RowSource::Master(self.current_stream_row.unwrap_or(u64::MAX))
            };
            if let RowSource::Master(n) = source {
                if n != self.next_stream_row {
                    self.rows_out_of_order += 1;
                }
                self.next_stream_row = n + 1;
            } else if source == RowSource::Patched {
                self.next_stream_row = self.stream_index.div_ceil(u64::from(self.needles));
            }
            self.rows.push(Row {
                source,
                needles: std::mem::take(&mut self.current),
            });
        }
        self.slave.poll_report()
    }

    /// The board's first report (a hello: it has no place in the stream until the master
    /// answers).
    pub fn announce(&mut self) -> Option<Report> {
        self.slave.poll_report()
    }

    /// The slave (statistics, mode).
    #[must_use]
    pub fn slave(&self) -> &Slave<RING> {
        &self.slave
    }

    /// The source's keys 1–8: the board's status line.
    #[must_use]
    pub fn status_line(&self) -> String {
        let s = self.slave.stats();
        let (row, col) = self.slave.position();
        format!(
            "machine {}: {} rpm, {:?}, row {row} needle {col}, ring {}/{RING}, underruns {}, least slack {}, stand-alone {:.1} s",
            self.index + 1,
            self.rpm,
            self.slave.mode(),
            self.slave.slack(),
            s.underruns,
            s.least_slack,
            self.standalone_needles as f64 * self.t0_ns as f64 / 1e9
        )
    }
}

/// The master side: the scheduler, the jobs and the link's counters.
#[derive(Debug)]
pub struct Host {
    /// The scheduler.
    pub master: Box<Master<MAX_MACHINES>>,
    /// Each machine's jobs.
    pub jobs: Vec<Jobs>,
    needles: u16,
    batch: u32,
    /// Refill frames sent.
    pub frames: u64,
    /// Items sent (resends included).
    pub items_sent: u64,
    /// Keep-alives sent.
    pub keep_alives: u64,
}

impl Host {
    /// A master for the boards' speeds.
    ///
    /// # Errors
    /// The master's error, as text.
    pub fn new(config: &Config, t0s: &[u64]) -> Result<Self, String> {
        let mut master: Box<Master<MAX_MACHINES>> = Box::default();
        for (i, &t0) in t0s.iter().enumerate() {
            let t0 = u32::try_from(t0).map_err(|_| "t0 too long")?;
            master
                .attach(
                    i,
                    SlaveParams {
                        capacity: RING as u16,
                        t0,
                    },
                )
                .map_err(|e| e.to_string())?;
        }
        Ok(Self {
            master,
            jobs: (0..t0s.len())
                .map(|i| Jobs::new(i as u32, config.job_rows))
                .collect(),
            needles: config.needles,
            batch: config.batch,
            frames: 0,
            items_sent: 0,
            keep_alives: 0,
        })
    }

    /// The master's byte at stream index `k` of machine `m`.
    pub fn byte(&mut self, m: usize, k: u64) -> u8 {
        let needles = u64::from(self.needles);
        let (job, row) = self.jobs[m].at(k / needles);
        pattern(job, row, (k % needles) as u16)
    }

    /// A report from machine `m` at `now`; returns a keep-alive frame when nothing is owed.
    pub fn report(&mut self, now: u64, m: usize, bytes: &[u8]) -> Option<Vec<u8>> {
        let Ok(regler_ring_transfer::Message::Report(report)) = regler_ring_transfer::decode(bytes)
        else {
            return None;
        };
        match self.master.on_report(now, m, &report) {
            Ok(ReportOutcome::Accepted { owed: 0 }) => {
                self.keep_alives += 1;
                let mut frame = vec![0u8; link::MAX_FRAME];
                let n = Refill::keep_alive(report.slave).encode(&mut frame).ok()?;
                frame.truncate(n);
                Some(frame)
            }
            _ => None,
        }
    }

    /// The scheduler's next frame: (machine, frame bytes, items).
    pub fn next_frame(&mut self, now: u64) -> Option<(usize, Vec<u8>, u64)> {
        let grant = self.master.next_refill(now, self.batch)?;
        let items: Vec<u8> = (0..u64::from(grant.count))
            .map(|k| self.byte(grant.slave, grant.first + k))
            .collect();
        let mut frame = vec![0u8; link::MAX_FRAME];
        let n = grant
            .refill(grant.slave as u8, &items)
            .encode(&mut frame)
            .ok()?;
        frame.truncate(n);
        self.frames += 1;
        self.items_sent += u64::from(grant.count);
        Some((grant.slave, frame, u64::from(grant.count)))
    }
}

/// An operator key of the level-2 keyboard.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// L: lock the keyboard.
    Lock,
    /// O: open it.
    Open,
    /// S: the dynamic flow of every machine.
    Flow,
    /// F: the jobs in memory.
    Jobs,
    /// P: the report.
    Report,
    /// T: key parameters.
    Parameters,
    /// C m j: machine m changes to job j after the current one.
    Change(usize, u32),
    /// 1–8: a machine's status.
    Status(usize),
    /// Shift 1–8: re-initialise a machine's interface.
    Reinit(usize),
    /// Break: back to the scheduler (ends the run).
    Break,
}

impl Key {
    /// Parses a script token list: `L`, `O`, `S`, `F`, `P`, `T`, `C M J`, `1`..`8` (any machine
    /// number), `shift N`, `break`.
    ///
    /// # Errors
    /// What was wrong.
    pub fn parse(words: &[&str]) -> Result<Self, String> {
        let number = |w: Option<&&str>, what: &str| -> Result<usize, String> {
            w.ok_or(format!("{what} missing"))?
                .parse::<usize>()
                .map_err(|_| format!("{what} must be a number"))
        };
        match words {
            [w] if w.eq_ignore_ascii_case("l") => Ok(Self::Lock),
            [w] if w.eq_ignore_ascii_case("o") => Ok(Self::Open),
            [w] if w.eq_ignore_ascii_case("s") => Ok(Self::Flow),
            [w] if w.eq_ignore_ascii_case("f") => Ok(Self::Jobs),
            [w] if w.eq_ignore_ascii_case("p") => Ok(Self::Report),
            [w] if w.eq_ignore_ascii_case("t") => Ok(Self::Parameters),
            [w] if w.eq_ignore_ascii_case("break") => Ok(Self::Break),
            [w, rest @ ..] if w.eq_ignore_ascii_case("c") => {
                let m = number(rest.first(), "machine")?;
                let j = number(rest.get(1), "job")?;
                Ok(Self::Change(
                    m,
                    u32::try_from(j).map_err(|_| "job too large")?,
                ))
            }
            [w, rest @ ..] if w.eq_ignore_ascii_case("shift") => {
                Ok(Self::Reinit(number(rest.first(), "machine")?))
            }
            [n] => Ok(Self::Status(number(Some(n), "key")?)),
            _ => Err(format!("unknown key '{}'", words.join(" "))),
        }
    }
}

/// A timed key of a script.
#[derive(Clone, Debug)]
pub struct Timed {
    /// Simulated seconds.
    pub at: f64,
    /// The key.
    pub key: Key,
}

/// Parses a script: lines `SECONDS KEY…`, `#` comments.
///
/// # Errors
/// The line and what was wrong.
pub fn parse_script(text: &str) -> Result<Vec<Timed>, String> {
    let mut out = Vec::new();
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        let err = |what: String| format!("script line {}: {what}: '{}'", n + 1, raw.trim());
        let at: f64 = words[0]
            .parse()
            .map_err(|_| err("time must be seconds".into()))?;
        if !(at.is_finite() && at >= 0.0) {
            return Err(err("time must be 0 or more seconds".into()));
        }
        let key = Key::parse(&words[1..]).map_err(err)?;
        out.push(Timed { at, key });
    }
    out.sort_by(|a, b| a.at.total_cmp(&b.at));
    Ok(out)
}

/// A per-machine line of the summary.
#[derive(Clone, Debug, Serialize)]
pub struct MachineSummary {
    /// Machine number (from 1).
    pub machine: usize,
    /// Speed.
    pub rpm: u32,
    /// Rows knitted.
    pub rows: usize,
    /// Rows from the master, whole.
    pub master_rows: usize,
    /// Rows from the ROM pattern.
    pub local_rows: usize,
    /// Rows with some needles not from the master.
    pub patched_rows: usize,
    /// Underruns (needles whose byte was late while the master was up).
    pub underruns: u32,
    /// Needles from the ROM after the master fell silent mid-row.
    pub fallbacks: u32,
    /// Least slack in the ring.
    pub least_slack: u16,
    /// Seconds knitted stand-alone.
    pub standalone_s: f64,
    /// Times the board went stand-alone.
    pub standalone_entries: u32,
    /// Grants the master made after their deadline.
    pub missed_deadlines: u32,
    /// Retry reports.
    pub retries: u32,
    /// Duplicated items dropped.
    pub duplicates_dropped: u32,
    /// Master bytes at a wrong stream position (must be 0).
    pub wrong_items: u64,
    /// Master rows out of stream order (must be 0).
    pub rows_out_of_order: u64,
    /// Mode at the end.
    pub linked: bool,
}

/// A run's result.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// The configuration.
    pub config: Config,
    /// Transport.
    pub transport: String,
    /// The capacity check.
    pub capacity: Capacity,
    /// Per machine.
    pub machines: Vec<MachineSummary>,
    /// Refill frames sent.
    pub frames: u64,
    /// Items sent.
    pub items_sent: u64,
    /// Keep-alives sent.
    pub keep_alives: u64,
    /// Frames lost by the link filter.
    pub frames_lost: u64,
    /// Frames duplicated by the link filter.
    pub frames_duplicated: u64,
    /// Link busy, percent of the run.
    pub link_busy_percent: f64,
    /// The operator's screen (answers to keys).
    pub screen: Vec<String>,
}

impl Summary {
    /// Totals: (underruns, wrong items, rows out of order).
    #[must_use]
    pub fn faults(&self) -> (u64, u64, u64) {
        self.machines.iter().fold((0, 0, 0), |(u, w, o), m| {
            (
                u + u64::from(m.underruns),
                w + m.wrong_items,
                o + m.rows_out_of_order,
            )
        })
    }

    /// The table printed at the end and by P.
    #[must_use]
    pub fn table(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "machine  rpm  rows  master  local  patched  underruns  least slack  stand-alone s  missed  retries  dup dropped"
        );
        for m in &self.machines {
            let _ = writeln!(
                s,
                "{:>7}  {:>3}  {:>4}  {:>6}  {:>5}  {:>7}  {:>9}  {:>11}  {:>13.1}  {:>6}  {:>7}  {:>11}",
                m.machine,
                m.rpm,
                m.rows,
                m.master_rows,
                m.local_rows,
                m.patched_rows,
                m.underruns,
                m.least_slack,
                m.standalone_s,
                m.missed_deadlines,
                m.retries,
                m.duplicates_dropped
            );
        }
        let (underruns, wrong, order) = self.faults();
        let _ = writeln!(
            s,
            "link ({}): {} frames, {} items, {} keep-alives; lost {}, duplicated {}; busy {:.1} %",
            self.transport,
            self.frames,
            self.items_sent,
            self.keep_alives,
            self.frames_lost,
            self.frames_duplicated,
            self.link_busy_percent
        );
        let _ = writeln!(
            s,
            "capacity check: {} (utilisation {:.1} % worst case; this link serves up to {} machines at the fastest speed)",
            self.capacity.verdict,
            self.capacity.utilisation_percent,
            self.capacity.max_machines_at_fastest
        );
        let _ = write!(
            s,
            "pattern check: {wrong} wrong bytes, {order} rows out of order, {underruns} underruns"
        );
        s
    }
}

/// Summarises boards and host.
#[must_use]
pub fn summarise(
    config: &Config,
    transport: &str,
    boards: &[Board],
    host: &Host,
    link: (u64, u64, f64),
    screen: Vec<String>,
) -> Summary {
    let machines = boards
        .iter()
        .map(|b| {
            let s = b.slave().stats();
            let status = host.master.status(b.index).unwrap_or_default();
            let count = |f: fn(&RowSource) -> bool| b.rows.iter().filter(|r| f(&r.source)).count();
            MachineSummary {
                machine: b.index + 1,
                rpm: b.rpm,
                rows: b.rows.len(),
                master_rows: count(|s| matches!(s, RowSource::Master(_))),
                local_rows: count(|s| *s == RowSource::Local),
                patched_rows: count(|s| *s == RowSource::Patched),
                underruns: s.underruns,
                fallbacks: s.fallbacks,
                least_slack: s.least_slack,
                standalone_s: b.standalone_needles as f64 * b.t0_ns as f64 / 1e9,
                standalone_entries: s.standalone_entries,
                missed_deadlines: status.missed,
                retries: s.retries,
                duplicates_dropped: s.duplicates,
                wrong_items: b.wrong_items,
                rows_out_of_order: b.rows_out_of_order,
                linked: b.slave().mode() == Mode::Linked,
            }
        })
        .collect();
    let t0s: Vec<u64> = boards.iter().map(|b| b.t0_ns).collect();
    Summary {
        config: config.clone(),
        transport: transport.into(),
        capacity: config.capacity(&t0s),
        machines,
        frames: host.frames,
        items_sent: host.items_sent,
        keep_alives: host.keep_alives,
        frames_lost: link.0,
        frames_duplicated: link.1,
        link_busy_percent: link.2,
        screen,
    }
}

/// Machine speeds for a seed: 120–140 rpm.
#[must_use]
pub fn speeds(config: &Config) -> Vec<u32> {
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    (0..config.machines)
        .map(|_| rng.random_range(120..=140))
        .collect()
}

/// The operator's keyboard at level 2: answers keys with lines of text.
#[derive(Debug, Default)]
pub struct Keyboard {
    locked: bool,
    /// Everything answered so far.
    pub screen: Vec<String>,
}

impl Keyboard {
    /// Answers one key; `true` when the key was Break.
    pub fn key(
        &mut self,
        key: Key,
        now_s: f64,
        boards: &[Board],
        host: &mut Host,
        config: &Config,
    ) -> bool {
        let mut say = |line: String| self.screen.push(format!("[{now_s:7.2} s] {line}"));
        if self.locked && key != Key::Open {
            say("keyboard locked (O opens it)".into());
            return false;
        }
        let machine = |n: usize| (1..=boards.len()).contains(&n).then(|| n - 1);
        match key {
            Key::Lock => {
                self.locked = true;
                say("keyboard locked".into());
            }
            Key::Open => {
                self.locked = false;
                say("keyboard open".into());
            }
            Key::Flow => {
                for b in boards {
                    let st = host.master.status(b.index).unwrap_or_default();
                    let (row, _) = b.slave().position();
                    say(format!(
                        "flow {:>3}: {:<10} row {row:>5}  ring {:>3}/{RING}  owed {:>3}  sent {:>8}  missed {}",
                        b.index + 1,
                        format!("{:?}", b.slave().mode()),
                        b.slave().slack(),
                        st.owed,
                        st.sent,
                        st.missed
                    ));
                }
            }
            Key::Jobs => {
                for (i, jobs) in host.jobs.iter().enumerate() {
                    let row = host.master.status(i).map(|s| s.sent).unwrap_or(0)
                        / u64::from(config.needles);
                    let (job, next) = jobs.shown(row);
                    let next = next.map_or("-".to_string(), |j| j.to_string());
                    say(format!("jobs {:>3}: job {job} now, next {next}", i + 1));
                }
            }
            Key::Report => {
                let s = summarise(config, "report", boards, host, (0, 0, 0.0), Vec::new());
                for line in s.table().lines() {
                    say(line.to_string());
                }
            }
            Key::Parameters => {
                let t0s: Vec<u64> = boards.iter().map(|b| b.t0_ns).collect();
                let cap = config.capacity(&t0s);
                say(format!(
                    "parameters: {} machines, {} needles, ring {RING}, byte {} ns, batch {}, loss {}, duplicate {}, silence {} needles",
                    boards.len(),
                    config.needles,
                    config.byte_ns,
                    config.batch,
                    config.loss,
                    config.duplicate,
                    config.silence_needles
                ));
                say(format!(
                    "capacity: {} ({:.1} %), up to {} machines",
                    cap.verdict, cap.utilisation_percent, cap.max_machines_at_fastest
                ));
            }
            Key::Change(n, job) => match machine(n) {
                Some(m) => {
                    host.jobs[m].change_after_current(job);
                    say(format!("machine {n}: job {job} after the current one"));
                }
                None => say(format!("no machine {n}")),
            },
            Key::Status(n) => match machine(n) {
                Some(m) => say(boards[m].status_line()),
                None => say(format!("no machine {n}")),
            },
            Key::Reinit(n) => match machine(n) {
                Some(m) => {
                    let _ = host.master.reinit(m);
                    say(format!("machine {n}: interface re-initialised"));
                }
                None => say(format!("no machine {n}")),
            },
            Key::Break => {
                say("break: back to the scheduler".into());
                return true;
            }
        }
        false
    }
}

#[derive(Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Event {
    /// The link finished a frame.
    LinkFree,
    /// A refill frame reaches machine m.
    Frame(usize, Vec<u8>),
    /// A report reaches the master.
    Report(usize, Vec<u8>),
    /// Machine m's next needle.
    Needle(usize),
    /// A scripted key.
    Key(usize),
}

/// The in-memory simulation: boards, host, link and keyboard.
#[derive(Debug)]
pub struct Sim {
    /// The configuration.
    pub config: Config,
    /// The boards.
    pub boards: Vec<Board>,
    /// The host.
    pub host: Host,
    /// The keyboard.
    pub keyboard: Keyboard,
    queue: BinaryHeap<Reverse<(u64, u64, Event)>>,
    seq: u64,
    rng: ChaCha8Rng,
    link_busy_until: u64,
    link_busy_total: u64,
    /// Frames lost.
    pub lost: u64,
    /// Frames duplicated.
    pub duplicated: u64,
    script: Vec<Timed>,
    /// Simulated time, ns.
    pub now: u64,
    stopped: bool,
}

impl Sim {
    /// A simulation ready to run.
    ///
    /// # Errors
    /// An invalid configuration.
    pub fn new(config: Config, script: Vec<Timed>) -> Result<Self, String> {
        config.validate()?;
        let boards = speeds(&config)
            .into_iter()
            .enumerate()
            .map(|(i, rpm)| Board::new(i, rpm, &config))
            .collect::<Result<Vec<_>, _>>()?;
        let t0s: Vec<u64> = boards.iter().map(|b| b.t0_ns).collect();
        let host = Host::new(&config, &t0s)?;
        let mut sim = Self {
            rng: ChaCha8Rng::seed_from_u64(config.seed ^ 0x5EED),
            config,
            boards,
            host,
            keyboard: Keyboard::default(),
            queue: BinaryHeap::new(),
            seq: 0,
            link_busy_until: 0,
            link_busy_total: 0,
            lost: 0,
            duplicated: 0,
            script,
            now: 0,
            stopped: false,
        };
        // Machines start at staggered phases, after the master's first fill.
        for i in 0..sim.boards.len() {
            let phase = sim.rng.random_range(0..sim.boards[i].t0_ns);
            sim.push(START_NS + phase, Event::Needle(i));
            // Each board announces itself.
            let mut frame = [0u8; link::REPORT_LEN];
            if let Some(hello) = sim.boards[i].announce() {
                if hello.encode(&mut frame).is_ok() {
                    sim.push(0, Event::Report(i, frame.to_vec()));
                }
            }
        }
        for k in 0..sim.script.len() {
            let at = (sim.script[k].at * 1e9) as u64;
            sim.push(at, Event::Key(k));
        }
        Ok(sim)
    }

    fn push(&mut self, at: u64, event: Event) {
        self.seq += 1;
        self.queue.push(Reverse((at, self.seq, event)));
    }

    fn master_up(&self, now: u64) -> bool {
        self.config.master_fault.is_none_or(|(from, len)| {
            let t = now as f64 / 1e9;
            !(from..from + len).contains(&t)
        })
    }

    /// Sends a frame through the faulty link: lost, once or twice.
    fn deliver(&mut self, at: u64, event: impl Fn() -> Event) {
        if self.rng.random_bool(self.config.loss) {
            self.lost += 1;
            return;
        }
        self.push(at, event());
        if self.rng.random_bool(self.config.duplicate) {
            self.duplicated += 1;
            let later = at + self.rng.random_range(0..2_000_000);
            self.push(later, event());
        }
    }

    fn serve(&mut self, now: u64) {
        if now < self.link_busy_until || !self.master_up(now) {
            return;
        }
        if let Some((m, frame, items)) = self.host.next_frame(now) {
            let done = now + self.config.frame_ns(items);
            self.link_busy_until = done;
            self.link_busy_total += done - now;
            self.push(done, Event::LinkFree);
            self.deliver(done, || Event::Frame(m, frame.clone()));
        }
    }

    /// Runs until `until_ns` (or the end of the run, or Break); `progress` gets simulated
    /// seconds done.
    pub fn run_until(&mut self, until_ns: u64) {
        let end = (self.config.seconds * 1e9) as u64;
        let until = until_ns.min(end);
        while let Some(Reverse((at, _, _))) = self.queue.peek() {
            if *at > until || self.stopped {
                break;
            }
            let Some(Reverse((at, _, event))) = self.queue.pop() else {
                break;
            };
            self.now = at;
            match event {
                Event::LinkFree => self.serve(at),
                Event::Frame(m, frame) => self.boards[m].frame(&frame),
                Event::Report(m, bytes) => {
                    if self.master_up(at) {
                        if let Some(keep_alive) = self.host.report(at, m, &bytes) {
                            // A keep-alive goes out between refills (short: 9 bytes).
                            self.deliver(at + self.config.frame_ns(0), || {
                                Event::Frame(m, keep_alive.clone())
                            });
                        }
                        self.serve(at);
                    }
                }
                Event::Needle(m) => {
                    let host = &mut self.host;
                    let report = self.boards[m].needle(|k| host.byte(m, k));
                    let next = at + self.boards[m].t0_ns;
                    self.push(next, Event::Needle(m));
                    if let Some(report) = report {
                        let mut frame = [0u8; link::REPORT_LEN];
                        if report.encode(&mut frame).is_ok() {
                            let arrive = at + self.config.report_ns;
                            self.deliver(arrive, || Event::Report(m, frame.to_vec()));
                        }
                    }
                }
                Event::Key(k) => {
                    let key = self.script[k].key;
                    self.key(key);
                }
            }
        }
        self.now = self.now.max(until);
    }

    /// Answers an operator key now.
    pub fn key(&mut self, key: Key) {
        let now_s = self.now as f64 / 1e9;
        if self
            .keyboard
            .key(key, now_s, &self.boards, &mut self.host, &self.config)
        {
            self.stopped = true;
        }
    }

    /// `true` once Break was pressed or the run's time is up.
    #[must_use]
    pub fn finished(&self) -> bool {
        self.stopped || self.now >= (self.config.seconds * 1e9) as u64
    }

    /// The summary.
    #[must_use]
    pub fn summary(&self) -> Summary {
        let busy = 100.0 * self.link_busy_total as f64 / self.now.max(1) as f64;
        summarise(
            &self.config,
            "in memory",
            &self.boards,
            &self.host,
            (self.lost, self.duplicated, busy),
            self.keyboard.screen.clone(),
        )
    }
}

/// Writes the fabric of every machine as a PNG: one column per machine, one pixel row per
/// knitted row (newest at the bottom), needles across; ROM rows in greys, needles that did not
/// get the master's byte in red, and a stripe at each column's left: green for master rows,
/// grey for stand-alone, red for patched.
///
/// # Errors
/// An I/O or encoding error, as text.
pub fn write_png(path: &std::path::Path, boards: &[Board], max_rows: usize) -> Result<(), String> {
    const MASTER: [[u8; 3]; 4] = [[245, 240, 225], [40, 70, 150], [190, 40, 60], [30, 30, 30]];
    const LOCAL: [[u8; 3]; 4] = [
        [200, 200, 200],
        [150, 150, 150],
        [110, 110, 110],
        [70, 70, 70],
    ];
    const SCALE: usize = 2;
    const GAP: usize = 6;
    const STRIPE: usize = 4;
    let needles = boards.first().map_or(0, |b| b.needles as usize);
    let rows = boards
        .iter()
        .map(|b| b.rows.len().min(max_rows))
        .max()
        .unwrap_or(0)
        .max(1);
    let column = STRIPE + needles * SCALE;
    let width = boards.len() * (column + GAP) + GAP;
    let height = rows * SCALE + 2 * GAP;
    let mut pixels = vec![255u8; width * height * 3];
    let mut put = |x: usize, y: usize, rgb: [u8; 3]| {
        let at = (y * width + x) * 3;
        if let Some(p) = pixels.get_mut(at..at + 3) {
            p.copy_from_slice(&rgb);
        }
    };
    for (i, board) in boards.iter().enumerate() {
        let x0 = GAP + i * (column + GAP);
        let first = board.rows.len().saturating_sub(max_rows);
        for (r, row) in board.rows[first..].iter().enumerate() {
            let stripe = match row.source {
                RowSource::Master(_) => [60, 170, 80],
                RowSource::Local => [150, 150, 150],
                RowSource::Patched => [220, 30, 30],
            };
            for dy in 0..SCALE {
                let y = GAP + r * SCALE + dy;
                for dx in 0..STRIPE - 1 {
                    put(x0 + dx, y, stripe);
                }
                for (n, &c) in row.needles.iter().enumerate() {
                    let rgb = if c & 0x80 != 0 {
                        [255, 0, 0]
                    } else if row.source == RowSource::Local {
                        LOCAL[usize::from(c & 3)]
                    } else {
                        MASTER[usize::from(c & 3)]
                    };
                    for sx in 0..SCALE {
                        put(x0 + STRIPE + n * SCALE + sx, y, rgb);
                    }
                }
            }
        }
    }
    let file =
        std::fs::File::create(path).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width as u32, height as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    writer
        .write_image_data(&pixels)
        .map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())
}

/// A seeded loss-and-duplication filter in front of a socket.
#[derive(Debug)]
struct Filter {
    rng: ChaCha8Rng,
    loss: f64,
    duplicate: f64,
    lost: u64,
    duplicated: u64,
}

impl Filter {
    fn new(seed: u64, config: &Config) -> Self {
        Self {
            rng: ChaCha8Rng::seed_from_u64(seed),
            loss: config.loss,
            duplicate: config.duplicate,
            lost: 0,
            duplicated: 0,
        }
    }

    /// How many times a received datagram is taken: 0 (lost), 1, or 2 (duplicated).
    fn copies(&mut self) -> usize {
        if self.rng.random_bool(self.loss) {
            self.lost += 1;
            0
        } else if self.rng.random_bool(self.duplicate) {
            self.duplicated += 1;
            2
        } else {
            1
        }
    }
}

/// Drains a non-blocking socket: every datagram waiting, through the filter.
fn drain(
    socket: &std::net::UdpSocket,
    filter: &mut Filter,
    mut take: impl FnMut(&[u8], std::net::SocketAddr),
) {
    let mut buf = [0u8; 512];
    while let Ok((n, from)) = socket.recv_from(&mut buf) {
        for _ in 0..filter.copies() {
            take(&buf[..n], from);
        }
    }
}

/// The same system over real datagrams: the master and every machine run as threads with their
/// own UDP sockets on 127.0.0.1, in real time, with the seeded filter in front of each socket.
/// Machines run the master's default jobs (no keyboard); a refill datagram carries up to 64
/// owed items. Returns the summary and the boards.
///
/// # Errors
/// A socket error or an invalid configuration, as text.
pub fn run_udp(config: &Config) -> Result<(Summary, Vec<Board>), String> {
    use std::net::UdpSocket;
    use std::time::{Duration, Instant};
    config.validate()?;
    let bind = || -> Result<UdpSocket, String> {
        let s =
            UdpSocket::bind("127.0.0.1:0").map_err(|e| format!("cannot bind 127.0.0.1: {e}"))?;
        s.set_nonblocking(true).map_err(|e| e.to_string())?;
        Ok(s)
    };
    let boards: Vec<Board> = speeds(config)
        .into_iter()
        .enumerate()
        .map(|(i, rpm)| Board::new(i, rpm, config))
        .collect::<Result<_, _>>()?;
    let t0s: Vec<u64> = boards.iter().map(|b| b.t0_ns).collect();
    let mut host = Host::new(config, &t0s)?;
    // A datagram is the link's unit: a refill carries as many owed items as fit (a burst of
    // one-item datagrams at the first fill would overrun the sockets' receive buffers).
    host.batch = link::MAX_REFILL as u32;
    let master_socket = bind()?;
    let master_address = master_socket.local_addr().map_err(|e| e.to_string())?;
    let board_sockets: Vec<UdpSocket> = (0..boards.len())
        .map(|_| bind())
        .collect::<Result<_, _>>()?;
    let board_addresses: Vec<std::net::SocketAddr> = board_sockets
        .iter()
        .map(|s| s.local_addr().map_err(|e| e.to_string()))
        .collect::<Result<_, _>>()?;
    let start = Instant::now();
    let run_for = Duration::from_secs_f64(config.seconds);
    let fault = config.master_fault;
    let master_up = move |t: Duration| {
        fault.is_none_or(|(from, len)| !(from..from + len).contains(&t.as_secs_f64()))
    };
    std::thread::scope(|scope| -> Result<(Summary, Vec<Board>), String> {
        let mut handles = Vec::new();
        for (i, (mut board, socket)) in boards.into_iter().zip(board_sockets).enumerate() {
            let config = config.clone();
            handles.push(scope.spawn(move || -> (Board, u64, u64) {
                let mut filter = Filter::new(config.seed.wrapping_add(1 + i as u64), &config);
                let mut jobs = Jobs::new(i as u32, config.job_rows);
                let needles = u64::from(config.needles);
                let mut expected = |k: u64| {
                    let (job, row) = jobs.at(k / needles);
                    pattern(job, row, (k % needles) as u16)
                };
                let send_report = |report: Report| {
                    let mut frame = [0u8; link::REPORT_LEN];
                    if report.encode(&mut frame).is_ok() {
                        let _ = socket.send_to(&frame, master_address);
                    }
                };
                if let Some(hello) = board.announce() {
                    send_report(hello);
                }
                let begin = Duration::from_millis(100);
                let mut done = 0u64;
                while start.elapsed() < run_for {
                    drain(&socket, &mut filter, |bytes, _| board.frame(bytes));
                    let elapsed = start.elapsed();
                    let due = elapsed.saturating_sub(begin).as_nanos() as u64 / board.t0_ns;
                    while done < due {
                        if let Some(report) = board.needle(&mut expected) {
                            send_report(report);
                        }
                        done += 1;
                    }
                    std::thread::sleep(Duration::from_micros(200));
                }
                (board, filter.lost, filter.duplicated)
            }));
        }
        let mut filter = Filter::new(config.seed ^ 0xA5A5, config);
        while start.elapsed() < run_for {
            let now = start.elapsed();
            let now_ns = now.as_nanos() as u64;
            let up = master_up(now);
            let mut replies = Vec::new();
            drain(&master_socket, &mut filter, |bytes, from| {
                if up {
                    if let Some(m) = board_addresses.iter().position(|a| *a == from) {
                        if let Some(keep_alive) = host.report(now_ns, m, bytes) {
                            replies.push((m, keep_alive));
                        }
                    }
                }
            });
            if up {
                while let Some((m, frame, _)) = host.next_frame(now_ns) {
                    replies.push((m, frame));
                }
            }
            for (m, frame) in replies {
                let _ = master_socket.send_to(&frame, board_addresses[m]);
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        let mut boards = Vec::new();
        let (mut lost, mut duplicated) = (filter.lost, filter.duplicated);
        for h in handles {
            let (board, l, d) = h.join().map_err(|_| "a machine thread panicked")?;
            lost += l;
            duplicated += d;
            boards.push(board);
        }
        let summary = summarise(
            config,
            "udp 127.0.0.1",
            &boards,
            &host,
            (lost, duplicated, f64::NAN),
            Vec::new(),
        );
        Ok((summary, boards))
    })
}
