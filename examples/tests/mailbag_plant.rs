//! End-to-end and property tests of the whole plant (`mailbag-sorter` without `--docks-only`,
//! and `regler_examples::mailbag::plant` directly).

mod common;

use std::process::Command;

use proptest::prelude::*;
use regler_examples::mailbag::plant::faults::{Fault, FaultKind};
use regler_examples::mailbag::plant::operator::{Immediate, PanelId};
use regler_examples::mailbag::plant::{self, Config, Reading, run::run_one};
use serde_json::Value;

fn sorter(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_mailbag-sorter"))
        .args(args)
        .output()
        .unwrap()
}

const EVERY_FAULT: [&str; 8] = [
    "--fault=misread@00:05:00:R5:0.02",
    "--fault=reader-fails@00:20:00:R8",
    "--fault=noise@00:02:00:P1:0.001",
    "--fault=stuck@00:10:00:full-E3:1:300",
    "--fault=chatter@00:10:00:waiting-D1:300",
    "--fault=power@00:25:00:30",
    "--fault=hang@00:35:00:5",
    "--fault=pulses@00:40:00:2:0.05:300",
];

#[test]
fn a_short_run_with_every_fault_keeps_every_sack() {
    let args = [
        &[
            "--hours",
            "1",
            "--traffic",
            "4",
            "--seed",
            "5",
            "--quiet",
            "--json",
        ][..],
        &EVERY_FAULT,
    ]
    .concat();
    let out = sorter(&args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let text = String::from_utf8(out.stdout).unwrap();
    common::assert_no_debug_text("json", &text, &[]);
    let v: Value = serde_json::from_str(&text).unwrap();
    for key in [
        "simulated_hours",
        "sacks_loaded",
        "sacks_delivered",
        "sacks_misdelivered",
        "sacks_rejected",
        "sacks_in_plant",
        "misdelivered_per_million",
        "watchdog_trips",
        "power_failures",
        "panel_bytes_corrupted",
        "panel_displays_wrong_after_next_sequence",
        "cpu_load_percent_mean",
        "realtime_ratio",
    ] {
        assert!(v.get(key).is_some(), "{key} missing");
    }
    assert!(v["misdelivered_per_million"]["parity_only"].is_number());
    assert!(v["misdelivered_per_million"]["voting"].is_number());
    let n = |k: &str| v[k].as_u64().unwrap();
    assert!(n("sacks_loaded") > 100, "{}", n("sacks_loaded"));
    assert_eq!(
        n("sacks_delivered") + n("sacks_misdelivered") + n("sacks_rejected") + n("sacks_in_plant"),
        n("sacks_loaded")
    );
    assert_eq!(n("watchdog_trips"), 1);
    assert_eq!(n("power_failures"), 1);
    // The watchdog took the outputs safe within 100 ms of the hang.
    let safe = v["runs"][1]["watchdog_safe_ms"].as_u64().unwrap();
    assert!(safe > 0 && safe <= 100, "{safe} ms");
    for run in v["runs"].as_array().unwrap() {
        let m = |k: &str| run[k].as_u64().unwrap();
        assert_eq!(
            m("sacks_delivered")
                + m("sacks_misdelivered")
                + m("sacks_rejected")
                + m("sacks_in_plant"),
            m("sacks_loaded")
        );
    }
}

#[test]
fn the_summary_names_both_readings_and_shows_no_debug_text() {
    let out = sorter(&["--hours", "0.5", "--quiet", "--fault", "hang@00:10:00:2"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("parity only") && text.contains("voting"),
        "{text}"
    );
    common::assert_no_debug_text("summary", &text, &["ParityOnly", "Voting,"]);
}

#[test]
fn bad_arguments_are_refused_naming_the_option() {
    let script = std::env::temp_dir().join(format!("regler-plant-{}.script", std::process::id()));
    std::fs::write(&script, "06:00 P1 type 3\n06:01 P1 type 99\n").unwrap();
    let script = script.to_str().unwrap();
    for (args, needles) in [
        (&["--hours", "0"][..], &["--hours", "got 0"][..]),
        (&["--fault", "nonsense"], &["--fault", "nonsense"]),
        (
            &["--fault", "misread@01:00:00:R13:0.1"],
            &["--fault", "R13"],
        ),
        (&["--fault", "power@25:99:00:10"], &["--fault", "time"]),
        (&["--script", script], &["--script", "line 2", "post type"]),
        (
            &["--script", "/nonexistent/script"],
            &["--script", "/nonexistent/script"],
        ),
        (&["--years", "1"], &["--years", "--docks-only"]),
        (
            &["--docks-only", "--hours", "2"],
            &["--hours", "--docks-only"],
        ),
    ] {
        let out = sorter(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        for needle in needles {
            assert!(err.contains(needle), "{args:?}: {needle} not in {err}");
        }
        common::assert_no_debug_text("stderr", &err, &[]);
    }
    std::fs::remove_file(script).ok();
}

#[test]
fn a_closed_pipe_ends_quietly() {
    for mode in [
        &["--hours", "0.2", "-q"][..],
        &["--hours", "0.2", "-q", "--json"],
    ] {
        for close in [common::Close::AtOnce, common::Close::AfterALine] {
            common::closes_quietly(env!("CARGO_BIN_EXE_mailbag-sorter"), mode, b"", close);
        }
    }
}

fn fault_strategy() -> impl Strategy<Value = Fault> {
    let at = 0u64..12 * 60_000;
    prop_oneof![
        (at.clone(), 0usize..12, 0.0..0.2f64).prop_map(|(at_ms, reader, rate)| Fault {
            at_ms,
            kind: FaultKind::Misread { reader, rate }
        }),
        (at.clone(), 0usize..12).prop_map(|(at_ms, reader)| Fault {
            at_ms,
            kind: FaultKind::ReaderFails { reader }
        }),
        (at.clone(), 0usize..6, 0.0..0.01f64).prop_map(|(at_ms, p, rate)| Fault {
            at_ms,
            kind: FaultKind::Noise {
                panel: PanelId::ALL[p],
                rate
            }
        }),
        (at.clone(), 0usize..544, any::<bool>(), 0u64..300).prop_map(|(at_ms, point, on, secs)| {
            Fault {
                at_ms,
                kind: FaultKind::Stuck { point, on, secs },
            }
        }),
        (at.clone(), 0usize..544, 1u64..300).prop_map(|(at_ms, point, secs)| Fault {
            at_ms,
            kind: FaultKind::Chatter { point, secs }
        }),
        (at.clone(), 1u64..120).prop_map(|(at_ms, secs)| Fault {
            at_ms,
            kind: FaultKind::Power { secs }
        }),
        (at.clone(), 1u64..30).prop_map(|(at_ms, secs)| Fault {
            at_ms,
            kind: FaultKind::Hang { secs }
        }),
        (at, 0usize..3, 0.0..0.5f64, 0u64..300).prop_map(|(at_ms, dock, rate, secs)| Fault {
            at_ms,
            kind: FaultKind::MissedPulses { dock, rate, secs }
        }),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// Under any schedule of faults, every loaded sack is delivered, misdelivered, rejected or
    /// still in the plant: checked every simulated minute inside the run (an error names the
    /// minute) and at its end.
    #[test]
    fn no_sack_is_ever_lost_under_any_faults(
        faults in proptest::collection::vec(fault_strategy(), 0..6),
        seed in any::<u64>(),
        voting in any::<bool>(),
    ) {
        let mut faults = faults;
        faults.sort_by_key(|f| f.at_ms);
        let config = Config { seed, hours: 0.25, traffic: 8.0, faults: faults.clone(), ..Config::default() };
        let (sacks, keyed) = config.traffic();
        let reading = if voting { Reading::Voting } else { Reading::ParityOnly };
        let mut desks = Immediate::default();
        let r = run_one(&config, reading, &mut desks, &sacks, &keyed, &faults, &|_| {});
        let r = r.map_err(TestCaseError::fail)?;
        let c = &r.counts;
        let loaded: u64 = c.loaded.iter().sum();
        prop_assert!(loaded > 0);
        prop_assert_eq!(c.delivered + c.misdelivered + c.rejected + r.in_plant, loaded);
    }
}

/// The point of voting, at plant level: at the source's 1 in 1000 misreads, on the same seed
/// and traffic, voting misdelivers at least 100 times fewer sacks than parity alone. Needs
/// some 80 000 sacks to see parity's misdeliveries at all (about 100 per million): release-sized
/// (about 20 s on two free cores), so run it with
/// `cargo test --release -p regler-examples --test mailbag_plant -- --ignored`.
#[test]
#[ignore = "release-sized (about 20 s in release): run with --release -- --ignored"]
fn voting_misdelivers_at_least_100_times_fewer_sacks_than_parity_alone() {
    let config = Config {
        seed: 21,
        hours: 48.0,
        traffic: 3.0,
        trolleys: 1500,
        ..Config::default()
    };
    let report = plant::run(&config, Immediate::default, &|_| {}).unwrap();
    let per_million = report.misdelivered_per_million;
    let [parity, voting] = &report.runs;
    assert!(parity.sacks_loaded > 60_000, "{}", parity.sacks_loaded);
    assert!(
        parity.sacks_misdelivered >= 5,
        "too few to compare: {}",
        parity.sacks_misdelivered
    );
    assert!(
        voting.sacks_misdelivered as f64 * 100.0 <= parity.sacks_misdelivered as f64,
        "parity {} per million, voting {} per million",
        per_million.parity_only,
        per_million.voting
    );
}

fn quiet_run(faults: Vec<Fault>) -> plant::RunResult {
    let config = Config {
        seed: 3,
        hours: 0.5,
        traffic: 4.0,
        faults: faults.clone(),
        ..Config::default()
    };
    let (sacks, keyed) = config.traffic();
    let mut desks = Immediate::default();
    run_one(
        &config,
        Reading::Voting,
        &mut desks,
        &sacks,
        &keyed,
        &faults,
        &|_| {},
    )
    .unwrap()
}

/// A photocell that chatters for ten minutes changes nothing: its debounce (3 equal readings)
/// holds the value it had, so the run is the run without the fault, sack for sack.
#[test]
fn debounce_holds_a_chattering_photocell() {
    let clean = quiet_run(Vec::new());
    let point = plant::layout::input_point("full-A1").unwrap();
    let chatter = quiet_run(vec![Fault {
        at_ms: 300_000,
        kind: FaultKind::Chatter { point, secs: 600 },
    }]);
    assert_eq!(clean.counts.loaded, chatter.counts.loaded);
    assert_eq!(clean.counts.delivered, chatter.counts.delivered);
    assert_eq!(clean.counts.lane_out, chatter.counts.lane_out);
    assert_eq!(clean.counts.passed, chatter.counts.passed);
}

/// A power failure stops the plant with the outputs safe; on return the trackers come back from
/// their snapshots and the program resumes where it stopped: nothing is lost or misdelivered,
/// and the sorted post on the chains is still tipped into its bins.
#[test]
fn a_power_failure_loses_nothing() {
    let r = quiet_run(vec![Fault {
        at_ms: 600_000,
        kind: FaultKind::Power { secs: 90 },
    }]);
    assert_eq!(r.power_failures, 1);
    assert_eq!(r.counts.misdelivered, 0);
    assert!(r.counts.delivered_sorted > 0);
    let loaded: u64 = r.counts.loaded.iter().sum();
    assert_eq!(r.counts.delivered + r.counts.rejected + r.in_plant, loaded);
}

/// A script that replaces the seeded traffic: three sacks keyed, then a schedule override
/// under which the fourth sack's postcode has no bin (refused, never loaded). All three reach
/// their right destination within half an hour.
#[test]
fn a_script_replaces_the_seeded_traffic() {
    let script =
        std::env::temp_dir().join(format!("regler-plant-ok-{}.script", std::process::id()));
    std::fs::write(
        &script,
        "replace\n# three sacks\n00:01 P1 type 3\n00:02 P2 postcode 20000\n00:03:30 P3 type 12\n\
         00:04 central schedule 2\n00:06 P1 postcode 20000\n",
    )
    .unwrap();
    let out = sorter(&[
        "--hours",
        "0.5",
        "--quiet",
        "--json",
        "--script",
        script.to_str().unwrap(),
    ]);
    std::fs::remove_file(&script).ok();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    for run in v["runs"].as_array().unwrap() {
        assert_eq!(run["sacks_loaded"], 3, "{run}");
        assert_eq!(run["sacks_delivered"], 3, "{run}");
        assert_eq!(run["entries_refused"], 1, "{run}");
    }
}
