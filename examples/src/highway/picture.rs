//! The picture: per crate along the loop, what happened to every thousand commands sent to it —
//! retries, errors its controller caught, commands that failed after every retry, demands served.

use super::{CrateSummary, Summary};
use crate::cli::number;
use crate::svg;

/// The SVG line chart of `s`, one point per crate address; the title names the line, the loop
/// and the noise, and the totals that matter (failed, undetected).
#[must_use]
pub fn picture(s: &Summary) -> String {
    let per_thousand = |f: fn(&CrateSummary) -> u64| -> Vec<(f64, f64)> {
        s.crates
            .iter()
            .map(|c| {
                (
                    f64::from(c.address),
                    1000.0 * f(c) as f64 / c.messages.max(1) as f64,
                )
            })
            .collect()
    };
    let series = [
        svg::Series {
            label: "retries",
            colour: "#1f77b4",
            dashed: false,
            points: per_thousand(|c| c.retries),
        },
        svg::Series {
            label: "errors caught by the crate",
            colour: "#d62728",
            dashed: false,
            points: per_thousand(|c| c.detected_errors),
        },
        svg::Series {
            label: "failed after every retry",
            colour: "#ff7f0e",
            dashed: false,
            points: per_thousand(|c| c.failed),
        },
        svg::Series {
            label: "demands served",
            colour: "#2ca02c",
            dashed: true,
            points: per_thousand(|c| c.demands_served),
        },
    ];
    let c = &s.config;
    svg::line_chart(
        &format!(
            "Highway, {}, {} crates, BER {}: {} failed, {} undetected",
            c.line,
            c.crates,
            number(c.ber),
            s.failed,
            s.undetected_errors
        ),
        "crate address (position on the loop)",
        "per 1000 commands to the crate",
        &series,
    )
}
