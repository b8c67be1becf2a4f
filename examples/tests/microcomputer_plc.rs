//! End-to-end: the `microcomputer-plc` binary, by script, by stdin, and over Modbus/TCP.

mod common;

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
            .any(|l| l.contains("breakpoint reached: output 1 came on")),
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
    assert!(text.contains("breakpoint reached: cycle 40"), "{text}");
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

/// Every refused argument: exit code 2 and a message naming the option (and the bound for a
/// range), never a panic.
#[test]
fn bad_inputs_are_refused_naming_the_option() {
    let dir = std::env::temp_dir().join(format!("regler-plc-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("bad.txt");
    std::fs::write(&script, "run 3\nforce in 99 1\n").unwrap();
    let not_text = dir.join("latin1.txt");
    std::fs::write(&not_text, b"run 3\nshow \xe9\n").unwrap();
    let (script, not_text) = (script.to_str().unwrap(), not_text.to_str().unwrap());
    let table: &[(&[&str], &[&str])] = &[
        (&["--signals", "motor,warp"], &["--signals", "warp"]),
        (&["--window", "0"], &["--window", "1 to 100000"]),
        (&["--window", "100001"], &["--window", "1 to 100000"]),
        (&["--window", "-1"], &["--window", "1 to 100000"]),
        (
            &["--seconds", "0", "--modbus", "127.0.0.1:0"],
            &["--seconds", "more than 0"],
        ),
        (
            &["--seconds", "-1", "--modbus", "127.0.0.1:0"],
            &["--seconds", "more than 0", "got -1"],
        ),
        (
            &["--seconds", "1e300", "--modbus", "127.0.0.1:0"],
            &["--seconds", "at most 86400", "got 1e300"],
        ),
        (
            &["--seconds", "5"],
            &["--seconds", "only applies with --modbus"],
        ),
        (
            &["--idle-timeout", "5"],
            &["--idle-timeout", "only applies with --modbus"],
        ),
        (
            &["--idle-timeout", "0", "--modbus", "127.0.0.1:0"],
            &["--idle-timeout", "more than 0"],
        ),
        (
            &["--idle-timeout", "1e300", "--modbus", "127.0.0.1:0"],
            &["--idle-timeout", "at most 86400"],
        ),
        (&["--seed", "-1"], &["--seed"]),
        (
            &["--script", "/nonexistent"],
            &["--script", "cannot read /nonexistent"],
        ),
        (&["--script", script], &["script line 2", "point 99"]),
        (&["--script", not_text], &["script line 2", "not UTF-8"]),
        (
            &["--script", script, "--interactive"],
            &["--script", "--interactive"],
        ),
        (
            &["--modbus", "127.0.0.1:0", "--interactive"],
            &["--modbus", "--interactive"],
        ),
        (
            &["--modbus", "127.0.0.1:0", "--script", script],
            &["--modbus", "--script"],
        ),
        (
            &["--modbus", "not an address"],
            &["--modbus", "cannot listen on not an address"],
        ),
        (
            &["--no-svg", "--svg", "x.svg"],
            &["--no-picture", "--picture"],
        ),
        (
            &["--no-svg", "--window", "100"],
            &["--window", "--no-picture"],
        ),
        (
            &["--no-svg", "--signals", "motor"],
            &["--signals", "--no-picture"],
        ),
        (
            &["--svg", "/nonexistent/dir/x.svg"],
            &["--picture", "cannot write"],
        ),
    ];
    for (args, needles) in table {
        let out = plc(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        for needle in *needles {
            assert!(err.contains(needle), "{args:?}: {needle:?} not in {err}");
        }
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
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

/// The PLC serving Modbus/TCP on a free port for `seconds`; its host and port.
fn modbus_server(seconds: &str) -> (std::process::Child, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_microcomputer-plc"))
        .args([
            "--modbus",
            "127.0.0.1:0",
            "--seconds",
            seconds,
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
    let address = line.split_whitespace().nth(2).unwrap().to_string();
    let (host, port) = address.rsplit_once(':').unwrap();
    (child, host.to_string(), port.to_string())
}

/// One request as raw bytes (unit id and PDU), the raw reply's unit id and PDU.
fn raw(stream: &mut std::net::TcpStream, unit: u8, pdu: &[u8]) -> (u8, Vec<u8>) {
    use std::io::Read;
    let mut frame = vec![0x12, 0x34, 0, 0];
    frame.extend_from_slice(&u16::try_from(pdu.len() + 1).unwrap().to_be_bytes());
    frame.push(unit);
    frame.extend_from_slice(pdu);
    stream.write_all(&frame).unwrap();
    let mut head = [0u8; 7];
    stream.read_exact(&mut head).unwrap();
    assert_eq!(
        head[..4],
        [0x12, 0x34, 0, 0],
        "transaction and protocol echoed"
    );
    let len = usize::from(u16::from_be_bytes([head[4], head[5]]));
    let mut body = vec![0u8; len - 1];
    stream.read_exact(&mut body).unwrap();
    (head[6], body)
}

/// Every rule of the specification the server must keep, checked with raw frames (no client
/// library between the test and the wire).
#[test]
fn modbus_raw_frames_follow_the_specification() {
    let (child, host, port) = modbus_server("6");
    let mut s = std::net::TcpStream::connect(format!("{host}:{port}")).unwrap();
    s.set_read_timeout(Some(std::time::Duration::from_secs(3)))
        .unwrap();
    let exc = |f: u8, code: u8| vec![f | 0x80, code];
    // Unit ids 0, 1 and 255 are answered; another is a gateway's "no device".
    for unit in [0, 1, 255] {
        let (u, pdu) = raw(&mut s, unit, &[2, 0, 0, 0, 16]);
        assert_eq!((u, pdu[0], pdu[1]), (unit, 2, 2), "unit {unit}");
    }
    assert_eq!(raw(&mut s, 7, &[2, 0, 0, 0, 16]).1, exc(2, 0x0B));
    // Function codes it does not serve, including those with the exception bit set.
    for f in [0x00, 0x07, 0x2B, 0x7F, 0x81, 0xFF] {
        assert_eq!(
            raw(&mut s, 1, &[f, 0, 0, 0, 1]).1,
            exc(f, 1),
            "function {f:#x}"
        );
    }
    // Addresses outside the map: exception 2.
    for pdu in [
        &[1, 0, 16, 0, 1][..],  // coil 16
        &[1, 0x03, 0xF2, 0, 8], // coils 1010-1017 cross the end
        &[2, 0, 16, 0, 1],      // discrete input 16
        &[4, 0, 19, 0, 1],      // input register 19
        &[3, 0, 1, 0, 15],      // holding registers 1-15
        &[5, 0, 20, 0xFF, 0],   // write coil 20
        &[6, 0, 3, 0, 1],       // write holding 3
    ] {
        assert_eq!(raw(&mut s, 1, pdu).1, exc(pdu[0], 2), "{pdu:?}");
    }
    // Quantities, byte counts and values: exception 3.
    for pdu in [
        &[1, 0, 0, 0, 0][..],          // quantity 0
        &[1, 0, 0, 0x07, 0xD1],        // 2001 coils
        &[4, 0, 0, 0, 126],            // 126 registers
        &[15, 0, 0, 0, 9, 1, 0xFF],    // 9 coils need 2 bytes, 1 given
        &[16, 0, 0, 0, 1, 3, 0, 1, 0], // 1 register needs 2 bytes, 3 given
        &[6, 0, 0, 0, 2],              // release-all register takes 0 or 1
        &[6, 0, 1, 0, 16],             // release output 16: no such point
        &[5, 0, 0, 0x12, 0x34],        // a coil value other than 0x0000 / 0xFF00
    ] {
        assert_eq!(raw(&mut s, 1, pdu).1, exc(pdu[0], 3), "{pdu:?}");
    }
    // Force output 3 and see it listed as forced, then release that one point.
    assert_eq!(
        raw(&mut s, 1, &[5, 0, 3, 0xFF, 0]).1,
        vec![5, 0, 3, 0xFF, 0]
    );
    let forced = |s: &mut std::net::TcpStream| raw(s, 1, &[2, 0, 100, 0, 16]).1[2] & 0b1000 != 0;
    let wait = |s: &mut std::net::TcpStream, want: bool| {
        for _ in 0..40 {
            if forced(s) == want {
                return true;
            }
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        false
    };
    assert!(wait(&mut s, true), "output 3 shown as forced");
    assert_eq!(raw(&mut s, 1, &[6, 0, 1, 0, 3]).1, vec![6, 0, 1, 0, 3]);
    assert!(wait(&mut s, false), "output 3 released alone");
    // Counters span two registers: cycles in 3-4.
    let r = raw(&mut s, 1, &[4, 0, 3, 0, 2]).1;
    let cycles = u32::from_be_bytes([r[2], r[3], r[4], r[5]]);
    assert!(cycles > 0, "{r:?}");
    drop(s);
    let out = child.wait_with_output().unwrap();
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    let log = r["log"].to_string();
    assert!(
        log.contains("force output 3 on") && log.contains("release output 3"),
        "{log}"
    );
}

/// Fails (under `--ignored`) with what to install when `tool` is not on the PATH.
fn need(tool: &str, install: &str) {
    let found = std::env::var_os("PATH")
        .is_some_and(|path| std::env::split_paths(&path).any(|dir| dir.join(tool).is_file()));
    assert!(found, "{tool} is not on the PATH: {install}");
}

/// mbpoll, a Modbus client from Debian, against the server: reads, single and block writes of
/// coils and registers (functions 5, 15, 6, 16), one-point releases and the exceptions, as a user
/// at a terminal would see them. `.ci/run` installs mbpoll and runs this test.
#[test]
#[ignore = "needs mbpoll on the PATH (apt-get install mbpoll); .ci/run runs it"]
fn modbus_with_mbpoll() {
    need("mbpoll", "apt-get install mbpoll");
    let (child, host, port) = modbus_server("10");
    let mbpoll = |args: &[&str]| {
        let out = Command::new("mbpoll")
            .args(["-m", "tcp", "-p", &port, "-0", "-1", "-o", "2"])
            .args(args)
            .output()
            .unwrap();
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stdout).to_string()
                + &String::from_utf8_lossy(&out.stderr),
        )
    };
    // Read the input image with unit id 255, the input registers with unit id 0.
    let (ok, text) = mbpoll(&["-a", "255", "-t", "1", "-r", "0", "-c", "16", &host]);
    assert!(ok && text.contains("[15]:"), "{text}");
    let (ok, text) = mbpoll(&["-a", "0", "-t", "3", "-r", "0", "-c", "19", &host]);
    assert!(ok && text.contains("[18]:"), "{text}");
    // Force input 1 (STOP) through coil 1001; discrete input 201 shows it forced.
    let (ok, text) = mbpoll(&["-a", "1", "-t", "0", "-r", "1001", &host, "1"]);
    assert!(ok, "{text}");
    std::thread::sleep(std::time::Duration::from_millis(300));
    let (ok, text) = mbpoll(&["-a", "1", "-t", "1", "-r", "201", &host]);
    assert!(ok && text.contains("[201]: \t1"), "{text}");
    // Release that one input (holding register 2 <- 1).
    let (ok, text) = mbpoll(&["-a", "1", "-t", "4", "-r", "2", &host, "1"]);
    assert!(ok, "{text}");
    std::thread::sleep(std::time::Duration::from_millis(300));
    let (_, text) = mbpoll(&["-a", "1", "-t", "1", "-r", "201", &host]);
    assert!(text.contains("[201]: \t0"), "{text}");
    // A block of coils (function 15): outputs 0 and 1 both forced, whatever they showed.
    let (ok, text) = mbpoll(&["-a", "1", "-t", "0", "-r", "0", &host, "1", "0"]);
    assert!(ok && text.contains("Written 2 references"), "{text}");
    std::thread::sleep(std::time::Duration::from_millis(300));
    let (ok, text) = mbpoll(&["-a", "1", "-t", "1", "-r", "100", "-c", "2", &host]);
    assert!(
        ok && text.contains("[100]: \t1") && text.contains("[101]: \t1"),
        "{text}"
    );
    // A block of registers (function 16): 0 ← 0 nothing, 1 ← 1 releases output 1, 2 ← 0 input 0.
    let (ok, text) = mbpoll(&["-a", "1", "-t", "4", "-r", "0", &host, "0", "1", "0"]);
    assert!(ok && text.contains("Written 3 references"), "{text}");
    std::thread::sleep(std::time::Duration::from_millis(300));
    let (ok, text) = mbpoll(&["-a", "1", "-t", "1", "-r", "100", "-c", "2", &host]);
    assert!(
        ok && text.contains("[100]: \t1") && text.contains("[101]: \t0"),
        "{text}"
    );
    // Blocks that reach past the map or hold a value not taken: refused whole.
    let (ok, text) = mbpoll(&["-a", "1", "-t", "0", "-r", "14", &host, "1", "0", "1"]);
    assert!(!ok && text.contains("Illegal data address"), "{text}");
    let (ok, text) = mbpoll(&["-a", "1", "-t", "4", "-r", "0", &host, "1", "16"]);
    assert!(!ok && text.contains("Illegal data value"), "{text}");
    std::thread::sleep(std::time::Duration::from_millis(300));
    let (ok, text) = mbpoll(&["-a", "1", "-t", "1", "-r", "100", "-c", "2", &host]);
    assert!(
        ok && text.contains("[100]: \t1"),
        "the refused block released nothing\n{text}"
    );
    // The exceptions, as mbpoll names them.
    let (ok, text) = mbpoll(&["-a", "1", "-t", "0", "-r", "16", &host]);
    assert!(!ok && text.contains("Illegal data address"), "{text}");
    let (ok, text) = mbpoll(&["-a", "1", "-t", "4", "-r", "0", &host, "2"]);
    assert!(!ok && text.contains("Illegal data value"), "{text}");
    let (ok, text) = mbpoll(&["-a", "1", "-t", "3", "-r", "10", "-c", "10", &host]);
    assert!(!ok && text.contains("Illegal data address"), "{text}");
    let out = child.wait_with_output().unwrap();
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    let log = r["log"].to_string();
    for line in [
        "release input 1",
        "force output 0 on",
        "force output 1 off",
        "release output 1",
        "release input 0",
    ] {
        assert!(log.contains(line), "{line}: {log}");
    }
    assert!(
        !log.contains("release all"),
        "the refused block acted: {log}"
    );
}

/// A real Modbus client that no one here wrote (pymodbus) reads the images, forces a coil and
/// sees the program react. Needs a `python3` on the PATH that imports pymodbus; `.ci/run`
/// installs it in a virtual environment and runs this test.
#[test]
#[ignore = "needs a python3 on the PATH that imports pymodbus (python3 -m venv /tmp/venv && /tmp/venv/bin/pip install pymodbus, then PATH=/tmp/venv/bin:$PATH); .ci/run runs it"]
fn modbus_with_pymodbus() {
    let importable = Command::new("python3")
        .args(["-c", "import pymodbus"])
        .output()
        .is_ok_and(|o| o.status.success());
    assert!(
        importable,
        "the python3 on the PATH cannot import pymodbus: python3 -m venv /tmp/venv && \
         /tmp/venv/bin/pip install pymodbus, then run with PATH=/tmp/venv/bin:$PATH"
    );
    let (child, host, port) = modbus_server("12");
    let client = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/modbus_client.py");
    let status = Command::new("python3")
        .args([client, &host, &port])
        .status()
        .unwrap();
    assert!(status.success(), "the pymodbus client's checks failed");
    let out = child.wait_with_output().unwrap();
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    let log = r["log"].to_string();
    assert!(
        log.contains("force input 0 on")
            && log.contains("force output 2 on")
            && log.contains("force output 1 ")
            && log.contains("release output 1"),
        "{log}"
    );
}

/// The monitor as an operator uses it: help, bounds stated, breakpoints passed with cont, no
/// Rust debug formatting anywhere in what it prints.
#[test]
fn monitor_commands_behave_like_a_monitor() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_microcomputer-plc"))
        .args(["--interactive", "--no-svg"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(b"help\nrun 99999999999\nbreak out motor on\ncont\ncont\nspool\nbogus\nquit\n")
        .unwrap();
    let out = child.wait_with_output().unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("force in|out POINT on|off"),
        "help lists the commands\n{text}"
    );
    assert!(
        text.contains("run takes 1 to 1000000 cycles, got 99999999999"),
        "{text}"
    );
    // cont stops where the motor comes on, then moves past it to the next time it comes on.
    let stops: Vec<&str> = text
        .lines()
        .filter(|l| l.contains("output 0 came on"))
        .collect();
    assert_eq!(stops.len(), 2, "{text}");
    assert!(
        text.contains("unknown command 'bogus' (help lists the commands)"),
        "{text}"
    );
    for debug in [
        "Some(",
        "Batch(",
        "Shift(",
        "OutputOn(",
        "Cycle(",
        "ForceOutput(",
    ] {
        assert!(!text.contains(debug), "debug formatting {debug}: {text}");
    }
}

#[test]
fn options_are_parsed_like_the_other_programs() {
    let err = |args: &[&str]| String::from_utf8(plc(args).stderr).unwrap();
    assert!(err(&["--seed", "-1"]).contains("invalid value '-1' for '--seed"));
    assert!(err(&["--seconds", "5"]).contains("--seconds: only applies with --modbus"));
    assert!(err(&["--window", "0"]).contains("must be from 1 to 100000, got 0"));
}

/// The default picture shows what the program is for: a reject-gate opening, with cycle ticks.
#[test]
fn default_timing_diagram_shows_the_gate() {
    let dir = std::env::temp_dir().join(format!("regler-plc-gate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("d.svg");
    for seed in ["1989", "42", "7"] {
        let out = plc(&["--quiet", "--seed", seed, "--svg", svg.to_str().unwrap()]);
        assert!(out.status.success());
        let picture = std::fs::read_to_string(&svg).unwrap();
        assert!(
            picture.contains("the reject gate last opened in cycle"),
            "seed {seed}"
        );
        assert!(
            picture.contains("text-anchor=\"middle\" font-size=\"10\""),
            "ticks"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The forced flags as the server shows them: discrete inputs 100–115 (outputs) or 200–215
/// (inputs) as a 16-bit mask.
fn forced_mask(s: &mut std::net::TcpStream, first: u8) -> u16 {
    let r = raw(s, 1, &[2, 0, first, 0, 16]).1;
    u16::from_le_bytes([r[2], r[3]])
}

/// Polls until the forced mask at `first` is `want` (the cycle carries requests out within 50 ms).
fn wait_mask(s: &mut std::net::TcpStream, first: u8, want: u16) -> u16 {
    let mut got = 0;
    for _ in 0..60 {
        got = forced_mask(s, first);
        if got == want {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    got
}

/// Every write function acts on every point it names — 15 as 5 does, also when the value written
/// is the one the coil shows; 16 as 6 does, register by register — and a block that reaches
/// past the map, or holds a value a register does not take, is an exception and acts on nothing.
#[test]
fn modbus_every_write_function_acts_on_every_point() {
    let (child, host, port) = modbus_server("8");
    let mut s = std::net::TcpStream::connect(format!("{host}:{port}")).unwrap();
    s.set_read_timeout(Some(std::time::Duration::from_secs(3)))
        .unwrap();
    let exc = |f: u8, code: u8| vec![f | 0x80, code];
    // Function 15 with the present values of coils 0-1 (the issue's case): both outputs forced.
    let present = raw(&mut s, 1, &[1, 0, 0, 0, 2]).1[2] & 0b11;
    assert_eq!(
        raw(&mut s, 1, &[15, 0, 0, 0, 2, 1, present]).1,
        vec![15, 0, 0, 0, 2]
    );
    assert_eq!(
        wait_mask(&mut s, 100, 0b11),
        0b11,
        "outputs 0-1 forced by function 15"
    );
    // Function 15 on the input coils: inputs 0, 1 and 2 forced to 1, 0, 1; read back as written.
    assert_eq!(
        raw(&mut s, 1, &[15, 0x03, 0xE8, 0, 3, 1, 0b101]).1,
        vec![15, 0x03, 0xE8, 0, 3]
    );
    assert_eq!(
        wait_mask(&mut s, 200, 0b111),
        0b111,
        "inputs 0-2 forced by function 15"
    );
    assert_eq!(raw(&mut s, 1, &[1, 0x03, 0xE8, 0, 3]).1, vec![1, 1, 0b101]);
    // Function 5 on output 3, writing off: forced as well.
    assert_eq!(raw(&mut s, 1, &[5, 0, 3, 0, 0]).1, vec![5, 0, 3, 0, 0]);
    assert_eq!(wait_mask(&mut s, 100, 0b1011), 0b1011);
    // Refused blocks act on nothing: coils 14-16 (past the map), registers 1-3 (past the map),
    // registers 0-1 with release-output 16 (no such point; register 0 ← 1 must not act either).
    for (pdu, code) in [
        (&[15, 0, 14, 0, 3, 1, 0b111][..], 2),
        (&[15, 0x03, 0xF6, 0, 8, 1, 0xFF], 2),
        (&[16, 0, 1, 0, 3, 6, 0, 0, 0, 0, 0, 0], 2),
        (&[16, 0, 0, 0, 2, 4, 0, 1, 0, 16], 3),
        (&[16, 0, 0, 0, 0x7C, 0xF8], 3),
        (&[15, 0, 0, 0x07, 0xB1, 0xF7], 3),
    ] {
        assert_eq!(raw(&mut s, 1, pdu).1, exc(pdu[0], code), "{pdu:?}");
    }
    std::thread::sleep(std::time::Duration::from_millis(200));
    assert_eq!(forced_mask(&mut s, 100), 0b1011, "nothing released");
    assert_eq!(forced_mask(&mut s, 200), 0b111, "nothing released");
    // Function 16 on registers 0-2 with 0, 1, 2: register 0 ← 0 does nothing, output 1 and input 2
    // are released.
    assert_eq!(
        raw(&mut s, 1, &[16, 0, 0, 0, 3, 6, 0, 0, 0, 1, 0, 2]).1,
        vec![16, 0, 0, 0, 3]
    );
    assert_eq!(
        wait_mask(&mut s, 100, 0b1001),
        0b1001,
        "output 1 released by function 16"
    );
    assert_eq!(
        wait_mask(&mut s, 200, 0b011),
        0b011,
        "input 2 released by function 16"
    );
    // The registers read 0 again.
    assert_eq!(
        raw(&mut s, 1, &[3, 0, 0, 0, 3]).1,
        vec![3, 6, 0, 0, 0, 0, 0, 0]
    );
    // Function 6: register 0 ← 1 releases everything.
    assert_eq!(raw(&mut s, 1, &[6, 0, 0, 0, 1]).1, vec![6, 0, 0, 0, 1]);
    assert_eq!(wait_mask(&mut s, 100, 0), 0);
    assert_eq!(wait_mask(&mut s, 200, 0), 0);
    drop(s);
    let out = child.wait_with_output().unwrap();
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    let log = r["log"].to_string();
    for line in [
        "force output 0 ",
        "force output 1 ",
        "force input 0 on",
        "force input 1 off",
        "force input 2 on",
        "force output 3 off",
        "release output 1",
        "release input 2",
        "release all forced points",
    ] {
        assert!(log.contains(line), "{line}: {log}");
    }
    assert!(!log.contains("release output 16"), "{log}");
}

/// The reader of stdout goes away after one line while the program still has far more than a
/// pipe buffer to write: a quiet, successful end in every output mode.
#[test]
fn a_closed_pipe_ends_quietly() {
    let dir = std::env::temp_dir().join(format!("regler-plc-pipe-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // 3 000 × help is about 4 MB of text (and of JSON log): far more than a pipe holds.
    let script = dir.join("long.txt");
    std::fs::write(&script, "run 10\nhelp\n".repeat(3_000)).unwrap();
    let script = script.to_str().unwrap();
    let stdin_commands = "help\n".repeat(3_000);
    let modes: [(&[&str], &str); 4] = [
        (&["--script", script, "--no-svg"], ""),
        (&["--script", script, "--no-svg", "--json"], ""),
        (&["--interactive", "--no-svg"], &stdin_commands),
        (&["--interactive", "--no-svg", "-q"], &stdin_commands),
    ];
    for (args, stdin) in modes {
        common::closes_quietly(
            env!("CARGO_BIN_EXE_microcomputer-plc"),
            args,
            stdin.as_bytes(),
            common::Close::AfterALine,
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The issue's own commands, through a shell pipe into `head`, as a user typed them.
#[test]
fn the_issue_pipes_into_head_end_quietly() {
    let plc = env!("CARGO_BIN_EXE_microcomputer-plc");
    // (the pipeline, the program's place in it)
    for (pipeline, place) in [
        (format!("'{plc}' --no-svg | head -3"), 0),
        (format!("'{plc}' --no-svg --json | head -3"), 0),
        (
            format!("yes stats | head -2000 | '{plc}' --interactive | head -2"),
            2,
        ),
    ] {
        for _ in 0..3 {
            let out = Command::new("bash")
                .args([
                    "-c",
                    &format!("{pipeline} >/dev/null; exit ${{PIPESTATUS[{place}]}}"),
                ])
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(out.status.success(), "{pipeline}: {:?} {err}", out.status);
            assert!(err.is_empty(), "{pipeline}: {err}");
        }
    }
}

/// Debug formatting that must never reach a user.
fn assert_no_debug(what: &str, text: &str) {
    common::assert_no_debug_text(
        what,
        text,
        &["Batch(", "Shift(", "OutputOn(", "ForceOutput(", "Cycle("],
    );
}

/// No user-facing output shows Rust `Debug` text: the demonstration, its JSON, the monitor's
/// answers and errors, and the stderr of refused runs.
#[test]
fn no_debug_text_reaches_the_user() {
    let text = plc(&["--no-svg"]);
    assert_no_debug("text", &String::from_utf8_lossy(&text.stdout));
    let json = plc(&["--no-svg", "--json"]);
    assert_no_debug("json", &String::from_utf8_lossy(&json.stdout));
    let mut child = Command::new(env!("CARGO_BIN_EXE_microcomputer-plc"))
        .args(["--interactive", "--no-svg"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(
            b"run\nforce in 3\nforce in 99 1\nbreak cycle 0\nbreak in part off\nforce out gate 1\n\
              step\nspool\nrun 2000\nspool\nbreak out jam on\ncont\nbogus\nunforce out x\nquit\n",
        )
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert_no_debug("monitor", &String::from_utf8_lossy(&out.stdout));
    assert_no_debug("monitor stderr", &String::from_utf8_lossy(&out.stderr));
    for args in [
        &["--window", "0"][..],
        &["--seconds", "-1", "--modbus", "127.0.0.1:0"],
        &["--modbus", "not an address"],
        &["--script", "/nonexistent"],
        &["--svg", "/nonexistent/dir/x.svg"],
    ] {
        assert_no_debug("stderr", &String::from_utf8_lossy(&plc(args).stderr));
    }
}

/// The monitor's messages: usage for incomplete commands, a non-UTF-8 line reported and passed
/// over, cont at its limit says so, and the closing statistics come once.
#[test]
fn monitor_messages_say_what_happened() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_microcomputer-plc"))
        .args(["--interactive", "--no-svg"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(b"run\nforce in 3\nshow \xff\xfe\ncont\nstats\nquit\n")
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("? usage: run N (run N cycles (at most 1000000), stopping at a breakpoint)"),
        "{text}"
    );
    assert!(
        text.contains("? usage: force in|out POINT on|off ("),
        "{text}"
    );
    assert!(
        text.contains("? line 3 is not UTF-8 text: ignored"),
        "{text}"
    );
    assert!(
        text.contains("ran 72000 cycles: stopped at cont's limit of 72000 cycles"),
        "the monitor went on after the bad line\n{text}"
    );
    assert_eq!(
        text.matches("cycles 72000  busy").count(),
        1,
        "the closing statistics right after `stats` are not printed again\n{text}"
    );
    // The demonstration ends with `stats`: printed once.
    let demo = String::from_utf8(plc(&["--no-svg"]).stdout).unwrap();
    assert_eq!(demo.matches("cycles 4571  busy").count(), 1, "{demo}");
}

/// The PLC serving Modbus/TCP with `extra` options; its child and address.
fn modbus_server_with(seconds: &str, extra: &[&str]) -> (std::process::Child, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_microcomputer-plc"))
        .args([
            "--modbus",
            "127.0.0.1:0",
            "--seconds",
            seconds,
            "--json",
            "--no-svg",
        ])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stderr.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let address = line.split_whitespace().nth(2).unwrap().to_string();
    (child, address)
}

/// Sends one frame with MBAP length `length` (unit id 1 and `pdu`); the reply's PDU, or `None`
/// if the server closed the connection.
fn raw_frame(s: &mut std::net::TcpStream, length: u16, pdu: &[u8]) -> Option<Vec<u8>> {
    use std::io::Read;
    let mut frame = vec![0x12, 0x34, 0, 0];
    frame.extend_from_slice(&length.to_be_bytes());
    frame.push(1);
    frame.extend_from_slice(pdu);
    s.write_all(&frame).ok()?;
    let mut head = [0u8; 7];
    s.read_exact(&mut head).ok()?;
    let mut body = vec![0u8; usize::from(u16::from_be_bytes([head[4], head[5]])) - 1];
    s.read_exact(&mut body).ok()?;
    Some(body)
}

/// The largest writes the specification allows (an ADU of 260 bytes, MBAP length 254) are
/// answered with an exception, not a closed connection; a longer frame closes it.
#[test]
fn modbus_legal_size_writes_get_exceptions() {
    let (child, address) = modbus_server_with("4", &[]);
    let mut s = std::net::TcpStream::connect(&address).unwrap();
    s.set_read_timeout(Some(std::time::Duration::from_secs(3)))
        .unwrap();
    let write = |f: u8, quantity: u16, bytes: u8| {
        let mut pdu = vec![f, 0, 0];
        pdu.extend_from_slice(&quantity.to_be_bytes());
        pdu.push(bytes);
        pdu.extend(std::iter::repeat_n(0, usize::from(bytes)));
        pdu
    };
    for (pdu, want) in [
        (write(15, 1968, 246), [0x8F, 2]), // length 253: past the map
        (write(16, 123, 246), [0x90, 2]),  // length 253: past the map
        (write(15, 1969, 247), [0x8F, 3]), // length 254: too many coils
    ] {
        let length = u16::try_from(pdu.len() + 1).unwrap();
        assert_eq!(
            raw_frame(&mut s, length, &pdu),
            Some(want.to_vec()),
            "function {} length {length}",
            pdu[0]
        );
    }
    // fc16 with 124 registers and byte count 248 is 254 bytes of PDU: one more than an ADU
    // holds, so it is framed here with the largest length, and its byte count says 3.
    let mut pdu = write(16, 124, 248);
    pdu.truncate(253);
    assert_eq!(raw_frame(&mut s, 254, &pdu), Some(vec![0x90, 3]));
    // Above 254 the connection is closed.
    let mut big = vec![4];
    big.extend(std::iter::repeat_n(0, 254));
    assert_eq!(raw_frame(&mut s, 255, &big), None, "length 255");
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
}

/// The function code is checked first: a function not served is exception 1 whatever follows
/// it (even nothing); a served one with too little or too much data is exception 3.
#[test]
fn modbus_function_code_is_checked_first() {
    let (child, address) = modbus_server_with("6", &[]);
    let mut s = std::net::TcpStream::connect(&address).unwrap();
    s.set_read_timeout(Some(std::time::Duration::from_secs(3)))
        .unwrap();
    let body = [0u8, 0, 0, 1, 2];
    for f in 0..=255u8 {
        for n in 0..=5 {
            let mut pdu = vec![f];
            pdu.extend_from_slice(&body[..n]);
            let reply = raw_frame(&mut s, u16::try_from(n + 2).unwrap(), &pdu)
                .unwrap_or_else(|| panic!("function {f:#04x}, {n} bytes: connection closed"));
            let served = matches!(f, 1..=6 | 15 | 16);
            if !served {
                assert_eq!(reply, vec![f | 0x80, 1], "function {f:#04x}, {n} bytes");
            } else if n == 4 && matches!(f, 1..=4 | 6) {
                assert_eq!(reply[0], f, "function {f:#04x}, {n} bytes: {reply:?}");
            } else {
                assert_eq!(reply, vec![f | 0x80, 3], "function {f:#04x}, {n} bytes");
            }
        }
    }
    drop(s);
    assert!(child.wait_with_output().unwrap().status.success());
}

/// At most 16 clients at once: one more is closed at once; a client silent for the idle
/// timeout is closed, and then a new client is answered. The summary counts them.
#[test]
fn modbus_clients_are_capped_and_idle_ones_closed() {
    use std::io::Read;
    let (child, address) = modbus_server_with("6", &["--idle-timeout", "2"]);
    let idle: Vec<_> = (0..16)
        .map(|_| std::net::TcpStream::connect(&address).unwrap())
        .collect();
    std::thread::sleep(std::time::Duration::from_millis(200));
    let started = std::time::Instant::now();
    let mut extra = std::net::TcpStream::connect(&address).unwrap();
    extra
        .set_read_timeout(Some(std::time::Duration::from_secs(5)))
        .unwrap();
    let mut byte = [0u8; 1];
    assert!(
        matches!(extra.read(&mut byte), Ok(0) | Err(_)),
        "the 17th client is closed"
    );
    assert!(
        started.elapsed() < std::time::Duration::from_secs(1),
        "at once, not after the idle timeout: {:?}",
        started.elapsed()
    );
    std::thread::sleep(std::time::Duration::from_millis(2500));
    let mut s = std::net::TcpStream::connect(&address).unwrap();
    s.set_read_timeout(Some(std::time::Duration::from_secs(3)))
        .unwrap();
    let (_, pdu) = raw(&mut s, 1, &[4, 0, 0, 0, 1]);
    assert_eq!(pdu[0], 4, "answered once the idle clients were closed");
    drop((s, idle));
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    let m = &r["modbus"];
    assert_eq!(m["max_clients"], 16, "{m}");
    assert_eq!(m["refused_over_cap"], 1, "{m}");
    assert_eq!(m["closed_idle"], 16, "{m}");
    assert_eq!(m["clients"], 18, "{m}"); // 16 idle, 1 over the cap, 1 answered
    assert_eq!(m["spawn_failures"], 0, "{m}");
    assert!(m["listener_error"].is_null(), "{m}");
}

/// Refusals quote at most an excerpt of what was typed, not a whole 10 kB line.
#[test]
fn monitor_refusals_quote_an_excerpt() {
    let long = "x".repeat(10_000);
    let nine = "9".repeat(10_000);
    for line in [
        format!("frobnicate {long}"),
        format!("run {nine}"),
        format!("break cycle {long}"),
        format!("force in {long} 1"),
        format!("force in 3 {long}"),
        format!("force {long} 3 1"),
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_microcomputer-plc"))
            .args(["--interactive", "--no-svg"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut stdin = child.stdin.take().unwrap();
        stdin
            .write_all(format!("{line}\nquit\n").as_bytes())
            .unwrap();
        drop(stdin);
        let out = child.wait_with_output().unwrap();
        let text = String::from_utf8(out.stdout).unwrap();
        let refusal = text
            .lines()
            .find(|l| l.starts_with("? "))
            .unwrap_or_else(|| panic!("no refusal for {}", &line[..20]));
        assert!(
            refusal.len() < 200 && refusal.contains('…'),
            "{}…",
            &refusal[..refusal.len().min(200)]
        );
    }
}

/// In a simulated run every cycle is busy 1 ms and starts 50 ms after the one before: the
/// jitter is 0 (it was 2 ms from the second cycle and 3 ms once the reserve ran a report,
/// as the reserve's clock reads cost simulated time the period did not allow for).
#[test]
fn simulated_cycles_have_no_jitter() {
    let dir = std::env::temp_dir().join(format!("regler-plc-jitter-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("run.txt");
    for cycles in [2, 1000] {
        std::fs::write(&script, format!("run {cycles}\n")).unwrap();
        let out = plc(&["--json", "--no-svg", "--script", script.to_str().unwrap()]);
        assert!(out.status.success());
        let r: Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(r["stats"]["last_us"], 1000, "{}", r["stats"]);
        assert_eq!(
            r["stats"]["jitter_us"], 0,
            "{cycles} cycles: {}",
            r["stats"]
        );
    }
}
