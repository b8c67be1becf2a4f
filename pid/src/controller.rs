//! The controller: Åström's PID with filtered derivative, set-point weights, back-calculation
//! anti-windup, rate limit and clamps.

use core::fmt;

use crate::config::{Config, ConfigError};
use crate::scalar::Scalar;

/// Whether the controller computes its output or follows the operator's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Mode {
    /// The controller computes the output.
    Auto,
    /// The output is the operator's; the controller tracks it so the return to automatic is
    /// bumpless.
    Manual,
}

/// Faults the controller has seen since they were last cleared.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Faults(u8);

impl Faults {
    const NON_FINITE_INPUT: u8 = 1;
    const OVERFLOW: u8 = 1 << 1;

    /// A set-point, measurement, feed-forward or tracking value was NaN or infinite: the output
    /// was held.
    #[must_use]
    pub const fn non_finite_input(self) -> bool {
        self.0 & Faults::NON_FINITE_INPUT != 0
    }

    /// The computation overflowed (a float became infinite): the output and state were held.
    #[must_use]
    pub const fn overflow(self) -> bool {
        self.0 & Faults::OVERFLOW != 0
    }

    /// Whether any fault is set.
    #[must_use]
    pub const fn any(self) -> bool {
        self.0 != 0
    }
}

impl fmt::Display for Faults {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.non_finite_input(), self.overflow()) {
            (false, false) => f.write_str("no fault"),
            (true, false) => f.write_str("non-finite input: output held"),
            (false, true) => f.write_str("overflow: output held"),
            (true, true) => f.write_str("non-finite input and overflow: output held"),
        }
    }
}

/// An operator or tracking value that is not a finite number.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ValueError {
    /// NaN or infinite.
    NotFinite,
}

impl fmt::Display for ValueError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("the value must be a finite number")
    }
}

impl core::error::Error for ValueError {}

/// Extra inputs of one update: see [`Pid::update_with`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inputs<T> {
    /// Added to the controller's output before the limits (e.g. a measured disturbance times
    /// its static gain).
    pub feedforward: T,
    /// The value the actuator really got, when something else chose it (an override selector,
    /// a cascade's inner loop at its limit). The integral tracks it instead of the controller's
    /// own output, so the controller does not wind up while it is not in charge.
    pub track: Option<T>,
}

impl<T: Scalar> Default for Inputs<T> {
    fn default() -> Inputs<T> {
        Inputs {
            feedforward: T::ZERO,
            track: None,
        }
    }
}

/// Åström's PID controller with the anti-windup of the 1985 source, for `f32`, `f64` and
/// fixed point.
///
/// Coefficients are computed once from the [`Config`] (the source's "pre-computations"), so
/// [`update`](Pid::update) does only multiplies, adds and compares:
///
/// ```text
/// P = s·K·(b·r − y)                    s = +1 direct, −1 reverse
/// D = ad·D − s·bd·((y − c·r) − (y_old − c·r_old))
/// v = P + I + D (+ feed-forward)
/// u = clamp(v, u_old ± dymax), then clamp(u, ymin, ymax)
/// I = I + s·bi·(r − y) + ao·(u − v)    bi = K·h/Ti, ad = Td/(Td + N·h),
///                                      bd = K·Td·N/(Td + N·h), ao = h/Tt
/// ```
///
/// Kinds without P use a gain of 1 for I and D, as the source does. The state is
/// I = D = 0 and u_old = 0 clamped into the limits at start; the first sample sets y_old, r_old.
///
/// A NaN or infinite set-point or measurement holds the output and sets a
/// [`Faults`] flag; `update` never returns NaN or infinity. A `Pid<f32>` takes 64 bytes.
///
/// ```
/// use regler_pid::{Config, Kind, Pid};
/// let config = Config { kind: Kind::PI, k: 2.0, ti: 10.0, h: 0.5, ymin: 0.0, ymax: 100.0, ..Config::default() };
/// let mut pid = Pid::<f32>::new(&config)?;
/// let mut temperature = 15.0f32;
/// for _ in 0..200 {
///     let heat = pid.update(20.0, temperature);
///     temperature += 0.5 * (0.05 * heat - 0.02 * (temperature - 10.0)); // a room losing heat
/// }
/// assert!((temperature - 20.0).abs() < 0.1);
/// # Ok::<(), regler_pid::ConfigError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Pid<T> {
    kp: T,
    b: T,
    c: T,
    bi: T,
    ad: T,
    bd: T,
    ao: T,
    ymin: T,
    ymax: T,
    dymax: T,
    i: T,
    d: T,
    y_old: T,
    r_old: T,
    u_old: T,
    has_dymax: bool,
    started: bool,
    mode: Mode,
    faults: Faults,
}

impl<T: Scalar> Pid<T> {
    /// A controller for `config`, or the error naming its bad parameter.
    pub fn new(config: &Config) -> Result<Pid<T>, ConfigError> {
        config.validate()?;
        let mut pid = Pid {
            kp: T::ZERO,
            b: T::ZERO,
            c: T::ZERO,
            bi: T::ZERO,
            ad: T::ZERO,
            bd: T::ZERO,
            ao: T::ZERO,
            ymin: T::ZERO,
            ymax: T::ZERO,
            dymax: T::ZERO,
            i: T::ZERO,
            d: T::ZERO,
            y_old: T::ZERO,
            r_old: T::ZERO,
            u_old: T::ZERO,
            has_dymax: false,
            started: false,
            mode: Mode::Auto,
            faults: Faults::default(),
        };
        pid.set_coefficients(config);
        pid.u_old = T::ZERO.clamp_within(pid.ymin, pid.ymax);
        Ok(pid)
    }

    fn set_coefficients(&mut self, config: &Config) {
        let s = config.action.sign();
        let kind = config.kind;
        let gain = if kind.has_p() { config.k } else { 1.0 };
        let dn = config.td + config.n * config.h;
        let f = T::from_f64;
        self.kp = f(if kind.has_p() { s * config.k } else { 0.0 });
        self.b = f(config.b);
        self.c = f(config.c);
        // Same operation order as the reference algorithm (s·bi, s·bd), so f64 results agree
        // to the last bit.
        self.bi = f(if kind.has_i() {
            s * (gain * config.h / config.ti)
        } else {
            0.0
        });
        self.ad = f(if kind.has_d() { config.td / dn } else { 0.0 });
        self.bd = f(if kind.has_d() {
            s * (gain * config.td * config.n / dn)
        } else {
            0.0
        });
        self.ao = f(if kind.has_i() {
            config.h / config.tt.unwrap_or(config.h)
        } else {
            0.0
        });
        self.ymin = f(config.ymin);
        self.ymax = f(config.ymax);
        self.has_dymax = config.dymax.is_some();
        self.dymax = f(config.dymax.unwrap_or(0.0));
    }

    /// One sample: the output for set-point `r` and measurement `y`.
    #[inline]
    pub fn update(&mut self, setpoint: T, measurement: T) -> T {
        self.step::<false>(setpoint, measurement, T::ZERO, None)
    }

    /// One sample with feed-forward and an external tracking value (see [`Inputs`]).
    /// Returns the controller's own output (before any outside selection).
    pub fn update_with(&mut self, setpoint: T, measurement: T, inputs: Inputs<T>) -> T {
        if !(inputs.feedforward.is_finite() && inputs.track.is_none_or(Scalar::is_finite)) {
            self.faults.0 |= Faults::NON_FINITE_INPUT;
            return self.u_old;
        }
        self.step::<true>(setpoint, measurement, inputs.feedforward, inputs.track)
    }

    #[inline(always)]
    fn step<const FEEDFORWARD: bool>(&mut self, r: T, y: T, feedforward: T, track: Option<T>) -> T {
        if !self.started {
            self.y_old = y;
            self.r_old = r;
            self.started = true;
        }
        let p = self.kp.mul(self.b.mul(r).sub(y));
        let change = y
            .sub(self.c.mul(r))
            .sub(self.y_old.sub(self.c.mul(self.r_old)));
        let d = self.ad.mul(self.d).sub(self.bd.mul(change)).flush_tiny();
        let (v, u, i) = match self.mode {
            Mode::Manual => {
                // The operator's output stands; I follows so that v = u when auto returns.
                let u = self.u_old;
                (u, u, u.sub(p).sub(d))
            }
            Mode::Auto => {
                let mut v = p.add(self.i).add(d);
                if FEEDFORWARD {
                    v = v.add(feedforward);
                }
                let mut u = v;
                if self.has_dymax {
                    u = u.clamp_within(self.u_old.sub(self.dymax), self.u_old.add(self.dymax));
                }
                u = u.clamp_within(self.ymin, self.ymax);
                let applied = track.unwrap_or(u);
                // I + (integral step + tracking), summed in the reference's order.
                let step = self.bi.mul(r.sub(y)).add(self.ao.mul(applied.sub(v)));
                let i = self.i.add(step);
                (v, u, i)
            }
        };
        // A NaN or infinite set-point or measurement reaches v or I whatever the coefficients
        // (0·∞ is NaN), so two checks guard both inputs and overflow.
        if !T::both_finite(v, i) {
            self.fault(r, y);
            return self.u_old;
        }
        self.i = i;
        self.d = d;
        self.y_old = y;
        self.r_old = r;
        self.u_old = track.unwrap_or(u);
        u
    }

    #[cold]
    fn fault(&mut self, r: T, y: T) {
        self.faults.0 |= if r.is_finite() && y.is_finite() {
            Faults::OVERFLOW
        } else {
            Faults::NON_FINITE_INPUT
        };
    }

    /// Changes the parameters, bumplessly: the integral is adjusted so that the output would
    /// not jump if the set-point and measurement stayed as at the last sample (a change of K
    /// or b moves P, the integral takes up the difference). A kind without an I term has its
    /// integral set to 0, one without a D term its derivative state; the state is otherwise kept.
    /// On an error nothing changes.
    pub fn set_config(&mut self, config: &Config) -> Result<(), ConfigError> {
        config.validate()?;
        let p_before = self.proportional(self.r_old, self.y_old);
        self.set_coefficients(config);
        if self.started && config.kind.has_i() {
            let p_after = self.proportional(self.r_old, self.y_old);
            self.i = self.i.add(p_before).sub(p_after);
        }
        if !config.kind.has_i() {
            self.i = T::ZERO;
        }
        if !config.kind.has_d() {
            self.d = T::ZERO;
        }
        Ok(())
    }

    fn proportional(&self, r: T, y: T) -> T {
        self.kp.mul(self.b.mul(r).sub(y))
    }

    /// Switches to manual with the output `u` (clamped into the output limits).
    pub fn set_manual(&mut self, u: T) -> Result<(), ValueError> {
        if !u.is_finite() {
            return Err(ValueError::NotFinite);
        }
        self.u_old = u.clamp_within(self.ymin, self.ymax);
        self.mode = Mode::Manual;
        Ok(())
    }

    /// Switches back to automatic, bumplessly: the integral is set so that the next output
    /// starts from the manual one.
    pub fn set_auto(&mut self) {
        if self.mode == Mode::Manual && self.started {
            let p = self.proportional(self.r_old, self.y_old);
            self.i = self.u_old.sub(p).sub(self.d);
        }
        self.mode = Mode::Auto;
    }

    /// Auto or manual.
    #[must_use]
    pub const fn mode(&self) -> Mode {
        self.mode
    }

    /// The last output.
    #[must_use]
    pub const fn output(&self) -> T {
        self.u_old
    }

    /// The integral term.
    #[must_use]
    pub const fn integral(&self) -> T {
        self.i
    }

    /// The (filtered) derivative term.
    #[must_use]
    pub const fn derivative(&self) -> T {
        self.d
    }

    /// Faults seen since the last [`clear_faults`](Pid::clear_faults).
    #[must_use]
    pub const fn faults(&self) -> Faults {
        self.faults
    }

    /// Clears the fault flags.
    pub fn clear_faults(&mut self) {
        self.faults = Faults::default();
    }

    /// Back to the state at construction (I = D = 0, output 0 clamped), same parameters.
    pub fn reset(&mut self) {
        self.i = T::ZERO;
        self.d = T::ZERO;
        self.started = false;
        self.mode = Mode::Auto;
        self.faults = Faults::default();
        self.u_old = T::ZERO.clamp_within(self.ymin, self.ymax);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{Action, Kind};

    fn pi() -> Config {
        Config {
            kind: Kind::PI,
            k: 2.0,
            ti: 4.0,
            h: 1.0,
            ymin: -10.0,
            ymax: 10.0,
            ..Config::default()
        }
    }

    #[test]
    fn pid_f32_is_64_bytes() {
        assert!(
            core::mem::size_of::<Pid<f32>>() <= 64,
            "{}",
            core::mem::size_of::<Pid<f32>>()
        );
    }

    #[test]
    fn first_steps_by_hand() {
        let mut pid = Pid::<f64>::new(&pi()).unwrap();
        // e = 1: P = 2, I = 0 -> u = 2; I += 2·1/4 = 0.5
        assert_eq!(pid.update(1.0, 0.0), 2.0);
        assert_eq!(pid.integral(), 0.5);
        assert_eq!(pid.update(1.0, 0.0), 2.5);
        let reverse = Config {
            action: Action::Reverse,
            ..pi()
        };
        let mut pid = Pid::<f64>::new(&reverse).unwrap();
        assert_eq!(pid.update(1.0, 0.0), -2.0);
    }

    #[test]
    fn back_calculation_is_the_sources_tracking() {
        // Saturated: u = ymax, I takes Y - V every sample (Tt = h).
        let mut pid = Pid::<f64>::new(&pi()).unwrap();
        let u = pid.update(100.0, 0.0); // P = 200, clamps to 10
        assert_eq!(u, 10.0);
        // I = 0 + 0.5·100 + (10 − 200) = −140, so v next = 200 − 140 = 60 → still 10, I = −140 + 50 − 50 …
        assert_eq!(pid.integral(), -140.0);
        let mut last = 0.0;
        for _ in 0..5 {
            last = pid.update(100.0, 0.0);
        }
        assert_eq!(last, 10.0);
        // Error flips sign: the output leaves the limit at once (no windup).
        assert!(pid.update(-1.0, 0.0) < 10.0);
    }

    #[test]
    fn rate_limit_and_clamp() {
        let config = Config {
            dymax: Some(0.5),
            ..pi()
        };
        let mut pid = Pid::<f32>::new(&config).unwrap();
        let mut prev = 0.0;
        for _ in 0..30 {
            let u = pid.update(100.0, 0.0);
            assert!((u - prev).abs() <= 0.5 + 1e-6);
            assert!(u <= 10.0);
            prev = u;
        }
        assert_eq!(prev, 10.0);
    }

    #[test]
    fn non_finite_inputs_hold_the_output_and_raise_a_fault() {
        let mut pid = Pid::<f32>::new(&pi()).unwrap();
        let u = pid.update(1.0, 0.0);
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert_eq!(pid.update(bad, 0.0), u);
            assert_eq!(pid.update(1.0, bad), u);
        }
        assert!(pid.faults().non_finite_input());
        assert!(!pid.faults().overflow());
        pid.clear_faults();
        assert!(!pid.faults().any());
        let tracked = Inputs {
            feedforward: 0.0,
            track: Some(f32::NAN),
        };
        assert_eq!(pid.update_with(1.0, 0.0, tracked), u);
    }

    #[test]
    fn overflow_holds_the_output() {
        let config = Config {
            k: 1e300,
            kind: Kind::P,
            ymin: -1.0,
            ymax: 1.0,
            ..Config::default()
        };
        let mut pid = Pid::<f64>::new(&config).unwrap();
        assert_eq!(pid.update(0.5, 0.0), 1.0);
        // P = 1e300·2e300 overflows to infinity: the output and the state are held.
        assert_eq!(pid.update(1e300, -1e300), 1.0);
        assert!(pid.faults().overflow());
        assert!(pid.integral().is_finite());
        pid.clear_faults();
        assert_eq!(pid.update(-0.5, 0.0), -1.0);
    }

    #[test]
    fn manual_and_bumpless_return() {
        let mut pid = Pid::<f64>::new(&pi()).unwrap();
        for _ in 0..3 {
            pid.update(5.0, 4.0);
        }
        pid.set_manual(7.5).unwrap();
        assert_eq!(pid.mode(), Mode::Manual);
        assert_eq!(pid.update(5.0, 4.5), 7.5);
        assert_eq!(pid.update(5.0, 4.5), 7.5);
        pid.set_auto();
        // Same set-point and measurement: the first automatic output is the manual one, then
        // the integral moves on by bi·e = 0.5·0.5 per sample.
        let u = pid.update(5.0, 4.5);
        assert!((u - 7.5).abs() < 1e-12, "{u}");
        let u = pid.update(5.0, 4.5);
        assert!((u - 7.75).abs() < 1e-12, "{u}");
        assert_eq!(pid.set_manual(f64::NAN), Err(ValueError::NotFinite));
        pid.set_manual(99.0).unwrap();
        assert_eq!(pid.output(), 10.0, "manual output clamped into the limits");
    }

    #[test]
    fn bumpless_gain_change() {
        let mut pid = Pid::<f64>::new(&pi()).unwrap();
        for _ in 0..5 {
            pid.update(3.0, 2.0);
        }
        let before = pid.update(3.0, 2.0);
        pid.set_config(&Config {
            k: 6.0,
            b: 0.5,
            ..pi()
        })
        .unwrap();
        let after = pid.update(3.0, 2.0);
        // Without the adjustment P would jump from 2 to 6·(1.5 − 2) = −3. Only the integral
        // step moves the output: bi = 6/4, e = 1.
        assert!((after - before - 0.5).abs() < 1e-9, "{before} {after}");
        assert!(pid.set_config(&Config { ti: 0.0, ..pi() }).is_err());
    }

    #[test]
    fn tracking_keeps_the_integral_from_winding_up() {
        let mut pid = Pid::<f64>::new(&pi()).unwrap();
        // An override holds the actuator at 1 while this controller asks for more.
        for _ in 0..100 {
            pid.update_with(
                5.0,
                0.0,
                Inputs {
                    feedforward: 0.0,
                    track: Some(1.0),
                },
            );
        }
        assert!(pid.integral().abs() < 20.0, "{}", pid.integral());
        // Released: the controller's output is near what the actuator had, not wound up.
        let u = pid.update(5.0, 0.0);
        assert!(u <= 10.0);
        let mut free = Pid::<f64>::new(&pi()).unwrap();
        let ff = free.update_with(
            0.0,
            0.0,
            Inputs {
                feedforward: 3.0,
                track: None,
            },
        );
        assert_eq!(ff, 3.0);
    }

    #[cfg(feature = "fixed")]
    #[test]
    fn fixed_point_follows_f64_closely() {
        use fixed::types::{I16F16, I32F32};
        let config = Config {
            kind: Kind::PID,
            k: 1.5,
            ti: 6.0,
            td: 1.0,
            n: 5.0,
            h: 0.5,
            ymin: 0.0,
            ymax: 10.0,
            dymax: Some(1.0),
            ..Config::default()
        };
        let mut a = Pid::<f64>::new(&config).unwrap();
        let mut b = Pid::<I32F32>::new(&config).unwrap();
        let mut c = Pid::<I16F16>::new(&config).unwrap();
        let mut y = 0.0;
        for k in 0..300 {
            let r = if k < 150 { 5.0 } else { 2.0 };
            let ua = a.update(r, y);
            let ub = b
                .update(I32F32::from_num(r), I32F32::from_num(y))
                .to_num::<f64>();
            let uc = c
                .update(I16F16::from_num(r), I16F16::from_num(y))
                .to_num::<f64>();
            assert!((ua - ub).abs() < 1e-6, "{k}: {ua} {ub}");
            assert!((ua - uc).abs() < 0.05, "{k}: {ua} {uc}");
            y += 0.5 * (0.8 * ua - y) * 0.5;
        }
        // Saturation instead of overflow with absurd inputs.
        let mut s = Pid::<I16F16>::new(&Config {
            k: 30000.0,
            ..config
        })
        .unwrap();
        assert_eq!(s.update(I16F16::MAX, I16F16::MIN), I16F16::from_num(1.0));
    }
}
