//! A probe, not a measurement: firmware whose panic handler calls a function that is declared
//! but defined nowhere, so it links only if no panic path is left in what it calls —
//! `capacity::check`, `max_slaves` and `min_ring` with inputs read at run time (a zero rate or
//! item time among what the compiler must allow for), and a `Master` and `Slave` round; and every
//! public operation on run-time values: `Ring` of 1, 2 and 16 items (every method, full and
//! empty), `SharedRing::split` and both halves, the link (`decode` of arbitrary stored bytes
//! and lengths, `Report::encode` and `Refill::encode` into buffers of run-time length,
//! `Refill::keep_alive`, `crc16`, `newer_boot`), a `Master<2>` at run-time slave numbers
//! (attach, detach, reinit, on_report, next_refill, earliest, status, attached, `Grant`'s
//! methods), a `Slave` of 1 and 2 items from a run-time configuration fed arbitrary frames
//! (on_frame, step, poll_report, report and every read-out), and every error's `Display`. The
//! build whose flash is measured is the probe; the measuring build (feature `measure`) runs the
//! calls under QEMU with an ordinary panic handler.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, at, finish, keep, refused, shown, stack};
use regler_ring_transfer::capacity::{self, LinkSpec, Load};
use regler_ring_transfer::{
    Master, Message, Refill, Report, Ring, SharedRing, Slave, SlaveConfig, SlaveParams, link,
};

static LOADS: [(u64, u32); 3] = [(2_308, 256), (2_100, 64), (0, 16)];
static ITEM_TIME: u64 = 28;
static LATENCY: u64 = 100;
static LIMIT: usize = usize::MAX;
static ROW: u16 = 200;
static mut OUT: u32 = 0;

/// Bytes as a line would deliver them (any `u8`).
static BYTES: [u8; 16] = [
    0x00, 0x01, 0x7F, 0x80, 0xFF, 0x7E, 0x7D, 0x02, 0x10, 0xC1, 0x55, 0xAA, 0x03, 0x40, 0x20, 0xFE,
];
/// Numbers as stored state or a peer would give them (0 and the maxima among them).
static WORDS: [u32; 8] = [0, 1, 2, 3, 64, 1000, 0xFFFF, u32::MAX];

fn byte(i: usize) -> u8 {
    at(&BYTES, i)
}

fn word(i: usize) -> u32 {
    at(&WORDS, i)
}

/// Every method of a `Ring<u8, N>`, filled past full and drained past empty.
fn rings<const N: usize>(seed: usize) -> u32 {
    let mut ring: Ring<u8, N> = Ring::new();
    let mut answer = ring.capacity() as u32;
    for i in 0..(3 * N + 5) {
        if !word(i + seed).is_multiple_of(3) {
            answer ^= u32::from(ring.receive(byte(i)).is_err());
        } else {
            answer ^= u32::from(ring.next().unwrap_or(0));
        }
        answer ^= ring.requests() as u32 ^ ring.slack() as u32 ^ ring.len() as u32;
        answer ^= u32::from(ring.is_empty()) ^ u32::from(ring.is_full());
        answer ^= ring.deadline(word(i)) as u32;
        let stats = ring.stats();
        let counters = ring.counters();
        keep(core::hint::black_box(&stats as *const _ as u32));
        keep(core::hint::black_box(&counters as *const _ as u32));
        if word(i) == 1000 {
            ring.reset_stats();
        }
        if word(i) == 0xFFFF {
            ring.clear();
        }
    }
    while let Some(b) = ring.next() {
        answer ^= u32::from(b);
    }
    answer ^ ring.next().map_or(7, u32::from)
}

/// The split halves of a shared ring, filled past full and drained past empty.
fn split() -> u32 {
    let mut shared: SharedRing<u8, 4> = SharedRing::new();
    let mut answer = shared.capacity() as u32;
    let (mut filler, mut drainer) = shared.split();
    for i in 0..40usize {
        if !word(i).is_multiple_of(3) {
            answer ^= u32::from(filler.receive(byte(i)).is_err());
        } else {
            answer ^= u32::from(drainer.next().unwrap_or(0));
        }
        answer ^= filler.requests() as u32 ^ filler.slack() as u32;
        let counters = filler.counters();
        let stats = filler.stats();
        keep(core::hint::black_box(&counters as *const _ as u32));
        keep(core::hint::black_box(&stats as *const _ as u32));
        answer ^= drainer.underruns() ^ drainer.consumed();
    }
    answer
}

/// The link's frames from arbitrary stored bytes, and encoding into buffers of any length.
fn frames() -> u32 {
    let mut answer = 0u32;
    let mut input = [0u8; link::MAX_FRAME + 2];
    let mut out = [0u8; link::MAX_FRAME + 2];
    for i in 0..100usize {
        for (k, b) in input.iter_mut().enumerate() {
            *b = byte(i.wrapping_mul(k + 3) ^ k);
        }
        let n = word(i) as usize % (input.len() + 1);
        match link::decode(&input[..n]) {
            Ok(Message::Report(r)) => answer ^= u32::from(r.consumed) ^ u32::from(r.hello),
            Ok(Message::Refill(r)) => answer ^= r.items.len() as u32 ^ u32::from(r.first),
            Err(e) => answer ^= shown(&e),
        }
        answer ^= u32::from(link::crc16(&input[..n]));
        answer ^= u32::from(link::newer_boot(byte(i), byte(i + 1)));
        let report = Report {
            slave: byte(i),
            consumed: word(i) as u16,
            received: word(i + 1) as u16,
            standalone: i.is_multiple_of(2),
            retry: i.is_multiple_of(3),
            boot: byte(i + 2),
            hello: i.is_multiple_of(5),
        };
        let len = (word(i + 2) as usize).min(out.len());
        match report.encode(&mut out[..len]) {
            Ok(k) => answer ^= k as u32 ^ u32::from(link::decode(&out[..k.min(len)]).is_ok()),
            Err(e) => answer ^= shown(&e),
        }
        let items = &input[..(word(i + 3) as usize).min(input.len())];
        let refill = if i.is_multiple_of(7) {
            Refill::keep_alive(byte(i))
        } else {
            Refill {
                slave: byte(i),
                first: word(i) as u16,
                items,
                boot: byte(i + 1),
                sync: i % 2 == 1,
            }
        };
        match refill.encode(&mut out[..len]) {
            Ok(k) => answer ^= k as u32,
            Err(e) => answer ^= shown(&e),
        }
    }
    answer
}

/// A master at run-time slave numbers and a slave of `N` items fed arbitrary frames.
fn master_and_slave<const N: usize>(seed: usize) -> u32 {
    let mut answer = 0u32;
    let mut master: Master<2> = Master::new();
    let config = SlaveConfig {
        address: byte(seed),
        row_len: word(seed + 1) as u16,
        silence_limit: word(seed + 2),
        retry_after: word(seed + 3),
        boot: byte(seed + 4),
    };
    let mut slave = match Slave::<N>::new(config) {
        Ok(s) => s,
        Err(e) => {
            answer ^= shown(&e);
            let sane = SlaveConfig {
                address: 1,
                row_len: 8,
                silence_limit: 64,
                retry_after: 16,
                boot: 1,
            };
            match Slave::<N>::new(sane) {
                Ok(s) => s,
                Err(e) => return answer ^ shown(&e),
            }
        }
    };
    let mut frame = [0u8; link::MAX_FRAME];
    let mut items = [0u8; link::MAX_REFILL];
    for i in 0..200usize {
        let now = u64::from(word(i)).wrapping_add(i as u64);
        let who = word(i + seed) as usize;
        match i % 11 {
            0 => {
                let params = SlaveParams {
                    capacity: word(i + 1) as u16,
                    t0: word(i + 2),
                };
                if let Err(e) = master.attach(who, params) {
                    answer ^= shown(&e);
                }
            }
            1 if word(i) == 2 => answer ^= u32::from(master.detach(who).is_err()),
            2 if word(i) == 3 => answer ^= u32::from(master.reinit(who).is_err()),
            _ => {}
        }
        if let Some(report) = slave.poll_report()
            && let Ok(n) = report.encode(&mut frame)
            && let Ok(Message::Report(r)) = link::decode(&frame[..n])
        {
            match master.on_report(now, who, &r) {
                Ok(outcome) => keep(core::hint::black_box(&outcome as *const _ as u32)),
                Err(e) => answer ^= shown(&e),
            }
        }
        let report = slave.report(i.is_multiple_of(2));
        let _ = master.on_report(now, who & 1, &report);
        if let Some(grant) = master.next_refill(now, word(i + 1)) {
            let n = (grant.count as usize).min(items.len());
            for (k, item) in items.iter_mut().take(n).enumerate() {
                *item = byte(k + i);
            }
            answer ^= u32::from(grant.first_wire());
            if let Ok(len) = grant.refill(byte(i), &items[..n]).encode(&mut frame) {
                let len = len ^ usize::from(byte(i) == 0x10);
                match slave.on_frame(&frame[..len.min(frame.len())]) {
                    Ok(k) => answer ^= k as u32,
                    Err(e) => answer ^= shown(&e),
                }
            }
        }
        // An arbitrary frame from the line.
        let n = word(i + 5) as usize % (frame.len() + 1);
        for (k, b) in frame.iter_mut().take(n).enumerate() {
            *b = byte(k ^ i);
        }
        if let Err(e) = slave.on_frame(&frame[..n]) {
            answer ^= shown(&e);
        }
        let out = slave.step(|row, col| byte(row as usize ^ usize::from(col)));
        answer ^= u32::from(out.item) ^ out.row ^ u32::from(out.col);
        answer ^= u32::from(slave.boot()) ^ u32::from(slave.placed());
        answer ^= u32::from(slave.mode() == slave.mode()) ^ slave.position().0;
        answer ^= slave.slack() as u32 ^ slave.requests() as u32;
        let stats = slave.stats();
        keep(core::hint::black_box(&stats as *const _ as u32));
        answer ^= u32::from(slave.config().row_len);
        answer ^= master.earliest().map_or(0, |(s, t)| s as u32 ^ t as u32);
        match master.status(who) {
            Ok(status) => keep(core::hint::black_box(&status as *const _ as u32)),
            Err(e) => answer ^= shown(&e),
        }
        answer ^= master.attached() as u32;
    }
    answer
}

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
    if let Err(e) = capacity::check(&loads, link) {
        answer ^= shown(&e) << 1;
    }
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
            && let Some(bytes) = frame.get(..n)
            && let Ok(link::Message::Report(r)) = link::decode(bytes)
        {
            let _ = master.on_report(now, 1, &r);
        }
        while let Some(grant) = master.next_refill(now, link::MAX_REFILL as u32) {
            let n = (grant.count as usize).min(items.len());
            for (k, item) in items.iter_mut().take(n).enumerate() {
                *item = (grant.first as u8).wrapping_add(k as u8);
            }
            // The length `encode` returns is at most the buffer's, but the probe cannot rely
            // on the optimiser seeing that through a call: `get`, not an index.
            if let Ok(len) = grant.refill(1, &items[..n]).encode(&mut frame)
                && let Some(bytes) = frame.get(..len)
            {
                let _ = slave.on_frame(bytes);
            }
        }
        answer ^= u32::from(slave.step(|_, col| col as u8).item);
    }
    answer ^= rings::<1>(0) ^ rings::<2>(1) ^ rings::<16>(2);
    answer ^= split() ^ frames();
    answer ^= master_and_slave::<1>(0) ^ master_and_slave::<2>(3);
    unsafe { write_volatile(&raw mut OUT, answer) };
    if MEASURING {
        finish();
    }
    loop {
        cortex_m::asm::nop();
    }
}

regler_footprint::no_panic_probe!();
