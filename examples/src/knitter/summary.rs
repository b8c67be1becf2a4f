//! Presentation of a run: the per-machine figures, the link's counters and the capacity check,
//! as the text table (printed at the end and by the P key) and as JSON.

use std::fmt::Write as _;

use regler_ring_transfer::Mode;
use serde::Serialize;

use super::boards::{Board, RowSource};
use super::master::Host;
use super::{Capacity, Config};

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
    /// Link busy, percent of the run: the time the refill frames hold a link of the run's byte
    /// time (see `link_busy_of`).
    pub link_busy_percent: f64,
    /// What the busy figure measures: the simulated link (in memory) or, over UDP, the refill
    /// frames' time at the run's byte time (the sockets' own time is not measured).
    pub link_busy_of: String,
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
            "link ({}): {} frames, {} items, {} keep-alives; lost {}, duplicated {}; busy {:.1} % ({})",
            self.transport,
            self.frames,
            self.items_sent,
            self.keep_alives,
            self.frames_lost,
            self.frames_duplicated,
            self.link_busy_percent,
            self.link_busy_of
        );
        let _ = writeln!(
            s,
            "capacity check: {} (utilisation {} worst case; this link serves up to {} machines at the fastest speed)",
            self.capacity.verdict,
            self.capacity.utilisation(),
            self.capacity.max_machines_at_fastest
        );
        let _ = write!(
            s,
            "pattern check: {wrong} wrong bytes, {order} rows out of order, {underruns} underruns"
        );
        s
    }
}

/// The link's counters of a run so far, for the summary and the P key alike.
#[derive(Clone, Copy, Debug, Default)]
pub struct Link {
    /// Frames the link's filter lost (both directions).
    pub lost: u64,
    /// Frames it delivered twice.
    pub duplicated: u64,
    /// Time run so far, nanoseconds (simulated in memory, real over UDP).
    pub elapsed_ns: u64,
    /// `true` when the link is modelled byte by byte (in memory); over UDP the busy figure is
    /// the refill frames' time at the configured byte time, as the sockets' own time is not
    /// measured.
    pub simulated: bool,
}

/// Summarises boards and host.
#[must_use]
pub fn summarise(
    config: &Config,
    transport: &str,
    boards: &[Board],
    host: &Host,
    link: Link,
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
        frames_lost: link.lost,
        frames_duplicated: link.duplicated,
        link_busy_percent: 100.0 * host.link_ns as f64 / link.elapsed_ns.max(1) as f64,
        link_busy_of: if link.simulated {
            "the simulated link".into()
        } else {
            format!(
                "the refill frames at {} ns per byte; the sockets' own time is not measured",
                config.byte_ns
            )
        },
        screen,
    }
}
