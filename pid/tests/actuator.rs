//! The three-point actuator driver against a simulated motor (it moves at 1/GT of the stroke per
//! second while driven and stops at its ends), and in a loop with the PID.
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "a test may panic: that is how it fails"
)]

use proptest::prelude::*;
use regler_pid::actuator::{ActuatorConfig, Drive, ThreePoint};
use regler_pid::{Config, Kind, Pid};

/// The real motor: where it is, moved by the pulses.
fn apply(real: &mut f64, drive: Drive, gt: f64) {
    match drive {
        Drive::Open(s) => *real = (*real + s / gt).min(1.0),
        Drive::Close(s) => *real = (*real - s / gt).max(0.0),
        Drive::Stop => {}
    }
}

proptest! {
    /// Whatever the targets (in or out of range), the estimate is where the motor is, and after
    /// enough samples the motor stands within the dead band (or the minimum pulse) of the target.
    #[test]
    fn estimate_follows_the_motor_and_settles_on_target(
        targets in proptest::collection::vec(-0.5f64..1.5, 1..20),
        start in 0.0f64..=1.0,
        gt in 5.0f64..120.0,
    ) {
        let config = ActuatorConfig { run_time: gt, min_pulse: 0.1, dead_band: 0.01, h: 0.5 };
        let mut v = ThreePoint::new(config, start).unwrap();
        let mut real = start;
        for &target in &targets {
            for _ in 0..(2.0 * gt / 0.5) as usize + 2 {
                let d = v.update(target).unwrap();
                apply(&mut real, d, gt);
                prop_assert!((v.position() - real).abs() < 1e-9);
            }
            let goal = target.clamp(0.0, 1.0);
            prop_assert!((real - goal).abs() <= 0.01 + 0.1 / gt + 1e-9, "{} vs {}", real, goal);
        }
    }

    /// Velocity form: the motor ends where the sum of the requests says (clamped at the ends at
    /// every step, the way a real stroke is), give or take what is still below a minimum pulse.
    #[test]
    fn velocity_form_integrates_the_requests(
        deltas in proptest::collection::vec(-0.2f64..0.2, 1..60),
        start in 0.0f64..=1.0,
    ) {
        let gt = 30.0;
        let config = ActuatorConfig { run_time: gt, min_pulse: 0.2, dead_band: 0.002, h: 1.0 };
        let mut v = ThreePoint::new(config, start).unwrap();
        let mut real = start;
        let mut wanted = start;
        for &d in &deltas {
            wanted = (wanted + d).clamp(0.0, 1.0);
            // Give each request time to be driven before the next.
            for k in 0..8 {
                let drive = v.update_delta(if k == 0 { d } else { 0.0 }).unwrap();
                apply(&mut real, drive, gt);
            }
            prop_assert!((v.position() - real).abs() < 1e-9);
        }
        let smallest = 0.002f64.max(0.2 / gt);
        prop_assert!((real - wanted).abs() <= smallest + 1e-9, "{} vs {}", real, wanted);
    }
}

/// A PI controller through a 60 s valve on a first-order process, in velocity form (the valve
/// integrates the output's changes): no windup when the set-point asks for more than the valve
/// can give, and it settles when it can.
#[test]
fn pid_through_a_slow_valve_in_velocity_form_does_not_wind_up() {
    let h = 1.0;
    let gt = 60.0;
    let mut valve = ThreePoint::new(
        ActuatorConfig {
            run_time: gt,
            min_pulse: 0.2,
            dead_band: 0.003,
            h,
        },
        0.0,
    )
    .unwrap();
    let config = Config::<f64> {
        kind: Kind::PI,
        k: 2.0,
        ti: 40.0,
        h,
        ymin: 0.0,
        ymax: 1.0,
        tt: Some(5.0),
        ..Config::default()
    };
    let mut pid: Pid<f64> = Pid::new(&config).unwrap();
    let (mut y, mut real) = (0.0f64, 0.0f64);
    let a = (-h / 30.0f64).exp();
    let mut last = 0.0;
    let mut run = |setpoint: f64, seconds: usize, y: &mut f64, real: &mut f64| {
        for _ in 0..seconds {
            let u = pid.update(setpoint, *y);
            apply(real, valve.update_delta(u - last).unwrap(), gt);
            last = u;
            *y = a * *y + (1.0 - a) * 100.0 * *real;
        }
    };
    // Unreachable: 150 % of what the full-open valve gives, for 20 minutes.
    run(150.0, 1200, &mut y, &mut real);
    assert_eq!(real, 1.0);
    // Back to reachable: it must come off the end at once, not after unwinding an integral.
    let before = real;
    run(50.0, 20, &mut y, &mut real);
    assert!(real < before - 0.1, "still stuck open: {real}");
    run(50.0, 1500, &mut y, &mut real);
    assert!((y - 50.0).abs() < 1.0, "{y}");
}
