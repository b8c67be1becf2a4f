//! The three-point driver's documented edges, in exact (dyadic) arithmetic, where a tolerance
//! would hide a wrong comparison or a wrong sign: an error of exactly the smallest move is
//! driven; the estimate reads the exact travel, correctly rounded, even when each sample's
//! travel is below half an ulp of it; a request in the velocity form is driven to the last
//! sample, none lost and none added. (Powers of two are written out: Miri perturbs `powi`,
//! whose result Rust does not guarantee exact.)
#![allow(
    clippy::unwrap_used,
    clippy::float_cmp,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    clippy::cast_precision_loss,
    reason = "a test may panic: that is how it fails; the numbers are exact by construction"
)]

use regler_pid::actuator::{ActuatorConfig, Drive, ThreePoint};

/// Module docs: "an error smaller than `smallest_move()` (the dead band or one minimum pulse's
/// travel, the larger) is not driven" — so an error of exactly `smallest_move()` is, in both
/// forms, whichever of the two sets it. Every number here is a power of two: no rounding.
#[test]
fn an_error_of_exactly_the_smallest_move_is_driven() {
    // (min_pulse, dead_band): the minimum pulse's travel 2^-7 sets the smallest move, then the
    // dead band 2^-7 does (over a minimum pulse's travel of 2^-8). Half a sample either way.
    for (min_pulse, dead_band) in [(0.5, 0.0), (0.5, (1.0 / 256.0)), (0.25, (1.0 / 128.0))] {
        let config = ActuatorConfig {
            run_time: 64.0,
            min_pulse,
            dead_band,
            h: 1.0,
        };
        let smallest = ThreePoint::new(config, 0.5).unwrap().smallest_move();
        assert_eq!(smallest, (min_pulse / 64.0f64).max(dead_band));
        let seconds = smallest * 64.0;
        for sign in [1.0, -1.0] {
            let drive = |s: f64| {
                if sign > 0.0 {
                    Drive::Open(s)
                } else {
                    Drive::Close(s)
                }
            };
            // Positional: exactly the smallest move is driven, and lands on the target.
            let mut v = ThreePoint::new(config, 0.5).unwrap();
            assert_eq!(v.update(0.5 + sign * smallest).unwrap(), drive(seconds));
            assert_eq!(v.position(), 0.5 + sign * smallest);
            assert_eq!(v.update(0.5 + sign * smallest).unwrap(), Drive::Stop);
            // Just under it is not.
            let mut v = ThreePoint::new(config, 0.5).unwrap();
            let under = 0.5 + sign * (smallest - (1.0 / 1_048_576.0));
            assert_eq!(v.update(under).unwrap(), Drive::Stop);
            // Velocity: a request of exactly the smallest move is driven at once; half of it
            // waits, and the second half completes it.
            let mut v = ThreePoint::new(config, 0.5).unwrap();
            assert_eq!(v.update_delta(sign * smallest).unwrap(), drive(seconds));
            assert_eq!(v.position(), 0.5 + sign * smallest);
            let mut v = ThreePoint::new(config, 0.5).unwrap();
            assert_eq!(v.update_delta(sign * smallest / 2.0).unwrap(), Drive::Stop);
            assert_eq!(
                v.update_delta(sign * smallest / 2.0).unwrap(),
                drive(seconds)
            );
            assert_eq!(v.position(), 0.5 + sign * smallest);
        }
    }
}

/// Module docs: "the estimate is a compensated sum, so one sample's travel is neither rounded
/// away nor rounded the same way every sample". In `f32` at 0.5 (an ulp of 2^-24 above, 2^-25
/// below), a travel of 2^-26 a sample is under half an ulp: a plain sum would never move. The
/// estimate read after n samples is the exact travel rounded to `f32` (ties to even) — opening
/// and closing, in both forms.
#[test]
fn the_estimate_reads_the_exact_travel_rounded_to_the_type() {
    let config = ActuatorConfig {
        run_time: 67_108_864.0,
        min_pulse: 0.0,
        dead_band: 0.0,
        h: 1.0,
    };
    let step = 1.0 / 67_108_864.0;
    for sign in [1.0f64, -1.0] {
        let mut positional = ThreePoint::new(config, 0.5f32).unwrap();
        let mut velocity = ThreePoint::new(config, 0.5f32).unwrap();
        // Positional: a target far away, one whole sample (2^-26 of the stroke) per update.
        let far = if sign > 0.0 { 1.0 } else { 0.0 };
        let whole_sample = if sign > 0.0 {
            Drive::Open(1.0)
        } else {
            Drive::Close(1.0)
        };
        for n in 1..=300u32 {
            let exact = 0.5 + sign * f64::from(n) * step;
            let d = positional.update(far).unwrap();
            assert_eq!(d, whole_sample);
            assert_eq!(
                positional.position(),
                exact as f32,
                "positional, {n} samples of {sign}·2^-26"
            );
            let d = velocity.update_delta((sign * step) as f32).unwrap();
            assert_eq!(d, whole_sample);
            assert_eq!(
                velocity.position(),
                exact as f32,
                "velocity, {n} samples of {sign}·2^-26"
            );
        }
    }
}

/// Module docs, velocity form: "requests smaller than `smallest_move()` wait and add up (kept as
/// a change ...)", and a request is driven until it is covered. A request of n samples' travel
/// is driven in exactly n whole-sample pulses and then nothing more, also when each sample's
/// travel is under half an ulp of the estimate (the part driven is taken off the request from the
/// compensated estimate, carry included).
#[test]
fn a_request_is_driven_to_the_last_sample_and_no_further() {
    for (run_time, start) in [(67_108_864.0, 0.5f32), (1024.0, 0.25), (64.0, 0.5)] {
        let config = ActuatorConfig {
            run_time,
            min_pulse: 0.0,
            dead_band: 0.0,
            h: 1.0,
        };
        let step = 1.0 / f64::from(run_time);
        for n in [1u32, 2, 3, 5, 17] {
            for sign in [1.0f64, -1.0] {
                let mut v = ThreePoint::new(config, start).unwrap();
                let request = sign * f64::from(n) * step;
                let mut pulses = 0;
                let mut first = v.update_delta(request as f32).unwrap();
                for _ in 0..n + 3 {
                    match first {
                        Drive::Open(s) | Drive::Close(s) => {
                            assert_eq!(s, 1.0, "run time {run_time}, {n} samples: whole pulses");
                            assert_eq!(matches!(first, Drive::Open(_)), sign > 0.0);
                            pulses += 1;
                        }
                        Drive::Stop => {}
                    }
                    first = v.update_delta(0.0).unwrap();
                }
                assert_eq!(
                    pulses, n,
                    "run time {run_time}, start {start}: a request of {n} samples' travel ({sign})"
                );
                let exact = f64::from(start) + request;
                assert_eq!(v.position(), exact as f32);
            }
        }
    }
}

/// With no dead band and no minimum pulse, an error that one sample's pulse covers is driven by
/// exactly one pulse, which puts the estimate on the target (positional form) or drives the
/// whole request (velocity form): the next sample is `Stop`, not a pulse of a rounding error's
/// length. Random run times, starts and errors within one sample's travel, in `f64` and `f32`
/// (`wanted · run_time / run_time` is not `wanted` in floating point: the driver must not leave
/// the difference to a second pulse).
#[test]
fn an_error_one_pulse_covers_takes_one_pulse() {
    let mut seed = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    macro_rules! check {
        ($f:ty) => {
            // Under Miri 200 cases a type (20 000 natively).
            for case in 0..if cfg!(miri) { 200 } else { 20_000 } {
                // At least 20 samples a stroke: the targets stay clear of the ends (snapped onto them).
                let run_time = (20.0 + 980.0 * next()) as $f;
                let h = (0.01 + 0.99 * next()) as $f;
                let config = ActuatorConfig {
                    run_time,
                    min_pulse: 0.0,
                    dead_band: 0.0,
                    h,
                };
                let start = (0.1 + 0.8 * next()) as $f;
                let travel = h / run_time;
                let error = travel * (next() as $f) * if next() < 0.5 { -1.0 } else { 1.0 };
                let target = start + error;
                let mut v = ThreePoint::new(config, start).unwrap();
                let first = v.update(target).unwrap();
                let second = v.update(target).unwrap();
                assert!(
                    target == start || first != Drive::Stop,
                    "case {case}: nothing driven"
                );
                assert_eq!(
                    second,
                    Drive::Stop,
                    "case {case} ({}): positional, gt {run_time}, h {h}, {start} -> {target}: a \
                     second pulse after {first:?}",
                    stringify!($f)
                );
                assert_eq!(v.position(), target, "case {case}: positional, on the target");
                let mut v = ThreePoint::new(config, start).unwrap();
                let first = v.update_delta(error).unwrap();
                let second = v.update_delta(0.0).unwrap();
                assert_eq!(
                    second,
                    Drive::Stop,
                    "case {case} ({}): velocity, gt {run_time}, h {h}, {start} + {error}: a \
                     second pulse after {first:?}",
                    stringify!($f)
                );
            }
        };
    }
    check!(f64);
    check!(f32);
}

/// `update`'s docs: the target is "clamped into 0..=1; within 64 ulps of an end it counts as
/// that end" — and a target at an end is driven into the stop. So a target beyond an end, or
/// closer to it than 64 ulps, ends with the estimate on the end and the driver stopped (no
/// endless pulses into a stop); a target exactly 64 ulps from an end is an ordinary target and
/// the estimate ends on it. In `f64` and `f32`, no dead band or minimum pulse (so that nothing
/// but the end rule decides where the estimate stops).
#[test]
fn targets_at_beyond_and_near_the_ends() {
    macro_rules! check {
        ($f:ty) => {
            let near = <$f>::EPSILON * 64.0;
            let config = ActuatorConfig::<$f> {
                run_time: 10.0,
                min_pulse: 0.0,
                dead_band: 0.0,
                h: 1.0,
            };
            let cases: [($f, $f); 10] = [
                (1.5, 1.0),
                (<$f>::MAX, 1.0),
                (1.0 - near / 2.0, 1.0),
                (1.0 - near + <$f>::EPSILON / 2.0, 1.0),
                (1.0 - near, 1.0 - near),
                (-0.5, 0.0),
                (<$f>::MIN, 0.0),
                (near / 2.0, 0.0),
                (near - near * <$f>::EPSILON, 0.0),
                (near, near),
            ];
            for (target, end) in cases {
                let mut v = ThreePoint::new(config, 0.5).unwrap();
                let mut pulses = 0;
                while v.update(target).unwrap() != Drive::Stop {
                    pulses += 1;
                    assert!(pulses <= 8, "{target}: still driving after {pulses} pulses");
                }
                assert_eq!(v.position(), end, "{} target {target}", stringify!($f));
                for _ in 0..3 {
                    assert_eq!(v.update(target).unwrap(), Drive::Stop, "{target}: stopped");
                }
            }
        };
    }
    check!(f64);
    check!(f32);
}

/// Requests below half an ulp of what is already pending add up, exactly as asked (the seventh
/// attack: the pending change was a plain sum, so 4·10⁻¹⁰ on 0.0099 in `f32`, and 8·10⁻¹⁹ on
/// 0.0099 in `f64`, rounded away every time and the dead band was never reached).
#[test]
#[cfg_attr(
    miri,
    ignore = "300 000 and 2 million requests: an hour under Miri; runs natively in every CI run"
)]
fn requests_below_the_pendings_resolution_add_up() {
    let config = ActuatorConfig {
        run_time: 60.0f32,
        min_pulse: 0.0,
        dead_band: 0.01,
        h: 1.0,
    };
    let mut v = ThreePoint::new(config, 0.5f32).unwrap();
    assert_eq!(v.update_delta(0.0099).unwrap(), Drive::Stop);
    // 1.2·10⁻⁴ more in all: past the dead band after 250 000 of them.
    let first = (0..300_000).position(|_| v.update_delta(4e-10).unwrap() != Drive::Stop);
    let first = first.expect("0.01002 of the stroke asked for, and nothing driven");
    assert!(
        (249_000..=251_000).contains(&first),
        "driven at request {first}"
    );

    let config = ActuatorConfig {
        run_time: 60.0f64,
        min_pulse: 0.0,
        dead_band: 0.01,
        h: 1.0,
    };
    let mut v = ThreePoint::new(config, 0.5f64).unwrap();
    assert_eq!(v.update_delta(0.0099).unwrap(), Drive::Stop);
    for _ in 0..2_000_000 {
        assert_eq!(v.update_delta(8e-19).unwrap(), Drive::Stop);
    }
    // 0.0099 + 1.6·10⁻¹² + 0.0001 − 10⁻¹²: 6·10⁻¹³ past the dead band.
    assert_ne!(
        v.update_delta(0.0001 - 1e-12).unwrap(),
        Drive::Stop,
        "0.01 + 6e-13 of the stroke asked for, and nothing driven"
    );
}

/// A valve asked to shut, shuts — also from an estimate a subnormal distance from the end,
/// whose error is too small to be a time (the seventh attack: `Stop` for ever at 10⁻⁴⁵ with no
/// minimum pulse). Positional and velocity forms, both ends, `f32` and `f64`.
#[test]
fn a_valve_a_subnormal_distance_from_an_end_is_driven_into_it() {
    fn check<F: regler_pid::Real>() {
        let f = F::from_f64_nearest;
        let config = ActuatorConfig {
            run_time: f(0.1),
            min_pulse: F::zero(),
            dead_band: F::zero(),
            h: f(0.01),
        };
        let tiny = F::min_positive_value() * F::epsilon(); // subnormal
        for (start, end) in [
            (tiny, F::zero()),
            (F::one() - F::epsilon() / f(2.0), F::one()),
        ] {
            let mut v = ThreePoint::new(config, start).unwrap();
            let drive = v.update(end).unwrap();
            assert_ne!(drive, Drive::Stop, "positional, from {start:?}");
            assert_eq!(v.position(), end);
            let mut v = ThreePoint::new(config, start).unwrap();
            let drive = v.update_delta(end - start).unwrap();
            assert_ne!(drive, Drive::Stop, "velocity form, from {start:?}");
            assert_eq!(v.position(), end);
        }
    }
    check::<f32>();
    check::<f64>();
}

/// A request that waits (below the smallest move) is not lost when the next request makes a
/// pulse that covers the whole pending change (the eighth attack: the pending sum was reset to
/// 0 after such a pulse, which dropped its carry — a request below half an ulp of the pending
/// change — every cycle of `[tiny, +0.5, −0.5]`; 1 000 cycles asked 2.9 × the smallest move in
/// `f32` and moved nothing).
#[test]
#[cfg_attr(
    miri,
    ignore = "300 000 requests: minutes under Miri; runs natively in every CI run"
)]
fn a_waiting_request_survives_a_pulse_that_covers_the_pending_change() {
    fn check<F: regler_pid::Real>(tiny: F, band: F, cycles: usize) {
        let f = F::from_f64_nearest;
        let config = ActuatorConfig {
            run_time: F::one(),
            min_pulse: F::zero(),
            dead_band: band,
            h: F::one(),
        };
        let mut v = ThreePoint::new(config, f(0.25)).unwrap();
        for _ in 0..cycles {
            for d in [tiny, f(0.5), f(-0.5)] {
                v.update_delta(d).unwrap();
            }
        }
        // The ±0.5 cancel exactly: tiny·cycles asked, several smallest moves.
        let asked = tiny.to_f64_exact() * cycles as f64;
        let moved = v.position().to_f64_exact() - 0.25;
        assert!(
            (asked - moved).abs() < band.to_f64_exact(),
            "asked {asked:e}, moved {moved:e}"
        );
    }
    check(2.9e-8f32, 1e-5, 1_000);
    check(5.5e-17f64, 1e-12, 100_000);
}

/// A run time so short that the pulse for a small error would be a subnormal number of seconds
/// is refused (the eighth attack: `run_time = h = 10⁻³⁷` s in `f32` was accepted, its pulses
/// snapped to the subnormal grid, and the estimate left the motor by 29 × its stated bound; at
/// the smallest subnormal, a held target was never driven). The smallest run time accepted,
/// 2 × the smallest normal number / ε, keeps a pulse's rounding within the stated ε²/4 of the
/// stroke: 2 000 targets a few ulps apart, each a subnormal pulse, stay within the bound there.
#[test]
fn a_run_time_too_short_for_a_pulse_to_be_a_normal_time_is_refused() {
    fn check<F: regler_pid::Real>() {
        let f = F::from_f64_nearest;
        let floor = F::min_positive_value() * f(2.0) / F::epsilon();
        for run_time in [F::min_positive_value() * F::epsilon(), floor * f(0.75)] {
            let config = ActuatorConfig {
                run_time,
                min_pulse: F::zero(),
                dead_band: F::zero(),
                h: run_time,
            };
            assert_eq!(
                ThreePoint::new(config, F::zero()).err(),
                Some(regler_pid::actuator::ActuatorError::Config(
                    "run_time is below 2 × the smallest normal number / ε of the float type: the pulse for a small error would be a subnormal number of seconds, too coarse for the estimate"
                ))
            );
        }
        let config = ActuatorConfig {
            run_time: floor,
            min_pulse: F::zero(),
            dead_band: F::zero(),
            h: floor,
        };
        let gt = floor.to_f64_exact();
        let start = f(0.01);
        let mut v = ThreePoint::new(config, start).unwrap();
        let (mut motor, mut strokes, mut pulses) = (start.to_f64_exact(), 0.0f64, 0u32);
        // Targets about three ulps apart near 0.01 (3.6·10⁻⁹ of the stroke in `f32`): each
        // pulse is 0.06 × the smallest normal number of seconds, subnormal, rounded on its grid.
        let step = F::epsilon() * f(0.03);
        let mut target = start;
        for _ in 0..2_000 {
            target = target + step;
            let s = match v.update(target).unwrap() {
                Drive::Open(s) => s.to_f64_exact(),
                Drive::Close(s) => -s.to_f64_exact(),
                Drive::Stop => 0.0,
            };
            motor += s / gt;
            strokes += s.abs() / gt;
            pulses += u32::from(s != 0.0);
        }
        let e = F::epsilon().to_f64_exact();
        let bound = e * (4.0 + strokes) + f64::from(pulses) * e * e / 4.0;
        let gap = (v.position().to_f64_exact() - motor).abs();
        assert!(gap <= bound, "gap {gap:e}, bound {bound:e}");
        assert!(pulses > 1_000, "{pulses} pulses");
    }
    check::<f32>();
    check::<f64>();
}

/// An end switch is a level: firmware reads it every sample while it is made. Re-anchoring on it
/// keeps the requests that move away from that end (the ninth attack: `at_end` cleared every
/// waiting request, so close requests below the smallest move never added up and the valve
/// stayed open for good — 0 pulses after asking for −100 strokes). Both ends, `f32` and `f64`.
#[test]
fn an_end_switch_read_every_sample_keeps_the_requests_away_from_it() {
    fn check<F: regler_pid::Real>() {
        let f = F::from_f64_nearest;
        let config = ActuatorConfig {
            run_time: f(60.0),
            min_pulse: f(0.2),
            dead_band: f(0.005),
            h: F::one(),
        };
        for (open, away) in [(true, f(-0.001)), (false, f(0.001))] {
            let start = if open { F::one() } else { F::zero() };
            let mut v = ThreePoint::new(config, start).unwrap();
            let mut first = None;
            for k in 0..100 {
                v.at_end(open); // the switch still made: the valve has not moved yet
                if v.update_delta(away).unwrap() != Drive::Stop {
                    first = Some(k);
                    break;
                }
            }
            // 0.005 (the dead band) asked for after 5 requests: driven at the fifth.
            assert_eq!(first, Some(4), "open {open}");
        }
        // A request beyond the end the switch reports is dropped (no windup), and so does not
        // absorb the next requests away from it: from mid-stroke, 0.003 waits toward the end
        // the switch then reports; −0.003 twice is the dead band's 0.005 and more, driven at
        // the second.
        for (open, toward) in [(true, f(0.003)), (false, f(-0.003))] {
            let mut v = ThreePoint::new(config, f(0.5)).unwrap();
            assert_eq!(v.update_delta(toward).unwrap(), Drive::Stop);
            v.at_end(open);
            assert_eq!(v.update_delta(-toward).unwrap(), Drive::Stop);
            let second = v.update_delta(-toward).unwrap();
            let expected = if open {
                Drive::Close(f(0.36))
            } else {
                Drive::Open(f(0.36))
            };
            assert_eq!(second, expected, "open {open}");
        }
    }
    check::<f32>();
    check::<f64>();
}

/// Requests that reach an end's margin (64 ulps) are driven into the stop; the travel that
/// took beyond what was asked stays as a request away from the end, so requests going back
/// and forth across the margin are neither lost nor turned into pulses to and fro (the ninth
/// attack: `[−0.001, +0.000995]` from fully open lost 5·10⁻⁶ a cycle, the whole −0.05 asked
/// over 10 000 cycles, with a pulse each way every cycle).
#[test]
#[cfg_attr(
    miri,
    ignore = "40 000 requests: minutes under Miri; runs natively in every CI run"
)]
fn requests_across_an_ends_margin_are_neither_lost_nor_hunted() {
    fn check<F: regler_pid::Real>(config: ActuatorConfig<F>, back: F, forth: F, cycles: u32) {
        let mut v = ThreePoint::new(config, F::one()).unwrap();
        let (mut asked, mut pulses) = (0.0f64, 0u32);
        for _ in 0..cycles {
            for d in [back, forth] {
                asked += d.to_f64_exact();
                pulses += u32::from(v.update_delta(d).unwrap() != Drive::Stop);
            }
        }
        let moved = v.position().to_f64_exact() - 1.0;
        assert!(
            (moved - asked).abs() <= 2.0 * v.smallest_move().to_f64_exact(),
            "asked {asked:e}, moved {moved:e}"
        );
        assert!(pulses <= cycles + 2, "{pulses} pulses in {cycles} cycles");
    }
    let f32_config = ActuatorConfig {
        run_time: 60.0f32,
        min_pulse: 0.01,
        dead_band: 0.001,
        h: 1.0,
    };
    check(f32_config, -0.001f32, 0.000_995, 10_000);
    let tiny = ActuatorConfig {
        run_time: 100.0f32,
        min_pulse: 1e-5,
        dead_band: 0.0,
        h: 1.0,
    };
    check(tiny, -2e-7f32, 1e-9, 10_000);
    let f64_config = ActuatorConfig {
        run_time: 60.0f64,
        min_pulse: 0.01,
        dead_band: 0.001,
        h: 1.0,
    };
    check(f64_config, -0.001f64, 0.001 - 1e-14, 10_000);
}

/// Requests to and fro near an end are not amplified: with no dead band and no minimum pulse,
/// a request waiting just inside the end's margin and then ±d every sample drove 64·ε to and
/// fro every sample whatever d was (the tenth attack: 4·10⁻⁷ requests, pulses of 7.7·10⁻⁶,
/// 999 reversals in 1 000 samples). The margin now has hysteresis (64·ε to leave a stop, 32·ε
/// to be taken into one): the travel driven is at most twice what is asked, plus one margin,
/// and the estimate ends within one margin of what was asked. Both ends, `f32` and `f64`,
/// dither from far below the margin to a few times it, after a request waiting 0 to 63·ε.
#[test]
fn requests_to_and_fro_near_an_end_are_not_amplified() {
    fn check<F: regler_pid::Real>(min_pulse: F) {
        let f = F::from_f64_nearest;
        let e = F::epsilon().to_f64_exact();
        let config = ActuatorConfig {
            run_time: f(60.0),
            min_pulse,
            dead_band: F::zero(),
            h: F::one(),
        };
        for open in [true, false] {
            let sign = if open { -1.0 } else { 1.0 };
            for d in [0.05, 0.4, 3.0, 20.0, 70.0, 130.0] {
                for wait in [0.0, 20.0, 31.0, 50.0, 63.0] {
                    let start = if open { F::one() } else { F::zero() };
                    let mut v = ThreePoint::new(config, start).unwrap();
                    let (mut asked, mut travel) = (0.0f64, 0.0f64);
                    let mut requests = vec![f(sign * wait * e)];
                    for k in 0..1_000 {
                        let away = if k % 2 == 0 { 1.0 } else { -1.0 };
                        requests.push(f(sign * away * d * e));
                    }
                    for &r in &requests {
                        asked += r.to_f64_exact();
                        travel += match v.update_delta(r).unwrap() {
                            Drive::Open(s) | Drive::Close(s) => s.to_f64_exact() / 60.0,
                            Drive::Stop => 0.0,
                        };
                    }
                    let requested: f64 = requests.iter().map(|r| r.to_f64_exact().abs()).sum();
                    let what = format!(
                        "open {open}, ±{d}ε after {wait}ε: travel {travel:e}, asked {requested:e}"
                    );
                    assert!(travel <= 2.0 * requested + 64.0 * e * 1.01, "{what}");
                    let moved = v.position().to_f64_exact() - start.to_f64_exact();
                    let slack = v.smallest_move().to_f64_exact() + 64.0 * e * 1.01;
                    assert!(
                        (moved - asked).abs() <= slack,
                        "{what}: moved {moved:e}, asked {asked:e} net"
                    );
                }
            }
        }
    }
    check::<f32>(0.0);
    check::<f32>(60.0 * 3e-6);
    check::<f64>(0.0);
}

/// A valve still on its way into a stop in partial pulses is not sent back and forth by tiny
/// requests across the margin (the eleventh attack: a 300 s valve sampled every 1 ms in `f32`,
/// 32.5·ε from the closed end, and requests of ±ε: every sample a whole sample's travel toward
/// the end, then back, 27 × the travel asked). The decision to take the valve into a stop holds
/// from sample to sample until the request leaves the wider margin.
#[test]
fn a_valve_on_its_way_into_a_stop_is_not_sent_back_and_forth() {
    fn check<F: regler_pid::Real>(run_time: F, h: F) {
        let e = F::epsilon();
        let f = F::from_f64_nearest;
        let config = ActuatorConfig {
            run_time,
            min_pulse: F::zero(),
            dead_band: F::zero(),
            h,
        };
        let mut v = ThreePoint::new(config, F::zero()).unwrap();
        let (mut asked, mut driven, mut visits, mut was) = (0.0f64, 0.0f64, 0u32, true);
        let gt = run_time.to_f64_exact();
        let mut step = |v: &mut ThreePoint<F>, d: F| {
            let s = match v.update_delta(d).unwrap() {
                Drive::Stop => 0.0,
                Drive::Open(s) | Drive::Close(s) => s.to_f64_exact(),
            };
            asked += d.to_f64_exact().abs();
            driven += s / gt;
            let now = v.position() == F::zero() || v.position() == F::one();
            visits += u32::from(now && !was);
            was = now;
        };
        step(&mut v, e * f(65.0)); // out of the stop (more than 64·ε)
        step(&mut v, -e * f(32.5)); // back to 32.5·ε, just outside the 32·ε margin
        for _ in 0..10 {
            step(&mut v, F::zero());
        }
        for _ in 0..1_000 {
            step(&mut v, -e);
            step(&mut v, e);
        }
        let e = e.to_f64_exact();
        let bound = 2.0 * asked + 64.0 * e * f64::from(visits + 1);
        assert!(
            driven <= bound,
            "travel {} ε > bound {} ε",
            driven / e,
            bound / e
        );
    }
    check(300.0f32, 0.001);
    check(1.0 / (20.0 * f64::EPSILON), 1.0f64);
}
