//! A probe, not a measurement: floating-point control with a panic handler that calls a
//! function declared but defined nowhere, so it links only if no panic path is left in what it
//! calls. For `f32` and `f64` alike: a `Pid` built from a `Config<f32>` read at run time and
//! every public operation of the controller (as `pid_fixed_no_panic` does for fixed point); a
//! `Station<_, f32>` with every public operation of the operator layer and of `Scaling`
//! (`EditError::display_message` included); and the `tuning` and `actuator` modules: the rules
//! (Ziegler–Nichols, AMIGO, SIMC) from run-time models, `Tuning::apply`,
//! `Fopdt::with_sampling_delay`, `identify_step` and `identify_step_at` over a run-time log and
//! step index, a `Relay` from a run-time configuration (update, result, abort, hand-over), a
//! `ThreePoint` actuator (update, update_delta, at_end, the read-outs), and the `Display` of
//! `RuleError` and `ActuatorError`. Inputs are volatile reads: NaN, ±∞ and subnormals among
//! them. Not the `Display` of the errors that print a float (`ConfigError`, `IdentifyError`,
//! `RelayError`, `HandOverError`): core's float formatting keeps panic paths of its own. The
//! measuring build (feature `measure`) runs the calls under QEMU with an ordinary panic handler.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, at, finish, keep, refused, shown};
use regler_pid::actuator::{ActuatorConfig, Drive, ThreePoint};
use regler_pid::tuning::{
    self, Fopdt, Relay, RelayConfig, RelayStep, Ultimate, amigo, identify_step, identify_step_at,
    simc, ziegler_nichols,
};
use regler_pid::{
    Action, Code, Config, Inputs, Kind, Mode, OperatorLimits, Parameters, Pid, Real, Scalar,
    Scaling, Station,
};

/// Parameters as stored: K, Ti, Td, h, ymin, ymax, set-point, RFEL, SCALEMIN, SCALEMAX, night
/// set-back.
static STORED: [f32; 11] = [2.0, 30.0, 1.0, 0.1, 0.0, 10.0, 20.0, 2.0, 0.0, 40.0, 5.0];

/// What the plant and the operator give at run time (the indices below).
static mut READINGS: [f32; 8] = [0.0; 8];
const MEASUREMENT: usize = 0;
const KEYED: usize = 1;
const FEEDFORWARD: usize = 2;
const TRACK: usize = 3;
const MANUAL: usize = 4;
const UNITS: usize = 5;
const VOLTS_IN: usize = 6;
const GAIN: usize = 7;

/// Keys and digital inputs: code number, kind, switches, an A/D count, a D/A count.
static mut SWITCHES: [u16; 6] = [0; 6];
const CODE: usize = 0;
const KIND: usize = 1;
const FLAGS: usize = 2;
const COUNT: usize = 3;
const DAC: usize = 4;
const CODE_INDEX: usize = 5;

static mut OUTPUT: u32 = 0;
static mut VOLTS: f32 = 0.0;
static mut WORD: u32 = 0;

fn stored(i: usize) -> f32 {
    unsafe { read_volatile(addr_of!(STORED).cast::<f32>().add(i)) }
}

fn reading(i: usize) -> f32 {
    unsafe { read_volatile((&raw const READINGS).cast::<f32>().add(i)) }
}

fn switch(i: usize) -> u16 {
    unsafe { read_volatile((&raw const SWITCHES).cast::<u16>().add(i)) }
}

fn flag(bit: u16) -> bool {
    switch(FLAGS) & (1 << bit) != 0
}

fn volts(v: f32) {
    unsafe { write_volatile(&raw mut VOLTS, v) };
}

fn word(w: u32) {
    unsafe { write_volatile(&raw mut WORD, w) };
}

fn output<T: Scalar>(u: T) {
    let v: f32 = u.to_real();
    unsafe { write_volatile(&raw mut OUTPUT, v.to_bits()) };
}

/// One pass over every public operation of the controller.
fn control<T: Scalar>(pid: &mut Pid<T>, config: &Config<f32>) {
    let y = T::from_real(reading(MEASUREMENT));
    let r = T::from_real(stored(6));
    output(pid.update(r, y));
    let inputs = Inputs {
        feedforward: T::from_real(reading(FEEDFORWARD)),
        track: flag(0).then(|| T::from_real(reading(TRACK))),
    };
    output(pid.update_with(r, y, inputs));
    if flag(1) {
        if pid.set_manual(T::from_real(reading(MANUAL))).is_err() {
            word(1);
        }
    } else {
        pid.set_auto();
    }
    word(u32::from(pid.mode() == Mode::Manual));
    output(pid.output());
    output(pid.integral());
    output(pid.derivative());
    let faults = pid.faults();
    word(u32::from(faults.any()) | u32::from(faults.overflow()) << 1);
    word(u32::from(faults.non_finite_input()));
    if flag(2) {
        pid.clear_faults();
    }
    if flag(3) {
        pid.reset();
    }
    if flag(4) {
        let retuned = Config {
            k: reading(GAIN),
            ..*config
        };
        if pid.set_config(&retuned).is_err() {
            word(2);
        }
    }
}

/// One pass over every public operation of the operator layer and of `Scaling`.
fn operate<T: Scalar>(station: &mut Station<T, f32>) {
    let keyed = reading(KEYED);
    // A code number as keyed (unknown and read-only ones included) and a code picked by index.
    let code = u8::try_from(switch(CODE)).unwrap_or(u8::MAX);
    let edited = station.staged_mut().edit_number(code, keyed);
    let by_code = Code::ALL
        .get(usize::from(switch(CODE_INDEX)))
        .map(|&c| station.staged_mut().edit(c, keyed));
    let kind = Kind::ALL
        .get(usize::from(switch(KIND)))
        .map(|&k| station.staged_mut().edit_kind(k));
    for result in [Some(edited), by_code, kind].into_iter().flatten() {
        if let Err(e) = result {
            // The panic-free route to the operator's text (not `{}`).
            word(e.display_message().len() as u32);
            word(e.code().map_or(0, |c| u32::from(c.number())));
        }
    }
    if flag(5) {
        station.staged_mut().commit();
    }
    if flag(6) {
        station.staged_mut().discard();
    }
    let staged = station.staged();
    word(u32::from(staged.commit_pending()) | u32::from(staged.edited()) << 1);
    word(u32::from(staged.pending().is_some()));
    for c in Code::ALL {
        volts(staged.active_value(c).unwrap_or(0.0));
        volts(staged.shadow_value(c).unwrap_or(0.0));
        volts(station.value(c).unwrap_or(0.0));
        word(u32::from(c.writable()) | u32::from(c.name().len() as u8) << 8);
    }
    volts(staged.active().setpoint + staged.shadow().setpoint);
    if staged.limits().validate().is_err() {
        word(3);
    }
    // The night set-back, feed-forward and tracking.
    station.set_night(flag(7));
    word(u32::from(station.night()));
    volts(station.setpoint());
    station.set_feedforward(reading(FEEDFORWARD));
    station.set_track(flag(8).then(|| reading(TRACK)));
    if flag(9) {
        station.acknowledge();
    }
    if let Some(e) = station.refused_commit() {
        word(u32::from(e.parameter().name().len() as u8));
    }
    volts(station.sample(reading(MEASUREMENT)));
    let alarm = station.alarm();
    word(u32::from(alarm.output_bits()) | u32::from(alarm.buzzer()) << 8);
    word(u32::from(alarm.lamp(flag(10))) | alarm.raised() << 1);
    word(u32::from(station.alarm_state() == alarm.state()));
    word(station.commits());
    output(station.pid().output());
    if flag(11)
        && station
            .pid_mut()
            .set_manual(T::from_real(reading(MANUAL)))
            .is_err()
    {
        word(4);
    }
    // Scaling: counts from the A/D, values to the D/A, run-time values all.
    let scaling = station.staged().scaling();
    volts(scaling.min() + scaling.max());
    match scaling.count_to_units(switch(COUNT)) {
        Ok(units) => volts(units),
        Err(_) => word(5),
    }
    word(u32::from(scaling.units_to_count(reading(UNITS))));
    word(u32::from(scaling.contains(reading(UNITS))));
    match Scaling::<f32>::volts_to_dac(reading(VOLTS_IN)) {
        Ok(count) => word(u32::from(count)),
        Err(_) => word(6),
    }
    volts(Scaling::<f32>::dac_to_volts(
        u8::try_from(switch(DAC)).unwrap_or(u8::MAX),
    ));
    if let Some(c) = Code::from_number(code) {
        word(u32::from(c.number()));
    }
}

fn station<T: Scalar>(params: Parameters<f32>, scaling: Scaling<f32>) -> Station<T, f32> {
    match Station::<T, f32>::new(params, scaling, OperatorLimits::default()) {
        Ok(station) => station,
        Err(_) => refused(),
    }
}

/// Numbers as a log, an operator or a stored model would give them (NaN, ±∞, 0, a subnormal).
static NUMBERS: [f32; 12] = [
    0.0,
    1.0,
    -1.0,
    0.5,
    2.5,
    100.0,
    1e-40,
    3.0e38,
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    0.01,
];
/// Counts: log lengths, step indices, cycles, kinds.
static COUNTS: [usize; 6] = [0, 1, 2, 7, 40, usize::MAX];

fn number<F: Real>(i: usize) -> F {
    F::from_f32_exact(at(&NUMBERS, i))
}

fn real<F: Real>(v: F) {
    keep(v.to_f64_exact().to_bits() as u32);
}

/// Every public operation of `tuning` and `actuator` in the float type `F`.
fn tune<F: Real + Scalar>(seed: usize) {
    let kinds = Kind::ALL;
    let kind = kinds[at(&COUNTS, seed) % kinds.len()];
    let ultimate = Ultimate {
        ku: number::<F>(seed),
        tu: number::<F>(seed + 1),
    };
    let model = Fopdt {
        gain: number::<F>(seed + 2),
        time_constant: number::<F>(seed + 3),
        dead_time: number::<F>(seed + 4),
    }
    .with_sampling_delay(number::<F>(seed + 5));
    let mut config = Config::<F>::default();
    for rule in [
        ziegler_nichols(ultimate, kind),
        amigo(model, kind),
        simc(model, number::<F>(seed + 6)),
    ] {
        match rule {
            Ok(t) => {
                real(t.k + t.ti + t.td + t.b);
                if t.apply(&mut config).is_err() {
                    keep(1);
                }
            }
            Err(e) => keep(shown(&e)),
        }
    }
    // A step-response log of run-time length and content, the step at a run-time index.
    let mut log = [F::default(); 64];
    for (i, v) in log.iter_mut().enumerate() {
        *v = number::<F>(seed.wrapping_mul(i) % 7 + usize::from(i > 20));
    }
    let n = at(&COUNTS, seed + 1).min(log.len());
    let h = number::<F>(seed + 7);
    let step = number::<F>(seed + 8);
    if let Ok(m) = identify_step(&log[..n], h, step) {
        real(m.gain + m.time_constant + m.dead_time);
    }
    if let Ok(m) = identify_step_at(&log[..n], at(&COUNTS, seed + 2), h, step) {
        real(m.gain);
    }
    // The relay experiment from a run-time configuration, over a run-time process.
    let relay_config = RelayConfig {
        action: if seed.is_multiple_of(2) {
            Action::Direct
        } else {
            Action::Reverse
        },
        bias: number::<F>(seed + 9),
        amplitude: number::<F>(seed + 1),
        hysteresis: number::<F>(seed + 11),
        h: number::<F>(seed + 3),
        cycles: at(&COUNTS, seed + 3) as u8,
        tolerance: number::<F>(seed + 4),
        timeout: number::<F>(seed + 5),
    };
    let relay = Relay::new(relay_config).or_else(|_| Relay::new(RelayConfig::<F>::default()));
    if let Ok(mut relay) = relay {
        let mut y = F::default();
        for i in 0..200usize {
            match relay.update(number::<F>(i + seed), y) {
                Ok(RelayStep::Running(u)) => y = u + number::<F>(i),
                Ok(RelayStep::Done(found)) => real(found.ku + found.tu),
                Err(_) => break,
            }
        }
        real(relay.output());
        if let Some(found) = relay.result() {
            real(found.ku);
        }
        match relay.hand_over::<F>(&config, number::<F>(seed), number::<F>(seed + 1)) {
            Ok(mut pid) => real(
                pid.update(number::<F>(seed), number::<F>(seed + 2))
                    .to_real::<F>(),
            ),
            Err(_) => keep(2),
        }
        real(relay.abort());
    }
    // The three-point actuator from a run-time configuration, run-time targets and ends.
    let actuator_config = ActuatorConfig {
        run_time: number::<F>(seed + 5),
        min_pulse: number::<F>(seed + 11),
        dead_band: number::<F>(seed + 11),
        h: number::<F>(seed + 1),
    };
    let valve = ThreePoint::new(actuator_config, number::<F>(seed + 3)).or_else(|_| {
        let sane = ActuatorConfig {
            run_time: number::<F>(5),
            min_pulse: number::<F>(11),
            dead_band: number::<F>(11),
            h: number::<F>(1),
        };
        ThreePoint::new(sane, F::default())
    });
    match valve {
        Ok(mut valve) => {
            for i in 0..100usize {
                let drive = if i.is_multiple_of(2) {
                    valve.update(number::<F>(i + seed))
                } else {
                    valve.update_delta(number::<F>(i))
                };
                match drive {
                    Ok(Drive::Open(t) | Drive::Close(t)) => real(t),
                    Ok(_) => keep(3),
                    Err(e) => keep(shown(&e)),
                }
                if i.is_multiple_of(17) {
                    valve.at_end(i.is_multiple_of(34));
                }
            }
            let (opened, closed) = valve.driven();
            real(valve.position() + valve.smallest_move() + opened + closed);
        }
        Err(e) => keep(shown(&e)),
    }
    let _ = tuning::RuleError::Kind(kind);
}

#[entry]
fn main() -> ! {
    let config = Config::<f32> {
        kind: Kind::PID,
        k: stored(0),
        ti: stored(1),
        td: stored(2),
        h: stored(3),
        ymin: stored(4),
        ymax: stored(5),
        ..Config::default()
    };
    let Ok(mut pid32) = Pid::<f32>::new(&config) else {
        refused()
    };
    let Ok(mut pid64) = Pid::<f64>::new(&config) else {
        refused()
    };
    let params = Parameters {
        config: Config { h: 1.0, ..config },
        setpoint: stored(6),
        rfel: stored(7),
        night_setback: stored(10),
    };
    let Ok(scaling) = Scaling::new(stored(8), stored(9)) else {
        refused()
    };
    let mut station32 = station::<f32>(params, scaling);
    let mut station64 = station::<f64>(params, scaling);
    let mut seed = 0usize;
    loop {
        control(&mut pid32, &config);
        control(&mut pid64, &config);
        operate(&mut station32);
        operate(&mut station64);
        tune::<f32>(seed);
        tune::<f64>(seed);
        seed = seed.wrapping_add(1);
        // The measuring build runs every operation once under QEMU.
        if MEASURING {
            finish();
        }
    }
}

regler_footprint::no_panic_probe!();
