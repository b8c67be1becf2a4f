//! The terminal of the 1985 controller: the start-up dialogue ([`super::startup`], each answer
//! checked as it is typed), the live status line, the change mode, and alarm acknowledge with C.
//!
//! The dialogue is a line-by-line state machine: every line the operator types goes to
//! [`Terminal::startup_line`] and then [`Terminal::running_line`], which return
//! what the terminal prints.

use regler_pid::{Action, Code, EditError, Scalar, Station};

use super::keypad::{StageError, trim};
pub use super::startup::{Answer, Question, Startup};
use super::startup::{Draft, words};

/// The terminal, from power-on to the change mode.
#[derive(Clone, Debug)]
pub enum Terminal {
    /// Asking the start-up questions.
    Startup {
        /// The question on screen.
        question: Question,
        /// The answers so far.
        draft: Draft,
    },
    /// Running: the status line is shown; Y enters the change mode, C acknowledges.
    Running,
    /// The change mode, asking parameter by parameter.
    Changing {
        /// The parameter on screen.
        code: Code,
    },
}

/// The order of the change mode's questions.
const CHANGE_ORDER: [Code; 10] = [
    Code::Typ,
    Code::Win,
    Code::S,
    Code::Kp,
    Code::Ti,
    Code::Td,
    Code::Ymin,
    Code::Ymax,
    Code::Dymax,
    Code::Rfel,
];

impl Default for Terminal {
    fn default() -> Terminal {
        Terminal::new()
    }
}

impl Terminal {
    /// A terminal at power-on, asking the first question, for a controller without a night
    /// set-back.
    #[must_use]
    pub fn new() -> Terminal {
        Terminal::with_night_setback(0.0)
    }

    /// A terminal at power-on for a controller that will run with `night_setback` (the scale
    /// the dialogue asks for must hold it).
    #[must_use]
    pub fn with_night_setback(night_setback: f64) -> Terminal {
        Terminal::Startup {
            question: Question::Type,
            draft: Draft::new(night_setback),
        }
    }

    /// The first prompt, as printed at power-on. The spellings `INITIALITION MODE` and `UTYPE`
    /// are the 1985 program listing's own (TFRT-5323, appendix: the BASIC source), kept as the
    /// operators saw them.
    #[must_use]
    pub fn banner() -> Vec<String> {
        vec!["INITIALITION MODE".into(), Question::Type.prompt().into()]
    }

    /// The start-up question on screen (`None` once the controller runs).
    #[must_use]
    pub fn question(&self) -> Option<Question> {
        match self {
            Terminal::Startup { question, .. } => Some(*question),
            _ => None,
        }
    }

    /// One line typed during start-up: what the terminal prints, whether it refused the
    /// answer, and the start-up result once the operator pressed CR at the end (the terminal
    /// then runs).
    pub fn startup_line(&mut self, line: &str) -> Answer {
        let Terminal::Startup { question, draft } = self else {
            return Answer {
                lines: vec!["WRONG COMMAND".into()],
                refused: Some("WRONG COMMAND".into()),
                started: None,
            };
        };
        let (next, answer) = super::startup::answer(*question, draft, line);
        *question = next;
        if answer.started.is_some() {
            *self = Terminal::Running;
        }
        answer
    }

    /// The live status line.
    #[must_use]
    pub fn status<T: Scalar>(station: &Station<T>) -> String {
        let dir = if station.staged().active().config.action == Action::Direct {
            "DIR"
        } else {
            "REV"
        };
        format!(
            "   XIN= {:<10} Y= {:<10} UTYPE={dir}",
            trim(station.value(Code::Xin).unwrap_or(f64::NAN)),
            trim(station.value(Code::Y).unwrap_or(f64::NAN)),
        )
    }

    /// One line typed while the controller runs.
    pub fn running_line<T: Scalar>(&mut self, line: &str, station: &mut Station<T>) -> Vec<String> {
        let answer = line.trim();
        match self {
            Terminal::Startup { .. } => vec!["WRONG COMMAND".into()],
            Terminal::Running => match answer.to_ascii_uppercase().as_str() {
                "Y" => {
                    *self = Terminal::Changing { code: Code::Typ };
                    vec![
                        "CHANGE MODE".into(),
                        "IF YOU DON'T WANT TO CHANGE ANY MORE PARAMETERS PRESS Q".into(),
                        prompt(Code::Typ, station),
                    ]
                }
                "C" => {
                    station.acknowledge();
                    vec!["ALARM ACKNOWLEDGED".into()]
                }
                "" => vec![Terminal::status(station)],
                _ => vec!["WRONG COMMAND".into()],
            },
            Terminal::Changing { code } => {
                let code = *code;
                if answer.eq_ignore_ascii_case("Q") {
                    *self = Terminal::Running;
                    return commit(station);
                }
                let mut out = Vec::new();
                if !answer.is_empty() {
                    let result = super::keypad::stage(station, code, answer);
                    if let Err(e) = result {
                        let why = if code == Code::Typ
                            && matches!(e, StageError::Edit(EditError::NotANumber(_)))
                        {
                            " WRONG TYPE".into()
                        } else {
                            format!(" {}", words(e))
                        };
                        let again = why.ends_with("TRY AGAIN");
                        out.push(why);
                        if !again {
                            out.push("TRY AGAIN".into());
                        }
                        out.push(prompt(code, station));
                        return out;
                    }
                }
                let kind = station.staged().shadow().config.kind;
                let next = CHANGE_ORDER
                    .iter()
                    .skip_while(|c| **c != code)
                    .skip(1)
                    .copied()
                    .find(|c| match c {
                        Code::Kp => kind.has_p(),
                        Code::Ti => kind.has_i(),
                        Code::Td => kind.has_d(),
                        _ => true,
                    });
                match next {
                    Some(next) => {
                        *self = Terminal::Changing { code: next };
                        out.push(prompt(next, station));
                    }
                    None => {
                        *self = Terminal::Running;
                        out.extend(commit(station));
                    }
                }
                out
            }
        }
    }
}

/// The end of the change mode: the shadow set is committed if the controller can run it (the
/// check the station's commit makes at the next sample, [`super::startup::try_on`]); else the
/// commit is refused, the edits are discarded and the values in force are shown.
fn commit<T: Scalar>(station: &mut Station<T>) -> Vec<String> {
    let staged = station.staged();
    match super::startup::try_on::<T>(*staged.shadow(), staged.scaling(), staged.limits()) {
        Ok(()) => {
            station.staged_mut().commit();
            vec!["PARAMETERS COMMITTED".into()]
        }
        Err(e) => refused_commit(station, &words(e)),
    }
}

/// A commit the controller refused (`why`): the edits are discarded, the terminal says so and
/// shows the values in force.
pub fn refused_commit<T: Scalar>(station: &mut Station<T>, why: &str) -> Vec<String> {
    station.staged_mut().discard();
    vec![format!("COMMIT REFUSED: {why}"), in_force(station)]
}

/// The parameters the controller runs on, as one line.
#[must_use]
pub fn in_force<T: Scalar>(station: &Station<T>) -> String {
    let active = station.staged().active();
    let mut text = format!("IN FORCE: TYP={}", active.config.kind);
    for code in &CHANGE_ORDER[1..] {
        if let Some(v) = station.staged().active_value(*code) {
            text.push_str(&format!(" {}={}", code.name(), trim(v)));
        }
    }
    text
}

fn prompt<T: Scalar>(code: Code, station: &Station<T>) -> String {
    let shadow = station.staged().shadow();
    let value = match code {
        Code::Typ => shadow.config.kind.to_string(),
        Code::Win => trim(shadow.setpoint),
        Code::S => trim(shadow.config.h),
        Code::Kp => trim(shadow.config.k),
        Code::Ti => trim(shadow.config.ti),
        Code::Td => trim(shadow.config.td),
        Code::Ymin => trim(shadow.config.ymin),
        Code::Ymax => trim(shadow.config.ymax),
        Code::Dymax => trim(shadow.config.dymax.unwrap_or(0.0)),
        Code::Rfel => trim(shadow.rfel),
        Code::Y | Code::Xin => String::new(),
    };
    format!("{}={value}    {} ?>", code.name(), code.name())
}

#[cfg(test)]
mod tests {
    use super::*;
    use regler_pid::{Action, Kind, OperatorLimits};

    fn start(answers: &[&str]) -> (Terminal, Vec<String>, Option<Startup>) {
        let mut t = Terminal::new();
        let mut printed = Vec::new();
        let mut result = None;
        for a in answers {
            let answer = t.startup_line(a);
            printed.extend(answer.lines);
            result = result.or(answer.started);
        }
        (t, printed, result)
    }

    #[test]
    fn startup_with_the_sources_limits_and_messages() {
        let answers = [
            "PX", "PID", // WRONG TYPE, then PID
            "300", "0", "5", // S: SMAX=255, SMIN=1, then 5
            "-1", "0", // YMIN: MINIMUM = 0 V, then 0
            "10", "0", // YMAX, DYMAX
            "20000", "2", // KP: KPMAX=10000, then 2
            "0", "8", // TI: must be > 0, then 8
            "1", "0", // TD, SCALE MIN
            "-5", "40", // SCALE MAX: SCALEMAX <= SCALEMIN, then 40
            "MAYBE", "DIR", "2", // direction, RFEL
            "50", "21", "", // WIN: SCALEMAX=40, then 21; CR starts
        ];
        let (t, printed, result) = start(&answers);
        for message in [
            "WRONG TYPE",
            "SMAX=255",
            "MINIMUM = 0 V",
            "KPMAX=10000",
            "TIMIN>0",
            "SCALEMAX <= SCALEMIN ! TRY AGAIN",
            "SCALEMAX=40",
        ] {
            assert!(
                printed.iter().any(|l| l == message),
                "missing {message}: {printed:?}"
            );
        }
        let s = result.expect("started");
        assert!(matches!(t, Terminal::Running));
        assert_eq!(s.params.config.kind, Kind::PID);
        assert_eq!(
            (s.params.config.h, s.params.config.k, s.params.config.ti),
            (5.0, 2.0, 8.0)
        );
        assert_eq!(s.params.setpoint, 21.0);
        assert_eq!((s.scaling.min(), s.scaling.max()), (0.0, 40.0));
    }

    #[test]
    fn pi_skips_the_derivative_question() {
        let (_, printed, result) = start(&[
            "PI", "10", "0", "10", "0", "3", "60", "0", "100", "REV", "5", "50", "",
        ]);
        assert!(!printed.iter().any(|l| l.starts_with("DERIVATION")));
        assert_eq!(result.unwrap().params.config.action, Action::Reverse);
    }

    #[test]
    fn change_mode_stages_and_commits() {
        let (mut t, _, result) = start(&[
            "PI", "10", "0", "10", "0", "3", "60", "0", "100", "DIR", "5", "50", "",
        ]);
        let s = result.unwrap();
        let mut st = Station::<f64>::new(s.params, s.scaling, OperatorLimits::default()).unwrap();
        st.sample(40.0);
        assert!(Terminal::status(&st).contains("XIN= 40"));
        t.running_line("Y", &mut st);
        t.running_line("", &mut st); // keep TYP
        let out = t.running_line("500", &mut st); // WIN above SCALEMAX
        assert!(out.iter().any(|l| l.contains("ILLEGAL VALUE")), "{out:?}");
        t.running_line("60", &mut st);
        let out = t.running_line("Q", &mut st);
        assert_eq!(out, ["PARAMETERS COMMITTED"]);
        st.sample(40.0);
        assert_eq!(st.value(Code::Win), Some(60.0));
        assert_eq!(t.running_line("C", &mut st), ["ALARM ACKNOWLEDGED"]);
    }

    #[test]
    fn a_commit_the_controller_cannot_run_is_refused_visibly() {
        let (mut t, _, result) = start(&[
            "PI", "10", "0", "10", "0", "3", "60", "0", "100", "DIR", "5", "50", "",
        ]);
        let s = result.unwrap();
        let limits = OperatorLimits::default();
        let mut st = Station::<f32>::new(s.params, s.scaling, limits).unwrap();
        // Typed: refused at its question, asked again.
        t.running_line("Y", &mut st);
        t.running_line("", &mut st);
        t.running_line("60", &mut st);
        t.running_line("", &mut st);
        t.running_line("", &mut st);
        let out = t.running_line("5e-324", &mut st);
        assert!(
            out.iter().any(|l| l.contains("ILLEGAL VALUE: ti")),
            "{out:?}"
        );
        assert_eq!(out.last().map(String::as_str), Some("TI=60    TI ?>"));
        assert_eq!(t.running_line("Q", &mut st), ["PARAMETERS COMMITTED"]);
        st.sample(40.0);
        assert_eq!((st.commits(), st.value(Code::Win)), (1, Some(60.0)));
        // Staged past the terminal's check: the commit is refused, the edits discarded.
        st.staged_mut().edit(Code::Ti, 5e-324).unwrap();
        t.running_line("Y", &mut st);
        let out = t.running_line("Q", &mut st);
        assert!(
            out[0].starts_with("COMMIT REFUSED: ILLEGAL VALUE: ti"),
            "{out:?}"
        );
        assert!(
            out[1].contains("WIN=60") && out[1].contains("TI=60"),
            "{out:?}"
        );
        assert!(!st.staged().commit_pending() && !st.staged().edited());
    }
}
