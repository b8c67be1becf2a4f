//! The controller: Åström's PID with filtered derivative, set-point weights, back-calculation
//! anti-windup, rate limit and clamps.

use core::fmt;

use crate::config::{Action, Config, ConfigError, Parameter};
use crate::real::Real;
use crate::scalar::Scalar;

#[cfg(feature = "fixed")]
pub(crate) mod raw;

/// Whether the controller computes its output or follows the operator's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Mode {
    /// The controller computes the output.
    Auto,
    /// The output is the operator's; the controller tracks it so the return to automatic is
    /// bumpless.
    Manual,
}

/// Faults the controller has seen since they were last cleared.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Faults(u8);

impl Faults {
    const NON_FINITE_INPUT: u8 = 1;
    const OVERFLOW: u8 = 1 << 1;

    /// A set-point, measurement, feed-forward or tracking value was NaN or infinite: the output
    /// was held.
    #[must_use]
    pub const fn non_finite_input(self) -> bool {
        self.0 & Faults::NON_FINITE_INPUT != 0
    }

    /// The computation overflowed (a float became infinite, or a fixed-point product or sum
    /// saturated): the output and state were held.
    ///
    /// One exception in `f32` and `f64`: the derivative term is bounded to
    /// [`STATE_BOUND`] output scales before anything else uses it, so a derivative that
    /// overflows (a measurement jumping by about `MAX`, e.g. from 0 to `f32::MAX`) is that
    /// bound, exactly as a large finite jump is, and raises no fault; the output goes to its
    /// limit. In fixed point the saturating product raises this fault and holds the output.
    #[must_use]
    pub const fn overflow(self) -> bool {
        self.0 & Faults::OVERFLOW != 0
    }

    /// Whether any fault is set.
    #[must_use]
    pub const fn any(self) -> bool {
        self.0 != 0
    }
}

impl fmt::Display for Faults {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.non_finite_input(), self.overflow()) {
            (false, false) => f.write_str("no fault"),
            (true, false) => f.write_str("non-finite input: output held"),
            (false, true) => f.write_str("overflow: output held"),
            (true, true) => f.write_str("non-finite input and overflow: output held"),
        }
    }
}

/// An operator or tracking value that is not a finite number.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ValueError {
    /// NaN or infinite.
    NotFinite,
}

impl fmt::Display for ValueError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("the value must be a finite number")
    }
}

impl core::error::Error for ValueError {}

/// Extra inputs of one update: see [`Pid::update_with`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inputs<T> {
    /// Added to the controller's output before the limits (e.g. a measured disturbance times
    /// its static gain).
    pub feedforward: T,
    /// The value the actuator really got, when something else chose it (an override selector,
    /// a cascade's inner loop at its limit). The integral tracks it instead of the controller's
    /// own output, so the controller does not wind up while it is not in charge.
    pub track: Option<T>,
}

impl<T: Scalar> Default for Inputs<T> {
    fn default() -> Inputs<T> {
        Inputs {
            feedforward: T::ZERO,
            track: None,
        }
    }
}

/// How far a coefficient or limit may move when it is converted into the controller's number
/// type: 2⁻¹⁰ (about 0.1 %) of its value (for the output limits: of the larger of |ymin| and
/// |ymax|). [`Pid::new`] refuses a configuration whose conversion is further off, overflows or
/// vanishes, and names the parameter ([`ConfigError::Unrepresentable`]).
pub const TOLERANCE: f32 = 1.0 / 1024.0;

/// How far the controller's states may reach, in output scales: the derivative term stays within
/// ±`STATE_BOUND`·S and the integral (of kinds with an I term) within `STATE_BOUND`·S beyond
/// what would hold the output at a limit in steady state (I = u − K·(b − 1)·r − feed-forward),
/// where S = max(ymax − ymin, |ymin|, |ymax|).
///
/// A state that far out drives the output hard into a limit, so the bound changes nothing a
/// working loop does; it keeps a single absurd but finite reading (a broken sensor's 1e300) from
/// parking a state so far away that it takes hours to decay (without it: about 690·Tt). With
/// it, a loop is back within 1 % of its undisturbed course after at most 14 of its slowest time
/// constants (Ti, Tt, Td/N, the plant's), over the loops the property tests try; the bound's
/// size hardly matters (10 scales: 11, 1 scale: 9.5), so it is wide.
pub const STATE_BOUND: u16 = 100;

/// Åström's PID controller with the anti-windup of the 1985 source, for `f32`, `f64` and
/// fixed point.
///
/// Coefficients are computed once from the [`Config`] (the source's "pre-computations"), so
/// [`update`](Pid::update) does only multiplies, adds and compares:
///
/// ```text
/// P = s·K·(b·r − y)                    s = +1 direct, −1 reverse
/// D = ad·D − s·bd·((y − c·r) − (y_old − c·r_old))
/// v = P + I + D (+ feed-forward)
/// u = clamp(v, u_old ± dymax), then clamp(u, ymin, ymax)
/// I = I + s·bi·(r − y) + ao·(u − v)    bi = K·h/Ti, ad = Td/(Td + N·h),
///                                      bd = K·Td·N/(Td + N·h), ao = h/Tt
/// ```
///
/// Kinds without P use a gain of 1 for I and D, as the source does. The state is
/// I = D = 0 and u_old = 0 clamped into the limits at start; the first sample with finite inputs
/// sets y_old, r_old. D and I are kept within [`STATE_BOUND`] output scales.
///
/// A NaN or infinite set-point or measurement (the first sample included) holds the output, sets a
/// [`Faults`] flag and leaves every state as it was, so the controller runs on as soon as the
/// inputs are finite again; `update` never returns NaN or infinity. A `Pid<T>` holds 19 values of
/// `T` and 3 bytes (flags, faults, the fixed-point gate), padded to `T`'s alignment: 80 bytes for
/// `f32` and `I16F16`, 160 for `f64` and `I32F32`.
///
/// ```
/// use regler_pid::{Config, Kind, Pid};
/// let config = Config { kind: Kind::PI, k: 2.0, ti: 10.0, h: 0.5, ymin: 0.0, ymax: 100.0, ..Config::default() };
/// let mut pid = Pid::<f32>::new(&config)?;
/// assert_eq!(pid.update(20.0, f32::NAN), 0.0); // a sensor not ready at power-up: held, flagged
/// assert!(pid.faults().non_finite_input());
/// pid.clear_faults();
/// let mut temperature = 15.0f32;
/// for _ in 0..200 {
///     let heat = pid.update(20.0, temperature);
///     temperature += 0.5 * (0.05 * heat - 0.02 * (temperature - 10.0)); // a room losing heat
/// }
/// assert!((temperature - 20.0).abs() < 0.1);
/// assert!(!pid.faults().any());
/// # Ok::<(), regler_pid::ConfigError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Pid<T> {
    // The order keeps the pairs one update uses side by side (ad and bd, bi and ao, D and its
    // input) apart in memory: adjacent, they tempt the compiler into two-lane vector code that
    // takes more instructions than the scalar arithmetic it replaces.
    kp: T,
    bi: T,
    b: T,
    ad: T,
    c: T,
    ao: T,
    ymin: T,
    bd: T,
    ymax: T,
    /// The rate limit per sample; `T::MAX` when there is none (the window then spans every
    /// value, so the update needs no branch for it).
    dymax: T,
    /// kp·(1 − b): the P term's steady-state offset per unit of set-point, which the integral
    /// must cancel; the integral's bounds move with it (0 for kinds without I).
    offset_slope: T,
    /// The middle of the integral's bounds at set-point 0: (ymin + ymax)/2.
    i_mid: T,
    /// The half-width of the integral's bounds: (ymax − ymin)/2 + [`STATE_BOUND`] scales.
    i_half: T,
    /// [`STATE_BOUND`] scales: the derivative term's bound either way (read it with
    /// [`derivative_bound`](Pid::derivative_bound)). For floats its sign also admits the fast
    /// path of [`step`](Pid::step): negative while the controller is started and automatic,
    /// positive otherwise (see [`set_flags`](Pid::set_flags)), so that one compare there stands
    /// for the mode test and both state bounds.
    d_bound: T,
    i: T,
    d: T,
    r_old: T,
    /// The derivative's input of the last sample as [`derivative_input`](Pid::derivative_input)
    /// stores it: y − c·r, for floats c·r − y (with `r_old` also the last measurement, for a
    /// bumpless change).
    yd_old: T,
    u_old: T,
    /// [`STARTED`] and [`MANUAL`] in one byte, so that the common case (automatic and
    /// running) is one test per sample.
    flags: u8,
    faults: Faults,
    /// Fixed point: the exponent of the input gate of the raw-integer update
    /// (`controller/raw.rs`), set with the coefficients; unused by floats.
    fast_gate: u8,
}

/// A sample has been taken since construction or reset.
const STARTED: u8 = 1;
/// The mode is [`Mode::Manual`].
const MANUAL: u8 = 1 << 1;

/// One sample's results before they are stored.
#[derive(Clone, Copy)]
struct Sample<T> {
    /// y − c·r: the derivative's input.
    yd: T,
    d: T,
    u: T,
    i: T,
    /// A fixed-point product or sum of the sample saturated (always false for floats).
    saturated: bool,
}

/// The coefficients of one configuration, converted and checked, before any is applied.
struct Coefficients<T> {
    kp: T,
    b: T,
    c: T,
    bi: T,
    ad: T,
    bd: T,
    ao: T,
    ymin: T,
    ymax: T,
    dymax: Option<T>,
    offset_slope: T,
    i_mid: T,
    i_half: T,
    d_bound: T,
}

#[allow(
    clippy::arithmetic_side_effects,
    reason = "arithmetic on Real (sealed: f32 or f64) cannot panic or wrap; the results are checked by hold()"
)]
impl<T: Scalar> Coefficients<T> {
    fn new<F: Real>(config: &Config<F>) -> Result<Coefficients<T>, ConfigError<F>> {
        config.validate()?;
        let zero = F::zero();
        let one = F::one();
        let kind = config.kind;
        let signed = |x: F| match config.action {
            Action::Direct => x,
            Action::Reverse => -x,
        };
        let gain = if kind.has_p() { config.k } else { one };
        let dn = config.td + config.n * config.h;
        // Same operation order as the reference algorithm (s·bi, s·bd), so f64 results agree
        // to the last bit.
        let kp = if kind.has_p() { signed(config.k) } else { zero };
        let bi = if kind.has_i() {
            signed(gain * config.h / config.ti)
        } else {
            zero
        };
        let ad = if kind.has_d() { config.td / dn } else { zero };
        let bd = if kind.has_d() {
            signed(gain * config.td * config.n / dn)
        } else {
            zero
        };
        let tt = config.tt.unwrap_or(config.h);
        let ao = if kind.has_i() { config.h / tt } else { zero };
        let term = |exact: F, parameter, value, coefficient, needed: bool| {
            hold::<T, F>(exact, exact.abs(), needed, parameter, value, coefficient)
        };
        let td_used = kind.has_d() && config.td != zero;
        let scale = config.ymin.abs().max(config.ymax.abs());
        let limit =
            |value: F, parameter, name| hold::<T, F>(value, scale, false, parameter, value, name);
        let dymax = match config.rate_limit() {
            Some(d) => Some(limit(d, Parameter::Dymax, "dymax")?),
            None => None,
        };
        let bound = F::from_u16(STATE_BOUND) * (config.ymax - config.ymin).max(scale);
        Ok(Coefficients {
            kp: term(
                kp,
                Parameter::K,
                config.k,
                "s·K",
                kind.has_p() && config.k != zero,
            )?,
            b: term(config.b, Parameter::B, config.b, "b", false)?,
            c: term(config.c, Parameter::C, config.c, "c", false)?,
            bi: term(
                bi,
                Parameter::Ti,
                config.ti,
                "K·h/Ti",
                kind.has_i() && gain != zero,
            )?,
            ad: term(ad, Parameter::Td, config.td, "Td/(Td + N·h)", td_used)?,
            bd: term(
                bd,
                Parameter::Td,
                config.td,
                "K·Td·N/(Td + N·h)",
                td_used && gain != zero,
            )?,
            ao: term(ao, Parameter::Tt, tt, "h/Tt", kind.has_i())?,
            ymin: limit(config.ymin, Parameter::Ymin, "ymin")?,
            ymax: limit(config.ymax, Parameter::Ymax, "ymax")?,
            dymax,
            // Kinds without I hold a constant bias (their manual reset), bounded around the
            // output limits where it is set; the per-sample check then never moves it.
            offset_slope: if kind.has_i() {
                T::from_real(kp * (one - config.b))
            } else {
                T::ZERO
            },
            i_mid: T::from_real((config.ymin + config.ymax) / F::from_u16(2)),
            i_half: T::from_real((config.ymax - config.ymin) / F::from_u16(2) + bound),
            d_bound: T::from_real(bound),
        })
    }
}

#[allow(
    clippy::arithmetic_side_effects,
    reason = "arithmetic on Real (sealed: f32 or f64) cannot panic or wrap; a non-finite result is refused"
)]
/// `exact` in `T`, if it survives the conversion within [`TOLERANCE`] of `scale` and, when
/// `needed`, did not vanish (underflow) on the way.
fn hold<T: Scalar, F: Real>(
    exact: F,
    scale: F,
    needed: bool,
    parameter: Parameter,
    value: F,
    coefficient: &'static str,
) -> Result<T, ConfigError<F>> {
    let converted = T::from_real(exact);
    let back: F = converted.to_real();
    let zero = F::zero();
    let vanished = (needed && exact == zero) || (exact != zero && !exact.is_normal());
    let close = (back - exact).abs() <= F::from_f32_exact(TOLERANCE) * scale;
    if exact.is_finite() && !vanished && close {
        Ok(converted)
    } else {
        Err(ConfigError::Unrepresentable {
            parameter,
            value,
            coefficient,
            exact,
        })
    }
}

/// `x` limited to `lo..=hi` (ordered), as [`Scalar::clamp_within`], except that a NaN becomes
/// a limit: for floats one `max` and one `min` that may read the limits from memory (a clamp
/// that keeps NaN needs them in registers). For values whose NaN is caught elsewhere.
#[inline(always)]
fn limit<T: PartialOrd>(x: T, lo: T, hi: T) -> T {
    let above = if x > lo { x } else { lo };
    if above < hi { above } else { hi }
}

/// How close to the end of `T`'s range a term may reach before a [`Station`](crate::Station)
/// refuses its configuration: within 2⁻⁸ of `T::MAX`, a margin that covers the rounding of
/// the converted coefficients (at most [`TOLERANCE`]) and of each fixed-point operation.
const REACH_MARGIN: f32 = 1.0 / 256.0;

#[allow(
    clippy::arithmetic_side_effects,
    reason = "arithmetic on Real (sealed: f32 or f64) cannot panic or wrap; a non-finite bound is refused"
)]
/// Checks that no product or sum the update computes can leave `T`'s range for a set-point and
/// a measurement anywhere in `lo..=hi` (and no feed-forward or tracking value): each term's
/// largest magnitude, bounded by the triangle inequality from the corners of the scale (every
/// term is affine in r and y), the state bounds ([`STATE_BOUND`]) and the output limits, must
/// stay below `T::MAX`·(1 − 2⁻⁸). The error names the first term that does not and the
/// parameter that sets it.
pub(crate) fn check_reach<T: Scalar, F: Real>(
    config: &Config<F>,
    lo: F,
    hi: F,
) -> Result<(), ConfigError<F>> {
    config.validate()?;
    let zero = F::zero();
    let one = F::one();
    let two = F::from_u16(2);
    let kind = config.kind;
    let gain = if kind.has_p() { config.k } else { one };
    let kp = if kind.has_p() { config.k.abs() } else { zero };
    let corners = [(lo, lo), (lo, hi), (hi, lo), (hi, hi)];
    let widest =
        |f: &dyn Fn(F, F) -> F| corners.iter().fold(zero, |m, &(r, y)| m.max(f(r, y).abs()));
    let m = lo.abs().max(hi.abs());
    let span = hi - lo;
    // P = K·(b·r − y), and its factor b·r.
    let p_in = widest(&|r, y| config.b * r - y).max(config.b.abs() * m);
    let p = kp * p_in;
    // D: ad·D − bd·((y − c·r) − (y_old − c·r_old)), D within the derivative bound.
    let yd_hi = corners
        .iter()
        .fold(F::neg_infinity(), |a, &(r, y)| a.max(y - config.c * r));
    let yd_lo = corners
        .iter()
        .fold(F::infinity(), |a, &(r, y)| a.min(y - config.c * r));
    let yd = yd_hi.abs().max(yd_lo.abs()).max(config.c.abs() * m);
    let scale = config.ymin.abs().max(config.ymax.abs());
    let bound = F::from_u16(STATE_BOUND) * (config.ymax - config.ymin).max(scale);
    let dn = config.td + config.n * config.h;
    let (ad, bd) = if kind.has_d() && config.td != zero {
        (config.td / dn, (gain * config.td * config.n / dn).abs())
    } else {
        (zero, zero)
    };
    let d_step = bd * (yd_hi - yd_lo);
    let d = ad * bound + d_step;
    // I: within i_half of its centre K·(1 − b)·r + (ymin + ymax)/2.
    let offset = if kind.has_i() {
        (kp * (one - config.b)).abs() * m
    } else {
        zero
    };
    let centre = offset + ((config.ymin + config.ymax) / two).abs();
    let i = centre + (config.ymax - config.ymin) / two + bound;
    let v = p + i + d;
    let (bi, ao) = if kind.has_i() {
        (
            (gain * config.h / config.ti).abs(),
            config.h / config.tt.unwrap_or(config.h),
        )
    } else {
        (zero, zero)
    };
    let integral_step = bi * span;
    let tracking = ao * (scale + v);
    let new_i = i + integral_step + tracking;
    let limit = T::MAX.to_real::<F>() * (one - F::from_f32_exact(REACH_MARGIN));
    let terms = [
        // The sums the update forms on every sample, for every kind: b·r − y, the change of
        // y − c·r between samples, and u − v before the tracking gain.
        (p_in, Parameter::B, config.b, "b·r − y"),
        (
            yd_hi - yd_lo,
            Parameter::C,
            config.c,
            "(y − c·r) − (y_old − c·r_old)",
        ),
        (scale + v, Parameter::K, config.k, "u − v"),
        (p, Parameter::K, config.k, "K·(b·r − y)"),
        (offset, Parameter::B, config.b, "K·(1 − b)·r"),
        (yd, Parameter::C, config.c, "y − c·r"),
        (d, Parameter::Td, config.td, "the derivative term"),
        (v, Parameter::K, config.k, "P + I + D"),
        (integral_step, Parameter::Ti, config.ti, "K·h/Ti·(r − y)"),
        (
            tracking,
            Parameter::Tt,
            config.tt.unwrap_or(config.h),
            "h/Tt·(u − v)",
        ),
        (
            new_i + centre,
            Parameter::K,
            config.k,
            "the integral's update",
        ),
    ];
    for (reach, parameter, value, term) in terms {
        // A NaN bound is refused too (an infinite one is above the limit).
        if reach.is_nan() || reach > limit {
            return Err(ConfigError::OutOfReach {
                parameter,
                value,
                term,
                reach,
            });
        }
    }
    Ok(())
}

impl<T: Scalar> Pid<T> {
    /// A controller for `config` (in `f64` or `f32`), or the error naming its bad parameter.
    ///
    /// Besides [`Config::validate`], every coefficient and limit must convert into `T` within
    /// [`TOLERANCE`]; otherwise [`ConfigError::Unrepresentable`] names the parameter. A
    /// coefficient of several parameters is named by the one listed with it, the error's
    /// `coefficient` giving the whole: `K·h/Ti` by `ti`, `Td/(Td + N·h)` and `K·Td·N/(Td + N·h)`
    /// by `td` (so `K = f64::MAX` with a derivative term is refused naming `td`), `h/Tt` by `tt`
    /// (`tt = f64::MAX` vanishes). A subnormal `dymax` is refused (not held within the
    /// tolerance); limits `f64::MIN..=f64::MAX` are accepted in `f64` (no limits: the states'
    /// bound, [`STATE_BOUND`] scales, is then infinite).
    pub fn new<F: Real>(config: &Config<F>) -> Result<Pid<T>, ConfigError<F>> {
        let k = Coefficients::<T>::new(config)?;
        // One mapping from coefficients to fields (`apply`, as `set_config` uses it), then the
        // state at construction (`reset`).
        let zero = T::ZERO;
        let mut pid = Pid {
            kp: zero,
            b: zero,
            c: zero,
            bi: zero,
            ad: zero,
            bd: zero,
            ao: zero,
            ymin: zero,
            ymax: zero,
            dymax: zero,
            offset_slope: zero,
            i_mid: zero,
            i_half: zero,
            d_bound: zero,
            i: zero,
            d: zero,
            yd_old: zero,
            r_old: zero,
            u_old: zero,
            flags: 0,
            faults: Faults::default(),
            fast_gate: 0,
        };
        pid.apply(k);
        pid.reset();
        Ok(pid)
    }

    fn apply(&mut self, k: Coefficients<T>) {
        self.kp = k.kp;
        self.b = k.b;
        self.c = k.c;
        self.bi = k.bi;
        self.ad = k.ad;
        self.bd = k.bd;
        self.ao = k.ao;
        self.ymin = k.ymin;
        self.ymax = k.ymax;
        self.dymax = k.dymax.unwrap_or(T::MAX);
        self.offset_slope = k.offset_slope;
        self.i_mid = k.i_mid;
        self.i_half = k.i_half;
        self.d_bound = k.d_bound;
        self.fast_gate = T::raw_gate(self);
        self.set_flags(self.flags);
    }

    /// Sets the mode flags ([`STARTED`], [`MANUAL`]) and, for floats, the fast path's
    /// admission (the sign of `d_bound`) with them.
    #[inline(always)]
    fn set_flags(&mut self, flags: u8) {
        self.flags = flags;
        if !T::SATURATES {
            let bound = self.d_bound.abs();
            self.d_bound = if flags == STARTED { bound.neg() } else { bound };
        }
    }

    /// The derivative term's bound, [`STATE_BOUND`] output scales.
    #[inline(always)]
    fn derivative_bound(&self) -> T {
        if T::SATURATES {
            self.d_bound
        } else {
            self.d_bound.abs()
        }
    }

    /// One sample: the output for set-point `r` and measurement `y`.
    #[inline]
    pub fn update(&mut self, setpoint: T, measurement: T) -> T {
        self.step::<false>(setpoint, measurement, T::ZERO, None)
    }

    /// One sample with feed-forward and an external tracking value (see [`Inputs`]).
    /// Returns the controller's own output (before any outside selection).
    pub fn update_with(&mut self, setpoint: T, measurement: T, inputs: Inputs<T>) -> T {
        if !(inputs.feedforward.is_finite() && inputs.track.is_none_or(Scalar::is_finite)) {
            self.faults.0 |= Faults::NON_FINITE_INPUT;
            return self.u_old;
        }
        self.step::<true>(setpoint, measurement, inputs.feedforward, inputs.track)
    }

    /// The centre of the integral's bounds at set-point `r`: [`STATE_BOUND`] output scales
    /// either side of the values that hold the output at a limit in steady state.
    #[inline(always)]
    fn integral_centre(&self, r: T, feedforward: T) -> T {
        self.offset_slope.mul(r).add(self.i_mid).sub(feedforward)
    }

    /// [`integral_centre`](Pid::integral_centre), noting a fixed-point saturation.
    #[inline(always)]
    fn integral_centre_noting(&self, r: T, feedforward: T, saturated: &mut bool) -> T {
        self.offset_slope
            .mul_noting(r, saturated)
            .add_noting(self.i_mid, saturated)
            .sub_noting(feedforward, saturated)
    }

    /// One sample. The common case — automatic, running, the integral inside its bounds —
    /// runs here, inlined into the caller; everything else (the first sample, manual mode, an
    /// integral at its bound, a fault) goes to [`step_general`](Pid::step_general), which
    /// computes the sample again from scratch (nothing has been stored yet). Being a tail
    /// call, it keeps no value of this path alive: on Cortex-M the update then needs no
    /// callee-saved FPU registers, which a call in the middle of it would (a 16-instruction
    /// prologue and epilogue on every sample).
    #[inline(always)]
    fn step<const FEEDFORWARD: bool>(&mut self, r: T, y: T, feedforward: T, track: Option<T>) -> T {
        if T::RAW_PATH {
            // Fixed point: the common sample on the raw integers (`controller/raw.rs`).
            if let Some(u) = T::raw_step::<FEEDFORWARD>(self, r, y, feedforward, track) {
                return u;
            }
            return self.step_general::<FEEDFORWARD>(r, y, feedforward, track);
        }
        if !T::SATURATES {
            // Floats: see `step_float`.
            if let Some(u) = self.step_float::<FEEDFORWARD>(r, y, feedforward, track) {
                return u;
            }
        } else if self.flags == STARTED {
            let s = self.compute::<FEEDFORWARD>(r, y, feedforward, track, self.yd_old, false);
            // One test accepts the sample: the new integral lies inside its bounds, which move
            // with the set-point. It also proves every value finite: a NaN or infinite r or y
            // makes P (and r − y) non-finite — 0·∞ is NaN, so kinds without P or I are no
            // exception — and a non-finite v reaches I through the tracking term ao·(u − v),
            // so a finite I means finite inputs, v and bounds.
            let centre =
                self.integral_centre(r, self.bounds_feedforward::<FEEDFORWARD>(feedforward));
            if !s.saturated && centre.sub(s.i).magnitude_within(self.i_half) {
                return self.commit(s, r, track);
            }
        }
        self.step_general::<FEEDFORWARD>(r, y, feedforward, track)
    }

    /// The fast path for floats: the sample of [`compute`](Pid::compute), stored and its output
    /// returned if it is admitted, or `None` (nothing stored) for
    /// [`step_general`](Pid::step_general) to compute again.
    ///
    /// One compare admits it: −(|centre − I| + |D|) > `d_bound`, where `d_bound` is
    /// −[`STATE_BOUND`] scales while started and automatic and +[`STATE_BOUND`] scales
    /// otherwise (nothing passes, not even 0 when the scale is 0: the compare is strict). That
    /// is the mode test, the derivative's bound (here, D is not clamped: an admitted D needs no
    /// clamp) and the integral's (the bound on |D| is the smaller of the two, and a rounded sum
    /// of magnitudes is never below either), and it proves every value finite as the test of
    /// `step` does: a NaN or infinite r or y makes P non-finite (0·∞ is NaN), and a non-finite
    /// v reaches I through ao·(u − v). Only states far outside any working loop's
    /// (|I − centre| + |D| at or beyond 100 output scales) take the general path that the
    /// separate bounds would have let through; it gives them the same result.
    ///
    /// The output limits drop a NaN (one `maxss`/`minss` each on x86, with the limit read from
    /// memory): a NaN v is caught through I all the same. I is computed as
    /// I − (bi·(y − r) + ao·(v − u)), the same number as the reference's I + bi·(r − y) +
    /// ao·(u − v) (a negation is exact in every rounding step), so that neither y nor v needs
    /// a copy on two-operand machines.
    #[inline(always)]
    fn step_float<const FEEDFORWARD: bool>(
        &mut self,
        r: T,
        y: T,
        feedforward: T,
        track: Option<T>,
    ) -> Option<T> {
        let p = self.kp.mul(self.b.mul(r).sub(y));
        let yd = self.derivative_input(r, y);
        // The change of y − c·r: yd, yd_old are its negations (see `derivative_input`).
        let d = self
            .ad
            .mul(self.d)
            .sub(self.bd.mul(self.yd_old.sub(yd)))
            .flush_tiny();
        let mut v = p.add(self.i).add(d);
        if FEEDFORWARD {
            v = v.add(feedforward);
        }
        let u = limit(
            v.clamp_within(self.u_old.sub(self.dymax), self.u_old.add(self.dymax)),
            self.ymin,
            self.ymax,
        );
        let applied = track.unwrap_or(u);
        let i = self
            .i
            .sub(self.bi.mul(y.sub(r)).add(self.ao.mul(v.sub(applied))));
        let centre = self.integral_centre(r, self.bounds_feedforward::<FEEDFORWARD>(feedforward));
        let reach = centre.sub(i).abs().neg().sub(d.abs());
        if reach > self.d_bound {
            self.i = i;
            self.d = d;
            self.yd_old = yd;
            self.r_old = r;
            self.u_old = self.held(track, u);
            Some(u)
        } else {
            None
        }
    }

    /// Every sample the fast path of [`step`](Pid::step) does not take: the first one (its
    /// derivative input is its own, so there is no kick), manual mode (the operator's output
    /// stands and I follows so that v = u when auto returns), the integral limited to its
    /// bounds, and faults (nothing stored, the output held).
    #[cold]
    #[inline(never)]
    fn step_general<const FEEDFORWARD: bool>(
        &mut self,
        r: T,
        y: T,
        feedforward: T,
        track: Option<T>,
    ) -> T {
        let yd_old = if self.started() {
            self.yd_old
        } else {
            self.derivative_input(r, y)
        };
        let manual = self.flags & MANUAL != 0;
        let mut s = self.compute::<FEEDFORWARD>(r, y, feedforward, track, yd_old, manual);
        let centre = self.integral_centre(r, self.bounds_feedforward::<FEEDFORWARD>(feedforward));
        // Inside its bounds, a float I is kept as computed (as the fast path keeps it; centre +
        // (I − centre) could be an ulp off). Fixed point takes the clamp always: there it is
        // exact inside the bounds, and centre − I may saturate, which with i_half = MAX would
        // read as inside for an I beyond the bounds (`raw.rs`,
        // `an_integral_beyond_bounds_that_span_the_type_is_bounded`).
        let bounded = if !T::SATURATES && centre.sub(s.i).magnitude_within(self.i_half) {
            s.i
        } else {
            centre.add(
                s.i.sub(centre)
                    .clamp_within(T::ZERO.sub(self.i_half), self.i_half),
            )
        };
        // A finite I implies finite inputs and v (see `step`; in manual I = u − P − D); the
        // bounds themselves may overflow when an absurd set-point moves them.
        if s.saturated || !T::both_finite(s.i, bounded) {
            self.fault(r, y);
            return self.u_old;
        }
        s.i = bounded;
        // The fast path runs only once started, so only this path marks it.
        self.set_flags(self.flags | STARTED);
        // In manual mode the output stays the operator's: a tracking value moves I only.
        self.commit(s, r, if manual { None } else { track })
    }

    /// The sample's new states and output, computed from the stored ones; nothing is stored.
    #[inline(always)]
    fn compute<const FEEDFORWARD: bool>(
        &self,
        r: T,
        y: T,
        feedforward: T,
        track: Option<T>,
        yd_old: T,
        manual: bool,
    ) -> Sample<T> {
        // Every product and sum of values below notes a fixed-point saturation (floats never
        // do: their overflow is an infinity, caught by the finiteness check); the bounds'
        // own arithmetic (u_old ± dymax with dymax = MAX when there is no rate limit, ±d_bound)
        // saturates by design and is not noted.
        let mut o = false;
        let p = self
            .kp
            .mul_noting(self.b.mul_noting(r, &mut o).sub_noting(y, &mut o), &mut o);
        let cr = self.c.mul_noting(r, &mut o);
        // The derivative's input as stored, and its change y − c·r − (y_old − c·r_old).
        let (yd, change) = if T::SATURATES {
            let yd = y.sub_noting(cr, &mut o);
            (yd, yd.sub_noting(yd_old, &mut o))
        } else {
            let yd = cr.sub(y);
            (yd, yd_old.sub(yd))
        };
        let d = self
            .ad
            .mul_noting(self.d, &mut o)
            .sub_noting(self.bd.mul_noting(change, &mut o), &mut o)
            .flush_tiny()
            .clamp_within(
                T::ZERO.sub(self.derivative_bound()),
                self.derivative_bound(),
            );
        if manual {
            let u = self.u_old;
            return Sample {
                yd,
                d,
                u,
                i: u.sub_noting(p, &mut o).sub_noting(d, &mut o),
                saturated: o,
            };
        }
        let mut v = p.add_noting(self.i, &mut o).add_noting(d, &mut o);
        if FEEDFORWARD {
            v = v.add_noting(feedforward, &mut o);
        }
        let u = v
            .clamp_within(self.u_old.sub(self.dymax), self.u_old.add(self.dymax))
            .clamp_within(self.ymin, self.ymax);
        let applied = track.unwrap_or(u);
        // I + (integral step + tracking), summed in the reference's order.
        let step = self
            .bi
            .mul_noting(r.sub_noting(y, &mut o), &mut o)
            .add_noting(
                self.ao.mul_noting(applied.sub_noting(v, &mut o), &mut o),
                &mut o,
            );
        let i = self.i.add_noting(step, &mut o);
        // The centre of the integral's bounds, noted too (the caller recomputes it).
        let _ = self.integral_centre_noting(
            r,
            self.bounds_feedforward::<FEEDFORWARD>(feedforward),
            &mut o,
        );
        Sample {
            yd,
            d,
            u,
            i,
            saturated: o,
        }
    }

    /// The feed-forward the integral's bounds follow: a kind with I has them move with it (the
    /// integral makes up the rest); a kind without I keeps its bias where it was set.
    #[inline(always)]
    fn bounds_feedforward<const FEEDFORWARD: bool>(&self, feedforward: T) -> T {
        if FEEDFORWARD && self.integrates() {
            feedforward
        } else {
            T::ZERO
        }
    }

    /// Stores an accepted sample; returns its output.
    #[inline(always)]
    fn commit(&mut self, s: Sample<T>, r: T, track: Option<T>) -> T {
        self.i = s.i;
        self.d = s.d;
        self.yd_old = s.yd;
        self.r_old = r;
        self.u_old = self.held(track, s.u);
        s.u
    }

    /// The output the next sample's rate limit starts from and a held output repeats: a
    /// tracking value (the actuator's position) within the limits, or the controller's own.
    #[inline(always)]
    pub(crate) fn held(&self, track: Option<T>, u: T) -> T {
        match track {
            Some(t) => t.clamp_within(self.ymin, self.ymax),
            None => u,
        }
    }

    /// A sample whose measurement could not be converted (not finite): the output is held and
    /// the non-finite-input fault raised, as [`update`](Pid::update) does.
    pub(crate) fn note_non_finite_input(&mut self) -> T {
        self.faults.0 |= Faults::NON_FINITE_INPUT;
        self.u_old
    }

    #[cold]
    fn fault(&mut self, r: T, y: T) {
        self.faults.0 |= if r.is_finite() && y.is_finite() {
            Faults::OVERFLOW
        } else {
            Faults::NON_FINITE_INPUT
        };
    }

    /// Whether the kind has I (the others hold a constant bias, their manual reset). Exactly
    /// the kinds with a tracking coefficient: `new` refuses an `ao` that vanishes for them.
    fn integrates(&self) -> bool {
        self.ao != T::ZERO
    }

    /// `i` within the integral's bounds at the last set-point (for a kind without I, whose
    /// bias a spike must not hold at a limit for good, the bounds sit around the output limits:
    /// its `offset_slope` is 0); a non-finite `i` (a new gain so large that the bumpless
    /// adjustment overflowed) becomes the nearest in-bound value to 0.
    fn bounded_integral(&self, i: T) -> T {
        let centre = self.integral_centre(self.r_old, T::ZERO);
        let (lo, hi) = (centre.sub(self.i_half), centre.add(self.i_half));
        if !T::both_finite(lo, hi) {
            return T::ZERO;
        }
        if i.is_finite() {
            i.clamp_within(lo, hi)
        } else {
            T::ZERO.clamp_within(lo, hi)
        }
    }

    /// Changes the parameters, bumplessly: the integral is adjusted so that the output would
    /// not jump if the set-point and measurement stayed as at the last sample (a change of K
    /// or b moves P, the integral takes up the difference). This holds for every kind: one
    /// without an I term keeps the adjusted value as a constant bias (its manual reset), so a
    /// bias set by a manual → auto switch survives a change of gain. A derivative state that
    /// the new kind lacks is dropped, into the integral where there is one. The held output is
    /// clamped into the new limits at once (in manual mode too).
    ///
    /// On an error nothing changes.
    pub fn set_config<F: Real>(&mut self, config: &Config<F>) -> Result<(), ConfigError<F>> {
        let k = Coefficients::<T>::new(config)?;
        let y_old = self.last_measurement();
        let p_before = self.proportional(self.r_old, y_old);
        self.apply(k);
        let mut i = self.i;
        if self.started() {
            let p_after = self.proportional(self.r_old, y_old);
            let moved = i.add(p_before).sub(p_after);
            // The derivative's input under the new weight c: steady readings stay steady.
            let yd = self.derivative_input(self.r_old, y_old);
            if T::both_finite(moved, yd) {
                i = moved;
                self.yd_old = yd;
            } else {
                // The last set-point is beyond what the new weights can carry (b·r or c·r
                // overflows a float): the next sample starts afresh as a first sample does (its
                // derivative input its own, no kick; I kept), where a stored infinity would hold
                // every later sample with the overflow fault.
                self.set_flags(self.flags & !STARTED);
            }
        }
        if !config.kind.has_d() {
            if config.kind.has_i() {
                i = i.add(self.d);
            }
            self.d = T::ZERO;
        }
        self.i = self.bounded_integral(i);
        self.u_old = self.u_old.clamp_within(self.ymin, self.ymax);
        Ok(())
    }

    /// Whether a sample has been taken since construction or reset.
    const fn started(&self) -> bool {
        self.flags & STARTED != 0
    }

    /// The last sample's measurement, from the derivative's input y − c·r (exact where c·r is,
    /// always for c = 0; within rounding otherwise).
    fn last_measurement(&self) -> T {
        let cr = self.c.mul(self.r_old);
        if T::SATURATES {
            self.yd_old.add(cr)
        } else {
            cr.sub(self.yd_old)
        }
    }

    /// The derivative's input y − c·r as `yd_old` stores it. Floats store its negation c·r − y
    /// (the same number with the sign flipped: negation is exact), which a two-operand machine
    /// computes without a copy of y; fixed point stores y − c·r (a saturated negation would
    /// not be exact).
    #[inline(always)]
    fn derivative_input(&self, r: T, y: T) -> T {
        let cr = self.c.mul(r);
        if T::SATURATES { y.sub(cr) } else { cr.sub(y) }
    }

    fn proportional(&self, r: T, y: T) -> T {
        self.kp.mul(self.b.mul(r).sub(y))
    }

    /// Switches to manual with the output `u` (clamped into the output limits).
    pub fn set_manual(&mut self, u: T) -> Result<(), ValueError> {
        if !u.is_finite() {
            return Err(ValueError::NotFinite);
        }
        self.u_old = u.clamp_within(self.ymin, self.ymax);
        self.set_flags(self.flags | MANUAL);
        Ok(())
    }

    /// Switches back to automatic, bumplessly: the integral is set so that the next output
    /// starts from the manual one (within its bounds, see [`STATE_BOUND`]).
    pub fn set_auto(&mut self) {
        if self.flags == STARTED | MANUAL {
            let p = self.proportional(self.r_old, self.last_measurement());
            self.i = self.bounded_integral(self.u_old.sub(p).sub(self.d));
        }
        self.set_flags(self.flags & !MANUAL);
    }

    /// Auto or manual.
    #[must_use]
    pub const fn mode(&self) -> Mode {
        if self.flags & MANUAL == 0 {
            Mode::Auto
        } else {
            Mode::Manual
        }
    }

    /// The last output.
    #[must_use]
    pub const fn output(&self) -> T {
        self.u_old
    }

    /// The integral term.
    #[must_use]
    pub const fn integral(&self) -> T {
        self.i
    }

    /// The (filtered) derivative term.
    #[must_use]
    pub const fn derivative(&self) -> T {
        self.d
    }

    /// Faults seen since the last [`clear_faults`](Pid::clear_faults).
    #[must_use]
    pub const fn faults(&self) -> Faults {
        self.faults
    }

    /// Clears the fault flags.
    pub fn clear_faults(&mut self) {
        self.faults = Faults::default();
    }

    /// Back to the state at construction (I = D = 0, output 0 clamped), same parameters.
    pub fn reset(&mut self) {
        self.i = T::ZERO;
        self.d = T::ZERO;
        self.yd_old = T::ZERO;
        self.r_old = T::ZERO;
        self.set_flags(0);
        self.faults = Faults::default();
        self.u_old = T::ZERO.clamp_within(self.ymin, self.ymax);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Kind;

    fn pi() -> Config {
        Config {
            kind: Kind::PI,
            k: 2.0,
            ti: 4.0,
            h: 1.0,
            ymin: -10.0,
            ymax: 10.0,
            ..Config::default()
        }
    }

    #[test]
    fn size_is_19_values_and_2_bytes_padded() {
        // 19 values of T, then the flags (started, manual), the faults and the fixed-point gate
        // (3 bytes), padded to T's alignment.
        assert_eq!(core::mem::size_of::<Pid<f32>>(), 19 * 4 + 4);
        assert_eq!(core::mem::size_of::<Pid<f64>>(), 19 * 8 + 8);
    }

    #[test]
    fn first_steps_by_hand() {
        let mut pid = Pid::<f64>::new(&pi()).unwrap();
        // e = 1: P = 2, I = 0 -> u = 2; I += 2·1/4 = 0.5
        assert_eq!(pid.update(1.0, 0.0), 2.0);
        assert_eq!(pid.integral(), 0.5);
        assert_eq!(pid.update(1.0, 0.0), 2.5);
        let reverse = Config {
            action: Action::Reverse,
            ..pi()
        };
        let mut pid = Pid::<f64>::new(&reverse).unwrap();
        assert_eq!(pid.update(1.0, 0.0), -2.0);
    }

    #[test]
    fn back_calculation_is_the_sources_tracking() {
        // Saturated: u = ymax, I takes Y - V every sample (Tt = h).
        let mut pid = Pid::<f64>::new(&pi()).unwrap();
        let u = pid.update(100.0, 0.0); // P = 200, clamps to 10
        assert_eq!(u, 10.0);
        // I = 0 + 0.5·100 + (10 − 200) = −140, so v next = 200 − 140 = 60 → still 10, I = −140 + 50 − 50 …
        assert_eq!(pid.integral(), -140.0);
        let mut last = 0.0;
        for _ in 0..5 {
            last = pid.update(100.0, 0.0);
        }
        assert_eq!(last, 10.0);
        // Error flips sign: the output leaves the limit at once (no windup).
        assert!(pid.update(-1.0, 0.0) < 10.0);
    }

    #[test]
    fn rate_limit_and_clamp() {
        let config = Config {
            dymax: Some(0.5),
            ..pi()
        };
        let mut pid = Pid::<f32>::new(&config).unwrap();
        let mut prev = 0.0;
        for _ in 0..30 {
            let u = pid.update(100.0, 0.0);
            assert!((u - prev).abs() <= 0.5 + 1e-6);
            prev = u;
        }
        assert_eq!(prev, 10.0);
    }

    #[test]
    fn non_finite_inputs_hold_the_output_and_raise_a_fault() {
        let mut pid = Pid::<f32>::new(&pi()).unwrap();
        let u = pid.update(1.0, 0.0);
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert_eq!(pid.update(bad, 0.0), u);
            assert_eq!(pid.update(1.0, bad), u);
        }
        assert!(pid.faults().non_finite_input());
        assert!(!pid.faults().overflow());
        pid.clear_faults();
        assert!(!pid.faults().any());
        let tracked = Inputs {
            feedforward: 0.0,
            track: Some(f32::NAN),
        };
        assert_eq!(pid.update_with(1.0, 0.0, tracked), u);
    }

    #[test]
    fn overflow_holds_the_output() {
        let config = Config {
            k: 1e300,
            kind: Kind::P,
            ymin: -1.0,
            ymax: 1.0,
            ..Config::default()
        };
        let mut pid = Pid::<f64>::new(&config).unwrap();
        assert_eq!(pid.update(0.5, 0.0), 1.0);
        // P = 1e300·2e300 overflows to infinity: the output and the state are held.
        assert_eq!(pid.update(1e300, -1e300), 1.0);
        assert!(pid.faults().overflow());
        assert!(pid.integral().is_finite());
        pid.clear_faults();
        assert_eq!(pid.update(-0.5, 0.0), -1.0);
    }

    #[test]
    fn manual_and_bumpless_return() {
        let mut pid = Pid::<f64>::new(&pi()).unwrap();
        for _ in 0..3 {
            pid.update(5.0, 4.0);
        }
        pid.set_manual(7.5).unwrap();
        assert_eq!(pid.mode(), Mode::Manual);
        assert_eq!(pid.update(5.0, 4.5), 7.5);
        assert_eq!(pid.update(5.0, 4.5), 7.5);
        pid.set_auto();
        // Same set-point and measurement: the first automatic output is the manual one, then
        // the integral moves on by bi·e = 0.5·0.5 per sample.
        let u = pid.update(5.0, 4.5);
        assert!((u - 7.5).abs() < 1e-12, "{u}");
        let u = pid.update(5.0, 4.5);
        assert!((u - 7.75).abs() < 1e-12, "{u}");
        assert_eq!(pid.set_manual(f64::NAN), Err(ValueError::NotFinite));
        pid.set_manual(99.0).unwrap();
        assert_eq!(pid.output(), 10.0, "manual output clamped into the limits");
    }

    #[test]
    fn bumpless_gain_change() {
        let mut pid = Pid::<f64>::new(&pi()).unwrap();
        for _ in 0..5 {
            pid.update(3.0, 2.0);
        }
        let before = pid.update(3.0, 2.0);
        pid.set_config(&Config {
            k: 6.0,
            b: 0.5,
            ..pi()
        })
        .unwrap();
        let after = pid.update(3.0, 2.0);
        // Without the adjustment P would jump from 2 to 6·(1.5 − 2) = −3. Only the integral
        // step moves the output: bi = 6/4, e = 1.
        assert!((after - before - 0.5).abs() < 1e-9, "{before} {after}");
        assert!(pid.set_config(&Config { ti: 0.0, ..pi() }).is_err());
    }

    #[test]
    fn tracking_keeps_the_integral_from_winding_up() {
        let mut pid = Pid::<f64>::new(&pi()).unwrap();
        // An override holds the actuator at 1 while this controller asks for more.
        for _ in 0..100 {
            pid.update_with(
                5.0,
                0.0,
                Inputs {
                    feedforward: 0.0,
                    track: Some(1.0),
                },
            );
        }
        assert!(pid.integral().abs() < 20.0, "{}", pid.integral());
        // Released: the controller's output is near what the actuator had, not wound up. The
        // tracking balances the integration at v = 1 + bi·e/ao = 1 + 0.5·5 = 3.5; without it the
        // integral would have grown by 250 and the output would sit at 10.
        let u = pid.update(5.0, 0.0);
        assert!((u - 3.5).abs() < 1e-9, "{u}");
        let mut free = Pid::<f64>::new(&pi()).unwrap();
        let ff = free.update_with(
            0.0,
            0.0,
            Inputs {
                feedforward: 3.0,
                track: None,
            },
        );
        assert_eq!(ff, 3.0);
    }

    /// A kick decays in the derivative filter: with ad > 1/2 plain float arithmetic would get
    /// stuck at the smallest subnormal (a third of an ulp rounds back up) and pay the
    /// subnormal penalty every sample; with the flush the decay ends on a normal number a few
    /// grid steps (2⁻¹²⁴, 2⁻¹⁰¹³) above 0, never on a subnormal.
    #[test]
    #[cfg_attr(
        miri,
        ignore = "20 000 controller samples in two types: hours under Miri; safe code, run natively in every CI run"
    )]
    fn a_decaying_derivative_never_goes_subnormal() {
        fn run<T: Scalar>(is_subnormal: fn(T) -> bool) -> f64 {
            let config = Config {
                kind: Kind::PD,
                k: 1.0,
                td: 9.0,
                n: 1.0,
                h: 1.0,
                ..Config::default()
            };
            let mut pid = Pid::<T>::new(&config).unwrap();
            pid.update(T::ZERO, T::ZERO);
            pid.update(T::ZERO, T::from_f64(1.0));
            assert!(pid.derivative().to_f64() < -0.5);
            // ad = 0.9: from 1 to 2⁻¹²⁴ takes about 820 samples, to 2⁻¹⁰¹³ about 6700.
            for n in 0..10_000 {
                pid.update(T::ZERO, T::from_f64(1.0));
                assert!(!is_subnormal(pid.derivative()), "sample {n}");
            }
            pid.derivative().to_f64()
        }
        // round(0.9·m) = m for m ≤ 4 grid steps: that is where the decay ends.
        let d = run::<f32>(f32::is_subnormal);
        // 2⁻¹²⁴ and 2⁻¹⁰¹³ from their bits: `powi` is not exact everywhere (nor under Miri).
        assert!(d.abs() <= 5.0 * f64::from_bits((1023 - 124) << 52), "{d:e}");
        let d = run::<f64>(f64::is_subnormal);
        assert!(
            d.abs() <= 5.0 * f64::from_bits((1023 - 1013) << 52),
            "{d:e}"
        );
    }

    /// A kind without I holds a constant bias (its manual reset): a feed-forward, however large,
    /// must not move it, while a kind with I has bounds that follow the feed-forward.
    #[test]
    fn feedforward_never_moves_the_bias_of_a_kind_without_i() {
        let config = Config {
            kind: Kind::PD,
            k: 1.0,
            td: 1.0,
            h: 0.1,
            ymin: -1.0,
            ymax: 1.0,
            ..Config::default()
        };
        let mut pid = Pid::<f64>::new(&config).unwrap();
        pid.update(0.0, 0.0);
        pid.set_manual(0.5).unwrap();
        pid.update(0.0, 0.0);
        pid.set_auto();
        let bias = pid.integral();
        assert_eq!(bias, 0.5);
        for feedforward in [1e6, -1e9, 3.0, 0.0] {
            let inputs = Inputs {
                feedforward,
                track: None,
            };
            pid.update_with(0.0, 0.0, inputs);
            assert_eq!(pid.integral(), bias, "feed-forward {feedforward}");
        }
        assert_eq!(pid.update(0.0, 0.0), 0.5);
    }

    #[cfg(feature = "fixed")]
    #[test]
    fn fixed_point_follows_f64_closely() {
        use fixed::types::{I16F16, I32F32};
        let config = Config {
            kind: Kind::PID,
            k: 1.5,
            ti: 6.0,
            td: 1.0,
            n: 5.0,
            h: 0.5,
            ymin: 0.0,
            ymax: 10.0,
            dymax: Some(1.0),
            ..Config::default()
        };
        let mut a = Pid::<f64>::new(&config).unwrap();
        let mut b = Pid::<I32F32>::new(&config).unwrap();
        let mut c = Pid::<I16F16>::new(&config).unwrap();
        let mut y = 0.0;
        for k in 0..300 {
            let r = if k < 150 { 5.0 } else { 2.0 };
            let ua = a.update(r, y);
            let ub = b
                .update(I32F32::from_num(r), I32F32::from_num(y))
                .to_num::<f64>();
            let uc = c
                .update(I16F16::from_num(r), I16F16::from_num(y))
                .to_num::<f64>();
            assert!((ua - ub).abs() < 1e-6, "{k}: {ua} {ub}");
            assert!((ua - uc).abs() < 0.05, "{k}: {ua} {uc}");
            y += 0.5 * (0.8 * ua - y) * 0.5;
        }
        // A gain I16F16 cannot hold is refused, naming the parameter; with one it can hold,
        // absurd inputs saturate a product: the output is held and the overflow fault raised.
        let too_big = Config {
            k: 30000.0,
            ..config
        };
        assert!(matches!(
            Pid::<I16F16>::new(&too_big),
            Err(ConfigError::Unrepresentable {
                parameter: Parameter::Td,
                ..
            })
        ));
        let mut s = Pid::<I16F16>::new(&Config { td: 0.0, ..too_big }).unwrap();
        assert_eq!(s.update(I16F16::MAX, I16F16::MIN), I16F16::ZERO, "held");
        assert!(s.faults().overflow());
        s.clear_faults();
        assert_eq!(
            s.update(I16F16::ZERO, I16F16::from_num(-0.5)),
            I16F16::from_num(1.0),
            "rate-limited from 0"
        );
        assert!(!s.faults().any());
    }

    /// A sample of the property tests: mostly sane readings, now and then a spike, a NaN or an
    /// infinity.
    fn reading() -> impl proptest::strategy::Strategy<Value = f64> {
        use proptest::prelude::{Just, prop_oneof};
        prop_oneof![
            8 => -100.0f64..100.0,
            1 => Just(0.0),
            1 => proptest::sample::select(vec![1e4, -1e4, 1e9, -1e9, 1e30, -1e30, 3e38, -3e38, 1e300]),
            1 => proptest::sample::select(vec![f64::NAN, f64::INFINITY, f64::NEG_INFINITY]),
        ]
    }

    fn any_config() -> impl proptest::strategy::Strategy<Value = Config> {
        use proptest::prelude::{Just, prop, prop_oneof};
        use proptest::strategy::Strategy;
        (
            (
                prop::sample::select(Kind::ALL.to_vec()),
                proptest::bool::ANY,
                0.01f64..20.0,
                0.1f64..100.0,
                0.0f64..20.0,
                1.0f64..20.0,
            ),
            (
                0.0f64..1.0,
                0.0f64..1.0,
                prop::option::of(0.51f64..50.0),
                0.01f64..5.0,
            ),
            (
                -50.0f64..0.0,
                0.0f64..50.0,
                prop::option::of(prop_oneof![Just(0.0), 0.01f64..10.0]),
                0u8..8,
            ),
        )
            .prop_map(
                |(
                    (kind, reverse, k, ti, td, n),
                    (b, c, tt_samples, h),
                    (ymin, ymax, dymax, shape),
                )| {
                    // Now and then limits that leave one output value (0 or another): a scale
                    // of 0 (bounds of 0) or a span of 0.
                    let (ymin, ymax) = match shape {
                        0 => (0.0, 0.0),
                        1 => (ymax, ymax),
                        _ => (ymin, ymax),
                    };
                    Config {
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
                        tt: tt_samples.map(|m| m * h),
                        h,
                        ymin,
                        ymax,
                        dymax,
                    }
                },
            )
    }

    /// One sample through `update` (or `update_with`) and the same sample through the general
    /// path on a copy: the same output and the same state, flags and faults. `event` 0..=5 is
    /// a plain sample, 6 one with feed-forward and tracking, 7 a switch to manual, 8 back to
    /// automatic.
    fn fast_equals_general<T: Scalar>(pid: &mut Pid<T>, event: u8, r: f64, y: f64, extra: f64) {
        let (rt, yt, xt) = (T::from_f64(r), T::from_f64(y), T::from_f64(extra));
        match event {
            7 => {
                let _ = pid.set_manual(xt);
                return;
            }
            8 => {
                pid.set_auto();
                return;
            }
            _ => {}
        }
        let mut general = pid.clone();
        let (fast, slow) = if event == 6 && extra.is_finite() {
            let inputs = Inputs {
                feedforward: xt,
                track: (r > 0.0).then_some(xt),
            };
            (
                pid.update_with(rt, yt, inputs),
                general.step_general::<true>(rt, yt, inputs.feedforward, inputs.track),
            )
        } else {
            (
                pid.update(rt, yt),
                general.step_general::<false>(rt, yt, T::ZERO, None),
            )
        };
        assert_eq!(fast, slow, "output for r = {r:e}, y = {y:e}");
        assert_eq!(*pid, general, "state after r = {r:e}, y = {y:e}");
    }

    /// The fast path of `update` is a shortcut, never another algorithm: for any configuration,
    /// any sequence of readings (spikes, NaN and infinities among them) and mode switches, it
    /// gives the output and leaves the state that the general path gives for the same sample, in
    /// `f32` and `f64`. It fails if the fast path admits a sample the general path would bound
    /// (an integral or derivative state beyond `STATE_BOUND`, a non-finite value), mis-signs a
    /// term, or runs in manual mode or on the first sample.
    #[test]
    fn the_fast_path_is_the_general_path() {
        use proptest::prelude::{ProptestConfig, prop, proptest};
        // Under Miri 4 runs of up to 20 samples.
        let longest = if cfg!(miri) { 20 } else { 120 };
        proptest!(ProptestConfig::with_cases(if cfg!(miri) { 4 } else { 500 }), |(
            config in any_config(),
            samples in prop::collection::vec((0u8..9, reading(), reading(), reading()), 1..longest),
        )| {
            // Degenerate limits (ymin = ymax = 0) make some rate limits unrepresentable.
            let (Ok(mut single), Ok(mut double)) = (Pid::<f32>::new(&config), Pid::<f64>::new(&config))
            else {
                return Ok(());
            };
            for &(event, r, y, extra) in &samples {
                fast_equals_general(&mut single, event, r, y, extra);
                fast_equals_general(&mut double, event, r, y, extra);
            }
        });
    }

    #[test]
    fn faults_say_which_and_any_follows_them() {
        let cases = [
            (0, false, "no fault"),
            (
                Faults::NON_FINITE_INPUT,
                true,
                "non-finite input: output held",
            ),
            (Faults::OVERFLOW, true, "overflow: output held"),
            (
                Faults::NON_FINITE_INPUT | Faults::OVERFLOW,
                true,
                "non-finite input and overflow: output held",
            ),
        ];
        for (bits, any, text) in cases {
            let faults = Faults(bits);
            assert_eq!(faults.any(), any, "{text}");
            assert_eq!(faults.to_string(), text);
        }
        // As a user meets them: a NaN measurement is a fault, named, until cleared.
        let mut pid = Pid::<f64>::new(&pi()).unwrap();
        assert!(!pid.faults().any());
        let _ = pid.update(1.0, f64::NAN);
        assert!(pid.faults().any());
        assert_eq!(pid.faults().to_string(), "non-finite input: output held");
        assert_eq!(
            ValueError::NotFinite.to_string(),
            "the value must be a finite number"
        );
    }
}
