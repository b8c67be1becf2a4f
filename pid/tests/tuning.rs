//! The relay experiment on Åström and Hägglund's benchmark processes: the estimated ultimate gain
//! and period against their analytic values; what noise, a silent process, a failing sensor and
//! an abort do to it; the bumpless hand-over to the tuned controller.
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    clippy::panic,
    clippy::too_many_arguments,
    reason = "a test may panic: that is how it fails"
)]

use std::collections::VecDeque;
use std::f64::consts::PI;

use regler_pid::tuning::{Relay, RelayConfig, RelayError, RelayStep, Ultimate, ziegler_nichols};
use regler_pid::{Config, Kind, Mode, Pid};

/// A sampled linear process: `n` equal first-order lags of time constant `t` after a dead time.
struct Process {
    lags: Vec<f64>,
    a: f64,
    delay: VecDeque<f64>,
}

impl Process {
    fn new(n: usize, t: f64, dead_time: f64, h: f64) -> Self {
        let steps = (dead_time / h).round() as usize;
        Process {
            lags: vec![0.0; n],
            a: (-h / t).exp(),
            delay: VecDeque::from(vec![0.0; steps]),
        }
    }

    fn output(&self) -> f64 {
        *self.lags.last().unwrap()
    }

    fn step(&mut self, u: f64) {
        self.delay.push_back(u);
        let mut input = self.delay.pop_front().unwrap();
        for x in &mut self.lags {
            *x = self.a * *x + (1.0 - self.a) * input;
            input = *x;
        }
    }
}

/// 1/(s+1)^n: the phase is −π at ω = tan(π/n), where |G| = (1 + ω²)^(−n/2).
fn lag_chain_ultimate(n: usize) -> Ultimate {
    let w = (PI / n as f64).tan();
    Ultimate {
        ku: (1.0 + w * w).powf(n as f64 / 2.0),
        tu: 2.0 * PI / w,
    }
}

/// e^(−s)/(1 + sT): the phase is −π where ω + atan(ωT) = π (bisection).
fn dead_time_ultimate(t: f64) -> Ultimate {
    let (mut lo, mut hi) = (0.0, PI);
    for _ in 0..200 {
        let w = 0.5 * (lo + hi);
        if w + (w * t).atan() < PI {
            lo = w
        } else {
            hi = w
        }
    }
    let w = 0.5 * (lo + hi);
    Ultimate {
        ku: (1.0 + w * w * t * t).sqrt(),
        tu: 2.0 * PI / w,
    }
}

fn run(
    process: &mut Process,
    relay: &mut Relay,
    noise: impl Fn(usize) -> f64,
) -> Result<Ultimate, RelayError> {
    let mut k = 0;
    loop {
        let y = process.output() + noise(k);
        k += 1;
        match relay.update(0.0, y)? {
            RelayStep::Running(u) => process.step(u),
            RelayStep::Done(found) => return Ok(found),
        }
    }
}

fn config(h: f64) -> RelayConfig {
    RelayConfig {
        h,
        hysteresis: 0.002,
        timeout: 2_000.0,
        ..RelayConfig::default()
    }
}

#[test]
#[cfg_attr(
    miri,
    ignore = "relay experiments on eleven benchmark processes, thousands of samples each: hours under Miri; runs natively in every CI run"
)]
fn relay_recovers_the_ultimate_point_of_the_benchmark_processes() {
    let h = 0.005;
    let mut cases: Vec<(String, Process, Ultimate)> = Vec::new();
    for n in [3usize, 4, 8] {
        cases.push((
            format!("1/(s+1)^{n}"),
            Process::new(n, 1.0, 0.0, h),
            lag_chain_ultimate(n),
        ));
    }
    for t in [0.1, 0.5, 1.0, 2.0, 10.0] {
        cases.push((
            format!("e^-s/(1+{t}s)"),
            Process::new(1, t, 1.0, h),
            dead_time_ultimate(t),
        ));
    }
    for (name, mut process, truth) in cases {
        let mut relay = Relay::new(config(h)).unwrap();
        let found = run(&mut process, &mut relay, |_| 0.0).unwrap();
        let ku_err = found.ku / truth.ku - 1.0;
        let tu_err = found.tu / truth.tu - 1.0;
        println!(
            "{name}: Ku {:.3} (true {:.3}, {:+.1} %), Tu {:.3} (true {:.3}, {:+.1} %)",
            found.ku,
            truth.ku,
            100.0 * ku_err,
            found.tu,
            truth.tu,
            100.0 * tu_err
        );
        // The describing function keeps only the fundamental: close for lag chains (their output
        // is nearly sinusoidal), high for dead-time-dominated processes, whose output is nearly
        // the relay's square wave (pure dead time: 4/π ≈ 1.27 × the true Ku).
        let ku_band = if name.starts_with("1/") {
            -0.05..=0.01
        } else {
            -0.25..=0.30
        };
        assert!(
            ku_band.contains(&ku_err),
            "{name}: Ku {} vs {}",
            found.ku,
            truth.ku
        );
        assert!(
            tu_err.abs() <= 0.05,
            "{name}: Tu {} vs {}",
            found.tu,
            truth.tu
        );
    }
}

#[test]
#[cfg_attr(
    miri,
    ignore = "noisy relay experiments of thousands of samples: hours under Miri; runs natively in every CI run"
)]
fn noise_below_the_hysteresis_is_harmless_and_above_it_is_named() {
    let h = 0.01;
    // Deterministic pseudo-noise of peak 0.01.
    let noise = |k: usize| 0.01 * ((k as f64 * 12.9898).sin() * 43_758.545).fract();
    let mut quiet = Relay::new(RelayConfig {
        hysteresis: 0.02,
        ..config(h)
    })
    .unwrap();
    let found = run(&mut Process::new(3, 1.0, 0.0, h), &mut quiet, noise).unwrap();
    // Noise widens the measured peak-to-peak and the hysteresis moves the cycle off −180°: both
    // bias Ku low (a safe direction: lower gains), here by about a fifth.
    assert!((-0.30..=0.0).contains(&(found.ku / 8.0 - 1.0)), "{found:?}");
    assert!(
        (found.tu / lag_chain_ultimate(3).tu - 1.0).abs() < 0.1,
        "{found:?}"
    );
    let mut chattering = Relay::new(RelayConfig {
        hysteresis: 0.0,
        ..config(h)
    })
    .unwrap();
    let err = run(&mut Process::new(3, 1.0, 0.0, h), &mut chattering, |k| {
        if k % 2 == 0 { 0.05 } else { -0.05 }
    });
    assert!(matches!(err, Err(RelayError::Chattering { .. })), "{err:?}");
    // The error stays: a failed experiment does not restart by itself.
    assert!(chattering.update(0.0, 0.0).is_err());
}

#[test]
fn a_process_that_never_answers_times_out() {
    let h = 0.1;
    // A disconnected actuator: the measurement never moves.
    let mut dead = Relay::new(RelayConfig {
        timeout: 60.0,
        ..config(h)
    })
    .unwrap();
    let mut out = Ok(());
    for _ in 0..1000 {
        if let Err(e) = dead.update(0.0, 0.0) {
            out = Err(e);
            break;
        }
    }
    assert_eq!(out, Err(RelayError::Timeout { periods: 0 }));
    // A first-order process without dead time has no ultimate point: the relay switches every
    // sample or two, which the experiment names instead of reporting a meaningless Ku.
    let mut relay = Relay::new(RelayConfig {
        timeout: 60.0,
        ..config(h)
    })
    .unwrap();
    let err = run(&mut Process::new(1, 1.0, 0.0, h), &mut relay, |_| 0.0);
    assert!(matches!(err, Err(RelayError::Chattering { .. })), "{err:?}");
}

#[test]
#[cfg_attr(
    miri,
    ignore = "200 000 samples of a relay experiment: hours under Miri; runs natively in every CI run"
)]
fn a_failing_sensor_only_pauses_the_experiment_and_abort_returns_the_bias() {
    let h = 0.01;
    let mut process = Process::new(3, 1.0, 0.0, h);
    let mut relay = Relay::new(RelayConfig {
        bias: 2.0,
        ..config(h)
    })
    .unwrap();
    let mut found = None;
    for k in 0..200_000 {
        // The sensor drops out for 20 samples in every 2 000 (a period is about 360).
        let y = if k % 2_000 < 20 {
            f64::NAN
        } else {
            process.output()
        };
        match relay.update(0.0, y).unwrap() {
            RelayStep::Running(u) => {
                assert!(u == 1.0 || u == 3.0, "{u}");
                process.step(u - 2.0);
            }
            RelayStep::Done(u) => {
                found = Some(u);
                break;
            }
        }
    }
    let found = found.expect("the experiment finished");
    assert!((found.ku / 8.0 - 1.0).abs() < 0.15, "{found:?}");
    let mut relay = Relay::new(RelayConfig {
        bias: 2.0,
        ..config(h)
    })
    .unwrap();
    relay.update(0.0, 0.0).unwrap();
    assert_eq!(relay.abort(), 2.0);
    assert_eq!(relay.output(), 2.0);
    assert_eq!(relay.update(0.0, 0.0), Err(RelayError::Aborted));
}

#[test]
#[cfg_attr(
    miri,
    ignore = "11 000 samples of a relay experiment and the tuned loop: hours under Miri; runs natively in every CI run"
)]
fn hand_over_is_bumpless_and_the_tuned_loop_settles() {
    let h = 0.01;
    let bias = 0.5;
    let mut process = Process::new(3, 1.0, 0.0, h);
    // Steady at the bias first: y = 0.5.
    for _ in 0..5_000 {
        process.step(bias);
    }
    let setpoint = process.output();
    let mut relay = Relay::new(RelayConfig {
        bias,
        amplitude: 0.2,
        ..config(h)
    })
    .unwrap();
    let ultimate = loop {
        match relay.update(setpoint, process.output()).unwrap() {
            RelayStep::Running(u) => process.step(u),
            RelayStep::Done(u) => break u,
        }
    };
    let tuning = ziegler_nichols(ultimate, Kind::PI).unwrap();
    let mut config = Config::<f64> {
        h,
        ymin: 0.0,
        ymax: 1.0,
        n: 10.0,
        ..Config::default()
    };
    tuning.apply(&mut config).unwrap();
    let mut pid: Pid<f64> = relay
        .hand_over(&config, setpoint, process.output())
        .unwrap();
    assert_eq!(pid.mode(), Mode::Auto);
    let first = pid.update(setpoint, process.output());
    // Bumpless: the first output continues from the bias (up to one sample of P and I).
    assert!((first - bias).abs() < 0.05, "{first}");
    let mut y = process.output();
    for _ in 0..6_000 {
        process.step(pid.update(setpoint, y));
        y = process.output();
    }
    assert!((y - setpoint).abs() < 1e-3, "{y} vs {setpoint}");
}

/// A logged open-loop step of `step` on `process`, from a baseline of 10, for `seconds`.
fn step_log(
    process: &mut Process,
    h: f64,
    step: f64,
    seconds: f64,
    noise: impl Fn(usize) -> f64,
) -> Vec<f64> {
    (0..=(seconds / h) as usize)
        .map(|k| {
            let y = 10.0 + process.output() + noise(k);
            process.step(step);
            y
        })
        .collect()
}

#[test]
#[cfg_attr(
    miri,
    ignore = "step logs of thousands of samples, fitted: hours under Miri; runs natively in every CI run"
)]
fn step_identification_recovers_fopdt_models_and_names_what_it_cannot_fit() {
    use regler_pid::tuning::{IdentifyError, amigo, identify_step, simc};
    let h = 0.05;
    for (k, t, l) in [(2.0, 5.0, 1.5), (-0.5, 1.0, 3.0), (1.0, 20.0, 0.5)] {
        let mut p = Process::new(1, t, l, h);
        // Gain k: scale the step into the unit-gain process and the response back out.
        let y: Vec<f64> = step_log(&mut p, h, 0.5, 10.0 * (t + l), |_| 0.0)
            .iter()
            .map(|v| 10.0 + (v - 10.0) * k)
            .collect();
        let m = identify_step(&y, h, 0.5).unwrap();
        assert!((m.gain / k - 1.0).abs() < 0.01, "{m:?}");
        assert!((m.time_constant / t - 1.0).abs() < 0.03, "{m:?}");
        assert!((m.dead_time - l).abs() < 2.0 * h, "{m:?}");
        // The model-based rules take it straight away.
        assert!(amigo(m, Kind::PI).is_ok() && simc(m, m.dead_time.max(h)).is_ok());
    }
    // Noise of peak 2 % of the change: the areas average it out.
    let noise = |k: usize| 0.02 * ((k as f64 * 78.233).sin() * 43_758.545).fract();
    let mut p = Process::new(1, 5.0, 1.5, h);
    let m = identify_step(&step_log(&mut p, h, 1.0, 80.0, noise), h, 1.0).unwrap();
    assert!(
        (m.gain - 1.0).abs() < 0.03
            && (m.time_constant / 5.0 - 1.0).abs() < 0.1
            && (m.dead_time - 1.5).abs() < 0.3,
        "{m:?}"
    );
    // 1/(s+1)^3: T + L equals the sum of the time constants, 3.
    let mut p = Process::new(3, 1.0, 0.0, h);
    let m = identify_step(&step_log(&mut p, h, 1.0, 30.0, |_| 0.0), h, 1.0).unwrap();
    assert!(
        (m.time_constant + m.dead_time - 3.0).abs() < 0.05 && m.dead_time > 0.3,
        "{m:?}"
    );
    // What it refuses, by name.
    let mut p = Process::new(1, 5.0, 1.5, h);
    let short = step_log(&mut p, h, 1.0, 5.0, |_| 0.0);
    assert!(matches!(
        identify_step(&short, h, 1.0),
        Err(IdentifyError::NotSettled(_))
    ));
    assert_eq!(
        identify_step(&[1.0; 10], h, 1.0),
        Err(IdentifyError::TooFewSamples(10))
    );
    assert_eq!(
        identify_step(&[1.0; 100], h, 1.0),
        Err(IdentifyError::NoResponse)
    );
    let mut bad = step_log(&mut Process::new(1, 1.0, 0.0, h), h, 1.0, 20.0, |_| 0.0);
    bad[40] = f64::NAN;
    assert_eq!(
        identify_step(&bad, h, 1.0),
        Err(IdentifyError::NotFinite(40))
    );
    assert_eq!(
        identify_step(&bad, h, 0.0),
        Err(IdentifyError::Input("the step"))
    );
}

/// Issue 19 item 12: every combination of the experiment's and the controller's action; a
/// mismatch is refused with both named, a match hands over.
#[test]
fn hand_over_refuses_a_controller_of_the_other_action() {
    use regler_pid::Action;
    use regler_pid::tuning::HandOverError;
    for experiment in [Action::Direct, Action::Reverse] {
        for controller in [Action::Direct, Action::Reverse] {
            let relay = Relay::new(RelayConfig {
                action: experiment,
                ..config(0.01)
            })
            .unwrap();
            let config = Config::<f64> {
                h: 0.01,
                kind: Kind::PI,
                k: 1.0,
                ti: 5.0,
                action: controller,
                ..Config::default()
            };
            let got = relay.hand_over::<f64>(&config, 0.0, 0.0);
            if experiment == controller {
                assert_eq!(got.unwrap().mode(), Mode::Auto);
            } else {
                let err = got.unwrap_err();
                assert_eq!(
                    err,
                    HandOverError::Action {
                        experiment,
                        controller
                    }
                );
                let text = err.to_string();
                assert!(
                    text.contains("direct") && text.contains("reverse"),
                    "{text}"
                );
            }
        }
    }
    // An invalid configuration is still named as such.
    let relay = Relay::new(config(0.01)).unwrap();
    let bad = Config::<f64> {
        h: 0.01,
        k: f64::NAN,
        ..Config::default()
    };
    assert!(matches!(
        relay.hand_over::<f64>(&bad, 0.0, 0.0),
        Err(HandOverError::Config(_))
    ));
}

/// Samples until the relay gives up on a process that never answers (at most `bound`).
fn samples_to_timeout<F: regler_pid::Real>(h: F, timeout: F, bound: u64) -> Option<u64> {
    let mut relay = Relay::new(RelayConfig::<F> {
        h,
        timeout,
        ..RelayConfig::default()
    })
    .unwrap();
    let zero = F::zero();
    for n in 1..=bound {
        match relay.update(zero, zero) {
            Ok(_) => {}
            Err(RelayError::Timeout { .. }) => return Some(n),
            Err(e) => panic!("{e}"),
        }
    }
    None
}

/// Issue 19 item 13: the time-out is a sample count: f32 gives up at the same sample as f64
/// (⌊timeout/h⌋ + 1), also where an f32 clock `t += h` stalls (h = 1 ms, 40 000 s: t/h ≈ 4·10⁷
/// > 2²⁴).
#[test]
#[cfg_attr(
    miri,
    ignore = "counts up to 40 million samples to the time-out: days under Miri; runs natively in every CI run"
)]
fn the_f32_relay_times_out_at_the_same_sample_as_the_f64_one() {
    for (h, timeout) in [(1e-3, 40_000.0), (0.1, 60.0), (0.01, 1_000.0)] {
        let expected = (timeout / h) as u64 + 1;
        let bound = expected + 10;
        assert_eq!(samples_to_timeout::<f64>(h, timeout, bound), Some(expected));
        assert_eq!(
            samples_to_timeout::<f32>(h as f32, timeout as f32, bound),
            Some(expected),
            "f32, h {h}, timeout {timeout}"
        );
    }
    // A time-out whose sample count does not fit the counter is refused, one that does works.
    assert!(matches!(
        Relay::new(RelayConfig::<f64> {
            h: 1e-300,
            timeout: 1e300,
            ..RelayConfig::default()
        }),
        Err(RelayError::Config(_))
    ));
    assert!(
        Relay::new(RelayConfig::<f64> {
            h: 1e-6,
            timeout: 40_000.0,
            ..RelayConfig::default()
        })
        .is_ok()
    );
}

/// Issue 19 item 13: Tu is right in f32 when the oscillation starts late (after 10⁵ to 2·10⁷
/// samples of a process that does not answer yet; h = 1 ms; past 2¹⁴ s an f32 clock rounds each
/// step of 1 ms to 2 ms): the period is a difference of
/// sample counts, not of two large float times.
#[test]
#[cfg_attr(
    miri,
    ignore = "up to 20 million samples before the oscillation: days under Miri; runs natively in every CI run"
)]
fn the_f32_relay_measures_a_late_oscillation_right() {
    let h = 1e-3f32;
    let truth = lag_chain_ultimate(3);
    for late in [100_000u64, 10_000_000, 20_000_000] {
        let mut relay = Relay::new(RelayConfig::<f32> {
            h,
            hysteresis: 0.002,
            timeout: 40_000.0,
            ..RelayConfig::default()
        })
        .unwrap();
        // Not connected yet: the measurement sits below the set-point, the relay stays high.
        for _ in 0..late {
            assert!(matches!(relay.update(0.0, -1.0), Ok(RelayStep::Running(_))));
        }
        let mut process = Process::new(3, 1.0, 0.0, f64::from(h));
        let found = loop {
            match relay.update(0.0, process.output() as f32).unwrap() {
                RelayStep::Running(u) => process.step(f64::from(u)),
                RelayStep::Done(found) => break found,
            }
        };
        let tu_err = f64::from(found.tu) / truth.tu - 1.0;
        let ku_err = f64::from(found.ku) / truth.ku - 1.0;
        assert!(tu_err.abs() <= 0.05, "after {late}: Tu {}", found.tu);
        assert!(
            (-0.05..=0.01).contains(&ku_err),
            "after {late}: Ku {}",
            found.ku
        );
    }
}

/// Issue 19 item 10: a log of an analytic response `f(t)` (per unit step, t from the step),
/// with `pre` samples before the step, a baseline, a step and uniform noise of peak `noise`
/// (in output units), in `F`.
fn log_of<F: regler_pid::Real>(
    f: impl Fn(f64) -> f64,
    pre: usize,
    n: usize,
    h: f64,
    base: f64,
    gain_step: f64,
    noise: f64,
    seed: u64,
) -> Vec<F> {
    let mut state = seed | 1;
    (0..pre + n)
        .map(|i| {
            // xorshift64*: uniform in −1..1.
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            let u = (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64;
            let t = (i as f64 - pre as f64) * h;
            let y = base + gain_step * if t <= 0.0 { 0.0 } else { f(t) } + noise * (2.0 * u - 1.0);
            F::from_f64_nearest(y)
        })
        .collect()
}

fn fopdt_response(t_c: f64, l: f64) -> impl Fn(f64) -> f64 {
    move |t| {
        if t <= l {
            0.0
        } else {
            1.0 - (-(t - l) / t_c).exp()
        }
    }
}

/// The tolerance the module docs state: K within 1 % + ν, T and L within 2 % of T + L, plus h,
/// plus ν·(T + L + 10·D/√N), with ν = noise/|K·step|, D = N·h the log's length from the step
/// and N its samples from the step (the final value's error counts over the whole log).
/// The factor of ν·D/√N in the stated tolerance.
const NOISE_LOG_FACTOR: f64 = 10.0;

fn within_tolerance(
    m: &regler_pid::tuning::Fopdt,
    k: f64,
    t: f64,
    l: f64,
    h: f64,
    relative_noise: f64,
    n: usize,
) -> bool {
    let tl = t + l;
    let d = n as f64 * h;
    let slack = 0.02 * tl + h + relative_noise * (tl + NOISE_LOG_FACTOR * d / (n as f64).sqrt());
    (m.gain / k - 1.0).abs() <= 0.01 + relative_noise
        && (m.time_constant - t).abs() <= slack
        && (m.dead_time - l).abs() <= slack
}

fn identify<F: regler_pid::Real>(
    y: &[F],
    pre: usize,
    h: f64,
    step: f64,
) -> Result<regler_pid::tuning::Fopdt, String> {
    regler_pid::tuning::identify_step_at(y, pre, F::from_f64_nearest(h), F::from_f64_nearest(step))
        .map(|m| regler_pid::tuning::Fopdt {
            gain: m.gain.to_f64_exact(),
            time_constant: m.time_constant.to_f64_exact(),
            dead_time: m.dead_time.to_f64_exact(),
        })
        .map_err(|e| e.to_string())
}

mod identify_properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 4 } else { 200 }))]

        /// Any FOPDT process (K of either sign over four decades, T over three, L from 0 to 3T,
        /// 30 to 3 000 samples per T + L, logged 8 to 20 time constants past the dead time,
        /// a baseline within 10⁴ × the change (10³ × in f32), uniform noise up to 2 % of the
        /// change with at least 20 samples before the step) gives a model within the stated
        /// tolerance, in f64 and f32. The corners are drawn on purpose (attack finding 5: L = 0,
        /// 30 samples per T + L, a 20 T log, 20 samples before the step and 2 % noise broke the
        /// earlier bound in 1 seed of 10).
        #[test]
        #[cfg_attr(miri, ignore = "step logs of up to 60 000 samples per case, fitted: hours under Miri; runs natively in every CI run")]
        fn any_fopdt_is_recovered_within_the_stated_tolerance(
            k_mag in 0.01f64..100.0,
            negative in any::<bool>(),
            t in 0.1f64..100.0,
            l_in_t in prop_oneof![Just(0.0f64), 0.0f64..3.0, Just(3.0)],
            per_tl in prop_oneof![Just(30.0f64), 30.0f64..3000.0, Just(3000.0)],
            settle in prop_oneof![Just(8.0f64), 8.0f64..20.0, Just(20.0)],
            base in -100.0f64..100.0,
            step in 0.1f64..10.0,
            noisy in any::<bool>(),
            relative_noise in prop_oneof![Just(0.02f64), 0.0f64..0.02],
            pre in prop_oneof![Just(20usize), 20usize..500],
            seed in any::<u64>(),
        ) {
            let k = if negative { -k_mag } else { k_mag };
            let l = l_in_t * t;
            let h = (t + l) / per_tl;
            let n = ((l + settle * t) / h) as usize;
            let relative_noise = if noisy { relative_noise } else { 0.0 };
            let noise = relative_noise * (k * step).abs();
            let pre = if noisy { pre } else { pre % 2 * pre };
            let f = fopdt_response(t, l);
            let y64 = log_of::<f64>(&f, pre, n, h, base, k * step, noise, seed);
            let m = identify(&y64, pre, h, step).map_err(TestCaseError::fail)?;
            prop_assert!(within_tolerance(&m, k, t, l, h, relative_noise, n), "f64 {m:?}");
            // f32: the baseline must not swamp the change in f32's 24 bits.
            prop_assume!(base.abs() < 1e3 * (k * step).abs());
            let y32 = log_of::<f32>(&f, pre, n, h, base, k * step, noise, seed);
            let m = identify(&y32, pre, h, step).map_err(TestCaseError::fail)?;
            prop_assert!(within_tolerance(&m, k, t, l, h, relative_noise, n), "f32 {m:?}");
        }

        /// Responses a first-order-plus-dead-time model cannot represent give an error, never a
        /// model: second order with an overshoot of 2 % or more, an inverse response that first
        /// goes the wrong way by 2 % or more, a sustained oscillation of 2 % or more, an
        /// integrating process (a ramp); noise up to 0.2 % of the change.
        #[test]
        #[cfg_attr(miri, ignore = "step logs of thousands of samples per case, fitted: hours under Miri; runs natively in every CI run")]
        fn any_response_it_cannot_represent_is_an_error(
            shape in 0usize..4,
            zeta in 0.05f64..0.77,
            w in 0.05f64..5.0,
            l in 0.0f64..5.0,
            a in 0.1f64..10.0,
            t1 in 0.5f64..10.0,
            t2_in_t1 in 0.05f64..0.95,
            k in -10.0f64..10.0,
            relative_noise in 0.0f64..0.002,
            seed in any::<u64>(),
        ) {
            prop_assume!(k.abs() > 0.01);
            let t2 = t2_in_t1 * t1;
            let (f, span): (Box<dyn Fn(f64) -> f64>, f64) = match shape {
                0 => {
                    // ωn = w, damping ζ: overshoot e^(−πζ/√(1−ζ²)) ≥ 2.26 %.
                    let wd = w * (1.0 - zeta * zeta).sqrt();
                    let phi = (zeta / (1.0 - zeta * zeta).sqrt()).atan();
                    (Box::new(move |t: f64| if t <= l { 0.0 } else {
                        let s = t - l;
                        1.0 - (-zeta * w * s).exp() * ((wd * s).cos() + phi.tan() * (wd * s).sin())
                    }), l + 12.0 / (zeta * w))
                }
                1 => {
                    // (1 − a·s)/((1 + T1 s)(1 + T2 s)).
                    (Box::new(move |t: f64| if t <= l { 0.0 } else {
                        let s = t - l;
                        1.0 - (t1 + a) / (t1 - t2) * (-s / t1).exp() + (t2 + a) / (t1 - t2) * (-s / t2).exp()
                    }), l + 15.0 * t1)
                }
                2 => (Box::new(move |t: f64| if t <= l { 0.0 } else {
                        1.0 + (0.02 + zeta) * (w * (t - l)).sin()
                    }), l + 40.0 / w),
                _ => (Box::new(move |t: f64| if t <= l { 0.0 } else {
                        let s = t - l;
                        (s - t1 * (1.0 - (-s / t1).exp())) / t1
                    }), l + 20.0 * t1),
            };
            let h = span / 4000.0;
            let n = (span / h) as usize;
            if shape == 1 {
                // Only inverse responses that go the wrong way by 2 % or more.
                let lowest = (0..n).map(|i| f(i as f64 * h)).fold(f64::INFINITY, f64::min);
                prop_assume!(lowest <= -0.02);
            }
            let noise = relative_noise * k.abs();
            for pre in [0usize, 100] {
                let y = log_of::<f64>(&f, pre, n, h, 5.0, k, noise, seed);
                let got = identify(&y, pre, h, 1.0);
                prop_assert!(got.is_err(), "shape {shape}: {got:?}");
            }
        }
    }
}

/// Issue 19 item 10, the reported case and beyond: 700 000 and 3 000 000 samples of
/// 2·e^(−5s)/(1 + 60s) (the tail is 70 000 and 300 000 samples, beyond u16), in f64 and f32,
/// with and without noise (1 % of the change, 1 000 samples before the step).
#[test]
#[cfg_attr(
    miri,
    ignore = "step logs of up to three million samples: hours under Miri; runs natively in every CI run"
)]
fn identify_step_is_right_on_logs_of_millions_of_samples() {
    let (k, t, l) = (2.0, 60.0, 5.0);
    for n in [700_000usize, 3_000_000] {
        let h = 1_000.0 / n as f64 * 1.2;
        for (pre, relative_noise) in [(0usize, 0.0), (1_000, 0.01)] {
            let noise = relative_noise * k;
            let f = fopdt_response(t, l);
            let y64 = log_of::<f64>(&f, pre, n, h, 10.0, k, noise, 7);
            let m = identify(&y64, pre, h, 1.0).unwrap();
            assert!(
                within_tolerance(&m, k, t, l, h, relative_noise, n),
                "f64 {n}: {m:?}"
            );
            let y32 = log_of::<f32>(&f, pre, n, h, 10.0, k, noise, 7);
            let m = identify(&y32, pre, h, 1.0).unwrap();
            assert!(
                within_tolerance(&m, k, t, l, h, relative_noise, n),
                "f32 {n}: {m:?}"
            );
        }
    }
}

/// Attack finding 5, the corners of the class over many noise seeds: L = 0 with 30 samples per
/// T + L, a 20 T log, 20 samples before the step and noise of peak 2 % (97 of 1 000 seeds broke
/// the earlier bound, by up to 1.73×), and the mid-class case K 0.549, T 6.54, L 3.61, 1.6 %
/// (8 of 1 000). Every seed must give a model within the stated tolerance.
#[test]
#[cfg_attr(
    miri,
    ignore = "step logs fitted over a thousand noise seeds: hours under Miri; runs natively in every CI run"
)]
fn the_stated_tolerance_holds_at_the_corners_over_many_noise_seeds() {
    let seeds: u64 = std::env::var("SEEDS").map_or(300, |v| v.parse().unwrap());
    for (k, t, l, per_tl, settle, pre, nu, step, base) in [
        (1.0, 10.0, 0.0, 30.0, 20.0, 20usize, 0.02, 1.0, 0.0),
        (
            0.5493, 6.5407, 3.6136, 55.2, 19.5, 399, 0.016321, -0.29884, -35.78,
        ),
        (1.0, 10.0, 30.0, 30.0, 20.0, 20, 0.02, 1.0, 0.0),
        (1.0, 10.0, 0.0, 30.0, 8.0, 20, 0.02, 1.0, 0.0),
    ] {
        let h = (t + l) / per_tl;
        let n = ((l + settle * t) / h) as usize;
        let mut worst = 0.0f64;
        for seed in 1..=seeds {
            let y = log_of::<f64>(
                fopdt_response(t, l),
                pre,
                n,
                h,
                base,
                k * step,
                nu * (k * step).abs(),
                seed,
            );
            let m = identify(&y, pre, h, step).unwrap();
            assert!(
                within_tolerance(&m, k, t, l, h, nu, n),
                "K {k} T {t} L {l} seed {seed}: {m:?}"
            );
            let d = n as f64 * h;
            let slack =
                0.02 * (t + l) + h + nu * (t + l + NOISE_LOG_FACTOR * d / (n as f64).sqrt());
            worst = worst
                .max((m.time_constant - t).abs() / slack)
                .max((m.dead_time - l).abs() / slack);
        }
        println!("K {k} T {t} L {l}: worst T/L error {worst:.2} of the tolerance");
    }
}

mod refusals {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 4 } else { 200 }))]

        /// Attack finding 2: a first-order response with an oscillation still going at the end
        /// of the log (amplitude 2 % to 50 % of the change, any phase, noise up to 0.2 %) is
        /// refused, never fitted: with 20 or more samples before the step for any period from 6
        /// samples up to a third of the last tenth; without them for periods of 32 samples and
        /// more (the noise is then read from the tail's neighbour-to-neighbour changes, which a
        /// faster oscillation looks like).
        #[test]
        #[cfg_attr(miri, ignore = "oscillating logs of 600 to 6 000 samples per case, fitted: hours under Miri; runs natively in every CI run")]
        fn a_sustained_oscillation_is_refused(
            t in 0.5f64..50.0,
            l_in_t in 0.0f64..2.0,
            amplitude in prop_oneof![Just(0.02f64), 0.02f64..0.5],
            period_pick in 0.0f64..=1.0,
            phase in 0.0f64..std::f64::consts::TAU,
            n in 600usize..6000,
            relative_noise in 0.0f64..0.002,
            window in any::<bool>(),
            pre in 20usize..300,
            seed in any::<u64>(),
        ) {
            let l = l_in_t * t;
            let h = (l + 15.0 * t) / n as f64;
            let shortest = if window { 6.0 } else { 32.0 };
            let longest = (n / 30) as f64;
            prop_assume!(longest > shortest);
            let period = (shortest + period_pick * (longest - shortest)) * h;
            let f = move |s: f64| {
                fopdt_response(t, l)(s)
                    + if s > l { amplitude * (std::f64::consts::TAU * (s - l) / period + phase).sin() } else { 0.0 }
            };
            let pre = if window { pre } else { 0 };
            let y = log_of::<f64>(f, pre, n, h, 5.0, 1.0, relative_noise, seed);
            let got = identify(&y, pre, h, 1.0);
            prop_assert!(got.is_err(), "{got:?}");
        }

        /// Attack finding 6: a noise-free first-order log shorter than the class (1 to 8 T past
        /// the dead time) is either refused (NotSettled) or gives a model within the stated short-log tolerance (K
        /// as in the class, T and L within 4 % of T + L instead of 2 %); noise-free, every log
        /// shorter than 5 T is refused.
        #[test]
        #[cfg_attr(miri, ignore = "step logs of up to 24 000 samples per case, fitted: hours under Miri; runs natively in every CI run")]
        fn a_short_log_is_refused_or_within_the_tolerance(
            t in 0.1f64..100.0,
            l_in_t in 0.0f64..3.0,
            per_tl in 30.0f64..3000.0,
            settle in 1.0f64..8.0,
            pre in 0usize..500,
            seed in any::<u64>(),
        ) {
            let relative_noise = 0.0;
            let l = l_in_t * t;
            let h = (t + l) / per_tl;
            let n = ((l + settle * t) / h) as usize;
            prop_assume!(n >= 20);
            let y = log_of::<f64>(fopdt_response(t, l), pre, n, h, 1.0, 1.0, relative_noise, seed);
            match identify(&y, pre, h, 1.0) {
                Ok(m) => {
                    // The short-log tolerance: twice the 2 % of T + L.
                    let tl = t + l;
                    let d = n as f64 * h;
                    let slack = 0.04 * tl + h
                        + relative_noise * (tl + NOISE_LOG_FACTOR * d / (n as f64).sqrt());
                    prop_assert!(
                        (m.gain - 1.0).abs() <= 0.01 + relative_noise
                            && (m.time_constant - t).abs() <= slack
                            && (m.dead_time - l).abs() <= slack,
                        "{m:?}"
                    );
                    prop_assert!(relative_noise > 0.0 || settle >= 5.0, "{settle} T accepted: {m:?}");
                }
                Err(e) => prop_assert!(e.contains("not settled"), "{e}"),
            }
        }
    }

    /// Attack findings 2 and 6, the reported cases: a 10 % oscillation of period 5 s on
    /// 1 − e^(−(t−2)/10) (fitted as K 1.0, T 10.26, L 1.88), the attacker's sweep (amplitudes
    /// 2–50 %, periods 1–40 s: 732 of 1 950 fitted), and a first-order log 2.3 T long (K off
    /// by 11 %).
    #[test]
    #[cfg_attr(
        miri,
        ignore = "650 oscillating logs, fitted: hours under Miri; runs natively in every CI run"
    )]
    fn the_reported_oscillations_and_short_log_are_refused() {
        let (h, n, pre) = (0.1, 3000usize, 50usize);
        for amplitude in [0.02, 0.05, 0.1, 0.2, 0.5] {
            for p10 in (10..400).step_by(3) {
                let period = f64::from(p10) / 10.0;
                let f = move |s: f64| {
                    fopdt_response(10.0, 2.0)(s)
                        + if s > 2.0 {
                            amplitude * (std::f64::consts::TAU * (s - 2.0) / period).sin()
                        } else {
                            0.0
                        }
                };
                let y = log_of::<f64>(f, pre, n, h, 0.0, 1.0, 0.0, 1);
                let got = identify(&y, pre, h, 1.0);
                assert!(
                    got.is_err(),
                    "amplitude {amplitude} period {period}: {got:?}"
                );
            }
        }
        let y = log_of::<f64>(fopdt_response(1.0, 0.0), 100, 230, 0.01, 0.0, 1.0, 0.0, 1);
        let got = identify(&y, 100, 0.01, 1.0);
        assert!(
            matches!(got, Err(ref e) if e.contains("not settled")),
            "{got:?}"
        );
    }
}

/// Attack finding 3: a hand-over at a sample whose set-point or measurement is NaN or infinite
/// left the controller not started (its first output 0, not the bias 40): refused, naming it.
#[test]
fn hand_over_refuses_a_non_finite_sample_by_name() {
    use regler_pid::tuning::HandOverError;
    let relay = Relay::new(RelayConfig {
        bias: 40.0,
        h: 0.1,
        ..RelayConfig::default()
    })
    .unwrap();
    let config = Config::<f64> {
        kind: Kind::PI,
        k: 2.0,
        ti: 10.0,
        h: 0.1,
        ymin: 0.0,
        ymax: 100.0,
        ..Config::default()
    };
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert_eq!(
            relay.hand_over::<f64>(&config, bad, 50.0).unwrap_err(),
            HandOverError::NotFinite("set-point")
        );
        let err = relay.hand_over::<f64>(&config, 50.0, bad).unwrap_err();
        assert_eq!(err, HandOverError::NotFinite("measurement"));
        assert!(err.to_string().contains("measurement"), "{err}");
    }
    let mut pid: Pid<f64> = relay.hand_over(&config, 50.0, 50.0).unwrap();
    assert_eq!(pid.update(50.0, 50.0), 40.0);
}

/// Attack finding 8, the relay: Ku from a²−ε² underflowed for an amplitude of 10⁻²³ in f32
/// (Done with Ku = ∞). Over the scales f32 holds the estimate is now finite and right; where
/// 4d/(πa) itself overflows it is an error naming the amplitude.
#[test]
fn the_relay_never_returns_a_non_finite_ku() {
    use regler_pid::tuning::RelayError;
    for (scale, amplitude) in [
        (1e-23f32, 1.0f32),
        (1e-19, 1.0),
        (1e18, 1.0),
        (1e20, 1.0),
        (1e-39, 1.0),
    ] {
        let h = 0.01f32;
        let a = (-h).exp();
        let mut x = [0.0f32; 3];
        let mut relay = Relay::new(RelayConfig {
            h,
            hysteresis: 0.0,
            amplitude,
            timeout: 1000.0,
            ..RelayConfig::default()
        })
        .unwrap();
        let got = loop {
            match relay.update(0.0, x[2] * scale) {
                Ok(RelayStep::Running(u)) => {
                    x[0] = a * x[0] + (1.0 - a) * u;
                    x[1] = a * x[1] + (1.0 - a) * x[0];
                    x[2] = a * x[2] + (1.0 - a) * x[1];
                }
                other => break other,
            }
        };
        let truth = 8.0 / f64::from(scale);
        match got {
            Ok(RelayStep::Done(u)) => {
                assert!(u.ku.is_finite(), "{scale:e}: {u:?}");
                assert!(
                    (f64::from(u.ku) / truth - 1.0).abs() < 0.1,
                    "{scale:e}: {u:?}"
                );
            }
            Err(RelayError::AmplitudeUnmeasurable { amplitude: a }) => {
                assert!(truth > f64::from(f32::MAX) / 2.0, "{scale:e}: refused {a}");
            }
            other => panic!("{scale:e}: {other:?}"),
        }
    }
}

/// Attack finding 8, identification: a step of 10⁻³¹⁰ gave Ok(gain ∞); a change that
/// overflows was reported as NoResponse. Both are named overflows now: in `f32`, −3·10³⁸ →
/// 3·10³⁸ (a change beyond `f32::MAX`). A change of 1.7·10³⁰⁸ in `f64` fits, and is modelled.
#[test]
fn identification_names_an_overflow() {
    use regler_pid::tuning::{IdentifyError, identify_step_at};
    let h = 0.1;
    let y = log_of::<f64>(fopdt_response(5.0, 1.0), 10, 600, h, 0.0, 1.0, 0.0, 1);
    assert_eq!(
        identify_step_at(&y, 10, h, 1e-310),
        Err(IdentifyError::Overflow("the gain (change / step)"))
    );
    let y = log_of::<f32>(fopdt_response(5.0, 1.0), 10, 600, h, -3e38, 6e38, 0.0, 1);
    let got = identify_step_at(&y, 10, h as f32, 1.0);
    assert!(matches!(got, Err(IdentifyError::Overflow(_))), "{got:?}");
    assert!(got.unwrap_err().to_string().contains("overflows"));
    let y = log_of::<f64>(
        fopdt_response(5.0, 1.0),
        10,
        600,
        h,
        -1e308,
        1.7e308,
        0.0,
        1,
    );
    let m = identify_step_at(&y, 10, h, 1.0).unwrap();
    assert!(
        within_tolerance(&m, 1.7e308, 5.0, 1.0, h, 0.0, 600),
        "{m:?}"
    );
}

/// Attack finding 8, the rules: AMIGO gave Ok with Ti NaN (T = 10³⁰ in f32) or K NaN
/// (T = L = 10⁻³⁰); every rule's Ok now has finite positive K and Ti and a finite Td ≥ 0.
#[test]
fn the_rules_never_return_non_finite_results() {
    use regler_pid::tuning::{Fopdt, RuleError, amigo, simc};
    let big = Fopdt {
        gain: 1.0f32,
        time_constant: 1e30,
        dead_time: 1.0,
    };
    let tiny = Fopdt {
        gain: 1.0f32,
        time_constant: 1e-30,
        dead_time: 1e-30,
    };
    for model in [
        big,
        tiny,
        Fopdt {
            gain: 1e-30,
            time_constant: 1e30,
            dead_time: 1e-30,
        },
    ] {
        for got in [
            amigo(model, Kind::PI),
            amigo(model, Kind::PID),
            simc(model, model.dead_time),
        ] {
            match got {
                Ok(t) => assert!(
                    t.k.is_finite()
                        && t.k > 0.0
                        && t.ti.is_finite()
                        && t.ti > 0.0
                        && t.td.is_finite(),
                    "{model:?}: {t:?}"
                ),
                Err(e) => assert!(matches!(e, RuleError::Result(_)), "{model:?}: {e:?}"),
            }
        }
    }
    assert!(matches!(amigo(big, Kind::PI), Err(RuleError::Result(_))));
    let zn = ziegler_nichols(
        Ultimate {
            ku: 3e38f32,
            tu: 1.0,
        },
        Kind::PID,
    );
    assert!(zn.is_ok_and(|t| t.k.is_finite()) || matches!(zn, Err(RuleError::Result(_))));
}

/// Attack finding 4: identify → AMIGO → apply on a pure lag (T = 10 s, h = 0.1 s) gave L ≈ 1 ms,
/// K ≈ 3 700 and Ti ≈ 13 ms, which apply took and which swung the valve 0 ↔ 100 forever. Now
/// apply refuses Ti < h by name; the model with the sampling delay (L + h/2) gives a loop that
/// settles — for AMIGO PI and PID and SIMC, on pure lags of 2 to 200 samples' time constant.
#[test]
#[cfg_attr(
    miri,
    ignore = "closed loops of at least 3 000 samples for four dead times: hours under Miri; runs natively in every CI run"
)]
fn a_pure_lag_is_refused_raw_and_settles_with_the_sampling_delay() {
    use regler_pid::tuning::{amigo, identify_step_at, simc};
    use regler_pid::{ConfigError, Parameter};
    let h = 0.1f64;
    for t in [0.2, 1.0, 10.0, 20.0] {
        let y = log_of::<f64>(
            fopdt_response(t, 0.0),
            50,
            (12.0 * t / h) as usize,
            h,
            0.0,
            1.0,
            0.0,
            1,
        );
        let m = identify_step_at(&y, 50, h, 1.0).unwrap();
        let base = Config::<f64> {
            kind: Kind::PI,
            h,
            ymin: 0.0,
            ymax: 100.0,
            ..Config::default()
        };
        if let Ok(raw) = amigo(m, Kind::PI) {
            let mut cfg = base;
            let err = raw.apply(&mut cfg);
            if raw.ti < h {
                assert!(
                    matches!(
                        err,
                        Err(ConfigError::OutOfRange {
                            parameter: Parameter::Ti,
                            ..
                        })
                    ),
                    "T {t}: {raw:?} -> {err:?}"
                );
                assert_eq!(cfg, base);
            }
        }
        let sampled = m.with_sampling_delay(h);
        for tuning in [
            amigo(sampled, Kind::PI).unwrap(),
            amigo(sampled, Kind::PID).unwrap(),
            simc(sampled, sampled.dead_time).unwrap(),
        ] {
            let mut cfg = base;
            tuning.apply(&mut cfg).unwrap();
            let mut pid = Pid::<f64>::new(&cfg).unwrap();
            let a = (-h / t).exp();
            let mut x = 50.0;
            let mut late: (f64, f64, f64) = (0.0, f64::MAX, f64::MIN);
            for k in 0..(3000.0f64.max(60.0 * t / h)) as usize {
                let u = pid.update(60.0, x);
                x = a * x + (1.0 - a) * u;
                if k > 2500 {
                    late = (late.0.max((x - 60.0).abs()), late.1.min(u), late.2.max(u));
                }
            }
            assert!(
                late.0 < 0.1 && late.2 - late.1 < 1.0,
                "T {t}: {tuning:?}: {late:?}"
            );
        }
    }
}

/// `Tuning::apply`: "an integral time shorter than the sample period is refused" — one equal to
/// it is applied; one just below is refused naming Ti, and the configuration is unchanged.
#[test]
fn a_rule_result_with_ti_at_the_sample_period_is_applied_and_below_it_refused() {
    use regler_pid::tuning::Tuning;
    use regler_pid::{ConfigError, Parameter};
    let base = Config {
        h: 0.5,
        ..Config::default()
    };
    let at = Tuning {
        kind: Kind::PI,
        k: 2.0,
        ti: 0.5,
        td: 0.0,
        b: 1.0,
    };
    let mut config = base;
    at.apply(&mut config).unwrap();
    assert_eq!((config.kind, config.k, config.ti), (Kind::PI, 2.0, 0.5));
    let below = Tuning {
        ti: 0.5 - f64::EPSILON,
        ..at
    };
    let mut config = base;
    let e = below.apply(&mut config).unwrap_err();
    assert!(
        matches!(e, ConfigError::OutOfRange { parameter: Parameter::Ti, value, .. } if value == 0.5 - f64::EPSILON),
        "{e:?}"
    );
    assert_eq!(config, base, "unchanged");
}

/// Each rule error says what was wrong, as a user reads it.
#[test]
fn rule_errors_say_what_was_wrong() {
    use regler_pid::tuning::RuleError;
    let zn = |ku: f64, tu: f64, kind| ziegler_nichols(Ultimate { ku, tu }, kind).unwrap_err();
    assert_eq!(zn(-1.0, 2.0, Kind::PI), RuleError::Input("Ku"));
    assert_eq!(
        zn(2.0, 4.0, Kind::PD).to_string(),
        "the rule has no setting for a PD controller"
    );
    assert_eq!(
        zn(f64::NAN, 4.0, Kind::PI).to_string(),
        "Ku must be finite and positive"
    );
    assert_eq!(
        RuleError::Result("integral time Ti").to_string(),
        "the rule's integral time Ti is not a finite positive number for these inputs (they overflow or vanish in this float type)"
    );
}

/// A rule's Td that overflows while K and Ti do not (AMIGO PID: Td = 0.5·L·T / (0.3·L + T),
/// and L·T overflows first) is refused naming Td, not handed on as an infinite derivative time.
#[test]
fn a_rule_whose_td_overflows_is_refused_naming_it() {
    use regler_pid::tuning::{Fopdt, RuleError, amigo};
    let model = Fopdt {
        gain: 1.0,
        time_constant: 1e200,
        dead_time: 1e200,
    };
    assert_eq!(
        amigo(model, Kind::PID),
        Err(RuleError::Result("derivative time Td"))
    );
}

/// Each rule gives the formulas its docs state, over a grid of inputs (process gains of either
/// sign and not 1, lag- and delay-dominated models), to rounding: Ziegler–Nichols P, PI, PID;
/// AMIGO PI and PID with b from τ = L/(L + T); SIMC PI.
#[test]
fn each_rule_gives_the_formulas_its_docs_state() {
    use regler_pid::tuning::{Fopdt, amigo, simc};
    let close = |got: f64, want: f64, what: &str| {
        assert!(
            (got - want).abs() <= 1e-12 * want.abs(),
            "{what}: {got} for {want}"
        );
    };
    for ku in [0.3, 2.0, 8.0, 150.0] {
        for tu in [0.5, 3.63, 40.0] {
            let u = Ultimate { ku, tu };
            let p = ziegler_nichols(u, Kind::P).unwrap();
            close(p.k, 0.5 * ku, "ZN P K");
            let pi = ziegler_nichols(u, Kind::PI).unwrap();
            close(pi.k, 0.45 * ku, "ZN PI K");
            close(pi.ti, tu / 1.2, "ZN PI Ti");
            let pid = ziegler_nichols(u, Kind::PID).unwrap();
            close(pid.k, 0.6 * ku, "ZN PID K");
            close(pid.ti, tu / 2.0, "ZN PID Ti");
            close(pid.td, tu / 8.0, "ZN PID Td");
            assert_eq!((p.b, pi.b, pid.b), (1.0, 1.0, 1.0));
        }
    }
    for kp in [-3.0f64, 0.25, 2.0] {
        for (t, l) in [
            (10.0, 1.0),
            (5.0, 5.0),
            (1.0, 4.0),
            (100.0, 0.3),
            (2.0, 2.1),
        ] {
            let model = Fopdt {
                gain: kp,
                time_constant: t,
                dead_time: l,
            };
            let g: f64 = kp.abs();
            let tau = l / (l + t);
            let b = if tau < 0.5 { 0.0 } else { 1.0 };
            let pi = amigo(model, Kind::PI).unwrap();
            close(
                pi.k,
                (0.15 + (0.35 - l * t / ((l + t) * (l + t))) * t / l) / g,
                "AMIGO PI K",
            );
            close(
                pi.ti,
                0.35 * l + 13.0 * l * t * t / (t * t + 12.0 * l * t + 7.0 * l * l),
                "AMIGO PI Ti",
            );
            assert_eq!((pi.td, pi.b), (0.0, b), "AMIGO PI b at tau {tau}");
            let pid = amigo(model, Kind::PID).unwrap();
            close(pid.k, (0.2 + 0.45 * t / l) / g, "AMIGO PID K");
            close(
                pid.ti,
                (0.4 * l + 0.8 * t) / (l + 0.1 * t) * l,
                "AMIGO PID Ti",
            );
            close(pid.td, 0.5 * l * t / (0.3 * l + t), "AMIGO PID Td");
            assert_eq!(pid.b, b, "AMIGO PID b at tau {tau}");
            for tc in [0.5 * l, l, 3.0 * l] {
                let s = simc(model, tc).unwrap();
                close(s.k, t / (g * (tc + l)), "SIMC K");
                close(s.ti, t.min(4.0 * (tc + l)), "SIMC Ti");
            }
        }
    }
}

/// The settling test of `identify_step_at` (module docs: the last tenth and the tenth before
/// "agree to 0.2 % of the change, plus four standard deviations of the difference of two means
/// of noise of this peak"): with a noise peak of 1 % of the change measured before the step,
/// that allowance is 0.2 % + 4 · 1 % / √20 ≈ 1.1 % for a tail of 20 samples. A response still
/// climbing by 2.3 % of the change from one tenth to the next is refused as not settled (its
/// message in percent); the same response without the climb is taken; and 20 samples from the
/// step are enough to be looked at.
#[test]
fn a_response_still_moving_past_the_noise_allowance_is_not_settled() {
    use regler_pid::tuning::{IdentifyError, identify_step_at};
    let log = |climb: f64, n: usize| -> Vec<f64> {
        let mut y: Vec<f64> = (0..30)
            .map(|k| if k % 2 == 0 { 0.01 } else { -0.01 })
            .collect();
        y.extend((0..n).map(|k| {
            let t = k as f64;
            1.0 - (-t / 10.0).exp() + climb * t
        }));
        y
    };
    let moving = log(0.0015, 200);
    match identify_step_at(&moving, 30, 1.0, 1.0) {
        Err(IdentifyError::NotSettled(m)) => {
            assert!(m > 0.02 && m < 0.025, "moving {m}");
            let text = IdentifyError::NotSettled(m).to_string();
            assert!(
                text.contains(&format!("by {:.2} % of the change", m * 100.0)),
                "{text}"
            );
        }
        other => panic!("{other:?}"),
    }
    assert!(identify_step_at(&log(0.0, 200), 30, 1.0, 1.0).is_ok());
    let short = identify_step_at(&log(0.0, 20), 30, 1.0, 1.0);
    assert!(
        !matches!(short, Err(IdentifyError::TooFewSamples(_))),
        "20 samples: {short:?}"
    );
    assert_eq!(
        identify_step_at(&log(0.0, 19), 30, 1.0, 1.0),
        Err(IdentifyError::TooFewSamples(19))
    );
}

/// A long log in `f32` — 10⁶ samples (17 minutes at 1 kHz) of a small step on a large level,
/// the case where sums of samples lose digits — identifies the same model as the log in `f64`,
/// to 10⁻⁴ of each parameter.
#[test]
#[cfg_attr(
    miri,
    ignore = "two logs of 10⁶ samples: hours under Miri; safe code, run natively in every CI run"
)]
fn a_long_f32_log_identifies_the_model_the_f64_log_does() {
    use regler_pid::tuning::identify_step_at;
    let (n, pre, h) = (1_000_000usize, 50_000usize, 0.001);
    let (level, change, t, l) = (50.0, 0.5, 60.0, 8.0);
    let y64: Vec<f64> = (0..n)
        .map(|k| {
            let after = (k as f64 - pre as f64) * h - l;
            level
                + if after > 0.0 {
                    change * (1.0 - (-after / t).exp())
                } else {
                    0.0
                }
        })
        .collect();
    let y32: Vec<f32> = y64.iter().map(|&v| v as f32).collect();
    let m64 = identify_step_at(&y64, pre, h, 1.0).unwrap();
    let m32 = identify_step_at(&y32, pre, h as f32, 1.0).unwrap();
    for (name, a, b) in [
        ("K", f64::from(m32.gain), m64.gain),
        ("T", f64::from(m32.time_constant), m64.time_constant),
        ("L", f64::from(m32.dead_time), m64.dead_time),
    ] {
        assert!((a - b).abs() <= 1e-4 * b.abs(), "{name}: f32 {a}, f64 {b}");
    }
}

/// An inverse response is refused with how far it first went the wrong way, as a positive
/// fraction of the change and in the message in percent: a dip of 5 % of the change during
/// the dead time, then a first-order rise.
#[test]
fn an_inverse_response_reports_its_dip() {
    use regler_pid::tuning::{IdentifyError, identify_step_at};
    let mut y = vec![0.0f64; 30];
    y.extend((0..400).map(|k| {
        let t = f64::from(k);
        let rise = if k < 40 {
            0.0
        } else {
            1.0 - (-(t - 40.0) / 20.0).exp()
        };
        let dip = if k < 40 {
            -0.05 * (std::f64::consts::PI * t / 40.0).sin()
        } else {
            0.0
        };
        rise + dip
    }));
    match identify_step_at(&y, 30, 1.0, 1.0) {
        Err(IdentifyError::Undershoot(by)) => {
            assert!(by > 0.04 && by < 0.06, "{by}");
            let text = IdentifyError::Undershoot(by).to_string();
            assert!(
                text.contains(&format!("wrong way by {:.1} %", by * 100.0)),
                "{text}"
            );
        }
        other => panic!("{other:?}"),
    }
}

/// The area method on noiseless, finely sampled FOPDT responses (h = T/500) whose dead time is
/// not a whole number of samples, from both ends of a sample: T and L come out within a twentieth
/// of a sample period (the trapezoidal rule's error on such a log is a few thousandths of h), so
/// the sub-sample parts of the areas — the end corrections, the interpolated last interval —
/// are each what they must be.
#[test]
fn a_noiseless_finely_sampled_fopdt_is_recovered_to_a_fraction_of_a_sample() {
    use regler_pid::tuning::identify_step_at;
    let h = 0.01;
    for (gain, t, l) in [
        (2.0, 5.0, 1.2345),
        (-0.5, 5.0, 0.4321),
        (1.0, 5.0, 2.005),
        (3.0, 8.0, 0.0075),
    ] {
        let pre = 25;
        let y: Vec<f64> = (0..pre + 20_000)
            .map(|k| {
                let after = (k as f64 - pre as f64) * h - l;
                if after > 0.0 {
                    gain * (1.0 - (-after / t).exp())
                } else {
                    0.0
                }
            })
            .collect();
        let m = identify_step_at(&y, pre, h, 1.0).unwrap();
        assert!((m.gain - gain).abs() <= 1e-6, "K {} for {gain}", m.gain);
        assert!(
            (m.time_constant - t).abs() <= 0.05 * h,
            "T {} for {t} (L {l})",
            m.time_constant
        );
        assert!(
            (m.dead_time - l).abs() <= 0.05 * h,
            "L {} for {l} (T {t})",
            m.dead_time
        );
    }
}

/// The relay experiment driven by a measurement of the test's own (no plant), so every period
/// and amplitude is exact: the relay switches only when the error is *beyond* the hysteresis;
/// a period of 4 samples is a limit cycle and one of 3 is chattering; periods that agree give
/// Tu = the period and Ku = 4d / (π·√(a² − ε²)); periods that do not agree never finish; and
/// each error says what happened.
#[test]
fn the_relay_on_a_synthetic_measurement() {
    use regler_pid::Action;
    let cfg = RelayConfig {
        action: Action::Direct,
        bias: 0.0,
        amplitude: 1.0,
        hysteresis: 0.5,
        h: 0.25,
        cycles: 3,
        tolerance: 0.05,
        timeout: 1000.0,
    };
    // The error is −measurement (set-point 0): the relay, high, goes low once the measurement
    // is above +ε, and high again once it is below −ε.
    let mut r = Relay::new(cfg).unwrap();
    assert_eq!(r.update(0.0, 0.0), Ok(RelayStep::Running(1.0)));
    assert_eq!(
        r.update(0.0, 0.5),
        Ok(RelayStep::Running(1.0)),
        "at +ε: no switch"
    );
    assert_eq!(r.update(0.0, 0.5 + 1e-9), Ok(RelayStep::Running(-1.0)));
    assert_eq!(
        r.update(0.0, -0.5),
        Ok(RelayStep::Running(-1.0)),
        "at −ε: no switch"
    );
    assert_eq!(r.update(0.0, -0.5 - 1e-9), Ok(RelayStep::Running(1.0)));

    // A wave of `period` samples between −2 and +2: one rise a period.
    let run = |periods: &[usize]| {
        let mut r = Relay::new(cfg).unwrap();
        let mut last = Ok(RelayStep::Running(0.0));
        for &p in periods.iter().cycle().take(40) {
            for k in 0..p {
                let y = if k < p / 2 { -2.0 } else { 2.0 };
                last = r.update(0.0, y);
                if !matches!(last, Ok(RelayStep::Running(_))) {
                    return last;
                }
            }
        }
        last
    };
    let a: f64 = 2.0;
    let ku = 4.0 / (std::f64::consts::PI * (a * a - 0.25).sqrt());
    for period in [4usize, 10, 24] {
        match run(&[period]) {
            Ok(RelayStep::Done(u)) => {
                assert!((u.tu - period as f64 * 0.25).abs() < 1e-12, "Tu {}", u.tu);
                assert!((u.ku - ku).abs() < 1e-12 * ku, "Ku {} for {ku}", u.ku);
            }
            other => panic!("period {period}: {other:?}"),
        }
    }
    let chatter = run(&[3]);
    assert_eq!(chatter, Err(RelayError::Chattering { period: 0.75 }));
    assert_eq!(
        chatter.unwrap_err().to_string(),
        "the relay chatters (period 0.75 s): raise the hysteresis above the measurement noise"
    );
    // Periods of 10 and 14 samples by turns: a spread of 1/3, never within 5 %.
    match run(&[10, 14]) {
        Err(RelayError::Timeout { periods }) => {
            assert!(periods > 10, "{periods}");
            assert_eq!(
                RelayError::<f64>::Timeout { periods }.to_string(),
                format!("no stable limit cycle before the time-out ({periods} periods seen)")
            );
        }
        Ok(RelayStep::Running(_)) => {}
        other => panic!("{other:?}"),
    }
    // Periods of 40 and 41 samples by turns: a spread of 2.5 %, within 5 %: done, Tu between.
    match run(&[40, 41]) {
        Ok(RelayStep::Done(u)) => assert!(u.tu > 10.0 && u.tu < 10.25, "Tu {}", u.tu),
        other => panic!("{other:?}"),
    }
    assert_eq!(
        RelayError::<f64>::Config("h must be finite and positive").to_string(),
        "relay configuration: h must be finite and positive"
    );
    // "How closely they must agree: largest relative spread": a spread exactly at the
    // tolerance agrees. Two periods at a time; periods of 3 and 4 s by turns (a spread of
    // 1/3.5), then periods of 3 s whose amplitude is 3 and 4 by turns (the same spread: the
    // low half at −2, the high one at 4 and 6; a period runs from rise to rise).
    let at = RelayConfig {
        cycles: 2,
        tolerance: 1.0 / 3.5,
        ..cfg
    };
    let waves: [&[(usize, f64, f64)]; 2] = [
        &[(12, -2.0, 2.0), (16, -2.0, 2.0)],
        &[(12, -2.0, 4.0), (12, -2.0, 6.0)],
    ];
    for wave in waves {
        let mut r = Relay::new(at).unwrap();
        let mut done = None;
        'run: for &(p, low, high) in wave.iter().cycle().take(20) {
            for k in 0..p {
                let y = if k < p / 2 { low } else { high };
                match r.update(0.0, y) {
                    Ok(RelayStep::Running(_)) => {}
                    other => {
                        done = Some(other);
                        break 'run;
                    }
                }
            }
        }
        match done {
            Some(Ok(RelayStep::Done(u))) => {
                assert_eq!(r.result(), Some(u), "the estimate, once done");
                assert_eq!(
                    r.update(0.0, 0.0),
                    Ok(RelayStep::Done(u)),
                    "and it stays done"
                );
            }
            other => panic!("{wave:?}: {other:?}"),
        }
    }
    assert_eq!(Relay::new(cfg).unwrap().result(), None);
    // A relay of 10⁻³⁰⁰ against an oscillation of 10³⁰⁰: Ku = 4d/(π·a) underflows to 0, which
    // is no estimate.
    let mut r = Relay::new(RelayConfig {
        amplitude: 1e-300,
        ..cfg
    })
    .unwrap();
    let mut last = Ok(RelayStep::Running(0.0));
    for k in 0..400 {
        last = r.update(0.0, if k % 10 < 5 { -1e300 } else { 1e300 });
        if !matches!(last, Ok(RelayStep::Running(_))) {
            break;
        }
    }
    assert_eq!(
        last,
        Err(RelayError::AmplitudeUnmeasurable { amplitude: 1e300 })
    );
}

/// From the attack on the identification (issue 22): a log near the type's largest value, or
/// with a sample period so long that the log's duration overflows, is never handed back as a
/// wrong model — the tenth before the last of an `f32` log from 3·10³⁸ (its plain sum
/// overflowed, the mean was NaN, and a NaN "movement" passed the settling check: Ok; the sums
/// are of deviations now, and the log is refused as not settled, as the same log at 2⁻¹⁰⁰ is,
/// with the same figure), and a two-lag response at h = 10³⁰⁶ (the slack for a negative dead
/// time became NaN and switched that check off: L = 0).
#[test]
fn a_log_near_the_largest_value_or_of_a_huge_period_is_never_modelled_wrongly() {
    use regler_pid::tuning::{IdentifyError, identify_step};
    let y: Vec<f32> = (0..200)
        .map(|i| {
            let r = if i < 20 {
                0.0
            } else if i < 180 {
                0.942 * (1.0 - (-(f64::from(i) - 20.0) / 15.0).exp())
            } else {
                1.0
            };
            (3e38 * (1.0 - r)) as f32
        })
        .collect();
    let got = identify_step(&y, 1.0f32, 1.0f32);
    assert!(matches!(got, Err(IdentifyError::NotSettled(_))), "{got:?}");
    // 2⁻¹⁰⁰ written out (its exponent field): Miri perturbs `powi`.
    let two_to_minus_100 = f32::from_bits((127 - 100) << 23);
    let scaled: Vec<f32> = y.iter().map(|v| v * two_to_minus_100).collect();
    assert_eq!(identify_step(&scaled, 1.0f32, 1.0f32), got);
    let two_lags: Vec<f64> = (0..1000)
        .map(|i| {
            let t = f64::from(i);
            1.0 - 0.5 * (-t).exp() - 0.5 * (-t / 100.0).exp()
        })
        .collect();
    assert_eq!(
        identify_step(&two_lags, 1.0, 1.0),
        Err(IdentifyError::NotFopdt)
    );
    let huge = identify_step(&two_lags, 1e306, 1.0);
    assert!(huge.is_err(), "{huge:?}");
}

/// What `identify_step_at` returns, in `F`.
type Fit<F> = Result<regler_pid::tuning::Fopdt<F>, regler_pid::tuning::IdentifyError<F>>;

/// The model of `y` and of `y` multiplied by `scale` (a power of two), in `F`.
fn models_at_scale<F: regler_pid::Real + core::ops::Mul<Output = F>>(
    y: &[F],
    pre: usize,
    h: F,
    scale: F,
) -> (Fit<F>, Fit<F>) {
    let scaled: Vec<F> = y.iter().map(|&v| v * scale).collect();
    (
        regler_pid::tuning::identify_step_at(y, pre, h, F::one()),
        regler_pid::tuning::identify_step_at(&scaled, pre, h, F::one()),
    )
}

/// Attack finding (break 3): the baseline's and the tails' means were plain sums of the
/// samples, so a long log at a high level was refused as an overflow although every mean, and
/// the model, fit the type (an `f32` log of 1.4 million samples at 10³³). The same log
/// multiplied by a power of two must give the same T and L and the gain multiplied by it,
/// exactly: in `f32` from 2⁻¹⁰⁰ to 2¹²³ (the largest sample just under 2¹²⁷), in `f64` from
/// 2⁻¹⁰⁰⁰ to 2¹⁰¹⁹, and the attack's long `f32` log at 2¹¹⁰.
#[test]
#[cfg_attr(
    miri,
    ignore = "2 000 fits of 2 200 samples and two of 1.4 million: hours under Miri; runs natively in every CI run"
)]
fn a_log_scaled_by_a_power_of_two_gives_the_same_model_scaled() {
    let f = fopdt_response(5.0, 1.5);
    let (pre, n, h) = (200, 2_000, 0.05);
    let y32 = log_of::<f32>(&f, pre, n, h, 10.0, 0.8, 0.004, 7);
    let y64 = log_of::<f64>(&f, pre, n, h, 10.0, 0.8, 0.004, 7);
    for k in -100i32..=123 {
        let scale = 2f32.powi(k);
        assert_eq!(scale.log2(), k as f32, "2^{k} written exactly");
        let (one, scaled) = models_at_scale(&y32, pre, h as f32, scale);
        let one = one.unwrap();
        let scaled = scaled.unwrap_or_else(|e| panic!("f32 at 2^{k}: {e}"));
        assert_eq!(scaled.gain, one.gain * scale, "f32 gain at 2^{k}");
        assert_eq!(scaled.time_constant, one.time_constant, "f32 T at 2^{k}");
        assert_eq!(scaled.dead_time, one.dead_time, "f32 L at 2^{k}");
    }
    for k in -1000i32..=1019 {
        let scale = 2f64.powi(k);
        assert_eq!(scale.log2(), f64::from(k), "2^{k} written exactly");
        let (one, scaled) = models_at_scale(&y64, pre, h, scale);
        let one = one.unwrap();
        let scaled = scaled.unwrap_or_else(|e| panic!("f64 at 2^{k}: {e}"));
        assert_eq!(scaled.gain, one.gain * scale, "f64 gain at 2^{k}");
        assert_eq!(scaled.time_constant, one.time_constant, "f64 T at 2^{k}");
        assert_eq!(scaled.dead_time, one.dead_time, "f64 L at 2^{k}");
    }
    // The attack's log: 400 000 samples before the step and a million after, level 1 and
    // change 1/100, in f32; then at 2¹¹⁰ (about 10³³), whose plain sums overflow.
    let long = log_of::<f32>(
        &fopdt_response(60.0, 8.0),
        400_000,
        1_000_000,
        0.001,
        1.0,
        0.01,
        0.0,
        1,
    );
    let scale = 2f32.powi(110);
    let (one, scaled) = models_at_scale(&long, 400_000, 0.001, scale);
    let one = one.unwrap();
    let scaled = scaled.unwrap_or_else(|e| panic!("the long f32 log at 2^110: {e}"));
    assert_eq!(scaled.gain, one.gain * scale);
    assert_eq!(scaled.time_constant, one.time_constant);
    assert_eq!(scaled.dead_time, one.dead_time);
}

/// The stated tolerance with the samples' rounding: ρ = ε times the largest sample's magnitude
/// (at least the type's smallest normal value) over the fitted change |K·step|; K within
/// 1 % + ν of K plus ρ of the fitted K, T and L within the noise tolerance plus
/// ρ·(10·(T + L) + 4·D).
fn within_tolerance_rounded<F: regler_pid::Real>(
    y: &[F],
    (epsilon, smallest_normal, smallest): (f64, f64, f64),
    m: &regler_pid::tuning::Fopdt,
    (k, t, l, h): (f64, f64, f64, f64),
    nu: f64,
    n: usize,
) -> Result<(), String> {
    let largest = y
        .iter()
        .map(|v| v.to_f64_exact().abs())
        .fold(smallest_normal, f64::max);
    // As a fraction first: ε times f64's smallest normal value underflows.
    let rho = epsilon * (largest / m.gain.abs());
    let tl = t + l;
    let d = n as f64 * h;
    let slack = 0.02 * tl
        + h
        + nu * (tl + NOISE_LOG_FACTOR * d / (n as f64).sqrt())
        + rho * (10.0 * tl + 4.0 * d);
    let subnormal = if m.gain.abs() < smallest_normal {
        smallest
    } else {
        0.0
    };
    let within = (m.gain - k).abs() <= (0.01 + nu) * k.abs() + rho * m.gain.abs() + subnormal
        && (m.time_constant - t).abs() <= slack
        && (m.dead_time - l).abs() <= slack;
    if within {
        Ok(())
    } else {
        Err(format!(
            "{m:?} for K {k}, T {t}, L {l}: ρ = {rho:.4}, T and L ±{slack:.3}"
        ))
    }
}

/// ε, the smallest normal value and the smallest positive value of `f32` and `f64`.
const F32_GRID: (f64, f64, f64) = (
    f32::EPSILON as f64,
    f32::MIN_POSITIVE as f64,
    1.401_298_464_324_817e-45,
);
const F64_GRID: (f64, f64, f64) = (f64::EPSILON, f64::MIN_POSITIVE, 5e-324);

/// Attack findings (break 5, and break 1 of the attack after it): the stated tolerance assumed
/// the change spans thousands of ulps of the samples, which a subnormal change does not (an
/// `f32` step of 10⁻⁴⁴, 7 ulps, gave T = 9.12 for 10 with ±0.34 allowed), nor a change under a
/// large baseline; and the rounding is not noise that averages out: a baseline just under half
/// an ulp off the grid and a final value just over it put the change a whole ulp off (an `f32`
/// change of 20.02 ulps under a baseline 4·10⁵ times larger: K 4.9 % off, T 3.7 s for 10). Every
/// noise-free FOPDT log is fitted within the tolerance with the rounding's term, ρ, or is no
/// response: changes of 1 to 2²³ − 1 ulps of the smallest subnormal (`f32` and `f64`, on the
/// grid and off it), `f32` changes of 2 to 1 000 ulps of the baseline at the offsets that round
/// the baseline and the final value apart, and 400 random baselines 10³ to 10⁶ times the change.
#[test]
#[cfg_attr(
    miri,
    ignore = "a few thousand fits of up to 3 000 samples: hours under Miri; runs natively in every CI run"
)]
fn a_change_of_few_ulps_is_recovered_within_the_rounding_tolerance() {
    use regler_pid::tuning::IdentifyError;
    fn check<F: regler_pid::Real>(
        y: &[F],
        grid: (f64, f64, f64),
        (k, t, l, h, pre, n): (f64, f64, f64, f64, usize, usize),
        what: &str,
    ) -> bool {
        match identify(y, pre, h, 1.0) {
            Ok(m) => {
                if let Err(e) = within_tolerance_rounded(y, grid, &m, (k, t, l, h), 0.0, n) {
                    panic!("{what}: {e}");
                }
                true
            }
            Err(e) => {
                assert_eq!(e, IdentifyError::<f64>::NoResponse.to_string(), "{what}");
                false
            }
        }
    }
    let (t, l, h, pre, n) = (10.0, 2.0, 0.1, 100, 1_000);
    let f = fopdt_response(t, l);
    let ulps = [
        1.0,
        2.0,
        3.0,
        5.0,
        7.0,
        10.0,
        14.0,
        20.0,
        33.0,
        50.0,
        77.0,
        100.0,
        300.0,
        1e3,
        1e4,
        1e5,
        1e6,
        8_388_607.0,
    ];
    // Subnormal changes from a baseline of 0, on the grid: one ulp is no response, two fit.
    for &u in &ulps {
        for sign in [1.0, -1.0] {
            let c32 = sign * u * f64::from(f32::from_bits(1));
            let y = log_of::<f32>(&f, pre, n, h, 0.0, c32, 0.0, 1);
            let fitted = check(
                &y,
                F32_GRID,
                (c32, t, l, h, pre, n),
                &format!("f32, {u} ulps"),
            );
            assert_eq!(fitted, u > 1.0, "f32, {u} ulps");
            let c64 = sign * u * f64::from_bits(1);
            let y = log_of::<f64>(&f, pre, n, h, 0.0, c64, 0.0, 1);
            let fitted = check(
                &y,
                F64_GRID,
                (c64, t, l, h, pre, n),
                &format!("f64, {u} ulps"),
            );
            assert_eq!(fitted, u > 1.0, "f64, {u} ulps");
        }
    }
    // Off the grid: the baseline and the final value rounded apart (and together), in f64
    // subnormals and in f32 under a baseline of 2¹⁸ (ulp 2⁻⁵), for T and L in samples.
    let offsets = [-0.49, -0.25, 0.0, 0.25, 0.49];
    let fractions = [0.02, 0.5, 0.98];
    for (t, l) in [(10.0, 2.0), (50.0, 20.0), (30.0, 0.0)] {
        let f = fopdt_response(t, l);
        let n = (l + 12.0 * t) as usize;
        for whole in [2.0, 3.0, 5.0, 7.0, 20.0, 100.0, 1000.0] {
            for fraction in fractions {
                for offset in offsets {
                    for sign in [1.0, -1.0] {
                        let change = sign * (whole + fraction);
                        let what = format!("{whole}+{fraction} ulps from {offset}, T {t}, L {l}");
                        let y: Vec<f64> = log_of::<f64>(&f, 100, n, 1.0, offset, change, 0.0, 1)
                            .iter()
                            .map(|v| v.round() * f64::from_bits(1))
                            .collect();
                        let k = change * f64::from_bits(1);
                        check(&y, F64_GRID, (k, t, l, 1.0, 100, n), &format!("f64 {what}"));
                        let ulp = 2f64.powi(-5);
                        let y = log_of::<f32>(
                            &f,
                            100,
                            n,
                            1.0,
                            262_144.0 + offset * ulp,
                            change * ulp,
                            0.0,
                            1,
                        );
                        check(
                            &y,
                            F32_GRID,
                            (change * ulp, t, l, 1.0, 100, n),
                            &format!("f32 {what}"),
                        );
                    }
                }
            }
        }
    }
    // Random baselines 10³ to 10⁶ times the change, off the grid, in f32; T of 30 to 200
    // samples, L up to 2T, logs of 12 T.
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut uniform = move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    };
    for case in 0..400 {
        let t = 30.0 + 170.0 * uniform();
        let l = 2.0 * t * uniform();
        let change = if uniform() < 0.5 { -1.0 } else { 1.0 } * (0.1 + uniform());
        let base = change.abs() * 10f64.powf(3.0 + 3.0 * uniform()) * (1.0 + uniform());
        let n = (l + 12.0 * t) as usize;
        let y = log_of::<f32>(&fopdt_response(t, l), 50, n, 1.0, base, change, 0.0, 1);
        check(
            &y,
            F32_GRID,
            (change, t, l, 1.0, 50, n),
            &format!("case {case}: base {base}, change {change}"),
        );
    }
}

/// Attack finding (second attack, re-checking the slack fix): the tolerance for a negative
/// dead time was computed in seconds, h + 2 % (T + L) + ν·(T + L + 10·h·√N), which overflowed
/// for an h at which T + L still fit (a noise-free lag refused as an overflow at h = 2·10³⁰⁶).
/// It is judged in samples now, so the verdict cannot depend on h: at every power of two h
/// from the smallest normal value up, a first-order log gives T and L exactly h times the fit
/// at h = 1, until T + L itself overflows, where it is named; and a two-lag log is `NotFopdt`
/// at every h, 2¹⁰²³ included (a fourth attack found the overflow named before the verdict).
#[test]
#[cfg_attr(
    miri,
    ignore = "4 000 fits of 1 000 samples: hours under Miri; runs natively in every CI run"
)]
fn the_verdict_and_the_fit_in_samples_do_not_depend_on_the_sample_period() {
    use regler_pid::tuning::{IdentifyError, identify_step};
    let lag: Vec<f64> = (0..1000)
        .map(|k| {
            if k < 30 {
                0.0
            } else {
                1.0 - (-(f64::from(k) - 30.0) / 50.0).exp()
            }
        })
        .collect();
    let two_lags: Vec<f64> = (0..1000)
        .map(|i| {
            let t = f64::from(i);
            1.0 - 0.5 * (-t).exp() - 0.5 * (-t / 100.0).exp()
        })
        .collect();
    let unit = identify_step(&lag, 1.0, 1.0).unwrap();
    assert_eq!(
        identify_step(&two_lags, 1.0, 1.0),
        Err(IdentifyError::NotFopdt)
    );
    let overflow = IdentifyError::Overflow("T + L (the sample period times the log)");
    for k in -1022i32..=1023 {
        let h = 2f64.powi(k);
        assert_eq!(h.log2(), f64::from(k), "2^{k} written exactly");
        match identify_step(&lag, h, 1.0) {
            Ok(m) => {
                assert_eq!(m.gain, unit.gain, "h = 2^{k}");
                assert_eq!(m.time_constant, unit.time_constant * h, "h = 2^{k}");
                assert_eq!(m.dead_time, unit.dead_time * h, "h = 2^{k}");
            }
            Err(e) => assert!(
                ((unit.time_constant + unit.dead_time) * h).is_infinite() && e == overflow,
                "h = 2^{k}: {e}"
            ),
        }
        // The verdict comes first: NotFopdt even where T + L (about 50.5 samples) overflows.
        assert_eq!(
            identify_step(&two_lags, h, 1.0),
            Err(IdentifyError::NotFopdt),
            "two lags, h = 2^{k}"
        );
    }
}

/// Attack findings (the attack after the deviation sums): the sum of a tail's deviations is
/// its count times its noise, which still overflowed near the type's largest value (a noisy
/// `f64` log of 10⁵ samples at 2¹⁰¹⁸, its largest sample `f64::MAX`/63, was refused as an
/// overflow of the change); and v − y0 overflowed for a noisy sample above the final value of
/// a change of 0.995 × `f64::MAX` from a negative baseline (`Overshoot(inf)`). Both scale
/// exactly now. And a T that overflows where T + L does not is named T.
#[test]
#[cfg_attr(
    miri,
    ignore = "noisy logs of 10⁵ and 10⁶ samples, fitted twice: hours under Miri; runs natively in every CI run"
)]
fn a_noisy_log_near_the_largest_value_scales_exactly() {
    use regler_pid::tuning::{IdentifyError, identify_step};
    let f = fopdt_response(5_000.0, 2_000.0);
    let y = log_of::<f64>(&f, 500, 100_000, 1.0, 0.0, 1.0, 0.02, 7);
    for k in [1016, 1018, 1020] {
        let (one, scaled) = models_at_scale(&y, 500, 1.0, 2f64.powi(k));
        let one = one.unwrap();
        let scaled = scaled.unwrap_or_else(|e| panic!("f64 at 2^{k}: {e}"));
        assert_eq!(scaled.gain, one.gain * 2f64.powi(k), "f64 at 2^{k}");
        assert_eq!(
            (scaled.time_constant, scaled.dead_time),
            (one.time_constant, one.dead_time)
        );
    }
    let f = fopdt_response(50_000.0, 20_000.0);
    let y = log_of::<f32>(&f, 500, 1_000_000, 1.0, 0.0, 1.0, 0.02, 7);
    let (one, scaled) = models_at_scale(&y, 500, 1.0f32, 2f32.powi(120));
    let one = one.unwrap();
    let scaled = scaled.unwrap_or_else(|e| panic!("f32 at 2^120: {e}"));
    assert_eq!(scaled.gain, one.gain * 2f32.powi(120));
    assert_eq!(
        (scaled.time_constant, scaled.dead_time),
        (one.time_constant, one.dead_time)
    );
    // From −0.995 to +0.995 with 1 % noise, then at 2¹⁰²³: the change is 0.995 × MAX.
    let y = log_of::<f64>(
        &fopdt_response(30.0, 10.0),
        20,
        400,
        1.0,
        -0.995,
        1.99,
        0.02,
        7,
    );
    let (one, scaled) = models_at_scale(&y, 20, 1.0, 2f64.powi(1023));
    let one = one.unwrap();
    let scaled = scaled.unwrap_or_else(|e| panic!("a change of 0.995 MAX: {e}"));
    assert_eq!(scaled.gain, one.gain * 2f64.powi(1023));
    assert_eq!(
        (scaled.time_constant, scaled.dead_time),
        (one.time_constant, one.dead_time)
    );
    // A first sample 0.25 below a baseline of −0.5, 40 samples before the step: at 2¹⁰²¹
    // (f64) and 2¹²⁵ (f32) the sum of the deviations before the step overflows where at 2⁰ it
    // does not; the mean, and so the model, must not change (a fourth attack found T and L a
    // few ulps apart when the sum switched to dividing by the count).
    let mut outlier: Vec<f64> =
        log_of::<f64>(&fopdt_response(7.0, 3.0), 40, 200, 1.0, -0.5, 0.875, 0.0, 1);
    for (k, v) in outlier.iter_mut().enumerate().take(40).skip(1) {
        *v += 0.01 * (k as f64 * 1.3).sin();
    }
    outlier[0] = -0.75;
    let (one, scaled) = models_at_scale(&outlier, 40, 1.0, 2f64.powi(1021));
    let (one, scaled) = (one.unwrap(), scaled.unwrap());
    assert_eq!(scaled.gain, one.gain * 2f64.powi(1021));
    assert_eq!(
        (scaled.time_constant, scaled.dead_time),
        (one.time_constant, one.dead_time)
    );
    let outlier: Vec<f32> = outlier.iter().map(|&v| v as f32).collect();
    let (one, scaled) = models_at_scale(&outlier, 40, 1.0f32, 2f32.powi(125));
    let (one, scaled) = (one.unwrap(), scaled.unwrap());
    assert_eq!(scaled.gain, one.gain * 2f32.powi(125));
    assert_eq!(
        (scaled.time_constant, scaled.dead_time),
        (one.time_constant, one.dead_time)
    );
    // T + L is 1.78 samples and T 2.27: at h = 2¹⁰²³ only T overflows, and is named.
    let mut y: Vec<f64> = (0..80)
        .map(|i| {
            let t = f64::from(i);
            1.0 - 0.5 * (-t / 0.3).exp() - 0.5 * (-t / 3.0).exp()
        })
        .collect();
    y[0] = 0.0;
    assert_eq!(
        identify_step(&y, 2f64.powi(1023), 1.0),
        Err(IdentifyError::Overflow(
            "T (the sample period times the log)"
        ))
    );
}

/// Attack findings (the fifth attack): a log whose tail spans past the largest value through a
/// one-sample dropout was refused as an overflow at 2¹⁰²³ though its change fits (the means now
/// never overflow: they halve what would); a gain that underflows to 0 or a few subnormal bits
/// came back as a model (a step of 2⁶⁰ on a change of 2⁻¹⁰⁰ in `f32`: gain 0; the docs now
/// state the subnormal gain's error), and a T that rounds to 0 at a sample period near the
/// smallest normal value came back as T = 0, which the docs say is never fitted: both zeros
/// are `Underflow`, named.
#[test]
#[cfg_attr(
    miri,
    ignore = "logs of 1 000 to 3 000 samples fitted at several scales: an hour under Miri; runs natively in every CI run"
)]
fn dropouts_near_the_largest_value_fit_and_underflows_are_named() {
    use regler_pid::tuning::{IdentifyError, identify_step, identify_step_at};
    // Noise-free: a lag to 1.985 from −0.9925, settled 1 % high, with one sample in each of
    // the last two tenths reading the baseline (a dropout).
    let (y0, change) = (-0.9925f64, 1.985f64);
    let mut y = vec![y0; 31];
    for i in 1..1020 {
        y.push(if i < 816 {
            y0 + change * (1.0 - (-f64::from(i) / 40.0).exp())
        } else if i == 850 || i == 950 {
            y0
        } else {
            y0 + change * 102.0 / 101.0
        });
    }
    let fit = |k: i32| {
        let scaled: Vec<f64> = y.iter().map(|v| v * 2f64.powi(k)).collect();
        identify_step_at(&scaled, 30, 1.0, 1.0)
    };
    let one = fit(0).unwrap();
    for k in [1000, 1022, 1023] {
        let at = fit(k).unwrap_or_else(|e| panic!("2^{k}: {e}"));
        assert_eq!(at.gain, one.gain * 2f64.powi(k), "2^{k}");
        assert_eq!(
            (at.time_constant, at.dead_time),
            (one.time_constant, one.dead_time),
            "2^{k}"
        );
    }
    // A gain that rounds to 0 is refused, naming it; a subnormal one is within the smallest
    // positive value of the exact quotient.
    let lag32 = log_of::<f32>(&fopdt_response(40.0, 15.0), 0, 3000, 1.0, 0.0, 1.7, 0.0, 1);
    let tiny32: Vec<f32> = lag32.iter().map(|v| v * 2f32.powi(-100)).collect();
    let gain = IdentifyError::Underflow("the gain (change / step)");
    assert_eq!(identify_step(&tiny32, 1.0, 2f32.powi(60)), Err(gain));
    let sub = identify_step(&tiny32, 1.0, 2f32.powi(50)).unwrap().gain;
    assert!(sub > 0.0 && !sub.is_normal());
    assert!(
        (f64::from(sub) - 1.7 * 2f64.powi(-150)).abs() <= F32_GRID.2,
        "{sub:e}"
    );
    let lag64 = log_of::<f64>(&fopdt_response(40.0, 15.0), 0, 3000, 1.0, 0.0, 1.7, 0.0, 1);
    let tiny64: Vec<f64> = lag64.iter().map(|v| v * 2f64.powi(-1000)).collect();
    assert_eq!(
        identify_step(&tiny64, 1.0, 2f64.powi(80)),
        Err(IdentifyError::Underflow("the gain (change / step)"))
    );
    let sub = identify_step(&tiny64, 1.0, 2f64.powi(60)).unwrap().gain;
    assert!(sub > 0.0 && !sub.is_normal());
    assert!(
        (sub - 1.7 * 2f64.powi(-1000) / 2f64.powi(60)).abs() <= F64_GRID.2,
        "{sub:e}"
    );
    assert_eq!(
        IdentifyError::<f64>::Underflow("the gain (change / step)").to_string(),
        "the gain (change / step) underflows the float type (it would lose its precision)"
    );
    // A nearly square step whose overshoot stays under 1 %: T is 4·10⁻³⁰ samples; at
    // h = 10⁻³⁰⁰ it rounds to 0 and is named.
    let d = f64::from_bits(0x3f81_1111_1111_1140);
    let mut square = vec![0.0f64; 10];
    square.push(1.0);
    square.extend(core::iter::repeat_n(1.0 + d, 60));
    square.resize(400, 1.0);
    let m = identify_step(&square, 1.0, 1.0).unwrap();
    assert!(m.time_constant > 0.0 && m.time_constant < 1e-20, "{m:?}");
    assert_eq!(
        identify_step(&square, 1e-300, 1.0),
        Err(IdentifyError::Underflow(
            "T (the sample period times the log)"
        ))
    );
}

/// The documented rule for a negative dead time: refused (`NotFopdt`) when the fitted L is
/// below minus the stated tolerance, h + 2 % (T + L) + ν·(T + L + 10·D/√N) (the rounding's
/// term is 10⁻¹⁶ of it here), fitted otherwise. Two lags, 1 − a·e^(−t/T1) − (1 − a)·e^(−t/T2),
/// whose method-of-areas T and L are known in closed form (A0 = a·T1 + (1 − a)·T2,
/// A1 = A0 − a·T1·(1 − e^(−A0/T1)) − (1 − a)·T2·(1 − e^(−A0/T2)), T = e·A1, L = A0 − T), swept
/// across the boundary, with noise only before the step (±p alternating: ν is exactly p over
/// the change): wherever L is more than 0.1 % of T + L from minus the tolerance (the sampling's
/// own error is far below that), the verdict is the rule's, on both sides.
#[test]
#[cfg_attr(
    miri,
    ignore = "hundreds of fits of up to 30 000 samples: hours under Miri; runs natively in every CI run"
)]
fn a_negative_dead_time_is_refused_exactly_beyond_the_stated_tolerance() {
    use regler_pid::tuning::{IdentifyError, identify_step_at};
    let (pre, h, base, change) = (40usize, 0.05f64, 3.0f64, 2.0f64);
    let (mut refused, mut fitted) = (0, 0);
    for (t1, t2, p) in [
        (1.0, 50.0, 0.02),
        (2.0, 30.0, 0.0),
        (5.0, 100.0, 0.01),
        (0.5, 20.0, 0.04),
    ] {
        let d = 15.0 * t2;
        let n = (d / h) as usize;
        let nu = p / change;
        for step in 0..=120 {
            let a = f64::from(step) * 0.0025;
            let a0 = a * t1 + (1.0 - a) * t2;
            let a1 =
                a0 - a * t1 * (1.0 - (-a0 / t1).exp()) - (1.0 - a) * t2 * (1.0 - (-a0 / t2).exp());
            let l = a0 - core::f64::consts::E * a1;
            let d_log = n as f64 * h;
            let tolerance = h + 0.02 * a0 + nu * (a0 + 10.0 * d_log / (n as f64).sqrt());
            let mut y: Vec<f64> = (0..pre)
                .map(|k| base + if k % 2 == 0 { p } else { -p })
                .collect();
            y.extend((0..n).map(|k| {
                let t = k as f64 * h;
                base + change * (1.0 - a * (-t / t1).exp() - (1.0 - a) * (-t / t2).exp())
            }));
            let got = identify_step_at(&y, pre, h, 1.0);
            let what = format!(
                "T1 {t1}, T2 {t2}, a {a}, ν {nu}: L {l:.4}, tolerance {tolerance:.4}: {got:?}"
            );
            if l < -tolerance - 0.001 * a0 {
                assert_eq!(got, Err(IdentifyError::NotFopdt), "{what}");
                refused += 1;
            } else if l > -tolerance + 0.001 * a0 {
                assert!(got.is_ok(), "{what}");
                fitted += 1;
            }
        }
    }
    assert!(
        refused > 40 && fitted > 40,
        "refused {refused}, fitted {fitted}"
    );
}

/// The same rule where the samples' rounding is a term of it: an `f32` log of a change of 2 on
/// a baseline of 2¹⁴ (ρ = ε·(2¹⁴ + 2)/2, about 10⁻³: the rounding's term ρ·(10·(T + L) + 4·D)
/// is then about as large as the rest of the tolerance). The baseline and the final value are
/// exact in `f32` (the noise before the step is ±2⁻⁴), so the fit stays at the closed form's,
/// and the samples between are rounded by at most 2⁻¹⁰ of the change. Wherever L is more than
/// 0.5 % of T + L from minus the tolerance, the verdict is the rule's — including logs whose L is
/// refused without the rounding's term and fitted with it.
#[test]
#[cfg_attr(
    miri,
    ignore = "hundreds of fits of up to 8 000 samples: hours under Miri; runs natively in every CI run"
)]
fn a_negative_dead_time_within_the_rounding_term_is_fitted_in_f32() {
    use regler_pid::tuning::{IdentifyError, identify_step_at};
    let (pre, h, base, change, p) = (40usize, 0.05f64, 16_384.0f64, 2.0f64, 0.0625f64);
    let (mut refused, mut fitted, mut by_rounding) = (0, 0, 0);
    for (t1, t2) in [(1.0, 40.0), (2.0, 25.0), (0.5, 15.0)] {
        let d = 10.0 * t2;
        let n = (d / h) as usize;
        for step in 0..=200 {
            let a = f64::from(step) * 0.002;
            let a0 = a * t1 + (1.0 - a) * t2;
            let a1 =
                a0 - a * t1 * (1.0 - (-a0 / t1).exp()) - (1.0 - a) * t2 * (1.0 - (-a0 / t2).exp());
            let l = a0 - core::f64::consts::E * a1;
            let mut y: Vec<f32> = (0..pre)
                .map(|k| (base + if k % 2 == 0 { p } else { -p }) as f32)
                .collect();
            y.extend((0..n).map(|k| {
                let t = k as f64 * h;
                (base + change * (1.0 - a * (-t / t1).exp() - (1.0 - a) * (-t / t2).exp())) as f32
            }));
            let largest = y.iter().fold(0.0f32, |m, v| m.max(v.abs()));
            let rho = f64::from(f32::EPSILON) * f64::from(largest) / change;
            let nu = p / change;
            let d_log = n as f64 * h;
            let without_rounding = h + 0.02 * a0 + nu * (a0 + 10.0 * d_log / (n as f64).sqrt());
            let tolerance = without_rounding + rho * (10.0 * a0 + 4.0 * d_log);
            let got = identify_step_at(&y, pre, h as f32, 1.0f32);
            let what = format!(
                "T1 {t1}, T2 {t2}, a {a}, ρ {rho:.2e}: L {l:.4}, tolerance {tolerance:.4} ({without_rounding:.4} without ρ): {got:?}"
            );
            if l < -tolerance - 0.005 * a0 {
                assert_eq!(got, Err(IdentifyError::NotFopdt), "{what}");
                refused += 1;
            } else if l > -tolerance + 0.005 * a0 {
                assert!(got.is_ok(), "{what}");
                fitted += 1;
                by_rounding += usize::from(l < -without_rounding - 0.005 * a0);
            }
        }
    }
    assert!(
        refused > 40 && fitted > 40 && by_rounding > 20,
        "refused {refused}, fitted {fitted}, fitted only by the rounding's term {by_rounding}"
    );
}

/// The areas are the integrals of the samples joined by straight lines, as the docs state: the
/// trapezoidal rule for A0 = ∫(1 − r) dt over the whole log (its two end samples counted half),
/// and ∫₀^(T+L) r dt with the last, partial interval interpolated. Checked against those
/// integrals computed here, plainly, from the documented baseline (the mean of the samples up to
/// and including the step instant) and final value (the mean of the last tenth), on noisy FOPDT
/// logs whose first sample, at the step instant, is off the baseline (so the end samples' halves
/// and the first interval count): T and T + L agree to 10⁻⁹ — a wrong end correction or
/// interpolation moves them by 10⁻⁵ or more here.
#[test]
#[cfg_attr(
    miri,
    ignore = "two dozen fits of up to 6 000 samples: minutes under Miri; runs natively in every CI run"
)]
fn the_areas_are_the_integrals_of_the_samples_joined_by_straight_lines() {
    use regler_pid::tuning::identify_step_at;
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut noise = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for (k, t, l, h, p) in [
        (2.0, 5.0, 1.3, 0.1, 0.004),
        (-0.5, 40.0, 7.7, 0.25, 0.002),
        (3.0, 1.0, 0.0, 0.01, 0.001),
        (1.0, 12.0, 30.0, 0.5, 0.0),
    ] {
        for first_off in [0.0, 0.3, -0.7] {
            for pre in [0usize, 25] {
                let (base, step) = (5.0, 2.0);
                let change = k * step;
                let n = ((l + 12.0 * t) / h) as usize;
                let mut y: Vec<f64> = (0..pre).map(|_| base + p * noise()).collect();
                y.extend((0..n).map(|i| {
                    let time = i as f64 * h;
                    let r = if time > l {
                        1.0 - (-(time - l) / t).exp()
                    } else {
                        0.0
                    };
                    base + change * r + p * noise()
                }));
                y[pre] = base + first_off * change * 0.01;
                let got = identify_step_at(&y, pre, h, step).unwrap();
                // The documented integrals, plainly.
                let mean = |part: &[f64]| part.iter().sum::<f64>() / part.len() as f64;
                let y0 = mean(&y[..=pre]);
                let response = &y[pre..];
                let tail = (response.len() / 10).max(2);
                let y_final = mean(&response[response.len() - tail..]);
                let r: Vec<f64> = response.iter().map(|v| (v - y0) / (y_final - y0)).collect();
                let a0: f64 = r.windows(2).map(|w| (2.0 - w[0] - w[1]) / 2.0).sum::<f64>();
                let whole = a0.floor() as usize;
                let mut a1: f64 = r[..=whole].windows(2).map(|w| (w[0] + w[1]) / 2.0).sum();
                let frac = a0 - whole as f64;
                let end = r[whole] + (r[whole + 1] - r[whole]) * frac;
                a1 += (r[whole] + end) / 2.0 * frac;
                let (t_ar, t_fit) = (a0 * h, core::f64::consts::E * a1 * h);
                let what = format!(
                    "K {k}, T {t}, L {l}, h {h}, first {first_off}, pre {pre}: {got:?}, T + L {t_ar}, T {t_fit}"
                );
                assert!(
                    r[0].abs() > 1e-3 || first_off == 0.0 || pre == 0,
                    "{what}: the premise"
                );
                // A dead time fitted below 0 (within the tolerance) is reported as 0.
                let sum = got.time_constant + got.dead_time;
                assert!((sum - t_ar.max(t_fit)).abs() <= 1e-9 * t_ar, "{what}");
                assert!((got.time_constant - t_fit).abs() <= 1e-9 * t_ar, "{what}");
                assert!(
                    (got.gain - (y_final - y0) / step).abs() <= 1e-12 * k.abs(),
                    "{what}"
                );
            }
        }
    }
}

/// The sixth attack's log: 2²⁴ + 1 `f32` samples before the step, the first at −0.0006 × MAX
/// and the rest at MAX. Their mean fits (it lies between them), and so does the noise's
/// measure only as "more than the change": the verdict is `NoResponse` by the stated rules —
/// it was `Overflow("the change (the samples' mean)")`, the mean rounded past MAX. The same
/// log at half the scale gets the same verdict.
#[test]
#[cfg_attr(
    miri,
    ignore = "a log of 2²⁴ + 101 f32 samples: days under Miri; runs natively in every CI run"
)]
fn a_long_f32_part_near_the_largest_value_has_a_mean_that_fits() {
    use regler_pid::tuning::{IdentifyError, identify_step_at};
    let pre = (1usize << 24) + 1;
    let mut y = vec![f32::MAX; pre];
    y[0] = -0.0006 * f32::MAX;
    y.extend((0..100).map(|k| if k == 0 { f32::MAX } else { 0.5 * f32::MAX }));
    assert_eq!(
        identify_step_at(&y, pre - 1, 1.0f32, 1.0f32),
        Err(IdentifyError::NoResponse)
    );
    let halved: Vec<f32> = y.iter().map(|v| v * 0.5).collect();
    assert_eq!(
        identify_step_at(&halved, pre - 1, 1.0f32, 1.0f32),
        Err(IdentifyError::NoResponse)
    );
}

/// "Not settled" is a movement of *more than* the allowance: a log whose last two tenths differ
/// by exactly the allowance (0.2 % of the change + 4·noise/√(samples in a tenth) + ρ, here with
/// no noise and ρ = ε: 0.002 + ε, an exact sum) is settled, and one whose tenth before the last
/// is one ulp lower is not. The final value F and the tenth before P were searched for (in
/// Python's `f64`, over random F in 1..2) so that (F − P)/F, the movement as a fraction of the
/// change F from a baseline of 0, rounds to that sum exactly; the premise is checked here.
#[test]
fn a_movement_of_exactly_the_allowance_is_settled() {
    use regler_pid::tuning::{IdentifyError, identify_step_at};
    let allowance = 0.002 + f64::EPSILON;
    assert_eq!(
        allowance - 0.002,
        f64::EPSILON,
        "the allowance is an exact sum"
    );
    for (f, p) in [
        (0x3ff7_d652_9651_32d7u64, 0x3ff7_ca1e_32b0_44a7u64),
        (0x3ffd_ee0a_bfe9_8f8d, 0x3ffd_deb7_c8be_98fc),
    ] {
        let (f, p) = (f64::from_bits(f), f64::from_bits(p));
        let lower = f64::from_bits(p.to_bits() - 1);
        assert_eq!((f - p) / f, allowance, "the premise: a tie");
        assert!((f - lower) / f > allowance, "the premise: past the tie");
        let log = |p: f64| {
            let mut y = vec![0.0f64; 20];
            // A first-order rise to P, P over the tenth before the last, F over the last.
            y.extend((0..800).map(|k| p * (1.0 - (-f64::from(k) / 50.0).exp())));
            y.extend(core::iter::repeat_n(p, 100));
            y.extend(core::iter::repeat_n(f, 100));
            y
        };
        let at_tie = identify_step_at(&log(p), 20, 1.0, 1.0);
        assert!(
            !matches!(at_tie, Err(IdentifyError::NotSettled(_))),
            "{at_tie:?}"
        );
        assert_eq!(
            identify_step_at(&log(lower), 20, 1.0, 1.0),
            Err(IdentifyError::NotSettled((f - lower) / f))
        );
    }
}

/// "Undershoot" is a first move the wrong way by *more than* the margin: a dip of exactly 1 % of
/// the change + twice the noise + 2ρ (here no noise and ρ = ε: 0.01 + 2ε, an exact sum) is not
/// one, and a dip one ulp deeper is. The final value F and the dip v were searched for (in
/// Python's `f64`, over random F in 1..2) so that −v/F, the dip as a fraction of the change F
/// from a baseline of 0, rounds to that sum exactly; the premise is checked here.
#[test]
fn a_dip_of_exactly_the_margin_is_not_an_undershoot() {
    use regler_pid::tuning::{IdentifyError, identify_step_at};
    let margin = 0.01 + 2.0 * f64::EPSILON;
    assert_eq!(
        margin - 0.01,
        2.0 * f64::EPSILON,
        "the margin is an exact sum"
    );
    for (f, v) in [
        (0x3ff2_1636_8b52_9b4bu64, 0xbf87_26ac_3773_fb1bu64),
        (0x3ffe_a7b5_5eb5_61a5, 0xbf93_9e88_8e88_915f),
    ] {
        let (f, v) = (f64::from_bits(f), f64::from_bits(v));
        let deeper = f64::from_bits(v.to_bits() + 1);
        assert_eq!(-v / f, margin, "the premise: a tie");
        assert!(-deeper / f > margin, "the premise: past the tie");
        let log = |dip: f64| {
            let mut y = vec![0.0f64; 21];
            // A dip at the first sample after the step, then a first-order rise to F.
            y.push(dip);
            y.extend((2..800).map(|k| f * (1.0 - (-f64::from(k) / 50.0).exp())));
            y.extend(core::iter::repeat_n(f, 200));
            y
        };
        let at_tie = identify_step_at(&log(v), 20, 1.0, 1.0);
        assert!(
            !matches!(at_tie, Err(IdentifyError::Undershoot(_))),
            "{at_tie:?}"
        );
        assert_eq!(
            identify_step_at(&log(deeper), 20, 1.0, 1.0),
            Err(IdentifyError::Undershoot(-deeper / f))
        );
    }
}

/// The last two tenths further apart than the type's largest value (the tenth before the last
/// at −0.9 × MAX, the last at +0.9 × MAX, from a baseline of 0): their difference overflows,
/// and is halved instead — exactly: the movement is 2 changes, `NotSettled(2)`, never an
/// overflow or a NaN that would pass the check.
#[test]
fn two_tenths_further_apart_than_the_largest_value_are_not_settled() {
    use regler_pid::tuning::{IdentifyError, identify_step_at};
    let big = 0.9 * f64::MAX;
    let mut y = vec![0.0f64; 21];
    y.extend((1..100).map(|i| match i {
        80..90 => -big,
        90.. => big,
        _ => 0.0,
    }));
    assert_eq!(
        identify_step_at(&y, 20, 1.0, 1.0),
        Err(IdentifyError::NotSettled(2.0))
    );
    let big = 0.9 * f32::MAX;
    let y: Vec<f32> = y
        .iter()
        .map(|&v| {
            if v > 0.0 {
                big
            } else if v < 0.0 {
                -big
            } else {
                0.0
            }
        })
        .collect();
    assert_eq!(
        identify_step_at(&y, 20, 1.0f32, 1.0f32),
        Err(IdentifyError::NotSettled(2.0f32))
    );
}

/// A fitted T that is not positive is `NotFopdt`, the documented rule, whatever the sample
/// period — not a T that "underflows": a response that stays 0.5 % below its baseline (within
/// the undershoot's allowance) for 200 samples and then jumps to its final value has
/// A1 = ∫₀^(T+L) r dt < 0.
#[test]
fn a_fitted_t_that_is_not_positive_is_not_fopdt() {
    use regler_pid::tuning::{IdentifyError, identify_step_at};
    let mut y = vec![10.0f64; 41];
    y.extend((1..2000).map(|i| if i < 200 { 10.0 - 0.005 } else { 11.0 }));
    for h in [1.0, 1e-300, 1e300] {
        assert_eq!(
            identify_step_at(&y, 40, h, 1.0),
            Err(IdentifyError::NotFopdt),
            "h = {h}"
        );
    }
}
