//! `Scaling::count_to_units` over all 4096 counts of many random scales, in `f32` and `f64`,
//! against a reference computed in double-double arithmetic: the ends exact, every count on the
//! scale, never decreasing, and within the stated bound of the exact value.
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    clippy::float_cmp,
    clippy::field_reassign_with_default,
    reason = "a test may panic: that is how it fails"
)]

use regler_pid::{ADC_FULL_SCALE, Scaling, ScalingError};

/// a + b as an unevaluated sum (hi, lo), exactly (Knuth's two-sum).
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// min + (max − min)·count/4095 as (hi, lo), to about 2⁻¹⁰⁰ relative.
fn exact(min: f64, max: f64, count: u16) -> (f64, f64) {
    let c = f64::from(count);
    let (span, span_lo) = two_sum(max, -min);
    let p = span * c;
    let p_lo = span.mul_add(c, -p) + span_lo * c;
    let q = p / 4095.0;
    let q_lo = ((-q).mul_add(4095.0, p) + p_lo) / 4095.0;
    let (s, e) = two_sum(min, q);
    (s, e + q_lo)
}

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    /// A value of random sign, mantissa and exponent in 2^lo..2^hi.
    fn value(&mut self, lo: i32, hi: i32) -> f64 {
        let x = self.next();
        let span = u64::try_from(hi - lo).unwrap();
        let e = i64::from(lo) + i64::try_from(x % span).unwrap();
        let m = 1.0 + (x >> 12) as f64 / (1u64 << 52) as f64;
        let sign = if x >> 63 == 1 { -1.0 } else { 1.0 };
        sign * m * 2f64.powi(i32::try_from(e).unwrap())
    }
    /// A scale: two ends of any magnitudes, a narrow span around a large value, or a span near
    /// the largest the type allows.
    fn scale(&mut self, max_exp: i32) -> (f64, f64) {
        let (a, b) = match self.next() % 4 {
            0 | 1 => (self.value(-30, 40), self.value(-30, 40)),
            2 => {
                let a = self.value(-10, 40);
                (a, a + a.abs() * self.value(-20, -1).abs())
            }
            _ => (
                self.value(max_exp - 14, max_exp - 12),
                self.value(max_exp - 14, max_exp - 12),
            ),
        };
        (a.min(b), a.max(b))
    }
}

macro_rules! sweep {
    ($t:ty, $max_exp:expr, $scales:expr, $seed:expr) => {{
        let mut rng = Rng($seed);
        let eps = f64::from(<$t>::EPSILON);
        let mut accepted = 0;
        for n in 0..$scales {
            let (lo, hi) = if n == 0 {
                (-0.1, 0.2)
            } else {
                rng.scale($max_exp)
            };
            let (min, max) = (lo as $t, hi as $t);
            let Ok(s) = Scaling::new(min, max) else {
                continue;
            };
            accepted += 1;
            let (min64, max64) = (f64::from(min), f64::from(max));
            let bound = 2.0 * eps * (max64 - min64) + eps * min64.abs().max(max64.abs());
            assert_eq!(s.count_to_units(0), Ok(min), "{min:e}..{max:e}");
            assert_eq!(
                s.count_to_units(ADC_FULL_SCALE),
                Ok(max),
                "{min:e}..{max:e}"
            );
            let mut last = min;
            for count in 0..=ADC_FULL_SCALE {
                let got = s.count_to_units(count).unwrap();
                assert!(
                    got.is_finite() && got >= min && got <= max,
                    "{min:e}..{max:e} count {count}: {got:e}"
                );
                assert!(
                    got >= last,
                    "{min:e}..{max:e} count {count}: {got:e} < {last:e}"
                );
                last = got;
                let (hi, lo) = exact(min64, max64, count);
                let error = (f64::from(got) - hi) - lo;
                assert!(
                    error.abs() <= bound,
                    "{min:e}..{max:e} count {count}: off by {error:e} > {bound:e}"
                );
            }
            assert_eq!(
                s.count_to_units(ADC_FULL_SCALE + 1),
                Err(ScalingError::CountOutOfRange { count: 4096 })
            );
        }
        assert!(accepted > $scales / 2, "{accepted} of {}", $scales);
    }};
}

#[test]
fn every_count_of_random_f64_scales_is_exact_at_the_ends_inside_monotonic_and_close() {
    // Under Miri 5 scales (one scale of 4 096 counts takes seconds interpreted).
    sweep!(
        f64,
        1023,
        if cfg!(miri) { 5 } else { 1_000 },
        0x2545_F491_4F6C_DD1D
    );
}

#[test]
fn every_count_of_random_f32_scales_is_exact_at_the_ends_inside_monotonic_and_close() {
    sweep!(
        f32,
        127,
        if cfg!(miri) { 5 } else { 2_000 },
        0x9E37_79B9_7F4A_7C15
    );
}

/// A span whose product with 4095 overflows is refused; every accepted scale converts every
/// count to a finite value (checked over spans around the limit).
#[test]
fn spans_that_overflow_are_refused() {
    assert_eq!(
        Scaling::new(0.0, f64::MAX / 4000.0),
        Err(ScalingError::SpanTooLarge {
            min: 0.0,
            max: f64::MAX / 4000.0
        })
    );
    assert!(matches!(
        Scaling::new(-f32::MAX / 8000.0, f32::MAX / 8000.0),
        Err(ScalingError::SpanTooLarge { .. })
    ));
    assert!(Scaling::new(-f64::MAX, f64::MAX).is_err());
    for k in 3900..4300u32 {
        let top = f64::MAX / f64::from(k);
        for (min, max) in [(0.0, top), (-top / 2.0, top / 2.0), (top / 2.0, top)] {
            if let Ok(s) = Scaling::new(min, max) {
                for count in [1, 2047, 4094, 4095] {
                    assert!(
                        s.count_to_units(count).unwrap().is_finite(),
                        "{min:e}..{max:e}"
                    );
                }
            }
        }
    }
    assert!(Scaling::new(0.0, f64::MAX / 4096.0).is_ok());
    let e = Scaling::new(0.0f32, f32::MAX / 2.0).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("SCALEMAX - SCALEMIN times 4095 must be finite"),
        "{e}"
    );
}
