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
/// forms it in one widening multiply ([`mul_round_wide`]).
///
/// ARMv6-M (Cortex-M0, M0+, M1) has none: there an `i64` product is a library call, and
/// [`mul_round_split`] takes its place. Stable Rust exposes no target feature that says so, but
/// ARMv6-M is also the only M profile without 32-bit atomics (`target_has_atomic = "32"`), which
/// is what selects it (ARMv8-M Baseline, which has atomics but no long multiply, keeps the
/// library call: slower, equally exact).
#[inline(always)]
fn mul_round_i32(a: i32, x: i32, frac: u32) -> i32 {
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    if frac <= 16 {
        return mul_round_split(a, x, frac);
    }
    mul_round_wide(a, x, frac)
}

/// (a·x + 2^(frac−1)) >> frac in one `i64` product.
#[inline(always)]
#[allow(clippy::cast_possible_truncation, reason = "the low bits, on purpose")]
fn mul_round_wide(a: i32, x: i32, frac: u32) -> i32 {
    let wide = i64::from(a).wrapping_mul(i64::from(x));
    let half = if frac == 0 {
        0
    } else {
        1i64.wrapping_shl(frac.wrapping_sub(1))
    };
    (wide.wrapping_add(half) >> frac) as i32
}

/// (a·x + 2^(frac−1)) >> frac for frac ≤ 16 from four 16 × 16 → 32 products of the halves,
/// a = ah·2¹⁶ + al (ah signed, al unsigned): a·x = ah·xh·2³² + (ah·xl + al·xh)·2¹⁶ + al·xl.
/// With frac ≤ 16 the first two terms stay integers when shifted right by frac, so the floor
/// of the sum is theirs plus the floor of the last; all summed modulo 2³², which is exact
/// whenever the result fits (it does on the gated path) and never panics otherwise.
#[cfg(any(test, all(target_arch = "arm", not(target_has_atomic = "32"))))]
#[inline(always)]
#[allow(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    clippy::cast_possible_wrap,
    reason = "halves and low words, on purpose"
)]
fn mul_round_split(a: i32, x: i32, frac: u32) -> i32 {
    let (ah, al) = (a >> 16, (a as u32) & 0xFFFF);
    let (xh, xl) = (x >> 16, (x as u32) & 0xFFFF);
    // |ah·xl|, |al·xh| < 2³¹ and al·xl + 2¹⁵ < 2³²: each product is exact in 32 bits.
    let high = if frac == 0 {
        0
    } else {
        ah.wrapping_mul(xh).wrapping_shl(32u32.wrapping_sub(frac))
    };
    let middle = ah
        .wrapping_mul(xl as i32)
        .wrapping_add((al as i32).wrapping_mul(xh))
        .wrapping_shl(16u32.wrapping_sub(frac));
    let half = if frac == 0 {
        0
    } else {
        1u32.wrapping_shl(frac.wrapping_sub(1))
    };
    let low = (al.wrapping_mul(xl).wrapping_add(half) >> frac) as i32;
    high.wrapping_add(middle).wrapping_add(low)
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
    pid.u_old = pid.held(track, u);
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
        // Every bound is a sum of non-negative terms, so these five cover all the values above
        // and their partial sums (b·r − y is br + g, P + I is below v, the centre and the new
        // integral below their difference's bound, r − y's 2g below the output's bound, which
        // is at least 3g, …).
        (br + g)
            .max(yd + g)
            .max(d_raw)
            .max(ys.max(g) + v)
            .max(centre + i)
            <= limit
    };
    for k in (0..=bits.saturating_sub(2)).rev() {
        // 2^k, its exponent field set directly (k < 64).
        let g = lsb * f64::from_bits(u64::from(1023 + k) << 52);
        if fits(g) {
            return k as u8;
        }
    }
    bits.saturating_sub(1) as u8
}

#[cfg(test)]
mod tests {
    use fixed::types::{I16F16, I32F32, I48F16};
    use fixed::{FixedI32, types::extra::U24};
    use proptest::prelude::{ProptestConfig, any, prop, prop_assert, proptest};
    use proptest::strategy::{Just, Strategy};

    use super::super::{Inputs, Pid, STARTED};
    use crate::Scalar;
    use crate::config::{Action, Config, Kind};

    /// Q8.24: a `FixedI32` whose products take the split path on ARMv6-M only for frac ≤ 16.
    type I8F24 = FixedI32<U24>;

    /// The update as it was before the raw path: the generic common sample, every operation
    /// checked, and the general path. The raw path must give the same, bit for bit. One
    /// difference, on purpose: the acceptance test of the common sample, |centre − I| ≤ i_half,
    /// is taken exactly, where the old one saturated centre − I first and so, with i_half at
    /// the type's maximum, accepted an integral beyond its bounds (see
    /// `an_integral_beyond_bounds_that_span_the_type_is_bounded`).
    fn checked<T: Scalar, const FEEDFORWARD: bool>(
        pid: &mut Pid<T>,
        r: T,
        y: T,
        feedforward: T,
        track: Option<T>,
    ) -> T {
        if pid.flags == STARTED {
            let s = pid.compute::<FEEDFORWARD>(r, y, feedforward, track, pid.yd_old, false);
            let centre = pid.integral_centre(r, pid.bounds_feedforward::<FEEDFORWARD>(feedforward));
            let mut wrapped = false;
            let away = centre.sub_noting(s.i, &mut wrapped);
            if !s.saturated && !wrapped && away.magnitude_within(pid.i_half) {
                return pid.commit(s, r, track);
            }
        }
        pid.step_general::<FEEDFORWARD>(r, y, feedforward, track)
    }

    /// Cases from `PROPTEST_CASES` (256 unless set); two under Miri, whose runs are also
    /// shorter (`RUN`).
    fn cases() -> ProptestConfig {
        let default = ProptestConfig::default();
        ProptestConfig {
            cases: if cfg!(miri) { 2 } else { default.cases },
            ..default
        }
    }

    /// Configurations over many scales: small and large gains, fast and slow integrals and
    /// derivatives, narrow and wide output ranges (many refused by `Pid::new` for a type: skipped).
    fn configs() -> impl Strategy<Value = Config> {
        let kind = prop::sample::select(vec![Kind::P, Kind::I, Kind::PI, Kind::PD, Kind::PID]);
        let log = |lo: f64, hi: f64| (lo.ln()..hi.ln()).prop_map(f64::exp);
        (
            kind,
            any::<bool>(),
            log(1e-3, 1e3),
            log(1e-2, 1e3),
            log(1e-3, 1e2),
            1.0..20.0f64,
            (0.0..2.0f64, 0.0..1.5f64),
            log(1e-3, 1.0),
            prop::option::of(0.6..20.0f64),
            (log(1e-2, 3e4), -1.0..1.0f64),
            prop::option::of(log(1e-3, 1e3)),
        )
            .prop_map(
                |(kind, reverse, k, ti, td, n, (b, c), h, tt, (span, low), dymax)| Config {
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
                    h,
                    tt: tt.map(|t| t * h),
                    ymin: span * low.min(0.0),
                    ymax: span * (low + 1.0).min(1.0),
                    dymax,
                },
            )
    }

    /// [`configs`] with set-point weights b and c from 2 to 40 and a gain from 10⁻³ to 0.3: the
    /// corners where |b·r − y| or |c·r − y| is the largest value a sample forms.
    fn heavy_weights() -> impl Strategy<Value = Config> {
        let log = |lo: f64, hi: f64| (lo.ln()..hi.ln()).prop_map(f64::exp);
        (configs(), log(2.0, 40.0), log(2.0, 40.0), log(1e-3, 0.3))
            .prop_map(|(config, b, c, k)| Config { b, c, k, ..config })
    }

    /// [`configs`] with an output range far from 0 (its centre 1 to 100 times its width away,
    /// either side) and set-point weights b from −10 to 10: the corners where the integral's
    /// centre, offset·r + the range's midpoint, is the largest value a sample forms.
    fn offset_outputs() -> impl Strategy<Value = Config> {
        (configs(), 1.0..100.0f64, any::<bool>(), -10.0..10.0f64).prop_map(
            |(config, away, below, b)| {
                let width = config.ymax - config.ymin;
                let centre = if below { -away } else { away } * width.max(1e-3);
                Config {
                    ymin: centre - width / 2.0,
                    ymax: centre + width / 2.0,
                    b,
                    ..config
                }
            },
        )
    }

    /// One step of a run: a sample (set-point and measurement as raw bits shifted right by a
    /// random count, so every magnitude up to the type's ends comes up), with feed-forward and
    /// tracking now and then, or an operator's action.
    #[derive(Clone, Debug)]
    enum Op {
        Sample(i64, u8, i64, u8),
        With(i64, u8, i64, u8, i64, u8, Option<(i64, u8)>),
        Manual(i64, u8),
        Auto,
        Reset,
    }

    fn ops() -> impl Strategy<Value = Vec<Op>> {
        let value = || (any::<i64>(), 0..64u8);
        let op = prop::strategy::Union::new_weighted(vec![
            (
                12,
                (value(), value())
                    .prop_map(|((r, rs), (y, ys))| Op::Sample(r, rs, y, ys))
                    .boxed(),
            ),
            (
                3,
                (value(), value(), value(), prop::option::of(value()))
                    .prop_map(|((r, rs), (y, ys), (f, fs), t)| Op::With(r, rs, y, ys, f, fs, t))
                    .boxed(),
            ),
            (1, value().prop_map(|(u, s)| Op::Manual(u, s)).boxed()),
            (1, Just(Op::Auto).boxed()),
            (1, Just(Op::Reset).boxed()),
        ]);
        prop::collection::vec(op, 1..RUN * 2)
    }

    /// The longest run of samples a property draws: 60 (operations: 120), 6 under Miri, which
    /// interprets every fixed-point product of four types.
    const RUN: usize = if cfg!(miri) { 6 } else { 60 };

    /// A value from raw bits and a shift: magnitudes from 0 to the type's ends, log-uniform
    /// (a shift of 32 or more in a 32-bit type lands near zero).
    trait FromRaw: Scalar {
        fn from_raw(bits: i64, shift: u8) -> Self;
    }
    macro_rules! from_raw {
        ($($t:ty: $bits:ty),*) => {$(
            impl FromRaw for $t {
                #[allow(clippy::cast_possible_truncation, reason = "a random value's low bits")]
                fn from_raw(bits: i64, shift: u8) -> $t {
                    <$t>::from_bits((bits >> (shift % 64)) as $bits)
                }
            }
        )*};
    }
    from_raw!(I16F16: i32, I8F24: i32, I32F32: i64, I48F16: i64);

    /// Runs `ops` on two copies of one controller, one through `update` (the raw path) and
    /// one through [`checked`]; every output and every state must agree. Returns how many
    /// samples the raw path took.
    fn same_as_checked<T: FromRaw>(config: &Config, ops: &[Op]) -> Result<usize, String> {
        let Ok(mut fast) = Pid::<T>::new(config) else {
            return Ok(0);
        };
        let mut slow = fast.clone();
        let v = T::from_raw;
        let mut taken = 0;
        for (n, op) in ops.iter().enumerate() {
            match *op {
                Op::Sample(r, rs, y, ys) => {
                    let (r, y) = (v(r, rs), v(y, ys));
                    taken += usize::from(
                        T::raw_step::<false>(&mut fast.clone(), r, y, T::ZERO, None).is_some(),
                    );
                    let a = fast.update(r, y);
                    let b = checked::<T, false>(&mut slow, r, y, T::ZERO, None);
                    if a != b || fast != slow {
                        return Err(format!("op {n} {op:?}: {a:?} {b:?}\n{fast:?}\n{slow:?}"));
                    }
                }
                Op::With(r, rs, y, ys, f, fs, t) => {
                    let (r, y, f) = (v(r, rs), v(y, ys), v(f, fs));
                    let track = t.map(|(t, ts)| v(t, ts));
                    taken += usize::from(
                        T::raw_step::<true>(&mut fast.clone(), r, y, f, track).is_some(),
                    );
                    let inputs = Inputs {
                        feedforward: f,
                        track,
                    };
                    let a = fast.update_with(r, y, inputs);
                    let b = checked::<T, true>(&mut slow, r, y, f, track);
                    if a != b || fast != slow {
                        return Err(format!("op {n} {op:?}: {a:?} {b:?}\n{fast:?}\n{slow:?}"));
                    }
                }
                Op::Manual(u, s) => {
                    let _ = fast.set_manual(v(u, s));
                    let _ = slow.set_manual(v(u, s));
                }
                Op::Auto => {
                    fast.set_auto();
                    slow.set_auto();
                }
                Op::Reset => {
                    fast.reset();
                    slow.reset();
                }
            }
        }
        Ok(taken)
    }

    /// The gate's corners are not vacuous: for a PID with feed-forward-sized ranges, most
    /// corners take the raw path in every type (the rest leave the integral's bounds).
    #[test]
    fn the_gate_corners_of_a_pid_take_the_raw_path() {
        let config = Config {
            kind: Kind::PID,
            k: 2.0,
            ti: 5.0,
            td: 0.5,
            h: 0.1,
            ymin: -10.0,
            ymax: 10.0,
            ..Config::default()
        };
        let corners = if cfg!(miri) { 2 * 14 } else { 2 * 512 };
        for (name, taken) in [
            (
                "I16F16",
                gate_corners_are_the_checked_update::<I16F16>(&config),
            ),
            (
                "I8F24",
                gate_corners_are_the_checked_update::<I8F24>(&config),
            ),
            (
                "I32F32",
                gate_corners_are_the_checked_update::<I32F32>(&config),
            ),
            (
                "I48F16",
                gate_corners_are_the_checked_update::<I48F16>(&config),
            ),
        ] {
            let taken = taken.unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(taken > corners / 4, "{name}: {taken} of {corners}");
        }
    }

    /// A gate at the edge of its bound: a P controller in `I16F16` whose largest value at the
    /// corners of the gate twice as wide, v − u_old = kp·4g + 6g with g = 16, is the type's
    /// range plus 2⁻²¹ of it. The gate is 16 (2²⁰ LSB), the corners of that gate are exact, and
    /// so every margin of the bound must hold: a limit loosened by 2⁻²⁰ of the range admits
    /// the wider gate, whose corners wrap.
    #[test]
    fn a_gate_at_the_edge_of_its_bound_keeps_its_corners_exact() {
        let max = I16F16::MAX.to_num::<f64>();
        let k = (max * (1.0 + 1.0 / 2_097_152.0) - 96.0) / 64.0;
        let config = Config {
            kind: Kind::P,
            k,
            h: 0.1,
            ymin: -10.0,
            ymax: 10.0,
            ..Config::default()
        };
        let pid = Pid::<I16F16>::new(&config).unwrap();
        assert_eq!(
            pid.fast_gate, 20,
            "the premise: g = 16 is the widest gate that fits"
        );
        let taken = gate_corners_are_the_checked_update::<I16F16>(&config).unwrap();
        assert!(taken > 0);
    }

    /// With bounds of half-width i_half = `MAX` (a wide output range in a narrow type), an
    /// integral more than the type's range from the bounds' centre was accepted by the old
    /// common sample (centre − I saturated to `MAX`, which passed |·| ≤ `MAX`); the bound holds
    /// now. Found by the property below (Q8.24, a PI with b = 1.45).
    #[test]
    fn an_integral_beyond_bounds_that_span_the_type_is_bounded() {
        let config = Config {
            kind: Kind::PI,
            k: 3.443_424_447_111_794,
            ti: 7.175_157_551_004_982_5,
            b: 1.450_814_850_713_115_3,
            h: 0.089_381_293_237_648_6,
            ymin: 0.0,
            ymax: 1.660_967_656_045_574,
            ..Config::default()
        };
        let mut pid = Pid::<I8F24>::new(&config).unwrap();
        assert_eq!(pid.i_half, I8F24::MAX);
        pid.update(I8F24::ZERO, I8F24::from_raw(-695_921_867_107_075_297, 1));
        let r = I8F24::from_raw(7_146_474_155_218_305_024, 15);
        pid.update(r, I8F24::MIN);
        let centre = pid.integral_centre(r, I8F24::ZERO).to_f64();
        let i = pid.integral().to_f64();
        assert!((centre - i).abs() <= I8F24::MAX.to_f64(), "{centre} {i}");
        assert!(!pid.faults().any());
    }

    /// One started, automatic sample in `f64`, from the controller's own coefficients and
    /// state: the formulas of [`Pid`]'s documentation, unrounded. Returns the output, the new
    /// I and D, the largest magnitude of the values the update checks for saturation, and the
    /// rounding the fixed-point update may add to u, I and D, in LSB.
    fn model<T: Scalar>(
        pid: &Pid<T>,
        r: T,
        y: T,
        feedforward: T,
        track: Option<T>,
    ) -> (f64, f64, f64, f64, [f64; 3]) {
        let f = |x: T| x.to_f64();
        let (r, y, ff) = (f(r), f(y), f(feedforward));
        let (kp, b, c, ad, bd) = (f(pid.kp), f(pid.b), f(pid.c), f(pid.ad), f(pid.bd));
        let (bi, ao, slope) = (f(pid.bi), f(pid.ao), f(pid.offset_slope));
        let (i, d, yd_old, u_old) = (f(pid.i), f(pid.d), f(pid.yd_old), f(pid.u_old));
        let br = b * r;
        let p = kp * (br - y);
        let yd = y - c * r;
        let d_raw = ad * d - bd * (yd - yd_old);
        let d_new = d_raw.clamp(-f(pid.d_bound), f(pid.d_bound));
        let v = p + i + d_new + ff;
        let dymax = f(pid.dymax);
        let u = v
            .clamp(u_old - dymax, u_old + dymax)
            .clamp(f(pid.ymin), f(pid.ymax));
        let applied = track.map_or(u, f);
        let integral_step = bi * (r - y);
        let tracking = ao * (applied - v);
        let i_new = i + (integral_step + tracking);
        let bounds_ff = if pid.integrates() { ff } else { 0.0 };
        let centre = slope * r + f(pid.i_mid) - bounds_ff;
        let half = f(pid.i_half);
        let i_bounded = i_new.clamp(centre - half, centre + half);
        let checked = [
            br,
            br - y,
            p,
            c * r,
            yd,
            ad * d,
            yd - yd_old,
            bd * (yd - yd_old),
            d_raw,
            p + i,
            p + i + d_new,
            v,
            r - y,
            integral_step,
            applied - v,
            tracking,
            integral_step + tracking,
            i_new,
            slope * r,
            slope * r + f(pid.i_mid),
            centre,
        ];
        let largest = checked.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        // Each product rounds by half an LSB, and carries its operand's rounding times the
        // coefficient; sums and clamps add nothing.
        let e_d = 0.5 + bd.abs() * 0.5 + 0.5;
        let e_v = 0.5 * kp.abs() + 0.5 + e_d;
        let e_i = 0.5 + ao.abs() * (e_v + e_v) + 0.5 + 0.5;
        (u, i_bounded, d_new, largest, [e_v, e_i, e_d])
    }

    /// A sample for [`follows_the_model`]: set-point and measurement (raw bits, shift), and
    /// now and then a feed-forward with or without a tracking value.
    type ModelSample = (i64, u8, i64, u8, Option<(i64, u8, Option<(i64, u8)>)>);

    /// Runs `samples` through a started controller, comparing each with [`model`]: within the
    /// model's rounding bound where it stays in the type's range (and no fault), the output held,
    /// the state kept and the overflow fault raised where it leaves it. Returns the samples that
    /// were checked in range and beyond it.
    fn follows_the_model<T: FromRaw>(
        config: &Config,
        first: (i64, u8, i64, u8),
        samples: &[ModelSample],
    ) -> Result<(usize, usize), String> {
        let Ok(mut pid) = Pid::<T>::new(config) else {
            return Ok((0, 0));
        };
        let v = T::from_raw;
        let lsb = T::from_raw(1, 0).to_f64();
        let max = T::MAX.to_f64();
        pid.update(v(first.0, first.1), v(first.2, first.3));
        let (mut inside, mut beyond) = (0, 0);
        for &(r, rs, y, ys, with) in samples {
            pid.clear_faults();
            if pid.flags != STARTED {
                break;
            }
            let (r, y) = (v(r, rs), v(y, ys));
            let (ff, track) = with.map_or((T::ZERO, None), |(f, fs, t)| {
                (v(f, fs), t.map(|(t, ts)| v(t, ts)))
            });
            let (u, i, d, largest, [e_u, e_i, e_d]) = model(&pid, r, y, ff, track);
            let before = pid.clone();
            let got = if with.is_some() {
                pid.update_with(
                    r,
                    y,
                    Inputs {
                        feedforward: ff,
                        track,
                    },
                )
            } else {
                pid.update(r, y)
            };
            // Where the model's values reach within a margin of the type's end, rounding decides.
            let margin = 1e-6 * max + 64.0 * lsb;
            let tiny = 1e-14 * largest;
            if largest <= max - margin {
                inside += 1;
                let near =
                    |got: T, want: f64, lsbs: f64| (got.to_f64() - want).abs() <= lsbs * lsb + tiny;
                if pid.faults().any()
                    || !near(got, u, e_u)
                    || !near(pid.i, i, e_i)
                    || !near(pid.d, d, e_d)
                {
                    return Err(format!(
                        "in range: got u {got:?} I {:?} D {:?}, model u {u} I {i} D {d} \
                         (±{e_u}, {e_i}, {e_d} LSB), {:?}",
                        pid.i,
                        pid.d,
                        pid.faults()
                    ));
                }
            } else if largest >= max + margin {
                beyond += 1;
                let mut held = before.clone();
                held.faults = pid.faults;
                if got != before.u_old || pid != held || !pid.faults().overflow() {
                    return Err(format!(
                        "beyond range ({largest:e}): got {got:?}, {:?}, state {pid:?}",
                        pid.faults()
                    ));
                }
            }
        }
        Ok((inside, beyond))
    }

    /// The loop of the benches (`benches/src/pid_loop.rs`: PID with filter, weights,
    /// back-calculation and rate limit on ±5, a first-order plant) runs on the raw path after
    /// its first sample: the gate is wide enough for a working loop.
    #[test]
    #[cfg_attr(
        miri,
        ignore = "15 000 samples, each cloned: the properties cover it under Miri"
    )]
    fn a_working_loop_takes_the_raw_path() {
        fn run<T: Scalar>() -> usize {
            let config = Config {
                kind: Kind::PID,
                k: 2.0,
                ti: 1.0,
                td: 0.02,
                n: 10.0,
                tt: Some(0.05),
                h: 0.01,
                ymin: -5.0,
                ymax: 5.0,
                dymax: Some(0.5),
                ..Config::default()
            };
            let mut pid = Pid::<T>::new(&config).unwrap();
            let (a, mut y) = (T::from_f64(0.05), T::ZERO);
            let mut general = 0;
            for n in 0..5_000 {
                let r = T::from_f64(if n < 2_500 { 1.0 } else { -3.0 });
                let raw = T::raw_step::<false>(&mut pid.clone(), r, y, T::ZERO, None).is_some();
                general += usize::from(!raw);
                let u = pid.update(r, y);
                y = y.add(a.mul(u.sub(y)));
            }
            assert!((y.to_f64() + 3.0).abs() < 0.01, "{y:?}");
            general
        }
        assert_eq!(
            run::<I16F16>(),
            1,
            "only the first sample takes the general path"
        );
        assert_eq!(run::<I32F32>(), 1);
        assert_eq!(run::<I8F24>(), 1);
    }

    /// The split product of ARMv6-M is the wide one wherever the result fits, for every
    /// fraction width it serves (0..=16): operands of every magnitude, from a xorshift, and the
    /// ends of the range.
    #[test]
    #[cfg_attr(
        miri,
        ignore = "850 000 products of plain integer arithmetic: nothing for Miri"
    )]
    fn the_split_product_is_the_wide_one() {
        let mut x: u32 = 0x1234_5678;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x
        };
        let ends = [
            0,
            1,
            -1,
            i32::MAX,
            i32::MIN,
            1 << 16,
            -(1 << 16),
            0xFFFF,
            -0xFFFF,
        ];
        for frac in 0..=16u32 {
            let mut pairs: Vec<(i32, i32)> = Vec::new();
            for &a in &ends {
                for &b in &ends {
                    pairs.push((a, b));
                }
            }
            for _ in 0..50_000 {
                let (a, b) = (next(), next());
                pairs.push(((a as i32) >> (b % 32), (b as i32) >> (a % 32)));
            }
            for (a, b) in pairs {
                let exact = (i64::from(a) * i64::from(b) + ((1i64 << frac) >> 1)) >> frac;
                if i32::try_from(exact).is_ok() {
                    assert_eq!(
                        super::mul_round_split(a, b, frac),
                        super::mul_round_wide(a, b, frac),
                        "{a} · {b} >> {frac}"
                    );
                    assert_eq!(i64::from(super::mul_round_wide(a, b, frac)), exact);
                }
            }
        }
    }

    /// Every value the gate admits set at one of its ends at once — set-point, measurement,
    /// feed-forward, tracking value and the states I, D, y_old and u_old each at −g or
    /// g − 1 LSB, the gate g the configuration's own — on a started controller: the sample
    /// gives the checked update's result bit for bit, with and without feed-forward and
    /// tracking. These corners are where the gate's bound is spent; a gate wider than its bound
    /// allows wraps at one of them. Returns how many samples took the raw path.
    /// [`gate_corners_are_the_checked_update`] in the four types the gate tests use.
    fn gate_corners_in_every_type(config: &Config) -> Result<(), String> {
        gate_corners_are_the_checked_update::<I16F16>(config)?;
        gate_corners_are_the_checked_update::<I8F24>(config)?;
        gate_corners_are_the_checked_update::<I32F32>(config)?;
        gate_corners_are_the_checked_update::<I48F16>(config)?;
        Ok(())
    }

    fn gate_corners_are_the_checked_update<T: FromRaw>(config: &Config) -> Result<usize, String> {
        let Ok(mut pid) = Pid::<T>::new(config) else {
            return Ok(0);
        };
        let k = u32::from(pid.fast_gate);
        let bits = 8 * u32::try_from(core::mem::size_of::<T>()).unwrap_or(4);
        if k + 1 >= bits {
            return Ok(0);
        }
        let _ = pid.update(T::ZERO, T::ZERO);
        let g = 1i64 << k;
        let ends = [T::from_raw(-g, 0), T::from_raw(g - 1, 0)];
        let mut taken = 0;
        let step = if cfg!(miri) { 37 } else { 1 };
        for corner in (0u32..512).step_by(step) {
            let at = |bit: u32| ends[usize::from(corner >> bit & 1 == 1)];
            let mut start = pid.clone();
            start.i = at(0);
            start.d = at(1);
            start.yd_old = at(2);
            start.u_old = at(3);
            let (r, y, f, t) = (at(4), at(5), at(6), at(7));
            let track = (corner >> 8 & 1 == 1).then_some(t);
            for with in [false, true] {
                let (mut fast, mut slow) = (start.clone(), start.clone());
                let (a, b) = if with {
                    taken += usize::from(
                        T::raw_step::<true>(&mut start.clone(), r, y, f, track).is_some(),
                    );
                    let inputs = Inputs {
                        feedforward: f,
                        track,
                    };
                    (
                        fast.update_with(r, y, inputs),
                        checked::<T, true>(&mut slow, r, y, f, track),
                    )
                } else {
                    taken += usize::from(
                        T::raw_step::<false>(&mut start.clone(), r, y, T::ZERO, None).is_some(),
                    );
                    (
                        fast.update(r, y),
                        checked::<T, false>(&mut slow, r, y, T::ZERO, None),
                    )
                };
                if a != b || fast != slow {
                    return Err(format!(
                        "corner {corner:09b}, feed-forward {with}: {a:?} {b:?}\n{fast:?}\n{slow:?}"
                    ));
                }
            }
        }
        Ok(taken)
    }

    proptest! {
        #![proptest_config(cases())]

        /// The raw-integer path is the checked update, bit for bit — outputs, states and
        /// faults — for `FixedI32` and `FixedI64` at two fraction widths each, over
        /// configurations of every kind and scale and inputs of every magnitude (saturating
        /// ones included), with feed-forward, tracking, manual mode and resets between.
        #[test]
        fn the_raw_path_is_the_checked_update_bit_for_bit(config in configs(), ops in ops()) {
            for result in [
                same_as_checked::<I16F16>(&config, &ops),
                same_as_checked::<I8F24>(&config, &ops),
                same_as_checked::<I32F32>(&config, &ops),
                same_as_checked::<I48F16>(&config, &ops),
            ] {
                prop_assert!(result.is_ok(), "{}", result.err().unwrap_or_default());
            }
        }

        /// The gate's corners (see [`gate_corners_are_the_checked_update`]) in four types, over
        /// configurations of every kind and scale; some corners take the raw path.
        #[test]
        fn every_corner_of_the_gate_is_the_checked_update(config in configs()) {
            let result = gate_corners_in_every_type(&config);
            prop_assert!(result.is_ok(), "{}", result.err().unwrap_or_default());
        }

        /// The same for output ranges far from 0, where the integral's centre is large.
        #[test]
        fn every_corner_of_the_gate_is_the_checked_update_for_outputs_far_from_0(
            config in offset_outputs(),
        ) {
            let result = gate_corners_in_every_type(&config);
            prop_assert!(result.is_ok(), "{}", result.err().unwrap_or_default());
        }

        /// The same with set-point weights far above 1 and a small gain: the bounds of b·r − y
        /// (P's input) and of c·r − y (D's) then exceed the output's, so they decide the gate,
        /// and the corners put those values at their bounds.
        #[test]
        fn every_corner_of_the_gate_is_the_checked_update_under_heavy_set_point_weights(
            config in heavy_weights(),
        ) {
            let result = gate_corners_in_every_type(&config);
            prop_assert!(result.is_ok(), "{}", result.err().unwrap_or_default());
        }

        /// Every sample of a started controller in automatic against the controller's formulas
        /// in `f64` (unrounded, from the same coefficients and state): the output and the new
        /// I and D within the rounding the fixed-point products can add (half an LSB each,
        /// carried through the coefficients: for u, ½·|kp| + ½·|bd| + 2 LSB) where every
        /// value the update forms stays within the type's range; where one leaves it (by more
        /// than 10⁻⁶ of the range), the overflow fault is raised, the output held and the state
        /// kept — saturation, never a wrapped or clipped result.
        #[test]
        fn each_sample_follows_the_f64_formulas_or_is_held_on_overflow(
            config in configs(),
            first in (any::<i64>(), 16..64u8, any::<i64>(), 16..64u8),
            samples in prop::collection::vec(
                (
                    any::<i64>(),
                    0..64u8,
                    any::<i64>(),
                    0..64u8,
                    prop::option::weighted(
                        0.2,
                        (any::<i64>(), 0..64u8, prop::option::of((any::<i64>(), 0..64u8))),
                    ),
                ),
                1..RUN,
            ),
        ) {
            for result in [
                follows_the_model::<I16F16>(&config, first, &samples),
                follows_the_model::<I8F24>(&config, first, &samples),
                follows_the_model::<I32F32>(&config, first, &samples),
                follows_the_model::<I48F16>(&config, first, &samples),
            ] {
                prop_assert!(result.is_ok(), "{}", result.err().unwrap_or_default());
            }
        }
    }
}
