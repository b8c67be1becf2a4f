//! Voting over the several readings a reader takes while one trolley passes.

use core::fmt;

use crate::code::{CODE_MASK, ReadError, TrolleyId, decode};

/// How a [`Voter`] turns the readings of one passage into a verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum Strategy {
    /// Identified when `k` consecutive readings decode to the same trolley, and no other trolley
    /// also reaches `k` consecutive decodes in the same passage (that is a conflict, a no-read).
    ///
    /// `k = 1` accepts the first reading that passes the parity check, as the 1977 plant did
    /// with its single reading, except that a second, different valid decode is a conflict.
    Consecutive {
        /// Consecutive identical decodes needed, at least 1.
        k: u8,
    },
    /// Each of the 13 cam bits is decided by a strict majority of the readings that saw cams;
    /// the majority word is then decoded. The verdict names that trolley only if the readings
    /// themselves support it: at least one reading decoded to it, and no other trolley was
    /// decoded by more readings. A tie on any bit, fewer than `min_samples` readings, a majority
    /// word that fails [`decode`], or a trolley no reading showed (three valid but different
    /// reads of 51, 15 and 60 have the bitwise majority 63) is a no-read.
    Majority {
        /// Readings with cams needed before a verdict, at least 1.
        min_samples: u8,
    },
}

impl Default for Strategy {
    /// Two consecutive identical decodes.
    fn default() -> Strategy {
        Strategy::Consecutive { k: 2 }
    }
}

/// A [`Strategy`] that cannot work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum StrategyError {
    /// `Consecutive { k: 0 }`: no run of readings is shorter than one.
    ZeroConsecutive,
    /// `Majority { min_samples: 0 }`: a verdict needs at least one reading.
    ZeroMinSamples,
}

impl fmt::Display for StrategyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StrategyError::ZeroConsecutive => {
                f.write_str("Consecutive k must be at least 1, got 0")
            }
            StrategyError::ZeroMinSamples => {
                f.write_str("Majority min_samples must be at least 1, got 0")
            }
        }
    }
}

impl core::error::Error for StrategyError {}

/// Why a passage gave no trolley number. The trolley must go to the reject path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum NoRead {
    /// No reading had any cam.
    NoCams,
    /// Fewer readings with cams than the strategy needs (`Majority`; a faulty word, with bits
    /// above the cams, does not count, so a passage of faulty words only has `got` 0).
    TooFewSamples {
        /// Readings with cams that were taken.
        got: u16,
        /// Readings the strategy needs.
        needed: u16,
    },
    /// No trolley number reached the required number of consecutive decodes.
    NoAgreement,
    /// Two different trolley numbers each reached the required consecutive decodes.
    Conflict {
        /// The first number confirmed.
        first: TrolleyId,
        /// A different number confirmed later in the same passage.
        second: TrolleyId,
    },
    /// As many readings had a cam bit set as had it clear.
    AmbiguousBit {
        /// The cam position, 0..=12.
        bit: u8,
    },
    /// The majority word itself does not decode.
    Undecodable(ReadError),
    /// The majority word decodes to a trolley that the readings do not support: no reading
    /// decoded to it, or another trolley was decoded by more readings.
    Unsupported {
        /// What the majority word decodes to.
        majority: TrolleyId,
    },
    /// More readings than the voter counts (65 535) in one passage: a trolley stuck at the
    /// reader or a reader that never sees the passage end. Nothing is decided on it.
    TooManySamples,
}

impl fmt::Display for NoRead {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            NoRead::NoCams => f.write_str("no reading saw any cam"),
            NoRead::TooFewSamples { got, needed } => {
                write!(f, "{got} readings with cams, {needed} needed")
            }
            NoRead::NoAgreement => f.write_str("no trolley number was read consistently enough"),
            NoRead::Conflict { first, second } => {
                write!(f, "conflicting reads: {first} and {second}")
            }
            NoRead::AmbiguousBit { bit } => write!(f, "cam {bit} tied between set and clear"),
            NoRead::Undecodable(e) => write!(f, "majority word does not decode: {e}"),
            NoRead::Unsupported { majority } => {
                write!(
                    f,
                    "majority word names {majority}, which the readings do not support"
                )
            }
            NoRead::TooManySamples => {
                f.write_str("more than 65535 readings in one passage: reader or trolley stuck")
            }
        }
    }
}

impl core::error::Error for NoRead {}

/// The verdict on one passage.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Verdict {
    /// The trolley was identified.
    Identified(TrolleyId),
    /// The trolley could not be identified safely.
    NoRead(NoRead),
}

impl Verdict {
    /// The trolley, if identified.
    #[must_use]
    pub const fn trolley(&self) -> Option<TrolleyId> {
        match *self {
            Verdict::Identified(id) => Some(id),
            Verdict::NoRead(_) => None,
        }
    }
}

/// What one passage looked like: the verdict and counts of what the readings showed.
/// [`ReaderHealth`](crate::ReaderHealth) keeps statistics over these.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Passage {
    /// The verdict.
    pub verdict: Verdict,
    /// Readings taken, at most `u16::MAX`; a passage with more is a
    /// [`NoRead::TooManySamples`].
    pub samples: u16,
    /// Readings that saw no cam.
    pub no_cams: u16,
    /// Readings with a parity error.
    pub parity_errors: u16,
    /// Readings with bits above the 13 cams (a reader fault).
    pub faulty_words: u16,
    /// Whether two different trolley numbers were decoded in this passage: a sign that the
    /// reader misreads even when the verdict is right.
    pub disagreement: bool,
}

/// Combines the readings a reader takes while one trolley passes into one [`Verdict`].
///
/// Feed every reading with [`sample`](Voter::sample) while the trolley is at the reader, then
/// call [`finish`](Voter::finish), which returns the [`Passage`] and makes the voter ready for the
/// next trolley. The voter keeps counts, not readings: its size does not depend on the number of
/// readings, and each reading costs a few instructions.
///
/// A `Voter` is 82 bytes whatever the number of readings (counts, the 13 cam tallies, and the
/// eight trolley numbers it can track per passage; a unit test checks it).
///
/// Whatever the strategy, [`Verdict::Identified`] names only a trolley that some reading of the
/// passage decoded to, and a passage of more than 65 535 readings is a no-read
/// ([`NoRead::TooManySamples`]) rather than a verdict on counters that stopped counting.
///
/// ```
/// use regler_trolley_id::{encode, Strategy, TrolleyId, Verdict, Voter, NoRead};
/// let lund = TrolleyId::try_from(1234)?;
/// let mut voter = Voter::new(Strategy::Majority { min_samples: 3 })?;
/// for raw in [encode(lund), encode(lund) ^ 0b11, encode(lund), 0] {
///     voter.sample(raw); // one double misread and one empty scan
/// }
/// let passage = voter.finish();
/// assert_eq!(passage.verdict, Verdict::Identified(lund));
/// assert!(passage.disagreement);
///
/// // Too few good readings: a no-read, so the trolley goes to the reject path.
/// voter.sample(encode(lund));
/// assert_eq!(
///     voter.finish().verdict,
///     Verdict::NoRead(NoRead::TooFewSamples { got: 1, needed: 3 })
/// );
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct Voter {
    strategy: Strategy,
    samples: u16,
    no_cams: u16,
    parity_errors: u16,
    faulty_words: u16,
    first_decoded: Option<TrolleyId>,
    disagreement: bool,
    // Consecutive
    run_id: Option<TrolleyId>,
    run_len: u8,
    confirmed: Option<TrolleyId>,
    conflict: Option<TrolleyId>,
    // Majority: how many readings with cams had each bit set
    with_cams: u16,
    ones: [u16; 13],
    // Majority: the distinct trolleys decoded so far and how many readings decoded to each
    decoded: [Option<(TrolleyId, u16)>; TRACKED],
    // More distinct trolleys than `decoded` holds: support can no longer be proven
    untracked: bool,
    // A reading arrived after `samples` reached u16::MAX
    overflowed: bool,
}

/// Distinct trolley numbers a [`Voter`] keeps counts of within one passage. A passage in which
/// more distinct numbers decode than this is far too noisy to identify anything unless the
/// majority trolley is among the first ones seen.
const TRACKED: usize = 8;

impl Voter {
    /// A voter using `strategy`, or an error if the strategy cannot work.
    pub const fn new(strategy: Strategy) -> Result<Voter, StrategyError> {
        match strategy {
            Strategy::Consecutive { k: 0 } => return Err(StrategyError::ZeroConsecutive),
            Strategy::Majority { min_samples: 0 } => return Err(StrategyError::ZeroMinSamples),
            _ => {}
        }
        Ok(Voter {
            strategy,
            ..Voter::cleared()
        })
    }

    /// The strategy in use.
    #[must_use]
    pub const fn strategy(&self) -> Strategy {
        self.strategy
    }

    /// Readings taken since the last [`finish`](Voter::finish).
    #[must_use]
    pub const fn samples(&self) -> u16 {
        self.samples
    }

    /// Takes one reading of the cams (a raw word as from the reader, any 16 bits).
    pub fn sample(&mut self, raw: u16) {
        let Some(samples) = self.samples.checked_add(1) else {
            // Every counter below is at most `samples`, so none has saturated yet; from here
            // on nothing is counted and the verdict is a no-read.
            self.overflowed = true;
            return;
        };
        self.samples = samples;
        let decoded = decode(raw);
        match decoded {
            Ok(id) => match self.first_decoded {
                None => self.first_decoded = Some(id),
                Some(first) if first != id => self.disagreement = true,
                Some(_) => {}
            },
            Err(ReadError::NoCams) => self.no_cams = self.no_cams.saturating_add(1),
            Err(ReadError::Parity { .. }) => {
                self.parity_errors = self.parity_errors.saturating_add(1);
            }
            Err(ReadError::BitsAboveCode { .. }) => {
                self.faulty_words = self.faulty_words.saturating_add(1);
            }
        }
        match self.strategy {
            Strategy::Consecutive { k } => self.sample_consecutive(decoded.ok(), k),
            Strategy::Majority { .. } => {
                if let Ok(id) = decoded {
                    self.support(id);
                }
                // Empty scans (trolley edges) and faulty words carry no vote.
                if raw != 0 && raw & !CODE_MASK == 0 {
                    self.with_cams = self.with_cams.saturating_add(1);
                    for (bit, count) in self.ones.iter_mut().enumerate() {
                        if raw >> bit & 1 == 1 {
                            *count = count.saturating_add(1);
                        }
                    }
                }
            }
        }
    }

    /// Counts one more reading that decoded to `id`.
    fn support(&mut self, id: TrolleyId) {
        for slot in &mut self.decoded {
            match slot {
                Some((seen, count)) if *seen == id => {
                    // At most `samples`, which has not overflowed.
                    *count = count.saturating_add(1);
                    return;
                }
                Some(_) => {}
                None => {
                    *slot = Some((id, 1));
                    return;
                }
            }
        }
        self.untracked = true;
    }

    /// How many readings decoded to `id`, if the voter tracked it.
    fn support_of(&self, id: TrolleyId) -> Option<u16> {
        self.decoded
            .iter()
            .flatten()
            .find(|(seen, _)| *seen == id)
            .map(|&(_, count)| count)
    }

    fn sample_consecutive(&mut self, decoded: Option<TrolleyId>, k: u8) {
        let Some(id) = decoded else {
            self.run_id = None;
            self.run_len = 0;
            return;
        };
        if self.run_id == Some(id) {
            self.run_len = self.run_len.saturating_add(1);
        } else {
            self.run_id = Some(id);
            self.run_len = 1;
        }
        if self.run_len == k {
            match self.confirmed {
                None => self.confirmed = Some(id),
                Some(first) if first != id && self.conflict.is_none() => {
                    self.conflict = Some(id);
                }
                Some(_) => {}
            }
        }
    }

    /// The verdict on the readings so far, without ending the passage.
    #[must_use]
    pub fn verdict(&self) -> Verdict {
        if self.overflowed {
            return Verdict::NoRead(NoRead::TooManySamples);
        }
        match self.strategy {
            Strategy::Consecutive { .. } => match (self.confirmed, self.conflict) {
                (Some(first), Some(second)) => Verdict::NoRead(NoRead::Conflict { first, second }),
                (Some(id), None) => Verdict::Identified(id),
                (None, _) if self.first_decoded.is_none() && self.no_cams == self.samples => {
                    Verdict::NoRead(NoRead::NoCams)
                }
                (None, _) => Verdict::NoRead(NoRead::NoAgreement),
            },
            Strategy::Majority { min_samples } => self.majority_verdict(u16::from(min_samples)),
        }
    }

    fn majority_verdict(&self, needed: u16) -> Verdict {
        let got = self.with_cams;
        // No cams only when no reading had any (as for `Consecutive`): faulty words have cams,
        // and a passage of nothing else is too few usable readings, not an empty hook.
        if got == 0 && self.no_cams == self.samples {
            return Verdict::NoRead(NoRead::NoCams);
        }
        if got < needed {
            return Verdict::NoRead(NoRead::TooFewSamples { got, needed });
        }
        let mut word = 0u16;
        for (bit, &count) in (0u8..).zip(self.ones.iter()) {
            let clear = got.saturating_sub(count);
            if count == clear {
                return Verdict::NoRead(NoRead::AmbiguousBit { bit });
            }
            if count > clear {
                word |= 1 << bit;
            }
        }
        let majority = match decode(word) {
            Ok(id) => id,
            Err(e) => return Verdict::NoRead(NoRead::Undecodable(e)),
        };
        // The bitwise majority of different valid reads can be a trolley none of them showed:
        // only a trolley that readings decoded to, and no other more often, is identified.
        let supported = self.support_of(majority).is_some_and(|count| {
            !self.untracked
                && self
                    .decoded
                    .iter()
                    .flatten()
                    .all(|&(other, n)| other == majority || n <= count)
        });
        if supported {
            Verdict::Identified(majority)
        } else {
            Verdict::NoRead(NoRead::Unsupported { majority })
        }
    }

    /// Ends the passage: returns its verdict and counts, and clears the voter for the next one.
    pub fn finish(&mut self) -> Passage {
        let passage = Passage {
            verdict: self.verdict(),
            samples: self.samples,
            no_cams: self.no_cams,
            parity_errors: self.parity_errors,
            faulty_words: self.faulty_words,
            disagreement: self.disagreement,
        };
        *self = Voter {
            strategy: self.strategy,
            ..Voter::cleared()
        };
        passage
    }

    const fn cleared() -> Voter {
        Voter {
            strategy: Strategy::Consecutive { k: 1 },
            samples: 0,
            no_cams: 0,
            parity_errors: 0,
            faulty_words: 0,
            first_decoded: None,
            disagreement: false,
            run_id: None,
            run_len: 0,
            confirmed: None,
            conflict: None,
            with_cams: 0,
            ones: [0; 13],
            decoded: [None; TRACKED],
            untracked: false,
            overflowed: false,
        }
    }

    /// Votes over a whole passage at once: the readings in the order they were taken.
    pub fn vote(&mut self, readings: &[u16]) -> Passage {
        for &raw in readings {
            self.sample(raw);
        }
        self.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_passage_of_faulty_words_only_is_too_few_samples_not_no_cams() {
        let mut majority = Voter::new(Strategy::Majority { min_samples: 1 }).unwrap();
        let p = majority.vote(&[0xFFFF, 0x2000]);
        assert_eq!(
            p.verdict,
            Verdict::NoRead(NoRead::TooFewSamples { got: 0, needed: 1 })
        );
        assert_eq!(
            majority.vote(&[0, 0]).verdict,
            Verdict::NoRead(NoRead::NoCams)
        );
        assert_eq!(majority.vote(&[]).verdict, Verdict::NoRead(NoRead::NoCams));
        let mut consecutive = Voter::new(Strategy::Consecutive { k: 1 }).unwrap();
        assert_eq!(
            consecutive.vote(&[0xFFFF]).verdict,
            Verdict::NoRead(NoRead::NoAgreement)
        );
    }
    use crate::code::encode;

    fn id(n: u16) -> TrolleyId {
        TrolleyId::new(n).unwrap()
    }

    #[test]
    fn size_is_fixed() {
        assert_eq!(core::mem::size_of::<Voter>(), 82);
    }

    #[test]
    fn zero_parameters_are_refused() {
        assert_eq!(
            Voter::new(Strategy::Consecutive { k: 0 }).unwrap_err(),
            StrategyError::ZeroConsecutive
        );
        assert_eq!(
            Voter::new(Strategy::Majority { min_samples: 0 }).unwrap_err(),
            StrategyError::ZeroMinSamples
        );
    }

    #[test]
    fn consecutive_needs_an_unbroken_run() {
        let mut v = Voter::new(Strategy::Consecutive { k: 3 }).unwrap();
        let a = encode(id(100));
        let p = v.vote(&[a, a, 0x0001, a, a]);
        assert_eq!(p.verdict, Verdict::NoRead(NoRead::NoAgreement));
        assert_eq!(p.parity_errors, 1);
        let p = v.vote(&[0, a, a, a, 0]);
        assert_eq!(p.verdict, Verdict::Identified(id(100)));
        assert_eq!(p.no_cams, 2);
        assert!(!p.disagreement);
    }

    #[test]
    fn consecutive_conflict_is_a_no_read() {
        let mut v = Voter::new(Strategy::Consecutive { k: 2 }).unwrap();
        let (a, b) = (encode(id(5)), encode(id(6)));
        let p = v.vote(&[a, a, b, b, a]);
        assert_eq!(
            p.verdict,
            Verdict::NoRead(NoRead::Conflict {
                first: id(5),
                second: id(6)
            })
        );
        assert!(p.disagreement);
        // A lone different decode does not confirm: verdict stands, disagreement is seen.
        let p = v.vote(&[a, b, a, a]);
        assert_eq!(p.verdict, Verdict::Identified(id(5)));
        assert!(p.disagreement);
    }

    /// Readings that saw cams but none decoded (parity errors, faulty words) are a no-read
    /// for want of agreement, not "no cams": a trolley was there.
    #[test]
    fn cams_without_a_decode_are_no_agreement_not_no_cams() {
        let mut v = Voter::new(Strategy::Consecutive { k: 1 }).unwrap();
        let p = v.vote(&[0, 0x0001, 0]);
        assert_eq!(p.verdict, Verdict::NoRead(NoRead::NoAgreement));
        assert_eq!((p.no_cams, p.parity_errors), (2, 1));
        let p = v.vote(&[0xE000]);
        assert_eq!(p.verdict, Verdict::NoRead(NoRead::NoAgreement));
        assert_eq!(p.faulty_words, 1);
    }

    #[test]
    fn empty_passage_is_no_cams() {
        for s in [
            Strategy::Consecutive { k: 1 },
            Strategy::Majority { min_samples: 1 },
        ] {
            let mut v = Voter::new(s).unwrap();
            assert_eq!(v.finish().verdict, Verdict::NoRead(NoRead::NoCams));
            assert_eq!(v.vote(&[0, 0]).verdict, Verdict::NoRead(NoRead::NoCams));
        }
    }

    #[test]
    fn majority_outvotes_double_misreads_and_refuses_ties() {
        let mut v = Voter::new(Strategy::Majority { min_samples: 3 }).unwrap();
        let a = encode(id(0x0F0));
        let p = v.vote(&[a ^ 0b11, a, a ^ 0b1100, a, a ^ 0b11]);
        assert_eq!(p.verdict, Verdict::Identified(id(0x0F0)));
        let p = v.vote(&[a, a ^ 0b11, a, a ^ 0b11]);
        assert_eq!(p.verdict, Verdict::NoRead(NoRead::AmbiguousBit { bit: 0 }));
        let p = v.vote(&[a, 0xE000 | a, a]);
        assert_eq!(
            p.verdict,
            Verdict::NoRead(NoRead::TooFewSamples { got: 2, needed: 3 })
        );
        assert_eq!(p.faulty_words, 1);
    }

    #[test]
    fn majority_word_with_bad_parity_is_undecodable() {
        let mut v = Voter::new(Strategy::Majority { min_samples: 1 }).unwrap();
        let p = v.vote(&[0x0001]);
        assert_eq!(
            p.verdict,
            Verdict::NoRead(NoRead::Undecodable(ReadError::Parity { raw: 0x0001 }))
        );
    }

    #[test]
    fn finish_clears_everything_but_the_strategy() {
        let mut v = Voter::new(Strategy::Majority { min_samples: 2 }).unwrap();
        v.vote(&[1, 2, 3, 0xFFFF]);
        assert_eq!(v.samples(), 0);
        assert_eq!(v.strategy(), Strategy::Majority { min_samples: 2 });
        let a = encode(id(7));
        assert_eq!(v.vote(&[a, a]).verdict, Verdict::Identified(id(7)));
    }

    #[test]
    #[cfg_attr(
        miri,
        ignore = "feeds 65 536 readings per strategy: hours under Miri; safe code, run natively in every CI run"
    )]
    fn a_passage_too_long_to_count_is_a_no_read() {
        for strategy in [
            Strategy::Consecutive { k: 255 },
            Strategy::Majority { min_samples: 1 },
        ] {
            let mut v = Voter::new(strategy).unwrap();
            // Counters that saturated used to let 65536 reads of 12 outvote 65535 reads of 3
            // as a trolley 15 that no reading showed.
            for _ in 0..65_535 {
                v.sample(encode(id(3)));
            }
            assert_eq!(v.verdict(), Verdict::Identified(id(3)), "{strategy:?}");
            for _ in 0..65_536 {
                v.sample(encode(id(12)));
            }
            assert_eq!(v.samples(), u16::MAX);
            let p = v.finish();
            assert_eq!(
                p.verdict,
                Verdict::NoRead(NoRead::TooManySamples),
                "{strategy:?}"
            );
            assert_eq!(
                v.vote(&[encode(id(3)); 300]).verdict,
                Verdict::Identified(id(3))
            );
        }
    }

    /// Parity errors can swing the bitwise majority to a trolley that valid reads show less
    /// often than another: 3 read twice, 5 once, and two misreads of 5 (0b1101, one cam too
    /// many) make the majority word 5. The readings support 3 more than 5: a no-read.
    #[test]
    fn majority_refuses_a_trolley_another_was_read_more_often_than() {
        let mut v = Voter::new(Strategy::Majority { min_samples: 3 }).unwrap();
        let (three, five, misread) = (encode(id(3)), encode(id(5)), 0b1101);
        assert_eq!(decode(misread), Err(ReadError::Parity { raw: misread }));
        let p = v.vote(&[three, three, five, misread, misread]);
        assert_eq!(
            p.verdict,
            Verdict::NoRead(NoRead::Unsupported { majority: id(5) })
        );
        assert_eq!(p.parity_errors, 2);
        // As often as the other is enough: 3 and 5 twice each, the misread deciding the bits.
        let p = v.vote(&[three, three, five, five, misread]);
        assert_eq!(p.verdict, Verdict::Identified(id(5)));
    }

    #[test]
    fn majority_names_only_a_trolley_the_readings_showed() {
        let mut v = Voter::new(Strategy::Majority { min_samples: 3 }).unwrap();
        let reads = [51, 15, 60].map(|n| encode(id(n)));
        assert_eq!(
            decode(
                encode(id(51)) & encode(id(15))
                    | encode(id(51)) & encode(id(60))
                    | encode(id(15)) & encode(id(60))
            ),
            Ok(id(63))
        );
        assert_eq!(
            v.vote(&reads).verdict,
            Verdict::NoRead(NoRead::Unsupported { majority: id(63) })
        );
        // A majority that readings support is named: 51 twice, 63 once.
        let (a, b) = (encode(id(51)), encode(id(63)));
        assert_eq!(v.vote(&[a, b, a]).verdict, Verdict::Identified(id(51)));
    }
}
