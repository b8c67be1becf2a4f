//! A probe, not a measurement: firmware whose panic handler calls a function that is declared
//! but defined nowhere, so it links only if no panic path is left in what it calls —
//! `ReaderHealth::new` with limits read at run time, `ReaderHealth::record` with passages voted
//! from readings read at run time (so the window's ring wraps at a place the compiler cannot
//! see), `reset`, and the voter; `decode`, `encode`, `TrolleyId::new`/`try_from` on run-time
//! words, a `Registry<u16>` (assign, release, destination, route, iter, clear, len) on run-time
//! numbers, a `Voter` of every strategy with run-time parameters (0 and 255 among them), and
//! the `Display` of every error. The measuring build (feature `measure`) runs the calls under
//! QEMU with an ordinary panic handler.
#![no_std]
#![no_main]

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, at, finish, keep, refused, shown, stack};
use regler_trolley_id::{
    AlarmLimits, ReaderHealth, Registry, Route, Strategy, TrolleyId, Verdict, Voter, decode, encode,
};

static READINGS: [u16; 5] = [0x04D2, 0x04D2, 0x04D0, 0, 0x0001];
static LIMITS: [u32; 3] = [5, 10, 37];
static PASSAGES: u32 = 1_000;
static mut OUT: u32 = 0;
/// Raw words as a reader or an operator's keyboard would give them (any `u16`).
static WORDS: [u16; 8] = [0, 1, 4095, 4096, 0x1FFF, 0x2000, 0xFFFF, 0x0A5A];
/// Strategy parameters as stored (0 is refused, 255 the largest).
static PARAMS: [u8; 4] = [0, 1, 3, 255];

/// `decode`, `encode`, `TrolleyId`, `Registry` and every `Voter` strategy on run-time words.
fn codes_registry_and_voters() -> u32 {
    let mut answer = 0u32;
    let mut registry: Registry<u16> = Registry::new();
    for i in 0..64usize {
        let raw = at(&WORDS, i)
            .wrapping_add(i as u16)
            .wrapping_mul(at(&WORDS, i / 8));
        match decode(raw) {
            Ok(id) => {
                answer ^= u32::from(encode(id)) ^ u32::from(id.get()) ^ shown(&id);
                let _ = registry.assign(id, raw);
            }
            Err(e) => answer ^= shown(&e),
        }
        match TrolleyId::try_from(raw) {
            Ok(id) => answer ^= u32::from(u16::from(id)),
            Err(e) => answer ^= shown(&e),
        }
        if let Some(id) = TrolleyId::new(raw) {
            answer ^= u32::from(registry.destination(id).copied().unwrap_or(0));
            if raw & 1 == 0 {
                answer ^= u32::from(registry.release(id).unwrap_or(0));
            }
            let route = registry.route(&Verdict::Identified(id), |d| *d & 2 == 0);
            answer ^= match route {
                Route::Deliver { destination, .. } => u32::from(destination),
                Route::Reject(why) => shown(&why),
            };
        }
    }
    for (id, d) in registry.iter() {
        answer = answer.rotate_left(1) ^ u32::from(id.get()) ^ u32::from(*d);
    }
    answer ^= registry.len() as u32 ^ u32::from(registry.is_empty());
    registry.clear();
    answer ^= u32::from(registry.is_empty());
    for p in 0..4usize {
        let n = at(&PARAMS, p);
        for strategy in [
            Strategy::Consecutive { k: n },
            Strategy::Majority { min_samples: n },
        ] {
            match Voter::new(strategy) {
                Err(e) => answer ^= shown(&e),
                Ok(mut voter) => {
                    for i in 0..(40 + p) {
                        voter.sample(at(&WORDS, i.wrapping_mul(p + 3)));
                    }
                    answer ^= u32::from(voter.samples());
                    let verdict = voter.verdict();
                    answer ^= verdict.trolley().map_or(0, |t| u32::from(t.get()));
                    if let Verdict::NoRead(why) = verdict {
                        answer ^= shown(&why);
                    }
                    let _ = voter.strategy();
                    let passage = voter.finish();
                    let route = registry.route(&passage.verdict, |_| true);
                    answer ^= u32::from(matches!(route, Route::Reject(_)));
                    let mut words = [0u16; 4];
                    for (k, w) in words.iter_mut().enumerate() {
                        *w = at(&WORDS, k + p);
                    }
                    let again = voter.vote(&words[..=p]);
                    answer ^= u32::from(again.samples) ^ u32::from(again.disagreement);
                }
            }
        }
    }
    answer
}

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
    let window = health.window();
    answer ^= window.per_mille(answer) ^ shown(&window) ^ health.totals().passages;
    answer ^= u32::from(health.alarm()) ^ health.limits().min_passages;
    answer ^= codes_registry_and_voters();
    keep(answer);
    unsafe { write_volatile(&raw mut OUT, answer) };
    if MEASURING {
        finish();
    }
    loop {
        cortex_m::asm::nop();
    }
}

regler_footprint::no_panic_probe!();
