//! The SVG pictures: a run (set-point and measurement, the outdoor temperature when it is fed
//! forward, the output; the commits marked) and an autotune (the limit cycle of the relay
//! experiment, and the tuned PI answering a set-point step, side by side).

use super::{AutotuneReport, Interface, ProcessKind, SimReport, TracePoint};
use crate::svg::{self, Series};

/// The height of one chart of [`svg`].
const PANEL_H: f64 = 420.0;

/// Charts in a grid, `columns` a row, each as wide as the widest in its column.
fn grid(charts: &[String], columns: usize) -> String {
    let width = |c: &str| -> f64 {
        c.split_once("width=\"")
            .and_then(|(_, rest)| rest.split_once('"'))
            .and_then(|(w, _)| w.parse().ok())
            .unwrap_or(720.0)
    };
    let columns = columns.max(1);
    let mut column_w = vec![0.0f64; columns];
    for (i, c) in charts.iter().enumerate() {
        column_w[i % columns] = column_w[i % columns].max(width(c));
    }
    let rows = charts.len().div_ceil(columns);
    let mut body = String::new();
    for (i, c) in charts.iter().enumerate() {
        let x: f64 = column_w[..i % columns].iter().sum();
        let y = (i / columns) as f64 * PANEL_H;
        body.push_str(&c.replacen("<svg ", &format!("<svg x=\"{x}\" y=\"{y}\" "), 1));
    }
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\">\n\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n{body}</svg>\n",
        column_w.iter().sum::<f64>(),
        rows as f64 * PANEL_H
    )
}

/// The measurement's axis label.
fn quantity(process: ProcessKind) -> &'static str {
    match process {
        ProcessKind::Room => "room temperature (°C)",
        ProcessKind::Tank => "tank level (%)",
    }
}

/// A time axis for a run of `seconds`: minutes up to two hours, hours beyond.
fn time_axis(seconds: f64) -> (f64, &'static str) {
    if seconds <= 2.0 * 3600.0 {
        (60.0, "minutes")
    } else {
        (3600.0, "hours")
    }
}

/// The picture of a run.
#[must_use]
pub fn run(r: &SimReport) -> String {
    let c = &r.config;
    let (scale, unit) = time_axis(r.simulated_h * 3600.0);
    let points = |f: fn(&TracePoint) -> Option<f64>| -> Vec<(f64, f64)> {
        r.picture
            .iter()
            .filter_map(|p| f(p).map(|v| (p.t_s / scale, v)))
            .collect()
    };
    let markers: Vec<f64> = r.commits_s.iter().map(|t| t / scale).collect();
    let started = match c.interface {
        Interface::Terminal => "terminal",
        Interface::Keypad => "keypad",
    };
    let actuator = match c.three_point_s {
        Some(gt) => format!("three-point motor {} s", crate::cli::number(gt)),
        None => "0–10 V output".into(),
    };
    let (process, measured) = match c.process {
        ProcessKind::Room => ("Room", "temperature"),
        ProcessKind::Tank => ("Tank", "level"),
    };
    let title = format!(
        "{process}: set-point and {measured} ({started} set-up, {actuator}, seed {})",
        c.seed
    );
    let mut charts = vec![svg::line_chart_fitted(
        &title,
        unit,
        quantity(c.process),
        &[
            Series {
                label: "set-point",
                colour: "#2c3e50",
                dashed: true,
                points: points(|p| Some(p.setpoint)),
            },
            Series {
                label: "measurement",
                colour: "#c0392b",
                dashed: false,
                points: points(|p| Some(p.measurement)),
            },
        ],
        &markers,
        "commit",
    )];
    // The outdoor temperature is what outdoor compensation acts on: a panel of its own when it
    // is on (on the room's axis it would squeeze the room's band flat).
    if c.outdoor_compensation && c.process == ProcessKind::Room {
        charts.push(svg::line_chart_fitted(
            "Outdoor temperature (fed forward)",
            unit,
            "outdoor temperature (°C)",
            &[Series {
                label: "outdoor",
                colour: "#7f8c8d",
                dashed: false,
                points: points(|p| p.outdoor),
            }],
            &markers,
            "commit",
        ));
    }
    let (output_title, output_label) = match c.three_point_s {
        Some(_) => (
            "Controller output: the wanted motor position",
            "position (V, 10 = open)",
        ),
        None => ("Controller output Y", "output (V)"),
    };
    charts.push(svg::line_chart_marked(
        output_title,
        unit,
        output_label,
        &[Series {
            label: "output Y",
            colour: "#2471a3",
            dashed: false,
            points: points(|p| Some(p.output)),
        }],
        &markers,
        "commit",
    ));
    grid(&charts, 1)
}

/// The picture of an autotune: on the left the relay experiment (the limit cycle the ultimate
/// point is read from), on the right the tuned PI from the hand-over on, answering the
/// set-point step; measurement above, output below.
#[must_use]
pub fn autotune(r: &AutotuneReport) -> String {
    let (scale, unit) = match r.process {
        ProcessKind::Room => (60.0, "minutes"),
        ProcessKind::Tank => (1.0, "seconds"),
    };
    let relay: Vec<_> = r.trace.iter().filter(|p| p.relay).collect();
    let tuned: Vec<_> = r.trace.iter().filter(|p| !p.relay).collect();
    let handover = r.experiment_s;
    let pick =
        |points: &[&super::AutotunePoint], from: f64, f: fn(&super::AutotunePoint) -> f64| {
            points
                .iter()
                .map(|p| ((p.t_s - from) / scale, f(p)))
                .collect::<Vec<_>>()
        };
    let u = r.process.unit();
    let found = match &r.ultimate {
        Ok((ku, tu)) => format!("Ku = {ku:.2} V/{u}, Tu = {tu:.0} s"),
        Err(e) => format!("failed: {e}"),
    };
    let process = r.process.name();
    let measured = |title: String, points: &[&super::AutotunePoint], from: f64| {
        svg::line_chart_fitted(
            &title,
            &format!(
                "{unit} {}",
                if from > 0.0 {
                    "after the hand-over"
                } else {
                    "of the experiment"
                }
            ),
            quantity(r.process),
            &[
                Series {
                    label: "set-point",
                    colour: "#2c3e50",
                    dashed: true,
                    points: pick(points, from, |p| p.setpoint),
                },
                Series {
                    label: "measurement",
                    colour: "#c0392b",
                    dashed: false,
                    points: pick(points, from, |p| p.measurement),
                },
            ],
            &[],
            "",
        )
    };
    let output = |title: &str, label: &'static str, points: &[&super::AutotunePoint], from: f64| {
        svg::line_chart_marked(
            title,
            &format!(
                "{unit} {}",
                if from > 0.0 {
                    "after the hand-over"
                } else {
                    "of the experiment"
                }
            ),
            "output (V)",
            &[Series {
                label,
                colour: "#2471a3",
                dashed: false,
                points: pick(points, from, |p| p.output),
            }],
            &[],
            "",
        )
    };
    let charts = [
        measured(
            format!("Relay experiment on the {process}: the limit cycle ({found})"),
            &relay,
            0.0,
        ),
        measured(
            format!(
                "Ziegler–Nichols PI (K = {:.2}, Ti = {:.0} s): a set-point step of {} {u}",
                r.k, r.ti, r.step
            ),
            &tuned,
            handover,
        ),
        output(
            &format!(
                "Relay output: {:.1} ± {:.1} V, hysteresis {} {u}",
                r.bias_v, r.relay_v, r.hysteresis
            ),
            "relay output",
            &relay,
            0.0,
        ),
        output(
            &format!(
                "PI output from the hand-over (jump {:.3} V)",
                r.handover_jump_v
            ),
            "PI output",
            &tuned,
            handover,
        ),
    ];
    grid(&charts, 2)
}
