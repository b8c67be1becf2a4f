//! regler-chain-tracker on the core: the 64-bit intermediate of the correction on a 32-bit core.

use regler_chain_tracker::{
    DistanceTable, EnterError, HeldTipper, Measurement, Snapshot, StretchConfig, StretchMeter,
    TipperEvent, Tracker, TrackerError, correct,
};

use crate::{Outcome, check};

pub fn correct_is_exact_at_the_extremes() -> Outcome {
    check!(correct(u32::MAX, u32::MAX, u32::MAX) == Ok(u32::MAX));
    check!(correct(3, 1, 2) == Ok(2)); // 1.5 rounds half up
    check!(correct(4000, 2985, 3000) == Ok(3980));
    check!(correct(u32::MAX, 2, 1).is_err());
    check!(correct(1, 1, 0).is_err());
    Ok(())
}

pub fn tracker_with_recalibration() -> Outcome {
    let table: DistanceTable<3> = DistanceTable::new(3000, &[10, 20, 30]).map_err(|_| "table")?;
    let mut tracker: Tracker<u16, 64, 3> = Tracker::new(table, 6).map_err(|_| "tracker")?;
    tracker.enter(1977, 2).map_err(|_| "enter")?;
    tracker.advance(10, |_| {});
    // The chain stretched 10 %: 20 pulses to go become 18.
    check!(tracker.recalibrate(2700) == Ok(true));
    let mut events = heapless::Vec::<(u32, TipperEvent<u16>), 4>::new();
    for _ in 0..40 {
        let now = tracker.now().wrapping_add(1);
        tracker.pulse(|e| {
            let _ = events.push((now, e));
        });
    }
    check!(
        events.as_slice()
            == [
                (
                    28,
                    TipperEvent::Set {
                        tipper: 2,
                        trolley: 1977
                    }
                ),
                (34, TipperEvent::Reset { tipper: 2 })
            ]
    );
    Ok(())
}

pub fn snapshot_restore_and_refusal() -> Outcome {
    let table: DistanceTable<3> = DistanceTable::new(1000, &[10, 20, 30]).map_err(|_| "table")?;
    let mut a: Tracker<u16, 16, 3> = Tracker::new(table, 6).map_err(|_| "tracker")?;
    for (k, tipper) in [0usize, 2, 1, 2].into_iter().enumerate() {
        a.enter(k as u16, tipper).map_err(|_| "enter")?;
        a.advance(2, |_| {});
    }
    let mut stored: Snapshot<u16, 16, 3> = Snapshot::new();
    a.snapshot_into(&mut stored);
    let mut b: Tracker<u16, 16, 3> = Tracker::new(table, 6).map_err(|_| "tracker")?;
    b.restore(&stored).map_err(|_| "restore")?;
    let (mut ea, mut eb) = (0u32, 0u32);
    for _ in 0..60 {
        a.pulse(|_| ea += 1);
        b.pulse(|_| eb += 1);
    }
    // Four sets; tipper 2 is set twice within one hold, so three resets.
    check!(ea == 7 && ea == eb);
    // A held tipper beyond this tracker's hold is refused and changes nothing.
    let mut bad = stored.clone();
    bad.held.clear();
    bad.held
        .push(HeldTipper {
            tipper: 0,
            remaining: 20,
        })
        .map_err(|_| "push")?;
    check!(matches!(
        b.restore(&bad),
        Err(TrackerError::HeldTooLong { .. })
    ));
    check!(b.is_empty());
    Ok(())
}

pub fn stretch_meter_confirms() -> Outcome {
    let mut meter = StretchMeter::new(StretchConfig::new(3000)).map_err(|_| "meter")?;
    check!(!matches!(meter.measure(2985), Measurement::Accepted { .. }));
    check!(meter.measure(2985) == Measurement::Accepted { dia: 2985 });
    check!(meter.stretch_per_mille() == 5);
    check!(StretchMeter::with_dia(StretchConfig::new(3000), 0).is_err());
    Ok(())
}

pub fn sizes_on_a_32_bit_core() -> Outcome {
    use core::mem::size_of;
    check!(size_of::<DistanceTable<40>>() == 8 * 40 + 8 + 4);
    check!(size_of::<Tracker<u16, 512, 40>>() == 7468);
    Ok(())
}

pub fn a_full_chain_hands_the_trolley_back() -> Outcome {
    let table: DistanceTable<2> = DistanceTable::new(1000, &[50, 60]).map_err(|_| "table")?;
    let mut t: Tracker<u16, 2, 2> = Tracker::new(table, 6).map_err(|_| "tracker")?;
    t.enter(1, 0).map_err(|_| "enter")?;
    t.enter(2, 1).map_err(|_| "enter")?;
    check!(matches!(t.enter(3, 0), Err(EnterError::Full(3))));
    check!(matches!(t.enter(4, 9), Err(e) if e.into_trolley() == 4));
    check!(t.len() == 2);
    Ok(())
}
