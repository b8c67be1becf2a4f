//! The performance report (`docs/PERFORMANCE.md`): what is measured, how the measurements are
//! written, read back and compared. The `report` binary runs the measurements; this module is the
//! part that needs no tools, so its tests run everywhere.
//!
//! The file keeps its raw measurements in three tables it can read back — every instruction
//! count with its counter, every criterion median, the on-target tables verbatim — and derives
//! everything else (the summary, the scaling tables, the READMEs' block) from them. So a run of
//! one part re-measures that part and re-reads the others, and a check can re-measure the parts
//! that repeat exactly and compare them figure by figure.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::highway::{encoded, of_extreme_length, workload};

/// Marks the start of the block the command writes into a README.
pub const README_BEGIN: &str = "<!-- performance:begin: written by `cargo run --release -p regler-benches --bin report` from docs/PERFORMANCE.md; do not edit by hand -->";
/// Marks the end of that block.
pub const README_END: &str = "<!-- performance:end -->";

/// Marks the start of a crate README's own block (`name`: the crate's directory).
#[must_use]
pub fn crate_begin(name: &str) -> String {
    format!(
        "<!-- performance:{name}:begin: written by `cargo run --release -p regler-benches --bin report` from docs/PERFORMANCE.md; do not edit by hand -->"
    )
}

/// Marks the end of a crate README's own block.
#[must_use]
pub fn crate_end(name: &str) -> String {
    format!("<!-- performance:{name}:end -->")
}
const ON_TARGET_BEGIN: &str = "<!-- on-target:begin -->";
const ON_TARGET_END: &str = "<!-- on-target:end -->";

/// The parts of the report, each measured by its own tool.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Part {
    /// Criterion medians on the host.
    Criterion,
    /// Instruction counts on the host (valgrind's callgrind, N and 2N operations).
    Instructions,
    /// Instruction counts on the cores under QEMU (`on-target/cycles`).
    OnTarget,
}

impl Part {
    /// Every part, in the order they run.
    pub const ALL: [Part; 3] = [Part::Instructions, Part::OnTarget, Part::Criterion];

    /// The part's name on the command line and in the file.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Part::Criterion => "criterion",
            Part::Instructions => "instructions",
            Part::OnTarget => "on-target",
        }
    }

    /// The part of a name, if it is one.
    #[must_use]
    pub fn parse(name: &str) -> Option<Part> {
        Part::ALL.into_iter().find(|p| p.name() == name)
    }
}

/// Where and when a part was measured.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Provenance {
    /// CPU model, cores, operating system.
    pub machine: String,
    /// `rustc --version` (and the counting tool's version where there is one).
    pub compiler: String,
    /// The commit measured (`-dirty` when the code differed from it).
    pub commit: String,
    /// The date, UTC.
    pub date: String,
}

/// One instruction counter: a binary of this package run with `{N}` operations.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Counter {
    /// The binary (`ring-pairs`, `pid-shapes`, …).
    pub bin: &'static str,
    /// Its arguments; `{N}` stands for the number of operations.
    pub args: Vec<String>,
    /// Operations of the first run (the second runs 2N).
    pub n: u64,
}

impl Counter {
    fn new(bin: &'static str, args: &str, n: u64) -> Counter {
        Counter {
            bin,
            args: args.split_whitespace().map(str::to_string).collect(),
            n,
        }
    }

    /// The counter's name in the file: the binary and its arguments.
    #[must_use]
    pub fn key(&self) -> String {
        format!("{} {}", self.bin, self.args.join(" "))
    }
}

/// An instruction count: N and the instructions per operation, to one decimal as written.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Count {
    /// Operations of the first run.
    pub n: u64,
    /// Instructions per operation, `(total(2N) − total(N)) / N` to one decimal.
    pub per_op: String,
}

/// Everything the file holds; the rest is derived from it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Data {
    /// Where and when each part was measured.
    pub provenance: BTreeMap<Part, Provenance>,
    /// Instruction counts by counter key, in the order written.
    pub counts: Vec<(String, Count)>,
    /// Criterion medians by full benchmark id, in nanoseconds per iteration.
    pub medians: BTreeMap<String, f64>,
    /// The on-target tables, verbatim (the lines of `on-target/cycles`' markdown tables).
    pub on_target: Vec<String>,
}

impl Data {
    fn count(&self, key: &str) -> Option<f64> {
        self.counts
            .iter()
            .find(|(k, _)| k == key)
            .and_then(|(_, c)| c.per_op.parse().ok())
    }
}

const PID_WORKLOADS: [&str; 4] = ["constant", "steps", "noise", "saturation"];
const SHAPES: [&str; 2] = ["firmware", "inlined"];
/// Sizes of the timer and chain scaling tables.
pub const SCALING_SIZES: [u32; 4] = [16, 256, 4096, 10_000];
/// Slaves of the master's scaling table.
pub const MASTER_SLAVES: [u32; 3] = [8, 80, 500];
/// The criterion bench targets, in the order they run.
pub const BENCHES: [&str; 6] = [
    "pid",
    "ring_transfer",
    "scan_cycle",
    "chain_tracker",
    "trolley_id",
    "panel_link",
];

/// Every instruction counter, with an N at which its count repeats (a multiple of the
/// workload's period where it has one; see `docs/PERFORMANCE.md`).
#[must_use]
pub fn counters() -> Vec<Counter> {
    let mut c = Vec::new();
    for shape in SHAPES {
        for who in [
            "ring",
            "spsc",
            "spsc-257",
            "split",
            "spsc-split",
            "array",
            "none",
        ] {
            c.push(Counter::new(
                "ring-pairs",
                &format!("{who} {shape} {{N}}"),
                100_000,
            ));
        }
    }
    for shape in SHAPES {
        for load in PID_WORKLOADS {
            for who in ["regler", "pid-crate", "none"] {
                let args = format!("{who} {shape} {load} {{N}}");
                c.push(Counter::new("pid-shapes", &args, 100_000));
            }
        }
    }
    for t in ["f32", "f64", "i16f16", "i32f32"] {
        c.push(Counter::new("pid-loop", &format!("{t} {{N}}"), 100_000));
    }
    for size in SCALING_SIZES {
        // The queue's wheel levels cascade every 64 and 4 096 ticks and its 64³ level every
        // 262 144: N = 262 144 covers whole periods.
        c.push(Counter::new(
            "scan-loop",
            &format!("wheel {size} {{N}}"),
            262_144,
        ));
        let n = (20_000_000 / (4 * u64::from(size))).clamp(500, 100_000);
        c.push(Counter::new(
            "scan-loop",
            &format!("count-down {size} {{N}}"),
            n,
        ));
    }
    c.push(Counter::new("scan-loop", "cycle 0 {N}", 20_000));
    for size in SCALING_SIZES {
        c.push(Counter::new(
            "chain-pulses",
            &format!("regler {size} {{N}}"),
            100_000,
        ));
        let n = (20_000_000 / (7 * u64::from(size))).clamp(500, 100_000);
        c.push(Counter::new(
            "chain-pulses",
            &format!("count-down {size} {{N}}"),
            n,
        ));
    }
    for slaves in MASTER_SLAVES {
        c.push(Counter::new(
            "master-decisions",
            &format!("{slaves} {{N}}"),
            50_000,
        ));
    }
    for which in [
        "encode",
        "decode",
        "decode-shortest",
        "decode-longest",
        "copy",
        "controller",
        "delay",
    ] {
        c.push(Counter::new("highway-codec", &format!("{which} {{N}}"), 50));
    }
    c
}

/// One side of a comparison: an instruction counter and a criterion benchmark, each divided
/// down to one operation, and optionally the same harness without the contestant (`none`) to
/// subtract for the net instructions.
#[derive(Clone, Debug, Default)]
struct Side {
    count: Option<String>,
    count_base: Option<String>,
    count_per: f64,
    time: Option<String>,
    time_per: f64,
}

impl Side {
    fn new() -> Side {
        Side {
            count_per: 1.0,
            time_per: 1.0,
            ..Side::default()
        }
    }
    fn count(mut self, key: String) -> Side {
        self.count = Some(key);
        self
    }
    fn net_of(mut self, key: String) -> Side {
        self.count_base = Some(key);
        self
    }
    fn count_per(mut self, ops: f64) -> Side {
        self.count_per = ops;
        self
    }
    fn time(mut self, id: String, ops: f64) -> Side {
        self.time = Some(id);
        self.time_per = ops;
        self
    }

    /// (instructions, gross instructions when net) per operation.
    fn instructions(&self, d: &Data) -> Option<(f64, Option<f64>)> {
        let gross = d.count(self.count.as_deref()?)? / self.count_per;
        match &self.count_base {
            Some(base) => Some((gross - d.count(base)? / self.count_per, Some(gross))),
            None => Some((gross, None)),
        }
    }

    fn median_ns(&self, d: &Data) -> Option<f64> {
        Some(d.medians.get(self.time.as_deref()?)? / self.time_per)
    }
}

/// A row of the hot-path table: regler's side, its anchor's, and the group it is summed up in.
struct Row {
    group: String,
    path: String,
    regler: Side,
    anchor_name: String,
    anchor: Side,
}

fn rows() -> Vec<Row> {
    let mut rows = Vec::new();
    let messages = workload();
    let (bytes, _) = encoded(&messages);
    let (messages, bytes) = (messages.len() as f64, bytes.len() as f64);
    for shape in SHAPES {
        for load in PID_WORKLOADS {
            let count = |who: &str| format!("pid-shapes {who} {shape} {load} {{N}}");
            let time = |who: &str| format!("pid_shape_{load}_{shape}_1000_samples/{who}");
            let base = count("none");
            rows.push(Row {
                group: format!("`Pid<f32>::update`, everything on, {shape} shape (4 workloads)"),
                path: format!("`Pid<f32>::update`, everything on — {shape}, {load}"),
                regler: Side::new()
                    .count(count("regler"))
                    .net_of(base.clone())
                    .time(time("regler_f32"), 1000.0),
                anchor_name: "`pid` crate 4".into(),
                anchor: Side::new()
                    .count(count("pid-crate"))
                    .net_of(base)
                    .time(time("pid_crate_f32"), 1000.0),
            });
        }
    }
    for shape in SHAPES {
        let count = |who: &str| format!("ring-pairs {who} {shape} {{N}}");
        let time = |who: &str| format!("ring/pair/{shape}/10000/{who}");
        let side = |who: &str, name: &str| {
            Side::new()
                .count(count(who))
                .net_of(count("none"))
                .time(time(name), 10_000.0)
        };
        let ring = || side("ring", "regler Ring 256");
        for (anchor, anchor_name, label) in [
            (
                "spsc",
                "heapless spsc Queue 256",
                "`heapless::spsc::Queue<u8, 256>` (holds 255)",
            ),
            (
                "spsc-257",
                "heapless spsc Queue 257",
                "`Queue<u8, 257>` (holds 256)",
            ),
            ("array", "plain array ring 256", "plain array ring"),
        ] {
            rows.push(Row {
                group: format!("`Ring<u8, 256>` receive + next vs {label}, {shape} shape"),
                path: format!("`Ring<u8, 256>` receive + next, statistics on — {shape}"),
                regler: ring(),
                anchor_name: label.into(),
                anchor: side(anchor, anchor_name),
            });
        }
        rows.push(Row {
            group: format!("split halves vs heapless `Producer` + `Consumer`, {shape} shape"),
            path: format!("`Filler` + `Drainer` (`SharedRing<u8, 256>`, holds 256) — {shape}"),
            regler: side("split", "regler Filler+Drainer 256"),
            anchor_name: "heapless `Producer` + `Consumer` (`Queue<u8, 256>`, holds 255)".into(),
            anchor: side("spsc-split", "heapless Producer+Consumer 256"),
        });
    }
    rows.push(Row {
        group: "two threads through the split halves vs heapless's".into(),
        path: "two threads, 1 million `u32` through a 256-slot ring, per item".into(),
        regler: Side::new().time("ring/two-thread transfer/regler Filler+Drainer".into(), 1e6),
        anchor_name: "heapless `Producer` + `Consumer`".into(),
        anchor: Side::new().time(
            "ring/two-thread transfer/heapless Producer+Consumer".into(),
            1e6,
        ),
    });
    for t in ["f64", "i16f16", "i32f32"] {
        rows.push(Row {
            group: format!("PID closed-loop sample, {t} vs f32"),
            path: format!("`Pid<{t}>` closed-loop sample (with the plant)"),
            regler: Side::new()
                .count(format!("pid-loop {t} {{N}}"))
                .time(format!("pid_closed_loop_sample/regler_{t}"), 1.0),
            anchor_name: "regler `Pid<f32>`".into(),
            anchor: Side::new()
                .count("pid-loop f32 {N}".into())
                .time("pid_closed_loop_sample/regler_f32".into(), 1.0),
        });
    }
    let largest = SCALING_SIZES[SCALING_SIZES.len() - 1];
    for size in [4096, largest] {
        rows.push(Row {
            group: format!(
                "timer tick at {} timers vs the count-down register",
                thousands(size)
            ),
            path: format!("`TimerQueue::tick`, {} timers", thousands(size)),
            regler: Side::new()
                .count(format!("scan-loop wheel {size} {{N}}"))
                .time(format!("timer_tick/regler_timer_queue/{size}"), 1.0),
            anchor_name: "count-down register".into(),
            anchor: Side::new()
                .count(format!("scan-loop count-down {size} {{N}}"))
                .time(format!("timer_tick/count_down_register/{size}"), 1.0),
        });
    }
    rows.push(Row {
        group: format!(
            "chain pulse at {} trolleys vs the count-down register",
            thousands(largest)
        ),
        path: format!("`Tracker::pulse`, {} trolleys", thousands(largest)),
        regler: Side::new()
            .count(format!("chain-pulses regler {largest} {{N}}"))
            .time(format!("chain_pulse/regler_tracker/{largest}"), 1.0),
        anchor_name: "count-down register".into(),
        anchor: Side::new()
            .count(format!("chain-pulses count-down {largest} {{N}}"))
            .time(format!("chain_pulse/count_down_register/{largest}"), 1.0),
    });
    rows.push(Row {
        group: "one full scan cycle, 544 inputs, 240 outputs".into(),
        path: "`Executive::cycle`, 544 debounced inputs, 240 outputs, forcing".into(),
        regler: Side::new()
            .count("scan-loop cycle 0 {N}".into())
            .time("full_cycle_544_in_240_out/regler_executive".into(), 1.0),
        anchor_name: "—".into(),
        anchor: Side::new(),
    });
    rows.push(Row {
        group: "trolley code `decode` vs a bit-by-bit decoder".into(),
        path: "`decode`, per word (all 8 192)".into(),
        regler: Side::new().time("decode_8192_words/regler_decode".into(), 8192.0),
        anchor_name: "bit-by-bit decoder".into(),
        anchor: Side::new().time("decode_8192_words/naive_bitwise_decode".into(), 8192.0),
    });
    for strategy in ["consecutive_k2", "majority_min3"] {
        rows.push(Row {
            group: "voter, one 5-reading passage vs a single `decode`".into(),
            path: format!("`Voter::vote`, {strategy}, one 5-reading passage"),
            regler: Side::new().time(format!("voter_passage_5_readings/{strategy}"), 1.0),
            anchor_name: "a single `decode`".into(),
            anchor: Side::new().time("voter_passage_5_readings/single_read_decode".into(), 1.0),
        });
    }
    for (which, group) in [
        ("encode", "highway_encode_1024_messages"),
        ("decode", "highway_decode_1024_messages"),
    ] {
        rows.push(Row {
            group: format!("serial-highway `{which}` vs a plain copy of the same bytes"),
            path: format!("serial-highway `{which}`, per message (1 024 mixed messages)"),
            regler: Side::new()
                .count(format!("highway-codec {which} {{N}}"))
                .count_per(messages)
                .time(format!("{group}/regler_{which}"), messages),
            anchor_name: "plain copy, message by message".into(),
            anchor: Side::new()
                .count("highway-codec copy {N}".into())
                .count_per(messages)
                .time(format!("{group}/plain_copy"), messages),
        });
    }
    rows.push(Row {
        group: "crate controller vs a one-byte delay".into(),
        path: "crate controller `clock`, per byte of the loop's traffic".into(),
        regler: Side::new()
            .count("highway-codec controller {N}".into())
            .count_per(bytes)
            .time("controller_stream/regler_controller_clock".into(), bytes),
        anchor_name: "plain copy with a one-byte delay".into(),
        anchor: Side::new()
            .count("highway-codec delay {N}".into())
            .count_per(bytes)
            .time(
                "controller_stream/plain_copy_with_one_byte_delay".into(),
                bytes,
            ),
    });
    rows
}

/// `10 000`, `4 096`, `256`: thousands apart, as the rest of the docs write them.
#[must_use]
pub fn thousands(n: u32) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, ch) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(ch);
    }
    out
}

/// Instructions to one decimal, thousands apart from 10 000 on.
fn figure(v: f64) -> String {
    let s = format!("{v:.1}");
    match s.split_once('.') {
        Some((whole, tenth)) if v.abs() >= 10_000.0 => match whole.parse::<u32>() {
            Ok(w) => format!("{}.{tenth}", thousands(w)),
            Err(_) => s,
        },
        _ => s,
    }
}

fn instr(v: Option<(f64, Option<f64>)>) -> String {
    match v {
        Some((net, Some(gross))) => format!("{} net ({} gross)", figure(net), figure(gross)),
        Some((v, None)) => figure(v),
        None => "—".into(),
    }
}

/// A time with three significant figures in ns, µs or ms.
#[must_use]
pub fn time(ns: Option<f64>) -> String {
    let Some(ns) = ns else {
        return "—".into();
    };
    let (v, unit) = if ns >= 1e6 {
        (ns / 1e6, "ms")
    } else if ns >= 1e3 {
        (ns / 1e3, "µs")
    } else {
        (ns, "ns")
    };
    let decimals = if v >= 100.0 {
        0
    } else if v >= 10.0 {
        1
    } else {
        2
    };
    format!("{v:.decimals$} {unit}")
}

/// regler / anchor: two decimals, and "N× fewer" when regler is far ahead.
#[must_use]
pub fn ratio(r: Option<f64>) -> String {
    match r {
        Some(r) if r.is_finite() && r > 0.0 && r < 0.1 => {
            format!("{r:.4}× ({:.0}× fewer)", 1.0 / r)
        }
        Some(r) if r.is_finite() => format!("{r:.2}×"),
        _ => "—".into(),
    }
}

fn div(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) if b != 0.0 => Some(a / b),
        _ => None,
    }
}

fn range(values: &[f64]) -> String {
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if values.is_empty() {
        "—".into()
    } else if ratio(Some(lo)) == ratio(Some(hi)) {
        ratio(Some(lo))
    } else {
        format!("{} – {}", ratio(Some(lo)), ratio(Some(hi)))
    }
}

/// The summary: one line per group of hot paths, regler / anchor in instructions (net where
/// the harness has a baseline) and in median time (gross), the range over the group's rows.
/// Written into `docs/PERFORMANCE.md` and between the READMEs' markers.
#[must_use]
pub fn headline(d: &Data) -> String {
    let mut groups: Vec<(String, Vec<f64>, Vec<f64>)> = Vec::new();
    for row in rows() {
        let i = div(
            row.regler.instructions(d).map(|v| v.0),
            row.anchor.instructions(d).map(|v| v.0),
        );
        let t = div(row.regler.median_ns(d), row.anchor.median_ns(d));
        if row.anchor.count.is_none() && row.anchor.time.is_none() {
            continue;
        }
        let at = match groups.iter().position(|g| g.0 == row.group) {
            Some(at) => at,
            None => {
                groups.push((row.group.clone(), Vec::new(), Vec::new()));
                groups.len() - 1
            }
        };
        if let Some(g) = groups.get_mut(at) {
            g.1.extend(i);
            g.2.extend(t);
        }
    }
    let mut s = String::from(
        "| hot path, beside its anchor | regler / anchor, instructions | regler / anchor, median time |\n|---|---|---|\n",
    );
    for (group, i, t) in groups {
        let _ = writeln!(s, "| {group} | {} | {} |", range(&i), range(&t));
    }
    s
}

fn scaling(
    s: &mut String,
    d: &Data,
    title: &str,
    unit: &str,
    sizes: &[u32],
    regler: impl Fn(u32) -> Side,
    anchor: Option<(&str, &dyn Fn(u32) -> Side)>,
) {
    let _ = writeln!(s, "### {title}\n");
    match anchor {
        Some((name, _)) => {
            let _ = writeln!(
                s,
                "| {unit} | regler, instructions | {name}, instructions | regler / {name} | regler, median | {name}, median | regler / {name}, time |\n|---|---|---|---|---|---|---|"
            );
        }
        None => {
            let _ = writeln!(s, "| {unit} | instructions | median |\n|---|---|---|");
        }
    }
    for &n in sizes {
        let r = regler(n);
        let (ri, rt) = (r.instructions(d), r.median_ns(d));
        match &anchor {
            Some((_, a)) => {
                let a = a(n);
                let (ai, at) = (a.instructions(d), a.median_ns(d));
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {} | {} |",
                    thousands(n),
                    instr(ri),
                    instr(ai),
                    ratio(div(ri.map(|v| v.0), ai.map(|v| v.0))),
                    time(rt),
                    time(at),
                    ratio(div(rt, at)),
                );
            }
            None => {
                let _ = writeln!(s, "| {} | {} | {} |", thousands(n), instr(ri), time(rt));
            }
        }
    }
    if let (Some(&first), Some(&last)) = (sizes.first(), sizes.last()) {
        let (a, b) = (regler(first), regler(last));
        let gi = div(
            b.instructions(d).map(|v| v.0),
            a.instructions(d).map(|v| v.0),
        );
        let gt = div(b.median_ns(d), a.median_ns(d));
        let f = |g: Option<f64>| g.map_or("—".into(), |g| format!("{g:.2}×"));
        let _ = writeln!(
            s,
            "\nregler's growth {} → {} {unit}: {} in instructions, {} in time.\n",
            thousands(first),
            thousands(last),
            f(gi),
            f(gt)
        );
    }
}

fn timer_scaling(s: &mut String, d: &Data) {
    scaling(
        s,
        d,
        "Timer tick, one expiry re-armed per tick",
        "timers",
        &SCALING_SIZES,
        |n| {
            Side::new()
                .count(format!("scan-loop wheel {n} {{N}}"))
                .time(format!("timer_tick/regler_timer_queue/{n}"), 1.0)
        },
        Some(("count-down", &|n| {
            Side::new()
                .count(format!("scan-loop count-down {n} {{N}}"))
                .time(format!("timer_tick/count_down_register/{n}"), 1.0)
        })),
    );
}

fn chain_scaling(s: &mut String, d: &Data) {
    scaling(
        s,
        d,
        "Chain pulse, a trolley entering every 4 pulses (40 tippers)",
        "trolleys",
        &SCALING_SIZES,
        |n| {
            Side::new()
                .count(format!("chain-pulses regler {n} {{N}}"))
                .time(format!("chain_pulse/regler_tracker/{n}"), 1.0)
        },
        Some(("count-down", &|n| {
            Side::new()
                .count(format!("chain-pulses count-down {n} {{N}}"))
                .time(format!("chain_pulse/count_down_register/{n}"), 1.0)
        })),
    );
}

fn master_scaling(s: &mut String, d: &Data) {
    scaling(
        s,
        d,
        "The master's EDF decision and one slave's report, every slave owed",
        "slaves",
        &MASTER_SLAVES,
        |n| {
            Side::new()
                .count(format!("master-decisions {n} {{N}}"))
                .time(format!("ring/scheduler decision/{n}"), 1.0)
        },
        None,
    );
}

const HEADER: &str = "# Performance

<!-- Written by `cargo run --release -p regler-benches --bin report` (`--help` for its options); do not edit by hand. -->

Each of regler's hot paths beside its **anchor** — what a user would pick instead (the `pid`
crate, `heapless::spsc`) or the source system's own method (the count-down registers) — measured
in the same run. Two measures: **instructions** counted by valgrind's callgrind on the host
(x86-64), each counter run with N and 2N operations and (total(2N) − total(N)) / N taken, so
start-up cancels (N is passed with 12 digits, so both runs' arguments have the same length and
their start-up costs the same wherever the checkout is) and the figure repeats exactly; and **median times** from criterion, which are
noisy on a shared machine and secondary. The ratio to read is regler / anchor: below 1.00× regler
is cheaper.

The anchors are configured at their best, as their own docs ask (heapless at a power-of-two
capacity; the `pid` crate with every term limited, as its examples do). The ring and the PID are
measured in two **shapes**: *firmware* (run-time configuration, state in memory, one out-of-line
call per operation, as an interrupt or a main loop calls them) and *inlined* (a constant
configuration, everything inlined into a tight loop). Both contestants run the same generic loop
with the same workload, and *net* instructions subtract the same loop run with no contestant
(`none`); times are gross. `cargo test -p regler-benches` fails when two contestants do not do the
same work. The harnesses and the anchors' configuration: `benches/README.md`.

Every instruction count below is reproduced by
`scripts/instructions-per-op N target/release/COUNTER` with the N and the counter of the table
\"Every instruction count\" (after `cargo build --release -p regler-benches --bins`). CI
re-measures the instruction counts and the on-target tables and fails when they differ from this
file, when it was written with the same compiler.
";

/// The whole file.
#[must_use]
pub fn render(d: &Data) -> String {
    let mut s = String::from(HEADER);
    s.push_str("\n## Where and when\n\n| part | machine | compiler and tools | commit | date (UTC) |\n|---|---|---|---|---|\n");
    for part in Part::ALL {
        let p = d.provenance.get(&part).cloned().unwrap_or_default();
        let dash = |v: &str| {
            if v.is_empty() {
                "—".to_string()
            } else {
                v.to_string()
            }
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} |",
            part.name(),
            dash(&p.machine),
            dash(&p.compiler),
            dash(&p.commit),
            dash(&p.date)
        );
    }
    s.push_str("\n## Summary\n\nThe range over each group's rows in the next table.\n\n");
    s.push_str(&headline(d));
    s.push_str("\n## Every hot path beside its anchor\n\nInstructions and medians per operation; regler / anchor in net instructions where there is a baseline, in gross time.\n\n| hot path | regler, instructions | regler, median | anchor | anchor, instructions | anchor, median | regler / anchor, instructions | regler / anchor, time |\n|---|---|---|---|---|---|---|---|\n");
    for row in rows() {
        let (ri, rt) = (row.regler.instructions(d), row.regler.median_ns(d));
        let (ai, at) = (row.anchor.instructions(d), row.anchor.median_ns(d));
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            row.path,
            instr(ri),
            time(rt),
            row.anchor_name,
            instr(ai),
            time(at),
            ratio(div(ri.map(|v| v.0), ai.map(|v| v.0))),
            ratio(div(rt, at)),
        );
    }
    s.push_str("\n## Scaling\n\nOne operation at each size, regler beside the source's method where there is one.\n\n");
    timer_scaling(&mut s, d);
    chain_scaling(&mut s, d);
    master_scaling(&mut s, d);
    s.push_str(COST_STATEMENTS_INTRO);
    s.push_str("| crate | statement | measured | bound | holds |\n|---|---|---|---|---|\n");
    for c in cost_statements(d) {
        let _ = writeln!(
            s,
            "| `regler-{}` | {} | {} | {} | {} |",
            c.krate,
            c.statement,
            c.measured_text(),
            c.bound_text(),
            if c.holds() { "yes" } else { "**no**" }
        );
    }
    s.push('\n');
    s.push_str("## On the core\n\nInstructions per call counted by QEMU (`on-target/cycles`; the method is in `docs/FOOTPRINT.md`), one table per core, as that script writes them.\n\n");
    s.push_str(ON_TARGET_BEGIN);
    s.push('\n');
    for line in &d.on_target {
        s.push_str(line);
        s.push('\n');
    }
    s.push_str(ON_TARGET_END);
    s.push_str("\n\n## Every instruction count\n\n| counter (`target/release/…`) | N | instructions per operation |\n|---|---|---|\n");
    for (key, c) in &d.counts {
        let _ = writeln!(s, "| `{key}` | {} | {} |", c.n, c.per_op);
    }
    s.push_str("\n## Every median time\n\nCriterion's median per iteration (`target/criterion`'s `median.point_estimate`), in ns.\n\n| criterion benchmark | median, ns per iteration |\n|---|---|\n");
    for (id, ns) in &d.medians {
        let _ = writeln!(s, "| `{id}` | {ns:.1} |");
    }
    s
}

const COST_STATEMENTS_INTRO: &str = "## Cost statements, checked

Each cost sentence of a crate README that the figures above can assert, as that README's block
prints it, with the figure it bounds. The report fails (exit status 1) when one does not hold:
when it writes this file and when CI checks it (`--check`), where the counts are re-measured.

";

/// The on-target tables' operations the crate blocks and the cost statements read.
mod op {
    pub const PID_F32_ALONE: &str = "Pid<f32>::update alone (its row less the f32 plant, one call)";
    pub const PID_FIXED_ALONE: &str =
        "Pid<I16F16>::update alone (its row less the I16F16 plant, one call)";
    pub const PID_CRATE_CALL: &str =
        "pid crate Pid<f32>::next_control_output + plant, one call per sample";
    pub const PLANT_CALL: &str = "plant alone, one call per sample";
    pub const PID_LOOP: &str = "regler Pid<f32>::update + plant";
    pub const PID_CRATE_LOOP: &str = "pid crate Pid<f32>::next_control_output + plant";
    pub const PLANT_LOOP: &str = "plant alone";
    pub const DECODE: &str = "decode";
    pub const CLOCK: &str = "highway Controller::clock, one byte of mixed traffic";
    pub const TICK: &str = "TimerQueue<u16, 256>::tick, one expiry re-armed per tick";
    pub const PULSE: &str = "Tracker<u16, 256, 8>::pulse, a trolley entering every 4 pulses";
}

/// The cores of the on-target tables: the target in their header and the name to print.
const CORES: [(&str, &str); 2] = [
    ("thumbv7em", "Cortex-M4F (thumbv7em)"),
    ("thumbv6m", "Cortex-M0 (thumbv6m)"),
];

/// The cores' names where `f32` matters.
fn float_core(core: &str) -> &'static str {
    if core == "thumbv6m" {
        "Cortex-M0 (thumbv6m, `f32` in soft float)"
    } else {
        "Cortex-M4F (thumbv7em, `f32` on the FPU)"
    }
}

/// The figure of the row `operation` in the on-target table of `core` (`thumbv7em`,
/// `thumbv6m`).
fn on_core(d: &Data, core: &str, operation: &str) -> Option<f64> {
    let mut in_core = false;
    for line in d
        .on_target
        .iter()
        .filter(|l| l.trim_start().starts_with('|'))
    {
        if line.contains("instructions per call on") {
            in_core = line.contains(core);
            continue;
        }
        let c = cells(line);
        if in_core && c.first().map(String::as_str) == Some(operation) {
            return c.get(1)?.trim_end_matches('×').trim().parse().ok();
        }
    }
    None
}

fn minus(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    Some(a? - b?)
}

/// A cost sentence of a crate README, asserted from figures that repeat exactly (callgrind's
/// and QEMU's instruction counts), never from times.
#[derive(Clone, Debug, PartialEq)]
pub struct CostStatement {
    /// The crate whose README states it (its directory).
    pub krate: &'static str,
    /// The statement, as the README's block and `docs/PERFORMANCE.md` print it.
    pub statement: String,
    /// The figure it bounds (a ratio, or instructions); `None` when a count is missing.
    pub measured: Option<f64>,
    /// The largest figure for which it holds.
    pub bound: f64,
    /// `×` for a ratio, ` instructions` for a count.
    pub unit: &'static str,
}

impl CostStatement {
    /// Whether the figure was measured and is within the bound.
    #[must_use]
    pub fn holds(&self) -> bool {
        self.measured.is_some_and(|m| m <= self.bound)
    }

    fn measured_text(&self) -> String {
        match self.measured {
            Some(m) if self.unit == "×" => format!("{m:.2}×"),
            Some(m) => format!("{}{}", figure(m), self.unit),
            None => "not measured".into(),
        }
    }

    fn bound_text(&self) -> String {
        if self.unit == "×" {
            format!("≤ {:.2}×", self.bound)
        } else {
            format!("≤ {}{}", figure(self.bound), self.unit)
        }
    }
}

/// The most over the fewest instructions among `keys`; `None` when one is missing.
fn spread(d: &Data, keys: impl IntoIterator<Item = String>) -> Option<f64> {
    let v: Vec<f64> = keys
        .into_iter()
        .map(|k| d.count(&k))
        .collect::<Option<_>>()?;
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    div(Some(hi), Some(lo)).filter(|_| lo > 0.0)
}

/// The serial-highway decoder's instructions per byte over the workload's messages of the
/// shortest (`longest` false) or the longest encoded length.
fn decode_per_byte(d: &Data, longest: bool) -> Option<f64> {
    let which = if longest { "longest" } else { "shortest" };
    let (bytes, _) = encoded(&of_extreme_length(longest));
    div(
        d.count(&format!("highway-codec decode-{which} {{N}}")),
        Some(bytes.len() as f64),
    )
}

fn pid_net(d: &Data, who: &str, shape: &str, load: &str) -> Option<f64> {
    Side::new()
        .count(format!("pid-shapes {who} {shape} {load} {{N}}"))
        .net_of(format!("pid-shapes none {shape} {load} {{N}}"))
        .instructions(d)
        .map(|v| v.0)
}

/// Every cost statement the crate READMEs make that the counts can check.
#[must_use]
pub fn cost_statements(d: &Data) -> Vec<CostStatement> {
    let mut out = Vec::new();
    let mut put = |krate, statement: String, measured, bound, unit| {
        out.push(CostStatement {
            krate,
            statement,
            measured,
            bound,
            unit,
        });
    };
    for shape in SHAPES {
        let worst = PID_WORKLOADS
            .iter()
            .map(|load| {
                div(
                    pid_net(d, "regler", shape, load),
                    pid_net(d, "pid-crate", shape, load),
                )
            })
            .collect::<Option<Vec<f64>>>()
            .map(|v| v.into_iter().fold(f64::NEG_INFINITY, f64::max));
        put(
            "pid",
            format!(
                "`Pid<f32>::update` with every feature on costs no more instructions than the `pid` crate's update in the {shape} shape, on each of the four workloads (x86-64, net)"
            ),
            worst,
            1.0,
            "×",
        );
    }
    let m4 = |o| on_core(d, "thumbv7em", o);
    let m0 = |o| on_core(d, "thumbv6m", o);
    put(
        "pid",
        "on a Cortex-M4F, one call per sample, `Pid<f32>::update` costs no more instructions than the `pid` crate's update".into(),
        div(m4(op::PID_F32_ALONE), minus(m4(op::PID_CRATE_CALL), m4(op::PLANT_CALL))),
        1.0,
        "×",
    );
    put(
        "pid",
        "on a Cortex-M0 (no FPU) `Pid<I16F16>::update` costs at most 0.30× the instructions of a soft-float `Pid<f32>::update`".into(),
        div(m0(op::PID_FIXED_ALONE), m0(op::PID_F32_ALONE)),
        0.3,
        "×",
    );
    let (first, rest) = MASTER_SLAVES.split_first().unwrap_or((&8, &[]));
    for &slaves in rest {
        let bound = f64::from(slaves).log2() / f64::from(*first).log2();
        put(
            "ring-transfer",
            format!(
                "the master's EDF decision with one slave's report grows as O(log S): at {slaves} slaves at most log₂ {slaves} / log₂ {first} = {bound:.2}× its instructions at {first} slaves"
            ),
            div(
                d.count(&format!("master-decisions {slaves} {{N}}")),
                d.count(&format!("master-decisions {first} {{N}}")),
            ),
            bound,
            "×",
        );
    }
    let sizes = || SCALING_SIZES.iter().map(|&n| thousands(n));
    let (fewest, most) = (
        sizes().next().unwrap_or_default(),
        sizes().next_back().unwrap_or_default(),
    );
    put(
        "scan-cycle",
        format!(
            "`TimerQueue::tick` is O(1): from {fewest} to {most} timers its instructions per tick (one expiry re-armed per tick) differ by at most 1.50× (the most over the fewest)"
        ),
        spread(
            d,
            SCALING_SIZES
                .iter()
                .map(|n| format!("scan-loop wheel {n} {{N}}")),
        ),
        1.5,
        "×",
    );
    put(
        "chain-tracker",
        format!(
            "`Tracker::pulse` is O(1) whatever the number of trolleys: from {fewest} to {most} trolleys its instructions per pulse differ by at most 1.50× (the most over the fewest)"
        ),
        spread(
            d,
            SCALING_SIZES
                .iter()
                .map(|n| format!("chain-pulses regler {n} {{N}}")),
        ),
        1.5,
        "×",
    );
    put(
        "trolley-id",
        "`decode` of a 13-cam word takes at most 40 instructions per call on a Cortex-M4F and on a Cortex-M0".into(),
        m4(op::DECODE).zip(m0(op::DECODE)).map(|(a, b)| a.max(b)),
        40.0,
        " instructions",
    );
    put(
        "panel-link",
        "`highway::decode` is O(1) per byte: per byte, the workload's longest messages cost no more than its shortest".into(),
        div(decode_per_byte(d, true), decode_per_byte(d, false)),
        1.0,
        "×",
    );
    out
}

/// The statements of one crate as the lines of a list.
fn statements_of(d: &Data, krate: &str) -> String {
    let mut s = String::from(
        "Checked from these counts on every run of the report and in CI (`cost_statements` in `benches/src/report.rs`; the run fails when one does not hold):\n\n",
    );
    for c in cost_statements(d).into_iter().filter(|c| c.krate == krate) {
        let _ = writeln!(
            s,
            "- {}: {} measured ({}){}.",
            c.statement,
            c.measured_text(),
            c.bound_text(),
            if c.holds() {
                ""
            } else {
                " — **does not hold**"
            }
        );
    }
    s
}

fn net(d: &Data, key: &str, base: &str) -> Option<f64> {
    minus(d.count(key), d.count(base))
}

fn pid_block(d: &Data) -> String {
    let mut s = String::from(
        "Instructions per sample on x86-64 (callgrind), the loop's own cost subtracted, `Pid<f32>::update` with every feature on beside the `pid` crate 4 on the same loop, plant and workload:\n\n| workload | firmware: regler | firmware: `pid` crate | regler / `pid` crate | inlined: regler | inlined: `pid` crate | regler / `pid` crate |\n|---|---|---|---|---|---|---|\n",
    );
    for load in PID_WORKLOADS {
        let _ = write!(s, "| {load} |");
        for shape in SHAPES {
            let (r, p) = (
                pid_net(d, "regler", shape, load),
                pid_net(d, "pid-crate", shape, load),
            );
            let _ = write!(
                s,
                " {} | {} | {} |",
                instr(r.map(|v| (v, None))),
                instr(p.map(|v| (v, None))),
                ratio(div(r, p))
            );
        }
        s.push('\n');
    }
    s.push_str("\nOn the cores (QEMU, `on-target/cycles`), the plant's own row subtracted: one call per sample (the firmware shape), and in the firmware's measuring loop, where LLVM's size heuristics (opt-level \"s\") decide what is inlined:\n\n| core | one call: regler | one call: `pid` crate | regler / `pid` crate | loop: regler | loop: `pid` crate | regler / `pid` crate |\n|---|---|---|---|---|---|---|\n");
    for (core, _) in CORES {
        let name = float_core(core);
        let g = |o| on_core(d, core, o);
        let (rc, pc) = (
            g(op::PID_F32_ALONE),
            minus(g(op::PID_CRATE_CALL), g(op::PLANT_CALL)),
        );
        let (rl, pl) = (
            minus(g(op::PID_LOOP), g(op::PLANT_LOOP)),
            minus(g(op::PID_CRATE_LOOP), g(op::PLANT_LOOP)),
        );
        let f = |v: Option<f64>| instr(v.map(|v| (v, None)));
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {} | {} | {} | {} |",
            f(rc),
            f(pc),
            ratio(div(rc, pc)),
            f(rl),
            f(pl),
            ratio(div(rl, pl))
        );
    }
    s.push_str("\nFixed point beside `f32`: instructions per closed-loop sample on x86-64 (controller and the same plant step in the same type, `benches/src/pid_loop.rs`), and one update on the cores, called out of line once per sample, its plant's row subtracted:\n\n| type | closed-loop sample, x86-64 | / `f32` |\n|---|---|---|\n");
    let f32_loop = d.count("pid-loop f32 {N}");
    for (t, name) in [
        ("f32", "`f32`"),
        ("f64", "`f64`"),
        ("i16f16", "`I16F16`"),
        ("i32f32", "`I32F32`"),
    ] {
        let v = d.count(&format!("pid-loop {t} {{N}}"));
        let _ = writeln!(
            s,
            "| {name} | {} | {} |",
            instr(v.map(|v| (v, None))),
            ratio(div(v, f32_loop))
        );
    }
    s.push_str("\n| core | `Pid<f32>::update` | `Pid<I16F16>::update` | `I16F16` / `f32` |\n|---|---|---|---|\n");
    for (core, _) in CORES {
        let name = float_core(core);
        let (f, x) = (
            on_core(d, core, op::PID_F32_ALONE),
            on_core(d, core, op::PID_FIXED_ALONE),
        );
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {} |",
            instr(f.map(|v| (v, None))),
            instr(x.map(|v| (v, None))),
            ratio(div(x, f))
        );
    }
    s.push('\n');
    s.push_str(&statements_of(d, "pid"));
    s
}

fn ring_block(d: &Data) -> String {
    let mut s = String::from(
        "Instructions per `receive` + `next` pair on a half-full ring of bytes, x86-64 (callgrind), the loop's own cost subtracted; firmware: each operation an out-of-line call, state in memory; inlined: a tight loop owning the ring:\n\n| contestant | firmware | inlined |\n|---|---|---|\n",
    );
    let pair = |who: &str, shape: &str| {
        net(
            d,
            &format!("ring-pairs {who} {shape} {{N}}"),
            &format!("ring-pairs none {shape} {{N}}"),
        )
    };
    let contestants = [
        ("ring", "`Ring<u8, 256>`, statistics on (holds 256)"),
        ("spsc", "heapless `Queue<u8, 256>` (holds 255)"),
        (
            "spsc-257",
            "heapless `Queue<u8, 257>` (holds 256; modulo indices)",
        ),
        ("array", "a plain array ring (holds 256)"),
        (
            "split",
            "`Filler` + `Drainer`, `SharedRing<u8, 256>` (holds 256)",
        ),
        (
            "spsc-split",
            "heapless `Producer` + `Consumer`, `Queue<u8, 256>`",
        ),
    ];
    for (who, name) in contestants {
        let f = |shape| instr(pair(who, shape).map(|v| (v, None)));
        let _ = writeln!(s, "| {name} | {} | {} |", f("firmware"), f("inlined"));
    }
    s.push_str("\n| ratio | firmware | inlined |\n|---|---|---|\n");
    for (who, anchor, name) in [
        ("ring", "spsc", "`Ring<u8, 256>` / `Queue<u8, 256>`"),
        ("ring", "spsc-257", "`Ring<u8, 256>` / `Queue<u8, 257>`"),
        (
            "split",
            "spsc-split",
            "`Filler` + `Drainer` / `Producer` + `Consumer`",
        ),
    ] {
        let f = |shape| ratio(div(pair(who, shape), pair(anchor, shape)));
        let _ = writeln!(s, "| {name} | {} | {} |", f("firmware"), f("inlined"));
    }
    s.push('\n');
    master_scaling(&mut s, d);
    s.push_str(&statements_of(d, "ring-transfer"));
    s
}

fn scan_block(d: &Data) -> String {
    let mut s = String::new();
    timer_scaling(&mut s, d);
    let _ = writeln!(
        s,
        "One full cycle at the 1977 plant's sizes (544 debounced inputs, 240 outputs, forcing): {} instructions on x86-64. On a Cortex-M4F a `TimerQueue<u16, 256>::tick` takes {} instructions (QEMU).\n",
        instr(d.count("scan-loop cycle 0 {N}").map(|v| (v, None))),
        instr(on_core(d, "thumbv7em", op::TICK).map(|v| (v, None)))
    );
    s.push_str(&statements_of(d, "scan-cycle"));
    s
}

fn chain_block(d: &Data) -> String {
    let mut s = String::new();
    chain_scaling(&mut s, d);
    let _ = writeln!(
        s,
        "On a Cortex-M4F a `Tracker<u16, 256, 8>::pulse` takes {} instructions (QEMU).\n",
        instr(on_core(d, "thumbv7em", op::PULSE).map(|v| (v, None)))
    );
    s.push_str(&statements_of(d, "chain-tracker"));
    s
}

fn trolley_block(d: &Data) -> String {
    let mut s = String::from("| `decode`, per call | instructions (QEMU) |\n|---|---|\n");
    for (core, name) in CORES {
        let _ = writeln!(
            s,
            "| {name} | {} |",
            instr(on_core(d, core, op::DECODE).map(|v| (v, None)))
        );
    }
    s.push('\n');
    s.push_str(&statements_of(d, "trolley-id"));
    s
}

fn panel_block(d: &Data) -> String {
    let mut s = String::from(
        "| x86-64 (callgrind) | regler, instructions | anchor | anchor, instructions | regler / anchor |\n|---|---|---|---|---|\n",
    );
    for row in rows()
        .into_iter()
        .filter(|r| r.path.contains("serial-highway") || r.path.contains("controller"))
    {
        let (ri, ai) = (row.regler.instructions(d), row.anchor.instructions(d));
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} |",
            row.path,
            instr(ri),
            row.anchor_name,
            instr(ai),
            ratio(div(ri.map(|v| v.0), ai.map(|v| v.0)))
        );
    }
    let per_byte = |longest| decode_per_byte(d, longest).map(|v| (v, None));
    let length = |longest| {
        let messages = of_extreme_length(longest);
        encoded(&messages).0.len() / messages.len().max(1)
    };
    let _ = writeln!(
        s,
        "\n`highway::decode` per byte: {} instructions over the workload's shortest messages ({} bytes), {} over its longest ({} bytes). The crate controller's `clock`, one byte of mixed traffic, on the cores (QEMU): {} instructions on a Cortex-M4F, {} on a Cortex-M0.\n",
        instr(per_byte(false)),
        length(false),
        instr(per_byte(true)),
        length(true),
        instr(on_core(d, "thumbv7em", op::CLOCK).map(|v| (v, None))),
        instr(on_core(d, "thumbv6m", op::CLOCK).map(|v| (v, None))),
    );
    s.push_str(&statements_of(d, "panel-link"));
    s
}

/// Writes a crate README's block from the figures.
type BlockWriter = fn(&Data) -> String;

/// A block the report writes into a README, between its markers.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadmeBlock {
    /// The README, from the workspace's root.
    pub file: &'static str,
    /// Its begin marker.
    pub begin: String,
    /// Its end marker.
    pub end: String,
    /// What goes between them.
    pub text: String,
}

/// Every README block, written from `d`: the summary in the workspace README and
/// `benches/README.md`, and each crate's own figures and checked cost statements in its README.
#[must_use]
pub fn readme_blocks(d: &Data) -> Vec<ReadmeBlock> {
    let summary = headline(d);
    let mut blocks: Vec<ReadmeBlock> = ["README.md", "benches/README.md"]
        .into_iter()
        .map(|file| ReadmeBlock {
            file,
            begin: README_BEGIN.into(),
            end: README_END.into(),
            text: summary.clone(),
        })
        .collect();
    let crates: [(&str, &'static str, BlockWriter); 6] = [
        ("pid", "pid/README.md", pid_block),
        ("ring-transfer", "ring-transfer/README.md", ring_block),
        ("scan-cycle", "scan-cycle/README.md", scan_block),
        ("chain-tracker", "chain-tracker/README.md", chain_block),
        ("trolley-id", "trolley-id/README.md", trolley_block),
        ("panel-link", "panel-link/README.md", panel_block),
    ];
    for (name, file, block) in crates {
        blocks.push(ReadmeBlock {
            file,
            begin: crate_begin(name),
            end: crate_end(name),
            text: block(d),
        });
    }
    blocks
}

fn cells(line: &str) -> Vec<String> {
    line.trim()
        .trim_start_matches('|')
        .trim_end_matches('|')
        .split('|')
        .map(|c| c.trim().trim_matches('`').to_string())
        .collect()
}

/// The rows of the table under `heading` (without its header and separator lines).
fn table_under<'a>(text: &'a str, heading: &str) -> Vec<&'a str> {
    let mut lines = text.lines().skip_while(|l| l.trim() != heading).skip(1);
    let mut rows = Vec::new();
    let mut in_table = false;
    for line in lines.by_ref() {
        if line.starts_with('|') {
            in_table = true;
            rows.push(line);
        } else if in_table || line.starts_with('#') {
            break;
        }
    }
    rows.into_iter().skip(2).collect()
}

/// Reads back the data of a file `render` wrote; what is missing stays empty.
#[must_use]
pub fn parse(text: &str) -> Data {
    let mut d = Data::default();
    for row in table_under(text, "## Where and when") {
        let c = cells(row);
        let (Some(part), Some(machine), Some(compiler), Some(commit), Some(date)) = (
            c.first().and_then(|p| Part::parse(p)),
            c.get(1),
            c.get(2),
            c.get(3),
            c.get(4),
        ) else {
            continue;
        };
        let v = |s: &String| if s == "—" { String::new() } else { s.clone() };
        if machine != "—" || commit != "—" {
            d.provenance.insert(
                part,
                Provenance {
                    machine: v(machine),
                    compiler: v(compiler),
                    commit: v(commit),
                    date: v(date),
                },
            );
        }
    }
    for row in table_under(text, "## Every instruction count") {
        let c = cells(row);
        if let (Some(key), Some(Ok(n)), Some(per_op)) =
            (c.first(), c.get(1).map(|n| n.parse()), c.get(2))
        {
            d.counts.push((
                key.clone(),
                Count {
                    n,
                    per_op: per_op.clone(),
                },
            ));
        }
    }
    for row in table_under(text, "## Every median time") {
        let c = cells(row);
        if let (Some(id), Some(Ok(ns))) = (c.first(), c.get(1).map(|v| v.parse())) {
            d.medians.insert(id.clone(), ns);
        }
    }
    d.on_target = text
        .lines()
        .skip_while(|l| l.trim() != ON_TARGET_BEGIN)
        .skip(1)
        .take_while(|l| l.trim() != ON_TARGET_END)
        .map(str::to_string)
        .collect();
    d
}

/// The markdown tables of a text whose header mentions instructions (`on-target/cycles`' output,
/// or the section of `docs/FOOTPRINT.md` it wrote), a blank line between tables, and any heading
/// line right above a table kept with it. Tables of other things (flash, stack) are left out.
#[must_use]
pub fn on_target_tables(text: &str) -> Vec<String> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out: Vec<String> = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let starts = lines
            .get(i)
            .is_some_and(|l| l.trim_start().starts_with('|'))
            && (i == 0
                || !lines
                    .get(i - 1)
                    .is_some_and(|l| l.trim_start().starts_with('|')));
        if !starts {
            i += 1;
            continue;
        }
        let end = (i..lines.len())
            .find(|&j| {
                !lines
                    .get(j)
                    .is_some_and(|l| l.trim_start().starts_with('|'))
            })
            .unwrap_or(lines.len());
        let header = lines.get(i).copied().unwrap_or("");
        if header.to_lowercase().contains("instructions") {
            if !out.is_empty() {
                out.push(String::new());
            }
            // A heading just above the table (a blank line between allowed) names the core.
            let above = (i >= 2)
                .then(|| lines.get(i - 2))
                .flatten()
                .filter(|l| {
                    l.starts_with('#') && lines.get(i - 1).is_some_and(|b| b.trim().is_empty())
                })
                .or_else(|| {
                    (i >= 1)
                        .then(|| lines.get(i - 1))
                        .flatten()
                        .filter(|l| l.starts_with('#'))
                });
            if let Some(h) = above {
                out.push(h.to_string());
                out.push(String::new());
            }
            out.extend(
                lines
                    .get(i..end)
                    .unwrap_or(&[])
                    .iter()
                    .map(|l| l.trim_end().to_string()),
            );
        }
        i = end;
    }
    out
}

/// Replaces what lies between the markers `begin` and `end` in `readme` with `block`; `None`
/// when the markers are not both there, in that order, once each.
#[must_use]
pub fn replace_block(readme: &str, begin: &str, end: &str, block: &str) -> Option<String> {
    let at = readme.find(begin)?;
    let after = at + begin.len();
    let to = after + readme.get(after..)?.find(end)?;
    let once = |m: &str| readme.matches(m).count() == 1;
    if !once(begin) || !once(end) {
        return None;
    }
    Some(format!(
        "{}{begin}\n{block}{}",
        readme.get(..at)?,
        readme.get(to..)?
    ))
}

/// The differences between the committed data and a fresh measurement of the parts that
/// repeat exactly: one line per figure that differs, is missing or is new.
#[must_use]
pub fn differences(committed: &Data, fresh: &Data, parts: &[Part]) -> Vec<String> {
    let mut out = Vec::new();
    if parts.contains(&Part::Instructions) {
        let old: BTreeMap<_, _> = committed.counts.iter().cloned().collect();
        let new: BTreeMap<_, _> = fresh.counts.iter().cloned().collect();
        for (key, c) in &new {
            match old.get(key) {
                None => out.push(format!(
                    "`{key}`: new counter, {} (not in the file)",
                    c.per_op
                )),
                Some(o) if o != c => out.push(format!(
                    "`{key}`: the file says {} at N = {}, measured {} at N = {}",
                    o.per_op, o.n, c.per_op, c.n
                )),
                Some(_) => {}
            }
        }
        for key in old.keys().filter(|k| !new.contains_key(*k)) {
            out.push(format!("`{key}`: in the file, no longer measured"));
        }
    }
    if parts.contains(&Part::OnTarget) && committed.on_target != fresh.on_target {
        let old: Vec<_> = committed
            .on_target
            .iter()
            .filter(|l| !fresh.on_target.contains(l))
            .collect();
        let new: Vec<_> = fresh
            .on_target
            .iter()
            .filter(|l| !committed.on_target.contains(l))
            .collect();
        out.push(format!(
            "on-target tables differ: the file has {old:?}, measured {new:?}"
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Data {
        let mut d = Data::default();
        d.provenance.insert(
            Part::Instructions,
            Provenance {
                machine: "x86_64 test CPU, 2 cores, Debian".into(),
                compiler: "rustc 1.95.0, valgrind-3.19.0".into(),
                commit: "abc1234".into(),
                date: "2026-11-24".into(),
            },
        );
        for (i, c) in counters().into_iter().enumerate() {
            d.counts.push((
                c.key(),
                Count {
                    n: c.n,
                    per_op: format!("{}.{}", 10 + i, i % 10),
                },
            ));
        }
        d.medians.insert(
            "pid_shape_steps_firmware_1000_samples/regler_f32".into(),
            14_700.0,
        );
        d.medians.insert(
            "pid_shape_steps_firmware_1000_samples/pid_crate_f32".into(),
            24_100.5,
        );
        d.on_target = vec![
            "| operation | instructions per call on thumbv7em |".into(),
            "|---|---|".into(),
            "| decode | 23.1 |".into(),
        ];
        d
    }

    #[test]
    fn what_render_writes_parse_reads_back() {
        let d = sample();
        let text = render(&d);
        assert_eq!(parse(&text), d);
        assert_eq!(render(&parse(&text)), text);
    }

    #[test]
    fn a_changed_count_is_a_difference_and_an_equal_one_is_not() {
        let d = sample();
        assert!(differences(&d, &d, &Part::ALL).is_empty());
        let mut fresh = d.clone();
        fresh.counts[3].1.per_op = "99.9".into();
        fresh.on_target[2] = "| decode | 23.2 |".into();
        let diff = differences(&d, &fresh, &Part::ALL);
        assert_eq!(diff.len(), 2, "{diff:?}");
        assert!(diff[0].contains("99.9"));
        // Only the parts asked for are compared.
        assert_eq!(differences(&d, &fresh, &[Part::OnTarget]).len(), 1);
        let mut fewer = d.clone();
        fewer.counts.pop();
        assert_eq!(differences(&d, &fewer, &[Part::Instructions]).len(), 1);
        assert_eq!(differences(&fewer, &d, &[Part::Instructions]).len(), 1);
    }

    #[test]
    fn on_target_tables_keep_every_core_and_leave_out_other_tables() {
        let footprint = "# Footprint\n\n| firmware | .text |\n|---|---|\n| pid | 1 |\n\n## Instructions per call on the core\n\ntext\n\n| operation | instructions per call on thumbv7em |\n|---|---|\n| decode | 23.1 |\n\n### Cortex-M0 (thumbv6m)\n\n| operation | instructions per call on thumbv6m |\n|---|---|\n| decode | 30.0 |\n";
        assert_eq!(
            on_target_tables(footprint),
            [
                "| operation | instructions per call on thumbv7em |",
                "|---|---|",
                "| decode | 23.1 |",
                "",
                "### Cortex-M0 (thumbv6m)",
                "",
                "| operation | instructions per call on thumbv6m |",
                "|---|---|",
                "| decode | 30.0 |",
            ]
        );
    }

    #[test]
    fn ratios_and_the_summary_come_from_the_counts() {
        let mut d = Data::default();
        let put = |d: &mut Data, key: &str, v: &str| {
            d.counts.push((
                key.into(),
                Count {
                    n: 1,
                    per_op: v.into(),
                },
            ));
        };
        for load in PID_WORKLOADS {
            put(
                &mut d,
                &format!("pid-shapes regler firmware {load} {{N}}"),
                "79.0",
            );
            put(
                &mut d,
                &format!("pid-shapes pid-crate firmware {load} {{N}}"),
                "106.0",
            );
            put(
                &mut d,
                &format!("pid-shapes none firmware {load} {{N}}"),
                "18.0",
            );
        }
        put(&mut d, "scan-loop wheel 4096 {N}", "200.0");
        put(&mut d, "scan-loop count-down 4096 {N}", "20000.0");
        let h = headline(&d);
        // (79 − 18) / (106 − 18) = 0.693…
        assert!(
            h.contains("firmware shape (4 workloads) | 0.69× | — |"),
            "{h}"
        );
        assert!(
            h.contains("4 096 timers vs the count-down register | 0.0100× (100× fewer) |"),
            "{h}"
        );
        assert!(h.contains("inlined shape (4 workloads) | — | — |"), "{h}");
    }

    #[test]
    fn the_readme_block_is_replaced_between_its_markers_only() {
        let readme = format!("a\n{README_BEGIN}\nold\n{README_END}\nb\n");
        assert_eq!(
            replace_block(&readme, README_BEGIN, README_END, "new\n"),
            Some(format!("a\n{README_BEGIN}\nnew\n{README_END}\nb\n"))
        );
        assert_eq!(
            replace_block("no markers", README_BEGIN, README_END, "new\n"),
            None
        );
        // A crate's block beside the summary's: each replaced between its own markers only.
        let (pb, pe) = (crate_begin("pid"), crate_end("pid"));
        let both = format!("a\n{README_BEGIN}\nold\n{README_END}\nb\n{pb}\nold pid\n{pe}\nc\n");
        assert_eq!(
            replace_block(&both, &pb, &pe, "new pid\n"),
            Some(format!(
                "a\n{README_BEGIN}\nold\n{README_END}\nb\n{pb}\nnew pid\n{pe}\nc\n"
            ))
        );
        assert_eq!(
            replace_block(&both, README_BEGIN, README_END, "new\n"),
            Some(format!(
                "a\n{README_BEGIN}\nnew\n{README_END}\nb\n{pb}\nold pid\n{pe}\nc\n"
            ))
        );
        // Another crate's markers are not this crate's; a marker twice or out of order is refused.
        assert_eq!(
            replace_block(&both, &crate_begin("pi"), &crate_end("pi"), "x"),
            None
        );
        let twice = format!("{pb}\n{pe}\n{pb}\n{pe}\n");
        assert_eq!(replace_block(&twice, &pb, &pe, "x"), None);
        assert_eq!(replace_block(&format!("{pe}\n{pb}\n"), &pb, &pe, "x"), None);
    }

    fn workspace_file(path: &str) -> String {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .parent()
            .map(std::path::Path::to_path_buf)
            .unwrap_or_default();
        std::fs::read_to_string(root.join(path)).unwrap_or_else(|e| panic!("{path}: {e}"))
    }

    #[test]
    fn every_readme_block_is_present_and_is_what_the_report_writes() {
        let committed = parse(&workspace_file("docs/PERFORMANCE.md"));
        let blocks = readme_blocks(&committed);
        for name in [
            "pid",
            "ring-transfer",
            "scan-cycle",
            "chain-tracker",
            "trolley-id",
            "panel-link",
        ] {
            assert!(
                blocks.iter().any(|b| b.file == format!("{name}/README.md")),
                "no block for {name}"
            );
        }
        for b in blocks {
            let text = workspace_file(b.file);
            let replaced = replace_block(&text, &b.begin, &b.end, &b.text);
            assert!(
                replaced.is_some(),
                "{} lacks the markers {}",
                b.file,
                b.begin
            );
            assert!(
                replaced.as_deref() == Some(text.as_str()),
                "{}'s block is stale: run `cargo run --release -p regler-benches --bin report -- --only instructions --on-target-from docs/FOOTPRINT.md`",
                b.file
            );
        }
    }

    #[test]
    fn cost_statements_hold_on_the_committed_figures() {
        let committed = parse(&workspace_file("docs/PERFORMANCE.md"));
        let statements = cost_statements(&committed);
        for krate in [
            "pid",
            "ring-transfer",
            "scan-cycle",
            "chain-tracker",
            "trolley-id",
            "panel-link",
        ] {
            assert!(statements.iter().any(|c| c.krate == krate), "{krate}");
        }
        for c in statements {
            assert!(c.holds(), "{c:?}");
        }
    }

    #[test]
    fn a_cost_statement_fails_when_its_figure_grows_past_the_bound_or_is_missing() {
        let committed = parse(&workspace_file("docs/PERFORMANCE.md"));
        let holds = |d: &Data, krate: &str, what: &str| {
            cost_statements(d)
                .into_iter()
                .filter(|c| c.krate == krate && c.statement.contains(what))
                .all(|c| c.holds())
        };
        let set = |d: &mut Data, key: &str, per_op: String| {
            if let Some((_, c)) = d.counts.iter_mut().find(|(k, _)| k == key) {
                c.per_op = per_op;
            }
        };
        // A tick that became O(N): 16 → 10 000 timers 10× the instructions.
        let mut d = committed.clone();
        let few = d.count("scan-loop wheel 16 {N}").unwrap_or(0.0);
        set(
            &mut d,
            "scan-loop wheel 10000 {N}",
            format!("{:.1}", few * 10.0),
        );
        assert!(holds(&committed, "scan-cycle", "TimerQueue"));
        assert!(!holds(&d, "scan-cycle", "TimerQueue"));
        // A pulse that grows linearly with the trolleys.
        let mut d = committed.clone();
        let few = d.count("chain-pulses regler 16 {N}").unwrap_or(0.0);
        set(
            &mut d,
            "chain-pulses regler 4096 {N}",
            format!("{:.1}", few * 2.0),
        );
        assert!(!holds(&d, "chain-tracker", "pulse"));
        // An EDF decision linear in the slaves: 500 / 8 = 62.5×.
        let mut d = committed.clone();
        let few = d.count("master-decisions 8 {N}").unwrap_or(0.0);
        set(
            &mut d,
            "master-decisions 500 {N}",
            format!("{:.1}", few * 62.5),
        );
        assert!(!holds(&d, "ring-transfer", "EDF"));
        // A regler update dearer than the `pid` crate's in one workload.
        let mut d = committed.clone();
        set(
            &mut d,
            "pid-shapes regler inlined noise {N}",
            "999.0".into(),
        );
        assert!(holds(&d, "pid", "firmware shape"));
        assert!(!holds(&d, "pid", "inlined shape"));
        // A decoder whose cost per byte grows with the message (0.60× → 1.20×).
        let mut d = committed.clone();
        let long = d.count("highway-codec decode-longest {N}").unwrap_or(0.0);
        set(
            &mut d,
            "highway-codec decode-longest {N}",
            format!("{:.1}", long * 2.0),
        );
        assert!(!holds(&d, "panel-link", "per byte"));
        // On the cores: a slower decode, a fixed-point update no cheaper than soft float.
        let mut d = committed.clone();
        for line in &mut d.on_target {
            if line.starts_with("| decode |") {
                *line = "| decode | 41.0 |".into();
            }
        }
        assert!(!holds(&d, "trolley-id", "decode"));
        // A missing figure is a statement not checked: it fails.
        let mut d = committed;
        d.on_target.clear();
        assert!(!holds(&d, "pid", "Cortex-M0"));
    }

    #[test]
    fn every_counter_is_named_once_and_every_compared_count_has_a_counter() {
        let keys: Vec<String> = counters().iter().map(Counter::key).collect();
        let mut unique = keys.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), keys.len());
        for row in rows() {
            for key in [&row.regler.count, &row.regler.count_base, &row.anchor.count]
                .into_iter()
                .flatten()
            {
                assert!(keys.contains(key), "{key} is not measured");
            }
        }
        assert_eq!(thousands(10_000), "10 000");
        assert_eq!(thousands(256), "256");
        assert_eq!(time(Some(14_700.0)), "14.7 µs");
        assert_eq!(time(Some(0.951)), "0.95 ns");
        assert_eq!(figure(70_233.4), "70 233.4");
        assert_eq!(figure(9_999.0), "9999.0");
    }
}
