//! The operator live: keys answered as they come, the run paced in real time. At a terminal
//! each key acts as it is typed (no Enter), as on the source's keyboard; from a pipe the keys
//! come one a line, written as in a script without the time (`S`, `C 3 7`, `2`, `shift 4`), and
//! the end of the input is Break.

use std::io::{BufRead, IsTerminal};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use super::keys::{KEYS, Key};
use super::memory::Sim;
use crate::cli::{Out, Stop};
use crate::outln;

/// The keys as the operator types them at a terminal.
pub const HELP: &str = "keys: L lock, O open, S flow, F jobs, P report, T parameters, \
                        C change job (machine and job, one digit each), 1-9 status, \
                        Shift 1-8 (! @ # $ % ^ & *) re-initialise, B break";

/// What the reader thread passes on.
enum Input {
    /// A key typed at the terminal.
    Typed(char),
    /// A line from a pipe: its number (from 1) and text.
    Line(usize, String),
    /// The pipe ended.
    End,
}

/// Where the keys come from.
fn keys() -> (mpsc::Receiver<Input>, bool) {
    let (tx, rx) = mpsc::channel();
    let terminal = std::io::stdin().is_terminal();
    std::thread::spawn(move || {
        if terminal {
            let term = console::Term::stdout();
            while let Ok(key) = term.read_key() {
                let ch = match key {
                    console::Key::Char(c) => c,
                    console::Key::Escape => 'b',
                    _ => continue,
                };
                if tx.send(Input::Typed(ch)).is_err() {
                    return;
                }
            }
        } else {
            let mut stdin = std::io::stdin().lock();
            let mut line = Vec::new();
            let mut n = 0;
            // Bytes, not `lines()`: a line that is not UTF-8 is answered, not the end.
            while matches!(stdin.read_until(b'\n', &mut line), Ok(k) if k > 0) {
                n += 1;
                let text = String::from_utf8_lossy(&line).trim().to_owned();
                line.clear();
                if tx.send(Input::Line(n, text)).is_err() {
                    return;
                }
            }
        }
        let _ = tx.send(Input::End);
    });
    (rx, terminal)
}

/// Runs `sim` at `speed` simulated seconds per real second, answering keys from stdin and
/// printing the keyboard's answers to `out` as they come.
///
/// # Errors
/// [`Stop::Closed`] when stdout's reader has gone; a write error.
pub fn run(sim: &mut Sim, speed: f64, out: &mut Out) -> Result<(), Stop> {
    let (rx, terminal) = keys();
    let machines = sim.boards.len();
    if terminal {
        outln!(out, "jacquard-knitter: {machines} machines; {HELP}")?;
    } else {
        outln!(
            out,
            "jacquard-knitter: {machines} machines; keys from stdin, one a line: {KEYS}; \
             the end of the input is break"
        )?;
    }
    out.flush()?;
    let start = Instant::now();
    let mut shown = sim.keyboard.screen.len();
    let mut change: Option<Vec<u32>> = None;
    while !sim.finished() {
        let target = (start.elapsed().as_secs_f64() * speed * 1e9) as u64;
        sim.run_until(target);
        while let Ok(input) = rx.try_recv() {
            match input {
                Input::Typed(ch) => typed(sim, ch, &mut change, out)?,
                Input::Line(n, text) => {
                    let words: Vec<&str> = text.split_whitespace().collect();
                    if words.is_empty() {
                        continue;
                    }
                    match Key::parse(&words, machines) {
                        Ok(key) => sim.key(key),
                        Err(e) => outln!(out, "line {n}: {e}")?,
                    }
                }
                Input::End => sim.key(Key::Break),
            }
            // Answers in the order of the keys.
            for line in &sim.keyboard.screen[shown..] {
                outln!(out, "{line}")?;
            }
            shown = sim.keyboard.screen.len();
        }
        out.flush()?;
        std::thread::sleep(Duration::from_millis(20));
    }
    out.flush()
}

/// One key typed at the terminal; `change` holds the digits after C.
fn typed(
    sim: &mut Sim,
    ch: char,
    change: &mut Option<Vec<u32>>,
    out: &mut Out,
) -> Result<(), Stop> {
    if let Some(digits) = change {
        if let Some(d) = ch.to_digit(10) {
            digits.push(d);
            out.text(&ch.to_string())?;
        }
        if let [m, j] = digits[..] {
            *change = None;
            out.line("")?;
            sim.key(Key::Change(m as usize, j));
        }
        return out.flush();
    }
    let key = match ch.to_ascii_lowercase() {
        'l' => Key::Lock,
        'o' => Key::Open,
        's' => Key::Flow,
        'f' => Key::Jobs,
        'p' => Key::Report,
        't' => Key::Parameters,
        'b' | 'q' => Key::Break,
        'c' => {
            *change = Some(Vec::new());
            out.text("C: machine, job (two digits): ")?;
            return out.flush();
        }
        d @ '0'..='9' => Key::Status(d.to_digit(10).unwrap_or(0) as usize),
        s => match "!@#$%^&*".find(s) {
            Some(n) => Key::Reinit(n + 1),
            None => return outln!(out, "unknown key '{s}'; {HELP}"),
        },
    };
    sim.key(key);
    Ok(())
}
