//! An L-type crate controller on a byte-serial highway: every byte in, one byte out, a crate of
//! 32 registers behind it; and `highway::decode` of what passes (a monitor would).
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, finish, refused, stack};
use regler_panel_link::highway::{
    Controller, ControllerConfig, Cycle, Dataway, MAX_MESSAGE, Message, decode,
};

static ADDRESS: u8 = 7;
static mut IN: u8 = 0xE0;
static mut OUT: u8 = 0;

struct Registers([u32; 32]);

impl Dataway for Registers {
    fn cycle(&mut self, n: u8, _a: u8, f: u8, write: Option<u32>) -> Cycle {
        let reg = &mut self.0[usize::from(n & 31)];
        if let Some(w) = write {
            *reg = w;
        }
        Cycle {
            read: *reg,
            x: true,
            q: f < 8,
        }
    }
}

#[entry]
fn main() -> ! {
    let address = unsafe { read_volatile(addr_of!(ADDRESS)) };
    let Ok(mut controller) = stack("Controller::new", || {
        Controller::new(ControllerConfig {
            address,
            demand_repeat: 4096,
        })
    }) else {
        refused()
    };
    let mut crate_ = Registers([0; 32]);
    if MEASURING {
        let command = Message::Command {
            crate_address: address,
            station: 3,
            subaddress: 0,
            function: 16,
            data: Some(5),
        };
        let mut buf = [0u8; MAX_MESSAGE];
        let len = command.encode(&mut buf).unwrap_or(0);
        for _ in 0..3 {
            for &b in buf.iter().take(len) {
                let out = stack("Controller::clock", || controller.clock(b, &mut crate_));
                unsafe { write_volatile(&raw mut OUT, out) };
            }
            let _ = stack("highway::decode", || decode(&buf[..len]));
        }
        finish();
    }
    loop {
        let input = unsafe { read_volatile(addr_of!(IN)) };
        let out = controller.clock(input, &mut crate_);
        unsafe { write_volatile(&raw mut OUT, out) };
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    refused()
}
