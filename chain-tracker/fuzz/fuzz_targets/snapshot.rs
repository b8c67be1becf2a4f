//! Arbitrary bytes as a life of the tracker: entries, pulses, advances (up to u32::MAX),
//! recalibrations by small and large steps, counter changes. After every operation the
//! tracker's own snapshot must restore, give the same snapshot back, and the restored tracker
//! must behave exactly like the original for the rest of the input (same events and results).
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_chain_tracker::{DistanceTable, TipperEvent, Tracker};

const N: usize = 16;
const T: usize = 4;
const HOLD: u32 = 6;

type Events = std::vec::Vec<TipperEvent<u16>>;

fn apply(t: &mut Tracker<u16, N, T>, op: u8, arg: u32, trolley: u16) -> (Events, String) {
    let mut events = Events::new();
    let result = match op % 6 {
        0 => format!("{:?}", t.enter(trolley, (arg % 5) as usize)),
        1 => {
            for _ in 0..arg % 64 {
                t.pulse(|e| events.push(e));
            }
            String::new()
        }
        2 => {
            // Mostly small deltas; sometimes anything up to u32::MAX.
            let k = if arg & 0x8000_0000 != 0 { arg } else { arg % 200 };
            t.advance(k, |e| events.push(e));
            String::new()
        }
        3 => {
            let delta = (arg % 25) as i32 - 12;
            let dia = t.table().dia().saturating_add_signed(delta).max(1);
            format!("{:?}", t.recalibrate(dia))
        }
        4 => format!("{:?}", t.recalibrate(arg % 3000 + 1)),
        _ => {
            t.set_now(arg);
            String::new()
        }
    };
    (events, result)
}

fuzz_target!(|data: &[u8]| {
    let Some((&sia_byte, rest)) = data.split_first() else { return };
    let sia = 20 + u32::from(sia_byte) * 8;
    let Ok(table) = DistanceTable::<T>::new(sia, &[0, 7, 50, 400]) else { return };
    let Ok(mut tracker) = Tracker::<u16, N, T>::new(table, HOLD) else { return };
    let mut restored: Option<Tracker<u16, N, T>> = None;
    for (i, chunk) in rest.chunks_exact(5).enumerate() {
        let arg = u32::from_le_bytes([chunk[1], chunk[2], chunk[3], chunk[4]]);
        let want = apply(&mut tracker, chunk[0], arg, i as u16);
        if let Some(r) = restored.as_mut() {
            assert_eq!(apply(r, chunk[0], arg, i as u16), want, "restored tracker differs");
        }
        let snapshot = tracker.snapshot();
        let mut fresh = Tracker::<u16, N, T>::new(table, HOLD).unwrap();
        if let Err(e) = fresh.restore(&snapshot) {
            panic!("own snapshot refused: {e}");
        }
        assert_eq!(fresh.snapshot(), snapshot);
        if chunk[0] & 0x80 != 0 {
            restored = Some(fresh);
        }
    }
});
