//! The controller's parameters in engineering units, and their validation.

use core::fmt;

/// Which terms the controller has (the source's TYP).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Kind {
    /// Proportional only.
    P,
    /// Integral only (gain 1, as the source does).
    I,
    /// Derivative only (gain 1).
    D,
    /// Proportional and integral.
    PI,
    /// Proportional and derivative.
    PD,
    /// Integral and derivative (gain 1).
    ID,
    /// All three.
    #[default]
    PID,
}

impl Kind {
    /// Every kind, in the source's order (its Q codes 1–7).
    pub const ALL: [Kind; 7] = [
        Kind::P,
        Kind::I,
        Kind::D,
        Kind::PI,
        Kind::PD,
        Kind::ID,
        Kind::PID,
    ];

    /// Whether the kind has a proportional term.
    #[must_use]
    pub const fn has_p(self) -> bool {
        matches!(self, Kind::P | Kind::PI | Kind::PD | Kind::PID)
    }

    /// Whether the kind has an integral term.
    #[must_use]
    pub const fn has_i(self) -> bool {
        matches!(self, Kind::I | Kind::PI | Kind::ID | Kind::PID)
    }

    /// Whether the kind has a derivative term.
    #[must_use]
    pub const fn has_d(self) -> bool {
        matches!(self, Kind::D | Kind::PD | Kind::ID | Kind::PID)
    }

    /// The kind named by `text` ("P", "PI", "pid", …), as typed at the source's terminal.
    #[must_use]
    pub fn parse(text: &str) -> Option<Kind> {
        Kind::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(text.trim()))
    }

    /// The source's name of the kind.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Kind::P => "P",
            Kind::I => "I",
            Kind::D => "D",
            Kind::PI => "PI",
            Kind::PD => "PD",
            Kind::ID => "ID",
            Kind::PID => "PID",
        }
    }
}

impl fmt::Display for Kind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Which way the process answers the actuator (the source's DIR/REV).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Action {
    /// More output raises the measurement (heating): error = set-point − measurement.
    #[default]
    Direct,
    /// More output lowers the measurement (cooling): error = measurement − set-point.
    Reverse,
}

impl Action {
    /// +1 for direct, −1 for reverse.
    #[must_use]
    pub const fn sign(self) -> f64 {
        match self {
            Action::Direct => 1.0,
            Action::Reverse => -1.0,
        }
    }
}

/// The parameters of a [`Pid`](crate::Pid), in engineering units.
///
/// Build one from [`Config::default`] and change the fields you need; every constructor checks
/// it with [`validate`](Config::validate).
///
/// ```
/// use regler_pid::{Action, Config, Kind};
/// let config = Config { kind: Kind::PI, action: Action::Reverse, k: 2.0, ti: 30.0, ..Config::default() };
/// assert!(config.validate().is_ok());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Config {
    /// Which terms the controller has.
    pub kind: Kind,
    /// Direct or reverse action.
    pub action: Action,
    /// Gain K (used only by kinds with a P term; the others use a gain of 1, as the source).
    pub k: f64,
    /// Integral time Ti, seconds; > 0 for kinds with an I term.
    pub ti: f64,
    /// Derivative time Td, seconds; ≥ 0.
    pub td: f64,
    /// Derivative filter N: the derivative gain at high frequency is limited to N·K; > 0.
    pub n: f64,
    /// Set-point weight in the P term (1 = error, 0 = measurement only).
    pub b: f64,
    /// Set-point weight in the D term (0 = derivative on measurement: no kick on a set-point
    /// step; 1 = derivative of the error, as the source).
    pub c: f64,
    /// Anti-windup tracking time Tt, seconds; `None` = one sample (Tt = h), exactly the
    /// source's H = H + Y − V + A1·E; > 0.
    pub tt: Option<f64>,
    /// Sample period h, seconds; > 0 (the source: 1–255 s).
    pub h: f64,
    /// Lowest output.
    pub ymin: f64,
    /// Highest output; ≥ `ymin`.
    pub ymax: f64,
    /// Largest output change per sample; `None` = no rate limit; ≥ 0.
    pub dymax: Option<f64>,
}

impl Default for Config {
    /// The keypad start-up values of the source: PID, direct, K = 10, Ti = 8 s, Td = 0 s,
    /// N = 5, sample period 1 s, output 0–10 (volts), no rate limit; b = 1, c = 0 (no
    /// derivative kick), Tt = one sample.
    fn default() -> Config {
        Config {
            kind: Kind::PID,
            action: Action::Direct,
            k: 10.0,
            ti: 8.0,
            td: 0.0,
            n: 5.0,
            b: 1.0,
            c: 0.0,
            tt: None,
            h: 1.0,
            ymin: 0.0,
            ymax: 10.0,
            dymax: None,
        }
    }
}

/// A parameter of [`Config`], as named in errors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Parameter {
    /// `k`
    K,
    /// `ti`
    Ti,
    /// `td`
    Td,
    /// `n`
    N,
    /// `b`
    B,
    /// `c`
    C,
    /// `tt`
    Tt,
    /// `h`
    H,
    /// `ymin`
    Ymin,
    /// `ymax`
    Ymax,
    /// `dymax`
    Dymax,
}

impl Parameter {
    /// The field name.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Parameter::K => "k",
            Parameter::Ti => "ti",
            Parameter::Td => "td",
            Parameter::N => "n",
            Parameter::B => "b",
            Parameter::C => "c",
            Parameter::Tt => "tt",
            Parameter::H => "h",
            Parameter::Ymin => "ymin",
            Parameter::Ymax => "ymax",
            Parameter::Dymax => "dymax",
        }
    }
}

impl fmt::Display for Parameter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A [`Config`] that cannot run: which parameter, what it must be, what it was.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ConfigError {
    /// A parameter is NaN or infinite.
    NotFinite {
        /// Which.
        parameter: Parameter,
        /// Its value.
        value: f64,
    },
    /// A parameter is outside its range.
    OutOfRange {
        /// Which.
        parameter: Parameter,
        /// Its value.
        value: f64,
        /// What it must be, e.g. "> 0 when the controller has integral action".
        requirement: &'static str,
    },
    /// `ymin` is above `ymax`.
    LimitsReversed {
        /// Lowest output asked for.
        ymin: f64,
        /// Highest output asked for.
        ymax: f64,
    },
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ConfigError::NotFinite { parameter, value } => {
                write!(f, "{parameter} must be a finite number, got {value}")
            }
            ConfigError::OutOfRange {
                parameter,
                value,
                requirement,
            } => {
                write!(f, "{parameter} must be {requirement}, got {value}")
            }
            ConfigError::LimitsReversed { ymin, ymax } => {
                write!(
                    f,
                    "ymin must not exceed ymax, got ymin {ymin} > ymax {ymax}"
                )
            }
        }
    }
}

impl core::error::Error for ConfigError {}

impl Config {
    /// Checks every parameter; the error names the first one that is wrong.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let finite = |parameter: Parameter, value: f64| {
            if value.is_finite() {
                Ok(value)
            } else {
                Err(ConfigError::NotFinite { parameter, value })
            }
        };
        let range = |parameter, value, ok: bool, requirement| {
            if ok {
                Ok(())
            } else {
                Err(ConfigError::OutOfRange {
                    parameter,
                    value,
                    requirement,
                })
            }
        };
        let k = finite(Parameter::K, self.k)?;
        let _ = k;
        let ti = finite(Parameter::Ti, self.ti)?;
        if self.kind.has_i() {
            range(
                Parameter::Ti,
                ti,
                ti > 0.0,
                "> 0 when the controller has integral action",
            )?;
        }
        let td = finite(Parameter::Td, self.td)?;
        range(Parameter::Td, td, td >= 0.0, ">= 0")?;
        let n = finite(Parameter::N, self.n)?;
        range(Parameter::N, n, n > 0.0, "> 0")?;
        finite(Parameter::B, self.b)?;
        finite(Parameter::C, self.c)?;
        if let Some(tt) = self.tt {
            let tt = finite(Parameter::Tt, tt)?;
            range(Parameter::Tt, tt, tt > 0.0, "> 0")?;
        }
        let h = finite(Parameter::H, self.h)?;
        range(Parameter::H, h, h > 0.0, "> 0")?;
        let ymin = finite(Parameter::Ymin, self.ymin)?;
        let ymax = finite(Parameter::Ymax, self.ymax)?;
        if ymin > ymax {
            return Err(ConfigError::LimitsReversed { ymin, ymax });
        }
        if let Some(dymax) = self.dymax {
            let dymax = finite(Parameter::Dymax, dymax)?;
            range(Parameter::Dymax, dymax, dymax >= 0.0, ">= 0")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_valid_and_the_source_keypad_defaults() {
        let c = Config::default();
        assert_eq!(c.validate(), Ok(()));
        assert_eq!(
            (c.kind, c.k, c.ti, c.h, c.ymin, c.ymax, c.n),
            (Kind::PID, 10.0, 8.0, 1.0, 0.0, 10.0, 5.0)
        );
    }

    #[test]
    fn each_bad_parameter_is_named() {
        let base = Config::default();
        let cases = [
            (
                Config {
                    k: f64::NAN,
                    ..base
                },
                "k must be a finite number",
            ),
            (
                Config { ti: -3.0, ..base },
                "ti must be > 0 when the controller has integral action, got -3",
            ),
            (Config { td: -1.0, ..base }, "td must be >= 0"),
            (Config { n: 0.0, ..base }, "n must be > 0"),
            (
                Config {
                    b: f64::INFINITY,
                    ..base
                },
                "b must be a finite number",
            ),
            (
                Config {
                    c: f64::NEG_INFINITY,
                    ..base
                },
                "c must be a finite number",
            ),
            (
                Config {
                    tt: Some(0.0),
                    ..base
                },
                "tt must be > 0",
            ),
            (Config { h: 0.0, ..base }, "h must be > 0"),
            (
                Config {
                    ymin: 5.0,
                    ymax: 1.0,
                    ..base
                },
                "ymin must not exceed ymax",
            ),
            (
                Config {
                    dymax: Some(-0.5),
                    ..base
                },
                "dymax must be >= 0",
            ),
            (
                Config {
                    ymax: f64::NAN,
                    ..base
                },
                "ymax must be a finite number",
            ),
        ];
        for (config, message) in cases {
            let err = config.validate().unwrap_err().to_string();
            assert!(err.starts_with(message), "{err}");
        }
    }

    #[test]
    fn ti_is_free_without_integral_action() {
        let c = Config {
            kind: Kind::PD,
            ti: 0.0,
            ..Config::default()
        };
        assert_eq!(c.validate(), Ok(()));
    }

    #[test]
    fn kinds_parse_and_name_their_terms() {
        assert_eq!(Kind::parse("pi"), Some(Kind::PI));
        assert_eq!(Kind::parse("PID "), Some(Kind::PID));
        assert_eq!(Kind::parse("DP"), None);
        let terms: Vec<_> = Kind::ALL
            .iter()
            .map(|k| (k.has_p(), k.has_i(), k.has_d()))
            .collect();
        assert_eq!(terms.iter().filter(|t| t.0).count(), 4);
        assert_eq!(terms.iter().filter(|t| t.1).count(), 4);
        assert_eq!(terms.iter().filter(|t| t.2).count(), 4);
    }
}
