//! The controller against the reference algorithm of the design, and what a plant does to it:
//! sensors that are not ready, spikes, configuration changes and operators.
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    clippy::float_cmp,
    clippy::field_reassign_with_default,
    reason = "a test may panic: that is how it fails"
)]

use proptest::prelude::{
    ProptestConfig, any, prop, prop_assert, prop_assert_eq, prop_oneof, proptest,
};
use proptest::strategy::{Just, Strategy};
use regler_pid::{Action, Config, Inputs, Kind, Mode, Pid, STATE_BOUND};
#[cfg(feature = "fixed")]
use regler_pid::{ConfigError, Parameter};

/// The reference algorithm, written out as the design states it, with the documented state
/// bounds (`STATE_BOUND` output scales).
#[derive(Clone)]
struct Reference {
    c: Config,
    i: f64,
    d: f64,
    y_old: f64,
    r_old: f64,
    u_old: f64,
    started: bool,
}

impl Reference {
    fn new(c: Config) -> Reference {
        Reference {
            c,
            i: 0.0,
            d: 0.0,
            y_old: 0.0,
            r_old: 0.0,
            u_old: 0.0f64.clamp(c.ymin, c.ymax),
            started: false,
        }
    }

    fn update(&mut self, r: f64, y: f64) -> f64 {
        let c = self.c;
        if !self.started {
            self.y_old = y;
            self.r_old = r;
            self.started = true;
        }
        let s = if c.action == Action::Direct {
            1.0
        } else {
            -1.0
        };
        let gain = if c.kind.has_p() { c.k } else { 1.0 };
        let bi = if c.kind.has_i() {
            gain * c.h / c.ti
        } else {
            0.0
        };
        let ad = if c.kind.has_d() {
            c.td / (c.td + c.n * c.h)
        } else {
            0.0
        };
        let bd = if c.kind.has_d() {
            gain * c.td * c.n / (c.td + c.n * c.h)
        } else {
            0.0
        };
        let ao = c.h / c.tt.unwrap_or(c.h);
        let kp = if c.kind.has_p() { s * c.k } else { 0.0 };
        let p = kp * (c.b * r - y);
        // The bounds: W = STATE_BOUND output scales.
        let scale = c.ymin.abs().max(c.ymax.abs());
        let w = f64::from(STATE_BOUND) * (c.ymax - c.ymin).max(scale);
        self.d =
            (ad * self.d - s * bd * ((y - c.c * r) - (self.y_old - c.c * self.r_old))).clamp(-w, w);
        let v = p + self.i + self.d;
        let mut u = v;
        if let Some(dymax) = c.dymax.filter(|d| *d > 0.0) {
            u = u.clamp(self.u_old - dymax, self.u_old + dymax);
        }
        u = u.clamp(c.ymin, c.ymax);
        if c.kind.has_i() {
            // Steady state needs I = u − kp·(b − 1)·r: the bounds sit W beyond that.
            let center = kp * (1.0 - c.b) * r;
            self.i = (self.i + s * bi * (r - y) + ao * (u - v))
                .clamp(c.ymin - w + center, c.ymax + w + center);
        }
        self.y_old = y;
        self.r_old = r;
        self.u_old = u;
        u
    }
}

fn kind() -> impl Strategy<Value = Kind> {
    prop::sample::select(Kind::ALL.to_vec())
}

fn config() -> impl Strategy<Value = Config> {
    (
        (
            kind(),
            any::<bool>(),
            0.01f64..20.0,
            0.1f64..100.0,
            0.0f64..20.0,
            1.0f64..20.0,
        ),
        (
            0.0f64..1.0,
            0.0f64..1.0,
            prop::option::of(0.51f64..50.0),
            0.01f64..5.0,
        ),
        (
            -50.0f64..0.0,
            0.0f64..50.0,
            prop::option::of(prop_oneof![Just(0.0), 0.01f64..10.0]),
        ),
    )
        .prop_map(
            |((kind, reverse, k, ti, td, n), (b, c, tt_samples, h), (ymin, ymax, dymax))| Config {
                kind,
                action: if reverse {
                    Action::Reverse
                } else {
                    Action::Direct
                },
                k,
                ti,
                td,
                n,
                b,
                c,
                tt: tt_samples.map(|m| m * h),
                h,
                ymin,
                ymax,
                dymax,
            },
        )
}

/// The longest run of samples a case draws: 200, under Miri 20 (one case of 200 samples took
/// about 30 s interpreted).
const LONG: usize = if cfg!(miri) { 20 } else { 200 };

fn signal() -> impl Strategy<Value = Vec<(f64, f64)>> {
    prop::collection::vec((-100.0f64..100.0, -100.0f64..100.0), 1..LONG)
}

/// A reading as a broken or unready sensor gives it, or a sane one.
fn reading() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -100.0f64..100.0,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => prop::sample::select(vec![1e6, -1e6, 1e300, -1e300, f64::MAX, -f64::MAX]),
    ]
}

/// A sane reading, or one a sensor gives while it is not ready.
fn sane_or_missing() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -100.0f64..100.0,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
    ]
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1.0)
}

// Under Miri one case a property (measured: 137 s for the file with four).
proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 1 } else { 2000 }))]

    #[test]
    fn f64_matches_the_reference(config in config(), inputs in signal()) {
        let mut pid = Pid::<f64>::new(&config).unwrap();
        let mut reference = Reference::new(config);
        for (r, y) in inputs {
            let (a, b) = (pid.update(r, y), reference.update(r, y));
            prop_assert!(close(a, b), "{a} vs {b}");
        }
    }

    /// A sample with a NaN or infinite set-point or measurement — the first one, after a reset,
    /// anywhere — holds the output and leaves no trace: on the finite samples the controller
    /// gives exactly what the reference gives on those samples alone.
    #[test]
    fn non_finite_samples_leave_no_trace(
        config in config(),
        inputs in prop::collection::vec((sane_or_missing(), sane_or_missing()), 1..LONG),
        reset_at in prop::option::of(0usize..LONG),
    ) {
        let mut pid = Pid::<f64>::new(&config).unwrap();
        let mut reference = Reference::new(config);
        for (n, (r, y)) in inputs.into_iter().enumerate() {
            if reset_at == Some(n) {
                pid.reset();
                reference = Reference::new(config);
            }
            let held = pid.output();
            let u = pid.update(r, y);
            if r.is_finite() && y.is_finite() {
                let want = reference.update(r, y);
                prop_assert!(close(u, want), "sample {n}: {u} vs {want}");
            } else {
                prop_assert_eq!(u, held);
                prop_assert!(pid.faults().non_finite_input());
            }
        }
    }

    /// The output stays within the limits, moves at most dymax per sample, and is finite, for
    /// any f32 input; with no escape at the limits (the held output is inside them already).
    #[test]
    fn output_within_limits_rate_limited_and_finite(
        config in config(),
        inputs in prop::collection::vec((any::<f32>(), any::<f32>()), 1..LONG),
    ) {
        let mut pid = Pid::<f32>::new(&config).unwrap();
        let (lo, hi) = (config.ymin as f32, config.ymax as f32);
        let mut prev = pid.output();
        for (r, y) in inputs {
            let u = pid.update(r, y);
            prop_assert!(u.is_finite());
            prop_assert!(u >= lo && u <= hi, "{u} outside [{lo}, {hi}]");
            if let Some(dymax) = config.dymax.filter(|d| *d > 0.0) {
                let step = (f64::from(u) - f64::from(prev)).abs();
                let rounding = f64::from(f32::EPSILON) * (f64::from(prev.abs()) + dymax);
                prop_assert!(step <= dymax + rounding, "step {step} > {dymax}");
            }
            prev = u;
        }
    }

    /// After any sequence of bad readings, configuration changes, manual/auto switches and
    /// resets, once the readings are sane again: no new fault once cleared, a finite integral
    /// within its bounds, and an output that still follows the error (it reaches the upper
    /// limit under a large positive error and the lower one under a large negative error).
    #[test]
    fn recovers_after_anything(
        configs in prop::collection::vec(config(), 1..4),
        events in prop::collection::vec((0u8..8, reading(), reading(), 0usize..4), 0..LONG * 3 / 5),
    ) {
        let mut pid = Pid::<f64>::new(&configs[0]).unwrap();
        let mut current = configs[0];
        for (what, a, b, which) in events {
            match what {
                0..=3 => { pid.update(a, b); }
                4 => {
                    let c = configs[which % configs.len()];
                    pid.set_config(&c).unwrap();
                    current = c;
                }
                5 => { let _ = pid.set_manual(a); }
                6 => pid.set_auto(),
                _ => pid.reset(),
            }
            prop_assert!(pid.integral().is_finite() && pid.derivative().is_finite());
            prop_assert!(pid.output() >= current.ymin && pid.output() <= current.ymax);
        }
        pid.set_auto();
        pid.clear_faults();
        let s = if current.action == Action::Direct { 1.0 } else { -1.0 };
        let scale = (current.ymax - current.ymin).max(current.ymin.abs()).max(current.ymax.abs());
        for _ in 0..5 {
            pid.update(10.0, 10.0);
        }
        prop_assert!(!pid.faults().any(), "{}", pid.faults());
        if current.kind.has_p() || current.kind.has_i() {
            // Large enough that P alone, or I within a few samples, crosses the bounds.
            let gain = if current.kind.has_p() { current.k } else { current.h / current.ti };
            let e = 1e3 * f64::from(STATE_BOUND) * scale.max(1.0) / gain;
            let mut reached = [false, false];
            let rate = current.rate_limit().map_or(0.0, |d| (current.ymax - current.ymin) / d);
            for (n, sign) in [1.0, -1.0].into_iter().enumerate() {
                for _ in 0..50 + 2 * rate.ceil() as usize {
                    let u = pid.update(10.0, 10.0 - s * sign * e);
                    let limit = if sign > 0.0 { current.ymax } else { current.ymin };
                    if u == limit {
                        reached[n] = true;
                        break;
                    }
                }
            }
            prop_assert!(reached == [true, true], "stuck: {reached:?}, output {}", pid.output());
        }
        prop_assert!(!pid.faults().any(), "{}", pid.faults());
    }

    /// A change of configuration does not move the output, for every pair of kinds and at a
    /// non-zero error: the first output after the commit is what the old configuration would
    /// have given (derivative steady: constant readings).
    /// A kind without I holds its bias (its manual reset) whatever the feed-forward, the
    /// readings and the set-point do, absurd values included; only a mode switch or a new
    /// configuration may move it.
    #[test]
    fn the_bias_of_a_kind_without_i_never_moves(
        config in config().prop_filter("no I", |c| !c.kind.has_i()),
        manual_output in -100.0f64..100.0,
        samples in prop::collection::vec((reading(), reading(), reading()), 1..LONG / 2),
    ) {
        let mut pid = Pid::<f64>::new(&config).unwrap();
        pid.update(1.0, 0.0);
        pid.set_manual(manual_output).unwrap();
        pid.update(1.0, 0.0);
        pid.set_auto();
        let bias = pid.integral();
        for (r, y, feedforward) in samples {
            let feedforward = if feedforward.is_finite() { feedforward } else { 0.0 };
            pid.update_with(r, y, Inputs { feedforward, track: None });
            prop_assert_eq!(pid.integral(), bias);
        }
    }

    #[test]
    fn bumpless_commit(before in config(), after in config(), r in -10.0f64..10.0, y in -10.0f64..10.0) {
        let wide = |c: Config| Config { ymin: -1e6, ymax: 1e6, dymax: None, ..c };
        let (before, after) = (wide(before), wide(after));
        let mut pid = Pid::<f64>::new(&before).unwrap();
        for _ in 0..20 {
            pid.update(r, y);
        }
        let mut unchanged = pid.clone();
        pid.set_config(&after).unwrap();
        let (u1, u0) = (pid.update(r, y), unchanged.update(r, y));
        prop_assert!((u1 - u0).abs() <= 1e-9 * u0.abs().max(1.0) + 1e-12 * pid.integral().abs(), "{u0} -> {u1}");
    }

    /// Whatever kind and gain, once `Pid::<I16F16>::new` accepts a configuration, the first
    /// integral step agrees with f64 within the tolerance (and the LSB of the error's product);
    /// a configuration it cannot hold is refused, naming a parameter.
    #[cfg(feature = "fixed")]
    #[test]
    fn fixed_point_coefficients_are_close_or_refused(
        k_exp in -6.0f64..6.0,
        ti_exp in -2.0f64..7.0,
        h in prop::sample::select(vec![0.01, 0.1, 1.0, 10.0]),
    ) {
        use fixed::types::I16F16;
        let config = Config { kind: Kind::PI, k: 10f64.powf(k_exp), ti: 10f64.powf(ti_exp), h, ymin: -1.0, ymax: 1.0, ..Config::default() };
        match Pid::<I16F16>::new(&config) {
            Ok(mut pid) => {
                let mut exact = Pid::<f64>::new(&config).unwrap();
                pid.update(I16F16::from_num(0.5), I16F16::ZERO);
                exact.update(0.5, 0.0);
                let (got, want) = (pid.integral().to_num::<f64>(), exact.integral());
                prop_assert!((got - want).abs() <= want.abs() / 1024.0 + 2.0 / 65536.0, "{got} vs {want}");
            }
            Err(e) => prop_assert!(matches!(e, ConfigError::Unrepresentable { .. }), "{e}"),
        }
    }

    /// The integral does not wind up: after a long saturation, the output leaves the limit within
    /// a few samples of the error changing sign.
    #[test]
    fn integral_does_not_wind_up(
        k in 0.1f64..10.0,
        ti in 0.5f64..50.0,
        tt_samples in prop::option::of(1.0f64..5.0),
        reverse in any::<bool>(),
    ) {
        let h = 0.1;
        let config = Config {
            kind: Kind::PI,
            action: if reverse { Action::Reverse } else { Action::Direct },
            k,
            ti,
            h,
            tt: tt_samples.map(|t| t * h),
            ymin: 0.0,
            ymax: 1.0,
            ..Config::default()
        };
        let mut pid = Pid::<f64>::new(&config).unwrap();
        let s = if reverse { -1.0 } else { 1.0 };
        // Under Miri 200 samples of saturation (without anti-windup the integral would grow
        // for all of them).
        for _ in 0..if cfg!(miri) { 200 } else { 2000 } {
            pid.update(s * 10.0, 0.0);
        }
        let mut left = None;
        for n in 0..5 {
            if pid.update(-s * 0.5, 0.0) < 1.0 {
                left = Some(n);
                break;
            }
        }
        prop_assert!(left.is_some(), "still saturated 5 samples after the error changed sign");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 1 } else { 300 }))]

    /// One absurd but finite reading in a settled loop costs a bounded number of time constants,
    /// whatever its size: the loop with the spike is back within 1 % of the loop without it after
    /// 15·max(Ti, Tt, Td/N, τ) (τ the plant's time constant). Measured worst case over a grid of
    /// these loops: 13.8. Without the state bounds a 1e300 reading took about 690·Tt.
    #[test]
    fn a_spike_costs_a_few_time_constants(
        tau in 1.0f64..100.0,
        plant_gain in 0.5f64..5.0,
        tt_samples in prop::option::of(1.0f64..20.0),
        td_frac in 0.0f64..0.5,
        n in 2.0f64..20.0,
        spike in prop::sample::select(vec![1e6, -1e6, 1e300, -1e300]),
    ) {
        let h = tau / 20.0;
        let config = Config {
            kind: Kind::PID,
            k: 1.0 / plant_gain,
            ti: tau,
            td: td_frac * tau,
            n,
            h,
            tt: tt_samples.map(|t| t * h),
            ymin: 0.0,
            ymax: 10.0,
            ..Config::default()
        };
        let a = (-h / tau).exp();
        let setpoint = plant_gain * 5.0;
        let run = |spike_at: Option<usize>, samples: usize| {
            let mut pid = Pid::<f64>::new(&config).unwrap();
            let (mut y, mut trace) = (0.0, Vec::new());
            for k in 0..samples {
                let reading = if spike_at == Some(k) { spike } else { y };
                let u = pid.update(setpoint, reading);
                y = a * y + (1.0 - a) * plant_gain * u;
                trace.push((u, y));
            }
            trace
        };
        let settle = 400;
        let slowest = [config.ti, config.tt.unwrap_or(h), config.td / n, tau].into_iter().fold(0.0, f64::max);
        let budget = (15.0 * slowest / h).ceil() as usize;
        let (clean, spiked) = (run(None, settle + budget + 1), run(Some(settle), settle + budget + 1));
        let (u0, y0) = clean[settle + budget];
        let (u1, y1) = spiked[settle + budget];
        prop_assert!((y1 - y0).abs() <= 0.01 * setpoint && (u1 - u0).abs() <= 0.1, "after {budget} samples: y {y0} vs {y1}, u {u0} vs {u1}");
    }
}

#[test]
fn nan_at_power_up_then_finite_runs_as_a_fresh_controller() {
    let config = Config {
        kind: Kind::PID,
        td: 2.0,
        c: 0.0,
        ..Config::default()
    };
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mut pid = Pid::<f32>::new(&config).unwrap();
        let mut fresh = Pid::<f32>::new(&config).unwrap();
        assert_eq!(pid.update(5.0, bad), 0.0);
        assert_eq!(pid.update(bad, 1.0), 0.0);
        assert!(pid.faults().non_finite_input() && !pid.faults().overflow());
        pid.clear_faults();
        for k in 0..50 {
            let y = k as f32 * 0.1;
            assert_eq!(pid.update(5.0, y), fresh.update(5.0, y), "sample {k}");
        }
        assert!(
            !pid.faults().any(),
            "no overflow reported for finite inputs"
        );
    }
}

#[test]
fn set_config_and_set_auto_keep_the_integral_finite() {
    let config = Config {
        kind: Kind::PI,
        k: 1e300,
        ymin: -1.0,
        ymax: 1.0,
        ..Config::default()
    };
    let mut pid = Pid::<f64>::new(&config).unwrap();
    pid.update(1e8, -1e8);
    // A gain that overflows P at the last readings: ∞ − ∞ must not reach the integral.
    pid.set_config(&Config {
        k: f64::MAX,
        ..config
    })
    .unwrap();
    assert!(pid.integral().is_finite());
    pid.set_manual(0.5).unwrap();
    pid.update(1e300, -1e300);
    pid.set_auto();
    assert!(pid.integral().is_finite());
    pid.set_config(&Config { k: 1.0, ..config }).unwrap();
    pid.clear_faults();
    let u = pid.update(0.0, 0.5);
    assert!(u.is_finite() && u < 1.0, "{u}");
}

#[test]
fn set_config_reclamps_the_held_output_and_keeps_a_p_bias() {
    let config = Config {
        kind: Kind::P,
        k: 1.0,
        ymin: 0.0,
        ymax: 10.0,
        ..Config::default()
    };
    let mut pid = Pid::<f64>::new(&config).unwrap();
    pid.update(5.0, 5.0);
    pid.set_manual(9.0).unwrap();
    pid.update(5.0, 5.0);
    pid.set_config(&Config {
        ymax: 5.0,
        ..config
    })
    .unwrap();
    assert_eq!(
        pid.output(),
        5.0,
        "manual output clamped into the new limits at once"
    );
    assert_eq!(pid.mode(), Mode::Manual);
    pid.set_manual(4.0).unwrap();
    pid.update(5.0, 5.0);
    pid.set_auto(); // bias 4 (the manual reset of a P controller)
    assert_eq!(pid.update(5.0, 5.0), 4.0);
    pid.set_config(&Config {
        k: 2.0,
        ymax: 5.0,
        ..config
    })
    .unwrap();
    assert_eq!(pid.update(5.0, 5.0), 4.0, "a gain change keeps the bias");
}

#[test]
fn dymax_zero_means_no_limit_in_config_as_at_the_keypad() {
    let free = Config {
        kind: Kind::P,
        k: 1.0,
        dymax: Some(0.0),
        ..Config::default()
    };
    let mut pid = Pid::<f64>::new(&free).unwrap();
    assert_eq!(pid.update(8.0, 0.0), 8.0, "not frozen");
}

#[cfg(feature = "fixed")]
#[test]
fn unusable_numbers_are_refused_naming_the_parameter() {
    use fixed::types::I16F16;
    let base = Config {
        kind: Kind::PI,
        ..Config::default()
    };
    let named = |e: ConfigError| e.parameter();
    assert_eq!(
        named(Pid::<f32>::new(&Config { k: 1e39, ..base }).unwrap_err()),
        Parameter::K
    );
    // K·h/Ti = 1e-50: zero in f32, so integral action would silently vanish.
    assert_eq!(
        named(
            Pid::<f32>::new(&Config {
                k: 1e-25,
                ti: 1e25,
                ..base
            })
            .unwrap_err()
        ),
        Parameter::Ti
    );
    assert_eq!(
        named(Pid::<I16F16>::new(&Config { k: 1e5, ..base }).unwrap_err()),
        Parameter::K
    );
    for bi in [5e-6, 1e-5] {
        let e = Pid::<I16F16>::new(&Config {
            k: 1.0,
            ti: 1.0 / bi,
            ..base
        })
        .unwrap_err();
        assert_eq!(named(e), Parameter::Ti, "bi {bi}");
        assert!(e.to_string().contains("K·h/Ti"), "{e}");
    }
    assert!(
        Pid::<I16F16>::new(&Config {
            k: 1.0,
            ti: 100.0,
            ..base
        })
        .is_ok()
    );
    // An f32 configuration computes in f32 and is checked there too.
    let mut c = Config::default();
    c.k = 1e-30f32;
    c.ti = 1e10;
    assert_eq!(Pid::<f32>::new(&c).unwrap_err().parameter(), Parameter::Ti);
}

#[test]
fn an_f32_config_runs_like_the_f64_one() {
    let mut c32 = Config::default();
    c32.kind = Kind::PID;
    c32.k = 1.5f32;
    c32.ti = 6.0;
    c32.td = 1.0;
    c32.h = 0.5;
    c32.dymax = Some(1.0);
    let c64 = Config {
        kind: Kind::PID,
        k: 1.5,
        ti: 6.0,
        td: 1.0,
        h: 0.5,
        dymax: Some(1.0),
        ..Config::default()
    };
    let mut a = Pid::<f32>::new(&c32).unwrap();
    let mut b = Pid::<f32>::new(&c64).unwrap();
    let mut y = 0.0f32;
    for k in 0..300 {
        let (ua, ub) = (a.update(5.0, y), b.update(5.0, y));
        assert!((ua - ub).abs() <= 1e-4, "{k}: {ua} {ub}");
        y += 0.25 * (0.8 * ua - y);
    }
}
