//! The stretch meter: pulses counted between two reference initiators, filtered into DIA.

use core::fmt;

use crate::table::stretch_per_mille;

/// How a [`StretchMeter`] judges its measurements.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct StretchConfig {
    /// SIA: pulses between the initiators when the chain was new (the static list's reference).
    pub sia: u32,
    /// How many consecutive equal measurements a new DIA needs before it is accepted; any other
    /// measurement in between (the accepted DIA, another value, or an
    /// [`Implausible`](Measurement::Implausible) one) starts the count again.
    /// 2 (the default) means a single missed or extra pulse never causes a recalculation:
    /// the next measurement returns to the old value and the odd one is forgotten.
    pub confirmations: u8,
    /// A measurement further than this (per mille) outside the range between the accepted
    /// DIA and SIA is not a chain but a fault (a dead initiator, a chain break) and is rejected
    /// outright. Default 100 (10 %). Beyond the accepted DIA it is measured from the accepted
    /// DIA: a chain stretches a little between two measurements, however far it has stretched
    /// in all, so the meter follows it for life. Anywhere back towards SIA, and up to this far
    /// beyond SIA (per mille of SIA), is plausible: a chain that was shortened or replaced,
    /// which still needs `confirmations` equal measurements.
    ///
    /// The band is never narrower than one pulse: one pulse beyond either end is always
    /// plausible, whatever this value (0, or SIA 100 with 5 ‰, would otherwise be a band of less
    /// than one pulse, and the meter could never follow a chain that stretches).
    pub plausible_per_mille: u32,
    /// Stretch (per mille, as [`StretchMeter::stretch_per_mille`]) past which the alarm is on:
    /// time to shorten the chain. Default 20 (2 %, 8 m on a 400 m chain).
    pub alarm_per_mille: u32,
}

impl StretchConfig {
    /// The defaults for a chain with `sia` pulses between its initiators.
    #[must_use]
    pub const fn new(sia: u32) -> StretchConfig {
        StretchConfig {
            sia,
            confirmations: 2,
            plausible_per_mille: 100,
            alarm_per_mille: 20,
        }
    }
}

/// A [`StretchConfig`] that cannot work.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum StretchConfigError {
    /// SIA is 0.
    ZeroReference,
    /// `confirmations` is 0: at least one measurement is needed.
    ZeroConfirmations,
    /// A starting (or stored) DIA of 0: no chain has 0 pulses between its initiators.
    ZeroMeasurement,
}

impl fmt::Display for StretchConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StretchConfigError::ZeroReference => f.write_str("sia must not be 0"),
            StretchConfigError::ZeroConfirmations => {
                f.write_str("confirmations must be at least 1, got 0")
            }
            StretchConfigError::ZeroMeasurement => f.write_str("the DIA must not be 0"),
        }
    }
}

impl core::error::Error for StretchConfigError {}

/// What one finished measurement did.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Measurement {
    /// Equal to the accepted DIA.
    Unchanged,
    /// Different, waiting for confirmation.
    Pending {
        /// The value measured.
        dia: u32,
    },
    /// A new DIA, confirmed: recalibrate the distance table (and the tracker) with it.
    Accepted {
        /// The new DIA.
        dia: u32,
    },
    /// More than `plausible_per_mille` (and more than one pulse) outside the range between the
    /// accepted DIA and SIA (see [`StretchConfig::plausible_per_mille`]), or 0: counted as a
    /// fault and otherwise ignored, except that it breaks "in a row": a half-confirmed
    /// candidate is forgotten and must be measured `confirmations` times again.
    Implausible {
        /// The value measured.
        dia: u32,
    },
}

/// Counts chain pulses between the two reference initiators and turns the counts into a DIA
/// that only changes when the chain really has.
///
/// Call [`pulse`](StretchMeter::pulse) on every chain pulse, [`start`](StretchMeter::start)
/// when the reference mark passes the first initiator and [`end`](StretchMeter::end) when it
/// passes the second; `end` returns the [`Measurement`]. When it says
/// [`Accepted`](Measurement::Accepted), hand the new DIA to
/// [`Tracker::recalibrate`](crate::Tracker::recalibrate).
///
/// ```
/// use regler_chain_tracker::{Measurement, StretchConfig, StretchMeter};
/// let mut meter = StretchMeter::new(StretchConfig::new(3000))?;
/// let measure = |meter: &mut StretchMeter, pulses: u32| {
///     meter.start();
///     for _ in 0..pulses { meter.pulse(); }
///     meter.end()
/// };
/// assert_eq!(measure(&mut meter, 2999), Some(Measurement::Pending { dia: 2999 })); // one pulse missed
/// assert_eq!(measure(&mut meter, 3000), Some(Measurement::Unchanged));             // forgotten
/// assert_eq!(measure(&mut meter, 2985), Some(Measurement::Pending { dia: 2985 })); // stretched...
/// assert_eq!(measure(&mut meter, 2985), Some(Measurement::Accepted { dia: 2985 })); // ...confirmed
/// assert_eq!(meter.stretch_per_mille(), 5);
/// # Ok::<(), regler_chain_tracker::StretchConfigError>(())
/// ```
///
/// Deserializing checks what [`StretchMeter::with_dia`] checks, and that a half-confirmed
/// candidate is below `confirmations`: stored data with SIA 0, no confirmations or a DIA of 0 is
/// an error, never a meter that divides by zero or accepts anything.
#[derive(Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "RawStretchMeter"))]
pub struct StretchMeter {
    config: StretchConfig,
    accepted: u32,
    counting: Option<u32>,
    candidate: Option<(u32, u8)>,
    measurements: u32,
    rejected: u32,
    orphan_ends: u32,
}

/// The stored form of a [`StretchMeter`], checked on the way in.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct RawStretchMeter {
    config: StretchConfig,
    accepted: u32,
    counting: Option<u32>,
    candidate: Option<(u32, u8)>,
    measurements: u32,
    rejected: u32,
    orphan_ends: u32,
}

#[cfg(feature = "serde")]
impl TryFrom<RawStretchMeter> for StretchMeter {
    type Error = StretchConfigError;
    fn try_from(raw: RawStretchMeter) -> Result<StretchMeter, StretchConfigError> {
        let meter = StretchMeter::with_dia(raw.config, raw.accepted)?;
        // A candidate seen `confirmations` times would have been accepted already.
        let candidate = raw
            .candidate
            .filter(|&(dia, seen)| dia != 0 && seen < raw.config.confirmations);
        Ok(StretchMeter {
            counting: raw.counting,
            candidate,
            measurements: raw.measurements,
            rejected: raw.rejected,
            orphan_ends: raw.orphan_ends,
            ..meter
        })
    }
}

impl StretchMeter {
    /// A meter with DIA = SIA (a new chain).
    pub const fn new(config: StretchConfig) -> Result<StretchMeter, StretchConfigError> {
        StretchMeter::with_dia(config, config.sia)
    }

    /// A meter that already accepted `dia` (restored after a restart).
    pub const fn with_dia(
        config: StretchConfig,
        dia: u32,
    ) -> Result<StretchMeter, StretchConfigError> {
        if config.sia == 0 {
            return Err(StretchConfigError::ZeroReference);
        }
        if config.confirmations == 0 {
            return Err(StretchConfigError::ZeroConfirmations);
        }
        if dia == 0 {
            return Err(StretchConfigError::ZeroMeasurement);
        }
        Ok(StretchMeter {
            config,
            accepted: dia,
            counting: None,
            candidate: None,
            measurements: 0,
            rejected: 0,
            orphan_ends: 0,
        })
    }

    /// One chain pulse.
    pub fn pulse(&mut self) {
        if let Some(count) = &mut self.counting {
            *count = count.saturating_add(1);
        }
    }

    /// The reference mark passed the first initiator: counting starts (again) from zero.
    pub fn start(&mut self) {
        self.counting = Some(0);
    }

    /// The reference mark passed the second initiator: the count is judged. `None` when no
    /// count was running (an `end` without a `start`, counted in
    /// [`orphan_ends`](StretchMeter::orphan_ends)).
    pub fn end(&mut self) -> Option<Measurement> {
        let Some(dia) = self.counting.take() else {
            self.orphan_ends = self.orphan_ends.saturating_add(1);
            return None;
        };
        Some(self.measure(dia))
    }

    /// Judges one measured DIA, as [`end`](StretchMeter::end) does with its own count (for
    /// plants whose hardware counts the pulses between the initiators).
    pub fn measure(&mut self, dia: u32) -> Measurement {
        self.measurements = self.measurements.saturating_add(1);
        // The range a chain can be in: from as stretched as accepted to as new (SIA); beyond
        // either end by at most plausible_per_mille of that end.
        let (short, long) = if self.accepted <= self.config.sia {
            (self.accepted, self.config.sia)
        } else {
            (self.config.sia, self.accepted)
        };
        let (end, off) = if dia < short {
            (short, short.abs_diff(dia))
        } else {
            (long, dia.saturating_sub(long))
        };
        // The band is at least one pulse: a chain stretches by whole pulses, and a band narrower
        // than one (`plausible_per_mille` 0, or `end · plausible_per_mille` < 1000) could never
        // follow it.
        let limit = u64::from(end)
            .saturating_mul(u64::from(self.config.plausible_per_mille))
            .max(1000);
        if dia == 0 || u64::from(off).saturating_mul(1000) > limit {
            self.rejected = self.rejected.saturating_add(1);
            // A fault breaks "in a row": the candidate must be measured again, from one.
            self.candidate = None;
            return Measurement::Implausible { dia };
        }
        if dia == self.accepted {
            self.candidate = None;
            return Measurement::Unchanged;
        }
        let seen = match self.candidate {
            Some((value, seen)) if value == dia => seen.saturating_add(1),
            _ => 1,
        };
        if seen >= self.config.confirmations {
            self.candidate = None;
            self.accepted = dia;
            Measurement::Accepted { dia }
        } else {
            self.candidate = Some((dia, seen));
            Measurement::Pending { dia }
        }
    }

    /// Makes the meter agree with the distance table after a restart: takes the table's DIA
    /// (`tracker.table().dia()`) as the accepted one and, if that changes the meter's DIA,
    /// forgets a half-confirmed candidate. When meter and table already agree (both stored
    /// and current), nothing changes: a candidate half-confirmed before the power failure
    /// goes on counting, so a chain moving on is followed as if power had not failed.
    /// Only for a table restored from its snapshot: after a refused snapshot the table is at
    /// SIA and the meter's DIA is the one to keep — [`start_up`](crate::start_up) does the
    /// right thing for each case.
    /// Returns whether the meter's DIA changed; a DIA of 0 is an error and changes nothing.
    ///
    /// The meter and the tracker are stored apart, so power can fail between an
    /// [`Accepted`](Measurement::Accepted) and the [`recalibrate`](crate::Tracker::recalibrate)
    /// it asks for, or between storing one and the other. Without this, a meter stored after
    /// accepting a DIA that the table never got says [`Unchanged`](Measurement::Unchanged) for
    /// ever while the table stays at the old DIA. After it, whichever of the two was stale, the
    /// next `confirmations` measurements of the chain's true DIA end in `Accepted` (or
    /// `Unchanged` when the table already has it), and the table follows.
    pub fn reconcile(&mut self, table_dia: u32) -> Result<bool, StretchConfigError> {
        if table_dia == 0 {
            return Err(StretchConfigError::ZeroMeasurement);
        }
        let changed = table_dia != self.accepted;
        if changed {
            self.accepted = table_dia;
            self.candidate = None;
        }
        Ok(changed)
    }

    /// The accepted DIA.
    #[must_use]
    pub const fn dia(&self) -> u32 {
        self.accepted
    }

    /// Chain elongation of the accepted DIA, per mille: (SIA − DIA)/DIA.
    #[must_use]
    pub const fn stretch_per_mille(&self) -> i32 {
        stretch_per_mille(self.config.sia, self.accepted)
    }

    /// Whether the stretch is past the configured alarm limit.
    #[must_use]
    pub const fn alarm(&self) -> bool {
        let s = self.stretch_per_mille();
        s > 0 && s.unsigned_abs() > self.config.alarm_per_mille
    }

    /// Measurements judged.
    #[must_use]
    pub const fn measurements(&self) -> u32 {
        self.measurements
    }

    /// Measurements rejected as implausible.
    #[must_use]
    pub const fn rejected(&self) -> u32 {
        self.rejected
    }

    /// `end` calls that came without a `start`.
    #[must_use]
    pub const fn orphan_ends(&self) -> u32 {
        self.orphan_ends
    }

    /// The configuration.
    #[must_use]
    pub const fn config(&self) -> StretchConfig {
        self.config
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_configs_are_refused() {
        assert_eq!(
            StretchMeter::new(StretchConfig::new(0)),
            Err(StretchConfigError::ZeroReference)
        );
        let c = StretchConfig {
            confirmations: 0,
            ..StretchConfig::new(5)
        };
        assert_eq!(
            StretchMeter::new(c),
            Err(StretchConfigError::ZeroConfirmations)
        );
    }

    #[test]
    fn single_glitches_never_recalibrate() {
        let mut m = StretchMeter::new(StretchConfig::new(3000)).unwrap();
        for glitch in [2999, 3001, 2999, 3001] {
            assert_eq!(m.measure(glitch), Measurement::Pending { dia: glitch });
            assert_eq!(m.measure(3000), Measurement::Unchanged);
        }
        // Alternating glitches never confirm each other either.
        assert_eq!(m.measure(2999), Measurement::Pending { dia: 2999 });
        assert_eq!(m.measure(3001), Measurement::Pending { dia: 3001 });
        assert_eq!(m.dia(), 3000);
    }

    #[test]
    fn follows_a_chain_past_ten_per_cent_step_by_step() {
        // 3000 pulses new; the chain stretches 25 % over its life, a few pulses at a time.
        let mut m = StretchMeter::new(StretchConfig::new(3000)).unwrap();
        let mut dia = 3000;
        while dia > 2400 {
            dia -= 5;
            m.measure(dia);
            m.measure(dia);
        }
        assert_eq!(m.dia(), 2400);
        assert_eq!(m.stretch_per_mille(), 250);
        assert_eq!(m.rejected(), 0);
        // A sudden jump further than 10 % past the accepted DIA, or past SIA, is a fault.
        assert_eq!(m.measure(2159), Measurement::Implausible { dia: 2159 });
        assert_eq!(m.measure(3301), Measurement::Implausible { dia: 3301 });
        // A replaced chain (back at SIA) is followed once confirmed.
        assert_eq!(m.measure(3000), Measurement::Pending { dia: 3000 });
        assert_eq!(m.measure(3000), Measurement::Accepted { dia: 3000 });
        assert!(!m.alarm());
    }

    #[test]
    fn implausible_counts_are_faults() {
        let mut m = StretchMeter::new(StretchConfig::new(3000)).unwrap();
        assert_eq!(m.measure(0), Measurement::Implausible { dia: 0 });
        assert_eq!(m.measure(6000), Measurement::Implausible { dia: 6000 });
        assert_eq!(m.measure(2700), Measurement::Pending { dia: 2700 }); // exactly 10 %
        assert_eq!(m.rejected(), 2);
        assert_eq!(m.end(), None);
        assert_eq!(m.orphan_ends(), 1);
    }

    #[test]
    fn alarm_past_limit() {
        let c = StretchConfig {
            confirmations: 1,
            alarm_per_mille: 5,
            ..StretchConfig::new(3000)
        };
        let mut m = StretchMeter::new(c).unwrap();
        assert_eq!(m.measure(2985), Measurement::Accepted { dia: 2985 });
        assert!(!m.alarm()); // 5 ‰ is not past 5 ‰
        m.measure(2980);
        assert!(m.alarm());
    }

    #[test]
    fn reconcile_takes_the_table_dia_and_says_whether_it_changed() {
        let mut m = StretchMeter::new(StretchConfig::new(3000)).unwrap();
        assert_eq!(m.measure(2990), Measurement::Pending { dia: 2990 });
        assert_eq!(m.reconcile(3000), Ok(false));
        // Meter and table agreed: the half-confirmed candidate goes on counting.
        assert_eq!(m.measure(2990), Measurement::Accepted { dia: 2990 });
        assert_eq!(m.measure(2980), Measurement::Pending { dia: 2980 });
        // A table at another DIA: taken, and the candidate forgotten.
        assert_eq!(m.reconcile(2995), Ok(true));
        assert_eq!(m.dia(), 2995);
        assert_eq!(m.measure(2980), Measurement::Pending { dia: 2980 });
        assert_eq!(m.reconcile(2990), Ok(true));
        assert_eq!(m.dia(), 2990);
        assert_eq!(m.reconcile(0), Err(StretchConfigError::ZeroMeasurement));
        assert_eq!(m.dia(), 2990);
    }

    #[test]
    fn counting_restarts_on_start() {
        let mut m = StretchMeter::new(StretchConfig {
            confirmations: 1,
            ..StretchConfig::new(10)
        })
        .unwrap();
        m.start();
        m.pulse();
        m.start();
        for _ in 0..9 {
            m.pulse();
        }
        assert_eq!(m.end(), Some(Measurement::Accepted { dia: 9 }));
        m.pulse(); // not counting: no effect
        assert_eq!(m.dia(), 9);
    }
}
