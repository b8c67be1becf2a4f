//! End-to-end: the `mailbag-sorter` binary's dock comparison (`--docks-only`) and its
//! simulation, in short seeded runs. The whole plant: `mailbag_plant.rs`.

mod common;

use std::process::Command;

use regler_examples::mailbag::{self, Config};
use serde_json::Value;

fn sorter(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_mailbag-sorter"))
        .arg("--docks-only")
        .args(args)
        .output()
        .unwrap()
}

const SHORT: &[&str] = &[
    "--years",
    "0.3",
    "--trolleys-per-year",
    "6000",
    "--quiet",
    "--no-svg",
];

fn short_json_seeded(seed: &str) -> Value {
    let out = sorter(&[SHORT, &["--json", "--seed", seed]].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn short_json() -> Value {
    short_json_seeded("7")
}

#[test]
fn json_run_reports_four_controllers_consistently() {
    let report = short_json();
    let scenarios = report["scenarios"].as_array().unwrap();
    assert_eq!(scenarios.len(), 4);
    let sacks = scenarios[0]["outcomes"]["sacks"].as_u64().unwrap();
    assert!(sacks > 1000);
    for s in scenarios {
        let o = &s["outcomes"];
        assert_eq!(
            o["sacks"].as_u64().unwrap(),
            sacks,
            "same trolleys in every scenario"
        );
        let accounted: u64 = [
            "delivered",
            "misdelivered",
            "rejected",
            "not_tipped",
            "on_chain",
        ]
        .iter()
        .map(|k| o[k].as_u64().unwrap())
        .sum();
        // Every sack is somewhere: no outcome counts one twice or loses one.
        assert_eq!(accounted, sacks, "{o}");
    }
    // Correction keeps the tip position right; without it the error grows with the stretch.
    let err = |i: usize| scenarios[i]["tip_error"]["mean_abs_m"].as_f64().unwrap();
    assert!(
        err(1) < 0.1 && err(3) < 0.1,
        "corrected errors {} {}",
        err(1),
        err(3)
    );
    assert!(err(0) > 3.0 * err(1));
    assert_eq!(report["readers"].as_array().unwrap().len(), 3);
}

#[test]
fn same_seed_same_result_other_seed_other_result() {
    assert_eq!(short_json(), short_json());
    assert_ne!(
        short_json_seeded("8")["scenarios"],
        short_json()["scenarios"]
    );
}

#[test]
fn human_summary_and_svg_picture() {
    let dir = std::env::temp_dir().join(format!("regler-mailbag-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("dock.svg");
    let args = [
        "--years",
        "0.1",
        "--trolleys-per-year",
        "3000",
        "-q",
        "--svg",
        svg.to_str().unwrap(),
    ];
    let out = sorter(&args);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("voting, stretch correction"));
    assert!(text.contains("Reader health"));
    let picture = std::fs::read_to_string(&svg).unwrap();
    assert!(picture.starts_with("<svg") && picture.trim_end().ends_with("</svg>"));
    assert!(picture.contains("Tip-position error"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every refused argument: exit code 2, a message that names the option the user typed (and
/// for a range its bounds), no panic, no Rust debug text, nothing on stdout.
#[test]
fn bad_input_is_refused_naming_the_option() {
    for (args, needles) in [
        (
            &["--years", "-1"][..],
            &["--years", "from 0.01 to 50", "got -1"][..],
        ),
        (&["--years", "1e300"], &["--years", "got 1e300"]),
        (&["--docks", "0"], &["--docks", "from 1 to 8", "got 0"]),
        (
            &["--strategy", "-inf"],
            &["--strategy", "majority, consecutive"],
        ),
        (&["--seed", "-1"], &["--seed", "got -1"]),
        (
            &["--docks", "many"],
            &["--docks", "whole number", "got many"],
        ),
        (&["--misread-rate", "NaN"], &["--misread-rate", "finite"]),
        (
            &["--misread-rate", "0.3"],
            &["--misread-rate", "from 0 to 0.25"],
        ),
        (&["--bins", "500"], &["--bins", "from 2 to 64", "got 500"]),
        (
            &["--chain-m", "20"],
            &["--chain-m", "from 50 to 2000", "got 20"],
        ),
        (
            &["--trolleys-per-year", "0"],
            &["--trolleys-per-year", "from 1 to 1000000"],
        ),
        (
            &["--reader-spread", "2"],
            &["--reader-spread", "from 0 to 1"],
        ),
        (
            &["--glitch-rate", "-0.1"],
            &["--glitch-rate", "from 0 to 1"],
        ),
        (&["--readings", "0"], &["--readings", "from 1 to 50"]),
        (
            &["--reader-alarm-per-mille", "5000"],
            &["--reader-alarm-per-mille", "from 0 to 1000", "got 5000"],
        ),
        (&["--vote-k", "0"], &["--vote-k", "from 1 to 50", "got 0"]),
        (&["--vote-k", "6"], &["--vote-k", "--readings (5)", "got 6"]),
        (
            &["--stretch-m-per-year", "30"],
            &["--stretch-m-per-year", "--chain-m", "got 30"],
        ),
        (
            &["--strategy", "best"],
            &["--strategy", "majority", "consecutive"],
        ),
        (
            &["--no-svg", "--svg", "x.svg"],
            &["--no-picture", "--picture"],
        ),
        (
            &["--svg", "/nonexistent/dir/m.svg"],
            &["cannot write /nonexistent/dir/m.svg", "No such file"],
        ),
    ] {
        // A short run where the row does not set the years itself.
        let short: &[&str] = if args.contains(&"--years") {
            &["-q"]
        } else {
            &["-q", "--years", "0.01"]
        };
        let out = sorter(&[args, short].concat());
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        for needle in needles {
            assert!(err.contains(needle), "{args:?}: no {needle:?} in {err}");
        }
        assert!(!err.contains("panicked"), "{err}");
        assert_no_debug_text(&err);
        assert!(out.stdout.is_empty(), "{args:?}");
    }
}

/// A chain shorter than the 300 m between the reference initiators runs (the initiators sit at
/// ¾ of it) instead of blaming an option that does not exist.
#[test]
fn a_short_chain_runs() {
    let out = sorter(&[
        "--chain-m",
        "200",
        "--years",
        "0.05",
        "-q",
        "--no-svg",
        "--json",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("initiator"), "{err}");
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["config"]["initiator_span_m"].as_f64(), Some(150.0));
    assert!(
        r["scenarios"][3]["tip_error"]["mean_abs_m"]
            .as_f64()
            .unwrap()
            < 0.1,
        "{r}"
    );
}

/// What a user reads never shows Rust's debug formatting.
fn assert_no_debug_text(text: &str) {
    common::assert_no_debug_text("output", text, &["Majority", "Consecutive", "0e0"]);
}

#[test]
fn no_debug_text_reaches_the_user() {
    let dir = std::env::temp_dir().join(format!("regler-mailbag-dbg-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("m.svg");
    for strategy in ["majority", "consecutive"] {
        let args = [
            "--years",
            "0.05",
            "--strategy",
            strategy,
            "--misread-rate",
            "0",
            "-q",
            "--svg",
            svg.to_str().unwrap(),
        ];
        let out = sorter(&args);
        assert!(out.status.success());
        let text = String::from_utf8(out.stdout).unwrap();
        assert_no_debug_text(&text);
        assert_no_debug_text(&std::fs::read_to_string(&svg).unwrap());
        let out = sorter(&[&args[..], &["--json"]].concat());
        assert_no_debug_text(&String::from_utf8(out.stdout).unwrap());
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `| head -1` in every output mode (`mailbag-sorter --json --no-svg -q | head -1` panicked
/// about one run in three): the program ends quietly, exit 0 and nothing on stderr, whether the
/// reader closes before the first write (the write fails at once, every time) or after the first
/// line.
#[test]
fn a_closed_pipe_ends_quietly() {
    let dir = std::env::temp_dir().join(format!("regler-mailbag-pipe-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("m.svg");
    let svg = svg.to_str().unwrap();
    for mode in [
        &["--no-svg"][..],
        &["--svg", svg],
        &["--json", "--no-svg"],
        &["--json", "--svg", svg],
    ] {
        for close in [common::Close::AtOnce, common::Close::AfterALine] {
            common::closes_quietly(
                env!("CARGO_BIN_EXE_mailbag-sorter"),
                &[&["--docks-only", "--years", "0.05", "-q"], mode].concat(),
                b"",
                close,
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn help_explains_the_options() {
    let out = sorter(&["--help"]);
    assert!(out.status.success());
    let help = String::from_utf8(out.stdout).unwrap();
    for option in ["--seed", "--years", "--json", "--svg", "--misread-rate"] {
        assert!(help.contains(option), "{option}");
    }
}

/// The point of voting: at a high misread rate, far fewer sacks go to the wrong bin.
#[test]
fn voting_cuts_misdeliveries_by_orders_of_magnitude() {
    let config = Config {
        years: 0.5,
        trolleys_per_year: 20_000,
        misread_rate: 0.02,
        seed: 3,
        ..Config::default()
    };
    let report = mailbag::run(&config, |_| {}).unwrap();
    let parity = report.scenarios[1].outcomes.misdelivered;
    let voting = report.scenarios[3].outcomes.misdelivered;
    assert!(parity >= 100, "parity only misdelivered {parity}");
    assert!(voting * 30 <= parity, "voting {voting} vs parity {parity}");
    assert!(report.scenarios[3].outcomes.rejected < report.scenarios[1].outcomes.rejected);
}

/// Reader health finds the bad reader at the plant's own misread rate: the worst reader's alarm
/// goes on, the best reader's never does.
#[test]
fn reader_health_finds_the_worst_reader() {
    let config = Config {
        years: 1.0,
        seed: 5,
        ..Config::default()
    };
    let report = mailbag::run(&config, |_| {}).unwrap();
    let alarms: Vec<u32> = report.readers.iter().map(|r| r.alarms_raised).collect();
    assert_eq!(alarms[0], 0, "{alarms:?}");
    assert!(
        alarms[2] > alarms[0] && alarms[2] >= alarms[1],
        "{alarms:?}"
    );
}

/// A chain that stretches past 10 % (the stretch meter's old plausibility window around SIA):
/// the meter follows it, and the corrected runs keep their tip position.
#[test]
fn the_meter_follows_a_chain_stretched_past_ten_per_cent() {
    let out = sorter(&[
        "--years",
        "3",
        "--stretch-m-per-year",
        "20",
        "--trolleys-per-year",
        "5000",
        "--quiet",
        "--no-svg",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["stretch"]["actual_per_mille"].as_f64(), Some(150.0));
    assert_eq!(r["stretch"]["measured_per_mille"].as_i64(), Some(150));
    let err = |i: usize| {
        r["scenarios"][i]["tip_error"]["mean_abs_m"]
            .as_f64()
            .unwrap()
    };
    assert!(err(3) < 0.25 && err(2) > 10.0, "{} {}", err(3), err(2));
}
