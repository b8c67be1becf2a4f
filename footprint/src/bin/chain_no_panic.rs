//! A probe, not a measurement: firmware whose panic handler calls a function that is declared
//! but defined nowhere, so it links only if no panic path is left in `Tracker::{new, enter,
//! pulse, advance, recalibrate, restore, snapshot_into, set_now}`, `StretchMeter::{with_dia,
//! measure, reconcile, start, pulse, end}`, `start_up` and `ReaderHealth::record`, all with
//! values read at run time (from an independent review, issue 24). The measuring build (feature
//! `measure`) runs the calls under QEMU with an ordinary panic handler.
#![no_std]
#![no_main]

use core::hint::black_box;
use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_chain_tracker::{
    DistanceTable, HeldTipper, InFlight, Snapshot, StretchConfig, StretchMeter, TipperEvent,
    Tracker, start_up,
};
use regler_footprint::{MEASURING, finish, refused};
use regler_trolley_id::{AlarmLimits, ReaderHealth, Strategy, Voter};

static INPUT: [u32; 16] = [
    3000,
    1000,
    2500,
    4000,
    6,
    2985,
    7,
    1,
    0xFFFF_FFFF,
    3,
    2,
    5,
    9,
    11,
    13,
    17,
];
/// Rounds of the loop (bounded, so the measuring build ends under QEMU).
static ROUNDS: u32 = 1_000;
static mut OUT: u32 = 0;
static mut SNAP: Snapshot<u16, 64, 8> = Snapshot::new();
static mut SNAP2: Snapshot<u16, 64, 8> = Snapshot::new();

fn inp(i: usize) -> u32 {
    unsafe { read_volatile(addr_of!(INPUT).cast::<u32>().add(i % 16)) }
}

#[entry]
fn main() -> ! {
    let sa = [inp(1), inp(2), inp(3), inp(9), inp(10), inp(11)];
    let n = (inp(13) as usize) % 7;
    let Ok(table) = DistanceTable::<8>::new(inp(0), black_box(&sa[..n])) else {
        refused()
    };
    let Ok(mut tr) = Tracker::<u16, 64, 8>::new(table, inp(4)) else {
        refused()
    };
    let mut tr2 = tr.clone();
    let mut cfg = StretchConfig::new(inp(0));
    cfg.confirmations = inp(7) as u8;
    cfg.plausible_per_mille = inp(12);
    cfg.alarm_per_mille = inp(14);
    let Ok(meter) = StretchMeter::with_dia(cfg, inp(5)) else {
        refused()
    };
    let limits = AlarmLimits {
        no_read_per_mille: inp(5),
        disagreement_per_mille: inp(6),
        min_passages: inp(7),
    };
    let Ok(mut health) = ReaderHealth::<37>::new(limits) else {
        refused()
    };
    let Ok(mut voter) = Voter::new(Strategy::Majority { min_samples: 3 }) else {
        refused()
    };
    let mut acc = 0u32;
    let mut ev = |e: TipperEvent<u16>| unsafe {
        let o = read_volatile(&raw const OUT);
        write_volatile(
            &raw mut OUT,
            o.wrapping_add(match e {
                TipperEvent::Set { tipper, trolley } => tipper as u32 ^ u32::from(trolley),
                TipperEvent::Reset { tipper } => tipper as u32,
            }),
        );
    };
    // Start-up from a stored snapshot and meter whose values the compiler cannot see.
    let stored = unsafe { &*addr_of!(SNAP2) };
    let Ok((mut meter, _)) = start_up(&mut tr2, Some(stored), Some(meter.clone()), cfg) else {
        refused()
    };
    let rounds = unsafe { read_volatile(addr_of!(ROUNDS)) };
    for i in 0..rounds as usize {
        let _ = tr.enter(inp(i) as u16, inp(i + 1) as usize);
        tr.pulse(&mut ev);
        tr.advance(inp(i + 2), &mut ev);
        let _ = tr.recalibrate(inp(i + 3));
        tr.set_now(inp(i + 4));
        if let regler_chain_tracker::Measurement::Accepted { dia } = meter.measure(inp(i + 5)) {
            let _ = tr.recalibrate(dia);
        }
        meter.start();
        meter.pulse();
        let _ = meter.end();
        let _ = meter.reconcile(inp(i + 6));
        unsafe {
            let s = &mut *addr_of!(SNAP).cast_mut();
            tr.snapshot_into(s);
            let _ = tr2.restore(s);
            let s2 = &mut *addr_of!(SNAP2).cast_mut();
            s2.now = inp(i + 7);
            s2.dia = inp(i + 8);
            s2.in_flight.clear();
            s2.held.clear();
            let _ = s2.in_flight.push(InFlight {
                trolley: inp(i + 9) as u16,
                tipper: inp(i + 10) as usize,
                remaining: inp(i + 11),
            });
            let _ = s2.held.push(HeldTipper {
                tipper: inp(i + 12) as usize,
                remaining: inp(i + 13),
            });
            let _ = tr2.restore(s2);
        }
        tr2.advance(inp(i + 14), &mut ev);
        for j in 0..3 {
            voter.sample(inp(i + j) as u16);
        }
        let p = voter.finish();
        if health.record(&p).is_some() {
            acc ^= 1;
        }
    }
    acc ^= tr.len() as u32 ^ tr2.now() ^ meter.dia() ^ health.window().no_reads;
    unsafe { write_volatile(&raw mut OUT, acc) };
    if MEASURING {
        finish();
    }
    loop {
        cortex_m::asm::nop();
    }
}

regler_footprint::no_panic_probe!();
