//! TimerQueue against a naive list, and the IEC blocks against straightforward references.
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "a test may panic: that is how it fails"
)]

use proptest::prelude::{any, prop, prop_assert_eq, prop_oneof, proptest};
use proptest::strategy::Strategy;
use regler_scan_cycle::{Ctu, TimerId, TimerQueue, Tof, Ton, Tp};

#[derive(Clone, Debug)]
enum Op {
    Insert(u32),
    Replace(usize, u32),
    Remove(usize),
    Tick(u32),
}

fn ticks() -> impl Strategy<Value = u32> {
    prop_oneof![
        0u32..5,
        0u32..100,
        60u32..5000,
        any::<u32>().prop_map(|t| t % 300_000)
    ]
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        3 => ticks().prop_map(Op::Insert),
        1 => (any::<usize>(), ticks()).prop_map(|(i, t)| Op::Replace(i, t)),
        1 => any::<usize>().prop_map(Op::Remove),
        3 => prop_oneof![1u32..3, 1u32..200, 1000u32..6000].prop_map(Op::Tick),
    ]
}

/// The naive register: a list of (deadline, order, action), scanned every tick.
#[derive(Default)]
struct Naive {
    now: u64,
    order: u64,
    entries: Vec<(u64, u64, u32)>,
}

proptest! {
    #[test]
    #[cfg_attr(
        miri,
        ignore = "up to 80 timer operations a case against a list: minutes interpreted; runs natively in every CI run"
    )]
    fn timer_queue_matches_a_naive_list(ops in prop::collection::vec(op(), 1..80)) {
        const N: usize = 16;
        let mut queue: TimerQueue<u32, N> = TimerQueue::new();
        let mut naive = Naive::default();
        let mut handles: Vec<(TimerId, u32)> = Vec::new(); // every handle ever issued, with its action
        let mut next_action = 0u32;
        for op in ops {
            match op {
                Op::Insert(t) => {
                    next_action += 1;
                    let got = queue.insert(t, next_action);
                    if naive.entries.len() == N {
                        prop_assert_eq!(got.unwrap_err().0, next_action);
                    } else {
                        handles.push((got.unwrap(), next_action));
                        naive.order += 1;
                        naive.entries.push((naive.now + u64::from(t.max(1)), naive.order, next_action));
                    }
                }
                Op::Replace(i, t) if !handles.is_empty() => {
                    let (id, action) = handles[i % handles.len()];
                    let waiting = naive.entries.iter().position(|e| e.2 == action);
                    prop_assert_eq!(queue.replace(id, t).is_ok(), waiting.is_some());
                    if let Some(p) = waiting {
                        naive.order += 1;
                        naive.entries[p] = (naive.now + u64::from(t.max(1)), naive.order, action);
                    }
                }
                Op::Remove(i) if !handles.is_empty() => {
                    let (id, action) = handles[i % handles.len()];
                    let waiting = naive.entries.iter().position(|e| e.2 == action);
                    prop_assert_eq!(queue.remove(id), waiting.map(|_| action));
                    if let Some(p) = waiting {
                        naive.entries.remove(p);
                    }
                }
                Op::Tick(k) => {
                    for _ in 0..k {
                        naive.now += 1;
                        let mut due: Vec<(u64, u64, u32)> = naive.entries.iter().copied().filter(|e| e.0 == naive.now).collect();
                        due.sort_by_key(|e| e.1);
                        naive.entries.retain(|e| e.0 != naive.now);
                        let mut got = Vec::new();
                        queue.tick(|a| got.push(a));
                        prop_assert_eq!(got, due.iter().map(|e| e.2).collect::<Vec<_>>());
                    }
                }
                _ => {}
            }
            prop_assert_eq!(queue.len(), naive.entries.len());
            for &(id, action) in &handles {
                let want = naive.entries.iter().find(|e| e.2 == action).map(|e| (e.0 - naive.now) as u32);
                prop_assert_eq!(queue.remaining(id), want);
            }
        }
    }

    /// TON and TOF against their definitions over random input and time steps.
    #[test]
    fn ton_tof_match_their_definitions(
        pt in 0u32..300,
        steps in prop::collection::vec((any::<bool>(), 0u32..120), 1..100),
        start in any::<u32>(),
    ) {
        let (mut ton, mut tof) = (Ton::new(pt), Tof::new(pt));
        let mut now = start;
        let (mut on_since, mut off_since): (Option<u64>, Option<u64>) = (None, None);
        let mut t: u64 = 0;
        let mut ever_on = false;
        for (input, dt) in steps {
            now = now.wrapping_add(dt);
            t += u64::from(dt);
            if input { on_since.get_or_insert(t); off_since = None; ever_on = true; } else { on_since = None; if ever_on { off_since.get_or_insert(t); } }
            let want_ton = on_since.is_some_and(|s| t - s >= u64::from(pt));
            let want_tof = input || off_since.is_some_and(|s| t - s < u64::from(pt));
            prop_assert_eq!(ton.call(input, now), want_ton);
            prop_assert_eq!(tof.call(input, now), want_tof);
            prop_assert_eq!(u64::from(ton.et()), on_since.map_or(0, |s| (t - s).min(u64::from(pt))));
        }
    }

    /// TON, TOF and TP against state machines written from the standard's ST bodies (as matiec
    /// has them), with PT changed at random moments: while timing a change counts, a finished
    /// timer stays finished until its input changes.
    #[test]
    fn timers_with_pt_changes_match_state_machines(
        pt0 in 0u32..300,
        steps in prop::collection::vec((any::<bool>(), 0u32..120, prop::option::weighted(0.2, 0u32..300)), 1..120),
        start in any::<u32>(),
    ) {
        #[derive(Clone, Copy, PartialEq, Debug)]
        enum State { Idle, Timing(u64), Done }
        let (mut ton, mut tof, mut tp) = (Ton::new(pt0), Tof::new(pt0), Tp::new(pt0));
        let (mut s_on, mut s_off, mut s_p) = (State::Idle, State::Idle, State::Idle);
        let (mut pt, mut now, mut t, mut prev_in) = (u64::from(pt0), start, 0u64, false);
        for (input, dt, new_pt) in steps {
            if let Some(p) = new_pt {
                pt = u64::from(p);
                ton.set_pt(p);
                tof.set_pt(p);
                tp.set_pt(p);
            }
            now = now.wrapping_add(dt);
            t += u64::from(dt);
            // TON: IN off resets; IN on times from the call it came on; done stays done.
            s_on = match (input, s_on) {
                (false, _) => State::Idle,
                (true, State::Idle) => if pt == 0 { State::Done } else { State::Timing(t) },
                (true, State::Timing(s)) if t - s >= pt => State::Done,
                (true, other) => other,
            };
            // TOF: IN on sets Q; IN off times from the call it went off; expired stays off.
            s_off = match (input, s_off) {
                (true, _) => State::Done, // Done here means "on"
                (false, State::Done) => if pt == 0 { State::Idle } else { State::Timing(t) },
                (false, State::Timing(s)) if t - s >= pt => State::Idle,
                (false, other) => other,
            };
            // TP: a rising edge outside a pulse starts one; an ended pulse waits for IN off.
            let rising = input && !prev_in;
            prev_in = input;
            s_p = match s_p {
                State::Idle | State::Done if rising => State::Timing(t),
                State::Done if !input => State::Idle,
                other => other,
            };
            if let State::Timing(s) = s_p {
                if t - s >= pt {
                    s_p = if input { State::Done } else { State::Idle };
                }
            }
            prop_assert_eq!(ton.call(input, now), s_on == State::Done, "TON at {}", t);
            prop_assert_eq!(tof.call(input, now), s_off != State::Idle, "TOF at {}", t);
            prop_assert_eq!(tp.call(input, now), matches!(s_p, State::Timing(_)), "TP at {}", t);
        }
    }

    /// CTU counts rising edges.
    #[test]
    fn ctu_counts_rising_edges(inputs in prop::collection::vec((any::<bool>(), prop::bool::weighted(0.05)), 1..200), pv in 0i32..20) {
        let mut ctu = Ctu::new(pv);
        let (mut cv, mut prev) = (0i32, false);
        for (cu, reset) in inputs {
            if reset { cv = 0 } else if cu && !prev { cv += 1 }
            prev = cu;
            prop_assert_eq!(ctu.call(cu, reset), cv >= pv);
            prop_assert_eq!(ctu.cv(), cv);
        }
    }
}

mod images {
    use proptest::prelude::{any, prop, prop_assert_eq, proptest};
    use regler_scan_cycle::{CycleConfig, Executive, Io};

    struct Raw {
        inputs: [u16; 2],
        outputs: [u16; 2],
    }
    impl Io<2, 2> for Raw {
        fn read_inputs(&mut self, raw: &mut [u16; 2]) {
            *raw = self.inputs;
        }
        fn write_outputs(&mut self, out: &[u16; 2]) {
            self.outputs = *out;
        }
        fn now_us(&mut self) -> u32 {
            0
        }
    }

    #[derive(Clone, Debug)]
    enum Op {
        ForceIn(usize, bool),
        UnforceIn(usize),
        ForceOut(usize, bool),
        UnforceOut(usize),
        Cycle([u16; 2], [u16; 2]),
    }

    fn op() -> impl proptest::strategy::Strategy<Value = Op> {
        use proptest::strategy::Strategy;
        proptest::prop_oneof![
            1 => (0usize..40, any::<bool>()).prop_map(|(p, v)| Op::ForceIn(p, v)),
            1 => (0usize..40).prop_map(Op::UnforceIn),
            1 => (0usize..40, any::<bool>()).prop_map(|(p, v)| Op::ForceOut(p, v)),
            1 => (0usize..40).prop_map(Op::UnforceOut),
            3 => (any::<[u16; 2]>(), any::<[u16; 2]>()).prop_map(|(i, o)| Op::Cycle(i, o)),
        ]
    }

    proptest! {
        /// Images and forcing against a model kept point by point: the program sees the raw
        /// inputs with forced points replaced, and the plant gets the program's outputs with
        /// forced points replaced; points outside the images are refused.
        #[test]
        #[cfg_attr(
            miri,
            ignore = "up to 60 image and forcing operations a case against a model: over a minute interpreted; runs natively in every CI run"
        )]
        fn images_and_forcing_match_a_model(ops in prop::collection::vec(op(), 1..60)) {
            let mut plc: Executive<2, 2> = Executive::new(CycleConfig::source());
            let mut io = Raw { inputs: [0; 2], outputs: [0; 2] };
            let (mut fin, mut fout): ([Option<bool>; 32], [Option<bool>; 32]) = ([None; 32], [None; 32]);
            for op in ops {
                match op {
                    Op::ForceIn(p, v) => {
                        prop_assert_eq!(plc.force_input(p, v).is_ok(), p < 32);
                        if p < 32 { fin[p] = Some(v); }
                    }
                    Op::UnforceIn(p) => {
                        prop_assert_eq!(plc.unforce_input(p).is_ok(), p < 32);
                        if p < 32 { fin[p] = None; }
                    }
                    Op::ForceOut(p, v) => {
                        prop_assert_eq!(plc.force_output(p, v).is_ok(), p < 32);
                        if p < 32 { fout[p] = Some(v); }
                    }
                    Op::UnforceOut(p) => {
                        prop_assert_eq!(plc.unforce_output(p).is_ok(), p < 32);
                        if p < 32 { fout[p] = None; }
                    }
                    Op::Cycle(raw, program_out) => {
                        io.inputs = raw;
                        let mut seen = [false; 32];
                        plc.cycle(&mut io, |s| {
                            for (p, b) in seen.iter_mut().enumerate() { *b = s.inputs.get(p); }
                            *s.outputs.words_mut() = program_out;
                        }).unwrap();
                        for p in 0..32 {
                            let raw_bit = raw[p / 16] >> (p % 16) & 1 == 1;
                            prop_assert_eq!(seen[p], fin[p].unwrap_or(raw_bit));
                            let prog_bit = program_out[p / 16] >> (p % 16) & 1 == 1;
                            let written = io.outputs[p / 16] >> (p % 16) & 1 == 1;
                            prop_assert_eq!(written, fout[p].unwrap_or(prog_bit));
                            prop_assert_eq!(plc.forced_outputs().forced(p), fout[p]);
                        }
                    }
                }
            }
        }
    }
}

mod debounce {
    use proptest::prelude::{any, prop, prop_assert_eq, proptest};
    use regler_scan_cycle::{Conditioning, Image};

    /// One input as the documentation describes it, counted with a plain integer.
    #[derive(Clone, Copy, Default)]
    struct Input {
        stable: bool,
        count: u8,
        k: u8,
        latched: bool,
        pending: bool,
    }

    proptest! {
        /// The bit-sliced debounce and latch against a per-input counter model, with counts
        /// changed mid-count and latched pulses captured between cycles.
        #[test]
        #[cfg_attr(
            miri,
            ignore = "a per-input counter model over long input runs: minutes interpreted; runs natively in every CI run"
        )]
        fn conditioning_matches_a_per_input_counter(
            ks in prop::collection::vec(1u8..=15, 32),
            latched in any::<u32>(),
            ops in prop::collection::vec((0u8..10, any::<u32>(), 0usize..32, 1u8..=15), 1..300),
        ) {
            let mut c: Conditioning<2> = Conditioning::new();
            let mut model = [Input::default(); 32];
            for (p, m) in model.iter_mut().enumerate() {
                // Latched points keep count 1; asking for both is refused.
                m.latched = latched >> p & 1 == 1;
                m.k = if m.latched { 1 } else { ks[p] };
                c.set_debounce(p, ks[p]).unwrap();
                let refused = c.set_latched(p, m.latched).is_err();
                prop_assert_eq!(refused, m.latched && ks[p] != 1);
                if refused {
                    c.set_debounce(p, 1).unwrap();
                    c.set_latched(p, true).unwrap();
                }
            }
            for (op, bits, point, k) in ops {
                let raw = [bits as u16, (bits >> 16) as u16];
                match op {
                    0 => {
                        let refused = c.set_debounce(point, k).is_err();
                        prop_assert_eq!(refused, model[point].latched && k != 1);
                        if !refused {
                            model[point].k = k;
                        }
                    }
                    1 => {
                        c.capture(&raw);
                        for (p, m) in model.iter_mut().enumerate() {
                            m.pending |= m.latched && bits >> p & 1 == 1;
                        }
                    }
                    _ => {
                        let mut out: Image<2> = Image::new();
                        c.condition(&raw, &mut out);
                        for (p, m) in model.iter_mut().enumerate() {
                            let reading = bits >> p & 1 == 1 || m.pending;
                            m.pending = false;
                            if reading == m.stable {
                                m.count = 0;
                            } else {
                                m.count += 1;
                                if m.count >= m.k {
                                    m.stable = reading;
                                    m.count = 0;
                                }
                            }
                            prop_assert_eq!(out.get(p), m.stable, "point {}", p);
                        }
                    }
                }
            }
        }
    }
}
