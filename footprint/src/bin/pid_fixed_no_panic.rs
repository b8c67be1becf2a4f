//! A probe, not a measurement: fixed-point control with a panic handler that calls a function
//! declared but defined nowhere, so it links only if no panic path is left in what it calls —
//! a `Pid<I16F16>` built from a `Config<f32>` read at run time and updated from measurements
//! converted with `Scalar::from_real` (NaN and ±∞ among what the compiler must allow for), and
//! a `Station<I16F16, f32>` (staged edits, commit, alarm, scaling) sampled in a loop. The
//! measuring build (feature `measure`) runs the calls under QEMU with an ordinary panic handler.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use fixed::types::I16F16;
use regler_footprint::{MEASURING, finish, refused, stack};
use regler_pid::{Code, Config, Kind, OperatorLimits, Parameters, Pid, Scalar, Scaling, Station};

/// Parameters as stored: K, Ti, Td, h, ymin, ymax, set-point, RFEL, SCALEMIN, SCALEMAX.
static STORED: [f32; 10] = [2.0, 30.0, 1.0, 0.1, 0.0, 10.0, 20.0, 2.0, 0.0, 40.0];
static mut MEASUREMENT: f32 = 0.0;
static mut OUTPUT: i32 = 0;
static mut KEYED: f32 = 0.0;
static mut VOLTS: f32 = 0.0;

fn stored(i: usize) -> f32 {
    unsafe { read_volatile(addr_of!(STORED).cast::<f32>().add(i)) }
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
    let params = Parameters {
        config: Config { h: 1.0, ..config },
        setpoint: stored(6),
        rfel: stored(7),
        night_setback: 0.0,
    };
    let Ok(scaling) = Scaling::new(stored(8), stored(9)) else {
        refused()
    };
    let new = || Station::<I16F16, f32>::new(params, scaling, OperatorLimits::default());
    let Ok(mut station) = stack("Station::<I16F16, f32>::new", new) else {
        refused()
    };
    if MEASURING {
        for _ in 0..3 {
            let y = unsafe { read_volatile(addr_of!(MEASUREMENT)) };
            let u = stack("Pid::<I16F16>::update", || {
                pid.update(I16F16::from_real(5.0f32), I16F16::from_real(y))
            });
            unsafe { write_volatile(&raw mut OUTPUT, u.to_bits()) };
            let v = stack("Station::<I16F16, f32>::sample", || station.sample(y));
            unsafe { write_volatile(&raw mut VOLTS, v) };
        }
        finish();
    }
    loop {
        // Any f32 the sensor gives, NaN and infinities included, goes through from_real.
        let y = unsafe { read_volatile(addr_of!(MEASUREMENT)) };
        let u = pid.update(I16F16::from_real(5.0f32), I16F16::from_real(y));
        unsafe { write_volatile(&raw mut OUTPUT, u.to_bits()) };
        let keyed = unsafe { read_volatile(addr_of!(KEYED)) };
        if keyed != 0.0 {
            match station.staged_mut().edit(Code::Kp, keyed) {
                Ok(_) => station.staged_mut().commit(),
                // The panic-free route to the operator's text (not `{}`).
                Err(e) => {
                    let m = e.display_message();
                    unsafe { write_volatile(&raw mut VOLTS, m.len() as f32) };
                    station.staged_mut().discard();
                }
            }
        }
        if y > 9.0 {
            station.acknowledge();
        }
        let v = station.sample(y);
        unsafe { write_volatile(&raw mut VOLTS, v) };
    }
}

regler_footprint::no_panic_probe!();
