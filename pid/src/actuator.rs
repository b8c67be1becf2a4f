//! Increase/decrease ("three-point") actuators: a valve or damper motor that only knows *open*,
//! *close* and *stop*, with a full-stroke run time GT — the actuator kind source 002's
//! specification asked for and the 1985 controller never drove.
//!
//! [`ThreePoint`] turns a wanted position (from a positional controller, [`ThreePoint::update`])
//! or a wanted change (velocity form, [`ThreePoint::update_delta`]) into one pulse per sample,
//! keeps an estimate of where the actuator stands (it has no position feedback), and never winds
//! up at the ends: a request beyond fully open or fully closed is dropped, not stored, so the
//! first request back moves the actuator at once. An end-position switch re-anchors the
//! estimate.
//!
//! # What the driver guarantees (tested in `tests/actuator.rs` for every configuration the
//! constructor accepts)
//! - Every pulse is one the motor can make: [`Drive::Stop`], or `Open(s)`/`Close(s)` with
//!   0 < s and `min_pulse` ≤ s ≤ `h` (s is the pulse's length in seconds within this sample),
//!   in both forms.
//! - Positional form: an error smaller than [`smallest_move`](ThreePoint::smallest_move) (the
//!   dead band or one minimum pulse's travel `min_pulse / run_time`, the larger) is not driven,
//!   and no pulse carries the estimate past the target, so a target held constant gives at most
//!   one reversal (the one away from where the actuator was going), from any start, over any
//!   horizon; the actuator ends within `smallest_move()` of the target. A target at an end is
//!   driven into the stop (at least one minimum pulse, and a whole sample where the error is too
//!   small to be a time; the stop ends it): a valve asked to shut, shuts.
//! - Velocity form: requests smaller than `smallest_move()` wait and add up (kept as a change
//!   in a compensated sum, so neither a change below the estimate's resolution nor one below
//!   half an ulp of what is already pending is lost — 4·10⁻¹⁰ a request on 0.0099 in `f32` —
//!   down to the sum's own resolution, about ε²/2 of the pending change; a pulse takes off the
//!   request exactly the travel it drives, so what waited under it stays, and an end switch
//!   ([`at_end`](ThreePoint::at_end)) keeps the requests away from its end). When the
//!   requests add up to an end (within 32·ε of it, ε the float type's epsilon: the rounding of
//!   changes that should reach it exactly, e.g. a saturating controller's), the actuator is
//!   driven into that stop however little is left, as in the positional form: a valve asked to
//!   shut, shuts. The travel this takes beyond the requests stays as a request away from the
//!   end, and a valve taken into a stop (on its way, or standing in it) is taken out again only
//!   for a request more than 64·ε away: requests to and fro near an end are neither lost nor
//!   amplified — the travel driven is at most twice what they ask (one margin, once per visit
//!   to the stop).
//! - The estimate stays in 0..=1 and follows a motor that moves `s / run_time` per pulse and
//!   stops at its ends, within ε·(4 + strokes travelled) + pulses·ε²/4 (ε the float type's
//!   epsilon: 1.2·10⁻⁷ in `f32`), in both forms and at any ratio `h / run_time` the
//!   constructor takes. The estimate is two numbers, which hold each pulse's travel to within
//!   ε²/4 of the stroke (3.6·10⁻¹⁵ in `f32`): a travel below that can be lost entirely
//!   (0.99·2⁻⁵⁰ of the stroke a sample in `f32`, a 1 ms sample on a valve of 36 000 years,
//!   stops moving the estimate after 2²⁴ samples), and the second term counts it. Above it,
//!   the estimate is a compensated sum, so one sample's travel is neither rounded away nor
//!   rounded the same way every sample (1 ms on a 200 s valve is 5·10⁻⁶ of the stroke: a plain
//!   `f32` sum near 0.5 rounds each by up to 0.6 %, one on a 10⁵ s valve it loses entirely). The
//!   estimate is never snapped onto an end; only targets within 64·ε of an end count as the
//!   end.
//! - Refused by [`ThreePoint::new`]: a run time or h that is not finite and positive, a minimum
//!   pulse outside 0..=h or longer than the run time, a dead band outside 0..1,
//!   `h / run_time` below the float type's smallest normal number (1.2·10⁻³⁸ in `f32`), and a
//!   run time below 2 × that number / ε (2·10⁻³¹ s in `f32`, 2·10⁻²⁹² s in `f64`): the pulse
//!   for a small error would be a subnormal number of seconds, rounded by more than the
//!   estimate's ε²/4 of the stroke.
//!
//! With a positional [`Pid`](crate::Pid), feed the *changes* of its output to
//! [`update_delta`](ThreePoint::update_delta) (the velocity form): changes too small for a pulse
//! add up in the driver and none is lost. Do not feed the driver's position estimate back as the
//! controller's one-sample tracking input while a dead band is set: the controller could then
//! never move more than one sample's integral step past the motor, and a step smaller than the
//! dead band would never be driven — a deadlock (the `autonomous-controller` example hit it).
#![allow(
    clippy::arithmetic_side_effects,
    reason = "arithmetic here is on Real (sealed: f32 or f64), which cannot panic or wrap; inputs are checked finite first"
)]

use core::fmt;

use crate::Real;
use crate::real::{Sum, two_sum};

/// How the actuator is driven.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ActuatorConfig<F = f64> {
    /// GT: seconds from fully closed to fully open.
    pub run_time: F,
    /// The shortest pulse the motor and its relay take, seconds (at most `h` and at most
    /// `run_time`).
    pub min_pulse: F,
    /// Position errors smaller than this (fraction of the stroke) are not driven: no hunting.
    pub dead_band: F,
    /// Sample period, seconds: the longest pulse one sample can give.
    pub h: F,
}

/// Why a configuration or an input was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ActuatorError {
    /// A value out of range (named).
    Config(&'static str),
    /// A non-finite request (ignored: the actuator stops).
    NotFinite,
}

impl fmt::Display for ActuatorError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Config(what) => write!(f, "actuator configuration: {what}"),
            Self::NotFinite => f.write_str("a non-finite request: the actuator stops"),
        }
    }
}

impl core::error::Error for ActuatorError {}

/// The pulse for this sample.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Drive<F = f64> {
    /// Both outputs off.
    Stop,
    /// Drive open for this many seconds (at most `h`), then stop.
    Open(F),
    /// Drive closed for this many seconds (at most `h`), then stop.
    Close(F),
}

/// A three-point actuator driver (see the [module](self) docs).
///
/// ```
/// use regler_pid::actuator::{ActuatorConfig, Drive, ThreePoint};
///
/// // A 60 s valve, 0.2 s minimum pulse, 0.5 % dead band, sampled every second.
/// let config = ActuatorConfig { run_time: 60.0f64, min_pulse: 0.2, dead_band: 0.005, h: 1.0 };
/// let mut valve = ThreePoint::new(config, 0.0)?;
/// assert_eq!(valve.update(0.5)?, Drive::Open(1.0)); // far away: a whole sample
/// for _ in 0..28 { valve.update(0.5)?; }
/// assert!((valve.position() - 29.0 / 60.0).abs() < 1e-9);
/// assert_eq!(valve.update(0.5)?, Drive::Open(1.0));
/// assert!(matches!(valve.update(0.5)?, Drive::Stop)); // there
/// # Ok::<(), regler_pid::actuator::ActuatorError>(())
/// ```
#[derive(Clone, Debug)]
pub struct ThreePoint<F = f64> {
    config: ActuatorConfig<F>,
    /// The estimate, in two parts (`position + carry`, compensated): one sample's travel
    /// `h / run_time` can be below half an ulp of the estimate (1 ms on a 200 s valve in `f32`:
    /// 5·10⁻⁶ against 3·10⁻⁸ near 0.5, and any increment next to an end snapped to it before),
    /// and a plain sum would lose or round it systematically.
    position: F,
    carry: F,
    /// Velocity form: requested change not yet driven (fraction of the stroke), kept within the
    /// stroke that is left; compensated, so a request below half an ulp of what is pending
    /// still adds up.
    pending: Sum<F>,
    /// Velocity form: the end the valve is being taken into or held at, until the request
    /// leaves its wider margin (64·ε; 32·ε to be taken in).
    toward: Option<F>,
    /// Seconds driven open and closed in total (wear, and a check on the estimate).
    driven: (F, F),
}

impl<F: Real> ThreePoint<F> {
    /// A driver for an actuator believed to stand at `position` (0 = closed, 1 = open).
    ///
    /// # Errors
    /// [`ActuatorError::Config`] naming the value out of range.
    pub fn new(config: ActuatorConfig<F>, position: F) -> Result<Self, ActuatorError> {
        let ok = |v: F| v.is_finite() && v > F::zero();
        if !ok(config.run_time) {
            return Err(ActuatorError::Config(
                "run_time must be finite and positive",
            ));
        }
        if !ok(config.h) {
            return Err(ActuatorError::Config("h must be finite and positive"));
        }
        if !(config.min_pulse.is_finite()
            && config.min_pulse >= F::zero()
            && config.min_pulse <= config.h)
        {
            return Err(ActuatorError::Config("min_pulse must be in 0..=h"));
        }
        if config.min_pulse > config.run_time {
            return Err(ActuatorError::Config(
                "min_pulse must not exceed run_time: the shortest pulse would move the actuator more than its whole stroke",
            ));
        }
        // A pulse for an error of e is e·run_time seconds: below 2·(smallest normal)/ε a small
        // error's pulse is subnormal, rounded by more than ε²/4 of the stroke (the estimate's
        // own resolution, stated): 10⁻³⁷ s in `f32` left the motor by 29 × the bound.
        if config.run_time < F::min_positive_value() * F::from_u16(2) / F::epsilon() {
            return Err(ActuatorError::Config(
                "run_time is below 2 × the smallest normal number / ε of the float type: the pulse for a small error would be a subnormal number of seconds, too coarse for the estimate",
            ));
        }
        if config.h / config.run_time < F::min_positive_value() {
            return Err(ActuatorError::Config(
                "h / run_time is below the smallest normal number of the float type: one sample's travel cannot be resolved",
            ));
        }
        if !(config.dead_band.is_finite()
            && config.dead_band >= F::zero()
            && config.dead_band < F::one())
        {
            return Err(ActuatorError::Config("dead_band must be in 0..1"));
        }
        if !(position.is_finite() && position >= F::zero() && position <= F::one()) {
            return Err(ActuatorError::Config("position must be in 0..=1"));
        }
        Ok(Self {
            config,
            position,
            carry: F::zero(),
            pending: Sum::new(),
            toward: None,
            driven: (F::zero(), F::zero()),
        })
    }

    /// Where the actuator is believed to stand (0 = closed, 1 = open).
    #[must_use]
    pub fn position(&self) -> F {
        self.position + self.carry
    }

    /// Seconds driven (open, closed) so far.
    #[must_use]
    pub const fn driven(&self) -> (F, F) {
        self.driven
    }

    /// The smallest position error the driver moves for: the dead band, or what one minimum
    /// pulse moves the actuator (`min_pulse / run_time`), whichever is larger.
    #[must_use]
    pub fn smallest_move(&self) -> F {
        self.config
            .dead_band
            .max(self.config.min_pulse / self.config.run_time)
    }

    /// Positional form: drive toward `target` (clamped into 0..=1; within 64·ε of an end it
    /// counts as that end).
    ///
    /// An error smaller than [`smallest_move`](Self::smallest_move) is not driven: a minimum
    /// pulse would carry the actuator past the target and the next sample back (hunting). A
    /// pulse never carries the estimate past the target, so a target held constant is
    /// approached from one side only: no reversal. A target at an end (0 or 1 after clamping)
    /// is driven all the way into the stop, at least one minimum pulse, whatever the dead band:
    /// the stop ends the pulse (harmless) and a valve asked to shut, shuts.
    ///
    /// # Errors
    /// [`ActuatorError::NotFinite`]: the request is ignored and the actuator stops.
    pub fn update(&mut self, target: F) -> Result<Drive<F>, ActuatorError> {
        if !target.is_finite() {
            return Err(ActuatorError::NotFinite);
        }
        let target = snap_to_end(target);
        self.pending = Sum::new();
        self.toward = None;
        let error = self.error_to(target);
        let at_end = target == F::zero() || target == F::one();
        if error == F::zero() || (!at_end && error.abs() < self.smallest_move()) {
            return Ok(Drive::Stop);
        }
        Ok(self.drive(error, Some(target)).0)
    }

    /// Velocity form: the controller asks for a change of `delta` (fraction of the stroke).
    /// Changes too small to drive add up until they are not; the part of a request beyond an
    /// end is dropped (no windup). When what has been asked adds up to an end (within 32·ε; a
    /// valve in its stop leaves it only for a request more than 64·ε away),
    /// the actuator is driven into the stop as in the positional form, however little is left
    /// (at least one minimum pulse): a valve asked to shut, shuts.
    ///
    /// # Errors
    /// [`ActuatorError::NotFinite`]: the request is ignored and the actuator stops.
    pub fn update_delta(&mut self, delta: F) -> Result<Drive<F>, ActuatorError> {
        if !delta.is_finite() {
            return Err(ActuatorError::NotFinite);
        }
        // Never ask for more than the stroke has left (no windup); the request is kept as a
        // change, not as a target, so a change below the estimate's ulp is not lost.
        let up = self.error_to(F::one());
        let down = self.error_to(F::zero());
        let mut wanted = self.pending;
        wanted.add(delta);
        let pending = wanted.value();
        let pending = if pending > up {
            self.pending = Sum::of(up);
            up
        } else if pending < down {
            self.pending = Sum::of(down);
            down
        } else {
            self.pending = wanted;
            pending
        };
        // A request that reaches an end's margin (the rounding of changes that add up to it) is
        // a request for the end: driven into the stop however little is left, and nothing
        // when the estimate is there already. The margin has hysteresis: 32ε to be taken into
        // a stop, 64ε to be taken out again — with one margin, requests to and fro across it
        // drove 64ε to and fro whatever their size (the tenth attack). The end held is the one
        // the valve is being taken into (kept from sample to sample: a valve on its way in
        // partial pulses was sent back and forth by tiny requests across the margin, the
        // eleventh attack), or the stop the estimate stands in.
        let standing = if self.carry != F::zero() {
            None
        } else if self.position == F::one() {
            Some(F::one())
        } else if self.position == F::zero() {
            Some(F::zero())
        } else {
            None
        };
        let reaches = |end: F, margin: F| {
            if end == F::one() {
                pending >= up - margin
            } else {
                pending <= down + margin
            }
        };
        let (enter, leave) = (end_margin::<F>() * c_half::<F>(), end_margin::<F>());
        let end = match self.toward.or(standing) {
            Some(held) if reaches(held, leave) => Some(held),
            _ if reaches(F::one(), enter) => Some(F::one()),
            _ if reaches(F::zero(), enter) => Some(F::zero()),
            _ => None,
        };
        self.toward = end;
        let error = end.map_or(pending, |e| self.error_to(e));
        if error == F::zero() || (end.is_none() && pending.abs() < self.smallest_move()) {
            return Ok(Drive::Stop);
        }
        let (drive, moved) = self.drive(error, end);
        // What the estimate was moved by, taken off the request exactly: a pulse that covers
        // the pending change leaves its carry, a request that waited below half an ulp of it
        // (resetting to 0 lost one every such pulse: the eighth attack); a pulse into a stop
        // leaves the travel it took beyond the request as a request away from the end, which
        // the next requests away from it use up (the end's margin, taken again and again,
        // had turned requests to and fro across it into pulses to and fro that lost them: the
        // ninth attack).
        let mut left = self.pending;
        left.add(-moved);
        self.pending = left;
        Ok(drive)
    }

    /// An end-position switch: the actuator is known to be fully open (`true`) or closed. The
    /// estimate is re-anchored there; a waiting request beyond that end is dropped (no
    /// windup), one away from it is kept — a switch is a level, read every sample while it is
    /// made, and dropping those left the valve at the end for good. Read the switch before the
    /// sample's [`update`](Self::update) or [`update_delta`](Self::update_delta): after it, a
    /// switch still made (the pulse has not run yet) re-anchors away the travel just driven. A
    /// switch stuck made is not detected here: the estimate then follows the switch, not the
    /// valve.
    pub fn at_end(&mut self, open: bool) {
        self.position = if open { F::one() } else { F::zero() };
        self.carry = F::zero();
        self.toward = None;
        let pending = self.pending.value();
        if (open && pending > F::zero()) || (!open && pending < F::zero()) {
            self.pending = Sum::new();
        }
    }

    /// `target − estimate`, with the estimate's carry.
    fn error_to(&self, target: F) -> F {
        (target - self.position) - self.carry
    }

    /// Adds `step` to the compensated estimate (the rounding error of `position + step` taken
    /// exactly, added to the carry, and the pair renormalised — exactly too, whatever the
    /// magnitudes: a carry larger than a sum that cancelled to near 0 included), clamped into
    /// 0..=1 (the motor stops at its ends).
    fn advance(&mut self, step: F) {
        let (sum, lost) = two_sum(self.position, step);
        let (position, carry) = two_sum(sum, self.carry + lost);
        self.position = position;
        self.carry = carry;
        // On the unrounded pair: `position()` rounds 1 − 10⁻⁹ to 1 in f32.
        if self.error_to(F::one()) <= F::zero() {
            self.set(F::one());
        } else if self.error_to(F::zero()) >= F::zero() {
            self.set(F::zero());
        }
    }

    fn set(&mut self, at: F) {
        self.position = at;
        self.carry = F::zero();
    }

    /// One pulse for a position error `error` (target − estimate), at most one sample long and
    /// at least the minimum pulse; the estimate moves with it and never past the target.
    /// `target` is the target when it is a number (the positional form, or an end), so a pulse
    /// that covers the whole error puts the estimate exactly on it; the velocity form's target
    /// is `estimate + error`, which need not be one. Returns the pulse and the travel it added
    /// to the estimate (without a target: the whole error when the pulse covers it, one
    /// sample's travel otherwise; 0 for no pulse). The callers ask only for errors of at least a minimum pulse's travel,
    /// or for an end (which stops the actuator): lengthening a pulse to `min_pulse` then only
    /// absorbs rounding or runs into the stop.
    fn drive(&mut self, error: F, target: Option<F>) -> (Drive<F>, F) {
        let gt = self.config.run_time;
        let wanted = error.abs() * gt;
        let mut seconds = wanted.min(self.config.h).max(self.config.min_pulse);
        if seconds <= F::zero() {
            // An error too small to be a time (underflow, with no minimum pulse): nothing to
            // drive, unless the target is an end — a valve a subnormal distance from shut is
            // asked to shut, and shuts: a whole sample into the stop, which ends it.
            if !matches!(target, Some(t) if t == F::zero() || t == F::one()) {
                return (Drive::Stop, F::zero());
            }
            seconds = self.config.h;
        }
        // A whole sample's travel, unless that covers the error. The error is never 0 here (the
        // callers stop first), so its sign is the direction.
        let opening = error > F::zero();
        let step = seconds / gt;
        let moved = if wanted <= seconds || step >= error.abs() {
            // The pulse covers the whole error (or runs into the stop).
            match target {
                Some(t) => self.set(t),
                None => self.advance(error),
            }
            error
        } else {
            let step = if opening { step } else { -step };
            self.advance(step);
            step
        };
        let drive = if opening {
            self.driven.0 = self.driven.0 + seconds;
            Drive::Open(seconds)
        } else {
            self.driven.1 = self.driven.1 + seconds;
            Drive::Close(seconds)
        };
        (drive, moved)
    }
}

/// ½, exactly.
fn c_half<F: Real>() -> F {
    F::one() / F::from_u16(2)
}

/// How close to an end a target or a request counts as the end: 64 ulps of 1 (rounding of a
/// sum of changes that should reach it exactly).
fn end_margin<F: Real>() -> F {
    F::epsilon() * F::from_u16(64)
}

/// `v` clamped into 0..=1, and snapped onto an end it is within [`end_margin`] of. Only targets
/// are snapped, never the estimate (which moves by as little as `h / run_time`).
fn snap_to_end<F: Real>(v: F) -> F {
    let near = end_margin::<F>();
    if v < near {
        F::zero()
    } else if v > F::one() - near {
        F::one()
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn valve() -> ThreePoint<f64> {
        ThreePoint::new(
            ActuatorConfig {
                run_time: 60.0,
                min_pulse: 0.2,
                dead_band: 0.005,
                h: 1.0,
            },
            0.5,
        )
        .unwrap()
    }

    #[test]
    fn config_is_checked() {
        let ok = ActuatorConfig {
            run_time: 60.0,
            min_pulse: 0.2,
            dead_band: 0.005,
            h: 1.0,
        };
        assert!(ThreePoint::new(ok, 0.0).is_ok());
        for (bad, pos) in [
            (
                ActuatorConfig {
                    run_time: 0.0,
                    ..ok
                },
                0.0,
            ),
            (ActuatorConfig { h: f64::NAN, ..ok }, 0.0),
            (
                ActuatorConfig {
                    min_pulse: 2.0,
                    ..ok
                },
                0.0,
            ),
            (
                ActuatorConfig {
                    dead_band: 1.0,
                    ..ok
                },
                0.0,
            ),
            (ok, 1.5),
        ] {
            assert!(matches!(
                ThreePoint::new(bad, pos),
                Err(ActuatorError::Config(_))
            ));
        }
    }

    #[test]
    fn no_windup_at_the_ends() {
        let mut v = valve();
        // Ask for far more opening than there is, for a long time.
        for _ in 0..200 {
            v.update_delta(0.1).unwrap();
        }
        assert_eq!(v.position(), 1.0);
        // The first request to close moves at once: nothing was stored beyond the end.
        assert!(
            matches!(v.update_delta(-0.05).unwrap(), Drive::Close(s) if (s - 1.0).abs() < 1e-12)
        );
        // Driven time equals the travel: 30 s from the middle to the end (and at most one
        // minimum pulse into the stop, where the 30 rounded steps of 1/60 left the estimate an
        // ulp short of it), 1 s back.
        assert!(
            (30.0 - 1e-9..=30.2 + 1e-9).contains(&v.driven().0)
                && (v.driven().1 - 1.0).abs() < 1e-9,
            "{:?}",
            v.driven()
        );
    }

    #[test]
    fn small_requests_add_up_to_a_minimum_pulse() {
        let mut v = valve();
        // 0.1 % per sample: below the 0.5 % dead band and the 0.2 s (0.33 %) minimum pulse.
        let mut pulses = 0;
        for _ in 0..20 {
            if let Drive::Open(s) = v.update_delta(0.001).unwrap() {
                assert!(s >= 0.2);
                pulses += 1;
            }
        }
        assert!(pulses >= 3, "{pulses}");
        assert!((v.position() - 0.52).abs() < 0.006, "{}", v.position());
        assert_eq!(v.update_delta(f64::NAN), Err(ActuatorError::NotFinite));
    }
}
