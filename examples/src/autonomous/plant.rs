//! The simulated processes: the heated room and the tank (what the controller measures and
//! drives), and the three-point actuator's motor between the controller and the process.
//!
//! The plant integrates in fixed steps (1 s for the room, 0.1 s for the
//! tank); the controller samples it every S seconds (see [`super::controller`]).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::ProcessKind;

/// Room heater: degrees above outdoor per volt at steady state.
pub(super) const HEATER_GAIN: f64 = 4.0;
/// Tank level, %, that 1 V of pump holds against a shut outflow valve: the pump is sized for
/// the largest outflow (30 % of the inflow range, plus disturbances) with margin, as one would
/// commission it, so the loop controls instead of saturating at 10 V.
pub(super) const PUMP_GAIN: f64 = 15.0;

pub(super) struct Plant {
    kind: ProcessKind,
    /// The measured quantity (°C or %).
    pub(super) x: f64,
    delay: std::collections::VecDeque<f64>,
    /// The sum of the `outdoor` steps so far, scale units.
    pub(super) disturbance: f64,
    noise: f64,
    rng: ChaCha8Rng,
    outdoor_mean: f64,
}

impl Plant {
    pub(super) fn new(kind: ProcessKind, seed: u64, outdoor_mean: f64) -> Plant {
        let delay_steps = match kind {
            ProcessKind::Room => 120,
            ProcessKind::Tank => 0,
        };
        let x = match kind {
            ProcessKind::Room => 15.0,
            ProcessKind::Tank => 20.0,
        };
        Plant {
            kind,
            x,
            delay: std::iter::repeat_n(0.0, delay_steps).collect(),
            disturbance: 0.0,
            noise: 0.0,
            rng: ChaCha8Rng::seed_from_u64(seed),
            outdoor_mean,
        }
    }

    /// Outdoor temperature (room) at `t`.
    pub(super) fn outdoor(&self, t: f64) -> f64 {
        let day = 2.0 * std::f64::consts::PI * (t / 86_400.0 - 0.625);
        self.outdoor_mean + 5.0 * day.sin() + self.disturbance + self.noise
    }

    pub(super) fn step(&mut self, t: f64, u: f64) {
        let dt = self.kind.dt();
        self.delay.push_back(u);
        let applied = self.delay.pop_front().unwrap_or(u);
        match self.kind {
            ProcessKind::Room => {
                // Weather noise: a slow random walk, pulled back toward zero.
                self.noise += dt * (-self.noise / 7200.0) + 0.01 * (self.rng.random::<f64>() - 0.5);
                let target = self.outdoor(t) + HEATER_GAIN * applied;
                self.x += dt * (target - self.x) / 1800.0;
            }
            ProcessKind::Tank => {
                // The outflow valve moves every five minutes, within its range.
                if (t / 300.0).fract() < dt / 300.0 {
                    self.noise = (self.noise + self.rng.random_range(-2.0..2.0)).clamp(0.0, 30.0);
                }
                let target = PUMP_GAIN * applied - self.disturbance - self.noise;
                self.x += dt * (target - self.x) / 30.0;
                self.x = self.x.clamp(0.0, 100.0);
            }
        }
    }
}

/// A three-point actuator: the driver (with its position estimate) and the real motor.
pub(super) struct Motor {
    driver: regler_pid::actuator::ThreePoint<f64>,
    gt: f64,
    h: f64,
    /// Where the motor really is, 0..1.
    position: f64,
    /// Seconds of the current pulse still to run, and its direction.
    pulse_left: f64,
    opening: bool,
    /// The controller output at the last sample (V).
    pub(super) last_u: f64,
}

impl Motor {
    pub(super) fn new(gt: f64, h: f64, position: f64) -> Result<Motor, String> {
        use regler_pid::actuator::{ActuatorConfig, ThreePoint};
        let config = ActuatorConfig {
            run_time: gt,
            min_pulse: 0.2f64.min(h),
            dead_band: 0.005,
            h,
        };
        let driver = ThreePoint::new(config, position).map_err(|e| e.to_string())?;
        Ok(Motor {
            driver,
            gt,
            h,
            position,
            pulse_left: 0.0,
            opening: false,
            last_u: 10.0 * position,
        })
    }

    /// A new sample: the controller's output changed by `delta_volts` (10 V = the full stroke).
    pub(super) fn command(&mut self, delta_volts: f64, h: f64) {
        use regler_pid::actuator::Drive;
        if (h - self.h).abs() > 1e-9 {
            // The operator changed the sample period: the longest pulse changes with it.
            if let Ok(m) = Motor::new(self.gt, h, self.driver.position()) {
                let (position, last_u) = (self.position, self.last_u);
                *self = m;
                (self.position, self.last_u) = (position, last_u);
            }
        }
        match self.driver.update_delta(delta_volts / 10.0) {
            Ok(Drive::Open(s)) => (self.pulse_left, self.opening) = (s, true),
            Ok(Drive::Close(s)) => (self.pulse_left, self.opening) = (s, false),
            _ => self.pulse_left = 0.0,
        }
    }

    /// The motor runs for `dt` seconds (or what is left of the pulse); returns its output in
    /// volts-equivalent (10 V = fully open).
    pub(super) fn run(&mut self, dt: f64) -> f64 {
        let m = dt.min(self.pulse_left);
        if m > 0.0 {
            let moved = m / self.gt;
            self.position = if self.opening {
                (self.position + moved).min(1.0)
            } else {
                (self.position - moved).max(0.0)
            };
            self.pulse_left -= m;
        }
        10.0 * self.position
    }
}
