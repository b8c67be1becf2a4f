//! The anchors the regler crates are measured against, and the workloads the benches and the
//! instruction-count binaries share. Nothing here is meant for production use.

pub mod count_down;
pub mod dock;
pub mod highway;
pub mod master;
pub mod naive_decode;
pub mod pid_loop;
pub mod pid_shapes;
pub mod report;
pub mod ring_pairs;
pub mod scan;
