#![allow(clippy::all, clippy::pedantic, clippy::restriction, missing_docs)]
//! From a second independent review (issue 24): the reach check of a fixed-point `Station`.
//! Each closed-loop case is refused by the check, or accepted and then tracks the f64 station;
//! 3 000 random accepted configurations (every kind, b and c anywhere) never overflow.
#![cfg(feature = "fixed")]
use fixed::types::{I16F16, I32F32};
use regler_pid::{Action, Config, Kind, OperatorLimits, Parameters, Scaling, Station};

fn limits() -> OperatorLimits<f64> {
    OperatorLimits {
        kp: (-1e4, 1e4),
        time: (0.0, 1e7),
        sample: (0.001, 255.0),
        output: (-1e4, 1e4),
    }
}

fn pi(k: f64, b: f64) -> Config<f64> {
    Config {
        kind: Kind::PI,
        action: Action::Direct,
        k,
        ti: 10.0,
        td: 0.0,
        b,
        c: 0.0,
        h: 1.0,
        ymin: 0.0,
        ymax: 10.0,
        ..Config::default()
    }
}

fn station<T: regler_pid::Scalar>(
    config: Config<f64>,
    lo: f64,
    hi: f64,
    sp: f64,
    setback: f64,
) -> Result<Station<T, f64>, regler_pid::EditError<f64>> {
    let params = Parameters {
        config,
        setpoint: sp,
        rfel: 1e9,
        night_setback: setback,
    };
    Station::<T, f64>::new(params, Scaling::new(lo, hi).unwrap(), limits())
}

/// README worked examples, exactly.
#[test]
#[cfg_attr(
    miri,
    ignore = "the README's worked examples again (nine fixed-point stations: 21 s interpreted), as tests/reach.rs::the_worked_examples_hold runs them under Miri; runs natively in every CI run"
)]
fn readme_examples() {
    assert!(station::<I16F16>(pi(278.0, 1.0), 0.0, 100.0, 50.0, 0.0).is_ok());
    assert!(station::<I16F16>(pi(279.0, 1.0), 0.0, 100.0, 50.0, 0.0).is_err());
    assert!(station::<I16F16>(pi(0.927, 1.0), 0.0, 30000.0, 50.0, 0.0).is_ok());
    assert!(station::<I16F16>(pi(0.928, 1.0), 0.0, 30000.0, 50.0, 0.0).is_err());
    assert!(station::<I16F16>(pi(2.0, 0.0), 0.0, 30000.0, 50.0, 0.0).is_err());
    assert!(station::<I16F16>(pi(1.0, 1.0), 0.0, 30000.0, 50.0, 0.0).is_err());
    for c in [pi(278.0, 1.0), pi(0.927, 1.0), pi(2.0, 0.0)] {
        assert!(station::<I32F32>(c, 0.0, 30000.0, 50.0, 0.0).is_ok());
    }
}

/// The closed form of the README against the check, on a grid of PI configs.
#[test]
#[cfg_attr(
    miri,
    ignore = "432 fixed-point stations built at the edge of the closed form: an hour under Miri (144 took minutes); runs natively in every CI run"
)]
fn closed_form_matches() {
    let l = 32767.99998474121 * (1.0 - 1.0 / 256.0);
    let mut bad = Vec::new();
    for &m in &[100.0, 1000.0, 10000.0, 30000.0] {
        for &y in &[1.0, 10.0, 100.0] {
            for &b in &[0.0, 0.3, 1.0] {
                for &tt in &[None, Some(2.0), Some(0.6)] {
                    for &ti in &[1.0, 10.0] {
                        let a = tt.map_or(1.0, |t: f64| 1.0 / t);
                        let coef = 2.0 * (1.0 - b) + a * (2.0 - b) + 1.0 / ti;
                        // K at which R = L, and for v.
                        let kr = (l - (101.5 + 102.0 * a) * y) / (m * coef);
                        let kv = (l - 102.0 * y) / (m * (2.0 - b));
                        let kmax = kr.min(kv);
                        if kmax <= 0.0 {
                            continue;
                        }
                        for (k, want) in [(kmax * 0.999, true), (kmax * 1.001, false)] {
                            let c = Config {
                                ti,
                                tt,
                                ymax: y,
                                ..pi(k, b)
                            };
                            let res = station::<I16F16>(c, 0.0, m, 0.0, 0.0);
                            if matches!(&res, Err(e) if !format!("{e:?}").contains("OutOfReach")) {
                                continue;
                            }
                            let got = res.is_ok();
                            if got != want {
                                bad.push((m, y, b, tt, ti, k, want, got));
                            }
                        }
                    }
                }
            }
        }
    }
    for b in &bad {
        println!("{b:?}");
    }
    assert!(bad.is_empty());
}

/// c = 1, scale -16000..16000: |y - c r| <= 32000 is checked, but the difference
/// (y - c r) - (y_old - c r_old) is not: it reaches 64000. A set-point step together with a
/// measurement jump saturates it; nothing is stored on the fault, so it saturates again at
/// every sample while r and y stay: the output is pinned for good.
#[test]
fn derivative_difference_pins_output() {
    let config = Config {
        kind: Kind::PID,
        action: Action::Direct,
        k: 0.02,
        ti: 1.0,
        td: 2.0,
        n: 2.0,
        b: 1.0,
        c: 1.0,
        h: 1.0,
        ymin: 0.0,
        ymax: 10.0,
        ..Config::default()
    };
    // Refused (the reach check), or accepted and it must track f64.
    let Ok(mut fx) = station::<I16F16>(config, -16000.0, 16000.0, 16000.0, 32000.0) else {
        return;
    };
    let mut fl = station::<f64>(config, -16000.0, 16000.0, 16000.0, 32000.0).unwrap();
    // night: set-point -16000, measurement at the top.
    fx.set_night(true);
    fl.set_night(true);
    for _ in 0..3 {
        fx.sample(16000.0);
        fl.sample(16000.0);
    }
    // day: set-point 16000, measurement at the bottom (the plant needs the output up).
    fx.set_night(false);
    fl.set_night(false);
    let mut outs = Vec::new();
    for _ in 0..50 {
        outs.push((fx.sample(-16000.0), fl.sample(-16000.0)));
    }
    println!("{outs:?} faults {:?}", fx.pid().faults());
    assert!(
        !fx.pid().faults().overflow(),
        "overflow on an accepted config: {outs:?}"
    );
}

/// Random accepted I16F16 stations, random on-scale inputs, set-point steps, night, feed-forward
/// and tracking within the output range, manual, commits: any overflow fault is a break.
#[test]
#[cfg_attr(
    miri,
    ignore = "3 000 fixed-point stations run 200 samples each: days under Miri (15 took two minutes); runs natively in every CI run"
)]
fn fuzz_accepted_never_overflow() {
    fuzz(false)
}

/// The same with b in [0, 1] and c = 0 (the two unchecked sums out of the way).
#[test]
#[cfg_attr(
    miri,
    ignore = "3 000 fixed-point stations run 200 samples each: days under Miri (15 took two minutes); runs natively in every CI run"
)]
fn fuzz_narrow_b_c0() {
    fuzz(true)
}

fn fuzz(narrow: bool) {
    let mut seed = 0x1234_5678_9abc_def0u64;
    let mut rnd = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let kinds = [
        Kind::P,
        Kind::I,
        Kind::PI,
        Kind::PD,
        Kind::PID,
        Kind::D,
        Kind::ID,
    ];
    let mut found = Vec::new();
    let mut accepted = 0;
    for case in 0..3000 {
        let pick = |r: f64, xs: &[f64]| xs[((r * xs.len() as f64) as usize).min(xs.len() - 1)];
        let m = pick(rnd(), &[10.0, 100.0, 1000.0, 10000.0, 30000.0]);
        let lo = if rnd() < 0.3 { -m / 2.0 } else { 0.0 };
        let hi = if lo < 0.0 { m / 2.0 } else { m };
        let ymax = pick(rnd(), &[1.0, 10.0, 100.0]);
        let ymin = if rnd() < 0.3 { -ymax } else { 0.0 };
        let config = Config {
            kind: kinds[(rnd() * 7.0) as usize % 7],
            action: if rnd() < 0.5 {
                Action::Direct
            } else {
                Action::Reverse
            },
            k: (if rnd() < 0.2 { -1.0 } else { 1.0 }) * 10f64.powf(rnd() * 6.0 - 4.0),
            ti: 10f64.powf(rnd() * 3.0),
            td: if rnd() < 0.5 {
                0.0
            } else {
                10f64.powf(rnd() * 3.0 - 1.0)
            },
            n: pick(rnd(), &[1.0, 5.0, 10.0, 20.0]),
            b: if narrow {
                pick(rnd(), &[0.0, 0.5, 1.0])
            } else {
                pick(rnd(), &[0.0, 0.5, 1.0, 1.5, -0.5])
            },
            c: if narrow {
                0.0
            } else {
                pick(rnd(), &[0.0, 0.5, 1.0, 2.0, -1.0])
            },
            tt: if rnd() < 0.5 {
                None
            } else {
                Some(10f64.powf(rnd() * 2.0))
            },
            h: 1.0,
            ymin,
            ymax,
            dymax: if rnd() < 0.5 {
                None
            } else {
                Some(ymax * rnd())
            },
        };
        let sp = lo + (hi - lo) * rnd();
        let mut config = config;
        if narrow && config.kind.has_p() {
            // push K to the edge of acceptance
            let mut k = config.k;
            while station::<I16F16>(
                Config {
                    k: k * 1.2,
                    ..config
                },
                lo,
                hi,
                sp,
                0.0,
            )
            .is_ok()
                && k.abs() < 1e4
            {
                k *= 1.2;
            }
            config.k = k;
        }
        let Ok(mut st) = station::<I16F16>(config, lo, hi, sp, (hi - lo) * rnd()) else {
            continue;
        };
        accepted += 1;
        let mut events: Vec<(u8, f64)> = Vec::new();
        for step in 0..200 {
            let x = rnd();
            events.push(((x * 100.0) as u8, 0.0));
            if x < 0.05 {
                st.set_night(!st.night());
            } else if x < 0.08 {
                st.staged_mut().edit_number(21, lo + (hi - lo) * rnd()).ok();
                st.staged_mut().commit();
            } else if x < 0.10 {
                st.set_feedforward((ymax - ymin) * (2.0 * rnd() - 1.0));
            } else if x < 0.12 {
                st.set_track(if rnd() < 0.5 {
                    None
                } else {
                    Some(ymin + (ymax - ymin) * rnd())
                });
            } else if x < 0.13 {
                st.pid_mut()
                    .set_manual(I16F16::from_num(ymin + (ymax - ymin) * rnd()))
                    .ok();
            } else if x < 0.15 {
                st.pid_mut().set_auto();
            } else if x < 0.17 {
                let k = st.value(regler_pid::Code::Kp).unwrap();
                st.staged_mut().edit_number(51, k * (0.3 + rnd())).ok();
                st.staged_mut().commit();
            }
            let xin = if rnd() < 0.3 {
                pick(rnd(), &[lo, hi])
            } else {
                lo + (hi - lo) * rnd()
            };
            events.last_mut().unwrap().1 = xin;
            st.sample(xin);
            if st.pid().faults().overflow() {
                if found.len() < 3 {
                    println!(
                        "case {case} step {step} lo {lo} hi {hi} sp {sp} {config:?}\n events {:?}",
                        &events[events.len().saturating_sub(6)..]
                    );
                }
                found.push((case, step, config));
                break;
            }
        }
    }
    println!("accepted {accepted}, overflows {}", found.len());
    assert!(found.is_empty(), "{:#?}", &found[..found.len().min(5)]);
}

/// Closed loop, PID with c = 1 (derivative on the error) on 0..32 600, accepted: the night
/// set-back (the whole span) switches on during the start-up transient. y − c·r jumps from
/// about −29 000 to +3 600 (a difference of 32 600 + Δy): the difference saturates, the fault holds the output at 10 V, nothing is stored (so
/// the stale y_old stays), the plant keeps rising and the difference only grows: the output is
/// pinned at the top for good while the set-point is 0. The f64 station goes to 0 V.
#[test]
fn night_during_startup_pins_output_at_max() {
    let config = Config {
        kind: Kind::PID,
        action: Action::Direct,
        k: 0.02,
        ti: 1.0,
        td: 5.0,
        n: 10.0,
        b: 1.0,
        c: 1.0,
        h: 1.0,
        ymin: 0.0,
        ymax: 10.0,
        ..Config::default()
    };
    // Refused (the reach check), or accepted and it must track f64.
    let Ok(mut fx) = station::<I16F16>(config, 0.0, 32600.0, 32600.0, 32600.0) else {
        return;
    };
    let mut fl = station::<f64>(config, 0.0, 32600.0, 32600.0, 32600.0).unwrap();
    let (mut yx, mut yl) = (0.0f64, 0.0f64);
    let mut log = Vec::new();
    for t in 0..300 {
        if yx > 3000.0 {
            fx.set_night(true);
            fl.set_night(true);
        }
        let ux = fx.sample(yx);
        let ul = fl.sample(yl);
        yx += 0.02 * (3260.0 * ux - yx);
        yl += 0.02 * (3260.0 * ul - yl);
        if t % 30 == 0 || t < 8 {
            log.push((t, ux, ul, yx as i64, yl as i64));
        }
    }
    println!(
        "(t, u fixed, u f64, y fixed, y f64): {log:?}\nfaults {:?}",
        fx.pid().faults()
    );
    assert!(
        (fx.value(regler_pid::Code::Y).unwrap() - fl.value(regler_pid::Code::Y).unwrap()).abs()
            < 0.5,
        "fixed-point output pinned: {log:?}"
    );
}

/// A PI with a small gain and b = 1.5 (or any kind without P, where b does not matter):
/// K·|b·r − y| is checked, b·r − y is not, and saturates.
#[test]
fn setpoint_weight_product_unchecked() {
    for kind in [Kind::PI, Kind::I] {
        let config = Config {
            kind,
            ti: 1.0,
            ..pi(0.02, 1.5)
        };
        // Refused (the reach check), or accepted and it must track f64.
        let Ok(mut st) = station::<I16F16>(config, 0.0, 30000.0, 30000.0, 0.0) else {
            return;
        };
        for _ in 0..10 {
            st.sample(1000.0);
        }
        assert!(
            !st.pid().faults().overflow(),
            "{kind:?}: overflow, output held at {:?}",
            st.value(regler_pid::Code::Y)
        );
    }
}

/// A measurement off the scale (a reading past SCALEMAX handed to `sample`) is clipped to
/// `I16F16::MAX` by the conversion without any fault (checks what happens; not a stated break).
#[test]
fn off_scale_measurement_clipped_silently() {
    let mut fx = station::<I16F16>(pi(0.5, 1.0), 0.0, 30000.0, 15000.0, 0.0).unwrap();
    let mut fl = station::<f64>(pi(0.5, 1.0), 0.0, 30000.0, 15000.0, 0.0).unwrap();
    for _ in 0..5 {
        fx.sample(40000.0);
        fl.sample(40000.0);
    }
    println!(
        "fixed {:?} f64 {:?} faults {:?}",
        fx.value(regler_pid::Code::Y),
        fl.value(regler_pid::Code::Y),
        fx.pid().faults()
    );
}

/// The review's two pinning configurations are refused, naming the parameter whose sum would
/// saturate: c (the change of y − c·r between samples) and b (b·r − y).
#[test]
fn the_pinning_configurations_are_refused_naming_c_and_b() {
    use regler_pid::{ConfigError, EditError, Parameter};
    let night = Config {
        kind: Kind::PID,
        action: Action::Direct,
        k: 0.02,
        ti: 1.0,
        td: 5.0,
        n: 10.0,
        b: 1.0,
        c: 1.0,
        h: 1.0,
        ymin: 0.0,
        ymax: 10.0,
        ..Config::default()
    };
    assert!(matches!(
        station::<I16F16>(night, 0.0, 32600.0, 32600.0, 32600.0),
        Err(EditError::Config(ConfigError::OutOfReach {
            parameter: Parameter::C,
            ..
        }))
    ));
    for kind in [Kind::PI, Kind::I] {
        let config = Config {
            kind,
            ti: 1.0,
            ..pi(0.02, 1.5)
        };
        assert!(matches!(
            station::<I16F16>(config, 0.0, 30000.0, 30000.0, 0.0),
            Err(EditError::Config(ConfigError::OutOfReach {
                parameter: Parameter::B,
                ..
            }))
        ));
        // The same in f64 runs: floats skip the check.
        assert!(station::<f64>(config, 0.0, 30000.0, 30000.0, 0.0).is_ok());
    }
}
