//! The operator at level 2: the source's keys (L, O, S, F, P, T, C M J, 1–8, Shift 1–8,
//! Break), parsed from a script or typed, and the keyboard that answers them with lines of text.

use super::boards::{Board, mode_name};
use super::master::Host;
use super::summary::{Link, summarise};
use super::{Config, JOBS, RING};
use crate::cli::number;

/// An operator key of the level-2 keyboard.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// L: lock the keyboard.
    Lock,
    /// O: open it.
    Open,
    /// S: the dynamic flow of every machine.
    Flow,
    /// F: the jobs in memory.
    Jobs,
    /// P: the report.
    Report,
    /// T: key parameters.
    Parameters,
    /// C m j: machine m changes to job j after the current one.
    Change(usize, u32),
    /// 1–8: a machine's status.
    Status(usize),
    /// Shift 1–8: re-initialise a machine's interface.
    Reinit(usize),
    /// Break: back to the scheduler (ends the run).
    Break,
}

/// The keys, for a message that refuses one.
pub const KEYS: &str = "L (lock), O (open), S (flow), F (jobs), P (report), T (parameters), \
                        C M J (machine M changes to job J), a machine number (its status), \
                        shift N (re-initialise machine N's interface), break";

impl Key {
    /// Parses a key as words: `L`, `O`, `S`, `F`, `P`, `T`, `C M J`, `N` (a machine's status),
    /// `shift N`, `break` (case does not matter), for a run of `machines` machines.
    ///
    /// # Errors
    /// What was wrong: an unknown key (and the keys there are), a machine that is not there, a
    /// job the master does not hold.
    pub fn parse(words: &[&str], machines: usize) -> Result<Self, String> {
        let machine = |w: Option<&&str>| -> Result<usize, String> {
            let w = w.ok_or(format!("machine number missing (1 to {machines})"))?;
            match w.parse::<usize>() {
                Ok(n) if (1..=machines).contains(&n) => Ok(n),
                _ => Err(format!(
                    "no machine {w}: the machines are 1 to {machines} (--machines)"
                )),
            }
        };
        let job = |w: Option<&&str>| -> Result<u32, String> {
            let w = w.ok_or(format!("job number missing (0 to {})", JOBS - 1))?;
            match w.parse::<u32>() {
                Ok(j) if j < JOBS => Ok(j),
                _ => Err(format!(
                    "job {w} does not exist: the master holds jobs 0 to {}",
                    JOBS - 1
                )),
            }
        };
        let too_many = |expected: usize| -> Result<(), String> {
            if words.len() > expected {
                Err(format!(
                    "'{}' is too much: the key takes {} word{}",
                    words[expected..].join(" "),
                    expected,
                    if expected == 1 { "" } else { "s" }
                ))
            } else {
                Ok(())
            }
        };
        let Some(first) = words.first() else {
            return Err(format!("key missing; the keys are {KEYS}"));
        };
        let key = match first.to_ascii_lowercase().as_str() {
            "l" => Self::Lock,
            "o" => Self::Open,
            "s" => Self::Flow,
            "f" => Self::Jobs,
            "p" => Self::Report,
            "t" => Self::Parameters,
            "break" | "b" => Self::Break,
            "c" => {
                let key = Self::Change(machine(words.get(1))?, job(words.get(2))?);
                too_many(3)?;
                return Ok(key);
            }
            "shift" => {
                let key = Self::Reinit(machine(words.get(1))?);
                too_many(2)?;
                return Ok(key);
            }
            w if w.bytes().all(|b| b.is_ascii_digit()) => Self::Status(machine(Some(first))?),
            _ => return Err(format!("unknown key '{first}'; the keys are {KEYS}")),
        };
        too_many(1)?;
        Ok(key)
    }
}

/// A timed key of a script.
#[derive(Clone, Debug)]
pub struct Timed {
    /// Simulated seconds.
    pub at: f64,
    /// The key.
    pub key: Key,
}

/// Parses a script for a run of `config`: lines `SECONDS KEY…`, `#` comments.
///
/// # Errors
/// `line N: ` what was wrong, and the line: a time that is not a number of seconds or after
/// the run's end, or a key [`Key::parse`] refuses.
pub fn parse_script(text: &str, config: &Config) -> Result<Vec<Timed>, String> {
    let mut out = Vec::new();
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some((time, key)) = words.split_first() else {
            continue;
        };
        let err = |what: String| format!("line {}: {what} ('{}')", n + 1, raw.trim());
        let at: f64 = time
            .parse()
            .map_err(|_| err(format!("the time must be seconds, got '{time}'")))?;
        if !(at.is_finite() && at >= 0.0) {
            return Err(err(format!(
                "the time must be 0 seconds or more, got {time}"
            )));
        }
        if at > config.seconds {
            return Err(err(format!(
                "the key at {} s would come after the run's end at {} s (--seconds)",
                number(at),
                number(config.seconds)
            )));
        }
        let key = Key::parse(key, config.machines).map_err(err)?;
        out.push(Timed { at, key });
    }
    out.sort_by(|a, b| a.at.total_cmp(&b.at));
    Ok(out)
}

/// The operator's keyboard at level 2: answers keys with lines of text.
#[derive(Debug, Default)]
pub struct Keyboard {
    locked: bool,
    /// Everything answered so far.
    pub screen: Vec<String>,
}

impl Keyboard {
    /// Answers one key; `true` when the key was Break.
    pub fn key(
        &mut self,
        key: Key,
        link: Link,
        boards: &[Board],
        host: &mut Host,
        config: &Config,
    ) -> bool {
        let now_s = link.elapsed_ns as f64 / 1e9;
        let mut say = |line: String| self.screen.push(format!("[{now_s:7.2} s] {line}"));
        if self.locked && key != Key::Open {
            say("keyboard locked (O opens it)".into());
            return false;
        }
        let machine = |n: usize| (1..=boards.len()).contains(&n).then(|| n - 1);
        match key {
            Key::Lock => {
                self.locked = true;
                say("keyboard locked".into());
            }
            Key::Open => {
                self.locked = false;
                say("keyboard open".into());
            }
            Key::Flow => {
                for b in boards {
                    let st = host.master.status(b.index).unwrap_or_default();
                    let (row, _) = b.slave().position();
                    say(format!(
                        "flow {:>3}: {:<10} row {row:>5}  ring {:>3}/{RING}  owed {:>3}  sent {:>8}  missed {}",
                        b.index + 1,
                        mode_name(b.slave().mode()),
                        b.slave().slack(),
                        st.owed,
                        st.sent,
                        st.missed
                    ));
                }
            }
            Key::Jobs => {
                for (i, jobs) in host.jobs.iter().enumerate() {
                    let row = host.master.status(i).map(|s| s.sent).unwrap_or(0)
                        / u64::from(config.needles);
                    let (job, next) = jobs.shown(row);
                    let next = next.map_or("-".to_string(), |j| j.to_string());
                    say(format!("jobs {:>3}: job {job} now, next {next}", i + 1));
                }
            }
            Key::Report => {
                let s = summarise(config, "in memory", boards, host, link, Vec::new());
                for line in s.table().lines() {
                    say(line.to_string());
                }
            }
            Key::Parameters => {
                let t0s: Vec<u64> = boards.iter().map(|b| b.t0_ns).collect();
                let cap = config.capacity(&t0s);
                say(format!(
                    "parameters: {} machines, {} needles, ring {RING}, byte {} ns, batch {}, loss {}, duplicate {}, silence {} needles",
                    boards.len(),
                    config.needles,
                    config.byte_ns,
                    config.batch,
                    config.loss,
                    config.duplicate,
                    config.silence_needles
                ));
                say(format!(
                    "capacity: {} ({}), up to {} machines",
                    cap.verdict,
                    cap.utilisation(),
                    cap.max_machines_at_fastest
                ));
            }
            Key::Change(n, job) => match machine(n) {
                Some(m) => {
                    host.jobs[m].change_after_current(job);
                    say(format!("machine {n}: job {job} after the current one"));
                }
                None => say(format!("no machine {n}")),
            },
            Key::Status(n) => match machine(n) {
                Some(m) => say(boards[m].status_line()),
                None => say(format!("no machine {n}")),
            },
            Key::Reinit(n) => match machine(n) {
                Some(m) => {
                    let _ = host.master.reinit(m);
                    say(format!("machine {n}: interface re-initialised"));
                }
                None => say(format!("no machine {n}")),
            },
            Key::Break => {
                say("break: back to the scheduler".into());
                return true;
            }
        }
        false
    }
}
