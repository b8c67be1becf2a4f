//! Bad inputs (issue 22 §5): every public constructor and operation of `regler-chain-tracker`
//! fed the extremes — distances, SIA and DIA of 0, 1 and `u32::MAX`, tables and trackers of
//! capacity 1 and 2 (full and empty), tippers at `T` and `usize::MAX`, holds of 0, 1 and MAX, the
//! pulse counter at and across its wrap, `advance(u32::MAX)`, corrupt snapshots with every field
//! at its extremes, stretch-meter settings of 0 and MAX — with the exact error or documented
//! result. A refused call is checked to have changed nothing.
#![allow(
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    clippy::type_complexity,
    reason = "a test may panic: that is how it fails"
)]

use regler_chain_tracker::{
    CorrectionError, DistanceTable, EnterError, HeldTipper, InFlight, Measurement, RESTORE_SLACK,
    Snapshot, StretchConfig, StretchConfigError, StretchMeter, TableError, TipperEvent, Tracker,
    TrackerError, correct,
};

const M: u32 = u32::MAX;

/// `correct(sa, dia, sia)` at 0, 1 and MAX of each argument: exact, rounded half up, or the
/// error.
#[test]
#[rustfmt::skip]
fn correct_at_the_extremes() {
    let rows: [(u32, u32, u32, Result<u32, CorrectionError>); 12] = [
        (0, 0, 1, Ok(0)),
        (1, 1, 2, Ok(1)),
        (1, 1, 3, Ok(0)),
        (M, 1, M, Ok(1)),
        (M, M, M, Ok(M)),
        (M, 0, 1, Ok(0)),
        (0, M, 1, Ok(0)),
        (M, 2, 1, Err(CorrectionError::Overflow { sa: M, dia: 2, sia: 1 })),
        (M, M, 1, Err(CorrectionError::Overflow { sa: M, dia: M, sia: 1 })),
        (5, 1, 0, Err(CorrectionError::ZeroReference)),
        (M, M, 0, Err(CorrectionError::ZeroReference)),
        (M - 1, M, M - 1, Ok(M)),
    ];
    for (sa, dia, sia, want) in rows {
        assert_eq!(correct(sa, dia, sia), want, "correct({sa}, {dia}, {sia})");
    }
}

/// Distance tables of capacity 1 and 2: empty, full, one too many; SIA 0; recalibration to 0,
/// 1, MAX and overflowing; tippers past the end. A refused call changes nothing.
#[test]
#[rustfmt::skip]
fn distance_tables_at_the_extremes() {
    // DistanceTable<2>::new: (sia, sa, result: number of tippers or the error)
    let rows: [(u32, &[u32], Result<usize, TableError>); 7] = [
        (1000, &[], Ok(0)),
        (1000, &[5], Ok(1)),
        (1000, &[0, M], Ok(2)),
        (1000, &[1, 2, 3], Err(TableError::TooManyTippers { given: 3, capacity: 2 })),
        (0, &[5], Err(TableError::ZeroReference)),
        (M, &[M, M], Ok(2)),
        (1, &[M], Ok(1)),
    ];
    for (sia, sa, want) in rows {
        assert_eq!(DistanceTable::<2>::new(sia, sa).map(|t| t.tippers()), want, "new({sia}, {sa:?})");
    }
    assert_eq!(DistanceTable::<1>::new(10, &[1, 2]).map(|t| t.tippers()), Err(TableError::TooManyTippers { given: 2, capacity: 1 }));
    // recalibrate: (sia, sa, dia, result, distances after)
    let rows: [(u32, &[u32], u32, Result<bool, TableError>, Vec<u32>); 8] = [
        (1000, &[100, 2000], 1000, Ok(false), vec![100, 2000]),
        (1000, &[100, 2000], 0, Err(TableError::ZeroMeasurement), vec![100, 2000]),
        (1000, &[100, 2000], 1, Ok(true), vec![0, 2]),
        (1000, &[100, 2000], M, Err(TableError::Overflow { tipper: 1 }), vec![100, 2000]),
        (1000, &[100, 1], 2_147_483, Ok(true), vec![214_748, 2_147]),
        (M, &[M, 0], 1, Ok(true), vec![1, 0]),
        (1, &[], M, Ok(true), vec![]),
        (1, &[0], M, Ok(true), vec![0]),
    ];
    for (sia, sa, dia, want, after) in rows {
        let mut t = DistanceTable::<2>::new(sia, sa).unwrap();
        let before = t;
        let r = t.recalibrate(dia);
        assert_eq!(r, want, "sia {sia}, sa {sa:?}: recalibrate({dia})");
        if r.is_err() {
            assert_eq!(t, before, "a refused recalibrate changed the table");
        }
        assert_eq!(t.distances(), &after[..], "sia {sia}, sa {sa:?}, dia {dia}");
    }
    let t = DistanceTable::<2>::new(1000, &[100]).unwrap();
    for tipper in [1, 2, usize::MAX] {
        assert_eq!((t.distance(tipper), t.static_distance(tipper)), (None, None), "tipper {tipper}");
    }
    // stretch_per_mille, (SIA − DIA)·1000/DIA rounded half away from zero, saturating: (sia, dia, per mille)
    for (sia, dia, per_mille) in [(1000, 1000, 0), (1000, 990, 10), (1000, 1010, -10), (M, 1, i32::MAX), (1, M, -1000), (1, 1, 0)] {
        let mut t = DistanceTable::<1>::new(sia, &[]).unwrap();
        t.recalibrate(dia).unwrap();
        assert_eq!(t.stretch_per_mille(), per_mille, "sia {sia}, dia {dia}");
    }
}

fn tracker<const N: usize>(sa: &[u32], hold: u32) -> Tracker<u16, N, 2> {
    Tracker::new(DistanceTable::new(1000, sa).unwrap(), hold).unwrap()
}

/// Trackers of capacity 1 and 2: hold 0, 1 and MAX; full; tippers past the end; a distance of
/// 0; `advance(0)` and `advance(u32::MAX)`; the pulse counter across its wrap.
#[test]
#[rustfmt::skip]
fn trackers_at_the_extremes() {
    let table = DistanceTable::<2>::new(1000, &[0, 3]).unwrap();
    assert_eq!(Tracker::<u16, 1, 2>::new(table, 0).map(|_| ()).unwrap_err(), TrackerError::ZeroHold);
    assert!(Tracker::<u16, 1, 2>::new(table, M).is_ok());
    // enter: (capacity 1) (trolley, tipper, result)
    let mut one = tracker::<1>(&[0, 3], 1);
    let rows: [(u16, usize, Result<(), EnterError<u16>>); 5] = [
        (1, 2, Err(EnterError::UnknownTipper { trolley: 1, tipper: 2 })),
        (2, usize::MAX, Err(EnterError::UnknownTipper { trolley: 2, tipper: usize::MAX })),
        (3, 1, Ok(())),
        (4, 1, Err(EnterError::Full(4))),
        (5, 0, Err(EnterError::Full(5))),
    ];
    for (trolley, tipper, want) in rows {
        let before = one.snapshot();
        let r = one.enter(trolley, tipper);
        assert_eq!(r, want, "enter({trolley}, {tipper})");
        if let Err(e) = r {
            assert_eq!(one.snapshot(), before, "a refused enter changed the tracker");
            assert_eq!(e.into_trolley(), trolley, "the trolley is handed back");
        }
    }
    assert_eq!((one.len(), one.capacity(), one.is_empty()), (1, 1, false));
    // A distance of 0 counts as 1; hold 1 resets one pulse later.
    let mut t = tracker::<2>(&[0, 3], 1);
    t.enter(7, 0).unwrap();
    // (pulse, event)
    let mut got = Vec::new();
    for pulse in 1..=3 {
        t.pulse(|e| got.push((pulse, e)));
    }
    assert_eq!(got, [(1, TipperEvent::Set { tipper: 0, trolley: 7 }), (2, TipperEvent::Reset { tipper: 0 })]);
    assert!(!t.is_set(0) && !t.is_set(2) && !t.is_set(usize::MAX));
    // advance(0) does nothing; advance(u32::MAX) on an empty chain wraps the counter, quietly.
    let mut t = tracker::<2>(&[0, 3], 6);
    let mut n = 0;
    t.advance(0, |_| n += 1);
    assert_eq!((t.now(), n), (0, 0));
    t.advance(M, |_| n += 1);
    assert_eq!((t.now(), n), (M, 0));
    // Across the wrap: a trolley entered at MAX - 1 for tipper 1 (3 pulses) sets at 1, resets at 7.
    let mut t = tracker::<2>(&[0, 3], 6);
    t.set_now(M - 1);
    t.enter(9, 1).unwrap();
    // (pulse counter after the pulse, event)
    let mut at = Vec::new();
    for _ in 0..10 {
        let mut here = Vec::new();
        t.pulse(|e| here.push(e));
        at.extend(here.into_iter().map(|e| (t.now(), e)));
    }
    assert_eq!(at, [(1, TipperEvent::Set { tipper: 1, trolley: 9 }), (7, TipperEvent::Reset { tipper: 1 })]);
    // advance(u32::MAX) with a trolley on the chain: it arrives and is reset, each once.
    let mut t = tracker::<2>(&[0, 3], 6);
    t.enter(9, 1).unwrap();
    let mut seen = Vec::new();
    t.advance(M, |e| seen.push(e));
    assert_eq!(seen, [TipperEvent::Set { tipper: 1, trolley: 9 }, TipperEvent::Reset { tipper: 1 }]);
    assert!(t.is_empty());
    // Hold MAX: a tipper set stays set across a full wrap of the counter but one pulse.
    let mut t = tracker::<1>(&[0, 3], M);
    t.enter(1, 0).unwrap();
    let mut seen = Vec::new();
    t.advance(M, |e| seen.push(e));
    assert_eq!(seen, [TipperEvent::Set { tipper: 0, trolley: 1 }]);
    assert!(t.is_set(0));
    t.advance(1, |e| seen.push(e));
    assert_eq!(seen.last(), Some(&TipperEvent::Reset { tipper: 0 }));
}

/// `Tracker::recalibrate` to 0, to an overflowing DIA, to MAX with trolleys on the chain: the
/// error, and nothing changed.
#[test]
#[rustfmt::skip]
fn tracker_recalibration_at_the_extremes() {
    let mut t = tracker::<2>(&[100, 2000], 6);
    t.enter(1, 1).unwrap();
    t.advance(10, |_| {});
    // (dia, result)
    let rows: [(u32, Result<bool, TrackerError>); 4] = [
        (0, Err(TrackerError::Table(TableError::ZeroMeasurement))),
        (M, Err(TrackerError::Table(TableError::Overflow { tipper: 1 }))),
        (1000, Ok(false)),
        (1, Ok(true)),
    ];
    for (dia, want) in rows {
        let mut u = t.clone();
        let before = u.snapshot();
        let r = u.recalibrate(dia);
        assert_eq!(r, want, "recalibrate({dia})");
        if r.is_err() {
            assert_eq!(u.snapshot(), before, "a refused recalibrate changed the tracker");
        }
    }
    // Rescaled to DIA 1 the trolley is at most its tipper's new distance (2), at least 1.
    let mut u = t.clone();
    u.recalibrate(1).unwrap();
    let f: Vec<InFlight<u16>> = u.in_flight().collect();
    assert_eq!(f.len(), 1);
    assert!((1..=2).contains(&f[0].remaining), "{f:?}");
}

/// Corrupt snapshots: every field at its extremes, each refused with the exact error and
/// nothing changed, or restored as a tracker that runs.
#[test]
#[rustfmt::skip]
fn corrupt_snapshots_at_the_extremes() {
    let mut base = tracker::<2>(&[100, 2000], 6);
    base.enter(1, 1).unwrap();
    base.enter(2, 0).unwrap();
    base.advance(95, |_| {});
    let good = base.snapshot();
    let fly = |tipper, remaining| InFlight { trolley: 3u16, tipper, remaining };
    let held = |tipper, remaining| HeldTipper { tipper, remaining };
    let snap = |now: u32, dia: u32, f: &[InFlight<u16>], h: &[HeldTipper]| {
        let mut s: Snapshot<u16, 2, 2> = Snapshot::new();
        s.now = now;
        s.dia = dia;
        for x in f { s.in_flight.push(*x).unwrap(); }
        for x in h { s.held.push(*x).unwrap(); }
        s
    };
    use TrackerError as E;
    // (what, snapshot, result)
    let rows: Vec<(&str, Snapshot<u16, 2, 2>, Result<(), TrackerError>)> = vec![
        ("its own", good.clone(), Ok(())),
        ("empty, now MAX", snap(M, 1000, &[], &[]), Ok(())),
        ("dia 0", snap(0, 0, &[], &[]), Err(E::Table(TableError::ZeroMeasurement))),
        ("dia MAX", snap(0, M, &[], &[]), Err(E::Table(TableError::Overflow { tipper: 1 }))),
        ("dia 1", snap(0, 1, &[fly(1, 2)], &[]), Ok(())),
        ("tipper 2", snap(0, 1000, &[fly(2, 5)], &[]), Err(E::UnknownTipper { tipper: 2 })),
        ("tipper usize::MAX", snap(0, 1000, &[fly(usize::MAX, 5)], &[]), Err(E::UnknownTipper { tipper: usize::MAX })),
        ("remaining 0", snap(0, 1000, &[fly(1, 0)], &[]), Err(E::ZeroRemaining)),
        ("remaining 1", snap(M, 1000, &[fly(1, 1)], &[]), Ok(())),
        ("remaining distance + slack", snap(0, 1000, &[fly(1, 2000 + RESTORE_SLACK)], &[]), Ok(())),
        ("remaining distance + slack + 1", snap(0, 1000, &[fly(1, 2001 + RESTORE_SLACK)], &[]), Err(E::TooFar { tipper: 1, remaining: 2003, distance: 2000 })),
        ("remaining MAX", snap(0, 1000, &[fly(0, M)], &[]), Err(E::TooFar { tipper: 0, remaining: M, distance: 100 })),
        ("out of order", snap(0, 1000, &[fly(1, 50), fly(1, 49)], &[]), Err(E::OutOfOrder { tipper: 1 })),
        ("same remaining twice", snap(0, 1000, &[fly(1, 50), fly(1, 50)], &[]), Ok(())),
        ("held tipper 2", snap(0, 1000, &[], &[held(2, 1)]), Err(E::UnknownTipper { tipper: 2 })),
        ("held tipper usize::MAX", snap(0, 1000, &[], &[held(usize::MAX, 1)]), Err(E::UnknownTipper { tipper: usize::MAX })),
        ("held remaining 0", snap(0, 1000, &[], &[held(0, 0)]), Err(E::ZeroRemaining)),
        ("held remaining = hold", snap(M, 1000, &[], &[held(0, 6)]), Ok(())),
        ("held remaining hold + 1", snap(0, 1000, &[], &[held(0, 7)]), Err(E::HeldTooLong { tipper: 0, remaining: 7, hold: 6 })),
        ("held remaining MAX", snap(0, 1000, &[], &[held(1, M)]), Err(E::HeldTooLong { tipper: 1, remaining: M, hold: 6 })),
        ("held twice", snap(0, 1000, &[], &[held(1, 1), held(1, 2)]), Err(E::DuplicateHeld { tipper: 1 })),
    ];
    for (what, s, want) in rows {
        let mut t = base.clone();
        let r = t.restore(&s);
        assert_eq!(r, want, "restore {what}");
        if r.is_err() {
            assert_eq!((t.snapshot(), t.now(), t.table().dia()), (good.clone(), base.now(), base.table().dia()), "a refused restore changed the tracker: {what}");
        } else {
            assert_eq!(t.snapshot(), s, "restore {what}: the tracker holds the snapshot");
            // It runs: everything on the chain arrives and every tipper resets, in order.
            let mut sets = 0;
            let mut resets = 0;
            t.advance(M, |e| match e {
                TipperEvent::Set { .. } => sets += 1,
                TipperEvent::Reset { .. } => resets += 1,
            });
            assert_eq!(sets, s.in_flight.len(), "{what}");
            assert!(t.is_empty() && !t.is_set(0) && !t.is_set(1), "{what}");
            assert!(resets >= s.held.len().min(1), "{what}");
        }
    }
}

/// `config` changed by `edit` (the type is non-exhaustive).
fn cfg(config: StretchConfig, edit: impl FnOnce(&mut StretchConfig)) -> StretchConfig {
    let mut c = config;
    edit(&mut c);
    c
}

/// Stretch meters: SIA 0, confirmations 0, DIA 0; measurements of 0, 1 and MAX; settings at
/// MAX; an end without a start; `reconcile(0)`.
#[test]
#[rustfmt::skip]
fn stretch_meter_at_the_extremes() {
    let c = StretchConfig::new(3000);
    // (what, config, dia, result)
    let rows: [(&str, StretchConfig, u32, Result<(), StretchConfigError>); 7] = [
        ("default", c, 3000, Ok(())),
        ("sia 0", cfg(c, |x| { x.sia = 0; }), 3000, Err(StretchConfigError::ZeroReference)),
        ("confirmations 0", cfg(c, |x| { x.confirmations = 0; }), 3000, Err(StretchConfigError::ZeroConfirmations)),
        ("dia 0", c, 0, Err(StretchConfigError::ZeroMeasurement)),
        ("sia MAX, dia 1", cfg(c, |x| { x.sia = M; }), 1, Ok(())),
        ("every setting MAX", cfg(c, |x| { x.sia = M; x.confirmations = u8::MAX; x.plausible_per_mille = M; x.alarm_per_mille = M; }), M, Ok(())),
        ("plausible and alarm 0", cfg(c, |x| { x.plausible_per_mille = 0; x.alarm_per_mille = 0; }), 3000, Ok(())),
    ];
    for (what, config, dia, want) in rows {
        assert_eq!(StretchMeter::with_dia(config, dia).map(|_| ()), want, "with_dia {what}");
    }
    assert_eq!(StretchMeter::new(cfg(c, |x| { x.sia = 0; })).map(|_| ()), Err(StretchConfigError::ZeroReference));
    // measure: (what, config, measured, result, accepted DIA after)
    let rows: [(&str, StretchConfig, u32, Measurement, u32); 8] = [
        ("0", c, 0, Measurement::Implausible { dia: 0 }, 3000),
        ("1", c, 1, Measurement::Implausible { dia: 1 }, 3000),
        ("MAX", c, M, Measurement::Implausible { dia: M }, 3000),
        ("SIA", c, 3000, Measurement::Unchanged, 3000),
        ("one pulse short, plausible 0", cfg(c, |x| { x.plausible_per_mille = 0; }), 2999, Measurement::Pending { dia: 2999 }, 3000),
        ("two pulses short, plausible 0", cfg(c, |x| { x.plausible_per_mille = 0; }), 2998, Measurement::Implausible { dia: 2998 }, 3000),
        ("MAX, plausible MAX, one confirmation", cfg(c, |x| { x.plausible_per_mille = M; x.confirmations = 1; }), M, Measurement::Accepted { dia: M }, M),
        ("1 at SIA MAX, plausible MAX", cfg(c, |x| { x.sia = M; x.plausible_per_mille = M; }), 1, Measurement::Pending { dia: 1 }, M),
    ];
    for (what, config, dia, want, after) in rows {
        let mut m = StretchMeter::new(config).unwrap();
        assert_eq!(m.measure(dia), want, "measure {what}");
        assert_eq!(m.dia(), after, "{what}");
    }
    // An end without a start; reconcile with 0 changes nothing.
    let mut m = StretchMeter::new(c).unwrap();
    assert_eq!((m.end(), m.orphan_ends(), m.measurements()), (None, 1, 0));
    m.measure(2990);
    let before = m.clone();
    assert_eq!(m.reconcile(0), Err(StretchConfigError::ZeroMeasurement));
    assert_eq!(m, before, "a refused reconcile changed the meter");
    assert_eq!(m.reconcile(M), Ok(true));
    assert_eq!(m.dia(), M);
    // The alarm at the ends of the stretch: (SIA − DIA)/DIA, saturating at i32::MAX.
    let mut m = StretchMeter::with_dia(cfg(c, |x| { x.sia = M; }), 1).unwrap();
    assert_eq!((m.stretch_per_mille(), m.alarm()), (i32::MAX, true));
    m.reconcile(M).unwrap();
    assert_eq!((m.stretch_per_mille(), m.alarm()), (0, false));
}

/// `start_up` with every combination of a good, a corrupt and no snapshot and a good, an
/// unusable (its DIA overflows the table) and no meter, and a refused meter configuration.
#[test]
#[rustfmt::skip]
fn start_up_at_the_extremes() {
    use regler_chain_tracker::{StartUp, start_up};
    let fresh = || tracker::<2>(&[100, 2000], 6);
    let mut running = fresh();
    running.recalibrate(990).unwrap();
    running.enter(1, 1).unwrap();
    let good = running.snapshot();
    let mut corrupt = good.clone();
    corrupt.in_flight[0].remaining = 0;
    let c = StretchConfig::new(1000);
    let meter = |dia| StretchMeter::with_dia(c, dia).unwrap();
    // (what, snapshot, meter, result: what was usable, the table's DIA after, trolleys on the chain)
    let rows: Vec<(&str, Option<&Snapshot<u16, 2, 2>>, Option<StretchMeter>, Result<(StartUp, u32, usize), StretchConfigError>)> = vec![
        ("both", Some(&good), Some(meter(990)), Ok((StartUp::Both, 990, 1))),
        ("both, meter stale", Some(&good), Some(meter(995)), Ok((StartUp::Both, 990, 1))),
        ("corrupt snapshot, meter", Some(&corrupt), Some(meter(995)), Ok((StartUp::MeterOnly, 995, 0))),
        ("no snapshot, meter", None, Some(meter(995)), Ok((StartUp::MeterOnly, 995, 0))),
        ("no snapshot, meter's DIA overflows the table", None, Some(meter(M)), Ok((StartUp::Neither, 1000, 0))),
        ("snapshot only", Some(&good), None, Ok((StartUp::SnapshotOnly, 990, 1))),
        ("corrupt snapshot only", Some(&corrupt), None, Ok((StartUp::Neither, 1000, 0))),
        ("nothing", None, None, Ok((StartUp::Neither, 1000, 0))),
    ];
    for (what, snapshot, stored, want) in rows {
        let mut t = fresh();
        let got = start_up(&mut t, snapshot, stored, c).map(|(m, how)| {
            assert_eq!(m.dia(), t.table().dia(), "{what}: meter and table agree");
            (how, t.table().dia(), t.len())
        });
        assert_eq!(got, want, "{what}");
    }
    // A meter configuration that is refused, when a new meter must be made.
    let mut t = fresh();
    let bad = { let mut b = c; b.confirmations = 0; b };
    assert_eq!(start_up(&mut t, None, None, bad).map(|_| ()), Err(StretchConfigError::ZeroConfirmations));
}
