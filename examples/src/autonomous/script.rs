//! The operator's timed input: the script format (one command a line, see the
//! [module docs](super)), and the built-in demonstration scripts.

use serde::Serialize;

use super::{Interface, ProcessKind};

/// One operator or plant input.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", content = "value", rename_all = "lowercase")]
pub enum Input {
    /// A line at the terminal.
    Term(String),
    /// Keys on the keypad.
    Keys(String),
    /// The night input.
    Night(bool),
    /// A disturbance step.
    Outdoor(f64),
}

impl std::fmt::Display for Input {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Input::Term(line) => write!(f, "term {line}"),
            Input::Keys(keys) => write!(f, "keys {keys}"),
            Input::Night(on) => write!(f, "night {}", if *on { "on" } else { "off" }),
            Input::Outdoor(delta) => write!(f, "outdoor {delta:+}"),
        }
    }
}

/// A timed input.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Event {
    /// Seconds from the start.
    pub t_s: f64,
    /// The script's line it came from (1 is the first; 0 for input typed interactively).
    pub line: usize,
    /// The input.
    pub input: Input,
}

/// Parses a script (see the module docs). Errors name the line.
pub fn parse_script(text: &str) -> Result<Vec<Event>, String> {
    let mut events = Vec::new();
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim_end();
        if line.trim().is_empty() {
            continue;
        }
        let err = |what: &str| format!("script line {}: {what}: '{}'", n + 1, raw.trim());
        let mut parts = line.trim_start().splitn(3, char::is_whitespace);
        let time = parts.next().ok_or_else(|| err("missing time"))?;
        let kind = parts
            .next()
            .ok_or_else(|| err("missing command (term, keys, night, outdoor)"))?;
        let rest = parts.next().unwrap_or("").trim();
        let t_s = parse_time(time)
            .ok_or_else(|| err("bad time (use 600, 90s, 15m, 2h or hh:mm, within a year)"))?;
        let input = match kind {
            "term" => Input::Term(rest.to_string()),
            "keys" => Input::Keys(rest.to_string()),
            "night" => match rest {
                "on" => Input::Night(true),
                "off" => Input::Night(false),
                _ => return Err(err("night takes on or off")),
            },
            "outdoor" => Input::Outdoor(
                rest.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| err("outdoor takes a number"))?,
            ),
            _ => return Err(err("unknown command (term, keys, night, outdoor)")),
        };
        events.push(Event {
            t_s,
            line: n + 1,
            input,
        });
    }
    events.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
    Ok(events)
}

/// Script times end at a year, the longest run.
const LAST_SCRIPT_S: f64 = 8760.0 * 3600.0;

fn parse_time(s: &str) -> Option<f64> {
    let value = if let Some((h, m)) = s.split_once(':') {
        let (h, m) = (h.parse::<f64>().ok()?, m.parse::<f64>().ok()?);
        (m < 60.0).then_some(h * 3600.0 + m * 60.0)?
    } else if let Some(v) = s.strip_suffix('h') {
        v.parse::<f64>().ok()? * 3600.0
    } else if let Some(v) = s.strip_suffix('m') {
        v.parse::<f64>().ok()? * 60.0
    } else if let Some(v) = s.strip_suffix('s') {
        v.parse::<f64>().ok()?
    } else {
        s.parse::<f64>().ok()?
    };
    (value.is_finite() && (0.0..=LAST_SCRIPT_S).contains(&value)).then_some(value)
}

/// The script used when none is given, one for each way of operating the controller.
///
/// At the terminal: the start-up dialogue, a set-point change on the keypad, an illegal value,
/// the alarm acknowledged, a night set-back, a disturbance and a retune in the change mode. On
/// the keypad alone: every parameter keyed in from the source's keypad start-up values, then the
/// same day of operation on the keys.
#[must_use]
pub fn demo_script(process: ProcessKind, interface: Interface) -> &'static str {
    match (process, interface) {
        (ProcessKind::Room, Interface::Terminal) => {
            "# start-up dialogue at the terminal
0 term PID
0 term 10       # S
0 term 0        # YMIN
0 term 10       # YMAX
0 term 0.5      # DYMAX
0 term 2        # KP
0 term 900      # TI
0 term 60       # TD
0 term 0        # SCALE MIN
0 term 40       # SCALE MAX
0 term DIR
0 term 1.5      # RFEL
0 term 20       # WIN
0 term
# the keypad: WIN 20 -> 22 (the source's example keyed 150 on its own scale)
4h keys * 21 * A 22 A D
# an illegal value stays on the LCD; D with nothing staged is no commit
5h keys * 51 * A 20000 A
5h keys D
6h term C
# night set-back from 22:00 to 06:00
22:00 night on
30:00 night off
# a cold snap
36h outdoor -8
# retune in the change mode: keep TYP and WIN, S 10, KP 3, TI 1200, then quit
40h term Y
40h term
40h term
40h term
40h term 3
40h term 1200
40h term Q
"
        }
        (ProcessKind::Room, Interface::Keypad) => {
            "# the keypad alone: from its start-up values (PID, K 10, Ti 8 s, 1 s, WIN 0) to a room
0 keys * 31 * A 10 A         # S 10 s
0 keys * 51 * A 2 A          # KP 2
0 keys * 71 * A 900 A        # TI 900 s
0 keys * 61 * A 60 A         # TD 60 s
0 keys * 83 * A 0.5 A        # DYMAX 0.5 V a sample
0 keys * 41 * A 1.5 A        # RFEL 1.5
0 keys * 21 * A 20 A D       # WIN 20, and commit them all at the next sample
4h keys * 21 * A 22 A D
5h keys * 51 * A 20000 A     # ILLEGAL VALUE stays on the LCD
5h keys D                    # nothing staged: no commit
6h keys C                    # acknowledge the alarm
22:00 night on
30:00 night off
36h outdoor -8
40h keys * 51 * A 3 A * 71 * A 1200 A D
"
        }
        (ProcessKind::Tank, Interface::Terminal) => {
            "0 term PI
0 term 1        # S
0 term 0
0 term 10
0 term 0        # DYMAX: no limit
0 term 1.5      # KP
0 term 40       # TI
0 term 0
0 term 100
0 term DIR
0 term 5        # RFEL
0 term 50       # WIN
0 term
10m keys * 21 * A 70 A D
20m outdoor 10
30m keys * 10 * A P I D A * 61 * A 1 A D
"
        }
        (ProcessKind::Tank, Interface::Keypad) => {
            "# the keypad alone: a PI for the tank from the keypad start-up values
0 keys * 10 * A P I A        # TYP PI
0 keys * 51 * A 1.5 A        # KP 1.5
0 keys * 71 * A 40 A         # TI 40 s
0 keys * 41 * A 5 A          # RFEL 5 %
0 keys * 21 * A 50 A D       # WIN 50 %, commit
10m keys * 21 * A 70 A D
20m outdoor 10
30m keys * 10 * A P I D A * 61 * A 1 A D
"
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn script_times_and_errors() {
        let events =
            parse_script("# c\n90s term PI\n2h keys * 21 *\n22:30 night on\n10m outdoor -3\n")
                .unwrap();
        let times: Vec<f64> = events.iter().map(|e| e.t_s).collect();
        assert_eq!(times, [90.0, 600.0, 7200.0, 81_000.0]);
        assert!(parse_script("x term").unwrap_err().contains("line 1"));
        assert!(
            parse_script("0 dance")
                .unwrap_err()
                .contains("unknown command")
        );
        assert!(parse_script("0 night maybe").is_err());
        assert!(parse_script("10:75 night on").is_err());
    }
}
