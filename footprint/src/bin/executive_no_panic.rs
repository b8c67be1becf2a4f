//! A probe, not a measurement: firmware whose panic handler calls a function that is declared
//! but defined nowhere, so it links only if no panic path is left in what it calls — the
//! `Executive` of 1×1, 2×2 and 34×15 words with every public method (`new`, `cycle`,
//! `cycle_with`, `reserve`, `reserve_with`, both watchdog checks and `reset_watchdog`,
//! `power_fail`/`resume` with either `Restart`, `capture`, forcing and unforcing by run-time
//! point, `set_now_ms`, the read-outs, `reached`, `watch`/`fired`, `check_breakpoints` and the
//! four `run` commands with run-time breakpoints and cycle counts), `Signals` (every method),
//! `StepChain` (push beyond its capacity, run), `Spool`, `CycleStats`, every IEC block (TON, TOF,
//! TP with run-time presets and times, CTU/CTD/CTUD at `i32::MIN`/`MAX` presets, R_TRIG,
//! F_TRIG, SR, RS), `Image`, `Forcing` and `Conditioning` on run-time points, words and counts,
//! and every error's `Display`. The clock, the inputs and every number come from volatile reads.
//! The measuring build (feature `measure`) runs the calls under QEMU with an ordinary panic
//! handler.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use regler_footprint::{MEASURING, at, finish, keep, shown};
use regler_scan_cycle::{
    Breakpoint, Conditioning, Ctd, Ctu, Ctud, CycleConfig, Executive, FTrig, Forcing, Image, Io,
    RTrig, Restart, Rs, Scan, Signals, Spool, Sr, StepChain, Tof, Ton, Tp,
};

/// Numbers as a clock, a keyboard or stored state would give them.
static WORDS: [u32; 10] = [
    0,
    1,
    2,
    15,
    16,
    50_000,
    0x7FFF_FFFF,
    0x8000_0000,
    u32::MAX - 1,
    u32::MAX,
];
/// Raw input words.
static RAW: [u16; 5] = [0, 0xFFFF, 0x00F0, 0x8001, 0x1234];

fn word(i: usize) -> u32 {
    at(&WORDS, i)
}

fn raw(i: usize) -> u16 {
    at(&RAW, i)
}

/// Hardware whose inputs and clock are run-time values; the clock steps by run-time amounts,
/// back and across the wrap included.
struct Hardware {
    now: u32,
    step: usize,
}

impl<const IW: usize, const OW: usize> Io<IW, OW> for Hardware {
    fn read_inputs(&mut self, raw_words: &mut [u16; IW]) {
        for (i, w) in raw_words.iter_mut().enumerate() {
            *w = raw(i + self.step);
        }
    }
    fn write_outputs(&mut self, outputs: &[u16; OW]) {
        keep(
            outputs
                .iter()
                .map(|&w| u32::from(w))
                .fold(0, u32::wrapping_add),
        );
    }
    fn now_us(&mut self) -> u32 {
        self.step = self.step.wrapping_add(1);
        self.now = self.now.wrapping_add(word(self.step));
        self.now
    }
    fn kick_watchdog(&mut self) {
        keep(1);
    }
}

fn breakpoint(i: usize) -> Breakpoint {
    let n = word(i) as usize;
    match i % 4 {
        0 => Breakpoint::Cycle(u64::from(word(i + 1))),
        1 => Breakpoint::InputOn(n),
        2 => Breakpoint::OutputOn(n),
        _ => Breakpoint::OutputOff(n),
    }
}

fn program<const IW: usize, const OW: usize>(scan: &mut Scan<'_, IW, OW>) {
    let p = word(scan.cycle as usize) as usize;
    let on = scan.inputs.get(p) ^ scan.previous.get(p + 1);
    if let Err(e) = scan.outputs.set(p, on) {
        keep(shown(&e));
    }
    if let Err(e) = scan.outputs.set_word(p, raw(p)) {
        keep(shown(&e));
    }
    keep(u32::from(scan.outputs.word(p).unwrap_or(0)) ^ scan.now_ms);
}

fn step_on<const IW: usize, const OW: usize>(scan: &Scan<'_, IW, OW>) -> bool {
    scan.inputs.get(word(3) as usize)
}

fn step_do<const IW: usize, const OW: usize>(scan: &mut Scan<'_, IW, OW>, count: &mut u32) {
    *count = count.wrapping_add(1);
    let _ = scan.outputs.set(*count as usize, true);
}

fn executive<const IW: usize, const OW: usize>(seed: usize) -> u32 {
    let mut answer = 0u32;
    let mut safe = Image::<OW>::new();
    let _ = safe.set_word(0, raw(seed));
    let config = CycleConfig {
        period_us: word(seed),
        watchdog_us: word(seed + 1),
        safe_outputs: safe,
    };
    let mut plc = Executive::<IW, OW>::new(config);
    let signals = Signals::<IW, OW>::new(&config);
    let mut io = Hardware {
        now: word(seed + 2),
        step: seed,
    };
    let mut chain: StepChain<u32, IW, OW, 2> = StepChain::new();
    for _ in 0..3 {
        if chain.push(step_on, step_do).is_err() {
            answer ^= 1;
        }
    }
    answer ^= chain.len() as u32 ^ u32::from(chain.is_empty());
    let mut spool: Spool<u32, 2> = Spool::new();
    let mut state = 0u32;
    for i in 0..60usize {
        let p = word(i + seed) as usize ^ i;
        if let Err(e) = plc.conditioning_mut().set_debounce(p, word(i) as u8) {
            answer ^= shown(&e);
        }
        if let Err(e) = plc
            .conditioning_mut()
            .set_latched(p + 1, i.is_multiple_of(3))
        {
            answer ^= shown(&e);
        }
        match i % 5 {
            0 => {
                if let Err(e) = plc.force_input(p, i.is_multiple_of(2)) {
                    answer ^= shown(&e);
                }
            }
            1 => {
                if let Err(e) = plc.force_output(p, i.is_multiple_of(2)) {
                    answer ^= shown(&e);
                }
            }
            2 => {
                let _ = plc.unforce_input(p);
                let _ = plc.unforce_output(p);
            }
            3 => {
                let mut raw_words = [0u16; IW];
                for (k, w) in raw_words.iter_mut().enumerate() {
                    *w = raw(k ^ i);
                }
                plc.capture(&raw_words);
                signals.capture(&raw_words);
            }
            _ => plc.set_now_ms(word(i)),
        }
        let result = if i.is_multiple_of(2) {
            plc.cycle(&mut io, |scan| {
                program(scan);
                chain.run(scan, &mut state);
            })
        } else {
            plc.cycle_with(&mut io, &signals, program)
        };
        if let Err(halt) = result {
            answer ^= shown(&halt);
        }
        let _ = spool.push(word(i));
        answer ^= spool.len() as u32 ^ u32::from(spool.is_empty());
        answer ^= spool.iter().fold(0, |a, &j| a ^ j);
        answer ^= if i.is_multiple_of(2) {
            plc.reserve(&mut io, &mut spool, word(i + 1), keep) as u32
        } else {
            plc.reserve_with(&mut io, &signals, &mut spool, word(i + 1), keep) as u32
        };
        answer ^= u32::from(plc.check_watchdog(&mut io));
        answer ^= u32::from(plc.check_watchdog_with(&mut io, &signals));
        answer ^= u32::from(signals.check_watchdog(word(i + 3)));
        match word(i + 7) % 7 {
            0 => {
                plc.power_fail(&mut io);
                signals.power_fail();
            }
            1 => {
                let restart = if i.is_multiple_of(2) {
                    Restart::Inhibit
                } else {
                    Restart::WhereStopped
                };
                plc.resume(restart);
                signals.resume(restart);
            }
            2 => {
                plc.reset_watchdog();
                signals.reset_watchdog();
            }
            _ => {}
        }
        answer ^=
            u32::from(signals.tripped()) ^ u32::from(signals.power_failed()) ^ signals.trips();
        answer ^= u32::from(signals.safe_outputs().word(0).unwrap_or(0));
    }
    // Breakpoints and the monitor's commands, with run-time breakpoints and counts.
    let breakpoints = [
        breakpoint(seed),
        breakpoint(seed + 1),
        breakpoint(seed + 2),
        breakpoint(seed + 3),
    ];
    let n = (word(seed) as usize) % (breakpoints.len() + 1);
    let breakpoints = &breakpoints[..n];
    if let Err(e) = plc.check_breakpoints(breakpoints) {
        answer ^= shown(&e);
    }
    let watch = plc.watch();
    for b in breakpoints {
        answer ^= u32::from(plc.reached(*b)) ^ shown(b);
    }
    let cycles = u64::from(word(seed + 1) % 8);
    let between = |_: &mut Executive<IW, OW>, _: &mut Hardware| keep(2);
    match plc.run(&mut io, cycles, breakpoints, program, between) {
        Ok((done, halt)) => answer ^= done as u32 ^ halt.map_or(0, |h| shown(&h)),
        Err(e) => answer ^= shown(&e),
    }
    match plc.run_until(&mut io, cycles, breakpoints, program, between, |p| {
        p.cycle_count() > 3
    }) {
        Ok((done, _, stopped)) => answer ^= done as u32 ^ u32::from(stopped),
        Err(e) => answer ^= shown(&e),
    }
    match plc.run_with(&mut io, &signals, cycles, breakpoints, program, between) {
        Ok((done, _)) => answer ^= done as u32,
        Err(e) => answer ^= shown(&e),
    }
    match plc.run_until_with(
        &mut io,
        &signals,
        cycles,
        breakpoints,
        program,
        between,
        |_| false,
    ) {
        Ok((done, _, _)) => answer ^= done as u32,
        Err(e) => answer ^= shown(&e),
    }
    if let Some(b) = watch.fired(&plc, breakpoints) {
        answer ^= shown(&b);
    }
    // The read-outs.
    let stats = plc.stats();
    answer ^= stats.mean_us() ^ stats.load_per_mille(word(seed)) ^ stats.jitter_us;
    answer ^= plc.now_ms() ^ plc.watchdog_trips() ^ plc.cycle_count() as u32;
    answer ^= u32::from(plc.halted().is_some()) ^ plc.config().period_us;
    answer ^= u32::from(plc.inputs().word(0).unwrap_or(0)) ^ u32::from(plc.outputs().get(seed));
    answer ^= plc
        .raw_inputs()
        .iter()
        .map(|&w| u32::from(w))
        .fold(0, u32::wrapping_add);
    answer ^= u32::from(plc.forced_inputs().any()) ^ u32::from(plc.forced_outputs().any());
    answer ^ state
}

fn images_and_conditioning<const W: usize>(seed: usize) -> u32 {
    let mut answer = 0u32;
    let mut image = Image::<W>::new();
    let mut forcing = Forcing::<W>::new();
    let mut conditioning = Conditioning::<W>::new();
    let mut raw_words = [0u16; W];
    for i in 0..40usize {
        let p = word(i + seed) as usize ^ i;
        answer ^= u32::from(image.get(p)) ^ u32::from(image.try_get(p).unwrap_or(false));
        if let Err(e) = image.set(p, i.is_multiple_of(2)) {
            answer ^= shown(&e);
        }
        if let Err(e) = image.set_word(p, raw(i)) {
            answer ^= shown(&e);
        }
        answer ^= u32::from(image.word(p).unwrap_or(0));
        if let Some(w) = image.words_mut().get_mut(p) {
            *w ^= 1;
        }
        answer ^= image.ones().take(4).fold(0, |a, q| a ^ q as u32);
        if let Err(e) = forcing.force(p, i.is_multiple_of(3)) {
            answer ^= shown(&e);
        }
        if i.is_multiple_of(4) && forcing.unforce(p).is_err() {
            answer ^= 3;
        }
        answer ^= u32::from(forcing.forced(p).unwrap_or(false)) ^ u32::from(forcing.any());
        answer ^= forcing
            .iter()
            .take(4)
            .fold(0, |a, (q, on)| a ^ q as u32 ^ u32::from(on));
        forcing.apply(&mut image);
        if let Err(e) = conditioning.set_debounce(p, word(i) as u8) {
            answer ^= shown(&e);
        }
        if let Err(e) = conditioning.set_latched(p, i.is_multiple_of(5)) {
            answer ^= shown(&e);
        }
        answer ^= u32::from(conditioning.debounce(p)) ^ u32::from(conditioning.latched(p));
        for (k, w) in raw_words.iter_mut().enumerate() {
            *w = raw(k + i);
        }
        conditioning.capture(&raw_words);
        conditioning.condition(&raw_words, &mut image);
        if i.is_multiple_of(13) {
            forcing.clear();
        }
    }
    answer ^= image
        .words()
        .iter()
        .map(|&w| u32::from(w))
        .fold(0, u32::wrapping_add);
    answer ^ u32::from(Image::<W>::from_words(raw_words).get(seed))
}

fn blocks(seed: usize) -> u32 {
    let mut answer = 0u32;
    let mut ton = Ton::new(word(seed));
    let mut tof = Tof::new(word(seed + 1));
    let mut tp = Tp::new(word(seed + 2));
    let pv = |i: usize| word(i) as i32;
    let mut ctu = Ctu::new(pv(seed + 3));
    let mut ctd = Ctd::new(pv(seed + 4));
    let mut ctud = Ctud::new(pv(seed + 5));
    let (mut rt, mut ft, mut sr, mut rs) = (RTrig::new(), FTrig::new(), Sr::new(), Rs::new());
    let mut now = word(seed + 6);
    for i in 0..200usize {
        now = now.wrapping_add(word(i));
        let a = raw(i) & 1 != 0;
        let b = raw(i + seed) & 2 != 0;
        answer ^= u32::from(ton.call(a, now)) ^ ton.et() ^ u32::from(ton.q()) ^ ton.pt();
        answer ^= u32::from(tof.call(b, now)) ^ tof.et() ^ u32::from(tof.q()) ^ tof.pt();
        answer ^= u32::from(tp.call(a ^ b, now)) ^ tp.et() ^ u32::from(tp.q()) ^ tp.pt();
        if i.is_multiple_of(17) {
            ton.set_pt(word(i));
            tof.set_pt(word(i + 1));
            tp.set_pt(word(i + 2));
            ctu.set_pv(pv(i));
            ctd.set_pv(pv(i + 1));
            ctud.set_pv(pv(i + 2));
        }
        answer ^= u32::from(ctu.call(a, b && i.is_multiple_of(50)))
            ^ ctu.cv() as u32
            ^ u32::from(ctu.q());
        answer ^= u32::from(ctd.call(b, a && i.is_multiple_of(50))) ^ ctd.cv() as u32;
        let (up, down) = ctud.call(a, b, i.is_multiple_of(60), i.is_multiple_of(70));
        answer ^= u32::from(up) ^ u32::from(down) ^ ctud.cv() as u32;
        answer ^= u32::from(rt.call(a)) ^ u32::from(ft.call(b));
        answer ^= u32::from(sr.call(a, b)) ^ u32::from(rs.call(b, a));
    }
    answer
}

#[entry]
fn main() -> ! {
    let mut answer = executive::<1, 1>(0);
    answer ^= executive::<2, 2>(3);
    answer ^= executive::<34, 15>(5);
    answer ^= images_and_conditioning::<1>(0);
    answer ^= images_and_conditioning::<2>(4);
    answer ^= blocks(0);
    answer ^= blocks(7);
    keep(answer);
    if MEASURING {
        finish();
    }
    loop {
        cortex_m::asm::nop();
    }
}

regler_footprint::no_panic_probe!();
