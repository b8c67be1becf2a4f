//! The SVG text of the plant map, in the order it is painted: title, rails, places with their
//! marks, legend.

use std::fmt::Write as _;

use super::super::map_data::{MapData, MapNode, NodeKind};
use super::layout::{BAR_H, BOX_H, Layout, MIN_WIDTH, ROW_GAP, Rect};
use super::{
    ALARM, COUNT_FONT, LEGEND_FONT, MARK_R, Mark, MarkScale, NAME_FONT, PAD, RAIL, Rates, Route,
    SMALL_FONT, TITLE_FONT, amount, count_text, escape, marks_of, n, nice_ceiling, text_w,
};

/// The pale fill of each kind of place, and what the legend calls it.
fn kind_style(kind: NodeKind) -> (&'static str, &'static str) {
    match kind {
        NodeKind::Loading => ("#cfe2f3", "loading station"),
        NodeKind::Reader => ("#ffffff", "code reader + switch"),
        NodeKind::Buffer => ("#d0ece7", "buffer lane"),
        NodeKind::Emptying => ("#dcedc8", "emptying station"),
        NodeKind::Dock => ("#d9d2e9", "dock chain"),
        NodeKind::Manual => ("#eadfcf", "manual station"),
        NodeKind::Return => ("#dddddd", "return rail"),
    }
}

const KINDS: [NodeKind; 7] = [
    NodeKind::Loading,
    NodeKind::Reader,
    NodeKind::Buffer,
    NodeKind::Emptying,
    NodeKind::Dock,
    NodeKind::Manual,
    NodeKind::Return,
];

pub(super) fn header(title: &str, width: f64, height: f64) -> String {
    // A long title is set smaller rather than cut.
    let size =
        TITLE_FONT.min(TITLE_FONT * (width - 40.0) / text_w(title, TITLE_FONT, true).max(1.0));
    format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="{SMALL_FONT}">
<rect width="100%" height="100%" fill="white"/>
<text x="{}" y="36" text-anchor="middle" font-size="{}" font-weight="bold">{}</text>
"#,
        n(width / 2.0),
        n(size),
        escape(title),
        w = n(width),
        h = n(height),
    )
}

/// A picture for a map with no places.
pub(super) fn empty(title: &str) -> String {
    let mut svg = header(title, MIN_WIDTH, 200.0);
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="110" text-anchor="middle" font-size="{LEGEND_FONT}">No places to draw: the run's map data is empty.</text>"#,
        n(MIN_WIDTH / 2.0)
    );
    svg.push_str("</svg>\n");
    svg
}

/// One line under the title: what the widths mean and what went wrong where.
pub(super) fn subtitle(svg: &mut String, data: &MapData, rates: &Rates, width: f64) {
    // Saturating: counts near u64::MAX must not wrap or panic.
    let total =
        |count: fn(&MapNode) -> u64| data.nodes.iter().map(count).fold(0u64, u64::saturating_add);
    let misdelivered = total(|n| n.misdelivered);
    let rejected = total(|n| n.rejected);
    let alarms = data.nodes.iter().filter(|n| n.alarm).count();
    let time = if rates.known {
        format!(
            "rail width: trolleys per hour over {} h",
            amount(data.hours)
        )
    } else {
        "no simulated time: trolleys per hour unknown, rails drawn thin".into()
    };
    let text = format!(
        "{time} · {misdelivered} sacks misdelivered · {rejected} trolleys rejected · {alarms} alarm{} on",
        if alarms == 1 { "" } else { "s" }
    );
    // Huge counts make a long line: it is set smaller rather than run off the picture.
    let size =
        LEGEND_FONT.min(LEGEND_FONT * (width - 40.0) / text_w(&text, LEGEND_FONT, false).max(1.0));
    let _ = writeln!(
        svg,
        r##"<text x="{}" y="62" text-anchor="middle" font-size="{}" fill="#333">{}</text>"##,
        n(width / 2.0),
        n(size),
        escape(&text)
    );
}

/// Every rail, under the places.
pub(super) fn rails(
    svg: &mut String,
    data: &MapData,
    layout: &Layout,
    routes: &[Route],
    attach: &[(f64, f64)],
    rates: &Rates,
) {
    let boxes = &layout.boxes;
    let name = |i: usize| escape(&data.nodes[i].name);
    let mut trunks: Vec<Trunk> = Vec::new();
    for (k, e) in data.edges.iter().enumerate() {
        let rate = rates.edge[k];
        let (y0, y1) = attach[k];
        let d = match routes[k] {
            Route::Skip => continue,
            Route::Forward => forward_path(layout, e.from, y0, e.to, y1),
            Route::Back => {
                // Out to the right, down under the columns, back left, up into the target's
                // left side: through the gutters, never across a box.
                let (a, b) = (boxes[e.from], boxes[e.to]);
                let low = layout.graph_bottom + 35.0;
                format!(
                    "M{} {} H{} V{} H{} V{} H{}",
                    n(a.right()),
                    n(y0),
                    n(a.right() + 12.0),
                    n(low),
                    n(b.x - 12.0),
                    n(y1),
                    n(b.x)
                )
            }
            Route::IntoReturn | Route::FromReturn => {
                let into = routes[k] == Route::IntoReturn;
                let (place, bar) = if into { (e.from, e.to) } else { (e.to, e.from) };
                let Some(column) = layout.column_of[place] else {
                    continue;
                };
                let y = if into { y0 } else { y1 };
                let key = (column, bar, into);
                let branch = (y, rate, e.trolleys);
                match trunks.iter_mut().find(|t| t.key == key) {
                    Some(t) => t.branches.push(branch),
                    None => trunks.push(Trunk {
                        key,
                        branches: vec![branch],
                    }),
                }
                let x = trunk_x(layout, column, into);
                let b = boxes[place];
                let side = if into { b.right() } else { b.x };
                format!("M{} {} H{}", n(side), n(y), n(x))
            }
        };
        let _ = writeln!(
            svg,
            r#"<path id="rail-{k}" d="{d}" {}><title>{} → {}: {} ({} trolleys)</title></path>"#,
            stroke(rates, rate, e.trolleys > 0),
            name(e.from),
            name(e.to),
            rates.label(rate),
            e.trolleys
        );
    }
    for Trunk {
        key: (column, bar, into),
        mut branches,
    } in trunks
    {
        branches.sort_by(|a, b| a.0.total_cmp(&b.0));
        let x = trunk_x(layout, column, into);
        let bar_y = boxes[bar].y;
        let (mut carried, mut used) = (0.0, false);
        for (i, &(y, rate, trolleys)) in branches.iter().enumerate() {
            carried += rate;
            used |= trolleys > 0;
            let next = branches.get(i + 1).map_or(bar_y, |b| b.0);
            let _ = writeln!(
                svg,
                r#"<path class="trunk" d="M{x} {} V{}" {} stroke-linecap="square"><title>return rail: {}</title></path>"#,
                n(y),
                n(next),
                stroke(rates, carried, used),
                rates.label(carried),
                x = n(x),
            );
        }
    }
}

/// A vertical of the return rail beside a column, joining its places' branches to the bar.
struct Trunk {
    /// (column, return node, into the bar rather than out of it).
    key: (usize, usize, bool),
    /// (attach y, trolleys per hour, trolleys) of each branch.
    branches: Vec<(f64, f64, u64)>,
}

/// Where the return rail's trunk of `column` runs: right of it (into the bar) or left of it.
fn trunk_x(layout: &Layout, column: usize, into: bool) -> f64 {
    let c = &layout.columns[column];
    if into { c.right() + 24.0 } else { c.x - 24.0 }
}

/// The stroke of a rail carrying `rate`: width by rate, dashed when no trolley `used` it.
fn stroke(rates: &Rates, rate: f64, used: bool) -> String {
    let dash = if used {
        ""
    } else {
        r#" stroke-dasharray="5 4""#
    };
    format!(
        r#"fill="none" stroke="{RAIL}" stroke-width="{}"{dash}"#,
        n(rates.width(rate))
    )
}

/// A rail to a column further right: level through the gaps of the columns it crosses, with
/// smooth bends between.
fn forward_path(layout: &Layout, from: usize, y0: f64, to: usize, y1: f64) -> String {
    let (a, b) = (layout.boxes[from], layout.boxes[to]);
    let mut points = vec![(a.right(), y0)];
    if let (Some(c0), Some(c1)) = (layout.column_of[from], layout.column_of[to]) {
        for c in c0 + 1..c1 {
            let column = &layout.columns[c];
            let share = (column.x - a.right()) / (b.x - a.right()).max(1.0);
            let y = gap_near(layout, c, y0 + (y1 - y0) * share);
            points.push((column.x - 8.0, y));
            points.push((column.right() + 8.0, y));
        }
    }
    points.push((b.x, y1));
    let mut d = format!("M{} {}", n(points[0].0), n(points[0].1));
    for pair in points.windows(2) {
        let ((x0, y0), (x1, y1)) = (pair[0], pair[1]);
        if (y1 - y0).abs() < 0.05 {
            let _ = write!(d, " H{}", n(x1));
        } else {
            let mid = (x0 + x1) / 2.0;
            let _ = write!(
                d,
                " C{} {} {} {} {} {}",
                n(mid),
                n(y0),
                n(mid),
                n(y1),
                n(x1),
                n(y1)
            );
        }
    }
    d
}

/// The free row of column `c` (between two boxes, above the first, below the last) nearest `y`.
fn gap_near(layout: &Layout, c: usize, y: f64) -> f64 {
    let boxes: Vec<Rect> = layout.columns[c]
        .nodes
        .iter()
        .map(|&i| layout.boxes[i])
        .collect();
    let mut gaps = Vec::with_capacity(boxes.len() + 1);
    if let Some(first) = boxes.first() {
        gaps.push(first.y - ROW_GAP / 2.0 - 4.0);
    }
    gaps.extend(boxes.windows(2).map(|w| (w[0].bottom() + w[1].y) / 2.0));
    if let Some(last) = boxes.last() {
        gaps.push(last.bottom() + ROW_GAP / 2.0 + 4.0);
    }
    gaps.into_iter()
        .min_by(|a, b| (a - y).abs().total_cmp(&(b - y).abs()))
        .unwrap_or(y)
}

/// A place (or the return rail's `bar`): its box in its kind's fill, name over rate, marks right-aligned, alarm on its
/// top edge near the right, clear of the rails and the name.
pub(super) fn place(
    svg: &mut String,
    i: usize,
    node: &MapNode,
    b: Rect,
    bar: bool,
    rates: &Rates,
    marks: &MarkScale,
) {
    let (fill, kind) = kind_style(node.kind);
    let label = rates.node_label(i);
    let name = escape(&node.name);
    let _ = writeln!(
        svg,
        r##"<rect id="node-{i}" x="{}" y="{}" width="{}" height="{}" rx="5" fill="{fill}" stroke="#555"><title>{name} ({kind}): {label}</title></rect>"##,
        n(b.x),
        n(b.y),
        n(b.w),
        n(b.h)
    );
    if bar {
        // The bar: name and rate side by side in its middle.
        let _ = writeln!(
            svg,
            r##"<text x="{}" y="{}" text-anchor="middle" font-size="{NAME_FONT}"><tspan font-weight="bold">{name}</tspan><tspan fill="#333" font-size="{SMALL_FONT}" dx="10">{label}</tspan></text>"##,
            n(b.mid_x()),
            n(b.y + BAR_H / 2.0 + 5.0),
        );
    } else {
        let _ = writeln!(
            svg,
            r##"<text x="{}" y="{}" font-size="{NAME_FONT}" font-weight="bold">{name}</text><text x="{}" y="{}" fill="#333">{label}</text>"##,
            n(b.x + PAD),
            n(b.y + 17.0),
            n(b.x + PAD),
            n(b.y + BOX_H - 8.0),
        );
    }
    let mut right = b.right() - PAD;
    let cy = b.mid_y();
    for (what, count) in marks_of(node) {
        let ink = what.colours().1;
        let number = count_text(count);
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{}" text-anchor="end" font-size="{COUNT_FONT}" font-weight="bold" fill="{ink}">{number}</text>"#,
            n(right),
            n(cy + 5.0)
        );
        right -= text_w(&number, COUNT_FONT, true) + 4.0 + MARK_R;
        let _ = writeln!(svg, "{}", mark(what, Some(i), right, cy, count, marks));
        right -= MARK_R + 8.0;
    }
    if node.alarm {
        let _ = writeln!(
            svg,
            "{}",
            alarm(&format!(r#" id="alarm-{i}""#), b.right() - 16.0, b.y)
        );
    }
}

/// A mark centred at (x, y): a circle for misdeliveries, a square for rejects; `node` gives
/// it its id (`misdelivered-7`), the legend's marks have none.
fn mark(what: Mark, node: Option<usize>, x: f64, y: f64, count: u64, marks: &MarkScale) -> String {
    let id = node.map_or(String::new(), |i| format!(r#" id="{}-{i}""#, what.name()));
    let (colour, _) = what.colours();
    let r = marks.radius(what, count);
    let title = format!("<title>{count} {}</title>", what.words());
    match what {
        Mark::Misdelivered => format!(
            r#"<circle{id} cx="{}" cy="{}" r="{}" fill="{colour}">{title}</circle>"#,
            n(x),
            n(y),
            n(r)
        ),
        // A square of about the circle's area.
        Mark::Rejected => format!(
            r#"<rect{id} x="{}" y="{}" width="{}" height="{}" fill="{colour}">{title}</rect>"#,
            n(x - 0.9 * r),
            n(y - 0.9 * r),
            n(1.8 * r),
            n(1.8 * r)
        ),
    }
}

/// A warning triangle with its tip at (x, y - 9).
fn alarm(id: &str, x: f64, y: f64) -> String {
    format!(
        r#"<g{id}><title>alarm on at the end of the run</title><path d="M{} {} L{} {} L{} {} Z" fill="{ALARM}" stroke="black" stroke-width="1.2"/><text x="{}" y="{}" text-anchor="middle" font-size="12" font-weight="bold">!</text></g>"#,
        n(x),
        n(y - 9.0),
        n(x - 9.0),
        n(y + 7.0),
        n(x + 9.0),
        n(y + 7.0),
        n(x),
        n(y + 5.5)
    )
}

/// The legend: rail widths, the kinds of place on this map, the marks.
pub(super) fn legend(svg: &mut String, data: &MapData, rates: &Rates, marks: &MarkScale, top: f64) {
    let x0 = 40.0;
    let text = |svg: &mut String, x: f64, y: f64, s: &str, bold: bool| -> f64 {
        let weight = if bold { r#" font-weight="bold""# } else { "" };
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{}" font-size="{LEGEND_FONT}"{weight}>{}</text>"#,
            n(x),
            n(y + 4.5),
            escape(s)
        );
        x + text_w(s, LEGEND_FONT, bold) + 14.0
    };
    // Row 1: the width scale.
    let y = top + 12.0;
    let mut x = text(svg, x0, y, "Rails", true);
    if rates.known {
        x = text(svg, x, y, "width = trolleys per hour:", false);
        // Round samples: a quarter and a half of the scale, rounded up, and the scale.
        let samples = [
            nice_ceiling(rates.scale * 0.25),
            nice_ceiling(rates.scale * 0.5),
            rates.scale,
        ];
        for rate in samples {
            let _ = writeln!(
                svg,
                r#"<path d="M{} {} h36" {}/>"#,
                n(x),
                n(y),
                stroke(rates, rate, true)
            );
            x = text(svg, x + 42.0, y, &rates.label(rate), false);
        }
    } else {
        x = text(
            svg,
            x,
            y,
            "no simulated time, so no rates: every rail drawn thin",
            false,
        );
    }
    let _ = writeln!(
        svg,
        r#"<path d="M{} {} h36" {}/>"#,
        n(x),
        n(y),
        stroke(rates, 0.0, false)
    );
    text(svg, x + 42.0, y, "no trolleys", false);

    // Row 2: the kinds of place present.
    let y = top + 44.0;
    let mut x = text(svg, x0, y, "Places", true);
    for kind in KINDS {
        if data.nodes.iter().any(|n| n.kind == kind) {
            let (fill, name) = kind_style(kind);
            let _ = writeln!(
                svg,
                r##"<rect x="{}" y="{}" width="26" height="16" rx="3" fill="{fill}" stroke="#555"/>"##,
                n(x),
                n(y - 8.0)
            );
            x = text(svg, x + 32.0, y, name, false);
        }
    }

    // Rows 3 and 4: the marks.
    let y = top + 76.0;
    let mut x = text(svg, x0, y, "Marks", true);
    for what in Mark::ALL {
        let largest = match what {
            Mark::Misdelivered => marks.misdelivered,
            Mark::Rejected => marks.rejected,
        };
        let _ = writeln!(
            svg,
            "{}",
            mark(what, None, x + MARK_R, y, largest.max(1), marks)
        );
        x = text(svg, x + 2.0 * MARK_R + 6.0, y, what.words(), false);
    }
    let _ = writeln!(svg, "{}", alarm("", x + 9.0, y));
    text(svg, x + 24.0, y, "alarm on at the end of the run", false);
    text(
        svg,
        x0 + text_w("Marks", LEGEND_FONT, true) + 14.0,
        top + 104.0,
        "a mark's area grows with its count (the largest on this map drawn biggest); the number is written beside it",
        false,
    );
}
