//! The controller on the crate: `regler_pid::Station` sampling the simulated process through the
//! source's 12-bit A/D and driving it through its 8-bit D/A (or a three-point motor), in
//! simulated time, with the terminal and the keypad in front of it; and the run of a whole
//! script ([`run`]), which measures the loop as it goes (IAE, the first step's overshoot and
//! settling time, alarms, commits).
//!
//! Timing: the plant integrates in steps of [`ProcessKind`]'s `dt` (1 s room, 0.1 s tank); the
//! controller samples when its period S is due; a script's inputs act at the first step at or
//! after their time; an interactive operator's at the step the plant has reached.

use std::ops::ControlFlow;

use regler_pid::{Config, OperatorLimits, Parameters, Scaling, Station};
use serde::Serialize;

use super::keypad::{self, KeyEffect, Keypad};
use super::plant::{HEATER_GAIN, Motor, Plant};
use super::script::{Event, Input};
use super::terminal::{Startup, Terminal};
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
            self.line, self.input, self.reply
        )
    }
}

/// Checks the configuration and the script against what a plant can have (the program's
/// argument parsers check the plain ranges first; this is the check of what depends on the
/// process, and the library's own guard). Errors name the option or the script line.
///
/// # Errors
/// The first value out of its range, in the words of [`cli::real`](crate::cli::real).
pub fn validate(config: &SimConfig) -> Result<(), String> {
    use crate::cli::number;
    let out_of = |option: &str, lo: f64, hi: f64, what: &str, got: f64| {
        format!(
            "{option}: must be from {} to {}{what}, got {}",
            number(lo),
            number(hi),
            number(got)
        )
    };
    if let Some(gt) = config.three_point_s {
        if !(gt.is_finite() && (5.0..=3600.0).contains(&gt)) {
            return Err(out_of(
                "--three-point",
                5.0,
                3600.0,
                " s (the run time)",
                gt,
            ));
        }
    }
    if !(config.hours.is_finite() && config.hours > 0.0 && config.hours <= 24.0 * 365.0) {
        return Err(format!(
            "--hours: must be more than 0 and at most 8760 (a year), got {}",
            number(config.hours)
        ));
    }
    let (scale_lo, scale_hi) = config.process.scale();
    let span = scale_hi - scale_lo;
    if !(config.night_setback.is_finite() && (0.0..=span).contains(&config.night_setback)) {
        return Err(out_of(
            "--night-setback",
            0.0,
            span,
            " (the scale's span)",
            config.night_setback,
        ));
    }
    if !(config.outdoor_mean.is_finite() && (-50.0..=50.0).contains(&config.outdoor_mean)) {
        return Err(out_of(
            "--outdoor-mean",
            -50.0,
            50.0,
            " °C (a climate a building is heated in)",
            config.outdoor_mean,
        ));
    }
    if !(config.trace_every_s.is_finite() && config.trace_every_s > 0.0) {
        return Err(format!(
            "--trace-every: must be more than 0 seconds, got {}",
            number(config.trace_every_s)
        ));
    }
    for event in &config.script {
        if let Input::Outdoor(delta) = event.input {
            if delta.abs() > span {
                return Err(format!(
                    "script line {}: an outdoor step must be within ±{} (the scale's span), got {}",
                    event.line,
                    number(span),
                    number(delta)
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
    refused: Vec<Refusal>,
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
            refused: Vec::new(),
        })
    }

    /// Simulated seconds from the start.
    #[must_use]
    pub fn now(&self) -> f64 {
        self.step as f64 * self.dt
    }

    /// Applies an operator's input now; returns how many lines it added to [`shown`](Sim::shown).
    pub fn input(&mut self, input: &Input) -> usize {
        let event = Event {
            t_s: self.now(),
            line: 0,
            input: input.clone(),
        };
        self.event(&event)
    }

    /// Applies a script's event now (a refused `term` line is noted with its script line);
    /// returns how many lines it added to [`shown`](Sim::shown).
    pub fn event(&mut self, event: &Event) -> usize {
        let before = self.shown.len();
        apply(
            event,
            &mut self.station,
            &mut self.terminal,
            &mut self.keypad,
            &mut self.plant,
            &mut self.shown,
        );
        if let (Input::Term(line), true) = (&event.input, event.line > 0) {
            let reply: Vec<&str> = self.shown[before..]
                .iter()
                .map(|s| s.text.as_str())
                .filter(|t| !t.starts_with("> ") && !t.ends_with("?>"))
                .collect();
            if reply
                .iter()
                .any(|t| t.contains("WRONG") || t.contains("TRY AGAIN"))
            {
                self.refused.push(Refusal {
                    line: event.line,
                    input: line.clone(),
                    reply: reply.join(" / ").trim().to_owned(),
                });
            }
        }
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
            simulated_h: self.now() / 3600.0,
            refused: self.refused.clone(),
        }
    }
}

/// Runs the simulation of `config` with its script; `trace` gets a point every
/// `config.trace_every_s` as it is computed (memory stays flat in the length of the run). When
/// `trace` breaks (its reader has gone), the run ends there and reports what it simulated.
pub fn run(
    config: &SimConfig,
    mut progress: impl FnMut(f64),
    mut trace: impl FnMut(&TracePoint) -> ControlFlow<()>,
) -> Result<SimReport, String> {
    validate(config)?;
    let mut shown: Vec<Shown> = Vec::new();
    let mut refused: Vec<Refusal> = Vec::new();
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
                let asked = terminal.question();
                let (out, result) = terminal.startup_line(line);
                if result.is_none() && terminal.question() == asked {
                    // The question is asked again: the script's next `term` line answers it.
                    let reply: Vec<&str> = out
                        .iter()
                        .map(String::as_str)
                        .filter(|t| !t.ends_with("?>") && !t.ends_with('!'))
                        .collect();
                    refused.push(Refusal {
                        line: event.line,
                        input: line.clone(),
                        reply: if reply.is_empty() {
                            "asked again".into()
                        } else {
                            format!("{} (asked again)", reply.join(" / ").trim())
                        },
                    });
                }
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
    sim.refused = refused;
    let end = config.hours * 3600.0;
    let steps = (end / sim.dt).round() as u64;
    for step in 0..=steps {
        let t = sim.now();
        while let Some(event) = events.next_if(|e| e.t_s <= t) {
            sim.event(event);
        }
        let mut stop = false;
        sim.advance(&mut |p| stop |= trace(p).is_break());
        if stop {
            return Ok(sim.report(config));
        }
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
    use crate::autonomous::script::parse_script;

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
            run(&config, |_| {}, |_| ControlFlow::Continue(()))
                .unwrap_err()
                .contains("start-up dialogue is not finished")
        );
    }
}
