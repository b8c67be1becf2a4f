//! Arbitrary bytes as a stored snapshot (a corrupt flash block, a snapshot from another
//! firmware) restored into a tracker, followed by pulses and entries. `restore` must refuse it or
//! give a tracker that keeps its promises: no tipper stays set longer than the hold after its
//! last arrival, every trolley arrives, and no panic.
#![no_main]

use heapless::Vec;
use libfuzzer_sys::fuzz_target;
use regler_chain_tracker::{DistanceTable, HeldTipper, InFlight, Snapshot, TipperEvent, Tracker};

const N: usize = 16;
const T: usize = 4;
const HOLD: u32 = 6;

fn u32_at(data: &[u8], at: usize) -> u32 {
    let mut b = [0u8; 4];
    for (i, byte) in b.iter_mut().enumerate() {
        *byte = data.get(at + i).copied().unwrap_or(0);
    }
    u32::from_le_bytes(b)
}

fuzz_target!(|data: &[u8]| {
    let Ok(table) = DistanceTable::<T>::new(1000, &[5, 40, 300, 2000]) else { return };
    let Ok(mut tracker) = Tracker::<u16, N, T>::new(table, HOLD) else { return };
    // Layout: now, dia, counts, then 6-byte records (tipper, 4 bytes of remaining, spare).
    let now = u32_at(data, 0);
    // DIA near SIA most of the time, anything sometimes.
    let dia = if data.get(4).copied().unwrap_or(0) & 1 == 0 { 990 + u32_at(data, 5) % 20 } else { u32_at(data, 5) };
    let flights = usize::from(data.get(9).copied().unwrap_or(0)) % (N + 1);
    let holds = usize::from(data.get(10).copied().unwrap_or(0)) % (T + 1);
    let mut in_flight = Vec::new();
    let mut held = Vec::new();
    let mut at = 11;
    for k in 0..flights {
        let tipper = usize::from(data.get(at).copied().unwrap_or(0) % 6);
        let remaining = u32_at(data, at + 1) % 4096;
        let _ = in_flight.push(InFlight { trolley: k as u16, tipper, remaining });
        at += 6;
    }
    for _ in 0..holds {
        let tipper = usize::from(data.get(at).copied().unwrap_or(0) % 6);
        let remaining = u32_at(data, at + 1) % 16;
        let _ = held.push(HeldTipper { tipper, remaining });
        at += 6;
    }
    let snapshot: Snapshot<u16, N, T> = Snapshot { now, dia, in_flight, held };
    if tracker.restore(&snapshot).is_err() {
        assert_eq!(tracker.len(), 0, "a refused snapshot changes nothing");
        return;
    }
    let mut last_set = [None::<u32>; T];
    let mut is_set = [false; T];
    for h in &snapshot.held {
        // Restored as set HOLD - remaining pulses ago (restore refused anything above HOLD).
        is_set[h.tipper] = true;
        last_set[h.tipper] = Some(0u32.wrapping_sub(HOLD - h.remaining));
    }
    let commands = data.get(at..).unwrap_or(&[]);
    let mut pulse = 0u32;
    for &c in commands.iter().chain(core::iter::repeat(&0u8).take(5000)) {
        if c & 0x80 != 0 {
            let _ = tracker.enter(u16::from(c), usize::from(c & 3));
            continue;
        }
        pulse += 1;
        tracker.pulse(|e| match e {
            TipperEvent::Set { tipper, .. } => {
                is_set[tipper] = true;
                last_set[tipper] = Some(pulse);
            }
            TipperEvent::Reset { tipper } => is_set[tipper] = false,
        });
        for tipper in 0..T {
            if is_set[tipper] {
                let since = last_set[tipper].map_or(0, |p| pulse.wrapping_sub(p));
                assert!(since <= HOLD, "tipper {tipper} set {since} pulses after its last arrival");
            }
        }
    }
    // 5000 pulses after the last command, more than the farthest tipper at this DIA: the chain
    // is empty and every tipper reset.
    let farthest = tracker.table().distances().iter().copied().max().unwrap_or(0);
    if farthest < 4000 {
        assert!(tracker.is_empty(), "{} trolleys never arrived", tracker.len());
        assert!((0..T).all(|t| !tracker.is_set(t)));
    }
});
