//! The whole 1977 Malmö Ban mailbag-sorting plant (source 000): loading desks, rails with
//! switches at code readers, buffer lanes, emptying stations, dock chains, six panels and the
//! control program on the regler crates.

pub mod map_data;
pub mod operator;
pub mod panels;
