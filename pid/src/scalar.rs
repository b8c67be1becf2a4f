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
}

macro_rules! float_scalar {
    ($t:ty) => {
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
        }
    };
}

float_scalar!(f32);
float_scalar!(f64);

#[cfg(feature = "fixed")]
macro_rules! fixed_scalar {
    ($fixed:ident, $bound:ident) => {
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
            #[inline(always)]
            fn mul(self, rhs: Self) -> Self {
                self.saturating_mul(rhs)
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                true
            }
        }
    };
}

#[cfg(feature = "fixed")]
fixed_scalar!(FixedI32, LeEqU32);
#[cfg(feature = "fixed")]
fixed_scalar!(FixedI64, LeEqU64);

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
