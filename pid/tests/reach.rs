//! The README's rule for what a fixed-point `Station` accepts (`ConfigError::OutOfReach`),
//! checked against the closed form the README gives (a model, not the implementation).
#![allow(
    clippy::float_cmp,
    clippy::unwrap_used,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation
)]
#![cfg(feature = "fixed")]

use fixed::types::{I16F16, I32F32};
use proptest::prelude::*;
use regler_pid::{
    Config, ConfigError, EditError, Kind, OperatorLimits, Parameters, Pid, Scalar, Scaling, Station,
};

fn params(config: Config<f64>, setpoint: f64) -> Parameters<f64> {
    Parameters {
        config,
        setpoint,
        rfel: 1.0,
        night_setback: 0.0,
    }
}

fn limits() -> OperatorLimits<f64> {
    // Gains up to 10⁹: the reach check, not the operator's KP limit, decides here.
    OperatorLimits {
        output: (0.0, 1000.0),
        kp: (-1.0, 1e9),
        ..OperatorLimits::default()
    }
}

/// The README's closed form for a PI (Td = 0) on a scale 0..M with 0 ≤ b ≤ 1, output limits
/// 0 ≤ ymin < ymax = Y and a = h/Tt (1 when Tt is unset): the largest of M,
/// v = K·M·(2 − b) + 102·Y and R = K·M·(2·(1 − b) + a·(2 − b) + h/Ti) + (101.5 + 102·a)·Y +
/// ymin/2.
fn reach(c: &Config<f64>, m: f64) -> f64 {
    let a = c.h / c.tt.unwrap_or(c.h);
    let (k, b, y) = (c.k.abs(), c.b, c.ymax);
    let v = k * m * (2.0 - b) + 102.0 * y;
    let r = k * m * (2.0 * (1.0 - b) + a * (2.0 - b) + c.h / c.ti)
        + (101.5 + 102.0 * a) * y
        + c.ymin / 2.0;
    m.max(v).max(r)
}

/// L = MAX·(1 − 2⁻⁸) of the type.
fn limit<T: Scalar>() -> f64 {
    T::MAX.to_real::<f64>() * (1.0 - 1.0 / 256.0)
}

fn pi() -> impl Strategy<Value = (Config<f64>, f64)> {
    (
        0.01f64..2.0,
        0.0f64..=1.0,
        1u8..=10,
        1.0f64..1000.0,
        prop::option::of(1.0f64..100.0),
        0.0f64..0.5,
        0.5f64..200.0,
        1.0f64..32_000.0,
    )
        .prop_map(|(q, b, h, ti_over_h, tt_over_h, ymin_frac, y, m)| {
            // K·M around the I16F16 limit, so both answers are common.
            let k = q * 20_000.0 / m;
            let h = f64::from(h);
            let config = Config {
                kind: Kind::PI,
                k,
                ti: h * ti_over_h,
                td: 0.0,
                b,
                c: 0.0,
                tt: tt_over_h.map(|t| t * h),
                h,
                ymin: ymin_frac * y,
                ymax: y,
                dymax: None,
                ..Config::default()
            };
            (config, m)
        })
}

/// Whether the station for `config` on 0..m is refused for reach: None when it is refused for
/// another reason (a coefficient the type cannot hold, which the README states separately).
fn refused_for_reach<T: Scalar>(config: Config<f64>, m: f64) -> Option<bool> {
    let sc = Scaling::new(0.0, m).unwrap();
    match Station::<T, f64>::new(params(config, m / 2.0), sc, limits()) {
        Ok(_) => Some(false),
        Err(EditError::Config(ConfigError::OutOfReach { reach, .. })) => {
            assert!(reach > limit::<T>(), "refused with reach {reach}");
            Some(true)
        }
        Err(_) => None,
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 1 } else { 2000 }))]

    /// README: "a PI on a scale 0..M ... is accepted exactly when max(M, v, R) ≤ L"
    /// (outside a 10⁻⁶ band around L, where rounding decides), in I16F16 and I32F32; `f32`
    /// and `f64` stations accept all of them.
    #[test]
    #[cfg_attr(
        miri,
        ignore = "four stations of four types per case, drawn until one is off the limit's rounding band (33 s for one case interpreted): the closed form is plain f64 arithmetic, and the_worked_examples_hold builds fixed-point stations under Miri; runs natively in every CI run"
    )]
    fn a_fixed_point_station_accepts_a_pi_exactly_when_the_closed_form_fits((config, m) in pi()) {
        for (got, l) in [
            (refused_for_reach::<I16F16>(config, m), limit::<I16F16>()),
            (refused_for_reach::<I32F32>(config, m), limit::<I32F32>()),
        ] {
            let want = reach(&config, m);
            prop_assume!((want / l - 1.0).abs() > 1e-6);
            if let Some(refused) = got {
                prop_assert_eq!(refused, want > l, "reach {} limit {}", want, l);
            }
        }
        let sc = Scaling::new(0.0, m).unwrap();
        prop_assert!(Station::<f64, f64>::new(params(config, m / 2.0), sc, limits()).is_ok());
        let cf = Config {
            kind: config.kind, k: config.k as f32, ti: config.ti as f32, td: 0.0,
            b: config.b as f32, c: 0.0, tt: config.tt.map(|t| t as f32), h: config.h as f32,
            ymin: config.ymin as f32, ymax: config.ymax as f32, dymax: None, n: config.n as f32,
            action: config.action,
        };
        let pf = Parameters { config: cf, setpoint: (m / 2.0) as f32, rfel: 1.0, night_setback: 0.0 };
        let lf = OperatorLimits { output: (0.0, 1000.0), kp: (-1.0, 1e9), ..OperatorLimits::default() };
        prop_assert!(Station::<f32, f32>::new(pf, Scaling::new(0.0, m as f32).unwrap(), lf).is_ok());
    }
}

fn worked(k: f64, b: f64) -> Config<f64> {
    Config {
        kind: Kind::PI,
        k,
        ti: 10.0,
        h: 1.0,
        b,
        ymin: 0.0,
        ymax: 10.0,
        ..Config::default()
    }
}

/// README's worked examples (I16F16, PI, b = 1, Tt unset, h/Ti = 0.1, output 0..10 V):
/// K·M ≤ 27 822, so K up to 278 on 0..100 and up to 0.927 on 0..30 000; K = 2, b = 0 on
/// 0..30 000 is refused.
#[test]
fn the_worked_examples_hold() {
    let st = |k: f64, b: f64, m: f64| {
        Station::<I16F16, f64>::new(
            params(worked(k, b), m / 2.0),
            Scaling::new(0.0, m).unwrap(),
            OperatorLimits::default(),
        )
    };
    assert!(st(278.0, 1.0, 100.0).is_ok());
    assert!(st(279.0, 1.0, 100.0).is_err());
    assert!(st(0.927, 1.0, 30_000.0).is_ok());
    assert!(st(0.928, 1.0, 30_000.0).is_err());
    assert!(st(2.0, 0.0, 30_000.0).is_err());
    // I32F32 holds all of them.
    for (k, b, m) in [
        (279.0, 1.0, 100.0),
        (0.928, 1.0, 30_000.0),
        (2.0, 0.0, 30_000.0),
    ] {
        let s = Station::<I32F32, f64>::new(
            params(worked(k, b), m / 2.0),
            Scaling::new(0.0, m).unwrap(),
            OperatorLimits::default(),
        );
        assert!(s.is_ok(), "{k} {b} {m}: {s:?}");
    }
}

/// README: the check is conservative — a configuration it refuses may run without any
/// saturation: K = 1, b = 1 on 0..30 000 (R = 35 035 > 32 640) is refused by an I16F16 station,
/// yet a `Pid<I16F16>` with it closes a loop over the whole scale with no fault and follows the
/// `f64` controller.
#[test]
fn the_check_is_conservative() {
    let config = worked(1.0, 1.0);
    let sc = Scaling::new(0.0, 30_000.0).unwrap();
    assert!(matches!(
        Station::<I16F16, f64>::new(params(config, 15_000.0), sc, OperatorLimits::default()),
        Err(EditError::Config(ConfigError::OutOfReach { .. }))
    ));
    let mut fixed = Pid::<I16F16>::new(&config).unwrap();
    let mut float = Pid::<f64>::new(&config).unwrap();
    let (mut yf, mut yd) = (0.0f64, 0.0f64);
    for step in 0..600 {
        let r = [0.0, 30_000.0, 5_000.0, 25_000.0, 15_000.0, 30_000.0][step / 100];
        let uf = fixed
            .update(I16F16::from_num(r), I16F16::from_num(yf))
            .to_num::<f64>();
        let ud = float.update(r, yd);
        assert!(!fixed.faults().any(), "fault at {step}");
        assert!((uf - ud).abs() < 0.01, "{step}: {uf} vs {ud}");
        // A plant of gain 3000 per volt, time constant 5 samples.
        yf += (3000.0 * uf - yf) / 5.0;
        yd += (3000.0 * ud - yd) / 5.0;
    }
}

/// README: a float station refuses only a configuration whose terms pass ~3.4e38 (`f32`):
/// K = 1e35 on 0..10 000.
#[test]
fn a_float_station_skips_the_check_and_an_overflow_holds_the_output() {
    let config = Config {
        kind: Kind::PI,
        k: 1e35f32,
        ti: 10.0,
        h: 1.0,
        ..Config::default()
    };
    let limits = OperatorLimits {
        kp: (-1.0, 1e36),
        ..OperatorLimits::default()
    };
    let p = Parameters {
        config,
        setpoint: 5000.0,
        rfel: 1.0,
        night_setback: 0.0,
    };
    let sc = Scaling::new(0.0f32, 10_000.0).unwrap();
    // Accepted: in f32 the products become infinite rather than saturate ...
    let mut station = Station::<f32, f32>::new(p, sc, limits).unwrap();
    let before = station.sample(5000.0);
    assert!(!station.pid().faults().overflow());
    // ... and the update catches the infinity: K·e = 1e35 · 5000 is beyond f32.
    let held = station.sample(0.0);
    assert!(
        station.pid().faults().overflow(),
        "{:?}",
        station.pid().faults()
    );
    assert_eq!(held.to_bits(), before.to_bits(), "the output is held");
    // A gain within I16F16 whose products leave it over this scale is refused before it runs.
    let fits = Parameters {
        config: Config { k: 100.0, ..config },
        ..p
    };
    assert!(matches!(
        Station::<I16F16, f32>::new(fits, sc, limits),
        Err(EditError::Config(ConfigError::OutOfReach { .. }))
    ));
}
