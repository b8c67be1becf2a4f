//! `--interactive`: the controller at a terminal. Each start-up question appears when the one
//! before is answered, each reply comes as the operator types, and the plant runs meanwhile at
//! `speed` times real time.
//!
//! Input is read by a thread of its own, line by line as bytes, and handed over a channel; the
//! main loop waits on the channel with a short timeout, so the plant advances (and, on a
//! terminal, the live status line at the top of the screen is redrawn) whether or not the
//! operator types. A line that is not UTF-8 text is reported and skipped, the dialogue goes on.
//!
//! Plain lines are typed at the terminal; `keys …`, `night on|off` and `outdoor D` act as in
//! scripts; `run S` skips S simulated seconds ahead; `quit` (or the end of input) ends the run.

use std::io::{self, BufRead, IsTerminal, Write};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use super::json::Trace;
use super::script::parse_script;
use super::startup::{Question, unfinished};
use super::summary::clock;
use super::terminal::Terminal;
use super::{Input, Interface, Shown, Sim, SimConfig, SimReport, keypad_startup};
use crate::cli::{Out, Stop, excerpt};

/// What the input thread read.
enum Typed {
    /// Line `n` (1 is the first), a line of text (without its line end).
    Line(usize, String),
    /// Line `n` (1 is the first) was not UTF-8 text.
    NotText(usize),
}

/// Reads stdin line by line on a thread of its own; the channel closes at the end of input.
fn reader() -> mpsc::Receiver<Typed> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut input = io::stdin().lock();
        let mut bytes = Vec::new();
        for n in 1.. {
            bytes.clear();
            match input.read_until(b'\n', &mut bytes) {
                Ok(0) | Err(_) => break,
                Ok(_) => {}
            }
            while bytes.last().is_some_and(|b| *b == b'\n' || *b == b'\r') {
                bytes.pop();
            }
            let typed = match String::from_utf8(bytes.clone()) {
                Ok(line) => Typed::Line(n, line),
                Err(_) => Typed::NotText(n),
            };
            if tx.send(typed).is_err() {
                break;
            }
        }
    });
    rx
}

/// Where the operator's screen goes: stdout, or stderr when stdout carries the JSON.
struct Screen<'a> {
    /// Stdout, or `None` when it carries the JSON (the screen then goes to stderr).
    out: Option<&'a mut Out>,
    /// Stdout is a terminal: the status line at its top is kept live.
    live: bool,
    /// The live status line last drawn.
    drawn: String,
}

impl Screen<'_> {
    fn say(&mut self, lines: &[String]) -> Result<(), Stop> {
        let Some(out) = self.out.as_deref_mut() else {
            let mut err = io::stderr().lock();
            for line in lines {
                let _ = writeln!(err, "{line}");
            }
            return Ok(());
        };
        for line in lines {
            out.line(line)?;
        }
        out.flush()
    }

    /// Redraws the status line on the screen's first row when it changed, leaving the cursor
    /// (and what the operator is typing) where it was.
    fn status(&mut self, sim: &Sim) -> Result<(), Stop> {
        let (true, Some(out)) = (self.live, self.out.as_deref_mut()) else {
            return Ok(());
        };
        let status = format!("[{}] {}  (live)", clock(sim.now()), sim.status());
        if status == self.drawn {
            return Ok(());
        }
        out.text(&format!("\x1b7\x1b[1;1H\x1b[2K{status}\x1b8"))?;
        out.flush()?;
        self.drawn = status;
        Ok(())
    }
}

/// Runs the controller with an operator at stdin; `json` streams the trace to `out` (the
/// operator's screen then goes to stderr). Returns the report of what was simulated.
///
/// # Errors
/// A configuration out of range, input that ended (or `quit`) before the start-up dialogue was
/// finished, or [`Stop::Closed`] when stdout's reader has gone.
pub fn run<'a>(
    config: &SimConfig,
    speed: f64,
    json: bool,
    out: &'a mut Out,
) -> Result<(SimReport, Trace<'a>), Stop> {
    super::controller::validate(config)?;
    let rx = reader();
    let typing = io::stdin().is_terminal();
    let live = !json && io::stdout().is_terminal();
    let (trace_out, screen_out) = if json {
        (Some(out), None)
    } else {
        (None, Some(out))
    };
    let mut screen = Screen {
        out: screen_out,
        live,
        drawn: String::new(),
    };
    if typing {
        screen.say(&["Answer the start-up questions; then Y (change mode), C (acknowledge), an empty line (status), keys …, night on|off, outdoor D, run SECONDS, quit.".into()])?;
    }
    let not_text = |n: usize| format!("input line {n} is not UTF-8 text: ignored");
    let mut terminal = Terminal::with_night_setback(config.night_setback);
    let mut transcript: Vec<Shown> = Vec::new();
    // Answers refused during start-up, named if the input ends before the dialogue does.
    let mut refused: Vec<String> = Vec::new();
    let startup = match config.interface {
        Interface::Keypad => keypad_startup(config.process)?,
        Interface::Terminal => {
            screen.say(&Terminal::banner())?;
            loop {
                let unanswered = terminal.question().unwrap_or(Question::Start);
                let (n, line) = match rx.recv() {
                    Ok(Typed::Line(n, line)) => (n, line),
                    Ok(Typed::NotText(n)) => {
                        screen.say(&[not_text(n)])?;
                        continue;
                    }
                    Err(_) => {
                        return Err(unfinished("the input ended", unanswered, &refused).into());
                    }
                };
                if line.trim().eq_ignore_ascii_case("quit") {
                    return Err(unfinished("quit", unanswered, &refused).into());
                }
                let echo = format!("> {}", excerpt(&line));
                if !typing {
                    screen.say(std::slice::from_ref(&echo))?;
                }
                transcript.push(Shown {
                    t_s: 0.0,
                    text: echo,
                });
                let answer = terminal.startup_line(&line);
                if let Some(reply) = answer.refused {
                    refused.push(format!(
                        "input line {n}: the controller refused '{}': {reply}",
                        excerpt(&line)
                    ));
                }
                screen.say(&answer.lines)?;
                transcript.extend(
                    answer
                        .lines
                        .into_iter()
                        .map(|text| Shown { t_s: 0.0, text }),
                );
                if let Some(startup) = answer.started {
                    break startup;
                }
            }
        }
    };
    let mut sim = Sim::new(config, startup, terminal)?;
    sim.shown = transcript;
    let end = config.hours * 3600.0;
    let started = Instant::now();
    let mut skipped = 0.0;
    let mut trace = Trace::new(trace_out);
    // Advances the plant to `to`, streaming the trace; false once the trace's reader has gone.
    let advance = |sim: &mut Sim, to: f64, trace: &mut Trace<'_>| {
        let mut closed = false;
        while sim.now() < to && !closed {
            sim.advance(&mut |p| closed |= trace.point(p).is_break());
        }
        !closed
    };
    // The first sample, so the status line shows the plant as it is, not the controller's
    // zeros before it has measured anything.
    let first_sample = sim.now() + 1e-9;
    if !advance(&mut sim, first_sample, &mut trace) {
        return Ok((sim.report(config), trace));
    }
    screen.say(&[format!("[{}] {}", clock(sim.now()), sim.status())])?;
    while sim.now() < end {
        // The plant runs at `speed` times real time, plus what `run S` skipped.
        let target = (started.elapsed().as_secs_f64() * speed + skipped).min(end);
        if !advance(&mut sim, target, &mut trace) {
            break;
        }
        screen.status(&sim)?;
        let line = match rx.recv_timeout(Duration::from_millis(50)) {
            Ok(Typed::Line(_, line)) => line,
            Ok(Typed::NotText(n)) => {
                screen.say(&[not_text(n)])?;
                continue;
            }
            Err(mpsc::RecvTimeoutError::Timeout) => continue,
            Err(mpsc::RecvTimeoutError::Disconnected) => break,
        };
        let trimmed = line.trim();
        if trimmed.eq_ignore_ascii_case("quit") {
            break;
        }
        let mut lines = Vec::new();
        if !typing {
            lines.push(format!("[{}] > {}", clock(sim.now()), excerpt(&line)));
        }
        if let Some(seconds) = trimmed.strip_prefix("run ") {
            match seconds.trim().parse::<f64>() {
                Ok(s) if s.is_finite() && s >= 0.0 => {
                    skipped += s;
                    let target = (started.elapsed().as_secs_f64() * speed + skipped).min(end);
                    if !advance(&mut sim, target, &mut trace) {
                        break;
                    }
                }
                _ => lines.push(format!(
                    "run takes simulated seconds (0 or more), got '{}'",
                    excerpt(seconds.trim())
                )),
            }
            lines.push(format!("[{}] {}", clock(sim.now()), sim.status()));
            screen.say(&lines)?;
            continue;
        }
        let input = match parse_script(&format!("0 {trimmed}"))
            .ok()
            .and_then(|mut e| e.pop())
        {
            Some(e) if !matches!(e.input, Input::Term(_)) => e.input,
            _ => Input::Term(line.clone()),
        };
        let from = sim.shown.len();
        sim.input(&input);
        for s in &sim.shown[from..] {
            if s.text.starts_with("> ") {
                continue; // the operator sees what they typed (and above, without a terminal)
            }
            for (i, text) in s.text.lines().enumerate() {
                lines.push(if i == 0 {
                    format!("[{}] {text}", clock(s.t_s))
                } else {
                    format!("        {text}")
                });
            }
        }
        // The state after the input, once: an empty line already answered with it.
        let status = sim.status();
        if !lines.last().is_some_and(|l| l.ends_with(&status)) {
            lines.push(format!("[{}] {status}", clock(sim.now())));
        }
        screen.say(&lines)?;
    }
    Ok((sim.report(config), trace))
}
