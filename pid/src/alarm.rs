//! The RFEL alarm unit of the source: blink and buzz on a new alarm, steady after acknowledge.

/// What the alarm lamp shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum AlarmState {
    /// No alarm: lamp off.
    #[default]
    Normal,
    /// A new alarm, not yet acknowledged: lamp blinking (about 0.25 s), buzzer sounding.
    Blinking,
    /// Acknowledged while the error is still too large: lamp steady, buzzer silent.
    Steady,
}

/// The source's two-bit alarm state machine (appendix 8.6 of the original), driven by
/// "|error| > RFEL" once per sample and by the operator's acknowledge (key C).
///
/// | state | error too large | error back | acknowledge |
/// |---|---|---|---|
/// | Normal | → Blinking (buzzer) | Normal | Normal |
/// | Blinking | Blinking | → Normal | → Steady if the error is still too large, else Normal |
/// | Steady | Steady | → Normal | Steady |
///
/// As in the source's program (lines 7950–7990), an alarm not yet acknowledged goes off by itself
/// when the error comes back; a new excursion after that, or after a steady alarm has cleared, is
/// a new alarm and sounds the buzzer again.
///
/// ```
/// use regler_pid::{Alarm, AlarmState};
/// let mut alarm = Alarm::new();
/// assert_eq!(alarm.update(true), AlarmState::Blinking);
/// assert!(alarm.buzzer());
/// alarm.acknowledge();
/// assert_eq!(alarm.state(), AlarmState::Steady);
/// assert!(!alarm.buzzer());
/// assert_eq!(alarm.update(false), AlarmState::Normal);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Alarm {
    state: AlarmState,
    too_large: bool,
    raised: u32,
}

impl Alarm {
    /// No alarm.
    #[must_use]
    pub const fn new() -> Alarm {
        Alarm {
            state: AlarmState::Normal,
            too_large: false,
            raised: 0,
        }
    }

    /// One sample: whether |error| exceeds RFEL now. Returns the new state.
    pub fn update(&mut self, error_too_large: bool) -> AlarmState {
        self.too_large = error_too_large;
        self.state = match (self.state, error_too_large) {
            (AlarmState::Normal, true) => {
                self.raised = self.raised.saturating_add(1);
                AlarmState::Blinking
            }
            (_, false) => AlarmState::Normal,
            (state, true) => state,
        };
        self.state
    }

    /// The operator acknowledged (key C at the keypad or the terminal).
    pub fn acknowledge(&mut self) {
        if self.state == AlarmState::Blinking {
            self.state = if self.too_large {
                AlarmState::Steady
            } else {
                AlarmState::Normal
            };
        }
    }

    /// The lamp state.
    #[must_use]
    pub const fn state(&self) -> AlarmState {
        self.state
    }

    /// Whether the buzzer sounds: only for a new, unacknowledged alarm.
    #[must_use]
    pub const fn buzzer(&self) -> bool {
        matches!(self.state, AlarmState::Blinking)
    }

    /// Whether the lamp is lit, given the blink oscillator's phase.
    #[must_use]
    pub const fn lamp(&self, blink_phase_on: bool) -> bool {
        match self.state {
            AlarmState::Normal => false,
            AlarmState::Blinking => blink_phase_on,
            AlarmState::Steady => true,
        }
    }

    /// The source's two output bits (port F400H): bit 0 = error too large, bit 1 =
    /// acknowledged. 0 off, 1 blinking, 3 steady.
    #[must_use]
    pub const fn output_bits(&self) -> u8 {
        match self.state {
            AlarmState::Normal => 0,
            AlarmState::Blinking => 1,
            AlarmState::Steady => 3,
        }
    }

    /// How many alarms were raised (entries into Blinking).
    #[must_use]
    pub const fn raised(&self) -> u32 {
        self.raised
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The full state table: (state, error too large, acknowledge) → (state, buzzer).
    #[test]
    fn state_table_of_the_alarm_unit() {
        use AlarmState::{Blinking, Normal, Steady};
        let table = [
            (Normal, false, false, Normal, false),
            (Normal, true, false, Blinking, true),
            (Normal, false, true, Normal, false),
            (Normal, true, true, Steady, false), // raised and acknowledged in the same sample
            (Blinking, true, false, Blinking, true),
            (Blinking, false, false, Normal, false),
            (Blinking, true, true, Steady, false),
            (Blinking, false, true, Normal, false),
            (Steady, true, false, Steady, false),
            (Steady, false, false, Normal, false),
            (Steady, true, true, Steady, false),
            (Steady, false, true, Normal, false),
        ];
        for (from, large, ack, to, buzzer) in table {
            let mut alarm = Alarm {
                state: from,
                too_large: from != Normal,
                raised: 0,
            };
            alarm.update(large);
            if ack {
                alarm.acknowledge();
            }
            assert_eq!(
                (alarm.state(), alarm.buzzer()),
                (to, buzzer),
                "{from:?} {large} {ack}"
            );
        }
    }

    #[test]
    fn buzzer_only_for_a_new_alarm() {
        let mut a = Alarm::new();
        a.update(true);
        a.acknowledge();
        for _ in 0..5 {
            a.update(true);
            assert!(!a.buzzer());
            assert!(a.lamp(false));
        }
        a.update(false);
        assert_eq!(a.output_bits(), 0);
        a.update(true);
        assert!(a.buzzer());
        assert_eq!(a.output_bits(), 1);
        assert!(!a.lamp(false) && a.lamp(true));
        assert_eq!(a.raised(), 2);
    }
}
