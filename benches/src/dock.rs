//! A steady dock: a trolley enters every `SPACING` pulses, bound for the tippers in turn, and
//! the tipper distances are chosen so that `trolleys` are on the chain on average. Every
//! implementation sees the same pulse and entry stream, so their costs compare.

/// Tippers on the bench dock.
pub const TIPPERS: usize = 40;
/// Pulses between entering trolleys (0.4 m of chain).
pub const SPACING: u32 = 4;

/// Tipper distances giving `trolleys` on the chain on average: the mean distance is
/// `trolleys × SPACING`, spread evenly over the tippers.
#[must_use]
pub fn distances(trolleys: u32) -> Vec<u32> {
    let tippers = TIPPERS as u32;
    let mean = trolleys * SPACING;
    (1..=tippers)
        .map(|j| (2 * mean * j / (tippers + 1)).max(1))
        .collect()
}

/// Drives one implementation: `enter(trolley, tipper)` and `pulse()`.
pub struct Feed {
    pulse: u64,
    next_trolley: u32,
}

impl Default for Feed {
    fn default() -> Feed {
        Feed::new()
    }
}

impl Feed {
    /// A feed at pulse 0.
    #[must_use]
    pub fn new() -> Feed {
        Feed {
            pulse: 0,
            next_trolley: 0,
        }
    }

    /// One step: possibly a trolley to enter (trolley, tipper), then one pulse.
    pub fn step(&mut self) -> Option<(u32, usize)> {
        self.pulse += 1;
        if !self.pulse.is_multiple_of(u64::from(SPACING)) {
            return None;
        }
        self.next_trolley = self.next_trolley.wrapping_add(1);
        // A stride coprime to the tipper count visits every tipper, in a mixed order.
        let tipper = (self.next_trolley as usize * 17) % TIPPERS;
        Some((self.next_trolley, tipper))
    }
}
