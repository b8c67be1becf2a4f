//! The picture, three panels one above the other: the tip-position error as the chain
//! stretches, without and with correction; the corrected error on its own scale; and what
//! voting buys once the tracking is right (misdelivered and rejected sacks per million).

use super::{Outcomes, Report, ScenarioReport, TipError};
use crate::cli::number;
use crate::svg::{self, Series};

/// Without correction (red) and with it (blue); the bars use other colours.
const WITHOUT: &str = "#c0392b";
const WITH: &str = "#2471a3";
const MISDELIVERED: &str = "#6c3483";
const REJECTED: &str = "#f39c12";
/// Each panel's height (the svg module's charts are 420 high).
const PANEL_H: u32 = 420;

/// The SVG of `r`: three charts stacked, as wide as the widest.
#[must_use]
pub fn picture(r: &Report) -> String {
    let c = &r.config;
    let setup = format!(
        "{} docks, chains stretching {} m/year",
        c.docks,
        number(c.stretch_m_per_year)
    );
    // Mean (solid) then maximum (dashed), without and with correction (the voting runs), over
    // twenty stretches of the run.
    let mut series = Vec::new();
    for (dashed, labels) in [
        (false, ["mean, no correction", "mean, with correction"]),
        (true, ["max, no correction", "max, with correction"]),
    ] {
        for sc in &r.scenarios[2..] {
            let stat = |e: &TipError| if dashed { e.max_abs_m } else { e.mean_abs_m };
            let correction = sc.scenario.correction;
            series.push(Series {
                label: labels[usize::from(correction)],
                colour: if correction { WITH } else { WITHOUT },
                dashed,
                points: sc
                    .curve
                    .iter()
                    .filter(|c| c.tip_error.count > 0)
                    .map(|c| (c.years, stat(&c.tip_error)))
                    .collect(),
            });
        }
    }
    let lines = svg::line_chart(
        &format!("Tip-position error (voting), {setup}"),
        "years in service",
        "|error| when the tipper is set (m)",
        &series,
    );
    // The corrected runs hug zero on that scale: the same two lines on a scale of their own.
    let corrected_only: Vec<Series<'_>> = series
        .iter()
        .filter(|s| s.colour == WITH)
        .cloned()
        .collect();
    let zoom = svg::line_chart(
        "With stretch correction, on its own scale",
        "years in service",
        "|error| when the tipper is set (m)",
        &corrected_only,
    );
    // What voting buys shows once the tracking is right: compare the two corrected runs.
    let corrected: Vec<&ScenarioReport> = r
        .scenarios
        .iter()
        .filter(|s| s.scenario.correction)
        .collect();
    let per_million = |f: fn(&Outcomes) -> u64| -> Vec<f64> {
        corrected
            .iter()
            .map(|s| 1e6 * f(&s.outcomes) as f64 / s.outcomes.sacks.max(1) as f64)
            .collect()
    };
    let names: Vec<String> = corrected
        .iter()
        .map(|s| {
            if s.scenario.voting {
                format!("voting ({} scans)", c.readings)
            } else {
                "parity only (one scan)".into()
            }
        })
        .collect();
    let bars = svg::bar_chart(
        &format!(
            "Sacks astray with correction, misread rate {} per scan",
            number(c.misread_rate)
        ),
        "sacks per million",
        &names,
        &[
            (
                "misdelivered",
                MISDELIVERED,
                per_million(|o| o.misdelivered),
            ),
            (
                "rejected (to the manual station)",
                REJECTED,
                per_million(|o| o.rejected),
            ),
        ],
    );
    stack(&[lines, zoom, bars])
}

/// Panels one above the other in one SVG, as wide as the widest.
fn stack(panels: &[String]) -> String {
    let width = panels
        .iter()
        .filter_map(|p| {
            p.split("width=\"")
                .nth(1)
                .and_then(|t| t.split('"').next())
                .and_then(|t| t.parse::<f64>().ok())
        })
        .fold(0.0, f64::max);
    let mut out = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{}\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
        PANEL_H * panels.len() as u32
    );
    for (i, p) in panels.iter().enumerate() {
        out.push_str(&p.replacen("<svg ", &format!("<svg y=\"{}\" ", PANEL_H * i as u32), 1));
    }
    out.push_str("</svg>\n");
    out
}
