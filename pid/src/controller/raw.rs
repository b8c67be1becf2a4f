//! The fixed-point update: the common sample on the raw integers, with no saturating arithmetic.
//!
//! [`Pid::update`] in fixed point must note every saturation of its products and sums (it
//! holds the output and raises [`Faults::overflow`](crate::Faults::overflow)). Checking each
//! operation costs more than the operations themselves, so this path checks the sample's
//! *inputs* instead: when set-point, measurement, feed-forward, tracking value and the states
//! I, D and y_old − c·r_old all lie within a gate ±g, no product or sum of the sample can leave
//! the type's range, and the update runs on the raw integers with wrapping adds (which then never
//! wrap) and one widening multiply per product, rounded to nearest (ties up) as
//! [`Scalar::mul`](crate::Scalar::mul) rounds. The result is bit for bit the one the checked
//! arithmetic gives. Any sample outside the gate, or whose integral leaves its bounds, goes to
//! the general path, which checks every operation.
//!
//! The gate g = 2^k LSB is chosen by [`gate`] when the coefficients change (`Pid::new`,
//! `Pid::set_config`): the largest k for which each of the sample's values, bounded from the
//! coefficients by the triangle inequality, stays below the type's maximum. Its test costs one
//! add and one or per gated value: x + g (as unsigned) is below 2g exactly when −g ≤ x < g.

use super::{Pid, STARTED};
use crate::scalar::Scalar;

/// The raw integer of a fixed-point type (`i32` for `FixedI32`, `i64` for `FixedI64`): wrapping
/// arithmetic, the rounded product, and the gate's unsigned words.
pub(crate) trait Raw: Copy + Ord {
    /// The unsigned integer of the same width.
    type Word: Copy + core::ops::BitOr<Output = Self::Word> + Ord;
    /// Zero.
    const ZERO: Self;
    /// Bits of the integer.
    const BITS: u32;
    /// `self + rhs`, wrapping.
    fn wadd(self, rhs: Self) -> Self;
    /// `self − rhs`, wrapping.
    fn wsub(self, rhs: Self) -> Self;
    /// |`self`| as an unsigned word.
    fn magnitude(self) -> Self::Word;
    /// The bits of `self` ≥ 0 as an unsigned word.
    fn word(self) -> Self::Word;
    /// `self` + `g` as an unsigned word: below 2g exactly when −g ≤ self < g.
    fn gated(self, g: Self) -> Self::Word;
    /// 2^k (k < BITS), as the integer and as the unsigned 2^(k+1) (0 when k = BITS − 1).
    fn gate(k: u8) -> (Self, Self::Word);
    /// (self·rhs + 2^(frac−1)) >> frac: the product rounded to nearest, ties up. Exact when the
    /// result fits; wraps (and never panics) when it does not.
    fn mul_round(self, rhs: Self, frac: u32) -> Self;
}

impl Raw for i32 {
    type Word = u32;
    const ZERO: i32 = 0;
    const BITS: u32 = 32;
    #[inline(always)]
    fn wadd(self, rhs: i32) -> i32 {
        self.wrapping_add(rhs)
    }
    #[inline(always)]
    fn wsub(self, rhs: i32) -> i32 {
        self.wrapping_sub(rhs)
    }
    #[inline(always)]
    fn magnitude(self) -> u32 {
        self.unsigned_abs()
    }
    #[inline(always)]
    #[allow(clippy::cast_sign_loss, reason = "a value known to be ≥ 0")]
    fn word(self) -> u32 {
        self as u32
    }
    #[inline(always)]
    #[allow(clippy::cast_sign_loss, reason = "the bits as unsigned, on purpose")]
    fn gated(self, g: i32) -> u32 {
        self.wrapping_add(g) as u32
    }
    #[inline(always)]
    #[allow(
        clippy::cast_possible_wrap,
        reason = "2^31 is the disabled gate, on purpose"
    )]
    fn gate(k: u8) -> (i32, u32) {
        let g = 1u32.wrapping_shl(u32::from(k));
        (g as i32, g.wrapping_add(g))
    }
    #[inline(always)]
    fn mul_round(self, rhs: i32, frac: u32) -> i32 {
        mul_round_i32(self, rhs, frac)
    }
}

impl Raw for i64 {
    type Word = u64;
    const ZERO: i64 = 0;
    const BITS: u32 = 64;
    #[inline(always)]
    fn wadd(self, rhs: i64) -> i64 {
        self.wrapping_add(rhs)
    }
    #[inline(always)]
    fn wsub(self, rhs: i64) -> i64 {
        self.wrapping_sub(rhs)
    }
    #[inline(always)]
    fn magnitude(self) -> u64 {
        self.unsigned_abs()
    }
    #[inline(always)]
    #[allow(clippy::cast_sign_loss, reason = "a value known to be ≥ 0")]
    fn word(self) -> u64 {
        self as u64
    }
    #[inline(always)]
    #[allow(clippy::cast_sign_loss, reason = "the bits as unsigned, on purpose")]
    fn gated(self, g: i64) -> u64 {
        self.wrapping_add(g) as u64
    }
    #[inline(always)]
    #[allow(
        clippy::cast_possible_wrap,
        reason = "2^63 is the disabled gate, on purpose"
    )]
    fn gate(k: u8) -> (i64, u64) {
        let g = 1u64.wrapping_shl(u32::from(k));
        (g as i64, g.wrapping_add(g))
    }
    #[inline(always)]
    #[allow(clippy::cast_possible_truncation, reason = "the low bits, on purpose")]
    fn mul_round(self, rhs: i64, frac: u32) -> i64 {
        let wide = i128::from(self).wrapping_mul(i128::from(rhs));
        let half = if frac == 0 {
            0
        } else {
            1i128.wrapping_shl(frac.wrapping_sub(1))
        };
        (wide.wrapping_add(half) >> frac) as i64
    }
}

/// The rounded `FixedI32` product. A core with a 32 × 32 → 64 multiply (x86, Cortex-M3/M4/M7)
/// forms it in one widening multiply.
#[cfg(not(all(target_arch = "arm", not(target_feature = "thumb2"))))]
#[inline(always)]
#[allow(clippy::cast_possible_truncation, reason = "the low bits, on purpose")]
fn mul_round_i32(a: i32, x: i32, frac: u32) -> i32 {
    let wide = i64::from(a).wrapping_mul(i64::from(x));
    let half = if frac == 0 {
        0
    } else {
        1i64.wrapping_shl(frac.wrapping_sub(1))
    };
    (wide.wrapping_add(half) >> frac) as i32
}

/// The rounded `FixedI32` product on a core whose only multiply is 32 × 32 → 32 (Cortex-M0,
/// M0+, M1: ARMv6-M), where an `i64` product is a library call: four 16 × 16 → 32 products of
/// the halves, a = ah·2¹⁶ + al (ah signed, al unsigned), summed modulo 2³², which is exact
/// whenever the result fits (it does on the gated path). For frac ≤ 16 only: the middle
/// products are then shifted left, so the floor of the sum is the sum of the floors.
#[cfg(all(target_arch = "arm", not(target_feature = "thumb2")))]
#[inline(always)]
#[allow(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    clippy::cast_possible_wrap,
    reason = "halves and low words, on purpose"
)]
fn mul_round_i32(a: i32, x: i32, frac: u32) -> i32 {
    if frac > 16 {
        let wide = i64::from(a).wrapping_mul(i64::from(x));
        let half = 1i64.wrapping_shl(frac.wrapping_sub(1));
        return (wide.wrapping_add(half) >> frac) as i32;
    }
    let (ah, al) = (a >> 16, (a as u32) & 0xFFFF);
    let (xh, xl) = (x >> 16, (x as u32) & 0xFFFF);
    // |ah·xl|, |al·xh| < 2³¹ and al·xl + 2¹⁵ < 2³²: each product is exact in 32 bits.
    let high = ah.wrapping_mul(xh);
    let middle = ah
        .wrapping_mul(xl as i32)
        .wrapping_add((al as i32).wrapping_mul(xh));
    let half = if frac == 0 {
        0
    } else {
        1u32.wrapping_shl(frac.wrapping_sub(1))
    };
    let low = (al.wrapping_mul(xl).wrapping_add(half) >> frac) as i32;
    high.wrapping_shl(32u32.wrapping_sub(frac))
        .wrapping_add(middle.wrapping_shl(16u32.wrapping_sub(frac)))
        .wrapping_add(low)
}

/// The common sample of a started controller in automatic on the raw integers, or `None` (the
/// caller then takes the general path; nothing has been stored). Bit for bit the checked
/// update's result: see the module's documentation.
#[inline(always)]
#[allow(
    clippy::too_many_arguments,
    reason = "the sample's inputs and the type's two conversions"
)]
pub(crate) fn step<T: Scalar, R: Raw, const FEEDFORWARD: bool>(
    pid: &mut Pid<T>,
    r: T,
    y: T,
    feedforward: T,
    track: Option<T>,
    frac: u32,
    raw: impl Fn(T) -> R,
    value: impl Fn(R) -> T,
) -> Option<T> {
    let (g, twice) = R::gate(pid.fast_gate);
    let (rr, yr, ir, dr, ydo) = (raw(r), raw(y), raw(pid.i), raw(pid.d), raw(pid.yd_old));
    let u_old = raw(pid.u_old);
    let mut outside =
        rr.gated(g) | yr.gated(g) | ir.gated(g) | dr.gated(g) | ydo.gated(g) | u_old.gated(g);
    let (ffr, trackr) = if FEEDFORWARD {
        let t = track.map(&raw);
        outside = outside | raw(feedforward).gated(g) | t.unwrap_or(rr).gated(g);
        (raw(feedforward), t)
    } else {
        (R::ZERO, None)
    };
    if pid.flags != STARTED || outside >= twice {
        return None;
    }
    let mul = |a: T, x: R| raw(a).mul_round(x, frac);
    // Two independent selects, as `Scalar::clamp_within` (`Ord::clamp` would link a panic).
    let clamp = |x: R, lo: R, hi: R| {
        let above = if x < lo { lo } else { x };
        if above > hi { hi } else { above }
    };
    let p = mul(pid.kp, mul(pid.b, rr).wsub(yr));
    let yd = yr.wsub(mul(pid.c, rr));
    let d_bound = raw(pid.d_bound);
    let d = clamp(
        mul(pid.ad, dr).wsub(mul(pid.bd, yd.wsub(ydo))),
        R::ZERO.wsub(d_bound),
        d_bound,
    );
    let mut v = p.wadd(ir).wadd(d);
    if FEEDFORWARD {
        v = v.wadd(ffr);
    }
    // The rate window u_old ± dymax, whose ends saturate in `compute` (dymax is MAX without a
    // rate limit): the same as limiting v − u_old to ±dymax (v − u_old fits, both being gated),
    // and u lies between u_old and v, so it fits too.
    let dymax = raw(pid.dymax);
    let u = u_old.wadd(clamp(v.wsub(u_old), R::ZERO.wsub(dymax), dymax));
    let u = clamp(u, raw(pid.ymin), raw(pid.ymax));
    let applied = trackr.unwrap_or(u);
    let step = mul(pid.bi, rr.wsub(yr)).wadd(mul(pid.ao, applied.wsub(v)));
    let i = ir.wadd(step);
    let mut centre = mul(pid.offset_slope, rr).wadd(raw(pid.i_mid));
    if FEEDFORWARD && pid.integrates() {
        centre = centre.wsub(ffr);
    }
    // i_half ≥ 0 (ymin ≤ ymax): its magnitude is its bits.
    if centre.wsub(i).magnitude() > raw(pid.i_half).word() {
        return None;
    }
    pid.i = value(i);
    pid.d = value(d);
    pid.yd_old = value(yd);
    pid.r_old = r;
    let u = value(u);
    pid.u_old = track.unwrap_or(u);
    Some(u)
}

/// The gate exponent k for the coefficients `pid` holds (g = 2^k LSB), or `BITS − 1` when no
/// gate keeps the sample in range (the gate test then never passes). `lsb` is the type's
/// smallest step, `max` its largest value, both as `f64`.
///
/// Every value the sample forms is bounded from g by the triangle inequality, each product
/// plus one LSB for its rounding; all must stay below `max`·(1 − 2⁻²⁰) − 4 LSB, a margin that
/// also covers the rounding of this bound in `f64` (53 bits) and of the coefficients' conversion
/// to it. Both shapes are bounded at once: with feed-forward and tracking values within ±g too.
#[allow(
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "f64 arithmetic cannot panic; k < 64"
)]
pub(crate) fn gate<T: Scalar, R: Raw>(pid: &Pid<T>, lsb: f64, max: f64) -> u8 {
    let bits = R::BITS;
    let m = |x: T| x.to_f64().abs();
    let (b, kp, c, ad, bd) = (m(pid.b), m(pid.kp), m(pid.c), m(pid.ad), m(pid.bd));
    let (bi, ao, slope) = (m(pid.bi), m(pid.ao), m(pid.offset_slope));
    let (d_bound, i_mid) = (m(pid.d_bound), m(pid.i_mid));
    let ys = m(pid.ymin).max(m(pid.ymax));
    let limit = max * (1.0 - 1.0 / 1_048_576.0) - 4.0 * lsb;
    let fits = |g: f64| {
        let product = |a: f64, x: f64| a * x + lsb;
        let br = product(b, g);
        let p = product(kp, br + g);
        let yd = g + product(c, g);
        let d_step = product(bd, yd + g);
        let d_raw = product(ad, g) + d_step;
        let v = p + g + d_raw.min(d_bound) + g;
        let integral_step = product(bi, g + g);
        let tracking = product(ao, ys.max(g) + v);
        let i = g + integral_step + tracking;
        let centre = product(slope, g) + i_mid + g;
        [
            g + g,
            br,
            br + g,
            p,
            p + g,
            yd,
            yd + g,
            d_step,
            d_raw,
            v,
            ys.max(g) + v,
            integral_step,
            tracking,
            integral_step + tracking,
            i,
            centre,
            centre + i,
        ]
        .into_iter()
        .all(|x| x <= limit)
    };
    let mut k = bits.saturating_sub(2);
    loop {
        // 2^k, its exponent field set directly (k < 64).
        let g = lsb * f64::from_bits(u64::from(1023 + k) << 52);
        if fits(g) {
            return k as u8;
        }
        if k == 0 {
            return bits.saturating_sub(1) as u8;
        }
        k -= 1;
    }
}
