//! A tracker's snapshot survives a trip through non-volatile memory (here: JSON).
#![allow(clippy::unwrap_used, reason = "a test may panic: that is how it fails")]
#![cfg(feature = "serde")]

use regler_chain_tracker::{
    DistanceTable, Measurement, Snapshot, StretchConfig, StretchMeter, Tracker,
};

#[test]
fn snapshot_round_trips_through_serde() {
    let table: DistanceTable<4> = DistanceTable::new(1000, &[10, 20, 30]).unwrap();
    let mut before: Tracker<u16, 16, 4> = Tracker::new(table, 6).unwrap();
    for (trolley, tipper) in (100u16..).zip([2, 0, 1, 2]) {
        before.enter(trolley, tipper).unwrap();
        before.advance(3, |_| {});
    }
    before.recalibrate(990).unwrap();
    let stored = serde_json::to_string(&before.snapshot()).unwrap();
    let snapshot: Snapshot<u16, 16, 4> = serde_json::from_str(&stored).unwrap();
    let mut after: Tracker<u16, 16, 4> = Tracker::new(table, 6).unwrap();
    after.restore(&snapshot).unwrap();
    let (mut a, mut b) = (Vec::new(), Vec::new());
    before.advance(60, |e| a.push(e));
    after.advance(60, |e| b.push(e));
    assert_eq!(a, b);
    assert_eq!(a.len(), 8, "four sets and four resets");
}

/// A stored stretch meter that breaks an invariant is an error, never a broken meter.
#[test]
fn bad_stored_stretch_meters_are_refused() {
    let meter = StretchMeter::with_dia(StretchConfig::new(3000), 2990).unwrap();
    let text = serde_json::to_string(&meter).unwrap();
    assert_eq!(serde_json::from_str::<StretchMeter>(&text).unwrap(), meter);
    let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
    for (field, bad, message) in [
        ("sia", 0, "sia must not be 0"),
        ("confirmations", 0, "confirmations must be at least 1"),
    ] {
        let mut v = value.clone();
        v["config"][field] = serde_json::json!(bad);
        let err = serde_json::from_value::<StretchMeter>(v)
            .unwrap_err()
            .to_string();
        assert!(err.contains(message), "{field}: {err}");
    }
    value["accepted"] = serde_json::json!(0);
    let err = serde_json::from_value::<StretchMeter>(value)
        .unwrap_err()
        .to_string();
    assert!(err.contains("DIA must not be 0"), "{err}");
    assert!(StretchMeter::with_dia(StretchConfig::new(3000), 0).is_err());
}

/// A stored meter comes back as it was stored: its counters, the count running between the
/// initiators and a half-confirmed candidate (power failed between two measurements of a
/// stretched chain: the next measurement confirms it, as without the power failure). A stored
/// candidate no meter could hold (one already seen `confirmations` times, or a DIA of 0) is
/// dropped: that one must be measured `confirmations` times again.
#[test]
fn a_stored_meter_comes_back_as_it_was_and_an_impossible_candidate_is_dropped() {
    let mut meter = StretchMeter::new(StretchConfig::new(3000)).unwrap(); // 2 confirmations
    assert_eq!(meter.measure(0), Measurement::Implausible { dia: 0 });
    assert_eq!(meter.end(), None);
    assert_eq!(meter.end(), None);
    assert_eq!(meter.measure(2990), Measurement::Pending { dia: 2990 });
    meter.start();
    for _ in 0..2990 {
        meter.pulse();
    }
    let text = serde_json::to_string(&meter).unwrap();
    let mut stored: StretchMeter = serde_json::from_str(&text).unwrap();
    assert_eq!(stored, meter);
    assert_eq!(
        (
            stored.measurements(),
            stored.rejected(),
            stored.orphan_ends()
        ),
        (2, 1, 2)
    );
    // The count that was running when power failed ends the measurement it belongs to, and
    // confirms the candidate.
    assert_eq!(stored.end(), Some(Measurement::Accepted { dia: 2990 }));

    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(value["candidate"], serde_json::json!([2990, 1]));
    for bad in [
        serde_json::json!([2990, 2]),
        serde_json::json!([2990, 255]),
        serde_json::json!([0, 1]),
    ] {
        let mut v = value.clone();
        v["candidate"] = bad.clone();
        let mut m: StretchMeter = serde_json::from_value(v).unwrap();
        assert_eq!(
            serde_json::to_value(&m).unwrap()["candidate"],
            serde_json::Value::Null,
            "{bad}"
        );
        assert_eq!(m.end(), Some(Measurement::Pending { dia: 2990 }), "{bad}");
        assert_eq!(m.dia(), 3000);
    }
}
