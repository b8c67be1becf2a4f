//! Arbitrary stored retentive state (a corrupt or tampered block, JSON as the examples store it)
//! restored into the executive's parts: the input conditioning, the calendar clock, the IEC
//! timers and counters, the program clock (`set_now_ms`). The first input byte picks the form:
//! even, a valid stored block whose every number, `null` and `bool` the input may replace
//! (values in and far out of range, options filled or emptied); odd, the rest as JSON text.
//!
//! Each part must be refused with an error or restored to a state that behaves
//! (README: "Stored state is checked on the way in"; "A restored TON goes on where it stood — it
//! neither fires at once nor freezes"):
//! - `Conditioning`: every point's debounce count 1..=15, no latched point debounced, no counter
//!   of 15 (it would wrap: the input would wait its count again); it round trips; fed one
//!   reading for 16 cycles each point reads only its stored value or the reading, and the
//!   reading from its k-th cycle on (k its count; a latched point from the second); from then
//!   on it conditions exactly as a fresh `Conditioning` configured with the same latches and
//!   counts (any readings and captures).
//! - `DateTime`: a date `DateTime::new` accepts, with milliseconds 0..=999; advancing keeps it
//!   one.
//! - `Ton`, `Tof`, `Tp`: input off → a TON is off with ET 0; a TON comes on only once it has run
//!   PT in all (the stored elapsed time included) or if it was stored finished; with the input
//!   held, it is on once PT has passed; a TOF is off once PT has passed with the input off; a TP
//!   pulse never outlasts PT after the restore; a finished TON/TOF/TP stays in step with its Q.
//! - The counters count edges from where they stood (saturating).
//! - `set_now_ms(saved)`: the program sees `saved` at the first cycle and counts on by the µs
//!   clock (within the carried rest).
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_scan_cycle::{
    Conditioning, Ctd, Ctu, CycleConfig, DateTime, Executive, Image, Io, Tof, Ton, Tp,
};
use serde_json::{Value, json};

const W: usize = 2;
const POINTS: usize = 16 * W;

/// The input, read a piece at a time; zeros once it runs out.
struct Input<'a>(&'a [u8]);

impl Input<'_> {
    fn byte(&mut self) -> u8 {
        let Some((&b, rest)) = self.0.split_first() else {
            return 0;
        };
        self.0 = rest;
        b
    }
    fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.byte(), self.byte()])
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.byte(), self.byte(), self.byte(), self.byte()])
    }
    fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// A valid stored block: what a firmware would have written.
fn stored_block(variant: u8) -> Value {
    let mut conditioning: Conditioning<W> = Conditioning::new();
    conditioning.set_debounce(3, 7).unwrap();
    conditioning.set_debounce(17, 15).unwrap();
    conditioning.set_latched(9, true).unwrap();
    conditioning.set_latched(30, true).unwrap();
    let mut out = Image::new();
    conditioning.condition(&[0xFFFF, 0x00F0], &mut out);
    conditioning.capture(&[1 << 9, 1 << 14]);
    let mut ton = Ton::new(500);
    let mut tof = Tof::new(300);
    let mut tp = Tp::new(200);
    let mut ctu = Ctu::new(3);
    let mut ctd = Ctd::new(2);
    for (k, now) in [0u32, 120, 260, 410]
        .into_iter()
        .take(usize::from(variant % 4) + 1)
        .enumerate()
    {
        ton.call(true, now);
        tof.call(k == 0, now);
        tp.call(k != 2, now);
        ctu.call(k % 2 == 0, false);
        ctd.call(k % 2 == 1, k == 0);
    }
    if variant & 4 != 0 {
        ton.call(true, 900); // finished
        tp.call(true, 900);
    }
    json!({
        "conditioning": conditioning,
        "clock": DateTime::new(2026, 2, 28, 23, 59, 59).unwrap(),
        "ton": ton,
        "tof": tof,
        "tp": tp,
        "ctu": ctu,
        "ctd": ctd,
        "now_ms": 4_000_000_000u32,
    })
}

/// Replaces leaves of `v` as the input says: numbers in and out of range, `null` filled (an
/// option with a value), options emptied, booleans flipped.
fn mutate(v: &mut Value, key: &str, input: &mut Input) {
    match v {
        Value::Object(map) => {
            for (k, child) in map.iter_mut() {
                mutate(child, k, input);
            }
        }
        Value::Array(items) => {
            for child in items.iter_mut() {
                mutate(child, key, input);
            }
        }
        _ => {
            let ctl = input.byte();
            if ctl & 1 == 0 {
                return; // kept
            }
            *v = match ctl >> 1 & 7 {
                0 => json!(input.byte()),
                1 => json!(input.u16()),
                2 => json!(input.u32()),
                3 => json!(u64::from(input.u32()) << 16 | u64::from(input.u16())),
                4 => json!(-i64::from(input.u16())),
                5 => Value::Null,
                6 if key == "running" => json!({"last_ms": input.u32(), "total_ms": input.u32()}),
                6 => json!(input.byte() & 1 == 1),
                _ => json!(input.u32() % 1000),
            };
        }
    }
}

fn check_conditioning(c: Conditioning<W>, input: &mut Input) {
    for p in 0..POINTS {
        let k = c.debounce(p);
        assert!((1..=15).contains(&k), "point {p} restored with count {k}");
        assert!(
            !c.latched(p) || k == 1,
            "point {p} latched and debounced ({k})"
        );
    }
    let text = serde_json::to_string(&c).unwrap();
    assert_eq!(
        serde_json::from_str::<Conditioning<W>>(&text).unwrap(),
        c,
        "round trip"
    );
    // One reading for 16 cycles: each point reads its stored value or the reading (once a
    // latched pulse is read), and the reading from its k-th cycle on, k its debounce count (a
    // restored input finishes its count within k readings; a latched point, count 1, may first
    // read its stored pulse, then the reading from the second cycle).
    let reading = [input.u16(), input.u16()];
    let mut restored = c;
    let mut out = Image::new();
    let mut first = Image::new();
    for cycle in 0..16 {
        restored.condition(&reading, &mut out);
        if cycle == 0 {
            first = out;
            continue;
        }
        for p in 0..POINTS {
            let want = reading[p / 16] >> (p % 16) & 1 == 1;
            let got = out.get(p);
            let deadline = if c.latched(p) { 2 } else { c.debounce(p) };
            assert!(
                cycle + 1 < usize::from(deadline) || got == want,
                "point {p} (count {}) not the reading after {} cycles",
                c.debounce(p),
                cycle + 1
            );
            if got != want {
                assert!(
                    !c.latched(p),
                    "latched point {p} reads {got} for a steady {want}"
                );
                assert_eq!(got, first.get(p), "point {p} changed, not to the reading");
            }
        }
    }
    for p in 0..POINTS {
        let want = reading[p / 16] >> (p % 16) & 1 == 1;
        assert_eq!(
            out.get(p),
            want,
            "point {p} not the reading after 16 cycles"
        );
    }
    // From here exactly a fresh conditioning with the same setting (settled on the same reading).
    let mut fresh: Conditioning<W> = Conditioning::new();
    for p in 0..POINTS {
        fresh.set_debounce(p, c.debounce(p)).unwrap();
        fresh.set_latched(p, c.latched(p)).unwrap();
    }
    let mut fresh_out = Image::new();
    for _ in 0..16 {
        fresh.condition(&reading, &mut fresh_out);
    }
    assert_eq!(fresh_out, out);
    for _ in 0..64 {
        if input.is_empty() {
            break;
        }
        let op = input.byte();
        let raw = [input.u16(), input.u16()];
        if op & 1 == 1 {
            restored.capture(&raw);
            fresh.capture(&raw);
        } else {
            restored.condition(&raw, &mut out);
            fresh.condition(&raw, &mut fresh_out);
            assert_eq!(
                out, fresh_out,
                "restored conditioning differs from a fresh one"
            );
        }
    }
}

fn check_clock(mut d: DateTime, input: &mut Input) {
    let again = DateTime::new(
        d.year(),
        d.month(),
        d.day(),
        d.hour(),
        d.minute(),
        d.second(),
    );
    assert!(again.is_ok(), "restored {d:?}, which new refuses");
    let text = serde_json::to_string(&d).unwrap();
    assert_eq!(serde_json::from_str::<DateTime>(&text).unwrap(), d);
    for _ in 0..4 {
        // Up to a day at a time: the calendar advances minute by minute.
        d.advance(input.u32() % 86_400_000);
        let text = serde_json::to_string(&d).unwrap();
        assert!(
            serde_json::from_str::<DateTime>(&text).is_ok(),
            "advanced to {d:?}"
        );
    }
}

/// Clock steps and IN, from the input. A step is under 2³¹ − 255 ms: the timers' contract is
/// calls less than 2³¹ ms apart (a longer gap reads as the clock stepping back), and the first
/// step comes after a restart up to 255 ms past the stored time (`restart_clock`). (Steps up to
/// 2³¹ − 1 once broke that contract: a stored TOF whose first call came 2³¹ − 1 + 91 ms after its
/// stored time took it for a step back and stayed on, as documented, where the check counted
/// the off-delay from the first call.)
fn steps(input: &mut Input) -> impl Iterator<Item = (u32, bool)> + use<> {
    let mut v = Vec::new();
    for _ in 0..24 {
        let b = input.byte();
        let step = match b >> 6 {
            0 => u32::from(b & 0x3F),
            1 => u32::from(input.u16()),
            2 => input.u32() % ((1 << 31) - 255),
            _ => 0,
        };
        v.push((step, b & 0x20 == 0));
    }
    v.into_iter()
}

/// The stored `running` of a timer: (last_ms, total_ms).
fn stored_running(stored: &Value) -> Option<(u32, u32)> {
    let r = stored.get("running")?;
    let last = u32::try_from(r.get("last_ms")?.as_u64()?).ok()?;
    let total = u32::try_from(r.get("total_ms")?.as_u64()?).ok()?;
    Some((last, total))
}

/// The program clock at restore: at or after the timer's last call (the firmware restores its
/// clock with `set_now_ms` before the first cycle; a clock behind it would only hold the timer).
fn restart_clock(stored: &Value, input: &mut Input) -> u32 {
    match stored_running(stored) {
        Some((last, _)) => last.wrapping_add(u32::from(input.byte())),
        None => input.u32(),
    }
}

/// Time accumulated as the documentation says: wrapping steps under 2³¹ ms add, others do not.
#[derive(Clone, Copy)]
struct Model {
    last: u32,
    total: u64,
}

impl Model {
    fn advance(&mut self, now: u32) -> u64 {
        let step = now.wrapping_sub(self.last);
        if step < 1 << 31 {
            self.total += u64::from(step);
            self.last = now;
        }
        self.total
    }
}

fn check_ton(stored: Ton, stored_value: &Value, input: &mut Input) {
    let pt = u64::from(stored.pt());
    let was_done = stored_value.get("done_et").is_some_and(|d| !d.is_null());
    let mut model = stored_running(stored_value).map(|(last, total)| Model {
        last,
        total: u64::from(total),
    });
    let mut ton = stored;
    let mut now = restart_clock(stored_value, input);
    let mut fresh = false;
    for (step, held) in steps(input) {
        now = now.wrapping_add(step);
        let q = ton.call(held, now);
        assert_eq!(ton.q(), q);
        if !held {
            assert!(!q && ton.et() == 0, "TON on or timing with IN off");
            fresh = true;
            model = None;
            continue;
        }
        let total = model
            .get_or_insert(Model {
                last: now,
                total: 0,
            })
            .advance(now);
        if q {
            assert!(
                (!fresh && was_done) || total >= pt,
                "TON on after {total} ms of {pt} (stored {stored_value})"
            );
        } else {
            assert!(
                total < pt,
                "TON held on for {total} ms of {pt} is off (stored {stored_value})"
            );
        }
    }
}

fn check_tof(stored: Tof, stored_value: &Value, input: &mut Input) {
    let pt = u64::from(stored.pt());
    let mut tof = stored;
    let mut now = restart_clock(stored_value, input);
    // Time since IN went off (since the restore's first call, for a stored off-delay: the
    // stored time can only make it shorter).
    let mut off: Option<Model> = None;
    for (step, held) in steps(input) {
        now = now.wrapping_add(step);
        let q = tof.call(held, now);
        assert_eq!(tof.q(), q);
        if held {
            assert!(q, "TOF off with IN on");
            off = None;
            continue;
        }
        let off_for = off
            .get_or_insert(Model {
                last: now,
                total: 0,
            })
            .advance(now);
        if off_for >= pt {
            assert!(
                !q,
                "TOF on {off_for} ms of {pt} after IN went off (stored {stored_value})"
            );
        }
    }
}

fn check_tp(stored: Tp, stored_value: &Value, input: &mut Input) {
    let pt = u64::from(stored.pt());
    let mut tp = stored;
    let mut now = restart_clock(stored_value, input);
    // The pulse under way: stored (from its stored time, or from the restore if it has none)
    // or started by a rising edge.
    let mut pulse: Option<Model> = stored_running(stored_value)
        .map(|(last, total)| Model {
            last,
            total: u64::from(total),
        })
        .or(Some(Model {
            last: now,
            total: 0,
        }));
    let mut prev_in = stored_value
        .get("prev_in")
        .and_then(Value::as_bool)
        .unwrap_or(false);
    for (step, held) in steps(input) {
        now = now.wrapping_add(step);
        let was_q = tp.q();
        let q = tp.call(held, now);
        assert_eq!(tp.q(), q);
        if held && !prev_in && !was_q {
            pulse = Some(Model {
                last: now,
                total: 0,
            });
        }
        prev_in = held;
        if q {
            let length = pulse.as_mut().map_or(u64::MAX, |p| p.advance(now));
            assert!(
                length < pt,
                "TP pulse {length} ms long, PT {pt} (stored {stored_value})"
            );
        } else {
            pulse = None;
        }
    }
}

struct Clock(u32);

impl Io<1, 1> for Clock {
    fn read_inputs(&mut self, raw: &mut [u16; 1]) {
        *raw = [0];
    }
    fn write_outputs(&mut self, _: &[u16; 1]) {}
    fn now_us(&mut self) -> u32 {
        self.0
    }
}

fn check_now(saved: u32, input: &mut Input) {
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    plc.set_now_ms(saved);
    let mut io = Clock(input.u32());
    let mut seen = None;
    plc.cycle(&mut io, |s| seen = Some(s.now_ms)).unwrap();
    assert_eq!(seen, Some(saved), "the first cycle sees the stored clock");
    let mut total_us = 0u64;
    for _ in 0..16 {
        let step = input.u32() % (1 << 31);
        io.0 = io.0.wrapping_add(step);
        total_us += u64::from(step);
        plc.cycle(&mut io, |_| {}).unwrap();
        let counted = u64::from(plc.now_ms().wrapping_sub(saved));
        assert_eq!(
            counted,
            total_us / 1000,
            "program clock after {total_us} µs from {saved}"
        );
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let mut input = Input(rest);
    let block = if mode & 1 == 0 {
        let mut block = stored_block(mode >> 1);
        mutate(&mut block, "", &mut input);
        block
    } else {
        // JSON text up to a NUL byte; what follows drives the checks.
        let end = rest.iter().position(|&b| b == 0).unwrap_or(rest.len());
        input = Input(rest.get(end + 1..).unwrap_or(&[]));
        match serde_json::from_slice::<Value>(&rest[..end]) {
            Ok(v) => v,
            Err(_) => return,
        }
    };
    let part = |name: &str| block.get(name).cloned().unwrap_or(Value::Null);
    if let Ok(c) = serde_json::from_value::<Conditioning<W>>(part("conditioning")) {
        check_conditioning(c, &mut input);
    }
    if let Ok(d) = serde_json::from_value::<DateTime>(part("clock")) {
        check_clock(d, &mut input);
    }
    if let Ok(t) = serde_json::from_value::<Ton>(part("ton")) {
        check_ton(t, &part("ton"), &mut input);
    }
    if let Ok(t) = serde_json::from_value::<Tof>(part("tof")) {
        check_tof(t, &part("tof"), &mut input);
    }
    if let Ok(t) = serde_json::from_value::<Tp>(part("tp")) {
        check_tp(t, &part("tp"), &mut input);
    }
    if let Ok(mut c) = serde_json::from_value::<Ctu>(part("ctu")) {
        let cv = c.cv();
        c.call(false, false);
        assert_eq!(c.cv(), cv, "no edge, no count");
        c.call(true, false);
        assert_eq!(c.cv(), cv.saturating_add(1), "an edge counts one");
        assert_eq!(
            c.q(),
            c.cv() >= serde_json::from_value::<i32>(part("ctu")["pv"].clone()).unwrap_or(0)
        );
    }
    if let Ok(mut c) = serde_json::from_value::<Ctd>(part("ctd")) {
        let cv = c.cv();
        c.call(false, false);
        assert_eq!(c.cv(), cv, "no edge, no count");
        let q = c.call(true, false);
        assert_eq!(c.cv(), cv.saturating_sub(1), "an edge counts one down");
        assert_eq!(q, c.cv() <= 0);
    }
    if let Some(saved) = part("now_ms").as_u64().and_then(|n| u32::try_from(n).ok()) {
        check_now(saved, &mut input);
    }
});
