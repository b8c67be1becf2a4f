//! regler's `Pid<f32>` beside the `pid` crate (4.x) on the same closed loop: the same plant
//! (a first-order step), the same four workloads, two shapes. Used by the PID benches, the
//! `pid-shapes` instruction counter and the test that both controllers do the same work.
//!
//! Shapes ([`Call`]):
//! - **firmware**: the controller is built from a configuration the compiler cannot see
//!   (`black_box`), lives in memory, and is updated by one out-of-line call per sample
//!   (`#[inline(never)]`, on a `&mut` behind `black_box`) — as a timer interrupt or a scheduler
//!   calls it;
//! - **inlined**: the loop owns a controller built from a constant configuration, the update
//!   inlined into it, so the compiler may fold the configuration and keep the state in
//!   registers.
//!
//! The workload is a type parameter ([`Workload`]), so the set-point schedule and the noise are
//! compiled into each loop: no per-sample dispatch on the workload, and the no-controller
//! baseline ([`Null`], subtracted to get a controller's net cost) runs the very same loop.
//!
//! The anchor is configured as its docs show it: `Pid::new(setpoint, output_limit)` and
//! `p(kp, limit)`, `i(ki, limit)`, `d(kd, limit)` with every term's limit equal to the output
//! limit (±5); the integral's limit is that crate's anti-windup. Its set-point is set each sample
//! through `setpoint()` (a store), the way its API takes a set-point.

use std::hint::black_box;

use crate::pid_loop::{H, K, PLANT_A, TD, TI, regler_config};
use regler_pid::Pid;

/// The output limit both controllers clamp to (±).
pub const LIMIT: f32 = 5.0;

/// A controller on the shared loop.
pub trait Controller {
    /// One sample: set-point, measurement → output.
    fn update(&mut self, setpoint: f32, measurement: f32) -> f32;
}

/// How a contestant is built in each shape.
pub trait Build: Controller + Sized {
    /// From a configuration the compiler sees (the inlined shape).
    fn constant() -> Self;
    /// From a configuration read at run time (the firmware shape).
    fn runtime() -> Self;
}

impl Controller for Pid<f32> {
    #[inline(always)]
    fn update(&mut self, setpoint: f32, measurement: f32) -> f32 {
        Pid::update(self, setpoint, measurement)
    }
}

/// regler's controller with everything on (filter, weights, back-calculation, rate limit,
/// non-finite guard, state bounds): [`regler_config`].
impl Build for Pid<f32> {
    #[inline(always)]
    fn constant() -> Self {
        regler()
    }
    #[inline(always)]
    fn runtime() -> Self {
        Pid::new(black_box(&regler_config())).expect("valid bench configuration")
    }
}

/// No controller: the output is the error. The loop's own cost (plant, workload, and in the
/// firmware shape the call), subtracted to get a controller's net cost per update.
pub struct Null;

impl Controller for Null {
    #[inline(always)]
    fn update(&mut self, setpoint: f32, measurement: f32) -> f32 {
        setpoint - measurement
    }
}

impl Build for Null {
    fn constant() -> Self {
        Null
    }
    fn runtime() -> Self {
        Null
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

/// The `pid` crate with the gains of regler's configuration (ideal form: kp = K, ki = K·h/Ti,
/// kd = K·Td/h) and every limit ±[`LIMIT`], as its docs configure it.
#[inline(always)]
fn anchor_from(kp: f32, ki: f32, kd: f32, limit: f32) -> Anchor {
    let mut pid = pid::Pid::new(1.0f32, limit);
    pid.p(kp, limit).i(ki, limit).d(kd, limit);
    Anchor(pid)
}

impl Build for Anchor {
    #[inline(always)]
    fn constant() -> Self {
        anchor()
    }
    #[inline(always)]
    fn runtime() -> Self {
        let (kp, ki, kd) = black_box(gains());
        anchor_from(kp, ki, kd, black_box(LIMIT))
    }
}

/// The anchor's gains: kp, ki, kd.
#[inline(always)]
fn gains() -> (f32, f32, f32) {
    (K as f32, (K * H / TI) as f32, (K * TD / H) as f32)
}

/// The `pid` crate configured as the bench's regler controller.
#[must_use]
#[inline(always)]
pub fn anchor() -> Anchor {
    let (kp, ki, kd) = gains();
    anchor_from(kp, ki, kd, LIMIT)
}

/// regler's controller with everything on (filter, weights, back-calculation, rate limit,
/// non-finite guard).
///
/// # Panics
/// Never: the configuration is valid.
#[must_use]
#[inline(always)]
pub fn regler() -> Pid<f32> {
    Pid::new(&regler_config()).expect("valid bench configuration")
}

/// How the controller meets the loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Call {
    /// Run-time configuration, state in memory, one out-of-line call per sample.
    Firmware,
    /// Constant configuration, the update inlined into a loop that owns the controller.
    Inlined,
}

impl Call {
    /// By name: `firmware`, `inlined`.
    #[must_use]
    pub fn parse(name: &str) -> Option<Call> {
        match name {
            "firmware" => Some(Call::Firmware),
            "inlined" => Some(Call::Inlined),
            _ => None,
        }
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

/// A workload, compiled into the loop: the set-point at sample `k` and what the sensor reads
/// when the plant is at `y`.
pub trait Workload: Default {
    /// The set-point at sample `k`.
    fn setpoint(&self, k: u64) -> f32;
    /// The measurement of `y`.
    fn measure(&mut self, y: f32) -> f32;
}

/// [`Shape::Constant`].
#[derive(Default)]
pub struct Constant;
/// [`Shape::Steps`].
#[derive(Default)]
pub struct Steps;
/// [`Shape::Noise`]: the xorshift state.
pub struct Noise(u32);
/// [`Shape::Saturation`].
#[derive(Default)]
pub struct Saturation;

impl Default for Noise {
    fn default() -> Self {
        Noise(0x9E37_79B9)
    }
}

impl Workload for Constant {
    #[inline(always)]
    fn setpoint(&self, _: u64) -> f32 {
        1.0
    }
    #[inline(always)]
    fn measure(&mut self, y: f32) -> f32 {
        y
    }
}

impl Workload for Steps {
    #[inline(always)]
    fn setpoint(&self, k: u64) -> f32 {
        if (k / 200).is_multiple_of(2) {
            1.0
        } else {
            -1.0
        }
    }
    #[inline(always)]
    fn measure(&mut self, y: f32) -> f32 {
        y
    }
}

impl Workload for Noise {
    #[inline(always)]
    fn setpoint(&self, _: u64) -> f32 {
        1.0
    }
    #[inline(always)]
    fn measure(&mut self, y: f32) -> f32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        y + (x >> 8) as f32 * (0.1 / 16_777_216.0) - 0.05
    }
}

impl Workload for Saturation {
    #[inline(always)]
    fn setpoint(&self, _: u64) -> f32 {
        10.0
    }
    #[inline(always)]
    fn measure(&mut self, y: f32) -> f32 {
        y
    }
}

/// Where a run ended: the plant output and the set-point of the last sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct End {
    /// The plant output after the last sample.
    pub y: f32,
    /// The set-point of the last sample.
    pub r: f32,
}

/// The firmware shape's update: out of line, on state in memory (the `black_box` on the
/// reference stops LLVM from promoting the controller's fields to arguments loaded by the caller).
#[inline(never)]
fn update_call<C: Controller>(c: &mut C, setpoint: f32, measurement: f32) -> f32 {
    black_box(c).update(setpoint, measurement)
}

/// The shared loop: `samples` samples of workload `W` on `c`; `FIRMWARE` (a constant) picks the
/// call, so neither shape pays a test per sample.
#[inline(always)]
fn closed_loop<C: Controller, W: Workload, const FIRMWARE: bool>(c: &mut C, samples: u64) -> End {
    let a = PLANT_A as f32;
    let mut w = W::default();
    let mut y = 0.0f32;
    let mut r = 0.0f32;
    for k in 0..samples {
        r = w.setpoint(k);
        let measured = black_box(w.measure(y));
        let u = if FIRMWARE {
            update_call(black_box(&mut *c), r, measured)
        } else {
            c.update(r, measured)
        };
        y += a * (u - y);
    }
    End { y, r }
}

/// The firmware shape: `c` (built at run time, kept between runs as firmware keeps it) updated
/// once per sample out of line.
#[inline(never)]
pub fn firmware<C: Controller, W: Workload>(c: &mut C, samples: u64) -> End {
    closed_loop::<C, W, true>(c, samples)
}

/// The inlined shape: the loop builds and owns its controller from the constant configuration.
#[inline(never)]
pub fn inlined<C: Build, W: Workload>(samples: u64) -> End {
    let mut c = C::constant();
    closed_loop::<C, W, false>(&mut c, samples)
}

/// Runs `samples` samples of `shape` in `call` with a fresh `C` (for the firmware shape built
/// by [`Build::runtime`]). The workload and the shape are chosen here, once, not per sample.
pub fn run<C: Build>(call: Call, shape: Shape, samples: u64) -> End {
    match call {
        Call::Firmware => run_firmware(&mut C::runtime(), shape, samples),
        Call::Inlined => match shape {
            Shape::Constant => inlined::<C, Constant>(samples),
            Shape::Steps => inlined::<C, Steps>(samples),
            Shape::Noise => inlined::<C, Noise>(samples),
            Shape::Saturation => inlined::<C, Saturation>(samples),
        },
    }
}

/// The firmware shape on an existing controller (the benches keep one across iterations).
pub fn run_firmware<C: Controller>(c: &mut C, shape: Shape, samples: u64) -> End {
    match shape {
        Shape::Constant => firmware::<C, Constant>(c, samples),
        Shape::Steps => firmware::<C, Steps>(c, samples),
        Shape::Noise => firmware::<C, Noise>(c, samples),
        Shape::Saturation => firmware::<C, Saturation>(c, samples),
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, reason = "a test may panic: that is how it fails")]
    use super::*;

    /// The harness compares two working controllers on the same work: at the end of every
    /// step (and of the other workloads) both saw the same set-point and both reached it (or,
    /// saturated, sit at the same limit), in both shapes — and the two shapes agree.
    #[test]
    fn both_controllers_reach_the_same_setpoints() {
        // 2 000 samples end a −1 segment of the steps, 2 200 and 3 000 a +1 segment.
        for samples in [2000, 2200, 3000] {
            for shape in [
                Shape::Constant,
                Shape::Steps,
                Shape::Noise,
                Shape::Saturation,
            ] {
                let mut ends = Vec::new();
                for call in [Call::Firmware, Call::Inlined] {
                    let a = run::<Pid<f32>>(call, shape, samples);
                    let b = run::<Anchor>(call, shape, samples);
                    let none = run::<Null>(call, shape, samples);
                    assert_eq!(a.r, b.r, "set-points differ: {shape:?} {call:?} {samples}");
                    assert_eq!(a.r, none.r, "the baseline runs another workload");
                    // Saturated, the plant settles at the output limit; otherwise at the
                    // set-point (within the noise and what is left of the step's transient).
                    let want = if shape == Shape::Saturation {
                        LIMIT
                    } else {
                        a.r
                    };
                    let tolerance = match shape {
                        Shape::Steps => 0.25, // 200 samples after a step of 2
                        Shape::Noise => 0.1,
                        Shape::Constant | Shape::Saturation => 0.02,
                    };
                    for (who, end) in [("regler", a), ("pid crate", b)] {
                        assert!(
                            (end.y - want).abs() < tolerance,
                            "{who} {shape:?} {call:?} {samples}: {end:?}, want {want}"
                        );
                    }
                    ends.push((a, b));
                }
                assert_eq!(ends[0], ends[1], "the shapes disagree: {shape:?} {samples}");
            }
        }
    }

    /// Both controllers are configured alike: same gains and limits, and the anchor's
    /// configuration is the one its docs show (every term limited to the output limit).
    #[test]
    fn the_anchor_is_configured_as_documented() {
        let p = anchor().0;
        let q = Anchor::runtime().0;
        assert_eq!(p, q);
        assert_eq!(p.output_limit, LIMIT);
        assert_eq!((p.p_limit, p.i_limit, p.d_limit), (LIMIT, LIMIT, LIMIT));
        assert_eq!((p.kp, p.ki, p.kd), (2.0, 0.02, 4.0));
        let c = regler_config();
        assert_eq!((c.ymin, c.ymax), (-f64::from(LIMIT), f64::from(LIMIT)));
    }
}
