//! The 4×5 keypad and 2×24 LCD of the 1985 controller, as a key-by-key state machine.
//!
//! ```text
//!  7 8 9 P C        digits, '.', '-'   codes and values
//!  4 5 6 I D        P I D              controller type (while entering TYP)
//!  1 2 3 D D        *                  keypad mode; show the parameter whose code was keyed
//!  0 . - * A        A                  alter the shown parameter; A again confirms
//!                   D                  commit every change (the source's ☒ key), back to display
//!                   C                  acknowledge the alarm
//! ```
//!
//! The source's example `* 21 * A 150 A D` changes the set-point WIN to 150: `*` enters keypad
//! mode ("CODE=?"), `21 *` shows WIN, `A` asks "WIN=?", `150 A` stages the value, `D` commits.

use regler_pid::{Code, EditError, Kind, Scalar, Staged, Station};

/// Characters on one line of the LCD.
pub const LCD_WIDTH: usize = 24;

/// The two LCD lines.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Lcd {
    /// Upper line: the shown parameter's active value, or the status.
    pub top: String,
    /// Lower line: the prompt or a message.
    pub bottom: String,
}

impl Lcd {
    fn set(&mut self, top: Option<String>, bottom: String) {
        if let Some(top) = top {
            self.top = fit(&top);
        }
        self.bottom = fit(&bottom);
    }

    /// The display drawn in a frame, as the example prints it.
    #[must_use]
    pub fn render(&self) -> String {
        let border = format!("+{}+", "-".repeat(LCD_WIDTH));
        format!(
            "{border}\n|{:<w$}|\n|{:<w$}|\n{border}",
            self.top,
            self.bottom,
            w = LCD_WIDTH
        )
    }
}

fn fit(s: &str) -> String {
    s.chars().take(LCD_WIDTH).collect()
}

#[derive(Clone, Debug, PartialEq)]
enum State {
    /// Not in keypad mode: the terminal has the operator.
    Display,
    /// "CODE=?" with the digits so far.
    Code(String),
    /// A parameter is shown; `A` alters it.
    Shown(Code),
    /// "WIN=?" with the entry so far.
    Entering(Code, String),
}

/// What a key did, for the example's log.
#[derive(Clone, Debug, PartialEq)]
pub enum KeyEffect {
    /// Nothing beyond the display.
    None,
    /// A value was staged.
    Staged(Code),
    /// The operator committed the staged values.
    Committed,
    /// The alarm was acknowledged.
    Acknowledged,
    /// An error message was shown.
    Message(&'static str),
}

/// The keypad and its LCD.
#[derive(Clone, Debug)]
pub struct Keypad {
    state: State,
    lcd: Lcd,
    /// The last parameter staged, shown with its new value after the commit.
    last_staged: Option<Code>,
}

impl Default for Keypad {
    fn default() -> Keypad {
        Keypad::new()
    }
}

impl Keypad {
    /// The keypad, in display mode.
    #[must_use]
    pub fn new() -> Keypad {
        Keypad {
            state: State::Display,
            lcd: Lcd::default(),
            last_staged: None,
        }
    }

    /// The LCD.
    #[must_use]
    pub fn lcd(&self) -> &Lcd {
        &self.lcd
    }

    /// Whether the keypad has the operator (keypad mode).
    #[must_use]
    pub fn active(&self) -> bool {
        self.state != State::Display
    }

    /// Refreshes the status line in display mode (XIN and Y, as the source's LCD showed).
    pub fn show_status<T: Scalar>(&mut self, station: &Station<T>) {
        if self.state == State::Display {
            let xin = station.value(Code::Xin).unwrap_or(f64::NAN);
            let y = station.value(Code::Y).unwrap_or(f64::NAN);
            self.lcd
                .set(Some(format!("XIN={xin:.1} Y={y:.2}")), String::new());
        }
    }

    /// One key press. Unknown characters are WRONG COMMAND.
    pub fn press<T: Scalar>(&mut self, key: char, station: &mut Station<T>) -> KeyEffect {
        let key = key.to_ascii_uppercase();
        match (self.state.clone(), key) {
            (State::Entering(code, mut text), k) if entry_key(code, k) => {
                text.push(k);
                self.lcd.set(None, format!("{}=?{text}", code.name()));
                self.state = State::Entering(code, text);
                KeyEffect::None
            }
            (State::Entering(code, text), 'A') => self.confirm(code, &text, station),
            (_, 'C') => {
                station.acknowledge();
                KeyEffect::Acknowledged
            }
            (State::Display, '*') => {
                self.state = State::Code(String::new());
                self.lcd.set(None, "CODE=?".into());
                KeyEffect::None
            }
            (State::Code(mut digits), k) if k.is_ascii_digit() => {
                digits.push(k);
                self.lcd.set(None, format!("CODE=?{digits}"));
                self.state = State::Code(digits);
                KeyEffect::None
            }
            (State::Shown(_), k) if k.is_ascii_digit() => {
                let digits = k.to_string();
                self.lcd.set(None, format!("CODE=?{digits}"));
                self.state = State::Code(digits);
                KeyEffect::None
            }
            // `*` starts a code from the display; at "CODE=?" with nothing keyed it does the same
            // (an operator starting the next parameter as they started the first).
            (State::Code(digits), '*') if digits.is_empty() => {
                self.lcd.set(None, "CODE=?".into());
                self.state = State::Code(digits);
                KeyEffect::None
            }
            (State::Code(digits), '*') => {
                match digits.parse::<u8>().ok().and_then(Code::from_number) {
                    Some(code) => {
                        self.lcd
                            .set(Some(shown_value(code, station)), "CODE=?".into());
                        self.state = State::Shown(code);
                        KeyEffect::None
                    }
                    None => {
                        self.lcd.set(None, "WRONG CODE".into());
                        self.state = State::Code(String::new());
                        KeyEffect::Message("WRONG CODE")
                    }
                }
            }
            (State::Shown(code), 'A') if code.writable() => {
                self.lcd.set(None, format!("{}=?", code.name()));
                self.state = State::Entering(code, String::new());
                KeyEffect::None
            }
            (State::Code(_) | State::Shown(_), 'D') => {
                self.state = State::Display;
                if !station.staged().edited() {
                    // Nothing staged: back to the display, no commit.
                    self.lcd.set(None, String::new());
                    return KeyEffect::None;
                }
                station.staged_mut().commit();
                // The value that will be in force from the next sample.
                let upper = self
                    .last_staged
                    .map(|code| staged_value(code, station))
                    .unwrap_or_default();
                self.lcd.set(Some(upper), "COMMITTED".into());
                KeyEffect::Committed
            }
            _ => {
                self.lcd.set(None, "WRONG COMMAND".into());
                if matches!(self.state, State::Entering(..)) {
                    self.state = State::Code(String::new());
                }
                KeyEffect::Message("WRONG COMMAND")
            }
        }
    }

    fn confirm<T: Scalar>(
        &mut self,
        code: Code,
        text: &str,
        station: &mut Station<T>,
    ) -> KeyEffect {
        let result = stage(station, code, text);
        self.state = State::Code(String::new());
        match result {
            Ok(()) => {
                self.lcd
                    .set(Some(staged_value(code, station)), "CODE=?".into());
                self.last_staged = Some(code);
                KeyEffect::Staged(code)
            }
            Err(e) => {
                let message = e.display_message();
                self.lcd.set(None, message.into());
                KeyEffect::Message(message)
            }
        }
    }
}

/// Stages an operator's entry for `code`: a controller type (P, PI, …) for TYP, a number for the
/// others. The keypad and the terminal both enter values this way.
pub fn stage<T: Scalar>(
    station: &mut Station<T>,
    code: Code,
    text: &str,
) -> Result<(), StageError> {
    if code == Code::Typ {
        let kind = Kind::parse(text).ok_or(StageError::Edit(EditError::NotANumber(code)))?;
        let mut trial = *station.staged();
        trial.edit_kind(kind).map_err(StageError::Edit)?;
        return try_staged::<T>(station, trial, code);
    }
    let value = text
        .trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| StageError::NotANumber {
            code,
            typed: text.trim().to_string(),
        })?;
    if code == Code::Rfel {
        super::startup::rfel_rule(value).map_err(StageError::Rule)?;
    }
    let mut trial = *station.staged();
    trial.edit(code, value).map_err(StageError::Edit)?;
    try_staged::<T>(station, trial, code)
}

/// Puts an edited copy of the staged set in place if the controller can run its shadow set
/// (the start-up's check, [`super::startup::try_on`]) and YMAX stays above YMIN; else refuses
/// it, the staged set unchanged.
fn try_staged<T: Scalar>(
    station: &mut Station<T>,
    trial: Staged,
    code: Code,
) -> Result<(), StageError> {
    let shadow = *trial.shadow();
    if matches!(code, Code::Ymin | Code::Ymax) && shadow.config.ymax <= shadow.config.ymin {
        return Err(StageError::Limits);
    }
    super::startup::try_on::<T>(shadow, trial.scaling(), trial.limits())
        .map_err(StageError::Edit)?;
    *station.staged_mut() = trial;
    Ok(())
}

/// Why an entry was refused: the crate's reason, or text that is no number at all.
#[derive(Clone, Debug, PartialEq)]
pub enum StageError {
    /// The station refused the value.
    Edit(EditError),
    /// What was typed is not a number.
    NotANumber {
        /// The parameter.
        code: Code,
        /// What the operator typed.
        typed: String,
    },
    /// YMAX would not be above YMIN ([`super::startup::LIMITS_RULE`]).
    Limits,
    /// A rule of the terminal's own (RFEL's range), with its message.
    Rule(String),
}

impl StageError {
    /// The source's message for the LCD.
    #[must_use]
    pub fn display_message(&self) -> &'static str {
        match self {
            StageError::Edit(EditError::NotANumber(_))
            | StageError::NotANumber { .. }
            | StageError::Rule(_) => "ILLEGAL VALUE",
            StageError::Limits => "YMAX <= YMIN",
            StageError::Edit(e) => e.display_message(),
        }
    }
}

impl std::fmt::Display for StageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StageError::Edit(e) => e.fmt(f),
            StageError::Limits => f.write_str(super::startup::LIMITS_RULE),
            StageError::Rule(why) => f.write_str(why),
            StageError::NotANumber { code, typed } => {
                write!(
                    f,
                    "ILLEGAL VALUE: {} must be a number, got '{typed}'",
                    code.name()
                )
            }
        }
    }
}

/// Keys that belong to an entry: P, I, D for TYP; digits, '.' and '-' for numbers.
fn entry_key(code: Code, k: char) -> bool {
    if code == Code::Typ {
        matches!(k, 'P' | 'I' | 'D')
    } else {
        k.is_ascii_digit() || k == '.' || k == '-'
    }
}

/// The upper line for a shown parameter: its active value (the staged one is not shown until
/// the commit, as in the source).
fn shown_value<T: Scalar>(code: Code, station: &Station<T>) -> String {
    if code == Code::Typ {
        let p = station.staged().active();
        let dir = if p.config.action == regler_pid::Action::Direct {
            "DIR"
        } else {
            "REV"
        };
        return format!("TYP={} {dir}", p.config.kind);
    }
    match station.value(code) {
        Some(v) => format!("{}={}", code.name(), trim(v)),
        None => format!("{}=?", code.name()),
    }
}

/// The upper line for a staged parameter: the value the shadow set holds for it.
fn staged_value<T: Scalar>(code: Code, station: &Station<T>) -> String {
    if code == Code::Typ {
        return format!("TYP={}", station.staged().shadow().config.kind);
    }
    match station.staged().shadow_value(code) {
        Some(v) => format!("{}={}", code.name(), trim(v)),
        None => format!("{}=?", code.name()),
    }
}

/// A number as the LCD shows it: at most three decimals, no trailing zeros.
#[must_use]
pub fn trim(v: f64) -> String {
    if v.abs() >= 1e9 {
        // 1e300 as typed, not in 301 digits.
        return crate::cli::number(v);
    }
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    match s {
        // A value that is not 0 is never shown as 0 (1e-45 as typed).
        "0" | "-0" if v != 0.0 => crate::cli::number(v),
        "-0" => "0".into(),
        _ => s.into(),
    }
}

/// Splits a key sequence as written in scripts ("* 21 * A 150 A D") into single keys.
#[must_use]
pub fn keys(sequence: &str) -> Vec<char> {
    sequence.chars().filter(|c| !c.is_whitespace()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use regler_pid::{Config, OperatorLimits, Parameters, Scaling};

    fn station() -> Station<f64> {
        let params = Parameters {
            config: Config::default(),
            setpoint: 100.0,
            rfel: 10.0,
            night_setback: 0.0,
        };
        Station::new(
            params,
            Scaling::new(0.0, 200.0).unwrap(),
            OperatorLimits::default(),
        )
        .unwrap()
    }

    fn press_all(pad: &mut Keypad, st: &mut Station<f64>, seq: &str) -> Vec<KeyEffect> {
        keys(seq).into_iter().map(|k| pad.press(k, st)).collect()
    }

    #[test]
    fn the_sources_example_changes_win() {
        let (mut pad, mut st) = (Keypad::new(), station());
        press_all(&mut pad, &mut st, "* 21 *");
        assert_eq!(pad.lcd().top, "WIN=100");
        assert_eq!(pad.lcd().bottom, "CODE=?");
        press_all(&mut pad, &mut st, "A 150");
        assert_eq!(pad.lcd().bottom, "WIN=?150");
        assert_eq!(
            press_all(&mut pad, &mut st, "A"),
            [KeyEffect::Staged(Code::Win)]
        );
        assert_eq!(st.value(Code::Win), Some(100.0), "not in force before D");
        assert_eq!(press_all(&mut pad, &mut st, "D"), [KeyEffect::Committed]);
        assert!(!pad.active());
        st.sample(100.0);
        assert_eq!(st.value(Code::Win), Some(150.0));
    }

    #[test]
    fn type_change_by_letters() {
        let (mut pad, mut st) = (Keypad::new(), station());
        press_all(&mut pad, &mut st, "* 10 * A P I A D");
        st.sample(100.0);
        assert_eq!(st.staged().active().config.kind, Kind::PI);
    }

    #[test]
    fn the_three_messages() {
        let (mut pad, mut st) = (Keypad::new(), station());
        let fx = press_all(&mut pad, &mut st, "* 42 *");
        assert_eq!(fx.last(), Some(&KeyEffect::Message("WRONG CODE")));
        let fx = press_all(&mut pad, &mut st, "21 * A 999 A");
        assert_eq!(fx.last(), Some(&KeyEffect::Message("ILLEGAL VALUE")));
        assert_eq!(pad.lcd().bottom, "ILLEGAL VALUE");
        let fx = press_all(&mut pad, &mut st, "91 * A");
        assert_eq!(fx.last(), Some(&KeyEffect::Message("WRONG COMMAND")));
        let mut fresh = Keypad::new();
        assert_eq!(
            fresh.press('A', &mut st),
            KeyEffect::Message("WRONG COMMAND")
        );
        assert_eq!(
            fresh.press('#', &mut st),
            KeyEffect::Message("WRONG COMMAND")
        );
    }

    #[test]
    fn lcd_lines_never_exceed_24_characters() {
        let (mut pad, mut st) = (Keypad::new(), station());
        press_all(&mut pad, &mut st, "* 21 * A 1234567890123456789012345678");
        assert!(pad.lcd().bottom.chars().count() <= LCD_WIDTH);
        assert_eq!(pad.lcd().render().lines().count(), 4);
    }
}
