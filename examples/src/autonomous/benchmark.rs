//! Automatic tuning on Åström and Hägglund's PID benchmark processes: for each process the relay
//! experiment (→ Ziegler–Nichols) and a logged step response (→ FOPDT → AMIGO, SIMC) are run in
//! simulation, exactly as a commissioning engineer would run them on the plant; each tuning is
//! then judged in closed loop (IAE for a set-point step and for a load step, overshoot) and by
//! its maximum sensitivity Ms = max |1/(1 + C(iω)P(iω))|.

use std::collections::VecDeque;
use std::f64::consts::PI;

use regler_pid::tuning::{
    Relay, RelayConfig, RelayStep, Tuning, Ultimate, amigo, identify_step, simc, ziegler_nichols,
};
use regler_pid::{Config, Kind, Pid};
use serde::Serialize;

/// Sample period of every simulation here, seconds.
const H: f64 = 0.01;

/// A benchmark process.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum Benchmark {
    /// 1/(s + 1)^n.
    Lags(usize),
    /// e^(−s)/(1 + sT).
    DeadTime(f64),
    /// (1 − αs)/(s + 1)³: a non-minimum-phase zero.
    InverseResponse(f64),
    /// 1/(s(s + 1)²): integrating.
    Integrating,
}

impl Benchmark {
    /// The set the evaluation runs.
    #[must_use]
    pub fn all() -> Vec<Benchmark> {
        vec![
            Benchmark::Lags(3),
            Benchmark::Lags(4),
            Benchmark::Lags(8),
            Benchmark::DeadTime(0.1),
            Benchmark::DeadTime(1.0),
            Benchmark::DeadTime(10.0),
            Benchmark::InverseResponse(0.5),
            Benchmark::Integrating,
        ]
    }

    /// Its transfer function, as text.
    #[must_use]
    pub fn name(self) -> String {
        match self {
            Benchmark::Lags(n) => format!("1/(s+1)^{n}"),
            Benchmark::DeadTime(t) => format!("e^-s/(1+{t}s)"),
            Benchmark::InverseResponse(a) => format!("(1-{a}s)/(s+1)^3"),
            Benchmark::Integrating => "1/(s(s+1)^2)".into(),
        }
    }

    /// The frequency response P(iω) as (re, im).
    fn response(self, w: f64) -> (f64, f64) {
        let lag = |t: f64, n: usize| {
            // 1/(1 + iωt)^n: magnitude (1 + ω²t²)^(−n/2), phase −n·atan(ωt).
            let m = (1.0 + w * w * t * t).powf(-(n as f64) / 2.0);
            let p = -(n as f64) * (w * t).atan();
            (m, p)
        };
        let (m, p) = match self {
            Benchmark::Lags(n) => lag(1.0, n),
            Benchmark::DeadTime(t) => {
                let (m, p) = lag(t, 1);
                (m, p - w)
            }
            Benchmark::InverseResponse(a) => {
                let (m, p) = lag(1.0, 3);
                (m * (1.0 + a * a * w * w).sqrt(), p - (a * w).atan())
            }
            Benchmark::Integrating => {
                let (m, p) = lag(1.0, 2);
                (m / w, p - PI / 2.0)
            }
        };
        (m * p.cos(), m * p.sin())
    }
}

/// The process simulated at `H`: lags stepped exactly (zero-order hold), the dead time as a
/// delay line, the zero as a combination of states, the integrator by the rectangle rule.
struct Plant {
    kind: Benchmark,
    lags: Vec<f64>,
    a: f64,
    delay: VecDeque<f64>,
    integral: f64,
}

impl Plant {
    fn new(kind: Benchmark) -> Plant {
        let (n, t, dead) = match kind {
            Benchmark::Lags(n) => (n, 1.0, 0.0),
            Benchmark::DeadTime(t) => (1, t, 1.0),
            Benchmark::InverseResponse(_) => (3, 1.0, 0.0),
            Benchmark::Integrating => (2, 1.0, 0.0),
        };
        Plant {
            kind,
            lags: vec![0.0; n],
            a: (-H / t).exp(),
            delay: VecDeque::from(vec![0.0; (dead / H).round() as usize]),
            integral: 0.0,
        }
    }

    fn output(&self) -> f64 {
        let last = self.lags.last().copied().unwrap_or(0.0);
        match self.kind {
            Benchmark::InverseResponse(alpha) => {
                let before = self.lags.get(1).copied().unwrap_or(0.0);
                last - alpha * (before - last) // x3 − α·x3'
            }
            _ => last,
        }
    }

    fn step(&mut self, u: f64) {
        self.delay.push_back(u);
        let mut input = self.delay.pop_front().unwrap_or(u);
        if self.kind == Benchmark::Integrating {
            self.integral += H * input;
            input = self.integral;
        }
        for x in &mut self.lags {
            *x = self.a * *x + (1.0 - self.a) * input;
            input = *x;
        }
    }
}

/// One tuning judged.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// The process.
    pub process: String,
    /// The rule.
    pub rule: String,
    /// K, Ti, Td.
    pub k: f64,
    /// Integral time.
    pub ti: f64,
    /// Derivative time.
    pub td: f64,
    /// Set-point weight.
    pub b: f64,
    /// IAE of a unit set-point step (over 25 % of the run).
    pub iae_setpoint: f64,
    /// IAE of a unit load step at the process input.
    pub iae_load: f64,
    /// Set-point overshoot, percent.
    pub overshoot_pct: f64,
    /// Maximum sensitivity.
    pub ms: f64,
}

/// What the experiments found for one process.
#[derive(Clone, Debug, Serialize)]
pub struct Found {
    /// The process.
    pub process: String,
    /// Relay estimate (None when the experiment failed, with why).
    pub ultimate: Option<(f64, f64)>,
    /// The analytic ultimate point where it has one.
    pub ultimate_true: Option<(f64, f64)>,
    /// FOPDT (K, T, L) from the step, or why not; in JSON `{"k": …, "t": …, "l": …}` or
    /// `{"none": "why"}`.
    #[serde(serialize_with = "fopdt_json")]
    pub fopdt: Result<(f64, f64, f64), String>,
    /// The tunings judged.
    pub rows: Vec<Row>,
}

/// The step model as a plain JSON object, never Rust's `{"Ok": …}`.
fn fopdt_json<S: serde::Serializer>(
    fopdt: &Result<(f64, f64, f64), String>,
    s: S,
) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut map = s.serialize_map(None)?;
    match fopdt {
        Ok((k, t, l)) => {
            map.serialize_entry("k", k)?;
            map.serialize_entry("t", t)?;
            map.serialize_entry("l", l)?;
        }
        Err(why) => map.serialize_entry("none", why)?,
    }
    map.end()
}

fn relay(kind: Benchmark) -> Option<Ultimate> {
    let mut plant = Plant::new(kind);
    let mut relay = Relay::new(RelayConfig {
        h: H,
        hysteresis: 0.002,
        timeout: 3_000.0,
        ..RelayConfig::default()
    })
    .ok()?;
    loop {
        match relay.update(0.0, plant.output()).ok()? {
            RelayStep::Running(u) => plant.step(u),
            RelayStep::Done(u) => return Some(u),
        }
    }
}

fn ultimate_true(kind: Benchmark) -> Option<(f64, f64)> {
    // Bisection on the phase reaching −π (all these are monotone in phase).
    let phase = |w: f64| {
        let (re, im) = kind.response(w);
        let mut p = im.atan2(re);
        // Unwrap: the phase only decreases with ω here.
        let approx = match kind {
            Benchmark::Lags(n) => -(n as f64) * w.atan(),
            Benchmark::DeadTime(t) => -(w * t).atan() - w,
            Benchmark::InverseResponse(a) => -3.0 * w.atan() - (a * w).atan(),
            Benchmark::Integrating => -PI / 2.0 - 2.0 * w.atan(),
        };
        while p - approx > PI {
            p -= 2.0 * PI;
        }
        while approx - p > PI {
            p += 2.0 * PI;
        }
        p
    };
    let (mut lo, mut hi) = (1e-4, 100.0);
    if phase(hi) > -PI {
        return None;
    }
    for _ in 0..200 {
        let mid = (lo * hi).sqrt();
        if phase(mid) > -PI { lo = mid } else { hi = mid }
    }
    let (re, im) = kind.response(lo);
    Some((1.0 / (re * re + im * im).sqrt(), 2.0 * PI / lo))
}

fn step_model(kind: Benchmark) -> Result<(f64, f64, f64), String> {
    let mut plant = Plant::new(kind);
    let samples: Vec<f64> = (0..(200.0 / H) as usize)
        .map(|_| {
            let y = plant.output();
            plant.step(1.0);
            y
        })
        .collect();
    identify_step(&samples, H, 1.0)
        .map(|m| (m.gain, m.time_constant, m.dead_time))
        .map_err(|e| match e {
            regler_pid::tuning::IdentifyError::NotSettled(_) => {
                "the step response does not settle".to_string()
            }
            other => other.to_string(),
        })
}

/// Ms of the loop with the ideal continuous controller K(1 + 1/(sTi) + sTd/(1 + sTd/N)).
fn max_sensitivity(kind: Benchmark, t: &Tuning, n: f64) -> f64 {
    let mut ms: f64 = 0.0;
    for k in 0..4000 {
        let w = 10f64.powf(-3.0 + 5.0 * k as f64 / 4000.0);
        // C(iω) = K(1 − i/(ωTi) + iωTd/(1 + iωTd/N)).
        let (mut cre, mut cim) = (1.0, 0.0);
        if t.kind.has_i() {
            cim -= 1.0 / (w * t.ti);
        }
        if t.td > 0.0 {
            let (dre, dim) = (1.0, w * t.td / n);
            let den = dre * dre + dim * dim;
            // iωTd / (1 + iωTd/N)
            let (nre, nim) = (0.0, w * t.td);
            cre += (nre * dre + nim * dim) / den;
            cim += (nim * dre - nre * dim) / den;
        }
        let (cre, cim) = (t.k * cre, t.k * cim);
        let (pre, pim) = kind.response(w);
        let (lre, lim) = (cre * pre - cim * pim, cre * pim + cim * pre);
        let s = 1.0 / ((1.0 + lre).powi(2) + lim * lim).sqrt();
        ms = ms.max(s);
    }
    ms
}

fn closed_loop(kind: Benchmark, rule: &str, t: Tuning) -> Option<Row> {
    let seconds = match kind {
        Benchmark::Lags(n) => 40.0 * n as f64,
        Benchmark::DeadTime(tc) => 60.0 + 20.0 * tc,
        _ => 200.0,
    };
    let mut config = Config::<f64> {
        h: H,
        n: 10.0,
        c: 0.0,
        ymin: -100.0,
        ymax: 100.0,
        ..Config::default()
    };
    t.apply(&mut config).ok()?;
    let mut pid: Pid<f64> = Pid::new(&config).ok()?;
    let mut plant = Plant::new(kind);
    let steps = (seconds / H) as usize;
    let (mut iae_sp, mut iae_load, mut peak) = (0.0, 0.0, 0.0f64);
    for k in 0..steps {
        let y = plant.output();
        let e = 1.0 - y;
        if k < steps / 2 {
            iae_sp += e.abs() * H;
            peak = peak.max(y);
        } else {
            iae_load += e.abs() * H;
        }
        let u = pid.update(1.0, y);
        let load = if k >= steps / 2 { 1.0 } else { 0.0 };
        plant.step(u + load);
    }
    Some(Row {
        process: kind.name(),
        rule: rule.into(),
        k: t.k,
        ti: t.ti,
        td: t.td,
        b: t.b,
        iae_setpoint: iae_sp,
        iae_load,
        overshoot_pct: 100.0 * (peak - 1.0).max(0.0),
        ms: max_sensitivity(kind, &t, 10.0),
    })
}

/// Runs the whole evaluation.
#[must_use]
pub fn evaluate() -> Vec<Found> {
    Benchmark::all()
        .into_iter()
        .map(|kind| {
            let ultimate = relay(kind);
            let fopdt = step_model(kind);
            let mut rows = Vec::new();
            if let Some(u) = ultimate {
                for (rule, k) in [("ZN PI (relay)", Kind::PI), ("ZN PID (relay)", Kind::PID)] {
                    if let Some(row) = ziegler_nichols(u, k)
                        .ok()
                        .and_then(|t| closed_loop(kind, rule, t))
                    {
                        rows.push(row);
                    }
                }
            }
            if let Ok((k, t, l)) = fopdt {
                let model = regler_pid::tuning::Fopdt {
                    gain: k,
                    time_constant: t,
                    dead_time: l.max(H),
                };
                let tunings = [
                    ("AMIGO PI (step)", amigo(model, Kind::PI).ok()),
                    ("AMIGO PID (step)", amigo(model, Kind::PID).ok()),
                    ("SIMC PI (step)", simc(model, model.dead_time).ok()),
                ];
                for (rule, t) in tunings {
                    if let Some(row) = t.and_then(|t| closed_loop(kind, rule, t)) {
                        rows.push(row);
                    }
                }
            }
            Found {
                process: kind.name(),
                ultimate: ultimate.map(|u| (u.ku, u.tu)),
                ultimate_true: ultimate_true(kind),
                fopdt,
                rows,
            }
        })
        .collect()
}

/// The evaluation as a Markdown table.
#[must_use]
pub fn markdown(found: &[Found]) -> String {
    let mut out = String::from(
        "| process | relay Ku, Tu (true) | FOPDT K, T, L | rule | K | Ti | Td | b | IAE set-point | IAE load | overshoot | Ms |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for f in found {
        let relay = match (f.ultimate, f.ultimate_true) {
            (Some((ku, tu)), Some((kt, tt))) => format!("{ku:.2}, {tu:.2} ({kt:.2}, {tt:.2})"),
            (Some((ku, tu)), None) => format!("{ku:.2}, {tu:.2}"),
            (None, _) => "failed".into(),
        };
        let fopdt = match &f.fopdt {
            Ok((k, t, l)) => format!("{k:.2}, {t:.2}, {l:.2}"),
            Err(e) => format!("none: {e}"),
        };
        for (i, r) in f.rows.iter().enumerate() {
            let (p, rl, fo) = if i == 0 {
                (f.process.as_str(), relay.as_str(), fopdt.as_str())
            } else {
                ("", "", "")
            };
            out.push_str(&format!(
                "| {p} | {rl} | {fo} | {} | {:.3} | {:.3} | {:.3} | {} | {:.2} | {:.2} | {:.0} % | {:.2} |\n",
                r.rule, r.k, r.ti, r.td, r.b, r.iae_setpoint, r.iae_load, r.overshoot_pct, r.ms
            ));
        }
    }
    out
}
