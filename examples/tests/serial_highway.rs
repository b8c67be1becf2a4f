//! End-to-end: the `serial-highway` binary on a simulated noisy loop, and over a real
//! pseudo-terminal pair made by `socat`.

mod common;

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

fn highway(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_serial-highway"))
        .args(args)
        .output()
        .unwrap()
}

fn json(args: &[&str]) -> Value {
    let out = highway(&[args, &["--json", "--no-svg"]].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn a_noisy_loop_of_62_crates_detects_every_error() {
    let r = json(&["--messages", "20000", "--seed", "3"]);
    assert_eq!(r["completed"], 20000, "{r}");
    assert_eq!(r["undetected_errors"], 0, "{r}");
    // The noise did bite, and was caught at the crates and at the driver.
    assert!(r["bits_flipped"].as_u64().unwrap() > 50, "{r}");
    assert!(r["detected_at_crates"].as_u64().unwrap() > 0, "{r}");
    assert!(r["garbled_at_driver"].as_u64().unwrap() > 0, "{r}");
    assert!(r["retries"].as_u64().unwrap() > 0, "{r}");
    // Counters raised LAMs; every demand was served.
    assert!(r["demands"].as_u64().unwrap() > 0, "{r}");
    let crates = r["crates"].as_array().unwrap();
    assert_eq!(crates.len(), 62);
    let sum = |f: &str| crates.iter().map(|c| c[f].as_u64().unwrap()).sum::<u64>();
    assert_eq!(sum("replies"), 20000);
    assert!(sum("demands_served") > 0);
    // Throughput: a 13-byte command per 14 clocks at best, at 5 MHz.
    let rate = r["messages_per_s_byte_serial"].as_f64().unwrap();
    assert!(rate > 100_000.0 && rate < 5e6 / 13.0, "{rate}");
}

#[test]
fn bit_serial_line_and_a_small_loop() {
    let r = json(&[
        "--messages",
        "5000",
        "--crates",
        "5",
        "--line",
        "bit-serial",
        "--ber",
        "1e-4",
    ]);
    assert_eq!(r["completed"], 5000, "{r}");
    assert_eq!(r["undetected_errors"], 0, "{r}");
    assert_eq!(r["config"]["line"], "bit-serial");
    let byte = r["messages_per_s_byte_serial"].as_f64().unwrap();
    let bit = r["messages_per_s_bit_serial"].as_f64().unwrap();
    assert!(
        (byte / bit - 10.0).abs() < 1e-6,
        "10 bits per byte: {byte} vs {bit}"
    );
}

#[test]
fn a_seed_gives_the_same_run() {
    let a = json(&["--messages", "3000", "--seed", "9", "--ber", "1e-4"]);
    let b = json(&["--messages", "3000", "--seed", "9", "--ber", "1e-4"]);
    assert_eq!(a, b);
    let c = json(&["--messages", "3000", "--seed", "10", "--ber", "1e-4"]);
    assert_ne!(a["bits_flipped"], c["bits_flipped"]);
}

#[test]
fn human_summary_and_picture() {
    let dir = std::env::temp_dir().join(format!("regler-sh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("highway.svg");
    let out = highway(&[
        "--messages",
        "2000",
        "--crates",
        "10",
        "--quiet",
        "--svg",
        svg.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("undetected errors: 0"), "{text}");
    assert!(text.contains("commands/s at 5 MHz byte-serial"), "{text}");
    let picture = std::fs::read_to_string(&svg).unwrap();
    assert!(picture.contains("</svg>") && picture.contains("retries"));
    std::fs::remove_dir_all(&dir).ok();
}

/// Every refused argument: exit code 2, a message that names the option (and for a range its
/// bounds), no panic, no Rust debug text.
#[test]
fn bad_arguments_are_refused_naming_the_option() {
    for (args, needles) in [
        (
            &["--crates", "0"][..],
            &["--crates", "from 1 to 62", "got 0"][..],
        ),
        (&["--crates", "63"], &["--crates", "from 1 to 62"]),
        (&["--crates", "-3"], &["--crates", "from 1 to 62", "got -3"]),
        (&["--ber", "0.7"], &["--ber", "from 0 to 0.1", "got 0.7"]),
        (&["--ber", "-1"], &["--ber", "from 0 to 0.1", "got -1"]),
        (&["--line", "-1"], &["--line", "byte-serial, bit-serial"]),
        (&["--seed", "-1"], &["--seed", "got -1"]),
        (&["--ber", "nan"], &["--ber", "finite"]),
        (&["--window", "0"], &["--window", "from 1 to 16"]),
        (&["--window", "17"], &["--window", "from 1 to 16"]),
        (&["--messages", "0"], &["--messages", "from 1 to 100000000"]),
        (
            &["--messages", "99999999999999"],
            &["--messages", "from 1 to 100000000", "got 99999999999999"],
        ),
        (
            &["--bit-rate", "1e300"],
            &["--bit-rate", "from 1000 to 100000000", "got 1e300"],
        ),
        (&["--bit-rate", "0"], &["--bit-rate", "from 1000"]),
        (&["--retries", "-1"], &["--retries", "from 0 to 255"]),
        // One command in flight per crate: a window above the crate count is refused.
        (
            &["--crates", "5", "--window", "16"],
            &["--window", "--crates (5)", "got 16"],
        ),
        // Options the ports mode would ignore are refused, each named.
        (
            &[
                "--ports",
                "/nonexistent/a",
                "/nonexistent/b",
                "--ber",
                "0.01",
                "--svg",
                "x.svg",
            ],
            &["--ports", "--ber", "--picture"],
        ),
        (
            &[
                "--ports",
                "/nonexistent/a",
                "/nonexistent/b",
                "--crates",
                "5",
            ],
            &["--ports", "--crates"],
        ),
        (
            &[
                "--ports",
                "/nonexistent/a",
                "/nonexistent/b",
                "--panel",
                "--messages",
                "5",
            ],
            &["--panel", "--messages"],
        ),
        (&["--panel"], &["--panel", "--ports"]),
        (
            &["--no-svg", "--svg", "x.svg"],
            &["--no-picture", "--picture"],
        ),
        (
            &["--line", "serial"],
            &["--line", "byte-serial", "bit-serial"],
        ),
        (
            &["--script", "/nonexistent/work.txt"],
            &["--script", "/nonexistent/work.txt", "No such file"],
        ),
        (
            &["--ports", "/nonexistent/a", "/nonexistent/b"],
            &["cannot open /nonexistent/"],
        ),
    ] {
        let out = highway(&[args, &["-q"]].concat());
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

/// What a user reads never shows Rust's debug formatting: no `(ByteSerial)`, no `Some(`, no
/// `{ field: … }`, and numbers as a user writes them (`0`, `1e-5`, not `0e0`).
fn assert_no_debug_text(text: &str) {
    common::assert_no_debug_text("output", text, &["ByteSerial", "BitSerial", "e0 ", "0e0"]);
}

#[test]
fn no_debug_text_reaches_the_user() {
    for line in ["byte-serial", "bit-serial"] {
        for ber in ["0", "1e-5", "0.001"] {
            let out = highway(&[
                "--messages",
                "300",
                "--crates",
                "4",
                "--line",
                line,
                "--ber",
                ber,
                "-q",
                "--no-svg",
            ]);
            assert!(out.status.success());
            let text = String::from_utf8(out.stdout).unwrap();
            assert!(
                text.contains(&format!("bit-error rate {ber} per link ({line})")),
                "{text}"
            );
            assert_no_debug_text(&text);
            let json = String::from_utf8(
                highway(&[
                    "--messages",
                    "300",
                    "--crates",
                    "4",
                    "--line",
                    line,
                    "--ber",
                    ber,
                    "--json",
                    "--no-svg",
                ])
                .stdout,
            )
            .unwrap();
            assert!(json.contains(&format!("\"line\": \"{line}\"")), "{json}");
            assert_no_debug_text(&json);
        }
    }
}

/// `| head -1` in every output mode: the program ends quietly, exit 0 and nothing on stderr,
/// whether the reader closes before the first write (the write fails at once, every time) or
/// after the first line.
#[test]
fn a_closed_pipe_ends_quietly() {
    let dir = std::env::temp_dir().join(format!("regler-sh-pipe-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("h.svg");
    let svg = svg.to_str().unwrap();
    for mode in [
        &["--no-svg"][..],
        &["--svg", svg],
        &["--json", "--no-svg"],
        &["--json", "--svg", svg],
    ] {
        for close in [common::Close::AtOnce, common::Close::AfterALine] {
            common::closes_quietly(
                env!("CARGO_BIN_EXE_serial-highway"),
                &[&["--messages", "2000", "--crates", "12"], mode].concat(),
                b"",
                close,
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_window_follows_a_small_loop_and_the_picture_says_what_ran() {
    let r = json(&["--messages", "500", "--crates", "5"]);
    assert_eq!(r["config"]["window"], 5, "{r}");
    assert_eq!(json(&["--messages", "500"])["config"]["window"], 16);
    let dir = std::env::temp_dir().join(format!("regler-sh-pic-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("h.svg");
    let out = highway(&[
        "--messages",
        "3000",
        "--crates",
        "6",
        "--ber",
        "2e-3",
        "--retries",
        "1",
        "--line",
        "bit-serial",
        "-q",
        "--svg",
        svg.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let picture = std::fs::read_to_string(&svg).unwrap();
    assert!(
        picture.contains("bit-serial, 6 crates, BER 0.002"),
        "{picture}"
    );
    assert!(picture.contains("failed after every retry"), "{picture}");
    assert!(picture.contains(" failed, 0 undetected"), "{picture}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Runs the example over a fresh `socat` pty pair with `args`; `None` when socat is missing.
fn over_a_pty_pair(args: &[&str]) -> Option<std::process::Output> {
    if Command::new("socat")
        .arg("-V")
        .stdout(Stdio::null())
        .status()
        .is_err()
    {
        eprintln!("socat not installed: skipping the serial-port test (.ci/run installs it)");
        return None;
    }
    let dir =
        std::env::temp_dir().join(format!("regler-pty-{}-{}", std::process::id(), args.len()));
    std::fs::create_dir_all(&dir).unwrap();
    let (a, b) = (dir.join("a"), dir.join("b"));
    let mut socat = Command::new("socat")
        .arg(format!("pty,raw,echo=0,link={}", a.display()))
        .arg(format!("pty,raw,echo=0,link={}", b.display()))
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !(a.exists() && b.exists()) {
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "socat made no ptys"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = highway(&[&["--ports", a.to_str().unwrap(), b.to_str().unwrap()], args].concat());
    socat.kill().ok();
    socat.wait().ok();
    std::fs::remove_dir_all(&dir).ok();
    Some(out)
}

/// The driver and one crate over a real pseudo-terminal pair, through the `embedded-io` adapter
/// and the `serialport` crate. Runs when `socat` is installed (`.ci/run` installs it).
#[test]
fn driver_and_crate_over_a_socat_pty_pair() {
    let Some(out) = over_a_pty_pair(&["--messages", "200", "--json"]) else {
        return;
    };
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["completed"], 200, "{r}");
    assert_eq!(r["failed"], 0, "{r}");
    assert_eq!(r["undetected_errors"], 0, "{r}");
}

/// The 1977 panel link over a real pseudo-terminal pair: every key once, in order; the panel
/// shows the host's registers.
#[test]
fn panel_link_over_a_socat_pty_pair() {
    let Some(out) = over_a_pty_pair(&["--panel", "--json", "--seed", "5"]) else {
        return;
    };
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["keys_delivered"], r["keys_pressed"], "{r}");
    assert_eq!(r["keys_pressed"].as_array().unwrap().len(), 5);
    assert_eq!(r["registers_match"], true, "{r}");
    assert!(r["sequences"].as_u64().unwrap() >= 5, "{r}");
}

#[test]
fn a_scripted_workload_runs_in_order_and_a_bad_line_is_named() {
    let dir = std::env::temp_dir().join(format!("regler-hs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("work.txt");
    std::fs::write(
        &script,
        "# write, read back, clear\n3 1 2 16 0xABCDEF\n3 1 2 0\n3 1 2 9\n7 20 0 8 # LAM test\n",
    )
    .unwrap();
    let r = json(&[
        "--script",
        script.to_str().unwrap(),
        "--messages",
        "400",
        "--crates",
        "8",
    ]);
    assert_eq!(r["completed"], 400, "{r}");
    assert_eq!(r["undetected_errors"], 0, "{r}");
    let crates = r["crates"].as_array().unwrap();
    // Three of every four lines go to crate 3, one to crate 7; demands add counter reads.
    assert!(crates[2]["messages"].as_u64().unwrap() >= 300, "{r}");
    assert!(crates[6]["messages"].as_u64().unwrap() >= 100, "{r}");
    std::fs::write(&script, "3 1 2 0\n3 1 2 16\n").unwrap();
    let out = highway(&[
        "--script",
        script.to_str().unwrap(),
        "--messages",
        "10",
        "--no-svg",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("script line 2") && err.contains("needs data"),
        "{err}"
    );
    std::fs::write(&script, "20 1 2 0\n").unwrap();
    let out = highway(&[
        "--script",
        script.to_str().unwrap(),
        "--messages",
        "10",
        "--crates",
        "8",
        "--no-svg",
    ]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("not on the loop"));
    std::fs::remove_dir_all(&dir).ok();
}
