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
    /// (Under Miri up to 4 targets and strokes up to 20 s: each target runs the stroke twice.)
    #[test]
    fn estimate_follows_the_motor_and_settles_on_target(
        targets in proptest::collection::vec(-0.5f64..1.5, 1..if cfg!(miri) { 4 } else { 20 }),
        start in 0.0f64..=1.0,
        gt in 5.0f64..if cfg!(miri) { 20.0 } else { 120.0 },
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

/// Every configuration the constructor takes, with the edges (a minimum pulse of 0, equal to h,
/// equal to the run time; no dead band).
fn any_config() -> impl Strategy<Value = ActuatorConfig> {
    (
        0.05f64..2.0,
        1.0f64..100.0,
        0usize..4,
        0.0f64..=1.0,
        0usize..3,
        0.0f64..0.05,
    )
        .prop_map(|(h, gt_in_h, pulse_kind, pulse_frac, band_kind, band)| {
            let run_time = h * gt_in_h;
            let min_pulse = match pulse_kind {
                0 => 0.0,
                1 => h,
                _ => h * pulse_frac,
            };
            let dead_band = if band_kind == 0 { 0.0 } else { band };
            ActuatorConfig {
                run_time,
                min_pulse,
                dead_band,
                h,
            }
        })
}

/// A target: anywhere, out of range, exactly at an end, or within a minimum pulse of one.
fn any_target() -> impl Strategy<Value = f64> {
    prop_oneof![
        -0.5f64..1.5,
        Just(0.0),
        Just(1.0),
        0.0f64..0.01,
        0.99f64..=1.0,
    ]
}

/// +1 open, −1 close, 0 stop; checks the pulse is one the motor can make: `Stop`, or
/// `Open(s)`/`Close(s)` with 0 < s, `min_pulse` ≤ s ≤ `h`.
fn direction(d: Drive, c: &ActuatorConfig) -> Result<i8, TestCaseError> {
    let (dir, s) = match d {
        Drive::Stop => return Ok(0),
        Drive::Open(s) => (1, s),
        Drive::Close(s) => (-1, s),
    };
    prop_assert!(s > 0.0 && s >= c.min_pulse && s <= c.h, "{d:?} with {c:?}");
    Ok(dir)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 4 } else { 512 }))]

    /// Issue 19 item 11, positional form: for any configuration, any history of targets and any
    /// target then held, every pulse is `Stop` or lasts `min_pulse..=h` (and more than 0), the
    /// estimate stays in 0..=1 and where the motor is, the held target gives at most one
    /// reversal (counting the last pulse before it), and the motor ends within
    /// `smallest_move()` of the target, or on it when it is an end (the driver runs into the stop).
    #[test]
    fn positional_pulses_are_makeable_and_a_constant_target_never_hunts(
        config in any_config(),
        start in 0.0f64..=1.0,
        history in proptest::collection::vec(any_target(), 0..30),
        held in any_target(),
    ) {
        let mut v = ThreePoint::new(config, start).unwrap();
        let mut real = start;
        let mut last = 0i8;
        for &target in &history {
            let d = v.update(target).unwrap();
            let dir = direction(d, &config)?;
            if dir != 0 { last = dir; }
            apply(&mut real, d, config.run_time);
        }
        let mut reversals = 0;
        // Long enough to cross the stroke twice over.
        let samples = (2.0 * config.run_time / config.h) as usize + 10;
        for _ in 0..samples {
            let d = v.update(held).unwrap();
            let dir = direction(d, &config)?;
            if dir != 0 {
                if last != 0 && dir != last { reversals += 1; }
                last = dir;
            }
            apply(&mut real, d, config.run_time);
            prop_assert!((0.0..=1.0).contains(&v.position()));
            prop_assert!((v.position() - real).abs() < 1e-9);
        }
        prop_assert!(reversals <= 1, "{reversals} reversals");
        let goal = held.clamp(0.0, 1.0);
        if goal == 0.0 || goal == 1.0 {
            // On the end (up to the motor model's rounding of s/GT).
            prop_assert!((real - goal).abs() < 1e-9, "{} vs {}", real, goal);
        } else {
            prop_assert!((real - goal).abs() < v.smallest_move() + 1e-9, "{} vs {}", real, goal);
        }
    }

    /// Velocity form, any configuration and requests: every pulse is one the motor can make and
    /// the estimate stays in 0..=1 and where the motor is.
    #[test]
    fn velocity_pulses_are_makeable(
        config in any_config(),
        start in 0.0f64..=1.0,
        deltas in proptest::collection::vec(-0.3f64..0.3, 1..200),
    ) {
        let mut v = ThreePoint::new(config, start).unwrap();
        let mut real = start;
        for &d in &deltas {
            let drive = v.update_delta(d).unwrap();
            direction(drive, &config)?;
            apply(&mut real, drive, config.run_time);
            prop_assert!((0.0..=1.0).contains(&v.position()));
            prop_assert!((v.position() - real).abs() < 1e-9);
        }
    }
}

/// Issue 19 item 11, the reported case: 0.502 from 0.5 (60 s valve, 0.2 s minimum pulse, 0.1 %
/// dead band, h = 1 s) for an hour: the 0.2 % error is below a minimum pulse's 0.33 %, so the
/// valve is not moved at all (it made 3 600 pulses and 3 599 reversals).
#[test]
fn a_small_constant_error_does_not_hunt() {
    let config = ActuatorConfig {
        run_time: 60.0,
        min_pulse: 0.2,
        dead_band: 0.001,
        h: 1.0,
    };
    let mut v = ThreePoint::new(config, 0.5).unwrap();
    // Under Miri six minutes (the hunting reversed the valve at every sample).
    let samples = if cfg!(miri) { 360 } else { 3600 };
    let pulses = (0..samples)
        .filter(|_| v.update(0.502).unwrap() != Drive::Stop)
        .count();
    assert_eq!(pulses, 0);
    // 0.504 is beyond a minimum pulse: exactly one pulse, then nothing.
    let pulses = (0..samples)
        .filter(|_| v.update(0.504).unwrap() != Drive::Stop)
        .count();
    assert_eq!(pulses, 1);
}

/// A minimum pulse longer than the stroke cannot work: refused with why.
#[test]
fn a_minimum_pulse_longer_than_the_stroke_is_refused() {
    let config = ActuatorConfig {
        run_time: 1.0,
        min_pulse: 2.0,
        dead_band: 0.0,
        h: 5.0,
    };
    let err = ThreePoint::new(config, 0.0).unwrap_err();
    assert!(err.to_string().contains("run_time"), "{err}");
    assert!(
        ThreePoint::new(
            ActuatorConfig {
                min_pulse: 1.0,
                ..config
            },
            0.0
        )
        .is_ok()
    );
}

/// The motor, in f64 whatever the driver's float type: it moves `s / run_time` per pulse and
/// stops at its ends. Its position is held as where it last stood still at an end (or started)
/// plus the seconds driven since (summed exactly: Knuth's two-sum), divided by the run time
/// once when read, so its own rounding stays far below the driver's; `apply` returns the
/// pulse's travel.
struct Motor {
    base: f64,
    gt: f64,
    seconds: (f64, f64),
}

impl Motor {
    fn new(at: f64, gt: f64) -> Self {
        Motor {
            base: at,
            gt,
            seconds: (0.0, 0.0),
        }
    }

    fn at(&self) -> f64 {
        self.base + (self.seconds.0 + self.seconds.1) / self.gt
    }

    fn apply<F: regler_pid::Real>(&mut self, drive: Drive<F>) -> f64 {
        let s = match drive {
            Drive::Stop => return 0.0,
            Drive::Open(s) => s.to_f64_exact(),
            Drive::Close(s) => -s.to_f64_exact(),
        };
        let (hi, lo) = self.seconds;
        let sum = hi + s;
        let virt = sum - hi;
        let err = (hi - (sum - virt)) + (s - virt);
        self.seconds = (sum, lo + err);
        if self.at() >= 1.0 {
            *self = Motor::new(1.0, self.gt);
        } else if self.at() <= 0.0 {
            *self = Motor::new(0.0, self.gt);
        }
        s.abs() / self.gt
    }
}

fn motor<F: regler_pid::Real>(real: &mut f64, drive: Drive<F>, gt: f64) -> f64 {
    let mut m = Motor::new(*real, gt);
    let travel = m.apply(drive);
    *real = m.at();
    travel
}

/// The tolerance the module docs state for the estimate against the motor: ε·(4 + strokes
/// travelled) + pulses·ε²/4, ε the float type's epsilon.
fn estimate_tolerance<F: regler_pid::Real>(travelled: f64, pulses: u64) -> f64 {
    let e = F::epsilon().to_f64_exact();
    e * (4.0 + travelled) + pulses as f64 * e * e / 4.0
}

/// Issue 19 item 11, attack finding 1: a 1 kHz loop on a 200 s valve in f32 (one sample's
/// travel 5·10⁻⁶, below the 64-ulp snap at the ends): the estimate stayed at 0 while every
/// sample drove open, and the motor ran fully open. Both forms, both ends.
#[test]
#[cfg_attr(
    miri,
    ignore = "eight runs of 300 000 samples: hours under Miri; runs natively in every CI run"
)]
fn f32_estimate_follows_a_slow_valve_from_either_end() {
    let gt = 200.0f32;
    for (start, target) in [(0.0f32, 0.5f32), (1.0, 0.5), (0.5, 0.0), (0.5, 1.0)] {
        for velocity in [false, true] {
            let cfg = ActuatorConfig {
                run_time: gt,
                min_pulse: 0.0,
                dead_band: if velocity { 0.0 } else { 0.005 },
                h: 0.001,
            };
            let mut v = ThreePoint::new(cfg, start).unwrap();
            let mut real = f64::from(start);
            let (mut travelled, mut pulses) = (0.0, 0);
            for k in 0..300_000 {
                let d = if velocity {
                    v.update_delta(if k == 0 { target - start } else { 0.0 })
                } else {
                    v.update(target)
                }
                .unwrap();
                pulses += u64::from(d != Drive::Stop);
                travelled += motor(&mut real, d, f64::from(gt));
            }
            let gap = (f64::from(v.position()) - real).abs();
            assert!(
                gap <= estimate_tolerance::<f32>(travelled, pulses),
                "from {start} to {target} (velocity {velocity}): estimate {} motor {real}",
                v.position()
            );
            // 300 s at 1/200 of the stroke per second: it got there.
            assert!((real - f64::from(target)).abs() <= 0.005 + 1e-6, "{real}");
        }
    }
}

/// Every configuration the constructor takes, with extreme ratios: h / run_time from 10⁻¹² to
/// 1, the minimum pulse 0, h, or between, the dead band 0 or up to 5 %.
fn extreme_config<F: regler_pid::Real>() -> impl Strategy<Value = ActuatorConfig<F>> {
    (
        -3.0f64..0.5,
        0.0f64..12.0,
        0usize..4,
        0.0f64..=1.0,
        0usize..3,
        0.0f64..0.05,
    )
        .prop_map(
            |(log_h, log_gt_in_h, pulse_kind, pulse_frac, band_kind, band)| {
                let f = F::from_f64_nearest;
                let h = 10f64.powf(log_h);
                let run_time = h * 10f64.powf(log_gt_in_h);
                let min_pulse = match pulse_kind {
                    0 => 0.0,
                    1 => h,
                    _ => h * pulse_frac,
                };
                ActuatorConfig {
                    run_time: f(run_time),
                    min_pulse: f(min_pulse),
                    dead_band: f(if band_kind == 0 { 0.0 } else { band }),
                    h: f(h),
                }
            },
        )
}

/// One request: a position (positional form), a change (velocity form), a non-finite value, or
/// the target held.
#[derive(Clone, Copy, Debug)]
enum Request {
    To(f64),
    By(f64),
    NotFinite,
}

fn any_request() -> impl Strategy<Value = Request> {
    prop_oneof![
        any_target().prop_map(Request::To),
        prop_oneof![-0.3f64..0.3, -1e-6f64..1e-6, Just(1.0), Just(-1.0)].prop_map(Request::By),
        Just(Request::NotFinite),
    ]
}

/// Drives `config` through `requests`, each held (or repeated as a zero change) for `hold`
/// samples, against the f64 motor; checks the stated tolerance at every sample.
fn follows_the_motor<F: regler_pid::Real>(
    config: ActuatorConfig<F>,
    start: f64,
    requests: &[Request],
    hold: usize,
) -> Result<(), TestCaseError> {
    let f = F::from_f64_nearest;
    let Ok(mut v) = ThreePoint::new(config, f(start)) else {
        // Only h / run_time below the smallest normal number is refused here.
        prop_assert!(
            (config.h / config.run_time).to_f64_exact() < F::min_positive_value().to_f64_exact()
        );
        return Ok(());
    };
    let gt = config.run_time.to_f64_exact();
    let mut m = Motor::new(v.position().to_f64_exact(), gt);
    let (mut travelled, mut pulses) = (0.0, 0);
    for &r in requests {
        for k in 0..hold {
            let d = match r {
                Request::To(t) => v.update(f(t)),
                Request::By(d) => v.update_delta(if k == 0 { f(d) } else { F::zero() }),
                Request::NotFinite => v.update(F::nan()),
            }
            .unwrap_or(Drive::Stop);
            pulses += u64::from(d != Drive::Stop);
            travelled += m.apply(d);
            let real = m.at();
            let p = v.position().to_f64_exact();
            prop_assert!((0.0..=1.0).contains(&p));
            prop_assert!(
                (p - real).abs() <= estimate_tolerance::<F>(travelled, pulses),
                "{config:?}: estimate {p} motor {real} after {travelled} strokes"
            );
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 4 } else { 256 }))]

    /// Issue 19 item 11, attack finding 1, as a property: for every accepted configuration
    /// (extreme ratios included), any mix of positional and velocity requests, in f32 and
    /// f64, the estimate follows the f64 motor within ε·(4 + strokes travelled) at every
    /// sample.
    #[test]
    fn the_estimate_follows_the_motor_in_f32_and_f64(
        c32 in extreme_config::<f32>(),
        c64 in extreme_config::<f64>(),
        start in prop_oneof![Just(0.0f64), Just(1.0), 0.0f64..=1.0],
        requests in proptest::collection::vec(any_request(), 1..12),
        hold in 1usize..400,
    ) {
        follows_the_motor(c32, start, &requests, hold)?;
        follows_the_motor(c64, start, &requests, hold)?;
    }

    /// Issue 19 item 11, attack finding 7: a saturating PI's output changes fed to
    /// `update_delta` (the composition the module docs recommend). Once the output sits at its
    /// limit 0 or 1, the valve is driven into that stop: shut or fully open, exactly — not left
    /// below one minimum pulse's travel from it.
    #[test]
    #[cfg_attr(miri, ignore = "thousands of samples per case until the stop: minutes under Miri; runs natively in every CI run")]
    fn velocity_form_driven_to_a_limit_reaches_the_stop(
        config in any_config(),
        start in 0.0f64..=1.0,
        open in any::<bool>(),
        k in 0.01f64..2.0,
    ) {
        let mut v = ThreePoint::new(config, start).unwrap();
        let pid_config = Config::<f64> {
            kind: Kind::PI,
            k,
            ti: 20.0 * config.h,
            h: config.h,
            ymin: 0.0,
            ymax: 1.0,
            ..Config::default()
        };
        let mut pid: Pid<f64> = Pid::new(&pid_config).unwrap();
        let _ = pid.set_manual(start);
        let _ = pid.update(0.5, 0.5);
        pid.set_auto();
        let mut last = start;
        let mut real = start;
        let setpoint = if open { 1.0 } else { -1.0 };
        let samples = (3.0 * config.run_time / config.h) as usize + 2_000;
        for _ in 0..samples {
            let u = pid.update(setpoint, 0.0);
            let d = v.update_delta(u - last).unwrap();
            last = u;
            direction(d, &config)?;
            motor(&mut real, d, config.run_time);
        }
        let goal = if open { 1.0 } else { 0.0 };
        prop_assert_eq!(last, goal);
        prop_assert_eq!(v.position(), goal);
        prop_assert!((real - goal).abs() < 1e-9, "motor {} estimate {}", real, v.position());
    }
}

/// Attack finding 7, the reported case: run time 60 s, minimum pulse 0.2 s, dead band 1 %; the
/// controller's output walks down from 0.5 and saturates at 0 — the valve stayed 0.9 % open.
#[test]
fn velocity_form_shuts_when_the_controller_output_reaches_zero() {
    let cfg = ActuatorConfig {
        run_time: 60.0,
        min_pulse: 0.2,
        dead_band: 0.01,
        h: 1.0,
    };
    let mut v = ThreePoint::new(cfg, 0.5).unwrap();
    let mut real = 0.5;
    let mut last = 0.5f64;
    for k in 1..400 {
        let u = (0.5 - 0.0093 * f64::from(k)).max(0.0);
        motor(&mut real, v.update_delta(u - last).unwrap(), 60.0);
        last = u;
    }
    assert_eq!(v.position(), 0.0);
    assert!(real < 1e-12, "{real}");
}

/// The only configurations refused for resolution: one sample's travel below the smallest
/// normal number (it could not be resolved at all).
#[test]
fn a_travel_per_sample_below_the_float_type_is_refused_with_why() {
    let cfg = ActuatorConfig {
        run_time: 1e30f32,
        min_pulse: 0.0,
        dead_band: 0.0,
        h: 1e-10,
    };
    let err = ThreePoint::new(cfg, 0.0).unwrap_err();
    assert!(err.to_string().contains("h / run_time"), "{err}");
    assert!(ThreePoint::new(ActuatorConfig { h: 1e-6, ..cfg }, 0.0).is_ok());
}

/// The estimate holds each pulse's travel to within ε²/4 of the stroke (the rounding of its
/// carry), so at a travel below that it can stop moving: the seventh attack drove an `f32`
/// actuator at 0.99·2⁻⁵⁰ of the stroke a sample (accepted: above the smallest normal number),
/// and after 2²⁴ samples each pulse left the estimate where it was. The documented bound
/// counts it: ε·(4 + strokes travelled) + pulses·ε²/4 — checked after every 2²⁰ samples up to
/// 2²⁴ + 2²² of them, and at 1.5·2⁻⁵⁰ (rounded up every time instead) and 2⁻⁴⁰.
#[test]
#[cfg_attr(
    miri,
    ignore = "50 million samples: days under Miri; runs natively in every CI run"
)]
fn a_travel_below_the_estimates_resolution_stays_within_the_stated_bound() {
    for ratio in [0.99f32, 1.5, 1024.0] {
        let h = ratio * f32::from_bits((127 - 50) << 23); // × 2⁻⁵⁰
        let config = ActuatorConfig {
            run_time: 1.0f32,
            min_pulse: 0.0,
            dead_band: 0.0,
            h,
        };
        let mut v = ThreePoint::new(config, 0.5f32).unwrap();
        let mut real = 0.5f64;
        let (mut travelled, mut pulses) = (0.0, 0u64);
        for k in 1..=(1u32 << 24) + (1 << 22) {
            let d = v.update(0.6).unwrap();
            pulses += u64::from(d != Drive::Stop);
            travelled += motor(&mut real, d, 1.0);
            if k % (1 << 20) == 0 {
                let gap = (f64::from(v.position()) - real).abs();
                assert!(
                    gap <= estimate_tolerance::<f32>(travelled, pulses),
                    "{ratio}·2⁻⁵⁰ a sample, after {k}: estimate {} motor {real}",
                    v.position()
                );
            }
        }
        assert_eq!(pulses, u64::from((1u32 << 24) + (1 << 22)));
    }
}
