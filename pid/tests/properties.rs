//! The controller against the reference algorithm of the design, and its safety properties.
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "a test may panic: that is how it fails"
)]

use proptest::prelude::{ProptestConfig, any, prop, prop_assert, proptest};
use proptest::strategy::Strategy;
use regler_pid::{Action, Config, Kind, Pid};

/// The reference algorithm, written out as the design states it.
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
        let p = if c.kind.has_p() {
            s * c.k * (c.b * r - y)
        } else {
            0.0
        };
        self.d = ad * self.d - s * bd * ((y - c.c * r) - (self.y_old - c.c * self.r_old));
        let v = p + self.i + self.d;
        let mut u = v;
        if let Some(dymax) = c.dymax {
            u = u.clamp(self.u_old - dymax, self.u_old + dymax);
        }
        u = u.clamp(c.ymin, c.ymax);
        if c.kind.has_i() {
            self.i += s * bi * (r - y) + ao * (u - v);
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
            prop::option::of(0.05f64..50.0),
            0.01f64..5.0,
        ),
        (-50.0f64..0.0, 0.0f64..50.0, prop::option::of(0.01f64..10.0)),
    )
        .prop_map(
            |((kind, reverse, k, ti, td, n), (b, c, tt, h), (ymin, ymax, dymax))| Config {
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
                tt,
                h,
                ymin,
                ymax,
                dymax,
            },
        )
}

/// Configurations of the kinds with an integral term (bumplessness needs one).
fn config_with_i() -> impl Strategy<Value = Config> {
    (
        config(),
        prop::sample::select(vec![Kind::I, Kind::PI, Kind::ID, Kind::PID]),
    )
        .prop_map(|(c, kind)| Config { kind, ..c })
}

fn signal() -> impl Strategy<Value = Vec<(f64, f64)>> {
    prop::collection::vec((-100.0f64..100.0, -100.0f64..100.0), 1..200)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1.0)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn f64_matches_the_reference(config in config(), inputs in signal()) {
        let mut pid = Pid::<f64>::new(&config).unwrap();
        let mut reference = Reference::new(config);
        for (r, y) in inputs {
            let (a, b) = (pid.update(r, y), reference.update(r, y));
            prop_assert!(close(a, b), "{a} vs {b}");
        }
    }
}

proptest! {
    #[test]
    fn output_within_limits_rate_limited_and_finite(
        config in config(),
        inputs in prop::collection::vec((any::<f32>(), any::<f32>()), 1..200),
    ) {
        let mut pid = Pid::<f32>::new(&config).unwrap();
        let (lo, hi) = (config.ymin as f32, config.ymax as f32);
        let mut prev = pid.output();
        for (r, y) in inputs {
            let u = pid.update(r, y);
            prop_assert!(u.is_finite());
            prop_assert!(u >= lo && u <= hi, "{u} outside [{lo}, {hi}]");
            if let Some(dymax) = config.dymax {
                // A clamp into the limits may pull further only toward them.
                let step = (u - prev).abs();
                prop_assert!(step <= dymax as f32 * 1.0001 + 1e-5 || u == lo || u == hi, "step {step} > {dymax}");
            }
            prev = u;
        }
    }

    /// After a long saturation, the output leaves the limit within a few samples of the error
    /// changing sign.
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
        for _ in 0..2000 {
            pid.update(s * 10.0, 0.0); // far from the set-point: saturated at ymax
        }
        prop_assert!(pid.output() == 1.0);
        let mut left = None;
        for n in 0..5 {
            if pid.update(-s * 0.5, 0.0) < 1.0 {
                left = Some(n);
                break;
            }
        }
        prop_assert!(left.is_some(), "still saturated 5 samples after the error changed sign");
    }

    /// A commit with the error at zero does not move the output.
    #[test]
    fn bumpless_commit(before in config_with_i(), after in config_with_i(), level in -10.0f64..10.0) {
        let wide = |c: Config| Config { ymin: -1e6, ymax: 1e6, dymax: None, ..c };
        let (before, after) = (wide(before), wide(after));
        let mut pid = Pid::<f64>::new(&before).unwrap();
        for _ in 0..50 {
            pid.update(level, level);
        }
        let u0 = pid.update(level, level);
        pid.set_config(&after).unwrap();
        let u1 = pid.update(level, level);
        prop_assert!((u1 - u0).abs() <= 1e-9 * u0.abs().max(1.0), "{u0} -> {u1}");
    }
}
