//! A board that restarts (a power cycle, a watchdog) at any moment — also when the counters
//! stand just below, at or past their half range and their wrap — is recognised, counted,
//! placed again where the board before it stopped, and linked again within a bound.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "a test may panic: that is how it fails"
)]

mod common;

use common::Sim;
use proptest::prelude::*;
use regler_ring_transfer::{Mode, SlaveConfig, Source};

const OFFSETS: [u64; 8] = [
    0,
    32_500,
    32_767,
    32_768,
    40_000,
    65_300,
    65_535,
    65_536 + 32_700,
];

fn config(row_len: u16) -> SlaveConfig {
    SlaveConfig {
        address: common::ADDRESS,
        row_len,
        silence_limit: 8,
        retry_after: 5,
        boot: 1,
    }
}

/// Runs `steps` steps with a reboot at `reboot_at`; returns the sim.
fn run<const N: usize>(
    row_len: u16,
    offset: u64,
    delay: u64,
    reboot_at: u64,
    steps: u64,
) -> Sim<N> {
    let mut sim: Sim<N> = Sim::new(config(row_len), offset, delay, 1);
    for now in 0..steps {
        if now == reboot_at {
            sim.reboot();
        }
        sim.step(now);
    }
    sim
}

/// What a clean link (every frame `delay` steps, none lost) guarantees after a reboot at any
/// step: the new board is placed exactly where the board before it stopped (the master heard
/// its every consumption: nothing skipped, nothing repeated), linked again within
/// `2·delay + row_len` steps, the master's status says linked again and counts the reboot; every
/// master item is the master's item at its index.
fn check_clean<const N: usize>(row_len: u16, offset: u64, delay: u64, reboot_at: u64) {
    let bound = 2 * delay + u64::from(row_len);
    let steps = reboot_at + bound + delay + 4;
    let sim: Sim<N> = run(row_len, offset, delay, reboot_at, steps);
    let ctx =
        format!("ring {N}, row {row_len}, offset {offset}, delay {delay}, reboot at {reboot_at}");
    sim.check_items();
    // Where the old board stopped: its consumed count after its last step.
    let old_final = sim
        .steps
        .iter()
        .filter(|s| s.boot == 1)
        .fold(offset, |_, s| {
            s.index
                .map_or(offset, |i| i + u64::from(s.out.source != Source::Local))
        });
    let placed = sim
        .placements
        .iter()
        .find(|p| p.0 == 2)
        .unwrap_or_else(|| panic!("{ctx}: new board never placed"));
    assert_eq!(
        placed.1, old_final,
        "{ctx}: placed at {} not where the old board stopped",
        placed.1
    );
    let linked_at = sim
        .steps
        .iter()
        .find(|s| s.boot == 2 && s.mode_after == Mode::Linked)
        .unwrap_or_else(|| panic!("{ctx}: not linked again"))
        .now;
    assert!(
        linked_at < reboot_at + bound,
        "{ctx}: linked at {linked_at}"
    );
    let status = sim.master.status(0).unwrap();
    // Reboots: the board that was running when the master started → boot 1 (if it lived to
    // say hello) → boot 2.
    assert_eq!(status.reboots, 1 + u32::from(reboot_at > 0), "{ctx}");
    assert!(status.linked, "{ctx}");
    assert_eq!(sim.stale_standalone, 0, "{ctx}");
    assert_eq!(sim.slave.stats().underruns, 0, "{ctx}");
}

/// Every step of a run as the reboot's moment (before, during and long after the first board
/// was placed; every column of a row), with counters near their half range and their wrap,
/// delays of 1–3 steps, a ring shorter and longer than a row (each longer than the round trip:
/// a shorter one underruns whatever happens).
#[test]
#[cfg_attr(
    miri,
    ignore = "a reboot at each of 90 steps for 8 counter offsets and 3 delays (2 160 simulated runs): hours under Miri; runs natively in every CI run"
)]
fn a_reboot_at_every_step_resumes_where_the_board_stopped() {
    for offset in OFFSETS {
        for delay in 1..=3 {
            for reboot_at in 0..90 {
                check_clean::<16>(4, offset, delay, reboot_at);
                check_clean::<8>(12, offset, delay, reboot_at);
            }
        }
    }
}

/// The case: the master's counter past 32 768 (40 000 items into the job), the board
/// power-cycled. The board must be placed at 40 000 + what it consumed, not at 65 536.
#[test]
#[cfg_attr(
    miri,
    ignore = "a simulated run of 40 400 steps: minutes under Miri; runs natively in every CI run"
)]
fn a_board_rebooted_after_half_the_counter_range_is_placed_where_it_stopped() {
    let sim: Sim<32> = run(10, 40_000, 1, 200, 400);
    sim.check_items();
    let placements: Vec<u64> = sim.placements.iter().map(|p| p.1).collect();
    assert_eq!(placements.len(), 2);
    assert_eq!(placements[0], 40_000);
    assert!((40_150..40_200).contains(&placements[1]), "{placements:?}");
    assert_eq!(sim.master.status(0).unwrap().reboots, 2);
    assert_eq!(sim.slave.mode(), Mode::Linked);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 4 } else { 512 }))]

    /// With frames lost, repeated and reordered around the reboot (then a clean link), the
    /// reboot at any step — while the first board's hellos and syncs are still on the link too:
    /// every master item is the master's item at its index; the new board is placed exactly at
    /// the newest consumed count of the board before it that reached the master before the new
    /// board's hello (nothing skipped; repeated are only the items that board consumed after
    /// that report), within `2·D + k·retry_after` steps of the reboot (`D` the longest delay
    /// of a frame, `k` the frames lost meanwhile); it is linked again and the master says so;
    /// the reboot is counted; the session is the new board's.
    #[test]
    #[cfg_attr(miri, ignore = "1 200 simulated steps of the ring per case: minutes under Miri, a simulated ring steps in tens of milliseconds under Miri; runs natively in every CI run")]
    fn a_reboot_on_a_faulty_link(
        seed in any::<u64>(),
        offset in prop::sample::select(OFFSETS.to_vec()),
        // Half the cases while the first board is still saying hello (its hellos and their
        // syncs on the link with the new board's), half anywhere.
        reboot_at in prop_oneof![0u64..24, 0u64..400],
        loss in 0u8..80,
        duplicate in 0u8..80,
        late in 0u8..80,
        delay in 1u64..4,
        batch in 1u32..20,
    ) {
        let mut sim: Sim<16> = Sim::new(config(6), offset, delay, seed);
        sim.batch = batch;
        for wire in [&mut sim.up, &mut sim.down] {
            wire.loss = loss;
            wire.duplicate = duplicate;
            wire.late = late;
            wire.jitter = 12;
        }
        let mut lost_at_reboot = 0;
        let mut placed_within = None;
        for now in 0..1_200 {
            sim.faulty = (reboot_at.saturating_sub(60)..reboot_at + 200).contains(&now);
            if now == reboot_at {
                sim.reboot();
                lost_at_reboot = sim.up.lost + sim.down.lost;
            }
            sim.step(now);
            if now >= reboot_at && placed_within.is_none() && sim.slave.placed() {
                placed_within = Some((now - reboot_at, sim.up.lost + sim.down.lost - lost_at_reboot));
            }
        }
        sim.check_items();
        let old_final = sim.steps.iter().filter(|s| s.boot == 1).fold(offset, |acc, s| {
            s.index.map_or(acc, |i| i + u64::from(s.out.source != Source::Local))
        });
        let placed = sim.placements.iter().find(|p| p.0 == 2).copied();
        prop_assert!(placed.is_some(), "never placed");
        let placed = placed.unwrap().1;
        let (took, lost) = placed_within.unwrap();
        let longest = delay + 12;
        let retry_after = u64::from(config(6).retry_after);
        prop_assert!(
            took <= 2 * longest + lost * retry_after,
            "placed {} steps after the reboot, {} frames lost", took, lost
        );
        prop_assert_eq!(placed, sim.newest_of_previous);
        prop_assert!(placed <= old_final, "skipped {}..{}", old_final, placed);
        prop_assert_eq!(sim.slave.mode(), Mode::Linked);
        let status = sim.master.status(0).unwrap();
        prop_assert!(status.linked);
        prop_assert!(status.reboots >= 1);
        prop_assert_eq!(status.boot, 2);
        prop_assert_eq!(sim.stale_standalone, 0);
        // The clean end: the last 300 steps are all the master's.
        prop_assert!(sim.steps[900..].iter().all(|s| s.out.source == Source::Master));
    }
}

/// Runs `sim` clean from `from` for `steps` steps.
fn run_clean<const N: usize>(sim: &mut Sim<N>, from: u64, steps: u64) {
    for now in from..from + steps {
        sim.step(now);
    }
}

/// The gap the first round left: a hello of an earlier start of the board (boot 1) reaches the
/// master after the new board (boot 2) was placed, and whatever the master answers it is lost.
/// The session must not move (the late hello is an earlier start: ignored, not counted), and the
/// board must keep the master's stream — at every counter position around the half range and
/// the wrap, and whether the late hello comes while the board is linked or while its hello's
/// sync is still in flight.
#[test]
#[cfg_attr(
    miri,
    ignore = "40 simulated runs of the ring (8 counter offsets, 5 delays): hours under Miri, a simulated ring steps in tens of milliseconds under Miri; runs natively in every CI run"
)]
fn a_late_hello_of_an_earlier_start_with_its_answer_lost_never_strands_the_board() {
    for offset in OFFSETS {
        for late_at in [3u64, 4, 5, 30, 100] {
            let delay = 2;
            let mut sim: Sim<16> = Sim::new(config(4), offset, delay, 7);
            // The first board's hello leaves, and is held back on the link.
            let old_hello = sim.slave.poll_report().unwrap();
            assert!(old_hello.hello && old_hello.boot == 1);
            sim.reboot();
            run_clean(&mut sim, 0, late_at);
            // The late hello arrives; every frame the master answers it with is lost.
            let outcome = sim.master.on_report(late_at, 0, &old_hello).unwrap();
            while sim.master.next_refill(late_at, 64).is_some() {}
            let status = sim.master.status(0).unwrap();
            let ctx = format!("offset {offset}, late hello at {late_at}: {outcome:?} {status:?}");
            assert_eq!(
                status.boot, 2,
                "{ctx}: the session moved to an earlier start"
            );
            assert_eq!(status.reboots, 1, "{ctx}: an earlier start counted again");
            run_clean(&mut sim, late_at, 300);
            sim.check_items();
            let status = sim.master.status(0).unwrap();
            assert!(status.linked && status.boot == 2, "{ctx}");
            assert_eq!(sim.slave.mode(), Mode::Linked, "{ctx}");
            // Linked from step 2·delay + row_len on, every item the master's.
            assert!(
                sim.steps[(2 * delay + 4) as usize + 4..]
                    .iter()
                    .all(|s| s.out.source == Source::Master),
                "{ctx}: the board lost the master's stream"
            );
        }
    }
}

/// The same defect after the master was re-initialised (or restarted): the first report it
/// takes is a late one of an earlier start (boot 1), so its session is boot 1 while the live
/// board (boot 2) is placed. The master tells the board which start it serves (a sync offer),
/// the board says hello, and is placed again within two round trips plus its report period —
/// instead of being ignored for good.
#[test]
#[cfg_attr(
    miri,
    ignore = "six simulated runs of the ring: minutes under Miri, a simulated ring steps in tens of milliseconds under Miri; runs natively in every CI run"
)]
fn a_master_that_took_an_earlier_start_for_the_session_re_offers_it() {
    for offset in [0u64, 32_500, 32_767, 40_000, 65_300, 65_535] {
        let delay = 2;
        let mut sim: Sim<16> = Sim::new(config(4), offset, delay, 11);
        let mut old = sim.slave.poll_report().unwrap();
        sim.reboot();
        run_clean(&mut sim, 0, 100);
        assert_eq!(sim.master.status(0).unwrap().boot, 2);
        // The master is re-initialised; the first report it hears is the earlier start's.
        sim.master.reinit(0).unwrap();
        old.hello = false;
        old.consumed = offset as u16;
        old.received = offset as u16;
        sim.master.on_report(100, 0, &old).unwrap();
        assert_eq!(sim.master.status(0).unwrap().boot, 1);
        run_clean(&mut sim, 100, 200);
        let ctx = format!("offset {offset}");
        let status = sim.master.status(0).unwrap();
        assert!(status.linked && status.boot == 2, "{ctx}: {status:?}");
        // Back within: the board's next report, the offer, the hello, the sync (one round trip
        // each way twice), then the ring covers a row again.
        let bound = 100 + 1 + 4 * delay + 2 + 4 + 16;
        assert!(
            sim.steps[bound as usize..]
                .iter()
                .all(|s| s.out.source == Source::Master),
            "{ctx}: not back on the master's stream by step {bound}"
        );
    }
}
