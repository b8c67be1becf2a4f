//! A probe, not a measurement: fixed-point control with a panic handler that calls a function
//! declared but defined nowhere, so it links only if no panic path is left in what it calls.
//! For `I16F16` and `I32F32` alike: a `Pid` built from a `Config<f32>` read at run time, every
//! public operation of the controller (update, update with feed-forward and tracking, manual
//! and automatic, a new configuration, faults, reset, the state read-outs), and a `Station<_,
//! f32>` with every public operation of the operator layer (edits by code number and by code,
//! a change of kind, commit and discard, the night set-back, feed-forward, tracking, the
//! alarm and acknowledge, the read-outs) and of `Scaling` — each fed values the compiler
//! cannot see (volatile reads of what a sensor, the keyboard and the digital inputs would
//! give: NaN and ±∞ among them). The measuring build (feature `measure`) runs the calls under
//! QEMU with an ordinary panic handler.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use fixed::types::{I16F16, I32F32};
use regler_footprint::{MEASURING, finish, refused, stack};
use regler_pid::{
    Code, Config, Inputs, Kind, Mode, OperatorLimits, Parameters, Pid, Scalar, Scaling, Station,
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
    if flag(11) && station.pid_mut().set_manual(T::from_real(reading(MANUAL))).is_err() {
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
    let Ok(mut pid) = stack("Pid::<I16F16>::new", || Pid::<I16F16>::new(&config)) else {
        refused()
    };
    let Ok(mut pid32) = Pid::<I32F32>::new(&config) else {
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
    let mut station16 = stack("Station::<I16F16, f32>::new", || {
        station::<I16F16>(params, scaling)
    });
    let mut station32 = station::<I32F32>(params, scaling);
    if MEASURING {
        for _ in 0..3 {
            let y = reading(MEASUREMENT);
            let u = stack("Pid::<I16F16>::update", || {
                pid.update(I16F16::from_real(5.0f32), I16F16::from_real(y))
            });
            output(u);
            let v = stack("Station::<I16F16, f32>::sample", || station16.sample(y));
            volts(v);
        }
        // Each operation once more, so the measuring build runs them all under QEMU.
        control(&mut pid, &config);
        control(&mut pid32, &config);
        operate(&mut station16);
        operate(&mut station32);
        finish();
    }
    loop {
        control(&mut pid, &config);
        control(&mut pid32, &config);
        operate(&mut station16);
        operate(&mut station32);
    }
}

regler_footprint::no_panic_probe!();
