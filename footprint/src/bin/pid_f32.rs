//! A `Pid<f32>` built from a configuration read at run time (six numbers from flash or EEPROM,
//! here volatile reads the compiler cannot fold) and updated from a measurement it cannot
//! predict: what firmware on a Cortex-M4F pays for the controller.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{finish, refused, stack};
use regler_pid::{Config, Kind, Pid};

/// Parameters as stored: K, Ti, Td, h, ymin, ymax.
static STORED: [f32; 6] = [2.0, 30.0, 1.0, 0.1, 0.0, 10.0];
static mut MEASUREMENT: f32 = 0.0;
static mut OUTPUT: f32 = 0.0;

fn stored(i: usize) -> f32 {
    // A volatile read of a static: the configuration is a run-time value.
    unsafe { read_volatile(addr_of!(STORED).cast::<f32>().add(i)) }
}

#[entry]
fn main() -> ! {
    let mut config = Config::<f32>::default();
    config.kind = Kind::PID;
    config.k = stored(0);
    config.ti = stored(1);
    config.td = stored(2);
    config.h = stored(3);
    config.ymin = stored(4);
    config.ymax = stored(5);
    let Ok(mut pid) = stack("Pid::<f32>::new", || Pid::<f32>::new(&config)) else {
        refused()
    };
    // Measured three times (the first call may differ); only in the measuring build.
    for _ in 0..if cfg!(feature = "measure") { 3 } else { 0 } {
        let y = unsafe { read_volatile(addr_of!(MEASUREMENT)) };
        let u = stack("Pid::<f32>::update", || pid.update(5.0, y));
        unsafe { write_volatile(&raw mut OUTPUT, u) };
    }
    if cfg!(feature = "measure") {
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
