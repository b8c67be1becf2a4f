//! The number type of a configuration and of the operator layer: `f32` or `f64`.

use core::fmt;

use num_traits::float::FloatCore;

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for f64 {}
}

/// A floating-point type a [`Config`](crate::Config), the operator layer and [`Scaling`](crate::Scaling)
/// can be written in: `f32` or `f64` (sealed).
///
/// Built on [`num_traits::float::FloatCore`], which needs neither `std` nor `libm`. Firmware on a
/// single-precision FPU (Cortex-M4F) writes its configuration in `f32` so that it links no `f64`
/// arithmetic; the `f64` path is the exact reference.
pub trait Real:
    FloatCore + Default + fmt::Debug + fmt::Display + Send + Sync + 'static + sealed::Sealed
{
    /// A small integer, exactly.
    fn from_u16(n: u16) -> Self;
    /// The value as `f32`: nearest, a finite value beyond `f32`'s range saturates at `±f32::MAX`,
    /// NaN and infinities stay what they are.
    fn to_f32_nearest(self) -> f32;
    /// The value as `f64` (exact).
    fn to_f64_exact(self) -> f64;
    /// The nearest value to an `f32` (exact).
    fn from_f32_exact(v: f32) -> Self;
    /// The nearest value to an `f64`, saturating like [`to_f32_nearest`](Real::to_f32_nearest).
    fn from_f64_nearest(v: f64) -> Self;
}

impl Real for f32 {
    #[inline(always)]
    fn from_u16(n: u16) -> f32 {
        f32::from(n)
    }
    #[inline(always)]
    fn to_f32_nearest(self) -> f32 {
        self
    }
    #[inline(always)]
    fn to_f64_exact(self) -> f64 {
        f64::from(self)
    }
    #[inline(always)]
    fn from_f32_exact(v: f32) -> f32 {
        v
    }
    fn from_f64_nearest(v: f64) -> f32 {
        v.to_f32_nearest()
    }
}

impl Real for f64 {
    #[inline(always)]
    fn from_u16(n: u16) -> f64 {
        f64::from(n)
    }
    fn to_f32_nearest(self) -> f32 {
        #[allow(
            clippy::cast_possible_truncation,
            reason = "range checked: finite values saturate"
        )]
        let narrow = self as f32;
        if self.is_finite() && narrow.is_infinite() {
            if self > 0.0 { f32::MAX } else { f32::MIN }
        } else {
            narrow
        }
    }
    #[inline(always)]
    fn to_f64_exact(self) -> f64 {
        self
    }
    #[inline(always)]
    fn from_f32_exact(v: f32) -> f64 {
        f64::from(v)
    }
    #[inline(always)]
    fn from_f64_nearest(v: f64) -> f64 {
        v
    }
}

/// `a + b` rounded, and its rounding error exactly (Knuth's two-sum: no condition on the
/// magnitudes; exact unless the sum overflows). The compensated sums of the step
/// identification and of the actuator's position estimate both rest on it.
#[allow(
    clippy::arithmetic_side_effects,
    reason = "float arithmetic on Real (f32 or f64): it cannot panic or wrap"
)]
pub(crate) fn two_sum<F: Real>(a: F, b: F) -> (F, F) {
    let sum = a + b;
    let b_part = sum - a;
    let a_part = sum - b_part;
    (sum, (a - a_part) + (b - b_part))
}

/// Compensated summation: the sum as an unevaluated pair `sum + carry`, the carry below half an
/// ulp of the sum. Each term's rounding error is computed exactly (Knuth's two-sum) and added
/// to the carry, and the carry is folded back into the sum at once, so it never grows. Each
/// term then loses at most about u² times the partial sum (u the unit roundoff), in the
/// rounding of `carry + error`: without cancellation the result is within an ulp of the sum
/// (10⁶ tenths in `f32`), but where the terms cancel the error is bounded by N·u²·max|partial
/// sum|, not by the final sum (an attack found 4 terms 16 384 ulps off an exact 8.3·10⁻⁵).
/// Neumaier's form, which lets the carry collect every error and adds it at the end, sums the
/// carry plainly: 10⁶ tenths in `f32` came to 99 994.2 instead of 100 000.0 (a plain sum is 1 %
/// off). The step identification's means and areas and the actuator's pending change use it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sum<F> {
    sum: F,
    carry: F,
}

#[allow(
    clippy::arithmetic_side_effects,
    reason = "float arithmetic on Real (f32 or f64): it cannot panic or wrap"
)]
impl<F: Real> Sum<F> {
    pub(crate) fn new() -> Self {
        Self {
            sum: F::zero(),
            carry: F::zero(),
        }
    }

    /// The pair holding `v` exactly.
    pub(crate) fn of(v: F) -> Self {
        Self {
            sum: v,
            carry: F::zero(),
        }
    }

    pub(crate) fn add(&mut self, v: F) {
        let (t, error) = two_sum(self.sum, v);
        let (sum, carry) = two_sum(t, self.carry + error);
        self.sum = sum;
        self.carry = carry;
    }

    /// The pair rounded to the type: `sum` itself, as every `add` leaves the pair normalised
    /// (`sum` is `sum + carry` rounded, and the carry what that rounding left), so adding the
    /// carry back would give `sum` again, ties included. Where a term overflowed, `sum` is
    /// infinite (and the carry NaN).
    pub(crate) fn value(self) -> F {
        self.sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn narrowing_saturates_finite_values_and_keeps_faults() {
        assert_eq!(1e39f64.to_f32_nearest(), f32::MAX);
        assert_eq!((-1e300f64).to_f32_nearest(), f32::MIN);
        assert_eq!(f64::INFINITY.to_f32_nearest(), f32::INFINITY);
        assert!(f64::NAN.to_f32_nearest().is_nan());
        assert_eq!(0.1f64.to_f32_nearest(), 0.1f32);
        assert_eq!(<f32 as Real>::from_f64_nearest(-1e40), f32::MIN);
    }

    #[test]
    fn two_sum_is_exact_whichever_operand_is_larger() {
        // A small operand with bits below the larger one's ulp: the error is all of it, in
        // either order (the fast form, which assumes |a| ≥ |b|, loses it when a is the small one).
        let small = f64::from_bits(0x3C30_0000_0000_0001); // 2⁻⁶⁰·(1 + 2⁻⁵²)
        assert_eq!(two_sum(small, 1.0), (1.0, small));
        assert_eq!(two_sum(1.0, small), (1.0, small));
        let small = f32::from_bits(0x2D80_0001); // 2⁻³⁶·(1 + 2⁻²³)
        assert_eq!(two_sum(small, -1.0f32), (-1.0, small));
        // A half-way sum rounds to even; the error is what was rounded off, exactly.
        let (sum, error) = two_sum(1.0f64, f64::EPSILON / 2.0);
        assert_eq!((sum, error), (1.0, f64::EPSILON / 2.0));
        let (sum, error) = two_sum(1.0 + f64::EPSILON, f64::EPSILON / 2.0);
        assert_eq!(
            (sum, error),
            (1.0 + 2.0 * f64::EPSILON, -f64::EPSILON / 2.0)
        );
    }
}
