//! Arbitrary bytes typed at the PLC example's monitor (`microcomputer-plc --monitor`), a line at a
//! time, into `Simulator::command`, then the same bytes on its stdin (`monitor::run_stdin`).
//! Long runs are shortened so an input stays fast: `run N` above 50 runs N mod 50 + 1 cycles,
//! `cont` is left out (it may run 72 000 cycles), `powerfail MS` above 5 000 ms lasts MS mod
//! 5 000 + 1 (the parser still sees every other line as typed).
//!
//! What the monitor's documentation promises, checked after every line:
//! - an error names the problem in a bounded message (what was typed is quoted as an excerpt,
//!   never echoed whole); a known command with missing or extra words gets its usage; an
//!   unknown one says so;
//! - a refused command changes nothing (forcing, breakpoints, cycles run);
//! - `force` puts the value in force and every cycle after shows it in the image (forced values
//!   win over the program and the hardware); `unforce` releases it;
//! - `break cycle N` is refused for a cycle already run; `run N` runs at most N cycles and
//!   stops early only at a breakpoint or a halt;
//! - on stdin a line that is not UTF-8 text is answered `? line N is not UTF-8 text: ignored`
//!   and the monitor goes on.
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_examples::plc::Simulator;
use regler_examples::plc::monitor::{self, COMMANDS, Transcript};

/// Shortens what would run long; `None` leaves the line out.
fn shorten(line: &str) -> Option<String> {
    let words: Vec<&str> = line.split_whitespace().collect();
    match words.as_slice() {
        ["cont" | "continue"] => None,
        ["run", n] => match n.parse::<u64>() {
            Ok(n) if n > 50 && n <= 1_000_000 => Some(format!("run {}", n % 50 + 1)),
            _ => Some(line.to_string()),
        },
        ["powerfail", ms] => match ms.parse::<u32>() {
            Ok(ms) if ms > 5_000 && ms <= 3_600_000 => {
                Some(format!("powerfail {}", ms % 5_000 + 1))
            }
            _ => Some(line.to_string()),
        },
        _ => Some(line.to_string()),
    }
}

/// The number of words of each form of `word` (`None`: no such command).
fn arities(word: &str) -> Option<Vec<usize>> {
    let word = if word == "continue" { "cont" } else { word };
    let forms: Vec<usize> = COMMANDS
        .iter()
        .filter(|(form, _)| form.split(' ').next() == Some(word))
        .map(|(form, _)| form.split(' ').count())
        .collect();
    (!forms.is_empty()).then_some(forms)
}

/// What a command may change, to compare before and after a refusal.
fn state(sim: &Simulator) -> (u64, usize, Vec<Option<bool>>) {
    let forced = (0..16)
        .flat_map(|p| {
            [
                sim.plc.forced_inputs().forced(p),
                sim.plc.forced_outputs().forced(p),
            ]
        })
        .collect();
    (sim.plc.cycle_count(), sim.breakpoints.len(), forced)
}

fn check_forcing_shown(sim: &Simulator) {
    for p in 0..16 {
        if let Some(v) = sim.plc.forced_inputs().forced(p) {
            assert_eq!(
                sim.plc.inputs().get(p),
                v,
                "forced input {p} not in the image"
            );
        }
        if let Some(v) = sim.plc.forced_outputs().forced(p) {
            assert_eq!(
                sim.plc.outputs().get(p),
                v,
                "forced output {p} not in the image"
            );
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let mut sim = Simulator::new(7);
    let mut typed = Vec::new();
    // The cycle count when the forcing last changed: the images show it from the next cycle.
    let mut forcing_changed_at = 0u64;
    for raw in data.split(|&b| b == b'\n').take(40) {
        let Ok(line) = std::str::from_utf8(raw) else {
            typed.extend_from_slice(raw);
            typed.push(b'\n');
            continue;
        };
        let Some(line) = shorten(line) else { continue };
        typed.extend_from_slice(line.as_bytes());
        typed.push(b'\n');
        let words: Vec<&str> = line.split_whitespace().collect();
        let before = state(&sim);
        match sim.command(&line) {
            Err(why) => {
                assert!(!why.is_empty());
                assert!(
                    why.chars().count() <= 160,
                    "a {}-character answer to {} characters typed: {why}",
                    why.chars().count(),
                    line.chars().count()
                );
                assert_eq!(
                    state(&sim),
                    before,
                    "the refused '{line}' changed something"
                );
                match arities(words[0]) {
                    None => assert!(why.contains("unknown command"), "'{line}': {why}"),
                    Some(n) if !n.contains(&words.len()) => {
                        assert!(why.starts_with("usage: "), "'{line}' gets {why}");
                    }
                    Some(_) => {}
                }
            }
            Ok(out) => {
                let after = state(&sim);
                match words.as_slice() {
                    [] => assert_eq!(after, before),
                    ["force", side, p, v] => {
                        let p: usize = match *p {
                            "start" => 0,
                            "stop" => 1,
                            "part" => 2,
                            "bad" => 3,
                            "reset" => 4,
                            "motor" => 0,
                            "jam" => 1,
                            "gate" => 2,
                            "run" => 3,
                            n => n.parse().expect("a point the monitor took"),
                        };
                        let on = matches!(*v, "on" | "1");
                        let forced = if *side == "in" {
                            sim.plc.forced_inputs().forced(p)
                        } else {
                            sim.plc.forced_outputs().forced(p)
                        };
                        assert_eq!(forced, Some(on), "'{line}'");
                        forcing_changed_at = after.0;
                    }
                    ["unforce", ..] => forcing_changed_at = after.0,
                    ["break", "cycle", n] => {
                        let n: u64 = n.parse().unwrap();
                        assert!(
                            n > before.0,
                            "break at cycle {n} taken after {} cycles",
                            before.0
                        );
                    }
                    ["run", n] => {
                        let n: u64 = n.parse().unwrap();
                        let done = after.0 - before.0;
                        assert!(
                            done <= n && out.starts_with(&format!("ran {done} cycle")),
                            "{out}"
                        );
                        if done < n {
                            assert!(
                                out.contains(':')
                                    || sim.breakpoints.iter().any(|b| sim.plc.reached(*b)),
                                "'{line}' stopped after {done} without a reason: {out}"
                            );
                        }
                    }
                    _ => {}
                }
                // After a cycle that ran since the forcing changed (a power failure in between
                // leaves the safe outputs until the next cycle).
                if after.0 > before.0 && after.0 > forcing_changed_at {
                    check_forcing_shown(&sim);
                }
            }
        }
    }
    // The same lines on stdin: every line that is not UTF-8 is answered and skipped.
    let mut sim = Simulator::new(7);
    let mut t = Transcript::new(false);
    let result = monitor::run_stdin(&mut sim, std::io::Cursor::new(&typed), false, &mut t);
    assert!(result.is_ok(), "the monitor stopped on bad input");
    let lines: Vec<&[u8]> = typed.split(|&b| b == b'\n').collect();
    // `typed` ends with a newline: the piece after it is no line.
    for (n, raw) in (1..).zip(&lines[..lines.len() - 1]) {
        match std::str::from_utf8(raw) {
            Err(_) => {
                let said = format!("? line {n} is not UTF-8 text: ignored");
                assert!(t.log.contains(&said), "no '{said}'");
            }
            Ok(line) if line.split('#').next().unwrap_or("").trim() == "quit" => break,
            Ok(_) => {}
        }
    }
});
