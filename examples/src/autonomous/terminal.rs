//! The terminal dialogue of the 1985 controller: the start-up questions with the source's limits
//! and messages, the live status line, the change mode, and alarm acknowledge with C.
//!
//! The dialogue is a line-by-line state machine: every line the operator types goes to
//! [`Terminal::startup_line`] and then [`Terminal::running_line`], which return
//! what the terminal prints.

use regler_pid::{Action, Code, Config, Kind, Parameters, Scalar, Scaling, Station};

use super::keypad::trim;

/// The start-up questions, in the source's order (type-dependent ones are skipped).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(missing_docs, reason = "each variant is the question its prompt asks")]
pub enum Question {
    Type,
    S,
    Ymin,
    Ymax,
    Dymax,
    Kp,
    Ti,
    Td,
    ScaleMin,
    ScaleMax,
    Direction,
    Rfel,
    Win,
    Start,
}

impl Question {
    fn prompt(self) -> &'static str {
        match self {
            Question::Type => "REGULATOR TYPE (P,I,D,PI,PD,ID,PID) ?>",
            Question::S => "SAMPLING PERIOD S (1-255 SEC.) ?>",
            Question::Ymin => "LOW OUTPUT LIMIT YMIN (0-10 VOLT) ?>",
            Question::Ymax => "HIGH OUTPUT LIMIT YMAX (0-10 VOLT) ?>",
            Question::Dymax => "MAX DER. OUTPUT Dymax (VOLT) ?>",
            Question::Kp => "GAIN KP ?>",
            Question::Ti => "INTEGRATION TIME TI ?>",
            Question::Td => "DERIVATION TIME TD ?>",
            Question::ScaleMin => "SCALE MIN ?>",
            Question::ScaleMax => "SCALE MAX ?>",
            Question::Direction => "DIRECT OR REVERSE UTYPE (DIR/REV) ?>",
            Question::Rfel => "MAX ERROR RFEL (SCALE UNIT) ?>",
            Question::Win => "REFERENCE WIN (SCALEMIN-SCALEMAX) ?>",
            Question::Start => "TO START THE REGULATOR PRESS (CR) !",
        }
    }

    fn next(self, kind: Kind) -> Question {
        let order = [
            Question::Type,
            Question::S,
            Question::Ymin,
            Question::Ymax,
            Question::Dymax,
            Question::Kp,
            Question::Ti,
            Question::Td,
            Question::ScaleMin,
            Question::ScaleMax,
            Question::Direction,
            Question::Rfel,
            Question::Win,
            Question::Start,
        ];
        let at = order
            .iter()
            .position(|q| *q == self)
            .unwrap_or(order.len() - 1);
        order
            .iter()
            .skip(at + 1)
            .copied()
            .find(|q| match q {
                Question::Kp => kind.has_p(),
                Question::Ti => kind.has_i(),
                Question::Td => kind.has_d(),
                _ => true,
            })
            .unwrap_or(Question::Start)
    }
}

/// What the start-up dialogue has collected.
#[derive(Clone, Copy, Debug)]
pub struct Draft {
    config: Config,
    scale_min: f64,
    scale_max: f64,
    rfel: f64,
    win: f64,
}

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

/// The start-up dialogue's result.
#[derive(Clone, Copy, Debug)]
pub struct Startup {
    /// The controller parameters.
    pub params: Parameters,
    /// The measurement scale.
    pub scaling: Scaling,
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
    /// A terminal at power-on, asking the first question.
    #[must_use]
    pub fn new() -> Terminal {
        let config = Config {
            dymax: None,
            ..Config::default()
        };
        Terminal::Startup {
            question: Question::Type,
            draft: Draft {
                config,
                scale_min: 0.0,
                scale_max: 0.0,
                rfel: 0.0,
                win: 0.0,
            },
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

    /// One line typed during start-up. Returns the printed lines, and the start-up result once
    /// the operator pressed CR at the end.
    pub fn startup_line(&mut self, line: &str) -> (Vec<String>, Option<Startup>) {
        let Terminal::Startup { question, draft } = self else {
            return (vec!["WRONG COMMAND".into()], None);
        };
        let (q, mut d) = (*question, *draft);
        let mut out = Vec::new();
        let answer = line.trim();
        let number = answer.parse::<f64>().ok().filter(|v| v.is_finite());
        let ok = match (q, number) {
            (Question::Type, _) => match Kind::parse(answer) {
                Some(kind) => {
                    d.config.kind = kind;
                    true
                }
                None => {
                    out.push("WRONG TYPE".into());
                    false
                }
            },
            (Question::S, Some(s)) if (1.0..=255.0).contains(&s) => {
                d.config.h = s;
                true
            }
            (Question::S, Some(s)) => {
                out.push(if s > 255.0 { "SMAX=255" } else { "SMIN=1" }.into());
                false
            }
            (Question::Ymin, Some(v)) if (0.0..=10.0).contains(&v) => {
                d.config.ymin = v;
                true
            }
            (Question::Ymax, Some(v)) if (0.0..=10.0).contains(&v) && v > d.config.ymin => {
                d.config.ymax = v;
                true
            }
            (Question::Ymax, Some(v)) if (0.0..=10.0).contains(&v) => {
                out.push("YMAX <= YMIN ! TRY AGAIN".into());
                false
            }
            (Question::Ymin | Question::Ymax, Some(v)) => {
                out.push(
                    if v < 0.0 {
                        "MINIMUM = 0 V"
                    } else {
                        "MAXIMUM = 10 V"
                    }
                    .into(),
                );
                out.push("TRY AGAIN".into());
                false
            }
            (Question::Dymax, Some(v)) => {
                let v = v.abs();
                d.config.dymax = if v == 0.0 { None } else { Some(v) };
                true
            }
            (Question::Kp, Some(v)) => range(&mut out, v, -1.0, 10_000.0, "KP")
                .then(|| d.config.k = v)
                .is_some(),
            (Question::Ti, Some(v)) if v > 0.0 => range(&mut out, v, 0.0, 1e7, "TI")
                .then(|| d.config.ti = v)
                .is_some(),
            (Question::Ti, Some(_)) => {
                out.push("TIMIN>0".into());
                false
            }
            (Question::Td, Some(v)) => range(&mut out, v, 0.0, 1e7, "TD")
                .then(|| d.config.td = v)
                .is_some(),
            (Question::ScaleMin, Some(v)) => {
                d.scale_min = v;
                true
            }
            (Question::ScaleMax, Some(v)) if v > d.scale_min => {
                d.scale_max = v;
                true
            }
            (Question::ScaleMax, Some(_)) => {
                out.push("SCALEMAX <= SCALEMIN ! TRY AGAIN".into());
                false
            }
            (Question::Direction, _) => match answer.to_ascii_uppercase().as_str() {
                "DIR" => {
                    d.config.action = Action::Direct;
                    true
                }
                "REV" => {
                    d.config.action = Action::Reverse;
                    true
                }
                _ => {
                    out.push("TRY AGAIN".into());
                    false
                }
            },
            (Question::Rfel, Some(v)) => {
                d.rfel = v.abs();
                true
            }
            (Question::Win, Some(v)) if v >= d.scale_min && v <= d.scale_max => {
                d.win = v;
                true
            }
            (Question::Win, Some(v)) => {
                out.push(if v > d.scale_max {
                    format!("SCALEMAX={}", trim(d.scale_max))
                } else {
                    format!("SCALEMIN={}", trim(d.scale_min))
                });
                false
            }
            (Question::Start, _) if answer.is_empty() => {
                let scaling = match Scaling::new(d.scale_min, d.scale_max) {
                    Ok(s) => s,
                    Err(e) => return (vec![e.to_string()], None),
                };
                let params = Parameters {
                    config: d.config,
                    setpoint: d.win,
                    rfel: d.rfel,
                    night_setback: 0.0,
                };
                *self = Terminal::Running;
                return (
                    vec!["REGULATOR STARTED".into()],
                    Some(Startup { params, scaling }),
                );
            }
            (Question::Start, _) => false,
            (_, None) => {
                out.push("TRY AGAIN".into());
                false
            }
        };
        let next = if ok { q.next(d.config.kind) } else { q };
        out.push(next.prompt().into());
        *self = Terminal::Startup {
            question: next,
            draft: d,
        };
        (out, None)
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
                    station.staged_mut().commit();
                    *self = Terminal::Running;
                    return vec!["PARAMETERS COMMITTED".into()];
                }
                let mut out = Vec::new();
                if !answer.is_empty() {
                    let result = super::keypad::stage(station, code, answer);
                    if let Err(e) = result {
                        out.push(if code == Code::Typ {
                            " WRONG TYPE".into()
                        } else {
                            format!(" {e}")
                        });
                        out.push("TRY AGAIN".into());
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
                        station.staged_mut().commit();
                        *self = Terminal::Running;
                        out.push("PARAMETERS COMMITTED".into());
                    }
                }
                out
            }
        }
    }
}

fn range(out: &mut Vec<String>, v: f64, lo: f64, hi: f64, name: &str) -> bool {
    if v > hi {
        out.push(format!("{name}MAX={}", trim(hi)));
        false
    } else if v < lo {
        out.push(format!("{name}MIN={}", trim(lo)));
        false
    } else {
        true
    }
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
    use regler_pid::OperatorLimits;

    fn start(answers: &[&str]) -> (Terminal, Vec<String>, Option<Startup>) {
        let mut t = Terminal::new();
        let mut printed = Vec::new();
        let mut result = None;
        for a in answers {
            let (out, done) = t.startup_line(a);
            printed.extend(out);
            result = result.or(done);
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
}
