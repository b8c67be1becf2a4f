//! The operator layer of the 1985 controller: parameters edited by code into a shadow set, each
//! edit checked on its own, all committed at once at a sample boundary; and the station that
//! ties controller, parameters, alarm and scaling together.
#![allow(
    clippy::arithmetic_side_effects,
    reason = "arithmetic here is on Real (sealed: f32 or f64), which cannot panic or wrap; an overflow is an infinity, and every path checks finiteness"
)]

use core::fmt;

use crate::alarm::{Alarm, AlarmState};
use crate::config::{Config, ConfigError, Kind, Parameter};
use crate::controller::{Inputs, Pid, check_reach};
use crate::real::Real;
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
pub struct OperatorLimits<F = f64> {
    /// KP range.
    pub kp: (F, F),
    /// TI and TD range, seconds.
    pub time: (F, F),
    /// Sample period range, seconds.
    pub sample: (F, F),
    /// Output range (YMIN, YMAX), volts.
    pub output: (F, F),
}

impl<F: Real> Default for OperatorLimits<F> {
    /// The source's: KP −1..10000, TI and TD 0..10⁷ s, S 1..255 s, output 0..10 V.
    fn default() -> OperatorLimits<F> {
        let n = F::from_u16;
        OperatorLimits {
            kp: (-n(1), n(10_000)),
            time: (n(0), n(10_000) * n(1000)),
            sample: (n(1), n(255)),
            output: (n(0), n(10)),
        }
    }
}

impl<F: Real> OperatorLimits<F> {
    /// Checks that every range is finite and ordered; the error names the range.
    pub fn validate(&self) -> Result<(), EditError<F>> {
        for (range, (min, max)) in [
            ("KP", self.kp),
            ("TI/TD", self.time),
            ("S", self.sample),
            ("YMIN/YMAX", self.output),
        ] {
            if !(min.is_finite() && max.is_finite() && min <= max) {
                return Err(EditError::BadLimits { range, min, max });
            }
        }
        Ok(())
    }
}

/// Everything the operator sets: the controller's [`Config`], the set-point and RFEL.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Parameters<F = f64> {
    /// The controller.
    pub config: Config<F>,
    /// WIN, in scale units.
    pub setpoint: F,
    /// RFEL, the largest error before the alarm, in scale units (≥ 0).
    pub rfel: F,
    /// Night set-back: subtracted from WIN while the station's night input is on (the
    /// source's wish for two set-points chosen by a digital input); 0 for none.
    pub night_setback: F,
}

/// What a refused value must be (part of [`EditError::IllegalValue`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Requirement<F = f64> {
    /// A finite number.
    Finite,
    /// Zero or more.
    NonNegative,
    /// Within the operator's limits for the parameter.
    Within {
        /// Lowest allowed.
        min: F,
        /// Highest allowed.
        max: F,
    },
    /// On the measurement scale, SCALEMIN..SCALEMAX.
    OnScale {
        /// SCALEMIN.
        min: F,
        /// SCALEMAX.
        max: F,
    },
    /// At most YMAX (for YMIN).
    AtMostYmax(F),
    /// At least YMIN (for YMAX).
    AtLeastYmin(F),
    /// A value that leaves the whole configuration valid; the inner error says which
    /// parameter breaks it and why.
    ValidConfig(ConfigError<F>),
    /// For TYP: the kind uses a parameter whose staged value is outside the operator's limits
    /// (TI for kinds with I, TD for kinds with D).
    KindUses {
        /// The parameter the kind would bring into use.
        code: Code,
        /// Its staged value.
        value: F,
        /// Lowest allowed.
        min: F,
        /// Highest allowed.
        max: F,
    },
}

impl<F: Real> fmt::Display for Requirement<F> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Requirement::Finite => f.write_str("a finite number"),
            Requirement::NonNegative => f.write_str(">= 0"),
            Requirement::Within { min, max } => write!(f, "within {min}..{max}"),
            Requirement::OnScale { min, max } => {
                write!(f, "between SCALEMIN {min} and SCALEMAX {max}")
            }
            Requirement::AtMostYmax(ymax) => write!(f, "<= YMAX ({ymax})"),
            Requirement::AtLeastYmin(ymin) => write!(f, ">= YMIN ({ymin})"),
            Requirement::ValidConfig(e) => write!(f, "such that {e}"),
            Requirement::KindUses {
                code,
                value,
                min,
                max,
            } => write!(
                f,
                "a kind whose {} ({value}) is within {min}..{max}",
                code.name()
            ),
        }
    }
}

/// An operator's edit, or a starting set, that was refused. The shadow set is unchanged.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EditError<F = f64> {
    /// No parameter has this code (the source's WRONG CODE).
    UnknownCode(u8),
    /// Y and XIN can be shown, not changed (WRONG COMMAND).
    ReadOnly(Code),
    /// The value is outside what the parameter allows (ILLEGAL VALUE).
    IllegalValue {
        /// The parameter.
        code: Code,
        /// The value keyed.
        value: F,
        /// What it must be.
        requirement: Requirement<F>,
    },
    /// TYP was given a value through the number path; use [`Staged::edit_kind`].
    NotANumber(Code),
    /// A starting configuration that does not validate, or that the controller's number type
    /// cannot hold; names the parameter.
    Config(ConfigError<F>),
    /// A starting night set-back that is negative, not finite, or larger than the scale's span
    /// SCALEMAX − SCALEMIN.
    NightSetback(F),
    /// A scale the controller's number type cannot hold (a fixed-point `Station` would clip
    /// the set-point and the measurement, or merge A/D counts): an end or the span beyond the
    /// type's range, or two A/D counts that give the same value in the type.
    ScaleUnrepresentable {
        /// SCALEMIN.
        min: F,
        /// SCALEMAX.
        max: F,
        /// What is wrong.
        reason: &'static str,
    },
    /// One of the [`OperatorLimits`] is not finite or has min > max.
    BadLimits {
        /// Which range: "KP", "TI/TD", "S" or "YMIN/YMAX".
        range: &'static str,
        /// Its lower end.
        min: F,
        /// Its upper end.
        max: F,
    },
}

impl<F> EditError<F> {
    /// The operator code the error is about, where there is one (a configuration error on
    /// N, b, c or Tt has none: those are not on the keypad).
    #[must_use]
    pub const fn code(&self) -> Option<Code> {
        match self {
            EditError::ReadOnly(code)
            | EditError::NotANumber(code)
            | EditError::IllegalValue { code, .. } => Some(*code),
            EditError::Config(e) => code_of(e.parameter()),
            EditError::UnknownCode(_)
            | EditError::NightSetback(_)
            | EditError::ScaleUnrepresentable { .. }
            | EditError::BadLimits { .. } => None,
        }
    }

    /// The source's display message for the error.
    #[must_use]
    pub const fn display_message(&self) -> &'static str {
        match self {
            EditError::UnknownCode(_) => "WRONG CODE",
            EditError::ReadOnly(_) | EditError::NotANumber(_) => "WRONG COMMAND",
            EditError::IllegalValue { .. }
            | EditError::Config(_)
            | EditError::NightSetback(_)
            | EditError::ScaleUnrepresentable { .. }
            | EditError::BadLimits { .. } => "ILLEGAL VALUE",
        }
    }
}

impl<F: Real> fmt::Display for EditError<F> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EditError::UnknownCode(n) => write!(f, "WRONG CODE: no parameter has code {n}"),
            EditError::ReadOnly(code) => write!(f, "WRONG COMMAND: {code} is read only"),
            EditError::IllegalValue {
                code,
                value,
                requirement: Requirement::ValidConfig(e),
            } => write!(f, "ILLEGAL VALUE: {} = {value} refused: {e}", code.name()),
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
            EditError::Config(e) => write!(f, "ILLEGAL VALUE: {e}"),
            EditError::NightSetback(v) => {
                write!(
                    f,
                    "ILLEGAL VALUE: the night set-back must be finite, >= 0 and at most SCALEMAX - SCALEMIN, got {v}"
                )
            }
            EditError::ScaleUnrepresentable { min, max, reason } => write!(
                f,
                "ILLEGAL VALUE: the scale SCALEMIN {min}, SCALEMAX {max} does not fit the controller's number type: {reason}"
            ),
            EditError::BadLimits { range, min, max } => write!(
                f,
                "ILLEGAL VALUE: the operator limits for {range} must be finite with min <= max, got {min}..{max}"
            ),
        }
    }
}

impl<F: Real> core::error::Error for EditError<F> {}

/// The operator code that edits a [`Config`] parameter, if any.
const fn code_of(parameter: Parameter) -> Option<Code> {
    Some(match parameter {
        Parameter::K => Code::Kp,
        Parameter::Ti => Code::Ti,
        Parameter::Td => Code::Td,
        Parameter::H => Code::S,
        Parameter::Ymin => Code::Ymin,
        Parameter::Ymax => Code::Ymax,
        Parameter::Dymax => Code::Dymax,
        _ => return None,
    })
}

/// The shadow (staged) parameter set of the source: the operator edits it parameter by
/// parameter, each edit checked on its own against the source's limits; the controller runs on
/// the active set until [`commit`](Staged::commit), after which a [`Station`] applies all
/// changes at once at its next sample. In `f64` (the default) or `f32`.
///
/// ```
/// use regler_pid::{Code, Config, OperatorLimits, Parameters, Scaling, Staged};
/// let scaling = Scaling::new(0.0, 200.0)?;
/// let active = Parameters { config: Config::default(), setpoint: 100.0, rfel: 10.0, night_setback: 0.0 };
/// let mut staged = Staged::new(active, scaling, OperatorLimits::default())?;
/// staged.edit(Code::Win, 150.0)?;                        // * 21 * A 150 A
/// assert_eq!(staged.active().setpoint, 100.0);          // still running on the old set
/// let refused = staged.edit(Code::Win, 250.0).unwrap_err();
/// assert_eq!(refused.to_string(), "ILLEGAL VALUE: WIN must be between SCALEMIN 0 and SCALEMAX 200, got 250");
/// assert!(staged.edit(Code::Y, 1.0).is_err());           // read only
/// staged.commit();                                       // key D
/// assert_eq!(staged.take_commit().map(|p| p.setpoint), Some(150.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Staged<F = f64> {
    active: Parameters<F>,
    shadow: Parameters<F>,
    scaling: Scaling<F>,
    limits: OperatorLimits<F>,
    /// The shadow set as it was at the last commit, waiting for the next sample.
    pending: Option<Parameters<F>>,
}

impl<F: Real> Staged<F> {
    /// Staged parameters starting from `active`. Checked: the limits themselves
    /// ([`OperatorLimits::validate`]), the config ([`Config::validate`], the error names the
    /// parameter), each operator value within its limits (TI only for kinds with I, TD only for
    /// kinds with D), the set-point on the scale, RFEL finite and ≥ 0, the night set-back finite,
    /// ≥ 0 and at most the scale's span.
    pub fn new(
        active: Parameters<F>,
        scaling: Scaling<F>,
        limits: OperatorLimits<F>,
    ) -> Result<Staged<F>, EditError<F>> {
        limits.validate()?;
        active.config.validate().map_err(EditError::Config)?;
        let staged = Staged {
            active,
            shadow: active,
            scaling,
            limits,
            pending: None,
        };
        let c = active.config;
        let nonneg = |v: F| v.is_finite() && v >= F::zero();
        let checks = [
            (
                Code::Win,
                active.setpoint,
                scaling.contains(active.setpoint),
            ),
            (Code::Rfel, active.rfel, nonneg(active.rfel)),
            (Code::S, c.h, within(limits.sample, c.h)),
            (Code::Kp, c.k, within(limits.kp, c.k)),
            (Code::Ymin, c.ymin, within(limits.output, c.ymin)),
            (Code::Ymax, c.ymax, within(limits.output, c.ymax)),
        ];
        for (code, value, ok) in checks {
            if !ok {
                return Err(EditError::IllegalValue {
                    code,
                    value,
                    requirement: staged.requirement(code),
                });
            }
        }
        // TI and TD only where the kind uses them ([`edit_kind`](Staged::edit_kind) checks
        // them when a kind brings them into use).
        for (code, value, used) in [
            (Code::Ti, c.ti, c.kind.has_i()),
            (Code::Td, c.td, c.kind.has_d()),
        ] {
            if used && !within(limits.time, value) {
                return Err(EditError::IllegalValue {
                    code,
                    value,
                    requirement: staged.requirement(code),
                });
            }
        }
        if !nonneg(active.night_setback) || active.night_setback > scaling.max() - scaling.min() {
            return Err(EditError::NightSetback(active.night_setback));
        }
        Ok(staged)
    }

    /// What a value for `code` must be, with this station's own limits and scale.
    fn requirement(&self, code: Code) -> Requirement<F> {
        let l = self.limits;
        let range = |(min, max): (F, F)| Requirement::Within { min, max };
        match code {
            Code::Win => Requirement::OnScale {
                min: self.scaling.min(),
                max: self.scaling.max(),
            },
            Code::S => range(l.sample),
            Code::Kp => range(l.kp),
            Code::Td | Code::Ti => range(l.time),
            Code::Ymin | Code::Ymax => range(l.output),
            Code::Rfel | Code::Dymax => Requirement::NonNegative,
            Code::Typ | Code::Y | Code::Xin => Requirement::Finite,
        }
    }

    /// Edits one parameter of the shadow set by its code number (as keyed).
    pub fn edit_number(&mut self, code: u8, value: F) -> Result<(), EditError<F>> {
        let code = Code::from_number(code).ok_or(EditError::UnknownCode(code))?;
        self.edit(code, value)
    }

    /// Edits one parameter of the shadow set. TYP goes through [`edit_kind`](Staged::edit_kind).
    pub fn edit(&mut self, code: Code, value: F) -> Result<(), EditError<F>> {
        let illegal = |requirement| EditError::IllegalValue {
            code,
            value,
            requirement,
        };
        if !code.writable() {
            return Err(EditError::ReadOnly(code));
        }
        if code == Code::Typ {
            return Err(EditError::NotANumber(code));
        }
        if !value.is_finite() {
            return Err(illegal(Requirement::Finite));
        }
        let l = self.limits;
        let mut next = self.shadow;
        let in_range = match code {
            Code::Win => self.scaling.contains(value),
            Code::S => within(l.sample, value),
            Code::Kp => within(l.kp, value),
            Code::Td | Code::Ti => within(l.time, value),
            Code::Ymin | Code::Ymax => within(l.output, value),
            _ => true,
        };
        if !in_range {
            return Err(illegal(self.requirement(code)));
        }
        match code {
            Code::Win => next.setpoint = value,
            Code::S => next.config.h = value,
            // The source takes the magnitude of RFEL and DYMAX.
            Code::Rfel => next.rfel = value.abs(),
            Code::Kp => next.config.k = value,
            Code::Td => next.config.td = value,
            Code::Ti => next.config.ti = value,
            Code::Ymin if value > next.config.ymax => {
                return Err(illegal(Requirement::AtMostYmax(next.config.ymax)));
            }
            Code::Ymin => next.config.ymin = value,
            Code::Ymax if value < next.config.ymin => {
                return Err(illegal(Requirement::AtLeastYmin(next.config.ymin)));
            }
            Code::Ymax => next.config.ymax = value,
            // 0 means no limit, here as in Config (the source's 0 froze the output).
            Code::Dymax => next.config.dymax = Some(value.abs()).filter(|d| *d > F::zero()),
            Code::Typ | Code::Y | Code::Xin => return Err(EditError::ReadOnly(code)),
        }
        next.config
            .validate()
            .map_err(|e| illegal(Requirement::ValidConfig(e)))?;
        self.shadow = next;
        Ok(())
    }

    /// Sets TYP in the shadow set. Refused (the shadow set unchanged) if the kind uses a
    /// parameter whose staged value is outside the operator's limits — TI for kinds with I, TD
    /// for kinds with D ([`Requirement::KindUses`]) — or leaves the configuration invalid (a
    /// kind with I and TI 0).
    pub fn edit_kind(&mut self, kind: Kind) -> Result<(), EditError<F>> {
        let mut next = self.shadow;
        next.config.kind = kind;
        let (min, max) = self.limits.time;
        for (code, value, used) in [
            (Code::Ti, next.config.ti, kind.has_i()),
            (Code::Td, next.config.td, kind.has_d()),
        ] {
            if used && !within(self.limits.time, value) {
                return Err(EditError::IllegalValue {
                    code: Code::Typ,
                    value: F::from_u16(u16::from(kind_number(kind))),
                    requirement: Requirement::KindUses {
                        code,
                        value,
                        min,
                        max,
                    },
                });
            }
        }
        next.config
            .validate()
            .map_err(|e| EditError::IllegalValue {
                code: Code::Typ,
                value: F::from_u16(u16::from(kind_number(kind))),
                requirement: Requirement::ValidConfig(e),
            })?;
        self.shadow = next;
        Ok(())
    }

    /// The operator is done (key D, the source's POP): the shadow set *as it is now* becomes
    /// active at the next sample. Edits keyed after the commit change only the shadow set and
    /// wait for a commit of their own; a second commit before the sample replaces the first
    /// (it carries the first one's edits too, as the shadow set does).
    pub fn commit(&mut self) {
        self.pending = Some(self.shadow);
    }

    /// Throws away the edits not yet committed: the shadow set goes back to the set that the
    /// next sample puts into force (a pending commit, else the active set). A commit already
    /// keyed stays pending.
    pub fn discard(&mut self) {
        self.shadow = self.pending.unwrap_or(self.active);
    }

    /// Whether a commit waits for the next sample.
    #[must_use]
    pub const fn commit_pending(&self) -> bool {
        self.pending.is_some()
    }

    /// The committed set waiting for the next sample, if any.
    #[must_use]
    pub const fn pending(&self) -> Option<&Parameters<F>> {
        self.pending.as_ref()
    }

    /// Whether the shadow set differs from the active one.
    #[must_use]
    pub fn edited(&self) -> bool {
        self.shadow != self.active
    }

    /// At a sample boundary: the parameters to apply now, if the operator committed — the
    /// shadow set as it was at the commit.
    pub fn take_commit(&mut self) -> Option<Parameters<F>> {
        let committed = self.pending.take()?;
        self.active = committed;
        Some(committed)
    }

    /// A commit the controller could not apply: `previous` is active again, the shadow set
    /// keeps the refused values for the operator to correct.
    fn refuse_commit(&mut self, previous: Parameters<F>) {
        self.active = previous;
    }

    /// The parameters the controller runs on.
    #[must_use]
    pub const fn active(&self) -> &Parameters<F> {
        &self.active
    }

    /// The shadow set being edited.
    #[must_use]
    pub const fn shadow(&self) -> &Parameters<F> {
        &self.shadow
    }

    /// The active value of a numeric parameter (`None` for TYP, Y and XIN, which a
    /// [`Station`] knows).
    #[must_use]
    pub fn active_value(&self, code: Code) -> Option<F> {
        value_of(&self.active, code)
    }

    /// The staged value of a numeric parameter, what a commit would bring into force (`None`
    /// for TYP, Y and XIN).
    #[must_use]
    pub fn shadow_value(&self, code: Code) -> Option<F> {
        value_of(&self.shadow, code)
    }

    /// The measurement scale.
    #[must_use]
    pub const fn scaling(&self) -> Scaling<F> {
        self.scaling
    }

    /// The operator limits.
    #[must_use]
    pub const fn limits(&self) -> OperatorLimits<F> {
        self.limits
    }
}

fn within<F: Real>((lo, hi): (F, F), value: F) -> bool {
    value >= lo && value <= hi
}

/// The source's Q code of a kind (1–7).
fn kind_number(kind: Kind) -> u8 {
    (1u8..)
        .zip(Kind::ALL)
        .find(|(_, k)| *k == kind)
        .map_or(0, |(n, _)| n)
}

fn value_of<F: Real>(p: &Parameters<F>, code: Code) -> Option<F> {
    Some(match code {
        Code::Win => p.setpoint,
        Code::S => p.config.h,
        Code::Rfel => p.rfel,
        Code::Kp => p.config.k,
        Code::Td => p.config.td,
        Code::Ti => p.config.ti,
        Code::Ymin => p.config.ymin,
        Code::Ymax => p.config.ymax,
        Code::Dymax => p.config.dymax.unwrap_or(F::zero()),
        Code::Typ | Code::Y | Code::Xin => return None,
    })
}

/// The RFEL alarm's hysteresis band: 1 % of the scale's span, but at most half of RFEL.
fn alarm_band<F: Real>(rfel: F, scaling: Scaling<F>) -> F {
    let span = (scaling.max() - scaling.min()) / F::from_u16(100);
    let half = rfel / F::from_u16(2);
    if span < half { span } else { half }
}

/// Whether `v` converts to `T` strictly inside its range (not saturated, finite).
fn held<T: Scalar, F: Real>(v: F) -> bool {
    let t = T::from_real(v);
    t.is_finite() && t < T::MAX && t > T::ZERO.sub(T::MAX)
}

/// The scale checks of [`Station::new`].
fn check_scale<T: Scalar, F: Real>(scaling: Scaling<F>) -> Result<(), EditError<F>> {
    let (min, max) = (scaling.min(), scaling.max());
    let refuse = |reason| EditError::ScaleUnrepresentable { min, max, reason };
    if !(held::<T, F>(min) && held::<T, F>(max) && held::<T, F>(max - min)) {
        return Err(refuse(
            "SCALEMIN, SCALEMAX and their difference must lie inside its range",
        ));
    }
    let mut last = T::from_real(min);
    for count in 1..=crate::scaling::ADC_FULL_SCALE {
        let next = scaling.count_to_units(count).map_or(last, T::from_real);
        if next <= last {
            return Err(refuse(
                "two A/D counts give the same value: the scale is too narrow for its resolution",
            ));
        }
        last = next;
    }
    Ok(())
}

/// The whole 1985 controller: a [`Pid`], its [`Staged`] parameters, the RFEL [`Alarm`] and the
/// measurement [`Scaling`]. The foreground (operator) edits and commits; the background calls
/// [`sample`](Station::sample) every S seconds, which applies a pending commit first, so all
/// changes land together at a sample boundary, bumplessly.
///
/// The RFEL alarm has a hysteresis: it is raised when |WIN − XIN| exceeds RFEL and goes off
/// only when |WIN − XIN| ≤ RFEL − band, band = the smaller of 1 % of the scale's span
/// (SCALEMAX − SCALEMIN) and RFEL / 2; so an error wandering around RFEL by less than the band
/// is one alarm, and the buzzer sounds once until the operator acknowledges. A NaN measurement
/// counts as too large.
///
/// `T` is the controller's number type, `F` the operator layer's (`f64` by default). A
/// `Station<f32, f32>` does all its work in `f32`, so a single-precision FPU runs it without any
/// soft-float `f64` routine.
///
/// ```
/// use regler_pid::{AlarmState, Code, Config, OperatorLimits, Parameters, Scaling, Station};
/// let params = Parameters { config: Config::default(), setpoint: 20.0f32, rfel: 2.0, night_setback: 0.0 };
/// let mut station = Station::<f32, f32>::new(params, Scaling::new(0.0, 40.0)?, OperatorLimits::default())?;
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
pub struct Station<T, F = f64> {
    pid: Pid<T>,
    staged: Staged<F>,
    alarm: Alarm,
    xin: F,
    y: F,
    commits: u32,
    night: bool,
    feedforward: F,
    track: Option<F>,
    refused: Option<ConfigError<F>>,
}

impl<T: Scalar, F: Real> Station<T, F> {
    /// A station running `params` on `scaling` (fixed at start-up, as in the source). Checked as
    /// [`Staged::new`], and the configuration must fit the controller's number type `T`; so
    /// must the scale ([`EditError::ScaleUnrepresentable`]): SCALEMIN, SCALEMAX and the span
    /// SCALEMAX − SCALEMIN strictly inside `T`'s range (so the set-point, a measurement on the
    /// scale and their difference are never clipped; with the night set-point on the scale too,
    /// every set-point the station can be given is held), and the 4096 A/D counts, converted
    /// to `T`, strictly increasing (no two counts merge). The second check converts every
    /// count once, at start-up only.
    ///
    /// The configuration must also be within reach ([`ConfigError::OutOfReach`], checked here
    /// and at every commit, where a refusal keeps the old set active): no product or sum the
    /// update forms may come within 2⁻⁸ of the end of `T`'s range for a set-point r and a
    /// measurement y anywhere on the scale lo..=hi (SCALEMIN..=SCALEMAX). The rule, computed in
    /// `F`: let m = max(|lo|, |hi|); the corners be the four pairs (r, y) with r and y each lo
    /// or hi; e = y − c·r, with e⁺ its largest and e⁻ its smallest value over the corners;
    /// A = max(|ymin|, |ymax|) and B = [`STATE_BOUND`](crate::STATE_BOUND)·max(ymax − ymin, A)
    /// (the states' bound); g = K for kinds with P and 1 for kinds without, and Kp = |K| for
    /// kinds with P and 0 for kinds without. Each of these bounds must be at most
    /// L = `T::MAX`·(1 − 2⁻⁸) (32 640 for `I16F16`, about 2.14·10⁹ for `I32F32`):
    ///
    /// 1. `b·r − y` (parameter b): E = max(|b·r − y| over the corners, |b|·m);
    /// 2. `(y − c·r) − (y_old − c·r_old)` (c): e⁺ − e⁻;
    /// 3. `u − v` (K): A + V;
    /// 4. `K·(b·r − y)` (K): P = Kp·E;
    /// 5. `K·(1 − b)·r` (b): O = Kp·|1 − b|·m for kinds with I, 0 for kinds without;
    /// 6. `y − c·r` (c): max(|e⁺|, |e⁻|, |c|·m);
    /// 7. `the derivative term` (Td): D = Td/(Td + N·h)·B + |g|·Td·N/(Td + N·h)·(e⁺ − e⁻) for
    ///    kinds with D and Td > 0, 0 otherwise;
    /// 8. `P + I + D` (K): V = P + I + D, where I = Ic + (ymax − ymin)/2 + B is the integral's
    ///    bound around its centre Ic = O + |ymin + ymax|/2;
    /// 9. `K·h/Ti·(r − y)` (Ti): |g|·h/Ti·(hi − lo) for kinds with I, 0 for kinds without;
    /// 10. `h/Tt·(u − v)` (Tt, or h when Tt is unset): a·(A + V) with a = h/Tt (1 when Tt is
    ///     unset) for kinds with I, 0 for kinds without;
    /// 11. `the integral's update` (K): I + (9) + (10) + Ic.
    ///
    /// The error is for the first bound in this order that exceeds L (or is NaN): it names the
    /// term (the text above), the parameter and its value, and `reach` is the bound. Since
    /// A + V is at least P, O, D and V, bounds 4, 5, 7 and 8 are never the first; they are
    /// listed as the sums they bound. Bounds 1 and 2 hold for every kind (the update forms
    /// b·r − y and the change of y − c·r on every sample), so a set-point weight b outside
    /// 0..1 or a c of 1 on a wide scale can be refused with a small gain. It is conservative
    /// (the worst case over the whole scale, r and y at opposite ends at once, states at their
    /// bounds), so some configurations that would never saturate are refused. It applies to
    /// saturating types only ([`Scalar::SATURATES`]): in `f32` and `f64` an overflow is an
    /// infinity, which the update catches (output held,
    /// [`Faults::overflow`](crate::Faults::overflow)), so float stations skip it and link none
    /// of it. The crate README gives the closed form for a PI on a scale 0..M and worked
    /// examples; `tests/reach_model.rs` checks this list term by term against a model.
    pub fn new(
        params: Parameters<F>,
        scaling: Scaling<F>,
        limits: OperatorLimits<F>,
    ) -> Result<Station<T, F>, EditError<F>> {
        let staged = Staged::new(params, scaling, limits)?;
        check_scale::<T, F>(scaling)?;
        let pid = Pid::<T>::new(&params.config).map_err(EditError::Config)?;
        if T::SATURATES {
            check_reach::<T, F>(&params.config, scaling.min(), scaling.max())
                .map_err(EditError::Config)?;
        }
        let y = pid.output().to_real();
        Ok(Station {
            pid,
            staged,
            alarm: Alarm::new(),
            xin: scaling.min(),
            y,
            commits: 0,
            night: false,
            feedforward: F::zero(),
            track: None,
            refused: None,
        })
    }

    /// One sample with the measurement `xin` in scale units; returns the output Y in volts.
    /// A pending commit is applied first; one the controller cannot take (its numbers do not
    /// fit `T`) is refused as a whole, the old set stays active, and
    /// [`refused_commit`](Station::refused_commit) says why. A non-finite `xin` holds the output
    /// and raises the controller's non-finite-input fault and the alarm.
    pub fn sample(&mut self, xin: F) -> F {
        if self.staged.commit_pending() {
            self.commit_staged();
        }
        let active = self.staged.active;
        let setpoint = self.setpoint();
        self.xin = xin;
        let u = if xin.is_finite() {
            let (r, y) = (T::from_real(setpoint), T::from_real(xin));
            if self.feedforward == F::zero() && self.track.is_none() {
                self.pid.update(r, y)
            } else {
                let inputs = Inputs {
                    feedforward: T::from_real(self.feedforward),
                    track: self.track.map(T::from_real),
                };
                self.pid.update_with(r, y, inputs)
            }
        } else {
            // Not converted: a fixed-point T would read NaN as 0.
            self.pid.note_non_finite_input()
        };
        self.y = u.to_real();
        let error = setpoint - xin;
        // Hysteresis: an alarm is raised when |error| > RFEL and stays until |error| <= RFEL -
        // band, so a noisy error near RFEL is one alarm, not one per crossing.
        let threshold = if self.alarm.state() == AlarmState::Normal {
            active.rfel
        } else {
            active.rfel - alarm_band(active.rfel, self.staged.scaling)
        };
        // A NaN measurement is an alarm too: the operator must look.
        self.alarm.update(error.is_nan() || error.abs() > threshold);
        self.y
    }

    /// Applies the staged parameters at a sample (rare: when the operator keyed a change). Out
    /// of line so that the sample's own stack frame stays small on the samples that do not
    /// commit (the controller's validation and coefficients need a few hundred bytes).
    #[cold]
    #[inline(never)]
    fn commit_staged(&mut self) {
        // The active set is copied only when a commit may have to be refused.
        let previous = self.staged.active;
        if let Some(p) = self.staged.take_commit() {
            let scaling = self.staged.scaling;
            let fits = if T::SATURATES {
                check_reach::<T, F>(&p.config, scaling.min(), scaling.max())
            } else {
                Ok(())
            };
            match fits.and_then(|()| self.pid.set_config(&p.config)) {
                Ok(()) => {
                    self.commits = self.commits.saturating_add(1);
                    self.refused = None;
                }
                Err(e) => {
                    self.staged.refuse_commit(previous);
                    self.refused = Some(e);
                }
            }
        }
    }

    /// Why the last commit was refused, if it was (cleared by the next commit that lands).
    #[must_use]
    pub const fn refused_commit(&self) -> Option<ConfigError<F>> {
        self.refused
    }

    /// The set-point in force: WIN, less the night set-back while the night input is on, but
    /// never below SCALEMIN (so it is always on the scale, and held by the controller's type).
    #[must_use]
    pub fn setpoint(&self) -> F {
        let active = self.staged.active;
        if self.night {
            let lowered = active.setpoint - active.night_setback;
            let min = self.staged.scaling.min();
            if lowered < min { min } else { lowered }
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
    pub fn set_feedforward(&mut self, volts: F) {
        self.feedforward = if volts.is_finite() { volts } else { F::zero() };
    }

    /// The output the actuator really has, in volts, from the next sample on (`None`: the
    /// controller's own) — a measured valve position, or the output an override selector chose —
    /// so the integral tracks what the plant really gets and does not wind up while something
    /// else is in charge. A non-finite value counts as `None`.
    pub fn set_track(&mut self, volts: Option<F>) {
        self.track = volts.filter(|v| v.is_finite());
    }

    /// The operator's acknowledge (key C).
    pub fn acknowledge(&mut self) {
        self.alarm.acknowledge();
    }

    /// The staged parameters, to edit and commit.
    pub fn staged_mut(&mut self) -> &mut Staged<F> {
        &mut self.staged
    }

    /// The staged parameters.
    #[must_use]
    pub const fn staged(&self) -> &Staged<F> {
        &self.staged
    }

    /// The active value of a parameter; Y and XIN are the last sample's.
    #[must_use]
    pub fn value(&self, code: Code) -> Option<F> {
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
        assert_eq!(s.shadow_value(Code::Rfel), Some(3.0));
        assert_eq!(s.active_value(Code::Rfel), Some(5.0));
        assert_eq!(s.shadow_value(Code::Y), None);
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
        assert_eq!(
            EditError::<f64>::UnknownCode(1).display_message(),
            "WRONG CODE"
        );
        assert_eq!(
            EditError::<f64>::ReadOnly(Code::Xin).display_message(),
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
        let wide = OperatorLimits {
            output: (-100.0, 100.0),
            ..OperatorLimits::default()
        };
        let err = Station::<f64>::new(
            params,
            Scaling::new(0.0, 40.0).unwrap(),
            OperatorLimits::default(),
        )
        .unwrap_err();
        assert_eq!(err.code(), Some(Code::Ymin));
        assert_eq!(
            err.to_string(),
            "ILLEGAL VALUE: YMIN must be within 0..10, got -100"
        );
        let mut st = Station::<f64>::new(params, Scaling::new(0.0, 40.0).unwrap(), wide).unwrap();
        assert_eq!(st.sample(18.0), 2.0);
        st.set_night(true);
        assert!(st.night());
        assert_eq!(st.setpoint(), 16.0);
        assert_eq!(st.sample(18.0), -2.0);
        st.set_feedforward(1.5);
        assert_eq!(st.sample(18.0), -0.5);
        st.set_feedforward(f64::NAN);
        assert_eq!(st.sample(18.0), -2.0);
        // Tracking: a PI station whose actuator is stuck at 3 V follows it instead of winding up.
        let pi = Parameters {
            config: Config {
                kind: Kind::PI,
                k: 1.0,
                ti: 1.0,
                h: 1.0,
                ymin: -100.0,
                ymax: 100.0,
                ..Config::default()
            },
            ..params
        };
        let mut st = Station::<f64>::new(pi, Scaling::new(0.0, 40.0).unwrap(), wide).unwrap();
        st.set_track(Some(3.0));
        for _ in 0..5 {
            st.sample(20.0);
        }
        assert!((st.sample(20.0) - 3.0).abs() < 1e-9);
        st.set_track(Some(f64::NAN)); // counts as no tracking
        assert!((st.sample(20.0) - 3.0).abs() < 1e-9);
        let bad = Parameters {
            night_setback: -1.0,
            ..params
        };
        assert_eq!(
            Staged::new(bad, Scaling::new(0.0, 40.0).unwrap(), wide),
            Err(EditError::NightSetback(-1.0))
        );
    }
}
