//! `Scalar` is a public trait: a user's own number type computes the controller too. Here a
//! saturating type of this test's own (an `f64` held within ±10¹², no NaN: what a wider fixed
//! point would be) takes the generic path for saturating types, the one neither `f32`/`f64`
//! nor the `fixed` types take (they have paths of their own). It must give what `Pid<f64>`
//! gives, through modes, tracking, feed-forward, limits, rate limits and configuration changes.
#![allow(
    clippy::unwrap_used,
    clippy::float_cmp,
    clippy::arithmetic_side_effects,
    clippy::cast_precision_loss,
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    clippy::indexing_slicing,
    reason = "a test may panic: that is how it fails"
)]

use regler_pid::{Config, Inputs, Kind, Pid, Real, Scalar};

const LIMIT: f64 = 1e12;

/// A saturating number: an `f64` clamped into ±`LIMIT`; a NaN becomes 0 (fixed point has none).
/// Its `*_noting` operations report a saturation, as the fixed-point types' do.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
struct Sat(f64);

impl Sat {
    fn new(v: f64) -> Sat {
        if v.is_nan() {
            Sat(0.0)
        } else {
            Sat(v.clamp(-LIMIT, LIMIT))
        }
    }
}

impl Scalar for Sat {
    const ZERO: Sat = Sat(0.0);
    const MAX: Sat = Sat(LIMIT);
    fn from_real<F: Real>(v: F) -> Sat {
        Sat::new(v.to_f64_exact())
    }
    fn to_real<F: Real>(self) -> F {
        F::from_f64_nearest(self.0)
    }
    fn add(self, rhs: Sat) -> Sat {
        Sat::new(self.0 + rhs.0)
    }
    fn sub(self, rhs: Sat) -> Sat {
        Sat::new(self.0 - rhs.0)
    }
    fn mul(self, rhs: Sat) -> Sat {
        Sat::new(self.0 * rhs.0)
    }
    fn add_noting(self, rhs: Sat, saturated: &mut bool) -> Sat {
        Sat::noting(self.0 + rhs.0, saturated)
    }
    fn sub_noting(self, rhs: Sat, saturated: &mut bool) -> Sat {
        Sat::noting(self.0 - rhs.0, saturated)
    }
    fn mul_noting(self, rhs: Sat, saturated: &mut bool) -> Sat {
        Sat::noting(self.0 * rhs.0, saturated)
    }
    fn is_finite(self) -> bool {
        true
    }
}

impl Sat {
    /// The nearest `Sat`, setting `*saturated` when that is a limit the value went past.
    fn noting(v: f64, saturated: &mut bool) -> Sat {
        let s = Sat::new(v);
        if s.0 != v {
            *saturated = true;
        }
        s
    }
}

fn random(seed: &mut u64) -> f64 {
    *seed ^= *seed << 13;
    *seed ^= *seed >> 7;
    *seed ^= *seed << 17;
    (*seed >> 11) as f64 / (1u64 << 53) as f64
}

#[test]
fn a_saturating_type_of_the_users_own_computes_what_f64_does() {
    let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
    let s = &mut seed;
    // Under Miri 6 configurations (400 natively).
    for case in 0..if cfg!(miri) { 6 } else { 400 } {
        let kind = Kind::ALL[(random(s) * 7.0) as usize % 7];
        let config = Config {
            kind,
            k: 0.2 + 4.0 * random(s),
            ti: 1.0 + 30.0 * random(s),
            td: 5.0 * random(s),
            n: 2.0 + 10.0 * random(s),
            b: random(s),
            c: random(s),
            h: 0.1 + random(s),
            ymin: -50.0,
            ymax: 50.0,
            dymax: if random(s) < 0.3 { Some(5.0) } else { None },
            ..Config::default()
        };
        let mut ours = Pid::<Sat>::new(&config).unwrap();
        let mut reference = Pid::<f64>::new(&config).unwrap();
        for n in 0..150 {
            let what = random(s);
            if what < 0.03 {
                let u = 100.0 * random(s) - 50.0;
                ours.set_manual(Sat(u)).unwrap();
                reference.set_manual(u).unwrap();
            } else if what < 0.08 {
                ours.set_auto();
                reference.set_auto();
            } else if what < 0.09 {
                let changed = Config {
                    k: 0.2 + 4.0 * random(s),
                    b: random(s),
                    ..config
                };
                ours.set_config(&changed).unwrap();
                reference.set_config(&changed).unwrap();
            }
            let (r, y) = (200.0 * random(s) - 100.0, 200.0 * random(s) - 100.0);
            let feedforward = if random(s) < 0.2 {
                10.0 * random(s)
            } else {
                0.0
            };
            let track = (random(s) < 0.1).then(|| 100.0 * random(s) - 50.0);
            let got = ours.update_with(
                Sat(r),
                Sat(y),
                Inputs {
                    feedforward: Sat(feedforward),
                    track: track.map(Sat),
                },
            );
            let want = reference.update_with(r, y, Inputs { feedforward, track });
            assert!(
                (got.0 - want).abs() <= 1e-9 * (1.0 + want.abs()),
                "case {case} ({kind}), sample {n}: {} for {want}",
                got.0
            );
            assert_eq!(ours.mode(), reference.mode());
            assert!(
                (ours.integral().0 - reference.integral()).abs()
                    <= 1e-9 * (1.0 + reference.integral().abs()),
                "case {case}, sample {n}: integral"
            );
        }
    }
}

/// `Faults::overflow`: "a fixed-point product or sum saturated: the output and state were
/// held" — for a saturating type of the user's own too. A controller running normally is given
/// a set-point at the type's end, where P saturates: the overflow fault is raised and the
/// output and integral stay as they were; at sane inputs again it runs on.
#[test]
fn a_saturated_sample_of_the_users_type_is_held_with_the_overflow_fault() {
    // K = 2, and K = 10⁻¹², where the saturated error times the gain is a small P and the
    // integral stays well inside its bounds: held all the same.
    for (kind, k) in Kind::ALL
        .into_iter()
        .flat_map(|kind| [(kind, 2.0), (kind, 1e-12)])
    {
        let config = Config {
            kind,
            k,
            ti: 10.0,
            td: 1.0,
            h: 0.5,
            ymin: -50.0,
            ymax: 50.0,
            ..Config::default()
        };
        let mut pid = Pid::<Sat>::new(&config).unwrap();
        for _ in 0..5 {
            pid.update(Sat(5.0), Sat(3.0));
        }
        let (u, i) = (pid.output(), pid.integral());
        assert!(!pid.faults().any());
        let held = pid.update(Sat(LIMIT), Sat(-LIMIT));
        assert!(pid.faults().overflow(), "{kind}: no overflow fault");
        assert_eq!(held, u, "{kind}: output not held");
        assert_eq!(pid.integral(), i, "{kind}: integral not held");
        pid.clear_faults();
        pid.update(Sat(5.0), Sat(3.0));
        assert!(!pid.faults().any(), "{kind}: still faulted at sane inputs");
    }
}

/// A float-like type of the user's own that keeps NaN and infinities, to check the trait's
/// provided operations against their docs.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
struct Plain(f64);

impl Scalar for Plain {
    const ZERO: Plain = Plain(0.0);
    const MAX: Plain = Plain(f64::MAX);
    fn from_real<F: Real>(v: F) -> Plain {
        Plain(v.to_f64_exact())
    }
    fn to_real<F: Real>(self) -> F {
        F::from_f64_nearest(self.0)
    }
    fn add(self, rhs: Plain) -> Plain {
        Plain(self.0 + rhs.0)
    }
    fn sub(self, rhs: Plain) -> Plain {
        Plain(self.0 - rhs.0)
    }
    fn mul(self, rhs: Plain) -> Plain {
        Plain(self.0 * rhs.0)
    }
    fn is_finite(self) -> bool {
        self.0.is_finite()
    }
}

/// The operations `Scalar` provides, as their docs state them, for a type that takes the
/// defaults: `abs` is |x| (NaN stays NaN), `both_finite` is both `is_finite`, and
/// `magnitude_within(bound)` is |x| ≤ bound, false for NaN and infinities — every pair of
/// values from ±0 to ±MAX, ±∞ and NaN, and bounds from 0 to MAX.
#[test]
fn the_provided_operations_do_what_their_docs_say() {
    let values = [
        f64::NEG_INFINITY,
        -f64::MAX,
        -3.0,
        -2.0,
        -f64::MIN_POSITIVE,
        -0.0,
        0.0,
        f64::MIN_POSITIVE,
        2.0,
        3.0,
        f64::MAX,
        f64::INFINITY,
        f64::NAN,
    ];
    for x in values {
        let abs = Plain(x).abs().0;
        assert!(
            abs == x.abs() || (x.is_nan() && abs.is_nan()),
            "|{x}| = {abs}"
        );
        for y in values {
            assert_eq!(
                Plain::both_finite(Plain(x), Plain(y)),
                x.is_finite() && y.is_finite(),
                "both_finite({x}, {y})"
            );
        }
        for bound in [0.0, 2.0, 3.0, f64::MAX] {
            assert_eq!(
                Plain(x).magnitude_within(Plain(bound)),
                x.is_finite() && x.abs() <= bound,
                "magnitude_within({x}, {bound})"
            );
        }
    }
}
