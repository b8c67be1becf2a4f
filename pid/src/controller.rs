//! The controller: Åström's PID with filtered derivative, set-point weights, back-calculation
//! anti-windup, rate limit and clamps.

use core::fmt;

use crate::config::{Action, Config, ConfigError, Parameter};
use crate::real::Real;
use crate::scalar::Scalar;

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

    /// The computation overflowed (a float became infinite): the output and state were held.
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
/// `T` and 4 bytes of flags, padded to `T`'s alignment: 80 bytes for `f32`, 160 for `f64` and
/// `I32F32`.
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
    kp: T,
    b: T,
    c: T,
    bi: T,
    ad: T,
    bd: T,
    ao: T,
    ymin: T,
    ymax: T,
    dymax: T,
    /// kp·(1 − b): the P term's steady-state offset per unit of set-point, which the integral
    /// must cancel; the integral's bounds move with it.
    offset_slope: T,
    i_lo: T,
    i_hi: T,
    d_bound: T,
    i: T,
    d: T,
    y_old: T,
    r_old: T,
    u_old: T,
    has_dymax: bool,
    started: bool,
    mode: Mode,
    faults: Faults,
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
    i_lo: T,
    i_hi: T,
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
            // Kinds without I hold a constant bias (their manual reset): no clamp per sample;
            // where the bias is set, `bounded_integral` bounds it around the output limits.
            offset_slope: if kind.has_i() {
                T::from_real(kp * (one - config.b))
            } else {
                T::ZERO
            },
            i_lo: if kind.has_i() {
                T::from_real(config.ymin - bound)
            } else {
                T::ZERO.sub(T::MAX)
            },
            i_hi: if kind.has_i() {
                T::from_real(config.ymax + bound)
            } else {
                T::MAX
            },
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

impl<T: Scalar> Pid<T> {
    /// A controller for `config` (in `f64` or `f32`), or the error naming its bad parameter.
    ///
    /// Besides [`Config::validate`], every coefficient and limit must convert into `T` within
    /// [`TOLERANCE`]; otherwise [`ConfigError::Unrepresentable`] names the parameter.
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
            i_lo: zero,
            i_hi: zero,
            d_bound: zero,
            i: zero,
            d: zero,
            y_old: zero,
            r_old: zero,
            u_old: zero,
            has_dymax: false,
            started: false,
            mode: Mode::Auto,
            faults: Faults::default(),
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
        self.has_dymax = k.dymax.is_some();
        self.dymax = k.dymax.unwrap_or(T::ZERO);
        self.offset_slope = k.offset_slope;
        self.i_lo = k.i_lo;
        self.i_hi = k.i_hi;
        self.d_bound = k.d_bound;
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

    /// The integral's bounds at set-point `r`: [`STATE_BOUND`] output scales beyond the values
    /// that hold the output at a limit in steady state.
    #[inline(always)]
    fn integral_bounds(&self, r: T, feedforward: T) -> (T, T) {
        let center = self.offset_slope.mul(r).sub(feedforward);
        (self.i_lo.add(center), self.i_hi.add(center))
    }

    #[inline(always)]
    fn step<const FEEDFORWARD: bool>(&mut self, r: T, y: T, feedforward: T, track: Option<T>) -> T {
        // Nothing is stored until the result is known to be finite: a NaN on the first sample
        // must not become y_old.
        let (y_old, r_old) = if self.started {
            (self.y_old, self.r_old)
        } else {
            (y, r)
        };
        let p = self.kp.mul(self.b.mul(r).sub(y));
        let change = y.sub(self.c.mul(r)).sub(y_old.sub(self.c.mul(r_old)));
        let d = self
            .ad
            .mul(self.d)
            .sub(self.bd.mul(change))
            .flush_tiny()
            .clamp_within(T::ZERO.sub(self.d_bound), self.d_bound);
        let (v, u, i) = match self.mode {
            Mode::Manual => {
                // The operator's output stands; I follows so that v = u when auto returns.
                let u = self.u_old;
                (u, u, u.sub(p).sub(d))
            }
            Mode::Auto => {
                let mut v = p.add(self.i).add(d);
                if FEEDFORWARD {
                    v = v.add(feedforward);
                }
                let mut u = v;
                if self.has_dymax {
                    u = u.clamp_within(self.u_old.sub(self.dymax), self.u_old.add(self.dymax));
                }
                u = u.clamp_within(self.ymin, self.ymax);
                let applied = track.unwrap_or(u);
                // I + (integral step + tracking), summed in the reference's order.
                let step = self.bi.mul(r.sub(y)).add(self.ao.mul(applied.sub(v)));
                (v, u, self.i.add(step))
            }
        };
        // The bounds move with the set-point (for kinds without I they are ±MAX and the clamp
        // changes nothing).
        let (lo, hi) = self.integral_bounds(r, feedforward);
        let bounded = i.clamp_within(lo, hi);
        // P is NaN or infinite whenever r or y is (0·∞ is NaN), and v and the unbounded I both
        // contain P; the bounds are infinite when an absurd set-point overflows them. One sum
        // and one test cover all three (a sum of two finite states overflows only beyond
        // 10³⁸, where a fault is the right answer anyway).
        if !T::both_finite(v, i.add(bounded)) {
            self.fault(r, y);
            return self.u_old;
        }
        let i = bounded;
        self.started = true;
        self.i = i;
        self.d = d;
        self.y_old = y;
        self.r_old = r;
        self.u_old = track.unwrap_or(u);
        u
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

    /// Whether the kind has I (the others hold a constant bias, their manual reset, bounded only
    /// where it is set). Exactly the kinds with a tracking coefficient: `new` refuses an `ao`
    /// that vanishes for them.
    fn integrates(&self) -> bool {
        self.ao != T::ZERO
    }

    /// `i` within the integral's bounds at the last set-point, or for a kind without I (whose
    /// bias a spike must not hold at a limit for good) within [`STATE_BOUND`] scales of the output
    /// limits; a non-finite `i` (a new gain so large that the bumpless adjustment overflowed)
    /// becomes the nearest in-bound value to 0.
    fn bounded_integral(&self, i: T) -> T {
        // A kind without I never moves its bias again, so its bounds must not follow a set-point
        // that may have been absurd: they sit around the output limits themselves.
        let (lo, hi) = if self.integrates() {
            self.integral_bounds(self.r_old, T::ZERO)
        } else {
            (self.ymin.sub(self.d_bound), self.ymax.add(self.d_bound))
        };
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
        let p_before = self.proportional(self.r_old, self.y_old);
        self.apply(k);
        let mut i = self.i;
        if self.started {
            let p_after = self.proportional(self.r_old, self.y_old);
            i = i.add(p_before).sub(p_after);
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

    fn proportional(&self, r: T, y: T) -> T {
        self.kp.mul(self.b.mul(r).sub(y))
    }

    /// Switches to manual with the output `u` (clamped into the output limits).
    pub fn set_manual(&mut self, u: T) -> Result<(), ValueError> {
        if !u.is_finite() {
            return Err(ValueError::NotFinite);
        }
        self.u_old = u.clamp_within(self.ymin, self.ymax);
        self.mode = Mode::Manual;
        Ok(())
    }

    /// Switches back to automatic, bumplessly: the integral is set so that the next output
    /// starts from the manual one (within its bounds, see [`STATE_BOUND`]).
    pub fn set_auto(&mut self) {
        if self.mode == Mode::Manual && self.started {
            let p = self.proportional(self.r_old, self.y_old);
            self.i = self.bounded_integral(self.u_old.sub(p).sub(self.d));
        }
        self.mode = Mode::Auto;
    }

    /// Auto or manual.
    #[must_use]
    pub const fn mode(&self) -> Mode {
        self.mode
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
        self.y_old = T::ZERO;
        self.r_old = T::ZERO;
        self.started = false;
        self.mode = Mode::Auto;
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
    fn size_is_19_values_and_4_bytes_padded() {
        // 19 values of T, then 2 flags, the mode and the faults (4 bytes), padded to T's alignment.
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
        // A gain I16F16 cannot hold is refused, naming the parameter; one it can hold
        // saturates instead of overflowing with absurd inputs.
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
        assert_eq!(
            s.update(I16F16::MAX, I16F16::MIN),
            I16F16::from_num(1.0),
            "rate-limited from 0"
        );
    }
}
