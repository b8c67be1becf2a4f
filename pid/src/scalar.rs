//! The number types a [`Pid`](crate::Pid) computes in.

use crate::real::Real;

/// A number type the controller computes in: `f32`, `f64`, and with the `fixed` feature any
/// `fixed::FixedI32` / `fixed::FixedI64` (such as `I16F16` and `I32F32`).
///
/// Coefficients are computed once in the configuration's [`Real`] type and converted with
/// [`from_real`](Scalar::from_real); [`Pid::new`](crate::Pid::new) checks that each conversion is
/// close enough. The update then uses only the operations below. For fixed point they saturate and
/// round to nearest, so an update can neither panic nor wrap, nor drift one way.
///
/// Why a trait of our own rather than `num_traits` alone: the floats' arithmetic is plain IEEE
/// (`num_traits::float::FloatCore` gives it, and [`Real`] is built on it), while fixed point must
/// saturate; `num_traits`' `Saturating*` traits have no float implementations, so no single
/// `num_traits` bound covers both.
pub trait Scalar: Copy + PartialOrd + core::fmt::Debug {
    /// Zero.
    const ZERO: Self;
    /// The largest value.
    const MAX: Self;
    /// The nearest value to `v`. Floats: a finite `v` beyond the range saturates at `±MAX`; NaN
    /// and infinities stay NaN and infinities, so a broken reading still reaches the controller's
    /// fault check. Fixed point: saturating, NaN → 0 (check finiteness before converting a
    /// measurement; [`Station`](crate::Station) does).
    #[must_use]
    fn from_real<F: Real>(v: F) -> Self;
    /// The value in a [`Real`] type (nearest; saturating as [`from_real`](Scalar::from_real)).
    #[must_use]
    fn to_real<F: Real>(self) -> F;
    /// [`from_real`](Scalar::from_real) from an `f64`.
    #[inline]
    #[must_use]
    fn from_f64(v: f64) -> Self {
        Self::from_real(v)
    }
    /// [`to_real`](Scalar::to_real) as an `f64`.
    #[inline]
    #[must_use]
    fn to_f64(self) -> f64 {
        self.to_real()
    }
    /// `self + rhs` (saturating for fixed point).
    #[must_use]
    fn add(self, rhs: Self) -> Self;
    /// `self − rhs` (saturating for fixed point).
    #[must_use]
    fn sub(self, rhs: Self) -> Self;
    /// `self × rhs` (saturating and rounded to nearest for fixed point).
    #[must_use]
    fn mul(self, rhs: Self) -> Self;
    /// Whether the value is a finite number (always true for fixed point).
    fn is_finite(self) -> bool;
    /// Whether both values are finite (one test where the type allows it).
    #[inline(always)]
    fn both_finite(a: Self, b: Self) -> bool {
        a.is_finite() && b.is_finite()
    }
    /// Zero for a magnitude so small that products of it would go subnormal (floats only:
    /// below 1e-30 for `f32`, 1e-290 for `f64`).
    /// Subnormal arithmetic costs about a hundred cycles on common CPUs; a decaying filter
    /// state would otherwise slow the controller twenty-fold once the loop has settled.
    #[inline(always)]
    #[must_use]
    fn flush_tiny(self) -> Self {
        self
    }
    /// `self` limited to `lo..=hi` (which must be ordered; never panics).
    #[inline(always)]
    #[must_use]
    fn clamp_within(self, lo: Self, hi: Self) -> Self {
        if self < lo {
            lo
        } else if self > hi {
            hi
        } else {
            self
        }
    }
}

// The flush threshold sits well above the smallest normal (1.2e-38 and 2.2e-308), so that one
// multiply by a filter coefficient cannot go subnormal, and far below any value a controller
// works with.
macro_rules! float_ops {
    ($t:ty, $tiny:expr) => {
        #[inline(always)]
        fn add(self, rhs: $t) -> $t {
            self + rhs
        }
        #[inline(always)]
        fn sub(self, rhs: $t) -> $t {
            self - rhs
        }
        #[inline(always)]
        fn mul(self, rhs: $t) -> $t {
            self * rhs
        }
        #[inline(always)]
        fn is_finite(self) -> bool {
            <$t>::is_finite(self)
        }
        #[inline(always)]
        fn flush_tiny(self) -> $t {
            if self.abs() < $tiny { 0.0 } else { self }
        }
        /// x − x is 0 for a finite x and NaN otherwise: three flops and one compare.
        #[inline(always)]
        #[allow(clippy::float_cmp, reason = "exactly zero is the test")]
        fn both_finite(a: $t, b: $t) -> bool {
            (a - a) + (b - b) == 0.0
        }
    };
}

impl Scalar for f32 {
    const ZERO: f32 = 0.0;
    const MAX: f32 = f32::MAX;
    #[inline(always)]
    fn from_real<F: Real>(v: F) -> f32 {
        v.to_f32_nearest()
    }
    #[inline(always)]
    fn to_real<F: Real>(self) -> F {
        F::from_f32_exact(self)
    }
    float_ops!(f32, 1e-30);
}

impl Scalar for f64 {
    const ZERO: f64 = 0.0;
    const MAX: f64 = f64::MAX;
    #[inline(always)]
    fn from_real<F: Real>(v: F) -> f64 {
        v.to_f64_exact()
    }
    #[inline(always)]
    fn to_real<F: Real>(self) -> F {
        F::from_f64_nearest(self)
    }
    float_ops!(f64, 1e-290);
}

#[cfg(feature = "fixed")]
macro_rules! fixed_scalar {
    ($fixed:ident, $bound:ident, $bits:ty, $wide:ty) => {
        impl<Frac: fixed::types::extra::$bound> Scalar for fixed::$fixed<Frac> {
            const ZERO: Self = Self::ZERO;
            const MAX: Self = Self::MAX;
            fn from_real<F: Real>(v: F) -> Self {
                if v.is_nan() {
                    Self::ZERO
                } else {
                    Self::saturating_from_num(v.to_f64_exact())
                }
            }
            fn to_real<F: Real>(self) -> F {
                F::from_f64_nearest(self.to_num::<f64>())
            }
            #[inline(always)]
            fn add(self, rhs: Self) -> Self {
                self.saturating_add(rhs)
            }
            #[inline(always)]
            fn sub(self, rhs: Self) -> Self {
                self.saturating_sub(rhs)
            }
            /// The product in the double-width integer (it cannot overflow there), rounded to
            /// nearest (half up) as it is shifted back, and clamped once: cheaper than a checked
            /// multiply, and without the downward drift of a plain shift (which rounds toward −∞
            /// and so pulls an integral down by up to one LSB every sample).
            #[inline(always)]
            fn mul(self, rhs: Self) -> Self {
                let wide = <$wide>::from(self.to_bits()).wrapping_mul(<$wide>::from(rhs.to_bits()));
                let half = match Frac::U32 {
                    0 => 0,
                    frac => <$wide>::from(1u8).wrapping_shl(frac.wrapping_sub(1)),
                };
                // |wide| <= 2^(2·bits − 2), so adding half an LSB cannot overflow the wide type.
                let shifted = wide.wrapping_add(half) >> Frac::U32;
                let clamped = if shifted > <$wide>::from(<$bits>::MAX) {
                    <$bits>::MAX
                } else if shifted < <$wide>::from(<$bits>::MIN) {
                    <$bits>::MIN
                } else {
                    #[allow(clippy::cast_possible_truncation, reason = "range checked above")]
                    let narrow = shifted as $bits;
                    narrow
                };
                Self::from_bits(clamped)
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                true
            }
        }
    };
}

#[cfg(feature = "fixed")]
fixed_scalar!(FixedI32, LeEqU32, i32, i64);
#[cfg(feature = "fixed")]
fixed_scalar!(FixedI64, LeEqU64, i64, i128);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_convert_saturating_and_keep_faults() {
        assert_eq!(<f32 as Scalar>::from_f64(0.5), 0.5f32);
        assert_eq!(<f32 as Scalar>::from_f64(1e39), f32::MAX);
        assert_eq!(<f32 as Scalar>::from_f64(-1e39), f32::MIN);
        assert!(<f32 as Scalar>::from_f64(f64::NAN).is_nan());
        assert_eq!(<f32 as Scalar>::from_real(f32::INFINITY), f32::INFINITY);
        assert_eq!(Scalar::mul(3.0f64, 2.0), 6.0);
        assert!(!Scalar::is_finite(f32::NAN));
    }

    #[cfg(feature = "fixed")]
    #[test]
    fn fixed_saturates_and_never_panics() {
        use fixed::types::{I16F16, I32F32};
        assert_eq!(<I16F16 as Scalar>::from_f64(1e9), I16F16::MAX);
        assert_eq!(<I16F16 as Scalar>::from_f64(-1e9), I16F16::MIN);
        assert_eq!(<I16F16 as Scalar>::from_f64(f64::NAN), I16F16::ZERO);
        assert_eq!(Scalar::mul(I16F16::MAX, I16F16::MAX), I16F16::MAX);
        assert_eq!(Scalar::mul(I16F16::MIN, I16F16::MAX), I16F16::MIN);
        assert_eq!(Scalar::sub(I32F32::MIN, I32F32::ONE), I32F32::MIN);
        assert_eq!(<I32F32 as Scalar>::from_f64(2.25).to_f64(), 2.25);
    }

    /// Every product of two I16F16 values drawn over the whole range is the exact product
    /// rounded to nearest (ties up), saturated: checked against i128 arithmetic.
    #[cfg(feature = "fixed")]
    #[test]
    fn fixed_multiply_rounds_to_nearest() {
        use fixed::types::I16F16;
        let mut x: u32 = 0x1234_5678;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x as i32
        };
        let mut signed_error = 0i128;
        for _ in 0..100_000 {
            let (a, b) = (next() >> (next() & 15), next() >> (next() & 15));
            let exact = i128::from(a) * i128::from(b);
            let want =
                ((exact + (1 << 15)) >> 16).clamp(i128::from(i32::MIN), i128::from(i32::MAX));
            let got = Scalar::mul(I16F16::from_bits(a), I16F16::from_bits(b)).to_bits();
            assert_eq!(i128::from(got), want, "{a} * {b}");
            if want.abs() < i128::from(i32::MAX) {
                signed_error += i128::from(got) * 65536 - exact;
            }
        }
        // Round to nearest: the errors cancel on average (a floor would sum to about −3e9).
        assert!(signed_error.abs() < 100_000 * 65536 / 50, "{signed_error}");
    }
}
