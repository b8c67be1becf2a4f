//! Regression tests for the attack on the whole plant (issue 21), findings 3, 4 and 7 and the
//! minor "power@ without seconds" and "overlapping power failures dropped": the `--fault` and
//! `--script` parsers. Each failed on the code before the fix.

use std::process::Command;

use regler_examples::mailbag::plant::faults::{FaultKind, parse_fault};
use regler_examples::mailbag::plant::traffic::parse_script;

/// The binary, writing no picture.
fn sorter(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_mailbag-sorter"))
        .arg("--no-svg")
        .args(args)
        .output()
        .unwrap()
}

/// Exit 2, the message naming the option and each needle.
fn refused(args: &[&str], needles: &[&str]) {
    let out = sorter(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?} not refused: {err}");
    assert!(out.stdout.is_empty(), "{args:?} printed on stdout");
    for n in needles {
        assert!(err.contains(n), "{args:?}: '{n}' not in: {err}");
    }
}

/// Finding 3: any u64 seconds were taken and `wall_ms + secs * 1000` overflowed (debug: panic,
/// release: a fault of ~0 s). Now every duration is at most 7 days.
#[test]
fn attack_fault_seconds_are_bounded_or_refused() {
    for s in [
        "power@00:10:00:18446744073709551615",
        "hang@00:10:00:18446744073709551615",
        "stuck@00:10:00:present-R5:1:18446744073709551615",
        "pulses@00:10:00:1:0.5:18446744073709551615",
        "chatter@00:10:00:pulse-1:18446744073709551615",
        "hang@00:10:00:604801",
    ] {
        assert!(parse_fault(s).is_err(), "'{s}' accepted");
        refused(&["--hours", "0.01", "--fault", s], &["--fault", "604800"]);
    }
    // The longest there is runs (saturating ends, no panic).
    let out = sorter(&[
        "--hours",
        "0.01",
        "--quiet",
        "--fault",
        "hang@00:00:10:604800",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Finding 4 and "power@ without seconds": the time is always HH:MM:SS, then exactly the
/// kind's arguments; nothing is silently dropped or read as another field.
#[test]
fn attack_fault_syntax_is_unambiguous() {
    let f = parse_fault("power@00:10:20:10").unwrap();
    assert_eq!((f.at_ms, f.kind), (620_000, FaultKind::Power { secs: 10 }));
    let f = parse_fault("hang@00:10:00:05").unwrap();
    assert_eq!((f.at_ms, f.kind), (600_000, FaultKind::Hang { secs: 5 }));
    let f = parse_fault("stuck@00:10:00:15:1:0").unwrap();
    assert_eq!(
        f.kind,
        FaultKind::Stuck {
            point: 15,
            on: true,
            secs: 0
        }
    );
    for s in [
        "reader-fails@00:00:00:R1:junk",
        "misread@00:00:00:R1:0.1:junk",
        "power@00:10:20:junk",
        "power@00:10:20:10:5",
        "power@25:00",
        "power@00:10:20",
        "hang@00:10",
        "stuck@00:10:15:1:0",
        "chatter@00:00:95:1",
    ] {
        assert!(parse_fault(s).is_err(), "'{s}' accepted");
        refused(&["--hours", "0.01", "--fault", s], &["--fault"]);
    }
}

/// "A second power@ at the same minute is dropped": a power failure that starts before the one
/// before it is over is refused (and so is a hang), naming --fault.
#[test]
fn attack_overlapping_power_failures_are_refused() {
    for pair in [
        ["power@00:00:10:20", "power@00:00:20:5"],
        ["power@00:00:10:20", "power@00:00:10:20"],
        ["hang@00:00:10:20", "hang@00:00:30:1"],
    ] {
        refused(
            &["--hours", "0.02", "--fault", pair[0], "--fault", pair[1]],
            &["--fault", "before the one before it is over"],
        );
    }
    let out = sorter(&[
        "--hours",
        "0.02",
        "--quiet",
        "--json",
        "--fault",
        "power@00:00:10:20",
        "--fault",
        "power@00:00:31:5",
    ]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let text = v.to_string();
    assert!(text.contains("\"power_failures\":2"), "{text}");
}

/// Finding 7: `--script` took lines no panel's keyboard would (exit 0): a station not the
/// panel's, a postcode with a bin in no schedule, an extra word; a non-UTF-8 script was refused
/// without a line number.
#[test]
fn attack_script_refuses_what_the_panels_would_not_take() {
    for (line, why) in [
        ("A emptying D1 C2", "station of panel A"),
        ("B emptying E9 A1", "station of panel B"),
        ("P1 postcode 12345", "no sorting schedule"),
        ("P1 type 3 4", "too many words"),
        ("central schedule 2 x", "too many words"),
        ("central assign 3 E2 E3", "too many words"),
    ] {
        let text = format!("# fine\n00:01 {line}\n");
        let e = parse_script(&text).expect_err(line);
        assert!(e.starts_with("line 2:") && e.contains(why), "{line}: {e}");
        let path = std::env::temp_dir().join(format!(
            "regler-attack-a-{}-{}.script",
            std::process::id(),
            line.len()
        ));
        std::fs::write(&path, &text).unwrap();
        refused(
            &["--hours", "0.01", "--script", path.to_str().unwrap()],
            &["--script", "line 2", why],
        );
        std::fs::remove_file(&path).ok();
    }
    let path = std::env::temp_dir().join(format!("regler-attack-a-{}.bin", std::process::id()));
    std::fs::write(&path, b"00:01 P1 type 3\n00:02 P1 type \xff\n").unwrap();
    refused(
        &["--hours", "0.01", "--script", path.to_str().unwrap()],
        &["--script", "line 2", "UTF-8"],
    );
    std::fs::remove_file(&path).ok();
    // What the panels take still passes.
    assert!(parse_script("00:01 B emptying E9 B1,C2\n00:02 P2 postcode 20211\n").is_ok());
}
