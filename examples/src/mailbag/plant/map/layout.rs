//! Where each place of the plant map goes: one column per `layer` (loading stations left,
//! downstream to the right), the nodes of a column ordered to follow their upstream places
//! (fewer crossing rails), the return rail as a bar along the bottom, the legend under it; and
//! how each rail runs between them.

use super::super::map_data::{MapData, MapEdge, NodeKind};

/// Height of a place's box.
pub(super) const BOX_H: f64 = 40.0;
/// Free space between two boxes of a column.
pub(super) const ROW_GAP: f64 = 14.0;
/// Free space between two columns, where the rails run: as much as fits a picture about
/// 1 500 px wide, within these bounds.
const GUTTER: (f64, f64) = (80.0, 130.0);
/// The width the gutters are chosen for: close to the 1 200 px a PNG of the map is made at.
const TARGET_WIDTH: f64 = 1500.0;
/// Margin left and right of the outer columns (the return rail's branches run there).
const MARGIN: f64 = 75.0;
/// Where the columns start: under the title and the subtitle.
pub(super) const GRAPH_TOP: f64 = 100.0;
/// Height of the return rail's bar.
pub(super) const BAR_H: f64 = 30.0;
/// The legend: three rows.
pub(super) const LEGEND_H: f64 = 130.0;
/// The narrowest picture: the legend's widest row needs this.
pub(super) const MIN_WIDTH: f64 = 1080.0;

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Rect {
    pub x: f64,
    pub y: f64,
    pub w: f64,
    pub h: f64,
}

impl Rect {
    pub fn right(self) -> f64 {
        self.x + self.w
    }
    pub fn bottom(self) -> f64 {
        self.y + self.h
    }
    pub fn mid_y(self) -> f64 {
        self.y + self.h / 2.0
    }
    pub fn mid_x(self) -> f64 {
        self.x + self.w / 2.0
    }
}

/// A column of places.
#[derive(Clone, Debug)]
pub(super) struct Column {
    /// Left edge of its boxes.
    pub x: f64,
    /// Width of its boxes (all the same, the widest content's).
    pub w: f64,
    /// Its nodes, top to bottom.
    pub nodes: Vec<usize>,
}

impl Column {
    pub fn right(&self) -> f64 {
        self.x + self.w
    }
}

/// The whole picture's geometry.
#[derive(Clone, Debug)]
pub(super) struct Layout {
    /// Each node's box (a return node's is its bar).
    pub boxes: Vec<Rect>,
    /// Each node's column, `None` for return nodes.
    pub column_of: Vec<Option<usize>>,
    /// The columns, left to right.
    pub columns: Vec<Column>,
    /// Bottom of the tallest column.
    pub graph_bottom: f64,
    /// Top of the legend.
    pub legend_top: f64,
    /// The picture's size.
    pub width: f64,
    pub height: f64,
}

/// The return rail drawn as the bar along the bottom: the first place of kind
/// [`NodeKind::Return`]. The plant has one; any further one is drawn as an ordinary place in its
/// layer's column, so that no rail has to cross a bar to reach another.
pub(super) fn return_rail(data: &MapData) -> Option<usize> {
    data.nodes.iter().position(|n| n.kind == NodeKind::Return)
}

impl Layout {
    /// Lays out `data`'s nodes, each as wide as `content_w[node]` asks; `dip` is the room
    /// under the columns for rails that run backwards.
    pub fn new(data: &MapData, content_w: &[f64], dip: f64) -> Self {
        let n = data.nodes.len();
        let bar = return_rail(data);
        let is_return = |i: usize| Some(i) == bar;
        let mut layers: Vec<u8> = (0..n)
            .filter(|&i| !is_return(i))
            .map(|i| data.nodes[i].layer)
            .collect();
        layers.sort_unstable();
        layers.dedup();
        let column_of: Vec<Option<usize>> = (0..n)
            .map(|i| {
                (!is_return(i))
                    .then(|| layers.binary_search(&data.nodes[i].layer).ok())
                    .flatten()
            })
            .collect();
        let mut columns: Vec<Column> = layers
            .iter()
            .enumerate()
            .map(|(c, _)| Column {
                x: 0.0,
                w: (0..n)
                    .filter(|&i| column_of[i] == Some(c))
                    .map(|i| content_w[i])
                    .fold(0.0, f64::max),
                nodes: (0..n).filter(|&i| column_of[i] == Some(c)).collect(),
            })
            .collect();
        order_by_upstream(data, &column_of, &mut columns);

        let tallest = columns.iter().map(|c| c.nodes.len()).max().unwrap_or(0);
        let column_h = |k: usize| k as f64 * (BOX_H + ROW_GAP) - ROW_GAP;
        let graph_h = column_h(tallest).max(0.0);
        let boxes_w: f64 = columns.iter().map(|c| c.w).sum();
        let gaps = columns.len().saturating_sub(1) as f64;
        let gutter = if gaps > 0.0 {
            ((TARGET_WIDTH - 2.0 * MARGIN - boxes_w) / gaps).clamp(GUTTER.0, GUTTER.1)
        } else {
            GUTTER.1
        };
        let content_w = MARGIN * 2.0 + boxes_w + gutter * gaps;
        let width = content_w.max(MIN_WIDTH).ceil();
        let mut x = (width - content_w) / 2.0 + MARGIN;
        let mut boxes = vec![
            Rect {
                x: 0.0,
                y: 0.0,
                w: 0.0,
                h: 0.0
            };
            n
        ];
        for column in &mut columns {
            column.x = x;
            let top = GRAPH_TOP + (graph_h - column_h(column.nodes.len())) / 2.0;
            for (row, &i) in column.nodes.iter().enumerate() {
                boxes[i] = Rect {
                    x,
                    y: top + row as f64 * (BOX_H + ROW_GAP),
                    w: column.w,
                    h: BOX_H,
                };
            }
            x += column.w + gutter;
        }
        let graph_bottom = GRAPH_TOP + graph_h;
        // The return rail's bar spans the columns and the margins where its branches run.
        let (left, right) = match (columns.first(), columns.last()) {
            (Some(first), Some(last)) => (first.x - MARGIN + 10.0, last.right() + MARGIN - 10.0),
            _ => (MARGIN, width - MARGIN),
        };
        let mut bottom = graph_bottom + dip;
        if let Some(i) = bar {
            boxes[i] = Rect {
                x: left,
                y: bottom + 55.0,
                w: right - left,
                h: BAR_H,
            };
            bottom = boxes[i].bottom();
        }
        let legend_top = bottom + 65.0;
        Self {
            boxes,
            column_of,
            columns,
            graph_bottom,
            legend_top,
            width,
            height: (legend_top + LEGEND_H).ceil(),
        }
    }
}

/// Orders each column's nodes: the places of one kind together and in their data order
/// (`A1, A2, A3`), the kinds by where their upstream places sit (the mean of their relative
/// positions), so that rails run roughly level; places fed from nowhere go below the rest.
fn order_by_upstream(data: &MapData, column_of: &[Option<usize>], columns: &mut [Column]) {
    let n = data.nodes.len();
    let mut position = vec![0.5; n];
    for (c, column) in columns.iter_mut().enumerate() {
        // Per node: (sum, count) of its upstream places' positions.
        let mut upstream = vec![(0.0, 0.0); n];
        for e in &data.edges {
            if e.from < n && e.to < n && matches!(column_of[e.from], Some(k) if k < c) {
                upstream[e.to].0 += position[e.from];
                upstream[e.to].1 += 1.0;
            }
        }
        let nodes = &column.nodes;
        let kind_key = |kind: NodeKind| {
            let (sum, count) = nodes
                .iter()
                .filter(|&&i| data.nodes[i].kind == kind)
                .fold((0.0, 0.0), |(s, k), &i| {
                    (s + upstream[i].0, k + upstream[i].1)
                });
            if count > 0.0 { sum / count } else { 2.0 }
        };
        let mut keyed: Vec<(f64, u8, usize)> = column
            .nodes
            .iter()
            .map(|&i| {
                let kind = data.nodes[i].kind;
                (kind_key(kind), kind as u8, i)
            })
            .collect();
        keyed.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
        column.nodes = keyed.into_iter().map(|(_, _, i)| i).collect();
        let len = column.nodes.len() as f64;
        for (row, &i) in column.nodes.iter().enumerate() {
            position[i] = (row as f64 + 0.5) / len;
        }
    }
}

/// How a rail is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Route {
    /// Rightwards, from column to column.
    Forward,
    /// Back or within a column: a loop under the columns.
    Back,
    /// Into the return rail, by the trunk right of its place's column.
    IntoReturn,
    /// Out of the return rail, by the trunk left of its place's column.
    FromReturn,
    /// Not drawn: an end is missing, or a loop on one place.
    Skip,
}

impl Route {
    pub(super) fn of(data: &MapData, e: &MapEdge) -> Self {
        let (Some(from), Some(to)) = (data.nodes.get(e.from), data.nodes.get(e.to)) else {
            return Self::Skip;
        };
        let bar = return_rail(data);
        match (Some(e.from) == bar, Some(e.to) == bar) {
            _ if e.from == e.to => Self::Skip,
            // Only a loop on the bar, caught above.
            (true, true) => Self::Skip,
            (false, true) => Self::IntoReturn,
            (true, false) => Self::FromReturn,
            (false, false) if to.layer > from.layer => Self::Forward,
            (false, false) => Self::Back,
        }
    }
}

/// Where each rail leaves and enters its places: `(start y, end y)`, spread over the box's
/// side in the order of the other ends, so that rails fan out instead of piling up.
pub(super) fn attachments(data: &MapData, layout: &Layout, routes: &[Route]) -> Vec<(f64, f64)> {
    let boxes = &layout.boxes;
    let mut ends: Vec<(f64, f64)> = data
        .edges
        .iter()
        .map(|e| {
            let mid = |i: usize| boxes.get(i).map_or(0.0, |b| b.mid_y());
            (mid(e.from), mid(e.to))
        })
        .collect();
    // Each node's two sides: the rails leaving on its right, those entering on its left, each
    // with the height of its other end (rails that loop back under the columns lowest).
    let n = data.nodes.len();
    let mut sides: Vec<[Vec<(f64, usize)>; 2]> = vec![[Vec::new(), Vec::new()]; n];
    for (k, e) in data.edges.iter().enumerate() {
        let back = routes[k] == Route::Back;
        let other = |i: usize| if back { f64::MAX } else { boxes[i].mid_y() };
        if matches!(routes[k], Route::Forward | Route::IntoReturn | Route::Back) {
            sides[e.from][0].push((other(e.to), k));
        }
        if matches!(routes[k], Route::Forward | Route::FromReturn | Route::Back) {
            sides[e.to][1].push((other(e.from), k));
        }
    }
    for (i, [leaving, entering]) in sides.iter_mut().enumerate() {
        for (side, out) in [(leaving, true), (entering, false)] {
            side.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let count = side.len() as f64;
            let step = if side.len() > 1 {
                ((BOX_H - 12.0) / (count - 1.0)).min(7.0)
            } else {
                0.0
            };
            for (rank, &(_, k)) in side.iter().enumerate() {
                let y = boxes[i].mid_y() + (rank as f64 - (count - 1.0) / 2.0) * step;
                if out {
                    ends[k].0 = y;
                } else {
                    ends[k].1 = y;
                }
            }
        }
    }
    ends
}
