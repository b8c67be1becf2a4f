//! Example plants for the map's tests: a plausible 24-hour run of the 1977 plant, and a crowded
//! map that pushes the layout.

use regler_examples::mailbag::plant::map_data::{MapData, MapEdge, MapNode, NodeKind};

/// A plausible 24-hour run of the plant: P1–P3 → R1 → letters / parcels / sorted readers →
/// lane readers → D1–D4, E1–E11 → A1–A3, B1–B2, C1–C2; sorted → dock readers → 3 docks;
/// rejects → manual; everything → return → P1–P3.
pub fn example_plant() -> MapData {
    let mut map = MapData {
        hours: 24.0,
        ..MapData::default()
    };
    let mut node = |name: &str, kind: NodeKind, layer: u8| {
        map.nodes.push(MapNode {
            name: name.into(),
            kind,
            layer,
            misdelivered: 0,
            rejected: 0,
            alarm: false,
        });
        map.nodes.len() - 1
    };
    let p: Vec<usize> = ["P1", "P2", "P3"]
        .iter()
        .map(|n| node(n, NodeKind::Loading, 0))
        .collect();
    let r1 = node("R1", NodeKind::Reader, 1);
    let (letters, parcels, sorted) = (
        node("R2", NodeKind::Reader, 2),
        node("R3", NodeKind::Reader, 2),
        node("R4", NodeKind::Reader, 2),
    );
    let lane_readers: Vec<usize> = ["R5", "R6", "R7", "R8"]
        .iter()
        .map(|n| node(n, NodeKind::Reader, 3))
        .collect();
    let dock_reader = node("R9", NodeKind::Reader, 3);
    let lanes: Vec<usize> = [
        "D1", "D2", "D3", "D4", "E1", "E2", "E3", "E4", "E5", "E6", "E7", "E8", "E9", "E10", "E11",
    ]
    .iter()
    .map(|n| node(n, NodeKind::Buffer, 4))
    .collect();
    let stations: Vec<usize> = ["A1", "A2", "A3", "B1", "B2", "C1", "C2"]
        .iter()
        .map(|n| node(n, NodeKind::Emptying, 5))
        .collect();
    let docks: Vec<usize> = ["dock 1", "dock 2", "dock 3"]
        .iter()
        .map(|n| node(n, NodeKind::Dock, 5))
        .collect();
    let manual = node("manual", NodeKind::Manual, 5);
    let ret = node("return", NodeKind::Return, 6);

    let mut edge = |from: usize, to: usize, trolleys: u64| {
        map.edges.push(MapEdge { from, to, trolleys });
    };
    for (&p, t) in p.iter().zip([980, 910, 560]) {
        edge(p, r1, t);
        edge(ret, p, t);
    }
    edge(r1, letters, 1_120);
    edge(r1, parcels, 690);
    edge(r1, sorted, 612);
    // Letters: D1–D4 by R5, E1–E6 by R6; parcels: E7–E9 by R7, E10–E11 by R8.
    edge(letters, lane_readers[0], 560);
    edge(letters, lane_readers[1], 553);
    edge(parcels, lane_readers[2], 410);
    edge(parcels, lane_readers[3], 276);
    edge(sorted, dock_reader, 606);
    let lane_feed = [
        (0, 0, 150),
        (0, 1, 140),
        (0, 2, 160),
        (0, 3, 109),
        (1, 4, 120),
        (1, 5, 98),
        (1, 6, 90),
        (1, 7, 101),
        (1, 8, 80),
        (1, 9, 63),
        (2, 10, 160),
        (2, 11, 130),
        (2, 12, 119),
        (3, 13, 140),
        (3, 14, 135),
    ];
    for (reader, lane, t) in lane_feed {
        edge(lane_readers[reader], lanes[lane], t);
    }
    // Letter lanes empty to A1–A3 in portions, parcel lanes to B1–B2 and C1–C2.
    for (k, &lane) in lanes.iter().enumerate().take(10) {
        let t = lane_feed[k].2;
        edge(lane, stations[k % 3], t * 2 / 3);
        edge(lane, stations[(k + 1) % 3], t - t * 2 / 3);
    }
    for (k, &lane) in lanes.iter().enumerate().skip(10) {
        edge(lane, stations[3 + (k % 4)], lane_feed[k].2);
    }
    for (&dock, t) in docks.iter().zip([250, 201, 155]) {
        edge(dock_reader, dock, t);
        edge(dock, ret, t);
    }
    for (&station, t) in stations.iter().zip([420, 405, 410, 146, 140, 160, 135]) {
        edge(station, ret, t);
    }
    for (reader, t) in [
        (r1, 12),
        (letters, 7),
        (parcels, 4),
        (sorted, 6),
        (lane_readers[1], 17),
        (dock_reader, 2),
    ] {
        edge(reader, manual, t);
        map.nodes[reader].rejected = t;
    }
    edge(manual, ret, 48);
    map.nodes[lane_readers[1]].alarm = true;
    for (place, count) in [
        (docks[1], 3),
        (stations[1], 1),
        (lanes[6], 2),
        (stations[4], 14),
    ] {
        map.nodes[place].misdelivered = count;
    }
    map
}

/// Eight layers of up to 20 places with long names and huge counts, every place fed from the
/// one before, some rails backwards and some to the return rail.
pub fn crowded_plant() -> MapData {
    let mut map = MapData {
        hours: 7.5,
        ..MapData::default()
    };
    let mut previous: Vec<usize> = Vec::new();
    for layer in 0..8u8 {
        let count = [3, 20, 5, 17, 1, 12, 20, 4][usize::from(layer)];
        let mut this = Vec::new();
        for k in 0..count {
            let i = map.nodes.len();
            map.nodes.push(MapNode {
                name: format!("L{layer} place {k}"),
                kind: [
                    NodeKind::Loading,
                    NodeKind::Reader,
                    NodeKind::Buffer,
                    NodeKind::Emptying,
                ][usize::from(layer) % 4],
                layer,
                misdelivered: if k % 3 == 0 {
                    10u64.pow(u32::from(layer) + 2)
                } else {
                    0
                },
                rejected: if k % 4 == 1 { u64::MAX } else { 0 },
                alarm: k % 5 == 2,
            });
            if let Some(&from) = previous.get(k % previous.len().max(1)) {
                map.edges.push(MapEdge {
                    from,
                    to: i,
                    trolleys: 100 * (k as u64 + 1),
                });
            }
            this.push(i);
        }
        previous = this;
    }
    let ret = map.nodes.len();
    map.nodes.push(MapNode {
        name: "return rail".into(),
        kind: NodeKind::Return,
        layer: 9,
        misdelivered: 0,
        rejected: 0,
        alarm: true,
    });
    for &i in &previous {
        map.edges.push(MapEdge {
            from: i,
            to: ret,
            trolleys: 400,
        });
    }
    map.edges.push(MapEdge {
        from: ret,
        to: 0,
        trolleys: 1_600,
    });
    // Backwards: from the last column to the second.
    map.edges.push(MapEdge {
        from: previous[0],
        to: 5,
        trolleys: 50,
    });
    map
}
