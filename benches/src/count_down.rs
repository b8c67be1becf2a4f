//! The source's method: one shift register of (trolley, tipper, distance) entries, every entry
//! counted down on every chain pulse.

/// A tipper event as the count-down register reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event {
    /// A trolley is over its tipper.
    Set { tipper: usize, trolley: u32 },
    /// The hold has passed.
    Reset { tipper: usize },
}

/// The count-down shift register.
pub struct CountDown {
    distances: Vec<u32>,
    hold: u32,
    entries: Vec<(u32, usize, u32)>,
    held: Vec<u32>,
}

impl CountDown {
    /// A register for tippers at `distances`, held `hold` pulses.
    #[must_use]
    pub fn new(distances: &[u32], hold: u32, capacity: usize) -> CountDown {
        CountDown {
            distances: distances.to_vec(),
            hold,
            entries: Vec::with_capacity(capacity),
            held: vec![0; distances.len()],
        }
    }

    /// Puts a trolley on the chain.
    pub fn enter(&mut self, trolley: u32, tipper: usize) {
        self.entries
            .push((trolley, tipper, self.distances[tipper].max(1)));
    }

    /// One pulse: every entry counted down, every held tipper too.
    pub fn pulse(&mut self, mut on_event: impl FnMut(Event)) {
        let mut i = 0;
        while i < self.entries.len() {
            let e = &mut self.entries[i];
            e.2 -= 1;
            if e.2 == 0 {
                let (trolley, tipper, _) = self.entries.swap_remove(i);
                self.held[tipper] = self.hold + 1;
                on_event(Event::Set { tipper, trolley });
            } else {
                i += 1;
            }
        }
        for (tipper, held) in self.held.iter_mut().enumerate() {
            if *held > 0 {
                *held -= 1;
                if *held == 0 {
                    on_event(Event::Reset { tipper });
                }
            }
        }
    }

    /// Trolleys on the chain.
    #[must_use]
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the chain is empty.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}
