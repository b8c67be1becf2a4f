//! Scaling between converter counts and engineering units: a 12-bit A/D in, an 8-bit D/A out.

use core::fmt;

/// Full-scale count of the 12-bit A/D converter.
pub const ADC_FULL_SCALE: u16 = 4095;
/// Full-scale count of the 8-bit D/A converter.
pub const DAC_FULL_SCALE: u8 = 255;
/// The converters' span in volts (both 0–10 V in the source).
pub const SPAN_VOLTS: f64 = 10.0;

/// Why a scaling could not be made or a value converted.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ScalingError {
    /// SCALEMIN or SCALEMAX is not finite.
    NotFinite,
    /// SCALEMAX ≤ SCALEMIN (the source: "SCALEMAX <= SCALEMIN ! TRY AGAIN").
    Reversed {
        /// SCALEMIN.
        min: f64,
        /// SCALEMAX.
        max: f64,
    },
    /// An A/D count above 4095.
    CountOutOfRange {
        /// The count.
        count: u16,
    },
    /// A voltage that is NaN.
    NotANumber,
}

impl fmt::Display for ScalingError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ScalingError::NotFinite => f.write_str("SCALEMIN and SCALEMAX must be finite"),
            ScalingError::Reversed { min, max } => {
                write!(
                    f,
                    "SCALEMAX must exceed SCALEMIN, got SCALEMIN {min}, SCALEMAX {max}"
                )
            }
            ScalingError::CountOutOfRange { count } => {
                write!(
                    f,
                    "a 12-bit A/D count is at most {ADC_FULL_SCALE}, got {count}"
                )
            }
            ScalingError::NotANumber => f.write_str("the voltage is NaN"),
        }
    }
}

impl core::error::Error for ScalingError {}

/// The measurement's scale, fixed at start-up: 0 V (count 0) is SCALEMIN, 10 V (count 4095)
/// is SCALEMAX. The output is in volts, 0–10 V, to an 8-bit D/A.
///
/// Rounding: A/D counts map linearly and exactly (in `f64`) to engineering units; volts map to
/// the nearest D/A count, halves rounded up, clamped to 0–255.
///
/// ```
/// use regler_pid::Scaling;
/// let room = Scaling::new(0.0, 40.0)?; // °C over 0–10 V
/// assert_eq!(room.count_to_units(4095)?, 40.0);
/// assert_eq!(room.count_to_units(0)?, 0.0);
/// assert_eq!(Scaling::volts_to_dac(5.0)?, 128); // 127.5 rounds up
/// assert_eq!(Scaling::volts_to_dac(12.0)?, 255);
/// # Ok::<(), regler_pid::ScalingError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Scaling {
    min: f64,
    max: f64,
}

impl Scaling {
    /// The scale SCALEMIN..SCALEMAX.
    pub fn new(scale_min: f64, scale_max: f64) -> Result<Scaling, ScalingError> {
        if !(scale_min.is_finite() && scale_max.is_finite()) {
            return Err(ScalingError::NotFinite);
        }
        if scale_max <= scale_min {
            return Err(ScalingError::Reversed {
                min: scale_min,
                max: scale_max,
            });
        }
        Ok(Scaling {
            min: scale_min,
            max: scale_max,
        })
    }

    /// SCALEMIN.
    #[must_use]
    pub const fn min(&self) -> f64 {
        self.min
    }

    /// SCALEMAX.
    #[must_use]
    pub const fn max(&self) -> f64 {
        self.max
    }

    /// A 12-bit A/D count in engineering units.
    pub fn count_to_units(&self, count: u16) -> Result<f64, ScalingError> {
        if count > ADC_FULL_SCALE {
            return Err(ScalingError::CountOutOfRange { count });
        }
        Ok(self.min + (self.max - self.min) * f64::from(count) / f64::from(ADC_FULL_SCALE))
    }

    /// An engineering value as the nearest A/D count (clamped to 0–4095), for simulators.
    #[must_use]
    pub fn units_to_count(&self, units: f64) -> u16 {
        nearest_count((units - self.min) / (self.max - self.min), ADC_FULL_SCALE)
    }

    /// Whether `units` lies within the scale (the source's check of WIN).
    #[must_use]
    pub fn contains(&self, units: f64) -> bool {
        units >= self.min && units <= self.max
    }

    /// Volts as the nearest 8-bit D/A count, halves up, clamped to 0–255.
    pub fn volts_to_dac(volts: f64) -> Result<u8, ScalingError> {
        if volts.is_nan() {
            return Err(ScalingError::NotANumber);
        }
        let count = nearest_count(volts / SPAN_VOLTS, u16::from(DAC_FULL_SCALE));
        Ok(u8::try_from(count).unwrap_or(DAC_FULL_SCALE))
    }

    /// An 8-bit D/A count in volts.
    #[must_use]
    pub fn dac_to_volts(count: u8) -> f64 {
        f64::from(count) * SPAN_VOLTS / f64::from(DAC_FULL_SCALE)
    }
}

/// The converter count nearest to `fraction` of full scale: halves up, clamped to 0..=`full`,
/// NaN as 0.
fn nearest_count(fraction: f64, full: u16) -> u16 {
    let x = fraction * f64::from(full);
    if x.is_nan() || x <= 0.0 {
        0
    } else if x >= f64::from(full) {
        full
    } else {
        #[allow(
            clippy::cast_possible_truncation,
            reason = "0 < x + 0.5 < full + 1 <= 65536"
        )]
        let count = (x + 0.5) as u16;
        count
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_count_round_trips() {
        let s = Scaling::new(-50.0, 150.0).unwrap();
        for count in 0..=ADC_FULL_SCALE {
            assert_eq!(s.units_to_count(s.count_to_units(count).unwrap()), count);
        }
        assert_eq!(
            s.count_to_units(4096),
            Err(ScalingError::CountOutOfRange { count: 4096 })
        );
    }

    #[test]
    fn every_dac_count_round_trips_and_halves_round_up() {
        for count in 0..=DAC_FULL_SCALE {
            assert_eq!(
                Scaling::volts_to_dac(Scaling::dac_to_volts(count)),
                Ok(count)
            );
        }
        assert_eq!(Scaling::volts_to_dac(-1.0), Ok(0));
        assert_eq!(Scaling::volts_to_dac(f64::INFINITY), Ok(255));
        assert_eq!(
            Scaling::volts_to_dac(f64::NAN),
            Err(ScalingError::NotANumber)
        );
        assert_eq!(Scaling::volts_to_dac(0.5 * 10.0 / 255.0), Ok(1));
    }

    #[test]
    fn bad_scales_are_refused() {
        assert_eq!(
            Scaling::new(5.0, 5.0),
            Err(ScalingError::Reversed { min: 5.0, max: 5.0 })
        );
        assert_eq!(Scaling::new(f64::NAN, 5.0), Err(ScalingError::NotFinite));
        assert!(Scaling::new(0.0, 1.0).unwrap().contains(1.0));
    }
}
