//! The source's method: one shift register of (trolley, tipper, distance) entries, every entry
//! counted down on every chain pulse.

use crate::dock::Feed;

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

    /// The register as `pulses` steps of `feed` (a possible entry, then a pulse) leave it, built
    /// from when each trolley entered instead of counting every entry down on every pulse — the
    /// warm-up at 10 000 trolleys would otherwise cost billions of instructions under callgrind.
    /// The entries may be in another order than the pulses would leave them, which changes no
    /// later pulse's work or events.
    #[must_use]
    pub fn warmed(
        distances: &[u32],
        hold: u32,
        capacity: usize,
        feed: &mut Feed,
        pulses: u64,
    ) -> CountDown {
        let mut register = CountDown::new(distances, hold, capacity);
        // (trolley, tipper, the pulse it reaches its tipper on)
        let mut entered = Vec::new();
        for t in 1..=pulses {
            if let Some((trolley, tipper)) = feed.step() {
                entered.push((trolley, tipper, t + u64::from(distances[tipper].max(1)) - 1));
            }
        }
        let mut last_set = vec![None; distances.len()];
        for (trolley, tipper, due) in entered {
            if due > pulses {
                register
                    .entries
                    .push((trolley, tipper, (due - pulses) as u32));
            } else {
                last_set[tipper] = last_set[tipper].max(Some(due));
            }
        }
        for (held, set) in register.held.iter_mut().zip(last_set) {
            // Set to hold + 1 on the pulse it fired, counted down on that pulse and every later.
            *held = set.map_or(0, |f| (u64::from(hold) + f).saturating_sub(pulses) as u32);
        }
        register
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dock::distances;

    fn state(r: &CountDown) -> (Vec<(u32, usize, u32)>, Vec<u32>) {
        let mut entries = r.entries.clone();
        entries.sort_unstable();
        (entries, r.held.clone())
    }

    #[test]
    fn a_warmed_register_holds_what_the_pulses_leave_and_fires_the_same() {
        for trolleys in [1, 16, 100] {
            let d = distances(trolleys);
            let pulses = 2 * u64::from(*d.iter().max().unwrap_or(&1)) + 7;
            let (mut feed_a, mut feed_b) = (Feed::new(), Feed::new());
            let mut pulsed = CountDown::new(&d, 6, 64);
            for _ in 0..pulses {
                if let Some((trolley, tipper)) = feed_a.step() {
                    pulsed.enter(trolley, tipper);
                }
                pulsed.pulse(|_| {});
            }
            let mut warmed = CountDown::warmed(&d, 6, 64, &mut feed_b, pulses);
            assert_eq!(state(&warmed), state(&pulsed), "{trolleys} trolleys");
            // And from there on the same events, pulse by pulse.
            for _ in 0..500 {
                let (mut a, mut b) = (Vec::new(), Vec::new());
                for (r, feed, out) in [
                    (&mut pulsed, &mut feed_a, &mut a),
                    (&mut warmed, &mut feed_b, &mut b),
                ] {
                    if let Some((trolley, tipper)) = feed.step() {
                        r.enter(trolley, tipper);
                    }
                    r.pulse(|e| out.push(e));
                }
                a.sort_by_key(|e| format!("{e:?}"));
                b.sort_by_key(|e| format!("{e:?}"));
                assert_eq!(a, b);
            }
        }
    }
}
