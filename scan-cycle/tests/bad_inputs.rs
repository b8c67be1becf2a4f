//! Bad inputs (issue 22 §5): every public constructor and operation of `regler-scan-cycle` fed
//! the extremes — times 0, 1, `u32::MAX` and across the wrap, a clock stepping back by exactly
//! 2³¹, presets 0 and MAX, counters at `i32::MAX`/`i32::MIN`, points and words one past the end,
//! capacities 1, 2 and 3, stale timer handles, dates at their limits, and corrupt snapshots —
//! with the exact error or documented result.
//!
//! Each test is a table: one row per (operation, extreme input, expected outcome).
#![allow(
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    clippy::type_complexity,
    reason = "a test may panic: that is how it fails"
)]

use regler_scan_cycle::{
    AddError, Breakpoint, BreakpointError, Conditioning, Ctd, Ctu, Ctud, CycleConfig, CycleStats,
    DateTime, DebounceError, Executive, FTrig, Forcing, Halt, Image, InvalidDateTime, Io,
    MinuteTable, PointError, RTrig, Rs, Signals, Spool, Sr, Start, StepChain, TimerQueue, Tof, Ton,
    Tp, Weekdays, WordError,
};

const HALF: u32 = 1 << 31;

#[derive(Clone, Copy, Debug)]
enum Timer {
    Ton,
    Tof,
    Tp,
}

/// Runs a timer of preset `pt` over `(IN, now_ms)` calls; returns Q of each call and ET after.
fn run(kind: Timer, pt: u32, calls: &[(bool, u32)]) -> (Vec<bool>, u32) {
    match kind {
        Timer::Ton => {
            let mut t = Ton::new(pt);
            let q = calls.iter().map(|&(i, now)| t.call(i, now)).collect();
            (q, t.et())
        }
        Timer::Tof => {
            let mut t = Tof::new(pt);
            let q = calls.iter().map(|&(i, now)| t.call(i, now)).collect();
            (q, t.et())
        }
        Timer::Tp => {
            let mut t = Tp::new(pt);
            let q = calls.iter().map(|&(i, now)| t.call(i, now)).collect();
            (q, t.et())
        }
    }
}

/// The IEC timers at PT 0 and `u32::MAX`, across the clock's wrap, and with the clock stepping
/// back by 2³¹ − 1 (time passes) and by exactly 2³¹ (no time passes).
#[test]
#[rustfmt::skip]
fn timers_at_the_extremes() {
    use Timer::*;
    let m = u32::MAX;
    // (what, timer, PT, calls (IN, now_ms), Q of each call, ET after)
    let rows: Vec<(&str, Timer, u32, Vec<(bool, u32)>, Vec<bool>, u32)> = vec![
        ("TON PT 0: on at once", Ton, 0, vec![(true, 7)], vec![true], 0),
        ("TON PT 0, IN off", Ton, 0, vec![(false, 7)], vec![false], 0),
        ("TON PT 1", Ton, 1, vec![(true, 0), (true, 0), (true, 1)], vec![false, false, true], 1),
        ("TON across the wrap", Ton, 20, vec![(true, m - 9), (true, 9), (true, 10)], vec![false, false, true], 20),
        ("TON PT MAX, time saturates at MAX", Ton, m, vec![(true, 0), (true, HALF - 1), (true, m - 1), (true, 0)], vec![false, false, false, true], m),
        ("TON step of 2^31 - 1 counts", Ton, HALF - 1, vec![(true, 5), (true, 5 + HALF - 1)], vec![false, true], HALF - 1),
        ("TON step of exactly 2^31 is the clock going back", Ton, 10, vec![(true, 5), (true, 5 + HALF)], vec![false, false], 0),
        ("TON clock back, then caught up", Ton, 100, vec![(true, 1000), (true, 500), (true, 1099), (true, 1100)], vec![false, false, false, true], 100),
        ("TON IN off resets", Ton, 10, vec![(true, 0), (true, 10), (false, 11), (true, 12)], vec![false, true, false, false], 0),
        ("TOF PT 0: off at once", Tof, 0, vec![(true, 0), (false, 0)], vec![true, false], 0),
        ("TOF never on: off", Tof, 0, vec![(false, 0), (false, m)], vec![false, false], 0),
        ("TOF across the wrap", Tof, 20, vec![(true, m - 5), (false, m - 5), (false, 13), (false, 14)], vec![true, true, true, false], 20),
        ("TOF PT MAX", Tof, m, vec![(true, 0), (false, 0), (false, HALF - 1), (false, m - 1), (false, 0)], vec![true, true, true, true, false], m),
        ("TOF step of exactly 2^31: no time", Tof, 10, vec![(true, 0), (false, 0), (false, HALF)], vec![true, true, true], 0),
        ("TP PT 0: no pulse", Tp, 0, vec![(true, 0), (true, 1), (false, 2)], vec![false, false, false], 0),
        ("TP PT 1", Tp, 1, vec![(true, 0), (false, 0), (false, 1)], vec![true, true, false], 0),
        ("TP across the wrap", Tp, 20, vec![(true, m - 9), (false, 9), (false, 10)], vec![true, true, false], 0),
        ("TP PT MAX", Tp, m, vec![(true, 0), (true, HALF - 1), (true, m - 1), (true, 0)], vec![true, true, true, false], m),
        ("TP step of exactly 2^31: the pulse runs on", Tp, 10, vec![(true, 0), (true, HALF)], vec![true, true], 0),
        ("TP no retrigger while IN stays on", Tp, 5, vec![(true, 0), (true, 5), (true, 100)], vec![true, false, false], 5),
    ];
    for (what, kind, pt, calls, q, et) in rows {
        assert_eq!(run(kind, pt, &calls), (q, et), "{what}");
    }
    // A PT change to 0 or MAX takes effect at the next call; a finished timer stays finished.
    let mut t = regler_scan_cycle::Ton::new(100);
    t.call(true, 0);
    t.set_pt(0);
    assert!(t.call(true, 0), "TON set_pt(0) while timing: on at the next call");
    t.set_pt(u32::MAX);
    assert!(t.call(true, 1), "TON finished stays finished after set_pt(MAX)");
    assert_eq!((t.q(), t.pt()), (true, u32::MAX));
}

/// Counters restored at `i32::MAX` and `i32::MIN` (any stored CV is a state calls reach)
/// saturate; PV at the extremes.
#[cfg(feature = "serde")]
#[test]
#[rustfmt::skip]
fn restored_counters_at_their_ends() {
    fn with_cv<T: serde::Serialize + serde::de::DeserializeOwned>(c: T, cv: i32) -> T {
        let mut v = serde_json::to_value(c).unwrap();
        v["cv"] = serde_json::json!(cv);
        serde_json::from_value(v).unwrap()
    }
    let (max, min) = (i32::MAX, i32::MIN);
    // (what, counter, CU, reset, CV after, Q)
    let up: [(&str, Ctu, bool, bool, i32, bool); 6] = [
        ("CTU at MAX saturates", with_cv(Ctu::new(max), max), true, false, max, true),
        ("CTU at MAX - 1 reaches MAX", with_cv(Ctu::new(max), max - 1), true, false, max, true),
        ("CTU at MIN counts up", with_cv(Ctu::new(0), min), true, false, min + 1, false),
        ("CTU reset from MAX", with_cv(Ctu::new(1), max), true, true, 0, false),
        ("CTU PV MIN: Q from the start", Ctu::new(min), false, false, 0, true),
        ("CTU PV 0: Q at 0", Ctu::new(0), false, false, 0, true),
    ];
    for (what, mut c, cu, reset, cv, q) in up {
        assert_eq!((c.call(cu, reset), c.cv()), (q, cv), "{what}");
    }
    // (what, counter, CD, load, CV after, Q)
    let down: [(&str, Ctd, bool, bool, i32, bool); 5] = [
        ("CTD at MIN saturates", with_cv(Ctd::new(5), min), true, false, min, true),
        ("CTD at MAX counts down", with_cv(Ctd::new(5), max), true, false, max - 1, false),
        ("CTD load PV MIN", Ctd::new(min), false, true, min, true),
        ("CTD load PV MAX", Ctd::new(max), false, true, max, false),
        ("CTD at 1 reaches 0: Q", with_cv(Ctd::new(5), 1), true, false, 0, true),
    ];
    for (what, mut c, cd, load, cv, q) in down {
        assert_eq!((c.call(cd, load), c.cv()), (q, cv), "{what}");
    }
    // (what, counter, CU, CD, R, LD, CV after, (QU, QD))
    let updown: [(&str, Ctud, bool, bool, bool, bool, i32, (bool, bool)); 6] = [
        ("CTUD up at MAX saturates", with_cv(Ctud::new(max), max), true, false, false, false, max, (true, false)),
        ("CTUD down at MIN saturates", with_cv(Ctud::new(max), min), false, true, false, false, min, (false, true)),
        ("CTUD both edges: no change", with_cv(Ctud::new(max), max), true, true, false, false, max, (true, false)),
        ("CTUD R wins over LD", with_cv(Ctud::new(7), max), false, false, true, true, 0, (false, true)),
        ("CTUD LD PV MIN", Ctud::new(min), false, false, false, true, min, (true, true)),
        ("CTUD PV MAX at MAX - 1 up", with_cv(Ctud::new(max), max - 1), true, false, false, false, max, (true, false)),
    ];
    for (what, mut c, cu, cd, r, ld, cv, q) in updown {
        assert_eq!((c.call(cu, cd, r, ld), c.cv()), (q, cv), "{what}");
    }
}

/// Counters loaded to `i32::MAX`/`i32::MIN` saturate; PV at the extremes changes Q at once; the
/// edge detectors and bistables over every previous state and input (exhaustive).
#[test]
#[rustfmt::skip]
fn counters_edges_and_bistables_at_their_ends() {
    let (max, min) = (i32::MAX, i32::MIN);
    let mut down = Ctd::new(min);
    down.call(false, true);
    assert_eq!((down.call(true, false), down.cv()), (true, min), "CTD loaded MIN, counted down: stays MIN");
    let mut updown = Ctud::new(max);
    updown.call(false, false, false, true);
    assert_eq!((updown.call(true, false, false, false), updown.cv()), ((true, false), max), "CTUD loaded MAX, counted up: stays MAX");
    let mut updown = Ctud::new(min);
    updown.call(false, false, false, true);
    assert_eq!((updown.call(false, true, false, false), updown.cv()), ((true, true), min), "CTUD loaded MIN, counted down: stays MIN");
    // set_pv at the extremes changes Q at once.
    let mut c = Ctu::new(5);
    c.set_pv(min);
    assert!(c.q());
    c.set_pv(max);
    assert!(!c.q());
    // Edge detectors and bistables: every previous state × every input.
    for prev in [false, true] {
        for clk in [false, true] {
            let (mut r, mut f) = (RTrig::new(), FTrig::new());
            r.call(prev);
            f.call(prev);
            assert_eq!(r.call(clk), clk && !prev, "R_TRIG {prev} -> {clk}");
            assert_eq!(f.call(clk), !clk && prev, "F_TRIG {prev} -> {clk}");
        }
        for (s, rr) in [(false, false), (false, true), (true, false), (true, true)] {
            let (mut sr, mut rs) = (Sr::new(), Rs::new());
            sr.call(prev, false);
            rs.call(prev, false);
            assert_eq!(sr.call(s, rr), s || (!rr && prev), "SR {prev} S{s} R{rr}");
            assert_eq!(rs.call(s, rr), !rr && (s || prev), "RS {prev} S{s} R{rr}");
        }
    }
}

/// Points and words at 0, the last, one past the end and `usize::MAX`, in images of 1 and 2
/// words; a refused set changes nothing.
#[test]
#[rustfmt::skip]
fn images_and_forcing_at_their_ends() {
    fn check<const W: usize>() {
        let last = W * 16 - 1;
        let past = W * 16;
        // (point, set result, try_get after setting on)
        let rows: [(usize, Result<(), PointError>, Option<bool>); 4] = [
            (0, Ok(()), Some(true)),
            (last, Ok(()), Some(true)),
            (past, Err(PointError { point: past, points: past }), None),
            (usize::MAX, Err(PointError { point: usize::MAX, points: past }), None),
        ];
        for (point, set, got) in rows {
            let mut image = Image::<W>::from_words([0x5A5A; W]);
            let before = image;
            let r = image.set(point, true);
            assert_eq!(r, set, "Image<{W}>::set({point})");
            if r.is_err() {
                assert_eq!(image, before, "a refused set changed the image");
            }
            assert_eq!(image.try_get(point), got, "Image<{W}>::try_get({point})");
            assert_eq!(image.get(point), got == Some(true), "Image<{W}>::get({point})");
            let mut f = Forcing::<W>::new();
            assert_eq!(f.force(point, true), set, "Forcing<{W}>::force({point})");
            assert_eq!(f.forced(point), got, "Forcing<{W}>::forced({point})");
            assert_eq!(f.unforce(point), set, "Forcing<{W}>::unforce({point})");
            assert_eq!(f.forced(point), got.map(|_| false).filter(|_| false), "after unforce");
            assert!(!f.any());
        }
        // Words: (index, set_word result, word after)
        let words: [(usize, Result<(), WordError>, Option<u16>); 3] = [
            (0, Ok(()), Some(u16::MAX)),
            (W - 1, Ok(()), Some(u16::MAX)),
            (W, Err(WordError { word: W, words: W }), None),
        ];
        for (index, set, got) in words {
            let mut image = Image::<W>::new();
            assert_eq!(image.set_word(index, u16::MAX), set, "set_word({index})");
            assert_eq!(image.word(index), got, "word({index})");
        }
        // Forcing every point of a full image off, and on, applies exactly.
        let mut f = Forcing::<W>::new();
        for p in 0..past {
            f.force(p, p % 2 == 0).unwrap();
        }
        let mut image = Image::<W>::from_words([u16::MAX; W]);
        f.apply(&mut image);
        assert!(image.ones().all(|p| p % 2 == 0) && image.ones().count() == past / 2);
        f.clear();
        assert!(!f.any());
    }
    check::<1>();
    check::<2>();
    check::<3>();
}

/// Debounce counts 0, 1, 15, 16, `u8::MAX`; points past the end; latching a debounced point.
/// A refused call changes nothing.
#[test]
#[rustfmt::skip]
fn conditioning_at_the_extremes() {
    let past = 32;
    // (what, point, count, result)
    let rows: [(&str, usize, u8, Result<(), DebounceError>); 7] = [
        ("count 0", 3, 0, Err(DebounceError::Count(0))),
        ("count 1", 3, 1, Ok(())),
        ("count 15", 3, 15, Ok(())),
        ("count 16", 3, 16, Err(DebounceError::Count(16))),
        ("count MAX", 3, u8::MAX, Err(DebounceError::Count(u8::MAX))),
        ("point past the end", past, 2, Err(DebounceError::Point(PointError { point: past, points: past }))),
        ("point usize::MAX", usize::MAX, 2, Err(DebounceError::Point(PointError { point: usize::MAX, points: past }))),
    ];
    for (what, point, count, want) in rows {
        let mut c = Conditioning::<2>::new();
        let before = c;
        let r = c.set_debounce(point, count);
        assert_eq!(r, want, "set_debounce {what}");
        if r.is_err() {
            assert_eq!(c, before, "a refused set_debounce changed the conditioning: {what}");
        } else {
            assert_eq!(c.debounce(point), count, "{what}");
        }
    }
    // debounce() outside the image reads 0 (documented), latched() false.
    let c = Conditioning::<2>::new();
    assert_eq!((c.debounce(past), c.debounce(usize::MAX)), (0, 0));
    assert!(!c.latched(past));
    // Latching: (what, point, count before, latch, result)
    let rows: [(&str, usize, u8, bool, Result<(), DebounceError>); 5] = [
        ("latch a count-1 point", 5, 1, true, Ok(())),
        ("latch a count-2 point", 5, 2, true, Err(DebounceError::Latched { point: 5, count: 2 })),
        ("latch a count-15 point", 5, 15, true, Err(DebounceError::Latched { point: 5, count: 15 })),
        ("unlatch a count-15 point", 5, 15, false, Ok(())),
        ("latch past the end", past, 1, true, Err(DebounceError::Point(PointError { point: past, points: past }))),
    ];
    for (what, point, count, latch, want) in rows {
        let mut c = Conditioning::<2>::new();
        if point < past {
            c.set_debounce(point, count).unwrap();
        }
        let before = c;
        let r = c.set_latched(point, latch);
        assert_eq!(r, want, "set_latched {what}");
        if r.is_err() {
            assert_eq!(c, before, "a refused set_latched changed the conditioning: {what}");
        }
    }
    let mut c = Conditioning::<2>::new();
    c.set_latched(5, true).unwrap();
    assert_eq!(c.set_debounce(5, 2), Err(DebounceError::Latched { point: 5, count: 2 }));
    assert_eq!(c.debounce(5), 1);
}

/// The timer queue at capacities 1, 2 and 3: full, empty, ticks 0, 1 and `u32::MAX`, stale
/// handles (expired, removed, from a bigger queue).
#[test]
#[rustfmt::skip]
fn timer_queue_at_the_extremes() {
    fn check<const N: usize>() {
        let mut q: TimerQueue<u32, N> = TimerQueue::new();
        assert_eq!((q.len(), q.is_empty(), q.capacity()), (0, true, N));
        let mut fired = Vec::new();
        q.tick(|a| fired.push(a));
        assert!(fired.is_empty(), "an empty queue ticks nothing");
        // Fill it: ticks 0 (counts as 1), u32::MAX, then 1s.
        let ticks = [0, u32::MAX, 1];
        let mut ids = Vec::new();
        for (n, t) in ticks.iter().take(N).enumerate() {
            ids.push(q.insert(*t, n as u32).unwrap());
        }
        assert_eq!(q.len(), N);
        // Full: the action is handed back, nothing changes.
        assert_eq!(q.insert(5, 99).map(|_| ()), Err(regler_scan_cycle::QueueFull(99)), "Queue<{N}> full");
        assert_eq!(q.len(), N);
        // remaining: (handle, ticks)
        assert_eq!(q.remaining(ids[0]), Some(1), "ticks 0 counts as 1");
        if N >= 2 {
            assert_eq!(q.remaining(ids[1]), Some(u32::MAX), "ticks MAX");
        }
        q.tick(|a| fired.push(a));
        let expected_first: Vec<u32> = if N >= 3 { vec![0, 2] } else { vec![0] };
        assert_eq!(fired, expected_first, "Queue<{N}>: the first tick");
        // Stale handles: expired, then removed, then a handle whose place was reused.
        let expired = ids[0];
        assert_eq!(q.remaining(expired), None);
        assert_eq!(q.remove(expired), None);
        assert_eq!(q.replace(expired, 3), Err(regler_scan_cycle::UnknownTimer(expired)));
        let reused = q.insert(1, 7).unwrap();
        assert_ne!(reused, expired, "a reused place gets a new handle");
        assert_eq!(q.remove(expired), None, "a stale handle never touches the newer timer");
        assert_eq!(q.remaining(reused), Some(1));
        assert_eq!(q.remove(reused), Some(7));
        assert_eq!(q.remove(reused), None, "removed twice");
        assert_eq!(q.replace(reused, 1), Err(regler_scan_cycle::UnknownTimer(reused)));
        if N >= 2 {
            // Replace MAX with 0: expires at the next tick.
            q.replace(ids[1], 0).unwrap();
            assert_eq!(q.remaining(ids[1]), Some(1));
            fired.clear();
            q.tick(|a| fired.push(a));
            assert_eq!(fired, [1]);
        }
    }
    check::<1>();
    check::<2>();
    check::<3>();
    // A handle from a bigger queue names nothing in a smaller one.
    let mut big: TimerQueue<u8, 8> = TimerQueue::new();
    let mut last = None;
    for a in 0..8 {
        last = Some(big.insert(1, a).unwrap());
    }
    let foreign = last.unwrap();
    let mut small: TimerQueue<u8, 1> = TimerQueue::new();
    small.insert(1, 0).unwrap();
    assert_eq!(small.remaining(foreign), None);
    assert_eq!(small.remove(foreign), None);
    assert_eq!(small.replace(foreign, 1), Err(regler_scan_cycle::UnknownTimer(foreign)));
    assert_eq!(small.len(), 1);
}

/// `DateTime::new` with every field at its limits and one past; `advance` by 0, 1 and
/// `u32::MAX` ms, and at the end of time.
#[test]
#[rustfmt::skip]
fn dates_at_their_limits() {
    use InvalidDateTime as E;
    // (year, month, day, hour, minute, second, result)
    let rows: [(u16, u8, u8, u8, u8, u8, Result<(), E>); 18] = [
        (1, 1, 1, 0, 0, 0, Ok(())),
        (9999, 12, 31, 23, 59, 59, Ok(())),
        (0, 1, 1, 0, 0, 0, Err(E::Year(0))),
        (10000, 1, 1, 0, 0, 0, Err(E::Year(10000))),
        (u16::MAX, 1, 1, 0, 0, 0, Err(E::Year(u16::MAX))),
        (2026, 0, 1, 0, 0, 0, Err(E::Month(0))),
        (2026, 13, 1, 0, 0, 0, Err(E::Month(13))),
        (2026, u8::MAX, 1, 0, 0, 0, Err(E::Month(u8::MAX))),
        (2026, 1, 0, 0, 0, 0, Err(E::Day { day: 0, days_in_month: 31 })),
        (2026, 2, 29, 0, 0, 0, Err(E::Day { day: 29, days_in_month: 28 })),
        (2024, 2, 29, 0, 0, 0, Ok(())),
        (2100, 2, 29, 0, 0, 0, Err(E::Day { day: 29, days_in_month: 28 })),
        (2000, 2, 29, 0, 0, 0, Ok(())),
        (2026, 4, u8::MAX, 0, 0, 0, Err(E::Day { day: u8::MAX, days_in_month: 30 })),
        (2026, 1, 1, 24, 0, 0, Err(E::Hour(24))),
        (2026, 1, 1, 0, 60, 0, Err(E::Minute(60))),
        (2026, 1, 1, 0, 0, 60, Err(E::Second(60))),
        (2026, 1, 1, u8::MAX, u8::MAX, u8::MAX, Err(E::Hour(u8::MAX))),
    ];
    for (y, mo, d, h, mi, s, want) in rows {
        assert_eq!(DateTime::new(y, mo, d, h, mi, s).map(|_| ()), want, "{y}-{mo}-{d} {h}:{mi}:{s}");
    }
    // advance: (start, ms, minutes begun, end)
    let at = |y, mo, d, h, mi, s| DateTime::new(y, mo, d, h, mi, s).unwrap();
    let rows: [(DateTime, u32, u32, DateTime); 6] = [
        (at(2026, 1, 1, 0, 0, 0), 0, 0, at(2026, 1, 1, 0, 0, 0)),
        (at(2026, 1, 1, 0, 0, 59), 999, 0, at(2026, 1, 1, 0, 0, 59)),
        (at(2026, 1, 1, 0, 0, 59), 1000, 1, at(2026, 1, 1, 0, 1, 0)),
        // u32::MAX ms = 49 days 17:02:47.295
        (at(2026, 1, 1, 0, 0, 0), u32::MAX, 71_582, at(2026, 2, 19, 17, 2, 47)),
        (DateTime::END, u32::MAX, 0, DateTime::END),
        (at(9999, 12, 31, 23, 58, 0), u32::MAX, 1, DateTime::END),
    ];
    for (start, ms, minutes, end) in rows {
        let mut t = start;
        assert_eq!(t.advance(ms), minutes, "{start} + {ms} ms");
        assert_eq!((t.year(), t.month(), t.day(), t.hour(), t.minute(), t.second()),
                   (end.year(), end.month(), end.day(), end.hour(), end.minute(), end.second()), "{start} + {ms} ms");
    }
    // Weekdays::contains: 0 and 8..=255 are no day, whatever the bits.
    for day in 0..=u8::MAX {
        assert_eq!(Weekdays(0xFF).contains(day), (1..=7).contains(&day), "day {day}");
        assert!(!Weekdays(0).contains(day));
    }
}

/// The minute table at capacities 1 and 2: full, hour 24, minute 60, `u8::MAX`; the line is
/// handed back; a refused add changes nothing.
#[test]
#[rustfmt::skip]
fn minute_table_at_the_extremes() {
    let line = |hour, minute, program| Start { hour, minute, days: Weekdays::ALL, program };
    let mut one: MinuteTable<u8, 1> = MinuteTable::new();
    // (line, result)
    let rows: [(Start<u8>, Result<(), AddError<u8>>); 6] = [
        (line(24, 0, 1), Err(AddError::InvalidTime(line(24, 0, 1)))),
        (line(0, 60, 2), Err(AddError::InvalidTime(line(0, 60, 2)))),
        (line(u8::MAX, u8::MAX, 3), Err(AddError::InvalidTime(line(u8::MAX, u8::MAX, 3)))),
        (line(23, 59, 4), Ok(())),
        (line(0, 0, 5), Err(AddError::Full(line(0, 0, 5)))),
        (line(24, 0, 6), Err(AddError::InvalidTime(line(24, 0, 6)))),
    ];
    for (start, want) in rows {
        assert_eq!(one.add(start), want, "{start:?}");
    }
    assert_eq!(one.iter().count(), 1);
    assert_eq!(AddError::Full(line(0, 0, 5)).into_start(), line(0, 0, 5));
    let mut two: MinuteTable<u8, 2> = MinuteTable::new();
    two.add(line(0, 0, 1)).unwrap();
    two.add(line(0, 0, 2)).unwrap();
    assert_eq!(two.add(line(0, 0, 3)), Err(AddError::Full(line(0, 0, 3))));
    // A check at the first and the last minute of time, on an empty and a full table.
    let mut empty: MinuteTable<u8, 1> = MinuteTable::new();
    let first = DateTime::new(1, 1, 1, 0, 0, 0).unwrap();
    let mut n = 0;
    empty.check(&first, |_| n += 1);
    empty.check(&DateTime::END, |_| n += 1);
    assert_eq!(n, 0);
    let mut ran = Vec::new();
    two.check(&first, |d| ran.push(*d.program));
    assert_eq!(ran, [1, 2], "both lines of 00:00 run in the first minute of time");
    ran.clear();
    let c = two.check(&DateTime::END, |d| ran.push(*d.program));
    assert_eq!(ran, [1, 2], "the clock jumped to the end of time: each line runs once, late");
    assert_eq!(c.late, 2);
}

/// Spools and step chains of capacity 1 and 2: full hands the item back.
#[test]
fn spool_and_step_chain_at_capacity() {
    let mut one: Spool<u8, 1> = Spool::new();
    assert!(one.is_empty());
    assert_eq!(one.push(1), Ok(()));
    assert_eq!(one.push(2), Err(2));
    assert_eq!(
        (one.len(), one.iter().copied().collect::<Vec<_>>()),
        (1, vec![1])
    );
    let mut two: Spool<u8, 2> = Spool::new();
    assert_eq!(
        (two.push(1), two.push(2), two.push(3)),
        (Ok(()), Ok(()), Err(3))
    );
    let mut chain: StepChain<u32, 1, 1, 1> = StepChain::new();
    assert!(chain.is_empty());
    assert!(chain.push(|_| true, |_, c| *c += 1).is_ok());
    assert!(chain.push(|_| true, |_, c| *c += 10).is_err());
    assert_eq!(chain.len(), 1);
}

struct Clock {
    t: u32,
    step: u32,
    out: [u16; 1],
}

impl Io<1, 1> for Clock {
    fn read_inputs(&mut self, raw: &mut [u16; 1]) {
        *raw = [0xFFFF];
    }
    fn write_outputs(&mut self, outputs: &[u16; 1]) {
        self.out = *outputs;
    }
    fn now_us(&mut self) -> u32 {
        self.t = self.t.wrapping_add(self.step);
        self.t
    }
}

/// The executive: forcing points past the end, breakpoints that can never fire, the clock
/// restored at 0 and `u32::MAX`, statistics at their ends, the watchdog limit 0 and MAX.
#[test]
#[rustfmt::skip]
fn executive_at_the_extremes() {
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    let past = 16;
    // (what, result)
    let rows: [(&str, Result<(), PointError>); 6] = [
        ("force input 15", plc.force_input(15, true)),
        ("force input 16", plc.force_input(past, true)),
        ("force output usize::MAX", plc.force_output(usize::MAX, true)),
        ("unforce input 16", plc.unforce_input(past)),
        ("unforce output 0", plc.unforce_output(0)),
        ("unforce output 16", plc.unforce_output(past)),
    ];
    let want = [
        Ok(()),
        Err(PointError { point: past, points: past }),
        Err(PointError { point: usize::MAX, points: past }),
        Err(PointError { point: past, points: past }),
        Ok(()),
        Err(PointError { point: past, points: past }),
    ];
    for ((what, got), want) in rows.into_iter().zip(want) {
        assert_eq!(got, want, "{what}");
    }
    assert_eq!(plc.forced_inputs().forced(15), Some(true));
    assert!(!plc.forced_outputs().any());
    // Breakpoints: (breakpoint, check)
    let rows: [(Breakpoint, Result<(), BreakpointError>); 6] = [
        (Breakpoint::Cycle(0), Err(BreakpointError::CycleZero)),
        (Breakpoint::Cycle(1), Ok(())),
        (Breakpoint::Cycle(u64::MAX), Ok(())),
        (Breakpoint::InputOn(past), Err(BreakpointError::NoSuchInput { point: past, inputs: past })),
        (Breakpoint::OutputOn(usize::MAX), Err(BreakpointError::NoSuchOutput { point: usize::MAX, outputs: past })),
        (Breakpoint::OutputOff(15), Ok(())),
    ];
    for (b, want) in rows {
        assert_eq!(plc.check_breakpoints(&[b]), want, "{b:?}");
    }
    let mut io = Clock { t: 0, step: 10, out: [0] };
    plc.cycle(&mut io, |_| {}).unwrap();
    assert_eq!(
        plc.check_breakpoints(&[Breakpoint::Cycle(1)]),
        Err(BreakpointError::CyclePassed { cycle: 1, count: 1 })
    );
    // The program clock restored at u32::MAX wraps to 0 after 1 ms.
    for (restored, step_us, seen) in [(0u32, 1000, 0u32), (u32::MAX, 1000, u32::MAX), (u32::MAX - 1, 2500, u32::MAX - 1)] {
        let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
        // The µs clock wraps too; it stands still within a cycle.
        let mut io = Clock { t: u32::MAX - 3, step: 0, out: [0] };
        plc.set_now_ms(restored);
        let mut times = Vec::new();
        for _ in 0..3 {
            plc.cycle(&mut io, |s| times.push(s.now_ms)).unwrap();
            io.t = io.t.wrapping_add(step_us);
        }
        assert_eq!(times[0], seen, "restored {restored}");
        let per = step_us / 1000;
        assert_eq!(times[1], seen.wrapping_add(per), "restored {restored}: across the wrap");
    }
    // Statistics at their ends: (stats, mean, load per mille of period)
    let s = |cycles, total_us| CycleStats { cycles, total_us, ..CycleStats::NONE };
    let rows: [(CycleStats, u32, u32, u32); 7] = [
        (CycleStats::NONE, 50_000, 0, 0),
        (s(1, u64::MAX), 50_000, u32::MAX, 85_899_345),
        (s(1, u64::MAX), 1, u32::MAX, u32::MAX),
        (s(u64::MAX, u64::MAX), 50_000, 1, 0),
        (s(2, 100_000), 0, 50_000, 0),
        (s(2, 100_000), 1, 50_000, 50_000_000),
        (s(2, 100_000), u32::MAX, 50_000, 0),
    ];
    for (stats, period, mean, load) in rows {
        assert_eq!((stats.mean_us(), stats.load_per_mille(period)), (mean, load), "{stats:?} period {period}");
    }
    // Watchdog limits 0 and MAX (MAX acts as 2^31 - 2 µs).
    let signals: Signals<1, 1> = Signals::new(&CycleConfig { watchdog_us: 0, ..CycleConfig::source() });
    assert!(!signals.check_watchdog(0), "the first check starts the count");
    assert!(signals.check_watchdog(1), "limit 0: 1 µs later trips");
    let signals: Signals<1, 1> = Signals::new(&CycleConfig { watchdog_us: u32::MAX, ..CycleConfig::source() });
    assert!(!signals.check_watchdog(0));
    assert!(!signals.check_watchdog(HALF - 2), "2^31 - 2 µs is within the limit");
    assert!(signals.check_watchdog(HALF - 1), "MAX acts as 2^31 - 2 µs");
    assert_eq!(signals.trips(), 1);
    // A tripped executive refuses a cycle with the halt named.
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig { watchdog_us: 0, ..CycleConfig::source() });
    let mut io = Clock { t: 0, step: 10, out: [0] };
    plc.cycle(&mut io, |s| { s.outputs.set(0, true).unwrap(); }).unwrap();
    plc.check_watchdog(&mut io);
    assert_eq!(plc.halted(), Some(Halt::Watchdog));
    assert_eq!(plc.cycle(&mut io, |_| {}), Err(Halt::Watchdog));
    assert_eq!(io.out, [0], "the safe outputs are written");
}

/// Corrupt snapshots of the timers (serde): every combination of the stored fields at their
/// extremes either comes back as a timer that behaves like one reached by calls, or is refused.
/// A timer whose Q disagrees with its stored state is refused: a TP with Q on and no pulse
/// running held Q on for ever, and one with a pulse running and Q off gave a phantom pulse.
#[cfg(feature = "serde")]
#[test]
#[rustfmt::skip]
fn corrupt_timer_snapshots() {
    use serde_json::json;
    let running = |last: u32, total: u32| json!({ "last_ms": last, "total_ms": total });
    let m = u32::MAX;
    // (what, timer, stored fields, restored?)
    let rows: Vec<(&str, Timer, serde_json::Value, bool)> = vec![
        ("TON idle", Timer::Ton, json!({"pt_ms": 10, "running": null, "q": false, "done_et": null}), true),
        ("TON timing, total MAX", Timer::Ton, json!({"pt_ms": m, "running": running(m, m), "q": false, "done_et": null}), true),
        ("TON done, ET MAX", Timer::Ton, json!({"pt_ms": 0, "running": running(0, m), "q": true, "done_et": m}), true),
        ("TON Q on, not done", Timer::Ton, json!({"pt_ms": 10, "running": running(0, 0), "q": true, "done_et": null}), false),
        ("TON done, Q off", Timer::Ton, json!({"pt_ms": 10, "running": running(0, 10), "q": false, "done_et": 10}), false),
        ("TOF idle", Timer::Tof, json!({"pt_ms": 10, "running": null, "q": false, "done_et": null}), true),
        ("TOF on", Timer::Tof, json!({"pt_ms": m, "running": null, "q": true, "done_et": null}), true),
        ("TOF delaying, total MAX", Timer::Tof, json!({"pt_ms": m, "running": running(m, m), "q": true, "done_et": null}), true),
        ("TOF ran out", Timer::Tof, json!({"pt_ms": 0, "running": running(0, 0), "q": false, "done_et": m}), true),
        ("TOF ran out, Q on", Timer::Tof, json!({"pt_ms": 10, "running": running(0, 10), "q": true, "done_et": 10}), false),
        ("TP idle", Timer::Tp, json!({"pt_ms": 10, "running": null, "q": false, "prev_in": false, "done_et": null}), true),
        ("TP pulsing, total MAX", Timer::Tp, json!({"pt_ms": m, "running": running(m, m), "q": true, "prev_in": true, "done_et": null}), true),
        ("TP ended, IN on", Timer::Tp, json!({"pt_ms": 0, "running": null, "q": false, "prev_in": true, "done_et": m}), true),
        ("TP Q on, no pulse running", Timer::Tp, json!({"pt_ms": 10, "running": null, "q": true, "prev_in": false, "done_et": null}), false),
        ("TP pulse running, Q off", Timer::Tp, json!({"pt_ms": 10, "running": running(0, 0), "q": false, "prev_in": false, "done_et": null}), false),
        ("TP pulsing and ended", Timer::Tp, json!({"pt_ms": 10, "running": running(0, 0), "q": true, "prev_in": true, "done_et": 10}), false),
    ];
    let mut fails = Vec::new();
    for (what, kind, value, ok) in rows {
        let restored = match kind {
            Timer::Ton => serde_json::from_value::<Ton>(value).map(|mut t| {
                let q = t.q();
                // A restored timer's Q follows its inputs: IN off switches it off.
                (q, t.call(false, 0), t.q())
            }),
            Timer::Tof => serde_json::from_value::<Tof>(value).map(|mut t| {
                let q = t.q();
                (q, t.call(true, 0), t.q())
            }),
            Timer::Tp => serde_json::from_value::<Tp>(value).map(|mut t| {
                let q = t.q();
                // With IN off, a pulse ends within PT; Q stays on no longer.
                let end = t.pt().saturating_add(1);
                (q, t.call(false, end), t.q())
            }),
        };
        match (restored, ok) {
            (Ok((_, after, q)), true) => {
                let want = matches!(kind, Timer::Tof);
                if (after, q) != (want, want) {
                    fails.push(format!("{what}: restored, then driven: Q {after}, want {want}"));
                }
            }
            (Err(e), false) => {
                let text = e.to_string();
                if !(text.starts_with("stored TON") || text.starts_with("stored TOF") || text.starts_with("stored TP")) {
                    fails.push(format!("{what}: {text}"));
                }
            }
            (r, _) => fails.push(format!("{what}: {:?}, want restored = {ok}", r.map_err(|e| e.to_string()))),
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

/// The other side of `corrupt_timer_snapshots`: every state a timer reaches by calls — every
/// sequence of up to four calls and PT changes, with IN off and on, time steps of 0, 1, PT and
/// 2³¹ ms, PT changes to 0 and MAX, for PT 0, 5 and MAX — is stored and restored unchanged
/// (exhaustive).
#[cfg(feature = "serde")]
#[test]
#[cfg_attr(miri, ignore = "110 000 serde round trips: minutes under Miri")]
fn every_reachable_timer_state_is_restored() {
    #[derive(Clone, Copy, Debug)]
    enum Op {
        Call(bool, u32),
        SetPt(u32),
    }
    fn walk<
        T: Clone + PartialEq + core::fmt::Debug + serde::Serialize + serde::de::DeserializeOwned,
    >(
        t: &T,
        now: u32,
        depth: usize,
        ops: &[Op],
        call: &impl Fn(&mut T, bool, u32),
        set_pt: &impl Fn(&mut T, u32),
        seen: &mut usize,
    ) {
        let text = serde_json::to_string(t).unwrap();
        let back: T = serde_json::from_str(&text)
            .unwrap_or_else(|e| panic!("a reachable state is refused: {text}: {e}"));
        assert_eq!(&back, t, "{text}");
        *seen += 1;
        if depth == 0 {
            return;
        }
        for &op in ops {
            let mut next = t.clone();
            let mut at = now;
            match op {
                Op::Call(input, step) => {
                    at = now.wrapping_add(step);
                    call(&mut next, input, at);
                }
                Op::SetPt(pt) => set_pt(&mut next, pt),
            }
            walk(&next, at, depth - 1, ops, call, set_pt, seen);
        }
    }
    let mut seen = 0;
    for pt in [0, 5, u32::MAX] {
        let mut ops = vec![Op::SetPt(0), Op::SetPt(u32::MAX)];
        for step in [0, 1, pt, HALF] {
            ops.push(Op::Call(false, step));
            ops.push(Op::Call(true, step));
        }
        walk(
            &Ton::new(pt),
            7,
            4,
            &ops,
            &|t, i, n| {
                t.call(i, n);
            },
            &|t, p| t.set_pt(p),
            &mut seen,
        );
        walk(
            &Tof::new(pt),
            7,
            4,
            &ops,
            &|t, i, n| {
                t.call(i, n);
            },
            &|t, p| t.set_pt(p),
            &mut seen,
        );
        walk(
            &Tp::new(pt),
            7,
            4,
            &ops,
            &|t, i, n| {
                t.call(i, n);
            },
            &|t, p| t.set_pt(p),
            &mut seen,
        );
    }
    assert_eq!(seen, 9 * 11_111);
}

/// Stored images and forcing with too few and too many words, and words at `u16::MAX`: the
/// exact count or an error, never a padded or cut image.
#[cfg(feature = "serde")]
#[test]
fn stored_images_at_the_extremes() {
    // (stored words, Image<2> restored?)
    let rows: [(&str, bool); 5] = [
        ("[]", false),
        ("[65535]", false),
        ("[65535,65535]", true),
        ("[0,0,0]", false),
        ("[65536,0]", false),
    ];
    for (words, ok) in rows {
        let image = serde_json::from_str::<Image<2>>(&format!("{{\"words\":{words}}}"));
        assert_eq!(image.is_ok(), ok, "Image<2> from {words}: {image:?}");
        if let Ok(image) = image {
            assert_eq!(image.words(), &[u16::MAX; 2]);
            assert_eq!(image.ones().count(), 32);
        }
    }
    let f = Forcing::<1>::new();
    let text = serde_json::to_string(&f).unwrap();
    assert_eq!(serde_json::from_str::<Forcing<1>>(&text).unwrap(), f);
    assert!(
        serde_json::from_str::<Forcing<2>>(&text).is_err(),
        "a one-word forcing is not a two-word one"
    );
}

/// Power failure and resume at the extremes: a power failure before any cycle, twice in a row,
/// a resume without one; the safe outputs are written and no cycle runs while it lasts.
#[test]
fn power_failures_at_the_extremes() {
    let safe = Image::<1>::from_words([0x0F0F]);
    let config = CycleConfig {
        safe_outputs: safe,
        ..CycleConfig::source()
    };
    let mut plc: Executive<1, 1> = Executive::new(config);
    let mut io = Clock {
        t: 0,
        step: 0,
        out: [0xFFFF],
    };
    plc.resume(regler_scan_cycle::Restart::Inhibit); // no power failure: nothing happens
    assert_eq!(plc.halted(), None);
    plc.power_fail(&mut io);
    plc.power_fail(&mut io);
    assert_eq!((io.out, plc.halted()), ([0x0F0F], Some(Halt::PowerFail)));
    assert_eq!(
        plc.cycle(&mut io, |_| panic!("no cycle while the power is off")),
        Err(Halt::PowerFail)
    );
    assert_eq!(plc.cycle_count(), 0);
    plc.resume(regler_scan_cycle::Restart::Inhibit);
    let mut previous = None;
    io.t = 1000;
    plc.cycle(&mut io, |s| previous = Some(*s.previous))
        .unwrap();
    assert_eq!(
        previous,
        Some(safe),
        "Restart::Inhibit starts from the safe outputs"
    );
    assert_eq!(plc.cycle_count(), 1);
}
