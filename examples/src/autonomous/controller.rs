//! The controller on the crate: `regler_pid::Station` sampling the simulated process through the
//! source's 12-bit A/D and driving it through its 8-bit D/A (or a three-point motor), in
//! simulated time, with the terminal and the keypad in front of it; and the run of a whole
//! script ([`run`]), which measures the loop as it goes ([`super::report`]: IAE, the first
//! step's overshoot and settling time, alarms, commits).
//!
//! Timing: the plant integrates in steps of [`ProcessKind`]'s `dt` (1 s room, 0.1 s tank); the
//! controller samples when its period S is due; a script's inputs act at the first step at or
//! after their time; an interactive operator's at the step the plant has reached.

use std::ops::ControlFlow;

use regler_pid::{Config, OperatorLimits, Parameters, Scaling, Station};

use super::keypad::{self, KeyEffect, Keypad};
use super::plant::{HEATER_GAIN, Motor, Plant};
use super::report::FirstStep;
use super::script::{Event, Input};
use super::startup::{Number, Question, Startup, unfinished};
use super::terminal::Terminal;
use super::{Interface, ProcessKind, Refusal, Shown, SimConfig, SimReport, TracePoint};
use crate::cli::excerpt;

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
    station: Station<Number>,
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
    /// The script line (and its text) that made the pending commit, to name if it is refused.
    commit_line: Option<(usize, String)>,
}

impl Sim {
    /// A controller started from `startup`, on the process of `config`.
    pub fn new(config: &SimConfig, startup: Startup, terminal: Terminal) -> Result<Sim, String> {
        let mut params = startup.params;
        params.night_setback = config.night_setback;
        let station = Station::<Number>::new(params, startup.scaling, OperatorLimits::default())
            .map_err(super::startup::words)?;
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
            commit_line: None,
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
            if self.station.staged().commit_pending() {
                self.commit_line = Some((event.line, line.clone()));
            }
            if reply
                .iter()
                .any(|t| t.contains("WRONG") || t.contains("TRY AGAIN") || t.contains("REFUSED"))
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
            let pending = self.station.staged().commit_pending();
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
            } else if let (true, Some(e)) = (pending, self.station.refused_commit()) {
                // The library refused the commit at this sample: the operator is told, the
                // edits are discarded, and a script names the line that committed.
                let why = super::startup::words(e);
                let lines = super::terminal::refused_commit(&mut self.station, &why);
                if let Some((line, input)) = self.commit_line.take().filter(|(l, _)| *l > 0) {
                    self.refused.push(Refusal {
                        line,
                        input,
                        reply: lines.join(" / "),
                    });
                }
                self.shown
                    .extend(lines.into_iter().map(|text| Shown { t_s: t, text }));
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
            commit_pending_at_end: self.station.staged().commit_pending(),
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
    let mut terminal = Terminal::with_night_setback(config.night_setback);
    let startup = match config.interface {
        Interface::Keypad => keypad_startup(config.process)?,
        Interface::Terminal => {
            for line in Terminal::banner() {
                shown.push(Shown {
                    t_s: 0.0,
                    text: line,
                });
            }
            loop {
                let Some(event) = events.next_if(|e| matches!(e.input, Input::Term(_))) else {
                    let named: Vec<String> = refused.iter().map(ToString::to_string).collect();
                    let question = terminal.question().unwrap_or(Question::Start);
                    return Err(unfinished(
                        "the script must answer every question with `term` lines before any \
                         other command",
                        question,
                        &named,
                    ));
                };
                let Input::Term(line) = &event.input else {
                    continue;
                };
                shown.push(Shown {
                    t_s: event.t_s,
                    text: format!("> {}", excerpt(line)),
                });
                let answer = terminal.startup_line(line);
                if let Some(reply) = answer.refused {
                    // The question is asked again: the script's next `term` line answers it.
                    refused.push(Refusal {
                        line: event.line,
                        input: line.clone(),
                        reply,
                    });
                }
                shown.extend(answer.lines.into_iter().map(|text| Shown {
                    t_s: event.t_s,
                    text,
                }));
                if let Some(startup) = answer.started {
                    break startup;
                }
            }
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
    station: &mut Station<Number>,
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
                text: format!("> {}", excerpt(line)),
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
