//! What a whole-plant run found: the JSON report (the top-level sack figures are the voting
//! run's), the map's data, and the text summary.

#![allow(
    clippy::needless_range_loop,
    reason = "an index names a reader, lane, desk or exit across several arrays"
)]

use std::fmt::Write as _;

use serde::Serialize;

use super::Config;
use super::field::{Outcome, Place};
use super::layout::{
    BINS_PER_DOCK, DESKS, DOCKS, EXITS, Next, R_CHAIN, R_EMPTYING, READER_NAMES, READERS, next,
};
use super::map_data::{MapData, MapEdge, MapNode, NodeKind};
use super::operator::{BUFFER_LANES, EMPTYING_STATIONS, PanelTotals, lane_name, station_name};
use super::run::{ReaderFigures, RunResult};
use crate::cli::number;

/// Mis-deliveries per million sacks loaded, for each way of reading.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct PerMillion {
    /// The source's single parity-checked scan.
    pub parity_only: f64,
    /// Voting over the scans.
    pub voting: f64,
}

/// One run's figures (both are in the report).
#[derive(Clone, Debug, Serialize)]
pub struct RunFigures {
    /// `parity_only` or `voting`.
    pub reading: &'static str,
    /// Sacks loaded.
    pub sacks_loaded: u64,
    /// Delivered to their right destination.
    pub sacks_delivered: u64,
    /// Delivered elsewhere.
    pub sacks_misdelivered: u64,
    /// To the manual station.
    pub sacks_rejected: u64,
    /// Still in the plant at the end.
    pub sacks_in_plant: u64,
    /// Entries refused at the desks (never loaded).
    pub entries_refused: u64,
    /// Sacks loaded per hour at P1–P3.
    pub sacks_per_hour_by_desk: [f64; DESKS],
    /// Sacks delivered per hour: letters (A), parcels (B, C), sorted post (bins).
    pub delivered_per_hour: DeliveredPerHour,
    /// Trolleys each reader sent to the manual station.
    pub rejected_by_reader: Vec<u64>,
    /// Each reader's health.
    pub readers: Vec<ReaderFigures>,
    /// Time-supervision faults reported.
    pub supervision_faults: u64,
    /// Stretch recalibrations.
    pub recalibrations: u64,
    /// Executive cycles.
    pub cycles: u64,
    /// CPU load per cycle, mean and max, percent.
    pub cpu_load_percent_mean: f64,
    /// Largest.
    pub cpu_load_percent_max: f64,
    /// The busiest cycle's busy time, ms (the cost model).
    pub busiest_cycle_ms: f64,
    /// Watchdog trips.
    pub watchdog_trips: u32,
    /// Longest time from a hang's start (or the power's return, for a hang begun during a
    /// power failure) to safe outputs, ms: at most 100.
    pub watchdog_safe_ms: u64,
    /// Power failures survived.
    pub power_failures: u32,
    /// Teletype lines printed.
    pub teletype_lines: usize,
    /// Printouts lost to a full spool.
    pub spool_overflow: u64,
    /// The panels.
    pub panels: PanelTotals,
    /// Real seconds.
    pub real_seconds: f64,
}

/// Delivered sacks per hour by destination class.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct DeliveredPerHour {
    /// Letters at A1–A3.
    pub letters: f64,
    /// Parcels at B and C.
    pub parcels: f64,
    /// Sorted post into the bins.
    pub sorted: f64,
}

/// The report of a whole-plant run.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Simulated hours.
    pub simulated_hours: f64,
    /// Seed.
    pub seed: u64,
    /// Trolleys.
    pub trolleys: u16,
    /// Voting run: sacks loaded.
    pub sacks_loaded: u64,
    /// Voting run: delivered.
    pub sacks_delivered: u64,
    /// Voting run: misdelivered.
    pub sacks_misdelivered: u64,
    /// Voting run: rejected.
    pub sacks_rejected: u64,
    /// Voting run: in the plant.
    pub sacks_in_plant: u64,
    /// Mis-deliveries per million, both runs.
    pub misdelivered_per_million: PerMillion,
    /// Voting run.
    pub watchdog_trips: u32,
    /// Voting run.
    pub power_failures: u32,
    /// Voting run: bytes the line noise changed.
    pub panel_bytes_corrupted: u64,
    /// Voting run.
    pub panel_displays_wrong_after_next_sequence: u64,
    /// Voting run.
    pub cpu_load_percent_mean: f64,
    /// Simulated time over real time (both runs in parallel).
    pub realtime_ratio: f64,
    /// Both runs in full.
    pub runs: [RunFigures; 2],
    /// The voting run's teletype printouts (the last 50).
    pub teletype: Vec<String>,
    /// The voting run's map.
    pub map: MapData,
    /// The parity-only run's map.
    pub map_parity_only: MapData,
}

fn per_million(r: &RunResult) -> f64 {
    let loaded: u64 = r.counts.loaded.iter().sum();
    if loaded == 0 {
        0.0
    } else {
        r.counts.misdelivered as f64 * 1e6 / loaded as f64
    }
}

fn figures(r: &RunResult) -> RunFigures {
    let h = r.hours.max(1e-9);
    let c = &r.counts;
    RunFigures {
        reading: r.reading.name(),
        sacks_loaded: c.loaded.iter().sum(),
        sacks_delivered: c.delivered,
        sacks_misdelivered: c.misdelivered,
        sacks_rejected: c.rejected,
        sacks_in_plant: r.in_plant,
        entries_refused: r.refused,
        sacks_per_hour_by_desk: std::array::from_fn(|p| c.loaded[p] as f64 / h),
        delivered_per_hour: DeliveredPerHour {
            letters: c.delivered_letters as f64 / h,
            parcels: c.delivered_parcels as f64 / h,
            sorted: c.delivered_sorted as f64 / h,
        },
        rejected_by_reader: r.rejected_by.to_vec(),
        readers: r.readers.clone(),
        supervision_faults: r.supervision_faults,
        recalibrations: r.recalibrations,
        cycles: r.cycles,
        cpu_load_percent_mean: f64::from(r.busy_mean_us) / 500.0,
        cpu_load_percent_max: f64::from(r.busy_max_us) / 500.0,
        busiest_cycle_ms: f64::from(r.busy_max_us) / 1000.0,
        watchdog_trips: r.watchdog_trips,
        watchdog_safe_ms: r.watchdog_safe_ms,
        power_failures: r.power_failures,
        teletype_lines: r.printed.len(),
        spool_overflow: r.spool_overflow,
        panels: r.panels,
        real_seconds: r.real_seconds,
    }
}

impl Report {
    /// The report of the two runs.
    #[must_use]
    pub fn new(config: &Config, parity: RunResult, voting: RunResult, real_seconds: f64) -> Report {
        let v = figures(&voting);
        let p = figures(&parity);
        Report {
            simulated_hours: config.hours,
            seed: config.seed,
            trolleys: config.trolleys,
            sacks_loaded: v.sacks_loaded,
            sacks_delivered: v.sacks_delivered,
            sacks_misdelivered: v.sacks_misdelivered,
            sacks_rejected: v.sacks_rejected,
            sacks_in_plant: v.sacks_in_plant,
            misdelivered_per_million: PerMillion {
                parity_only: per_million(&parity),
                voting: per_million(&voting),
            },
            watchdog_trips: v.watchdog_trips,
            power_failures: v.power_failures,
            panel_bytes_corrupted: v.panels.bytes_corrupted,
            panel_displays_wrong_after_next_sequence: v.panels.displays_wrong_after_next_sequence,
            cpu_load_percent_mean: v.cpu_load_percent_mean,
            realtime_ratio: config.hours * 3600.0 / real_seconds.max(1e-9),
            teletype: voting
                .printed
                .iter()
                .rev()
                .take(50)
                .rev()
                .cloned()
                .collect(),
            map: map(&voting),
            map_parity_only: map(&parity),
            runs: [p, v],
        }
    }
}

/// The plant map of a run: places, rail sections with their trolleys, where sacks went wrong.
#[must_use]
pub fn map(r: &RunResult) -> MapData {
    let mut nodes = Vec::new();
    let mut node = |name: String, kind, layer| {
        nodes.push(MapNode {
            name,
            kind,
            layer,
            misdelivered: 0,
            rejected: 0,
            alarm: false,
        });
        nodes.len() - 1
    };
    let desks: Vec<usize> = (0..DESKS)
        .map(|p| node(format!("P{}", p + 1), NodeKind::Loading, 0))
        .collect();
    let layers = [1, 1, 1, 2, 3, 4, 4, 3, 6, 4, 4, 4];
    let readers: Vec<usize> = (0..READERS)
        .map(|i| node(READER_NAMES[i].into(), NodeKind::Reader, layers[i]))
        .collect();
    let lanes: Vec<usize> = (0..BUFFER_LANES)
        .map(|l| node(lane_name(l).into(), NodeKind::Buffer, 5))
        .collect();
    let stations: Vec<usize> = (0..EMPTYING_STATIONS)
        .map(|s| node(station_name(s).into(), NodeKind::Emptying, 7))
        .collect();
    let docks: Vec<usize> = (0..DOCKS)
        .map(|d| node(format!("dock {}", d + 1), NodeKind::Dock, 5))
        .collect();
    let manual = node("manual".into(), NodeKind::Manual, 8);
    let ret = node("return".into(), NodeKind::Return, 9);
    let mut edges = Vec::new();
    let c = &r.counts;
    for p in 0..DESKS {
        edges.push(MapEdge {
            from: desks[p],
            to: readers[p],
            trolleys: c.loaded[p],
        });
        edges.push(MapEdge {
            from: readers[p],
            to: readers[3],
            trolleys: c.loaded[p],
        });
    }
    for (reader, exits) in c.passed.iter().enumerate() {
        for e in 0..EXITS[reader] {
            let to = match next(reader, e) {
                Some(Next::Reader(n)) => readers[n],
                Some(Next::Lane(l)) => lanes[usize::from(l)],
                Some(Next::Station(s)) => stations[usize::from(s)],
                Some(Next::Chain(d)) => docks[d],
                None => continue,
            };
            edges.push(MapEdge {
                from: readers[reader],
                to,
                trolleys: exits[e],
            });
        }
        if reader >= R_CHAIN {
            edges.push(MapEdge {
                from: readers[reader],
                to: docks[reader - R_CHAIN],
                trolleys: exits[0],
            });
        }
        if exits[15] > 0 {
            edges.push(MapEdge {
                from: readers[reader],
                to: manual,
                trolleys: exits[15],
            });
        }
    }
    for (l, &out) in c.lane_out.iter().enumerate() {
        edges.push(MapEdge {
            from: lanes[l],
            to: readers[R_EMPTYING],
            trolleys: out,
        });
    }
    for (s, &node) in stations.iter().enumerate() {
        edges.push(MapEdge {
            from: node,
            to: ret,
            trolleys: c.passed[R_EMPTYING][s],
        });
    }
    for (d, &dock) in docks.iter().enumerate() {
        edges.push(MapEdge {
            from: dock,
            to: ret,
            trolleys: c.passed[R_CHAIN + d][0],
        });
    }
    let manual_in: u64 = c.passed.iter().map(|e| e[15]).sum();
    edges.push(MapEdge {
        from: manual,
        to: ret,
        trolleys: manual_in,
    });
    for (place, outcome) in &c.ended {
        match (place, outcome) {
            (Place::Station(s), Outcome::Misdelivered) => {
                nodes[stations[usize::from(*s)]].misdelivered += 1
            }
            (Place::Bin(b), Outcome::Misdelivered) => {
                nodes[docks[usize::from(*b) / BINS_PER_DOCK]].misdelivered += 1
            }
            (Place::Manual(from), Outcome::Rejected) => {
                let n = if *from < READERS {
                    readers[*from]
                } else {
                    manual
                };
                nodes[n].rejected += 1;
            }
            _ => {}
        }
    }
    for (i, f) in r.readers.iter().enumerate() {
        nodes[readers[i]].alarm = f.alarm;
    }
    MapData {
        hours: r.hours,
        nodes,
        edges,
    }
}

/// The text summary.
#[must_use]
pub fn summary_text(report: &Report) -> String {
    let mut s = String::new();
    let [p, v] = &report.runs;
    let _ = writeln!(
        s,
        "mailbag-sorter: the whole 1977 Malmö Ban plant, {} simulated hours, seed {}, {} trolleys",
        number(report.simulated_hours),
        report.seed,
        report.trolleys
    );
    let _ = writeln!(
        s,
        "\nsacks (voting run)          loaded {}  delivered {}  misdelivered {}  rejected {}  in the plant {}  refused at the desks {}",
        v.sacks_loaded,
        v.sacks_delivered,
        v.sacks_misdelivered,
        v.sacks_rejected,
        v.sacks_in_plant,
        v.entries_refused
    );
    let _ = writeln!(
        s,
        "sacks (parity-only run)     loaded {}  delivered {}  misdelivered {}  rejected {}  in the plant {}  refused at the desks {}",
        p.sacks_loaded,
        p.sacks_delivered,
        p.sacks_misdelivered,
        p.sacks_rejected,
        p.sacks_in_plant,
        p.entries_refused
    );
    let _ = writeln!(
        s,
        "misdelivered per million    parity only {}   voting {}   (same seed, same traffic)",
        tenths(report.misdelivered_per_million.parity_only),
        tenths(report.misdelivered_per_million.voting)
    );
    let _ = writeln!(
        s,
        "sacks per hour loaded       P1 {}  P2 {}  P3 {}",
        tenths(v.sacks_per_hour_by_desk[0]),
        tenths(v.sacks_per_hour_by_desk[1]),
        tenths(v.sacks_per_hour_by_desk[2])
    );
    let _ = writeln!(
        s,
        "delivered per hour          letters (A) {}  parcels (B, C) {}  sorted post (bins) {}",
        tenths(v.delivered_per_hour.letters),
        tenths(v.delivered_per_hour.parcels),
        tenths(v.delivered_per_hour.sorted)
    );
    let _ = writeln!(
        s,
        "\nreaders (voting run)   passages  no-reads  disagreements  to manual  alarm"
    );
    for (i, f) in v.readers.iter().enumerate() {
        let _ = writeln!(
            s,
            "  {:<5} {:>15} {:>9} {:>14} {:>10}  {}",
            READER_NAMES[i],
            f.passages,
            f.no_reads,
            f.disagreements,
            v.rejected_by_reader[i],
            if f.alarm { "ON" } else { "off" }
        );
    }
    let panels = &v.panels;
    let _ = writeln!(
        s,
        "\npanels                      bytes sent {}  corrupted {}  errors detected {}  displays wrong after the next sequence {}  commands {}",
        panels.bytes_sent,
        panels.bytes_corrupted,
        panels.errors_detected,
        panels.displays_wrong_after_next_sequence,
        panels.commands
    );
    let _ = writeln!(
        s,
        "executive                   {} cycles of 50 ms; CPU load mean {} %, max {} %; busiest cycle {} ms busy",
        v.cycles,
        tenths(v.cpu_load_percent_mean),
        tenths(v.cpu_load_percent_max),
        number(v.busiest_cycle_ms)
    );
    let _ = writeln!(
        s,
        "faults                      watchdog trips {}{}  power failures survived {}  time-supervision reports {}",
        v.watchdog_trips,
        if v.watchdog_trips > 0 {
            format!(" (outputs safe {} ms after the hang)", v.watchdog_safe_ms)
        } else {
            String::new()
        },
        v.power_failures,
        v.supervision_faults
    );
    let _ = writeln!(
        s,
        "teletype                    {} printouts{}",
        v.teletype_lines,
        if v.spool_overflow > 0 {
            format!(" ({} lost to a full spool)", v.spool_overflow)
        } else {
            String::new()
        }
    );
    for line in report.teletype.iter().rev().take(5).rev() {
        let _ = writeln!(s, "  {line}");
    }
    let _ = writeln!(
        s,
        "\nspeed                       {} × real time (both runs in parallel)",
        whole(report.realtime_ratio)
    );
    s
}

/// `x` to one decimal, as the summary prints rates and loads (`-` if it is not a number).
fn tenths(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.1}")
    } else {
        "-".to_string()
    }
}

/// `x` rounded to a whole number, as the summary prints the speed (`-` if it is not a number).
fn whole(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.0}")
    } else {
        "-".to_string()
    }
}
