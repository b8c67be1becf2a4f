//! As `pid_f32`, but with the configuration in `f64` (what the f64-only API cost): a configuration read at run time (six numbers from flash or EEPROM,
//! here volatile reads the compiler cannot fold) and updated from a measurement it cannot
//! predict: what firmware on a Cortex-M4F pays for the controller.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, finish, refused, stack};
use regler_pid::{Config, Kind, Pid};

/// Parameters as stored: K, Ti, Td, h, ymin, ymax.
static STORED: [f64; 6] = [2.0, 30.0, 1.0, 0.1, 0.0, 10.0];
static mut MEASUREMENT: f32 = 0.0;
static mut OUTPUT: f32 = 0.0;

fn stored(i: usize) -> f64 {
    // A volatile read of a static: the configuration is a run-time value.
    unsafe { read_volatile(addr_of!(STORED).cast::<f64>().add(i)) }
}

#[entry]
fn main() -> ! {
    let config = Config::<f64> {
        kind: Kind::PID,
        k: stored(0),
        ti: stored(1),
        td: stored(2),
        h: stored(3),
        ymin: stored(4),
        ymax: stored(5),
        ..Config::default()
    };
    let Ok(mut pid) = stack("Pid::<f32>::new from f64", || Pid::<f32>::new(&config)) else {
        refused()
    };
    // Measured three times (the first call may differ); only in the measuring build.
    if MEASURING {
        for _ in 0..3 {
            let y = unsafe { read_volatile(addr_of!(MEASUREMENT)) };
            let u = stack("Pid::<f32>::update (f64 config)", || pid.update(5.0, y));
            unsafe { write_volatile(&raw mut OUTPUT, u) };
        }
    }
    if MEASURING {
        finish();
    }
    loop {
        let y = unsafe { read_volatile(addr_of!(MEASUREMENT)) };
        let u = pid.update(5.0, y);
        unsafe { write_volatile(&raw mut OUTPUT, u) };
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    refused()
}
