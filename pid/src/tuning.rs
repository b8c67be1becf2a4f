//! Tuning rules and the relay auto-tuning experiment — the "adaptivity: a simple adaptive
//! algorithm, or a discrete Ziegler–Nichols-style rule" that source 002's specification asked for
//! and the 1985 controller never got.
//!
//! - [`Relay`]: the Åström–Hägglund relay experiment, one [`Relay::update`] per sample like the
//!   controller. A relay with hysteresis around the set-point drives the process into a limit
//!   cycle; from its amplitude *a* and period the experiment estimates the ultimate gain
//!   Ku = 4d / (π·√(a² − ε²)) and the ultimate period Tu. It checks that enough cycles agree, that
//!   the oscillation is not noise chatter, that the amplitude clears the hysteresis, and gives up
//!   after a time-out; it can be aborted at any sample and hands over bumplessly to the tuned
//!   controller ([`Relay::hand_over`]).
//! - Rules: [`ziegler_nichols`] (classic, from Ku and Tu), [`amigo`] (Åström–Hägglund's AMIGO,
//!   from a first-order-plus-dead-time model), [`simc`] (Skogestad's SIMC, from the same model).
//!   Each gives a [`Tuning`] that [`Tuning::apply`] writes into a [`Config`].
//! - [`identify_step_at`] (and [`identify_step`], the log starting at the step): a
//!   first-order-plus-dead-time model from a logged step response (method of areas), for the
//!   model-based rules.
//!
//! The relay counts its samples in a `u64` and computes every time as count·h where it is used
//! (an `f32` clock `t += h` stops advancing): in `f32` and `f64` it gives up at the same sample,
//! ⌊timeout/h⌋ + 1 (when timeout/h is exact in both; a time-out of more than 2⁶⁴ samples is
//! refused), and a period is a difference of counts however late the oscillation starts.
//! [`Relay::hand_over`] refuses a controller whose [`Action`] is not the experiment's, and a
//! set-point or measurement that is not finite (naming which). The relay never returns a
//! non-finite Ku: √(a² − ε²) is computed as a·√(1 − (ε/a)²) (no underflow at a = 10⁻²³ in
//! `f32`), and a Ku that still overflows is [`RelayError::AmplitudeUnmeasurable`].
//!
//! # What the step identification accepts and how close it gets
//! Tested in `tests/tuning.rs` (property over K of either sign from 0.01 to 100, T from 0.1 to
//! 100 s, L from 0 to 3T, 30 to 3 000 samples per T + L, logs reaching 8 to 20 time constants
//! past the dead time, a baseline within 10⁴ × the change in `f64` and 10³ × in `f32` (the
//! change then spans at least 8 000 ulps of the samples: a change of 80 ulps rounds every
//! sample by 0.6 % of it), uniform noise of peak up to 2 % of the change with 20 to 500 samples
//! before the step, corners drawn on purpose, 5 000 cases run once and 20 000 noise seeds at
//! the corners; and logs of 0.7 and 3 million samples): K is within 1 % + ν, and T and L
//! within 2 % of T + L, plus h, plus ν·(T + L + 10·D/√N), where ν is the noise's peak as a
//! fraction of the change, D the log's length from the step and N its number of samples from
//! the step (the final value is a mean over the last tenth, and its error counts over the
//! whole log). Without samples before the step the baseline is one sample and its noise
//! enters the model unaveraged (tested noise-free only). The noise term is for white noise
//! (independent from sample to sample, as tested), which the means average: a bias of ν
//! confined to the last tenth is not averaged out, and moves T + L by up to about ν·D.
//!
//! The samples' own rounding adds to that tolerance. With ρ = ε times the largest sample's
//! magnitude (at least the type's smallest normal value), over the fitted change |K·step| —
//! one to two ulps of the largest sample, as a fraction of the change — K is within the
//! tolerance above plus ρ of the fitted K (plus the smallest positive value of the type where
//! the gain is subnormal), and T and L plus ρ·(10·(T + L) + 4·D): the baseline
//! and the final value are each off by up to half an ulp, an error that no averaging removes
//! and that the areas integrate over the whole log. ρ is 10⁻¹⁶ × the baseline's ratio to the
//! change in `f64` and 10⁻⁷ × in `f32`: it matters only for a change of few ulps, a subnormal
//! change or one under a baseline 10⁵ times larger in `f32`. Tested noise-free with changes of
//! 1 to 2²³ − 1 ulps of the smallest subnormal value in `f32` and `f64`, and with `f32`
//! changes under baselines up to 10⁶ times them, at the offsets from the float grid that round
//! the baseline and the final value apart (a change of one ulp is
//! [`IdentifyError::NoResponse`]). The rules below allow for the rounding too.
//!
//! The means are sums of deviations from their first sample: a log multiplied by a power of
//! two gives the same T and L and the gain multiplied by it, exactly, as long as the change
//! fits the type, the gain is normal, and the means' deviations stay normal (from 2⁻¹⁰⁰ × a log of unit level in
//! `f32`, 2⁻¹⁰⁰⁰ × in `f64`: below, a subnormal deviation loses bits) — tested from 2⁻¹⁰⁰ to
//! 2¹²³ in `f32`, 2⁻¹⁰⁰⁰ to 2¹⁰²³ in `f64`, noisy logs of 10⁵ and 10⁶ samples, a log of 1.4
//! million `f32` samples at 2¹¹⁰, a change of 0.995 × `f64::MAX` from a negative baseline, and
//! logs whose first sample is an outlier at the scales where their means' sums overflow. The
//! verdict does not depend on the sample period h (it is reached in samples): at a
//! power-of-two h, T and L are exactly h times the fit at h = 1 while they stay normal, and
//! T + L or T that overflow, or a T that rounds to 0, are named after the verdict.
//!
//! A noise-free first-order log shorter than that (1 to 8 T past the dead time, tested) is
//! refused when shorter than 5 T and otherwise gives K within 1 % and T and L within 4 % of
//! T + L plus h. A noisy log shorter than 8 T can pass with K off by more: log at least 8 T.
//!
//! The response is refused, never fitted, when — with "noise" the largest deviation from the
//! baseline of the samples it is the mean of (those before the step and the one at its instant)
//! when 20 or more samples precede the step (a process still oscillating at the end of the log
//! is not its own noise), otherwise the larger of that and half the largest change between
//! neighbouring samples of the last tenth:
//! - it has not settled: the mean of the last tenth differs from the mean of the tenth before
//!   by more than 0.2 % of the change plus 4·noise/√(samples in a tenth) plus ρ of it
//!   ([`IdentifyError::NotSettled`]; an integrating process's ramp ends here);
//! - the change is within twice the noise plus ρ of it (the rounding's peak, twice)
//!   ([`IdentifyError::NoResponse`]: a change of one ulp is none);
//! - it rises above its final level (the last tenth's mean) by more than 1 % of the change
//!   plus twice the noise plus 2ρ of it ([`IdentifyError::Overshoot`]: an underdamped or oscillating
//!   response), or first goes the wrong way by as much ([`IdentifyError::Undershoot`]: an
//!   inverse response);
//! - the fitted T is not positive or L is below minus the tolerance above
//!   ([`IdentifyError::NotFopdt`]);
//! - the change, the gain change/step, T + L or T overflow the float type (the means never
//!   do: a mean of values of the type is one) ([`IdentifyError::Overflow`]), or the gain or
//!   T round to 0 ([`IdentifyError::Underflow`]).
//!
//! Tested: second-order responses with an overshoot of 2 % or more, inverse responses that go
//! the wrong way by 2 % or more, and integrating processes, with noise up to 0.2 % of the
//! change, all give an error; so does a first-order response with an oscillation of 2 % to
//! 50 % of the change still going at the end of the log, of any period from 6 samples up to a
//! third of the last tenth with 20 or more samples before the step, and from 32 samples
//! without them (a faster oscillation then reads as noise).
//!
//! # Tuning rules and the sample period
//! Every rule's `Ok` has K and Ti finite and positive and Td finite and not negative; a result
//! that overflows or vanishes is [`RuleError::Result`]. AMIGO and SIMC need a dead time, and
//! a sampled controller adds h/2 of it: tune from [`Fopdt::with_sampling_delay`]. A model with a
//! dead time far below h (a pure lag fitted with L ≈ 0) gives Ti < h and a huge gain;
//! [`Tuning::apply`] refuses Ti < h. Tested: identify → AMIGO PI/PID or SIMC → apply on pure
//! lags of T = 2 to 200 samples: the raw model is refused where Ti < h, the model with the
//! sampling delay gives a loop that settles.
//!
//! # How close the relay gets
//! The estimate rests on the describing function, which keeps only the fundamental of the
//! oscillation. Measured by `tests/tuning.rs` (h = 5 ms, ε = 0.002, d = 1) against the analytic
//! ultimate points:
//!
//! | process | Ku found / true | Tu found / true |
//! |---|---|---|
//! | 1/(s+1)³ | 7.79 / 8.00 (−2.7 %) | 3.69 / 3.63 (+1.7 %) |
//! | 1/(s+1)⁴ | 3.97 / 4.00 (−0.8 %) | 6.32 / 6.28 (+0.5 %) |
//! | 1/(s+1)⁸ | 1.88 / 1.88 (−0.4 %) | 15.09 / 15.17 (−0.5 %) |
//! | e^(−s)/(1+0.1s) | 1.27 / 1.04 (+22 %) | 2.14 / 2.20 (−2.5 %) |
//! | e^(−s)/(1+0.5s) | 1.47 / 1.52 (−3.2 %) | 2.63 / 2.75 (−4.2 %) |
//! | e^(−s)/(1+s) | 2.01 / 2.26 (−11 %) | 2.99 / 3.10 (−3.5 %) |
//! | e^(−s)/(1+2s) | 3.23 / 3.81 (−15 %) | 3.34 / 3.42 (−2.4 %) |
//! | e^(−s)/(1+10s) | 13.1 / 16.4 (−20 %) | 3.90 / 3.85 (+1.3 %) |
//!
//! Tu is within 5 % everywhere; Ku within a few % for lag chains, and from −20 % (lag-dominated
//! with dead time) to +22 % (nearly pure dead time: the output is almost the relay's square wave)
//! otherwise — the classic limits of the method. Measurement noise and a large hysteresis bias Ku
//! low, the safe direction.
#![allow(
    clippy::arithmetic_side_effects,
    reason = "arithmetic here is on Real (sealed: f32 or f64), which cannot panic or wrap; every input is checked finite first and results are validated by Config"
)]

use core::fmt;

use crate::real::Sum;
use crate::{Action, Config, ConfigError, Kind, Pid, Real, Scalar};

/// The ultimate point of a process: where its phase reaches −180°.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Ultimate<F = f64> {
    /// Ultimate gain Ku: the proportional gain at which the loop oscillates.
    pub ku: F,
    /// Ultimate period Tu, seconds.
    pub tu: F,
}

/// A first-order-plus-dead-time model K·e^(−sL) / (1 + sT).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Fopdt<F = f64> {
    /// Static gain K (output units per controller-output unit; its sign is the process's).
    pub gain: F,
    /// Time constant T, seconds.
    pub time_constant: F,
    /// Dead time L, seconds.
    pub dead_time: F,
}

impl<F: Real> Fopdt<F> {
    /// The model a controller sampled every `h` seconds sees: the dead time plus h/2, the
    /// average delay of the sample-and-hold (Skogestad's practice for digital control). The
    /// model-based rules need a dead time: a process without one (a pure lag, which
    /// [`identify_step_at`] fits with L ≈ 0) gets its gain bounded by the sampling instead of
    /// an unbounded one.
    ///
    /// ```
    /// use regler_pid::Kind;
    /// use regler_pid::tuning::{amigo, Fopdt};
    ///
    /// let pure_lag = Fopdt { gain: 1.0, time_constant: 10.0, dead_time: 0.0 };
    /// assert!(amigo(pure_lag, Kind::PI).is_err()); // no dead time: no setting
    /// let t = amigo(pure_lag.with_sampling_delay(0.1), Kind::PI)?;
    /// assert!(t.k < 100.0 && t.ti > 0.1);
    /// # Ok::<(), regler_pid::tuning::RuleError>(())
    /// ```
    #[must_use]
    pub fn with_sampling_delay(self, h: F) -> Self {
        Self {
            dead_time: self.dead_time + h * F::from_f64_nearest(0.5),
            ..self
        }
    }
}

/// Controller parameters a rule gives.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Tuning<F = f64> {
    /// P, PI or PID.
    pub kind: Kind,
    /// Gain K (positive; the direction is the configuration's [`Action`]).
    pub k: F,
    /// Integral time Ti, seconds (unused for P).
    pub ti: F,
    /// Derivative time Td, seconds (0 without D).
    pub td: F,
    /// Set-point weight on P that the rule recommends.
    pub b: F,
}

impl<F: Real> Tuning<F> {
    /// Writes kind, K, Ti, Td and b into `config` (everything else — action, filter, limits,
    /// sample period — stays) and validates the result.
    ///
    /// An integral time shorter than the sample period is refused: a rule gives one for a model
    /// whose dead time is a small fraction of h (AMIGO PI: Ti ≈ 13·L for L ≪ T), and the gain
    /// that comes with it (≈ 0.35·T/L) makes the sampled loop swing between its limits. Tune
    /// from [`Fopdt::with_sampling_delay`] instead.
    ///
    /// # Errors
    /// The configuration's own validation error; [`ConfigError::OutOfRange`] for
    /// [`Parameter::Ti`](crate::Parameter::Ti) when the kind has I and Ti < `config.h`;
    /// `config` is unchanged then.
    pub fn apply(&self, config: &mut Config<F>) -> Result<(), ConfigError<F>> {
        if self.kind.has_i() && self.ti < config.h {
            return Err(ConfigError::OutOfRange {
                parameter: crate::Parameter::Ti,
                value: self.ti,
                requirement: "at least the sample period h for a tuning rule's result (the model's dead time is far below h: tune from Fopdt::with_sampling_delay(h))",
            });
        }
        let mut next = *config;
        next.kind = self.kind;
        next.k = self.k;
        if self.kind.has_i() {
            next.ti = self.ti;
        }
        next.td = self.td;
        next.b = self.b;
        next.validate()?;
        *config = next;
        Ok(())
    }
}

/// Why a rule could not give parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum RuleError {
    /// Every input must be finite and positive (the gain's magnitude is used); this one is not.
    Input(&'static str),
    /// The rule has no setting for this controller kind.
    Kind(Kind),
    /// The rule's result (named) is not a finite positive number for these inputs (they are
    /// finite, but their ratios overflow or vanish in this float type).
    Result(&'static str),
}

impl fmt::Display for RuleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Input(name) => write!(f, "{name} must be finite and positive"),
            Self::Kind(kind) => write!(
                f,
                "the rule has no setting for a {} controller",
                kind.name()
            ),
            Self::Result(name) => write!(
                f,
                "the rule's {name} is not a finite positive number for these inputs (they overflow or vanish in this float type)"
            ),
        }
    }
}

impl core::error::Error for RuleError {}

fn positive<F: Real>(value: F, name: &'static str) -> Result<F, RuleError> {
    if value.is_finite() && value > F::zero() {
        Ok(value)
    } else {
        Err(RuleError::Input(name))
    }
}

/// A rule's result, checked: K and Ti finite and positive, Td finite and not negative.
fn checked<F: Real>(t: Tuning<F>) -> Result<Tuning<F>, RuleError> {
    positive(t.k, "gain K").map_err(|_| RuleError::Result("gain K"))?;
    positive(t.ti, "Ti").map_err(|_| RuleError::Result("integral time Ti"))?;
    if !(t.td.is_finite() && t.td >= F::zero()) {
        return Err(RuleError::Result("derivative time Td"));
    }
    Ok(t)
}

fn c<F: Real>(v: f64) -> F {
    F::from_f64_nearest(v)
}

/// Ziegler–Nichols' classic frequency-response rule: P: K = 0.5·Ku; PI: K = 0.45·Ku,
/// Ti = Tu/1.2; PID: K = 0.6·Ku, Ti = Tu/2, Td = Tu/8 (b = 1).
///
/// ```
/// use regler_pid::Kind;
/// use regler_pid::tuning::{ziegler_nichols, Ultimate};
///
/// let t = ziegler_nichols(Ultimate { ku: 8.0, tu: 3.63 }, Kind::PID)?;
/// assert_eq!((t.k, t.ti, t.td), (4.8, 1.815, 0.45375));
/// # Ok::<(), regler_pid::tuning::RuleError>(())
/// ```
///
/// # Errors
/// Ku or Tu not finite and positive; a kind other than P, PI, PID; [`RuleError::Result`] when a
/// result overflows.
pub fn ziegler_nichols<F: Real>(ultimate: Ultimate<F>, kind: Kind) -> Result<Tuning<F>, RuleError> {
    let ku = positive(ultimate.ku, "Ku")?;
    let tu = positive(ultimate.tu, "Tu")?;
    let one = F::one();
    let (k, ti, td) = match kind {
        Kind::P => (ku * c(0.5), tu, F::zero()),
        Kind::PI => (ku * c(0.45), tu / c(1.2), F::zero()),
        Kind::PID => (ku * c(0.6), tu * c(0.5), tu * c(0.125)),
        other => return Err(RuleError::Kind(other)),
    };
    checked(Tuning {
        kind,
        k,
        ti,
        td,
        b: one,
    })
}

/// AMIGO (Åström & Hägglund, *Advanced PID Control*, 2006) from an FOPDT model, for PI or PID.
/// With τ = L/(L + T):
/// - PI: K·Kp = 0.15 + (0.35 − LT/(L + T)²)·T/L, Ti = 0.35L + 13LT²/(T² + 12LT + 7L²);
/// - PID: K·Kp = 0.2 + 0.45·T/L, Ti = (0.4L + 0.8T)/(L + 0.1T)·L, Td = 0.5LT/(0.3L + T);
/// - b = 0 when τ < 0.5 (lag-dominated: weight the set-point out of P), else 1.
///
/// # Errors
/// K, T or L not finite and non-zero (L > 0, T > 0); a kind other than PI or PID;
/// [`RuleError::Result`] naming a result that is not a finite positive number (T = 10³⁰ or
/// T = L = 10⁻³⁰ in `f32`: the ratios overflow or vanish).
pub fn amigo<F: Real>(model: Fopdt<F>, kind: Kind) -> Result<Tuning<F>, RuleError> {
    let gain = positive(model.gain.abs(), "the process gain")?;
    let t = positive(model.time_constant, "the time constant")?;
    let l = positive(model.dead_time, "the dead time")?;
    let tau = l / (l + t);
    let b = if tau < c(0.5) { F::zero() } else { F::one() };
    match kind {
        Kind::PI => {
            let k = (c::<F>(0.15) + (c::<F>(0.35) - l * t / ((l + t) * (l + t))) * t / l) / gain;
            let ti = c::<F>(0.35) * l
                + c::<F>(13.0) * l * t * t / (t * t + c::<F>(12.0) * l * t + c::<F>(7.0) * l * l);
            checked(Tuning {
                kind,
                k,
                ti,
                td: F::zero(),
                b,
            })
        }
        Kind::PID => {
            let k = (c::<F>(0.2) + c::<F>(0.45) * t / l) / gain;
            let ti = (c::<F>(0.4) * l + c::<F>(0.8) * t) / (l + c::<F>(0.1) * t) * l;
            let td = c::<F>(0.5) * l * t / (c::<F>(0.3) * l + t);
            checked(Tuning { kind, k, ti, td, b })
        }
        other => Err(RuleError::Kind(other)),
    }
}

/// SIMC (Skogestad, 2003) PI from an FOPDT model with closed-loop time constant `tc` (Skogestad's
/// default for tight control is tc = L): Kp = T / (K·(tc + L)), Ti = min(T, 4·(tc + L)).
///
/// ```
/// use regler_pid::tuning::{simc, Fopdt};
///
/// let model = Fopdt { gain: 2.0, time_constant: 10.0, dead_time: 1.0 };
/// let t = simc(model, 1.0)?;
/// assert_eq!((t.k, t.ti), (2.5, 8.0));
/// # Ok::<(), regler_pid::tuning::RuleError>(())
/// ```
///
/// # Errors
/// An input that is not finite and positive (the gain's magnitude is used);
/// [`RuleError::Result`] naming a result that is not a finite positive number.
pub fn simc<F: Real>(model: Fopdt<F>, tc: F) -> Result<Tuning<F>, RuleError> {
    let gain = positive(model.gain.abs(), "the process gain")?;
    let t = positive(model.time_constant, "the time constant")?;
    let l = positive(model.dead_time, "the dead time")?;
    let tc = positive(tc, "the closed-loop time constant")?;
    let k = t / (gain * (tc + l));
    let four = c::<F>(4.0) * (tc + l);
    let ti = if t < four { t } else { four };
    checked(Tuning {
        kind: Kind::PI,
        k,
        ti,
        td: F::zero(),
        b: F::one(),
    })
}

/// Why a step response could not be turned into a model.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum IdentifyError<F = f64> {
    /// Fewer than 20 samples from the step on.
    TooFewSamples(usize),
    /// The sample period is not finite, positive and normal, or the step size not finite and
    /// non-zero (named). A subnormal sample period (below 2.2·10⁻³⁰⁸ s in `f64`) is refused:
    /// T and L, multiples of it, would come out a few ulps long, beyond the stated tolerance.
    Input(&'static str),
    /// The step index is not inside the log (the index, the log's length).
    StepOutsideLog(usize, usize),
    /// A sample is not finite (at this index).
    NotFinite(usize),
    /// The response has not settled: the mean of its last tenth differs from the mean of the
    /// tenth before by this fraction of the change (e.g. an integrating process, whose step
    /// response is a ramp, or a log too short for the process).
    NotSettled(F),
    /// The process did not respond (its change is within twice the samples' noise, their
    /// rounding included: a change of one ulp is no response).
    NoResponse,
    /// The response rises above its final value by this fraction of the change: an overshoot
    /// or an oscillation, which a first-order-plus-dead-time response never has.
    Overshoot(F),
    /// The response first moves the wrong way, by this fraction of the change: an inverse
    /// response, which a first-order-plus-dead-time response never has.
    Undershoot(F),
    /// The response is not of the first-order-plus-dead-time kind (the fitted time constant
    /// came out not positive or the dead time clearly negative).
    NotFopdt,
    /// A quantity (named) overflows the float type: a change (final value − baseline) beyond
    /// its largest value, or a step so small that change / step does not fit, or T + L or T
    /// (a huge sample period), or the last tenths' movement over the change.
    Overflow(&'static str),
    /// A quantity (named) underflows the float type: a gain change / step that rounds to 0 (a
    /// step huge against the change), or a T that rounds to 0 (a fraction of a sample at a
    /// sample period near the smallest normal value).
    Underflow(&'static str),
}

impl<F: Real> fmt::Display for IdentifyError<F> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooFewSamples(n) => {
                write!(f, "{n} samples from the step on: at least 20 are needed")
            }
            Self::Input(what) => write!(
                f,
                "{what} is out of range (the sample period must be finite, positive and normal, the step finite and non-zero)"
            ),
            Self::StepOutsideLog(at, len) => {
                write!(
                    f,
                    "the step at sample {at} is outside the log of {len} samples"
                )
            }
            Self::NotFinite(k) => write!(f, "sample {k} is not finite"),
            Self::NotSettled(moving) => {
                write!(
                    f,
                    "the response has not settled (its last tenth differs from the tenth before by {:.2} % of the change): log longer",
                    percent(*moving)
                )
            }
            Self::NoResponse => f.write_str("the process did not respond to the step"),
            Self::Overshoot(by) => write!(
                f,
                "the response overshoots its final value by {:.1} % of the change: not a first-order-plus-dead-time process",
                percent(*by)
            ),
            Self::Undershoot(by) => write!(
                f,
                "the response first moves the wrong way by {:.1} % of the change (inverse response): not a first-order-plus-dead-time process",
                percent(*by)
            ),
            Self::NotFopdt => {
                f.write_str("the response does not fit a first-order-plus-dead-time model")
            }
            Self::Overflow(what) => write!(f, "{what} overflows the float type"),
            Self::Underflow(what) => write!(
                f,
                "{what} underflows the float type (it would lose its precision)"
            ),
        }
    }
}

impl<F: Real> core::error::Error for IdentifyError<F> {}

/// The factor of ν·D/√N in the stated tolerance (see the module docs).
const NOISE_LOG_FACTOR: f64 = 10.0;

/// Samples before the step from which the noise is measured there (and only there).
const PRE_WINDOW: usize = 20;

/// A fraction as a percentage, for messages.
fn percent<F: Real>(fraction: F) -> F {
    fraction * F::from_u16(100)
}

/// (a − b)/d, rounded once, also where a − b overflows (two means of the last tenths, or a
/// sample beyond the final value of a change near the type's largest value). a and b are then
/// at least half an ulp of the largest value apart from 0 and of opposite signs, and d — the
/// change, a non-zero difference with one of them — is a multiple of an ulp of values that
/// large: all three are normal, so halving them is exact and gives the same quotient.
fn difference_over<F: Real>(a: F, b: F, d: F) -> F {
    let difference = a - b;
    if difference.is_finite() {
        difference / d
    } else {
        let half = c::<F>(0.5);
        (a * half - b * half) / (d * half)
    }
}

/// A count as F (nearest: exact below 2²⁴ in `f32`, relative error below 10⁻⁷ above).
fn count<F: Real>(n: usize) -> F {
    <F as num_traits::NumCast>::from(n).unwrap_or_else(F::max_value)
}

/// The compensated mean of a non-empty slice, and the largest deviation from it. The sum is
/// of the deviations from the first sample, so it overflows only when the count times the
/// part's spread does, not the count times its level (an attack found a log of 1.4 million
/// `f32` samples at 10³³ refused); and a power-of-two scaling of the samples scales the mean
/// exactly. Should that sum overflow (a long noisy part near the type's largest value, or a
/// deviation beyond it), the half of each deviation, scaled down by a power of two at least the
/// count, is summed instead, and the mean formed as twice the mean of the halves: every step
/// exact, so the same mean as the plain sum wherever it fits. The mean is then held between the
/// part's least and greatest values, where a mean lies: the rounding of many deviations (more
/// than 2²⁴ in `f32`, all rounded the same way when the first sample is far from the rest) had
/// carried it past them and past the largest value of the type (the sixth attack). So it never
/// overflows.
fn mean_and_spread<F: Real>(part: &[F]) -> (F, F) {
    let reference = part.first().copied().unwrap_or_else(F::zero);
    let n = count::<F>(part.len().max(1));
    let mut s = Sum::new();
    let (mut least, mut greatest) = (reference, reference);
    for &v in part {
        s.add(v - reference);
        least = if v < least { v } else { least };
        greatest = if v > greatest { v } else { greatest };
    }
    let shift = s.value() / n;
    let mean = if shift.is_finite() {
        reference + shift
    } else {
        let half = c::<F>(0.5);
        // 2^−⌈log₂ len⌉: one halving per bit of len − 1 (at most 64).
        let halvings = usize::BITS.saturating_sub(part.len().saturating_sub(1).leading_zeros());
        let mut down = F::one();
        for _ in 0..halvings {
            down = down * half;
        }
        let mut s = Sum::new();
        for &v in part {
            s.add((v * half - reference * half) * down);
        }
        (reference * half + s.value() / (n * down)) * F::from_u16(2)
    };
    // The rounding of n deviations and of the count (past 2²⁴ in `f32`) can carry the mean
    // outside the part's values, and past the largest value of the type: it is held within
    // them. Their least and greatest scale exactly, so the hold keeps a power-of-two scaling
    // exact.
    let mean = if mean > greatest {
        greatest
    } else if mean < least {
        least
    } else {
        mean
    };
    let mut spread = F::zero();
    for &v in part {
        let d = (v - mean).abs();
        spread = if d > spread { d } else { spread };
    }
    (mean, spread)
}

/// A first-order-plus-dead-time model from a logged open-loop step response whose first sample
/// is the instant of the step: [`identify_step_at`] with no samples before the step, so the
/// baseline is the single sample `samples[0]` and its noise goes straight into K and the areas
/// (±5 % noise on it moves L by about ±25 %). Log a few seconds before the step and use
/// [`identify_step_at`] when the measurement is noisy.
///
/// ```
/// use regler_pid::tuning::identify_step;
///
/// // 2·e^(−1.5s)/(1 + 5s), a step of 0.5, sampled every 0.1 s for 60 s.
/// let y: Vec<f64> = (0..=600)
///     .map(|k| {
///         let t = k as f64 * 0.1;
///         if t < 1.5 { 10.0 } else { 10.0 + 2.0 * 0.5 * (1.0 - (-(t - 1.5) / 5.0).exp()) }
///     })
///     .collect();
/// let model = identify_step(&y, 0.1, 0.5)?;
/// assert!((model.gain - 2.0).abs() < 0.01);
/// assert!((model.time_constant - 5.0).abs() < 0.1);
/// assert!((model.dead_time - 1.5).abs() < 0.1);
/// # Ok::<(), regler_pid::tuning::IdentifyError>(())
/// ```
///
/// # Errors
/// See [`IdentifyError`] and [`identify_step_at`].
pub fn identify_step<F: Real>(samples: &[F], h: F, step: F) -> Result<Fopdt<F>, IdentifyError<F>> {
    identify_step_at(samples, 0, h, step)
}

/// A first-order-plus-dead-time model from a logged open-loop step response, by the method of
/// areas (Åström & Hägglund): with r(t) the response normalised to go from 0 to 1,
/// A0 = ∫(1 − r) dt = T + L and A1 = ∫₀^(T+L) r dt = T/e, so T = e·A1 and L = A0 − T; K is the
/// change over the step. Areas average over many samples, so the method tolerates noise far
/// better than reading two crossing times off the curve. The integrals are those of the samples
/// joined by straight lines: the trapezoidal rule over the whole log for A0, and for A1 the
/// same up to the last whole interval before T + L, then the partial one interpolated — exact
/// for a response linear between samples.
///
/// `samples[..step_at]` were logged before the step, `samples[step_at]` at the instant of the
/// step (before the process could answer), one sample every `h` seconds; `step` is the change of
/// the controller output. The baseline is the mean of `samples[..=step_at]`, the final value
/// the mean of the last tenth of the samples from the step on (at least 2); every sum is
/// compensated, so logs of millions of samples lose no precision in `f32`, and the means sum
/// deviations, so a long log near the type's largest value does not overflow. Counts are
/// `usize`.
///
/// The response must look like an FOPDT response; otherwise the function names why (see the
/// [module](self) docs for the exact rules and the tolerances tested).
///
/// # Errors
/// See [`IdentifyError`].
pub fn identify_step_at<F: Real>(
    samples: &[F],
    step_at: usize,
    h: F,
    step: F,
) -> Result<Fopdt<F>, IdentifyError<F>> {
    let Some(response) = samples.get(step_at..).filter(|r| !r.is_empty()) else {
        return Err(IdentifyError::StepOutsideLog(step_at, samples.len()));
    };
    let n = response.len();
    if n < 20 {
        return Err(IdentifyError::TooFewSamples(n));
    }
    if !(h.is_normal() && h > F::zero()) {
        return Err(IdentifyError::Input("the sample period"));
    }
    if !(step.is_finite() && step != F::zero()) {
        return Err(IdentifyError::Input("the step"));
    }
    // Every sample finite, and the largest magnitude, for the samples' rounding below (at
    // least the smallest normal value: the ulp of subnormals is fixed).
    let mut largest = F::min_positive_value();
    for (k, v) in samples.iter().enumerate() {
        if !v.is_finite() {
            return Err(IdentifyError::NotFinite(k));
        }
        largest = if v.abs() > largest { v.abs() } else { largest };
    }
    let before = samples.get(..=step_at).unwrap_or(&[]);
    let (y0, pre_noise) = mean_and_spread(before);
    let tail_len = (n / 10).max(2);
    let split = n.saturating_sub(tail_len);
    let tail = response.get(split..).unwrap_or(&[]);
    let (y_final, _) = mean_and_spread(tail);
    // The noise: from the samples before the step when there are enough of them — a process
    // still oscillating at the end of the log must not count as its own noise. Without such a
    // window, from the tail's largest change between neighbours (half of it): white noise of
    // peak ν gives about ν, an oscillation of amplitude a and period P samples a·sin(π/P).
    let noise = if step_at >= PRE_WINDOW {
        pre_noise
    } else {
        let mut jump = F::zero();
        for pair in tail.windows(2) {
            if let [x, y] = pair {
                let d = (*y - *x).abs();
                jump = if d > jump { d } else { jump };
            }
        }
        let half_jump = jump * c::<F>(0.5);
        if half_jump > pre_noise {
            half_jump
        } else {
            pre_noise
        }
    };
    let change = y_final - y0;
    if !(change.is_finite() && y0.is_finite()) {
        return Err(IdentifyError::Overflow("the change (the samples' mean)"));
    }
    // The noise ν and the samples' rounding ρ, as fractions of the change. A sample is rounded
    // by at most half an ulp of the largest, and ε times the largest sample (at least the
    // smallest normal value: the ulp of subnormals is fixed) is one to two ulps of it, so the
    // baseline and the final value, means of rounded samples, are each off by at most ρ/2 of
    // the change — an error no averaging removes. Computed as fractions: half an ulp of a
    // subnormal is not representable.
    let relative_noise = noise / change.abs();
    let rounding = F::epsilon() * (largest / change.abs());
    let two = F::from_u16(2);
    // Within twice the noise, the rounding's peak (ρ/2) included; NaN: a change of 0.
    let peak = relative_noise + rounding * c::<F>(0.5);
    if peak.is_nan() || two * peak >= F::one() {
        return Err(IdentifyError::NoResponse);
    }
    let gain = change / step;
    if !gain.is_finite() {
        return Err(IdentifyError::Overflow("the gain (change / step)"));
    }
    // A gain of 0 has lost everything (a step of 2⁶⁰ on a change of 2⁻¹⁰⁰ in `f32`); a
    // subnormal one is off by up to half the smallest subnormal value (stated).
    if gain == F::zero() {
        return Err(IdentifyError::Underflow("the gain (change / step)"));
    }
    // Settled: the last tenth's mean and the tenth before's agree to 0.2 % of the change, plus
    // four standard deviations of the difference of two means of noise of this peak.
    let previous = response
        .get(split.saturating_sub(tail_len)..split)
        .unwrap_or(&[]);
    let (y_previous, _) = mean_and_spread(previous);
    let moving = difference_over(y_final, y_previous, change).abs();
    // A movement that is not finite would pass every comparison below.
    if !moving.is_finite() {
        return Err(IdentifyError::Overflow(
            "the movement (the last tenths' means over the change)",
        ));
    }
    let allowed =
        c::<F>(0.002) + c::<F>(4.0) * relative_noise / sqrt(count::<F>(tail_len)) + rounding;
    if moving > allowed {
        return Err(IdentifyError::NotSettled(moving));
    }
    let late = y_final;
    // The normalised response r = (y − y0)/change goes from 0 to 1 and never leaves 0..=1
    // for an FOPDT process; beyond 1 % of the change plus twice the noise (and twice the
    // rounding: r is off by up to 2ρ) it is another shape.
    let half = c::<F>(0.5);
    let unit = |v: F| difference_over(v, y0, change);
    let margin = c::<F>(0.01) + two * (relative_noise + rounding);
    let (mut lo, mut hi) = (F::infinity(), F::neg_infinity());
    for &v in response {
        let r = unit(v);
        lo = if r < lo { r } else { lo };
        hi = if r > hi { r } else { hi };
    }
    let overshoot = hi - unit(late);
    if overshoot > margin {
        return Err(IdentifyError::Overshoot(overshoot));
    }
    if -lo > margin {
        return Err(IdentifyError::Undershoot(-lo));
    }
    // A0 = ∫(1 − r) dt by the trapezoidal rule: h·(Σ(1 − r) − ends/2).
    let first = F::one() - unit(response.first().copied().unwrap_or(y0));
    let last = F::one() - unit(response.last().copied().unwrap_or(y_final));
    let mut a0 = Sum::new();
    for &v in response {
        a0.add(F::one() - unit(v));
    }
    a0.add(-(first + last) * half);
    // Everything up to the verdict is in samples (the times over h), so the verdict is the same
    // for every h; the times in seconds, and their overflow, come after it.
    let a0 = a0.value(); // (T + L)/h
    // A1 = ∫₀^(T+L) r dt: whole intervals up to ⌊(T+L)/h⌋, then the partial one interpolated.
    let whole = num_traits::ToPrimitive::to_usize(&a0.floor());
    let Some(whole) = whole.filter(|&w| w.saturating_add(1) < n) else {
        return Err(IdentifyError::NotFopdt); // T + L not positive, or beyond the log
    };
    let mut a1 = Sum::new();
    let mut previous = F::zero();
    for (i, &v) in response.iter().enumerate().take(whole.saturating_add(1)) {
        let r = unit(v);
        if i > 0 {
            a1.add((previous + r) * half);
        }
        previous = r;
    }
    let frac = a0 - count::<F>(whole);
    let next = response
        .get(whole.saturating_add(1))
        .map_or(previous, |&v| unit(v));
    let end = previous + (next - previous) * frac;
    a1.add((previous + end) * half * frac);
    let e = F::from_f64_nearest(core::f64::consts::E);
    let a1 = e * a1.value(); // T/h
    // A dead time a little below zero is sampling error, noise and rounding (the stated
    // tolerance); below that it is another shape. Judged in samples (the times over h), before
    // the times in seconds: the tolerance h + 2 % (T + L) + ν·(T + L + 10·D/√N) +
    // ρ·(10·(T + L) + 4·D) is, over h, 1 + 2 % A0 + ν·(A0 + 10·√N) + ρ·(10·A0 + 4·N), which
    // never overflows (in seconds it overflowed where T + L did not, and a NaN or infinite
    // tolerance switched the check off).
    let slack = F::one()
        + c::<F>(0.02) * a0
        + relative_noise * (a0 + c::<F>(NOISE_LOG_FACTOR) * sqrt(count::<F>(n)))
        + rounding * (c::<F>(10.0) * a0 + c::<F>(4.0) * count::<F>(n));
    if a1.is_nan() || a1 <= F::zero() || a0 - a1 < -slack {
        return Err(IdentifyError::NotFopdt);
    }
    let t_ar = a0 * h; // T + L
    if !t_ar.is_finite() {
        return Err(IdentifyError::Overflow(
            "T + L (the sample period times the log)",
        ));
    }
    let time_constant = a1 * h;
    if !time_constant.is_finite() {
        return Err(IdentifyError::Overflow(
            "T (the sample period times the log)",
        ));
    }
    // A fraction of a sample at a sample period near the smallest normal value can round to 0
    // (a subnormal T is within the tolerance, which counts h; 0 is not positive).
    if time_constant <= F::zero() {
        return Err(IdentifyError::Underflow(
            "T (the sample period times the log)",
        ));
    }
    let dead_time = t_ar - time_constant;
    let dead_time = if dead_time > F::zero() {
        dead_time
    } else {
        F::zero()
    };
    Ok(Fopdt {
        gain,
        time_constant,
        dead_time,
    })
}

/// How the relay experiment is run.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RelayConfig<F = f64> {
    /// Direct: more output raises the measurement (as for the controller).
    pub action: Action,
    /// The output the relay switches around (e.g. the output that held the process steady).
    pub bias: F,
    /// Relay amplitude d: the output is bias ± d.
    pub amplitude: F,
    /// Hysteresis ε on the error: at least the measurement noise's peak, so noise cannot switch
    /// the relay.
    pub hysteresis: F,
    /// Sample period h, seconds.
    pub h: F,
    /// Periods that must agree before the estimate is accepted (at least 2; the first period,
    /// still settling, never counts).
    pub cycles: u8,
    /// How closely they must agree: largest relative spread of period and amplitude.
    pub tolerance: F,
    /// Give up after this many seconds.
    pub timeout: F,
}

impl<F: Real> Default for RelayConfig<F> {
    fn default() -> Self {
        Self {
            action: Action::Direct,
            bias: F::zero(),
            amplitude: F::one(),
            hysteresis: c(0.01),
            h: c(0.1),
            cycles: 3,
            tolerance: c(0.05),
            timeout: c(600.0),
        }
    }
}

/// Why the relay experiment cannot run or failed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum RelayError<F = f64> {
    /// A configuration value is out of range (named).
    Config(&'static str),
    /// No stable limit cycle within the time-out; `periods` complete periods were seen.
    Timeout {
        /// Complete periods seen.
        periods: u16,
    },
    /// The relay switched within a few samples: the hysteresis is below the measurement noise.
    Chattering {
        /// The short period, seconds.
        period: F,
    },
    /// The oscillation's amplitude does not clear the hysteresis: Ku cannot be estimated.
    AmplitudeBelowHysteresis {
        /// The amplitude seen.
        amplitude: F,
    },
    /// The experiment was aborted.
    Aborted,
    /// Ku = 4d/(π·√(a² − ε²)) is not a finite number in this float type: the amplitude a is
    /// too small against the relay amplitude d (or too close to the hysteresis ε) to measure.
    AmplitudeUnmeasurable {
        /// The amplitude seen.
        amplitude: F,
    },
}

impl<F: fmt::Display> fmt::Display for RelayError<F> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Config(what) => write!(f, "relay configuration: {what}"),
            Self::Timeout { periods } => {
                write!(
                    f,
                    "no stable limit cycle before the time-out ({periods} periods seen)"
                )
            }
            Self::Chattering { period } => write!(
                f,
                "the relay chatters (period {period} s): raise the hysteresis above the measurement noise"
            ),
            Self::AmplitudeBelowHysteresis { amplitude } => write!(
                f,
                "the oscillation's amplitude {amplitude} does not clear the hysteresis: lower it or raise the relay amplitude"
            ),
            Self::Aborted => f.write_str("the relay experiment was aborted"),
            Self::AmplitudeUnmeasurable { amplitude } => write!(
                f,
                "the oscillation's amplitude {amplitude} is too small against the relay amplitude for Ku to be a finite number: raise the measurement's scale or lower the relay amplitude"
            ),
        }
    }
}

impl<F: fmt::Debug + fmt::Display> core::error::Error for RelayError<F> {}

/// Why [`Relay::hand_over`] refused to hand the loop over.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum HandOverError<F = f64> {
    /// The controller's action is not the experiment's: it would drive the loop to a limit.
    Action {
        /// The action the experiment ran with (the process's direction).
        experiment: Action,
        /// The action in the controller's configuration.
        controller: Action,
    },
    /// The controller's configuration is not valid.
    Config(ConfigError<F>),
    /// The set-point or the measurement of the hand-over sample is not finite (named): the
    /// controller could not start from it, so its first output would not continue from the
    /// bias. Hand over at a sample with a good measurement.
    NotFinite(&'static str),
}

const fn action_name(action: Action) -> &'static str {
    match action {
        Action::Direct => "direct",
        Action::Reverse => "reverse",
    }
}

impl<F: Real> fmt::Display for HandOverError<F> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Action {
                experiment,
                controller,
            } => write!(
                f,
                "the relay experiment ran {}-acting but the controller is configured {}-acting: it would drive the loop to a limit",
                action_name(*experiment),
                action_name(*controller)
            ),
            Self::Config(e) => write!(f, "the tuned configuration: {e}"),
            Self::NotFinite(what) => write!(
                f,
                "the {what} at the hand-over is not finite: the controller cannot start bumplessly from it"
            ),
        }
    }
}

impl<F: Real> core::error::Error for HandOverError<F> {}

/// What one sample of the experiment gives.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RelayStep<F = f64> {
    /// Still running: apply this output.
    Running(F),
    /// Finished: the estimate (keep applying the bias until the tuned controller takes over).
    Done(Ultimate<F>),
}

/// Periods remembered for the agreement check (the largest `cycles`).
const HISTORY: usize = 8;

/// The relay experiment (see the [module](self) docs).
///
/// ```
/// use regler_pid::tuning::{Relay, RelayConfig, RelayStep};
///
/// // 1/(s+1)^3 sampled every 10 ms: Ku = 8, Tu = 2π/√3 ≈ 3.63 s.
/// let h = 0.01;
/// let a = f64::exp(-h);
/// let mut x = [0.0f64; 3];
/// let mut relay = Relay::new(RelayConfig { h, hysteresis: 0.001, ..RelayConfig::default() })?;
/// let found = loop {
///     match relay.update(0.0, x[2])? {
///         RelayStep::Running(u) => {
///             x[0] = a * x[0] + (1.0 - a) * u;
///             x[1] = a * x[1] + (1.0 - a) * x[0];
///             x[2] = a * x[2] + (1.0 - a) * x[1];
///         }
///         RelayStep::Done(ultimate) => break ultimate,
///     }
/// };
/// assert!((found.ku / 8.0 - 1.0).abs() < 0.1, "{}", found.ku);
/// assert!((found.tu / 3.628 - 1.0).abs() < 0.05, "{}", found.tu);
/// # Ok::<(), regler_pid::tuning::RelayError>(())
/// ```
#[derive(Clone, Debug)]
pub struct Relay<F = f64> {
    config: RelayConfig<F>,
    high: bool,
    /// Samples taken so far (an integer: a float clock `t += h` stops advancing once t/h
    /// passes 2²⁴ in `f32`); every time is `count·h`, computed where it is used.
    count: u64,
    /// The sample count past which the experiment gives up: ⌊timeout/h⌋, computed once.
    limit: u64,
    /// Sample count of the last switch to high (a period boundary), once there was one.
    last_rise: Option<u64>,
    y_max: F,
    y_min: F,
    periods: [(F, F); HISTORY],
    seen: u16,
    /// How the experiment ended (an estimate, a failure or an abort), once it has.
    outcome: Option<Result<Ultimate<F>, RelayError<F>>>,
}

impl<F: Real> Relay<F> {
    /// An experiment about to start (the relay starts high).
    ///
    /// # Errors
    /// [`RelayError::Config`] naming the value out of range.
    pub fn new(config: RelayConfig<F>) -> Result<Self, RelayError<F>> {
        let finite = |v: F| v.is_finite();
        if !finite(config.bias) {
            return Err(RelayError::Config("bias must be finite"));
        }
        if !(finite(config.amplitude) && config.amplitude > F::zero()) {
            return Err(RelayError::Config("amplitude must be finite and positive"));
        }
        if !(finite(config.hysteresis) && config.hysteresis >= F::zero()) {
            return Err(RelayError::Config(
                "hysteresis must be finite and not negative",
            ));
        }
        if !(finite(config.h) && config.h > F::zero()) {
            return Err(RelayError::Config("h must be finite and positive"));
        }
        if !(2..=8).contains(&config.cycles) {
            return Err(RelayError::Config("cycles must be 2..=8"));
        }
        if !(finite(config.tolerance) && config.tolerance > F::zero()) {
            return Err(RelayError::Config("tolerance must be finite and positive"));
        }
        if !(finite(config.timeout) && config.timeout > config.h) {
            return Err(RelayError::Config(
                "timeout must be finite and longer than h",
            ));
        }
        // The time-out in samples, ⌊timeout/h⌋ rounded once in F: the same count in f32 and
        // f64 whenever the quotient is exact in both (40 000 s at 1 ms: 40 000 000).
        let Some(limit) = num_traits::ToPrimitive::to_u64(&(config.timeout / config.h).floor())
        else {
            return Err(RelayError::Config("timeout/h must be at most 2^64 samples"));
        };
        Ok(Self {
            config,
            high: true,
            count: 0,
            limit,
            last_rise: None,
            y_max: F::neg_infinity(),
            y_min: F::infinity(),
            periods: [(F::zero(), F::zero()); HISTORY],
            seen: 0,
            outcome: None,
        })
    }

    /// The output the relay applies now.
    #[must_use]
    pub fn output(&self) -> F {
        if self.outcome.is_some() {
            return self.config.bias;
        }
        if self.high {
            self.config.bias + self.config.amplitude
        } else {
            self.config.bias - self.config.amplitude
        }
    }

    /// Stops the experiment; the output goes back to the bias.
    pub fn abort(&mut self) -> F {
        self.outcome = Some(Err(RelayError::Aborted));
        self.config.bias
    }

    /// One sample: the set-point and the measurement.
    ///
    /// A non-finite measurement is skipped (the relay holds its output; the experiment goes on
    /// when the sensor is back).
    ///
    /// # Errors
    /// A failed experiment (time-out, chattering, amplitude below hysteresis) or one aborted.
    /// After an error the relay keeps returning it; make a new one to try again.
    pub fn update(&mut self, setpoint: F, measurement: F) -> Result<RelayStep<F>, RelayError<F>> {
        if let Some(outcome) = self.outcome {
            return outcome.map(RelayStep::Done);
        }
        self.count = self.count.saturating_add(1);
        if self.count > self.limit {
            return self.end(Err(RelayError::Timeout { periods: self.seen }));
        }
        if !(measurement.is_finite() && setpoint.is_finite()) {
            return Ok(RelayStep::Running(self.output()));
        }
        let s = F::from_f64_nearest(self.config.action.sign());
        let e = s * (setpoint - measurement);
        if measurement > self.y_max {
            self.y_max = measurement;
        }
        if measurement < self.y_min {
            self.y_min = measurement;
        }
        let eps = self.config.hysteresis;
        if self.high && e < -eps {
            self.high = false;
        } else if !self.high && e > eps {
            self.high = true;
            match self.period_ended() {
                Ok(None) => {}
                Ok(Some(done)) => return self.end(Ok(done)),
                Err(failed) => return self.end(Err(failed)),
            }
        }
        Ok(RelayStep::Running(self.output()))
    }

    /// The experiment is over: remembered, so every later sample gives the same answer.
    fn end(
        &mut self,
        outcome: Result<Ultimate<F>, RelayError<F>>,
    ) -> Result<RelayStep<F>, RelayError<F>> {
        self.outcome = Some(outcome);
        outcome.map(RelayStep::Done)
    }

    /// A rise closes a period: record it and see whether the last ones agree.
    fn period_ended(&mut self) -> Result<Option<Ultimate<F>>, RelayError<F>> {
        let now = self.count;
        let two = F::from_u16(2);
        let amplitude = (self.y_max - self.y_min) / two;
        self.y_max = F::neg_infinity();
        self.y_min = F::infinity();
        let Some(start) = self.last_rise.replace(now) else {
            return Ok(None); // the first rise only starts the count
        };
        let samples = now.saturating_sub(start);
        // Rounded to F only now: a period of a few thousand samples is exact in f32.
        let period = samples_to_real::<F>(samples) * self.config.h;
        if samples < 4 {
            return Err(RelayError::Chattering { period });
        }
        self.periods.rotate_left(1);
        if let Some(last) = self.periods.last_mut() {
            *last = (period, amplitude);
        }
        self.seen = self.seen.saturating_add(1);
        let need = u16::from(self.config.cycles);
        // The first period is still settling: it never counts.
        if self.seen <= need {
            return Ok(None);
        }
        let recent = self
            .periods
            .get(HISTORY.saturating_sub(usize::from(self.config.cycles))..)
            .unwrap_or(&[]);
        let spread = |pick: fn(&(F, F)) -> F| {
            let (mut lo, mut hi, mut sum) = (F::infinity(), F::neg_infinity(), F::zero());
            for p in recent {
                let v = pick(p);
                lo = if v < lo { v } else { lo };
                hi = if v > hi { v } else { hi };
                sum = sum + v;
            }
            let mean = sum / F::from_u16(u16::from(self.config.cycles));
            ((hi - lo) / mean, mean)
        };
        let (period_spread, tu) = spread(|p| p.0);
        let (amplitude_spread, a) = spread(|p| p.1);
        if period_spread > self.config.tolerance || amplitude_spread > self.config.tolerance {
            return Ok(None);
        }
        let eps = self.config.hysteresis;
        if a <= eps {
            return Err(RelayError::AmplitudeBelowHysteresis { amplitude: a });
        }
        let pi = F::from_f64_nearest(core::f64::consts::PI);
        // √(a² − ε²) as a·√(1 − (ε/a)²): a² underflows for a tiny amplitude (1e-23 in f32) and
        // overflows for a huge one, ε/a < 1 does neither.
        let ratio = eps / a;
        let root = a * sqrt(F::one() - ratio * ratio);
        let ku = F::from_u16(4) * self.config.amplitude / (pi * root);
        if !(ku.is_finite() && ku > F::zero()) {
            return Err(RelayError::AmplitudeUnmeasurable { amplitude: a });
        }
        Ok(Some(Ultimate { ku, tu }))
    }

    /// The estimate, once the experiment is done.
    #[must_use]
    pub fn result(&self) -> Option<Ultimate<F>> {
        self.outcome.and_then(Result::ok)
    }

    /// Hands the loop over to a controller configured by `config`, bumplessly: the controller
    /// starts in manual at the relay's bias with this sample's set-point and measurement, then
    /// switches to automatic, so its first output continues from the bias.
    ///
    /// The experiment's [`Action`] says which way the process answered; a controller of the
    /// other action would push the loop away from the set-point to a limit, so it is refused.
    ///
    /// # Errors
    /// [`HandOverError::Action`] when `config.action` differs from the experiment's action
    /// (every combination is checked); [`HandOverError::Config`], the configuration's
    /// validation error; [`HandOverError::NotFinite`] naming a set-point or measurement that is
    /// not finite (the relay skips such a sample; the hand-over refuses it).
    pub fn hand_over<T: Scalar>(
        &self,
        config: &Config<F>,
        setpoint: T,
        measurement: T,
    ) -> Result<Pid<T>, HandOverError<F>> {
        if config.action != self.config.action {
            return Err(HandOverError::Action {
                experiment: self.config.action,
                controller: config.action,
            });
        }
        if !setpoint.is_finite() {
            return Err(HandOverError::NotFinite("set-point"));
        }
        if !measurement.is_finite() {
            return Err(HandOverError::NotFinite("measurement"));
        }
        let mut pid = Pid::new(config).map_err(HandOverError::Config)?;
        let _ = pid.set_manual(T::from_real(self.config.bias));
        let _ = pid.update(setpoint, measurement);
        pid.set_auto();
        Ok(pid)
    }
}

/// A sample count as F (nearest; every count below 2²⁴ exactly in `f32`).
fn samples_to_real<F: Real>(n: u64) -> F {
    <F as num_traits::NumCast>::from(n).unwrap_or_else(F::max_value)
}

/// √x for x ≥ 0 by Newton's iteration (FloatCore has no square root; `libm` is not needed for
/// one root per experiment).
fn sqrt<F: Real>(x: F) -> F {
    if x.is_nan() || x <= F::zero() || !x.is_finite() {
        return F::zero();
    }
    let two = F::from_u16(2);
    // Start at a power of two just above the root (from the exponent): the iteration then
    // decreases monotonically and converges in a handful of steps at any magnitude.
    let (mantissa, exponent, _) = x.integer_decode();
    let bits = 64i32.saturating_sub(mantissa.leading_zeros() as i32);
    let log2 = i32::from(exponent).saturating_add(bits);
    let mut r = two.powi(log2.div_euclid(2).saturating_add(1));
    for _ in 0..100 {
        let next = (r + x / r) / two;
        if next >= r {
            break;
        }
        r = next;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_subnormal_or_huge_sample_period_is_named() {
        let lag: std::vec::Vec<f64> = (0..60)
            .map(|k| {
                if k < 3 {
                    0.0
                } else {
                    1.0 - (-(f64::from(k) - 3.0) / 5.0).exp()
                }
            })
            .collect();
        assert_eq!(
            identify_step(&lag, f64::from_bits(1), 1.0),
            Err(IdentifyError::Input("the sample period"))
        );
        assert_eq!(
            identify_step(&lag, f64::MAX, 1.0),
            Err(IdentifyError::Overflow(
                "T + L (the sample period times the log)"
            ))
        );
        assert!(identify_step(&lag, f64::MIN_POSITIVE, 1.0).is_ok());
    }

    #[test]
    fn newton_root() {
        for x in [0.0f64, 1e-12, 0.25, 1.0, 2.0, 1e6, 1e300] {
            let r = sqrt(x);
            assert!(
                (r - x.sqrt()).abs() <= 1e-12 * x.sqrt().max(1e-300),
                "{x}: {r}"
            );
        }
        assert_eq!(sqrt(-1.0), 0.0);
        assert_eq!(sqrt(f64::NAN), 0.0);
        assert!((sqrt(2.0f32) - core::f32::consts::SQRT_2).abs() < 1e-6);
    }

    #[test]
    fn rules_match_their_published_formulas() {
        let zn = ziegler_nichols(Ultimate { ku: 10.0, tu: 4.0 }, Kind::PI).unwrap();
        assert_eq!((zn.k, zn.ti, zn.td), (4.5, 4.0 / 1.2, 0.0));
        assert_eq!(
            ziegler_nichols(Ultimate { ku: 10.0, tu: 4.0 }, Kind::P)
                .unwrap()
                .k,
            5.0
        );
        assert_eq!(
            ziegler_nichols(Ultimate { ku: 10.0, tu: 4.0 }, Kind::PD),
            Err(RuleError::Kind(Kind::PD))
        );
        assert_eq!(
            ziegler_nichols(
                Ultimate {
                    ku: f64::NAN,
                    tu: 4.0
                },
                Kind::PI
            ),
            Err(RuleError::Input("Ku"))
        );
        // AMIGO PI for K = 1, T = 1, L = 1 (tau = 0.5): K = 0.15 + (0.35 - 0.25) = 0.25,
        // Ti = 0.35 + 13/(1 + 12 + 7) = 1.0.
        let m = Fopdt {
            gain: 1.0f64,
            time_constant: 1.0,
            dead_time: 1.0,
        };
        let pi = amigo(m, Kind::PI).unwrap();
        assert!(
            (pi.k - 0.25).abs() < 1e-12 && (pi.ti - 1.0).abs() < 1e-12,
            "{pi:?}"
        );
        assert_eq!(pi.b, 1.0);
        // AMIGO PID: K = 0.2 + 0.45 = 0.65, Ti = 1.2/1.1, Td = 0.5/1.3.
        let pid = amigo(m, Kind::PID).unwrap();
        assert!((pid.k - 0.65).abs() < 1e-12);
        assert!((pid.ti - 1.2 / 1.1).abs() < 1e-12 && (pid.td - 0.5 / 1.3).abs() < 1e-12);
        // A lag-dominated process gets b = 0; a negative process gain is taken by magnitude.
        let lag = amigo(
            Fopdt {
                gain: -2.0,
                time_constant: 10.0,
                dead_time: 1.0,
            },
            Kind::PI,
        )
        .unwrap();
        assert_eq!(lag.b, 0.0);
        assert!(lag.k > 0.0);
        assert!(
            amigo(
                Fopdt {
                    dead_time: 0.0,
                    ..m
                },
                Kind::PI
            )
            .is_err()
        );
        // SIMC with tc = L: Ti limited by 4(tc + L) for a slow process.
        let s = simc(
            Fopdt {
                gain: 1.0,
                time_constant: 100.0,
                dead_time: 1.0,
            },
            1.0,
        )
        .unwrap();
        assert_eq!((s.k, s.ti), (50.0, 8.0));
    }

    #[test]
    fn apply_keeps_the_rest_and_refuses_a_bad_result() {
        let mut config = Config::<f64> {
            h: 0.1,
            ymax: 100.0,
            ..Config::default()
        };
        let before = config;
        let t = Tuning {
            kind: Kind::PI,
            k: 2.0,
            ti: 5.0,
            td: 0.0,
            b: 1.0,
        };
        t.apply(&mut config).unwrap();
        assert_eq!(
            (config.kind, config.k, config.ti, config.td),
            (Kind::PI, 2.0, 5.0, 0.0)
        );
        assert_eq!(
            (config.h, config.ymax, config.n),
            (before.h, before.ymax, before.n)
        );
        let bad = Tuning { k: f64::NAN, ..t };
        assert!(bad.apply(&mut config).is_err());
        assert_eq!(config.k, 2.0);
    }

    #[test]
    fn relay_config_is_checked() {
        let ok = RelayConfig::<f64>::default();
        assert!(Relay::new(ok).is_ok());
        for bad in [
            RelayConfig {
                amplitude: 0.0,
                ..ok
            },
            RelayConfig {
                hysteresis: -1.0,
                ..ok
            },
            RelayConfig { h: f64::NAN, ..ok },
            RelayConfig { cycles: 1, ..ok },
            RelayConfig { cycles: 9, ..ok },
            RelayConfig {
                tolerance: 0.0,
                ..ok
            },
            RelayConfig {
                timeout: 0.05,
                ..ok
            },
            RelayConfig {
                bias: f64::INFINITY,
                ..ok
            },
        ] {
            assert!(
                matches!(Relay::new(bad), Err(RelayError::Config(_))),
                "{bad:?}"
            );
        }
    }

    /// A mean lies between its part's least and greatest values, and never overflows: `f32`
    /// parts of more than 2²⁴ samples whose first sample is far below the rest (the sixth attack:
    /// 2²⁴ + 1 samples at or just under `f32::MAX` after one at −0.0006·MAX; each halved
    /// deviation rounds by up to half an ulp the same way, the count rounds down, and the mean
    /// came out past `MAX`, infinite). Also: the mean of the part scaled by ½ is exactly half
    /// its mean.
    #[test]
    #[cfg_attr(
        miri,
        ignore = "parts of 2²⁴ + 1 and 2²⁴ + 2 f32 samples, each mean taken three times: days under Miri; safe code, run natively in every CI run"
    )]
    fn a_mean_stays_between_the_least_and_greatest_samples() {
        let (far, farther) = (-0.0006 * f32::MAX, f32::from_bits(0x7f00_0000));
        for (len, first, ulps_under) in [
            ((1usize << 24) + 1, far, 0u32),
            ((1usize << 24) + 1, far, 3),
            ((1usize << 24) + 2, farther, 1),
            ((1usize << 24) + 1, 0.0, 0),
        ] {
            let top = f32::from_bits(f32::MAX.to_bits() - ulps_under);
            let mut part = vec![top; len];
            part[0] = first;
            // Every third sample one ulp further under (the attack's "30 % 1–3 ulps below").
            for v in part.iter_mut().skip(1).step_by(3) {
                *v = f32::from_bits(v.to_bits() - 1);
            }
            let (mean, _) = mean_and_spread(&part);
            let what = format!("{len} samples, first {first:e}, {ulps_under} ulps under");
            assert!(
                mean.is_finite() && mean >= first && mean <= top,
                "{what}: {mean:e}"
            );
            let halved: Vec<f32> = part.iter().map(|v| v * 0.5).collect();
            assert_eq!(mean_and_spread(&halved).0 * 2.0, mean, "{what}, halved");
            let negated: Vec<f32> = part.iter().map(|v| -v).collect();
            assert_eq!(mean_and_spread(&negated).0, -mean, "{what}, negated");
        }
    }

    /// The compensated sum keeps what a plain one loses, whichever term is the larger, and
    /// reads it back with its carry: exact on sums a plain `f32` sum gets wrong, within an ulp
    /// of the sum over 10⁶ terms. (Under Neumaier's form, which summed its carry plainly, the
    /// tenths came to 99 994.2.)
    #[test]
    #[cfg_attr(
        miri,
        ignore = "4 million f32 additions: hours under Miri; safe code, run natively in every CI run"
    )]
    fn the_compensated_sum_keeps_the_small_terms() {
        let sum = |terms: &[f32]| {
            let mut s = Sum::new();
            for &t in terms {
                s.add(t);
            }
            s.value()
        };
        // The large term first, then last: the small ones survive either way.
        assert_eq!(sum(&[1e8, 1.0, -1e8]), 1.0);
        assert_eq!(sum(&[1.0, 1e8, -1e8]), 1.0);
        assert_eq!(sum(&[1.0, 1e8, 1.0, -1e8]), 2.0);
        assert_eq!(sum(&[3.0, 5.0]), 8.0);
        // 10⁶ tenths: a plain f32 sum is off by about 1 %, the compensated one by under an
        // ulp of the sum (2⁻⁷ at 10⁵); the same for 10⁶ terms alternating ±.
        let tenths = vec![0.1f32; 1_000_000];
        let exact = 1e6 * f64::from(0.1f32);
        let got = f64::from(sum(&tenths));
        assert!((got - exact).abs() <= 1.0 / 128.0, "{got} for {exact}");
        let mixed: Vec<f32> = (0..1_000_000u32)
            .map(|k| if k % 3 == 0 { -0.7 } else { 0.45 })
            .collect();
        let exact: f64 = mixed.iter().map(|&t| f64::from(t)).sum();
        let got = f64::from(sum(&mixed));
        assert!((got - exact).abs() <= 1.0 / 128.0, "{got} for {exact}");
        let plain: f32 = tenths.iter().sum();
        assert!(
            (f64::from(plain) - exact).abs() > exact * 1e-3,
            "the plain sum's loss"
        );
    }
}
