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

use crate::highway::{encoded, workload};

/// Marks the start of the block the command writes into a README.
pub const README_BEGIN: &str = "<!-- performance:begin: written by `cargo run --release -p regler-benches --bin report` from docs/PERFORMANCE.md; do not edit by hand -->";
/// Marks the end of that block.
pub const README_END: &str = "<!-- performance:end -->";
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
    for which in ["encode", "decode", "copy", "controller", "delay"] {
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
            path: format!("`Filler` + `Drainer` (`SharedRing<u8, 256>`) — {shape}"),
            regler: side("split", "regler Filler+Drainer 256"),
            anchor_name: "heapless `Producer` + `Consumer` (`Queue<u8, 256>`)".into(),
            anchor: side("spsc-split", "heapless Producer+Consumer 256"),
        });
    }
    rows.push(Row {
        group: "two threads through the split halves vs heapless's".into(),
        path: "two threads, 10 million `u32` through a 256-slot ring, per item".into(),
        regler: Side::new().time("ring/two-thread transfer/regler Filler+Drainer".into(), 1e7),
        anchor_name: "heapless `Producer` + `Consumer`".into(),
        anchor: Side::new().time(
            "ring/two-thread transfer/heapless Producer+Consumer".into(),
            1e7,
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
    scaling(
        &mut s,
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
    scaling(
        &mut s,
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
    scaling(
        &mut s,
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

/// Replaces the block between [`README_BEGIN`] and [`README_END`] in `readme` with `block`;
/// `None` when the markers are not both there, in that order.
#[must_use]
pub fn replace_block(readme: &str, block: &str) -> Option<String> {
    let begin = readme.find(README_BEGIN)?;
    let after = begin + README_BEGIN.len();
    let end = after + readme.get(after..)?.find(README_END)?;
    Some(format!(
        "{}{README_BEGIN}\n{block}{}",
        readme.get(..begin)?,
        readme.get(end..)?
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
            replace_block(&readme, "new\n"),
            Some(format!("a\n{README_BEGIN}\nnew\n{README_END}\nb\n"))
        );
        assert_eq!(replace_block("no markers", "new\n"), None);
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
