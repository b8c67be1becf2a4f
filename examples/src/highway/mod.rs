//! The CAMAC serial highway of source 004 (IEEE 595, as a Russian textbook chapter describes it)
//! rebuilt on `regler-panel-link`: one driver and up to 62 L-type crate controllers on a loop of
//! one-way links, each link flipping bits at a set rate; simulated crates with register modules
//! and a counter that raises a LAM. The simulation is the loop a firmware would run: one byte
//! clock at a time, every machine called exactly as on a real highway.
//!
//! # Timing
//! Time is counted in byte clocks. Every controller passes a byte on one clock after it took
//! it, so a command reaches crate *k* after *k* clocks and its reply travels the rest of the
//! loop; the driver gives up on an attempt after [`Config::timeout`] clocks and sends it again
//! (at most `retries` times). Line time is the clocks at the byte-serial clock (5 MHz: eight
//! lines and a clock) or ten bit times each at `bit_rate_hz` (bit-serial: start, 8 bits, stop).
//!
//! # Truth
//! The harness knows the truth the protocol does not: which command the driver issued to each
//! crate and what each dataway cycle read. An **undetected error** is a cycle that ran a command
//! the driver did not issue, or a completed command whose answer (data, X, Q) no run of it gave.
//!
//! # Files, as the data flows
//! [`Config`] here; the crates' modules ([`SimCrate`], `dataway.rs`); a scripted workload
//! ([`parse_script`]); the loop and its harness ([`Sim`], [`run`]); the figures and the text
//! ([`Summary`], [`summary_text`]); the picture ([`picture`]); the same driver and one crate over
//! two real serial ports ([`ports`]).

mod dataway;
mod picture;
pub mod ports;
mod script;
mod sim;
mod summary;

use std::fmt;

use serde::Serialize;

use crate::cli::number;

pub use self::dataway::{CycleRecord, SimCrate};
pub use self::picture::picture;
pub use self::script::parse_script;
pub use self::sim::{Sim, run};
pub use self::summary::{CrateSummary, Summary, Undetected, summary_text};

/// The driver's window: commands in flight at most (one per crate).
pub const WINDOW: usize = 16;
/// Crate addresses on one loop: 1 to 62.
pub const MAX_CRATES: u8 = 62;
/// Most commands in one run (about a minute of a release build).
pub const MAX_MESSAGES: u64 = 100_000_000;
/// Highest bit-error rate of a link: one bit in ten.
pub const MAX_BER: f64 = 0.1;
/// Slowest line for the throughput figures: 1 kbit/s (or bytes/s).
pub const MIN_RATE: f64 = 1e3;
/// Fastest: 100 Mbit/s, twenty times the 5 MHz of the standard.
pub const MAX_RATE: f64 = 1e8;
/// The counter module's station.
pub const COUNTER_STATION: u8 = 20;
/// Register modules sit at stations 1..=REGISTER_STATIONS.
pub const REGISTER_STATIONS: u8 = 4;

/// How the bytes travel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LineKind {
    /// Eight lines and a clock: noise hits the 8 bits of each byte.
    ByteSerial,
    /// Start 0, 8 bits LSB first, stop 1: noise hits all 10 bits; a frame with a broken start or
    /// stop bit reaches the controller as a byte with even parity (a detected error).
    BitSerial,
}

impl LineKind {
    /// As the user writes it: `byte-serial`, `bit-serial`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::ByteSerial => "byte-serial",
            Self::BitSerial => "bit-serial",
        }
    }
}

impl fmt::Display for LineKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One run's parameters.
#[derive(Clone, Debug, Serialize)]
pub struct Config {
    /// Crate controllers on the loop (1–62).
    pub crates: u8,
    /// Commands to complete (or fail).
    pub messages: u64,
    /// Bit-error rate of every link (0 to 0.1).
    pub ber: f64,
    /// Seed of the workload and of the noise.
    pub seed: u64,
    /// Line encoding.
    pub line: LineKind,
    /// Commands in flight at most (1–16, and at most one per crate).
    pub window: usize,
    /// Retries per command.
    pub retries: u8,
    /// Counter counts before it raises its LAM.
    pub lam_preset: u32,
    /// Byte clocks per counter count.
    pub count_period: u32,
    /// Byte-serial clock (Hz) for the throughput figure.
    pub byte_rate_hz: f64,
    /// Bit-serial bit rate (bit/s) for the throughput figure.
    pub bit_rate_hz: f64,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            crates: 62,
            messages: 1_000_000,
            ber: 1e-5,
            seed: 1976,
            line: LineKind::ByteSerial,
            window: WINDOW,
            retries: 5,
            lam_preset: 5_000,
            count_period: 7,
            byte_rate_hz: 5e6,
            bit_rate_hz: 5e6,
        }
    }
}

impl Config {
    /// Checks every parameter; the message names the command-line option (`--crates: must be
    /// from 1 to 62, got 0`).
    ///
    /// # Errors
    /// The first bad one, named.
    pub fn validate(&self) -> Result<(), String> {
        if !(1..=MAX_CRATES).contains(&self.crates) {
            return Err(format!(
                "--crates: must be from 1 to {MAX_CRATES}, got {}",
                self.crates
            ));
        }
        if !(1..=MAX_MESSAGES).contains(&self.messages) {
            return Err(format!(
                "--messages: must be from 1 to {MAX_MESSAGES}, got {}",
                self.messages
            ));
        }
        if !(self.ber.is_finite() && (0.0..=MAX_BER).contains(&self.ber)) {
            return Err(format!(
                "--ber: must be from 0 to {}, got {}",
                number(MAX_BER),
                number(self.ber)
            ));
        }
        if !(1..=WINDOW).contains(&self.window) {
            return Err(format!(
                "--window: must be from 1 to {WINDOW}, got {}",
                self.window
            ));
        }
        if self.window > usize::from(self.crates) {
            return Err(format!(
                "--window: one command in flight per crate, so at most --crates ({}), got {}",
                self.crates, self.window
            ));
        }
        if self.lam_preset == 0 || self.count_period == 0 {
            return Err("lam preset and count period must be at least 1".into());
        }
        for (name, v) in [
            ("byte rate", self.byte_rate_hz),
            ("--bit-rate", self.bit_rate_hz),
        ] {
            if !(v.is_finite() && (MIN_RATE..=MAX_RATE).contains(&v)) {
                return Err(format!(
                    "{name}: must be from {} to {}, got {}",
                    number(MIN_RATE),
                    number(MAX_RATE),
                    number(v)
                ));
            }
        }
        Ok(())
    }

    /// The window for `crates` crates when none is asked for: one command per crate, at most
    /// [`WINDOW`].
    #[must_use]
    pub fn default_window(crates: u8) -> usize {
        WINDOW.min(usize::from(crates))
    }

    /// Byte clocks a reply may take at most: every controller may hold 3 bytes behind a demand
    /// on top of its one byte of delay, and a command and its reply must pass.
    #[must_use]
    pub fn timeout(&self) -> u32 {
        4 * (u32::from(self.crates) + 1) + 64
    }
}
