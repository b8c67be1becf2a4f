//! The plant map: an SVG picture of a run over the plant's graph ([`MapData`]).
//!
//! Places stand in columns by [`MapNode::layer`](super::map_data::MapNode::layer): loading
//! stations left, readers, buffer lanes, then emptying stations, docks and the manual station
//! right; the return rail is a bar along the bottom, fed from the right and feeding the loading
//! stations on the left. Each rail section is drawn as wide as its trolleys per hour (linear,
//! the legend gives the scale; a section no trolley used is a thin dashed line). A red circle in
//! a place's box counts the sacks misdelivered there, an orange square the trolleys a reader
//! rejected to the manual station (area grows with the count, the number beside it); a yellow
//! warning triangle on a box's top edge is an alarm still on at the end of the run. A rail that
//! skips columns runs level through the gaps between their boxes; one that runs backwards loops
//! under the columns; the places of a column are grouped by kind, in the data's order.
//!
//! Every colour has one meaning: the place kinds' pale fills, one dark colour for rails, red,
//! orange and yellow only for the marks. Every number printed is finite: zero or unknown hours
//! give "no time" and thin rails, an empty map says so.
//!
//! ```
//! use regler_examples::mailbag::plant::map::draw;
//! use regler_examples::mailbag::plant::map_data::{MapData, MapEdge, MapNode, NodeKind};
//!
//! let place = |name: &str, kind, layer| MapNode {
//!     name: name.into(),
//!     kind,
//!     layer,
//!     misdelivered: 0,
//!     rejected: 0,
//!     alarm: false,
//! };
//! let map = MapData {
//!     hours: 24.0,
//!     nodes: vec![place("P1", NodeKind::Loading, 0), place("R1", NodeKind::Reader, 1)],
//!     edges: vec![MapEdge { from: 0, to: 1, trolleys: 480 }],
//! };
//! let svg = draw(&map, "one rail, 24 h");
//! assert!(svg.starts_with("<svg") && svg.contains(">R1<") && svg.contains("20 /h"));
//! ```

mod draw;
mod layout;

use super::map_data::{MapData, MapEdge, MapNode, NodeKind};
use draw::{empty, header, legend, place, rails, subtitle};
use layout::{Layout, Route, attachments};

const TITLE_FONT: f64 = 22.0;
const NAME_FONT: f64 = 15.0;
const SMALL_FONT: f64 = 13.0;
const COUNT_FONT: f64 = 13.0;
const LEGEND_FONT: f64 = 13.0;

/// Rails, every one of them.
const RAIL: &str = "#34495e";
/// An alarm on at the end of the run.
const ALARM: &str = "#ffd400";

/// Narrowest and widest rail, px.
const MIN_W: f64 = 1.5;
const MAX_W: f64 = 14.0;
/// Largest marker radius, px.
const MARK_R: f64 = 10.0;
/// Padding inside a box.
const PAD: f64 = 10.0;

/// Draws `data` as an SVG map titled `title` (name the run in it: "voting, 24 h, seed 1977").
/// Never panics; an empty map or zero hours gives a picture that says so.
#[must_use]
pub fn draw(data: &MapData, title: &str) -> String {
    if data.nodes.is_empty() {
        return empty(title);
    }
    let rates = Rates::new(data);
    let marks = MarkScale::new(data);
    let content: Vec<f64> = data
        .nodes
        .iter()
        .enumerate()
        .map(|(i, node)| content_width(node, &rates.node_label(i)))
        .collect();
    let routes: Vec<Route> = data.edges.iter().map(|e| Route::of(data, e)).collect();
    let dip = if routes.contains(&Route::Back) {
        70.0
    } else {
        0.0
    };
    let layout = Layout::new(data, &content, dip);
    let mut svg = header(title, layout.width, layout.height);
    subtitle(&mut svg, data, &rates, layout.width);
    let attach = attachments(data, &layout, &routes);
    rails(&mut svg, data, &layout, &routes, &attach, &rates);
    for (i, node) in data.nodes.iter().enumerate() {
        let bar = layout.column_of[i].is_none();
        place(&mut svg, i, node, layout.boxes[i], bar, &rates, &marks);
    }
    legend(&mut svg, data, &rates, &marks, layout.legend_top);
    svg.push_str("</svg>\n");
    svg
}

/// A number for the SVG: one decimal, and never NaN or infinite.
fn n(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.1}")
    } else {
        "0".into()
    }
}

/// A rate or an hour count as a reader wants it: whole above 10, else a few decimals, no
/// trailing zeros.
fn amount(v: f64) -> String {
    if !v.is_finite() || v <= 0.0 {
        return "0".into();
    }
    if v < 0.005 {
        // Some trolleys, too few to show in two decimals: not "0".
        return "< 0.01".into();
    }
    let s = if v >= 10.0 {
        format!("{v:.0}")
    } else if v >= 1.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    };
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').into()
    } else {
        s
    }
}

/// A count as a mark's number: whole below 100 000, else three digits and a unit
/// (`123k`, `4.56M`, `18.4E`), so that a huge count does not widen its column.
fn count_text(count: u64) -> String {
    if count < 100_000 {
        return count.to_string();
    }
    let units = ["k", "M", "G", "T", "P", "E"];
    let mut value = count as f64 / 1000.0;
    let mut unit = 0;
    while value >= 999.5 && unit + 1 < units.len() {
        value /= 1000.0;
        unit += 1;
    }
    let digits = if value >= 99.95 {
        0
    } else if value >= 9.995 {
        1
    } else {
        2
    };
    format!("{value:.digits$}{}", units[unit])
}

/// `s` as XML text or attribute value: markup escaped, and the characters XML 1.0 cannot
/// carry at all (control characters but tab and line ends, U+FFFE, U+FFFF) shown as U+FFFD.
fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\t' | '\n' | '\r' => out.push(c),
            c if c.is_control() || c == '\u{FFFE}' || c == '\u{FFFF}' => out.push('\u{FFFD}'),
            c => out.push(c),
        }
    }
    out
}

/// Estimated width of `text` at `font` px: each glyph's width in em, a little over DejaVu
/// Sans' (the usual sans-serif where SVGs are turned into PNGs), so that text stays in its box.
fn text_w(text: &str, font: f64, bold: bool) -> f64 {
    let em: f64 = text
        .chars()
        .map(|c| match c {
            ' ' | 'i' | 'j' | 'l' | '!' | '.' | ',' | ':' | ';' | '\'' | '|' => 0.36,
            'f' | 'r' | 't' | 'I' | 'J' | '(' | ')' | '[' | ']' | '-' | '/' => 0.48,
            'm' | 'w' => 1.0,
            'M' | 'W' => 1.08,
            '0'..='9' | 'a'..='z' => 0.66,
            'A'..='Z' | '#' | '%' | '&' | '<' | '>' | '?' | '@' => 0.8,
            c if c.is_ascii() => 0.66,
            // Beyond ASCII: up to a full em (CJK), so reckon with one.
            _ => 1.0,
        })
        .sum();
    em * font * if bold { 1.1 } else { 1.0 }
}

/// Trolleys per hour on every rail and through every place, and the width scale.
struct Rates {
    /// Hours are known (finite, above 0) and every rate came out finite.
    known: bool,
    edge: Vec<f64>,
    node: Vec<f64>,
    /// The rate drawn [`MAX_W`] wide: a round number at least the largest rate.
    scale: f64,
}

impl Rates {
    fn new(data: &MapData) -> Self {
        let n = data.nodes.len();
        let hours = data.hours;
        let valid = |e: &&MapEdge| e.from < n && e.to < n && e.from != e.to;
        let edge: Vec<f64> = data
            .edges
            .iter()
            .map(|e| e.trolleys as f64 / hours)
            .collect();
        let mut into = vec![0.0; n];
        let mut out = vec![0.0; n];
        let mut has_in = vec![false; n];
        for (e, r) in data.edges.iter().zip(&edge) {
            if valid(&e) {
                out[e.from] += r;
                into[e.to] += r;
                has_in[e.to] = true;
            }
        }
        // A loading station, or a place fed from nowhere, shows what it sent; every other
        // place what reached it.
        let node: Vec<f64> = (0..n)
            .map(|i| {
                if has_in[i] && data.nodes[i].kind != NodeKind::Loading {
                    into[i]
                } else {
                    out[i]
                }
            })
            .collect();
        let known =
            hours.is_finite() && hours > 0.0 && edge.iter().chain(&node).all(|r| r.is_finite());
        if !known {
            return Self {
                known,
                edge: vec![0.0; edge.len()],
                node: vec![0.0; n],
                scale: 1.0,
            };
        }
        // The return rail's trunks carry sums, so the scale covers the places' totals too.
        let largest = edge.iter().chain(&node).copied().fold(0.0, f64::max);
        Self {
            known,
            edge,
            node,
            scale: nice_ceiling(largest),
        }
    }

    /// Rail width for `rate` trolleys per hour: linear, so more trolleys never draw thinner.
    fn width(&self, rate: f64) -> f64 {
        if !(self.known && rate > 0.0) {
            return 1.0;
        }
        (MIN_W + (MAX_W - MIN_W) * rate / self.scale).min(MAX_W)
    }

    fn label(&self, rate: f64) -> String {
        if self.known {
            format!("{} /h", amount(rate))
        } else {
            "no time".into()
        }
    }

    fn node_label(&self, i: usize) -> String {
        self.label(self.node[i])
    }
}

/// A round number at least `max` (1, 1.2, 1.5, 2, 2.5, 3, 4, 5, 6 or 8 times a power of ten),
/// close enough that the busiest rail is drawn nearly full width; 1 for nothing.
fn nice_ceiling(max: f64) -> f64 {
    if !(max.is_finite() && max > 0.0) {
        return 1.0;
    }
    let exponent = max.log10().floor();
    // Dividing by a power of ten keeps 0.3 at 0.3 (0.1 × 3 would be 0.30000000000000004).
    let at = |m: f64| {
        if exponent >= 0.0 {
            m * 10f64.powf(exponent)
        } else {
            m / 10f64.powf(-exponent)
        }
    };
    [1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0]
        .into_iter()
        .map(at)
        .find(|v| *v >= max)
        .unwrap_or(max)
}

/// What a mark in a place's box counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mark {
    /// Sacks that ended up here but were meant for somewhere else: a red circle.
    Misdelivered,
    /// Trolleys this reader sent to the manual station: an orange square.
    Rejected,
}

impl Mark {
    const ALL: [Mark; 2] = [Mark::Misdelivered, Mark::Rejected];

    /// The word in the mark's id (`misdelivered-7`).
    fn name(self) -> &'static str {
        match self {
            Self::Misdelivered => "misdelivered",
            Self::Rejected => "rejected",
        }
    }

    /// The mark's fill, and the darker ink of its number (readable on a pale box).
    fn colours(self) -> (&'static str, &'static str) {
        match self {
            Self::Misdelivered => ("#d62728", "#a01515"),
            Self::Rejected => ("#ff7f0e", "#b35300"),
        }
    }

    /// What it counts, for the legend and the tooltips.
    fn words(self) -> &'static str {
        match self {
            Self::Misdelivered => "sacks misdelivered here",
            Self::Rejected => "trolleys a reader rejected to the manual station",
        }
    }

    fn count(self, node: &MapNode) -> u64 {
        match self {
            Self::Misdelivered => node.misdelivered,
            Self::Rejected => node.rejected,
        }
    }
}

/// The largest count of each mark on the map, which gets the largest marker.
struct MarkScale {
    misdelivered: u64,
    rejected: u64,
}

impl MarkScale {
    fn new(data: &MapData) -> Self {
        let largest = |mark: Mark| data.nodes.iter().map(|n| mark.count(n)).max().unwrap_or(0);
        Self {
            misdelivered: largest(Mark::Misdelivered),
            rejected: largest(Mark::Rejected),
        }
    }

    /// Radius of `mark`'s marker for `count`: its area grows with the count, the largest on
    /// the map drawn [`MARK_R`].
    fn radius(&self, mark: Mark, count: u64) -> f64 {
        let max = match mark {
            Mark::Misdelivered => self.misdelivered,
            Mark::Rejected => self.rejected,
        };
        let share = if max == 0 {
            0.0
        } else {
            count as f64 / max as f64
        };
        4.0 + (MARK_R - 4.0) * share.min(1.0).sqrt()
    }
}

/// The marks a place shows, with their counts.
fn marks_of(node: &MapNode) -> impl Iterator<Item = (Mark, u64)> + '_ {
    Mark::ALL
        .into_iter()
        .map(|mark| (mark, mark.count(node)))
        .filter(|m| m.1 > 0)
}

/// Width a place's box needs: name over rate, then its marks with their numbers.
fn content_width(node: &MapNode, rate: &str) -> f64 {
    let text = text_w(&node.name, NAME_FONT, true).max(text_w(rate, SMALL_FONT, false));
    let marks: f64 = marks_of(node)
        .map(|(_, count)| 2.0 * MARK_R + 4.0 + text_w(&count_text(count), COUNT_FONT, true) + 8.0)
        .sum();
    PAD + text + 12.0 + marks + PAD
}

/// The maps of the two runs of one plant run in one picture, the voting run above the
/// parity-only run: the same traffic, so what differs is what the readers' decisions did.
/// Each map is [`draw`]n whole, with its own title, and placed as a nested `<svg>`.
pub fn draw_runs(voting: &MapData, parity_only: &MapData, title: &str) -> String {
    let top = draw(voting, &format!("{title}: voting over the scans"));
    let bottom = draw(parity_only, &format!("{title}: parity only (the source)"));
    let (w1, h1) = size_of(&top);
    let (w2, h2) = size_of(&bottom);
    let width = w1.max(w2);
    let height = h1 + h2;
    let mut svg = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}">
<rect width="100%" height="100%" fill="white"/>
"#,
        w = n(width),
        h = n(height),
    );
    svg.push_str(&nested(&top, 0.0));
    svg.push_str(&nested(&bottom, h1));
    svg.push_str("</svg>\n");
    svg
}

/// The `width` and `height` of an SVG that [`draw`] wrote (0 where they cannot be read).
fn size_of(svg: &str) -> (f64, f64) {
    let head = svg.split('>').next().unwrap_or("");
    let attr = |name: &str| {
        head.split(&format!(" {name}=\""))
            .nth(1)
            .and_then(|rest| rest.split('"').next())
            .and_then(|v| v.parse::<f64>().ok())
            .filter(|v| v.is_finite() && *v >= 0.0)
            .unwrap_or(0.0)
    };
    (attr("width"), attr("height"))
}

/// `svg` placed `y` down in a larger picture: its root element gains `y="…"`.
fn nested(svg: &str, y: f64) -> String {
    svg.replacen("<svg ", &format!("<svg y=\"{}\" ", n(y)), 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_stay_short() {
        for (count, text) in [
            (0, "0"),
            (99_999, "99999"),
            (100_000, "100k"),
            (123_456, "123k"),
            (999_499, "999k"),
            (999_500, "1.00M"),
            (4_560_000, "4.56M"),
            (u64::MAX, "18.4E"),
        ] {
            assert_eq!(count_text(count), text, "{count}");
        }
        for count in (0..64).map(|b| 1u64 << b).chain([u64::MAX, 999_999_999]) {
            assert!(
                count_text(count).len() <= 6,
                "{count}: {}",
                count_text(count)
            );
        }
    }

    #[test]
    fn wide_letters_are_reckoned_wide() {
        assert!(text_w("WWW", 10.0, false) > 3.0 * 10.0);
        assert!(text_w("iii", 10.0, false) < text_w("eee", 10.0, false));
        assert!(text_w("E10", 15.0, true) > text_w("E10", 15.0, false));
        assert!(text_w("郵便", 10.0, false) >= 20.0);
        assert_eq!(text_w("", 10.0, true), 0.0);
    }

    #[test]
    fn rates_read_as_people_write_them() {
        assert_eq!(amount(103.4), "103");
        assert_eq!(amount(5.0), "5");
        assert_eq!(amount(6.25), "6.2");
        assert_eq!(amount(0.25), "0.25");
        assert_eq!(amount(0.001), "< 0.01");
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(amount(bad), "0");
        }
        assert_eq!(n(f64::NAN), "0");
        assert_eq!(n(f64::NEG_INFINITY), "0");
    }

    #[test]
    fn the_scale_is_round_and_close_above_the_busiest_rail() {
        assert_eq!(nice_ceiling(103.0), 120.0);
        assert_eq!(nice_ceiling(100.0), 100.0);
        assert_eq!(nice_ceiling(0.3), 0.3);
        assert_eq!(nice_ceiling(0.0), 1.0);
        assert_eq!(nice_ceiling(f64::NAN), 1.0);
        for max in [0.07, 1.0, 9.9, 41.0, 1e6, 3.3e17] {
            let scale = nice_ceiling(max);
            assert!(scale >= max && scale <= max * 1.25, "{max} → {scale}");
        }
    }

    #[test]
    fn two_runs_stack_in_one_picture() {
        let map = MapData {
            hours: 1.0,
            ..MapData::default()
        };
        let one = draw(&map, "x");
        let (w, h) = size_of(&one);
        assert!(w > 0.0 && h > 0.0, "{w} {h}");
        let both = draw_runs(&map, &map, "x");
        let (w2, h2) = size_of(&both);
        assert_eq!((w2, h2), (w, 2.0 * h));
        assert_eq!(both.matches("<svg ").count(), 3);
        assert!(both.contains(&format!("<svg y=\"{}\" ", n(h))));
        assert!(both.contains("x: voting over the scans"));
        assert!(both.contains("x: parity only (the source)"));
    }
}
