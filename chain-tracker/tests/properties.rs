//! The tracker against the source's method: one list of trolleys, every entry counted down on
//! every pulse.
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "a test may panic: that is how it fails"
)]

use proptest::prelude::{any, prop, prop_assert, prop_assert_eq, prop_oneof, proptest};
use proptest::strategy::Strategy;
use regler_chain_tracker::{
    DistanceTable, EnterError, HeldTipper, InFlight, Measurement, Snapshot, StretchConfig,
    StretchMeter, TipperEvent, Tracker, correct,
};

const N: usize = 12;
const T: usize = 4;
const SIA: u32 = 1000;
const HOLD: u32 = 3;

/// The count-down shift register, with the tracker's documented rules spelled out naively.
struct CountDown {
    sa: Vec<u32>,
    dia: u32,
    entries: Vec<(u16, usize, u32)>, // trolley, tipper, remaining; in order of entry
    held: Vec<u32>,                  // per tipper: pulses until reset, 0 = not set
}

impl CountDown {
    fn distance(&self, tipper: usize) -> u32 {
        correct(self.sa[tipper], self.dia, SIA).unwrap()
    }

    fn enter(&mut self, trolley: u16, tipper: usize) -> Result<(), EnterError<u16>> {
        if tipper >= self.sa.len() {
            return Err(EnterError::UnknownTipper { trolley, tipper });
        }
        if self.entries.len() == N {
            return Err(EnterError::Full(trolley));
        }
        let ahead = self
            .entries
            .iter()
            .filter(|e| e.1 == tipper)
            .map(|e| e.2)
            .max()
            .unwrap_or(0);
        self.entries
            .push((trolley, tipper, self.distance(tipper).max(1).max(ahead)));
        Ok(())
    }

    fn pulse(&mut self) -> Vec<TipperEvent<u16>> {
        let mut sets = Vec::new();
        for e in &mut self.entries {
            e.2 -= 1;
            if e.2 == 0 {
                sets.push(TipperEvent::Set {
                    tipper: e.1,
                    trolley: e.0,
                });
            }
        }
        self.entries.retain(|e| e.2 > 0);
        // The tracker reports sets tipper by tipper, each tipper's in entry order.
        sets.sort_by_key(|e| match e {
            TipperEvent::Set { tipper, .. } => *tipper,
            TipperEvent::Reset { .. } => usize::MAX,
        });
        let mut events = sets.clone();
        for (tipper, held) in self.held.iter_mut().enumerate() {
            let set_now = sets
                .iter()
                .any(|e| matches!(e, TipperEvent::Set { tipper: t, .. } if *t == tipper));
            if set_now {
                *held = HOLD;
            } else if *held > 0 {
                *held -= 1;
                if *held == 0 {
                    events.push(TipperEvent::Reset { tipper });
                }
            }
        }
        events
    }

    fn recalibrate(&mut self, dia: u32) {
        let old = self.dia;
        self.dia = dia;
        let mut ahead = vec![1u32; self.sa.len()];
        let distance: Vec<u32> = (0..self.sa.len())
            .map(|t| self.distance(t).max(1))
            .collect();
        for e in &mut self.entries {
            // Rescaled, but never further than the tipper is from the reader, nor ahead of the
            // trolley before it.
            e.2 = correct(e.2, dia, old)
                .unwrap()
                .min(distance[e.1])
                .max(ahead[e.1]);
            ahead[e.1] = e.2;
        }
    }

    fn in_flight(&self) -> Vec<InFlight<u16>> {
        let mut list: Vec<InFlight<u16>> = self
            .entries
            .iter()
            .map(|&(trolley, tipper, remaining)| InFlight {
                trolley,
                tipper,
                remaining,
            })
            .collect();
        list.sort_by_key(|f| f.tipper); // stable: entry order within a tipper
        list
    }
}

#[derive(Clone, Debug)]
enum Op {
    Enter(usize),
    Pulses(u32),
    /// `Tracker::advance` by this many pulses, against as many model pulses.
    Advance(u32),
    Recalibrate(u32),
    PowerFailure,
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        4 => (0..T + 1).prop_map(Op::Enter),
        4 => (1u32..40).prop_map(Op::Pulses),
        2 => (0u32..80).prop_map(Op::Advance),
        1 => (950u32..1050).prop_map(Op::Recalibrate),
        1 => prop::strategy::Just(Op::PowerFailure),
    ]
}

proptest! {
    #[test]
    fn tracker_matches_count_down(
        sa in prop::collection::vec(0u32..60, T - 1..=T),
        ops in prop::collection::vec(op(), 1..if cfg!(miri) { 20 } else { 120 }),
        start in prop_oneof![prop::strategy::Just(0u32), any::<u32>(), prop::strategy::Just(u32::MAX - 50)],
    ) {
        let table: DistanceTable<T> = DistanceTable::new(SIA, &sa).unwrap();
        let mut tracker: Tracker<u16, N, T> = Tracker::new(table, HOLD).unwrap();
        tracker.set_now(start);
        let mut model = CountDown { sa: sa.clone(), dia: SIA, entries: Vec::new(), held: vec![0; sa.len()] };
        let mut next_trolley = 0u16;
        for op in ops {
            match op {
                Op::Enter(tipper) => {
                    next_trolley += 1;
                    prop_assert_eq!(tracker.enter(next_trolley, tipper), model.enter(next_trolley, tipper));
                }
                Op::Pulses(k) => {
                    for _ in 0..k {
                        let mut got = Vec::new();
                        tracker.pulse(|e| got.push(e));
                        prop_assert_eq!(got, model.pulse());
                    }
                }
                Op::Advance(k) => {
                    let mut got = Vec::new();
                    tracker.advance(k, |e| got.push(e));
                    let want: Vec<_> = (0..k).flat_map(|_| model.pulse()).collect();
                    prop_assert_eq!(got, want);
                }
                Op::Recalibrate(dia) => {
                    let changed = tracker.recalibrate(dia).unwrap();
                    prop_assert_eq!(changed, dia != model.dia);
                    model.recalibrate(dia);
                }
                Op::PowerFailure => {
                    let snapshot = tracker.snapshot();
                    let mut fresh: Tracker<u16, N, T> = Tracker::new(table, HOLD).unwrap();
                    fresh.restore(&snapshot).unwrap();
                    prop_assert_eq!(fresh.snapshot(), snapshot);
                    tracker = fresh;
                }
            }
            prop_assert_eq!(tracker.in_flight().collect::<Vec<_>>(), model.in_flight());
            prop_assert_eq!(tracker.len(), model.entries.len());
            for tipper in 0..sa.len() {
                prop_assert_eq!(tracker.is_set(tipper), model.held[tipper] > 0);
            }
        }
    }

    /// DA = SA·DIA/SIA against exact 128-bit arithmetic for every u32 input.
    #[test]
    fn correct_is_exact(sa in any::<u32>(), dia in any::<u32>(), sia in any::<u32>()) {
        let want = if sia == 0 {
            None
        } else {
            let (a, b, c) = (u128::from(sa), u128::from(dia), u128::from(sia));
            u32::try_from((2 * a * b + c) / (2 * c)).ok()
        };
        prop_assert_eq!(correct(sa, dia, sia).ok(), want);
    }

    /// A recalibration that overflows leaves the tracker as it was.
    #[test]
    fn refused_recalibration_is_atomic(far in (1u32 << 31)..u32::MAX, dia in 2u32..10) {
        let table: DistanceTable<T> = DistanceTable::new(1, &[1, far]).unwrap();
        let mut tracker: Tracker<u16, N, T> = Tracker::new(table, HOLD).unwrap();
        tracker.enter(1, 0).unwrap();
        tracker.enter(2, 1).unwrap();
        let before = tracker.snapshot();
        prop_assert!(tracker.recalibrate(dia).is_err());
        prop_assert_eq!(tracker.snapshot(), before);
    }
}

proptest! {
    /// Any stored snapshot — corrupt, or from a firmware with another configuration — is refused
    /// (changing nothing) or gives a tracker that keeps its promises: no tipper stays set longer
    /// than the hold after its last arrival, and every trolley arrives. (The fuzz target
    /// `restore` tries the same over arbitrary bytes.)
    #[test]
    fn any_snapshot_is_refused_or_safe(
        now in any::<u32>(),
        dia in prop_oneof![990u32..1010, any::<u32>()],
        in_flight in prop::collection::vec((0usize..6, 0u32..400), 0..=N),
        held in prop::collection::vec((0usize..6, 0u32..10), 0..=T),
        pulses in 0u32..500,
    ) {
        let table = DistanceTable::<T>::new(SIA, &[5, 40, 120, 250]).unwrap();
        let mut tracker = Tracker::<u16, N, T>::new(table, HOLD).unwrap();
        let mut snapshot: Snapshot<u16, N, T> = Snapshot { now, dia, in_flight: heapless::Vec::new(), held: heapless::Vec::new() };
        for (k, (tipper, remaining)) in in_flight.into_iter().enumerate() {
            snapshot.in_flight.push(InFlight { trolley: k as u16, tipper, remaining }).unwrap();
        }
        for (tipper, remaining) in held {
            snapshot.held.push(HeldTipper { tipper, remaining }).unwrap();
        }
        let before = tracker.snapshot();
        if tracker.restore(&snapshot).is_err() {
            prop_assert_eq!(tracker.snapshot(), before);
            return Ok(());
        }
        let mut since = [None::<u32>; T];
        for h in &snapshot.held {
            since[h.tipper] = Some(HOLD - h.remaining);
        }
        // Distances at an absurd DIA can be 10^9 pulses: pulse on long enough to see every
        // restored trolley arrive and every hold end, but not for ever.
        let farthest = tracker.table().distances().iter().copied().max().unwrap().min(2000);
        for _ in 0..farthest + HOLD + 3 + pulses {
            let mut arrived = Vec::new();
            tracker.pulse(|e| if let TipperEvent::Set { tipper, .. } = e { arrived.push(tipper) });
            for s in since.iter_mut().flatten() {
                *s += 1;
            }
            for tipper in arrived {
                since[tipper] = Some(0);
            }
            for (tipper, since) in since.iter().enumerate() {
                if tracker.is_set(tipper) {
                    let s = since.unwrap_or(u32::MAX);
                    prop_assert!(s < HOLD, "tipper {} set {} pulses after its last arrival", tipper, s);
                }
            }
        }
        if farthest < 2000 {
            prop_assert!(tracker.is_empty());
            prop_assert!((0..T).all(|t| !tracker.is_set(t)));
        }
    }
}

#[derive(Clone, Debug)]
enum Step {
    Enter(usize),
    Pulses(u32),
    Advance(u32),
    /// A recalibration by a small step from the DIA in force (the stretch meter's usual
    /// output), or a large one.
    Recalibrate(i32),
    SetNow(u32),
    PowerFailure,
}

fn step() -> impl Strategy<Value = Step> {
    prop_oneof![
        4 => (0..T).prop_map(Step::Enter),
        3 => (1u32..30).prop_map(Step::Pulses),
        2 => (0u32..80).prop_map(Step::Advance),
        3 => (-12i32..=12).prop_map(Step::Recalibrate),
        1 => (-200i32..=200).prop_map(Step::Recalibrate),
        1 => any::<u32>().prop_map(Step::SetNow),
        1 => prop::strategy::Just(Step::PowerFailure),
    ]
}

type Events = Vec<TipperEvent<u16>>;

fn apply(t: &mut Tracker<u16, N, T>, step: &Step, trolley: u16) -> (Events, String) {
    let mut events = Vec::new();
    let result = match *step {
        Step::Enter(tipper) => format!("{:?}", t.enter(trolley, tipper)),
        Step::Pulses(k) => {
            for _ in 0..k {
                t.pulse(|e| events.push(e));
            }
            String::new()
        }
        Step::Advance(k) => {
            t.advance(k, |e| events.push(e));
            String::new()
        }
        Step::Recalibrate(delta) => {
            let dia = t.table().dia().saturating_add_signed(delta).max(1);
            format!("{:?}", t.recalibrate(dia))
        }
        Step::SetNow(now) => {
            t.set_now(now);
            String::new()
        }
        Step::PowerFailure => String::new(),
    };
    (events, result)
}

proptest! {
    /// Every snapshot a tracker takes, at any moment of any sequence of arrivals, pulses,
    /// advances, recalibrations (small steps that round the same way many times, and large
    /// ones) and counter changes, restores; and the restored tracker then behaves exactly like
    /// the original (same events, same results, same snapshots) for the rest of the sequence.
    #[test]
    fn every_snapshot_restores_and_the_restored_tracker_behaves_the_same(
        sa in prop::collection::vec(0u32..80, T),
        sia in prop_oneof![prop::strategy::Just(SIA), 20u32..5000],
        steps in prop::collection::vec(step(), 1..if cfg!(miri) { 20 } else { 150 }),
    ) {
        let table: DistanceTable<T> = DistanceTable::new(sia, &sa).unwrap();
        let mut tracker: Tracker<u16, N, T> = Tracker::new(table, HOLD).unwrap();
        let mut restored: Option<Tracker<u16, N, T>> = None;
        for (i, step) in steps.iter().enumerate() {
            let trolley = i as u16;
            let want = apply(&mut tracker, step, trolley);
            if let Some(r) = restored.as_mut() {
                prop_assert_eq!(apply(r, step, trolley), want.clone(), "step {} {:?}", i, step);
                prop_assert_eq!(r.snapshot(), tracker.snapshot());
            }
            let snapshot = tracker.snapshot();
            let mut fresh: Tracker<u16, N, T> = Tracker::new(table, HOLD).unwrap();
            let restore = fresh.restore(&snapshot);
            prop_assert!(restore.is_ok(), "step {} {:?}: own snapshot refused: {:?}", i, step, restore);
            prop_assert_eq!(fresh.snapshot(), snapshot);
            if matches!(step, Step::PowerFailure) {
                restored = Some(fresh);
            }
        }
    }
}

/// Events of `pulses` pulses one by one, after the last event skipped with `set_now` (a cheap
/// stand-in for pulses on which nothing happens, checked by `advance_is_pulses` above).
fn pulses_then_quiet(t: &mut Tracker<u16, N, T>, pulses: u32) -> Vec<(u32, TipperEvent<u16>)> {
    let mut events = Vec::new();
    let mut done = 0u32;
    while done < pulses && !(t.is_empty() && (0..T).all(|k| !t.is_set(k))) {
        done += 1;
        t.pulse(|e| events.push((done, e)));
    }
    let now = t.now();
    t.set_now(now.wrapping_add(pulses - done));
    events
}

/// The longest short advance: the reference runs it pulse by pulse (500 under Miri, which
/// interprets each pulse; Miri also draws at most 20 operations or steps below, not 120 or 150:
/// every snapshot is restored and replayed).
const SHORT: u32 = if cfg!(miri) { 500 } else { 5000 };

proptest! {
    /// `advance(k)` is k pulses for any k up to u32::MAX (a wrapped hardware counter), and it
    /// costs what its arrivals and resets cost: about a third of the cases advance a full chain
    /// by u32::MAX (pulse by pulse one such call took ~9 s optimised, so this test would not
    /// finish; no clock is read, the bound is the test run's own time limit).
    #[test]
    fn a_huge_advance_is_its_pulses_at_the_cost_of_its_arrivals(
        sa in prop::collection::vec(0u32..3000, T),
        entries in prop::collection::vec((0..T, 0u32..50), 1..=N),
        start in any::<u32>(),
        pulses in prop_oneof![prop::strategy::Just(u32::MAX), (u32::MAX - SHORT)..=u32::MAX, 0u32..SHORT],
    ) {
        let table: DistanceTable<T> = DistanceTable::new(SIA, &sa).unwrap();
        let mut a: Tracker<u16, N, T> = Tracker::new(table, HOLD).unwrap();
        a.set_now(start);
        for (k, &(tipper, gap)) in entries.iter().enumerate() {
            a.enter(k as u16, tipper).unwrap();
            a.advance(gap, |_| {});
        }
        let mut b = a.clone();
        let mut got = Vec::new();
        let from = a.now();
        a.advance(pulses, |e| got.push(e));
        let want: Vec<_> = pulses_then_quiet(&mut b, pulses).into_iter().map(|(_, e)| e).collect();
        prop_assert_eq!(got, want);
        prop_assert_eq!(a.now(), from.wrapping_add(pulses));
        prop_assert_eq!(a.snapshot(), b.snapshot());
    }
}

/// Whether `dia` lies in the range the docs call plausible: between the accepted DIA and SIA,
/// or beyond either end by at most `per_mille` of that end (computed in real numbers).
fn plausible(accepted: u32, sia: u32, per_mille: u32, dia: u32) -> bool {
    let (lo, hi) = (f64::from(accepted.min(sia)), f64::from(accepted.max(sia)));
    let p = f64::from(per_mille) / 1000.0;
    let d = f64::from(dia);
    dia != 0 && d >= lo - lo * p && d <= hi + hi * p
}

proptest! {
    /// Every measurement in the documented range is followed after `confirmations` equal
    /// measurements — a chain stretched further, or shortened or replaced anywhere back towards
    /// (and a little past) SIA — and every one outside it is `Implausible` and changes nothing.
    #[test]
    fn the_meter_follows_every_plausible_chain_and_only_those(
        sia in 1u32..100_000,
        accepted_per_mille in 500u32..1500,
        per_mille in 0u32..300,
        confirmations in 1u8..4,
        dia_per_mille in 0u32..2000,
    ) {
        let accepted = (u64::from(sia) * u64::from(accepted_per_mille) / 1000).max(1) as u32;
        let dia = (u64::from(sia) * u64::from(dia_per_mille) / 1000) as u32;
        let mut config = StretchConfig::new(sia);
        config.confirmations = confirmations;
        config.plausible_per_mille = per_mille;
        let mut meter = StretchMeter::with_dia(config, accepted).unwrap();
        let mut last = None;
        for _ in 0..confirmations {
            last = Some(meter.measure(dia));
        }
        let want = if !plausible(accepted, sia, per_mille, dia) {
            Measurement::Implausible { dia }
        } else if dia == accepted {
            Measurement::Unchanged
        } else {
            Measurement::Accepted { dia }
        };
        prop_assert_eq!(last, Some(want));
        let expected = if matches!(want, Measurement::Implausible { .. }) { accepted } else { dia };
        prop_assert_eq!(meter.dia(), expected);
    }

    /// Power fails at any moment of a life of stretch measurements and recalibrations, with the
    /// meter and the tracker stored at different moments (the meter after an `Accepted`, the
    /// tracker before its `recalibrate`, or the other way round). After the documented start-up
    /// — restore the tracker, `reconcile` the meter with its table — at most `confirmations`
    /// measurements of the chain later, table and meter both hold the chain's true DIA.
    #[test]
    fn after_start_up_meter_and_table_agree_with_the_chain(
        stretch_steps in prop::collection::vec(0u32..8, 1..40),
        fail_at in any::<prop::sample::Index>(),
        // 0: meter stored, tracker not; 1: both; 2: tracker stored, meter not.
        stored in 0u8..3,
        confirmations in 1u8..4,
    ) {
        let mut config = StretchConfig::new(3000);
        config.confirmations = confirmations;
        let table: DistanceTable<T> = DistanceTable::new(3000, &[100, 900, 2000, 2900]).unwrap();
        let mut tracker: Tracker<u16, N, T> = Tracker::new(table, HOLD).unwrap();
        let mut meter = StretchMeter::new(config).unwrap();
        // Each action: measure the chain once; on Accepted, recalibrate. Stores happen after
        // every action; power fails after action `fail`, possibly between a meter store and a
        // tracker store.
        let mut chain = 3000u32;
        let mut actions = Vec::new();
        for s in &stretch_steps {
            chain -= s;
            for _ in 0..confirmations {
                actions.push(chain);
            }
        }
        let fail = fail_at.index(actions.len());
        let (mut stored_meter, mut stored_tracker) = (meter.clone(), tracker.snapshot());
        for (i, &measured) in actions.iter().enumerate() {
            let accepted = meter.measure(measured);
            if i != fail || stored != 2 {
                stored_meter = meter.clone();
            }
            if i == fail && stored == 0 {
                break; // power fails after the meter was stored, before recalibrate
            }
            if let Measurement::Accepted { dia } = accepted {
                tracker.recalibrate(dia).unwrap();
            }
            stored_tracker = tracker.snapshot();
            if i == fail {
                break;
            }
        }
        let true_dia = actions[fail];
        // Start-up.
        let mut tracker: Tracker<u16, N, T> = Tracker::new(table, HOLD).unwrap();
        tracker.restore(&stored_tracker).unwrap();
        let mut meter = stored_meter;
        meter.reconcile(tracker.table().dia()).unwrap();
        for _ in 0..confirmations {
            if let Measurement::Accepted { dia } = meter.measure(true_dia) {
                tracker.recalibrate(dia).unwrap();
            }
        }
        prop_assert_eq!(tracker.table().dia(), true_dia);
        prop_assert_eq!(meter.dia(), true_dia);
        prop_assert_eq!(meter.measure(true_dia), Measurement::Unchanged);
    }
}
