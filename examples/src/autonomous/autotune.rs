//! `--autotune`: the relay auto-tuning experiment on the simulated room or tank (Åström and
//! Hägglund's relay feedback on `regler_pid::tuning`), the Ziegler–Nichols PI it gives, the
//! bumpless hand-over and the tuned loop's answer to a set-point step.

use regler_pid::Config;
use serde::{Serialize, Serializer};

use super::ProcessKind;
use super::plant::Plant;

/// One point of the autotune trace.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct AutotunePoint {
    /// Seconds from the start of the relay experiment.
    pub t_s: f64,
    /// Set-point.
    pub setpoint: f64,
    /// Measurement.
    pub measurement: f64,
    /// Output, volts.
    pub output: f64,
    /// The relay drives the output (false: the tuned PI does).
    pub relay: bool,
}

/// The relay's result as a plain JSON object, never Rust's `{"Ok": …}`.
fn ultimate_json<S: Serializer>(
    ultimate: &Result<(f64, f64), String>,
    s: S,
) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut map = s.serialize_map(Some(2))?;
    match ultimate {
        Ok((ku, tu)) => {
            map.serialize_entry("ku", ku)?;
            map.serialize_entry("tu_s", tu)?;
        }
        Err(why) => map.serialize_entry("failed", why)?,
    }
    map.end()
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
    /// Ultimate gain (V per scale unit) and period (s), or why the experiment failed; in JSON
    /// `{"ku": …, "tu_s": …}` or `{"failed": "why"}`.
    #[serde(serialize_with = "ultimate_json")]
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
    /// The experiment and the step: the relay every 10 s for the room and 0.1 s for the tank,
    /// the tuned PI every 30 s and 1 s.
    pub trace: Vec<AutotunePoint>,
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
    // The limit cycle finer than the step after it: some 50 points a period of the relay.
    let (every_relay, every_pi) = match kind {
        ProcessKind::Room => (10.0, 30.0),
        ProcessKind::Tank => (0.1, 1.0),
    };
    let record = |t: f64, r: f64, y: f64, u: f64, relay: bool, trace: &mut Vec<_>| {
        let every: f64 = if relay { every_relay } else { every_pi };
        if every <= dt || (t / every).fract() < dt / every {
            trace.push(AutotunePoint {
                t_s: t,
                setpoint: r,
                measurement: y,
                output: u,
                relay,
            });
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
