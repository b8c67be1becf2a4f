//! A simulated loading dock of the 1977 Malmö Ban mailbag sorter (source 000), run on
//! `regler-trolley-id` and `regler-chain-tracker` exactly as its controller would call them.
//!
//! # The plant
//! Each dock has a chain of `chain_m` metres carrying trolleys past `bins` bins; initiators give
//! one pulse per decimetre of chain *as it was new*. The chain stretches linearly by
//! `stretch_m_per_year`, so a pulse stands for a little more chain every day, while the bins
//! stay where they are. Two reference initiators `initiator_span_m` apart (300 m, or ¾ of a
//! shorter chain) let the stretch meter count DIA once per chain revolution; a count is off by
//! one pulse with probability `glitch_rate` (a missed or an extra pulse).
//!
//! # Time
//! The simulation steps one chain pulse at a time. A trolley enters every `mean_gap_pulses` on
//! average (at least [`MIN_GAP_PULSES`] apart), so a simulated year is `trolleys_per_year ×
//! mean_gap_pulses` pulses: a sample of the real traffic, with the chain stretching as in a
//! real year. DIA is measured `measurements_per_year` times a year, spaced by traffic.
//!
//! At commissioning every reader→tipper distance SA was measured and set `LEAD_PULSES` short, so
//! the tipper is set just before the trolley reaches the bin; the tipper stays set for the
//! source's 6 pulses. A sack falls into bin `j` when its trolley passes bin `j` while that
//! tipper is set, whichever trolley the tracker meant.
//!
//! # The reader
//! A code reader at the chain start takes `readings` scans of each passing trolley. A passage is
//! *disturbed* (the trolley swings) with probability `rate / DISTURBED_SHARE`; in a disturbed
//! passage each scan is wrong with probability `DISTURBED_SHARE`, so a single scan is wrong with
//! probability `rate`, the figure of the source (1 in 1000). Readers differ: reader `i` of `n`
//! has `rate = misread_rate × (1 + reader_spread × (2i/(n−1) − 1))`. A wrong scan has 1, 2 or 3
//! cams flipped (50 %, 35 %, 15 %): parity catches odd counts; two flipped cams are another
//! trolley's number.
//!
//! # The controller
//! *Without voting* it decodes the first scan, as the source did; *with voting* a
//! [`Voter`] combines all scans. Either way the
//! [`Registry`](regler_trolley_id::Registry) routes the trolley: delivered if
//! the number read has a destination on this dock, else rejected (to the manual station).
//! *With correction* every accepted DIA recalibrates the tracker; *without* the distances stay
//! as commissioned.
//!
//! # Files, as the data flows
//! [`Config`] here; the code readers' scans and the source's single read (`readers.rs`); one
//! dock's chain, tracker, stretch meter and tippers pulse by pulse (`docks.rs`); the four
//! controllers over every dock ([`Scenario`], [`run`]); what a run found ([`Report`]); the text
//! summary ([`summary_text`]) and the picture ([`picture`]).

mod docks;
mod picture;
pub mod plant;
mod readers;
mod report;
mod scenarios;
mod summary;

use regler_trolley_id::{Strategy, Voter};
use serde::Serialize;

use crate::cli::number;

pub use self::picture::picture;
pub use self::report::{
    CURVE_POINTS, CurvePoint, Outcomes, ReaderReport, Report, ScenarioReport, StretchReport,
    TipError, YearReport,
};
pub use self::scenarios::{SCENARIOS, Scenario, run};
pub use self::summary::summary_text;

/// Pulses per metre of new chain (one per decimetre).
pub const PULSES_PER_M: f64 = 10.0;
/// Pulses by which the commissioned distances fall short of the bins.
pub const LEAD_PULSES: u32 = 2;
/// Share of scans that are wrong in a disturbed passage.
pub const DISTURBED_SHARE: f64 = 0.5;
/// Most bins a dock may have.
pub const MAX_BINS: usize = 64;
/// Most trolleys on one chain.
pub const MAX_ON_CHAIN: usize = 2048;
/// Least pulses between two trolleys on the chain: they hang on the chain's dogs at least a
/// metre apart, more than the tipper hold plus the lead, so a set tipper never catches the next
/// trolley when tracking is right.
pub const MIN_GAP_PULSES: u32 = 10;

/// Where a sack should go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Destination {
    /// Dock, from 0.
    pub dock: u8,
    /// Bin on that dock, from 0.
    pub bin: u16,
}

/// The simulation's parameters (the example's command line).
#[derive(Clone, Debug, Serialize)]
pub struct Config {
    /// Seed of every random choice.
    pub seed: u64,
    /// Simulated years.
    pub years: f64,
    /// Trolleys through each dock per simulated year (a sample of the real traffic).
    pub trolleys_per_year: u32,
    /// Docks, each with its chain and reader.
    pub docks: u8,
    /// Bins per dock.
    pub bins: u16,
    /// Chain length, metres.
    pub chain_m: f64,
    /// Distance between the reference initiators, metres.
    pub initiator_span_m: f64,
    /// Chain stretch, metres per year.
    pub stretch_m_per_year: f64,
    /// Mean chance that one scan is wrong.
    pub misread_rate: f64,
    /// How uneven the readers are, 0 (equal) to 1.
    pub reader_spread: f64,
    /// Scans per passing trolley.
    pub readings: u8,
    /// Voting strategy when voting.
    #[serde(skip)]
    pub strategy: Strategy,
    /// Mean pulses between entering trolleys.
    pub mean_gap_pulses: u32,
    /// Chance that a DIA measurement is off by one pulse.
    pub glitch_rate: f64,
    /// Reader alarm: passages with two different numbers decoded, per thousand over the last
    /// 1000 passages, above which a reader's alarm goes on.
    pub alarm_disagreement_per_mille: u32,
    /// DIA measurements per year: one per chain revolution in the real plant (an 800 m loop
    /// at 0.5 m/s for 16 hours a day makes about 13 000). The simulation compresses time, so it
    /// spaces the measurements by simulated traffic, not by revolutions.
    pub measurements_per_year: u32,
}

impl Default for Config {
    fn default() -> Config {
        Config {
            seed: 1977,
            years: 5.0,
            trolleys_per_year: 20_000,
            docks: 3,
            bins: 40,
            chain_m: 400.0,
            initiator_span_m: 300.0,
            stretch_m_per_year: 2.0,
            misread_rate: 0.001,
            reader_spread: 0.8,
            readings: 5,
            strategy: Strategy::Majority { min_samples: 3 },
            mean_gap_pulses: 15,
            glitch_rate: 0.02,
            alarm_disagreement_per_mille: 4,
            measurements_per_year: 10_000,
        }
    }
}

/// Ranges of the command line's numbers, shared by the option parsers and [`Config::validate`].
pub mod limits {
    /// `--years`.
    pub const YEARS: (f64, f64) = (0.01, 50.0);
    /// `--trolleys-per-year`.
    pub const TROLLEYS_PER_YEAR: (u32, u32) = (1, 1_000_000);
    /// `--docks`.
    pub const DOCKS: (u8, u8) = (1, 8);
    /// `--bins`.
    pub const BINS: (u16, u16) = (2, super::MAX_BINS as u16);
    /// `--chain-m`.
    pub const CHAIN_M: (f64, f64) = (50.0, 2000.0);
    /// `--stretch-m-per-year`: at most a twentieth of the chain a year (checked against
    /// `--chain-m`), here its largest.
    pub const STRETCH_M_PER_YEAR: (f64, f64) = (0.0, 100.0);
    /// `--misread-rate`: up to half the share of wrong scans in a disturbed passage.
    pub const MISREAD_RATE: (f64, f64) = (0.0, super::DISTURBED_SHARE / 2.0);
    /// `--reader-spread`.
    pub const READER_SPREAD: (f64, f64) = (0.0, 1.0);
    /// `--readings`.
    pub const READINGS: (u8, u8) = (1, 50);
    /// `--glitch-rate`.
    pub const GLITCH_RATE: (f64, f64) = (0.0, 1.0);
    /// `--reader-alarm-per-mille`: 1000 never raises the alarm.
    pub const ALARM_PER_MILLE: (u32, u32) = (0, 1000);
    /// The reference initiators sit this far apart, or ¾ of a shorter chain.
    pub const INITIATOR_SPAN_M: f64 = 300.0;
}

impl Config {
    /// Checks every parameter; the message names the command-line option that is wrong
    /// (`--years: must be from 0.01 to 50, got 60`).
    ///
    /// # Errors
    /// The first bad parameter, named.
    pub fn validate(&self) -> Result<(), String> {
        use limits::*;
        let real = |name: &str, v: f64, (lo, hi): (f64, f64)| {
            if v.is_finite() && v >= lo && v <= hi {
                Ok(())
            } else {
                Err(format!(
                    "{name}: must be from {} to {}, got {}",
                    number(lo),
                    number(hi),
                    number(v)
                ))
            }
        };
        fn whole<T: PartialOrd + std::fmt::Display>(
            name: &str,
            v: T,
            (lo, hi): (T, T),
        ) -> Result<(), String> {
            if v >= lo && v <= hi {
                Ok(())
            } else {
                Err(format!("{name}: must be from {lo} to {hi}, got {v}"))
            }
        }
        real("--years", self.years, YEARS)?;
        real("--chain-m", self.chain_m, CHAIN_M)?;
        if !(self.initiator_span_m.is_finite()
            && self.initiator_span_m >= 10.0
            && self.initiator_span_m <= self.chain_m)
        {
            return Err(format!(
                "the reference initiators must be from 10 m apart to the chain's length ({} m), got {} m",
                number(self.chain_m),
                number(self.initiator_span_m)
            ));
        }
        real(
            "--stretch-m-per-year",
            self.stretch_m_per_year,
            STRETCH_M_PER_YEAR,
        )?;
        if self.stretch_m_per_year > self.chain_m / 20.0 {
            return Err(format!(
                "--stretch-m-per-year: at most a twentieth of --chain-m ({} m a year), got {}",
                number(self.chain_m / 20.0),
                number(self.stretch_m_per_year)
            ));
        }
        real("--misread-rate", self.misread_rate, MISREAD_RATE)?;
        real("--reader-spread", self.reader_spread, READER_SPREAD)?;
        real("--glitch-rate", self.glitch_rate, GLITCH_RATE)?;
        whole(
            "--trolleys-per-year",
            self.trolleys_per_year,
            TROLLEYS_PER_YEAR,
        )?;
        whole(
            "measurements per year",
            self.measurements_per_year,
            (1, 1_000_000),
        )?;
        whole("--docks", self.docks, DOCKS)?;
        whole("--bins", self.bins, BINS)?;
        whole("--readings", self.readings, READINGS)?;
        whole(
            "--reader-alarm-per-mille",
            self.alarm_disagreement_per_mille,
            ALARM_PER_MILLE,
        )?;
        // The voter needs k readings (with cams, or consecutive): more than a passage has would
        // reject every trolley.
        let k = match self.strategy {
            Strategy::Majority { min_samples } => min_samples,
            Strategy::Consecutive { k } => k,
            _ => 1,
        };
        if k == 0 || k > self.readings {
            return Err(format!(
                "--vote-k: must be from 1 to --readings ({}), got {k}",
                self.readings
            ));
        }
        whole(
            "mean gap in pulses",
            self.mean_gap_pulses,
            (MIN_GAP_PULSES, 1000),
        )?;
        Voter::new(self.strategy).map_err(|e| format!("--strategy: {e}"))?;
        Ok(())
    }

    /// The span of the reference initiators on a chain of `chain_m` metres: 300 m as at
    /// commissioning, or ¾ of a shorter chain.
    #[must_use]
    pub fn initiator_span_for(chain_m: f64) -> f64 {
        limits::INITIATOR_SPAN_M.min(0.75 * chain_m)
    }

    /// Pulses each dock runs in the whole simulation.
    #[must_use]
    pub fn pulses_per_dock(&self) -> u64 {
        (self.years * f64::from(self.trolleys_per_year) * f64::from(self.mean_gap_pulses)) as u64
    }

    /// Total pulse steps of a run (every scenario, every dock): the progress bar's length.
    #[must_use]
    pub fn total_steps(&self) -> u64 {
        self.pulses_per_dock() * u64::from(self.docks) * SCENARIOS.len() as u64
    }

    /// Single-scan misread rate of reader `i`.
    #[must_use]
    pub fn reader_rate(&self, i: u8) -> f64 {
        let n = f64::from(self.docks);
        let position = if self.docks > 1 {
            2.0 * f64::from(i) / (n - 1.0) - 1.0
        } else {
            0.0
        };
        self.misread_rate * (1.0 + self.reader_spread * position)
    }

    fn bin_position_m(&self, bin: u16) -> f64 {
        let first = 0.1 * self.chain_m;
        let last = self.chain_m - 0.05 * self.chain_m;
        first + (last - first) * f64::from(bin) / f64::from(self.bins - 1)
    }
}
