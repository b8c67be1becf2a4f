//! `Tracker<u16, 64, 8>`: a dock chain with a distance table read at run time, trolleys entering
//! and chain pulses moving them to their tippers.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_chain_tracker::{DistanceTable, TipperEvent, Tracker};
use regler_footprint::{MEASURING, finish, refused, stack};

static SA: [u32; 8] = [100, 200, 300, 400, 500, 600, 700, 800];
static mut TIPPED: u32 = 0;
static mut DIA: u32 = 3000;

#[entry]
fn main() -> ! {
    let sa = unsafe { read_volatile(addr_of!(SA)) };
    let Ok(table) = DistanceTable::<8>::new(3000, &sa) else {
        refused()
    };
    let Ok(mut tracker) = stack("Tracker::<u16, 64, 8>::new", || {
        Tracker::<u16, 64, 8>::new(table, 6)
    }) else {
        refused()
    };
    let step = |tracker: &mut Tracker<u16, 64, 8>, n: u32| {
        if n.is_multiple_of(4) {
            let _ = tracker.enter(n as u16, (n % 8) as usize);
        }
        tracker.pulse(|e| {
            if let TipperEvent::Set { trolley, .. } = e {
                unsafe { write_volatile(&raw mut TIPPED, u32::from(trolley)) };
            }
        });
    };
    // Measured three times; only in the measuring build.
    if MEASURING {
        for n in 0..3u32 {
            stack("Tracker::enter + pulse", || step(&mut tracker, n));
        }
    }
    let dia = unsafe { read_volatile(addr_of!(DIA)) };
    if MEASURING {
        let _ = stack("Tracker::recalibrate", || {
            tracker.recalibrate(dia.wrapping_sub(15))
        });
    }
    if MEASURING {
        finish();
    }
    let mut n = 0u32;
    loop {
        step(&mut tracker, n);
        n = n.wrapping_add(1);
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    refused()
}
