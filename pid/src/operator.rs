//! The operator layer of the 1985 controller: parameters edited by code into a shadow set, each
//! edit checked on its own, all committed at once at a sample boundary; and the station that
//! ties controller, parameters, alarm and scaling together.

use core::fmt;

use crate::alarm::{Alarm, AlarmState};
use crate::config::{Config, ConfigError, Kind};
use crate::controller::{Inputs, Pid};
use crate::scalar::Scalar;
use crate::scaling::Scaling;

/// The source's parameter codes, as keyed on the keypad (`* 21 * A 150 A`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Code {
    /// 10: controller type.
    Typ,
    /// 21: set-point WIN, in scale units.
    Win,
    /// 31: sample period S, 1–255 s.
    S,
    /// 41: largest allowed error RFEL, in scale units.
    Rfel,
    /// 51: gain KP.
    Kp,
    /// 61: derivative time TD, s.
    Td,
    /// 71: integral time TI, s.
    Ti,
    /// 81: lowest output YMIN, volts.
    Ymin,
    /// 82: highest output YMAX, volts.
    Ymax,
    /// 83: largest output change per sample DYMAX, volts (0: no limit).
    Dymax,
    /// 91: the output Y (read only).
    Y,
    /// 95: the measurement XIN (read only).
    Xin,
}

impl Code {
    /// Every code, in the source's order.
    pub const ALL: [Code; 12] = [
        Code::Typ,
        Code::Win,
        Code::S,
        Code::Rfel,
        Code::Kp,
        Code::Td,
        Code::Ti,
        Code::Ymin,
        Code::Ymax,
        Code::Dymax,
        Code::Y,
        Code::Xin,
    ];

    /// The number keyed for the code.
    #[must_use]
    pub const fn number(self) -> u8 {
        match self {
            Code::Typ => 10,
            Code::Win => 21,
            Code::S => 31,
            Code::Rfel => 41,
            Code::Kp => 51,
            Code::Td => 61,
            Code::Ti => 71,
            Code::Ymin => 81,
            Code::Ymax => 82,
            Code::Dymax => 83,
            Code::Y => 91,
            Code::Xin => 95,
        }
    }

    /// The code keyed as `number`, if there is one.
    #[must_use]
    pub fn from_number(number: u8) -> Option<Code> {
        Code::ALL.into_iter().find(|c| c.number() == number)
    }

    /// The name shown on the display ("WIN").
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Code::Typ => "TYP",
            Code::Win => "WIN",
            Code::S => "S",
            Code::Rfel => "RFEL",
            Code::Kp => "KP",
            Code::Td => "TD",
            Code::Ti => "TI",
            Code::Ymin => "YMIN",
            Code::Ymax => "YMAX",
            Code::Dymax => "DYMAX",
            Code::Y => "Y",
            Code::Xin => "XIN",
        }
    }

    /// Whether the operator may change it (all but Y and XIN).
    #[must_use]
    pub const fn writable(self) -> bool {
        !matches!(self, Code::Y | Code::Xin)
    }
}

impl fmt::Display for Code {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", self.name(), self.number())
    }
}

/// The ranges an operator's entries must fall in; [`Default`] is the source's.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct OperatorLimits {
    /// KP range.
    pub kp: (f64, f64),
    /// TI and TD range, seconds.
    pub time: (f64, f64),
    /// Sample period range, seconds.
    pub sample: (f64, f64),
    /// Output range (YMIN, YMAX), volts.
    pub output: (f64, f64),
}

impl Default for OperatorLimits {
    /// The source's: KP −1..10000, TI and TD 0..10⁷ s, S 1..255 s, output 0..10 V.
    fn default() -> OperatorLimits {
        OperatorLimits {
            kp: (-1.0, 10_000.0),
            time: (0.0, 1e7),
            sample: (1.0, 255.0),
            output: (0.0, 10.0),
        }
    }
}

/// Everything the operator sets: the controller's [`Config`], the set-point and RFEL.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Parameters {
    /// The controller.
    pub config: Config,
    /// WIN, in scale units.
    pub setpoint: f64,
    /// RFEL, the largest error before the alarm, in scale units (≥ 0).
    pub rfel: f64,
    /// Night set-back: subtracted from WIN while the station's night input is on (the
    /// source's wish for two set-points chosen by a digital input); 0 for none.
    pub night_setback: f64,
}

/// An operator's edit that was refused. The shadow set is unchanged.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EditError {
    /// No parameter has this code (the source's WRONG CODE).
    UnknownCode(u8),
    /// Y and XIN can be shown, not changed (WRONG COMMAND).
    ReadOnly(Code),
    /// The value is outside what the parameter allows (ILLEGAL VALUE).
    IllegalValue {
        /// The parameter.
        code: Code,
        /// The value keyed.
        value: f64,
        /// What it must be.
        requirement: &'static str,
    },
    /// TYP was given a value through the number path; use [`Staged::edit_kind`].
    NotANumber(Code),
}

impl EditError {
    /// The source's display message for the error.
    #[must_use]
    pub const fn display_message(&self) -> &'static str {
        match self {
            EditError::UnknownCode(_) => "WRONG CODE",
            EditError::ReadOnly(_) | EditError::NotANumber(_) => "WRONG COMMAND",
            EditError::IllegalValue { .. } => "ILLEGAL VALUE",
        }
    }
}

impl fmt::Display for EditError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            EditError::UnknownCode(n) => write!(f, "WRONG CODE: no parameter has code {n}"),
            EditError::ReadOnly(code) => write!(f, "WRONG COMMAND: {code} is read only"),
            EditError::IllegalValue {
                code,
                value,
                requirement,
            } => {
                write!(
                    f,
                    "ILLEGAL VALUE: {} must be {requirement}, got {value}",
                    code.name()
                )
            }
            EditError::NotANumber(code) => {
                write!(
                    f,
                    "WRONG COMMAND: {code} takes a controller type, not a number"
                )
            }
        }
    }
}

impl core::error::Error for EditError {}

/// The shadow (staged) parameter set of the source: the operator edits it parameter by
/// parameter, each edit checked on its own against the source's limits; the controller runs on
/// the active set until [`commit`](Staged::commit), after which a [`Station`] applies all
/// changes at once at its next sample.
///
/// ```
/// use regler_pid::{Code, Config, OperatorLimits, Parameters, Scaling, Staged};
/// let scaling = Scaling::new(0.0, 200.0)?;
/// let active = Parameters { config: Config::default(), setpoint: 100.0, rfel: 10.0, night_setback: 0.0 };
/// let mut staged = Staged::new(active, scaling, OperatorLimits::default())?;
/// staged.edit(Code::Win, 150.0)?;                        // * 21 * A 150 A
/// assert_eq!(staged.active().setpoint, 100.0);          // still running on the old set
/// assert!(staged.edit(Code::Win, 250.0).is_err());       // ILLEGAL VALUE: above SCALEMAX
/// assert!(staged.edit(Code::Y, 1.0).is_err());           // read only
/// staged.commit();                                       // key D
/// assert_eq!(staged.take_commit().map(|p| p.setpoint), Some(150.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Staged {
    active: Parameters,
    shadow: Parameters,
    scaling: Scaling,
    limits: OperatorLimits,
    commit_requested: bool,
}

impl Staged {
    /// Staged parameters starting from `active` (checked: the config must validate, the
    /// set-point lie on the scale, RFEL be finite and ≥ 0).
    pub fn new(
        active: Parameters,
        scaling: Scaling,
        limits: OperatorLimits,
    ) -> Result<Staged, EditError> {
        let staged = Staged {
            active,
            shadow: active,
            scaling,
            limits,
            commit_requested: false,
        };
        staged.check_whole(Code::Typ, active)?;
        if !scaling.contains(active.setpoint) {
            return Err(EditError::IllegalValue {
                code: Code::Win,
                value: active.setpoint,
                requirement: "between SCALEMIN and SCALEMAX",
            });
        }
        if !(active.rfel.is_finite() && active.rfel >= 0.0) {
            return Err(EditError::IllegalValue {
                code: Code::Rfel,
                value: active.rfel,
                requirement: "a finite value >= 0",
            });
        }
        if !(active.night_setback.is_finite() && active.night_setback >= 0.0) {
            return Err(EditError::IllegalValue {
                code: Code::Win,
                value: active.night_setback,
                requirement: "a night set-back that is finite and >= 0",
            });
        }
        Ok(staged)
    }

    /// Edits one parameter of the shadow set by its code number (as keyed).
    pub fn edit_number(&mut self, code: u8, value: f64) -> Result<(), EditError> {
        let code = Code::from_number(code).ok_or(EditError::UnknownCode(code))?;
        self.edit(code, value)
    }

    /// Edits one parameter of the shadow set. TYP goes through [`edit_kind`](Staged::edit_kind).
    pub fn edit(&mut self, code: Code, value: f64) -> Result<(), EditError> {
        let illegal = |requirement| EditError::IllegalValue {
            code,
            value,
            requirement,
        };
        if !code.writable() {
            return Err(EditError::ReadOnly(code));
        }
        if !value.is_finite() {
            return Err(illegal("a finite number"));
        }
        let within = |(lo, hi): (f64, f64)| value >= lo && value <= hi;
        let l = self.limits;
        let mut next = self.shadow;
        match code {
            Code::Typ => return Err(EditError::NotANumber(code)),
            Code::Win if self.scaling.contains(value) => next.setpoint = value,
            Code::Win => return Err(illegal("between SCALEMIN and SCALEMAX")),
            Code::S if within(l.sample) => next.config.h = value,
            Code::S => return Err(illegal("within the sample-period limits (1-255 s)")),
            Code::Rfel => next.rfel = value.abs(),
            Code::Kp if within(l.kp) => next.config.k = value,
            Code::Kp => return Err(illegal("within the KP limits (-1..10000)")),
            Code::Td if within(l.time) => next.config.td = value,
            Code::Td => return Err(illegal("within the time limits (0..1e7 s)")),
            Code::Ti if within(l.time) => next.config.ti = value,
            Code::Ti => return Err(illegal("within the time limits (0..1e7 s)")),
            Code::Ymin if within(l.output) && value <= next.config.ymax => next.config.ymin = value,
            Code::Ymin => return Err(illegal("within the output range and <= YMAX")),
            Code::Ymax if within(l.output) && value >= next.config.ymin => next.config.ymax = value,
            Code::Ymax => return Err(illegal("within the output range and >= YMIN")),
            Code::Dymax => {
                // The source takes the magnitude; 0 here means no limit (the source's 0 froze
                // the output, which no operator wants).
                let v = value.abs();
                next.config.dymax = if v == 0.0 { None } else { Some(v) };
            }
            Code::Y | Code::Xin => return Err(EditError::ReadOnly(code)),
        }
        self.check_whole(code, next)?;
        self.shadow = next;
        Ok(())
    }

    /// Sets TYP in the shadow set. Refused if the kind needs a TI > 0 and the shadow TI is 0.
    pub fn edit_kind(&mut self, kind: Kind) -> Result<(), EditError> {
        let mut next = self.shadow;
        next.config.kind = kind;
        self.check_whole(Code::Typ, next)?;
        self.shadow = next;
        Ok(())
    }

    fn check_whole(&self, code: Code, next: Parameters) -> Result<(), EditError> {
        next.config.validate().map_err(|e| EditError::IllegalValue {
            code,
            value: match e {
                ConfigError::NotFinite { value, .. } | ConfigError::OutOfRange { value, .. } => {
                    value
                }
                ConfigError::LimitsReversed { ymin, .. } => ymin,
            },
            requirement: match e {
                ConfigError::OutOfRange { requirement, .. } => requirement,
                ConfigError::LimitsReversed { .. } => "such that YMIN <= YMAX",
                _ => "a finite number",
            },
        })
    }

    /// The operator is done (key D, the source's POP): the shadow set becomes active at the
    /// next sample.
    pub fn commit(&mut self) {
        self.commit_requested = true;
    }

    /// Throws the shadow edits away.
    pub fn discard(&mut self) {
        self.shadow = self.active;
        self.commit_requested = false;
    }

    /// Whether a commit waits for the next sample.
    #[must_use]
    pub const fn commit_pending(&self) -> bool {
        self.commit_requested
    }

    /// Whether the shadow set differs from the active one.
    #[must_use]
    pub fn edited(&self) -> bool {
        self.shadow != self.active
    }

    /// At a sample boundary: the parameters to apply now, if the operator committed.
    pub fn take_commit(&mut self) -> Option<Parameters> {
        if !self.commit_requested {
            return None;
        }
        self.commit_requested = false;
        self.active = self.shadow;
        Some(self.active)
    }

    /// The parameters the controller runs on.
    #[must_use]
    pub const fn active(&self) -> &Parameters {
        &self.active
    }

    /// The shadow set being edited.
    #[must_use]
    pub const fn shadow(&self) -> &Parameters {
        &self.shadow
    }

    /// The active value of a numeric parameter (`None` for TYP, Y and XIN, which a
    /// [`Station`] knows).
    #[must_use]
    pub fn active_value(&self, code: Code) -> Option<f64> {
        value_of(&self.active, code)
    }

    /// The measurement scale.
    #[must_use]
    pub const fn scaling(&self) -> Scaling {
        self.scaling
    }
}

fn value_of(p: &Parameters, code: Code) -> Option<f64> {
    Some(match code {
        Code::Win => p.setpoint,
        Code::S => p.config.h,
        Code::Rfel => p.rfel,
        Code::Kp => p.config.k,
        Code::Td => p.config.td,
        Code::Ti => p.config.ti,
        Code::Ymin => p.config.ymin,
        Code::Ymax => p.config.ymax,
        Code::Dymax => p.config.dymax.unwrap_or(0.0),
        Code::Typ | Code::Y | Code::Xin => return None,
    })
}

/// The whole 1985 controller: a [`Pid`], its [`Staged`] parameters, the RFEL [`Alarm`] and the
/// measurement [`Scaling`]. The foreground (operator) edits and commits; the background calls
/// [`sample`](Station::sample) every S seconds, which applies a pending commit first, so all
/// changes land together at a sample boundary, bumplessly.
///
/// ```
/// use regler_pid::{AlarmState, Code, Config, OperatorLimits, Parameters, Scaling, Station};
/// let params = Parameters { config: Config::default(), setpoint: 20.0, rfel: 2.0, night_setback: 0.0 };
/// let mut station = Station::<f32>::new(params, Scaling::new(0.0, 40.0)?, OperatorLimits::default())?;
/// let y = station.sample(15.0);               // 5 degrees below: an alarm, and heat
/// assert!(y > 0.0);
/// assert_eq!(station.alarm().state(), AlarmState::Blinking);
/// station.acknowledge();                      // key C
/// assert_eq!(station.alarm().state(), AlarmState::Steady);
/// station.staged_mut().edit(Code::Win, 18.0)?;
/// station.staged_mut().commit();
/// station.sample(17.0);                       // the new set-point is in force from here
/// assert_eq!(station.value(Code::Win), Some(18.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct Station<T> {
    pid: Pid<T>,
    staged: Staged,
    alarm: Alarm,
    xin: f64,
    y: f64,
    commits: u32,
    night: bool,
    feedforward: f64,
}

impl<T: Scalar> Station<T> {
    /// A station running `params` on `scaling` (fixed at start-up, as in the source).
    pub fn new(
        params: Parameters,
        scaling: Scaling,
        limits: OperatorLimits,
    ) -> Result<Station<T>, EditError> {
        let staged = Staged::new(params, scaling, limits)?;
        let pid = Pid::<T>::new(&params.config).map_err(|_| EditError::IllegalValue {
            code: Code::Typ,
            value: f64::NAN,
            requirement: "a valid configuration",
        })?;
        let y = pid.output().to_f64();
        Ok(Station {
            pid,
            staged,
            alarm: Alarm::new(),
            xin: scaling.min(),
            y,
            commits: 0,
            night: false,
            feedforward: 0.0,
        })
    }

    /// One sample with the measurement `xin` in scale units; returns the output Y in volts.
    /// A pending commit is applied first.
    pub fn sample(&mut self, xin: f64) -> f64 {
        if let Some(p) = self.staged.take_commit() {
            // Validated edit by edit and as a whole: set_config cannot refuse it.
            let _ = self.pid.set_config(&p.config);
            self.commits = self.commits.saturating_add(1);
        }
        let active = self.staged.active;
        let setpoint = self.setpoint();
        self.xin = xin;
        let (r, y) = (T::from_f64(setpoint), T::from_f64(xin));
        self.y = if self.feedforward == 0.0 {
            self.pid.update(r, y)
        } else {
            let inputs = Inputs {
                feedforward: T::from_f64(self.feedforward),
                track: None,
            };
            self.pid.update_with(r, y, inputs)
        }
        .to_f64();
        let error = setpoint - xin;
        // A NaN measurement is an alarm too: the operator must look.
        self.alarm
            .update(error.is_nan() || error.abs() > active.rfel);
        self.y
    }

    /// The set-point in force: WIN, less the night set-back while the night input is on.
    #[must_use]
    pub fn setpoint(&self) -> f64 {
        let active = self.staged.active;
        if self.night {
            active.setpoint - active.night_setback
        } else {
            active.setpoint
        }
    }

    /// The night input (a digital input: a time switch, say).
    pub fn set_night(&mut self, night: bool) {
        self.night = night;
    }

    /// Whether the night input is on.
    #[must_use]
    pub const fn night(&self) -> bool {
        self.night
    }

    /// Feed-forward added to the controller's output from the next sample on, in volts (for
    /// outdoor compensation: the heat the building loses at the present outdoor temperature).
    /// A non-finite value is ignored and counts as 0.
    pub fn set_feedforward(&mut self, volts: f64) {
        self.feedforward = if volts.is_finite() { volts } else { 0.0 };
    }

    /// The operator's acknowledge (key C).
    pub fn acknowledge(&mut self) {
        self.alarm.acknowledge();
    }

    /// The staged parameters, to edit and commit.
    pub fn staged_mut(&mut self) -> &mut Staged {
        &mut self.staged
    }

    /// The staged parameters.
    #[must_use]
    pub const fn staged(&self) -> &Staged {
        &self.staged
    }

    /// The active value of a parameter; Y and XIN are the last sample's.
    #[must_use]
    pub fn value(&self, code: Code) -> Option<f64> {
        match code {
            Code::Y => Some(self.y),
            Code::Xin => Some(self.xin),
            _ => self.staged.active_value(code),
        }
    }

    /// The alarm.
    #[must_use]
    pub const fn alarm(&self) -> &Alarm {
        &self.alarm
    }

    /// The alarm's state.
    #[must_use]
    pub const fn alarm_state(&self) -> AlarmState {
        self.alarm.state()
    }

    /// The controller.
    #[must_use]
    pub const fn pid(&self) -> &Pid<T> {
        &self.pid
    }

    /// The controller, for manual mode and tracking.
    pub fn pid_mut(&mut self) -> &mut Pid<T> {
        &mut self.pid
    }

    /// Commits applied so far.
    #[must_use]
    pub const fn commits(&self) -> u32 {
        self.commits
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn staged() -> Staged {
        let active = Parameters {
            config: Config::default(),
            setpoint: 50.0,
            rfel: 5.0,
            night_setback: 0.0,
        };
        Staged::new(
            active,
            Scaling::new(0.0, 100.0).unwrap(),
            OperatorLimits::default(),
        )
        .unwrap()
    }

    #[test]
    fn codes_round_trip() {
        for code in Code::ALL {
            assert_eq!(Code::from_number(code.number()), Some(code));
        }
        assert_eq!(Code::from_number(42), None);
        assert!(!Code::Y.writable() && !Code::Xin.writable() && Code::Dymax.writable());
    }

    #[test]
    fn each_edit_is_checked_on_its_own() {
        let mut s = staged();
        let illegal = |r: Result<(), EditError>| matches!(r, Err(EditError::IllegalValue { .. }));
        assert!(illegal(s.edit(Code::S, 0.5)));
        assert!(illegal(s.edit(Code::S, 256.0)));
        assert!(illegal(s.edit(Code::Kp, 10_001.0)));
        assert!(illegal(s.edit(Code::Kp, -2.0)));
        assert!(illegal(s.edit(Code::Ti, 0.0))); // PID needs TI > 0
        assert!(illegal(s.edit(Code::Td, -1.0)));
        assert!(illegal(s.edit(Code::Ymin, 11.0)));
        assert!(illegal(s.edit(Code::Ymax, -0.5)));
        assert!(illegal(s.edit(Code::Win, f64::NAN)));
        assert_eq!(s.edit_number(42, 1.0), Err(EditError::UnknownCode(42)));
        assert_eq!(s.edit_number(91, 1.0), Err(EditError::ReadOnly(Code::Y)));
        assert_eq!(
            s.edit(Code::Typ, 1.0),
            Err(EditError::NotANumber(Code::Typ))
        );
        assert!(!s.edited(), "refused edits change nothing");
        s.edit(Code::Ymax, 8.0).unwrap();
        assert!(illegal(s.edit(Code::Ymin, 9.0)));
        s.edit(Code::Rfel, -3.0).unwrap();
        assert_eq!(s.shadow().rfel, 3.0);
        s.edit(Code::Dymax, -0.5).unwrap();
        assert_eq!(s.shadow().config.dymax, Some(0.5));
        s.edit(Code::Dymax, 0.0).unwrap();
        assert_eq!(s.shadow().config.dymax, None);
    }

    #[test]
    fn kind_change_needs_a_valid_ti() {
        let mut s = staged();
        s.edit_kind(Kind::PD).unwrap();
        s.edit(Code::Ti, 0.0).unwrap(); // fine without integral action
        assert!(matches!(
            s.edit_kind(Kind::PI),
            Err(EditError::IllegalValue {
                code: Code::Typ,
                ..
            })
        ));
        s.edit(Code::Ti, 4.0).unwrap();
        s.edit_kind(Kind::PI).unwrap();
    }

    #[test]
    fn messages_are_the_sources() {
        assert_eq!(EditError::UnknownCode(1).display_message(), "WRONG CODE");
        assert_eq!(
            EditError::ReadOnly(Code::Xin).display_message(),
            "WRONG COMMAND"
        );
        let e = staged().edit(Code::Kp, 1e6).unwrap_err();
        assert_eq!(e.display_message(), "ILLEGAL VALUE");
        assert!(e.to_string().contains("KP"));
    }

    #[test]
    fn commit_lands_at_the_next_sample_all_at_once() {
        let params = Parameters {
            config: Config::default(),
            setpoint: 50.0,
            rfel: 5.0,
            night_setback: 0.0,
        };
        let mut st = Station::<f64>::new(
            params,
            Scaling::new(0.0, 100.0).unwrap(),
            OperatorLimits::default(),
        )
        .unwrap();
        st.sample(50.0);
        st.staged_mut().edit(Code::Win, 60.0).unwrap();
        st.staged_mut().edit(Code::Kp, 2.0).unwrap();
        st.sample(50.0);
        assert_eq!(
            st.value(Code::Win),
            Some(50.0),
            "not committed: old set runs"
        );
        st.staged_mut().commit();
        assert!(st.staged().commit_pending());
        assert_eq!(st.value(Code::Kp), Some(10.0));
        st.sample(50.0);
        assert_eq!(
            (st.value(Code::Win), st.value(Code::Kp)),
            (Some(60.0), Some(2.0))
        );
        assert_eq!(st.commits(), 1);
        st.staged_mut().edit(Code::Win, 70.0).unwrap();
        st.staged_mut().discard();
        assert!(!st.staged().edited());
    }

    #[test]
    fn night_input_lowers_the_setpoint_and_feedforward_adds() {
        let config = Config {
            kind: Kind::P,
            k: 1.0,
            ymin: -100.0,
            ymax: 100.0,
            ..Config::default()
        };
        let params = Parameters {
            config,
            setpoint: 20.0,
            rfel: 50.0,
            night_setback: 4.0,
        };
        let mut st = Station::<f64>::new(
            params,
            Scaling::new(0.0, 40.0).unwrap(),
            OperatorLimits::default(),
        )
        .unwrap();
        assert_eq!(st.sample(18.0), 2.0);
        st.set_night(true);
        assert!(st.night());
        assert_eq!(st.setpoint(), 16.0);
        assert_eq!(st.sample(18.0), -2.0);
        st.set_feedforward(1.5);
        assert_eq!(st.sample(18.0), -0.5);
        st.set_feedforward(f64::NAN);
        assert_eq!(st.sample(18.0), -2.0);
        let bad = Parameters {
            night_setback: -1.0,
            ..params
        };
        assert!(
            Staged::new(
                bad,
                Scaling::new(0.0, 40.0).unwrap(),
                OperatorLimits::default()
            )
            .is_err()
        );
    }
}
