//! The 1985 autonomous PID controller (source 002) on a simulated process, run in simulated
//! time on `regler-pid`'s [`Station`], operated through the source's terminal dialogue or its
//! keypad and LCD.
//!
//! # Processes
//! - **room**: a room heated by a 0–10 V heater through a first-order lag (time constant
//!   30 min) with a dead time of 2 min; 10 V holds the room 40 °C above the outdoor temperature,
//!   which follows a daily sine (mean `outdoor_mean`, ±5 °C) plus seeded weather noise.
//!   Scale 0–40 °C.
//! - **tank**: a tank level fed by a 0–10 V pump, first-order, time constant 30 s, no dead time;
//!   10 V would hold 150 % with the outflow valve shut (the pump sized for the largest outflow
//!   with margin); the valve moves every five minutes (a seeded random walk, 0–30 % of the
//!   inflow range).
//!   Scale 0–100 %.
//!
//! The measurement goes through the source's 12-bit A/D and the output through its 8-bit D/A.
//!
//! # Scripts
//! One command a line, `TIME KIND ARGUMENTS`; `#` starts a comment. TIME is seconds, or with a
//! unit `90s`, `15m`, `2h`, or a clock time `hh:mm`. KIND is
//! - `term TEXT`: a line typed at the terminal (start-up answers, `Y` for the change mode, `C`);
//!   `term` alone is an empty line (CR);
//! - `keys KEYS`: keys pressed on the keypad, e.g. `keys * 21 * A 22 A D` (set-point 22 on the room's 0–40 °C scale; the source's own example keyed 150 on its scale);
//! - `night on|off`: the night input (set-back);
//! - `outdoor DELTA`: a step in the outdoor temperature (room) or outflow (tank), in scale units.

pub mod benchmark;
pub mod keypad;
pub mod terminal;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use regler_pid::{Config, OperatorLimits, Parameters, Scaling, Station};
use serde::Serialize;

use self::keypad::{KeyEffect, Keypad};
use self::terminal::{Startup, Terminal};

/// The simulated process.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ProcessKind {
    /// A heated room (slow, dead time, outdoor disturbance).
    Room,
    /// A tank level (fast).
    Tank,
}

impl ProcessKind {
    /// The measurement scale.
    #[must_use]
    pub fn scale(self) -> (f64, f64) {
        match self {
            ProcessKind::Room => (0.0, 40.0),
            ProcessKind::Tank => (0.0, 100.0),
        }
    }

    /// Integration step, seconds.
    fn dt(self) -> f64 {
        match self {
            ProcessKind::Room => 1.0,
            ProcessKind::Tank => 0.1,
        }
    }
}

/// Which operator interface starts the controller.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Interface {
    /// The terminal: the script's first `term` lines answer the start-up questions.
    Terminal,
    /// The keypad only: the source's keypad start-up values (PID, S = 1 s, KP = 10, TI = 8,
    /// 0–10 V, WIN = SCALEMIN).
    Keypad,
}

/// One operator or plant input.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", content = "value", rename_all = "lowercase")]
pub enum Input {
    /// A line at the terminal.
    Term(String),
    /// Keys on the keypad.
    Keys(String),
    /// The night input.
    Night(bool),
    /// A disturbance step.
    Outdoor(f64),
}

impl std::fmt::Display for Input {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Input::Term(line) => write!(f, "term {line}"),
            Input::Keys(keys) => write!(f, "keys {keys}"),
            Input::Night(on) => write!(f, "night {}", if *on { "on" } else { "off" }),
            Input::Outdoor(delta) => write!(f, "outdoor {delta:+}"),
        }
    }
}

/// A timed input.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Event {
    /// Seconds from the start.
    pub t_s: f64,
    /// The input.
    pub input: Input,
}

/// Parses a script (see the module docs). Errors name the line.
pub fn parse_script(text: &str) -> Result<Vec<Event>, String> {
    let mut events = Vec::new();
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim_end();
        if line.trim().is_empty() {
            continue;
        }
        let err = |what: &str| format!("script line {}: {what}: '{}'", n + 1, raw.trim());
        let mut parts = line.trim_start().splitn(3, char::is_whitespace);
        let time = parts.next().ok_or_else(|| err("missing time"))?;
        let kind = parts
            .next()
            .ok_or_else(|| err("missing command (term, keys, night, outdoor)"))?;
        let rest = parts.next().unwrap_or("").trim();
        let t_s = parse_time(time)
            .ok_or_else(|| err("bad time (use 600, 90s, 15m, 2h or hh:mm, within a year)"))?;
        let input = match kind {
            "term" => Input::Term(rest.to_string()),
            "keys" => Input::Keys(rest.to_string()),
            "night" => match rest {
                "on" => Input::Night(true),
                "off" => Input::Night(false),
                _ => return Err(err("night takes on or off")),
            },
            "outdoor" => Input::Outdoor(
                rest.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| err("outdoor takes a number"))?,
            ),
            _ => return Err(err("unknown command (term, keys, night, outdoor)")),
        };
        events.push(Event { t_s, input });
    }
    events.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
    Ok(events)
}

/// Script times end at a year, the longest run.
const LAST_SCRIPT_S: f64 = 8760.0 * 3600.0;

fn parse_time(s: &str) -> Option<f64> {
    let value = if let Some((h, m)) = s.split_once(':') {
        let (h, m) = (h.parse::<f64>().ok()?, m.parse::<f64>().ok()?);
        (m < 60.0).then_some(h * 3600.0 + m * 60.0)?
    } else if let Some(v) = s.strip_suffix('h') {
        v.parse::<f64>().ok()? * 3600.0
    } else if let Some(v) = s.strip_suffix('m') {
        v.parse::<f64>().ok()? * 60.0
    } else if let Some(v) = s.strip_suffix('s') {
        v.parse::<f64>().ok()?
    } else {
        s.parse::<f64>().ok()?
    };
    (value.is_finite() && (0.0..=LAST_SCRIPT_S).contains(&value)).then_some(value)
}

/// The script used when none is given, one for each way of operating the controller.
///
/// At the terminal: the start-up dialogue, a set-point change on the keypad, an illegal value,
/// the alarm acknowledged, a night set-back, a disturbance and a retune in the change mode. On
/// the keypad alone: every parameter keyed in from the source's keypad start-up values, then the
/// same day of operation on the keys.
#[must_use]
pub fn demo_script(process: ProcessKind, interface: Interface) -> &'static str {
    match (process, interface) {
        (ProcessKind::Room, Interface::Terminal) => {
            "# start-up dialogue at the terminal
0 term PID
0 term 10       # S
0 term 0        # YMIN
0 term 10       # YMAX
0 term 0.5      # DYMAX
0 term 2        # KP
0 term 900      # TI
0 term 60       # TD
0 term 0        # SCALE MIN
0 term 40       # SCALE MAX
0 term DIR
0 term 1.5      # RFEL
0 term 20       # WIN
0 term
# the keypad: WIN 20 -> 22 (the source's example keyed 150 on its own scale)
4h keys * 21 * A 22 A D
# an illegal value stays on the LCD; D with nothing staged is no commit
5h keys * 51 * A 20000 A
5h keys D
6h term C
# night set-back from 22:00 to 06:00
22:00 night on
30:00 night off
# a cold snap
36h outdoor -8
# retune in the change mode: keep TYP and WIN, S 10, KP 3, TI 1200, then quit
40h term Y
40h term
40h term
40h term
40h term 3
40h term 1200
40h term Q
"
        }
        (ProcessKind::Room, Interface::Keypad) => {
            "# the keypad alone: from its start-up values (PID, K 10, Ti 8 s, 1 s, WIN 0) to a room
0 keys * 31 * A 10 A         # S 10 s
0 keys * 51 * A 2 A          # KP 2
0 keys * 71 * A 900 A        # TI 900 s
0 keys * 61 * A 60 A         # TD 60 s
0 keys * 83 * A 0.5 A        # DYMAX 0.5 V a sample
0 keys * 41 * A 1.5 A        # RFEL 1.5
0 keys * 21 * A 20 A D       # WIN 20, and commit them all at the next sample
4h keys * 21 * A 22 A D
5h keys * 51 * A 20000 A     # ILLEGAL VALUE stays on the LCD
5h keys D                    # nothing staged: no commit
6h keys C                    # acknowledge the alarm
22:00 night on
30:00 night off
36h outdoor -8
40h keys * 51 * A 3 A * 71 * A 1200 A D
"
        }
        (ProcessKind::Tank, Interface::Terminal) => {
            "0 term PI
0 term 1        # S
0 term 0
0 term 10
0 term 0        # DYMAX: no limit
0 term 1.5      # KP
0 term 40       # TI
0 term 0
0 term 100
0 term DIR
0 term 5        # RFEL
0 term 50       # WIN
0 term
10m keys * 21 * A 70 A D
20m outdoor 10
30m keys * 10 * A P I D A * 61 * A 1 A D
"
        }
        (ProcessKind::Tank, Interface::Keypad) => {
            "# the keypad alone: a PI for the tank from the keypad start-up values
0 keys * 10 * A P I A        # TYP PI
0 keys * 51 * A 1.5 A        # KP 1.5
0 keys * 71 * A 40 A         # TI 40 s
0 keys * 41 * A 5 A          # RFEL 5 %
0 keys * 21 * A 50 A D       # WIN 50 %, commit
10m keys * 21 * A 70 A D
20m outdoor 10
30m keys * 10 * A P I D A * 61 * A 1 A D
"
        }
    }
}

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
    /// Samples taken.
    pub samples: u64,
    /// Controller faults seen.
    pub faults: String,
    /// The points the picture is drawn from (at most 3000, evenly spread; the full-resolution
    /// trace goes to the `trace` callback of [`run`] as it is computed).
    #[serde(skip)]
    pub picture: Vec<TracePoint>,
    /// What the terminal printed and the LCD showed, in order.
    pub shown: Vec<Shown>,
    /// The LCD at the end.
    pub final_lcd: String,
}

/// Room heater: degrees above outdoor per volt at steady state.
const HEATER_GAIN: f64 = 4.0;
/// Tank level, %, that 1 V of pump holds against a shut outflow valve: the pump is sized for
/// the largest outflow (30 % of the inflow range, plus disturbances) with margin, as one would
/// commission it, so the loop controls instead of saturating at 10 V.
const PUMP_GAIN: f64 = 15.0;

struct Plant {
    kind: ProcessKind,
    x: f64,
    delay: std::collections::VecDeque<f64>,
    disturbance: f64,
    noise: f64,
    rng: ChaCha8Rng,
    outdoor_mean: f64,
}

impl Plant {
    fn new(kind: ProcessKind, seed: u64, outdoor_mean: f64) -> Plant {
        let delay_steps = match kind {
            ProcessKind::Room => 120,
            ProcessKind::Tank => 0,
        };
        let x = match kind {
            ProcessKind::Room => 15.0,
            ProcessKind::Tank => 20.0,
        };
        Plant {
            kind,
            x,
            delay: std::iter::repeat_n(0.0, delay_steps).collect(),
            disturbance: 0.0,
            noise: 0.0,
            rng: ChaCha8Rng::seed_from_u64(seed),
            outdoor_mean,
        }
    }

    /// Outdoor temperature (room) at `t`.
    fn outdoor(&self, t: f64) -> f64 {
        let day = 2.0 * std::f64::consts::PI * (t / 86_400.0 - 0.625);
        self.outdoor_mean + 5.0 * day.sin() + self.disturbance + self.noise
    }

    fn step(&mut self, t: f64, u: f64) {
        let dt = self.kind.dt();
        self.delay.push_back(u);
        let applied = self.delay.pop_front().unwrap_or(u);
        match self.kind {
            ProcessKind::Room => {
                // Weather noise: a slow random walk, pulled back toward zero.
                self.noise += dt * (-self.noise / 7200.0) + 0.01 * (self.rng.random::<f64>() - 0.5);
                let target = self.outdoor(t) + HEATER_GAIN * applied;
                self.x += dt * (target - self.x) / 1800.0;
            }
            ProcessKind::Tank => {
                // The outflow valve moves every five minutes, within its range.
                if (t / 300.0).fract() < dt / 300.0 {
                    self.noise = (self.noise + self.rng.random_range(-2.0..2.0)).clamp(0.0, 30.0);
                }
                let target = PUMP_GAIN * applied - self.disturbance - self.noise;
                self.x += dt * (target - self.x) / 30.0;
                self.x = self.x.clamp(0.0, 100.0);
            }
        }
    }
}

/// What `--autotune` did: the relay experiment on the simulated process, the tuning it gave, and
/// the tuned loop's answer to a set-point step.
#[derive(Clone, Debug, Serialize)]
pub struct AutotuneReport {
    /// The process.
    pub process: ProcessKind,
    /// Output the process was steadied at before the experiment (V).
    pub bias_v: f64,
    /// Relay amplitude (V) and hysteresis (scale units).
    pub relay_v: f64,
    /// Hysteresis, scale units.
    pub hysteresis: f64,
    /// Ultimate gain (V per scale unit) and period (s), or why the experiment failed.
    pub ultimate: Result<(f64, f64), String>,
    /// Seconds the experiment took.
    pub experiment_s: f64,
    /// The tuned PI: K, Ti (Ziegler–Nichols from Ku, Tu).
    pub k: f64,
    /// Integral time, s.
    pub ti: f64,
    /// Set-point step applied after the hand-over (scale units).
    pub step: f64,
    /// Largest output jump at the hand-over (V): bumpless means small.
    pub handover_jump_v: f64,
    /// Overshoot of the step, percent of the step.
    pub overshoot_pct: f64,
    /// Seconds until the measurement stays within 5 % of the step.
    pub settling_s: Option<f64>,
    /// (t s, set-point, measurement, output V, relay on) every few seconds.
    pub trace: Vec<(f64, f64, f64, f64, bool)>,
}

/// Runs the relay experiment on the simulated `kind` (steadied first at half output), tunes a PI
/// controller by Ziegler–Nichols, hands over bumplessly and answers a set-point step.
///
/// # Errors
/// Only for a relay configuration the process cannot take (never with these values).
pub fn autotune(kind: ProcessKind, seed: u64, outdoor_mean: f64) -> Result<AutotuneReport, String> {
    use regler_pid::tuning::{Relay, RelayConfig, RelayStep, ziegler_nichols};
    use regler_pid::{Kind, Pid};
    let dt = kind.dt();
    let (bias, amplitude, hysteresis, step, timeout) = match kind {
        ProcessKind::Room => (4.0, 2.0, 0.1, 2.0, 6.0 * 3600.0),
        ProcessKind::Tank => (3.0, 1.5, 1.0, 10.0, 1800.0),
    };
    let mut plant = Plant::new(kind, seed, outdoor_mean);
    let mut t = 0.0;
    let mut trace = Vec::new();
    let every = match kind {
        ProcessKind::Room => 30.0,
        ProcessKind::Tank => 1.0,
    };
    let record = |t: f64, r: f64, y: f64, u: f64, relay: bool, trace: &mut Vec<_>| {
        if (t / every).fract() < dt / every {
            trace.push((t, r, y, u, relay));
        }
    };
    // Steady at the bias.
    let settle = match kind {
        ProcessKind::Room => 4.0 * 3600.0,
        ProcessKind::Tank => 300.0,
    };
    while t < settle {
        plant.step(t, bias);
        t += dt;
    }
    let setpoint = plant.x;
    let config = RelayConfig {
        bias,
        amplitude,
        hysteresis,
        h: dt,
        cycles: 3,
        tolerance: 0.1,
        timeout,
        ..RelayConfig::default()
    };
    let mut relay = Relay::new(config).map_err(|e| e.to_string())?;
    let start = t;
    let outcome = loop {
        let y = plant.x;
        match relay.update(setpoint, y) {
            Ok(RelayStep::Running(u)) => {
                record(t - start, setpoint, y, u, true, &mut trace);
                plant.step(t, u);
                t += dt;
            }
            Ok(RelayStep::Done(found)) => break Ok(found),
            Err(e) => break Err(e.to_string()),
        }
    };
    let experiment_s = t - start;
    let ultimate = outcome.map(|u| (u.ku, u.tu));
    let Ok((ku, tu)) = ultimate else {
        return Ok(AutotuneReport {
            process: kind,
            bias_v: bias,
            relay_v: amplitude,
            hysteresis,
            ultimate,
            experiment_s,
            k: 0.0,
            ti: 0.0,
            step,
            handover_jump_v: 0.0,
            overshoot_pct: 0.0,
            settling_s: None,
            trace,
        });
    };
    let tuning = ziegler_nichols(regler_pid::tuning::Ultimate { ku, tu }, Kind::PI)
        .map_err(|e| e.to_string())?;
    let mut pid_config = Config::<f64> {
        h: dt,
        ymin: 0.0,
        ymax: 10.0,
        c: 0.0,
        ..Config::default()
    };
    tuning.apply(&mut pid_config).map_err(|e| e.to_string())?;
    let mut pid: Pid<f64> = relay
        .hand_over(&pid_config, setpoint, plant.x)
        .map_err(|e| e.to_string())?;
    let mut last_u = relay.output();
    let mut jump: f64 = 0.0;
    let after = start + experiment_s;
    let run_for = match kind {
        ProcessKind::Room => 8.0 * 3600.0,
        ProcessKind::Tank => 600.0,
    };
    let step_at = after + run_for / 8.0;
    let (mut peak, mut settled_at): (f64, Option<f64>) = (f64::NEG_INFINITY, None);
    while t < after + run_for {
        let r = if t >= step_at {
            setpoint + step
        } else {
            setpoint
        };
        let y = plant.x;
        let u = pid.update(r, y);
        if t < after + 10.0 * dt {
            jump = jump.max((u - last_u).abs());
        }
        last_u = u;
        if t >= step_at {
            peak = peak.max(y);
            let inside = (y - (setpoint + step)).abs() <= 0.05 * step;
            settled_at = match (settled_at, inside) {
                (None, true) => Some(t - step_at),
                (Some(s), true) => Some(s),
                (_, false) => None,
            };
        }
        record(t - start, r, y, u, false, &mut trace);
        plant.step(t, u);
        t += dt;
    }
    Ok(AutotuneReport {
        process: kind,
        bias_v: bias,
        relay_v: amplitude,
        hysteresis,
        ultimate,
        experiment_s,
        k: tuning.k,
        ti: tuning.ti,
        step,
        handover_jump_v: jump,
        overshoot_pct: 100.0 * ((peak - setpoint - step) / step).max(0.0),
        settling_s: settled_at,
        trace,
    })
}

/// Checks the configuration and the script against what a plant can have.
fn validate(config: &SimConfig) -> Result<(), String> {
    if let Some(gt) = config.three_point_s {
        if !(gt.is_finite() && (5.0..=3600.0).contains(&gt)) {
            return Err(format!("three-point run time must be 5..=3600 s, got {gt}"));
        }
    }
    if !(config.hours.is_finite() && config.hours > 0.0 && config.hours <= 24.0 * 365.0) {
        return Err(format!(
            "hours must be more than 0 and at most 8760 (a year), got {}",
            config.hours
        ));
    }
    let (scale_lo, scale_hi) = config.process.scale();
    let span = scale_hi - scale_lo;
    if !(config.night_setback.is_finite() && (0.0..=span).contains(&config.night_setback)) {
        return Err(format!(
            "night-setback must be between 0 and the scale's span ({span}), got {}",
            config.night_setback
        ));
    }
    if !(config.outdoor_mean.is_finite() && (-50.0..=50.0).contains(&config.outdoor_mean)) {
        return Err(format!(
            "outdoor-mean must be between -50 and 50 °C (a climate a building is heated in), got {}",
            config.outdoor_mean
        ));
    }
    if !(config.trace_every_s.is_finite() && config.trace_every_s > 0.0) {
        return Err(format!(
            "trace-every must be more than 0 seconds, got {}",
            config.trace_every_s
        ));
    }
    for event in &config.script {
        if let Input::Outdoor(delta) = event.input {
            if delta.abs() > span {
                return Err(format!(
                    "an outdoor step must be within ±{span} (the scale's span), got {delta}"
                ));
            }
        }
    }
    Ok(())
}

/// The start-up for the keypad interface: the source's keypad start-up values.
pub fn keypad_startup(process: ProcessKind) -> Result<Startup, String> {
    let (scale_min, scale_max) = process.scale();
    let scaling = Scaling::new(scale_min, scale_max).map_err(|e| e.to_string())?;
    let params = Parameters {
        config: Config::default(),
        setpoint: scale_min,
        rfel: 0.1 * (scale_max - scale_min),
        night_setback: 0.0,
    };
    Ok(Startup { params, scaling })
}

/// The first approach to the set-point, measured as the samples come (the same definitions as a
/// pass over the whole trace, without keeping it): overshoot and settling time.
#[derive(Clone, Debug, Default)]
struct FirstStep {
    /// Set-point, measurement and step at the first sample.
    start: Option<(f64, f64)>,
    /// Still at the first set-point.
    open: bool,
    overshoot: f64,
    settled_at: Option<f64>,
    out_pending: bool,
}

impl FirstStep {
    fn sample(&mut self, t: f64, setpoint: f64, measurement: f64) {
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
    fn result(&self) -> (f64, Option<f64>) {
        match self.start {
            None => (0.0, None),
            Some((_, step)) if step.abs() < 1e-9 => (0.0, Some(0.0)),
            Some((_, step)) => (100.0 * self.overshoot / step.abs(), self.settled_at),
        }
    }
}

/// Points kept for the picture: at most `PICTURE_POINTS`, evenly spread over the run so far
/// (when full, every other point goes and the spacing doubles), so memory stays flat however
/// long the run.
const PICTURE_POINTS: usize = 3000;

/// The controller, its operator interfaces and the process, advanced step by step: a script
/// drives it in [`run`], an operator at a terminal in the program's `--interactive` mode.
pub struct Sim {
    process: ProcessKind,
    outdoor_compensation: bool,
    trace_every_s: f64,
    station: Station<f32>,
    scaling: Scaling,
    terminal: Terminal,
    keypad: Keypad,
    plant: Plant,
    step: u64,
    dt: f64,
    next_sample: f64,
    next_trace: f64,
    u: f64,
    samples: u64,
    iae: f64,
    commits: Vec<f64>,
    first: FirstStep,
    picture: Vec<TracePoint>,
    picture_stride: u64,
    motor: Option<Motor>,
    /// Lines the operator saw.
    pub shown: Vec<Shown>,
}

/// A three-point actuator: the driver (with its position estimate) and the real motor.
struct Motor {
    driver: regler_pid::actuator::ThreePoint<f64>,
    gt: f64,
    h: f64,
    /// Where the motor really is, 0..1.
    position: f64,
    /// Seconds of the current pulse still to run, and its direction.
    pulse_left: f64,
    opening: bool,
    /// The controller output at the last sample (V).
    last_u: f64,
}

impl Motor {
    fn new(gt: f64, h: f64, position: f64) -> Result<Motor, String> {
        use regler_pid::actuator::{ActuatorConfig, ThreePoint};
        let config = ActuatorConfig {
            run_time: gt,
            min_pulse: 0.2f64.min(h),
            dead_band: 0.005,
            h,
        };
        let driver = ThreePoint::new(config, position).map_err(|e| e.to_string())?;
        Ok(Motor {
            driver,
            gt,
            h,
            position,
            pulse_left: 0.0,
            opening: false,
            last_u: 10.0 * position,
        })
    }

    /// A new sample: the controller's output changed by `delta_volts` (10 V = the full stroke).
    fn command(&mut self, delta_volts: f64, h: f64) {
        use regler_pid::actuator::Drive;
        if (h - self.h).abs() > 1e-9 {
            // The operator changed the sample period: the longest pulse changes with it.
            if let Ok(m) = Motor::new(self.gt, h, self.driver.position()) {
                let (position, last_u) = (self.position, self.last_u);
                *self = m;
                (self.position, self.last_u) = (position, last_u);
            }
        }
        match self.driver.update_delta(delta_volts / 10.0) {
            Ok(Drive::Open(s)) => (self.pulse_left, self.opening) = (s, true),
            Ok(Drive::Close(s)) => (self.pulse_left, self.opening) = (s, false),
            _ => self.pulse_left = 0.0,
        }
    }

    /// The motor runs for `dt` seconds (or what is left of the pulse); returns its output in
    /// volts-equivalent (10 V = fully open).
    fn run(&mut self, dt: f64) -> f64 {
        let m = dt.min(self.pulse_left);
        if m > 0.0 {
            let moved = m / self.gt;
            self.position = if self.opening {
                (self.position + moved).min(1.0)
            } else {
                (self.position - moved).max(0.0)
            };
            self.pulse_left -= m;
        }
        10.0 * self.position
    }
}

impl Sim {
    /// A controller started from `startup`, on the process of `config`.
    pub fn new(config: &SimConfig, startup: Startup, terminal: Terminal) -> Result<Sim, String> {
        let mut params = startup.params;
        params.night_setback = config.night_setback;
        let station = Station::<f32>::new(params, startup.scaling, OperatorLimits::default())
            .map_err(|e| e.to_string())?;
        Ok(Sim {
            process: config.process,
            outdoor_compensation: config.outdoor_compensation,
            trace_every_s: config.trace_every_s,
            station,
            scaling: startup.scaling,
            terminal,
            keypad: Keypad::new(),
            plant: Plant::new(config.process, config.seed, config.outdoor_mean),
            step: 0,
            dt: config.process.dt(),
            next_sample: 0.0,
            next_trace: 0.0,
            u: 0.0,
            samples: 0,
            iae: 0.0,
            commits: Vec::new(),
            first: FirstStep::default(),
            picture: Vec::new(),
            picture_stride: 1,
            motor: match config.three_point_s {
                Some(gt) => Some(Motor::new(gt, params.config.h, 0.0)?),
                None => None,
            },
            shown: Vec::new(),
        })
    }

    /// Simulated seconds from the start.
    #[must_use]
    pub fn now(&self) -> f64 {
        self.step as f64 * self.dt
    }

    /// Applies an operator's input now; returns how many lines it added to [`shown`](Sim::shown).
    pub fn input(&mut self, input: &Input) -> usize {
        let before = self.shown.len();
        let event = Event {
            t_s: self.now(),
            input: input.clone(),
        };
        apply(
            &event,
            &mut self.station,
            &mut self.terminal,
            &mut self.keypad,
            &mut self.plant,
            &mut self.shown,
        );
        self.shown.len() - before
    }

    /// Runs one integration step (with a controller sample when one is due); `trace` gets a
    /// point every `trace_every_s`.
    pub fn advance(&mut self, trace: &mut impl FnMut(&TracePoint)) {
        let t = self.now();
        let (dt, scaling) = (self.dt, self.scaling);
        if t + 1e-9 >= self.next_sample {
            let before = self.station.commits();
            if self.outdoor_compensation && self.process == ProcessKind::Room {
                // Heat the building loses now, in heater volts: (set-point − outdoor) / gain.
                let loss = (self.station.setpoint() - self.plant.outdoor(t)) / HEATER_GAIN;
                self.station.set_feedforward(loss);
            }
            let measured = scaling
                .count_to_units(scaling.units_to_count(self.plant.x))
                .unwrap_or(self.plant.x);
            let y = self.station.sample(measured);
            self.u = Scaling::volts_to_dac(y)
                .map(Scaling::dac_to_volts)
                .unwrap_or(0.0);
            if let Some(motor) = &mut self.motor {
                // Velocity form: the motor integrates the controller's output changes; changes
                // below a minimum pulse add up in the driver, none is lost.
                let h = self.station.staged().active().config.h;
                motor.command(self.u - motor.last_u, h);
                motor.last_u = self.u;
            }
            if self.station.commits() > before {
                self.commits.push(t);
            }
            self.next_sample += self.station.staged().active().config.h;
            self.samples += 1;
            let point = TracePoint {
                t_s: t,
                setpoint: self.station.setpoint(),
                measurement: measured,
                output: self.u,
                outdoor: (self.process == ProcessKind::Room).then(|| self.plant.outdoor(t)),
            };
            self.first.sample(t, point.setpoint, point.measurement);
            if t + 1e-9 >= self.next_trace {
                trace(&point);
                self.next_trace += self.trace_every_s;
            }
            if self.samples.is_multiple_of(self.picture_stride) {
                if self.picture.len() == PICTURE_POINTS {
                    let kept: Vec<TracePoint> = self.picture.iter().step_by(2).copied().collect();
                    self.picture = kept;
                    self.picture_stride *= 2;
                }
                self.picture.push(point);
            }
            self.keypad.show_status(&self.station);
        }
        self.iae += (self.station.setpoint() - self.plant.x).abs() * dt;
        let applied = match &mut self.motor {
            Some(motor) => motor.run(dt),
            None => self.u,
        };
        self.plant.step(t, applied);
        self.step += 1;
    }

    /// The terminal's status line now.
    #[must_use]
    pub fn status(&self) -> String {
        Terminal::status(&self.station)
    }

    /// The LCD now.
    #[must_use]
    pub fn lcd(&self) -> String {
        self.keypad.lcd().render()
    }

    /// The results so far.
    #[must_use]
    pub fn report(&self, config: &SimConfig) -> SimReport {
        let (overshoot, settling) = self.first.result();
        SimReport {
            config: config.clone(),
            iae_unit_hours: self.iae / 3600.0,
            overshoot_percent: overshoot,
            settling_time_s: settling,
            alarms: self.station.alarm().raised(),
            commits_s: self.commits.clone(),
            samples: self.samples,
            faults: self.station.pid().faults().to_string(),
            picture: self.picture.clone(),
            shown: self.shown.clone(),
            final_lcd: self.lcd(),
        }
    }
}

/// Runs the simulation of `config` with its script; `trace` gets a point every
/// `config.trace_every_s` as it is computed (memory stays flat in the length of the run).
pub fn run(
    config: &SimConfig,
    mut progress: impl FnMut(f64),
    mut trace: impl FnMut(&TracePoint),
) -> Result<SimReport, String> {
    validate(config)?;
    let mut shown: Vec<Shown> = Vec::new();
    let mut events = config.script.iter().peekable();
    let mut terminal = Terminal::new();
    let startup = match config.interface {
        Interface::Keypad => keypad_startup(config.process)?,
        Interface::Terminal => {
            for line in Terminal::banner() {
                shown.push(Shown {
                    t_s: 0.0,
                    text: line,
                });
            }
            let mut done = None;
            while done.is_none() {
                let Some(event) = events.next_if(|e| matches!(e.input, Input::Term(_))) else {
                    return Err(
                        "the start-up dialogue is not finished: the script must answer every \
                                question with `term` lines before any other command"
                            .into(),
                    );
                };
                let Input::Term(line) = &event.input else {
                    continue;
                };
                shown.push(Shown {
                    t_s: event.t_s,
                    text: format!("> {line}"),
                });
                let (out, result) = terminal.startup_line(line);
                shown.extend(out.into_iter().map(|text| Shown {
                    t_s: event.t_s,
                    text,
                }));
                done = result;
            }
            done.ok_or("start-up did not finish")?
        }
    };
    let mut sim = Sim::new(config, startup, terminal)?;
    sim.shown = shown;
    let end = config.hours * 3600.0;
    let steps = (end / sim.dt).round() as u64;
    for step in 0..=steps {
        let t = sim.now();
        while let Some(event) = events.next_if(|e| e.t_s <= t) {
            sim.input(&event.input);
        }
        sim.advance(&mut trace);
        if step % 100_000 == 0 {
            progress(step as f64 / steps.max(1) as f64);
        }
    }
    for event in events {
        sim.shown.push(Shown {
            t_s: event.t_s,
            text: format!("(not reached: {} after the end of the run)", event.input),
        });
    }
    progress(1.0);
    Ok(sim.report(config))
}

fn apply(
    event: &Event,
    station: &mut Station<f32>,
    terminal: &mut Terminal,
    keypad: &mut Keypad,
    plant: &mut Plant,
    shown: &mut Vec<Shown>,
) {
    let t_s = event.t_s;
    match &event.input {
        Input::Term(line) => {
            shown.push(Shown {
                t_s,
                text: format!("> {line}"),
            });
            for text in terminal.running_line(line, station) {
                shown.push(Shown { t_s, text });
            }
        }
        Input::Keys(sequence) => {
            // The screen after every key that showed a message stays in the transcript: a
            // refused entry is seen even when more keys follow on the same line.
            let mut pressed = String::new();
            for key in keypad::keys(sequence) {
                pressed.push(key);
                pressed.push(' ');
                if let KeyEffect::Message(_) = keypad.press(key, station) {
                    shown.push(Shown {
                        t_s,
                        text: format!("keys: {}\n{}", pressed.trim_end(), keypad.lcd().render()),
                    });
                    pressed.clear();
                }
            }
            if !pressed.is_empty() {
                shown.push(Shown {
                    t_s,
                    text: format!("keys: {}\n{}", pressed.trim_end(), keypad.lcd().render()),
                });
            }
        }
        Input::Night(on) => {
            station.set_night(*on);
            shown.push(Shown {
                t_s,
                text: format!("night input {}", if *on { "on" } else { "off" }),
            });
        }
        Input::Outdoor(delta) => {
            plant.disturbance += delta;
            shown.push(Shown {
                t_s,
                text: format!("disturbance step {delta:+}"),
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn script_times_and_errors() {
        let events =
            parse_script("# c\n90s term PI\n2h keys * 21 *\n22:30 night on\n10m outdoor -3\n")
                .unwrap();
        let times: Vec<f64> = events.iter().map(|e| e.t_s).collect();
        assert_eq!(times, [90.0, 600.0, 7200.0, 81_000.0]);
        assert!(parse_script("x term").unwrap_err().contains("line 1"));
        assert!(
            parse_script("0 dance")
                .unwrap_err()
                .contains("unknown command")
        );
        assert!(parse_script("0 night maybe").is_err());
        assert!(parse_script("10:75 night on").is_err());
    }

    #[test]
    fn unfinished_startup_is_an_error() {
        let config = SimConfig {
            process: ProcessKind::Room,
            seed: 1,
            hours: 1.0,
            interface: Interface::Terminal,
            night_setback: 0.0,
            outdoor_compensation: false,
            outdoor_mean: 0.0,
            trace_every_s: 60.0,
            three_point_s: None,
            script: parse_script("0 term PID\n0 keys *").unwrap(),
        };
        assert!(
            run(&config, |_| {}, |_| {})
                .unwrap_err()
                .contains("start-up dialogue is not finished")
        );
    }
}
