//! End-to-end: the `microcomputer-plc` binary, by script, by stdin, and over Modbus/TCP.

use std::io::{BufRead, BufReader, Write};
use std::process::{Command, Stdio};

use serde_json::Value;

fn plc(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_microcomputer-plc"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn demonstration_sorts_parts_and_reports() {
    let out = plc(&["--json", "--no-svg"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(r["parts"].as_i64().unwrap() > 100);
    assert!(r["tally"]["bad_rejected"].as_u64().unwrap() > 5);
    assert!(
        r["reports_run"].as_u64().unwrap() > 5,
        "the spool ran in the reserve"
    );
    assert_eq!(r["stats"]["overruns"], 0);
    let log: Vec<&str> = r["log"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_str().unwrap())
        .collect();
    assert!(
        log.iter()
            .any(|l| l.contains("breakpoint OutputOn(1) reached")),
        "{log:?}"
    );
    assert!(log.iter().any(|l| l.contains("jam    1")));
    assert_eq!(
        plc(&["--json", "--no-svg"]).stdout,
        out.stdout,
        "deterministic"
    );
}

#[test]
fn script_with_forcing_steps_and_breakpoints() {
    let dir = std::env::temp_dir().join(format!("regler-plc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("s.txt");
    std::fs::write(
        &script,
        "run 30\nforce in stop 1\nstep\nbreak cycle 40\ncont\nshow\nspool\n",
    )
    .unwrap();
    let svg = dir.join("t.svg");
    let out = plc(&[
        "--script",
        script.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
        "--signals",
        "start,stop,motor",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("stop   1  FORCED"), "{text}");
    assert!(
        text.contains("motor  0"),
        "STOP forced: the motor is off\n{text}"
    );
    assert!(text.contains("breakpoint Cycle(40) reached"));
    let picture = std::fs::read_to_string(&svg).unwrap();
    assert!(picture.contains("in  stop") && picture.contains("out motor"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn interactive_monitor_on_stdin() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_microcomputer-plc"))
        .args(["--interactive", "--no-svg", "-q"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(b"run 100\nbogus\nforce out gate 1\nstep\nquit\nrun 5\n")
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("? unknown command"), "{text}");
    assert!(text.contains("gate   1  FORCED"), "{text}");
    assert!(
        text.contains("cycles 101"),
        "quit stops before `run 5`\n{text}"
    );
}

#[test]
fn bad_input_is_a_clear_message() {
    for (args, needle) in [
        (vec!["--signals", "motor,warp"], "no signal"),
        (vec!["--window", "0"], "window"),
        (vec!["--script", "/nonexistent"], "cannot read"),
        (
            vec!["--modbus", "127.0.0.1:5020", "--seconds", "0"],
            "seconds",
        ),
        (vec!["--modbus", "not an address"], "cannot listen"),
    ] {
        let out = plc(&[args.as_slice(), &["--no-svg"]].concat());
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    let dir = std::env::temp_dir().join(format!("regler-plc-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("bad.txt");
    std::fs::write(&script, "run 3\nforce in 99 1\n").unwrap();
    let out = plc(&["--script", script.to_str().unwrap(), "--no-svg"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("script line 2"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn help() {
    let help = String::from_utf8(plc(&["--help"]).stdout).unwrap();
    for option in [
        "--script",
        "--interactive",
        "--modbus",
        "--seed",
        "--json",
        "--svg",
    ] {
        assert!(help.contains(option), "{option}");
    }
}

/// A real Modbus client that no one here wrote (pymodbus) reads the images, forces a coil and
/// sees the program react. Needs `python3` with pymodbus on the PATH; `.ci/run` installs it in a virtual environment and
/// runs this test.
#[test]
#[ignore = "needs python3 with pymodbus (python3 -m pip install pymodbus); .ci/run runs it"]
fn modbus_with_pymodbus() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_microcomputer-plc"))
        .args([
            "--modbus",
            "127.0.0.1:0",
            "--seconds",
            "12",
            "--json",
            "--no-svg",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stderr.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let address = line
        .split_whitespace()
        .nth(2)
        .unwrap()
        .trim_end_matches(':');
    let (host, port) = address.rsplit_once(':').unwrap();
    let client = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/modbus_client.py");
    let status = Command::new("python3")
        .args([client, host, port])
        .status()
        .unwrap();
    assert!(status.success(), "the pymodbus client's checks failed");
    let out = child.wait_with_output().unwrap();
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    let log = r["log"].to_string();
    assert!(
        log.contains("ForceInput(0, true)") && log.contains("ForceOutput(2, true)"),
        "{log}"
    );
}
