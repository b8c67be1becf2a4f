//! Regression tests from an independent attack on the executive and Signals (issue 24): the
//! reproducers as the attacker wrote them, adapted only where the fix is a new API (the idle
//! loop's check over `Signals` is `check_watchdog_with`).
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects
)]

use std::cell::RefCell;
use std::rc::Rc;

use regler_scan_cycle::{
    Breakpoint, CycleConfig, Executive, Halt, Image, Io, Restart, Signals, Ton,
};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Op {
    Trip,
    Pf,
    ResumeI,
    ResumeW,
    Reset,
}
const OPS: [Op; 5] = [Op::Trip, Op::Pf, Op::ResumeI, Op::ResumeW, Op::Reset];

const SAFE: [u16; 3] = [0x8000, 0x0000, 0x0001];

struct World {
    bus: [u16; 3],
    t: u32,
    point: usize,
    plan: Vec<(usize, Vec<Op>)>,
    events_before_confirm: bool,
    events_after_confirm: bool,
    any_trip: bool,
    any_inhibit: bool,
    inputs: [u16; 1],
}

struct Plant {
    w: Rc<RefCell<World>>,
    s: Rc<Signals<1, 3>>,
}

fn apply(w: &Rc<RefCell<World>>, s: &Signals<1, 3>) {
    let (point, ops) = {
        let mut wb = w.borrow_mut();
        let p = wb.point;
        wb.point += 1;
        let ops: Vec<Op> = wb
            .plan
            .iter()
            .filter(|(at, _)| *at == p)
            .flat_map(|(_, o)| o.clone())
            .collect();
        (p, ops)
    };
    for op in ops {
        let t = w.borrow().t;
        let event = match op {
            Op::Trip => {
                s.check_watchdog(t);
                let tripped = s.check_watchdog(t.wrapping_add(1_000_000));
                if tripped {
                    w.borrow_mut().bus = *s.safe_outputs().words(); // the handler
                    w.borrow_mut().any_trip = true;
                }
                tripped
            }
            Op::Pf => {
                let was = s.power_failed();
                s.power_fail();
                w.borrow_mut().bus = *s.safe_outputs().words();
                let _ = was;
                true
            }
            Op::ResumeI => {
                if s.power_failed() {
                    w.borrow_mut().any_inhibit = true;
                }
                s.resume(Restart::Inhibit);
                false
            }
            Op::ResumeW => {
                s.resume(Restart::WhereStopped);
                false
            }
            Op::Reset => {
                s.reset_watchdog();
                false
            }
        };
        if event {
            let mut wb = w.borrow_mut();
            if point <= 9 {
                wb.events_before_confirm = true;
            } else {
                wb.events_after_confirm = true;
            }
        }
    }
}

impl Io<1, 3> for Plant {
    fn read_inputs(&mut self, raw: &mut [u16; 1]) {
        *raw = self.w.borrow().inputs;
        apply(&self.w, &self.s);
    }
    fn write_outputs(&mut self, out: &[u16; 3]) {
        for (i, word) in out.iter().enumerate() {
            apply(&self.w, &self.s);
            self.w.borrow_mut().bus[i] = *word;
            apply(&self.w, &self.s);
        }
    }
    fn now_us(&mut self) -> u32 {
        let t = {
            let mut w = self.w.borrow_mut();
            w.t = w.t.wrapping_add(1000);
            w.t
        };
        apply(&self.w, &self.s);
        t
    }
    fn kick_watchdog(&mut self) {
        apply(&self.w, &self.s);
    }
}

fn program(scan: &mut regler_scan_cycle::Scan<'_, 1, 3>) {
    let run = (scan.inputs.get(0) || scan.previous.get(0)) && !scan.inputs.get(1);
    scan.outputs.set(0, run).unwrap();
    scan.outputs.set(16, true).unwrap();
}

/// Points: 0 now(start), 1 read, 2 program, 3..=8 around the 3 words, 9 now(end), 10 kick.
fn one(plan: Vec<(usize, Vec<Op>)>, t0: u32) -> Result<(), String> {
    let config = CycleConfig {
        safe_outputs: Image::from_words(SAFE),
        ..CycleConfig::source()
    };
    let s = Rc::new(Signals::<1, 3>::new(&config));
    let w = Rc::new(RefCell::new(World {
        bus: [0; 3],
        t: t0,
        point: 100,
        plan: vec![],
        events_before_confirm: false,
        events_after_confirm: false,
        any_trip: false,
        any_inhibit: false,
        inputs: [1],
    }));
    let mut io = Plant {
        w: w.clone(),
        s: s.clone(),
    };
    let mut plc: Executive<1, 3> = Executive::new(config);
    // Cycle 1: start pressed, motor seals in.
    plc.cycle_with(&mut io, &s, program).unwrap();
    plc.cycle_with(&mut io, &s, program).unwrap();
    assert_eq!(w.borrow().bus[0] & 1, 1);
    {
        let mut wb = w.borrow_mut();
        wb.inputs = [0];
        wb.plan = plan.clone();
        wb.point = 0;
    }
    let ms_before = plc.now_ms();
    let s2 = s.clone();
    let w2 = w.clone();
    let r = plc.cycle_with(&mut io, &s, |scan| {
        apply(&w2, &s2);
        program(scan)
    });
    let wb = w.borrow();
    let ctx = format!("plan {plan:?}: r={r:?} bus={:04x?}", wb.bus);
    if plc.cycle_count() != plc.stats().cycles {
        return Err(format!(
            "{ctx}: cycle_count {} != stats {}",
            plc.cycle_count(),
            plc.stats().cycles
        ));
    }
    let halted_now = s.tripped() || s.power_failed();
    if wb.events_before_confirm {
        if r.is_ok() {
            return Err(format!("{ctx}: event before confirm but Ok"));
        }
    } else if !wb.events_after_confirm && r.is_err() {
        return Err(format!("{ctx}: no event but Err"));
    }
    if (wb.events_before_confirm || wb.events_after_confirm) && wb.bus != SAFE {
        return Err(format!("{ctx}: event but bus not safe"));
    }
    if r.is_err() && plc.cycle_count() != 2 {
        return Err(format!("{ctx}: halted cycle counted"));
    }
    let any_trip = wb.any_trip;
    let any_inhibit = wb.any_inhibit;
    let any_event = wb.events_before_confirm || wb.events_after_confirm;
    drop(wb);
    // While halted: the next cycle is refused and writes nothing.
    if halted_now {
        let bus = w.borrow().bus;
        w.borrow_mut().plan.clear();
        let r2 = plc.cycle_with(&mut io, &s, program);
        if r2.is_ok() || w.borrow().bus != bus {
            return Err(format!("{ctx}: halted but cycle ran ({r2:?})"));
        }
    }
    // Operator: 10 minutes later, reset and resume where stopped.
    w.borrow_mut().plan.clear();
    let tnow = w.borrow().t;
    w.borrow_mut().t = tnow.wrapping_add(600_000_000);
    s.reset_watchdog();
    s.resume(Restart::WhereStopped);
    let mut seen_ms = 0;
    let r3 = plc.cycle_with(&mut io, &s, |scan| {
        seen_ms = scan.now_ms;
        program(scan)
    });
    if r3.is_err() {
        return Err(format!("{ctx}: recovery cycle refused {r3:?}"));
    }
    let motor = w.borrow().bus[0] & 1 == 1;
    let want_motor = !(any_trip || any_inhibit);
    if motor != want_motor {
        return Err(format!(
            "{ctx}: motor {motor}, want {want_motor} (trip {any_trip}, inhibit {any_inhibit})"
        ));
    }
    if any_event {
        // No program time for the halt: at most the 2 ms of the halted cycle's own step.
        if seen_ms.wrapping_sub(ms_before) > 5 {
            return Err(format!(
                "{ctx}: halt added {} ms",
                seen_ms.wrapping_sub(ms_before)
            ));
        }
    }
    if plc.cycle_count() != plc.stats().cycles {
        return Err(format!("{ctx}: count mismatch at end"));
    }
    Ok(())
}

fn seqs() -> Vec<Vec<Op>> {
    let mut v = vec![];
    for a in OPS {
        v.push(vec![a]);
        for b in OPS {
            v.push(vec![a, b]);
            for c in OPS {
                v.push(vec![a, b, c]);
            }
        }
    }
    v
}

#[test]
#[cfg_attr(
    miri,
    ignore = "every sequence of operations at every point of three clocks: hours under Miri; runs natively in every CI run"
)]
fn every_op_sequence_at_every_point() {
    let mut fails = vec![];
    for t0 in [0u32, u32::MAX - 3500, (1 << 31) - 2500] {
        for p in 0..=10 {
            for seq in seqs() {
                if let Err(e) = one(vec![(p, seq)], t0) {
                    fails.push(e);
                }
            }
        }
        for p in 0..=10 {
            for q in p..=10 {
                for a in OPS {
                    for b in OPS {
                        if let Err(e) = one(vec![(p, vec![a]), (q, vec![b])], t0) {
                            fails.push(e);
                        }
                    }
                }
            }
        }
    }
    for f in fails.iter().take(30) {
        eprintln!("{f}");
    }
    assert!(fails.is_empty(), "{} failures", fails.len());
}

// ---------------------------------------------------------------------------------------------
// Focused attacks.

struct Simple {
    t: u32,
    step: u32,
    inputs: [u16; 1],
    out: [u16; 1],
    writes: u32,
}
impl Io<1, 1> for Simple {
    fn read_inputs(&mut self, raw: &mut [u16; 1]) {
        *raw = self.inputs;
    }
    fn write_outputs(&mut self, out: &[u16; 1]) {
        self.out = *out;
        self.writes += 1;
    }
    fn now_us(&mut self) -> u32 {
        self.t = self.t.wrapping_add(self.step);
        self.t
    }
}
fn simple() -> Simple {
    Simple {
        t: 0,
        step: 0,
        inputs: [0],
        out: [0],
        writes: 0,
    }
}

/// README: "[`Executive::check_watchdog`] the same watchdog from the main loop (sees hangs
/// between cycles only)"; Signals::power_fail: "A power failure is not a hang: while it lasts
/// nothing trips"; Signals::resume: "cycles may run again".
#[test]
fn executive_watchdog_trips_on_a_signals_outage() {
    let s: Signals<1, 1> = Signals::new(&CycleConfig::source());
    let mut io = simple();
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    for _ in 0..3 {
        io.t += 50_000;
        plc.cycle_with(&mut io, &s, |_| {}).unwrap();
        assert!(!plc.check_watchdog_with(&mut io, &s));
    }
    // The power fails (interrupt), the idle loop keeps checking.
    s.power_fail();
    io.t += 1_000_000;
    let tripped_during = plc.check_watchdog_with(&mut io, &s);
    s.resume(Restart::WhereStopped);
    let r = plc.cycle_with(&mut io, &s, |_| {});
    assert!(
        !tripped_during && r.is_ok(),
        "an outage of 1 s through Signals trips the executive's watchdog: tripped {tripped_during}, \
         next cycle {r:?}, trips {}",
        plc.watchdog_trips()
    );
}

/// Same, checked only after the power came back (before the first cycle).
#[test]
fn executive_watchdog_trips_right_after_signals_resume() {
    let s: Signals<1, 1> = Signals::new(&CycleConfig::source());
    let mut io = simple();
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    io.t = 50_000;
    plc.cycle_with(&mut io, &s, |_| {}).unwrap();
    s.power_fail();
    io.t += 1_000_000; // the outage
    s.resume(Restart::WhereStopped);
    io.t += 1_000;
    assert!(
        !plc.check_watchdog_with(&mut io, &s),
        "1 ms after the power came back the executive's watchdog trips (Signals' does not: {})",
        s.check_watchdog(io.t)
    );
}

/// The Signals trip is reset by the operator; the executive's own watchdog then trips at once.
#[test]
fn executive_watchdog_trips_after_signals_trip_reset() {
    let s: Signals<1, 1> = Signals::new(&CycleConfig::source());
    let mut io = simple();
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    io.t = 50_000;
    plc.cycle_with(&mut io, &s, |_| {}).unwrap();
    assert!(s.check_watchdog(io.t + 150_000));
    io.t += 60_000_000; // the operator takes a minute
    s.reset_watchdog();
    io.t += 1_000;
    assert!(
        !plc.check_watchdog_with(&mut io, &s),
        "reset Signals trip -> executive watchdog trips at once"
    );
}

/// README: "A `u32` µs clock cannot tell a gap of 2³¹ µs (35.8 min) or more between two cycles
/// from a step back: such a gap counts as none." and "a step under 2³¹ µs adds its µs".
/// After such a gap the program clock stands still for another 2³² − gap µs while cycles run
/// every 50 ms: a jam timer does not fire for up to 35.8 minutes.
#[test]
fn program_clock_stalls_after_a_long_gap() {
    let mut io = simple();
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    io.step = 0;
    io.t = 0;
    plc.cycle(&mut io, |_| {}).unwrap();
    // A gap of 2^31 + 1 ms with no halt (the main loop was held up, a debugger stop, ...).
    io.t = io.t.wrapping_add((1 << 31) + 1_000);
    plc.cycle(&mut io, |_| {}).unwrap();
    let after_gap = plc.now_ms();
    let mut jam = Ton::new(2_000);
    let mut fired_at = None;
    // Then 10 s of normal 50 ms cycles with the part sensor covered.
    for i in 0..200 {
        io.t = io.t.wrapping_add(50_000);
        plc.cycle(&mut io, |scan| {
            if jam.call(true, scan.now_ms) && fired_at.is_none() {
                fired_at = Some(i);
            }
        })
        .unwrap();
    }
    let gained = plc.now_ms().wrapping_sub(after_gap);
    assert!(
        gained >= 9_900 && fired_at.is_some(),
        "10 s of 50 ms cycles after a 2^31 µs gap added {gained} ms; the 2 s jam timer fired at {fired_at:?}"
    );
}

/// Signals::capture: "Captures go on through a power failure"; cycle_with: "Such a cycle is not
/// counted (cycle_count, statistics, images and Io::kick_watchdog as before it)".
/// A stop pulse latched just before a power blip is eaten by the cycle the halt overtook.
#[test]
fn latched_stop_pulse_is_lost_in_a_cycle_overtaken_by_a_power_blip() {
    let s: Signals<1, 1> = Signals::new(&CycleConfig::source());
    let mut io = simple();
    io.step = 1000;
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    const START: usize = 0;
    const STOP: usize = 1;
    plc.conditioning_mut().set_latched(STOP, true).unwrap();
    let prog = |scan: &mut regler_scan_cycle::Scan<'_, 1, 1>| {
        let run = (scan.inputs.get(START) || scan.previous.get(0)) && !scan.inputs.get(STOP);
        scan.outputs.set(0, run).unwrap();
    };
    io.inputs = [1 << START];
    plc.cycle_with(&mut io, &s, prog).unwrap();
    io.inputs = [0];
    plc.cycle_with(&mut io, &s, prog).unwrap();
    assert_eq!(io.out, [1], "motor sealed in");
    let inputs_before = *plc.inputs();
    // The operator taps STOP (shorter than a cycle): the fast input interrupt latches it.
    s.capture(&[1 << STOP]);
    // The power blips while the cycle runs its program.
    let r = plc.cycle_with(&mut io, &s, |scan| {
        s.power_fail();
        s.resume(Restart::WhereStopped);
        prog(scan)
    });
    assert_eq!(r, Err(Halt::PowerFail));
    let inputs_after_halt = *plc.inputs();
    let mut stop_seen = false;
    plc.cycle_with(&mut io, &s, |scan| {
        stop_seen = scan.inputs.get(STOP);
        prog(scan)
    })
    .unwrap();
    assert!(
        stop_seen && io.out == [0],
        "the latched stop pulse was consumed by the halted cycle: stop seen {stop_seen}, \
         motor {:?}; inputs() before {:?} after the halted cycle {:?}",
        io.out,
        inputs_before.words(),
        inputs_after_halt.words()
    );
}

/// Narrower: the input image of a halted cycle. cycle_with: "images ... as before it".
#[test]
fn halted_cycle_leaves_the_input_image_as_before() {
    let s: Signals<1, 1> = Signals::new(&CycleConfig::source());
    let mut io = simple();
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    io.inputs = [0];
    plc.cycle_with(&mut io, &s, |_| {}).unwrap();
    io.inputs = [0xffff];
    let r = plc.cycle_with(&mut io, &s, |_| s.power_fail());
    assert_eq!(r, Err(Halt::PowerFail));
    assert_eq!(
        plc.inputs().words(),
        &[0],
        "inputs() shows the halted cycle's image"
    );
}

/// Docs of check_breakpoints: "Refuses breakpoints that could never fire". Cycle(n) with n
/// already passed can never fire (the count only grows) and is not refused; a continuous run
/// "to cycle 4" after cycle 10 never stops.
#[test]
fn a_passed_cycle_breakpoint_is_not_refused() {
    let mut io = simple();
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    plc.run(&mut io, 10, &[], |_| {}, |_, _| {}).unwrap();
    let r = plc.check_breakpoints(&[Breakpoint::Cycle(4)]);
    let ran = plc.run(&mut io, 1000, &[Breakpoint::Cycle(4)], |_| {}, |_, _| {});
    assert!(
        r.is_err(),
        "Cycle(4) after cycle 10 accepted; run gave {ran:?}"
    );
    let want = Err(regler_scan_cycle::BreakpointError::CyclePassed {
        cycle: 4,
        count: 10,
    });
    assert_eq!(r, want);
    assert_eq!(
        ran,
        Err(regler_scan_cycle::BreakpointError::CyclePassed {
            cycle: 4,
            count: 10
        }),
        "run refuses it before running a cycle"
    );
    assert_eq!(plc.cycle_count(), 10);
    assert_eq!(
        plc.check_breakpoints(&[Breakpoint::Cycle(10)]),
        Err(regler_scan_cycle::BreakpointError::CyclePassed {
            cycle: 10,
            count: 10
        })
    );
    assert_eq!(plc.check_breakpoints(&[Breakpoint::Cycle(11)]), Ok(()));
    assert_eq!(
        plc.run(&mut io, 1000, &[Breakpoint::Cycle(11)], |_| {}, |_, _| {}),
        Ok((1, Some(Halt::Breakpoint(Breakpoint::Cycle(11)))))
    );
}

/// The bus write holds no critical section: a power failure from another thread (a second
/// core / an interrupt) during a slow write completes while the write is running, and the safe
/// outputs are the last thing on the bus.
#[test]
fn power_fail_from_another_thread_during_a_slow_write() {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::{Arc, Mutex};
    use std::time::Duration;
    let config = CycleConfig {
        safe_outputs: Image::from_words([0x00f0]),
        ..CycleConfig::source()
    };
    let s: Arc<Signals<1, 1>> = Arc::new(Signals::new(&config));
    let bus = Arc::new(Mutex::new(Vec::<u16>::new()));
    struct Slow {
        s: Arc<Signals<1, 1>>,
        bus: Arc<Mutex<Vec<u16>>>,
        fire: bool,
        done_in_write: Arc<AtomicBool>,
        t: u32,
    }
    impl Io<1, 1> for Slow {
        fn read_inputs(&mut self, raw: &mut [u16; 1]) {
            *raw = [0];
        }
        fn write_outputs(&mut self, out: &[u16; 1]) {
            if self.fire {
                self.fire = false;
                let (s, bus, flag) = (self.s.clone(), self.bus.clone(), self.done_in_write.clone());
                let h = std::thread::spawn(move || {
                    s.power_fail();
                    bus.lock().unwrap().push(s.safe_outputs().words()[0]);
                    flag.store(true, Ordering::SeqCst);
                });
                // The write is slow; wait (bounded) for the interrupt to finish.
                for _ in 0..200 {
                    if self.done_in_write.load(Ordering::SeqCst) {
                        break;
                    }
                    std::thread::sleep(Duration::from_millis(5));
                }
                self.bus.lock().unwrap().push(out[0]);
                h.join().unwrap();
                return;
            }
            self.bus.lock().unwrap().push(out[0]);
        }
        fn now_us(&mut self) -> u32 {
            self.t += 1000;
            self.t
        }
    }
    let flag = Arc::new(AtomicBool::new(false));
    let mut io = Slow {
        s: s.clone(),
        bus: bus.clone(),
        fire: false,
        done_in_write: flag.clone(),
        t: 0,
    };
    let mut plc: Executive<1, 1> = Executive::new(config);
    plc.cycle_with(&mut io, &s, |sc| sc.outputs.set(0, true).unwrap())
        .unwrap();
    io.fire = true;
    let r = plc.cycle_with(&mut io, &s, |sc| sc.outputs.set(0, true).unwrap());
    assert!(
        flag.load(Ordering::SeqCst),
        "the interrupt could not get in during the write"
    );
    assert_eq!(r, Err(Halt::PowerFail));
    assert_eq!(*bus.lock().unwrap().last().unwrap(), 0x00f0);
    assert_eq!(plc.cycle_count(), plc.stats().cycles);
}

#[test]
fn watchdog_limits_0_1_max_both_watchdogs() {
    for limit in [
        0u32,
        1,
        2,
        (1 << 31) - 3,
        (1 << 31) - 2,
        (1 << 31) - 1,
        1 << 31,
        u32::MAX,
    ] {
        let eff = limit.min((1 << 31) - 2);
        for kick in [0u32, 1, (1 << 31) - 1, 1 << 31, u32::MAX - 5, u32::MAX] {
            let config = CycleConfig {
                watchdog_us: limit,
                ..CycleConfig::source()
            };
            // Signals
            let s: Signals<1, 1> = Signals::new(&config);
            let mut io = simple();
            io.t = kick;
            let mut plc: Executive<1, 1> = Executive::new(config);
            plc.cycle_with(&mut io, &s, |_| {}).unwrap();
            // cycle end = kick (step 0)
            for d in [
                0u32,
                1,
                eff.saturating_sub(1),
                eff,
                eff + 1,
                (1 << 31) - 1,
                1 << 31,
                u32::MAX,
            ] {
                let s2: Signals<1, 1> = Signals::new(&config);
                let mut p2: Executive<1, 1> = Executive::new(config);
                let mut io2 = simple();
                io2.t = kick;
                p2.cycle_with(&mut io2, &s2, |_| {}).unwrap();
                let want = d > eff && d < (1 << 31);
                let got = s2.check_watchdog(kick.wrapping_add(d));
                assert_eq!(got, want, "Signals limit {limit} kick {kick} d {d}");
                let mut io3 = simple();
                io3.t = kick;
                let mut p3: Executive<1, 1> = Executive::new(config);
                p3.cycle(&mut io3, |_| {}).unwrap();
                io3.t = kick.wrapping_add(d);
                assert_eq!(
                    p3.check_watchdog(&mut io3),
                    want,
                    "exec limit {limit} kick {kick} d {d}"
                );
                if want {
                    assert_eq!(p3.cycle(&mut io3, |_| {}), Err(Halt::Watchdog));
                    assert_eq!(p3.cycle_count(), 1);
                }
            }
        }
    }
}

#[test]
fn reserve_runs_nothing_while_halted_and_halt_mid_spool() {
    use regler_scan_cycle::Spool;
    let s: Signals<1, 1> = Signals::new(&CycleConfig::source());
    let mut io = simple();
    io.step = 10;
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    plc.cycle_with(&mut io, &s, |_| {}).unwrap();
    let mut spool: Spool<u32, 8> = Spool::new();
    for j in 0..8 {
        spool.push(j).unwrap();
    }
    // A job that fails the power: no further job.
    let n = plc.reserve_with(&mut io, &s, &mut spool, 0, |j| {
        if j == 2 {
            s.power_fail();
        }
    });
    assert_eq!(n, 3);
    assert_eq!(plc.reserve_with(&mut io, &s, &mut spool, 0, |_| {}), 0);
    s.resume(Restart::Inhibit);
    // A job that trips the watchdog.
    let n = plc.reserve_with(&mut io, &s, &mut spool, 0, |_| {
        s.check_watchdog(0);
        assert!(s.check_watchdog(io_time_far()));
    });
    assert_eq!(n, 1);
    assert_eq!(plc.reserve_with(&mut io, &s, &mut spool, 0, |_| {}), 0);
    // A job longer than the reserve: only one.
    s.reset_watchdog();
    plc.cycle_with(&mut io, &s, |_| {}).unwrap();
    let t = std::cell::Cell::new(0u32);
    let _ = t;
    // Executive's own halt
    io.t += 10_000_000;
    assert!(plc.check_watchdog(&mut io));
    assert_eq!(plc.reserve(&mut io, &mut spool, 0, |_| {}), 0);
    assert_eq!(plc.stats().spool_jobs, 4);
}
fn io_time_far() -> u32 {
    50_000_000
}

/// Resume with WhereStopped after a Signals trip does not undo the trip; reset after it restarts
/// from safe. Also trip -> power_fail -> reset -> resume(WhereStopped).
#[test]
fn trip_power_orders() {
    for order in 0..6 {
        let config = CycleConfig::source();
        let s: Signals<1, 1> = Signals::new(&config);
        let mut io = simple();
        io.step = 1000;
        let mut plc: Executive<1, 1> = Executive::new(config);
        let prog = |scan: &mut regler_scan_cycle::Scan<'_, 1, 1>| {
            let run = (scan.inputs.get(0) || scan.previous.get(0)) && !scan.inputs.get(1);
            scan.outputs.set(0, run).unwrap();
        };
        io.inputs = [1];
        plc.cycle_with(&mut io, &s, prog).unwrap();
        io.inputs = [0];
        let t = io.t;
        let ops: [&dyn Fn(); 3] = [
            &|| {
                s.check_watchdog(t);
                s.check_watchdog(t + 10_000_000);
            },
            &|| s.power_fail(),
            &|| s.reset_watchdog(),
        ];
        let perms = [
            [0, 1, 2],
            [0, 2, 1],
            [1, 0, 2],
            [1, 2, 0],
            [2, 0, 1],
            [2, 1, 0],
        ];
        for &i in &perms[order] {
            ops[i]();
        }
        s.resume(Restart::WhereStopped);
        s.reset_watchdog();
        plc.cycle_with(&mut io, &s, prog).unwrap();
        let tripped = s.trips() > 0;
        // motor must be off whenever a trip happened
        if tripped {
            assert_eq!(io.out, [0], "order {:?}", perms[order]);
        }
    }
}

/// Consequence of the halted cycle keeping its input image: an InputOn breakpoint whose input
/// came on in a cycle a power blip overtook never fires when the run is continued.
#[test]
fn input_breakpoint_missed_after_a_halted_cycle() {
    let s: Signals<1, 1> = Signals::new(&CycleConfig::source());
    let mut io = simple();
    io.step = 1000;
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    let bp = [Breakpoint::InputOn(0)];
    assert_eq!(
        plc.run_with(&mut io, &s, 3, &bp, |_| {}, |_, _| {})
            .unwrap(),
        (3, None)
    );
    io.inputs = [1];
    let (n, h) = plc
        .run_with(
            &mut io,
            &s,
            3,
            &bp,
            |_| {
                s.power_fail();
                s.resume(Restart::WhereStopped);
            },
            |_, _| {},
        )
        .unwrap();
    assert_eq!((n, h), (0, Some(Halt::PowerFail)));
    // The monitor continues: input 0 is on, and was off after the last cycle that ran.
    let r = plc
        .run_with(&mut io, &s, 3, &bp, |_| {}, |_, _| {})
        .unwrap();
    assert_eq!(
        r,
        (1, Some(Halt::Breakpoint(Breakpoint::InputOn(0)))),
        "breakpoint missed"
    );
}

// ---------------------------------------------------------------------------------------------
// Beyond the reproducers: the rules the fixes state, over their classes.

use proptest::prelude::*;

proptest! {
    /// `now_ms`: a clock that moves to a new base (a step back of any size, or a gap of 2³¹ µs
    /// or more) once, between cycles of a steady period, loses exactly the interval into the
    /// cycle that first read the new base: every other period counts, and the clock stands
    /// still for that one cycle at most. Model: the sum of the steady periods.
    #[test]
    fn a_new_clock_base_costs_one_cycle_and_no_more(
        start in any::<u32>(),
        period in 1u32..200_000,
        jump in (1u32 << 31)..=u32::MAX,
        before in 1usize..20,
        after in 1usize..40,
    ) {
        let mut io = simple();
        io.t = start;
        let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
        plc.cycle(&mut io, |_| {}).unwrap();
        let mut model_us = 0u64;
        for i in 0..before + 1 + after {
            if i == before {
                io.t = io.t.wrapping_add(jump);
            } else {
                io.t = io.t.wrapping_add(period);
                model_us += u64::from(period);
            }
            let was = plc.now_ms();
            plc.cycle(&mut io, |_| {}).unwrap();
            prop_assert_eq!(u64::from(plc.now_ms()), model_us / 1000, "cycle {}", i);
            if i > before && period >= 1000 {
                prop_assert!(plc.now_ms() != was, "frozen at cycle {}", i);
            }
        }
    }
}

/// `now_ms`: what a glitch two readings long costs. A clock that reads d behind for two
/// readings p apart, both behind the reference (the last good reading, one period p before the
/// first), makes the second count on from the first (a new base), and the true reading after
/// count on from the second: the clock gains d − p. A glitch read once costs nothing, nor one
/// whose second reading is forward of the reference again (a 16-bit timer's 65 536 µs at 50 ms).
#[test]
fn a_two_reading_glitch_gains_the_glitch_less_one_period() {
    let p = 50_000u32;
    for (d, glitch_readings, want_extra_us) in [
        (150_000u32, 2u32, 150_000 - 50_000),
        (1_000_000, 2, 1_000_000 - 50_000),
        (65_536, 2, 0),
        (150_000, 1, 0),
        (1_000_000, 1, 0),
    ] {
        let mut io = simple();
        io.t = 10_000_000;
        let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
        plc.cycle(&mut io, |_| {}).unwrap();
        let t0 = io.t;
        for k in 1..=5u32 {
            io.t = t0 + k * p - if k <= glitch_readings { d } else { 0 };
            plc.cycle(&mut io, |_| {}).unwrap();
        }
        assert_eq!(
            plc.now_ms(),
            (5 * p + want_extra_us) / 1000,
            "d {d}, {glitch_readings} readings"
        );
    }
}

/// Both watchdogs: a permanent step back of the clock holds them off only until the next cycle
/// ends, which re-arms them at the new base; then they trip exactly past the limit.
#[test]
fn a_permanent_step_back_holds_the_watchdogs_off_until_the_next_cycle() {
    for back in [1u32, 1_000, 10_000_000, 1 << 31, u32::MAX] {
        let s: Signals<1, 1> = Signals::new(&CycleConfig::source());
        let mut io = simple();
        io.t = 7_000_000;
        let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
        plc.cycle_with(&mut io, &s, |_| {}).unwrap();
        io.t = io.t.wrapping_sub(back);
        plc.cycle_with(&mut io, &s, |_| {}).unwrap();
        let end = io.t;
        assert!(!s.check_watchdog(end.wrapping_add(100_000)), "back {back}");
        assert!(s.check_watchdog(end.wrapping_add(100_001)), "back {back}");
        let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
        io.t = 7_000_000;
        plc.cycle(&mut io, |_| {}).unwrap();
        io.t = io.t.wrapping_sub(back);
        plc.cycle(&mut io, |_| {}).unwrap();
        let end = io.t;
        io.t = end.wrapping_add(100_000);
        assert!(!plc.check_watchdog(&mut io), "back {back}");
        io.t = end.wrapping_add(100_001);
        assert!(plc.check_watchdog(&mut io), "back {back}");
    }
}

/// A halted cycle keeps every pulse it read pending, whatever way it came: captured by
/// `Signals`, captured by `Executive::capture` between cycles, or on in its own raw read of a
/// latched input. Unlatched inputs are not kept (a level is read again). Forcing plays no part.
#[test]
fn a_halted_cycle_keeps_every_latched_pulse_it_read() {
    for way in 0..3 {
        for halt_at_write in [false, true] {
            let s: Signals<1, 1> = Signals::new(&CycleConfig::source());
            let mut io = simple();
            io.step = 1000;
            let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
            plc.conditioning_mut().set_latched(3, true).unwrap();
            plc.force_input(9, true).unwrap();
            plc.cycle_with(&mut io, &s, |_| {}).unwrap();
            let (raw_before, inputs_before) = (*plc.raw_inputs(), *plc.inputs());
            match way {
                0 => s.capture(&[1 << 3 | 1 << 5]),
                1 => plc.capture(&[1 << 3 | 1 << 5]),
                _ => io.inputs = [1 << 3 | 1 << 5],
            }
            let r = plc.cycle_with(&mut io, &s, |sc| {
                assert!(sc.inputs.get(3));
                if !halt_at_write {
                    s.power_fail();
                }
            });
            if halt_at_write {
                // The halt came only after the write: power_fail from the next clock read.
                assert!(r.is_ok());
                continue;
            }
            assert_eq!(r, Err(Halt::PowerFail));
            assert_eq!(
                (*plc.raw_inputs(), *plc.inputs()),
                (raw_before, inputs_before)
            );
            assert_eq!(plc.cycle_count(), 1);
            s.resume(Restart::WhereStopped);
            io.inputs = [0];
            let mut seen = (false, false);
            plc.cycle_with(&mut io, &s, |sc| {
                seen = (sc.inputs.get(3), sc.inputs.get(5))
            })
            .unwrap();
            assert_eq!(seen, (true, false), "way {way}");
            plc.cycle_with(&mut io, &s, |sc| {
                seen = (sc.inputs.get(3), sc.inputs.get(5))
            })
            .unwrap();
            assert_eq!(seen, (false, false), "read once, way {way}");
        }
    }
}

/// `check_watchdog_with`, every order of power failure, resume, trip, reset and check through
/// `Signals` (each op at most once, up to four of them, with a check after each and 10 s of
/// clock between): the executive's own watchdog never trips while the cycles are refused by
/// `Signals` nor at any check after, before the first cycle has had the limit to run.
#[test]
#[cfg_attr(
    miri,
    ignore = "every order of up to four of five events (781 runs), each against the model: minutes under Miri; runs natively in every CI run"
)]
fn check_watchdog_with_never_trips_on_a_signals_halt_in_any_order() {
    #[derive(Clone, Copy, Debug)]
    enum E {
        Pf,
        ResumeW,
        ResumeI,
        Trip,
        Reset,
    }
    let all = [E::Pf, E::ResumeW, E::ResumeI, E::Trip, E::Reset];
    let mut orders: Vec<Vec<E>> = vec![vec![]];
    for _ in 0..4 {
        let mut next = vec![];
        for o in &orders {
            for &e in &all {
                let mut v = o.clone();
                v.push(e);
                next.push(v);
            }
        }
        orders.extend(next);
    }
    for order in orders {
        let s: Signals<1, 1> = Signals::new(&CycleConfig::source());
        let mut io = simple();
        let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
        plc.cycle_with(&mut io, &s, |_| {}).unwrap();
        for &e in &order {
            match e {
                E::Pf => s.power_fail(),
                E::ResumeW => s.resume(Restart::WhereStopped),
                E::ResumeI => s.resume(Restart::Inhibit),
                E::Trip => {
                    s.check_watchdog(io.t);
                    s.check_watchdog(io.t.wrapping_add(10_000_000));
                }
                E::Reset => s.reset_watchdog(),
            }
            // While Signals refuses cycles, 10 s pass and nothing trips; otherwise 1 ms.
            let halted = s.tripped() || s.power_failed();
            assert!(
                !plc.check_watchdog_with(&mut io, &s),
                "{order:?} after {e:?}"
            );
            io.t = io.t.wrapping_add(if halted { 10_000_000 } else { 1_000 });
            assert!(
                !plc.check_watchdog_with(&mut io, &s),
                "{order:?} after {e:?}, halted {halted}"
            );
        }
        // Whatever happened, once Signals lets cycles run: the next check re-arms or counts
        // from the last cycle, and a cycle runs.
        s.resume(Restart::Inhibit);
        s.reset_watchdog();
        let quiet = !plc.check_watchdog_with(&mut io, &s);
        let r = plc.cycle_with(&mut io, &s, |_| {});
        if quiet {
            assert!(r.is_ok(), "{order:?}: {r:?}");
        }
        // A hang after that cycle still trips, exactly past the limit.
        let end = io.t;
        io.t = end.wrapping_add(100_000);
        assert!(!plc.check_watchdog_with(&mut io, &s) || !quiet, "{order:?}");
        io.t = end.wrapping_add(100_001);
        assert!(plc.check_watchdog_with(&mut io, &s), "{order:?}");
    }
}

/// `set_now_ms`: the first cycle after it sees exactly the value set, the clock counts on from
/// there (wrapping at 2³² ms), and a timer kept across the "power cycle" (a new executive) goes
/// on where it stood — without serde, so every build checks it.
#[test]
fn set_now_ms_restores_the_program_clock() {
    for saved in [0u32, 1, 123_456_789, u32::MAX - 20] {
        let mut io = simple();
        io.t = 999;
        let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
        plc.set_now_ms(saved);
        let mut ton = Ton::new(1_000);
        let mut seen = Vec::new();
        let mut fired = None;
        for i in 0..30u32 {
            plc.cycle(&mut io, |s| {
                seen.push(s.now_ms);
                if ton.call(true, s.now_ms) && fired.is_none() {
                    fired = Some(i);
                }
            })
            .unwrap();
            io.t = io.t.wrapping_add(50_000);
        }
        let want: Vec<u32> = (0..30).map(|i| saved.wrapping_add(50 * i)).collect();
        assert_eq!(seen, want, "saved {saved}");
        assert_eq!(fired, Some(20), "saved {saved}");
        // Between cycles: the µs since the last cycle are dropped.
        io.t = io.t.wrapping_add(12_345_000);
        plc.set_now_ms(7);
        plc.cycle(&mut io, |s| assert_eq!(s.now_ms, 7)).unwrap();
    }
}
