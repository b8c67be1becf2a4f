//! A probe, not a measurement: firmware whose panic handler calls a function that is declared
//! but defined nowhere, so it links only if no panic path is left in what it calls —
//! `capacity::check`, `max_slaves` and `min_ring` with inputs read at run time (a zero rate or
//! item time among what the compiler must allow for), and a `Master` and `Slave` round. The
//! build whose flash is measured is the probe; the measuring build (feature `measure`) runs the
//! calls under QEMU with an ordinary panic handler.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, finish, refused, stack};
use regler_ring_transfer::capacity::{self, LinkSpec, Load};
use regler_ring_transfer::{Master, Slave, SlaveConfig, SlaveParams, link};

static LOADS: [(u64, u32); 3] = [(2_308, 256), (2_100, 64), (0, 16)];
static ITEM_TIME: u64 = 28;
static LATENCY: u64 = 100;
static LIMIT: usize = usize::MAX;
static ROW: u16 = 200;
static mut OUT: u32 = 0;

#[entry]
fn main() -> ! {
    let mut loads = [Load { t0: 1, ring: 2 }; 3];
    for (load, stored) in loads
        .iter_mut()
        .zip(unsafe { read_volatile(addr_of!(LOADS)) })
    {
        *load = Load {
            t0: stored.0,
            ring: stored.1,
        };
    }
    let link = LinkSpec {
        item_time: unsafe { read_volatile(addr_of!(ITEM_TIME)) },
        latency: unsafe { read_volatile(addr_of!(LATENCY)) },
    };
    let limit = unsafe { read_volatile(addr_of!(LIMIT)) };
    let mut answer = 0u32;
    let verdict = stack("capacity::check (2 slaves)", || {
        capacity::check(&loads[..2], link)
    });
    answer ^= u32::from(verdict.is_ok_and(|v| v.is_schedulable()));
    // The third load has t0 = 0: an error, never a division by zero.
    answer ^= u32::from(capacity::check(&loads, link).is_err()) << 1;
    let most = stack("capacity::max_slaves", || {
        capacity::max_slaves(loads[0], link, limit)
    });
    answer ^= most.map_or(0, |n| n as u32);
    let ring = stack("capacity::min_ring", || {
        capacity::min_ring(&loads[..2], link, 1, u32::MAX)
    });
    answer ^= ring.ok().flatten().unwrap_or(0);

    let config = SlaveConfig {
        address: 1,
        row_len: unsafe { read_volatile(addr_of!(ROW)) },
        silence_limit: 64,
        retry_after: 16,
        boot: 1,
    };
    let Ok(mut slave) = Slave::<64>::new(config) else {
        refused()
    };
    let mut master: Master<2> = Master::new();
    if master
        .attach(
            1,
            SlaveParams {
                capacity: 64,
                t0: 2_308,
            },
        )
        .is_err()
    {
        refused()
    }
    let mut frame = [0u8; link::MAX_FRAME];
    let mut items = [0u8; link::MAX_REFILL];
    for now in 0..1_000u64 {
        if let Some(report) = slave.poll_report()
            && let Ok(n) = report.encode(&mut frame)
            && let Ok(link::Message::Report(r)) = link::decode(&frame[..n])
        {
            let _ = master.on_report(now, 1, &r);
        }
        while let Some(grant) = master.next_refill(now, link::MAX_REFILL as u32) {
            let n = (grant.count as usize).min(items.len());
            for (k, item) in items.iter_mut().take(n).enumerate() {
                *item = (grant.first as u8).wrapping_add(k as u8);
            }
            if let Ok(len) = grant.refill(1, &items[..n]).encode(&mut frame) {
                let _ = slave.on_frame(&frame[..len]);
            }
        }
        answer ^= u32::from(slave.step(|_, col| col as u8).item);
    }
    unsafe { write_volatile(&raw mut OUT, answer) };
    if MEASURING {
        finish();
    }
    loop {
        cortex_m::asm::nop();
    }
}

regler_footprint::no_panic_probe!();
