//! The controller's parameters in engineering units, and their validation.
#![allow(
    clippy::arithmetic_side_effects,
    reason = "arithmetic here is on Real (sealed: f32 or f64), which cannot panic or wrap; an overflow is an infinity, and every path checks finiteness"
)]

use core::fmt;

use crate::real::Real;

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

/// The parameters of a [`Pid`](crate::Pid), in engineering units, in `f64` (the default) or
/// `f32` ([`Real`]).
///
/// Build one from [`Config::default`] and change the fields you need; every constructor checks
/// it with [`validate`](Config::validate). Firmware on a single-precision FPU writes its numbers
/// as `f32` and links no `f64` arithmetic:
///
/// ```
/// use regler_pid::{Action, Config, Kind, Pid};
/// let config = Config { kind: Kind::PI, action: Action::Reverse, k: 2.0, ti: 30.0, ..Config::default() };
/// assert!(config.validate().is_ok()); // Config<f64>: float literals default to f64
///
/// let mut c = Config::default();      // Config<f32>, from the field types below
/// c.k = 2.0f32;
/// c.ti = 30.0;
/// let mut pid = Pid::<f32>::new(&c)?;
/// assert_eq!(pid.update(1.0, 0.0), 2.0);
/// # Ok::<(), regler_pid::ConfigError<f32>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Config<F = f64> {
    /// Which terms the controller has.
    pub kind: Kind,
    /// Direct or reverse action.
    pub action: Action,
    /// Gain K (used only by kinds with a P term; the others use a gain of 1, as the source).
    pub k: F,
    /// Integral time Ti, seconds; > 0 for kinds with an I term.
    pub ti: F,
    /// Derivative time Td, seconds; ≥ 0.
    pub td: F,
    /// Derivative filter N: the derivative gain at high frequency is limited to N·K; > 0.
    pub n: F,
    /// Set-point weight in the P term (1 = error, 0 = measurement only).
    pub b: F,
    /// Set-point weight in the D term (0 = derivative on measurement: no kick on a set-point
    /// step; 1 = derivative of the error, as the source).
    pub c: F,
    /// Anti-windup tracking time Tt, seconds; `None` = one sample (Tt = h), exactly the
    /// source's H = H + Y − V + A1·E. Must exceed h/2: the tracking step h/Tt must stay below 2,
    /// or the integral oscillates with growing amplitude once the output saturates.
    pub tt: Option<F>,
    /// Sample period h, seconds; > 0 (the source: 1–255 s).
    pub h: F,
    /// Lowest output.
    pub ymin: F,
    /// Highest output; ≥ `ymin`.
    pub ymax: F,
    /// Largest output change per sample, ≥ 0; `None` or `Some(0)` = no rate limit (as the
    /// operator layer's DYMAX 0: the source's 0 froze the output, which manual mode does better).
    pub dymax: Option<F>,
}

impl<F: Real> Default for Config<F> {
    /// The keypad start-up values of the source: PID, direct, K = 10, Ti = 8 s, Td = 0 s,
    /// N = 5, sample period 1 s, output 0–10 (volts), no rate limit; b = 1, c = 0 (no
    /// derivative kick), Tt = one sample.
    fn default() -> Config<F> {
        let n = F::from_u16;
        Config {
            kind: Kind::PID,
            action: Action::Direct,
            k: n(10),
            ti: n(8),
            td: n(0),
            n: n(5),
            b: n(1),
            c: n(0),
            tt: None,
            h: n(1),
            ymin: n(0),
            ymax: n(10),
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
pub enum ConfigError<F = f64> {
    /// A parameter is NaN or infinite.
    NotFinite {
        /// Which.
        parameter: Parameter,
        /// Its value.
        value: F,
    },
    /// A parameter is outside its range.
    OutOfRange {
        /// Which.
        parameter: Parameter,
        /// Its value.
        value: F,
        /// What it must be, e.g. "> 0 when the controller has integral action".
        requirement: &'static str,
    },
    /// `ymin` is above `ymax`.
    LimitsReversed {
        /// Lowest output asked for.
        ymin: F,
        /// Highest output asked for.
        ymax: F,
    },
    /// `tt` is at most h/2: the tracking step h/Tt would be 2 or more, and the integral would
    /// oscillate with growing amplitude whenever the output saturates.
    TrackingUnstable {
        /// The tracking time asked for.
        tt: F,
        /// The sample period.
        h: F,
    },
    /// The parameter is valid, but a coefficient it gives cannot be held by the controller's
    /// number type within [`TOLERANCE`](crate::TOLERANCE) (it overflows, vanishes, or rounds
    /// too far: `K·h/Ti` = 5e-6 is 0 in `I16F16`, `K` = 1e5 saturates there).
    Unrepresentable {
        /// The parameter that sets the coefficient.
        parameter: Parameter,
        /// Its value.
        value: F,
        /// The coefficient, e.g. "K·h/Ti".
        coefficient: &'static str,
        /// The coefficient's value, computed in the configuration's type.
        exact: F,
    },
    /// The parameter is valid and every coefficient fits the controller's number type, but a
    /// product or sum the update computes can reach beyond the type's range for a set-point and
    /// measurement on the scale (a fixed-point `Station` would saturate it and lose the
    /// set-point): `K·(b·r − y)` = 60 000 for K = 2 on a 0..30 000 scale in `I16F16`.
    /// Checked by [`Station`](crate::Station) at start-up and at every commit; the bounds, their
    /// order and the term each names are listed in [`Station::new`](crate::Station::new).
    OutOfReach {
        /// The parameter that sets the term.
        parameter: Parameter,
        /// Its value.
        value: F,
        /// The term, e.g. "K·(b·r − y)": the first of the listed bounds that exceeds the limit.
        term: &'static str,
        /// That bound: the largest magnitude the term can reach on the scale (an upper bound,
        /// computed in the configuration's type as listed).
        reach: F,
    },
}

impl<F: Real> fmt::Display for ConfigError<F> {
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
            ConfigError::TrackingUnstable { tt, h } => {
                let half = h / F::from_u16(2);
                write!(
                    f,
                    "tt must be > h/2 = {half} for stable anti-windup tracking, got {tt}"
                )
            }
            ConfigError::Unrepresentable {
                parameter,
                value,
                coefficient,
                exact,
            } => {
                write!(
                    f,
                    "{parameter} = {value} gives {coefficient} = {exact}, which the controller's number type cannot hold within 0.1 %"
                )
            }
            ConfigError::OutOfReach {
                parameter,
                value,
                term,
                reach,
            } => {
                write!(
                    f,
                    "{parameter} = {value} lets {term} reach {reach} on the scale, beyond the controller's number type"
                )
            }
        }
    }
}

impl<F: Real> core::error::Error for ConfigError<F> {}

impl<F> ConfigError<F> {
    /// The parameter the error is about (`ymax` for reversed limits, `tt` for unstable
    /// tracking).
    #[must_use]
    pub const fn parameter(&self) -> Parameter {
        match self {
            ConfigError::NotFinite { parameter, .. }
            | ConfigError::OutOfRange { parameter, .. }
            | ConfigError::Unrepresentable { parameter, .. }
            | ConfigError::OutOfReach { parameter, .. } => *parameter,
            ConfigError::LimitsReversed { .. } => Parameter::Ymax,
            ConfigError::TrackingUnstable { .. } => Parameter::Tt,
        }
    }
}

impl<F: Real> Config<F> {
    /// Checks every parameter; the error names the first one that is wrong.
    ///
    /// Ranges: k, b, c finite; ti > 0 for kinds with an I term; td ≥ 0; n > 0; h > 0;
    /// tt > h/2; ymin ≤ ymax; dymax ≥ 0. Whether the number type of a [`Pid`](crate::Pid) can
    /// hold the resulting coefficients is checked by [`Pid::new`](crate::Pid::new).
    pub fn validate(&self) -> Result<(), ConfigError<F>> {
        let zero = F::zero();
        let finite = |parameter: Parameter, value: F| {
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
        finite(Parameter::K, self.k)?;
        let ti = finite(Parameter::Ti, self.ti)?;
        if self.kind.has_i() {
            range(
                Parameter::Ti,
                ti,
                ti > zero,
                "> 0 when the controller has integral action",
            )?;
        }
        let td = finite(Parameter::Td, self.td)?;
        range(Parameter::Td, td, td >= zero, ">= 0")?;
        let n = finite(Parameter::N, self.n)?;
        range(Parameter::N, n, n > zero, "> 0")?;
        finite(Parameter::B, self.b)?;
        finite(Parameter::C, self.c)?;
        let h = finite(Parameter::H, self.h)?;
        range(Parameter::H, h, h > zero, "> 0")?;
        if let Some(tt) = self.tt {
            let tt = finite(Parameter::Tt, tt)?;
            range(Parameter::Tt, tt, tt > zero, "> 0")?;
            // h/tt < 2, written so that it cannot overflow: tt > h/2.
            if tt <= h / F::from_u16(2) {
                return Err(ConfigError::TrackingUnstable { tt, h });
            }
        }
        let ymin = finite(Parameter::Ymin, self.ymin)?;
        let ymax = finite(Parameter::Ymax, self.ymax)?;
        if ymin > ymax {
            return Err(ConfigError::LimitsReversed { ymin, ymax });
        }
        if let Some(dymax) = self.dymax {
            let dymax = finite(Parameter::Dymax, dymax)?;
            range(Parameter::Dymax, dymax, dymax >= zero, ">= 0")?;
        }
        Ok(())
    }

    /// The largest output change per sample, if there is a rate limit (`Some(0)` is none).
    #[must_use]
    pub fn rate_limit(&self) -> Option<F> {
        self.dymax.filter(|d| *d > F::zero())
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
    fn tracking_faster_than_half_a_sample_is_refused() {
        let at = |tt: f64| {
            Config {
                tt: Some(tt),
                h: 1.0,
                ..Config::default()
            }
            .validate()
        };
        assert_eq!(
            at(0.1),
            Err(ConfigError::TrackingUnstable { tt: 0.1, h: 1.0 })
        );
        assert!(
            at(0.5).is_err(),
            "h/Tt = 2 is the edge: the integral oscillates for ever"
        );
        assert!(at(0.500_001).is_ok());
        assert_eq!(
            at(0.25).unwrap_err().to_string(),
            "tt must be > h/2 = 0.5 for stable anti-windup tracking, got 0.25"
        );
        // No overflow in the check itself.
        assert!(
            Config {
                tt: Some(f64::MAX),
                h: f64::MAX,
                ..Config::default()
            }
            .validate()
            .is_ok()
        );
    }

    #[test]
    #[allow(
        clippy::field_reassign_with_default,
        reason = "the contract's own spelling"
    )]
    fn an_f32_config_validates_in_f32() {
        let mut c = Config::default();
        c.k = 2.0f32;
        c.tt = Some(0.2);
        assert_eq!(
            c.validate(),
            Err(ConfigError::TrackingUnstable { tt: 0.2f32, h: 1.0 })
        );
        assert_eq!(Config::<f32>::default().rate_limit(), None);
        assert_eq!(
            Config {
                dymax: Some(0.0),
                ..Config::default()
            }
            .rate_limit(),
            None
        );
        assert_eq!(
            Config {
                dymax: Some(0.5),
                ..Config::default()
            }
            .rate_limit(),
            Some(0.5)
        );
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

    #[test]
    fn kinds_print_as_the_source_named_them_and_parse_back() {
        let names = ["P", "I", "D", "PI", "PD", "ID", "PID"];
        for (kind, name) in Kind::ALL.iter().zip(names) {
            assert_eq!(kind.to_string(), name);
            assert_eq!(Kind::parse(&kind.to_string()), Some(*kind));
        }
    }

    #[test]
    fn the_action_sign_is_plus_for_direct_and_minus_for_reverse() {
        assert_eq!(Action::Direct.sign(), 1.0);
        assert_eq!(Action::Reverse.sign(), -1.0);
        assert_eq!(Action::default(), Action::Direct);
    }
}
