//! What every program's end-to-end tests check the same way: a closed pipe ends quietly, and no
//! Rust `Debug` text reaches a user.
#![allow(dead_code, reason = "each test file uses what it needs")]

use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Command, Stdio};

/// When the reader of stdout goes away.
#[derive(Clone, Copy, Debug)]
pub enum Close {
    /// Before the program's first write (the write fails at once, every time).
    AtOnce,
    /// After its first byte.
    AfterAByte,
    /// After its first line.
    AfterALine,
}

/// Runs `bin` with `args` and `stdin` (fed from a thread; a program that ends before it read
/// everything is no failure), closes stdout as `close` says, and checks the promise: exit
/// status success and nothing on stderr (no panic, no "Broken pipe").
pub fn closes_quietly(bin: &str, args: &[&str], stdin: &[u8], close: Close) {
    let mut child = Command::new(bin)
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut input = child.stdin.take().unwrap();
    let data = stdin.to_vec();
    let feeder = std::thread::spawn(move || {
        let _ = input.write_all(&data);
    });
    let stdout = child.stdout.take().unwrap();
    match close {
        Close::AtOnce => drop(stdout),
        Close::AfterAByte => {
            let mut byte = [0u8; 1];
            BufReader::new(stdout).read_exact(&mut byte).unwrap();
        }
        Close::AfterALine => {
            let mut line = String::new();
            BufReader::new(stdout).read_line(&mut line).unwrap();
            assert!(!line.is_empty(), "{args:?}: no output at all");
        }
    }
    let out = child.wait_with_output().unwrap();
    let _ = feeder.join();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "{args:?} ({close:?}): {:?} {err}",
        out.status
    );
    assert!(err.is_empty(), "{args:?} ({close:?}): {err}");
}

/// Rust `Debug` spellings that never belong in what a user reads.
pub const DEBUG_TEXT: [&str; 9] = [
    "Some(", "None", "Ok(", "Err(", "\"Ok\":", "\"Err\":", "Custom {", "kind:", " { ",
];

/// `text` (from `what`) shows none of [`DEBUG_TEXT`] and none of `extra` (a program's own enum
/// variant names, say).
pub fn assert_no_debug_text(what: &str, text: &str, extra: &[&str]) {
    for debug in DEBUG_TEXT.iter().chain(extra) {
        assert!(!text.contains(debug), "{what}: {debug:?} in\n{text}");
    }
}
