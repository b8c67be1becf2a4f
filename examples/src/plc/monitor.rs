//! The monitor, as the 1989 simulator was driven: run N cycles, one cycle, continuous with
//! breakpoints, show and force I/O, spool and statistics — from a script, or typed line by line
//! (a person at a terminal, or another program on a pipe).
//!
//! A command with missing or extra words is answered with its usage; a line that is not UTF-8
//! text is reported and skipped at the monitor (a script names its line and stops, as for any
//! bad script line).

use std::fmt::Write as _;
use std::io::{BufRead, Write as _};

use regler_scan_cycle::Breakpoint;

use super::SIGNALS;
use super::simulator::Simulator;
use crate::cli::{self, Out, Stop};

/// The most cycles one `run N` takes: 1 000 000 cycles of 50 ms, 13.9 simulated hours.
pub const RUN_MAX: u64 = 1_000_000;
/// `cont` runs until a breakpoint, at most this many cycles (one simulated hour).
pub const CONT_MAX: u64 = 72_000;
/// The longest power failure `powerfail` takes, ms (one hour).
pub const POWERFAIL_MAX_MS: u32 = 3_600_000;

/// The monitor's commands: the form (its usage) and what it does, as `help` lists them.
pub const COMMANDS: [(&str, &str); 15] = [
    (
        "run N",
        "run N cycles (at most 1000000), stopping at a breakpoint",
    ),
    ("step", "one cycle, then show the images"),
    (
        "cont",
        "run until a breakpoint, at most 72000 cycles (one simulated hour)",
    ),
    ("break cycle N", "stop after cycle N"),
    ("break in POINT on", "stop when an input comes on"),
    (
        "break out POINT on|off",
        "stop when an output comes on / goes off",
    ),
    ("clear breaks", "remove every breakpoint"),
    (
        "force in|out POINT on|off",
        "force a point (the program and the hardware cannot change it)",
    ),
    ("unforce in|out POINT", "release a forced point"),
    (
        "powerfail MS",
        "power off for MS ms (1-3600000): outputs safe, tracked parts kept",
    ),
    ("show", "the images, forced points marked"),
    ("spool", "reports waiting in the spool and run"),
    ("stats", "parts, cycle statistics, load"),
    ("help", "this list"),
    ("quit", "end (the summary and the timing diagram follow)"),
];

/// What `help` prints: every command, then what a POINT is.
#[must_use]
pub fn help() -> String {
    let mut s = String::new();
    for (form, what) in COMMANDS {
        let _ = writeln!(s, "{form:<27}{what}");
    }
    s.push_str(
        "POINT is a number 0-15 or a name: start stop part bad reset (inputs), motor jam gate run (outputs)\n",
    );
    s
}

/// The usage of the command `word` (`continue` is `cont`), or `None` for no such command.
#[must_use]
pub fn usage(word: &str) -> Option<String> {
    let word = if word == "continue" { "cont" } else { word };
    let forms: Vec<&str> = COMMANDS
        .iter()
        .map(|(form, _)| *form)
        .filter(|form| form.split(' ').next() == Some(word))
        .collect();
    match forms.as_slice() {
        [] => None,
        [form] => {
            let what = COMMANDS
                .iter()
                .find(|(f, _)| f == form)
                .map_or("", |(_, w)| w);
            Some(format!("usage: {form} ({what})"))
        }
        several => Some(format!("usage: {}", several.join(" | "))),
    }
}

/// Why a run stopped, in words.
fn ran(done: u64, why: Option<regler_scan_cycle::Halt>, limit: Option<u64>) -> String {
    let plural = if done == 1 { "" } else { "s" };
    match (why, limit) {
        (Some(w), _) => format!("ran {done} cycle{plural}: {w}"),
        (None, Some(limit)) if done == limit => format!(
            "ran {done} cycle{plural}: stopped at cont's limit of {limit} cycles (one simulated hour) without reaching a breakpoint"
        ),
        (None, _) => format!("ran {done} cycle{plural}"),
    }
}

impl Simulator {
    /// Executes one monitor command; returns what it prints. Errors name the problem: a
    /// command with missing or extra words gets its usage.
    ///
    /// # Errors
    /// The command's usage, an unknown command, or why a value was refused.
    pub fn command(&mut self, line: &str) -> Result<String, String> {
        let words: Vec<&str> = line.split_whitespace().collect();
        let point = |s: &str| -> Result<usize, String> {
            SIGNALS
                .iter()
                .find(|(name, ..)| *name == s)
                .map(|&(_, _, p)| p)
                .or_else(|| s.parse().ok())
                .ok_or_else(|| {
                    format!(
                        "no such point: {} (a number 0-15 or a name; help lists them)",
                        cli::excerpt(s)
                    )
                })
                .and_then(|p| {
                    // Input word 1 is the belt encoder's counter, not 16 points.
                    if (16..32).contains(&p) {
                        Err(format!(
                            "no such point: {p} (16-31 would be the belt encoder's counter word; points are 0-15)"
                        ))
                    } else {
                        Ok(p)
                    }
                })
        };
        let level = |s: &str| -> Result<bool, String> {
            match s {
                "1" | "on" => Ok(true),
                "0" | "off" => Ok(false),
                other => Err(format!(
                    "expected on/off or 1/0, got {}",
                    cli::excerpt(other)
                )),
            }
        };
        let io_side = |s: &str| -> Result<bool, String> {
            match s {
                "in" => Ok(true),
                "out" => Ok(false),
                other => Err(format!("expected in or out, got {}", cli::excerpt(other))),
            }
        };
        let mut out = String::new();
        match words.as_slice() {
            [] => {}
            ["run", n] => {
                let n: u64 = n
                    .parse()
                    .ok()
                    .filter(|n| (1..=RUN_MAX).contains(n))
                    .ok_or_else(|| {
                        format!("run takes 1 to {RUN_MAX} cycles, got {}", cli::excerpt(n))
                    })?;
                let (done, why) = self.run(n);
                let _ = writeln!(out, "{}", ran(done, why, None));
            }
            ["step"] => {
                let (done, why) = self.run(1);
                let _ = writeln!(out, "{}", ran(done, why, None));
                out.push_str(&self.show());
            }
            ["cont" | "continue"] => {
                // Continuous, bounded so a script without breakpoints ends: one simulated hour.
                let (done, why) = self.run(CONT_MAX);
                let _ = writeln!(out, "{}", ran(done, why, Some(CONT_MAX)));
            }
            ["break", "cycle", n] => {
                let n = n.parse().map_err(|_| {
                    format!("break cycle takes a cycle number, got {}", cli::excerpt(n))
                })?;
                // A cycle already run can never be reached again: refused, as `run` does.
                let b = Breakpoint::Cycle(n);
                self.plc
                    .check_breakpoints(&[b])
                    .map_err(|e| e.to_string())?;
                self.breakpoints.push(b);
            }
            ["break", side, p, lvl] => {
                let (input, p, on) = (io_side(side)?, point(p)?, level(lvl)?);
                self.breakpoints.push(match (input, on) {
                    (true, true) => Breakpoint::InputOn(p),
                    (false, true) => Breakpoint::OutputOn(p),
                    (false, false) => Breakpoint::OutputOff(p),
                    (true, false) => {
                        return Err("input breakpoints are on rising inputs only (in P on)".into());
                    }
                });
            }
            ["clear", "breaks"] => self.breakpoints.clear(),
            ["force", side, p, lvl] => {
                let (input, p, on) = (io_side(side)?, point(p)?, level(lvl)?);
                let r = if input {
                    self.plc.force_input(p, on)
                } else {
                    self.plc.force_output(p, on)
                };
                r.map_err(|e| e.to_string())?;
            }
            ["unforce", side, p] => {
                let (input, p) = (io_side(side)?, point(p)?);
                let r = if input {
                    self.plc.unforce_input(p)
                } else {
                    self.plc.unforce_output(p)
                };
                r.map_err(|e| e.to_string())?;
            }
            ["powerfail", ms] => {
                let ms: u32 = ms
                    .parse()
                    .ok()
                    .filter(|ms| (1..=POWERFAIL_MAX_MS).contains(ms))
                    .ok_or_else(|| {
                        format!(
                            "powerfail takes 1 to {POWERFAIL_MAX_MS} ms, got {}",
                            cli::excerpt(ms)
                        )
                    })?;
                let tracked = self.program.tracked();
                self.power_failure(ms)
                    .map_err(|e| format!("the program did not start again: {e}"))?;
                let _ = writeln!(
                    out,
                    "power off for {} s after cycle {}: outputs safe; {tracked} bad part{} kept in the tracker; START 1 s after the power came back",
                    cli::number(f64::from(ms) / 1000.0),
                    self.plc.cycle_count(),
                    if tracked == 1 { "" } else { "s" },
                );
            }
            ["show"] => out.push_str(&self.show()),
            ["spool"] => {
                let waiting: Vec<String> =
                    self.program.spool.iter().map(ToString::to_string).collect();
                let _ = writeln!(
                    out,
                    "spool: {} waiting [{}], {} run, {} refused",
                    waiting.len(),
                    waiting.join("; "),
                    self.reports_run,
                    self.program.spool_refused
                );
            }
            ["stats"] => out.push_str(&self.stats()),
            ["help"] => out.push_str(&help()),
            [first, ..] => {
                return Err(usage(first).unwrap_or_else(|| {
                    format!(
                        "unknown command '{}' (help lists the commands)",
                        cli::excerpt(line)
                    )
                }));
            }
        }
        Ok(out)
    }

    /// The I/O images with forced points marked.
    #[must_use]
    pub fn show(&self) -> String {
        let mut s = format!("cycle {}  {}\n", self.plc.cycle_count(), self.clock);
        for &(name, input, p) in &SIGNALS {
            let (value, forced) = if input {
                (self.plc.inputs().get(p), self.plc.forced_inputs().forced(p))
            } else {
                (
                    self.plc.outputs().get(p),
                    self.plc.forced_outputs().forced(p),
                )
            };
            let _ = writeln!(
                s,
                "  {} {:>2} {:<6} {}{}",
                if input { "in " } else { "out" },
                p,
                name,
                u8::from(value),
                if forced.is_some() { "  FORCED" } else { "" }
            );
        }
        s
    }

    /// Cycle statistics and counts.
    #[must_use]
    pub fn stats(&self) -> String {
        let st = self.plc.stats();
        let t = self.plant.tally;
        format!(
            "cycles {}  busy last/min/mean/max {}/{}/{}/{} us  jitter {} us  load {} per mille  overruns {}\n\
             parts {}  good passed {}  bad rejected {}  bad passed {}  good rejected {}  jams {}  reports {}\n",
            st.cycles,
            st.last_us,
            if st.cycles == 0 { 0 } else { st.min_us },
            st.mean_us(),
            st.max_us,
            st.jitter_us,
            st.load_per_mille(self.plc.config().period_us),
            st.overruns,
            self.program.parts(),
            t.good_passed,
            t.bad_rejected,
            t.bad_passed,
            t.good_rejected,
            t.jams,
            self.reports_run
        )
    }
}

/// The built-in demonstration: what an engineer would type at the 1989 simulator.
pub const DEMO_SCRIPT: &str = "# run the section for a minute and look at it
run 1200
show
stats
# stop at the next jam, look, then step through the reset
break out jam on
cont
show
clear breaks
run 100
# force the reject gate open for a second: good parts go to the reject bin
force out gate 1
run 20
unforce out gate
run 2400
spool
stats
";

/// Whether the monitor goes on after a line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// Next line.
    Go,
    /// `quit`: the summary follows.
    Quit,
}

/// What the monitor printed and keeps: stdout (ending quietly on a closed pipe), whether to
/// print at all (not with `--quiet` / `--json`), and the log of every command and its output
/// for the JSON summary.
pub struct Transcript {
    out: Out,
    print: bool,
    /// Every command (`> line`) and each line of its output, and the Modbus requests.
    pub log: Vec<String>,
    last_output: String,
}

impl Transcript {
    /// A transcript that prints when `print`.
    #[must_use]
    pub fn new(print: bool) -> Transcript {
        Transcript {
            out: Out::new(),
            print,
            log: Vec::new(),
            last_output: String::new(),
        }
    }

    /// Stdout.
    pub fn out(&mut self) -> &mut Out {
        &mut self.out
    }

    /// Logs `line` and prints it (when printing), sent at once.
    ///
    /// # Errors
    /// [`Stop::Closed`] when stdout's reader has gone.
    pub fn note(&mut self, line: String) -> Result<(), Stop> {
        if self.print {
            self.out.line(&line)?;
            self.out.flush()?;
        }
        self.log.push(line);
        Ok(())
    }

    /// Whether the last command's output, as printed, was `text` (the closing statistics are
    /// not printed a second time right after a `stats`).
    #[must_use]
    pub fn printed_last(&self, text: &str) -> bool {
        self.print && self.last_output == text
    }

    fn record(&mut self, line: &str, output: &str, echo_command: bool) -> Result<(), Stop> {
        if self.print {
            if echo_command {
                self.out.line(&format!("> {line}"))?;
            }
            self.out.text(output)?;
            self.last_output = output.to_owned();
        }
        self.log.push(format!("> {line}"));
        self.log.extend(output.lines().map(str::to_string));
        Ok(())
    }
}

/// The command on a line: comments (`#` to the end) and blanks removed; `None` if nothing is left.
fn command_of(line: &str) -> Option<&str> {
    let line = line.split('#').next().unwrap_or("").trim();
    (!line.is_empty()).then_some(line)
}

/// Runs one monitor line: `Ok(Ok(Quit))` for `quit`, `Ok(Err(why))` for a refused command,
/// `Err` when stdout failed.
fn execute(
    sim: &mut Simulator,
    line: &str,
    echo_command: bool,
    t: &mut Transcript,
) -> Result<Result<Step, String>, Stop> {
    let Some(line) = command_of(line) else {
        return Ok(Ok(Step::Go));
    };
    if line == "quit" {
        return Ok(Ok(Step::Quit));
    }
    match sim.command(line) {
        Ok(output) => {
            t.record(line, &output, echo_command)?;
            Ok(Ok(Step::Go))
        }
        Err(why) => Ok(Err(why)),
    }
}

/// Runs a script (its bytes, one command a line): every command echoed as `> command` before its
/// output. A refused command or a line that is not UTF-8 text stops it with the line's number.
///
/// # Errors
/// `script line N: why`, or [`Stop::Closed`] when stdout's reader has gone.
pub fn run_script(sim: &mut Simulator, script: &[u8], t: &mut Transcript) -> Result<Step, Stop> {
    for (n, raw) in script.split(|&b| b == b'\n').enumerate() {
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let line = std::str::from_utf8(raw)
            .map_err(|_| format!("script line {}: not UTF-8 text", n + 1))?;
        match execute(sim, line, true, t)? {
            Ok(Step::Go) => {}
            Ok(Step::Quit) => return Ok(Step::Quit),
            Err(why) => return Err(format!("script line {}: {why}", n + 1).into()),
        }
    }
    t.out.flush()?;
    Ok(Step::Go)
}

/// The monitor on `input` until `quit` or its end. At a terminal (`terminal`) a prompt on stderr
/// and no echo (the operator sees what they typed); on a pipe each command is echoed as
/// `> command`. A refused command or a line that is not UTF-8 text is answered with `? why` and
/// the monitor goes on. The output is sent after every line, so a program on the other end of a
/// pipe gets each answer before it writes the next command.
///
/// # Errors
/// Reading `input` failed, or [`Stop::Closed`] when stdout's reader has gone.
pub fn run_stdin(
    sim: &mut Simulator,
    mut input: impl BufRead,
    terminal: bool,
    t: &mut Transcript,
) -> Result<(), Stop> {
    let prompt = || {
        if terminal {
            let mut e = std::io::stderr();
            let _ = write!(e, "monitor> ");
            let _ = e.flush();
        }
    };
    if terminal {
        let _ = writeln!(
            std::io::stderr(),
            "microcomputer-plc monitor: 'help' lists the commands, 'quit' ends."
        );
    }
    let mut raw = Vec::new();
    for n in 1.. {
        prompt();
        raw.clear();
        let read = input
            .read_until(b'\n', &mut raw)
            .map_err(|e| format!("cannot read the commands on stdin: {}", cli::io_message(&e)))?;
        if read == 0 {
            break;
        }
        let answer = match std::str::from_utf8(&raw) {
            Ok(line) => execute(sim, line.trim_end_matches(['\n', '\r']), !terminal, t)?,
            Err(_) => Err(format!("line {n} is not UTF-8 text: ignored")),
        };
        match answer {
            Ok(Step::Go) => {}
            Ok(Step::Quit) => break,
            Err(why) => {
                if t.print || terminal {
                    t.out.line(&format!("? {why}"))?;
                }
                t.log.push(format!("? {why}"));
            }
        }
        t.out.flush()?;
    }
    t.out.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_and_their_errors() {
        let mut sim = Simulator::new(1);
        assert!(sim.command("run 10").unwrap().contains("ran 10"));
        sim.command("force in start 1").unwrap();
        assert!(sim.command("step").unwrap().contains("FORCED"));
        sim.command("break cycle 15").unwrap();
        assert!(sim.command("cont").unwrap().contains("breakpoint"));
        assert!(sim.command("force in 99 1").is_err());
        assert!(sim.command("fly").unwrap_err().contains("unknown command"));
        assert!(sim.command("run many").is_err());
        assert!(sim.command("break in part off").is_err());
        // Cycle 15 has run: a breakpoint there could never fire.
        let passed = sim.command("break cycle 15").unwrap_err();
        assert!(passed.contains("cycle 15 can never fire"), "{passed}");
        sim.command("break cycle 0").unwrap_err();
    }

    #[test]
    fn missing_words_get_the_usage() {
        let mut sim = Simulator::new(1);
        assert_eq!(
            sim.command("run").unwrap_err(),
            "usage: run N (run N cycles (at most 1000000), stopping at a breakpoint)"
        );
        assert!(
            sim.command("force in 3")
                .unwrap_err()
                .starts_with("usage: force in|out POINT on|off"),
        );
        assert_eq!(
            sim.command("break").unwrap_err(),
            "usage: break cycle N | break in POINT on | break out POINT on|off"
        );
        assert!(
            sim.command("show me")
                .unwrap_err()
                .starts_with("usage: show")
        );
        assert!(sim.command("continue").is_ok());
    }

    #[test]
    fn cont_says_it_stopped_at_its_limit() {
        let mut sim = Simulator::new(1);
        let text = sim.command("cont").unwrap();
        assert!(
            text.contains("ran 72000 cycles: stopped at cont's limit of 72000 cycles"),
            "{text}"
        );
    }
}
