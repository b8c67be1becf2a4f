//! IEC 61131-3 standard function blocks: timers, counters, edge detectors and bistables.
//!
//! Time is a wrapping `u32` millisecond count passed in by the caller. The timers accumulate the
//! time between calls (wrapping difference), so they work across the wrap of the counter as long
//! as two calls are less than 2³¹ ms (24.8 days) apart; elapsed time saturates at `u32::MAX`. A
//! clock that steps back (a wrapping difference of 2³¹ or more) adds no time: the timers wait
//! until it has caught up with the latest time they saw, instead of taking the step for 49 days
//! and firing.
//!
//! A timer that has finished stays finished until its input says otherwise, whatever happens to
//! PT meanwhile: a TON that is on stays on while IN stays on; a TOF that has gone off stays off
//! while IN stays off; a TP whose pulse has ended gives no new pulse without a new rising edge.
//! A PT change while a timer is timing takes effect at the next call. This is the behaviour of
//! the standard's ST bodies as matiec and CODESYS implement them.

/// Accumulated time since a timer started, robust to the wrap of the clock.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
struct Elapsed {
    last_ms: u32,
    total_ms: u32,
}

impl Elapsed {
    fn start(now_ms: u32) -> Elapsed {
        Elapsed {
            last_ms: now_ms,
            total_ms: 0,
        }
    }

    fn advance(&mut self, now_ms: u32) -> u32 {
        let step = now_ms.wrapping_sub(self.last_ms);
        // A step of 2^31 ms or more is the clock going back: no time passes, and the latest
        // time seen stays the reference.
        if step < 1 << 31 {
            self.total_ms = self.total_ms.saturating_add(step);
            self.last_ms = now_ms;
        }
        self.total_ms
    }
}

/// TON, on-delay timer: Q goes on when IN has been on for PT; ET counts while IN is on.
///
/// ```
/// use regler_scan_cycle::Ton;
/// let mut jam = Ton::new(500);
/// assert!(!jam.call(true, 1_000));
/// assert!(!jam.call(true, 1_499));
/// assert!(jam.call(true, 1_500));
/// assert_eq!(jam.et(), 500);
/// assert!(!jam.call(false, 1_600)); // IN off: Q off, ET 0
/// assert_eq!(jam.et(), 0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "RawTimer"))]
pub struct Ton {
    pt_ms: u32,
    running: Option<Elapsed>,
    q: bool,
    /// ET once the timer has finished; a finished timer stays finished until IN goes off.
    done_et: Option<u32>,
}

impl Ton {
    /// A timer with preset time `pt_ms`.
    #[must_use]
    pub const fn new(pt_ms: u32) -> Ton {
        Ton {
            pt_ms,
            running: None,
            q: false,
            done_et: None,
        }
    }

    /// One call: input IN at time `now_ms`; returns Q.
    pub fn call(&mut self, input: bool, now_ms: u32) -> bool {
        if !input {
            self.running = None;
            self.q = false;
            self.done_et = None;
            return false;
        }
        if self.done_et.is_some() {
            return true;
        }
        let running = self.running.get_or_insert(Elapsed::start(now_ms));
        if running.advance(now_ms) >= self.pt_ms {
            self.q = true;
            self.done_et = Some(self.pt_ms);
        }
        self.q
    }
}

/// TOF, off-delay timer: Q is on while IN is on and for PT after IN goes off.
///
/// ```
/// use regler_scan_cycle::Tof;
/// let mut run_on = Tof::new(300);
/// assert!(run_on.call(true, 0));
/// assert!(run_on.call(false, 100));  // off-delay running
/// assert!(run_on.call(false, 399));
/// assert!(!run_on.call(false, 400));
/// assert_eq!(run_on.et(), 300);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "RawTimer"))]
pub struct Tof {
    pt_ms: u32,
    running: Option<Elapsed>,
    q: bool,
    /// ET once the off-delay has run out; it stays out until IN comes on.
    done_et: Option<u32>,
}

impl Tof {
    /// A timer with preset time `pt_ms`.
    #[must_use]
    pub const fn new(pt_ms: u32) -> Tof {
        Tof {
            pt_ms,
            running: None,
            q: false,
            done_et: None,
        }
    }

    /// One call: input IN at time `now_ms`; returns Q.
    pub fn call(&mut self, input: bool, now_ms: u32) -> bool {
        if input {
            self.running = None;
            self.done_et = None;
            self.q = true;
            return true;
        }
        if self.q {
            let running = self.running.get_or_insert(Elapsed::start(now_ms));
            if running.advance(now_ms) >= self.pt_ms {
                self.q = false;
                self.done_et = Some(self.pt_ms);
            }
        }
        self.q
    }
}

/// TP, pulse timer: a rising edge of IN starts a pulse of exactly PT; edges during the pulse
/// are ignored. After the pulse ET holds at PT while IN stays on and returns to 0 when IN is off.
///
/// ```
/// use regler_scan_cycle::Tp;
/// let mut gate = Tp::new(200);
/// assert!(gate.call(true, 0));
/// assert!(gate.call(false, 150)); // the pulse runs on
/// assert!(!gate.call(false, 200));
/// assert_eq!(gate.et(), 0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "RawTp"))]
pub struct Tp {
    pt_ms: u32,
    running: Option<Elapsed>,
    q: bool,
    prev_in: bool,
    /// ET once the pulse has ended with IN still on; no new pulse without a new rising edge.
    done_et: Option<u32>,
}

impl Tp {
    /// A timer with pulse length `pt_ms`.
    #[must_use]
    pub const fn new(pt_ms: u32) -> Tp {
        Tp {
            pt_ms,
            running: None,
            q: false,
            prev_in: false,
            done_et: None,
        }
    }

    /// One call: input IN at time `now_ms`; returns Q.
    pub fn call(&mut self, input: bool, now_ms: u32) -> bool {
        let rising = input && !self.prev_in;
        self.prev_in = input;
        if rising && !self.q {
            self.running = Some(Elapsed::start(now_ms));
            self.done_et = None;
        }
        if let Some(running) = &mut self.running {
            if running.advance(now_ms) >= self.pt_ms {
                // The pulse is over: ET holds while IN stays on, and a longer PT set now
                // starts nothing.
                self.q = false;
                self.running = None;
                self.done_et = input.then_some(self.pt_ms);
            } else {
                self.q = true;
            }
        } else if !input {
            self.done_et = None;
        }
        self.q
    }
}

/// Stored timer state (deserialized) that no sequence of calls leaves a timer in — a corrupt or
/// tampered block — refused, instead of restored into a timer that would come on at once or
/// give a pulse that never ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum StoredTimerError {
    /// A TON with Q on that has not finished: it would be on at once, before PT.
    TonOnUnfinished,
    /// A TON that has finished with Q off.
    TonFinishedOff,
    /// A TOF whose off-delay has run out with Q still on.
    TofRunOutOn,
    /// A TP with Q on and no pulse running: its pulse would never end.
    TpOnWithoutPulse,
    /// A TP with a pulse running and Q off.
    TpPulseOff,
    /// A TP holding the ET of an ended pulse while IN is off or a pulse runs.
    TpEndedPulseHeld,
}

impl core::fmt::Display for StoredTimerError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            StoredTimerError::TonOnUnfinished => {
                "stored TON has Q on but has not finished: it would be on before PT"
            }
            StoredTimerError::TonFinishedOff => "stored TON has finished but has Q off",
            StoredTimerError::TofRunOutOn => "stored TOF has run out its off-delay but has Q on",
            StoredTimerError::TpOnWithoutPulse => {
                "stored TP has Q on without a pulse running: the pulse would never end"
            }
            StoredTimerError::TpPulseOff => "stored TP has a pulse running with Q off",
            StoredTimerError::TpEndedPulseHeld => {
                "stored TP holds an ended pulse's ET while IN is off or a pulse runs"
            }
        })
    }
}

impl core::error::Error for StoredTimerError {}

/// The stored form of a [`Ton`] or a [`Tof`] (their fields, in their order), checked on the way
/// in by each.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
#[serde(expecting = "struct Ton or Tof")] // what serde's messages name
struct RawTimer {
    pt_ms: u32,
    running: Option<Elapsed>,
    q: bool,
    done_et: Option<u32>,
}

#[cfg(feature = "serde")]
impl TryFrom<RawTimer> for Ton {
    type Error = StoredTimerError;
    fn try_from(r: RawTimer) -> Result<Ton, StoredTimerError> {
        // Q is on exactly when the timer has finished (until IN goes off).
        match (r.q, r.done_et.is_some()) {
            (true, false) => Err(StoredTimerError::TonOnUnfinished),
            (false, true) => Err(StoredTimerError::TonFinishedOff),
            _ => Ok(Ton {
                pt_ms: r.pt_ms,
                running: r.running,
                q: r.q,
                done_et: r.done_et,
            }),
        }
    }
}

#[cfg(feature = "serde")]
impl TryFrom<RawTimer> for Tof {
    type Error = StoredTimerError;
    fn try_from(r: RawTimer) -> Result<Tof, StoredTimerError> {
        if r.q && r.done_et.is_some() {
            return Err(StoredTimerError::TofRunOutOn);
        }
        Ok(Tof {
            pt_ms: r.pt_ms,
            running: r.running,
            q: r.q,
            done_et: r.done_et,
        })
    }
}

/// The stored form of a [`Tp`], checked on the way in.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
#[serde(expecting = "struct Tp")] // what serde's messages name
struct RawTp {
    pt_ms: u32,
    running: Option<Elapsed>,
    q: bool,
    prev_in: bool,
    done_et: Option<u32>,
}

#[cfg(feature = "serde")]
impl TryFrom<RawTp> for Tp {
    type Error = StoredTimerError;
    fn try_from(r: RawTp) -> Result<Tp, StoredTimerError> {
        // Q is on exactly while a pulse runs; an ended pulse's ET is held only while IN stays on.
        match (r.q, r.running.is_some()) {
            (true, false) => return Err(StoredTimerError::TpOnWithoutPulse),
            (false, true) => return Err(StoredTimerError::TpPulseOff),
            _ => {}
        }
        if r.done_et.is_some() && (r.q || !r.prev_in) {
            return Err(StoredTimerError::TpEndedPulseHeld);
        }
        Ok(Tp {
            pt_ms: r.pt_ms,
            running: r.running,
            q: r.q,
            prev_in: r.prev_in,
            done_et: r.done_et,
        })
    }
}

/// ET, Q, PT and a PT change, alike for the three timers (each has `pt_ms`, `running`, `q`).
macro_rules! timer_accessors {
    ($timer:ident, $et_doc:literal) => {
        impl $timer {
            #[doc = $et_doc]
            #[must_use]
            pub fn et(&self) -> u32 {
                match self.done_et {
                    Some(et) => et,
                    None => self.running.map_or(0, |r| r.total_ms.min(self.pt_ms)),
                }
            }

            /// Q as of the last call.
            #[must_use]
            pub const fn q(&self) -> bool {
                self.q
            }

            /// The preset time PT, ms.
            #[must_use]
            pub const fn pt(&self) -> u32 {
                self.pt_ms
            }

            /// Changes PT; takes effect at the next call if the timer is timing (it compares the
            /// time it has really run with the new PT). A finished timer stays finished until
            /// its input changes.
            pub fn set_pt(&mut self, pt_ms: u32) {
                self.pt_ms = pt_ms;
            }
        }
    };
}

timer_accessors!(Ton, "Elapsed time ET while IN is on, saturating at PT.");
timer_accessors!(
    Tof,
    "Elapsed time ET since IN went off, saturating at PT (0 while IN is on)."
);
timer_accessors!(Tp, "Elapsed time ET of the pulse, saturating at PT.");

/// R_TRIG: Q is on for the one call in which CLK goes from off to on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RTrig {
    m: bool,
}

impl RTrig {
    /// A detector that has seen CLK off.
    #[must_use]
    pub const fn new() -> RTrig {
        RTrig { m: false }
    }

    /// One call; returns Q.
    pub fn call(&mut self, clk: bool) -> bool {
        let q = clk && !self.m;
        self.m = clk;
        q
    }
}

/// F_TRIG: Q is on for the one call in which CLK goes from on to off.
///
/// Where the editions differ: this follows the 3rd edition (IEC 61131-3:2013), whose memory
/// starts as if CLK had been off, so a detector whose first call sees CLK off does not fire. The
/// 2nd edition's ST body (as matiec has it: `Q := NOT CLK AND NOT M; M := NOT CLK;` with M
/// initially FALSE) fires on that first call. The other blocks here behave the same in both
/// editions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FTrig {
    m: bool,
}

impl Default for FTrig {
    fn default() -> FTrig {
        FTrig::new()
    }
}

impl FTrig {
    /// A detector that has seen CLK off.
    #[must_use]
    pub const fn new() -> FTrig {
        FTrig { m: true }
    }

    /// One call; returns Q.
    pub fn call(&mut self, clk: bool) -> bool {
        let q = !clk && !self.m;
        self.m = !clk;
        q
    }
}

/// CTU, up-counter: CV counts rising edges of CU up to `i32::MAX`; R resets it; Q = CV ≥ PV.
///
/// ```
/// use regler_scan_cycle::Ctu;
/// let mut parts = Ctu::new(3);
/// for cu in [true, false, true, false, true] {
///     parts.call(cu, false);
/// }
/// assert_eq!(parts.cv(), 3);
/// assert!(parts.call(true, false)); // CU still on: no new edge, Q on
/// assert!(!parts.call(false, true)); // reset
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Ctu {
    pv: i32,
    cv: i32,
    cu: RTrig,
}

impl Ctu {
    /// A counter at 0 with preset PV.
    #[must_use]
    pub const fn new(pv: i32) -> Ctu {
        Ctu {
            pv,
            cv: 0,
            cu: RTrig::new(),
        }
    }

    /// One call; returns Q.
    pub fn call(&mut self, cu: bool, reset: bool) -> bool {
        let edge = self.cu.call(cu);
        if reset {
            self.cv = 0;
        } else if edge {
            self.cv = self.cv.saturating_add(1);
        }
        self.q()
    }

    /// Current value CV.
    #[must_use]
    pub const fn cv(&self) -> i32 {
        self.cv
    }

    /// Q = CV ≥ PV.
    #[must_use]
    pub const fn q(&self) -> bool {
        self.cv >= self.pv
    }

    /// Changes PV.
    pub fn set_pv(&mut self, pv: i32) {
        self.pv = pv;
    }
}

/// CTD, down-counter: CV counts rising edges of CD down to `i32::MIN`; LD loads PV; Q = CV ≤ 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Ctd {
    pv: i32,
    cv: i32,
    cd: RTrig,
}

impl Ctd {
    /// A counter at 0 with preset PV (load it with LD before counting down).
    #[must_use]
    pub const fn new(pv: i32) -> Ctd {
        Ctd {
            pv,
            cv: 0,
            cd: RTrig::new(),
        }
    }

    /// One call; returns Q.
    pub fn call(&mut self, cd: bool, load: bool) -> bool {
        let edge = self.cd.call(cd);
        if load {
            self.cv = self.pv;
        } else if edge {
            self.cv = self.cv.saturating_sub(1);
        }
        self.cv <= 0
    }

    /// Current value CV.
    #[must_use]
    pub const fn cv(&self) -> i32 {
        self.cv
    }

    /// Changes PV.
    pub fn set_pv(&mut self, pv: i32) {
        self.pv = pv;
    }
}

/// CTUD, up-down counter: rising CU counts up, rising CD down (both at once: no change);
/// R resets (and wins over LD), LD loads PV. Returns (QU = CV ≥ PV, QD = CV ≤ 0).
///
/// ```
/// use regler_scan_cycle::Ctud;
/// let mut buffer = Ctud::new(2);
/// buffer.call(true, false, false, false);
/// buffer.call(false, false, false, false);
/// assert_eq!(buffer.call(true, false, false, false), (true, false));
/// assert_eq!(buffer.call(false, true, false, false), (false, false));
/// assert_eq!(buffer.cv(), 1);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Ctud {
    pv: i32,
    cv: i32,
    cu: RTrig,
    cd: RTrig,
}

impl Ctud {
    /// A counter at 0 with preset PV.
    #[must_use]
    pub const fn new(pv: i32) -> Ctud {
        Ctud {
            pv,
            cv: 0,
            cu: RTrig::new(),
            cd: RTrig::new(),
        }
    }

    /// One call; returns (QU, QD).
    pub fn call(&mut self, cu: bool, cd: bool, reset: bool, load: bool) -> (bool, bool) {
        let (up, down) = (self.cu.call(cu), self.cd.call(cd));
        if reset {
            self.cv = 0;
        } else if load {
            self.cv = self.pv;
        } else if up && !down {
            self.cv = self.cv.saturating_add(1);
        } else if down && !up {
            self.cv = self.cv.saturating_sub(1);
        }
        (self.cv >= self.pv, self.cv <= 0)
    }

    /// Current value CV.
    #[must_use]
    pub const fn cv(&self) -> i32 {
        self.cv
    }

    /// Changes PV.
    pub fn set_pv(&mut self, pv: i32) {
        self.pv = pv;
    }
}

/// SR, set-dominant bistable: Q1 = S1 OR (NOT R AND Q1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Sr {
    q1: bool,
}

impl Sr {
    /// Off.
    #[must_use]
    pub const fn new() -> Sr {
        Sr { q1: false }
    }

    /// One call; returns Q1.
    pub fn call(&mut self, set: bool, reset: bool) -> bool {
        self.q1 = set || (!reset && self.q1);
        self.q1
    }
}

/// RS, reset-dominant bistable: Q1 = NOT R1 AND (S OR Q1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Rs {
    q1: bool,
}

impl Rs {
    /// Off.
    #[must_use]
    pub const fn new() -> Rs {
        Rs { q1: false }
    }

    /// One call; returns Q1.
    pub fn call(&mut self, set: bool, reset: bool) -> bool {
        self.q1 = !reset && (set || self.q1);
        self.q1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs a timer over (time, IN) samples and returns (Q, ET) at each.
    fn trace(
        mut call: impl FnMut(bool, u32) -> (bool, u32),
        samples: &[(u32, bool)],
    ) -> Vec<(bool, u32)> {
        samples.iter().map(|&(t, i)| call(i, t)).collect()
    }

    #[test]
    fn ton_timing_diagram() {
        let mut t = Ton::new(100);
        let got = trace(
            |i, n| (t.call(i, n), t.et()),
            &[
                (0, false),
                (10, true),
                (60, true),
                (110, true),
                (150, true),
                (160, false),
                (170, true),
                (200, false),
            ],
        );
        assert_eq!(
            got,
            [
                (false, 0),
                (false, 0),
                (false, 50),
                (true, 100),
                (true, 100),
                (false, 0),
                (false, 0),
                (false, 0)
            ]
        );
    }

    #[test]
    fn ton_pt_zero_and_pt_change_while_running() {
        let mut t = Ton::new(0);
        assert!(t.call(true, 5));
        let mut t = Ton::new(100);
        t.call(true, 0);
        t.call(true, 60);
        t.set_pt(50); // already past the new PT
        assert!(t.call(true, 61));
        assert_eq!(t.et(), 50);
        t.set_pt(200); // finished: stays finished while IN stays on (matiec's STATE 2)
        assert!(t.call(true, 150));
        assert_eq!(t.et(), 50);
        assert!(!t.call(false, 160));
        // While timing, a PT change takes effect: counts on from the real elapsed time.
        t.call(true, 1000);
        t.set_pt(100);
        assert!(!t.call(true, 1099));
        t.set_pt(300);
        assert!(!t.call(true, 1200));
        assert_eq!(t.et(), 200);
        assert!(t.call(true, 1300));
    }

    #[test]
    fn tof_stays_off_after_expiry_when_pt_rises() {
        let mut t = Tof::new(100);
        assert!(t.call(true, 0));
        assert!(t.call(false, 10));
        assert!(!t.call(false, 110));
        t.set_pt(1000);
        assert!(!t.call(false, 120), "an expired TOF must not come back on");
        assert_eq!(t.et(), 100);
        // While timing a change takes effect.
        assert!(t.call(true, 200));
        assert!(t.call(false, 300));
        t.set_pt(50);
        assert!(!t.call(false, 350));
    }

    #[test]
    fn tp_gives_no_pulse_without_an_edge_when_pt_rises() {
        let mut t = Tp::new(100);
        assert!(t.call(true, 0));
        assert!(!t.call(true, 100));
        t.set_pt(500);
        assert!(!t.call(true, 150), "no rising edge, no pulse");
        assert_eq!(t.et(), 100);
        assert!(!t.call(false, 160));
        assert_eq!(t.et(), 0);
        assert!(t.call(true, 200), "a new edge: a pulse of the new PT");
        assert!(t.call(false, 650));
        assert!(!t.call(false, 700));
    }

    #[test]
    fn a_clock_that_steps_back_fires_nothing() {
        let mut t = Ton::new(500);
        t.call(true, 10_000);
        assert!(!t.call(true, 9_999), "1 ms back is not 49 days forward");
        assert!(!t.call(true, 10_400));
        assert!(t.call(true, 10_500));
        let mut p = Tp::new(500);
        assert!(p.call(true, 10_000));
        assert!(p.call(true, 9_000));
        assert!(!p.call(true, 10_500));
    }

    #[test]
    fn tof_timing_diagram() {
        let mut t = Tof::new(100);
        let got = trace(
            |i, n| (t.call(i, n), t.et()),
            &[
                (0, false),
                (10, true),
                (20, false),
                (70, false),
                (80, true),
                (90, false),
                (189, false),
                (190, false),
                (300, false),
            ],
        );
        assert_eq!(
            got,
            [
                (false, 0),
                (true, 0),
                (true, 0),
                (true, 50),
                (true, 0),
                (true, 0),
                (true, 99),
                (false, 100),
                (false, 100)
            ]
        );
        let mut z = Tof::new(0);
        assert!(z.call(true, 0));
        assert!(!z.call(false, 0));
    }

    #[test]
    fn tp_timing_diagram() {
        let mut t = Tp::new(100);
        let got = trace(
            |i, n| (t.call(i, n), t.et()),
            &[
                (0, true),
                (20, false),
                (50, true),
                (99, true),
                (100, true),
                (120, true),
                (130, false),
                (140, true),
                (250, false),
            ],
        );
        assert_eq!(
            got,
            [
                (true, 0),
                (true, 20),
                (true, 50),
                (true, 99),
                (false, 100),
                (false, 100),
                (false, 0),
                (true, 0),
                (false, 0)
            ]
        );
        let mut z = Tp::new(0);
        assert!(!z.call(true, 0));
        assert_eq!(z.et(), 0);
    }

    #[test]
    fn timers_work_across_the_clock_wrap() {
        let start = u32::MAX - 30;
        let mut on = Ton::new(100);
        assert!(!on.call(true, start));
        assert!(!on.call(true, start.wrapping_add(99)));
        assert!(on.call(true, start.wrapping_add(100)));
        let mut off = Tof::new(50);
        off.call(true, start);
        off.call(false, start.wrapping_add(10));
        assert!(off.call(false, start.wrapping_add(59)));
        assert!(!off.call(false, start.wrapping_add(60)));
        let mut p = Tp::new(40);
        assert!(p.call(true, start));
        assert!(p.call(true, start.wrapping_add(39)));
        assert!(!p.call(true, start.wrapping_add(40)));
    }

    #[test]
    fn counters_follow_the_standard() {
        let mut up = Ctu::new(2);
        assert!(!up.call(true, false));
        assert!(!up.call(true, false)); // held: one edge only
        up.call(false, false);
        assert!(up.call(true, false));
        assert!(!up.call(true, true)); // reset wins
        assert_eq!(up.cv(), 0);

        let mut down = Ctd::new(2);
        assert!(down.call(false, false)); // CV 0 <= 0
        assert!(!down.call(false, true)); // loaded with 2
        assert!(!down.call(true, false));
        down.call(false, false);
        assert!(down.call(true, false));
        assert_eq!(down.cv(), 0);

        let mut ud = Ctud::new(1);
        assert_eq!(ud.call(true, true, false, false), (false, true)); // both edges: no change
        assert_eq!(ud.call(false, false, false, true), (true, false)); // load
        assert_eq!(ud.call(false, false, true, true), (false, true)); // reset wins over load
    }

    /// CTD and CTUD against a model written from IEC 61131-3's text, over every sequence of
    /// four calls (every combination of CU, CD, R and LD on each) for presets around 0, then a
    /// new preset: LD loads the new one, and CTUD's QU compares with it at once.
    #[test]
    fn down_and_up_down_counters_match_the_standard_over_every_short_sequence() {
        let steps = if cfg!(miri) { 2 } else { 4 };
        for pv in [-1, 0, 1, 2] {
            for seq in 0..16u32.pow(steps) {
                let mut ctd = Ctd::new(pv);
                let mut ctud = Ctud::new(pv);
                // The model: CV, and the last CU and CD seen (edges are rising ones).
                let (mut down_cv, mut down_last) = (0i32, false);
                let (mut cv, mut last_cu, mut last_cd) = (0i32, false, false);
                for step in 0..steps {
                    let bits = seq / 16u32.pow(step) % 16;
                    let (cu, cd, r, ld) =
                        (bits & 1 != 0, bits & 2 != 0, bits & 4 != 0, bits & 8 != 0);
                    let (up_edge, down_edge) = (cu && !last_cu, cd && !last_cd);
                    (last_cu, last_cd) = (cu, cd);
                    if r {
                        cv = 0;
                    } else if ld {
                        cv = pv;
                    } else if up_edge && !down_edge {
                        cv += 1;
                    } else if down_edge && !up_edge {
                        cv -= 1;
                    }
                    let got = ctud.call(cu, cd, r, ld);
                    assert_eq!(
                        got,
                        (cv >= pv, cv <= 0),
                        "CTUD pv {pv} seq {seq:x} step {step}"
                    );
                    assert_eq!(ctud.cv(), cv, "CTUD pv {pv} seq {seq:x} step {step}");

                    let down = cd && !down_last;
                    down_last = cd;
                    if ld {
                        down_cv = pv;
                    } else if down {
                        down_cv -= 1;
                    }
                    assert_eq!(
                        ctd.call(cd, ld),
                        down_cv <= 0,
                        "CTD pv {pv} seq {seq:x} step {step}"
                    );
                    assert_eq!(ctd.cv(), down_cv, "CTD pv {pv} seq {seq:x} step {step}");
                }
                // A new preset: CTUD's QU follows it at the next call, LD loads it.
                ctud.set_pv(cv + 1);
                assert_eq!(ctud.call(false, false, false, false), (false, cv <= 0));
                ctud.set_pv(cv);
                assert_eq!(ctud.call(false, false, false, false), (true, cv <= 0));
                ctud.set_pv(7);
                assert_eq!(ctud.call(false, false, false, true), (true, false));
                assert_eq!(ctud.cv(), 7);
                ctd.set_pv(9);
                assert!(!ctd.call(false, true));
                assert_eq!(ctd.cv(), 9);
            }
        }
    }

    #[test]
    fn counters_saturate() {
        let mut up = Ctu::new(0);
        up.cv = i32::MAX;
        up.call(true, false);
        assert_eq!(up.cv(), i32::MAX);
        let mut down = Ctd::new(0);
        down.cv = i32::MIN;
        down.call(true, false);
        assert_eq!(down.cv(), i32::MIN);
    }

    #[test]
    fn edges_and_bistables() {
        let mut r = RTrig::new();
        assert_eq!(
            [
                r.call(false),
                r.call(true),
                r.call(true),
                r.call(false),
                r.call(true)
            ],
            [false, true, false, false, true]
        );
        let mut f = FTrig::new();
        assert_eq!(
            [f.call(false), f.call(true), f.call(false), f.call(false)],
            [false, false, true, false]
        );
        let mut sr = Sr::new();
        assert!(sr.call(true, true)); // set dominant
        assert!(sr.call(false, false));
        assert!(!sr.call(false, true));
        let mut rs = Rs::new();
        assert!(!rs.call(true, true)); // reset dominant
        assert!(rs.call(true, false));
        assert!(rs.call(false, false));
        assert!(!rs.call(false, true));
    }
}
