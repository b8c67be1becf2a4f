//! A probe, not a measurement: firmware whose panic handler calls a function that is declared
//! but defined nowhere, so it links only if no panic path is left in what it calls —
//! `ReaderHealth::new` with limits read at run time, `ReaderHealth::record` with passages voted
//! from readings read at run time (so the window's ring wraps at a place the compiler cannot
//! see), `reset`, and the voter. The measuring build (feature `measure`) runs the calls under
//! QEMU with an ordinary panic handler.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, finish, refused, stack};
use regler_trolley_id::{AlarmLimits, ReaderHealth, Strategy, Voter};

static READINGS: [u16; 5] = [0x04D2, 0x04D2, 0x04D0, 0, 0x0001];
static LIMITS: [u32; 3] = [5, 10, 37];
static PASSAGES: u32 = 1_000;
static mut OUT: u32 = 0;

fn reading(i: usize) -> u16 {
    unsafe { read_volatile(addr_of!(READINGS).cast::<u16>().add(i % 5)) }
}

#[entry]
fn main() -> ! {
    let stored = unsafe { read_volatile(addr_of!(LIMITS)) };
    let limits = AlarmLimits {
        no_read_per_mille: stored[0],
        disagreement_per_mille: stored[1],
        min_passages: stored[2],
    };
    let Ok(mut health) = stack("ReaderHealth::<37>::new", || {
        ReaderHealth::<37>::new(limits)
    }) else {
        refused()
    };
    let Ok(mut voter) = Voter::new(Strategy::Consecutive { k: 2 }) else {
        refused()
    };
    let passages = unsafe { read_volatile(addr_of!(PASSAGES)) };
    let mut answer = 0u32;
    for n in 0..passages {
        let start = n as usize;
        for i in 0..3 {
            voter.sample(reading(start.wrapping_add(i)));
        }
        let passage = voter.finish();
        let change = stack("ReaderHealth::record", || health.record(&passage));
        answer ^= u32::from(change.is_some()) << (n % 32);
        if n % 500 == 499 {
            health.reset();
        }
    }
    answer ^= health.window().no_reads ^ health.alarms_raised();
    unsafe { write_volatile(&raw mut OUT, answer) };
    if MEASURING {
        finish();
    }
    loop {
        cortex_m::asm::nop();
    }
}

regler_footprint::no_panic_probe!();
