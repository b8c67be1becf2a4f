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
//!   driven into the stop (at least one minimum pulse; the stop ends it): a valve asked to shut,
//!   shuts.
//! - Velocity form: requests smaller than `smallest_move()` wait and add up.
//! - The estimate stays in 0..=1 and follows a motor that moves `s / run_time` per pulse and
//!   stops at its ends.
//! - Refused by [`ThreePoint::new`]: a run time or h that is not finite and positive, a minimum
//!   pulse outside 0..=h or longer than the run time, a dead band outside 0..1.
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
    position: F,
    /// Velocity form: requested change not yet driven (fraction of the stroke).
    pending: F,
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
            pending: F::zero(),
            driven: (F::zero(), F::zero()),
        })
    }

    /// Where the actuator is believed to stand (0 = closed, 1 = open).
    #[must_use]
    pub const fn position(&self) -> F {
        self.position
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

    /// Positional form: drive toward `target` (clamped into 0..=1).
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
        let target = clamp01(target);
        self.pending = F::zero();
        let error = target - self.position;
        let at_end = target == F::zero() || target == F::one();
        if error == F::zero() || (!at_end && error.abs() < self.smallest_move()) {
            return Ok(Drive::Stop);
        }
        Ok(self.drive(target))
    }

    /// Velocity form: the controller asks for a change of `delta` (fraction of the stroke).
    /// Changes too small to drive add up until they are not; the part of a request beyond an
    /// end is dropped (no windup).
    ///
    /// # Errors
    /// [`ActuatorError::NotFinite`]: the request is ignored and the actuator stops.
    pub fn update_delta(&mut self, delta: F) -> Result<Drive<F>, ActuatorError> {
        if !delta.is_finite() {
            return Err(ActuatorError::NotFinite);
        }
        // Never ask for more than the stroke has left.
        let target = clamp01(self.position + self.pending + delta);
        self.pending = target - self.position;
        if self.pending == F::zero() || self.pending.abs() < self.smallest_move() {
            return Ok(Drive::Stop);
        }
        let drive = self.drive(target);
        self.pending = target - self.position;
        Ok(drive)
    }

    /// An end-position switch: the actuator is known to be fully open (`true`) or closed.
    pub fn at_end(&mut self, open: bool) {
        self.position = if open { F::one() } else { F::zero() };
        self.pending = F::zero();
    }

    /// One pulse toward `target` (in 0..=1, not the estimate), at most one sample long and at
    /// least the minimum pulse; the estimate moves with it and never past the target. The
    /// callers ask only for errors of at least a minimum pulse's travel, or for an end (which
    /// stops the actuator): lengthening a pulse to `min_pulse` then only absorbs rounding or
    /// runs into the stop.
    fn drive(&mut self, target: F) -> Drive<F> {
        let gt = self.config.run_time;
        let error = target - self.position;
        let wanted = error.abs() * gt;
        let seconds = wanted.min(self.config.h).max(self.config.min_pulse);
        if seconds <= F::zero() {
            return Drive::Stop; // an error too small to be a time (underflow)
        }
        self.position = if wanted <= seconds {
            target // the pulse covers the whole error (or runs into the stop)
        } else if error > F::zero() {
            clamp01((self.position + seconds / gt).min(target))
        } else {
            clamp01((self.position - seconds / gt).max(target))
        };
        if error > F::zero() {
            self.driven.0 = self.driven.0 + seconds;
            Drive::Open(seconds)
        } else {
            self.driven.1 = self.driven.1 + seconds;
            Drive::Close(seconds)
        }
    }
}

/// `v` clamped into 0..=1, and snapped onto an end it is within rounding of (64 ulps): a run of
/// pulses that adds up to the full stroke must read as the end, in `f32` too.
fn clamp01<F: Real>(v: F) -> F {
    let near = F::epsilon() * F::from_u16(64);
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
        // Driven time equals the travel: 30 s from the middle to the end, 1 s back.
        assert!(
            (v.driven().0 - 30.0).abs() < 1e-9 && (v.driven().1 - 1.0).abs() < 1e-9,
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
