//! The number types a [`Pid`](crate::Pid) computes in.

use crate::Pid;
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
    /// Whether arithmetic saturates silently at the type's ends (fixed point), rather than
    /// overflowing to an infinity that the update's finiteness check catches (floats). A
    /// [`Station`](crate::Station) checks the reach of a configuration only for saturating
    /// types. `true` unless a type says otherwise, so a new type is checked.
    const SATURATES: bool = true;
    /// The nearest value to `v`. Floats: a finite `v` beyond the range saturates at `±MAX`; NaN
    /// and infinities stay NaN and infinities, so a broken reading still reaches the controller's
    /// fault check. Fixed point: the nearest value, ties away from zero, saturating at
    /// `MIN`/`MAX`; +∞ → `MAX`, −∞ → `MIN`, NaN → 0 (check finiteness before converting a
    /// measurement; [`Station`](crate::Station) does). No panic path is linked, so a firmware
    /// whose panic handler is undefined links (`footprint/src/bin/pid_fixed_no_panic.rs`).
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
    /// [`add`](Scalar::add), setting `*saturated` when a fixed-point sum saturated (floats
    /// never set it: their overflow is an infinity, which the controller's finiteness check
    /// sees).
    #[inline(always)]
    #[must_use]
    fn add_noting(self, rhs: Self, saturated: &mut bool) -> Self {
        let _ = saturated;
        self.add(rhs)
    }
    /// [`sub`](Scalar::sub), noting saturation as [`add_noting`](Scalar::add_noting).
    #[inline(always)]
    #[must_use]
    fn sub_noting(self, rhs: Self, saturated: &mut bool) -> Self {
        let _ = saturated;
        self.sub(rhs)
    }
    /// [`mul`](Scalar::mul), noting saturation as [`add_noting`](Scalar::add_noting).
    #[inline(always)]
    #[must_use]
    fn mul_noting(self, rhs: Self, saturated: &mut bool) -> Self {
        let _ = saturated;
        self.mul(rhs)
    }
    /// −`self` (saturating for fixed point: −`MIN` is `MAX`). Exact for floats, whose sign
    /// bit it flips (−0 for 0, unlike `ZERO − self`).
    #[inline(always)]
    #[must_use]
    fn neg(self) -> Self {
        Self::ZERO.sub(self)
    }
    /// |`self`| (saturating for fixed point: |`MIN`| is `MAX`). Exact for floats; NaN stays
    /// NaN.
    #[inline(always)]
    #[must_use]
    fn abs(self) -> Self {
        if self < Self::ZERO { self.neg() } else { self }
    }
    /// Whether the value is a finite number (always true for fixed point).
    fn is_finite(self) -> bool;
    /// Whether both values are finite (one test where the type allows it).
    #[inline(always)]
    fn both_finite(a: Self, b: Self) -> bool {
        a.is_finite() && b.is_finite()
    }
    /// Whether |`self`| ≤ `bound` (`bound` ≥ 0); false for NaN and infinities. One test where
    /// a range check would take two.
    #[inline(always)]
    fn magnitude_within(self, bound: Self) -> bool {
        self.is_finite() && self <= bound && self >= Self::ZERO.sub(bound)
    }
    /// The value, with magnitudes so small that products of them would go subnormal moved to 0
    /// or a normal number (floats only). For `f32`: below 2⁻¹²⁵ (2.4e-38) it becomes 0; below
    /// 2⁻⁷⁵ (2.6e-23) it is rounded onto the multiples of 2⁻¹²⁴ (normal numbers), moving by at
    /// most 2⁻²³·(|x| + 2⁻¹⁰⁰); from 2⁻⁷⁵ up it passes unchanged. For `f64` the same with
    /// 2⁻¹⁰¹⁴, 2⁻⁹⁰⁶, 2⁻¹⁰¹³ and 2⁻⁵²·(|x| + 2⁻⁹⁶⁰). Fixed point: unchanged.
    /// Subnormal arithmetic costs about a hundred cycles on common CPUs; a decaying filter
    /// state would otherwise slow the controller twenty-fold once the loop has settled.
    #[inline(always)]
    #[must_use]
    fn flush_tiny(self) -> Self {
        self
    }
    /// Whether [`Pid::update`] takes [`raw_step`](Scalar::raw_step) for its common sample
    /// (fixed point) instead of the generic one. An implementation detail of the fixed-point
    /// types, not meant to be set elsewhere.
    #[doc(hidden)]
    const RAW_PATH: bool = false;
    /// The common sample of a started controller in automatic on the raw integers, or `None`
    /// for the general path (nothing stored). An implementation detail of the fixed-point
    /// types (`pid/src/controller/raw.rs`).
    #[doc(hidden)]
    #[inline(always)]
    #[must_use]
    fn raw_step<const FEEDFORWARD: bool>(
        pid: &mut Pid<Self>,
        setpoint: Self,
        measurement: Self,
        feedforward: Self,
        track: Option<Self>,
    ) -> Option<Self> {
        let _ = (pid, setpoint, measurement, feedforward, track);
        None
    }
    /// The gate exponent of [`raw_step`](Scalar::raw_step) for the coefficients `pid` holds.
    /// An implementation detail of the fixed-point types.
    #[doc(hidden)]
    #[inline(always)]
    #[must_use]
    fn raw_gate(pid: &Pid<Self>) -> u8 {
        let _ = pid;
        0
    }
    /// `self` limited to `lo..=hi` (which must be ordered; never panics). NaN stays NaN, so a
    /// fault still reaches the controller's check.
    ///
    /// Two independent selects (first the lower bound, then the upper), not an `if … else if`:
    /// for ordered bounds the result is the same, and a float clamp becomes one `max` and one
    /// `min` instruction instead of a compare-and-blend chain.
    #[inline(always)]
    #[must_use]
    fn clamp_within(self, lo: Self, hi: Self) -> Self {
        let above = if self < lo { lo } else { self };
        if above > hi { hi } else { above }
    }
}

// The flush anchors: 2⁻¹⁰⁰ (7.9e-31) and 2⁻⁹⁶⁰ (1.0e-289). Half an ulp of each (2⁻¹²⁴, 2⁻¹⁰¹³)
// is still a normal number (the smallest are 2⁻¹²⁶ and 2⁻¹⁰²²), and both sit far below any value
// a controller works with.
const F32_FLUSH_ANCHOR: f32 = f32::from_bits((127 - 100) << 23);
const F64_FLUSH_ANCHOR: f64 = f64::from_bits((1023 - 960) << 52);

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
        fn neg(self) -> $t {
            -self
        }
        #[inline(always)]
        fn abs(self) -> $t {
            <$t>::abs(self)
        }
        #[inline(always)]
        fn is_finite(self) -> bool {
            <$t>::is_finite(self)
        }
        #[inline(always)]
        fn magnitude_within(self, bound: $t) -> bool {
            self.abs() <= bound
        }
        /// Adding and subtracting the anchor: two flops and no compare. Exact where the anchor
        /// is below half an ulp of x (|x| ≥ 2²⁵ anchors for f32, 2⁵⁴ for f64); anything
        /// smaller comes out as 0 or a multiple of half the anchor's ulp, still a normal
        /// number: a decaying state ends on 0 or a few such steps, never on a subnormal.
        #[inline(always)]
        fn flush_tiny(self) -> $t {
            (self + $tiny) - $tiny
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
    const SATURATES: bool = false;
    #[inline(always)]
    fn from_real<F: Real>(v: F) -> f32 {
        v.to_f32_nearest()
    }
    #[inline(always)]
    fn to_real<F: Real>(self) -> F {
        F::from_f32_exact(self)
    }
    float_ops!(f32, F32_FLUSH_ANCHOR);
}

impl Scalar for f64 {
    const ZERO: f64 = 0.0;
    const MAX: f64 = f64::MAX;
    const SATURATES: bool = false;
    #[inline(always)]
    fn from_real<F: Real>(v: F) -> f64 {
        v.to_f64_exact()
    }
    #[inline(always)]
    fn to_real<F: Real>(self) -> F {
        F::from_f64_nearest(self)
    }
    float_ops!(f64, F64_FLUSH_ANCHOR);
}

#[cfg(feature = "fixed")]
macro_rules! fixed_scalar {
    ($fixed:ident, $bound:ident, $bits:ty, $wide:ty) => {
        impl<Frac: fixed::types::extra::$bound> Scalar for fixed::$fixed<Frac> {
            const ZERO: Self = Self::ZERO;
            const MAX: Self = Self::MAX;
            const RAW_PATH: bool = true;
            #[inline(always)]
            fn raw_step<const FEEDFORWARD: bool>(
                pid: &mut Pid<Self>,
                setpoint: Self,
                measurement: Self,
                feedforward: Self,
                track: Option<Self>,
            ) -> Option<Self> {
                crate::controller::raw::step::<Self, $bits, FEEDFORWARD>(
                    pid,
                    setpoint,
                    measurement,
                    feedforward,
                    track,
                    Frac::U32,
                    Self::to_bits,
                    Self::from_bits,
                )
            }
            fn raw_gate(pid: &Pid<Self>) -> u8 {
                // 2^-frac (frac <= 64): the exponent field of an f64 set directly.
                let lsb = f64::from_bits(u64::from(1023u32.saturating_sub(Frac::U32)) << 52);
                crate::controller::raw::gate::<Self, $bits>(pid, lsb, Self::MAX.to_num::<f64>())
            }
            /// Scaled by 2^frac (exact: a power of two), rounded to nearest with ties away
            /// from zero, saturated; NaN → 0, +∞ → `MAX`, −∞ → `MIN`. Written out rather than
            /// `saturating_from_num`, which links a `panic!` for NaN: a firmware whose panic
            /// handler is undefined would not link (`footprint/src/bin/pid_fixed_no_panic.rs`).
            fn from_real<F: Real>(v: F) -> Self {
                // 2^frac (frac <= 64): the exponent field of an f64 set directly.
                let exponent = 1023u64.saturating_add(u64::from(Frac::U32));
                let pow2 = f64::from_bits(exponent.wrapping_shl(52));
                #[allow(clippy::arithmetic_side_effects, reason = "f64: cannot panic")]
                let scaled = v.to_f64_exact() * pow2;
                let bits = nearest_i64(scaled);
                Self::from_bits(<$bits>::try_from(bits).unwrap_or(if bits < 0 {
                    <$bits>::MIN
                } else {
                    <$bits>::MAX
                }))
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
            fn add_noting(self, rhs: Self, saturated: &mut bool) -> Self {
                let (sum, wrapped) = self.overflowing_add(rhs);
                *saturated |= wrapped;
                if wrapped {
                    self.saturating_add(rhs)
                } else {
                    sum
                }
            }
            #[inline(always)]
            fn sub_noting(self, rhs: Self, saturated: &mut bool) -> Self {
                let (difference, wrapped) = self.overflowing_sub(rhs);
                *saturated |= wrapped;
                if wrapped {
                    self.saturating_sub(rhs)
                } else {
                    difference
                }
            }
            #[inline(always)]
            fn mul_noting(self, rhs: Self, saturated: &mut bool) -> Self {
                let product = Scalar::mul(self, rhs);
                // The rounded product saturated exactly when it lies at an end of the range
                // and the exact one is beyond it: recomputed in the double width.
                if product == Self::MAX || product == Self::MIN {
                    let wide =
                        <$wide>::from(self.to_bits()).wrapping_mul(<$wide>::from(rhs.to_bits()));
                    let half = match Frac::U32 {
                        0 => 0,
                        frac => <$wide>::from(1u8).wrapping_shl(frac.wrapping_sub(1)),
                    };
                    let shifted = wide.wrapping_add(half) >> Frac::U32;
                    *saturated |= shifted > <$wide>::from(<$bits>::MAX)
                        || shifted < <$wide>::from(<$bits>::MIN);
                }
                product
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                true
            }
            #[inline(always)]
            fn magnitude_within(self, bound: Self) -> bool {
                self.to_bits().unsigned_abs() <= bound.to_bits().unsigned_abs()
            }
        }
    };
}

/// `x` rounded to the nearest integer, ties away from zero, saturated to `i64`; NaN → 0. No
/// panic path: the float-to-integer casts saturate.
#[cfg(feature = "fixed")]
#[allow(
    clippy::cast_possible_truncation,
    clippy::cast_precision_loss,
    clippy::arithmetic_side_effects,
    reason = "the casts saturate (and are exact where it matters, see below); f64 arithmetic cannot panic"
)]
fn nearest_i64(x: f64) -> i64 {
    // Truncation toward zero, saturating (NaN → 0). Below 2⁵² in magnitude, x − t is the exact
    // fraction; from 2⁵² up x is an integer, so t = x exactly (or saturated) and the rest is 0
    // (or of the sign that keeps the saturation).
    let t = x as i64;
    let rest = x - t as f64;
    if rest >= 0.5 {
        t.saturating_add(1)
    } else if rest <= -0.5 {
        t.saturating_sub(1)
    } else {
        t
    }
}

#[cfg(feature = "fixed")]
fixed_scalar!(FixedI32, LeEqU32, i32, i64);
#[cfg(feature = "fixed")]
fixed_scalar!(FixedI64, LeEqU64, i64, i128);

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples in the sweeps below: two million natively; under Miri, which interprets every
    /// instruction, 2 048 (every f64 exponent is still visited, every f32 one eight times).
    const SWEEP: u32 = if cfg!(miri) { 2_048 } else { 2_000_000 };

    /// 2^e, exactly, for a normal exponent (−1022 ≤ e ≤ 1023). `powi`'s precision is unspecified
    /// (Miri perturbs it on purpose), so a check's constants are built from their bits.
    fn pow2(e: i32) -> f64 {
        f64::from_bits(u64::try_from(1023 + e).unwrap_or(0) << 52)
    }

    /// 2^e as an `f32`, exactly, for a normal exponent (−126 ≤ e ≤ 127).
    fn pow2f(e: i32) -> f32 {
        f32::from_bits(u32::try_from(127 + e).unwrap_or(0) << 23)
    }

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

    #[test]
    fn neg_and_abs_are_exact_for_floats_and_saturate_for_fixed() {
        for x in [0.0f32, -0.0, 1.5, -2.5, f32::MAX, f32::MIN, f32::INFINITY] {
            assert_eq!(Scalar::neg(x).to_bits(), (-x).to_bits());
            assert_eq!(Scalar::abs(x).to_bits(), x.abs().to_bits());
        }
        assert!(Scalar::abs(f64::NAN).is_nan());
        #[cfg(feature = "fixed")]
        {
            use fixed::types::I16F16;
            assert_eq!(Scalar::neg(I16F16::MIN), I16F16::MAX);
            assert_eq!(Scalar::abs(I16F16::MIN), I16F16::MAX);
            assert_eq!(Scalar::abs(I16F16::from_num(-3)), I16F16::from_num(3));
            assert_eq!(Scalar::neg(I16F16::from_num(2)), I16F16::from_num(-2));
        }
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

    /// The conversion is the nearest value, ties away from zero, saturated; NaN → 0 and the
    /// infinities saturate: checked against `f64::round` (ties away) in i128 over values of
    /// every exponent, sign and many mantissas, and against the `fixed` crate's own conversion
    /// off the ties (it rounds ties to even).
    #[cfg(feature = "fixed")]
    #[test]
    fn fixed_from_real_is_nearest_and_saturating_everywhere() {
        use fixed::types::{I0F32, I16F16, I32F0, I32F32, I48F16};
        macro_rules! check {
            ($t:ty, $v:expr) => {{
                let v: f64 = $v;
                let got = <$t as Scalar>::from_f64(v).to_bits();
                let x = v * pow2(<$t>::FRAC_NBITS as i32);
                let (lo, hi) = (
                    i128::from(<$t>::MIN.to_bits()),
                    i128::from(<$t>::MAX.to_bits()),
                );
                let want = if v.is_nan() {
                    0
                } else {
                    (x.round() as i128).clamp(lo, hi)
                };
                assert_eq!(i128::from(got), want, "{} {v:e}", stringify!($t));
                if !v.is_nan() && x.fract().abs() != 0.5 {
                    assert_eq!(got, <$t>::saturating_from_num(v).to_bits(), "{v:e}");
                }
                // Through f32 too (exact widening), as a Station<_, f32> converts.
                let narrow = v as f32;
                let x32 = f64::from(narrow) * pow2(<$t>::FRAC_NBITS as i32);
                let want32 = if narrow.is_nan() {
                    0
                } else {
                    (x32.round() as i128).clamp(lo, hi)
                };
                assert_eq!(
                    i128::from(<$t as Scalar>::from_real(narrow).to_bits()),
                    want32,
                    "{narrow:e}"
                );
            }};
        }
        let mut x: u64 = 0x2545_F491_4F6C_DD1D;
        let specials = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -2.5,
            f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
            f64::MAX,
            f64::MIN,
            32768.0,
            -32768.0,
            32767.99999,
            pow2(31),
            -pow2(31),
            pow2(63),
            -pow2(63),
            pow2(52) + 1.0,
            0.5 - f64::EPSILON / 4.0,
        ];
        let randoms = (0..u64::from(SWEEP) / 10).map(|n| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            // Exponents from 2^-70 to 2^70 (where every type goes from 0 to saturated), and now
            // and then one anywhere; ties made on purpose every eighth value.
            let e = if n % 16 == 0 {
                x >> 53 & 0x7FF
            } else {
                1023 - 70 + (x >> 40) % 141
            };
            let v = f64::from_bits((x & 0x800F_FFFF_FFFF_FFFF) | (e << 52));
            if n % 8 == 1 {
                (v * 65536.0).trunc() / 65536.0 + 0.5 / 65536.0
            } else {
                v
            }
        });
        for v in specials.into_iter().chain(randoms) {
            check!(I16F16, v);
            check!(I32F32, v);
            check!(I0F32, v);
            check!(I32F0, v);
            check!(I48F16, v);
        }
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
        for _ in 0..SWEEP / 20 {
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

    /// Bits spread over the whole f32 range: every exponent, with mantissas from a xorshift.
    fn f32_samples() -> impl Iterator<Item = f32> {
        let mut x: u32 = 0x9E37_79B9;
        (0..SWEEP).map(move |n| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            // The exponent walks through all 256 values; sign and mantissa are random.
            let exponent = (n % 256) << 23;
            f32::from_bits((x & 0x807F_FFFF) | exponent)
        })
    }

    #[test]
    fn flush_never_leaves_a_subnormal_and_keeps_every_working_value() {
        for x in f32_samples().chain([0.0, -0.0, f32::MIN_POSITIVE, -f32::MIN_POSITIVE]) {
            let got = Scalar::flush_tiny(x);
            if x.is_nan() {
                assert!(got.is_nan());
                continue;
            }
            assert!(!got.is_subnormal(), "{x:e} -> {got:e}");
            if x.abs() >= pow2f(-75) || x.is_infinite() {
                assert_eq!(got.to_bits(), x.to_bits(), "{x:e} changed");
            } else {
                let error = f64::from(got) - f64::from(x);
                let allowed = pow2(-23) * (f64::from(x.abs()) + pow2(-100));
                assert!(error.abs() <= allowed, "{x:e} -> {got:e}");
                assert_eq!(got % pow2f(-124), 0.0, "{x:e} -> {got:e} off the grid");
            }
            if x.abs() < pow2f(-125) {
                assert_eq!(got, 0.0, "{x:e}");
            }
        }
        let mut x: u64 = 0x2545_F491_4F6C_DD1D;
        for n in 0..u64::from(SWEEP) {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f64::from_bits((x & 0x800F_FFFF_FFFF_FFFF) | ((n % 2048) << 52));
            let got = Scalar::flush_tiny(v);
            if v.is_nan() {
                assert!(got.is_nan());
                continue;
            }
            assert!(!got.is_subnormal(), "{v:e} -> {got:e}");
            if v.abs() >= pow2(-906) || v.is_infinite() {
                assert_eq!(got.to_bits(), v.to_bits(), "{v:e} changed");
            } else {
                // Scaled up by 2¹⁰⁰⁰ so the check's own arithmetic stays normal.
                let (g, w) = (got * pow2(1000), v * pow2(1000));
                let allowed = pow2(-52) * (w.abs() + pow2(40));
                assert!((g - w).abs() <= allowed, "{v:e} -> {got:e}");
                assert_eq!(got % pow2(-1013), 0.0, "{v:e} -> {got:e} off the grid");
            }
            if v.abs() < pow2(-1014) {
                assert_eq!(got, 0.0, "{v:e}");
            }
        }
    }

    #[test]
    fn clamp_and_magnitude_agree_with_std_and_keep_nan() {
        let bounds = [
            (0.0f32, 0.0f32),
            (-1.0, 1.0),
            (-5.0, 3.0),
            (2.0, 1e30),
            (-f32::MAX, f32::MAX),
        ];
        for x in f32_samples().step_by(7) {
            for (lo, hi) in bounds {
                let got = Scalar::clamp_within(x, lo, hi);
                if x.is_nan() {
                    assert!(got.is_nan());
                } else {
                    assert_eq!(got, x.clamp(lo, hi), "{x} in [{lo}, {hi}]");
                }
                let bound = hi.abs();
                assert_eq!(
                    Scalar::magnitude_within(x, bound),
                    x.is_finite() && x.abs() <= bound,
                    "|{x}| <= {bound}"
                );
            }
        }
    }

    #[cfg(feature = "fixed")]
    #[test]
    fn fixed_magnitude_matches_the_default_everywhere() {
        use fixed::types::I16F16;
        let mut x: u32 = 0x0BAD_F00D;
        for _ in 0..SWEEP / 10 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            let v = I16F16::from_bits(x as i32);
            let bound = I16F16::from_bits((x.rotate_left(7) as i32) >> (x & 31)).abs();
            let wide = i64::from(v.to_bits()).abs() <= i64::from(bound.to_bits());
            assert_eq!(Scalar::magnitude_within(v, bound), wide, "{v} {bound}");
        }
        assert!(!Scalar::magnitude_within(I16F16::MIN, I16F16::MAX));
        assert!(Scalar::magnitude_within(I16F16::MAX, I16F16::MAX));
    }
}
