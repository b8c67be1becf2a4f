//! What a run gives: the figures per crate and for the whole loop, and the text summary.

use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;

use super::Config;
use crate::cli::number;

/// Per-crate figures.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CrateSummary {
    /// Crate address.
    pub address: u8,
    /// Commands the driver issued to it.
    pub messages: u64,
    /// Commands completed.
    pub replies: u64,
    /// Errors its controller detected (ERR replies, truncated commands).
    pub detected_errors: u64,
    /// Re-sends of its commands.
    pub retries: u64,
    /// Commands that failed after every retry.
    pub failed: u64,
    /// Demands received from it.
    pub demands: u64,
    /// Demands served (its counter read and cleared).
    pub demands_served: u64,
    /// Cycles run.
    pub cycles: u64,
}

/// What a run gives.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// The configuration.
    pub config: Config,
    /// Byte clocks run.
    pub clocks: u64,
    /// Commands completed.
    pub completed: u64,
    /// Commands failed.
    pub failed: u64,
    /// Commands re-sent.
    pub retries: u64,
    /// Messages damaged on the way back to the driver (rejected by `decode`).
    pub garbled_at_driver: u64,
    /// Errors the controllers detected.
    pub detected_at_crates: u64,
    /// Time-outs at the driver.
    pub timeouts: u64,
    /// Bits the noise flipped.
    pub bits_flipped: u64,
    /// The figure that matters: wrong cycles run plus wrong answers accepted.
    pub undetected_errors: u64,
    /// The same, by kind.
    pub undetected: Undetected,
    /// Demands received.
    pub demands: u64,
    /// Demands served.
    pub demands_served: u64,
    /// Completed commands per second of line time, byte-serial.
    pub messages_per_s_byte_serial: f64,
    /// Completed commands per second of line time, bit-serial.
    pub messages_per_s_bit_serial: f64,
    /// Per crate.
    pub crates: Vec<CrateSummary>,
}

/// The undetected errors by kind.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Undetected {
    /// A crate ran a cycle that was not the command issued to it.
    pub wrong_cycles: u64,
    /// The driver accepted an answer no run of the command gave.
    pub wrong_answers: u64,
    /// A demand arrived from a crate address not on the loop.
    pub phantom_demands: u64,
}

impl Undetected {
    /// All of them.
    #[must_use]
    pub fn total(&self) -> u64 {
        self.wrong_cycles + self.wrong_answers + self.phantom_demands
    }
}

/// The text summary: the run's configuration, what went through, what was caught and what was
/// not, the throughput, and a table of the crates (the first and last four of a long loop);
/// `picture` is named at the end when one was written.
#[must_use]
pub fn summary_text(s: &Summary, picture: Option<&Path>) -> String {
    let mut out = String::new();
    // Writing to a String cannot fail.
    macro_rules! line {
        ($($t:tt)*) => { let _ = writeln!(out, $($t)*); };
    }
    let c = &s.config;
    line!(
        "serial-highway: {} crates, {} commands, bit-error rate {} per link ({}), seed {}",
        c.crates,
        c.messages,
        number(c.ber),
        c.line,
        c.seed
    );
    line!(
        "  completed {}, failed {}, retries {}, time-outs {}",
        s.completed,
        s.failed,
        s.retries,
        s.timeouts
    );
    line!(
        "  bits flipped {}; detected at the crates {}, at the driver {}",
        s.bits_flipped,
        s.detected_at_crates,
        s.garbled_at_driver
    );
    line!(
        "  undetected errors: {} (wrong cycles run {}, wrong answers accepted {}, phantom demands {})",
        s.undetected_errors,
        s.undetected.wrong_cycles,
        s.undetected.wrong_answers,
        s.undetected.phantom_demands
    );
    line!("  demands {}, served {}", s.demands, s.demands_served);
    line!(
        "  throughput: {:.0} commands/s at {} MHz byte-serial, {:.0} commands/s at {} Mbit/s bit-serial",
        s.messages_per_s_byte_serial,
        number(c.byte_rate_hz / 1e6),
        s.messages_per_s_bit_serial,
        number(c.bit_rate_hz / 1e6)
    );
    line!("  crate  messages  replies  detected  retries  failed  demands  served");
    let show: Vec<_> = if s.crates.len() > 12 {
        // The first and last four.
        let mut picked: Vec<_> = s
            .crates
            .iter()
            .take(4)
            .chain(s.crates.iter().rev().take(4))
            .collect();
        picked.sort_by_key(|c| c.address);
        picked.dedup_by_key(|c| c.address);
        picked
    } else {
        s.crates.iter().collect()
    };
    for k in show {
        line!(
            "  {:>5}  {:>8}  {:>7}  {:>8}  {:>7}  {:>6}  {:>7}  {:>6}",
            k.address,
            k.messages,
            k.replies,
            k.detected_errors,
            k.retries,
            k.failed,
            k.demands,
            k.demands_served
        );
    }
    if s.crates.len() > 12 {
        line!("  (all {} crates: --json, or the picture)", s.crates.len());
    }
    if let Some(path) = picture {
        line!("  picture: {}", path.display());
    }
    out.trim_end().to_string()
}
