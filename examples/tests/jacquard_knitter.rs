//! End-to-end: the `jacquard-knitter` binary in memory, with faults, with operator keys, over
//! real UDP sockets, and at a real terminal.

use std::process::Command;

use serde_json::Value;

fn knitter(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_jacquard-knitter"))
        .args(args)
        .output()
        .unwrap()
}

fn json(args: &[&str]) -> Value {
    let out = knitter(&[args, &["--json", "--no-picture"]].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn machines(r: &Value) -> &Vec<Value> {
    r["machines"].as_array().unwrap()
}

fn total(r: &Value, field: &str) -> u64 {
    machines(r).iter().map(|m| m[field].as_u64().unwrap()).sum()
}

/// Every byte the machines took from the master was the right one, in order.
fn pattern_intact(r: &Value) {
    assert_eq!(total(r, "wrong_items"), 0, "{r}");
    assert_eq!(total(r, "rows_out_of_order"), 0, "{r}");
}

fn temp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("regler-jk-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn eight_machines_knit_without_underrun_while_schedulable() {
    let r = json(&["--seconds", "10"]);
    assert_eq!(r["capacity"]["schedulable"], true);
    assert_eq!(machines(&r).len(), 8);
    assert_eq!(total(&r, "underruns"), 0);
    assert_eq!(total(&r, "missed_deadlines"), 0);
    pattern_intact(&r);
    for m in machines(&r) {
        let rpm = m["rpm"].as_u64().unwrap();
        assert!((120..=140).contains(&rpm));
        // 10 s at rpm/60 rows per second, less the 100 ms start.
        let rows = m["rows"].as_u64().unwrap();
        assert!(rows + 1 >= rpm * 10 / 60 && rows <= rpm * 10 / 60, "{m}");
        assert_eq!(m["master_rows"], m["rows"]);
    }
}

#[test]
fn a_silent_master_and_a_lossy_link_leave_whole_rows() {
    let png = temp("fault.png");
    let out = knitter(&[
        "--seconds",
        "20",
        "--master-fault",
        "5:5",
        "--loss",
        "0.02",
        "--duplicate",
        "0.02",
        "--json",
        "--png",
        png.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    pattern_intact(&r);
    assert_eq!(total(&r, "underruns"), 0);
    assert!(r["frames_lost"].as_u64().unwrap() > 0 && r["frames_duplicated"].as_u64().unwrap() > 0);
    for m in machines(&r) {
        // About 5 s stand-alone (less the ring's half second and the silence limit).
        let s = m["standalone_s"].as_f64().unwrap();
        assert!((4.0..5.5).contains(&s), "{m}");
        assert_eq!(m["standalone_entries"], 1);
        assert!(m["local_rows"].as_u64().unwrap() >= 8);
        // At most the one row the failure cut short is patched.
        assert!(m["patched_rows"].as_u64().unwrap() <= 1, "{m}");
        assert_eq!(m["linked"], true);
        assert!(m["duplicates_dropped"].as_u64().unwrap() > 0);
    }
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
}

#[test]
fn an_overloaded_link_is_called_so_and_falls_short() {
    // 30 machines on a link of 80 µs per byte: 30 × 10 × 80 µs = 24 ms of link per 2.3 ms.
    // A new board knits its local pattern until its ring covers a row (30 × 200 items at
    // 0.8 ms: about 5 s); then the link cannot keep up: grants come late, and every machine
    // knits most of its rows from its local pattern (or patched after underruns).
    let r = json(&["--seconds", "8", "--machines", "30", "--byte-ns", "80000"]);
    assert_eq!(r["capacity"]["schedulable"], false);
    assert!(total(&r, "missed_deadlines") > 0);
    for m in machines(&r) {
        let rows = m["rows"].as_u64().unwrap();
        let master = m["master_rows"].as_u64().unwrap();
        assert!(master * 2 < rows, "{m}");
    }
    pattern_intact(&r);
}

#[test]
fn the_same_seed_knits_the_same() {
    let a = json(&[
        "--seconds",
        "3",
        "--loss",
        "0.05",
        "--duplicate",
        "0.05",
        "--seed",
        "7",
    ]);
    let b = json(&[
        "--seconds",
        "3",
        "--loss",
        "0.05",
        "--duplicate",
        "0.05",
        "--seed",
        "7",
    ]);
    assert_eq!(a, b);
    let c = json(&[
        "--seconds",
        "3",
        "--loss",
        "0.05",
        "--duplicate",
        "0.05",
        "--seed",
        "8",
    ]);
    assert_ne!(a["frames_lost"], c["frames_lost"]);
}

#[test]
fn operator_keys_from_a_script() {
    let script = temp("keys.txt");
    std::fs::write(
        &script,
        "# time key\n1 T\n2 C 3 7\n2.5 F\n3 S\n4 2\n5 shift 4\n6 L\n6.5 S\n7 O\n8 P\n12 break\n",
    )
    .unwrap();
    let r = json(&["--seconds", "30", "--script", script.to_str().unwrap()]);
    let screen: Vec<&str> = r["screen"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_str().unwrap())
        .collect();
    let has = |needle: &str| screen.iter().any(|l| l.contains(needle));
    assert!(has("capacity: Schedulable"), "{screen:?}");
    assert!(has("machine 3: job 7 after the current one"));
    assert!(has("jobs   3: job 2 now, next 7"), "{screen:?}");
    assert!(has("flow   1: Linked"));
    assert!(has("machine 2: 1"), "the status line of machine 2");
    assert!(has("machine 4: interface re-initialised"));
    assert!(
        has("keyboard locked (O opens it)"),
        "S while locked is refused"
    );
    assert!(has("keyboard open"));
    assert!(has("pattern check: 0 wrong bytes"));
    assert!(has("break: back to the scheduler"));
    // Break at 12 s ends the run early.
    let rows = machines(&r)[0]["rows"].as_u64().unwrap();
    assert!(rows < 30, "{rows}");
    pattern_intact(&r);
    assert_eq!(total(&r, "underruns"), 0);
}

#[test]
fn bad_arguments_are_named() {
    for (args, needle) in [
        (
            vec!["--machines", "0"],
            "machines must be between 1 and 100",
        ),
        (vec!["--loss", "0.9"], "loss must be a probability"),
        (vec!["--master-fault", "5"], "START:SECONDS"),
        (
            vec!["--transport", "udp", "--interactive"],
            "without a keyboard",
        ),
    ] {
        let out = knitter(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

#[test]
fn eight_machines_over_udp_lose_no_row() {
    // Real datagrams on 127.0.0.1 through a filter that loses and duplicates 5 % of them.
    let r = json(&[
        "--transport",
        "udp",
        "--seconds",
        "3",
        "--loss",
        "0.05",
        "--duplicate",
        "0.05",
    ]);
    assert_eq!(r["transport"], "udp 127.0.0.1");
    pattern_intact(&r);
    assert_eq!(total(&r, "underruns"), 0);
    assert!(r["frames_lost"].as_u64().unwrap() > 0);
    assert!(r["frames_duplicated"].as_u64().unwrap() > 0);
    for m in machines(&r) {
        assert!(m["master_rows"].as_u64().unwrap() >= 4, "{m}");
        assert_eq!(m["patched_rows"], 0);
    }
}

/// At a terminal: keys answered as they are typed (run by `.ci/run`, which installs tmux).
#[test]
#[ignore = "needs tmux"]
fn interactive_under_tmux_answers_each_key() {
    use std::time::{Duration, Instant};
    let session = format!("regler-jk-{}", std::process::id());
    let tmux = |args: &[&str]| {
        let out = Command::new("tmux").args(args).output().unwrap();
        String::from_utf8_lossy(&out.stdout).to_string()
    };
    let program = format!(
        "{} --interactive --seconds 60 --no-picture --machines 3",
        env!("CARGO_BIN_EXE_jacquard-knitter")
    );
    tmux(&[
        "new-session",
        "-d",
        "-s",
        &session,
        "-x",
        "160",
        "-y",
        "50",
        &program,
    ]);
    tmux(&["set-option", "-t", &session, "remain-on-exit", "on"]);
    let screen = || tmux(&["capture-pane", "-p", "-S", "-200", "-t", &session]);
    let wait_for = |needle: &str| {
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(10) {
            if screen().contains(needle) {
                return true;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        false
    };
    assert!(wait_for("keys: L lock"), "{}", screen());
    // Single keys, no Enter: each is answered at once. A board runs stand-alone until the
    // master has placed it and its ring covers a row, so ask for the flow until machine 3 is
    // linked.
    let start = Instant::now();
    let mut linked = false;
    while !linked && start.elapsed() < Duration::from_secs(10) {
        tmux(&["send-keys", "-t", &session, "s"]);
        std::thread::sleep(Duration::from_millis(300));
        linked = screen().contains("flow   3: Linked");
    }
    assert!(linked, "{}", screen());
    tmux(&["send-keys", "-t", &session, "2"]);
    assert!(wait_for("machine 2: 1"), "{}", screen());
    tmux(&["send-keys", "-t", &session, "!"]);
    assert!(
        wait_for("machine 1: interface re-initialised"),
        "{}",
        screen()
    );
    tmux(&["send-keys", "-t", &session, "c", "3", "5"]);
    assert!(
        wait_for("machine 3: job 5 after the current one"),
        "{}",
        screen()
    );
    tmux(&["send-keys", "-t", &session, "l", "t"]);
    assert!(wait_for("keyboard locked (O opens it)"), "{}", screen());
    tmux(&["send-keys", "-t", &session, "o", "b"]);
    assert!(wait_for("pattern check: 0 wrong bytes"), "{}", screen());
    tmux(&["kill-session", "-t", &session]);
}

/// Every silence the knitter accepts is one its boards accept (the counters cannot drift half
/// their range in an outage), and the largest is accepted: 32 767 − needles − 256.
#[test]
fn silence_is_capped_by_the_counter_drift() {
    use regler_examples::knitter::{Board, Config, RING};
    for needles in [8u16, 200, 1000] {
        let max = 32_767 - u32::from(needles) - RING as u32;
        for silence in [1, max, max + 1, 100_000] {
            let config = Config {
                needles,
                silence_needles: silence,
                ..Config::default()
            };
            let accepted = config.validate().is_ok();
            assert_eq!(
                accepted,
                silence <= max,
                "needles {needles} silence {silence}"
            );
            assert_eq!(
                Board::new(0, 130, &config).is_ok(),
                accepted,
                "needles {needles} silence {silence}: the board agrees"
            );
        }
    }
    let out = knitter(&["--silence", "100000", "--no-picture"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("silence must be 1..=32311"));
}

/// Consecutive starts of a machine never share a boot number, for any seed and machine.
#[test]
fn consecutive_starts_get_different_boot_numbers() {
    use regler_examples::knitter::boot_number;
    for seed in [0u64, 1, 1981, u64::MAX] {
        for machine in 0..100 {
            for start in 0..600u32 {
                assert_ne!(
                    boot_number(seed, machine, start),
                    boot_number(seed, machine, start + 1),
                    "seed {seed} machine {machine} start {start}"
                );
            }
        }
    }
}
