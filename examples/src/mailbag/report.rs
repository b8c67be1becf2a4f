//! What a run found: where the sacks went, the tip-position error, the readers' health and the
//! stretch meter, per scenario, per year and over the run (also the JSON).

use serde::Serialize;

use super::Config;
use super::scenarios::Scenario;

/// Where sacks ended up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Outcomes {
    /// Trolleys that passed a reader with a sack.
    pub sacks: u64,
    /// Into their own bin.
    pub delivered: u64,
    /// Into another bin.
    pub misdelivered: u64,
    /// Sent to the manual station by the reader (no-read or implausible number).
    pub rejected: u64,
    /// Routed, but never tipped: reached the chain end with the sack.
    pub not_tipped: u64,
    /// Routed and still on the chain when the run ended. The five outcomes add up to `sacks`.
    pub on_chain: u64,
}

impl Outcomes {
    pub(super) fn add(&mut self, o: &Outcomes) {
        self.sacks += o.sacks;
        self.delivered += o.delivered;
        self.misdelivered += o.misdelivered;
        self.rejected += o.rejected;
        self.not_tipped += o.not_tipped;
        self.on_chain += o.on_chain;
    }
}

/// Tip-position error statistics: where the tracked trolley was when its tipper was set,
/// against where commissioning meant it to be, in metres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct TipError {
    /// Tipper sets measured.
    pub count: u64,
    /// Mean of |error|.
    pub mean_abs_m: f64,
    /// Largest |error|.
    pub max_abs_m: f64,
    #[serde(skip)]
    sum_abs: f64,
}

impl TipError {
    pub(super) fn record(&mut self, error_m: f64) {
        self.count += 1;
        self.sum_abs += error_m.abs();
        self.max_abs_m = self.max_abs_m.max(error_m.abs());
        self.mean_abs_m = self.sum_abs / self.count as f64;
    }

    pub(super) fn merge(&mut self, o: &TipError) {
        self.count += o.count;
        self.sum_abs += o.sum_abs;
        self.max_abs_m = self.max_abs_m.max(o.max_abs_m);
        self.mean_abs_m = if self.count == 0 {
            0.0
        } else {
            self.sum_abs / self.count as f64
        };
    }
}

/// One simulated year of one scenario, all docks together.
#[derive(Clone, Debug, Default, Serialize)]
pub struct YearReport {
    /// Year number, from 1 (the last may be partial).
    pub year: u32,
    /// Sack outcomes.
    pub outcomes: Outcomes,
    /// Tip-position error.
    pub tip_error: TipError,
}

/// A scenario's results.
#[derive(Clone, Debug, Serialize)]
pub struct ScenarioReport {
    /// The scenario.
    pub scenario: Scenario,
    /// Its name.
    pub name: String,
    /// Sack outcomes over the whole run.
    pub outcomes: Outcomes,
    /// Misdelivered sacks per million.
    pub misdelivered_per_million: f64,
    /// Tip-position error over the whole run.
    pub tip_error: TipError,
    /// Year by year.
    pub years: Vec<YearReport>,
    /// Tip-position error over `CURVE_POINTS` equal stretches of the run, for the picture.
    pub curve: Vec<CurvePoint>,
    /// Recalibrations of the trackers (all docks).
    pub recalibrations: u64,
}

/// One reader's health (from the voting scenario with correction).
#[derive(Clone, Debug, Serialize)]
pub struct ReaderReport {
    /// Dock (and reader) number, from 1.
    pub dock: u8,
    /// The reader's single-scan misread rate in the simulation.
    pub misread_rate: f64,
    /// Passages.
    pub passages: u32,
    /// Passages with a parity error in any scan.
    pub parity_errors: u32,
    /// Passages that gave no trolley.
    pub no_reads: u32,
    /// Passages that decoded two different numbers.
    pub disagreements: u32,
    /// Times the health alarm was raised.
    pub alarms_raised: u32,
    /// Whether the alarm is on at the end.
    pub alarm_at_end: bool,
}

/// The stretch meter at the end (dock 1 of the run with correction and voting).
#[derive(Clone, Debug, Serialize)]
pub struct StretchReport {
    /// Chain stretch the plant ended with, per mille.
    pub actual_per_mille: f64,
    /// Stretch the meter accepted, per mille.
    pub measured_per_mille: i32,
    /// DIA measurements.
    pub measurements: u32,
    /// Whether the stretch alarm is on.
    pub alarm: bool,
}

/// Everything a run found.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The parameters.
    pub config: Config,
    /// One per scenario, in [`SCENARIOS`](super::SCENARIOS) order.
    pub scenarios: Vec<ScenarioReport>,
    /// One per reader.
    pub readers: Vec<ReaderReport>,
    /// The stretch meter.
    pub stretch: StretchReport,
}

/// Points in each scenario's tip-error curve.
pub const CURVE_POINTS: usize = 20;

/// Tip-position error over one stretch of the run.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct CurvePoint {
    /// End of the stretch, years from the start.
    pub years: f64,
    /// The error in that stretch.
    pub tip_error: TipError,
}
