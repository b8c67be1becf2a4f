//! regler-pid on the core: f32 on the FPU (or soft float on the M0), f64, fixed point.

use fixed::types::I16F16;
use regler_pid::{
    Alarm, AlarmState, Code, Config, ConfigError, EditError, Inputs, Kind, Mode, OperatorLimits,
    Parameter, Parameters, Pid, Scaling, Staged, Station, ValueError,
};

use crate::{Outcome, check};

#[allow(
    clippy::field_reassign_with_default,
    reason = "the contract's own spelling for an f32 config"
)]
fn room() -> Config<f32> {
    let mut c = Config::default();
    c.kind = Kind::PI;
    c.k = 2.0;
    c.ti = 10.0;
    c.h = 0.5;
    c.ymax = 100.0;
    c
}

pub fn f32_closed_loop_survives_nan_at_power_up() -> Outcome {
    let mut pid = Pid::<f32>::new(&room()).map_err(|_| "config")?;
    check!(pid.update(20.0, f32::NAN) == 0.0);
    check!(pid.faults().non_finite_input());
    pid.clear_faults();
    let mut t = 15.0f32;
    for k in 0..400 {
        let reading = if k == 100 { f32::INFINITY } else { t };
        let heat = pid.update(20.0, reading);
        check!(heat.is_finite() && (0.0..=100.0).contains(&heat));
        t += 0.5 * (0.05 * heat - 0.02 * (t - 10.0));
    }
    check!((t - 20.0).abs() < 0.05);
    check!(pid.integral().is_finite());
    Ok(())
}

pub fn f64_matches_hand_computed_steps() -> Outcome {
    let c = Config {
        kind: Kind::PI,
        k: 2.0,
        ti: 4.0,
        h: 1.0,
        ymin: -10.0,
        ymax: 10.0,
        ..Config::default()
    };
    let mut pid = Pid::<f64>::new(&c).map_err(|_| "config")?;
    check!(pid.update(1.0, 0.0) == 2.0);
    check!(pid.integral() == 0.5);
    check!(pid.update(1.0, 0.0) == 2.5);
    check!(pid.update(100.0, 0.0) == 10.0);
    Ok(())
}

pub fn fixed_point_follows_f32() -> Outcome {
    let c = Config {
        kind: Kind::PID,
        k: 1.5,
        ti: 6.0,
        td: 1.0,
        h: 0.5,
        ymax: 10.0,
        dymax: Some(1.0),
        ..Config::default()
    };
    let mut a = Pid::<f32>::new(&c).map_err(|_| "f32")?;
    let mut b = Pid::<I16F16>::new(&c).map_err(|_| "I16F16")?;
    let mut y = 0.0f32;
    for _ in 0..300 {
        let ua = a.update(5.0, y);
        let ub = b
            .update(I16F16::from_num(5.0), I16F16::from_num(y))
            .to_num::<f32>();
        check!((ua - ub).abs() < 0.05);
        y += 0.25 * (0.8 * ua - y);
    }
    // A gain I16F16 cannot hold is refused, naming it.
    let big = Config { k: 1e5, ..c };
    check!(matches!(Pid::<I16F16>::new(&big), Err(e) if e.parameter() == Parameter::K));
    Ok(())
}

pub fn config_errors_name_the_parameter() -> Outcome {
    let mut c = room();
    c.tt = Some(0.1);
    check!(matches!(
        c.validate(),
        Err(ConfigError::TrackingUnstable { .. })
    ));
    let mut c = room();
    c.k = 1e-30;
    c.ti = 1e10;
    check!(matches!(Pid::<f32>::new(&c), Err(e) if e.parameter() == Parameter::Ti));
    Ok(())
}

pub fn spike_is_forgotten() -> Outcome {
    let c = Config {
        kind: Kind::PID,
        k: 0.5,
        ti: 10.0,
        td: 1.0,
        h: 0.5,
        tt: Some(5.0),
        ymax: 10.0,
        ..Config::default()
    };
    let run = |spike: bool| -> f32 {
        let Ok(mut pid) = Pid::<f32>::new(&c) else {
            return f32::NAN;
        };
        let mut y = 0.0f32;
        for k in 0..2000 {
            let reading = if spike && k == 1000 { 1e30 } else { y };
            let u = pid.update(5.0, reading);
            y += 0.05 * (2.0 * u - y);
        }
        y
    };
    check!((run(true) - run(false)).abs() < 0.05);
    Ok(())
}

pub fn station_commits_at_a_sample_in_f32() -> Outcome {
    let params = Parameters {
        config: Config::<f32>::default(),
        setpoint: 20.0,
        rfel: 2.0,
        night_setback: 0.0,
    };
    let scale = Scaling::new(0.0f32, 40.0).map_err(|_| "scale")?;
    let mut st = Station::<f32, f32>::new(params, scale, OperatorLimits::default())
        .map_err(|_| "station")?;
    check!(st.sample(15.0) > 0.0);
    check!(st.alarm_state() == AlarmState::Blinking);
    st.staged_mut().edit(Code::Win, 18.0).map_err(|_| "edit")?;
    check!(st.staged_mut().edit(Code::Win, 50.0).is_err());
    st.staged_mut().commit();
    check!(st.value(Code::Win) == Some(20.0));
    st.sample(17.0);
    check!(st.value(Code::Win) == Some(18.0));
    check!(st.commits() == 1);
    st.sample(f32::NAN);
    check!(st.pid().faults().non_finite_input());
    Ok(())
}

pub fn alarm_blinks_then_steady() -> Outcome {
    let mut alarm = Alarm::new();
    alarm.update(true);
    check!(alarm.state() == AlarmState::Blinking);
    alarm.acknowledge();
    check!(alarm.state() == AlarmState::Steady);
    alarm.update(false);
    check!(alarm.state() == AlarmState::Normal);
    Ok(())
}

pub fn scaling_round_trips_every_count() -> Outcome {
    let s = Scaling::new(-50.0f32, 150.0).map_err(|_| "scale")?;
    for count in 0..=4095u16 {
        let units = s.count_to_units(count).map_err(|_| "count")?;
        check!(s.units_to_count(units) == count);
    }
    for count in 0..=255u8 {
        check!(Scaling::volts_to_dac(Scaling::<f32>::dac_to_volts(count)) == Ok(count));
    }
    Ok(())
}

pub fn sizes_on_a_32_bit_core() -> Outcome {
    // 19 values and 2 bytes of flags, padded.
    check!(core::mem::size_of::<Pid<f32>>() == 80);
    check!(core::mem::size_of::<Pid<I16F16>>() == 80);
    Ok(())
}

pub fn manual_tracking_and_feedforward() -> Outcome {
    let c = Config {
        kind: Kind::PI,
        k: 2.0,
        ti: 4.0,
        h: 1.0,
        ymin: -10.0,
        ymax: 10.0,
        ..Config::default()
    };
    let mut pid = Pid::<f32>::new(&c).map_err(|_| "config")?;
    pid.update(5.0, 4.0);
    pid.set_manual(7.5).map_err(|_| "manual")?;
    check!(pid.mode() == Mode::Manual);
    check!(pid.update(5.0, 4.5) == 7.5);
    check!(pid.set_manual(f32::NAN) == Err(ValueError::NotFinite));
    pid.set_auto();
    check!((pid.update(5.0, 4.5) - 7.5).abs() < 1e-5);
    let mut free = Pid::<f32>::new(&c).map_err(|_| "config")?;
    check!(
        free.update_with(
            0.0,
            0.0,
            Inputs {
                feedforward: 3.0,
                track: None
            }
        ) == 3.0
    );
    check!(
        free.update_with(
            0.0,
            0.0,
            Inputs {
                feedforward: f32::NAN,
                track: None
            }
        ) == 3.0
    );
    check!(free.faults().non_finite_input());
    Ok(())
}

pub fn staged_edits_say_what_was_wrong() -> Outcome {
    let active = Parameters {
        config: Config::<f32>::default(),
        setpoint: 50.0,
        rfel: 5.0,
        night_setback: 0.0,
    };
    let scale = Scaling::new(0.0f32, 100.0).map_err(|_| "scale")?;
    let mut staged = Staged::new(active, scale, OperatorLimits::default()).map_err(|_| "staged")?;
    check!(staged.edit_number(42, 1.0) == Err(EditError::UnknownCode(42)));
    check!(matches!(
        staged.edit(Code::Kp, 1e6),
        Err(EditError::IllegalValue { code: Code::Kp, .. })
    ));
    check!(matches!(staged.edit(Code::Ti, 0.0), Err(e) if e.code() == Some(Code::Ti)));
    staged.edit(Code::Dymax, 0.0).map_err(|_| "dymax")?;
    check!(staged.shadow().config.dymax.is_none());
    check!(!staged.edited());
    Ok(())
}

/// The relay experiment in f32 on the core: 1/(s+1)^3 (Ku = 8, Tu = 3.63 s), sampled at 20 ms,
/// the lags stepped with a precomputed factor (no `exp` on the core).
pub fn relay_autotune_in_f32() -> Outcome {
    use regler_pid::tuning::{Relay, RelayConfig, RelayStep, ziegler_nichols};
    let a = 0.980_198_7f32; // e^(-0.02)
    let mut x = [0.0f32; 3];
    let mut relay = Relay::new(RelayConfig::<f32> {
        h: 0.02,
        hysteresis: 0.002,
        timeout: 300.0,
        ..RelayConfig::default()
    })
    .map_err(|_| "relay config")?;
    let mut found = None;
    for _ in 0..20_000 {
        match relay.update(0.0, x[2]).map_err(|_| "relay failed")? {
            RelayStep::Running(u) => {
                x[0] = a * x[0] + (1.0 - a) * u;
                x[1] = a * x[1] + (1.0 - a) * x[0];
                x[2] = a * x[2] + (1.0 - a) * x[1];
            }
            RelayStep::Done(u) => {
                found = Some(u);
                break;
            }
        }
    }
    let u = found.ok_or("no estimate")?;
    check!(u.ku > 7.2 && u.ku < 8.1);
    check!(u.tu > 3.5 && u.tu < 3.8);
    let t = ziegler_nichols(u, Kind::PI).map_err(|_| "rule")?;
    let mut config = Config::<f32> {
        h: 0.02,
        ymax: 10.0,
        ..Config::default()
    };
    t.apply(&mut config).map_err(|_| "apply")?;
    check!(config.kind == Kind::PI && config.k > 3.0);
    Ok(())
}

/// The three-point actuator: a position estimate that follows the pulses, no windup at the end.
pub fn three_point_actuator() -> Outcome {
    use regler_pid::actuator::{ActuatorConfig, Drive, ThreePoint};
    let mut valve = ThreePoint::new(
        ActuatorConfig::<f32> {
            run_time: 60.0,
            min_pulse: 0.2,
            dead_band: 0.005,
            h: 1.0,
        },
        0.5,
    )
    .map_err(|_| "config")?;
    for _ in 0..100 {
        valve.update_delta(0.1).map_err(|_| "delta")?;
    }
    check!(valve.position() == 1.0);
    check!(matches!(valve.update_delta(-0.05), Ok(Drive::Close(s)) if s == 1.0));
    check!(valve.update(f32::NAN).is_err());
    Ok(())
}
