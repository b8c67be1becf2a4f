//! Scaling between converter counts and engineering units: a 12-bit A/D in, an 8-bit D/A out.
#![allow(
    clippy::arithmetic_side_effects,
    reason = "arithmetic here is on Real (sealed: f32 or f64), which cannot panic or wrap; an overflow is an infinity, and every path checks finiteness"
)]

use core::fmt;

use crate::real::Real;

/// Full-scale count of the 12-bit A/D converter.
pub const ADC_FULL_SCALE: u16 = 4095;
/// Full-scale count of the 8-bit D/A converter.
pub const DAC_FULL_SCALE: u8 = 255;
/// The converters' span in volts (both 0–10 V in the source).
pub const SPAN_VOLTS: u16 = 10;

/// Why a scaling could not be made or a value converted.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ScalingError<F = f64> {
    /// SCALEMIN or SCALEMAX is not finite.
    NotFinite,
    /// SCALEMAX ≤ SCALEMIN (the source: "SCALEMAX <= SCALEMIN ! TRY AGAIN").
    Reversed {
        /// SCALEMIN.
        min: F,
        /// SCALEMAX.
        max: F,
    },
    /// An A/D count above 4095.
    CountOutOfRange {
        /// The count.
        count: u16,
    },
    /// A voltage that is NaN.
    NotANumber,
    /// SCALEMAX − SCALEMIN times 4095 is not finite in the number type: the conversion of a
    /// count would overflow.
    SpanTooLarge {
        /// SCALEMIN.
        min: F,
        /// SCALEMAX.
        max: F,
    },
    /// SCALEMIN, SCALEMAX (other than 0) or the span SCALEMAX − SCALEMIN is subnormal: the
    /// error bound of [`Scaling::count_to_units`] does not hold there.
    Subnormal {
        /// SCALEMIN.
        min: F,
        /// SCALEMAX.
        max: F,
    },
}

impl<F: Real> fmt::Display for ScalingError<F> {
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
            ScalingError::SpanTooLarge { min, max } => write!(
                f,
                "SCALEMAX - SCALEMIN times {ADC_FULL_SCALE} must be finite, got SCALEMIN {min}, SCALEMAX {max}"
            ),
            ScalingError::Subnormal { min, max } => write!(
                f,
                "SCALEMIN, SCALEMAX and SCALEMAX - SCALEMIN must be 0 or normal numbers (not subnormal), got SCALEMIN {min}, SCALEMAX {max}"
            ),
        }
    }
}

impl<F: Real> core::error::Error for ScalingError<F> {}

/// The measurement's scale, fixed at start-up: 0 V (count 0) is SCALEMIN, 10 V (count 4095)
/// is SCALEMAX. The output is in volts, 0–10 V, to an 8-bit D/A. In `f64` (the default) or `f32`.
///
/// Rounding: A/D counts map linearly to engineering units, SCALEMIN + (SCALEMAX − SCALEMIN) ·
/// count / 4095 computed in the scale's type: count 0 is SCALEMIN and count 4095 is SCALEMAX
/// exactly (bit for bit, −0.0 included), every count lands within SCALEMIN..=SCALEMAX, a higher count never gives a lower
/// value, and each value is within 2ε·(SCALEMAX − SCALEMIN) + ε·max(|SCALEMIN|, |SCALEMAX|) of
/// the exact one (ε = the type's `EPSILON`: 2⁻⁵² for `f64`, 2⁻²³ for `f32`). Volts map to the nearest D/A count, halves rounded up, clamped to 0–255.
/// Deserializing goes through [`Scaling::new`], so stored data with SCALEMAX ≤ SCALEMIN is an
/// error, never a scale that divides by zero.
///
/// ```
/// use regler_pid::Scaling;
/// let room = Scaling::new(0.0, 40.0)?; // °C over 0–10 V
/// assert_eq!(room.count_to_units(4095)?, 40.0);
/// assert_eq!(room.count_to_units(0)?, 0.0);
/// assert_eq!(Scaling::volts_to_dac(5.0)?, 128); // 127.5 rounds up
/// assert_eq!(Scaling::volts_to_dac(12.0f32), Ok(255)); // f32 all the way
/// # Ok::<(), regler_pid::ScalingError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(
        try_from = "RawScaling<F>",
        bound(
            serialize = "F: serde::Serialize",
            deserialize = "F: Real + serde::Deserialize<'de>"
        )
    )
)]
pub struct Scaling<F = f64> {
    min: F,
    max: F,
}

/// The stored form of a [`Scaling`], checked by [`Scaling::new`] on the way in.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct RawScaling<F> {
    min: F,
    max: F,
}

#[cfg(feature = "serde")]
impl<F: Real> TryFrom<RawScaling<F>> for Scaling<F> {
    type Error = ScalingError<F>;
    fn try_from(raw: RawScaling<F>) -> Result<Scaling<F>, ScalingError<F>> {
        Scaling::new(raw.min, raw.max)
    }
}

impl<F: Real> Scaling<F> {
    /// The scale SCALEMIN..SCALEMAX. Refused: an end that is not finite, SCALEMAX ≤ SCALEMIN,
    /// a span (SCALEMAX − SCALEMIN) whose product with 4095 is not finite, and a subnormal end
    /// or span ([`ScalingError::Subnormal`]; an end may be 0 or −0).
    pub fn new(scale_min: F, scale_max: F) -> Result<Scaling<F>, ScalingError<F>> {
        if !(scale_min.is_finite() && scale_max.is_finite()) {
            return Err(ScalingError::NotFinite);
        }
        if scale_max <= scale_min {
            return Err(ScalingError::Reversed {
                min: scale_min,
                max: scale_max,
            });
        }
        // The span times the full-scale count must be finite too, or a conversion overflows.
        if !((scale_max - scale_min) * F::from_u16(ADC_FULL_SCALE)).is_finite() {
            return Err(ScalingError::SpanTooLarge {
                min: scale_min,
                max: scale_max,
            });
        }
        let zero = F::zero();
        let subnormal = |x: F| x != zero && !x.is_normal();
        if subnormal(scale_min) || subnormal(scale_max) || subnormal(scale_max - scale_min) {
            return Err(ScalingError::Subnormal {
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
    pub const fn min(&self) -> F {
        self.min
    }

    /// SCALEMAX.
    #[must_use]
    pub const fn max(&self) -> F {
        self.max
    }

    /// A 12-bit A/D count in engineering units.
    pub fn count_to_units(&self, count: u16) -> Result<F, ScalingError<F>> {
        if count > ADC_FULL_SCALE {
            return Err(ScalingError::CountOutOfRange { count });
        }
        if count == ADC_FULL_SCALE {
            return Ok(self.max);
        }
        if count == 0 {
            // SCALEMIN bit for bit (min + 0 would turn −0.0 into +0.0).
            return Ok(self.min);
        }
        // Each step rounds monotonically, so the result never decreases with the count; the
        // clamp keeps rounding from leaving the scale and keeps the order.
        let units =
            self.min + (self.max - self.min) * F::from_u16(count) / F::from_u16(ADC_FULL_SCALE);
        Ok(if units > self.max { self.max } else { units })
    }

    /// An engineering value as the nearest A/D count (clamped to 0–4095: ±∞ give 4095 and 0),
    /// for simulators; NaN gives 0.
    #[must_use]
    pub fn units_to_count(&self, units: F) -> u16 {
        nearest_count((units - self.min) / (self.max - self.min), ADC_FULL_SCALE)
    }

    /// Whether `units` lies within the scale (the source's check of WIN).
    #[must_use]
    pub fn contains(&self, units: F) -> bool {
        units >= self.min && units <= self.max
    }

    /// Volts as the nearest 8-bit D/A count, halves up, clamped to 0–255.
    pub fn volts_to_dac(volts: F) -> Result<u8, ScalingError<F>> {
        if volts.is_nan() {
            return Err(ScalingError::NotANumber);
        }
        let count = nearest_count(volts / F::from_u16(SPAN_VOLTS), u16::from(DAC_FULL_SCALE));
        Ok(u8::try_from(count).unwrap_or(DAC_FULL_SCALE))
    }

    /// An 8-bit D/A count in volts.
    #[must_use]
    pub fn dac_to_volts(count: u8) -> F {
        F::from_u16(u16::from(count)) * F::from_u16(SPAN_VOLTS)
            / F::from_u16(u16::from(DAC_FULL_SCALE))
    }
}

/// The converter count nearest to `fraction` of full scale: halves up, clamped to 0..=`full`,
/// NaN as 0.
fn nearest_count<F: Real>(fraction: F, full: u16) -> u16 {
    let full_f = F::from_u16(full);
    let x = fraction * full_f;
    if x.is_nan() || x <= F::zero() {
        0
    } else if x >= full_f {
        full
    } else {
        // 0 < x + 0.5 < full + 1 <= 65536; the float-to-int conversion saturates in any case.
        let half = F::from_u16(1) / F::from_u16(2);
        // Truncation toward zero is the floor here, as x + 0.5 > 0.
        num_traits::ToPrimitive::to_u16(&(x + half)).unwrap_or(full)
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
                Scaling::volts_to_dac(Scaling::<f64>::dac_to_volts(count)),
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
    fn f32_scale_round_trips_every_count() {
        let s = Scaling::new(0.0f32, 40.0).unwrap();
        for count in 0..=ADC_FULL_SCALE {
            assert_eq!(s.units_to_count(s.count_to_units(count).unwrap()), count);
        }
        for count in 0..=DAC_FULL_SCALE {
            assert_eq!(
                Scaling::volts_to_dac(Scaling::<f32>::dac_to_volts(count)),
                Ok(count)
            );
        }
    }

    #[test]
    fn bad_scales_are_refused() {
        assert!(
            Scaling::new(-f64::MAX, f64::MAX).is_err(),
            "an infinite span"
        );
        assert_eq!(
            Scaling::new(5.0, 5.0),
            Err(ScalingError::Reversed { min: 5.0, max: 5.0 })
        );
        assert_eq!(Scaling::new(f64::NAN, 5.0), Err(ScalingError::NotFinite));
        assert!(Scaling::new(0.0, 1.0).unwrap().contains(1.0));
    }
}
