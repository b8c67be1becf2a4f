//! A small hand-written SVG line and bar chart: enough for the examples' pictures, without a
//! plotting stack that needs system fonts.

use std::fmt::Write as _;

/// One line of a line chart.
#[derive(Clone, Debug)]
pub struct Series<'a> {
    /// Legend text.
    pub label: &'a str,
    /// CSS colour.
    pub colour: &'a str,
    /// Dashed line.
    pub dashed: bool,
    /// Points (x, y).
    pub points: Vec<(f64, f64)>,
}

const H: f64 = 420.0;
const LEFT: f64 = 70.0;
/// The plot's width; the legend to its right takes what its longest label needs.
const PLOT_W: f64 = 460.0;
const TOP: f64 = 50.0;
const BOTTOM: f64 = 55.0;
/// Legend text at 11 px: a generous average glyph width, so a label never touches the edge.
const LEGEND_GLYPH: f64 = 6.6;

/// The picture's width: the plot, and a legend as wide as its longest label.
#[derive(Clone, Copy, Debug)]
struct Frame {
    width: f64,
}

impl Frame {
    fn for_legend<'a>(labels: impl Iterator<Item = &'a str>) -> Self {
        let longest = labels.map(|l| l.chars().count()).max().unwrap_or(0);
        let legend = 15.0 + 28.0 + LEGEND_GLYPH * longest as f64 + 15.0;
        Self {
            width: (LEFT + PLOT_W + legend.max(190.0)).ceil(),
        }
    }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A "nice" upper bound for an axis: 1, 2 or 5 times a power of ten, at least `max`.
fn nice_ceiling(max: f64) -> f64 {
    if !(max.is_finite() && max > 0.0) {
        return 1.0;
    }
    let magnitude = 10f64.powf(max.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * magnitude)
        .find(|v| *v >= max)
        .unwrap_or(max)
}

/// A line chart with axes, five grid lines and a legend.
#[must_use]
pub fn line_chart(title: &str, x_label: &str, y_label: &str, series: &[Series<'_>]) -> String {
    line_chart_marked(title, x_label, y_label, series, &[], "")
}

/// A line chart with vertical dashed markers at the x values `markers`, labelled `marker_label`
/// in the legend. The y axis starts at 0.
#[must_use]
pub fn line_chart_marked(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series<'_>],
    markers: &[f64],
    marker_label: &str,
) -> String {
    chart(
        title,
        x_label,
        y_label,
        series,
        markers,
        marker_label,
        false,
    )
}

/// As [`line_chart_marked`], with the y axis fitted to the data (a round range around it), so
/// a thin band of values is drawn large enough to read.
#[must_use]
pub fn line_chart_fitted(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series<'_>],
    markers: &[f64],
    marker_label: &str,
) -> String {
    chart(title, x_label, y_label, series, markers, marker_label, true)
}

/// A round axis covering `lo..=hi` and fitted to it: the smallest step of 1, 2 or 5 times a
/// power of ten that covers the data in at most eight steps, from the step below `lo` to the
/// step above `hi` (data ending at 525 gets an axis to 600, not 1 000).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Axis {
    start: f64,
    step: f64,
    steps: u32,
}

impl Axis {
    fn fitted(lo: f64, hi: f64) -> Self {
        if !(lo.is_finite() && hi.is_finite() && hi >= lo) {
            return Self {
                start: 0.0,
                step: 0.2,
                steps: 5,
            };
        }
        let mut step = nice_ceiling(
            ((hi - lo) / 8.0)
                .max(hi.abs().max(lo.abs()) * 1e-9)
                .max(1e-12),
        );
        loop {
            let start = (lo / step).floor() * step;
            let steps = ((hi - start) / step - 1e-9).ceil().max(1.0);
            if steps <= 8.0 {
                return Self {
                    start,
                    step,
                    // At most 8: the cast is exact.
                    steps: steps as u32,
                };
            }
            step = nice_ceiling(step * 1.000_001);
        }
    }

    fn end(self) -> f64 {
        self.start + self.step * f64::from(self.steps)
    }

    fn tick(self, i: u32) -> f64 {
        self.start + self.step * f64::from(i)
    }
}

/// The round range of [`Axis::fitted`].
#[cfg(test)]
fn nice_range(lo: f64, hi: f64) -> (f64, f64) {
    let a = Axis::fitted(lo, hi);
    (a.start, a.end())
}

fn chart(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series<'_>],
    markers: &[f64],
    marker_label: &str,
    fit_y: bool,
) -> String {
    let points = series.iter().flat_map(|s| s.points.iter());
    let finite = |v: &f64| v.is_finite();
    let xs = points.clone().map(|p| p.0).filter(finite);
    let x_axis = Axis::fitted(xs.clone().fold(0.0, f64::min), xs.fold(0.0, f64::max));
    let ys = points.map(|p| p.1).filter(finite);
    let y_axis = if fit_y {
        Axis::fitted(
            ys.clone().fold(f64::INFINITY, f64::min),
            ys.fold(f64::NEG_INFINITY, f64::max),
        )
    } else {
        Axis::fitted(ys.clone().fold(0.0, f64::min), ys.fold(0.0, f64::max))
    };
    let labels = series
        .iter()
        .map(|s| s.label)
        .chain((!markers.is_empty()).then_some(marker_label));
    let frame = Frame::for_legend(labels);
    let (pw, ph) = (PLOT_W, H - TOP - BOTTOM);
    let (x0, x1) = (x_axis.start, x_axis.end());
    let sx = |x: f64| LEFT + pw * (x - x0) / (x1 - x0);
    let (y_min, y_max) = (y_axis.start, y_axis.end());
    let sy = |y: f64| TOP + ph * (1.0 - (y - y_min) / (y_max - y_min));
    let mut svg = header(title, frame);
    grid(&mut svg, y_axis);
    for i in 0..=x_axis.steps {
        let fx = x_axis.tick(i);
        let _ = writeln!(
            svg,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            sx(fx),
            TOP + ph + 18.0,
            trim(fx)
        );
    }
    axes(&mut svg, frame, x_label, y_label);
    for (i, s) in series.iter().enumerate() {
        let path: Vec<String> = s
            .points
            .iter()
            .map(|&(x, y)| format!("{:.1},{:.1}", sx(x), sy(y)))
            .collect();
        let dash = if s.dashed {
            r#" stroke-dasharray="6 4""#
        } else {
            ""
        };
        let _ = writeln!(
            svg,
            r#"<polyline fill="none" stroke="{}" stroke-width="2"{dash} points="{}"/>"#,
            s.colour,
            path.join(" ")
        );
        // Dots only where they can be told apart.
        for &(x, y) in s.points.iter().filter(|_| s.points.len() <= 60) {
            let _ = writeln!(
                svg,
                r#"<circle cx="{:.1}" cy="{:.1}" r="2.5" fill="{}"/>"#,
                sx(x),
                sy(y),
                s.colour
            );
        }
        legend(&mut svg, frame, i, s.label, s.colour, s.dashed);
    }
    // Markers closer than 5 px are spread apart, so that two commits at once show as two.
    let mut last_x = f64::NEG_INFINITY;
    for &m in markers {
        let x = sx(m).max(last_x + 5.0);
        last_x = x;
        let _ = writeln!(
            svg,
            r##"<line x1="{x:.1}" x2="{x:.1}" y1="{TOP}" y2="{:.1}" stroke="#8e44ad" stroke-dasharray="3 3"/>"##,
            TOP + ph,
        );
    }
    if !markers.is_empty() {
        legend(&mut svg, frame, series.len(), marker_label, "#8e44ad", true);
    }
    svg.push_str("</svg>\n");
    svg
}

/// A grouped bar chart: one group per category, one bar per series value, log-free.
#[must_use]
pub fn bar_chart(
    title: &str,
    y_label: &str,
    categories: &[String],
    series: &[(&str, &str, Vec<f64>)],
) -> String {
    let y_axis = Axis::fitted(
        0.0,
        series
            .iter()
            .flat_map(|s| s.2.iter().copied())
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max),
    );
    let y_max = y_axis.end();
    let frame = Frame::for_legend(series.iter().map(|s| s.0));
    let (pw, ph) = (PLOT_W, H - TOP - BOTTOM);
    let sy = |y: f64| TOP + ph * (1.0 - y / y_max);
    let mut svg = header(title, frame);
    grid(&mut svg, y_axis);
    axes(&mut svg, frame, "", y_label);
    let group_w = pw / categories.len().max(1) as f64;
    let bar_w = group_w * 0.8 / series.len().max(1) as f64;
    for (g, category) in categories.iter().enumerate() {
        let x0 = LEFT + group_w * g as f64 + group_w * 0.1;
        for (k, (_, colour, values)) in series.iter().enumerate() {
            let v = values.get(g).copied().unwrap_or(0.0);
            let x = x0 + bar_w * k as f64;
            let _ = writeln!(
                svg,
                r#"<rect x="{x:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{colour}"><title>{}</title></rect>"#,
                sy(v),
                bar_w * 0.9,
                TOP + ph - sy(v),
                trim(v)
            );
            // The value above the bar, so that a zero bar is seen to be zero, not missing.
            let _ = writeln!(
                svg,
                r#"<text x="{:.1}" y="{:.1}" text-anchor="middle" font-size="11">{}</text>"#,
                x + bar_w * 0.45,
                sy(v) - 4.0,
                trim(v)
            );
        }
        let _ = writeln!(
            svg,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle" font-size="11">{}</text>"#,
            x0 + group_w * 0.4,
            TOP + ph + 16.0,
            escape(category)
        );
    }
    for (i, (label, colour, _)) in series.iter().enumerate() {
        legend(&mut svg, frame, i, label, colour, false);
    }
    svg.push_str("</svg>\n");
    svg
}

/// The horizontal grid lines of `axis`, with their values.
fn grid(svg: &mut String, axis: Axis) {
    let ph = H - TOP - BOTTOM;
    for i in 0..=axis.steps {
        let y = TOP + ph * (1.0 - f64::from(i) / f64::from(axis.steps));
        let _ = writeln!(
            svg,
            r##"<line x1="{LEFT}" x2="{:.1}" y1="{y:.1}" y2="{y:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
            LEFT + PLOT_W,
            LEFT - 6.0,
            y + 4.0,
            trim(axis.tick(i)),
        );
    }
}

fn header(title: &str, frame: Frame) -> String {
    let w = frame.width;
    // The title is as wide as the picture allows: a long one is set smaller rather than cut.
    let size = (16.0f64).min((w - 20.0) / (0.62 * title.chars().count().max(1) as f64));
    format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{H}" viewBox="0 0 {w} {H}" font-family="sans-serif" font-size="12">
<rect width="100%" height="100%" fill="white"/>
<text x="{:.1}" y="28" text-anchor="middle" font-size="{size:.1}" font-weight="bold">{}</text>
"#,
        w / 2.0,
        escape(title)
    )
}

fn axes(svg: &mut String, _frame: Frame, x_label: &str, y_label: &str) {
    let (pw, ph) = (PLOT_W, H - TOP - BOTTOM);
    let _ = writeln!(
        svg,
        r#"<line x1="{LEFT}" x2="{LEFT}" y1="{TOP}" y2="{:.1}" stroke="black"/><line x1="{LEFT}" x2="{:.1}" y1="{:.1}" y2="{:.1}" stroke="black"/>"#,
        TOP + ph,
        LEFT + pw,
        TOP + ph,
        TOP + ph
    );
    let _ = writeln!(
        svg,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text><text transform="translate(18 {:.1}) rotate(-90)" text-anchor="middle">{}</text>"#,
        LEFT + pw / 2.0,
        H - 12.0,
        escape(x_label),
        TOP + ph / 2.0,
        escape(y_label)
    );
}

fn legend(svg: &mut String, _frame: Frame, i: usize, label: &str, colour: &str, dashed: bool) {
    let x = LEFT + PLOT_W + 15.0;
    let y = TOP + 10.0 + 20.0 * i as f64;
    let dash = if dashed {
        r#" stroke-dasharray="6 4""#
    } else {
        ""
    };
    let _ = writeln!(
        svg,
        r#"<line x1="{x:.1}" x2="{:.1}" y1="{y:.1}" y2="{y:.1}" stroke="{colour}" stroke-width="3"{dash}/><text x="{:.1}" y="{:.1}" font-size="11">{}</text>"#,
        x + 22.0,
        x + 28.0,
        y + 4.0,
        escape(label)
    );
}

fn trim(v: f64) -> String {
    let s = format!("{v:.2}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_are_fitted_to_their_data_in_round_steps() {
        assert_eq!(nice_range(15.2, 22.4), (15.0, 23.0));
        assert_eq!(nice_range(0.0, 10.0), (0.0, 10.0));
        // Data ending at 525 min: an axis to 600, not to 1 000; 62 crates: to 70, not 100.
        assert_eq!(nice_range(0.0, 525.0), (0.0, 600.0));
        assert_eq!(nice_range(0.0, 62.0), (0.0, 70.0));
        assert_eq!(nice_range(0.0, 48.0 * 3600.0).1, 200_000.0);
        for (lo, hi) in [
            (-3.7, 41.0),
            (0.0, 1e-7),
            (3.0, 3.0),
            (-1e6, -2.0),
            (0.0, 625.0),
        ] {
            let a = Axis::fitted(lo, hi);
            assert!(a.start <= lo && a.end() >= hi, "{lo} {hi}: {a:?}");
            assert!((1..=8).contains(&a.steps), "{lo} {hi}: {a:?}");
            // Fitted: one step less would not cover the data.
            assert!(
                a.end() - a.step < hi || a.start + a.step > lo || hi == lo,
                "{lo} {hi}: {a:?}"
            );
        }
    }

    #[test]
    fn a_long_legend_widens_the_picture() {
        let s = |label| Series {
            label,
            colour: "red",
            dashed: false,
            points: vec![(0.0, 1.0), (1.0, 2.0)],
        };
        let narrow = line_chart("t", "x", "y", &[s("a")]);
        assert!(narrow.contains(r#"width="720""#), "{narrow}");
        let label = "errors caught by the crate controller, per 1000";
        let wide = line_chart("t", "x", "y", &[s(label)]);
        let w: f64 = wide
            .split("width=\"")
            .nth(1)
            .and_then(|t| t.split('"').next())
            .and_then(|t| t.parse().ok())
            .unwrap();
        assert!(
            w >= LEFT + PLOT_W + 15.0 + 28.0 + 6.0 * label.len() as f64,
            "{w}"
        );
    }

    #[test]
    fn nice_ceilings() {
        assert_eq!(nice_ceiling(0.0), 1.0);
        assert_eq!(nice_ceiling(3.2), 5.0);
        assert_eq!(nice_ceiling(12.0), 20.0);
        assert_eq!(nice_ceiling(f64::NAN), 1.0);
    }

    #[test]
    fn charts_are_well_formed() {
        let s = Series {
            label: "a<b",
            colour: "red",
            dashed: true,
            points: vec![(0.0, 1.0), (1.0, 2.0)],
        };
        let svg = line_chart("t", "x", "y", &[s]);
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>\n"));
        assert!(svg.contains("a&lt;b"));
        assert_eq!(svg.matches("<polyline").count(), 1);
        let bars = bar_chart(
            "t",
            "y",
            &["one".into(), "two".into()],
            &[("s", "blue", vec![1.0, 3.0])],
        );
        assert_eq!(bars.matches("<rect x=").count(), 2);
    }
}
