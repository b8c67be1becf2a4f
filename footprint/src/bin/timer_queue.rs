//! `TimerQueue<u8, 64>`: timers inserted with run-time delays and ticked, as a PLC's timer shift
//! register would be.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, finish, refused, stack};
use regler_scan_cycle::TimerQueue;

static DELAYS: [u32; 4] = [3, 70, 5000, 1];
static mut FIRED: u32 = 0;

fn delay(i: usize) -> u32 {
    unsafe { read_volatile(addr_of!(DELAYS).cast::<u32>().add(i % 4)) }
}

#[entry]
fn main() -> ! {
    let mut queue = stack("TimerQueue::<u8, 64>::new", TimerQueue::<u8, 64>::new);
    for n in 0..8u8 {
        if queue.insert(delay(usize::from(n)), n).is_err() {
            refused();
        }
    }
    let tick = |queue: &mut TimerQueue<u8, 64>| {
        queue.tick(|a| unsafe { write_volatile(&raw mut FIRED, u32::from(a)) });
        if queue.len() < 8 {
            let _ = queue.insert(delay(queue.len()), 1);
        }
    };
    // Measured three times (the first call may differ); only in the measuring build.
    if MEASURING {
        for _ in 0..3 {
            stack("TimerQueue::tick", || tick(&mut queue));
        }
    }
    if MEASURING {
        finish();
    }
    loop {
        tick(&mut queue);
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    refused()
}
