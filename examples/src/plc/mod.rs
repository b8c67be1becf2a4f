//! A soft-PLC on `regler-scan-cycle` running a conveyor section (source 003's controller with
//! source 000's timer register), against a simulated plant, driven like the 1989 simulator:
//! run N cycles, one cycle, continuous with breakpoints, show and force I/O, spool and statistics.
//!
//! # The conveyor section
//! Inputs: 0 START, 1 STOP, 2 PART (photo eye at the reject gate), 3 BAD (a quality sensor
//! 2 s up the belt flags a bad part), 4 RESET (jam reset). Outputs: 0 MOTOR, 1 JAM lamp,
//! 2 GATE (reject gate), 3 RUN lamp.
//!
//! The program: the motor is latched by START and dropped by STOP or a jam (an SR block); a part
//! covering the photo eye for more than 3 s is a jam (TON) until RESET; every part passing the
//! eye is counted (CTU) and every tenth part queues a batch report on the spool; a bad part at the
//! quality sensor inserts "open gate" into the timer register for when it reaches the gate, and
//! the opening inserts "close gate" 0.6 s later. The register ticks only while the belt runs, so a
//! jam does not throw the gate out of step with the parts.

use std::fmt::Write as _;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use regler_scan_cycle::{
    Breakpoint, Ctu, CycleConfig, DateTime, Executive, Halt, Io, MinuteTable, RTrig, Spool, Sr,
    Start, TimerQueue, Ton, Weekdays,
};
use serde::Serialize;

/// Input words.
pub const IW: usize = 1;
/// Output words.
pub const OW: usize = 1;
/// Cycle period, ms (the 1977 plant's 50 ms).
pub const PERIOD_MS: u32 = 50;

/// Input points.
pub mod input {
    /// Start push-button.
    pub const START: usize = 0;
    /// Stop push-button.
    pub const STOP: usize = 1;
    /// Photo eye at the reject gate.
    pub const PART: usize = 2;
    /// Quality sensor: the part under it is bad.
    pub const BAD: usize = 3;
    /// Jam reset push-button.
    pub const RESET: usize = 4;
}

/// Output points.
pub mod output {
    /// Belt motor.
    pub const MOTOR: usize = 0;
    /// Jam lamp.
    pub const JAM: usize = 1;
    /// Reject gate.
    pub const GATE: usize = 2;
    /// Running lamp.
    pub const RUN: usize = 3;
}

/// Signal names for the timing diagram and commands.
pub const SIGNALS: [(&str, bool, usize); 9] = [
    ("start", true, input::START),
    ("stop", true, input::STOP),
    ("part", true, input::PART),
    ("bad", true, input::BAD),
    ("reset", true, input::RESET),
    ("motor", false, output::MOTOR),
    ("jam", false, output::JAM),
    ("gate", false, output::GATE),
    ("run", false, output::RUN),
];

/// A one-shot job for the reserve: a printout.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Report {
    /// Every tenth part: the batch count.
    Batch(u32),
    /// A shift change from the minute table: the hour.
    Shift(u8),
}

impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Report::Batch(n) => write!(f, "batch of 10 parts, {n} parts in all"),
            Report::Shift(h) => write!(f, "shift report at {h:02}:00"),
        }
    }
}

/// Samples of the timing diagram kept (the last ones): memory stays flat however long it runs.
pub const TRACE_CAP: usize = 100_000;
/// Reports kept for `spool` and the summary (the total is counted apart).
pub const REPORTS_KEPT: usize = 1_000;
/// The most cycles one `run N` takes: 1 000 000 cycles of 50 ms, 13.9 simulated hours.
pub const RUN_MAX: u64 = 1_000_000;
/// `cont` runs until a breakpoint, at most this many cycles (one simulated hour).
pub const CONT_MAX: u64 = 72_000;

/// The monitor's commands, as `help` lists them.
pub const HELP: &str = "\
run N                      run N cycles (at most 1000000), stopping at a breakpoint
step                       one cycle, then show the images
cont                       run until a breakpoint, at most 72000 cycles (one simulated hour)
break cycle N              stop after cycle N
break in POINT on          stop when an input comes on
break out POINT on|off     stop when an output comes on / goes off
clear breaks               remove every breakpoint
force in|out POINT on|off  force a point (the program and the hardware cannot change it)
unforce in|out POINT       release a forced point
show                       the images, forced points marked
spool                      reports waiting in the spool and run
stats                      parts, cycle statistics, load
help                       this list
quit                       end (the summary and the timing diagram follow)
POINT is a number 0-15 or a name: start stop part bad reset (inputs), motor jam gate run (outputs)
";

/// Actions in the timer register.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum GateAction {
    Open,
    Close,
}

/// The application program and its function blocks.
pub struct Conveyor {
    motor: Sr,
    jam_timer: Ton,
    jammed: Sr,
    parts: Ctu,
    part_edge: RTrig,
    bad_edge: RTrig,
    timers: TimerQueue<GateAction, 64>,
    gate: bool,
    /// Reports waiting for the reserve.
    pub spool: Spool<Report, 8>,
    /// Reports refused by a full spool.
    pub spool_refused: u32,
}

/// Cycles a bad part takes from the quality sensor to the gate (2 s at 50 ms).
const TRAVEL_CYCLES: u32 = 40;
/// Gate open time, cycles.
const GATE_OPEN_CYCLES: u32 = 12;

impl Default for Conveyor {
    fn default() -> Self {
        Conveyor::new()
    }
}

impl Conveyor {
    /// The program at power-on.
    #[must_use]
    pub fn new() -> Conveyor {
        Conveyor {
            motor: Sr::new(),
            jam_timer: Ton::new(3_000),
            jammed: Sr::new(),
            parts: Ctu::new(i32::MAX),
            part_edge: RTrig::new(),
            bad_edge: RTrig::new(),
            timers: TimerQueue::new(),
            gate: false,
            spool: Spool::new(),
            spool_refused: 0,
        }
    }

    /// Parts counted (CTU's CV).
    #[must_use]
    pub fn parts(&self) -> i32 {
        self.parts.cv()
    }

    /// The jam timer's elapsed time, ms.
    #[must_use]
    pub fn jam_et(&self) -> u32 {
        self.jam_timer.et()
    }

    /// Timers waiting in the register.
    #[must_use]
    pub fn timers_waiting(&self) -> usize {
        self.timers.len()
    }

    /// One scan of the program.
    pub fn scan(&mut self, s: &mut regler_scan_cycle::Scan<'_, IW, OW>) {
        let i = s.inputs;
        let part = i.get(input::PART);
        let jam = self
            .jam_timer
            .call(part && s.previous.get(output::MOTOR), s.now_ms);
        let jammed = self.jammed.call(jam, i.get(input::RESET) && !part);
        let motor = self
            .motor
            .call(i.get(input::START) && !jammed, i.get(input::STOP) || jammed);
        if self.part_edge.call(part) {
            self.parts.call(true, false);
            if self.parts.cv() % 10 == 0
                && self
                    .spool
                    .push(Report::Batch(self.parts.cv().unsigned_abs()))
                    .is_err()
            {
                self.spool_refused += 1;
            }
        } else {
            self.parts.call(false, false);
        }
        if self.bad_edge.call(i.get(input::BAD)) && motor {
            // Lost only if 64 bad parts were on the belt at once: then the part goes through.
            let _ = self.timers.insert(TRAVEL_CYCLES, GateAction::Open);
        }
        let mut opened = 0;
        let mut gate = self.gate;
        // The register counts belt time: a stopped belt (a jam) holds every part where it is.
        if s.previous.get(output::MOTOR) {
            self.timers.tick(|action| match action {
                GateAction::Open => {
                    gate = true;
                    opened += 1;
                }
                GateAction::Close => gate = false,
            });
        }
        for _ in 0..opened {
            let _ = self.timers.insert(GATE_OPEN_CYCLES, GateAction::Close);
        }
        self.gate = gate;
        let _ = s.outputs.set(output::MOTOR, motor);
        let _ = s.outputs.set(output::JAM, jammed);
        let _ = s.outputs.set(output::GATE, gate);
        let _ = s.outputs.set(output::RUN, motor && !jammed);
    }
}

/// A part on the belt.
#[derive(Clone, Copy, Debug)]
struct Part {
    position_ms: u32,
    bad: bool,
    stuck_for_ms: u32,
}

/// The simulated conveyor section: parts arrive, travel while the motor runs, pass the quality
/// sensor and the gate; now and then one sticks at the eye. An operator presses START at 0.5 s.
pub struct Plant {
    rng: ChaCha8Rng,
    /// Raw inputs.
    pub inputs: [u16; IW],
    /// Outputs as last written.
    pub outputs: [u16; OW],
    /// Simulated time, µs.
    pub clock_us: u64,
    /// In real-time mode (the Modbus server) the clock is the wall clock, so the executive's
    /// busy time, jitter and load are the real ones.
    real_clock: Option<std::time::Instant>,
    parts: Vec<Part>,
    next_arrival_ms: u32,
    /// Outcomes.
    pub tally: Tally,
    press: Vec<(u32, usize, u32)>,
    jam_since_ms: Option<u32>,
}

/// What happened to the parts.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Tally {
    /// Good parts that went on.
    pub good_passed: u32,
    /// Bad parts the gate took out.
    pub bad_rejected: u32,
    /// Bad parts that went on.
    pub bad_passed: u32,
    /// Good parts the gate took out.
    pub good_rejected: u32,
    /// Jams.
    pub jams: u32,
    /// Stuck parts the operator took off the belt.
    pub cleared_by_hand: u32,
}

const GATE_AT_MS: u32 = 2_000;
const EYE_WIDTH_MS: u32 = 150;

impl Plant {
    /// A plant with the given seed; the operator presses START at 0.5 s (for 200 ms).
    #[must_use]
    pub fn new(seed: u64) -> Plant {
        Plant {
            rng: ChaCha8Rng::seed_from_u64(seed),
            inputs: [0; IW],
            outputs: [0; OW],
            clock_us: 0,
            real_clock: None,
            parts: Vec::new(),
            next_arrival_ms: 1_000,
            tally: Tally::default(),
            press: vec![(500, input::START, 200)],
            jam_since_ms: None,
        }
    }

    /// Presses a push-button at `at_ms` for `for_ms`.
    pub fn press(&mut self, at_ms: u32, point: usize, for_ms: u32) {
        self.press.push((at_ms, point, for_ms));
    }

    fn now_ms(&self) -> u32 {
        u32::try_from(self.clock_us / 1000).unwrap_or(u32::MAX)
    }

    /// Advances the plant by `ms` (between cycles).
    pub fn advance(&mut self, ms: u32) {
        let motor = self.outputs[0] & (1 << output::MOTOR) != 0;
        let gate = self.outputs[0] & (1 << output::GATE) != 0;
        for _ in 0..ms {
            self.clock_us += 1000;
            let now = self.now_ms();
            if motor {
                if now >= self.next_arrival_ms
                    && self.parts.last().is_none_or(|p| p.position_ms > 400)
                {
                    let bad = self.rng.random_bool(0.1);
                    let stuck_for_ms = if self.rng.random_bool(0.02) { 4_000 } else { 0 };
                    self.parts.push(Part {
                        position_ms: 0,
                        bad,
                        stuck_for_ms,
                    });
                    self.next_arrival_ms = now + self.rng.random_range(300..1500);
                }
                // The part at the eye may stick; the ones behind it wait.
                let mut blocked = false;
                for p in &mut self.parts {
                    let at_eye =
                        p.position_ms >= GATE_AT_MS && p.position_ms < GATE_AT_MS + EYE_WIDTH_MS;
                    if at_eye && p.stuck_for_ms > 0 {
                        if p.stuck_for_ms == 4_000 {
                            self.tally.jams += 1;
                        }
                        p.stuck_for_ms -= 1;
                        blocked = true;
                    } else if !blocked {
                        p.position_ms += 1;
                    }
                }
            }
            // Parts leave at the gate: into the reject bin if it is open, on otherwise.
            let mut kept = Vec::with_capacity(self.parts.len());
            for p in self.parts.drain(..) {
                if p.position_ms >= GATE_AT_MS + EYE_WIDTH_MS {
                    match (p.bad, gate) {
                        (true, true) => self.tally.bad_rejected += 1,
                        (true, false) => self.tally.bad_passed += 1,
                        (false, true) => self.tally.good_rejected += 1,
                        (false, false) => self.tally.good_passed += 1,
                    }
                } else {
                    kept.push(p);
                }
            }
            self.parts = kept;
        }
        let now = self.now_ms();
        let mut word = 0u16;
        if self
            .parts
            .iter()
            .any(|p| p.position_ms >= GATE_AT_MS && p.position_ms < GATE_AT_MS + EYE_WIDTH_MS)
        {
            word |= 1 << input::PART;
        }
        if self.parts.iter().any(|p| p.bad && p.position_ms < 100) {
            word |= 1 << input::BAD;
        }
        for &(at, point, dur) in &self.press {
            if now >= at && now < at + dur {
                word |= 1 << point;
            }
        }
        self.inputs = [word];
        // Two seconds after the jam lamp comes on, the operator takes the stuck part off the
        // belt, presses RESET, then START.
        if self.outputs[0] & (1 << output::JAM) == 0 {
            self.jam_since_ms = None;
        } else if now.saturating_sub(*self.jam_since_ms.get_or_insert(now)) >= 2_000 {
            let before = self.parts.len();
            self.parts.retain(|p| {
                !(p.position_ms >= GATE_AT_MS && p.position_ms < GATE_AT_MS + EYE_WIDTH_MS)
            });
            self.tally.cleared_by_hand += u32::try_from(before - self.parts.len()).unwrap_or(0);
            self.press.push((now + 100, input::RESET, 200));
            self.press.push((now + 500, input::START, 200));
            self.jam_since_ms = Some(u32::MAX / 2); // handled: wait for the lamp to go out
        }
    }
}

impl Plant {
    /// From now on the clock is the wall clock (real-time mode): the cycle statistics measure
    /// this machine, not the simulated CPU.
    pub fn use_real_clock(&mut self) {
        self.real_clock = Some(std::time::Instant::now());
    }
}

impl Io<IW, OW> for Plant {
    fn read_inputs(&mut self, raw: &mut [u16; IW]) {
        *raw = self.inputs;
    }
    fn write_outputs(&mut self, outputs: &[u16; OW]) {
        self.outputs = *outputs;
    }
    fn now_us(&mut self) -> u32 {
        if let Some(start) = self.real_clock {
            // The wall clock, wrapping at 2^32 µs as a hardware timer would.
            return (start.elapsed().as_micros() & u128::from(u32::MAX)) as u32;
        }
        // Each clock read costs the simulated CPU 1 ms, so a cycle (two reads) is busy 1 ms.
        self.clock_us += 1_000;
        (self.clock_us & u64::from(u32::MAX)) as u32
    }
}

/// One sample of the timing diagram.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Sample {
    /// Cycle number.
    pub cycle: u64,
    /// Input word.
    pub inputs: u16,
    /// Output word.
    pub outputs: u16,
}

/// The soft-PLC with its plant, as the simulator drives it.
pub struct Simulator {
    /// The executive.
    pub plc: Executive<IW, OW>,
    /// The program.
    pub program: Conveyor,
    /// The plant.
    pub plant: Plant,
    /// Active breakpoints; each stops a run on the cycle it comes to hold.
    pub breakpoints: Vec<Breakpoint>,
    /// The timing diagram.
    pub trace: std::collections::VecDeque<Sample>,
    /// Reports run in the reserve.
    pub reports: std::collections::VecDeque<Report>,
    /// Reports run in all.
    pub reports_run: u64,
    /// The calendar clock, advanced by the plant's wall clock.
    pub clock: DateTime,
    /// Shift changes: programs started at given minutes.
    pub table: MinuteTable<Report, 4>,
}

impl Simulator {
    /// A simulator with the plant seeded by `seed`.
    #[must_use]
    pub fn new(seed: u64) -> Simulator {
        let config = CycleConfig {
            period_us: PERIOD_MS * 1000,
            ..CycleConfig::source()
        };
        let mut plc = Executive::new(config);
        // The photo eye chatters at edges: two equal readings needed.
        let _ = plc.conditioning_mut().set_debounce(input::PART, 2);
        // The quality sensor's pulse can be shorter than a cycle: latch it.
        let _ = plc.conditioning_mut().set_latched(input::BAD, true);
        // Shift reports at the shift changes, as the 1977 plant printed statistics at 24:00.
        let mut table = MinuteTable::new();
        for hour in [6, 14, 22] {
            let _ = table.add(Start {
                hour,
                minute: 0,
                days: Weekdays::ALL,
                program: Report::Shift(hour),
            });
        }
        Simulator {
            plc,
            program: Conveyor::new(),
            plant: Plant::new(seed),
            breakpoints: Vec::new(),
            trace: std::collections::VecDeque::new(),
            reports: std::collections::VecDeque::new(),
            reports_run: 0,
            clock: DateTime::new(2026, 11, 23, 13, 58, 30).unwrap_or_else(|_| unreachable!()),
            table,
        }
    }

    /// Runs up to `cycles` cycles, stopping at a breakpoint; returns the cycles run and why it
    /// stopped early.
    pub fn run(&mut self, cycles: u64) -> (u64, Option<Halt>) {
        let mut done = 0u64;
        while done < cycles {
            let watch = self.plc.watch();
            let program = &mut self.program;
            if let Err(halt) = self.plc.cycle(&mut self.plant, |scan| program.scan(scan)) {
                return (done, Some(halt));
            }
            done += 1;
            // The calendar goes by the plant's wall clock (here the simulated period), never by
            // the executive's program time, which leaves power outages out. The minute table
            // hands out each start once, late if the clock jumped over its minute.
            self.clock.advance(PERIOD_MS);
            let (spool, refused) = (&mut self.program.spool, &mut self.program.spool_refused);
            self.table.check(&self.clock, |due| {
                if spool.push(*due.program).is_err() {
                    *refused += 1;
                }
            });
            // Level C: the reserve runs the spool.
            let (reports, run) = (&mut self.reports, &mut self.reports_run);
            self.plc
                .reserve(&mut self.plant, &mut self.program.spool, 5_000, |batch| {
                    if reports.len() == REPORTS_KEPT {
                        reports.pop_front();
                    }
                    reports.push_back(batch);
                    *run += 1;
                });
            if self.trace.len() == TRACE_CAP {
                self.trace.pop_front();
            }
            self.trace.push_back(Sample {
                cycle: self.plc.cycle_count(),
                inputs: self.plc.inputs().word(0).unwrap_or(0),
                outputs: self.plc.outputs().word(0).unwrap_or(0),
            });
            // The rest of the period passes; the plant moves; latched pulses are caught.
            let busy_ms = self.plc.stats().last_us / 1000;
            self.plant.advance(PERIOD_MS.saturating_sub(busy_ms).max(1));
            self.plc.capture(&self.plant.inputs);
            // A breakpoint stops the run on the cycle it comes to hold, not while it holds.
            if let Some(b) = watch.fired(&self.plc, &self.breakpoints) {
                return (done, Some(Halt::Breakpoint(b)));
            }
        }
        (done, None)
    }

    /// Executes one monitor command; returns what it prints. Errors name the problem.
    pub fn command(&mut self, line: &str) -> Result<String, String> {
        let words: Vec<&str> = line.split_whitespace().collect();
        let point = |s: Option<&&str>| -> Result<usize, String> {
            let s = s.ok_or("missing point")?;
            SIGNALS
                .iter()
                .find(|(name, ..)| name == s)
                .map(|&(_, _, p)| p)
                .or_else(|| s.parse().ok())
                .ok_or_else(|| format!("no such point: {s}"))
        };
        let level = |s: Option<&&str>| -> Result<bool, String> {
            match s.copied() {
                Some("1" | "on") => Ok(true),
                Some("0" | "off") => Ok(false),
                Some(other) => Err(format!("expected on/off or 1/0, got {other}")),
                None => Err("expected on/off or 1/0 at the end".into()),
            }
        };
        let io_side = |s: Option<&&str>| -> Result<bool, String> {
            match s.copied() {
                Some("in") => Ok(true),
                Some("out") => Ok(false),
                Some(other) => Err(format!("expected in or out, got {other}")),
                None => Err("expected in or out".into()),
            }
        };
        let mut out = String::new();
        match words.as_slice() {
            [] => {}
            ["run", n] => {
                let n: u64 = n
                    .parse()
                    .ok()
                    .filter(|n| (1..=RUN_MAX).contains(n))
                    .ok_or_else(|| format!("run takes 1 to {RUN_MAX} cycles, got {n}"))?;
                let (done, why) = self.run(n);
                let _ = writeln!(
                    out,
                    "ran {done} cycle(s){}",
                    why.map(|w| format!(": {w}")).unwrap_or_default()
                );
            }
            ["step"] => {
                let (done, why) = self.run(1);
                let _ = writeln!(
                    out,
                    "ran {done} cycle{}",
                    why.map(|w| format!(": {w}")).unwrap_or_default()
                );
                out.push_str(&self.show());
            }
            ["cont"] | ["continue"] => {
                // Continuous, bounded so a script without breakpoints ends: one simulated hour.
                let (done, why) = self.run(CONT_MAX);
                let _ = writeln!(
                    out,
                    "ran {done} cycle(s){}",
                    why.map(|w| format!(": {w}")).unwrap_or_default()
                );
            }
            ["break", "cycle", n] => {
                let n = n
                    .parse()
                    .map_err(|_| format!("break cycle takes a number, got {n}"))?;
                // A cycle already run can never be reached again: refused, as `run` does.
                let b = Breakpoint::Cycle(n);
                self.plc
                    .check_breakpoints(&[b])
                    .map_err(|e| e.to_string())?;
                self.breakpoints.push(b);
            }
            ["break", side, p, lvl] => {
                let (input, p, on) = (io_side(Some(side))?, point(Some(p))?, level(Some(lvl))?);
                self.breakpoints.push(match (input, on) {
                    (true, true) => Breakpoint::InputOn(p),
                    (false, true) => Breakpoint::OutputOn(p),
                    (false, false) => Breakpoint::OutputOff(p),
                    (true, false) => {
                        return Err("input breakpoints are on rising inputs only (in P on)".into());
                    }
                });
            }
            ["clear", "breaks"] => self.breakpoints.clear(),
            ["force", side, p, lvl] => {
                let (input, p, on) = (io_side(Some(side))?, point(Some(p))?, level(Some(lvl))?);
                let r = if input {
                    self.plc.force_input(p, on)
                } else {
                    self.plc.force_output(p, on)
                };
                r.map_err(|e| e.to_string())?;
            }
            ["unforce", side, p] => {
                let (input, p) = (io_side(Some(side))?, point(Some(p))?);
                let r = if input {
                    self.plc.unforce_input(p)
                } else {
                    self.plc.unforce_output(p)
                };
                r.map_err(|e| e.to_string())?;
            }
            ["show"] => out.push_str(&self.show()),
            ["spool"] => {
                let waiting: Vec<String> =
                    self.program.spool.iter().map(ToString::to_string).collect();
                let _ = writeln!(
                    out,
                    "spool: {} waiting [{}], {} run, {} refused",
                    waiting.len(),
                    waiting.join("; "),
                    self.reports_run,
                    self.program.spool_refused
                );
            }
            ["stats"] => out.push_str(&self.stats()),
            ["help"] => out.push_str(HELP),
            _ => {
                return Err(format!(
                    "unknown command '{line}' (help lists the commands)"
                ));
            }
        }
        Ok(out)
    }

    /// The I/O images with forced points marked.
    #[must_use]
    pub fn show(&self) -> String {
        let mut s = format!("cycle {}  {}\n", self.plc.cycle_count(), self.clock);
        for &(name, input, p) in &SIGNALS {
            let (value, forced) = if input {
                (self.plc.inputs().get(p), self.plc.forced_inputs().forced(p))
            } else {
                (
                    self.plc.outputs().get(p),
                    self.plc.forced_outputs().forced(p),
                )
            };
            let _ = writeln!(
                s,
                "  {} {:>2} {:<6} {}{}",
                if input { "in " } else { "out" },
                p,
                name,
                u8::from(value),
                if forced.is_some() { "  FORCED" } else { "" }
            );
        }
        s
    }

    /// Cycle statistics and counts.
    #[must_use]
    pub fn stats(&self) -> String {
        let st = self.plc.stats();
        let t = self.plant.tally;
        format!(
            "cycles {}  busy last/min/mean/max {}/{}/{}/{} us  jitter {} us  load {} per mille  overruns {}\n\
             parts {}  good passed {}  bad rejected {}  bad passed {}  good rejected {}  jams {}  reports {}\n",
            st.cycles,
            st.last_us,
            if st.cycles == 0 { 0 } else { st.min_us },
            st.mean_us(),
            st.max_us,
            st.jitter_us,
            st.load_per_mille(self.plc.config().period_us),
            st.overruns,
            self.program.parts(),
            t.good_passed,
            t.bad_rejected,
            t.bad_passed,
            t.good_rejected,
            t.jams,
            self.reports_run
        )
    }
}

/// The built-in demonstration: what an engineer would type at the 1989 simulator.
pub const DEMO_SCRIPT: &str = "# run the section for a minute and look at it
run 1200
show
stats
# stop at the next jam, look, then step through the reset
break out jam on
cont
show
clear breaks
run 100
# force the reject gate open for a second: good parts go to the reject bin
force out gate 1
run 20
unforce out gate
run 2400
spool
stats
";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_program_runs_the_section() {
        let mut sim = Simulator::new(7);
        sim.run(6_000); // five minutes
        let t = sim.plant.tally;
        assert!(sim.program.parts() > 100, "{}", sim.program.parts());
        // Parts held behind a stuck one while the jam timer runs can slip past the gate's
        // timing; everything else is sorted right.
        assert!(t.bad_rejected > 5 && t.bad_passed <= t.jams, "{t:?}");
        assert!(t.good_rejected <= t.jams, "{t:?}");
        assert_eq!(t.cleared_by_hand, t.jams);
        assert!(sim.reports.iter().any(|r| matches!(r, Report::Batch(_))));
        assert!(
            sim.reports.contains(&Report::Shift(14)),
            "the 14:00 shift report ran"
        );
        assert!(sim.plc.stats().overruns == 0);
    }

    #[test]
    fn commands_and_their_errors() {
        let mut sim = Simulator::new(1);
        assert!(sim.command("run 10").unwrap().contains("ran 10"));
        sim.command("force in start 1").unwrap();
        assert!(sim.command("step").unwrap().contains("FORCED"));
        sim.command("break cycle 15").unwrap();
        assert!(sim.command("cont").unwrap().contains("breakpoint"));
        assert!(sim.command("force in 99 1").is_err());
        assert!(sim.command("fly").unwrap_err().contains("unknown command"));
        assert!(sim.command("run many").is_err());
        assert!(sim.command("break in part off").is_err());
        // Cycle 15 has run: a breakpoint there could never fire.
        let passed = sim.command("break cycle 15").unwrap_err();
        assert!(passed.contains("cycle 15 can never fire"), "{passed}");
        sim.command("break cycle 0").unwrap_err();
    }
}
