//! What the plant map shows: the plant as a graph of places and rail sections, with what a run
//! counted on them. The control program's simulation fills it (`plant::run`); `plant::map`
//! draws it.

use serde::Serialize;

/// What kind of place a node of the map is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum NodeKind {
    /// A loading station P1–P3.
    Loading,
    /// A decision point: a code reader and the switch behind it.
    Reader,
    /// A buffer lane D1–D4, E1–E11.
    Buffer,
    /// An emptying station A1–C2.
    Emptying,
    /// A dock chain with its bins.
    Dock,
    /// The manual station, where rejected trolleys go.
    Manual,
    /// The return rail that takes empty trolleys back to the loading stations.
    Return,
}

/// A place on the map.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MapNode {
    /// Its name in the plant (`P1`, `R3`, `E7`, `A2`, `dock 1`, `manual`, `return`).
    pub name: String,
    /// What it is.
    pub kind: NodeKind,
    /// Its column, from 0 at the loading stations, growing downstream.
    pub layer: u8,
    /// Sacks that ended up here but were meant for somewhere else.
    pub misdelivered: u64,
    /// Trolleys this reader sent to the manual station (no plausible destination read).
    pub rejected: u64,
    /// A health alarm is on here at the end of the run (a reader's misread alarm).
    pub alarm: bool,
}

/// A rail section between two places.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MapEdge {
    /// Index of the upstream node in [`MapData::nodes`].
    pub from: usize,
    /// Index of the downstream node.
    pub to: usize,
    /// Trolleys that ran along it over the run.
    pub trolleys: u64,
}

/// The plant map's data.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct MapData {
    /// Simulated hours the counts cover (trolleys per hour = count / hours).
    pub hours: f64,
    /// The places.
    pub nodes: Vec<MapNode>,
    /// The rail sections.
    pub edges: Vec<MapEdge>,
}
