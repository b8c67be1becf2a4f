//! Retentive state across a real power cycle (serde): the executive's clock restarts at 0.
#![allow(clippy::unwrap_used)]
#![cfg(feature = "serde")]
use regler_scan_cycle::{CycleConfig, Executive, Io, Ton};

struct P(u32);
impl Io<1, 1> for P {
    fn read_inputs(&mut self, raw: &mut [u16; 1]) {
        *raw = [1];
    }
    fn write_outputs(&mut self, _: &[u16; 1]) {}
    fn now_us(&mut self) -> u32 {
        self.0
    }
}

/// README: "Features: ... `serde` (images, blocks, statistics: retentive state)"; blocks: "a clock
/// stepping back adds no time". A Ton saved after 25 days of uptime and restored into the
/// firmware after a power cycle (a new Executive: now_ms from 0) fired at once; with the clock
/// restored by `Executive::set_now_ms` it goes on where it stood.
#[test]
#[cfg_attr(
    miri,
    ignore = "3 320 executive cycles (25 days in 2³⁰ µs strides, then a minute): a minute under Miri; runs natively in every CI run"
)]
fn retentive_ton_fires_at_once_after_a_power_cycle() {
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    let mut io = P(0);
    let mut ton = Ton::new(60_000); // one minute
    // 25 days of 50 ms... simulate by stepping the µs clock in 2^30 µs strides.
    for _ in 0..2020 {
        io.0 = io.0.wrapping_add(1 << 30);
        plc.cycle(&mut io, |s| {
            ton.call(false, s.now_ms);
        })
        .unwrap();
    }
    assert!(plc.now_ms() > 1 << 31, "{}", plc.now_ms());
    // The part sensor is covered: the 1-minute timer starts, 1 s passes.
    for _ in 0..20 {
        io.0 = io.0.wrapping_add(50_000);
        plc.cycle(&mut io, |s| assert!(!ton.call(true, s.now_ms)))
            .unwrap();
    }
    let saved = serde_json::to_string(&ton).unwrap();
    let saved_ms = plc.now_ms();
    // Power cycle: the firmware restarts, restores its retentive timer.
    let mut ton: Ton = serde_json::from_str(&saved).unwrap();
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    plc.set_now_ms(saved_ms); // the start-up restores the program clock with the timers
    let mut io = P(12345);
    let mut q = false;
    plc.cycle(&mut io, |s| q = ton.call(true, s.now_ms))
        .unwrap();
    assert!(
        !q,
        "a 1-minute TON 1 s into its time fired on the first cycle after the power cycle (et {})",
        ton.et()
    );
    // It goes on where it stood: 59 s more of 50 ms cycles, it fires on the cycle that reaches
    // 60 s, neither before nor frozen.
    let et0 = ton.et();
    let mut fired_at = None;
    for i in 1..=1300u32 {
        io.0 = io.0.wrapping_add(50_000);
        plc.cycle(&mut io, |s| {
            if ton.call(true, s.now_ms) && fired_at.is_none() {
                fired_at = Some(i);
            }
        })
        .unwrap();
    }
    let want = (60_000 - et0).div_ceil(50);
    assert_eq!(fired_at, Some(want), "et at restore {et0} ms");
}
