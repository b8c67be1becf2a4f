//! The start-up dialogue of the 1985 terminal: the questions in the source's order, each answer
//! checked when it is typed — against the source's limits with its messages (`SMAX=255`,
//! `SCALEMAX <= SCALEMIN ! TRY AGAIN`), and against what the controller can run: the answer is
//! tried on a [`Station`] of the run's number type ([`Number`]) with the answers so far, so a
//! value the controller would refuse (SCALE MAX 1e300, which `f32` cannot hold; a span narrower
//! than the night set-back; DYMAX 1e300) is refused at its question, which is asked again, as the
//! source's terminal did. The answers are tried once more at the final CR; a refusal there goes
//! back to the question to change, so the dialogue never ends in a controller that cannot start.

use std::fmt::Display;

use regler_pid::{
    Action, Code, Config, EditError, Kind, OperatorLimits, Parameter, Parameters, Scalar, Scaling,
    Station,
};

use super::keypad::trim;
use crate::cli::number;

/// The controller's number type: the run's `Station<Number>` computes in it.
pub type Number = f32;

/// The start-up questions, in the source's order (type-dependent ones are skipped).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
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
    /// The prompt, as the source printed it.
    #[must_use]
    pub fn prompt(self) -> &'static str {
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

    /// Its short name in messages: `SCALE MAX`, `KP`, `the final CR`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Question::Type => "REGULATOR TYPE",
            Question::S => "SAMPLING PERIOD S",
            Question::Ymin => "YMIN",
            Question::Ymax => "YMAX",
            Question::Dymax => "DYMAX",
            Question::Kp => "KP",
            Question::Ti => "TI",
            Question::Td => "TD",
            Question::ScaleMin => "SCALE MIN",
            Question::ScaleMax => "SCALE MAX",
            Question::Direction => "DIR/REV",
            Question::Rfel => "RFEL",
            Question::Win => "WIN",
            Question::Start => "the final CR",
        }
    }

    fn next(self, kind: Kind) -> Question {
        const ORDER: [Question; 14] = [
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
        ORDER
            .iter()
            .copied()
            .filter(|q| *q > self)
            .find(|q| match q {
                Question::Kp => kind.has_p(),
                Question::Ti => kind.has_i(),
                Question::Td => kind.has_d(),
                _ => true,
            })
            .unwrap_or(Question::Start)
    }

    /// The question that sets an operator code.
    fn of(code: Code) -> Question {
        match code {
            Code::Typ => Question::Type,
            Code::Win => Question::Win,
            Code::S => Question::S,
            Code::Kp => Question::Kp,
            Code::Ti => Question::Ti,
            Code::Td => Question::Td,
            Code::Ymin => Question::Ymin,
            Code::Ymax => Question::Ymax,
            Code::Dymax => Question::Dymax,
            Code::Rfel => Question::Rfel,
            Code::Y | Code::Xin => Question::Start,
        }
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
    /// The night set-back the run will use (`--night-setback`): it must fit in the scale's span.
    night_setback: f64,
}

impl Draft {
    /// Nothing answered yet; `night_setback` is the set-back the controller will run with.
    #[must_use]
    pub fn new(night_setback: f64) -> Draft {
        Draft {
            config: Config {
                dymax: None,
                ..Config::default()
            },
            scale_min: 0.0,
            scale_max: 0.0,
            rfel: 0.0,
            win: 0.0,
            night_setback,
        }
    }
}

/// The start-up dialogue's result.
#[derive(Clone, Copy, Debug)]
pub struct Startup {
    /// The controller parameters.
    pub params: Parameters,
    /// The measurement scale.
    pub scaling: Scaling,
}

/// What the terminal does with one start-up answer.
#[derive(Debug, Default)]
pub struct Answer {
    /// The lines it prints (the reply, then the next prompt).
    pub lines: Vec<String>,
    /// When the answer was refused: the controller's reply and which question comes again, as
    /// `SMAX=255 (asked again)` or `… (back to SCALE MAX)`.
    pub refused: Option<String>,
    /// The start-up result, once the operator pressed CR at the end.
    pub started: Option<Startup>,
}

/// One answer `line` to question `q`: updates `d`, returns the question now on screen and what
/// the terminal does.
pub(super) fn answer(q: Question, d: &mut Draft, line: &str) -> (Question, Answer) {
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
            out.push(LIMITS_RULE.into());
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
        (Question::ScaleMin, Some(v)) if held(v) => {
            d.scale_min = v;
            true
        }
        (Question::ScaleMin, Some(v)) => {
            out.push(format!(
                "ILLEGAL VALUE: SCALE MIN must be 0 or a normal number within ±{} (the \
                 controller's number type), got {}",
                number_of(Number::MAX),
                crate::cli::number(v)
            ));
            out.push("TRY AGAIN".into());
            false
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
        (Question::Rfel, Some(v)) => match rfel_rule(v) {
            Ok(()) => {
                d.rfel = v;
                true
            }
            Err(why) => {
                out.push(why);
                out.push("TRY AGAIN".into());
                false
            }
        },
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
        (Question::Start, _) => answer.is_empty(),
        (_, None) => {
            out.push("TRY AGAIN".into());
            false
        }
    };
    // The answer is tried on the controller as it will run, with the answers so far.
    let (next, refused, started) = if ok {
        match check(q, d) {
            Ok(started) => (q.next(d.config.kind), false, started),
            Err((why, back)) => {
                out.push(why);
                out.push("TRY AGAIN".into());
                (back, true, None)
            }
        }
    } else {
        (q, true, None)
    };
    if let Some(started) = started {
        out.push("REGULATOR STARTED".into());
        return (
            q,
            Answer {
                lines: out,
                refused: None,
                started: Some(started),
            },
        );
    }
    let refused = refused.then(|| {
        let reply: Vec<&str> = out.iter().map(|l| l.trim()).collect();
        let again = if next == q {
            "asked again".to_string()
        } else {
            format!("back to {}", next.name())
        };
        if reply.is_empty() {
            again
        } else {
            format!("{} ({again})", reply.join(" / "))
        }
    });
    out.push(next.prompt().into());
    (
        next,
        Answer {
            lines: out,
            refused,
            started: None,
        },
    )
}

/// Tries the answers so far on a [`Station`] of the run's number type: the scale once SCALE MAX
/// is answered (before, a stand-in 0..100), RFEL and WIN once answered. At the final CR, the
/// start-up result. A refusal gives the controller's reply and the question to ask again: the
/// one answered, or an earlier one that sets what was refused.
fn check(q: Question, d: &Draft) -> Result<Option<Startup>, (String, Question)> {
    let refuse = |why: String, back: Question| Err((why, back.min(q)));
    let (scaling, night_setback) = if q >= Question::ScaleMax {
        match Scaling::new(d.scale_min, d.scale_max) {
            Ok(s) => (s, d.night_setback),
            Err(e) => return refuse(format!("ILLEGAL VALUE: {}", words(e)), Question::ScaleMax),
        }
    } else {
        match Scaling::new(0.0, 100.0) {
            Ok(s) => (s, 0.0),
            Err(e) => return refuse(words(e), q),
        }
    };
    let params = Parameters {
        config: d.config,
        setpoint: if q >= Question::Win {
            d.win
        } else {
            scaling.min()
        },
        rfel: if q >= Question::Rfel { d.rfel } else { 0.0 },
        night_setback,
    };
    match try_on::<Number>(params, scaling, OperatorLimits::default()) {
        Ok(()) => Ok((q == Question::Start).then_some(Startup { params, scaling })),
        Err(e) => {
            let back = match &e {
                EditError::ScaleUnrepresentable { .. } | EditError::NightSetback(_) => {
                    Question::ScaleMax
                }
                EditError::Config(c) if c.parameter() == Parameter::Tt => Question::S,
                _ => e.code().map_or(q, Question::of),
            };
            let why = match e {
                EditError::NightSetback(v) => format!(
                    "ILLEGAL VALUE: SCALEMAX - SCALEMIN = {} is less than the night set-back {} \
                     (--night-setback)",
                    number(d.scale_max - d.scale_min),
                    number(v)
                ),
                // The library names the parameter whose term fails (`ti = 8`, maybe a stand-in
                // not yet asked): the answer refused is named first.
                EditError::Config(c) => match answered(q, d) {
                    Some(v)
                        if !c
                            .to_string()
                            .to_lowercase()
                            .starts_with(&q.name().to_lowercase()) =>
                    {
                        format!(
                            "ILLEGAL VALUE: {} = {} refused: {}",
                            q.name(),
                            number(v),
                            words(c)
                        )
                    }
                    _ => words(e),
                },
                e => words(e),
            };
            refuse(why, back)
        }
    }
}

/// Tries `params` on a [`Station`] of the number type `T`, as the controller will run them: the
/// check of every start-up answer (`T` = [`Number`]) and of every change-mode answer and commit
/// (the run's station type). A commit of a set that passes lands at the next sample: the
/// station's commit checks what its constructor checks.
///
/// # Errors
/// The library's refusal.
pub fn try_on<T: Scalar>(
    params: Parameters,
    scaling: Scaling,
    limits: OperatorLimits,
) -> Result<(), EditError> {
    Station::<T>::new(params, scaling, limits).map(|_| ())
}

/// The source's rule for the output limits, with its message: YMAX must be above YMIN (equal
/// limits pin the output). The start-up and the change mode both hold it.
pub const LIMITS_RULE: &str = "YMAX <= YMIN ! TRY AGAIN";

/// RFEL must be 0 or more and held by the controller's number type (the alarm compares it in
/// the scale's units); the start-up and the change mode both hold this.
///
/// # Errors
/// The message, with the range.
pub fn rfel_rule(v: f64) -> Result<(), String> {
    if v >= 0.0 && held(v) {
        Ok(())
    } else {
        Err(format!(
            "ILLEGAL VALUE: RFEL must be 0 or from {} to {} (the controller's number type), \
             got {}",
            number_of(Number::MIN_POSITIVE),
            number_of(Number::MAX),
            number(v)
        ))
    }
}

/// The number answered to `q` (`None` for the questions that take words).
fn answered(q: Question, d: &Draft) -> Option<f64> {
    Some(match q {
        Question::S => d.config.h,
        Question::Ymin => d.config.ymin,
        Question::Ymax => d.config.ymax,
        Question::Dymax => d.config.dymax.unwrap_or(0.0),
        Question::Kp => d.config.k,
        Question::Ti => d.config.ti,
        Question::Td => d.config.td,
        Question::ScaleMin => d.scale_min,
        Question::ScaleMax => d.scale_max,
        Question::Rfel => d.rfel,
        Question::Win => d.win,
        Question::Type | Question::Direction | Question::Start => return None,
    })
}

/// Whether the controller's number type holds `v` (strictly inside its range, as the
/// controller's own scale check asks) and `v` is 0 or a normal number (as [`Scaling`] asks).
fn held(v: f64) -> bool {
    let t = <Number as Scalar>::from_real(v);
    t.is_finite() && t.abs() < Number::MAX && (v == 0.0 || v.is_normal())
}

fn number_of(x: Number) -> String {
    number(f64::from(x))
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

/// A message of the controller's library with its numbers as a user writes them: a number
/// printed in more than 12 characters (1e300 in full is 301 digits, 1e-320 has 320) is
/// rewritten by [`cli::number`](crate::cli::number).
pub fn words(message: impl Display) -> String {
    let text = message.to_string();
    let mut out = String::with_capacity(text.len());
    let mut rest = text.as_str();
    while let Some(start) = rest.find(|c: char| c.is_ascii_digit()) {
        out.push_str(&rest[..start]);
        let tail = &rest[start..];
        let len = tail
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(tail.len());
        // A full stop after a number is the sentence's.
        let token = tail[..len].trim_end_matches('.');
        match token.parse::<f64>() {
            Ok(v) if token.len() > 12 => out.push_str(&number(v)),
            _ => out.push_str(token),
        }
        rest = &tail[token.len()..];
    }
    out.push_str(rest);
    out
}

/// The error of a start-up dialogue that did not finish: `why` it ended, the question left
/// unanswered, and every answer refused on the way (each with its line and the reply), so a
/// refusal that made the answers after it shift is seen.
#[must_use]
pub fn unfinished(why: &str, question: Question, refused: &[String]) -> String {
    let mut text = format!(
        "the start-up dialogue is not finished: {why}; {} (\"{}\") was left unanswered",
        question.name(),
        question.prompt()
    );
    if !refused.is_empty() {
        text.push_str("; the controller refused on the way:");
        for r in refused {
            text.push_str("\n  ");
            text.push_str(r);
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_numbers_in_messages_are_written_as_typed() {
        assert_eq!(words(format!("got {}.", 1e300)), "got 1e300.");
        assert_eq!(
            words(format!("SCALEMIN {}, x", -1e300)),
            "SCALEMIN -1e300, x"
        );
        assert_eq!(words(format!("{}", 1e-320)), "1e-320");
        assert_eq!(
            words("KP must be within -1..10000, got 2.5"),
            "KP must be within -1..10000, got 2.5"
        );
    }

    #[test]
    fn a_refusal_names_the_answer_refused() {
        let mut d = Draft::new(0.0);
        let (q, a) = answer(Question::Kp, &mut d, "1.4e-45");
        assert_eq!(q, Question::Kp);
        assert!(
            a.lines[0].starts_with("ILLEGAL VALUE: KP = 1.4e-45 refused: "),
            "{:?}",
            a.lines
        );
        let (_, a) = answer(Question::Rfel, &mut d, "-1");
        assert!(
            a.lines[0].contains("RFEL must be 0 or from"),
            "{:?}",
            a.lines
        );
    }

    #[test]
    fn an_answer_the_controller_cannot_run_is_asked_again() {
        let mut d = Draft::new(3.0);
        d.scale_min = 0.0;
        let (q, a) = answer(Question::ScaleMax, &mut d, "1e300");
        assert_eq!(q, Question::ScaleMax);
        assert!(a.refused.unwrap().ends_with("(asked again)"));
        let (q, a) = answer(Question::ScaleMax, &mut d, "1");
        assert_eq!(q, Question::ScaleMax, "span 1 < night set-back 3");
        assert!(
            a.lines.iter().any(|l| l.contains("night set-back 3")),
            "{:?}",
            a.lines
        );
        let (q, a) = answer(Question::ScaleMax, &mut d, "40");
        assert_eq!((q, a.refused), (Question::Direction, None));
    }
}
