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
    DistanceTable, EnterError, HeldTipper, InFlight, Snapshot, TipperEvent, Tracker, correct,
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
        for e in &mut self.entries {
            e.2 = correct(e.2, dia, old).unwrap().max(ahead[e.1]);
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
    Recalibrate(u32),
    PowerFailure,
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        4 => (0..T + 1).prop_map(Op::Enter),
        4 => (1u32..40).prop_map(Op::Pulses),
        1 => (950u32..1050).prop_map(Op::Recalibrate),
        1 => prop::strategy::Just(Op::PowerFailure),
    ]
}

proptest! {
    #[test]
    fn tracker_matches_count_down(
        sa in prop::collection::vec(0u32..60, T - 1..=T),
        ops in prop::collection::vec(op(), 1..120),
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
