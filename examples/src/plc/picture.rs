//! The picture: a timing diagram of chosen signals, one row each (inputs blue, outputs red,
//! high = on), over a window of cycles that ends a quarter of its width after the reject gate
//! last opened — the gate is what the program is for, so the bad part, the gate and the belt
//! travel between them are in the picture. Without an opening in the run the window is the last cycles.

use std::fmt::Write as _;

use super::program::GATE_PULSES;
use super::simulator::{Sample, Simulator};
use super::{MM_PER_PULSE, PERIOD_MS, SIGNALS, input, output};

/// The window over `trace` as `start..end` indices and, if the gate opened, the index of its
/// last opening.
#[must_use]
pub fn window(trace: &[Sample], window: usize) -> (std::ops::Range<usize>, Option<usize>) {
    let gate = output::GATE;
    let opened = |a: &Sample, b: &Sample| a.outputs >> gate & 1 == 0 && b.outputs >> gate & 1 == 1;
    let last_opening = trace
        .windows(2)
        .rposition(|w| opened(&w[0], &w[1]))
        .map(|i| i + 1);
    let end = match last_opening {
        Some(i) => (i + window / 4 + 1)
            .min(trace.len())
            .max(window.min(trace.len())),
        None => trace.len(),
    };
    (end.saturating_sub(window)..end, last_opening)
}

/// The timing diagram of `signals` (names from [`SIGNALS`]) over `window` cycles (see the
/// module's documentation), as SVG; `seed` is named in the title.
#[must_use]
pub fn timing_diagram(
    sim: &Simulator,
    signals: &[String],
    window_cycles: usize,
    seed: u64,
) -> String {
    let all: Vec<Sample> = sim.trace.iter().copied().collect();
    let (range, last_opening) = window(&all, window_cycles);
    let start = range.start;
    let trace = &all[range];
    let total = sim.plc.cycle_count();
    let (first_cycle, last_cycle) = (
        trace.first().map_or(0, |s| s.cycle),
        trace.last().map_or(0, |s| s.cycle),
    );
    let caption = match last_opening.map(|i| all[i].cycle) {
        Some(c) => format!(
            "Conveyor section, seed {seed}: cycles {first_cycle}–{last_cycle} of {total} (the reject gate last opened in cycle {c})"
        ),
        None => format!(
            "Conveyor section, seed {seed}: cycles {first_cycle}–{last_cycle} of {total} (the reject gate did not open)"
        ),
    };
    let (left, row, top) = (80.0, 34.0, 40.0);
    let width = 900.0;
    let plot = width - left - 20.0;
    let height = top + row * signals.len() as f64 + 52.0;
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" font-family=\"monospace\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{}\" y=\"22\" text-anchor=\"middle\" font-size=\"14\" font-family=\"sans-serif\">{caption}</text>\n",
        width / 2.0,
    );
    let n = trace.len().max(1) as f64;
    let x_of = |i: usize| left + plot * i as f64 / n;
    // Cycle ticks: about eight, at round cycle numbers.
    if let (Some(first), Some(last)) = (trace.first(), trace.last()) {
        let span = (last.cycle - first.cycle).max(1);
        let raw = span as f64 / 8.0;
        let magnitude = 10f64.powf(raw.log10().floor());
        let step = [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|m| m * magnitude)
            .find(|s| *s >= raw)
            .unwrap_or(raw)
            .max(1.0) as u64;
        let axis = top + row * signals.len() as f64 + 4.0;
        let mut c = first.cycle.div_ceil(step) * step;
        while c <= last.cycle {
            let x = left + plot * (c - first.cycle) as f64 / n;
            let _ = writeln!(
                svg,
                "<line x1=\"{x:.1}\" x2=\"{x:.1}\" y1=\"{top}\" y2=\"{axis:.1}\" stroke=\"#eee\"/><text x=\"{x:.1}\" y=\"{:.1}\" text-anchor=\"middle\" font-size=\"10\">{c}</text>",
                axis + 12.0
            );
            c += step;
        }
    }
    let mut rows = Vec::new();
    for (k, name) in signals.iter().enumerate() {
        let Some(&(_, input, point)) = SIGNALS.iter().find(|(s, ..)| s == name) else {
            continue;
        };
        let base = top + row * (k as f64 + 1.0) - 8.0;
        rows.push((name.as_str(), base));
        let colour = if input { "#2471a3" } else { "#c0392b" };
        let _ = writeln!(
            svg,
            "<text x=\"8\" y=\"{base:.1}\" fill=\"{colour}\">{}{name}</text>",
            if input { "in  " } else { "out " }
        );
        let mut path = String::new();
        for (i, s) in trace.iter().enumerate() {
            let word = if input { s.inputs } else { s.outputs };
            let y = if word >> point & 1 == 1 {
                base - 18.0
            } else {
                base
            };
            let _ = write!(
                path,
                "{}{:.1},{y:.1} L{:.1},{y:.1} ",
                if i == 0 { "M" } else { "L" },
                x_of(i),
                x_of(i + 1)
            );
        }
        let _ = writeln!(
            svg,
            "<path d=\"{path}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"1.6\"/>"
        );
        let _ = writeln!(
            svg,
            "<line x1=\"{left}\" x2=\"{:.1}\" y1=\"{:.1}\" y2=\"{:.1}\" stroke=\"#eee\"/>",
            left + plot,
            base + 4.0,
            base + 4.0
        );
    }
    // The point of the picture: the bad part flagged at the quality sensor and the gate opening
    // for it when it reaches the gate, marked for the last opening.
    let row_of = |name: &str| rows.iter().find(|(n, _)| *n == name).map(|&(_, b)| b);
    if let (Some(bad_row), Some(gate_row), Some(opening)) =
        (row_of("bad"), row_of("gate"), last_opening)
    {
        if let Some(flagged) = flagged_for(&all, opening).filter(|&k| k >= start) {
            let (x0, x1) = (x_of(flagged - start), x_of(opening - start));
            let (y0, y1) = (bad_row - 18.0, gate_row - 18.0);
            let _ = writeln!(
                svg,
                "<line x1=\"{x0:.1}\" y1=\"{y0:.1}\" x2=\"{x1:.1}\" y2=\"{y1:.1}\" stroke=\"#555\" stroke-dasharray=\"4 3\"/>\n<text x=\"{:.1}\" y=\"{:.1}\" font-family=\"sans-serif\" font-size=\"11\" fill=\"#555\" text-anchor=\"{}\">bad part reaches the gate after {GATE_PULSES} encoder pulses ({} m of belt)</text>",
                if x1 > left + plot / 2.0 {
                    x1 - 6.0
                } else {
                    x1 + 6.0
                },
                y1 - 4.0,
                if x1 > left + plot / 2.0 {
                    "end"
                } else {
                    "start"
                },
                crate::cli::number(f64::from(GATE_PULSES * MM_PER_PULSE) / 1000.0)
            );
        }
    }
    let _ = writeln!(
        svg,
        "<text x=\"{left}\" y=\"{:.1}\" font-family=\"sans-serif\">cycle number ({PERIOD_MS} ms each: {} cycles = {} s shown); <tspan fill=\"#2471a3\">inputs blue</tspan>, <tspan fill=\"#c0392b\">outputs red</tspan>; high = on</text>\n</svg>",
        height - 8.0,
        trace.len(),
        crate::cli::number(trace.len() as f64 * f64::from(PERIOD_MS) / 1000.0)
    );
    svg
}

/// The sample where the quality sensor flagged the part the gate opened for at `opening`:
/// [`GATE_PULSES`] encoder pulses of belt travel earlier (the tracker counts the belt's
/// movement, so stops and stalls in between do not count).
fn flagged_for(trace: &[Sample], opening: usize) -> Option<usize> {
    let bad = |k: usize| trace[k].inputs >> input::BAD & 1 == 1;
    // Walk back summing the belt's travel: the latest rising edge of the flag at least
    // GATE_PULSES before the opening; the parts ride at least 400 mm (40 pulses) apart, so one
    // within 20 more is this part's.
    let mut belt = 0u32;
    let mut k = opening;
    while k > 1 && belt < GATE_PULSES + 20 {
        belt += u32::from(trace[k].encoder.wrapping_sub(trace[k - 1].encoder));
        k -= 1;
        if belt >= GATE_PULSES && bad(k) && !bad(k - 1) {
            return Some(k);
        }
    }
    None
}
