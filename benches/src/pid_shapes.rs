//! One loop shape for both controllers, four workloads: the fair comparison the PID benches and
//! the `pid-shapes` instruction counter share. The loop is the same generic function for both
//! sides (`#[inline(never)]` per controller type, the controller's `update` inlined into it the
//! same way, `#[inline(always)]` so that neither depends on the compiler's size heuristics), the plant is the same first-order step, and the workload's own cost (set-point
//! schedule, measurement noise) is the same on both sides.

use crate::pid_loop::{H, K, PLANT_A, TD, TI, regler_config};
use regler_pid::Pid;

/// A controller on the shared loop.
pub trait Controller {
    /// One sample: set-point, measurement → output.
    fn update(&mut self, setpoint: f32, measurement: f32) -> f32;
}

impl Controller for Pid<f32> {
    #[inline(always)]
    fn update(&mut self, setpoint: f32, measurement: f32) -> f32 {
        Pid::update(self, setpoint, measurement)
    }
}

/// No controller: the output is the error. Measures the loop's own cost (plant, shape), which is
/// subtracted to get a controller's cost per update.
pub struct Null;

impl Controller for Null {
    #[inline(always)]
    fn update(&mut self, setpoint: f32, measurement: f32) -> f32 {
        setpoint - measurement
    }
}

/// The `pid` crate, given the set-point each sample the way its API takes it.
pub struct Anchor(pub pid::Pid<f32>);

impl Controller for Anchor {
    #[inline(always)]
    fn update(&mut self, setpoint: f32, measurement: f32) -> f32 {
        self.0.setpoint(setpoint);
        self.0.next_control_output(measurement).output
    }
}

/// The `pid` crate configured as the bench's regler controller (ideal form, limits ±5).
#[must_use]
pub fn anchor() -> Anchor {
    let mut pid = pid::Pid::new(1.0f32, 5.0);
    pid.p(K as f32, 100.0)
        .i((K * H / TI) as f32, 5.0)
        .d((K * TD / H) as f32, 100.0);
    Anchor(pid)
}

/// regler's controller with everything on (filter, weights, back-calculation, rate limit,
/// non-finite guard).
///
/// # Panics
/// Never: the configuration is valid.
#[must_use]
pub fn regler() -> Pid<f32> {
    Pid::new(&regler_config()).expect("valid bench configuration")
}

/// A controller called out of line, once per sample: the shape of firmware, where a timer
/// interrupt or a scheduler calls `update` and nothing of the controller stays in registers
/// between samples (no coefficient load hoisted out of a loop, prologue and epilogue paid every
/// sample). [`run`] with a bare controller shows the other extreme: the update inlined into the
/// loop.
pub struct OutOfLine<C>(pub C);

impl<C: Controller> Controller for OutOfLine<C> {
    #[inline(never)]
    fn update(&mut self, setpoint: f32, measurement: f32) -> f32 {
        self.0.update(setpoint, measurement)
    }
}

/// How the controller meets the loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Call {
    /// `update` inlined into the loop.
    Inlined,
    /// One out-of-line call per sample ([`OutOfLine`]).
    PerSample,
}

/// Runs `samples` samples of `shape` with `c` met the way `call` says.
pub fn run_with<C: Controller>(c: &mut C, call: Call, shape: Shape, samples: u64) -> f32 {
    match call {
        Call::Inlined => run(c, shape, samples),
        Call::PerSample => run(&mut OutOfLine(&mut *c), shape, samples),
    }
}

impl<C: Controller> Controller for &mut C {
    #[inline(always)]
    fn update(&mut self, setpoint: f32, measurement: f32) -> f32 {
        (**self).update(setpoint, measurement)
    }
}

/// The workloads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Set-point 1 throughout: after the first transient the loop sits still.
    Constant,
    /// Set-point ±1, switching every 200 samples.
    Steps,
    /// Set-point 1, the measurement with uniform noise of ±0.05 (xorshift).
    Noise,
    /// Set-point 10: beyond what the ±5 output can reach, the controller saturates.
    Saturation,
}

impl Shape {
    /// By name: `constant`, `steps`, `noise`, `saturation`.
    #[must_use]
    pub fn parse(name: &str) -> Option<Shape> {
        Some(match name {
            "constant" => Shape::Constant,
            "steps" => Shape::Steps,
            "noise" => Shape::Noise,
            "saturation" => Shape::Saturation,
            _ => return None,
        })
    }
}

/// Runs `samples` samples of `shape`; returns the last measurement.
#[inline(never)]
pub fn run<C: Controller>(c: &mut C, shape: Shape, samples: u64) -> f32 {
    let a = PLANT_A as f32;
    let mut y = 0.0f32;
    let mut x = 0x9E37_79B9u32;
    for k in 0..samples {
        let r = match shape {
            Shape::Constant | Shape::Noise => 1.0,
            Shape::Steps => {
                if (k / 200) % 2 == 0 {
                    1.0
                } else {
                    -1.0
                }
            }
            Shape::Saturation => 10.0,
        };
        let measured = if shape == Shape::Noise {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            y + (x >> 8) as f32 * (0.1 / 16_777_216.0) - 0.05
        } else {
            y
        };
        let u = c.update(r, std::hint::black_box(measured));
        y += a * (u - y);
    }
    y
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, reason = "a test may panic: that is how it fails")]
    use super::*;

    /// The harness measures working loops: both controllers settle on the set-point, follow
    /// the steps, hold through the noise and sit at the limit when saturated, inlined or called.
    #[test]
    fn both_controllers_control_every_shape() {
        for call in [Call::Inlined, Call::PerSample] {
            for (shape, want, tolerance) in [
                (Shape::Constant, 1.0, 0.01),
                (Shape::Steps, 1.0, 0.25),
                (Shape::Noise, 1.0, 0.1),
                (Shape::Saturation, 5.0, 0.01),
            ] {
                // 3 000 samples end 200 into a set-point of +1 on the steps (coming from −1).
                let a = run_with(&mut regler(), call, shape, 3000);
                let b = run_with(&mut anchor(), call, shape, 3000);
                for (who, y) in [("regler", a), ("pid crate", b)] {
                    assert!(
                        (y - want).abs() < tolerance,
                        "{who} {shape:?} {call:?}: {y}"
                    );
                }
            }
        }
    }
}
