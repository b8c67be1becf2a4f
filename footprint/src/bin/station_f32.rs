//! The whole 1985 controller in `f32`: `Station<f32, f32>` (controller, staged operator
//! parameters, RFEL alarm, scaling) with its parameters read at run time and a sample per loop.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, finish, refused, stack};
use regler_pid::{Code, Config, OperatorLimits, Parameters, Scaling, Station};

/// Parameters as stored: K, Ti, set-point, RFEL, SCALEMIN, SCALEMAX.
static STORED: [f32; 6] = [2.0, 30.0, 20.0, 2.0, 0.0, 40.0];
static mut MEASUREMENT: f32 = 0.0;
static mut OUTPUT: f32 = 0.0;
static mut KEYED: f32 = 0.0;

fn stored(i: usize) -> f32 {
    unsafe { read_volatile(addr_of!(STORED).cast::<f32>().add(i)) }
}

#[entry]
fn main() -> ! {
    let config = Config::<f32> {
        k: stored(0),
        ti: stored(1),
        ..Config::default()
    };
    let params = Parameters {
        config,
        setpoint: stored(2),
        rfel: stored(3),
        night_setback: 0.0,
    };
    let Ok(scaling) = Scaling::new(stored(4), stored(5)) else {
        refused()
    };
    let new = || Station::<f32, f32>::new(params, scaling, OperatorLimits::default());
    let Ok(mut station) = stack("Station::<f32, f32>::new", new) else {
        refused()
    };
    // Measured three times (the first call may differ); only in the measuring build.
    if MEASURING {
        for _ in 0..3 {
            let y = stack("Station::<f32, f32>::sample", || {
                station.sample(unsafe { read_volatile(addr_of!(MEASUREMENT)) })
            });
            unsafe { write_volatile(&raw mut OUTPUT, y) };
        }
    }
    if MEASURING {
        finish();
    }
    loop {
        // The operator keys a new set-point now and then; the sample applies it.
        let keyed = unsafe { read_volatile(addr_of!(KEYED)) };
        if keyed != 0.0 && station.staged_mut().edit(Code::Win, keyed).is_ok() {
            station.staged_mut().commit();
        }
        let y = station.sample(unsafe { read_volatile(addr_of!(MEASUREMENT)) });
        unsafe { write_volatile(&raw mut OUTPUT, y) };
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    refused()
}
