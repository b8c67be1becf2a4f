//! regler-scan-cycle on the core: 32-bit usize in the wheel, the critical section of a real core.

use regler_scan_cycle::{
    Breakpoint, Conditioning, Ctd, Ctu, Ctud, CycleConfig, DateTime, Executive, FTrig, Halt, Io,
    MinuteTable, RTrig, Restart, Rs, Signals, Spool, Sr, Start, StepChain, TimerQueue, Tof, Ton,
    Tp, Weekdays,
};

use crate::{Outcome, check};

pub fn iec_timers_and_pt_changes() -> Outcome {
    let mut ton = Ton::new(500);
    check!(!ton.call(true, 1_000));
    check!(ton.call(true, 1_500));
    ton.set_pt(5_000);
    check!(ton.call(true, 1_600)); // finished stays finished
    check!(!ton.call(false, 1_700));
    let mut tof = Tof::new(300);
    check!(tof.call(true, 0));
    check!(tof.call(false, 100));
    check!(!tof.call(false, 400));
    tof.set_pt(1_000);
    check!(!tof.call(false, 450)); // expired stays off
    let mut tp = Tp::new(200);
    check!(tp.call(true, 0));
    check!(!tp.call(true, 200));
    tp.set_pt(900);
    check!(!tp.call(true, 300)); // no edge, no pulse
    // Across the wrap of the millisecond clock.
    let mut wrap = Ton::new(10);
    check!(!wrap.call(true, u32::MAX - 5));
    check!(wrap.call(true, 4));
    Ok(())
}

pub fn counters_edges_bistables() -> Outcome {
    let mut ctu = Ctu::new(3);
    for cu in [true, false, true, false] {
        ctu.call(cu, false);
    }
    check!(ctu.cv() == 2 && !ctu.call(false, false));
    check!(ctu.call(true, false));
    let mut ctd = Ctd::new(2);
    ctd.call(false, true);
    ctd.call(true, false);
    check!(ctd.cv() == 1);
    let mut ctud = Ctud::new(2);
    ctud.call(true, false, false, false);
    check!(ctud.call(false, false, false, false) == (false, false));
    let (mut r, mut f) = (RTrig::new(), FTrig::new());
    // F_TRIG: no pulse on a first call with CLK off (3rd edition); R_TRIG once on the edge.
    check!(!f.call(false) && r.call(true) && !r.call(true) && !f.call(false));
    check!(!f.call(true) && f.call(false));
    let (mut sr, mut rs) = (Sr::new(), Rs::new());
    check!(sr.call(true, true) && !rs.call(true, true));
    Ok(())
}

pub fn timer_queue_across_wheel_levels() -> Outcome {
    let mut q: TimerQueue<u8, 32> = TimerQueue::new();
    // Deadlines on every level of the wheel: 1, 64, 4096, 262144 ticks and between.
    let ticks = [1u32, 63, 64, 65, 4095, 4097, 262_150, 100];
    let mut ids = heapless::Vec::<_, 8>::new();
    for (n, &t) in ticks.iter().enumerate() {
        ids.push(q.insert(t, n as u8).map_err(|_| "full")?)
            .map_err(|_| "vec")?;
    }
    // Replace one, remove one: the stale handle must never touch a newer timer.
    q.replace(ids[7], 2).map_err(|_| "replace")?;
    check!(q.remove(ids[4]) == Some(4));
    check!(q.remove(ids[4]).is_none());
    let mut fired = heapless::Vec::<(u32, u8), 8>::new();
    for now in 1..=262_150u32 {
        q.tick(|a| {
            let _ = fired.push((now, a));
        });
    }
    check!(
        fired.as_slice()
            == [
                (1, 0),
                (2, 7),
                (63, 1),
                (64, 2),
                (65, 3),
                (4097, 5),
                (262_150, 6)
            ]
    );
    check!(q.is_empty());
    Ok(())
}

/// A plant with a fixed input pattern and a clock that moves 1 ms per call.
struct Bench {
    inputs: [u16; 2],
    outputs: [u16; 1],
    t: u32,
}

impl Io<2, 1> for Bench {
    fn read_inputs(&mut self, raw: &mut [u16; 2]) {
        *raw = self.inputs;
    }
    fn write_outputs(&mut self, out: &[u16; 1]) {
        self.outputs = *out;
    }
    fn now_us(&mut self) -> u32 {
        self.t = self.t.wrapping_add(1_000);
        self.t
    }
}

pub fn executive_with_debounce_and_forcing() -> Outcome {
    let mut plant = Bench {
        inputs: [0; 2],
        outputs: [0],
        t: 0,
    };
    let mut plc: Executive<2, 1> = Executive::new(CycleConfig::source());
    plc.conditioning_mut()
        .set_debounce(0, 3)
        .map_err(|_| "debounce")?;
    plc.force_output(5, true).map_err(|_| "force")?;
    plant.inputs = [1, 0];
    let mut seen = [false; 4];
    for s in &mut seen {
        plc.cycle(&mut plant, |scan| {
            let on = scan.inputs.get(0);
            let _ = scan.outputs.set(0, on);
            *s = on;
        })
        .map_err(|_| "cycle")?;
    }
    check!(seen == [false, false, true, true]);
    check!(plant.outputs == [1 | 1 << 5]);
    let mut c: Conditioning<1> = Conditioning::new();
    check!(c.set_debounce(0, 16).is_err());
    Ok(())
}

pub fn signals_trip_inside_a_cycle() -> Outcome {
    // A static, as firmware has it, with the core's real critical section (interrupts masked).
    static SIGNALS: Signals<2, 1> = Signals::new(&CycleConfig::source());
    let mut plant = Bench {
        inputs: [0; 2],
        outputs: [0],
        t: 0,
    };
    let mut plc: Executive<2, 1> = Executive::new(CycleConfig::source());
    plc.conditioning_mut()
        .set_latched(3, true)
        .map_err(|_| "latch")?;
    SIGNALS.capture(&[1 << 3, 0]);
    let mut latched = false;
    plc.cycle_with(&mut plant, &SIGNALS, |s| latched = s.inputs.get(3))
        .map_err(|_| "cycle")?;
    check!(latched);
    let r = plc.cycle_with(&mut plant, &SIGNALS, |s| {
        let _ = SIGNALS.check_watchdog(10_000_000); // the timer interrupt, 10 s later
        let _ = s.outputs.set(0, true);
    });
    check!(r == Err(Halt::Watchdog));
    check!(plant.outputs == [0]);
    SIGNALS.power_fail();
    SIGNALS.resume(Restart::Inhibit);
    check!(SIGNALS.tripped());
    SIGNALS.reset_watchdog();
    let mut previous_safe = false;
    check!(
        plc.cycle_with(&mut plant, &SIGNALS, |s| previous_safe =
            s.previous.words() == &[0])
            .is_ok()
    );
    check!(previous_safe);
    // The power fails while the program runs: nothing of this cycle reaches the outputs (the
    // interrupt's handler writes the safe ones), and after a restart-inhibited resume the
    // program starts from the safe outputs.
    check!(
        plc.cycle_with(&mut plant, &SIGNALS, |s| {
            let _ = s.outputs.set(0, true);
        })
        .is_ok()
    );
    check!(plant.outputs == [1]);
    let r = plc.cycle_with(&mut plant, &SIGNALS, |s| {
        SIGNALS.power_fail(); // the power-fail interrupt
        let _ = s.outputs.set(1, true);
    });
    check!(r == Err(Halt::PowerFail));
    check!(plant.outputs == [1]); // the cycle wrote nothing
    SIGNALS.resume(Restart::Inhibit);
    previous_safe = false;
    check!(
        plc.cycle_with(&mut plant, &SIGNALS, |s| previous_safe =
            s.previous.words() == &[0])
            .is_ok()
    );
    check!(previous_safe && plant.outputs == [0]);
    Ok(())
}

pub fn calendar_and_minute_table() -> Outcome {
    let mut clock = DateTime::new(2026, 11, 23, 5, 59, 30).map_err(|_| "date")?;
    let mut table: MinuteTable<u8, 4> = MinuteTable::new();
    table
        .add(Start {
            hour: 6,
            minute: 0,
            days: Weekdays::WORKDAYS,
            program: 1,
        })
        .map_err(|_| "add")?;
    check!(clock.advance(30_000) == 1);
    check!(table.due(&clock).next() == Some(&1));
    check!(clock.weekday() == 1);
    let mut end = DateTime::new(9999, 12, 31, 23, 59, 59).map_err(|_| "date")?;
    end.advance(5_000);
    check!(end == DateTime::END);
    Ok(())
}

pub fn sizes_on_a_32_bit_core() -> Outcome {
    use core::mem::size_of;
    check!(size_of::<usize>() == 4);
    check!(size_of::<Conditioning<34>>() == 22 * 34);
    // 2 816 bytes of slot heads, 16 bytes of counters, 24 bytes per entry for a one-byte action
    // (the action, a u32 deadline, a u64 generation and links, padded to the u64 alignment).
    check!(size_of::<TimerQueue<u8, 64>>() == 2816 + 16 + 64 * 24);
    Ok(())
}

pub fn step_chain_spool_and_breakpoints() -> Outcome {
    struct Counts {
        seen: u32,
    }
    let mut chain: StepChain<Counts, 2, 1, 4> = StepChain::new();
    chain
        .push(
            |s| s.inputs.get(0),
            |s, c| {
                c.seen += 1;
                let _ = s.outputs.set(2, s.cycle % 10 < 3);
            },
        )
        .map_err(|_| "push")?;
    let mut plant = Bench {
        inputs: [1, 0],
        outputs: [0],
        t: 0,
    };
    let mut plc: Executive<2, 1> = Executive::new(CycleConfig::source());
    let mut counts = Counts { seen: 0 };
    // The monitor: run until output 2 comes on, then cont to its next rising edge.
    let on = [Breakpoint::OutputOn(2)];
    let (n1, why) = plc
        .run(
            &mut plant,
            100,
            &on,
            |s| chain.run(s, &mut counts),
            |_, _| {},
        )
        .map_err(|_| "breakpoints")?;
    check!(why == Some(Halt::Breakpoint(Breakpoint::OutputOn(2))));
    let (n2, _) = plc
        .run(
            &mut plant,
            100,
            &on,
            |s| chain.run(s, &mut counts),
            |_, _| {},
        )
        .map_err(|_| "breakpoints")?;
    check!(n1 == 1 && n2 == 9); // on in cycles 1-2 and 10-12: the next edge is cycle 10
    check!(counts.seen == 10);
    // Level C: jobs in the reserve after a cycle; a full spool hands the job back.
    let mut spool: Spool<u8, 2> = Spool::new();
    check!(spool.push(1).is_ok() && spool.push(2).is_ok() && spool.push(3) == Err(3));
    let mut done = 0u8;
    plc.cycle(&mut plant, |_| {}).map_err(|_| "cycle")?;
    plc.reserve(&mut plant, &mut spool, 0, |j| done += j);
    check!(done == 3 && spool.is_empty());
    Ok(())
}
