//! The number types a [`Pid`](crate::Pid) computes in.

/// A number type the controller can run on: `f32`, `f64`, and with the `fixed` feature any
/// `fixed::FixedI32` / `fixed::FixedI64` (such as `I16F16` and `I32F32`).
///
/// Coefficients are converted once from the `f64` [`Config`](crate::Config); the update then uses
/// only these operations. For fixed point they saturate, so an update can neither panic nor wrap.
pub trait Scalar: Copy + PartialOrd + core::fmt::Debug {
    /// Zero.
    const ZERO: Self;
    /// The largest value.
    const MAX: Self;
    /// The nearest value to `v`; saturating at the type's range, and 0 for NaN.
    fn from_f64(v: f64) -> Self;
    /// The value as `f64`.
    fn to_f64(self) -> f64;
    /// `self + rhs` (saturating for fixed point).
    #[must_use]
    fn add(self, rhs: Self) -> Self;
    /// `self − rhs` (saturating for fixed point).
    #[must_use]
    fn sub(self, rhs: Self) -> Self;
    /// `self × rhs` (saturating for fixed point).
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

macro_rules! float_scalar {
    ($t:ty, $tiny:expr) => {
        impl Scalar for $t {
            const ZERO: $t = 0.0;
            const MAX: $t = <$t>::MAX;
            #[allow(
                clippy::cast_possible_truncation,
                reason = "nearest f32 is what is wanted"
            )]
            fn from_f64(v: f64) -> $t {
                v as $t
            }
            fn to_f64(self) -> f64 {
                f64::from(self)
            }
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
        }
    };
}

// Well above the smallest normal (1.2e-38 and 2.2e-308) so that one multiply by a filter
// coefficient cannot go subnormal, far below any value a controller works with.
float_scalar!(f32, 1e-30);
float_scalar!(f64, 1e-290);

#[cfg(feature = "fixed")]
macro_rules! fixed_scalar {
    ($fixed:ident, $bound:ident, $bits:ty, $wide:ty) => {
        impl<Frac: fixed::types::extra::$bound> Scalar for fixed::$fixed<Frac> {
            const ZERO: Self = Self::ZERO;
            const MAX: Self = Self::MAX;
            fn from_f64(v: f64) -> Self {
                if v.is_nan() {
                    Self::ZERO
                } else {
                    Self::saturating_from_num(v)
                }
            }
            fn to_f64(self) -> f64 {
                self.to_num::<f64>()
            }
            #[inline(always)]
            fn add(self, rhs: Self) -> Self {
                self.saturating_add(rhs)
            }
            #[inline(always)]
            fn sub(self, rhs: Self) -> Self {
                self.saturating_sub(rhs)
            }
            /// The product in the double-width integer (it cannot overflow there), shifted back
            /// (rounding toward −∞) and clamped once: cheaper than a checked multiply.
            #[inline(always)]
            fn mul(self, rhs: Self) -> Self {
                let wide = <$wide>::from(self.to_bits()).wrapping_mul(<$wide>::from(rhs.to_bits()));
                let shifted = wide >> Frac::U32;
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
    fn floats_convert_and_compute() {
        assert_eq!(<f32 as Scalar>::from_f64(0.5), 0.5f32);
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
        assert_eq!(Scalar::sub(I32F32::MIN, I32F32::ONE), I32F32::MIN);
        assert_eq!(<I32F32 as Scalar>::from_f64(2.25).to_f64(), 2.25);
    }
}
