//! What the interrupts own: the watchdog, the latch capture and the power-failure flag, shared
//! with the cycle through a critical section.

use core::cell::Cell;

use critical_section::Mutex;

use crate::executive::{
    Begin, CycleConfig, HALF_RANGE_US, Halt, MAX_WATCHDOG_US, Restart, Supervision,
};
use crate::image::Image;

#[derive(Clone, Copy)]
struct Shared<const IW: usize> {
    captured: [u16; IW],
    /// When the last cycle finished, or when the first check armed the watchdog.
    kicked_us: Option<u32>,
    tripped: bool,
    power_failed: bool,
    trips: u32,
    /// Trips and power failures so far (wrapping): a cycle that sees it change between its
    /// start and its end has been overtaken by a halt.
    events: u32,
    /// The last of those events.
    last_event: Halt,
    /// The plant has the safe outputs and the program must start from them (a trip, or a
    /// power failure resumed with [`Restart::Inhibit`]); taken by the next cycle.
    restart_from_safe: bool,
}

/// The executive's supervision as interrupt handlers need it: every method takes `&self`, so a
/// `static Signals` is shared by a timer interrupt (the watchdog), a fast input interrupt
/// (latch capture), the power-fail interrupt and the main loop that runs
/// [`Executive::cycle_with`](crate::Executive::cycle_with).
///
/// [`Executive::check_watchdog`](crate::Executive::check_watchdog) needs the executive, which
/// [`cycle`](crate::Executive::cycle) holds for the whole scan, so it can see a hang only between
/// cycles — not what a watchdog is for. [`Signals::check_watchdog`] runs in the timer interrupt
/// and trips while the program is stuck inside a cycle.
///
/// The state lives in a [`critical_section::Mutex`]; each call holds the critical section for a
/// few word operations (`capture` for one OR per input word). The executive's own bus write is
/// never inside it: the cycle checks and commits in one section, writes the outputs with
/// interrupts on, and checks again in a second section; a trip or a power failure that came in
/// between makes the main context write the safe outputs once more after its own write, so
/// whatever the moment of the interrupt, the safe outputs are the last thing written and the
/// cycle returns the halt. A bus write that never returns is caught by the timer interrupt
/// (the watchdog trips and its handler writes the safe outputs, if the bus lets it) and by the
/// hardware watchdog, which [`Io::kick_watchdog`](crate::Io::kick_watchdog) pulses only after a
/// cycle's write has returned and been confirmed.
///
/// The firmware provides the critical section implementation, as for any embedded crate built on
/// `critical-section` (on a single-core Cortex-M: `cortex-m`'s `critical-section-single-core`
/// feature; on a host: `critical-section`'s `std` feature). No `unsafe` here.
///
/// ```
/// use regler_scan_cycle::{CycleConfig, Executive, Halt, Io, Signals};
/// static SIGNALS: Signals<1, 1> = Signals::new(&CycleConfig::source());
///
/// struct Plant { t: u32, out: [u16; 1] }
/// impl Io<1, 1> for Plant {
///     fn read_inputs(&mut self, raw: &mut [u16; 1]) { *raw = [0]; }
///     fn write_outputs(&mut self, out: &[u16; 1]) { self.out = *out; }
///     fn now_us(&mut self) -> u32 { self.t }
/// }
/// let mut plant = Plant { t: 0, out: [0] };
/// let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
/// plc.cycle_with(&mut plant, &SIGNALS, |scan| {
///     scan.outputs.set(0, true).ok(); // point 0 exists: an error is impossible here
/// })?;
/// assert_eq!(plant.out, [1]);
///
/// // The program hangs; the timer interrupt checks 150 ms after the last cycle ended.
/// let result = plc.cycle_with(&mut plant, &SIGNALS, |scan| {
///     assert!(SIGNALS.check_watchdog(150_000)); // (inside the interrupt handler)
///     scan.outputs.set(0, true).ok();
/// });
/// assert_eq!(result, Err(Halt::Watchdog)); // the cycle wrote nothing after the trip
/// assert_eq!(SIGNALS.safe_outputs().words(), &[0]); // what the handler wrote
/// # Ok::<(), Halt>(())
/// ```
pub struct Signals<const IW: usize, const OW: usize> {
    shared: Mutex<Cell<Shared<IW>>>,
    watchdog_us: u32,
    safe_outputs: Image<OW>,
}

impl<const IW: usize, const OW: usize> Signals<IW, OW> {
    /// Supervision with `config`'s watchdog limit and safe outputs. A `const fn`, for a
    /// `static`. A limit above 2³¹ − 2 µs (35.8 minutes) acts as 2³¹ − 2 µs: a longer time
    /// cannot be told from a clock stepping back.
    #[must_use]
    pub const fn new(config: &CycleConfig<OW>) -> Signals<IW, OW> {
        let limit = if config.watchdog_us <= MAX_WATCHDOG_US {
            config.watchdog_us
        } else {
            MAX_WATCHDOG_US
        };
        Signals {
            shared: Mutex::new(Cell::new(Shared {
                captured: [0; IW],
                kicked_us: None,
                tripped: false,
                power_failed: false,
                trips: 0,
                events: 0,
                last_event: Halt::Watchdog,
                restart_from_safe: false,
            })),
            watchdog_us: limit,
            safe_outputs: config.safe_outputs,
        }
    }

    fn update<R>(&self, f: impl FnOnce(&mut Shared<IW>) -> R) -> R {
        critical_section::with(|cs| {
            let cell = self.shared.borrow(cs);
            let mut shared = cell.get();
            let r = f(&mut shared);
            cell.set(shared);
            r
        })
    }

    fn read(&self) -> Shared<IW> {
        critical_section::with(|cs| self.shared.borrow(cs).get())
    }

    /// From the timer interrupt, with the time now in µs (the [`Io`](crate::Io) clock): trips
    /// the watchdog when the clock is more than the limit past the end of the last cycle —
    /// counted from the first check while no cycle has finished, so a program that never
    /// completes a cycle trips it too. Returns `true` when it trips now: the handler must then
    /// write [`safe_outputs`](Signals::safe_outputs). A power failure is not a hang: while it
    /// lasts nothing trips.
    ///
    /// A reading 2³¹ µs or more behind the last cycle's end (wrapping) is a clock stepping back,
    /// or a time the handler read just before the cycle ended: it never trips, and the watchdog
    /// goes on counting from the cycle's end (a clock that stepped back by d holds the trip off
    /// for d; the hardware watchdog covers a clock that is wrong for longer).
    pub fn check_watchdog(&self, now_us: u32) -> bool {
        let limit = self.watchdog_us;
        self.update(|s| {
            if s.tripped || s.power_failed {
                return false;
            }
            match s.kicked_us {
                None => {
                    s.kicked_us = Some(now_us);
                    false
                }
                Some(kicked) => {
                    let since = now_us.wrapping_sub(kicked);
                    if since > limit && since < HALF_RANGE_US {
                        s.tripped = true;
                        s.trips = s.trips.saturating_add(1);
                        s.events = s.events.wrapping_add(1);
                        s.last_event = Halt::Watchdog;
                        s.restart_from_safe = true;
                        true
                    } else {
                        false
                    }
                }
            }
        })
    }

    /// From a fast input interrupt: remembers which inputs are on now; the next cycle reads
    /// each latched input that was on in any capture since the last cycle (see
    /// [`Conditioning`](crate::Conditioning)). Captures go on through a power failure, as the
    /// source's battery-backed input flip-flops did.
    pub fn capture(&self, raw: &[u16; IW]) {
        self.update(|s| {
            for (c, r) in s.captured.iter_mut().zip(raw) {
                *c |= r;
            }
        });
    }

    /// From the power-fail interrupt: from this moment no cycle writes outputs — one running
    /// now writes the safe outputs again after its own write and returns [`Halt::PowerFail`] —
    /// and cycles are refused until [`resume`](Signals::resume). The handler writes
    /// [`safe_outputs`](Signals::safe_outputs). A watchdog trip stays.
    pub fn power_fail(&self) {
        self.update(|s| {
            s.power_failed = true;
            s.events = s.events.wrapping_add(1);
            s.last_event = Halt::PowerFail;
        });
    }

    /// Power is back: cycles may run again (unless the watchdog had tripped: a power cycle is
    /// not an operator's reset), starting from the previous output image `restart` says —
    /// [`Restart::Inhibit`] (what EN 60204-1 asks for) or [`Restart::WhereStopped`]. The
    /// outage is not program time: the executive's clock goes on from where it stood. The
    /// watchdog re-arms at its next check. Without a power failure this does nothing.
    pub fn resume(&self, restart: Restart) {
        self.update(|s| {
            if s.power_failed {
                s.power_failed = false;
                s.kicked_us = None;
                if restart == Restart::Inhibit {
                    s.restart_from_safe = true;
                }
            }
        });
    }

    /// The operator has looked at the trip: cycles may run again, starting from the safe
    /// outputs as the previous output image; the watchdog re-arms at its next check. A reset
    /// while the watchdog has not tripped does nothing (a bouncing reset key does not hold off
    /// a trip).
    pub fn reset_watchdog(&self) {
        self.update(|s| {
            if s.tripped {
                s.tripped = false;
                s.kicked_us = None;
            }
        });
    }

    /// The count of trips and power failures so far, and whether cycles are refused now.
    pub(crate) fn watch_state(&self) -> (u32, bool) {
        let s = self.read();
        (s.events, halt_of(&s).is_some())
    }

    /// Whether the watchdog has tripped (and not been reset).
    #[must_use]
    pub fn tripped(&self) -> bool {
        self.read().tripped
    }

    /// Whether the power has failed and not come back.
    #[must_use]
    pub fn power_failed(&self) -> bool {
        self.read().power_failed
    }

    /// Times the watchdog tripped.
    #[must_use]
    pub fn trips(&self) -> u32 {
        self.read().trips
    }

    /// The outputs to write on a trip or a power failure.
    #[must_use]
    pub const fn safe_outputs(&self) -> &Image<OW> {
        &self.safe_outputs
    }
}

fn halt_of<const IW: usize>(s: &Shared<IW>) -> Option<Halt> {
    if s.power_failed {
        Some(Halt::PowerFail)
    } else if s.tripped {
        Some(Halt::Watchdog)
    } else {
        None
    }
}

/// The executive's side of the shared state, used by [`Executive::cycle_with`](crate::Executive::cycle_with).
impl<const IW: usize, const OW: usize> Supervision<IW, OW> for Signals<IW, OW> {
    fn halted(&self) -> Option<Halt> {
        halt_of(&self.read())
    }

    fn begin(&self) -> Result<Begin<IW>, Halt> {
        self.update(|s| {
            if let Some(halt) = halt_of(s) {
                return Err(halt);
            }
            Ok(Begin {
                events: s.events,
                captured: Some(core::mem::replace(&mut s.captured, [0; IW])),
                restart_from_safe: core::mem::replace(&mut s.restart_from_safe, false),
            })
        })
    }

    fn commit(&self, events: u32) -> Result<(), Halt> {
        let s = self.read();
        if s.events == events {
            Ok(())
        } else {
            Err(halt_of(&s).unwrap_or(s.last_event))
        }
    }

    fn confirm(&self, events: u32, end_us: u32) -> Result<(), Halt> {
        self.update(|s| {
            if s.events == events {
                s.kicked_us = Some(end_us);
                Ok(())
            } else {
                Err(halt_of(s).unwrap_or(s.last_event))
            }
        })
    }

    fn safe_outputs(&self) -> Option<&Image<OW>> {
        Some(&self.safe_outputs)
    }
}

impl<const IW: usize, const OW: usize> core::fmt::Debug for Signals<IW, OW> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let s = self.read();
        f.debug_struct("Signals")
            .field("tripped", &s.tripped)
            .field("power_failed", &s.power_failed)
            .field("trips", &s.trips)
            .field("watchdog_us", &self.watchdog_us)
            .finish_non_exhaustive()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tripped watchdog is not tripped again, and a power failure is not a hang: neither is
    /// counted as another trip however long the checks go on.
    #[test]
    fn no_trip_while_tripped_or_while_the_power_is_off() {
        let signals: Signals<1, 1> = Signals::new(&CycleConfig::source());
        assert!(!signals.check_watchdog(0));
        assert!(signals.check_watchdog(150_000), "past the 100 ms limit");
        assert_eq!(signals.trips(), 1);
        assert!(
            !signals.check_watchdog(300_000),
            "already tripped: not a new trip"
        );
        assert_eq!((signals.trips(), signals.tripped()), (1, true));

        let signals: Signals<1, 1> = Signals::new(&CycleConfig::source());
        assert!(!signals.check_watchdog(0));
        signals.power_fail();
        for now in [50_000, 150_000, 1_000_000] {
            assert!(
                !signals.check_watchdog(now),
                "an outage is not a hang ({now} µs)"
            );
        }
        assert_eq!((signals.trips(), signals.tripped()), (0, false));
    }

    #[test]
    fn debug_text_shows_the_state() {
        let signals: Signals<1, 1> = Signals::new(&CycleConfig::source());
        assert_eq!(
            std::format!("{signals:?}"),
            "Signals { tripped: false, power_failed: false, trips: 0, watchdog_us: 100000, .. }"
        );
    }
}
