//! `Slave<256>`: a knitting-machine board — refill frames in, one byte per needle out, a report
//! after each — and `Master<8>` serving eight boards by earliest deadline.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, finish, refused, stack};
use regler_ring_transfer::{Master, Refill, Slave, SlaveConfig, SlaveParams, link};

static ROW: u16 = 200;
static T0: u32 = 2_308;
static mut OUT: u8 = 0;

#[entry]
fn main() -> ! {
    let row_len = unsafe { read_volatile(addr_of!(ROW)) };
    let t0 = unsafe { read_volatile(addr_of!(T0)) };
    let config = SlaveConfig {
        address: 1,
        row_len,
        silence_limit: 64,
        retry_after: 16,
        boot: 1,
    };
    let Ok(mut slave) = stack("Slave::<256>::new", || Slave::<256>::new(config)) else {
        refused()
    };
    let mut master: Master<8> = Master::new();
    for i in 0..8 {
        if master.attach(i, SlaveParams { capacity: 256, t0 }).is_err() {
            refused()
        }
    }
    let mut frame = [0u8; link::MAX_FRAME];
    let mut items = [0u8; link::MAX_REFILL];
    let mut now = 0u64;
    let mut round = |slave: &mut Slave<256>, master: &mut Master<8>| {
        now = now.wrapping_add(u64::from(t0));
        if let Some(report) = slave.poll_report() {
            let _ = master.on_report(now, 1, &report);
        }
        while let Some(grant) = master.next_refill(now, link::MAX_REFILL as u32) {
            let n = (grant.count as usize).min(items.len());
            for (k, item) in items.iter_mut().take(n).enumerate() {
                *item = (grant.first as u8).wrapping_add(k as u8);
            }
            let refill = grant.refill(1, &items[..n]);
            if let Ok(len) = refill.encode(&mut frame) {
                let _ = slave.on_frame(&frame[..len]);
            }
        }
        let out = slave.step(|_, col| col as u8);
        unsafe { write_volatile(&raw mut OUT, out.item) };
    };
    if MEASURING {
        for _ in 0..3 {
            stack("Slave round: report, EDF, refill frame, step", || {
                round(&mut slave, &mut master)
            });
        }
        let mut buf = [0u8; link::MAX_FRAME];
        let n = Refill {
            slave: 1,
            first: 0,
            items: &[1, 2, 3],
            boot: 1,
            sync: false,
        }
        .encode(&mut buf)
        .unwrap_or(0);
        let _ = stack("Slave::on_frame", || slave.on_frame(&buf[..n]));
        let _ = stack("Slave::step", || slave.step(|_, _| 0));
        finish();
    }
    loop {
        round(&mut slave, &mut master);
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    refused()
}
