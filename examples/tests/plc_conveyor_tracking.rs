//! The soft-PLC conveyor's reject gate under jams (issue 21, "The soft-PLC's conveyor").

use regler_examples::plc::Simulator;

/// Ten seeded ten-minute runs of the conveyor section, with the jams the plant brings (a part
/// sticks at the eye and stalls the belt): no bad part passes the reject gate and no good part
/// is rejected. The timer-register gate failed this: its register went on counting while the
/// stalled belt held the parts, so the gate opened early and bad parts went on.
#[test]
fn no_bad_part_passes_and_no_good_part_is_rejected_during_jams() {
    let (mut jams, mut bad) = (0, 0);
    for seed in 0..10 {
        let mut sim = Simulator::new(seed);
        sim.run(12_000);
        let t = sim.plant.tally;
        assert_eq!(
            (t.bad_passed, t.good_rejected),
            (0, 0),
            "seed {seed}: bad passed, good rejected; jams {}",
            t.jams
        );
        jams += t.jams;
        bad += t.bad_rejected;
    }
    assert!(jams >= 10 && bad >= 100, "jams {jams}, bad parts {bad}");
}

use proptest::prelude::*;
use regler_examples::plc::{Conveyor, PERIOD_MS, input};

/// A power failure of `for_ms` after cycle 800 (40 s), when bad parts are on their way (checked):
/// the tracker's snapshot, kept through it, brings every one of them to the gate. The same
/// outage with the program's memory lost (a fresh tracker) lets them through: the snapshot is
/// what keeps them.
#[test]
fn a_power_failure_loses_no_tracked_part() {
    for for_ms in [1, 50, 2_000, 60_000] {
        let mut kept = Simulator::new(3);
        let mut lost = Simulator::new(3);
        for sim in [&mut kept, &mut lost] {
            // Run on to a cycle with bad parts in flight, past the quality sensor.
            sim.run(800);
            while sim.program.tracked() == 0 || sim.plc.inputs().get(input::BAD) {
                sim.run(1);
            }
        }
        let in_flight = kept.program.tracked();
        kept.power_failure(for_ms).unwrap();
        lost.power_failure(for_ms).unwrap();
        lost.program = Conveyor::new();
        assert_eq!(kept.program.tracked(), in_flight);
        assert_eq!(kept.power_failures, 1);
        for sim in [&mut kept, &mut lost] {
            sim.run(2_400);
        }
        let (k, l) = (kept.plant.tally, lost.plant.tally);
        assert_eq!(
            (k.bad_passed, k.good_rejected),
            (0, 0),
            "{for_ms} ms: {k:?}"
        );
        assert!(l.bad_passed >= 1, "{for_ms} ms, memory lost: {l:?}");
    }
}

/// What can happen to the belt: it stalls (something wedged in it, wherever the parts are) for
/// a while, motor on; the operator stops it and starts it again later; the power fails.
#[derive(Clone, Copy, Debug)]
enum Event {
    Stall { at_ms: u32, for_ms: u32 },
    Stop { at_ms: u32, for_ms: u32 },
    PowerFail { at_ms: u32, for_ms: u32 },
}

fn event() -> impl Strategy<Value = Event> {
    // Stalls of every length from 1 ms to well past the jam detector's 3 s and the operator's
    // 2 s after the lamp; stops from a press to 10 s.
    prop_oneof![
        (0..RUN_MS, 1..9_000u32).prop_map(|(at_ms, for_ms)| Event::Stall { at_ms, for_ms }),
        (0..RUN_MS, 300..10_000u32).prop_map(|(at_ms, for_ms)| Event::Stop { at_ms, for_ms }),
        (0..RUN_MS, 1..20_000u32).prop_map(|(at_ms, for_ms)| Event::PowerFail { at_ms, for_ms }),
    ]
}

/// Two simulated minutes.
const RUN_MS: u32 = 120_000;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Over seeded runs with stalls of every length at every moment, stops, power failures and
    /// the plant's own stuck parts: no bad part passes the gate, no good part goes into the reject bin, and no
    /// part goes missing (put on = passed + rejected + cleared by hand + still on the belt).
    #[test]
    fn every_bad_part_and_only_bad_parts_are_rejected_whatever_the_belt_does(
        seed in any::<u64>(),
        events in proptest::collection::vec(event(), 0..6),
    ) {
        let mut sim = Simulator::new(seed);
        let mut outages = Vec::new();
        for e in &events {
            match *e {
                Event::Stall { at_ms, for_ms } => sim.plant.stall(at_ms, for_ms),
                Event::Stop { at_ms, for_ms } => {
                    sim.plant.press(at_ms, input::STOP, 200);
                    sim.plant.press(at_ms + for_ms, input::START, 200);
                }
                Event::PowerFail { at_ms, for_ms } => outages.push((at_ms / PERIOD_MS, for_ms)),
            }
        }
        // The outages fall between cycles; the stalls and presses go by the plant's clock.
        outages.sort_unstable();
        let cycles = u64::from(RUN_MS / PERIOD_MS);
        for (at_cycle, for_ms) in outages {
            let done = sim.plc.cycle_count();
            sim.run(u64::from(at_cycle).saturating_sub(done));
            sim.power_failure(for_ms).unwrap();
        }
        let done = sim.plc.cycle_count();
        sim.run(cycles.saturating_sub(done).max(1_200));
        let t = sim.plant.tally;
        prop_assert_eq!((t.bad_passed, t.good_rejected), (0, 0), "{:?}", t);
        let out = t.good_passed + t.bad_rejected + t.bad_passed + t.good_rejected
            + t.cleared_by_hand;
        prop_assert_eq!(t.arrived as usize, out as usize + sim.plant.on_belt());
        prop_assert_eq!(sim.program.untracked, 0);
    }
}

/// The monitor's `powerfail MS`: says what happened, refuses what it cannot do, and the run goes
/// on with the parts it kept.
#[test]
fn the_monitor_cuts_the_power() {
    let mut sim = Simulator::new(1989);
    sim.command("run 900").unwrap();
    let said = sim.command("powerfail 2500").unwrap();
    assert!(
        said.starts_with("power off for 2.5 s after cycle 900: outputs safe; "),
        "{said}"
    );
    assert!(said.contains("kept in the tracker"), "{said}");
    assert!(!sim.plc.outputs().get(regler_examples::plc::output::MOTOR));
    for bad in [
        "powerfail 0",
        "powerfail 3600001",
        "powerfail x",
        "powerfail",
    ] {
        let e = sim.command(bad).unwrap_err();
        assert!(e.contains("powerfail"), "{bad}: {e}");
    }
    sim.command("run 40").unwrap();
    assert!(
        sim.plc.outputs().get(regler_examples::plc::output::MOTOR),
        "START after the power came back"
    );
    let t = sim.plant.tally;
    assert_eq!(
        (t.bad_passed, t.good_rejected, sim.power_failures),
        (0, 0, 1)
    );
}
