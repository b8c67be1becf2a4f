//! A reader's passage: readings decoded and voted on with the majority strategy.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, finish, refused, stack};
use regler_trolley_id::{Strategy, Voter, decode};

static READINGS: [u16; 5] = [0x04D2, 0x04D2, 0x04D0, 0, 0x04D2];
static mut ROUTED: u16 = 0;

fn reading(i: usize) -> u16 {
    unsafe { read_volatile(addr_of!(READINGS).cast::<u16>().add(i % 5)) }
}

#[entry]
fn main() -> ! {
    let Ok(mut voter) = stack("Voter::new", || {
        Voter::new(Strategy::Majority { min_samples: 3 })
    }) else {
        refused()
    };
    let passage = |voter: &mut Voter| {
        for i in 0..5 {
            voter.sample(reading(i));
        }
        let p = voter.finish();
        let id = p.verdict.trolley().map_or(0, |t| t.get());
        let ok = u16::from(decode(reading(0)).is_ok());
        unsafe { write_volatile(&raw mut ROUTED, id | ok << 15) };
    };
    // Measured three times (the first call may differ); only in the measuring build.
    if MEASURING {
        for _ in 0..3 {
            stack("Voter: 5 readings and finish", || passage(&mut voter));
        }
    }
    if MEASURING {
        finish();
    }
    loop {
        passage(&mut voter);
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    refused()
}
