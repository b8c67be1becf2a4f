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
use regler_examples::plc::input;

/// What can happen to the belt: it stalls (something wedged in it, wherever the parts are) for
/// a while, motor on, or the operator stops it and starts it again later.
#[derive(Clone, Copy, Debug)]
enum Event {
    Stall { at_ms: u32, for_ms: u32 },
    Stop { at_ms: u32, for_ms: u32 },
}

fn event() -> impl Strategy<Value = Event> {
    // Stalls of every length from 1 ms to well past the jam detector's 3 s and the operator's
    // 2 s after the lamp; stops from a press to 10 s.
    prop_oneof![
        (0..RUN_MS, 1..9_000u32).prop_map(|(at_ms, for_ms)| Event::Stall { at_ms, for_ms }),
        (0..RUN_MS, 300..10_000u32).prop_map(|(at_ms, for_ms)| Event::Stop { at_ms, for_ms }),
    ]
}

/// Two simulated minutes.
const RUN_MS: u32 = 120_000;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Over seeded runs with stalls of every length at every moment, stops, and the plant's own
    /// stuck parts: no bad part passes the gate, no good part goes into the reject bin, and no
    /// part goes missing (put on = passed + rejected + cleared by hand + still on the belt).
    #[test]
    fn every_bad_part_and_only_bad_parts_are_rejected_whatever_the_belt_does(
        seed in any::<u64>(),
        events in proptest::collection::vec(event(), 0..6),
    ) {
        let mut sim = Simulator::new(seed);
        for e in &events {
            match *e {
                Event::Stall { at_ms, for_ms } => sim.plant.stall(at_ms, for_ms),
                Event::Stop { at_ms, for_ms } => {
                    sim.plant.press(at_ms, input::STOP, 200);
                    sim.plant.press(at_ms + for_ms, input::START, 200);
                }
            }
        }
        sim.run(u64::from(RUN_MS / regler_examples::plc::PERIOD_MS));
        let t = sim.plant.tally;
        prop_assert_eq!((t.bad_passed, t.good_rejected), (0, 0), "{:?}", t);
        let out = t.good_passed + t.bad_rejected + t.bad_passed + t.good_rejected
            + t.cleared_by_hand;
        prop_assert_eq!(t.arrived as usize, out as usize + sim.plant.on_belt());
        prop_assert_eq!(sim.program.untracked, 0);
    }
}
