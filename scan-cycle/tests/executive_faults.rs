//! The executive under the plant's faults (issue 24): a trip or a power failure at every moment
//! of a cycle, the restart after a halt, the monitor and reserve over `Signals`, clocks that
//! wrap, jump and step back, breakpoints that cannot fire.
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "a test may panic: that is how it fails"
)]

use std::cell::{Cell, RefCell};
use std::vec::Vec;

use proptest::prelude::{any, prop, prop_assert_eq, prop_oneof, proptest};
use proptest::strategy::Strategy;
use regler_scan_cycle::{
    Breakpoint, BreakpointError, CycleConfig, Executive, Halt, Image, Io, Restart, Scan, Signals,
    Spool, Ton,
};

const OW: usize = 3;
const SAFE: [u16; OW] = [0b100, 0, 0x8000];
const PROGRAM: [u16; OW] = [0b011, 0xffff, 0x0001];

fn config() -> CycleConfig<OW> {
    CycleConfig {
        safe_outputs: Image::from_words(SAFE),
        ..CycleConfig::source()
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Interrupt {
    /// The timer interrupt finds the watchdog overdue.
    Trip,
    /// The power-fail interrupt.
    PowerFail,
    /// A trip, and the operator's reset before the cycle's write is done.
    TripAndReset,
    /// A power failure and the power back before the cycle's write is done.
    Blip,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Write {
    Program(usize, u16),
    SafeByIsr(usize, u16),
    SafeByMain(usize, u16),
}

/// The bus and the interrupt that fires at one chosen step: every `Io` call and every word of
/// an output write is a step, and so is the program (through `Bus::step`).
struct Bus<'a> {
    signals: &'a Signals<2, OW>,
    out: RefCell<[u16; OW]>,
    log: RefCell<Vec<Write>>,
    steps: Cell<u32>,
    fire_at: Cell<Option<u32>>,
    interrupt: Interrupt,
    fired: Cell<bool>,
    t: Cell<u32>,
    kicks: Cell<u32>,
}

impl<'a> Bus<'a> {
    fn new(signals: &'a Signals<2, OW>, interrupt: Interrupt) -> Bus<'a> {
        Bus {
            signals,
            out: RefCell::new([0; OW]),
            log: RefCell::new(Vec::new()),
            steps: Cell::new(0),
            fire_at: Cell::new(None),
            interrupt,
            fired: Cell::new(false),
            t: Cell::new(1_000),
            kicks: Cell::new(0),
        }
    }

    /// One step of the main context; the interrupt fires here if this is its step.
    fn step(&self) {
        let n = self.steps.get();
        self.steps.set(n + 1);
        if self.fire_at.get() == Some(n) {
            self.fire();
        }
    }

    /// The interrupt handler, as firmware has it: the watchdog check or the power-fail flag,
    /// then the safe outputs on the bus.
    fn fire(&self) {
        let write_safe = match self.interrupt {
            Interrupt::Trip => self
                .signals
                .check_watchdog(self.t.get().wrapping_add(10_000_000)),
            Interrupt::PowerFail => {
                self.signals.power_fail();
                true
            }
            Interrupt::TripAndReset => {
                let tripped = self
                    .signals
                    .check_watchdog(self.t.get().wrapping_add(10_000_000));
                self.signals.reset_watchdog();
                tripped
            }
            Interrupt::Blip => {
                self.signals.power_fail();
                self.signals.resume(Restart::WhereStopped);
                true
            }
        };
        if write_safe {
            self.fired.set(true);
            for (i, w) in self.signals.safe_outputs().words().iter().enumerate() {
                self.out.borrow_mut()[i] = *w;
                self.log.borrow_mut().push(Write::SafeByIsr(i, *w));
            }
        }
    }
}

struct Plant<'b, 'a>(&'b Bus<'a>);

impl Io<2, OW> for Plant<'_, '_> {
    fn read_inputs(&mut self, raw: &mut [u16; 2]) {
        self.0.step();
        *raw = [1, 0];
    }
    fn write_outputs(&mut self, outputs: &[u16; OW]) {
        let safe = outputs == &SAFE;
        for (i, w) in outputs.iter().enumerate() {
            self.0.step();
            self.0.out.borrow_mut()[i] = *w;
            self.0.log.borrow_mut().push(if safe {
                Write::SafeByMain(i, *w)
            } else {
                Write::Program(i, *w)
            });
        }
        self.0.step();
    }
    fn now_us(&mut self) -> u32 {
        self.0.step();
        self.0.t.get()
    }
    fn kick_watchdog(&mut self) {
        self.0.kicks.set(self.0.kicks.get() + 1);
        self.0.step();
    }
}

/// One supervised cycle whose program sets `PROGRAM`, the interrupt firing at `fire_at`.
fn cycle_firing(
    plc: &mut Executive<2, OW>,
    bus: &Bus<'_>,
    fire_at: Option<u32>,
) -> Result<(), Halt> {
    bus.steps.set(0);
    bus.fire_at.set(fire_at);
    bus.t.set(bus.t.get().wrapping_add(50_000));
    let signals = bus.signals;
    plc.cycle_with(&mut Plant(bus), signals, |scan| {
        bus.step();
        *scan.outputs = Image::from_words(PROGRAM);
    })
}

/// Items 1 and 3: whatever the moment the trip or the power failure comes — before the cycle,
/// while it reads, while the program runs, before, between or after any word of the output
/// write, at the end — the last thing on the bus is the safe outputs, and the cycle reports the
/// halt unless the interrupt came after the cycle had committed its outputs (then the next
/// cycle is refused).
#[test]
#[cfg_attr(
    miri,
    ignore = "a trip and a power failure at every moment of a cycle: a minute interpreted; runs natively in every CI run"
)]
fn a_trip_or_power_failure_at_every_moment_of_a_cycle_leaves_the_safe_outputs() {
    for interrupt in [
        Interrupt::Trip,
        Interrupt::PowerFail,
        Interrupt::TripAndReset,
        Interrupt::Blip,
    ] {
        let lasts = matches!(interrupt, Interrupt::Trip | Interrupt::PowerFail);
        // The number of steps of a cycle without an interrupt.
        let total = {
            let signals = Signals::new(&config());
            let bus = Bus::new(&signals, interrupt);
            let mut plc = Executive::new(config());
            cycle_firing(&mut plc, &bus, None).unwrap();
            bus.steps.get()
        };
        assert!(total >= 7, "{total}");
        for fire_at in 0..=total {
            let signals = Signals::new(&config());
            let bus = Bus::new(&signals, interrupt);
            let mut plc = Executive::new(config());
            cycle_firing(&mut plc, &bus, None).unwrap();
            bus.log.borrow_mut().clear();
            bus.kicks.set(0);
            let halt = match interrupt {
                Interrupt::Trip | Interrupt::TripAndReset => Halt::Watchdog,
                Interrupt::PowerFail | Interrupt::Blip => Halt::PowerFail,
            };
            let mut result = cycle_firing(&mut plc, &bus, Some(fire_at));
            let completed = u64::from(result.is_ok());
            // The hardware watchdog is pulsed only by a cycle whose write was confirmed.
            assert_eq!(
                u64::from(bus.kicks.get()),
                completed,
                "{interrupt:?} at {fire_at}"
            );
            if fire_at == total && lasts {
                // After the cycle has returned: the next cycle must be refused.
                bus.fire();
                assert!(result.is_ok());
                result = cycle_firing(&mut plc, &bus, None);
            }
            if !lasts {
                if fire_at == total {
                    continue; // nothing to see: the halt came and went between cycles
                }
                assert_eq!(*bus.out.borrow(), SAFE, "{interrupt:?} at step {fire_at}");
                assert_eq!(
                    result.is_err(),
                    fire_at + 1 < total,
                    "{interrupt:?} {fire_at}"
                );
                if let Err(h) = result {
                    assert_eq!(h, halt, "{interrupt:?} at step {fire_at}");
                }
                continue;
            }
            let log = bus.log.borrow().clone();
            assert!(bus.fired.get(), "{interrupt:?} at step {fire_at}");
            assert_eq!(
                *bus.out.borrow(),
                SAFE,
                "{interrupt:?} at step {fire_at}: {log:?}"
            );
            match result {
                Err(h) => assert_eq!(h, halt, "{interrupt:?} at step {fire_at}"),
                Ok(()) => {
                    // Only an interrupt after the commit may leave the cycle Ok: the program's
                    // outputs were all written before it, and the next cycle is refused.
                    let last_program = log.iter().rposition(|w| matches!(w, Write::Program(..)));
                    let first_isr = log.iter().position(|w| matches!(w, Write::SafeByIsr(..)));
                    assert!(
                        last_program < first_isr,
                        "{interrupt:?} at step {fire_at}: {log:?}"
                    );
                    assert_eq!(
                        plc.cycle_with(&mut Plant(&bus), &signals, |_| {}),
                        Err(halt)
                    );
                }
            }
            // A halted cycle is not a cycle: counts and statistics agree.
            assert_eq!(
                plc.cycle_count(),
                1 + completed,
                "{interrupt:?} at {fire_at}"
            );
            assert_eq!(
                plc.stats().cycles,
                1 + completed,
                "{interrupt:?} at {fire_at}"
            );
            // Only an interrupt after the write was confirmed (the hardware watchdog's kick,
            // after the cycle) lets the cycle complete.
            assert_eq!(
                completed == 1,
                fire_at + 1 >= total,
                "{interrupt:?} at {fire_at}"
            );
            // Nothing is written while the halt lasts.
            let before = bus.log.borrow().len();
            assert_eq!(cycle_firing(&mut plc, &bus, None), Err(halt));
            assert_eq!(bus.log.borrow().len(), before);
        }
    }
}

/// Item 3: the output write runs outside the critical section — an interrupt (here another
/// thread, which the `std` critical section blocks while the section is held) gets in while the
/// bus write is going on, and trips the watchdog of a write that hangs.
#[test]
fn the_output_write_does_not_hold_the_critical_section() {
    use std::sync::mpsc;
    use std::time::Duration;
    static SIGNALS: Signals<1, 1> = Signals::new(&CycleConfig::source());
    struct SlowBus {
        got_in: Option<bool>,
    }
    impl Io<1, 1> for SlowBus {
        fn read_inputs(&mut self, raw: &mut [u16; 1]) {
            *raw = [0];
        }
        fn write_outputs(&mut self, out: &[u16; 1]) {
            if out == &[1] && self.got_in.is_none() {
                // The timer interrupt, 1 s after the last cycle: the write hangs.
                let (tx, rx) = mpsc::channel();
                std::thread::spawn(move || {
                    tx.send(SIGNALS.check_watchdog(1_000_000)).ok();
                });
                self.got_in = rx.recv_timeout(Duration::from_secs(2)).ok();
            }
        }
        fn now_us(&mut self) -> u32 {
            0
        }
    }
    let mut bus = SlowBus { got_in: None };
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    plc.cycle_with(&mut bus, &SIGNALS, |_| {}).unwrap(); // kicks at 0
    let r = plc.cycle_with(&mut bus, &SIGNALS, |s| s.outputs.set(0, true).unwrap());
    assert_eq!(
        bus.got_in,
        Some(true),
        "the interrupt ran and tripped during the write"
    );
    assert_eq!(r, Err(Halt::Watchdog));
}

/// A plain bench for the executive's own watchdog and power failure.
struct Bench {
    inputs: [u16; 2],
    out: [u16; OW],
    writes: Vec<[u16; OW]>,
    t: u32,
}

impl Io<2, OW> for Bench {
    fn read_inputs(&mut self, raw: &mut [u16; 2]) {
        *raw = self.inputs;
    }
    fn write_outputs(&mut self, outputs: &[u16; OW]) {
        self.out = *outputs;
        self.writes.push(*outputs);
    }
    fn now_us(&mut self) -> u32 {
        self.t
    }
}

fn bench() -> Bench {
    Bench {
        inputs: [0; 2],
        out: [0; OW],
        writes: Vec::new(),
        t: 0,
    }
}

const START: usize = 0;
const STOP: usize = 1;
const MOTOR: usize = 0;

/// The README's seal-in rung.
fn seal_in(scan: &mut Scan<'_, 2, OW>) {
    let running = (scan.inputs.get(START) || scan.previous.get(MOTOR)) && !scan.inputs.get(STOP);
    scan.outputs.set(MOTOR, running).unwrap();
}

/// Starts the motor (START pressed for one cycle, then released).
fn motor_running(plc: &mut Executive<2, OW>, io: &mut Bench) {
    io.inputs = [1 << START, 0];
    io.t = io.t.wrapping_add(50_000);
    plc.cycle(io, seal_in).unwrap();
    io.inputs = [0, 0];
    io.t = io.t.wrapping_add(50_000);
    plc.cycle(io, seal_in).unwrap();
    assert!(io.out[0] & 1 == 1, "motor sealed in");
}

/// Item 2: after a trip of the executive's own watchdog and the operator's reset, the previous
/// image is the safe outputs the plant has: the sealed-in motor stays off without START.
#[test]
fn a_sealed_in_motor_stays_off_after_a_trip_and_reset() {
    let mut io = bench();
    let mut plc = Executive::new(config());
    motor_running(&mut plc, &mut io);
    io.t = io.t.wrapping_add(200_000);
    assert!(plc.check_watchdog(&mut io));
    assert_eq!(io.out, SAFE);
    assert_eq!(plc.outputs().words(), &SAFE, "the image the plant has");
    plc.reset_watchdog();
    io.t = io.t.wrapping_add(50_000);
    plc.cycle(&mut io, |scan| {
        assert_eq!(scan.previous.words(), &SAFE);
        seal_in(scan);
    })
    .unwrap();
    assert_eq!(io.out[0] & 1, 0, "the motor restarted by itself");
}

/// Item 2 through `Signals`, for a trip between cycles and one inside a cycle.
#[test]
fn a_sealed_in_motor_stays_off_after_a_signals_trip_and_reset() {
    for inside in [false, true] {
        let signals: Signals<2, OW> = Signals::new(&config());
        let mut io = bench();
        let mut plc = Executive::new(config());
        io.inputs = [1 << START, 0];
        plc.cycle_with(&mut io, &signals, seal_in).unwrap();
        io.inputs = [0, 0];
        let trip = || {
            assert!(signals.check_watchdog(1_000_000));
        };
        if inside {
            assert_eq!(
                plc.cycle_with(&mut io, &signals, |s| {
                    trip();
                    seal_in(s);
                }),
                Err(Halt::Watchdog)
            );
        } else {
            trip();
        }
        signals.reset_watchdog();
        plc.cycle_with(&mut io, &signals, |scan| {
            assert_eq!(scan.previous.words(), &SAFE, "inside: {inside}");
            seal_in(scan);
        })
        .unwrap();
        assert_eq!(io.out[0] & 1, 0, "inside: {inside}: motor restarted");
    }
}

/// Item 2: after a power failure the restart is the caller's explicit choice, for the
/// executive's own flags and for `Signals`: `Inhibit` resumes with the safe outputs as the
/// previous image (the motor stays off), `WhereStopped` with the image from before (it runs on).
#[test]
fn resume_inhibits_or_restarts_as_asked() {
    for (restart, motor_after) in [(Restart::Inhibit, 0), (Restart::WhereStopped, 1)] {
        let mut io = bench();
        let mut plc = Executive::new(config());
        motor_running(&mut plc, &mut io);
        plc.power_fail(&mut io);
        assert_eq!(io.out, SAFE);
        plc.resume(restart);
        plc.cycle(&mut io, seal_in).unwrap();
        assert_eq!(io.out[0] & 1, motor_after, "{restart:?}");

        let signals: Signals<2, OW> = Signals::new(&config());
        let mut io = bench();
        let mut plc = Executive::new(config());
        io.inputs = [1 << START, 0];
        plc.cycle_with(&mut io, &signals, seal_in).unwrap();
        io.inputs = [0, 0];
        signals.power_fail();
        signals.resume(restart);
        plc.cycle_with(&mut io, &signals, seal_in).unwrap();
        assert_eq!(io.out[0] & 1, motor_after, "Signals, {restart:?}");
        // A trip before the outage is never undone by a `WhereStopped` resume.
        assert!(signals.check_watchdog(10_000_000));
        signals.power_fail();
        signals.resume(Restart::WhereStopped);
        signals.reset_watchdog();
        plc.cycle_with(&mut io, &signals, |s| {
            assert_eq!(s.previous.words(), &SAFE);
        })
        .unwrap();
    }
}

/// Item 4: the monitor over `Signals` refuses to run while the watchdog is tripped, and it
/// kicks the watchdog every cycle.
#[test]
fn the_monitor_runs_over_signals() {
    let signals: Signals<2, OW> = Signals::new(&config());
    let mut io = bench();
    let mut plc = Executive::new(config());
    // 40 cycles of 50 ms: 2 s, far over the 100 ms limit, with the timer interrupt checking
    // between cycles.
    let (n, why) = plc
        .run_with(&mut io, &signals, 40, &[], seal_in, |_, io| {
            io.t = io.t.wrapping_add(50_000);
            assert!(!signals.check_watchdog(io.t), "a running monitor trips");
        })
        .unwrap();
    assert_eq!((n, why), (40, None));
    assert!(signals.check_watchdog(io.t.wrapping_add(100_001)));
    let writes = io.writes.len();
    let (n, why, _) = plc
        .run_until_with(&mut io, &signals, 3, &[], seal_in, |_, _| {}, |_| false)
        .unwrap();
    assert_eq!((n, why), (0, Some(Halt::Watchdog)));
    assert_eq!(
        io.writes.len(),
        writes,
        "the program's outputs written after a trip"
    );
}

/// Item 5: an outage reported through `Signals` is not program time: a running TON resumes
/// where it stood and the outage is no jitter.
#[test]
fn a_signals_outage_is_not_program_time() {
    let signals: Signals<2, OW> = Signals::new(&config());
    let mut io = bench();
    let mut plc = Executive::new(config());
    let mut ton = Ton::new(5_000);
    for _ in 0..10 {
        io.t = io.t.wrapping_add(50_000);
        plc.cycle_with(&mut io, &signals, |s| {
            ton.call(true, s.now_ms);
        })
        .unwrap();
    }
    let before = plc.now_ms();
    signals.power_fail();
    io.t = io.t.wrapping_add(60_000_000);
    signals.resume(Restart::WhereStopped);
    io.t = io.t.wrapping_add(50_000);
    let mut q = true;
    plc.cycle_with(&mut io, &signals, |s| q = ton.call(true, s.now_ms))
        .unwrap();
    assert_eq!(plc.now_ms(), before, "the outage counted as program time");
    assert!(!q, "the 5 s TON fired after 0.5 s of running");
    assert!(plc.stats().jitter_us < 1_000, "{}", plc.stats().jitter_us);
}

/// Item 5: a halt (trip and reset, power failure and resume) stops the program's clock,
/// however long it lasts — 2 h included, longer than the µs clock's 71.6 min wrap.
#[test]
fn a_halt_of_any_length_stops_the_program_clock() {
    for gap_us in [0u32, 1, 999_999, 1 << 31, u32::MAX, 7_200_000_000u64 as u32] {
        for halt in 0..4 {
            let signals: Signals<2, OW> = Signals::new(&config());
            let mut io = bench();
            let mut plc = Executive::new(config());
            for _ in 0..3 {
                io.t = io.t.wrapping_add(50_000);
                plc.cycle_with(&mut io, &signals, |_| {}).unwrap();
            }
            let before = plc.now_ms();
            io.t = io.t.wrapping_add(200_000);
            match halt {
                0 => assert!(plc.check_watchdog(&mut io)),
                1 => plc.power_fail(&mut io),
                2 => assert!(signals.check_watchdog(io.t)),
                _ => signals.power_fail(),
            }
            io.t = io.t.wrapping_add(gap_us);
            match halt {
                0 => plc.reset_watchdog(),
                1 => plc.resume(Restart::Inhibit),
                2 => signals.reset_watchdog(),
                _ => signals.resume(Restart::Inhibit),
            }
            plc.cycle_with(&mut io, &signals, |_| {}).unwrap();
            assert_eq!(plc.now_ms(), before, "gap {gap_us}, halt {halt}");
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum Step {
    /// The clock moves by this many µs (wrapping) between cycles.
    Clock(u32),
    /// A cycle.
    Cycle,
}

fn clock_steps() -> impl Strategy<Value = Vec<Step>> {
    let delta = prop_oneof![
        0u32..200_000,
        any::<u32>(),
        (0u32..70_000).prop_map(|d| 0u32.wrapping_sub(d)), // steps back a little
        prop_oneof![Just(1u32 << 31), Just((1u32 << 31) - 1), Just(u32::MAX)],
    ];
    prop::collection::vec(
        prop_oneof![3 => delta.prop_map(Step::Clock), 2 => Just(Step::Cycle)],
        0..60,
    )
}

use proptest::strategy::Just;

proptest! {
    /// Item 5 (and the attack's item 1): the program's clock against a model — forward steps
    /// under 2³¹ µs between two cycles add their time (µs carried exactly), a reading 2³¹ µs
    /// or more ahead (behind) adds none; the next reading counts from the reference if it is
    /// forward of it, else from the behind reading if forward of that (a new base).
    #[test]
    #[cfg_attr(
        miri,
        ignore = "clock step sequences against a model: a minute interpreted; runs natively in every CI run"
    )]
    fn the_program_clock_counts_forward_steps_only(start in any::<u32>(), steps in clock_steps()) {
        let mut io = bench();
        io.t = start;
        let mut plc = Executive::new(config());
        let mut model_us: u64 = 0;
        let mut last: Option<u32> = None;
        let mut behind: Option<u32> = None;
        for step in steps {
            match step {
                Step::Clock(d) => io.t = io.t.wrapping_add(d),
                Step::Cycle => {
                    match last {
                        None => last = Some(io.t),
                        Some(l) => {
                            let d = io.t.wrapping_sub(l);
                            let from_behind = behind.map(|b| io.t.wrapping_sub(b));
                            if d < 1 << 31 {
                                model_us += u64::from(d);
                                last = Some(io.t);
                                behind = None;
                            } else if let Some(e) = from_behind.filter(|&e| e < 1 << 31) {
                                model_us += u64::from(e);
                                last = Some(io.t);
                                behind = None;
                            } else {
                                behind = Some(io.t);
                            }
                        }
                    }
                    let mut seen = 0;
                    plc.cycle(&mut io, |s| seen = s.now_ms).unwrap();
                    prop_assert_eq!(seen, (model_us / 1000) as u32);
                    prop_assert_eq!(plc.now_ms(), (model_us / 1000) as u32);
                    // The jitter is a deviation within one forward step, never a step back.
                    prop_assert!(plc.stats().jitter_us < 1 << 31);
                }
            }
        }
    }

    /// Item 5: the `Signals` watchdog trips exactly when the clock is more than the limit past
    /// the last kick; a reading before the kick (a step back, or a time read before the kick
    /// landed) never trips, anywhere on the wrapping clock.
    #[test]
    fn the_signals_watchdog_trips_only_past_the_limit(kick in any::<u32>(), d in any::<u32>()) {
        let signals: Signals<1, 1> = Signals::new(&CycleConfig::source());
        let mut io = KickAt(kick);
        let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
        plc.cycle_with(&mut io, &signals, |_| {}).unwrap();
        let now = kick.wrapping_add(d);
        let expected = d > 100_000 && d < 1 << 31;
        prop_assert_eq!(signals.check_watchdog(now), expected, "kick {} now {}", kick, now);
        let mut plc2: Executive<1, 1> = Executive::new(CycleConfig::source());
        plc2.cycle(&mut io, |_| {}).unwrap();
        io.0 = now;
        prop_assert_eq!(plc2.check_watchdog(&mut io), expected);
    }
}

use proptest::prop_assert;

struct KickAt(u32);
impl Io<1, 1> for KickAt {
    fn read_inputs(&mut self, raw: &mut [u16; 1]) {
        *raw = [0];
    }
    fn write_outputs(&mut self, _: &[u16; 1]) {}
    fn now_us(&mut self) -> u32 {
        self.0
    }
}

#[test]
fn a_watchdog_check_one_microsecond_before_the_kick_does_not_trip() {
    for kick in [0u32, 1, 150_000, u32::MAX, u32::MAX - 50_000] {
        let signals: Signals<1, 1> = Signals::new(&CycleConfig::source());
        let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
        plc.cycle_with(&mut KickAt(kick), &signals, |_| {}).unwrap();
        assert!(!signals.check_watchdog(kick.wrapping_sub(1)), "{kick}");
        // Exactly half the clock's range away reads as behind, for both watchdogs.
        assert!(
            !signals.check_watchdog(kick.wrapping_add(1 << 31)),
            "{kick}"
        );
        let mut io = KickAt(kick);
        let mut own: Executive<1, 1> = Executive::new(CycleConfig::source());
        own.cycle(&mut io, |_| {}).unwrap();
        io.0 = kick.wrapping_add(1 << 31);
        assert!(!own.check_watchdog(&mut io), "{kick}");
        assert!(
            !signals.check_watchdog(kick.wrapping_add(100_000)),
            "{kick}"
        );
        assert!(signals.check_watchdog(kick.wrapping_add(100_001)), "{kick}");
    }
}

/// A watchdog limit beyond what the wrapping clock can tell from a step back acts as the
/// longest it can: 2³¹ − 2 µs, at both watchdogs.
#[test]
fn the_longest_watchdog_limit_still_trips() {
    let max = (1u32 << 31) - 2;
    for (limit, trips_at) in [
        (max - 1, max),
        (max, max + 1),
        (max + 1, max + 1),
        (u32::MAX, max + 1),
    ] {
        let config = CycleConfig::<1> {
            watchdog_us: limit,
            ..CycleConfig::source()
        };
        for kick in [0u32, u32::MAX - 10] {
            let signals: Signals<1, 1> = Signals::new(&config);
            let mut plc: Executive<1, 1> = Executive::new(config);
            plc.cycle_with(&mut KickAt(kick), &signals, |_| {}).unwrap();
            assert!(
                !signals.check_watchdog(kick.wrapping_add(trips_at - 1)),
                "{limit}"
            );
            assert!(
                signals.check_watchdog(kick.wrapping_add(trips_at)),
                "{limit}"
            );
            let mut io = KickAt(kick);
            let mut plc: Executive<1, 1> = Executive::new(config);
            plc.cycle(&mut io, |_| {}).unwrap();
            io.0 = kick.wrapping_add(trips_at - 1);
            assert!(!plc.check_watchdog(&mut io), "{limit}");
            io.0 = kick.wrapping_add(trips_at);
            assert!(plc.check_watchdog(&mut io), "{limit}");
        }
    }
}

/// Item 7: the reserve runs no job while the power has failed or the watchdog is tripped.
#[test]
fn the_reserve_runs_nothing_while_halted() {
    for halt in 0..4 {
        let signals: Signals<2, OW> = Signals::new(&config());
        let mut io = bench();
        let mut plc = Executive::new(config());
        plc.cycle(&mut io, |_| {}).unwrap();
        match halt {
            0 => plc.power_fail(&mut io),
            1 => {
                io.t = 200_000;
                assert!(plc.check_watchdog(&mut io));
                io.t = 0;
            }
            2 => signals.power_fail(),
            _ => {
                assert!(!signals.check_watchdog(0)); // arms
                assert!(signals.check_watchdog(1_000_000));
            }
        }
        let mut spool: Spool<u8, 4> = Spool::new();
        spool.push(1).unwrap();
        let mut ran = 0;
        let n = if halt < 2 {
            plc.reserve(&mut io, &mut spool, 0, |_| ran += 1)
        } else {
            plc.reserve_with(&mut io, &signals, &mut spool, 0, |_| ran += 1)
        };
        assert_eq!((n, ran, spool.len()), (0, 0, 1), "halt {halt}");
    }
}

/// The reserve's room: a job starts only while the clock is less than `period − margin` past
/// the cycle's start, with and without `Signals`; a clock that stepped back leaves no room.
#[test]
fn the_reserve_starts_jobs_only_with_room_left() {
    for with_signals in [false, true] {
        for (since, runs) in [
            (0u32, true),
            (39_999, true),
            (40_000, false),
            (u32::MAX, false),
        ] {
            let signals: Signals<2, OW> = Signals::new(&config());
            let mut io = bench();
            io.t = 7;
            let mut plc = Executive::new(config());
            plc.cycle(&mut io, |_| {}).unwrap();
            io.t = 7u32.wrapping_add(since);
            let mut spool: Spool<u8, 4> = Spool::new();
            spool.push(1).unwrap();
            let n = if with_signals {
                plc.reserve_with(&mut io, &signals, &mut spool, 10_000, |_| {})
            } else {
                plc.reserve(&mut io, &mut spool, 10_000, |_| {})
            };
            assert_eq!(n, usize::from(runs), "{since} {with_signals}");
            assert_eq!(plc.stats().spool_jobs, u64::from(runs));
        }
    }
}

/// Item 7: a reset of a watchdog that has not tripped (a bouncing reset key) does not re-arm
/// its timing: a hung program still trips it.
#[test]
fn a_bouncing_reset_does_not_hold_off_the_watchdog() {
    let signals: Signals<1, 1> = Signals::new(&CycleConfig::source());
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    plc.cycle_with(&mut KickAt(0), &signals, |_| {}).unwrap();
    for t in (10_000..=100_000).step_by(10_000) {
        signals.reset_watchdog();
        assert!(!signals.check_watchdog(t));
    }
    signals.reset_watchdog();
    assert!(signals.check_watchdog(100_001));
    // The same for the executive's own watchdog.
    let mut io = KickAt(0);
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    plc.cycle(&mut io, |_| {}).unwrap();
    for t in (10_000..=100_000).step_by(10_000) {
        plc.reset_watchdog();
        io.0 = t;
        assert!(!plc.check_watchdog(&mut io));
    }
    plc.reset_watchdog();
    io.0 = 100_001;
    assert!(plc.check_watchdog(&mut io));
}

/// Item 7: breakpoints that can never fire are refused, by every run command.
#[test]
fn breakpoints_that_cannot_fire_are_refused() {
    let mut io = bench();
    let mut plc = Executive::new(config());
    let signals: Signals<2, OW> = Signals::new(&config());
    for (b, err) in [
        (Breakpoint::Cycle(0), BreakpointError::CycleZero),
        (
            Breakpoint::InputOn(32),
            BreakpointError::NoSuchInput {
                point: 32,
                inputs: 32,
            },
        ),
        (
            Breakpoint::OutputOn(48),
            BreakpointError::NoSuchOutput {
                point: 48,
                outputs: 48,
            },
        ),
        (
            Breakpoint::OutputOff(usize::MAX),
            BreakpointError::NoSuchOutput {
                point: usize::MAX,
                outputs: 48,
            },
        ),
    ] {
        assert_eq!(plc.check_breakpoints(&[Breakpoint::Cycle(3), b]), Err(err));
        assert_eq!(plc.run(&mut io, 5, &[b], |_| {}, |_, _| {}), Err(err));
        assert_eq!(
            plc.run_until(&mut io, 5, &[b], |_| {}, |_, _| {}, |_| false),
            Err(err)
        );
        assert_eq!(
            plc.run_with(&mut io, &signals, 5, &[b], |_| {}, |_, _| {}),
            Err(err)
        );
        assert_eq!(plc.cycle_count(), 0, "nothing ran");
        assert!(!err.to_string().is_empty());
    }
    for b in [
        Breakpoint::Cycle(1),
        Breakpoint::InputOn(31),
        Breakpoint::OutputOn(47),
        Breakpoint::OutputOff(0),
    ] {
        assert_eq!(plc.check_breakpoints(&[b]), Ok(()));
    }
}
