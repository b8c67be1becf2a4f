//! What a run gives: its configuration, the trace points, the lines the operator saw, the
//! script lines the controller refused, and the loop's measures — IAE, and the first step's
//! overshoot and settling time, measured as the samples come.

use serde::Serialize;

use super::script::Event;
use super::{Interface, ProcessKind};

/// Simulation parameters (the example's command line).
#[derive(Clone, Debug, Serialize)]
pub struct SimConfig {
    /// The process.
    pub process: ProcessKind,
    /// Seed of the disturbances.
    pub seed: u64,
    /// Simulated hours.
    pub hours: f64,
    /// Which interface starts the controller.
    pub interface: Interface,
    /// Night set-back, scale units (0: none).
    pub night_setback: f64,
    /// Outdoor compensation: feed-forward of the heat loss (room only).
    pub outdoor_compensation: bool,
    /// Mean outdoor temperature, °C (room).
    pub outdoor_mean: f64,
    /// Seconds between trace points handed out (at least one sample period apart).
    pub trace_every_s: f64,
    /// Drive an increase/decrease (three-point) actuator with this full-stroke run time GT,
    /// seconds, instead of the 0–10 V output (the output then means the wanted position).
    #[serde(default)]
    pub three_point_s: Option<f64>,
    /// The timed inputs.
    #[serde(skip)]
    pub script: Vec<Event>,
}

/// A point of the trace.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct TracePoint {
    /// Seconds from the start.
    pub t_s: f64,
    /// Set-point in force.
    pub setpoint: f64,
    /// Measurement.
    pub measurement: f64,
    /// Output, volts.
    pub output: f64,
    /// Outdoor temperature, °C (room only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outdoor: Option<f64>,
}

/// A line the operator saw, with its time.
#[derive(Clone, Debug, Serialize)]
pub struct Shown {
    /// Seconds from the start.
    pub t_s: f64,
    /// Terminal line or LCD picture.
    pub text: String,
}

/// The results.
#[derive(Clone, Debug, Serialize)]
pub struct SimReport {
    /// The parameters.
    pub config: SimConfig,
    /// Integral of |set-point − measurement|, scale units × hours.
    pub iae_unit_hours: f64,
    /// Overshoot of the first approach to the set-point, % of the step.
    pub overshoot_percent: f64,
    /// Time until the measurement stays within 2 % of the first step (at least 0.2 units),
    /// seconds; `None` if it never settles.
    pub settling_time_s: Option<f64>,
    /// Alarms raised.
    pub alarms: u32,
    /// Times (s) at which a commit took effect.
    pub commits_s: Vec<f64>,
    /// A commit was keyed but the run ended before the sample that puts it into force.
    pub commit_pending_at_end: bool,
    /// Samples taken.
    pub samples: u64,
    /// Controller faults seen.
    pub faults: String,
    /// The points the picture is drawn from (at most 3000, evenly spread; the full-resolution
    /// trace goes to the `trace` callback of [`run`](super::run) as it is computed).
    #[serde(skip)]
    pub picture: Vec<TracePoint>,
    /// What the terminal printed and the LCD showed, in order.
    pub shown: Vec<Shown>,
    /// The LCD at the end.
    pub final_lcd: String,
    /// Hours simulated: `config.hours`, or less when the operator quit early.
    pub simulated_h: f64,
    /// Script lines the controller refused (a start-up answer out of range, a change-mode value,
    /// a WRONG COMMAND at the terminal).
    pub refused: Vec<Refusal>,
}

/// A script line the terminal refused, with the controller's answer.
#[derive(Clone, Debug, Serialize)]
pub struct Refusal {
    /// The script's line.
    pub line: usize,
    /// What it typed.
    pub input: String,
    /// What the controller answered.
    pub reply: String,
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "script line {}: the controller refused '{}': {}",
            self.line,
            crate::cli::excerpt(&self.input),
            self.reply
        )
    }
}

/// The first approach to the set-point, measured as the samples come (the same definitions as a
/// pass over the whole trace, without keeping it): overshoot and settling time.
#[derive(Clone, Debug, Default)]
pub(super) struct FirstStep {
    /// Set-point, measurement and step at the first sample.
    start: Option<(f64, f64)>,
    /// Still at the first set-point.
    open: bool,
    overshoot: f64,
    settled_at: Option<f64>,
    out_pending: bool,
}

impl FirstStep {
    pub(super) fn sample(&mut self, t: f64, setpoint: f64, measurement: f64) {
        let (r, step) = match self.start {
            None => {
                let step = setpoint - measurement;
                self.start = Some((setpoint, step));
                self.open = true;
                self.settled_at = Some(0.0);
                (setpoint, step)
            }
            Some(s) => s,
        };
        if !self.open || (setpoint - r).abs() >= 1e-9 {
            self.open = false;
            return;
        }
        if step.abs() < 1e-9 {
            return;
        }
        self.overshoot = self.overshoot.max((measurement - r) * step.signum());
        let band = (0.02 * step.abs()).max(0.2);
        if (measurement - r).abs() > band {
            self.settled_at = None;
            self.out_pending = true;
        } else if self.out_pending {
            self.settled_at = Some(t);
            self.out_pending = false;
        }
    }

    /// Overshoot (% of the step) and settling time.
    pub(super) fn result(&self) -> (f64, Option<f64>) {
        match self.start {
            None => (0.0, None),
            Some((_, step)) if step.abs() < 1e-9 => (0.0, Some(0.0)),
            Some((_, step)) => (100.0 * self.overshoot / step.abs(), self.settled_at),
        }
    }
}
