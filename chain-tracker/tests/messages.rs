//! Every error's message, read as a user reads it: it names what was wrong (the value, the limit
//! it broke, the tipper). Written out in full, so a message that loses its value or its limit
//! fails. Where an operation returns the error, it is taken from there.
#![allow(clippy::unwrap_used, reason = "a test may panic: that is how it fails")]

use heapless::Vec;
use regler_chain_tracker::{
    CorrectionError, DistanceTable, EnterError, HeldTipper, InFlight, Snapshot, StretchConfig,
    StretchConfigError, StretchMeter, TableError, Tracker, TrackerError, correct,
};

fn check<E: core::fmt::Display + core::fmt::Debug>(e: E, text: &str) {
    assert_eq!(e.to_string(), text, "{e:?}");
}

#[test]
fn every_error_message_names_what_was_wrong() {
    // The correction SA·DIA/SIA: the three values it was given.
    check(
        correct(5, 1, 0).unwrap_err(),
        "SIA (original pulses between the initiators) must not be 0",
    );
    check(
        correct(u32::MAX, 3, 2).unwrap_err(),
        "SA·DIA/SIA = 4294967295·3/2 does not fit in 32 bits",
    );
    assert_eq!(
        correct(u32::MAX, 3, 2),
        Err(CorrectionError::Overflow {
            sa: u32::MAX,
            dia: 3,
            sia: 2
        })
    );

    // The table: how many distances for how many places, which tipper overflowed.
    check(
        DistanceTable::<2>::new(10, &[1, 2, 3]).unwrap_err(),
        "3 tipper distances given, the table holds 2",
    );
    check(
        DistanceTable::<2>::new(0, &[1]).unwrap_err(),
        "SIA (original pulses between the initiators) must not be 0",
    );
    let mut table = DistanceTable::<3>::new(1, &[5, 7, u32::MAX]).unwrap();
    check(
        table.recalibrate(0).unwrap_err(),
        "DIA (measured pulses between the initiators) must not be 0",
    );
    let overflow = table.recalibrate(2).unwrap_err();
    assert_eq!(overflow, TableError::Overflow { tipper: 2 });
    check(
        overflow,
        "corrected distance of tipper 2 does not fit in 32 bits",
    );

    // The stretch meter's configuration.
    check(
        StretchMeter::new(StretchConfig::new(0)).unwrap_err(),
        "sia must not be 0",
    );
    let mut no_confirmations = StretchConfig::new(3000);
    no_confirmations.confirmations = 0;
    check(
        StretchMeter::new(no_confirmations).unwrap_err(),
        "confirmations must be at least 1, got 0",
    );
    let zero = StretchMeter::with_dia(StretchConfig::new(3000), 0).unwrap_err();
    assert_eq!(zero, StretchConfigError::ZeroMeasurement);
    check(zero, "the DIA must not be 0");

    // The tracker: entering, building, recalibrating.
    let table = DistanceTable::<2>::new(3000, &[10, 4_000_000_000]).unwrap();
    let mut tracker: Tracker<u16, 1, 2> = Tracker::new(table, 6).unwrap();
    let unknown = tracker.enter(1977, 9).unwrap_err();
    assert_eq!(
        unknown,
        EnterError::UnknownTipper {
            trolley: 1977,
            tipper: 9
        }
    );
    check(unknown, "no tipper 9 in the distance table");
    tracker.enter(1, 1).unwrap();
    check(
        tracker.enter(2, 0).unwrap_err(),
        "tracker full: no room for another trolley",
    );
    check(
        Tracker::<u16, 1, 2>::new(table, 0).unwrap_err(),
        "the tipper hold must be at least 1 pulse",
    );
    // The distance table's own message, after what refused.
    check(
        tracker.recalibrate(0).unwrap_err(),
        "distance table: DIA (measured pulses between the initiators) must not be 0",
    );
    check(
        tracker.recalibrate(4000).unwrap_err(),
        "distance table: corrected distance of tipper 1 does not fit in 32 bits",
    );
    check(
        TrackerError::RescaleOverflow,
        "rescaled distance of a trolley on the chain does not fit in 32 bits",
    );

    // Snapshots `restore` refuses: the tipper, the pulses to go and the limit they broke.
    let table = DistanceTable::<2>::new(3000, &[10, 20]).unwrap();
    let mut tracker: Tracker<u16, 4, 2> = Tracker::new(table, 6).unwrap();
    let trolley = |tipper, remaining| InFlight {
        trolley: 7u16,
        tipper,
        remaining,
    };
    let snapshot = |in_flight: &[InFlight<u16>], held: &[HeldTipper]| {
        let mut s: Snapshot<u16, 4, 2> = Snapshot::new();
        s.dia = 3000;
        s.in_flight = Vec::from_slice(in_flight).unwrap();
        s.held = Vec::from_slice(held).unwrap();
        s
    };
    let held = |tipper, remaining| HeldTipper { tipper, remaining };
    let refused: [(Snapshot<u16, 4, 2>, &str); 7] = [
        (
            snapshot(&[trolley(2, 5)], &[]),
            "snapshot names tipper 2, which the table does not have",
        ),
        (
            snapshot(&[trolley(0, 0)], &[]),
            "snapshot holds a trolley with 0 pulses to go",
        ),
        (
            snapshot(&[], &[held(1, 9)]),
            "snapshot holds tipper 1 set for 9 more pulses, but the hold is 6",
        ),
        (
            snapshot(&[], &[held(0, 3), held(0, 2)]),
            "snapshot names tipper 0 as set twice",
        ),
        (
            snapshot(&[trolley(1, 23)], &[]),
            "snapshot holds a trolley 23 pulses from tipper 1, which is only 20 from the reader",
        ),
        (
            snapshot(&[trolley(0, 8), trolley(0, 4)], &[]),
            "snapshot lists the trolleys for tipper 0 out of order (one would overtake another)",
        ),
        (
            Snapshot {
                dia: 0,
                ..snapshot(&[], &[])
            },
            "distance table: DIA (measured pulses between the initiators) must not be 0",
        ),
    ];
    for (s, text) in refused {
        check(tracker.restore(&s).unwrap_err(), text);
    }
}
