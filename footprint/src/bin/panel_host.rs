//! The computer's side of the 1977 panel link for the central desk (46 registers): a byte each
//! time the UART is ready, the MOT poll every 10 ms, the key bytes received.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, finish, refused, stack};
use regler_panel_link::panel::{CENTRAL_DESK, Host, HostConfig, HostEvent};

static mut MOT: bool = false;
static mut RX: u8 = 0;
static mut TX: u8 = 0;
static mut KEY: u8 = 0;

#[entry]
fn main() -> ! {
    let Ok(mut host) = stack("Host::<46>::new", || {
        Host::<CENTRAL_DESK>::new(HostConfig::default())
    }) else {
        refused()
    };
    let mut tick = 0u32;
    let mut round = |host: &mut Host<CENTRAL_DESK>| {
        for i in 0..CENTRAL_DESK {
            let _ = host.set(i, (tick as u8).wrapping_add(i as u8) & 0x7F);
        }
        if let Some(byte) = host.next_byte() {
            unsafe { write_volatile(&raw mut TX, byte) };
        }
        tick = tick.wrapping_add(1);
        if tick.is_multiple_of(4) {
            let _ = host.poll_mot(unsafe { read_volatile(addr_of!(MOT)) });
        }
        if let Some(HostEvent::Key(k)) = host.receive(Ok(unsafe { read_volatile(addr_of!(RX)) })) {
            unsafe { write_volatile(&raw mut KEY, k) };
        }
    };
    if MEASURING {
        for _ in 0..3 {
            stack("Host round: set 46, next_byte, poll_mot, receive", || {
                round(&mut host)
            });
        }
        finish();
    }
    loop {
        round(&mut host);
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    refused()
}
