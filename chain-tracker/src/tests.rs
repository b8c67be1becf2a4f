//! Unit tests of the tracker (the table and the meter test themselves in their modules).

use super::*;

type Events = Vec<(u32, TipperEvent<u16>)>;

fn tracker<const N: usize>(sa: &[u32], hold: u32) -> Tracker<u16, N, 8> {
    Tracker::new(DistanceTable::new(1000, sa).unwrap(), hold).unwrap()
}

fn run<const N: usize>(t: &mut Tracker<u16, N, 8>, pulses: u32) -> Events {
    let mut events = Vec::new();
    for _ in 0..pulses {
        let now = t.now();
        t.pulse(|e| events.push((now.wrapping_add(1), e)));
    }
    events
}

#[test]
fn arrives_after_distance_and_resets_after_hold() {
    let mut t = tracker::<4>(&[3, 5], SOURCE_HOLD_PULSES);
    t.enter(7, 1).unwrap();
    assert!(!t.is_empty());
    let events = run(&mut t, 20);
    assert_eq!(
        events,
        [
            (
                5,
                TipperEvent::Set {
                    tipper: 1,
                    trolley: 7
                }
            ),
            (11, TipperEvent::Reset { tipper: 1 })
        ]
    );
    assert!(t.is_empty());
}

#[test]
fn two_arrivals_within_the_hold_keep_the_tipper_set() {
    let mut t = tracker::<4>(&[4], 6);
    t.enter(1, 0).unwrap();
    run(&mut t, 3);
    t.enter(2, 0).unwrap(); // arrives at pulse 7, within the hold of the first (4..10)
    let events = run(&mut t, 20);
    assert_eq!(
        events,
        [
            (
                4,
                TipperEvent::Set {
                    tipper: 0,
                    trolley: 1
                }
            ),
            (
                7,
                TipperEvent::Set {
                    tipper: 0,
                    trolley: 2
                }
            ),
            (13, TipperEvent::Reset { tipper: 0 }),
        ]
    );
}

#[test]
fn arrival_on_the_reset_pulse_keeps_the_tipper_set() {
    let mut t = tracker::<4>(&[4], 2);
    t.enter(1, 0).unwrap();
    run(&mut t, 2);
    t.enter(2, 0).unwrap(); // arrives at 6 = reset pulse of the first
    let events = run(&mut t, 10);
    assert_eq!(
        events,
        [
            (
                4,
                TipperEvent::Set {
                    tipper: 0,
                    trolley: 1
                }
            ),
            (
                6,
                TipperEvent::Set {
                    tipper: 0,
                    trolley: 2
                }
            ),
            (8, TipperEvent::Reset { tipper: 0 }),
        ]
    );
}

#[test]
fn full_and_unknown_tipper_change_nothing() {
    let mut t = tracker::<2>(&[10, 20], 6);
    t.enter(1, 0).unwrap();
    t.enter(2, 1).unwrap();
    assert_eq!(t.enter(3, 0), Err(EnterError::Full(3)));
    assert_eq!(
        t.enter(4, 2),
        Err(EnterError::UnknownTipper {
            trolley: 4,
            tipper: 2
        })
    );
    assert_eq!(t.enter(4, 2).unwrap_err().into_trolley(), 4);
    assert_eq!(t.len(), 2);
    let events = run(&mut t, 30);
    assert_eq!(
        events
            .iter()
            .filter(|(_, e)| matches!(e, TipperEvent::Set { .. }))
            .count(),
        2
    );
    // The places are free again.
    t.enter(5, 0).unwrap();
    t.enter(6, 0).unwrap();
}

#[test]
fn zero_distance_counts_as_one_and_zero_hold_is_refused() {
    let mut t = tracker::<2>(&[0], 1);
    t.enter(1, 0).unwrap();
    assert_eq!(
        run(&mut t, 1),
        [(
            1,
            TipperEvent::Set {
                tipper: 0,
                trolley: 1
            }
        )]
    );
    assert_eq!(run(&mut t, 1), [(2, TipperEvent::Reset { tipper: 0 })]);
    let table = DistanceTable::<8>::new(1, &[1]).unwrap();
    assert_eq!(
        Tracker::<u16, 2, 8>::new(table, 0).unwrap_err(),
        TrackerError::ZeroHold
    );
}

#[test]
fn wraps_across_u32_max() {
    let mut t = tracker::<8>(&[5, 10], 6);
    t.set_now(u32::MAX - 3);
    t.enter(1, 0).unwrap();
    t.enter(2, 1).unwrap();
    let events = run(&mut t, 20);
    assert_eq!(
        events,
        [
            (
                1,
                TipperEvent::Set {
                    tipper: 0,
                    trolley: 1
                }
            ),
            (
                6,
                TipperEvent::Set {
                    tipper: 1,
                    trolley: 2
                }
            ),
            (7, TipperEvent::Reset { tipper: 0 }),
            (12, TipperEvent::Reset { tipper: 1 }),
        ]
    );
}

#[test]
fn cannot_overtake_the_trolley_ahead() {
    let mut t = tracker::<8>(&[100], 6);
    t.enter(1, 0).unwrap();
    t.recalibrate(900).unwrap(); // stretched: new entries need 90 pulses
    // The trolley ahead was rescaled to 90 too; the one behind arrives no earlier.
    t.enter(2, 0).unwrap();
    let sets: Vec<_> = run(&mut t, 100)
        .into_iter()
        .filter(|(_, e)| matches!(e, TipperEvent::Set { .. }))
        .collect();
    assert_eq!(
        sets,
        [
            (
                90,
                TipperEvent::Set {
                    tipper: 0,
                    trolley: 1
                }
            ),
            (
                90,
                TipperEvent::Set {
                    tipper: 0,
                    trolley: 2
                }
            ),
        ]
    );
}

#[test]
fn recalibration_rescales_trolleys_on_the_chain() {
    let mut t = tracker::<8>(&[1000, 2000], 6);
    t.enter(1, 1).unwrap();
    run(&mut t, 1000); // half way: 1000 to go
    assert!(t.recalibrate(990).unwrap()); // 1 % more pulses' worth of chain per pulse
    assert_eq!(t.table().distance(1), Some(1980));
    assert_eq!(
        t.in_flight().next(),
        Some(InFlight {
            trolley: 1,
            tipper: 1,
            remaining: 990
        })
    );
    assert!(!t.recalibrate(990).unwrap());
    let events = run(&mut t, 990);
    assert_eq!(
        events,
        [(
            1990,
            TipperEvent::Set {
                tipper: 1,
                trolley: 1
            }
        )]
    );
}

#[test]
fn failed_recalibration_changes_nothing() {
    let mut t: Tracker<u16, 4, 8> =
        Tracker::new(DistanceTable::new(1, &[1, 1 << 30]).unwrap(), 6).unwrap();
    t.enter(1, 1).unwrap();
    let before = t.snapshot();
    assert_eq!(
        t.recalibrate(8),
        Err(TrackerError::Table(TableError::Overflow { tipper: 1 }))
    );
    assert_eq!(
        t.recalibrate(0),
        Err(TrackerError::Table(TableError::ZeroMeasurement))
    );
    assert_eq!(t.snapshot(), before);
    assert_eq!(t.table().dia(), 1);
}

#[test]
fn snapshot_and_restore_lose_nothing() {
    let mut a = tracker::<16>(&[10, 20, 30], 6);
    for (i, tipper) in [0, 1, 2, 1, 0, 2, 2].into_iter().enumerate() {
        a.enter(i as u16, tipper).unwrap();
        run(&mut a, 2);
    }
    a.recalibrate(1010).unwrap();
    let snapshot = a.snapshot();
    assert!(!snapshot.held.is_empty());
    let mut b = tracker::<16>(&[10, 20, 30], 6);
    b.restore(&snapshot).unwrap();
    assert_eq!(b.snapshot(), snapshot);
    assert_eq!(run(&mut a, 50), run(&mut b, 50));
}

#[test]
fn restore_refuses_bad_snapshots() {
    let mut t = tracker::<4>(&[10], 6);
    t.enter(9, 0).unwrap();
    let good = t.snapshot();
    let mut bad = good.clone();
    bad.in_flight[0].tipper = 5;
    assert_eq!(
        t.restore(&bad),
        Err(TrackerError::UnknownTipper { tipper: 5 })
    );
    let mut bad = good.clone();
    bad.in_flight[0].remaining = 0;
    assert_eq!(t.restore(&bad), Err(TrackerError::ZeroRemaining));
    let mut bad = good.clone();
    bad.dia = 0;
    assert_eq!(
        t.restore(&bad),
        Err(TrackerError::Table(TableError::ZeroMeasurement))
    );
    assert_eq!(t.snapshot(), good);
}

#[test]
fn error_messages_name_the_problem() {
    assert!(
        EnterError::UnknownTipper {
            trolley: 1u16,
            tipper: 9
        }
        .to_string()
        .contains('9')
    );
    assert!(TrackerError::ZeroHold.to_string().contains("hold"));
    assert!(
        CorrectionError::Overflow {
            sa: 1,
            dia: 2,
            sia: 3
        }
        .to_string()
        .contains("1·2/3")
    );
}
