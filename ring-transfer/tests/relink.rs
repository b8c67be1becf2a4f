//! A stand-alone slave whose master answers again is linked again within
//! `retry_after + 4·d + row_len + 1` steps, for every configuration `Slave::new` accepts (small
//! ranges of every field) and link delays `d` of 1–4 steps. (Outages that cut the link both ways
//! and eat refills the master counted as sent, where the second round trip of the bound is
//! needed: `tests/attack_fixes.rs::relink_within_four_delays_when_the_outage_eats_refills`.)
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
use regler_ring_transfer::{Mode, SlaveConfig};

/// Runs a board through a master outage long enough to put it stand-alone, starting at the
/// first step from `start` on at which the board is linked; returns the step at which it was
/// linked again, counted from the end of the outage.
fn outage<const N: usize>(config: SlaveConfig, delay: u64, start: u64, jitter: (u8, u64)) -> u64 {
    let mut sim: Sim<N> = Sim::new(config, 0, delay, u64::from(config.retry_after) << 8 | start);
    sim.down.late = jitter.0;
    sim.down.jitter = jitter.1;
    sim.up.late = jitter.0;
    sim.up.jitter = jitter.1;
    let ctx = format!("ring {N}, {config:?}, delay {delay}, outage from {start}");
    let row = u64::from(config.row_len);
    let length = u64::from(config.silence_limit) + N as u64 + 2 * row + 2 * delay + 20;
    let bound = u64::from(config.retry_after) + 4 * (delay + jitter.1) + row + 1;
    // A faulty link may itself put the board stand-alone before the outage (frames later than
    // the silence limit, a ring shorter than the late refills need): the outage then starts at
    // the first step from `start` on at which the board is linked, and it must get there.
    let mut now = 0;
    while now < start || sim.slave.mode() != Mode::Linked {
        sim.faulty = jitter.0 > 0;
        sim.step(now);
        now += 1;
        assert!(
            now <= start + 8 * (bound + length),
            "{ctx}: never linked before the outage"
        );
    }
    let start = now;
    let end = start + length;
    let entries_before;
    loop {
        if now == start {
            assert_eq!(
                sim.slave.mode(),
                Mode::Linked,
                "{ctx}: linked before the outage"
            );
            sim.master_up = false;
        }
        if now == end {
            sim.master_up = true;
            sim.faulty = false;
        }
        sim.faulty = now < end && jitter.0 > 0;
        sim.step(now);
        if now == end {
            entries_before = sim.slave.stats().standalone_entries;
            assert!(entries_before > 0, "{ctx}: the outage put it stand-alone");
            assert_eq!(sim.slave.mode(), Mode::StandAlone, "{ctx}");
            break;
        }
        now += 1;
    }
    loop {
        now += 1;
        sim.step(now);
        if sim.slave.mode() == Mode::Linked {
            break;
        }
        assert!(
            now - end <= bound,
            "{ctx}: still stand-alone {} steps after the master came back",
            now - end
        );
    }
    sim.check_items();
    now - end
}

fn configs() -> impl Iterator<Item = SlaveConfig> {
    (1..=10u16).flat_map(|row_len| {
        (1..=10u32).flat_map(move |retry_after| {
            (1..=12u32).map(move |silence_limit| SlaveConfig {
                address: common::ADDRESS,
                row_len,
                silence_limit,
                retry_after,
                boot: 1,
            })
        })
    })
}

/// Every configuration in the ranges (row 1–10, retry 1–10, silence limit 1–12: every order
/// of the three, the row 10 / retry 10 / silence 2–6 among them), delays 1–4 with a
/// ring of 16 slots, and rings of 1 and 4 slots (shorter than most rows) with a delay of 1
/// (a ring shorter than the round trip underruns whatever the configuration): relinked
/// within the bound after every outage.
#[test]
#[cfg_attr(
    miri,
    ignore = "every configuration and delay after an outage (1 200 simulated runs): hours under Miri, a simulated ring steps in tens of milliseconds under Miri; runs natively in every CI run"
)]
fn every_configuration_relinks_after_an_outage() {
    let mut worst = 0;
    for (k, config) in configs().enumerate() {
        for delay in 1..=4 {
            let start = 40 + (k as u64 * 7 + delay) % 23;
            worst = worst.max(outage::<16>(config, delay, start, (0, 0)));
            if delay == 1 {
                worst = worst.max(outage::<4>(config, delay, start, (0, 0)));
                worst = worst.max(outage::<1>(config, delay, start, (0, 0)));
            }
        }
    }
    assert!(worst > 0);
}

/// The case CI's random draw found (ring 32 shorter than a row of 34–36, silence limit 3,
/// delay 2, frames late by up to 3 more steps): the faulty link itself put the board
/// stand-alone before the outage began (88 of these 1 200 runs), which the harness took for a
/// failure. Every chance of a late frame and every jitter: the outage starts once the board is
/// linked, and it relinks within the bound.
#[test]
#[cfg_attr(
    miri,
    ignore = "a simulated run of the ring on a faulty link: minutes under Miri, a simulated ring steps in tens of milliseconds under Miri; runs natively in every CI run"
)]
fn a_board_the_faulty_link_put_stand_alone_before_the_outage() {
    for row_len in [34, 36] {
        for late in 0..200 {
            for jitter in 1..4 {
                let config = SlaveConfig {
                    address: common::ADDRESS,
                    row_len,
                    silence_limit: 3,
                    retry_after: 36,
                    boot: 1,
                };
                outage::<32>(config, 2, 90, (late, jitter));
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 4 } else { 256 }))]

    /// Any configuration (wider ranges), any moment of the outage, frames late by up to a few
    /// more steps before the master comes back.
    #[test]
    #[cfg_attr(miri, ignore = "simulated runs of the ring with late frames per case: minutes under Miri, a simulated ring steps in tens of milliseconds under Miri; runs natively in every CI run")]
    fn relinks_with_late_frames(
        row_len in 1u16..40,
        retry_after in 1u32..40,
        silence_limit in 1u32..60,
        delay in 1u64..5,
        start in 40u64..120,
        late in 0u8..200,
        jitter in 0u64..4,
    ) {
        let config = SlaveConfig { address: common::ADDRESS, row_len, silence_limit, retry_after, boot: 1 };
        outage::<32>(config, delay, start, (late, jitter));
    }
}
