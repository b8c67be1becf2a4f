//! End-to-end: the `mailbag-sorter` binary and its simulation, in short seeded runs.

use std::process::Command;

use regler_examples::mailbag::{self, Config};
use serde_json::Value;

fn sorter(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_mailbag-sorter"))
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

#[test]
fn bad_input_is_a_clear_message_not_a_panic() {
    for (args, needle) in [
        (&["--years", "-1"][..], "years"),
        (&["--docks", "0"][..], "docks"),
        (&["--misread-rate", "NaN"][..], "misread-rate"),
        (&["--bins", "500"][..], "bins"),
        (
            &["--vote-k", "0"][..],
            "vote-k must be between 1 and readings (5), got 0",
        ),
        (
            &["--vote-k", "6"][..],
            "vote-k must be between 1 and readings (5), got 6",
        ),
        (&["--docks", "many"][..], "invalid value"),
    ] {
        let out = sorter(&[args, &["--no-svg", "-q"]].concat());
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
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
