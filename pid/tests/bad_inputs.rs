//! Bad inputs (issue 22 §5): every public constructor and operation of `regler-pid` fed the
//! extremes — 0, −0.0, the smallest subnormal, MAX, MIN, NaN, ±∞ in `f32` and `f64`, MAX/MIN
//! and the smallest step in `I16F16` and `I32F32` — and the exact error or documented result.
//!
//! Each test is a table: one row per (operation, extreme input, expected outcome). A refused
//! call is checked to have changed nothing (the whole value compared, where it is `PartialEq`).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    clippy::float_cmp,
    clippy::field_reassign_with_default,
    clippy::too_many_arguments,
    clippy::type_complexity,
    reason = "a test may panic: that is how it fails"
)]

#[cfg(feature = "fixed")]
use fixed::types::{I16F16, I32F32};
use regler_pid::actuator::{ActuatorConfig, ActuatorError, Drive, ThreePoint};
use regler_pid::tuning::{
    Fopdt, Relay, RelayConfig, RelayError, RelayStep, RuleError, Tuning, Ultimate, amigo,
    identify_step, identify_step_at, simc, ziegler_nichols,
};
use regler_pid::{
    Code, Config, ConfigError, EditError, Inputs, Kind, Mode, OperatorLimits, Parameter,
    Parameters, Pid, Requirement, Scaling, ScalingError, Staged, Station, ValueError,
};

/// What a configuration check gives, without the value (NaN ≠ NaN).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Want {
    Ok,
    NotFinite(Parameter),
    OutOfRange(Parameter),
    Reversed,
    Tracking,
    Unrepresentable(Parameter),
}

fn shape<F: core::fmt::Debug>(r: &Result<(), ConfigError<F>>) -> Want {
    match r {
        Ok(()) => Want::Ok,
        Err(ConfigError::NotFinite { parameter, .. }) => Want::NotFinite(*parameter),
        Err(ConfigError::OutOfRange { parameter, .. }) => Want::OutOfRange(*parameter),
        Err(ConfigError::LimitsReversed { .. }) => Want::Reversed,
        Err(ConfigError::TrackingUnstable { .. }) => Want::Tracking,
        Err(ConfigError::Unrepresentable { parameter, .. }) => Want::Unrepresentable(*parameter),
        Err(e) => panic!("unexpected {e:?}"),
    }
}

/// The configuration table, one row per (parameter, extreme, outcome), for one float type.
/// `Config::validate` must give the outcome; `Pid::<F>::new` too, except where the row names
/// what the controller's own type cannot hold; `set_config` must give it and, when refused,
/// leave a running controller exactly as it was.
#[rustfmt::skip]
macro_rules! config_table {
    ($f:ty) => {{
        type F = $f;
        let base = Config::<F> {
            kind: Kind::PID,
            k: 2.0,
            ti: 4.0,
            td: 1.0,
            n: 5.0,
            h: 1.0,
            ymin: -10.0,
            ymax: 10.0,
            ..Config::default()
        };
        let sub = F::from_bits(1); // the smallest subnormal
        let (nan, inf, max, min) = (F::NAN, F::INFINITY, F::MAX, F::MIN);
        use Parameter as P;
        use Want::*;
        // (what, config, validate, Pid::new in the same type)
        let rows: Vec<(&str, Config<F>, Want, Want)> = vec![
            ("base", base, Ok, Ok),
            ("k NaN", Config { k: nan, ..base }, NotFinite(P::K), NotFinite(P::K)),
            ("k +inf", Config { k: inf, ..base }, NotFinite(P::K), NotFinite(P::K)),
            ("k -inf", Config { k: -inf, ..base }, NotFinite(P::K), NotFinite(P::K)),
            ("k 0", Config { k: 0.0, ..base }, Ok, Ok),
            ("k -0", Config { k: -0.0, ..base }, Ok, Ok),
            ("k subnormal", Config { k: sub, ..base }, Ok, Unrepresentable(P::K)),
            ("k MAX (K·Td·N/(Td + N·h) overflows)", Config { k: max, ..base }, Ok, Unrepresentable(P::Td)),
            ("k MAX, kind PI (K·h/Ti finite)", Config { k: max, kind: Kind::PI, ..base }, Ok, Ok),
            ("k MIN", Config { k: min, ..base }, Ok, Unrepresentable(P::Td)),
            ("ti NaN", Config { ti: nan, ..base }, NotFinite(P::Ti), NotFinite(P::Ti)),
            ("ti +inf", Config { ti: inf, ..base }, NotFinite(P::Ti), NotFinite(P::Ti)),
            ("ti 0", Config { ti: 0.0, ..base }, OutOfRange(P::Ti), OutOfRange(P::Ti)),
            ("ti -0", Config { ti: -0.0, ..base }, OutOfRange(P::Ti), OutOfRange(P::Ti)),
            ("ti MIN", Config { ti: min, ..base }, OutOfRange(P::Ti), OutOfRange(P::Ti)),
            ("ti subnormal", Config { ti: sub, ..base }, Ok, Unrepresentable(P::Ti)),
            ("ti MAX", Config { ti: max, ..base }, Ok, Unrepresentable(P::Ti)),
            ("ti 0 without I", Config { kind: Kind::PD, ti: 0.0, ..base }, Ok, Ok),
            ("ti NaN without I", Config { kind: Kind::PD, ti: nan, ..base }, NotFinite(P::Ti), NotFinite(P::Ti)),
            ("td NaN", Config { td: nan, ..base }, NotFinite(P::Td), NotFinite(P::Td)),
            ("td -inf", Config { td: -inf, ..base }, NotFinite(P::Td), NotFinite(P::Td)),
            ("td -0", Config { td: -0.0, ..base }, Ok, Ok),
            ("td -subnormal", Config { td: -sub, ..base }, OutOfRange(P::Td), OutOfRange(P::Td)),
            ("td MIN", Config { td: min, ..base }, OutOfRange(P::Td), OutOfRange(P::Td)),
            ("td MAX", Config { td: max, ..base }, Ok, Unrepresentable(P::Td)),
            ("n NaN", Config { n: nan, ..base }, NotFinite(P::N), NotFinite(P::N)),
            ("n 0", Config { n: 0.0, ..base }, OutOfRange(P::N), OutOfRange(P::N)),
            ("n -0", Config { n: -0.0, ..base }, OutOfRange(P::N), OutOfRange(P::N)),
            ("n MAX", Config { n: max, ..base }, Ok, Unrepresentable(P::Td)),
            ("n MAX without D", Config { n: max, td: 0.0, ..base }, Ok, Ok),
            ("b NaN", Config { b: nan, ..base }, NotFinite(P::B), NotFinite(P::B)),
            ("b -inf", Config { b: -inf, ..base }, NotFinite(P::B), NotFinite(P::B)),
            ("b MAX (an update overflows: held, tested below)", Config { b: max, ..base }, Ok, Ok),
            ("c NaN", Config { c: nan, ..base }, NotFinite(P::C), NotFinite(P::C)),
            ("c +inf", Config { c: inf, ..base }, NotFinite(P::C), NotFinite(P::C)),
            ("h NaN", Config { h: nan, ..base }, NotFinite(P::H), NotFinite(P::H)),
            ("h +inf", Config { h: inf, ..base }, NotFinite(P::H), NotFinite(P::H)),
            ("h 0", Config { h: 0.0, ..base }, OutOfRange(P::H), OutOfRange(P::H)),
            ("h -0", Config { h: -0.0, ..base }, OutOfRange(P::H), OutOfRange(P::H)),
            ("h MIN", Config { h: min, ..base }, OutOfRange(P::H), OutOfRange(P::H)),
            ("h subnormal", Config { h: sub, ..base }, Ok, Unrepresentable(P::Ti)),
            ("h MAX", Config { h: max, ..base }, Ok, Unrepresentable(P::Ti)),
            ("tt NaN", Config { tt: Some(nan), ..base }, NotFinite(P::Tt), NotFinite(P::Tt)),
            ("tt +inf", Config { tt: Some(inf), ..base }, NotFinite(P::Tt), NotFinite(P::Tt)),
            ("tt 0", Config { tt: Some(0.0), ..base }, OutOfRange(P::Tt), OutOfRange(P::Tt)),
            ("tt -0", Config { tt: Some(-0.0), ..base }, OutOfRange(P::Tt), OutOfRange(P::Tt)),
            ("tt subnormal", Config { tt: Some(sub), ..base }, Tracking, Tracking),
            ("tt h/2", Config { tt: Some(0.5), ..base }, Tracking, Tracking),
            ("tt just above h/2", Config { tt: Some(0.5 + F::EPSILON / 2.0), ..base }, Ok, Ok),
            ("tt MAX (h/Tt vanishes)", Config { tt: Some(max), ..base }, Ok, Unrepresentable(P::Tt)),
            ("tt MAX without I", Config { tt: Some(max), kind: Kind::PD, ..base }, Ok, Ok),
            ("tt MAX, h MAX", Config { tt: Some(max), h: max, kind: Kind::P, ..base }, Ok, Ok),
            ("ymin NaN", Config { ymin: nan, ..base }, NotFinite(P::Ymin), NotFinite(P::Ymin)),
            ("ymax -inf", Config { ymax: -inf, ..base }, NotFinite(P::Ymax), NotFinite(P::Ymax)),
            ("ymin = ymax", Config { ymin: 3.0, ymax: 3.0, ..base }, Ok, Ok),
            ("ymin = ymax = -0", Config { ymin: -0.0, ymax: 0.0, ..base }, Ok, Ok),
            ("ymin above ymax", Config { ymin: 3.0, ymax: 2.0, ..base }, Reversed, Reversed),
            ("ymin = ymax = MAX", Config { ymin: max, ymax: max, ..base }, Ok, Ok),
            ("limits MIN..MAX (no limits: the states' bound is infinite)", Config { ymin: min, ymax: max, ..base }, Ok, Ok),
            ("dymax NaN", Config { dymax: Some(nan), ..base }, NotFinite(P::Dymax), NotFinite(P::Dymax)),
            ("dymax +inf", Config { dymax: Some(inf), ..base }, NotFinite(P::Dymax), NotFinite(P::Dymax)),
            ("dymax -subnormal", Config { dymax: Some(-sub), ..base }, OutOfRange(P::Dymax), OutOfRange(P::Dymax)),
            ("dymax 0", Config { dymax: Some(0.0), ..base }, Ok, Ok),
            ("dymax -0", Config { dymax: Some(-0.0), ..base }, Ok, Ok),
            ("dymax subnormal (not held within TOLERANCE)", Config { dymax: Some(sub), ..base }, Ok, Unrepresentable(P::Dymax)),
            ("dymax MIN_POSITIVE", Config { dymax: Some(F::MIN_POSITIVE), ..base }, Ok, Ok),
            ("dymax MAX", Config { dymax: Some(max), ..base }, Ok, Ok),
        ];
        rows
    }};
}

#[rustfmt::skip]
macro_rules! check_config_table {
    ($f:ty) => {{
        let mut fails = Vec::new();
        for (what, config, validate, new) in config_table!($f) {
            let v = shape(&config.validate());
            if v != validate {
                fails.push(format!(
                    "{} validate {what}: got {v:?}, want {validate:?}",
                    stringify!($f)
                ));
            }
            let built = shape(&Pid::<$f>::new(&config).map(|_| ()));
            if built != new {
                fails.push(format!(
                    "{} Pid::new {what}: got {built:?}, want {new:?}",
                    stringify!($f)
                ));
            }
            // A running controller refuses the same, and is left exactly as it was.
            let mut pid = Pid::<$f>::new(&config_table!($f)[0].1).unwrap();
            pid.update(1.0, 0.5);
            pid.update(1.0, 0.25);
            let before = pid.clone();
            let r = pid.set_config(&config);
            if shape(&r) != new {
                fails.push(format!(
                    "{} set_config {what}: got {:?}, want {new:?}",
                    stringify!($f),
                    shape(&r)
                ));
            }
            if r.is_err() && pid != before {
                fails.push(format!(
                    "{} refused set_config changed the controller: {what}",
                    stringify!($f)
                ));
            }
        }
        assert!(fails.is_empty(), "{}", fails.join("\n"));
    }};
}

#[test]
#[rustfmt::skip]
fn config_validate_new_and_set_config_at_the_extremes_f64() {
    check_config_table!(f64);
}

#[test]
#[rustfmt::skip]
fn config_validate_new_and_set_config_at_the_extremes_f32() {
    check_config_table!(f32);
}

/// `rate_limit`: `None`, 0 and −0 are no limit; any positive value, subnormal and MAX
/// included, is a limit.
#[test]
#[rustfmt::skip]
fn rate_limit_at_the_extremes() {
    let rows: [(Option<f64>, Option<f64>); 6] = [
        (None, None),
        (Some(0.0), None),
        (Some(-0.0), None),
        (Some(f64::from_bits(1)), Some(f64::from_bits(1))),
        (Some(1.0), Some(1.0)),
        (Some(f64::MAX), Some(f64::MAX)),
    ];
    for (dymax, want) in rows {
        let c = Config {
            dymax,
            ..Config::default()
        };
        assert_eq!(c.rate_limit(), want, "dymax {dymax:?}");
    }
}

/// What one sample with extreme inputs must give.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Sample {
    /// Output held, `Faults::non_finite_input`, no state changed.
    HeldNonFinite,
    /// Output held, `Faults::overflow`, no state changed.
    HeldOverflow,
    /// Runs: no fault, the output within the limits.
    Runs,
}

/// Feeds one bad sample to a controller that has run a few sane ones; checks the outcome and,
/// when the output is held, that clearing the fault leaves the controller exactly as it was.
fn check_sample<T: regler_pid::Scalar + core::fmt::Debug>(
    what: &str,
    pid: &Pid<T>,
    r: T,
    y: T,
    inputs: Option<Inputs<T>>,
    want: Sample,
    lo: T,
    hi: T,
) -> Result<(), String> {
    let mut p = pid.clone();
    let u = match inputs {
        None => p.update(r, y),
        Some(i) => p.update_with(r, y, i),
    };
    let f = p.faults();
    let got = if u == pid.output() && f.non_finite_input() && !f.overflow() && {
        let mut q = p.clone();
        q.clear_faults();
        &q == pid
    } {
        Sample::HeldNonFinite
    } else if u == pid.output() && f.overflow() && !f.non_finite_input() && {
        let mut q = p.clone();
        q.clear_faults();
        &q == pid
    } {
        Sample::HeldOverflow
    } else if !f.any() && u >= lo && u <= hi {
        Sample::Runs
    } else {
        return Err(format!(
            "{what}: output {u:?} (before {:?}), {f:?}, want {want:?}",
            pid.output()
        ));
    };
    if got == want {
        Ok(())
    } else {
        Err(format!(
            "{what}: got {got:?}, want {want:?} (output {u:?}, before {:?})",
            pid.output()
        ))
    }
}

fn pi_config() -> Config {
    Config {
        kind: Kind::PID,
        k: 2.0,
        ti: 4.0,
        td: 1.0,
        h: 1.0,
        ymin: -10.0,
        ymax: 10.0,
        ..Config::default()
    }
}

#[rustfmt::skip]
macro_rules! float_sample_table {
    ($t:ty) => {{
        type T = $t;
        let mut pid = Pid::<T>::new(&pi_config()).unwrap();
        pid.update(1.0, 0.5);
        pid.update(1.0, 0.75);
        let fresh = Pid::<T>::new(&pi_config()).unwrap();
        let (nan, inf, max, min, sub) = (T::NAN, T::INFINITY, T::MAX, T::MIN, T::from_bits(1));
        use Sample::*;
        let none = Inputs::<T>::default();
        let ff = |feedforward: T| {
            Some(Inputs {
                feedforward,
                track: None,
            })
        };
        let track = |t: T| {
            Some(Inputs {
                feedforward: 0.0,
                track: Some(t),
            })
        };
        let rows: Vec<(&str, &Pid<T>, T, T, Option<Inputs<T>>, Sample)> = vec![
            ("r NaN", &pid, nan, 0.5, None, HeldNonFinite),
            ("y NaN", &pid, 1.0, nan, None, HeldNonFinite),
            ("y +inf", &pid, 1.0, inf, None, HeldNonFinite),
            ("y -inf", &pid, 1.0, -inf, None, HeldNonFinite),
            ("r +inf, y +inf", &pid, inf, inf, None, HeldNonFinite),
            ("first sample y NaN", &fresh, 1.0, nan, None, HeldNonFinite),
            ("first sample r -inf", &fresh, -inf, 0.0, None, HeldNonFinite),
            ("r MAX, y 0", &pid, max, 0.0, None, HeldOverflow),
            ("r MAX, y MIN", &pid, max, min, None, HeldOverflow),
            ("r 0, y MIN", &pid, 0.0, min, None, HeldOverflow),
            ("r MAX, y MAX (derivative bounded)", &pid, max, max, None, Runs),
            ("r 0, y 0", &pid, 0.0, 0.0, None, Runs),
            ("r -0, y -0", &pid, -0.0, -0.0, None, Runs),
            ("r subnormal, y -subnormal", &pid, sub, -sub, None, Runs),
            ("first sample r MAX, y MAX (no error, no kick)", &fresh, max, max, None, Runs),
            ("update_with defaults", &pid, 1.0, 0.5, Some(none), Runs),
            ("feed-forward NaN", &pid, 1.0, 0.5, ff(nan), HeldNonFinite),
            ("feed-forward -inf", &pid, 1.0, 0.5, ff(-inf), HeldNonFinite),
            ("feed-forward MAX", &pid, 1.0, 0.5, ff(max), Runs),
            ("feed-forward subnormal", &pid, 1.0, 0.5, ff(sub), Runs),
            ("track NaN", &pid, 1.0, 0.5, track(nan), HeldNonFinite),
            ("track +inf", &pid, 1.0, 0.5, track(inf), HeldNonFinite),
            ("track MAX (integral bounded)", &pid, 1.0, 0.5, track(max), Runs),
            ("track MIN", &pid, 1.0, 0.5, track(min), Runs),
            ("track -0", &pid, 1.0, 0.5, track(-0.0), Runs),
        ];
        let fails: Vec<String> = rows
            .into_iter()
            .filter_map(|(what, p, r, y, inputs, want)| {
                check_sample(
                    &format!("{} {what}", stringify!($t)),
                    p,
                    r,
                    y,
                    inputs,
                    want,
                    -10.0,
                    10.0,
                )
                .err()
            })
            .collect();
        assert!(fails.is_empty(), "{}", fails.join("\n"));
        // −0.0 is 0: the same output, bit for bit up to the sign of zero.
        let (mut a, mut b) = (pid.clone(), pid.clone());
        assert_eq!(a.update(-0.0, -0.0), b.update(0.0, 0.0));
    }};
}

/// `update` and `update_with` with NaN, ±∞, MAX, MIN, subnormal and −0 as set-point,
/// measurement, feed-forward and tracking value, `f32` and `f64`, at the first sample and later.
///
/// Decided here (documented in `Pid`'s docs): r = y = MAX has no control error, but the
/// derivative's input `y − c·r` jumps by MAX from the last sample, which overflows: held, with
/// `Faults::overflow`; so does a MAX tracking value (`u − v` overflows).
#[test]
#[rustfmt::skip]
fn float_samples_at_the_extremes() {
    float_sample_table!(f32);
    float_sample_table!(f64);
}

#[cfg(feature = "fixed")]
#[rustfmt::skip]
macro_rules! fixed_sample_table {
    ($t:ty) => {{
        type T = $t;
        let cfg = pi_config();
        let mut pid = Pid::<T>::new(&cfg).unwrap();
        let n = |v: f64| T::from_num(v);
        pid.update(n(1.0), n(0.5));
        pid.update(n(1.0), n(0.75));
        let fresh = Pid::<T>::new(&cfg).unwrap();
        let (max, min, delta, zero) = (T::MAX, T::MIN, T::DELTA, T::ZERO);
        use Sample::*;
        let ff = |feedforward: T| {
            Some(Inputs {
                feedforward,
                track: None,
            })
        };
        let track = |t: T| {
            Some(Inputs {
                feedforward: zero,
                track: Some(t),
            })
        };
        let rows: Vec<(&str, &Pid<T>, T, T, Option<Inputs<T>>, Sample)> = vec![
            ("r MAX, y 0", &pid, max, zero, None, HeldOverflow),
            ("r MAX, y MIN", &pid, max, min, None, HeldOverflow),
            ("r 0, y MIN", &pid, zero, min, None, HeldOverflow),
            ("r MIN, y MAX", &pid, min, max, None, HeldOverflow),
            ("first sample r MAX, y 0", &fresh, max, zero, None, HeldOverflow),
            ("r 0, y 0", &pid, zero, zero, None, Runs),
            ("r DELTA, y -DELTA", &pid, delta, -delta, None, Runs),
            ("feed-forward MAX", &pid, n(1.0), n(0.5), ff(max), HeldOverflow),
            ("feed-forward MIN", &pid, n(1.0), n(0.5), ff(min), HeldOverflow),
            ("feed-forward DELTA", &pid, n(1.0), n(0.5), ff(delta), Runs),
            ("track MAX (integral bounded)", &pid, n(1.0), n(0.5), track(max), Runs),
            ("track MIN (MIN − v saturates)", &pid, n(1.0), n(0.5), track(min), HeldOverflow),
            ("track 0", &pid, n(1.0), n(0.5), track(zero), Runs),
        ];
        let fails: Vec<String> = rows
            .into_iter()
            .filter_map(|(what, p, r, y, inputs, want)| {
                check_sample(
                    &format!("{} {what}", stringify!($t)),
                    p,
                    r,
                    y,
                    inputs,
                    want,
                    n(-10.0),
                    n(10.0),
                )
                .err()
            })
            .collect();
        assert!(fails.is_empty(), "{}", fails.join("\n"));
    }};
}

/// Fixed point has no NaN: its extremes are MAX, MIN and the smallest step DELTA. A product or
/// sum that saturates holds the output with `Faults::overflow` (pid-2).
#[cfg(feature = "fixed")]
#[test]
#[rustfmt::skip]
fn fixed_samples_at_the_extremes() {
    fixed_sample_table!(I16F16);
    fixed_sample_table!(I32F32);
}

/// Fixed-point controllers refuse what their type cannot hold, naming the parameter.
#[cfg(feature = "fixed")]
#[test]
#[rustfmt::skip]
fn fixed_point_new_at_the_extremes() {
    let base = pi_config();
    use Parameter as P;
    use Want::*;
    let rows: [(&str, Config, Want, Want); 8] = [
        // (what, config, I16F16, I32F32)
        ("base", base, Ok, Ok),
        ("k 1e5", Config { k: 1e5, ..base }, Unrepresentable(P::K), Ok),
        ("k 1e10", Config { k: 1e10, ..base }, Unrepresentable(P::K), Unrepresentable(P::K)),
        ("k subnormal", Config { k: f64::from_bits(1), ..base }, Unrepresentable(P::K), Unrepresentable(P::K)),
        ("ymax 1e6", Config { ymax: 1e6, ..base }, Unrepresentable(P::Ymax), Ok),
        ("ymin MIN..ymax MAX", Config { ymin: f64::MIN, ymax: f64::MAX, ..base }, Unrepresentable(P::Ymin), Unrepresentable(P::Ymin)),
        ("h subnormal", Config { h: f64::from_bits(1), ..base }, Unrepresentable(P::Ti), Unrepresentable(P::Ti)),
        ("ti MAX", Config { ti: f64::MAX, ..base }, Unrepresentable(P::Ti), Unrepresentable(P::Ti)),
    ];
    for (what, config, w16, w32) in rows {
        assert_eq!(
            shape(&Pid::<I16F16>::new(&config).map(|_| ())),
            w16,
            "I16F16 {what}"
        );
        assert_eq!(
            shape(&Pid::<I32F32>::new(&config).map(|_| ())),
            w32,
            "I32F32 {what}"
        );
    }
}

/// `set_manual`: NaN and ±∞ are refused (`ValueError::NotFinite`) and change nothing; any
/// finite value is clamped into the limits; `set_auto`, `reset` and `clear_faults` after any of
/// them give a controller that runs.
#[test]
#[rustfmt::skip]
fn set_manual_at_the_extremes() {
    let mut pid = Pid::<f64>::new(&pi_config()).unwrap();
    pid.update(1.0, 0.5);
    // (value, result, output after, mode after)
    let rows: [(f64, Result<(), ValueError>, f64, Mode); 9] = [
        (f64::NAN, Err(ValueError::NotFinite), pid.output(), Mode::Auto),
        (f64::INFINITY, Err(ValueError::NotFinite), pid.output(), Mode::Auto),
        (f64::NEG_INFINITY, Err(ValueError::NotFinite), pid.output(), Mode::Auto),
        (f64::MAX, Ok(()), 10.0, Mode::Manual),
        (f64::MIN, Ok(()), -10.0, Mode::Manual),
        (0.0, Ok(()), 0.0, Mode::Manual),
        (-0.0, Ok(()), 0.0, Mode::Manual),
        (f64::from_bits(1), Ok(()), f64::from_bits(1), Mode::Manual),
        (10.0, Ok(()), 10.0, Mode::Manual),
    ];
    for (v, want, out, mode) in rows {
        let mut p = pid.clone();
        assert_eq!(p.set_manual(v), want, "set_manual({v})");
        if want.is_err() {
            assert_eq!(p, pid, "a refused set_manual({v}) changed the controller");
        }
        assert_eq!((p.output(), p.mode()), (out, mode), "set_manual({v})");
        p.set_auto();
        let u = p.update(1.0, 0.5);
        assert!(
            (-10.0..=10.0).contains(&u) && !p.faults().any(),
            "after set_manual({v}): {u}"
        );
        p.reset();
        assert_eq!(
            p,
            Pid::<f64>::new(&pi_config()).unwrap(),
            "reset after set_manual({v})"
        );
    }
    #[cfg(feature = "fixed")]
    {
        let mut fixed = Pid::<I16F16>::new(&pi_config()).unwrap();
        for (v, out) in [
            (I16F16::MAX, 10.0),
            (I16F16::MIN, -10.0),
            (I16F16::DELTA, I16F16::DELTA.to_num()),
        ] {
            assert_eq!(fixed.set_manual(v), Ok(()));
            assert_eq!(fixed.output().to_num::<f64>(), out, "I16F16 set_manual({v})");
        }
    }
}

/// `Scaling::new`, `count_to_units`, `units_to_count`, `contains`, `volts_to_dac` and
/// `dac_to_volts` at the extremes, `f32` and `f64`.
#[rustfmt::skip]
macro_rules! scaling_table {
    ($t:ty) => {{
        type F = $t;
        let (nan, inf, max, min, sub, tiny) = (
            F::NAN,
            F::INFINITY,
            F::MAX,
            F::MIN,
            F::from_bits(1),
            F::MIN_POSITIVE,
        );
        // new: (min, max, outcome as a string of the variant)
        let rows: [(F, F, &str); 16] = [
            (nan, 1.0, "NotFinite"),
            (0.0, nan, "NotFinite"),
            (-inf, 0.0, "NotFinite"),
            (0.0, inf, "NotFinite"),
            (1.0, 1.0, "Reversed"),
            (1.0, 0.0, "Reversed"),
            (-0.0, 0.0, "Reversed"),
            (min, max, "SpanTooLarge"),
            (0.0, max, "SpanTooLarge"),
            (0.0, max / 4096.0, "Ok"),
            (0.0, sub, "Subnormal"),
            (-sub, 1.0, "Subnormal"),
            (tiny, tiny + sub, "Subnormal"),
            (tiny, tiny + tiny, "Ok"),
            (-0.0, 1.0, "Ok"),
            (1.0, 1.0 + F::EPSILON, "Ok"),
        ];
        for (lo, hi, want) in rows {
            let got = match Scaling::<F>::new(lo, hi) {
                Ok(s) => {
                    assert_eq!(
                        (s.min().to_bits(), s.max().to_bits()),
                        (lo.to_bits(), hi.to_bits())
                    );
                    "Ok"
                }
                Err(ScalingError::NotFinite) => "NotFinite",
                Err(ScalingError::Reversed { .. }) => "Reversed",
                Err(ScalingError::SpanTooLarge { .. }) => "SpanTooLarge",
                Err(ScalingError::Subnormal { .. }) => "Subnormal",
                Err(e) => panic!("{e:?}"),
            };
            assert_eq!(got, want, "{} Scaling::new({lo:e}, {hi:e})", stringify!($t));
        }
        let s = Scaling::<F>::new(-0.0, 40.0).unwrap();
        // count_to_units: (count, result)
        let counts: [(u16, Result<F, ScalingError<F>>); 5] = [
            (0, Ok(-0.0)),
            (1, Ok(40.0 / 4095.0)),
            (4095, Ok(40.0)),
            (4096, Err(ScalingError::CountOutOfRange { count: 4096 })),
            (u16::MAX, Err(ScalingError::CountOutOfRange { count: u16::MAX })),
        ];
        for (count, want) in counts {
            assert_eq!(s.count_to_units(count), want, "count_to_units({count})");
        }
        assert!(
            s.count_to_units(0).unwrap().is_sign_negative(),
            "count 0 is SCALEMIN bit for bit"
        );
        // units_to_count and contains: (units, count, on the scale)
        let units: [(F, u16, bool); 10] = [
            (nan, 0, false),
            (inf, 4095, false),
            (-inf, 0, false),
            (max, 4095, false),
            (min, 0, false),
            (0.0, 0, true),
            (-0.0, 0, true),
            (sub, 0, true),
            (-sub, 0, false),
            (40.0, 4095, true),
        ];
        for (u, count, inside) in units {
            assert_eq!(s.units_to_count(u), count, "units_to_count({u:e})");
            assert_eq!(s.contains(u), inside, "contains({u:e})");
        }
        // volts_to_dac: (volts, result)
        let volts: [(F, Result<u8, ScalingError<F>>); 10] = [
            (nan, Err(ScalingError::NotANumber)),
            (inf, Ok(255)),
            (-inf, Ok(0)),
            (max, Ok(255)),
            (min, Ok(0)),
            (0.0, Ok(0)),
            (-0.0, Ok(0)),
            (sub, Ok(0)),
            (10.0, Ok(255)),
            (5.0, Ok(128)),
        ];
        for (v, want) in volts {
            assert_eq!(Scaling::<F>::volts_to_dac(v), want, "volts_to_dac({v:e})");
        }
        for (count, v) in [(0u8, 0.0), (255, 10.0)] {
            assert_eq!(Scaling::<F>::dac_to_volts(count), v);
        }
    }};
}

#[test]
#[rustfmt::skip]
fn scaling_at_the_extremes() {
    scaling_table!(f32);
    scaling_table!(f64);
}

#[rustfmt::skip]
macro_rules! actuator_table {
    ($t:ty) => {{
        type F = $t;
        let (nan, inf, max, min, sub) = (F::NAN, F::INFINITY, F::MAX, F::MIN, F::from_bits(1));
        let base = ActuatorConfig::<F> { run_time: 60.0, min_pulse: 0.2, dead_band: 0.005, h: 1.0 };
        let run_time = "run_time must be finite and positive";
        let h = "h must be finite and positive";
        let pulse = "min_pulse must be in 0..=h";
        let pulse_stroke = "min_pulse must not exceed run_time: the shortest pulse would move the actuator more than its whole stroke";
        let ratio = "h / run_time is below the smallest normal number of the float type: one sample's travel cannot be resolved";
        let short = "run_time is below 2 × the smallest normal number / ε of the float type: the pulse for a small error would be a subnormal number of seconds, too coarse for the estimate";
        let floor = F::MIN_POSITIVE * 2.0 / F::EPSILON;
        let band = "dead_band must be in 0..1";
        let position = "position must be in 0..=1";
        // new: (what, config, position, Ok or the message)
        let rows: Vec<(&str, ActuatorConfig<F>, F, Result<(), &str>)> = vec![
            ("base", base, 0.0, Ok(())),
            ("run_time 0", ActuatorConfig { run_time: 0.0, ..base }, 0.0, Err(run_time)),
            ("run_time -0", ActuatorConfig { run_time: -0.0, ..base }, 0.0, Err(run_time)),
            ("run_time NaN", ActuatorConfig { run_time: nan, ..base }, 0.0, Err(run_time)),
            ("run_time inf", ActuatorConfig { run_time: inf, ..base }, 0.0, Err(run_time)),
            ("run_time MIN", ActuatorConfig { run_time: min, ..base }, 0.0, Err(run_time)),
            ("run_time MAX", ActuatorConfig { run_time: max, ..base }, 0.0, Err(ratio)),
            ("run_time subnormal", ActuatorConfig { run_time: sub, min_pulse: 0.0, ..base }, 0.0, Err(short)),
            ("run_time 2·MIN_POSITIVE/ε", ActuatorConfig { run_time: floor, h: floor, min_pulse: 0.0, ..base }, 0.0, Ok(())),
            ("run_time an ulp below 2·MIN_POSITIVE/ε", ActuatorConfig { run_time: F::from_bits(floor.to_bits() - 1), h: floor, min_pulse: 0.0, ..base }, 0.0, Err(short)),
            ("h 0", ActuatorConfig { h: 0.0, ..base }, 0.0, Err(h)),
            ("h NaN", ActuatorConfig { h: nan, ..base }, 0.0, Err(h)),
            ("h -inf", ActuatorConfig { h: -inf, ..base }, 0.0, Err(h)),
            ("h subnormal", ActuatorConfig { h: sub, min_pulse: 0.0, ..base }, 0.0, Err(ratio)),
            ("h MAX", ActuatorConfig { h: max, run_time: max, min_pulse: 0.0, ..base }, 0.0, Ok(())),
            ("min_pulse NaN", ActuatorConfig { min_pulse: nan, ..base }, 0.0, Err(pulse)),
            ("min_pulse -subnormal", ActuatorConfig { min_pulse: -sub, ..base }, 0.0, Err(pulse)),
            ("min_pulse -0", ActuatorConfig { min_pulse: -0.0, ..base }, 0.0, Ok(())),
            ("min_pulse above h", ActuatorConfig { min_pulse: 1.0 + F::EPSILON, ..base }, 0.0, Err(pulse)),
            ("min_pulse = h", ActuatorConfig { min_pulse: 1.0, ..base }, 0.0, Ok(())),
            ("min_pulse above run_time", ActuatorConfig { min_pulse: 1.0, run_time: 0.5, ..base }, 0.0, Err(pulse_stroke)),
            ("dead_band NaN", ActuatorConfig { dead_band: nan, ..base }, 0.0, Err(band)),
            ("dead_band 1", ActuatorConfig { dead_band: 1.0, ..base }, 0.0, Err(band)),
            ("dead_band -subnormal", ActuatorConfig { dead_band: -sub, ..base }, 0.0, Err(band)),
            ("dead_band just below 1", ActuatorConfig { dead_band: 1.0 - F::EPSILON, ..base }, 0.0, Ok(())),
            ("position NaN", base, nan, Err(position)),
            ("position -subnormal", base, -sub, Err(position)),
            ("position -0", base, -0.0, Ok(())),
            ("position 1", base, 1.0, Ok(())),
            ("position above 1", base, 1.0 + F::EPSILON, Err(position)),
            ("position inf", base, inf, Err(position)),
        ];
        for (what, config, pos, want) in rows {
            let got = ThreePoint::new(config, pos).map(|_| ()).map_err(|e| match e {
                ActuatorError::Config(m) => m,
                e => panic!("{e:?}"),
            });
            assert_eq!(got, want, "{} ThreePoint::new {what}", stringify!($t));
        }
        // update / update_delta from the middle: (what, positional?, request, result)
        let mid = ThreePoint::new(base, 0.5).unwrap();
        let rows: Vec<(&str, bool, F, Result<Drive<F>, ActuatorError>)> = vec![
            ("target NaN", true, nan, Err(ActuatorError::NotFinite)),
            ("target +inf", true, inf, Err(ActuatorError::NotFinite)),
            ("target -inf", true, -inf, Err(ActuatorError::NotFinite)),
            ("target MAX (clamped to 1)", true, max, Ok(Drive::Open(1.0))),
            ("target MIN (clamped to 0)", true, min, Ok(Drive::Close(1.0))),
            ("target 0.5 (there)", true, 0.5, Ok(Drive::Stop)),
            ("target 0.5 + subnormal", true, 0.5 + sub, Ok(Drive::Stop)),
            ("delta NaN", false, nan, Err(ActuatorError::NotFinite)),
            ("delta -inf", false, -inf, Err(ActuatorError::NotFinite)),
            ("delta MAX (to the stop)", false, max, Ok(Drive::Open(1.0))),
            ("delta MIN (to the stop)", false, min, Ok(Drive::Close(1.0))),
            ("delta 0", false, 0.0, Ok(Drive::Stop)),
            ("delta -0", false, -0.0, Ok(Drive::Stop)),
            ("delta subnormal", false, sub, Ok(Drive::Stop)),
        ];
        for (what, positional, v, want) in rows {
            let mut a = mid.clone();
            let got = if positional { a.update(v) } else { a.update_delta(v) };
            assert_eq!(got, want, "{} {what}", stringify!($t));
            if got.is_err() || got == Ok(Drive::Stop) {
                assert_eq!((a.position(), a.driven()), (mid.position(), mid.driven()), "{what}");
            }
            let p = a.position();
            assert!((0.0..=1.0).contains(&p), "{what}: estimate {p}");
        }
        // A refused request leaves a pending velocity request as it was.
        let mut a = mid.clone();
        a.update_delta(0.001).unwrap();
        let mut b = a.clone();
        assert_eq!(b.update_delta(nan), Err(ActuatorError::NotFinite));
        assert_eq!(b.update_delta(0.001), a.update_delta(0.001));
        // The shortest run time accepted (a subnormal one is refused, above): every sample's
        // travel is the whole stroke many times over; the estimate stays in 0..=1 and a target
        // at an end is reached in one sample.
        let mut fast = ThreePoint::new(ActuatorConfig { run_time: floor, min_pulse: 0.0, ..base }, 0.0).unwrap();
        assert!(matches!(fast.update(1.0), Ok(Drive::Open(_))));
        assert_eq!(fast.position(), 1.0, "subnormal run time");
        // at_end re-anchors the estimate at either end, from anywhere.
        for (open, at) in [(true, 1.0), (false, 0.0)] {
            let mut a = mid.clone();
            a.at_end(open);
            assert_eq!(a.position(), at);
        }
    }};
}

/// `ThreePoint::new`, `update`, `update_delta` and `at_end` at the extremes.
#[test]
#[rustfmt::skip]
fn actuator_at_the_extremes() {
    actuator_table!(f32);
    actuator_table!(f64);
}

/// The tuning rules: every input NaN, ±∞, 0, −0, subnormal, MAX; the exact error naming it,
/// or a finite positive result.
#[test]
#[rustfmt::skip]
fn tuning_rules_at_the_extremes() {
    let (nan, inf, max, sub) = (f64::NAN, f64::INFINITY, f64::MAX, f64::from_bits(1));
    let u = |ku, tu| Ultimate { ku, tu };
    let rows: [(&str, Ultimate, Kind, Result<(), RuleError>); 13] = [
        ("ku NaN", u(nan, 1.0), Kind::PID, Err(RuleError::Input("Ku"))),
        ("ku +inf", u(inf, 1.0), Kind::PID, Err(RuleError::Input("Ku"))),
        ("ku 0", u(0.0, 1.0), Kind::PID, Err(RuleError::Input("Ku"))),
        ("ku -0", u(-0.0, 1.0), Kind::PID, Err(RuleError::Input("Ku"))),
        ("ku MIN", u(f64::MIN, 1.0), Kind::PI, Err(RuleError::Input("Ku"))),
        ("tu NaN", u(1.0, nan), Kind::PID, Err(RuleError::Input("Tu"))),
        ("tu 0", u(1.0, 0.0), Kind::P, Err(RuleError::Input("Tu"))),
        ("ku subnormal, PID (0.6·Ku rounds up)", u(sub, 1.0), Kind::PID, Ok(())),
        ("ku subnormal, P (0.5·Ku rounds to 0)", u(sub, 1.0), Kind::P, Err(RuleError::Result("gain K"))),
        ("tu subnormal (Tu/2 rounds to 0)", u(1.0, sub), Kind::PID, Err(RuleError::Result("integral time Ti"))),
        ("ku MAX", u(max, 1.0), Kind::PID, Ok(())),
        ("tu MAX", u(1.0, max), Kind::PI, Ok(())),
        ("kind PD", u(1.0, 1.0), Kind::PD, Err(RuleError::Kind(Kind::PD))),
    ];
    for (what, ult, kind, want) in rows {
        let got = ziegler_nichols(ult, kind);
        assert_eq!(got.map(|_| ()), want, "ziegler_nichols {what}");
        if let Ok(t) = got {
            assert!(
                t.k.is_finite() && t.k > 0.0 && t.ti.is_finite() && t.td.is_finite(),
                "{what}: {t:?}"
            );
        }
    }
    let m = |gain, time_constant, dead_time| Fopdt {
        gain,
        time_constant,
        dead_time,
    };
    let rows: [(&str, Fopdt, Result<(), RuleError>, Result<(), RuleError>); 12] = [
        // (what, model, amigo PI, simc with tc = 1)
        ("gain NaN", m(nan, 10.0, 1.0), Err(RuleError::Input("the process gain")), Err(RuleError::Input("the process gain"))),
        ("gain 0", m(0.0, 10.0, 1.0), Err(RuleError::Input("the process gain")), Err(RuleError::Input("the process gain"))),
        ("gain -0", m(-0.0, 10.0, 1.0), Err(RuleError::Input("the process gain")), Err(RuleError::Input("the process gain"))),
        ("gain -inf", m(-inf, 10.0, 1.0), Err(RuleError::Input("the process gain")), Err(RuleError::Input("the process gain"))),
        ("gain -2 (reverse process)", m(-2.0, 10.0, 1.0), Ok(()), Ok(())),
        ("time constant 0", m(2.0, 0.0, 1.0), Err(RuleError::Input("the time constant")), Err(RuleError::Input("the time constant"))),
        ("time constant NaN", m(2.0, nan, 1.0), Err(RuleError::Input("the time constant")), Err(RuleError::Input("the time constant"))),
        ("dead time 0", m(2.0, 10.0, 0.0), Err(RuleError::Input("the dead time")), Err(RuleError::Input("the dead time"))),
        ("dead time +inf", m(2.0, 10.0, inf), Err(RuleError::Input("the dead time")), Err(RuleError::Input("the dead time"))),
        ("gain subnormal", m(sub, 10.0, 1.0), Err(RuleError::Result("gain K")), Err(RuleError::Result("gain K"))),
        ("gain MAX (simc: K·(tc + L) overflows, K = 0)", m(max, 10.0, 1.0), Ok(()), Err(RuleError::Result("gain K"))),
        ("time constant MAX (amigo: T² overflows)", m(2.0, max, 1.0), Err(RuleError::Result("integral time Ti")), Ok(())),
    ];
    for (what, model, want_amigo, want_simc) in rows {
        assert_eq!(
            amigo(model, Kind::PI).map(|_| ()),
            want_amigo,
            "amigo {what}"
        );
        assert_eq!(simc(model, 1.0).map(|_| ()), want_simc, "simc {what}");
    }
    let good = m(2.0, 10.0, 1.0);
    for (tc, want) in [
        (nan, Err(RuleError::Input("the closed-loop time constant"))),
        (0.0, Err(RuleError::Input("the closed-loop time constant"))),
        (-0.0, Err(RuleError::Input("the closed-loop time constant"))),
        (inf, Err(RuleError::Input("the closed-loop time constant"))),
        (sub, Ok(())),
        (max, Err(RuleError::Result("gain K"))),
    ] {
        assert_eq!(simc(good, tc).map(|_| ()), want, "simc tc {tc:e}");
    }
    assert_eq!(
        amigo(good, Kind::PD).map(|_| ()),
        Err(RuleError::Kind(Kind::PD))
    );
    // with_sampling_delay: h/2 added, NaN and ∞ passed on (the rules then refuse them).
    assert_eq!(good.with_sampling_delay(0.0), good);
    assert_eq!(good.with_sampling_delay(2.0).dead_time, 2.0);
    assert_eq!(
        amigo(good.with_sampling_delay(nan), Kind::PI).map(|_| ()),
        Err(RuleError::Input("the dead time"))
    );
    assert_eq!(
        amigo(good.with_sampling_delay(inf), Kind::PI).map(|_| ()),
        Err(RuleError::Input("the dead time"))
    );
}

/// `Tuning::apply`: a result that would make the configuration invalid is refused with the
/// configuration's own error and the configuration is unchanged.
#[test]
#[rustfmt::skip]
fn tuning_apply_at_the_extremes() {
    let t = |k, ti, td, b| Tuning {
        kind: Kind::PID,
        k,
        ti,
        td,
        b,
    };
    use Parameter as P;
    use Want::*;
    let rows: [(&str, Tuning, Want); 8] = [
        ("good", t(2.0, 10.0, 1.0, 1.0), Ok),
        ("k NaN", t(f64::NAN, 10.0, 1.0, 1.0), NotFinite(P::K)),
        ("ti NaN", t(2.0, f64::NAN, 1.0, 1.0), NotFinite(P::Ti)),
        ("ti below h", t(2.0, 0.5, 1.0, 1.0), OutOfRange(P::Ti)),
        ("ti 0", t(2.0, 0.0, 1.0, 1.0), OutOfRange(P::Ti)),
        ("td -inf", t(2.0, 10.0, f64::NEG_INFINITY, 1.0), NotFinite(P::Td)),
        ("td -subnormal", t(2.0, 10.0, -f64::from_bits(1), 1.0), OutOfRange(P::Td)),
        ("b +inf", t(2.0, 10.0, 1.0, f64::INFINITY), NotFinite(P::B)),
    ];
    for (what, tuning, want) in rows {
        let mut c = Config::default();
        let before = c;
        let r = tuning.apply(&mut c);
        assert_eq!(shape(&r), want, "apply {what}");
        if r.is_err() {
            assert_eq!(
                c, before,
                "a refused apply changed the configuration: {what}"
            );
        }
    }
}

/// `identify_step` and `identify_step_at`: empty, one-sample and short logs, a step index past
/// the log (`usize::MAX` included), bad h and step, a NaN or ∞ sample (named by its index).
#[test]
#[rustfmt::skip]
fn identify_step_at_the_extremes() {
    let flat = vec![1.0f64; 40];
    let mut with_nan = flat.clone();
    with_nan[7] = f64::NAN;
    // A first-order lag, T = 5 samples, dead time 3 samples; and a jump from 0 to MAX.
    let lag: Vec<f64> = (0..60)
        .map(|k| if k < 3 { 0.0 } else { 1.0 - (-(f64::from(k) - 3.0) / 5.0).exp() })
        .collect();
    let to_max: Vec<f64> = (0..45).map(|k| if k < 5 { -f64::MAX } else { f64::MAX }).collect();
    let mut with_inf = flat.clone();
    with_inf[39] = f64::NEG_INFINITY;
    use regler_pid::tuning::IdentifyError as E;
    let rows: Vec<(&str, &[f64], usize, f64, f64, E<f64>)> = vec![
        ("empty log", &[], 0, 1.0, 1.0, E::StepOutsideLog(0, 0)),
        ("one sample", &flat[..1], 0, 1.0, 1.0, E::TooFewSamples(1)),
        ("19 samples", &flat[..19], 0, 1.0, 1.0, E::TooFewSamples(19)),
        ("step at the end", &flat, 40, 1.0, 1.0, E::StepOutsideLog(40, 40)),
        ("step at usize::MAX", &flat, usize::MAX, 1.0, 1.0, E::StepOutsideLog(usize::MAX, 40)),
        ("h NaN", &flat, 0, f64::NAN, 1.0, E::Input("the sample period")),
        ("h 0", &flat, 0, 0.0, 1.0, E::Input("the sample period")),
        ("h subnormal", &flat, 0, f64::from_bits(1), 1.0, E::Input("the sample period")),
        ("h -MIN_POSITIVE", &flat, 0, -f64::MIN_POSITIVE, 1.0, E::Input("the sample period")),
        ("h MAX: T + L overflows", &lag, 0, f64::MAX, 1.0, E::Overflow("T + L (the sample period times the log)")),
        ("step 0", &flat, 0, 1.0, 0.0, E::Input("the step")),
        ("step subnormal: change / step overflows", &lag, 0, 1.0, f64::from_bits(1), E::Overflow("the gain (change / step)")),
        ("samples -MAX then MAX: the change overflows", &to_max, 0, 1.0, 1.0, E::Overflow("the change (the samples' mean)")),
        ("step -0", &flat, 0, 1.0, -0.0, E::Input("the step")),
        ("step +inf", &flat, 0, 1.0, f64::INFINITY, E::Input("the step")),
        ("a NaN sample", &with_nan, 0, 1.0, 1.0, E::NotFinite(7)),
        ("a -inf sample", &with_inf, 0, 1.0, 1.0, E::NotFinite(39)),
        ("no response", &flat, 0, 1.0, 1.0, E::NoResponse),
    ];
    for (what, log, at, h, step, want) in rows {
        let got = if at == 0 {
            identify_step(log, h, step)
        } else {
            identify_step_at(log, at, h, step)
        };
        assert_eq!(got, Err(want), "{what}");
    }
    // The smallest normal sample period and a step of MAX are fitted; T and L scale with h.
    let tiny = identify_step(&lag, f64::MIN_POSITIVE, 1.0).unwrap();
    let unit = identify_step(&lag, 1.0, 1.0).unwrap();
    assert_eq!(tiny.gain, unit.gain);
    assert!((tiny.time_constant / f64::MIN_POSITIVE / unit.time_constant - 1.0).abs() < 1e-12, "{tiny:?}");
    // A change of MAX fits (0 then MAX): a step to MAX, never an overflow.
    let zero_to_max: Vec<f64> = to_max.iter().map(|&v| v.max(0.0)).collect();
    let jump = identify_step(&zero_to_max, 1.0, 1.0).unwrap();
    assert_eq!(jump.gain, f64::MAX);
    let huge_step = identify_step(&lag, 1.0, f64::MAX).unwrap();
    assert_eq!(huge_step.time_constant, unit.time_constant);
    assert!(huge_step.gain > 0.0 && huge_step.gain.is_finite());
}

/// `Relay::new` with each value at its extremes, and `update` with NaN and ∞ measurements
/// (skipped: the relay holds its output) and after an abort.
#[test]
#[rustfmt::skip]
fn relay_at_the_extremes() {
    let base = RelayConfig::<f64>::default();
    let rows: Vec<(&str, RelayConfig, Result<(), RelayError>)> = vec![
        ("default", base, Ok(())),
        ("bias NaN", RelayConfig { bias: f64::NAN, ..base }, Err(RelayError::Config("bias must be finite"))),
        ("amplitude 0", RelayConfig { amplitude: 0.0, ..base }, Err(RelayError::Config("amplitude must be finite and positive"))),
        ("amplitude +inf", RelayConfig { amplitude: f64::INFINITY, ..base }, Err(RelayError::Config("amplitude must be finite and positive"))),
        ("hysteresis -subnormal", RelayConfig { hysteresis: -f64::from_bits(1), ..base }, Err(RelayError::Config( "hysteresis must be finite and not negative", ))),
        ("hysteresis -0", RelayConfig { hysteresis: -0.0, ..base }, Ok(())),
        ("h 0", RelayConfig { h: 0.0, ..base }, Err(RelayError::Config("h must be finite and positive"))),
        ("h NaN", RelayConfig { h: f64::NAN, ..base }, Err(RelayError::Config("h must be finite and positive"))),
        ("cycles 0", RelayConfig { cycles: 0, ..base }, Err(RelayError::Config("cycles must be 2..=8"))),
        ("cycles 1", RelayConfig { cycles: 1, ..base }, Err(RelayError::Config("cycles must be 2..=8"))),
        ("cycles 2", RelayConfig { cycles: 2, ..base }, Ok(())),
        ("cycles 8", RelayConfig { cycles: 8, ..base }, Ok(())),
        ("cycles 9", RelayConfig { cycles: 9, ..base }, Err(RelayError::Config("cycles must be 2..=8"))),
        ("cycles u8::MAX", RelayConfig { cycles: u8::MAX, ..base }, Err(RelayError::Config("cycles must be 2..=8"))),
        ("tolerance 0", RelayConfig { tolerance: 0.0, ..base }, Err(RelayError::Config("tolerance must be finite and positive"))),
        ("timeout = h", RelayConfig { timeout: 0.1, ..base }, Err(RelayError::Config( "timeout must be finite and longer than h", ))),
        ("timeout +inf", RelayConfig { timeout: f64::INFINITY, ..base }, Err(RelayError::Config( "timeout must be finite and longer than h", ))),
        ("timeout MAX, h subnormal", RelayConfig { timeout: f64::MAX, h: f64::from_bits(1), ..base }, Err(RelayError::Config("timeout/h must be at most 2^64 samples"))),
        ("timeout/h 2^64", RelayConfig { timeout: 18_446_744_073_709_551_616.0, h: 1.0, ..base }, Err(RelayError::Config("timeout/h must be at most 2^64 samples"))),
        ("timeout/h below 2^64", RelayConfig { timeout: 9_223_372_036_854_775_808.0, h: 1.0, ..base }, Ok(())),
    ];
    for (what, config, want) in rows {
        assert_eq!(Relay::new(config).map(|_| ()), want, "Relay::new {what}");
    }
    let mut relay = Relay::new(base).unwrap();
    let high = relay.output();
    for y in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert_eq!(
            relay.update(0.0, y),
            Ok(RelayStep::Running(high)),
            "measurement {y}"
        );
    }
    assert_eq!(relay.abort(), 0.0);
    assert_eq!(relay.update(0.0, 0.0), Err(RelayError::Aborted));
    assert_eq!(relay.output(), 0.0);
}

fn station_params() -> Parameters {
    Parameters {
        config: Config {
            kind: Kind::PI,
            k: 1.0,
            ti: 10.0,
            ..Config::default()
        },
        setpoint: 20.0,
        rfel: 5.0,
        night_setback: 3.0,
    }
}

/// The operator layer: `Staged::new`, `edit_number`, `edit` with codes and values at their
/// extremes; a refused edit leaves the shadow set as it was.
#[test]
#[rustfmt::skip]
fn staged_edits_at_the_extremes() {
    let scale = Scaling::new(0.0, 40.0).unwrap();
    let limits = OperatorLimits::default();
    let p = station_params();
    // Staged::new: (what, parameters, limits, Ok or the error's code)
    let rows: Vec<(&str, Parameters, OperatorLimits, Result<(), Option<Code>>)> = vec![
        ("good", p, limits, Ok(())),
        ("setpoint NaN", Parameters { setpoint: f64::NAN, ..p }, limits, Err(Some(Code::Win))),
        ("setpoint above the scale", Parameters { setpoint: 40.0 + 1e-9, ..p }, limits, Err(Some(Code::Win))),
        ("setpoint -0 (on the scale)", Parameters { setpoint: -0.0, ..p }, limits, Ok(())),
        ("rfel -inf", Parameters { rfel: f64::NEG_INFINITY, ..p }, limits, Err(Some(Code::Rfel))),
        ("rfel -0", Parameters { rfel: -0.0, ..p }, limits, Ok(())),
        ("night set-back NaN", Parameters { night_setback: f64::NAN, ..p }, limits, Err(None)),
        ("night set-back beyond the span", Parameters { night_setback: 40.0 + 1e-9, ..p }, limits, Err(None)),
        ("night set-back the span", Parameters { night_setback: 40.0, ..p }, limits, Ok(())),
        ("limits NaN", p, OperatorLimits { kp: (f64::NAN, 1.0), ..limits }, Err(None)),
        ("limits reversed", p, OperatorLimits { sample: (2.0, 1.0), ..limits }, Err(None)),
    ];
    for (what, params, lim, want) in rows {
        let got = Staged::new(params, scale, lim)
            .map(|_| ())
            .map_err(|e| e.code());
        assert_eq!(got, want, "Staged::new {what}");
    }
    let staged = Staged::new(p, scale, limits).unwrap();
    // edit_number: (code number, value, Ok or the error)
    let rows: Vec<(u8, f64, Result<(), EditError>)> = vec![
        (0, 1.0, Err(EditError::UnknownCode(0))),
        (u8::MAX, 1.0, Err(EditError::UnknownCode(u8::MAX))),
        (Code::Y.number(), 1.0, Err(EditError::ReadOnly(Code::Y))),
        (Code::Xin.number(), 1.0, Err(EditError::ReadOnly(Code::Xin))),
        (Code::Typ.number(), 1.0, Err(EditError::NotANumber(Code::Typ))),
        (Code::Kp.number(), f64::NAN, Err(EditError::IllegalValue { code: Code::Kp, value: f64::NAN, requirement: Requirement::Finite, })),
        (Code::Win.number(), f64::INFINITY, Err(EditError::IllegalValue { code: Code::Win, value: f64::INFINITY, requirement: Requirement::Finite, })),
        (Code::Win.number(), f64::MAX, Err(EditError::IllegalValue { code: Code::Win, value: f64::MAX, requirement: Requirement::OnScale { min: 0.0, max: 40.0, }, })),
        (Code::S.number(), 0.0, Err(EditError::IllegalValue { code: Code::S, value: 0.0, requirement: Requirement::Within { min: 1.0, max: 255.0, }, })),
        (Code::Kp.number(), f64::MIN, Err(EditError::IllegalValue { code: Code::Kp, value: f64::MIN, requirement: Requirement::Within { min: -1.0, max: 10_000.0, }, })),
        (Code::Ti.number(), -0.0, Err(EditError::IllegalValue { code: Code::Ti, value: -0.0, requirement: Requirement::ValidConfig(ConfigError::OutOfRange { parameter: Parameter::Ti, value: -0.0, requirement: "> 0 when the controller has integral action", }), })),
        (Code::Ymin.number(), 10.0 + 1e-9, Err(EditError::IllegalValue { code: Code::Ymin, value: 10.0 + 1e-9, requirement: Requirement::Within { min: 0.0, max: 10.0, }, })),
        (Code::Rfel.number(), -f64::MAX, Ok(())),
        (Code::Dymax.number(), -0.0, Ok(())),
        (Code::Win.number(), -0.0, Ok(())),
        (Code::Kp.number(), 0.0, Ok(())),
    ];
    for (code, v, want) in rows {
        let mut s = staged;
        let got = s.edit_number(code, v);
        let ok = want.is_ok();
        // Compare the NaN row by its Debug text (NaN ≠ NaN).
        assert_eq!(
            format!("{got:?}"),
            format!("{want:?}"),
            "edit_number({code}, {v})"
        );
        if !ok {
            assert_eq!(
                s.shadow(),
                staged.shadow(),
                "a refused edit({code}, {v}) changed the shadow set"
            );
            assert!(!s.edited());
        }
    }
    let mut s = staged;
    s.edit_number(Code::Rfel.number(), -f64::MAX).unwrap();
    assert_eq!(s.shadow().rfel, f64::MAX, "RFEL is taken as its magnitude");
    s.edit_number(Code::Dymax.number(), -0.0).unwrap();
    assert_eq!(s.shadow().config.dymax, None, "DYMAX 0 is no limit");
}

/// A `Station`'s sample with NaN, ±∞ and MAX measurements, and non-finite feed-forward and
/// tracking values (ignored: they count as 0 and `None`), in `f64` and `I16F16`.
#[test]
#[rustfmt::skip]
fn station_samples_at_the_extremes() {
    let scale = Scaling::new(0.0, 40.0).unwrap();
    let limits = OperatorLimits::default();
    let mut st = Station::<f64>::new(station_params(), scale, limits).unwrap();
    st.sample(18.0);
    let held = st.pid().output();
    for xin in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut s = st.clone();
        assert_eq!(s.sample(xin), held, "xin {xin}");
        assert!(s.pid().faults().non_finite_input(), "xin {xin}");
        assert_ne!(
            s.alarm_state(),
            regler_pid::AlarmState::Normal,
            "xin {xin}: no alarm"
        );
    }
    let mut s = st.clone();
    assert_eq!(
        s.sample(f64::MAX),
        0.0,
        "xin MAX: K·(r − y) = −MAX, finite: the output at YMIN"
    );
    assert!(!s.pid().faults().any());
    // Non-finite feed-forward and tracking values are ignored.
    let (mut a, mut b) = (st.clone(), st.clone());
    a.set_feedforward(f64::NAN);
    a.set_track(Some(f64::INFINITY));
    assert_eq!(a.sample(18.0), b.sample(18.0));
    assert!(!a.pid().faults().any());
    // Fixed point: a measurement beyond the type saturates to its end; the output stays in
    // the limits and is finite.
    #[cfg(feature = "fixed")]
    {
        let mut f = Station::<I16F16>::new(station_params(), scale, limits).unwrap();
        for xin in [f64::MAX, f64::MIN, 1e9, -0.0, f64::from_bits(1)] {
            let y = f.sample(xin);
            assert!((0.0..=10.0).contains(&y), "I16F16 xin {xin:e}: {y}");
        }
        for xin in [f64::NAN, f64::INFINITY] {
            let before = f.pid().output().to_num::<f64>();
            assert_eq!(f.sample(xin), before, "I16F16 xin {xin}");
            assert!(f.pid().faults().non_finite_input());
        }
    }
}

/// Key codes over every `u8` (exhaustive): exactly the twelve codes of the source are codes;
/// `Kind::parse` of empty, blank, padded, mixed-case and unknown text.
#[test]
fn codes_and_kinds_over_every_input() {
    let known = [10u8, 21, 31, 41, 51, 61, 71, 81, 82, 83, 91, 95];
    for n in 0..=u8::MAX {
        let code = Code::from_number(n);
        assert_eq!(code.is_some(), known.contains(&n), "code {n}");
        if let Some(c) = code {
            assert_eq!(c.number(), n);
        }
    }
    // (text, kind)
    let rows: [(&str, Option<Kind>); 8] = [
        ("", None),
        ("   ", None),
        ("pid", Some(Kind::PID)),
        (" Pi\t", Some(Kind::PI)),
        ("PIDD", None),
        ("P I", None),
        ("\u{0}", None),
        ("ΡΙ", None), // Greek capitals that look like PI
    ];
    for (text, kind) in rows {
        assert_eq!(Kind::parse(text), kind, "{text:?}");
    }
}

/// A fixed-point `Station` refuses a scale its type cannot hold, naming it; the same scale is
/// accepted in `f32` and `f64`.
#[cfg(feature = "fixed")]
#[test]
fn station_scales_at_the_extremes() {
    let limits = OperatorLimits::default();
    // A P controller of small gain, so that the reach check (pid-12) does not refuse first.
    let params = |setpoint| {
        let mut p = Parameters {
            setpoint,
            ..station_params()
        };
        p.config.kind = Kind::P;
        p.config.k = 0.05;
        p
    };
    // (min, max, I16F16 accepts, I32F32 accepts)
    let rows: [(f64, f64, bool, bool); 5] = [
        (0.0, 40.0, true, true),
        (0.0, 30_000.0, true, true),
        (0.0, 40_000.0, false, true),
        (-1e9, 1e9, false, true),
        (0.0, 1e12, false, false),
    ];
    for (lo, hi, i16f16, i32f32) in rows {
        let scale = Scaling::new(lo, hi).unwrap();
        let p = params(lo.max(0.0).min(hi));
        let shape = |r: Result<(), EditError>| match r {
            Ok(()) => true,
            Err(EditError::ScaleUnrepresentable { min, max, .. }) => {
                assert_eq!((min, max), (lo, hi));
                false
            }
            Err(e) => panic!("scale {lo}..{hi}: {e:?}"),
        };
        assert_eq!(
            shape(Station::<I16F16>::new(p, scale, limits).map(|_| ())),
            i16f16,
            "I16F16 {lo}..{hi}"
        );
        assert_eq!(
            shape(Station::<I32F32>::new(p, scale, limits).map(|_| ())),
            i32f32,
            "I32F32 {lo}..{hi}"
        );
        assert!(
            Station::<f64>::new(p, scale, limits).is_ok(),
            "f64 {lo}..{hi}"
        );
    }
}

proptest::proptest! {
    /// Any positive sample period, from the smallest subnormal to MAX (its bits drawn
    /// uniformly): refused by name when subnormal, an overflow named when T + L does not fit,
    /// otherwise T and L are the unit fit's times h (to 10⁻⁹), normal numbers. Before the fix a
    /// subnormal h gave T and L a few ulps long, and a huge one was refused as "not FOPDT".
    #[test]
    fn any_sample_period_is_refused_by_name_or_scales_the_fit(bits in 1u64..0x7FF0_0000_0000_0000) {
        use regler_pid::tuning::IdentifyError as E;
        let h = f64::from_bits(bits);
        let lag: Vec<f64> = (0..60)
            .map(|k| if k < 3 { 0.0 } else { 1.0 - (-(f64::from(k) - 3.0) / 5.0).exp() })
            .collect();
        let unit = identify_step(&lag, 1.0, 1.0).unwrap();
        match identify_step(&lag, h, 1.0) {
            Err(E::Input("the sample period")) => proptest::prop_assert!(!h.is_normal()),
            Err(E::Overflow("T + L (the sample period times the log)")) => {
                // T + L is about 8 h: it overflows only for h within a factor 8 of MAX.
                proptest::prop_assert!(h > f64::MAX / 16.0, "h {:e}", h);
            }
            Ok(fit) => {
                proptest::prop_assert!(h.is_normal());
                proptest::prop_assert!((fit.time_constant / h / unit.time_constant - 1.0).abs() < 1e-9, "{:?}", fit);
                proptest::prop_assert!(fit.time_constant.is_normal());
                let scale = unit.time_constant + unit.dead_time;
                proptest::prop_assert!((fit.dead_time / h - unit.dead_time).abs() < 1e-9 * scale, "{:?}", fit);
            }
            other => proptest::prop_assert!(false, "h {h:e}: {other:?}"),
        }
    }
}
