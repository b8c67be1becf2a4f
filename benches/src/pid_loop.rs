//! regler's controller in each number type on one closed loop: the controller and a first-order
//! plant (y ← y + a·(u − y)), set-point 1, so every type does the same work per sample. The
//! comparison with the `pid` crate is in [`pid_shapes`](crate::pid_shapes), where both
//! controllers run in one generic loop function.

use regler_pid::{Config, Kind, Pid, Scalar};

/// Plant pole: the share of the gap to the output the measurement closes per sample.
pub const PLANT_A: f64 = 0.05;
/// Controller gain.
pub const K: f64 = 2.0;
/// Integral time, s.
pub const TI: f64 = 1.0;
/// Derivative time, s: short enough that the `pid` crate's unfiltered derivative (gain K·Td/h = 4)
/// leaves its loop stable (at Td = 0.2 s its loop rings between the output limits for good).
pub const TD: f64 = 0.02;
/// Sample period, s.
pub const H: f64 = 0.01;

/// regler's configuration with everything on: derivative filter, set-point weights,
/// back-calculation, rate limit and clamps.
#[must_use]
pub fn regler_config() -> Config {
    Config {
        kind: Kind::PID,
        k: K,
        ti: TI,
        td: TD,
        n: 10.0,
        b: 1.0,
        c: 0.0,
        tt: Some(0.05),
        h: H,
        ymin: -5.0,
        ymax: 5.0,
        dymax: Some(0.5),
        ..Config::default()
    }
}

/// A regler controller on the loop.
pub struct ReglerLoop<T> {
    pid: Pid<T>,
    y: T,
    a: T,
    r: T,
}

impl<T: Scalar> ReglerLoop<T> {
    /// The loop at rest.
    ///
    /// # Panics
    /// Never: the configuration is valid.
    #[must_use]
    pub fn new() -> ReglerLoop<T> {
        let pid = Pid::new(&regler_config()).expect("valid bench configuration");
        ReglerLoop {
            pid,
            y: T::ZERO,
            a: T::from_f64(PLANT_A),
            r: T::from_f64(1.0),
        }
    }

    /// One sample: controller update and plant step; returns the measurement.
    #[inline]
    pub fn step(&mut self) -> T {
        let u = self.pid.update(self.r, self.y);
        self.y = self.y.add(self.a.mul(u.sub(self.y)));
        self.y
    }
}

impl<T: Scalar> Default for ReglerLoop<T> {
    fn default() -> ReglerLoop<T> {
        ReglerLoop::new()
    }
}
