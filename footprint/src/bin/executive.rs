//! `Executive<34, 15>` (the 1977 plant's 544 inputs and 240 outputs) running a small program with
//! a TON and a debounced input, with forcing: one scan cycle.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, finish, refused, stack};
use regler_scan_cycle::{CycleConfig, Executive, Io, Ton};

static mut INPUTS: [u16; 34] = [0; 34];
static mut OUTPUTS: [u16; 15] = [0; 15];
static mut CLOCK_US: u32 = 0;

struct Hardware;

impl Io<34, 15> for Hardware {
    fn read_inputs(&mut self, raw: &mut [u16; 34]) {
        *raw = unsafe { read_volatile(addr_of!(INPUTS)) };
    }
    fn write_outputs(&mut self, out: &[u16; 15]) {
        unsafe { write_volatile(&raw mut OUTPUTS, *out) };
    }
    fn now_us(&mut self) -> u32 {
        unsafe { read_volatile(addr_of!(CLOCK_US)) }
    }
}

#[entry]
fn main() -> ! {
    let mut plc = stack("Executive::<34, 15>::new", || {
        Executive::<34, 15>::new(CycleConfig::source())
    });
    if plc.conditioning_mut().set_debounce(3, 4).is_err() || plc.force_output(7, true).is_err() {
        refused();
    }
    let mut jam = Ton::new(500);
    let mut cycle = |plc: &mut Executive<34, 15>| {
        let _ = plc.cycle(&mut Hardware, |scan| {
            let stuck = jam.call(scan.inputs.get(3), scan.now_ms);
            let _ = scan.outputs.set(0, stuck);
            let _ = scan.outputs.set(1, !scan.inputs.get(4));
        });
    };
    // Measured three times (the first call may differ); only in the measuring build.
    if MEASURING {
        for _ in 0..3 {
            stack("Executive::cycle", || cycle(&mut plc));
        }
    }
    if MEASURING {
        finish();
    }
    loop {
        cycle(&mut plc);
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    refused()
}
