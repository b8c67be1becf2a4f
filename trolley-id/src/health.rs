//! Per-reader health: what the last passages at one reader looked like, and an alarm.

use core::fmt;

use crate::voter::{Passage, Verdict};

const PARITY: u8 = 1;
const NO_READ: u8 = 1 << 1;
const DISAGREEMENT: u8 = 1 << 2;
const FAULTY: u8 = 1 << 3;

/// A limit (‰) at or above which a symptom's share can never exceed it: that symptom is off.
const SWITCHED_OFF: u32 = 1000;

/// Counts of passages at one reader: how many there were and how many showed each symptom.
///
/// A passage counts once per symptom however many of its readings showed it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct HealthStats {
    /// Passages.
    pub passages: u32,
    /// Passages with at least one parity error.
    pub parity_errors: u32,
    /// Passages whose verdict was a no-read.
    pub no_reads: u32,
    /// Passages in which two different trolley numbers were decoded.
    pub disagreements: u32,
    /// Passages with a word that had bits above the 13 cams.
    pub faulty_words: u32,
}

impl HealthStats {
    /// No passages at all.
    pub const ZERO: HealthStats = HealthStats {
        passages: 0,
        parity_errors: 0,
        no_reads: 0,
        disagreements: 0,
        faulty_words: 0,
    };

    fn add(&mut self, flags: u8) {
        let bump = |count: &mut u32, flag: u8| {
            if flags & flag != 0 {
                *count = count.saturating_add(1);
            }
        };
        self.passages = self.passages.saturating_add(1);
        bump(&mut self.parity_errors, PARITY);
        bump(&mut self.no_reads, NO_READ);
        bump(&mut self.disagreements, DISAGREEMENT);
        bump(&mut self.faulty_words, FAULTY);
    }

    fn remove(&mut self, flags: u8) {
        let drop = |count: &mut u32, flag: u8| {
            if flags & flag != 0 {
                *count = count.saturating_sub(1);
            }
        };
        self.passages = self.passages.saturating_sub(1);
        drop(&mut self.parity_errors, PARITY);
        drop(&mut self.no_reads, NO_READ);
        drop(&mut self.disagreements, DISAGREEMENT);
        drop(&mut self.faulty_words, FAULTY);
    }

    /// `count` per thousand passages, rounded down (0 when there were no passages): for display.
    /// The alarm does not use it; it compares the counts exactly (1 no-read in 170 passages is
    /// 5.88 ‰, which this shows as 5 but the alarm counts as above a 5 ‰ limit).
    #[must_use]
    pub fn per_mille(&self, count: u32) -> u32 {
        let scaled = u64::from(count)
            .saturating_mul(1000)
            .checked_div(u64::from(self.passages))
            .unwrap_or(0);
        u32::try_from(scaled).unwrap_or(u32::MAX)
    }
}

/// When a reader's alarm goes on and off.
///
/// The alarm is raised when the window holds at least `min_passages` passages and the share of
/// no-reads or of disagreements in it exceeds its limit: `no_reads / passages >
/// no_read_per_mille / 1000`, compared exactly (counts cross-multiplied, nothing rounded). It
/// clears only when both shares are at or below half their limits (exactly, so half of 5 ‰ is
/// 2.5 ‰), so a reader near its limit does not make the alarm chatter. A limit of 1000 ‰ or more
/// can never be exceeded: it switches that symptom off, and a switched-off symptom takes no part
/// in raising or clearing (a reader disagreeing on most passages, with disagreements switched
/// off, clears a no-read alarm as soon as the no-reads are at or below half their limit).
///
/// [`ReaderHealth::new`] refuses limits whose `min_passages` exceeds the window `W`: the window
/// could never hold that many passages and the alarm could never be raised.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct AlarmLimits {
    /// No-reads per thousand passages above which the alarm is raised.
    pub no_read_per_mille: u32,
    /// Disagreements per thousand passages above which the alarm is raised.
    pub disagreement_per_mille: u32,
    /// Passages the window must hold before the alarm can be raised.
    pub min_passages: u32,
}

impl Default for AlarmLimits {
    /// 5 ‰ no-reads or 10 ‰ disagreements, over at least 100 passages: five times the
    /// plant-wide misread rate of the source (1 read in 1000).
    fn default() -> AlarmLimits {
        AlarmLimits {
            no_read_per_mille: 5,
            disagreement_per_mille: 10,
            min_passages: 100,
        }
    }
}

/// Why [`ReaderHealth::new`] refused its limits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AlarmLimitsError {
    /// `min_passages` is more than the window holds: the alarm could never be raised.
    MinPassagesAboveWindow {
        /// The limits' `min_passages`.
        min_passages: u32,
        /// The window `W`, in passages.
        window: usize,
    },
}

impl fmt::Display for AlarmLimitsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AlarmLimitsError::MinPassagesAboveWindow {
                min_passages,
                window,
            } => write!(
                f,
                "min_passages is {min_passages} but the window holds only {window} passages: the alarm could never be raised"
            ),
        }
    }
}

impl core::error::Error for AlarmLimitsError {}

/// A change of a reader's alarm.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AlarmChange {
    /// The alarm went on.
    Raised,
    /// The alarm went off.
    Cleared,
}

/// Health of one reader over a sliding window of its last `W` passages, with lifetime totals
/// and an alarm.
///
/// Each passage costs O(1) whatever `W`; the window is a ring of one byte per passage: a
/// `ReaderHealth<W>` is `W` bytes plus two `usize` for the window, two `HealthStats` (20 bytes
/// each), the limits (12) and 5 bytes of alarm state (a flag and a count), padded to the
/// alignment of a `usize` (a unit test checks it).
/// [`record`](ReaderHealth::record) has no panic path (the no-panic probe firmware
/// `footprint/src/bin/trolley_no_panic.rs` links only if none is left).
///
/// ```
/// use regler_trolley_id::{AlarmChange, AlarmLimits, encode, ReaderHealth, Strategy, TrolleyId, Voter};
/// let limits = AlarmLimits { no_read_per_mille: 100, disagreement_per_mille: 1000, min_passages: 10 };
/// let mut health: ReaderHealth<50> = ReaderHealth::new(limits)?;
/// let mut voter = Voter::new(Strategy::Consecutive { k: 2 })?;
/// let good = encode(TrolleyId::try_from(7)?);
/// for _ in 0..9 {
///     assert_eq!(health.record(&voter.vote(&[good, good])), None);
/// }
/// // Two no-reads in eleven passages is 181 ‰, above the 100 ‰ limit.
/// health.record(&voter.vote(&[0x0001]));
/// assert_eq!(health.record(&voter.vote(&[0x0001])), Some(AlarmChange::Raised));
/// assert!(health.alarm());
/// assert_eq!(health.window().no_reads, 2);
/// // The default limits want 100 passages: a window of 64 could never raise the alarm.
/// assert!(ReaderHealth::<64>::new(AlarmLimits::default()).is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// `new` is a `const fn`: limits fixed in the program can be checked when it is compiled.
///
/// ```compile_fail
/// use regler_trolley_id::{AlarmLimits, ReaderHealth};
/// // Refused at compile time: 100 passages do not fit in a window of 64.
/// const HEALTH: ReaderHealth<64> = match ReaderHealth::new(AlarmLimits {
///     no_read_per_mille: 5,
///     disagreement_per_mille: 10,
///     min_passages: 100,
/// }) {
///     Ok(h) => h,
///     Err(_) => panic!("min_passages above the window"), // ok: in a const, the compile-time refusal shown
/// };
/// # let _ = HEALTH;
/// ```
#[derive(Clone, Debug)]
pub struct ReaderHealth<const W: usize> {
    limits: AlarmLimits,
    /// The symptom flags of the last `W` passages, `next` the slot the next one goes into.
    ring: [u8; W],
    next: usize,
    /// Passages in the ring (up to `W`).
    filled: usize,
    window: HealthStats,
    totals: HealthStats,
    alarm: bool,
    alarms_raised: u32,
}

impl<const W: usize> ReaderHealth<W> {
    /// A reader with no passages yet, raising its alarm at `limits`; an error when
    /// `limits.min_passages` exceeds the window `W` (the alarm could never be raised).
    pub const fn new(limits: AlarmLimits) -> Result<ReaderHealth<W>, AlarmLimitsError> {
        const { assert!(W > 0, "a reader health window holds at least one passage") };
        // u32 → u64 and usize → u64 are lossless on every target Rust supports.
        #[allow(clippy::cast_lossless, reason = "u64::from is not const")]
        if limits.min_passages as u64 > W as u64 {
            return Err(AlarmLimitsError::MinPassagesAboveWindow {
                min_passages: limits.min_passages,
                window: W,
            });
        }
        Ok(ReaderHealth {
            limits,
            ring: [0; W],
            next: 0,
            filled: 0,
            window: HealthStats::ZERO,
            totals: HealthStats::ZERO,
            alarm: false,
            alarms_raised: 0,
        })
    }

    /// Records one passage; returns the alarm change it caused, if any.
    pub fn record(&mut self, passage: &Passage) -> Option<AlarmChange> {
        let mut flags = 0;
        if passage.parity_errors > 0 {
            flags |= PARITY;
        }
        if matches!(passage.verdict, Verdict::NoRead(_)) {
            flags |= NO_READ;
        }
        if passage.disagreement {
            flags |= DISAGREEMENT;
        }
        if passage.faulty_words > 0 {
            flags |= FAULTY;
        }
        // `next` < W always; `get_mut` rather than indexing so that no panic path is linked.
        if let Some(slot) = self.ring.get_mut(self.next) {
            // The passage that falls out of the window leaves the window's counts.
            if self.filled == W {
                self.window.remove(*slot);
            } else {
                self.filled = self.filled.saturating_add(1);
            }
            *slot = flags;
        }
        let after = self.next.saturating_add(1);
        self.next = if after >= W { 0 } else { after };
        self.window.add(flags);
        self.totals.add(flags);
        self.update_alarm()
    }

    fn update_alarm(&mut self) -> Option<AlarmChange> {
        let w = &self.window;
        let l = &self.limits;
        // share > limit ‰  ⇔  count · 1000 > limit · passages, in u64: no rounding, no overflow.
        let scaled = |count: u32, times: u64| u64::from(count).saturating_mul(times);
        let of = |limit: u32| u64::from(limit).saturating_mul(u64::from(w.passages));
        if !self.alarm
            && w.passages >= l.min_passages
            && (scaled(w.no_reads, 1000) > of(l.no_read_per_mille)
                || scaled(w.disagreements, 1000) > of(l.disagreement_per_mille))
        {
            self.alarm = true;
            self.alarms_raised = self.alarms_raised.saturating_add(1);
            return Some(AlarmChange::Raised);
        }
        // share <= limit/2 ‰  ⇔  count · 2000 <= limit · passages. A switched-off symptom
        // (limit >= 1000 ‰, never exceeded) takes no part: half of 1000 ‰ is 500 ‰, and a reader
        // disagreeing on more than half its passages would keep a no-read alarm on for ever.
        let at_half =
            |count: u32, limit: u32| limit >= SWITCHED_OFF || scaled(count, 2000) <= of(limit);
        if self.alarm
            && at_half(w.no_reads, l.no_read_per_mille)
            && at_half(w.disagreements, l.disagreement_per_mille)
        {
            self.alarm = false;
            return Some(AlarmChange::Cleared);
        }
        None
    }

    /// Statistics over the last `W` passages (fewer while the window fills).
    #[must_use]
    pub const fn window(&self) -> HealthStats {
        self.window
    }

    /// Statistics over every passage since creation or [`reset`](ReaderHealth::reset)
    /// (saturating at `u32::MAX`).
    #[must_use]
    pub const fn totals(&self) -> HealthStats {
        self.totals
    }

    /// Whether the alarm is on.
    #[must_use]
    pub const fn alarm(&self) -> bool {
        self.alarm
    }

    /// How many times the alarm was raised.
    #[must_use]
    pub const fn alarms_raised(&self) -> u32 {
        self.alarms_raised
    }

    /// The limits in force.
    #[must_use]
    pub const fn limits(&self) -> AlarmLimits {
        self.limits
    }

    /// Forgets every passage (after the reader was repaired) and clears the alarm.
    pub fn reset(&mut self) {
        self.ring = [0; W];
        self.next = 0;
        self.filled = 0;
        self.window = HealthStats::ZERO;
        self.totals = HealthStats::ZERO;
        self.alarm = false;
        self.alarms_raised = 0;
    }
}

impl fmt::Display for HealthStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} passages, {} with parity errors, {} no-reads, {} disagreements, {} faulty",
            self.passages, self.parity_errors, self.no_reads, self.disagreements, self.faulty_words
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{NoRead, TrolleyId};

    #[test]
    fn size_is_the_documented_formula() {
        use core::mem::size_of;
        let size = |w: usize| {
            (w + 2 * size_of::<usize>() + 2 * 20 + 12 + 5).next_multiple_of(size_of::<usize>())
        };
        assert_eq!(size_of::<ReaderHealth<1000>>(), size(1000));
        assert_eq!(size_of::<ReaderHealth<7>>(), size(7));
    }

    fn passage(no_read: bool, parity: u16, disagreement: bool) -> Passage {
        Passage {
            verdict: if no_read {
                Verdict::NoRead(NoRead::NoAgreement)
            } else {
                Verdict::Identified(TrolleyId::MIN)
            },
            samples: 3,
            no_cams: 0,
            parity_errors: parity,
            faulty_words: 0,
            disagreement,
        }
    }

    #[test]
    fn window_forgets_old_passages_totals_do_not() {
        let limits = AlarmLimits {
            min_passages: 4,
            ..AlarmLimits::default()
        };
        let mut h: ReaderHealth<4> = ReaderHealth::new(limits).unwrap();
        h.record(&passage(true, 2, true));
        for _ in 0..4 {
            h.record(&passage(false, 0, false));
        }
        assert_eq!(
            h.window(),
            HealthStats {
                passages: 4,
                ..HealthStats::default()
            }
        );
        assert_eq!(h.totals().passages, 5);
        assert_eq!(h.totals().no_reads, 1);
        assert_eq!(h.totals().parity_errors, 1);
        assert_eq!(h.totals().disagreements, 1);
    }

    /// A passage with a word above the 13 cams counts once as faulty, in the window and in the
    /// totals, whatever else it showed; the window forgets it, the totals do not.
    #[test]
    fn faulty_words_count_once_per_passage() {
        let limits = AlarmLimits {
            min_passages: 2,
            ..AlarmLimits::default()
        };
        let mut h: ReaderHealth<2> = ReaderHealth::new(limits).unwrap();
        let faulty = |words: u16| Passage {
            faulty_words: words,
            ..passage(false, 0, false)
        };
        h.record(&faulty(3));
        h.record(&faulty(0));
        let once = HealthStats {
            passages: 2,
            faulty_words: 1,
            ..HealthStats::default()
        };
        assert_eq!(h.window(), once);
        assert_eq!(h.totals(), once);
        // Only the faulty flag: no parity error, no-read or disagreement is counted with it.
        h.record(&Passage {
            parity_errors: 1,
            ..faulty(1)
        });
        assert_eq!(
            h.window(),
            HealthStats {
                passages: 2,
                parity_errors: 1,
                faulty_words: 1,
                ..HealthStats::default()
            }
        );
        h.record(&faulty(0));
        h.record(&faulty(0));
        assert_eq!(h.window().faulty_words, 0);
        assert_eq!(h.totals().faulty_words, 2);
        assert_eq!(h.totals().passages, 5);
    }

    /// `alarms_raised` counts every time the alarm went on, not whether it is on; `reset`
    /// starts it again from 0.
    #[test]
    fn alarms_raised_counts_every_raise_until_reset() {
        let limits = AlarmLimits {
            no_read_per_mille: 200,
            disagreement_per_mille: 1000,
            min_passages: 1,
        };
        let mut h: ReaderHealth<2> = ReaderHealth::new(limits).unwrap();
        assert_eq!(h.alarms_raised(), 0);
        for raise in 1..=3 {
            assert_eq!(h.record(&no_read()), Some(AlarmChange::Raised));
            assert_eq!(h.alarms_raised(), raise);
            h.record(&passage(false, 0, false));
            assert_eq!(
                h.record(&passage(false, 0, false)),
                Some(AlarmChange::Cleared)
            );
            assert_eq!(h.alarms_raised(), raise);
        }
        h.reset();
        assert_eq!(h.alarms_raised(), 0);
        assert!(!h.alarm());
    }

    #[test]
    fn alarm_raises_above_limit_and_clears_at_half() {
        let limits = AlarmLimits {
            no_read_per_mille: 200,
            disagreement_per_mille: 1000,
            min_passages: 5,
        };
        let mut h: ReaderHealth<10> = ReaderHealth::new(limits).unwrap();
        // Three no-reads among the first four: below min_passages, no alarm yet.
        for nr in [true, true, true, false] {
            assert_eq!(h.record(&passage(nr, 0, false)), None);
        }
        assert_eq!(
            h.record(&passage(false, 0, false)),
            Some(AlarmChange::Raised)
        );
        assert_eq!(h.alarms_raised(), 1);
        // 3/10 no-reads after ten passages: still on; clears when <= 100 ‰ (1 in 10).
        let mut cleared_at = None;
        for i in 0..10 {
            if h.record(&passage(false, 0, false)) == Some(AlarmChange::Cleared) {
                cleared_at = Some(i);
            }
        }
        // Record 6 + i; the window of 10 drops the no-reads of records 1, 2, 3 at records
        // 11, 12, 13. After record 12 (i = 6) one no-read is left: 100 ‰, half the limit.
        assert_eq!(cleared_at, Some(6));
        assert!(!h.alarm());
        h.reset();
        assert_eq!(h.totals().passages, 0);
    }

    #[test]
    fn per_mille_handles_zero_and_rounds_down() {
        let s = HealthStats {
            passages: 3,
            no_reads: 1,
            ..HealthStats::default()
        };
        assert_eq!(s.per_mille(s.no_reads), 333);
        assert_eq!(HealthStats::default().per_mille(5), 0);
    }

    fn no_read() -> Passage {
        passage(true, 0, false)
    }

    /// Every window and `min_passages` pair `new` accepts can raise the alarm (by the passage
    /// that fills `min_passages`, when every passage is a no-read), and every pair it refuses is
    /// one whose window could never hold `min_passages` passages.
    #[test]
    #[cfg_attr(
        miri,
        ignore = "exhaustive over every accepted window and passage count: hours under Miri; safe code, run natively in every CI run"
    )]
    fn every_accepted_window_and_min_passages_can_raise_the_alarm() {
        fn sweep<const W: usize>() {
            for min_passages in 0..=(W as u32 + 3) {
                for no_read_per_mille in [0, 5, 999] {
                    let limits = AlarmLimits {
                        no_read_per_mille,
                        disagreement_per_mille: 10,
                        min_passages,
                    };
                    let made = ReaderHealth::<W>::new(limits);
                    if min_passages as usize > W {
                        assert_eq!(
                            made.unwrap_err(),
                            AlarmLimitsError::MinPassagesAboveWindow {
                                min_passages,
                                window: W
                            }
                        );
                        continue;
                    }
                    let mut h = made.unwrap();
                    let raised_at = (1..=2 * W as u32 + 2)
                        .find(|_| h.record(&no_read()) == Some(AlarmChange::Raised));
                    assert_eq!(raised_at, Some(min_passages.max(1)), "W {W}, {limits:?}");
                }
            }
        }
        sweep::<1>();
        sweep::<2>();
        sweep::<3>();
        sweep::<16>();
        sweep::<64>();
        sweep::<100>();
        sweep::<101>();
        sweep::<1000>();
        // The issue's case: the default limits and a window of 64 are refused.
        assert!(ReaderHealth::<64>::new(AlarmLimits::default()).is_err());
        assert!(ReaderHealth::<100>::new(AlarmLimits::default()).is_ok());
    }

    /// One no-read in 170 passages is 5.88 ‰: above a 5 ‰ limit, although `per_mille` shows 5.
    #[test]
    fn shares_are_compared_exactly_not_in_rounded_per_mille() {
        let mut h: ReaderHealth<200> = ReaderHealth::new(AlarmLimits::default()).unwrap();
        for _ in 0..169 {
            assert_eq!(h.record(&passage(false, 0, false)), None);
        }
        assert_eq!(h.record(&no_read()), Some(AlarmChange::Raised));
        assert_eq!(h.window().per_mille(h.window().no_reads), 5);
        // One in 200 is exactly 5 ‰: not above it.
        let mut h: ReaderHealth<200> = ReaderHealth::new(AlarmLimits::default()).unwrap();
        for _ in 0..199 {
            h.record(&passage(false, 0, false));
        }
        assert_eq!(h.record(&no_read()), None);
    }

    #[test]
    fn limits_error_names_both_values() {
        let e = AlarmLimitsError::MinPassagesAboveWindow {
            min_passages: 100,
            window: 64,
        };
        let text = e.to_string();
        assert!(text.contains("100") && text.contains("64"), "{text}");
    }
}
