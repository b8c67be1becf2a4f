//! The plant map picture (`mailbag::plant::map::draw`): well-formed SVG, every place named,
//! rail widths that follow the trolleys, marks exactly where something went wrong, no NaN, no
//! overlapping boxes, an empty map that says so.
//!
//! Set `MAP_SVG_OUT=path.svg` to write the example plant's map there and look at it
//! (`rsvg-convert path.svg -w 1200 -o path.png`); `MAP_SVG_OUT_CROWDED` and
//! `MAP_SVG_OUT_BARE` write the crowded map and the one without rails or time.

use proptest::prelude::*;
use regler_examples::mailbag::plant::map::draw;
use regler_examples::mailbag::plant::map_data::{MapData, MapEdge, MapNode, NodeKind};

#[path = "mailbag_map/plants.rs"]
mod plants;
use plants::{crowded_plant, example_plant};

/// Checks that `svg` is well-formed XML with one `<svg>` root: tags nest and close, quotes
/// pair, every `&` starts an entity, no text outside the root.
fn assert_well_formed(svg: &str) {
    let mut open: Vec<&str> = Vec::new();
    let mut roots = 0;
    let mut rest = svg;
    while let Some(lt) = rest.find('<') {
        let text = &rest[..lt];
        assert_entities(text);
        assert!(
            !open.is_empty() || text.trim().is_empty(),
            "text outside the root: {text:?}"
        );
        rest = &rest[lt..];
        let gt = rest.find('>').expect("a tag that never closes");
        let tag = &rest[1..gt];
        rest = &rest[gt + 1..];
        assert_eq!(tag.matches('"').count() % 2, 0, "unpaired quote in <{tag}>");
        assert!(!tag.contains('<'), "'<' inside <{tag}>");
        assert_entities(tag);
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(
                open.pop(),
                Some(name.trim()),
                "</{name}> closes the wrong tag"
            );
            continue;
        }
        let name = tag
            .split(|c: char| c.is_whitespace() || c == '/')
            .next()
            .unwrap();
        assert!(
            !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric()),
            "bad tag name in <{tag}>"
        );
        if open.is_empty() {
            roots += 1;
            assert_eq!(name, "svg", "the root is <{name}>");
        }
        if !tag.ends_with('/') {
            open.push(name);
        }
    }
    assert!(rest.trim().is_empty(), "text after the root: {rest:?}");
    assert!(open.is_empty(), "never closed: {open:?}");
    assert_eq!(roots, 1);
}

fn assert_entities(text: &str) {
    // Characters XML 1.0 cannot carry, even escaped.
    assert!(
        !text
            .chars()
            .any(|c| (c.is_control() && !"\t\n\r".contains(c))
                || c == '\u{FFFE}'
                || c == '\u{FFFF}'),
        "a character XML forbids in {text:?}"
    );
    for (i, _) in text.match_indices('&') {
        let after = &text[i..];
        assert!(
            ["&amp;", "&lt;", "&gt;", "&quot;", "&apos;"]
                .iter()
                .any(|e| after.starts_with(e)),
            "a bare & in {text:?}"
        );
    }
}

/// The tag carrying `id="<id>"`, if there is one.
fn element<'a>(svg: &'a str, id: &str) -> Option<&'a str> {
    let at = svg.find(&format!(r#" id="{id}""#))?;
    let start = svg[..at].rfind('<')?;
    let end = at + svg[at..].find('>')?;
    Some(&svg[start..=end])
}

fn attr(tag: &str, name: &str) -> f64 {
    let key = format!(r#" {name}=""#);
    let at = tag
        .find(&key)
        .unwrap_or_else(|| panic!("no {name} in {tag}"))
        + key.len();
    let value = &tag[at..at + tag[at..].find('"').unwrap()];
    value
        .parse()
        .unwrap_or_else(|_| panic!("{name}={value:?} in {tag}"))
}

/// The drawn width of rail `k`, if it is drawn.
fn rail_width(svg: &str, k: usize) -> Option<f64> {
    element(svg, &format!("rail-{k}")).map(|tag| attr(tag, "stroke-width"))
}

/// Every box of the picture (places and the return rail's bars): (x, y, width, height).
fn all_boxes(svg: &str, map: &MapData) -> Vec<(f64, f64, f64, f64)> {
    (0..map.nodes.len())
        .map(|i| {
            let tag = element(svg, &format!("node-{i}")).unwrap();
            (
                attr(tag, "x"),
                attr(tag, "y"),
                attr(tag, "width"),
                attr(tag, "height"),
            )
        })
        .collect()
}

/// The straight and curved pieces of every rail's path, as the boxes they sweep:
/// (x from, x to, y from, y to). Paths use M, H, V and C (curves with their control points
/// between their ends, so they stay within the box of their ends).
fn rail_pieces(svg: &str) -> Vec<(f64, f64, f64, f64)> {
    let mut pieces = Vec::new();
    for path in svg.split("<path").skip(1) {
        if !(path.contains(r#" id="rail-"#) || path.contains(r#"class="trunk""#)) {
            continue;
        }
        let d = path
            .split(r#" d=""#)
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap();
        let mut words = d.split_whitespace().peekable();
        let (mut x, mut y) = (0.0, 0.0);
        let num = |w: &str| -> f64 {
            w.trim_start_matches(|c: char| c.is_ascii_alphabetic())
                .parse()
                .unwrap()
        };
        while let Some(word) = words.next() {
            let (x0, y0) = (x, y);
            match &word[..1] {
                "M" => {
                    x = num(word);
                    y = num(words.next().unwrap());
                    continue;
                }
                "H" => x = num(word),
                "V" => y = num(word),
                "C" => {
                    for _ in 0..3 {
                        words.next();
                    }
                    x = num(words.next().unwrap());
                    y = num(words.next().unwrap());
                }
                other => panic!("path command {other} in {d}"),
            }
            pieces.push((x0.min(x), x0.max(x), y0.min(y), y0.max(y)));
        }
    }
    pieces
}

/// Rails run in the gutters and the gaps between boxes, never through one. (Coordinates are
/// written with one decimal, so an end on a box's side may sit 0.1 px inside it.)
fn assert_rails_clear_of_boxes(svg: &str, map: &MapData) {
    const SLACK: f64 = 0.15;
    let inside = |a0: f64, a1: f64, b0: f64, b1: f64| {
        if a0 == a1 {
            b0 + SLACK < a0 && a0 < b1 - SLACK
        } else {
            a0.max(b0) < a1.min(b1) - SLACK
        }
    };
    let boxes = all_boxes(svg, map);
    for (x0, x1, y0, y1) in rail_pieces(svg) {
        for &(bx, by, bw, bh) in &boxes {
            assert!(
                !(inside(x0, x1, bx, bx + bw) && inside(y0, y1, by, by + bh)),
                "rail piece x {x0}..{x1} y {y0}..{y1} through the box at ({bx}, {by}) {bw} x {bh}"
            );
        }
    }
}

#[test]
fn example_plant_map_is_well_formed_and_names_every_place() {
    let map = example_plant();
    let svg = draw(&map, "voting, 24 h, seed 1977");
    if let Ok(path) = std::env::var("MAP_SVG_OUT") {
        std::fs::write(path, &svg).unwrap();
    }
    assert_well_formed(&svg);
    assert_rails_clear_of_boxes(&svg, &map);
    assert!(svg.contains(">voting, 24 h, seed 1977<"));
    for node in &map.nodes {
        assert!(
            svg.contains(&format!(">{}<", node.name)),
            "{} unnamed",
            node.name
        );
    }
    for (k, _) in map.edges.iter().enumerate() {
        assert!(rail_width(&svg, k).is_some(), "rail {k} not drawn");
    }
    // The legend gives the scale and names every kind of place on the map.
    for words in [
        "trolleys per hour",
        "loading station",
        "buffer lane",
        "dock chain",
        "return rail",
    ] {
        assert!(svg.contains(words), "{words}");
    }
}

/// The box of the place called `name`: (x, y, width, height).
fn place_box(svg: &str, map: &MapData, name: &str) -> (f64, f64, f64, f64) {
    let i = map.nodes.iter().position(|n| n.name == name).unwrap();
    let tag = element(svg, &format!("node-{i}")).unwrap();
    (
        attr(tag, "x"),
        attr(tag, "y"),
        attr(tag, "width"),
        attr(tag, "height"),
    )
}

#[test]
fn the_example_reads_left_to_right_with_the_return_rail_under_it() {
    let map = example_plant();
    let svg = draw(&map, "t");
    let b = |name| place_box(&svg, &map, name);
    // Downstream is to the right: P → R1 → R2 → R5 → D1 → A1, and the docks with the stations.
    let chain = ["P1", "R1", "R2", "R5", "D1", "A1"];
    for pair in chain.windows(2) {
        assert!(b(pair[0]).0 + b(pair[0]).2 < b(pair[1]).0, "{pair:?}");
    }
    assert_eq!(b("dock 1").0, b("A1").0);
    // A column keeps the data's order within a kind: A1 over A2 over A3, D1 over E11.
    for pair in [["A1", "A2"], ["A2", "A3"], ["D1", "E11"], ["P1", "P3"]] {
        assert!(b(pair[0]).1 < b(pair[1]).1, "{pair:?}");
    }
    // The return rail: under every place, from the loading stations to the docks.
    let ret = b("return");
    for node in &map.nodes {
        if node.name != "return" {
            let p = b(&node.name);
            assert!(p.1 + p.3 < ret.1, "{} under the return rail", node.name);
            assert!(ret.0 < p.0 && p.0 + p.2 < ret.0 + ret.2, "{}", node.name);
        }
    }
    // Loading stations show what they sent: P1 sent 980 trolleys in 24 h.
    assert!(svg.contains(">41 /h<"), "P1's rate");
}

#[test]
fn the_busier_rail_of_the_example_is_wider() {
    let map = example_plant();
    let svg = draw(&map, "t");
    // R1 → R2 (1 120 trolleys) against R2 → R5 (560): exactly twice.
    let find = |from: &str, to: &str| {
        map.edges
            .iter()
            .position(|e| map.nodes[e.from].name == from && map.nodes[e.to].name == to)
            .unwrap()
    };
    let wide = rail_width(&svg, find("R1", "R2")).unwrap();
    let narrow = rail_width(&svg, find("R2", "R5")).unwrap();
    assert!(wide > narrow, "{wide} vs {narrow}");
}

#[test]
fn an_empty_map_is_a_valid_picture_that_says_so() {
    let svg = draw(&MapData::default(), "nothing & nobody");
    assert_well_formed(&svg);
    assert!(svg.contains("empty"), "{svg}");
    assert!(svg.contains("nothing &amp; nobody"));
    // Places without rails or time are drawn, with no rates.
    let mut lone = example_plant();
    lone.edges.clear();
    lone.hours = 0.0;
    let svg = draw(&lone, "no time, no rails");
    if let Ok(path) = std::env::var("MAP_SVG_OUT_BARE") {
        std::fs::write(path, &svg).unwrap();
    }
    assert_well_formed(&svg);
    assert!(svg.contains("no time"));
}

#[test]
fn without_time_no_rate_is_printed() {
    for hours in [
        0.0,
        -3.0,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        1e-320,
    ] {
        let mut map = example_plant();
        map.hours = hours;
        let svg = draw(&map, "t");
        assert_well_formed(&svg);
        assert!(!svg.contains("NaN") && !svg.contains("inf"), "{hours}");
        assert!(svg.contains("no time"), "{hours}");
        assert!(!svg.contains(" /h"), "{hours}: a rate shown");
    }
}

/// Any small plant: up to 8 layers of up to 16 places each (one return rail now and then),
/// random rails (some to missing places), counts from 0 to huge, any hours.
fn any_map() -> impl Strategy<Value = MapData> {
    let kind = prop_oneof![
        Just(NodeKind::Loading),
        Just(NodeKind::Reader),
        Just(NodeKind::Buffer),
        Just(NodeKind::Emptying),
        Just(NodeKind::Dock),
        Just(NodeKind::Manual),
        Just(NodeKind::Return),
    ];
    let count = prop_oneof![Just(0u64), 0u64..50, Just(u64::MAX)];
    let node = (
        "[A-Z][a-z0-9 <&]{0,7}",
        kind,
        0u8..8,
        count.clone(),
        count.clone(),
        any::<bool>(),
    )
        .prop_map(
            |(name, kind, layer, misdelivered, rejected, alarm)| MapNode {
                name,
                kind,
                layer,
                misdelivered,
                rejected,
                alarm,
            },
        );
    let hours = prop_oneof![
        Just(0.0),
        Just(f64::NAN),
        Just(1e-300),
        0.01f64..200.0,
        Just(24.0)
    ];
    (
        hours,
        prop::collection::vec(node, 0..40),
        prop::collection::vec((0usize..42, 0usize..42, count), 0..60),
    )
        .prop_map(|(hours, nodes, edges)| MapData {
            hours,
            nodes,
            edges: edges
                .into_iter()
                .map(|(from, to, trolleys)| MapEdge { from, to, trolleys })
                .collect(),
        })
}

/// Names of any printable characters, of any characters, or of those XML forbids or escapes.
const NASTY_NAME: &str = "\\PC{0,6}|.{0,6}|[\u{0}-\u{1f}\u{fffe}\u{ffff}&<>\"']{1,4}";

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn any_map_is_well_formed_without_nan(map in any_map()) {
        let svg = draw(&map, "any");
        assert_well_formed(&svg);
        prop_assert!(!svg.contains("NaN") && !svg.contains("inf"));
        for node in &map.nodes {
            let name = node.name.replace('&', "&amp;").replace('<', "&lt;");
            prop_assert!(svg.contains(&name), "{} unnamed", node.name);
        }
    }

    #[test]
    fn any_name_and_title_give_well_formed_xml(
        names in prop::collection::vec(NASTY_NAME, 1..6),
        title in ".{0,30}",
    ) {
        let mut map = plants::example_plant();
        for (node, name) in map.nodes.iter_mut().zip(names) {
            node.name = name;
        }
        assert_well_formed(&draw(&map, &title));
    }

    #[test]
    fn more_trolleys_never_draw_a_thinner_rail(map in any_map()) {
        let svg = draw(&map, "widths");
        let drawn: Vec<(u64, f64)> = map
            .edges
            .iter()
            .enumerate()
            .filter_map(|(k, e)| rail_width(&svg, k).map(|w| (e.trolleys, w)))
            .collect();
        for &(t1, w1) in &drawn {
            for &(t2, w2) in &drawn {
                if t1 >= t2.saturating_mul(2) {
                    prop_assert!(w1 >= w2, "{t1} trolleys {w1} px, {t2} trolleys {w2} px");
                }
                if t1 > t2 {
                    prop_assert!(w1 >= w2);
                }
            }
        }
    }

    #[test]
    fn a_rail_is_dashed_exactly_when_no_trolley_used_it(map in any_map()) {
        let svg = draw(&map, "dashes");
        for (k, e) in map.edges.iter().enumerate() {
            if let Some(tag) = element(&svg, &format!("rail-{k}")) {
                prop_assert_eq!(tag.contains("stroke-dasharray"), e.trolleys == 0, "{}", tag);
            }
        }
    }

    #[test]
    fn marks_are_exactly_where_something_went_wrong(map in any_map()) {
        let svg = draw(&map, "marks");
        for (i, node) in map.nodes.iter().enumerate() {
            for (what, wrong) in [
                ("misdelivered", node.misdelivered > 0),
                ("rejected", node.rejected > 0),
                ("alarm", node.alarm),
            ] {
                prop_assert_eq!(element(&svg, &format!("{what}-{i}")).is_some(), wrong, "{} {}", what, i);
            }
            if node.misdelivered > 0 {
                let number = format!("<title>{} sacks misdelivered here", node.misdelivered);
                prop_assert!(svg.contains(&number), "no {} written", node.misdelivered);
            }
        }
        let marks = svg.matches(r#" id="misdelivered-"#).count()
            + svg.matches(r#" id="rejected-"#).count();
        let wrong = map.nodes.iter().map(|n| usize::from(n.misdelivered > 0) + usize::from(n.rejected > 0)).sum::<usize>();
        prop_assert_eq!(marks, wrong);
    }

    #[test]
    fn boxes_never_overlap_and_stay_in_the_picture(map in any_map()) {
        let svg = draw(&map, "boxes");
        assert_rails_clear_of_boxes(&svg, &map);
        let (w, h) = {
            let root = &svg[..svg.find('>').unwrap()];
            (attr(root, "width"), attr(root, "height"))
        };
        let boxes: Vec<(f64, f64, f64, f64)> = (0..map.nodes.len())
            .map(|i| {
                let tag = element(&svg, &format!("node-{i}")).unwrap();
                (attr(tag, "x"), attr(tag, "y"), attr(tag, "width"), attr(tag, "height"))
            })
            .collect();
        for (i, a) in boxes.iter().enumerate() {
            prop_assert!(a.0 >= 0.0 && a.1 >= 0.0 && a.0 + a.2 <= w && a.1 + a.3 <= h, "{:?} outside {} x {}", a, w, h);
            for b in &boxes[..i] {
                let apart = a.0 + a.2 <= b.0 || b.0 + b.2 <= a.0 || a.1 + a.3 <= b.1 || b.1 + b.3 <= a.1;
                prop_assert!(apart, "{:?} overlaps {:?}", a, b);
            }
        }
    }
}

#[test]
fn a_crowded_map_keeps_its_boxes_apart() {
    let map = crowded_plant();
    let svg = draw(&map, "crowded: 8 layers, up to 20 places each, huge counts");
    assert_rails_clear_of_boxes(&svg, &map);
    if let Ok(path) = std::env::var("MAP_SVG_OUT_CROWDED") {
        std::fs::write(path, &svg).unwrap();
    }
    assert_well_formed(&svg);
    assert!(!svg.contains("NaN") && !svg.contains("inf"));
    for node in &map.nodes {
        assert!(
            svg.contains(&format!(">{}<", node.name)),
            "{} unnamed",
            node.name
        );
    }
}
