//! The cyclic executive: read all inputs, run the program on the images, write all outputs,
//! swap the output images; watchdog, power failure, statistics, spool and monitor.

use core::fmt;

use heapless::Deque;

use crate::image::{Conditioning, Forcing, Image, PointError};
use crate::signals::Signals;

/// The only bridge between the executive and the plant: the program never sees it.
pub trait Io<const IW: usize, const OW: usize> {
    /// Reads every input word (the executive calls it once, at the start of a cycle).
    fn read_inputs(&mut self, raw: &mut [u16; IW]);
    /// Writes every output word (once, at the end of a cycle, or the safe state).
    fn write_outputs(&mut self, outputs: &[u16; OW]);
    /// Microseconds from a free-running clock (wrapping).
    ///
    /// **The clock must count forward**, wrapping at 2³² only. A µs counter built from a
    /// 16-bit timer and an overflow interrupt must be read race-free — read the overflow count,
    /// the timer, and the overflow count again, and retry if it changed (or take the overflow
    /// count together with the timer's pending-overflow flag) — or a reading taken just as the
    /// timer overflows is one overflow (65 536 µs) behind. The executive survives a clock that
    /// steps back ([`Executive::now_ms`] never goes back, and a single step back adds it no
    /// time), but it cannot tell a glitch from a new base: the watchdogs and [`CycleStats`] take
    /// each reading as given (a reading behind can trip a watchdog early — towards the safe
    /// outputs — or count a false overrun), and glitches read twice running make `now_ms` gain
    /// their size each time, so the IEC timers run early.
    fn now_us(&mut self) -> u32;
    /// Pulses a hardware watchdog, if the plant has one (the source pulsed it every 50 ms).
    fn kick_watchdog(&mut self) {}
}

/// What the program sees in one cycle: the conditioned (and forced) input image, the output
/// image of the previous cycle, and the output image it writes.
#[derive(Debug)]
pub struct Scan<'a, const IW: usize, const OW: usize> {
    /// The input image, read at the start of this cycle.
    pub inputs: &'a Image<IW>,
    /// The outputs as written at the end of the previous cycle.
    pub previous: &'a Image<OW>,
    /// The outputs this cycle writes; it starts as a copy of `previous`.
    pub outputs: &'a mut Image<OW>,
    /// The cycle's number, from 1.
    pub cycle: u64,
    /// Milliseconds at the cycle's start, for the timers: the executive's own clock, advanced by
    /// the `Io` clock between cycles and wrapping at 2³² ms.
    pub now_ms: u32,
}

/// The executive's parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CycleConfig<const OW: usize> {
    /// Cycle period, µs (the source: 50 ms).
    pub period_us: u32,
    /// A cycle that does not finish within this many µs of the last one trips the watchdog
    /// (the source: 100 ms). A limit above 2³¹ − 2 µs (35.8 minutes) acts as 2³¹ − 2 µs: a
    /// longer time cannot be told from the clock stepping back.
    pub watchdog_us: u32,
    /// The outputs written on a watchdog trip or a power failure (the source: all off).
    pub safe_outputs: Image<OW>,
}

impl<const OW: usize> CycleConfig<OW> {
    /// The source's timing: 50 ms cycle, 100 ms watchdog, all outputs off when safe.
    #[must_use]
    pub const fn source() -> CycleConfig<OW> {
        CycleConfig {
            period_us: 50_000,
            watchdog_us: 100_000,
            safe_outputs: Image::new(),
        }
    }
}

/// Why the executive did not run a cycle, or stopped running.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Halt {
    /// The power failed: outputs are safe and the state frozen until [`Executive::resume`].
    PowerFail,
    /// The watchdog tripped: outputs are safe until [`Executive::reset_watchdog`].
    Watchdog,
    /// A breakpoint was reached (after the cycle that reached it).
    Breakpoint(Breakpoint),
}

impl fmt::Display for Halt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Halt::PowerFail => f.write_str("power failure: outputs safe, state frozen"),
            Halt::Watchdog => f.write_str("watchdog tripped: outputs safe"),
            Halt::Breakpoint(b) => write!(f, "breakpoint reached: {b}"),
        }
    }
}

impl core::error::Error for Halt {}

/// A breakpoint of the monitor. It fires on a change: the run stops after the cycle in which it
/// comes to hold, not again while it goes on holding, so continuing a run moves past it (to the
/// next time it comes to hold).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Breakpoint {
    /// After cycle number n (once).
    Cycle(u64),
    /// When an input point comes on.
    InputOn(usize),
    /// When an output point comes on.
    OutputOn(usize),
    /// When an output point goes off.
    OutputOff(usize),
}

/// The images and cycle count the breakpoints saw before a cycle ([`Executive::watch`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BreakpointWatch<const IW: usize, const OW: usize> {
    cycle: u64,
    inputs: Image<IW>,
    outputs: Image<OW>,
}

impl<const IW: usize, const OW: usize> BreakpointWatch<IW, OW> {
    /// The first of `breakpoints` that holds in `now` but did not when the watch was taken: the
    /// breakpoint that came to hold in the cycles between.
    #[must_use]
    pub fn fired(&self, now: &Executive<IW, OW>, breakpoints: &[Breakpoint]) -> Option<Breakpoint> {
        breakpoints.iter().copied().find(|&b| {
            now.reached(b) && !Executive::holds(b, self.cycle, &self.inputs, &self.outputs)
        })
    }
}

/// Half the wrapping range of the µs clock: a reading this far or farther "ahead" of a
/// reference is the clock stepping back.
pub(crate) const HALF_RANGE_US: u32 = 1 << 31;

/// The longest watchdog limit: one µs more must still read as time going forward.
pub(crate) const MAX_WATCHDOG_US: u32 = HALF_RANGE_US - 2;

/// The µs from `from` to `to` on the wrapping clock, or `None` when `to` is behind `from` (a
/// wrapping difference of 2³¹ µs or more: the clock stepped back).
fn forward_us(from: u32, to: u32) -> Option<u32> {
    let d = to.wrapping_sub(from);
    (d < HALF_RANGE_US).then_some(d)
}

/// How the program starts again after a power failure ([`Executive::resume`],
/// [`Signals::resume`]).
///
/// EN 60204-1 (7.5) forbids a machine to restart by itself when the power returns where that
/// could be dangerous: that is [`Restart::Inhibit`]. The previous output image is only part of
/// what a program remembers — its own timers, counters and variables are its own, and a
/// program that latches a run request there must clear it itself.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Restart {
    /// The program starts from the safe outputs as its previous output image — what the plant
    /// has after the outage: a sealed-in motor stays off until it is started again.
    Inhibit,
    /// The program starts from the output image of the last cycle before the outage, as the
    /// source did: a sealed-in motor runs on by itself.
    WhereStopped,
}

/// What supervises a cycle from outside it: nothing ([`Executive::cycle`]) or [`Signals`]
/// ([`Executive::cycle_with`]).
pub(crate) trait Supervision<const IW: usize, const OW: usize> {
    /// Whether cycles are refused now, and why.
    fn halted(&self) -> Option<Halt>;
    /// At a cycle's start: the halt that refuses it, or the state to run it from.
    fn begin(&self) -> Result<Begin<IW>, Halt>;
    /// Before the output write: no trip or power failure since `events` was taken.
    fn commit(&self, events: u32) -> Result<(), Halt>;
    /// After the output write, in one step: no trip or power failure since the start, and the
    /// watchdog kicked at `end_us`.
    fn confirm(&self, events: u32, end_us: u32) -> Result<(), Halt>;
    /// The outputs the interrupt handlers write on a halt.
    fn safe_outputs(&self) -> Option<&Image<OW>>;
}

/// What a supervised cycle starts from.
pub(crate) struct Begin<const IW: usize> {
    /// The count of trips and power failures so far.
    pub(crate) events: u32,
    /// Inputs latched by the interrupt since the last cycle.
    pub(crate) captured: Option<[u16; IW]>,
    /// The plant has the safe outputs: the program starts from them.
    pub(crate) restart_from_safe: bool,
}

/// No supervision: the executive's own watchdog and flags only.
struct Unsupervised;

impl<const IW: usize, const OW: usize> Supervision<IW, OW> for Unsupervised {
    fn halted(&self) -> Option<Halt> {
        None
    }
    fn begin(&self) -> Result<Begin<IW>, Halt> {
        Ok(Begin {
            events: 0,
            captured: None,
            restart_from_safe: false,
        })
    }
    fn commit(&self, _events: u32) -> Result<(), Halt> {
        Ok(())
    }
    fn confirm(&self, _events: u32, _end_us: u32) -> Result<(), Halt> {
        Ok(())
    }
    fn safe_outputs(&self) -> Option<&Image<OW>> {
        None
    }
}

impl fmt::Display for Breakpoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Breakpoint::Cycle(n) => write!(f, "cycle {n}"),
            Breakpoint::InputOn(p) => write!(f, "input {p} came on"),
            Breakpoint::OutputOn(p) => write!(f, "output {p} came on"),
            Breakpoint::OutputOff(p) => write!(f, "output {p} went off"),
        }
    }
}

/// A breakpoint that could never fire, refused by the monitor's run commands and
/// [`Executive::check_breakpoints`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum BreakpointError {
    /// `Breakpoint::Cycle(0)`: cycles are numbered from 1.
    CycleZero,
    /// `Breakpoint::Cycle(cycle)` for a cycle already run: the count only grows.
    CyclePassed {
        /// The cycle asked for.
        cycle: u64,
        /// Cycles run so far ([`Executive::cycle_count`]).
        count: u64,
    },
    /// An input point the executive does not have.
    NoSuchInput {
        /// The point asked for.
        point: usize,
        /// Input points there are (0 to `inputs − 1`).
        inputs: usize,
    },
    /// An output point the executive does not have.
    NoSuchOutput {
        /// The point asked for.
        point: usize,
        /// Output points there are (0 to `outputs − 1`).
        outputs: usize,
    },
}

impl fmt::Display for BreakpointError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            BreakpointError::CycleZero => {
                f.write_str("breakpoint at cycle 0 can never fire: cycles are numbered from 1")
            }
            BreakpointError::CyclePassed { cycle, count } => write!(
                f,
                "breakpoint at cycle {cycle} can never fire: {count} cycles have run already"
            ),
            BreakpointError::NoSuchInput { point, inputs } => write!(
                f,
                "breakpoint on input {point} can never fire: there are {inputs} inputs (0 to {})",
                inputs.saturating_sub(1)
            ),
            BreakpointError::NoSuchOutput { point, outputs } => write!(
                f,
                "breakpoint on output {point} can never fire: there are {outputs} outputs (0 to {})",
                outputs.saturating_sub(1)
            ),
        }
    }
}

impl core::error::Error for BreakpointError {}

/// Cycle statistics, as the source measured its load. Before the first cycle `min_us` is
/// `u32::MAX` (no cycle yet), in [`CycleStats::NONE`], [`Default`] and a new executive alike.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CycleStats {
    /// Cycles run.
    pub cycles: u64,
    /// Busy time of the last cycle (read, program, write), µs.
    pub last_us: u32,
    /// Shortest busy time, µs.
    pub min_us: u32,
    /// Longest busy time, µs.
    pub max_us: u32,
    /// Sum of busy times, µs (for the mean).
    pub total_us: u64,
    /// Largest deviation of a cycle start from the period after the previous start, µs.
    pub jitter_us: u32,
    /// Cycles whose busy time left no reserve (busy ≥ period).
    pub overruns: u64,
    /// Spool jobs run in the reserve.
    pub spool_jobs: u64,
}

impl Default for CycleStats {
    fn default() -> CycleStats {
        CycleStats::NONE
    }
}

impl CycleStats {
    /// No cycle yet.
    pub const NONE: CycleStats = CycleStats {
        cycles: 0,
        last_us: 0,
        min_us: u32::MAX,
        max_us: 0,
        total_us: 0,
        jitter_us: 0,
        overruns: 0,
        spool_jobs: 0,
    };

    /// Mean busy time, µs.
    #[must_use]
    pub fn mean_us(&self) -> u32 {
        u32::try_from(self.total_us.checked_div(self.cycles).unwrap_or(0)).unwrap_or(u32::MAX)
    }

    /// Load: mean busy time as per mille of the period (the source: about 300).
    #[must_use]
    pub fn load_per_mille(&self, period_us: u32) -> u32 {
        let busy = u64::from(self.mean_us()).saturating_mul(1000);
        u32::try_from(busy.checked_div(u64::from(period_us)).unwrap_or(0)).unwrap_or(u32::MAX)
    }
}

/// One-shot jobs run in the performance reserve (printouts, archiving), in order.
///
/// ```
/// use regler_scan_cycle::Spool;
/// let mut spool: Spool<&str, 2> = Spool::new();
/// assert!(spool.push("print shift report").is_ok());
/// assert!(spool.push("archive counters").is_ok());
/// assert_eq!(spool.push("one too many"), Err("one too many")); // handed back
/// ```
#[derive(Clone, Debug)]
pub struct Spool<J, const S: usize> {
    jobs: Deque<J, S>,
}

impl<J, const S: usize> Default for Spool<J, S> {
    fn default() -> Self {
        Spool::new()
    }
}

impl<J, const S: usize> Spool<J, S> {
    /// An empty spool.
    #[must_use]
    pub const fn new() -> Spool<J, S> {
        Spool { jobs: Deque::new() }
    }

    /// Queues a job; a full spool refuses it and hands it back.
    pub fn push(&mut self, job: J) -> Result<(), J> {
        self.jobs.push_back(job)
    }

    /// Jobs waiting.
    #[must_use]
    pub fn len(&self) -> usize {
        self.jobs.len()
    }

    /// Whether no job waits.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.jobs.is_empty()
    }

    /// The waiting jobs, oldest first.
    pub fn iter(&self) -> impl Iterator<Item = &J> {
        self.jobs.iter()
    }

    fn pop(&mut self) -> Option<J> {
        self.jobs.pop_front()
    }
}

/// The cyclic executive of the 1989 controller (and the 1977 plant's levels A–C).
///
/// Each [`cycle`](Executive::cycle): read all inputs through [`Io`] into the raw image, condition
/// them (latch, debounce) and apply the forced inputs; copy the previous output image into the
/// next one; run the program on the images; apply the forced outputs; write the outputs; swap.
/// [`reserve`](Executive::reserve) then runs spool jobs while time remains before the next cycle.
///
/// An `Executive<IW, OW>` is `30·IW + 10·OW` bytes of images (raw, conditioned, forced and
/// conditioning inputs; previous, next, forced and safe outputs) plus about 130 bytes of
/// statistics, clocks and flags — 1.7 KB at the 1977 plant's 34 input and 15 output words. A unit
/// test checks the formula; [`new`](Executive::new) is a `const fn`.
///
/// ```
/// use regler_scan_cycle::{CycleConfig, Executive, Io};
///
/// struct Bench { inputs: [u16; 1], outputs: [u16; 1], t: u32 }
/// impl Io<1, 1> for Bench {
///     fn read_inputs(&mut self, raw: &mut [u16; 1]) { *raw = self.inputs; }
///     fn write_outputs(&mut self, out: &[u16; 1]) { self.outputs = *out; }
///     fn now_us(&mut self) -> u32 { self.t += 10; self.t }
/// }
///
/// let mut plant = Bench { inputs: [0b1], outputs: [0], t: 0 };
/// let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
/// // Output 0 follows input 0 inverted; output 1 counts cycles' parity from the previous image.
/// plc.cycle(&mut plant, |scan| {
///     scan.outputs.set(0, !scan.inputs.get(0)).ok();
///     scan.outputs.set(1, !scan.previous.get(1)).ok();
/// })?;
/// assert_eq!(plant.outputs, [0b10]);
/// # Ok::<(), regler_scan_cycle::Halt>(())
/// ```
#[derive(Clone, Debug)]
pub struct Executive<const IW: usize, const OW: usize> {
    config: CycleConfig<OW>,
    raw: [u16; IW],
    inputs: Image<IW>,
    previous: Image<OW>,
    next: Image<OW>,
    conditioning: Conditioning<IW>,
    force_inputs: Forcing<IW>,
    force_outputs: Forcing<OW>,
    stats: CycleStats,
    /// The power has failed and not come back.
    power_failed: bool,
    /// The watchdog tripped and the operator has not reset it (a power failure keeps it).
    tripped: bool,
    /// Where the watchdog counts from before any cycle has finished: it is armed from the
    /// first check, so a program that never finishes a cycle trips it too.
    watch_from_us: Option<u32>,
    cycle: u64,
    last_start_us: Option<u32>,
    /// The program's millisecond clock: wraps at 2³² ms like the IEC timers expect (the µs
    /// clock of `Io` wraps every 71.6 minutes, so `now_us / 1000` would jump back).
    clock_ms: u32,
    clock_rest_us: u32,
    clock_last_us: Option<u32>,
    /// The last reading, when it was behind `clock_last_us`.
    clock_behind_us: Option<u32>,
    last_end_us: Option<u32>,
    watchdog_trips: u32,
    /// The count of `Signals` trips and power failures the last cycle started with.
    seen_events: u32,
    /// The count of `Signals` trips and power failures the watchdog was last armed under
    /// ([`check_watchdog_with`](Executive::check_watchdog_with)).
    watch_events: u32,
}

impl<const IW: usize, const OW: usize> Executive<IW, OW> {
    /// An executive with all images off.
    #[must_use]
    pub const fn new(config: CycleConfig<OW>) -> Executive<IW, OW> {
        Executive {
            config,
            raw: [0; IW],
            inputs: Image::new(),
            previous: Image::new(),
            next: Image::new(),
            conditioning: Conditioning::new(),
            force_inputs: Forcing::new(),
            force_outputs: Forcing::new(),
            stats: CycleStats::NONE,
            power_failed: false,
            tripped: false,
            watch_from_us: None,
            cycle: 0,
            last_start_us: None,
            last_end_us: None,
            watchdog_trips: 0,
            seen_events: 0,
            clock_ms: 0,
            clock_rest_us: 0,
            clock_last_us: None,
            clock_behind_us: None,
            watch_events: 0,
        }
    }

    /// One cycle with `program`. Refused while the power has failed or the watchdog is tripped.
    pub fn cycle<I: Io<IW, OW>>(
        &mut self,
        io: &mut I,
        program: impl FnOnce(&mut Scan<'_, IW, OW>),
    ) -> Result<(), Halt> {
        self.run_cycle(io, &Unsupervised, program)
    }

    /// One cycle with `program`, supervised through `signals`, whose watchdog, latch capture and
    /// power failure live with the interrupts (see [`Signals`]). Refused while `signals` says the
    /// power has failed or the watchdog has tripped. The inputs latched by
    /// [`Signals::capture`] since the last cycle are read.
    ///
    /// If the watchdog trips or the power fails at any moment after the cycle's start — while
    /// it reads, while the program runs, before, during or after the output write — the cycle
    /// returns the halt ([`Halt::Watchdog`], [`Halt::PowerFail`]) and the safe outputs are the
    /// last thing written: a halt before the write leaves the write out, one during or after it
    /// makes the cycle write [`Signals::safe_outputs`] once more after its own write. Such a
    /// cycle is not counted ([`cycle_count`](Executive::cycle_count), statistics, input and
    /// output images and [`Io::kick_watchdog`] as before it), and every latched pulse it read
    /// (captured by [`Signals::capture`] or [`capture`](Executive::capture), or on in its raw
    /// read) is pending again for the next cycle. Its reading does advance the debounce counts
    /// (it was a real reading of the plant), and its start counts for
    /// [`now_ms`](Executive::now_ms) up to the halt. The check before the write and the check after it
    /// are each a few word operations in a critical section; the bus write itself runs with
    /// interrupts on.
    ///
    /// After a trip, or a power failure resumed with [`Restart::Inhibit`], the next cycle's
    /// previous output image is the safe outputs; after any trip or power failure the gap until
    /// the next cycle is not program time (see [`now_ms`](Executive::now_ms)).
    pub fn cycle_with<I: Io<IW, OW>>(
        &mut self,
        io: &mut I,
        signals: &Signals<IW, OW>,
        program: impl FnOnce(&mut Scan<'_, IW, OW>),
    ) -> Result<(), Halt> {
        self.run_cycle(io, signals, program)
    }

    /// The cycle, supervised by `signals` or by nothing: generic, so a firmware that never uses
    /// [`Signals`] links no critical-section code and needs no critical-section implementation.
    fn run_cycle<I: Io<IW, OW>, S: Supervision<IW, OW>>(
        &mut self,
        io: &mut I,
        signals: &S,
        program: impl FnOnce(&mut Scan<'_, IW, OW>),
    ) -> Result<(), Halt> {
        if let Some(halt) = self.halted() {
            return Err(halt);
        }
        let begin = signals.begin()?;
        if begin.events != self.seen_events {
            // A trip or a power failure since the last cycle: the halt is not program time,
            // nor jitter.
            self.seen_events = begin.events;
            self.clock_last_us = None;
            self.last_start_us = None;
        }
        if begin.restart_from_safe
            && let Some(safe) = signals.safe_outputs()
        {
            self.previous = *safe;
        }
        if let Some(captured) = begin.captured {
            self.conditioning.capture(&captured);
        }
        // What a halted cycle puts back: the input images as before it.
        let (raw_before, inputs_before) = (self.raw, self.inputs);
        let start = io.now_us();
        // The jitter counts only if the cycle is (a halted cycle leaves the statistics alone).
        let jitter = self
            .last_start_us
            .and_then(|last| forward_us(last, start))
            .map(|interval| interval.abs_diff(self.config.period_us));
        self.last_start_us = Some(start);
        // Level A: all inputs in.
        io.read_inputs(&mut self.raw);
        self.conditioning.condition(&self.raw, &mut self.inputs);
        // The readings before forcing: a latched point is not debounced, so its bit here is
        // what the cycle read (a pending pulse, a capture or the raw word).
        let read = self.inputs;
        self.force_inputs.apply(&mut self.inputs);
        // Level B: the program, on the images only.
        self.next = self.previous;
        let cycle = self.cycle.saturating_add(1);
        let now_ms = self.tick_clock(start);
        program(&mut Scan {
            inputs: &self.inputs,
            previous: &self.previous,
            outputs: &mut self.next,
            cycle,
            now_ms,
        });
        self.force_outputs.apply(&mut self.next);
        // Level A: all outputs out, images swapped. The write runs with interrupts on; a halt
        // that came before it leaves it out, one during or after it is answered by writing
        // the safe outputs again, so they are the last thing on the bus either way.
        let overtaken = match signals.commit(begin.events) {
            Err(halt) => Some(halt),
            Ok(()) => {
                io.write_outputs(self.next.words());
                let end = io.now_us();
                match signals.confirm(begin.events, end) {
                    Ok(()) => {
                        self.watch_events = begin.events;
                        self.finish(io, cycle, start, end, jitter);
                        None
                    }
                    Err(halt) => {
                        if let Some(safe) = signals.safe_outputs() {
                            io.write_outputs(safe.words());
                        }
                        Some(halt)
                    }
                }
            }
        };
        match overtaken {
            None => Ok(()),
            Some(halt) => {
                // Not counted: the input images as before the cycle, and every pulse it read
                // (pending, captured or in the raw read) pending again for the next cycle.
                self.conditioning.capture(read.words());
                self.raw = raw_before;
                self.inputs = inputs_before;
                Err(halt)
            }
        }
    }

    /// The end of a cycle that ran to its confirmed write: kick, count, swap, statistics.
    fn finish<I: Io<IW, OW>>(
        &mut self,
        io: &mut I,
        cycle: u64,
        start: u32,
        end: u32,
        jitter: Option<u32>,
    ) {
        io.kick_watchdog();
        if let Some(jitter) = jitter {
            self.stats.jitter_us = self.stats.jitter_us.max(jitter);
        }
        self.cycle = cycle;
        self.previous = self.next;
        self.last_end_us = Some(end);
        // A clock that stepped back inside the cycle counts it as 0 µs busy.
        let busy = forward_us(start, end).unwrap_or(0);
        let s = &mut self.stats;
        s.cycles = s.cycles.saturating_add(1);
        s.last_us = busy;
        s.min_us = s.min_us.min(busy);
        s.max_us = s.max_us.max(busy);
        s.total_us = s.total_us.saturating_add(u64::from(busy));
        if busy >= self.config.period_us {
            s.overruns = s.overruns.saturating_add(1);
        }
    }

    /// Advances the program's millisecond clock by the µs elapsed since the last cycle; a
    /// reading behind the last one (the clock stepped back) adds nothing and the last reading
    /// stays the reference.
    fn tick_clock(&mut self, now_us: u32) -> u32 {
        let Some(last) = self.clock_last_us else {
            self.clock_last_us = Some(now_us);
            self.clock_behind_us = None;
            return self.clock_ms;
        };
        // Forward from the reference; or forward from the last reading, which was behind it:
        // two readings agree the clock has a new base, and it counts on from there.
        let step = forward_us(last, now_us).or_else(|| {
            self.clock_behind_us
                .and_then(|behind| forward_us(behind, now_us))
        });
        match step {
            Some(step) => {
                let total = u64::from(self.clock_rest_us).saturating_add(u64::from(step));
                let ms = u32::try_from(total / 1000).unwrap_or(u32::MAX);
                self.clock_ms = self.clock_ms.wrapping_add(ms);
                self.clock_rest_us = u32::try_from(total % 1000).unwrap_or(0);
                self.clock_last_us = Some(now_us);
                self.clock_behind_us = None;
            }
            None => self.clock_behind_us = Some(now_us),
        }
        self.clock_ms
    }

    /// Sets the program's millisecond clock ([`now_ms`](Executive::now_ms)) to `ms`, for a
    /// start-up that restores retentive timers: save `now_ms()` with the timers, and after the
    /// power cycle call this with the saved value before the first cycle. The first cycle then
    /// sees `now_ms == ms`, and the clock counts on from there: a restored timer goes on where
    /// it stood (the time the power was off is not program time, as with
    /// [`power_fail`](Executive::power_fail)). Called between cycles, the next cycle starts
    /// from `ms` plus nothing: the µs since the last cycle are dropped.
    pub fn set_now_ms(&mut self, ms: u32) {
        self.clock_ms = ms;
        self.clock_rest_us = 0;
        self.clock_last_us = None;
        self.clock_behind_us = None;
    }

    /// The program's millisecond clock at the start of the last cycle (wrapping at 2³² ms),
    /// also [`Scan::now_ms`].
    ///
    /// It counts the `Io` clock's µs between cycle starts, carried exactly across the µs
    /// clock's wrap. A reading 2³¹ µs or more (35.8 minutes) ahead of the last one, wrapping,
    /// is behind it (a µs counter built from a 16-bit timer and an overflow interrupt steps
    /// back for a moment; a clock may be set back; a gap of 2³¹ µs or more looks the same): it
    /// adds no time. The next reading counts on from the last reading before it if it is
    /// forward of that; otherwise, if it is forward of the behind reading, the two readings
    /// agree the clock has a new base, and it counts on from the behind reading. So the clock
    /// stands still for one cycle at most, the one that first read the new base (that
    /// interval is lost); a glitch read once costs nothing, and one read twice running, d
    /// behind the reference both times, gains d less the interval from the reference to the
    /// first glitch reading (such pairs add up: [`Io::now_us`] must count forward). A gap
    /// between two cycles counts only if it is under 2³¹ µs: a
    /// `u32` µs clock cannot tell a longer one from a shorter one. Halts do not count: after a
    /// power failure or a watchdog trip (of the executive or of [`Signals`]) the clock goes on
    /// from where it stood at the last cycle's start, however long the halt lasted — timers
    /// resume where they were.
    #[must_use]
    pub const fn now_ms(&self) -> u32 {
        self.clock_ms
    }

    /// Level C, the performance reserve: runs spool jobs while the next cycle is more than
    /// `margin_us` away, then returns the jobs run. A job is never started without room left,
    /// nor while the power has failed or the watchdog is tripped (use
    /// [`reserve_with`](Executive::reserve_with) when [`Signals`] has them). A clock that
    /// stepped back since the cycle's start leaves no room.
    pub fn reserve<I: Io<IW, OW>, J, const S: usize>(
        &mut self,
        io: &mut I,
        spool: &mut Spool<J, S>,
        margin_us: u32,
        run: impl FnMut(J),
    ) -> usize {
        self.run_reserve(io, &Unsupervised, spool, margin_us, run)
    }

    /// [`reserve`](Executive::reserve) under `signals`: no job starts while `signals` says the
    /// power has failed or the watchdog has tripped (checked before each job).
    pub fn reserve_with<I: Io<IW, OW>, J, const S: usize>(
        &mut self,
        io: &mut I,
        signals: &Signals<IW, OW>,
        spool: &mut Spool<J, S>,
        margin_us: u32,
        run: impl FnMut(J),
    ) -> usize {
        self.run_reserve(io, signals, spool, margin_us, run)
    }

    fn run_reserve<I: Io<IW, OW>, V: Supervision<IW, OW>, J, const S: usize>(
        &mut self,
        io: &mut I,
        signals: &V,
        spool: &mut Spool<J, S>,
        margin_us: u32,
        mut run: impl FnMut(J),
    ) -> usize {
        let Some(start) = self.last_start_us else {
            return 0;
        };
        let deadline = self.config.period_us.saturating_sub(margin_us);
        let mut done = 0usize;
        while self.halted().is_none()
            && signals.halted().is_none()
            && forward_us(start, io.now_us()).is_some_and(|d| d < deadline)
        {
            let Some(job) = spool.pop() else { break };
            run(job);
            done = done.saturating_add(1);
        }
        self.stats.spool_jobs = self
            .stats
            .spool_jobs
            .saturating_add(u64::try_from(done).unwrap_or(u64::MAX));
        done
    }

    /// Checks the watchdog from the same context as the cycles (the idle loop): if the `Io`
    /// clock is more than the limit past the end of the last cycle — counted from the first
    /// check when none has finished yet — the safe outputs are written, they become the output
    /// image (the program's previous image after the reset), and cycles are refused. Returns
    /// whether the watchdog is (now) tripped. A reading 2³¹ µs or more behind the last cycle's
    /// end (a clock stepping back) does not trip it; a limit above 2³¹ − 2 µs acts as
    /// 2³¹ − 2 µs.
    ///
    /// This sees a hang only between cycles, since [`cycle`](Executive::cycle) holds the
    /// executive; to catch a program that hangs inside a cycle, check from a timer interrupt
    /// through [`Signals::check_watchdog`] and run the cycles with
    /// [`cycle_with`](Executive::cycle_with). With `cycle_with`, check from the idle loop
    /// with [`check_watchdog_with`](Executive::check_watchdog_with): this one does not see a
    /// [`Signals`] outage or trip.
    ///
    /// A clock that steps back for good holds the watchdog off only until the next cycle
    /// ends: that end is the new reference.
    pub fn check_watchdog<I: Io<IW, OW>>(&mut self, io: &mut I) -> bool {
        if self.tripped {
            return true;
        }
        if self.power_failed {
            return false; // an outage is not a hang
        }
        let now = io.now_us();
        let since = match (self.last_end_us, self.watch_from_us) {
            (Some(end), _) | (None, Some(end)) => end,
            (None, None) => {
                self.watch_from_us = Some(now);
                return false;
            }
        };
        let limit = self.config.watchdog_us.min(MAX_WATCHDOG_US);
        if forward_us(since, now).is_some_and(|d| d > limit) {
            io.write_outputs(self.config.safe_outputs.words());
            self.previous = self.config.safe_outputs;
            self.tripped = true;
            self.watchdog_trips = self.watchdog_trips.saturating_add(1);
            return true;
        }
        false
    }

    /// [`check_watchdog`](Executive::check_watchdog) for an executive whose cycles run with
    /// [`cycle_with`](Executive::cycle_with) under `signals`: the idle loop's check must use
    /// this one. It never trips while `signals` says the power has failed or its watchdog has
    /// tripped (the interrupt handlers have the plant safe; an outage is not a hang), and after
    /// any [`Signals`] trip or power failure it re-arms from this check, as after the
    /// executive's own resume or reset — so neither an outage nor the operator's time before a
    /// [`Signals::reset_watchdog`] trips it. Returns whether the executive's own watchdog is
    /// (now) tripped.
    ///
    /// The plain [`check_watchdog`](Executive::check_watchdog) cannot see [`Signals`]: with
    /// `cycle_with` it counts a `Signals` outage or trip as a hang and trips after one longer
    /// than the limit. Do not mix them.
    pub fn check_watchdog_with<I: Io<IW, OW>>(
        &mut self,
        io: &mut I,
        signals: &Signals<IW, OW>,
    ) -> bool {
        if self.tripped {
            return true;
        }
        let (events, halted) = signals.watch_state();
        if halted {
            return false;
        }
        if events != self.watch_events {
            self.watch_events = events;
            self.last_end_us = None;
            self.watch_from_us = None;
        }
        self.check_watchdog(io)
    }

    /// The operator has looked at the trip: cycles may run again from the safe outputs as the
    /// previous output image; the watchdog re-arms at the next check, and the time tripped is
    /// not program time. A reset while the watchdog has not tripped does nothing.
    pub fn reset_watchdog(&mut self) {
        if self.tripped {
            self.tripped = false;
            self.last_end_us = None;
            self.last_start_us = None;
            self.clock_last_us = None;
            self.watch_from_us = None;
        }
    }

    /// Power failure: writes the safe outputs and freezes the state (images, conditioning,
    /// latched inputs, statistics; the program's timers and counters are its own and are not
    /// touched). Latched inputs are still captured, as the source's battery-backed input
    /// flip-flops did. A watchdog trip stays tripped through the outage.
    pub fn power_fail<I: Io<IW, OW>>(&mut self, io: &mut I) {
        io.write_outputs(self.config.safe_outputs.words());
        self.power_failed = true;
    }

    /// Power is back: the next cycle reads the inputs latched meanwhile and starts from the
    /// previous output image `restart` says — [`Restart::Inhibit`]: the safe outputs the plant
    /// has (what EN 60204-1 asks for: a sealed-in motor stays off), [`Restart::WhereStopped`]:
    /// the image of the last cycle before the outage (the source's behaviour: it runs on). The
    /// outage is not counted as jitter, nor as time for the program's timers: they resume
    /// where they stood. A watchdog that had tripped stays tripped until
    /// [`reset_watchdog`](Executive::reset_watchdog): a power cycle is not an operator's reset.
    /// Without a power failure this does nothing.
    pub fn resume(&mut self, restart: Restart) {
        if self.power_failed {
            self.power_failed = false;
            self.last_start_us = None;
            self.last_end_us = None;
            self.clock_last_us = None;
            self.watch_from_us = None;
            if restart == Restart::Inhibit {
                self.previous = self.config.safe_outputs;
            }
        }
    }

    /// Captures the latched inputs between cycles (see [`Conditioning`]).
    pub fn capture(&mut self, raw: &[u16; IW]) {
        self.conditioning.capture(raw);
    }

    /// Input conditioning: latching and debounce counts.
    pub fn conditioning_mut(&mut self) -> &mut Conditioning<IW> {
        &mut self.conditioning
    }

    /// Forces input `point` (the monitor).
    pub fn force_input(&mut self, point: usize, on: bool) -> Result<(), PointError> {
        self.force_inputs.force(point, on)
    }

    /// Releases input `point`.
    pub fn unforce_input(&mut self, point: usize) -> Result<(), PointError> {
        self.force_inputs.unforce(point)
    }

    /// Forces output `point`.
    pub fn force_output(&mut self, point: usize, on: bool) -> Result<(), PointError> {
        self.force_outputs.force(point, on)
    }

    /// Releases output `point`.
    pub fn unforce_output(&mut self, point: usize) -> Result<(), PointError> {
        self.force_outputs.unforce(point)
    }

    /// The forced inputs.
    #[must_use]
    pub const fn forced_inputs(&self) -> &Forcing<IW> {
        &self.force_inputs
    }

    /// The forced outputs.
    #[must_use]
    pub const fn forced_outputs(&self) -> &Forcing<OW> {
        &self.force_outputs
    }

    /// The input image of the last cycle.
    #[must_use]
    pub const fn inputs(&self) -> &Image<IW> {
        &self.inputs
    }

    /// The output image the plant has: written at the end of the last cycle, or the safe
    /// outputs after a trip of [`check_watchdog`](Executive::check_watchdog) or a
    /// [`Restart::Inhibit`] resume (after a [`Signals`] trip or outage, from the next
    /// [`cycle_with`](Executive::cycle_with) that runs). The next cycle's previous image.
    #[must_use]
    pub const fn outputs(&self) -> &Image<OW> {
        &self.previous
    }

    /// The raw input words of the last read.
    #[must_use]
    pub const fn raw_inputs(&self) -> &[u16; IW] {
        &self.raw
    }

    /// Cycle statistics.
    #[must_use]
    pub const fn stats(&self) -> &CycleStats {
        &self.stats
    }

    /// Cycles run to the end (a cycle a halt overtook is not counted), as `stats().cycles`.
    #[must_use]
    pub const fn cycle_count(&self) -> u64 {
        self.cycle
    }

    /// Times the watchdog tripped.
    #[must_use]
    pub const fn watchdog_trips(&self) -> u32 {
        self.watchdog_trips
    }

    /// Whether cycles are refused, and why.
    #[must_use]
    pub const fn halted(&self) -> Option<Halt> {
        if self.power_failed {
            Some(Halt::PowerFail)
        } else if self.tripped {
            Some(Halt::Watchdog)
        } else {
            None
        }
    }

    /// The configuration.
    #[must_use]
    pub const fn config(&self) -> &CycleConfig<OW> {
        &self.config
    }

    /// Whether `breakpoint`'s condition holds after the last cycle (for `Cycle(n)`: n cycles
    /// or more have run).
    #[must_use]
    pub fn reached(&self, breakpoint: Breakpoint) -> bool {
        Self::holds(breakpoint, self.cycle, &self.inputs, &self.previous)
    }

    /// What the breakpoints see now, to tell after the next cycle which of them came to hold
    /// in it ([`BreakpointWatch::fired`]). [`run`](Executive::run) uses it; so can a monitor
    /// that runs its own loop (a plant simulation between cycles, say).
    #[must_use]
    pub const fn watch(&self) -> BreakpointWatch<IW, OW> {
        BreakpointWatch {
            cycle: self.cycle,
            inputs: self.inputs,
            outputs: self.previous,
        }
    }

    fn holds(breakpoint: Breakpoint, cycle: u64, inputs: &Image<IW>, outputs: &Image<OW>) -> bool {
        match breakpoint {
            Breakpoint::Cycle(n) => cycle >= n,
            Breakpoint::InputOn(p) => inputs.get(p),
            Breakpoint::OutputOn(p) => outputs.get(p),
            Breakpoint::OutputOff(p) => outputs.try_get(p) == Some(false),
        }
    }

    /// Refuses breakpoints that could never fire: `Cycle(0)` (cycles are numbered from 1),
    /// `Cycle(n)` for a cycle already run (`n ≤ cycle_count()`: the count only grows), and
    /// points beyond the images (`16 × IW` inputs, `16 × OW` outputs).
    pub fn check_breakpoints(&self, breakpoints: &[Breakpoint]) -> Result<(), BreakpointError> {
        let inputs = Image::<IW>::POINTS;
        let outputs = Image::<OW>::POINTS;
        for &b in breakpoints {
            match b {
                Breakpoint::Cycle(0) => return Err(BreakpointError::CycleZero),
                Breakpoint::Cycle(n) if n <= self.cycle => {
                    return Err(BreakpointError::CyclePassed {
                        cycle: n,
                        count: self.cycle,
                    });
                }
                Breakpoint::InputOn(point) if point >= inputs => {
                    return Err(BreakpointError::NoSuchInput { point, inputs });
                }
                Breakpoint::OutputOn(point) | Breakpoint::OutputOff(point) if point >= outputs => {
                    return Err(BreakpointError::NoSuchOutput { point, outputs });
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// The monitor's run command: up to `cycles` cycles (`u64::MAX`: continuous), stopping after
    /// the first cycle in which one of `breakpoints` comes to hold (it did not before the
    /// cycle). `between` runs after every cycle (the reserve, the plant simulation). Returns the
    /// cycles run and why the run stopped early, or refuses breakpoints that could never fire
    /// ([`check_breakpoints`](Executive::check_breakpoints)) before running any cycle.
    pub fn run<I: Io<IW, OW>, P: FnMut(&mut Scan<'_, IW, OW>)>(
        &mut self,
        io: &mut I,
        cycles: u64,
        breakpoints: &[Breakpoint],
        program: P,
        between: impl FnMut(&mut Self, &mut I),
    ) -> Result<(u64, Option<Halt>), BreakpointError> {
        let (done, halt, _) = self.monitor(
            io,
            &Unsupervised,
            cycles,
            breakpoints,
            program,
            between,
            |_| false,
        )?;
        Ok((done, halt))
    }

    /// [`run`](Executive::run) with a condition breakpoint as well: `stop` is asked after every
    /// cycle (with the images and statistics in reach) and ends the run when it says so. The
    /// third value tells whether `stop` ended it.
    pub fn run_until<I: Io<IW, OW>, P: FnMut(&mut Scan<'_, IW, OW>)>(
        &mut self,
        io: &mut I,
        cycles: u64,
        breakpoints: &[Breakpoint],
        program: P,
        between: impl FnMut(&mut Self, &mut I),
        stop: impl FnMut(&Self) -> bool,
    ) -> Result<(u64, Option<Halt>, bool), BreakpointError> {
        self.monitor(
            io,
            &Unsupervised,
            cycles,
            breakpoints,
            program,
            between,
            stop,
        )
    }

    /// [`run`](Executive::run) with every cycle run by [`cycle_with`](Executive::cycle_with)
    /// under `signals`: the run stops with the halt when the watchdog trips or the power fails
    /// (it writes nothing while they last), and every cycle kicks the watchdog.
    pub fn run_with<I: Io<IW, OW>, P: FnMut(&mut Scan<'_, IW, OW>)>(
        &mut self,
        io: &mut I,
        signals: &Signals<IW, OW>,
        cycles: u64,
        breakpoints: &[Breakpoint],
        program: P,
        between: impl FnMut(&mut Self, &mut I),
    ) -> Result<(u64, Option<Halt>), BreakpointError> {
        let (done, halt, _) =
            self.monitor(io, signals, cycles, breakpoints, program, between, |_| {
                false
            })?;
        Ok((done, halt))
    }

    /// [`run_until`](Executive::run_until) under `signals`, as [`run_with`](Executive::run_with).
    #[allow(
        clippy::too_many_arguments,
        reason = "run_until's arguments and the Signals; a struct would hide the closures' types"
    )]
    pub fn run_until_with<I: Io<IW, OW>, P: FnMut(&mut Scan<'_, IW, OW>)>(
        &mut self,
        io: &mut I,
        signals: &Signals<IW, OW>,
        cycles: u64,
        breakpoints: &[Breakpoint],
        program: P,
        between: impl FnMut(&mut Self, &mut I),
        stop: impl FnMut(&Self) -> bool,
    ) -> Result<(u64, Option<Halt>, bool), BreakpointError> {
        self.monitor(io, signals, cycles, breakpoints, program, between, stop)
    }

    #[allow(
        clippy::too_many_arguments,
        reason = "the run commands' arguments, passed through"
    )]
    fn monitor<I: Io<IW, OW>, V: Supervision<IW, OW>, P: FnMut(&mut Scan<'_, IW, OW>)>(
        &mut self,
        io: &mut I,
        signals: &V,
        cycles: u64,
        breakpoints: &[Breakpoint],
        mut program: P,
        mut between: impl FnMut(&mut Self, &mut I),
        mut stop: impl FnMut(&Self) -> bool,
    ) -> Result<(u64, Option<Halt>, bool), BreakpointError> {
        self.check_breakpoints(breakpoints)?;
        let mut done = 0u64;
        while done < cycles {
            // The images before the cycle, to see which breakpoints come to hold in it.
            let watch = self.watch();
            if let Err(halt) = self.run_cycle(io, signals, &mut program) {
                return Ok((done, Some(halt), false));
            }
            done = done.saturating_add(1);
            between(self, io);
            if let Some(b) = watch.fired(self, breakpoints) {
                return Ok((done, Some(Halt::Breakpoint(b)), false));
            }
            if stop(self) {
                return Ok((done, None, true));
            }
        }
        Ok((done, None, false))
    }
}

/// A test of level B: a condition on the images.
pub type Condition<const IW: usize, const OW: usize> = fn(&Scan<'_, IW, OW>) -> bool;
/// A routine of level B: runs when its condition holds, on the images and the program's state.
pub type Routine<C, const IW: usize, const OW: usize> = fn(&mut Scan<'_, IW, OW>, &mut C);

/// The 1977 plant's level B: the program as a long chain of tests on the registered inputs, each
/// positive test calling its routine, in order. Steps are plain function pointers in a fixed
/// array of `N`; `C` is the program's own state (its timers, counters, data lists).
///
/// ```
/// use regler_scan_cycle::{CycleConfig, Executive, Io, StepChain};
/// struct Plant([u16; 1], [u16; 1]);
/// impl Io<1, 1> for Plant {
///     fn read_inputs(&mut self, raw: &mut [u16; 1]) { *raw = self.0; }
///     fn write_outputs(&mut self, out: &[u16; 1]) { self.1 = *out; }
///     fn now_us(&mut self) -> u32 { 0 }
/// }
/// struct Counts { trolleys: u32 }
/// let mut chain: StepChain<Counts, 1, 1, 4> = StepChain::new();
/// chain.push(|s| s.inputs.get(0), |s, c| { c.trolleys += 1; s.outputs.set(0, true).ok(); }).ok();
/// chain.push(|s| !s.inputs.get(0), |s, _| { s.outputs.set(0, false).ok(); }).ok();
/// let (mut plant, mut counts) = (Plant([1], [0]), Counts { trolleys: 0 });
/// let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
/// plc.cycle(&mut plant, |scan| chain.run(scan, &mut counts))?;
/// assert_eq!((plant.1, counts.trolleys), ([1], 1));
/// # Ok::<(), regler_scan_cycle::Halt>(())
/// ```
pub struct StepChain<C, const IW: usize, const OW: usize, const N: usize> {
    steps: heapless::Vec<(Condition<IW, OW>, Routine<C, IW, OW>), N>,
}

impl<C, const IW: usize, const OW: usize, const N: usize> Default for StepChain<C, IW, OW, N> {
    fn default() -> Self {
        StepChain::new()
    }
}

impl<C, const IW: usize, const OW: usize, const N: usize> StepChain<C, IW, OW, N> {
    /// An empty chain.
    #[must_use]
    pub const fn new() -> Self {
        StepChain {
            steps: heapless::Vec::new(),
        }
    }

    /// Appends a step; a full chain hands it back.
    #[allow(
        clippy::type_complexity,
        reason = "the step handed back is the pair given"
    )]
    pub fn push(
        &mut self,
        condition: Condition<IW, OW>,
        routine: Routine<C, IW, OW>,
    ) -> Result<(), (Condition<IW, OW>, Routine<C, IW, OW>)> {
        self.steps.push((condition, routine))
    }

    /// Runs the chain once: every step whose condition holds (tested when its turn comes, so a
    /// routine's outputs are visible to the tests after it) calls its routine.
    pub fn run(&self, scan: &mut Scan<'_, IW, OW>, state: &mut C) {
        for (condition, routine) in &self.steps {
            if condition(scan) {
                routine(scan, state);
            }
        }
    }

    /// Steps in the chain.
    #[must_use]
    pub fn len(&self) -> usize {
        self.steps.len()
    }

    /// Whether the chain has no step.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.steps.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    struct Sim {
        inputs: [u16; 2],
        outputs: [u16; 1],
        writes: u32,
        t: u32,
        step_us: u32,
    }

    impl Io<2, 1> for Sim {
        fn read_inputs(&mut self, raw: &mut [u16; 2]) {
            *raw = self.inputs;
        }
        fn write_outputs(&mut self, out: &[u16; 1]) {
            self.outputs = *out;
            self.writes += 1;
        }
        fn now_us(&mut self) -> u32 {
            self.t = self.t.wrapping_add(self.step_us);
            self.t
        }
    }

    fn sim() -> Sim {
        Sim {
            inputs: [0; 2],
            outputs: [0],
            writes: 0,
            t: 0,
            step_us: 1000,
        }
    }

    #[test]
    fn halts_and_breakpoint_errors_say_what_happened() {
        use std::string::ToString;
        assert_eq!(
            Halt::PowerFail.to_string(),
            "power failure: outputs safe, state frozen"
        );
        assert_eq!(Halt::Watchdog.to_string(), "watchdog tripped: outputs safe");
        for (b, text) in [
            (Breakpoint::Cycle(12), "cycle 12"),
            (Breakpoint::InputOn(3), "input 3 came on"),
            (Breakpoint::OutputOn(4), "output 4 came on"),
            (Breakpoint::OutputOff(5), "output 5 went off"),
        ] {
            assert_eq!(b.to_string(), text);
            assert_eq!(
                Halt::Breakpoint(b).to_string(),
                std::format!("breakpoint reached: {text}")
            );
        }
        for (e, text) in [
            (
                BreakpointError::CycleZero,
                "breakpoint at cycle 0 can never fire: cycles are numbered from 1",
            ),
            (
                BreakpointError::CyclePassed { cycle: 7, count: 9 },
                "breakpoint at cycle 7 can never fire: 9 cycles have run already",
            ),
            (
                BreakpointError::NoSuchInput {
                    point: 32,
                    inputs: 32,
                },
                "breakpoint on input 32 can never fire: there are 32 inputs (0 to 31)",
            ),
            (
                BreakpointError::NoSuchOutput {
                    point: 16,
                    outputs: 16,
                },
                "breakpoint on output 16 can never fire: there are 16 outputs (0 to 15)",
            ),
        ] {
            assert_eq!(e.to_string(), text);
        }
    }

    #[test]
    fn program_sees_images_only_and_outputs_swap() {
        let (mut io, mut plc) = (sim(), Executive::<2, 1>::new(CycleConfig::source()));
        io.inputs = [0b1, 0];
        plc.cycle(&mut io, |s| {
            assert!(s.inputs.get(0));
            assert!(!s.previous.get(0));
            s.outputs.set(0, true).unwrap();
        })
        .unwrap();
        assert_eq!(io.outputs, [1]);
        io.inputs = [0, 0];
        plc.cycle(&mut io, |s| {
            assert!(s.previous.get(0), "previous output image");
            assert!(s.outputs.get(0), "next image starts as the previous");
            s.outputs.set(0, false).unwrap();
        })
        .unwrap();
        assert_eq!(io.outputs, [0]);
        assert_eq!(plc.cycle_count(), 2);
    }

    #[test]
    fn forced_values_win_over_program_and_hardware() {
        let (mut io, mut plc) = (sim(), Executive::<2, 1>::new(CycleConfig::source()));
        plc.force_input(17, true).unwrap();
        plc.force_output(3, true).unwrap();
        plc.cycle(&mut io, |s| {
            assert!(s.inputs.get(17));
            s.outputs.set(3, false).unwrap();
        })
        .unwrap();
        assert_eq!(io.outputs, [1 << 3]);
        assert_eq!(plc.forced_outputs().forced(3), Some(true));
        plc.unforce_output(3).unwrap();
        plc.cycle(&mut io, |s| s.outputs.set(3, false).unwrap())
            .unwrap();
        assert_eq!(io.outputs, [0]);
        assert!(plc.force_input(32, true).is_err());
    }

    #[test]
    fn watchdog_trips_to_safe_outputs() {
        let mut config = CycleConfig::source();
        config.safe_outputs = Image::from_words([0b100]);
        let (mut io, mut plc) = (sim(), Executive::<2, 1>::new(config));
        plc.cycle(&mut io, |s| s.outputs.set(0, true).unwrap())
            .unwrap();
        io.step_us = 50_000;
        assert!(!plc.check_watchdog(&mut io)); // 50 ms since the last cycle
        assert!(!plc.check_watchdog(&mut io)); // 100 ms: at the limit
        assert!(plc.check_watchdog(&mut io)); // 150 ms: tripped
        assert_eq!(io.outputs, [0b100]);
        assert_eq!(plc.cycle(&mut io, |_| {}), Err(Halt::Watchdog));
        assert_eq!(plc.watchdog_trips(), 1);
        plc.reset_watchdog();
        assert!(plc.cycle(&mut io, |_| {}).is_ok());
    }

    #[test]
    fn power_failure_freezes_and_resume_keeps_latched_inputs() {
        let (mut io, mut plc) = (sim(), Executive::<2, 1>::new(CycleConfig::source()));
        plc.conditioning_mut().set_latched(5, true).unwrap();
        plc.cycle(&mut io, |s| s.outputs.set(1, true).unwrap())
            .unwrap();
        plc.power_fail(&mut io);
        assert_eq!(io.outputs, [0]);
        assert_eq!(plc.halted(), Some(Halt::PowerFail));
        assert_eq!(plc.cycle(&mut io, |_| {}), Err(Halt::PowerFail));
        plc.capture(&[1 << 5, 0]); // a pulse during the outage
        plc.resume(Restart::WhereStopped);
        plc.cycle(&mut io, |s| {
            assert!(s.inputs.get(5), "latched during the outage");
            assert!(s.previous.get(1), "output image kept");
        })
        .unwrap();
        assert_eq!(io.outputs, [0b10]);
    }

    #[test]
    fn stats_overruns_and_spool() {
        let (mut io, mut plc) = (
            sim(),
            Executive::<2, 1>::new(CycleConfig {
                period_us: 10_000,
                ..CycleConfig::source()
            }),
        );
        plc.cycle(&mut io, |_| {}).unwrap();
        assert_eq!(plc.stats().overruns, 0, "busy 1 ms of a 10 ms period");
        io.step_us = 20_000; // a slow cycle: busy 20 ms > 10 ms period
        plc.cycle(&mut io, |_| {}).unwrap();
        let s = *plc.stats();
        assert_eq!(
            (s.cycles, s.overruns, s.min_us, s.max_us),
            (2, 1, 1000, 20_000)
        );
        // Busy exactly the period is an overrun too: no time is left for the reserve.
        io.step_us = 10_000;
        plc.cycle(&mut io, |_| {}).unwrap();
        assert_eq!(plc.stats().overruns, 2);
        plc = Executive::<2, 1>::new(CycleConfig {
            period_us: 10_000,
            ..CycleConfig::source()
        });
        io.step_us = 1000;
        plc.cycle(&mut io, |_| {}).unwrap();
        io.step_us = 20_000;
        plc.cycle(&mut io, |_| {}).unwrap();
        let s = *plc.stats();
        assert_eq!(s.mean_us(), 10_500);
        assert_eq!(s.load_per_mille(10_000), 1050);
        io.step_us = 1000;
        plc.cycle(&mut io, |_| {}).unwrap();
        let mut spool: Spool<u32, 8> = Spool::new();
        assert!(spool.is_empty());
        for j in 0..8 {
            spool.push(j).unwrap();
            assert!(!spool.is_empty());
        }
        assert_eq!(spool.push(8), Err(8), "a full spool hands the job back");
        let mut ran = Vec::new();
        // 1 ms per clock read: the reserve before the 10 ms period (less 3 ms margin) fits 5 jobs.
        let n = plc.reserve(&mut io, &mut spool, 3_000, |j| ran.push(j));
        assert_eq!(n, ran.len());
        assert!((1..8).contains(&n), "{n}");
        assert_eq!(ran, (0..n as u32).collect::<Vec<_>>());
        assert_eq!(spool.len(), 8 - n);
    }

    #[test]
    fn a_step_chain_runs_the_steps_whose_test_holds_in_order() {
        let mut chain: StepChain<Vec<u8>, 2, 1, 3> = StepChain::new();
        assert!(chain.is_empty());
        assert_eq!(chain.len(), 0);
        // Step 1 sets output 0 when input 0 is on; step 2 tests that output (so it sees step
        // 1's write in the same cycle); step 3 tests input 1.
        assert!(
            chain
                .push(
                    |s| s.inputs.get(0),
                    |s, ran| {
                        s.outputs.set(0, true).ok();
                        ran.push(1);
                    }
                )
                .is_ok()
        );
        assert!(
            chain
                .push(|s| s.outputs.get(0), |_, ran| ran.push(2))
                .is_ok()
        );
        assert!(
            chain
                .push(|s| s.inputs.get(1), |_, ran| ran.push(3))
                .is_ok()
        );
        assert_eq!((chain.len(), chain.is_empty()), (3, false));
        assert!(chain.push(|_| true, |_, ran| ran.push(4)).is_err(), "full");
        assert_eq!(chain.len(), 3);
        let (mut io, mut plc) = (sim(), Executive::<2, 1>::new(CycleConfig::source()));
        let mut ran = Vec::new();
        for (inputs, want) in [
            (0b00, &[][..]),
            (0b01, &[1, 2][..]),
            (0b10, &[3][..]),
            (0b11, &[1, 2, 3][..]),
        ] {
            io.inputs = [inputs, 0];
            ran.clear();
            plc.cycle(&mut io, |scan| {
                scan.outputs.set(0, false).ok();
                chain.run(scan, &mut ran);
            })
            .unwrap();
            assert_eq!(ran, want, "inputs {inputs:02b}");
        }
    }

    #[test]
    fn every_watchdog_trip_is_counted() {
        let (mut io, mut plc) = (sim(), Executive::<2, 1>::new(CycleConfig::source()));
        assert_eq!(plc.watchdog_trips(), 0);
        for trips in 1..=2 {
            plc.cycle(&mut io, |_| {}).unwrap();
            io.step_us = 150_000; // past the 100 ms watchdog
            assert!(plc.check_watchdog(&mut io));
            assert_eq!(plc.watchdog_trips(), trips);
            assert!(
                plc.check_watchdog(&mut io),
                "still tripped: not counted again"
            );
            assert_eq!(plc.watchdog_trips(), trips);
            plc.reset_watchdog();
            io.step_us = 1000;
        }
    }

    #[test]
    fn program_clock_runs_across_the_microsecond_wrap() {
        let (mut io, mut plc) = (sim(), Executive::<2, 1>::new(CycleConfig::source()));
        io.t = u32::MAX - 120_000; // 120 ms before the µs clock wraps
        io.step_us = 25_000; // two reads a cycle: 50 ms per cycle
        let mut ton = crate::Ton::new(1_000);
        let mut fired_after = None;
        for cycle in 1..=40 {
            plc.cycle(&mut io, |s| {
                if ton.call(true, s.now_ms) && fired_after.is_none() {
                    fired_after = Some(cycle);
                }
            })
            .unwrap();
        }
        // Started at cycle 1; 1 000 ms later is cycle 21, not the wrap at cycle 3.
        assert_eq!(fired_after, Some(21));
        assert_eq!(plc.now_ms(), 39 * 50);
    }

    #[test]
    fn run_stops_at_breakpoints() {
        let (mut io, mut plc) = (sim(), Executive::<2, 1>::new(CycleConfig::source()));
        let (n, why) = plc
            .run(&mut io, 10, &[Breakpoint::Cycle(4)], |_| {}, |_, _| {})
            .unwrap();
        assert_eq!((n, why), (4, Some(Halt::Breakpoint(Breakpoint::Cycle(4)))));
        let program = |s: &mut Scan<'_, 2, 1>| {
            s.outputs.set(2, s.cycle.is_multiple_of(3)).unwrap();
        };
        let (n, why) = plc
            .run(
                &mut io,
                u64::MAX,
                &[Breakpoint::OutputOn(2)],
                program,
                |_, _| {},
            )
            .unwrap();
        assert_eq!(
            (n, why),
            (2, Some(Halt::Breakpoint(Breakpoint::OutputOn(2))))
        );
        let (n, why) = plc.run(&mut io, 3, &[], program, |_, _| {}).unwrap();
        assert_eq!((n, why), (3, None));
        // A breakpoint passed is not hit again at once: the cycle breakpoint fires once, and
        // `cont` runs on from an output breakpoint to its next rising edge.
        assert_eq!(
            plc.run(&mut io, 5, &[Breakpoint::Cycle(4)], program, |_, _| {}),
            Err(BreakpointError::CyclePassed { cycle: 4, count: 9 })
        );
        let (n, why) = plc.run(&mut io, 5, &[], program, |_, _| {}).unwrap();
        assert_eq!((n, why), (5, None));
        // A condition breakpoint: both outputs 0 and 2 on.
        let both = |s: &mut Scan<'_, 2, 1>| {
            s.outputs.set(0, s.cycle.is_multiple_of(2)).unwrap();
            s.outputs.set(2, s.cycle.is_multiple_of(5)).unwrap();
        };
        let (_, why, by_condition) = plc
            .run_until(
                &mut io,
                100,
                &[],
                both,
                |_, _| {},
                |p| p.outputs().get(0) && p.outputs().get(2),
            )
            .unwrap();
        assert!(by_condition && why.is_none());
        assert!(plc.cycle_count().is_multiple_of(10));
    }

    #[test]
    fn the_watchdog_is_armed_from_the_start_and_survives_a_power_cycle() {
        let (mut io, mut plc) = (sim(), Executive::<2, 1>::new(CycleConfig::source()));
        io.step_us = 60_000;
        // No cycle ever finishes: the first check arms, a later one trips.
        assert!(!plc.check_watchdog(&mut io));
        assert!(!plc.check_watchdog(&mut io)); // 60 ms
        assert!(plc.check_watchdog(&mut io)); // 120 ms
        plc.power_fail(&mut io);
        assert_eq!(plc.halted(), Some(Halt::PowerFail));
        plc.resume(Restart::WhereStopped);
        assert_eq!(
            plc.halted(),
            Some(Halt::Watchdog),
            "a power cycle is not a reset"
        );
        assert_eq!(plc.cycle(&mut io, |_| {}), Err(Halt::Watchdog));
        plc.reset_watchdog();
        assert!(plc.cycle(&mut io, |_| {}).is_ok());
        assert_eq!(plc.watchdog_trips(), 1);
    }

    #[test]
    fn signals_trip_inside_a_cycle_and_keep_the_trip_through_power_failure() {
        let signals: Signals<2, 1> = Signals::new(&CycleConfig::source());
        let (mut io, mut plc) = (sim(), Executive::<2, 1>::new(CycleConfig::source()));
        plc.cycle_with(&mut io, &signals, |s| s.outputs.set(0, true).unwrap())
            .unwrap();
        let writes = io.writes;
        // The timer interrupt fires while the program hangs in the cycle.
        let r = plc.cycle_with(&mut io, &signals, |s| {
            // 1 s on the Io clock, long after the last cycle ended.
            assert!(signals.check_watchdog(1_000_000));
            s.outputs.set(0, false).unwrap();
        });
        assert_eq!(r, Err(Halt::Watchdog));
        assert_eq!(io.writes, writes, "no outputs written after the trip");
        signals.power_fail();
        assert_eq!(
            plc.cycle_with(&mut io, &signals, |_| {}),
            Err(Halt::PowerFail)
        );
        signals.resume(Restart::WhereStopped);
        assert_eq!(
            plc.cycle_with(&mut io, &signals, |_| {}),
            Err(Halt::Watchdog)
        );
        signals.reset_watchdog();
        assert!(plc.cycle_with(&mut io, &signals, |_| {}).is_ok());
        assert_eq!(signals.trips(), 1);
        // Nothing trips while the power is off.
        signals.power_fail();
        assert!(!signals.check_watchdog(u32::MAX));
        signals.resume(Restart::WhereStopped);
        assert!(!signals.check_watchdog(0), "re-armed from this check");
        assert!(signals.check_watchdog(100_001));
    }

    #[test]
    fn latched_pulses_captured_by_another_thread_are_read_once() {
        use std::sync::Arc;
        let signals: Arc<Signals<2, 1>> = Arc::new(Signals::new(&CycleConfig::source()));
        let (mut io, mut plc) = (sim(), Executive::<2, 1>::new(CycleConfig::source()));
        plc.conditioning_mut().set_latched(3, true).unwrap();
        plc.conditioning_mut().set_latched(20, true).unwrap();
        // A short pulse on input 3 and one on 20, seen only by the "interrupt" thread; input 5
        // is not latched, so its pulse is lost as it would be on the real plant.
        let isr = Arc::clone(&signals);
        std::thread::spawn(move || isr.capture(&[1 << 3 | 1 << 5, 1 << 4]))
            .join()
            .unwrap();
        let mut seen = Vec::new();
        for _ in 0..2 {
            plc.cycle_with(&mut io, &signals, |s| {
                seen.push((s.inputs.get(3), s.inputs.get(5), s.inputs.get(20)));
            })
            .unwrap();
        }
        assert_eq!(seen, [(true, false, true), (false, false, false)]);
    }

    #[test]
    fn size_is_the_documented_formula() {
        use core::mem::size_of;
        let fixed = size_of::<Executive<1, 1>>() - 40;
        assert!(fixed <= 136, "{fixed}");
        for (iw, ow, size) in [
            (34, 15, size_of::<Executive<34, 15>>()),
            (4, 4, size_of::<Executive<4, 4>>()),
            (100, 1, size_of::<Executive<100, 1>>()),
        ] {
            let formula = 30 * iw + 10 * ow + fixed;
            assert!(
                size.abs_diff(formula) < 8,
                "{iw}, {ow}: {size} vs {formula}"
            );
        }
    }

    #[test]
    fn cycle_stats_start_alike_everywhere() {
        let plc = Executive::<2, 1>::new(CycleConfig::source());
        assert_eq!(*plc.stats(), CycleStats::default());
        assert_eq!(CycleStats::default().min_us, u32::MAX);
    }

    #[test]
    fn cont_moves_past_a_breakpoint_to_its_next_edge() {
        let (mut io, mut plc) = (sim(), Executive::<2, 1>::new(CycleConfig::source()));
        // Output 2 is on in cycles 3, 4, 5 of every ten.
        let program = |s: &mut Scan<'_, 2, 1>| {
            s.outputs.set(2, (3..=5).contains(&(s.cycle % 10))).unwrap();
        };
        let on = [Breakpoint::OutputOn(2)];
        let mut stops = Vec::new();
        for _ in 0..3 {
            plc.run(&mut io, 100, &on, program, |_, _| {}).unwrap();
            stops.push(plc.cycle_count());
        }
        assert_eq!(stops, [3, 13, 23], "level-triggered would stop at 3, 4, 5");
        let off = [Breakpoint::OutputOff(2)];
        plc.run(&mut io, 100, &off, program, |_, _| {}).unwrap();
        assert_eq!(plc.cycle_count(), 26);
    }
}
