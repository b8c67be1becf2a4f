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

const W: f64 = 720.0;
const H: f64 = 420.0;
const LEFT: f64 = 70.0;
const RIGHT: f64 = 190.0;
const TOP: f64 = 50.0;
const BOTTOM: f64 = 55.0;

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

/// A round axis range covering `lo..=hi`: five grid steps of 1, 2 or 5 times a power of ten.
fn nice_range(lo: f64, hi: f64) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let mut step = nice_ceiling(((hi - lo) / 5.0).max(1e-9));
    let mut start = (lo / step).floor() * step;
    // Flooring the start can push the top past five steps: take the next round step then.
    while start + 5.0 * step < hi {
        step = nice_ceiling(step * 1.000_001);
        start = (lo / step).floor() * step;
    }
    (start, start + 5.0 * step)
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
    let x_max = nice_ceiling(points.clone().map(|p| p.0).fold(0.0, f64::max));
    let (y_min, y_max) = if fit_y {
        let lo = points.clone().map(|p| p.1).fold(f64::INFINITY, f64::min);
        let hi = points.map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
        nice_range(lo, hi)
    } else {
        (0.0, nice_ceiling(points.map(|p| p.1).fold(0.0, f64::max)))
    };
    let (pw, ph) = (W - LEFT - RIGHT, H - TOP - BOTTOM);
    let sx = |x: f64| LEFT + pw * x / x_max;
    let sy = |y: f64| TOP + ph * (1.0 - (y - y_min) / (y_max - y_min));
    let mut svg = header(title);
    grid_between(&mut svg, y_min, y_max);
    for i in 0..=5 {
        let fx = x_max * f64::from(i) / 5.0;
        let _ = writeln!(
            svg,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            sx(fx),
            TOP + ph + 18.0,
            trim(fx)
        );
    }
    axes(&mut svg, x_label, y_label);
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
        legend(&mut svg, i, s.label, s.colour, s.dashed);
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
        legend(&mut svg, series.len(), marker_label, "#8e44ad", true);
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
    let y_max = nice_ceiling(
        series
            .iter()
            .flat_map(|s| s.2.iter().copied())
            .fold(0.0, f64::max),
    );
    let (pw, ph) = (W - LEFT - RIGHT, H - TOP - BOTTOM);
    let sy = |y: f64| TOP + ph * (1.0 - y / y_max);
    let mut svg = header(title);
    horizontal_grid(&mut svg, y_max);
    axes(&mut svg, "", y_label);
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
        legend(&mut svg, i, label, colour, false);
    }
    svg.push_str("</svg>\n");
    svg
}

/// Five horizontal grid lines with their values, 0 to `y_max`.
fn horizontal_grid(svg: &mut String, y_max: f64) {
    grid_between(svg, 0.0, y_max);
}

/// Five horizontal grid lines with their values, `y_min` to `y_max`.
fn grid_between(svg: &mut String, y_min: f64, y_max: f64) {
    let (pw, ph) = (W - LEFT - RIGHT, H - TOP - BOTTOM);
    for i in 0..=5 {
        let fy = y_min + (y_max - y_min) * f64::from(i) / 5.0;
        let y = TOP + ph * (1.0 - f64::from(i) / 5.0);
        let _ = writeln!(
            svg,
            r##"<line x1="{LEFT}" x2="{:.1}" y1="{y:.1}" y2="{y:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
            LEFT + pw,
            LEFT - 6.0,
            y + 4.0,
            trim(fy),
        );
    }
}

fn header(title: &str) -> String {
    format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" font-family="sans-serif" font-size="12">
<rect width="100%" height="100%" fill="white"/>
<text x="{:.1}" y="28" text-anchor="middle" font-size="16" font-weight="bold">{}</text>
"#,
        W / 2.0,
        escape(title)
    )
}

fn axes(svg: &mut String, x_label: &str, y_label: &str) {
    let (pw, ph) = (W - LEFT - RIGHT, H - TOP - BOTTOM);
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

fn legend(svg: &mut String, i: usize, label: &str, colour: &str, dashed: bool) {
    let x = W - RIGHT + 15.0;
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
    fn nice_ranges_cover_the_data_in_five_round_steps() {
        assert_eq!(nice_range(15.2, 22.4), (14.0, 24.0));
        assert_eq!(nice_range(0.0, 10.0), (0.0, 10.0));
        let (a, b) = nice_range(-3.7, 41.0);
        assert!(a <= -3.7 && b >= 41.0, "{a} {b}");
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
