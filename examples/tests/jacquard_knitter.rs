//! End-to-end: the `jacquard-knitter` binary in memory, with faults, with operator keys, over
//! real UDP sockets, and at a real terminal.

mod common;

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
    assert!(has("capacity: schedulable"), "{screen:?}");
    assert!(has("machine 3: job 7 after the current one"));
    assert!(has("jobs   3: job 2 now, next 7"), "{screen:?}");
    assert!(has("flow   1: linked"));
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

/// Every refused argument: exit code 2 and a message naming the option (and, for a range,
/// its bounds); a script's bad line by its number and what is wrong with it.
#[test]
fn bad_inputs_are_refused_naming_the_option() {
    let script = |name: &str, text: &str| {
        let path = temp(name);
        std::fs::write(&path, text).unwrap();
        path.to_str().unwrap().to_owned()
    };
    let late = script("late.txt", "# a key long after the end\n1 S\n1e300 S\n");
    let job = script("job.txt", "1 C 1 999\n");
    let machine = script("machine.txt", "1 shift 9\n");
    let frob = script("frob.txt", "1 S\n2 frob\n");
    let time = script("time.txt", "soon S\n");
    let rows: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            vec!["--machines", "0"],
            vec!["--machines", "from 1 to 100", "got 0"],
        ),
        (
            vec!["--machines", "101"],
            vec!["--machines", "from 1 to 100"],
        ),
        (vec!["--needles", "7"], vec!["--needles", "from 8 to 1000"]),
        (
            vec!["--seconds", "-1"],
            vec!["--seconds", "more than 0 and at most 86400", "got -1"],
        ),
        (vec!["--seconds", "0"], vec!["--seconds", "more than 0"]),
        (vec!["--seconds", "1e300"], vec!["--seconds", "got 1e300"]),
        (vec!["--loss", "0.9"], vec!["--loss", "from 0 to 0.5"]),
        (
            vec!["--duplicate", "-0.1"],
            vec!["--duplicate", "from 0 to 0.5"],
        ),
        (vec!["--batch", "65"], vec!["--batch", "from 1 to 64"]),
        (
            vec!["--byte-ns", "0"],
            vec!["--byte-ns", "from 1 to 1000000"],
        ),
        (vec!["--job-rows", "0"], vec!["--job-rows", "from 1"]),
        (
            vec!["--picture-rows", "0"],
            vec!["--picture-rows", "from 1 to 100000"],
        ),
        (
            vec!["--master-fault", "5"],
            vec!["--master-fault", "START:SECONDS"],
        ),
        (
            vec!["--master-fault", "5:0"],
            vec!["--master-fault", "SECONDS must be more than 0"],
        ),
        (
            vec!["--master-fault", "100:10"],
            vec![
                "--master-fault",
                "at 100 s",
                "ends at 60 s",
                "--seconds",
                "never happens",
            ],
        ),
        (
            vec!["--seconds", "5", "--script", &late],
            vec![
                "--script",
                "line 3",
                "1e300 s",
                "after the run's end at 5 s",
            ],
        ),
        (
            vec!["--script", &job],
            vec!["--script", "line 1", "job 999 does not exist", "0 to 99"],
        ),
        (
            vec!["--script", &machine],
            vec!["--script", "line 1", "no machine 9", "1 to 8"],
        ),
        (
            vec!["--script", &frob],
            vec![
                "--script",
                "line 2",
                "unknown key 'frob'",
                "the keys are L (lock)",
                "break",
            ],
        ),
        (
            vec!["--script", &time],
            vec!["--script", "line 1", "the time must be seconds"],
        ),
        (
            vec!["--script", "/nonexistent/keys.txt"],
            vec!["--script", "cannot read"],
        ),
        (vec!["--speed", "2"], vec!["--speed", "--interactive"]),
        (
            vec!["--interactive", "--speed", "0"],
            vec!["--speed", "more than 0"],
        ),
        (
            vec!["--interactive", "--json"],
            vec!["--interactive", "--json"],
        ),
        (
            vec!["--no-png", "--png", "x.png"],
            vec!["--no-picture", "--picture"],
        ),
        (
            vec!["--transport", "udp", "--interactive"],
            vec!["--transport udp", "without a keyboard"],
        ),
        (
            vec!["--png", "/nonexistent/dir/k.png", "--seconds", "1"],
            vec!["cannot write /nonexistent/dir/k.png"],
        ),
    ];
    for (args, needles) in rows {
        let out = Command::new(env!("CARGO_BIN_EXE_jacquard-knitter"))
            .args(&args)
            .arg("-q")
            .stdin(std::process::Stdio::null())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        for needle in needles {
            assert!(err.contains(needle), "{args:?}: no {needle:?} in {err}");
        }
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

/// The link's busy figure is one computation: the summary and the P key at the end of the run
/// agree, and over UDP it is a number too (never NaN / null), saying what it measures.
#[test]
fn link_busy_is_the_same_everywhere_and_never_nan() {
    let script = temp("busy.txt");
    std::fs::write(&script, "5 P\n").unwrap();
    let r = json(&["--seconds", "5", "--script", script.to_str().unwrap()]);
    let busy = r["link_busy_percent"].as_f64().unwrap();
    assert!(busy > 5.0 && busy < 15.0, "{busy}");
    assert_eq!(r["link_busy_of"], "the simulated link");
    let line = r["screen"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(Value::as_str)
        .find(|l| l.contains("link (in memory)"))
        .unwrap()
        .to_owned();
    assert!(
        line.contains(&format!("busy {busy:.1} %")),
        "P says {line}, the summary {busy}"
    );
    assert!(line.contains("lost 0, duplicated 0"), "{line}");

    let out = knitter(&["--transport", "udp", "--seconds", "1", "--no-picture", "-q"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!text.contains("NaN"), "{text}");
    assert!(
        text.contains(
            "% (the refill frames at 3000 ns per byte; the sockets' own time is not measured)"
        ),
        "{text}"
    );
    let r = json(&["--transport", "udp", "--seconds", "1"]);
    let busy = r["link_busy_percent"].as_f64().unwrap();
    assert!(busy > 0.0 && busy < 100.0, "{r}");
}

/// `--interactive` with keys from a pipe: each line is a key, answered in order; a bad line is
/// answered with what is wrong; the end of the input is Break.
#[test]
fn interactive_reads_keys_from_a_pipe_line_by_line() {
    use std::io::Write;
    let mut child = Command::new(env!("CARGO_BIN_EXE_jacquard-knitter"))
        .args([
            "--interactive",
            "--seconds",
            "60",
            "--no-picture",
            "--machines",
            "3",
        ])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(b"T\n2\nfrob\nC 3 5\n")
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "keys from stdin, one a line",
        "parameters: 3 machines",
        "machine 2: 1",
        "line 3: unknown key 'frob'; the keys are L (lock)",
        "machine 3: job 5 after the current one",
        "break: back to the scheduler",
        "pattern check: 0 wrong bytes",
    ] {
        assert!(text.contains(needle), "no {needle:?} in {text}");
    }
}

/// Spawns the knitter with `stdin` as its input, reads one line of its output and closes the
/// pipe: the program must end quietly (exit 0, no panic, no "Broken pipe").
fn closes_quietly(args: &[&str], stdin: &[u8]) {
    for _ in 0..3 {
        common::closes_quietly(
            env!("CARGO_BIN_EXE_jacquard-knitter"),
            args,
            stdin,
            common::Close::AfterALine,
        );
    }
}

/// `| head -1` in every output mode: the text summary, JSON, and the interactive answers. Each
/// writes far more than a pipe holds after the reader has gone (every P answers a dozen lines).
#[test]
fn a_closed_pipe_ends_quietly() {
    let script = temp("pipe.txt");
    let keys: String = (0..3000)
        .map(|k| format!("{} P\n", f64::from(k) / 1000.0))
        .collect();
    std::fs::write(&script, keys).unwrap();
    let script = script.to_str().unwrap();
    closes_quietly(&["--seconds", "3", "--no-picture", "--script", script], b"");
    closes_quietly(
        &[
            "--seconds",
            "3",
            "--no-picture",
            "--json",
            "--script",
            script,
        ],
        b"",
    );
    closes_quietly(
        &[
            "--interactive",
            "--seconds",
            "30",
            "--no-picture",
            "--machines",
            "2",
        ],
        "P\n".repeat(3000).as_bytes(),
    );
}

/// No Rust `Debug` text reaches the user: not in the summary, the JSON, the operator's answers
/// or the messages of a refused run.
#[test]
fn no_debug_text_reaches_the_user() {
    let script = temp("debug.txt");
    std::fs::write(&script, "1 T\n1 S\n1 2\n2 P\n").unwrap();
    let script = script.to_str().unwrap();
    let mut outputs = Vec::new();
    for args in [
        vec!["--seconds", "3", "--no-picture", "--script", script],
        vec![
            "--seconds",
            "3",
            "--no-picture",
            "--json",
            "--script",
            script,
        ],
        vec!["--seconds", "1", "--no-picture", "--transport", "udp"],
        vec![
            "--seconds",
            "1",
            "--no-picture",
            "--transport",
            "udp",
            "--json",
        ],
        vec!["--master-fault", "100:10"],
        vec!["--png", "/nonexistent/dir/k.png", "--seconds", "1"],
        vec!["--script", "/nonexistent/keys.txt"],
    ] {
        let out = knitter(&args);
        outputs.push((
            args.join(" "),
            String::from_utf8_lossy(&out.stdout).to_string(),
        ));
        outputs.push((
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).to_string(),
        ));
    }
    for (args, text) in outputs {
        common::assert_no_debug_text(
            &args,
            &text,
            &[
                "NaN",
                "(Linked)",
                "StandAlone",
                "Schedulable",
                "Overloaded",
                "utilisation_ppm",
            ],
        );
    }
}

/// The picture says what it is: a title band with text above the fabric, a legend below.
#[test]
fn the_picture_has_a_title_and_a_legend() {
    let path = temp("titled.png");
    let out = knitter(&["--seconds", "3", "-q", "--picture", path.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut pixels).unwrap();
    let (w, h) = (info.width as usize, info.height as usize);
    let ink = |y0: usize, y1: usize| {
        (y0..y1).any(|y| (0..w).any(|x| pixels[(y * w + x) * 3..][..3] == [20, 20, 20]))
    };
    assert!(ink(16, 30), "title line");
    assert!(ink(h - 40, h - 16), "legend");
    // The stripes and the yarns: never the colour that marks a missed byte.
    let magenta = (0..w * h)
        .filter(|&p| pixels[p * 3..][..3] == [255, 0, 255])
        .count();
    assert_eq!(
        magenta,
        2 * 12 * 12,
        "only the legend's two swatches: no byte was missed"
    );
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
#[ignore = "runs the program in a tmux session (needs tmux and a few seconds of real time): cargo test -p regler-examples -- --ignored"]
fn interactive_under_tmux_answers_each_key() {
    use std::time::{Duration, Instant};
    assert!(
        Command::new("tmux").arg("-V").output().is_ok(),
        "tmux not found: this test runs the program in a tmux session; install tmux \
         (apt-get install tmux) and run: cargo test -p regler-examples -- --ignored"
    );
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
        linked = screen().contains("flow   3: linked");
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
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("--silence: must be from 1 to 32311"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
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
