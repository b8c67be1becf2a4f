//! Process images (words of 16 I/O points), forcing, and input conditioning.

use core::fmt;

/// I/O points per image word, as the source hardware's 16-bit words.
pub const POINTS_PER_WORD: usize = 16;

/// A point number outside an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PointError {
    /// The point asked for.
    pub point: usize,
    /// Points in the image.
    pub points: usize,
}

impl fmt::Display for PointError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "I/O point {} is outside the image of {} points",
            self.point, self.points
        )
    }
}

impl core::error::Error for PointError {}

/// A word number outside an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WordError {
    /// The word asked for.
    pub word: usize,
    /// Words in the image.
    pub words: usize,
}

impl fmt::Display for WordError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "I/O word {} is outside the image of {} words",
            self.word, self.words
        )
    }
}

impl core::error::Error for WordError {}

/// A process image: `W` words of 16 points; point `p` is bit `p % 16` of word `p / 16`.
///
/// ```
/// use regler_scan_cycle::Image;
/// let mut outputs: Image<15> = Image::new(); // the 1977 plant's 240 outputs
/// outputs.set(37, true)?;
/// assert!(outputs.get(37));
/// assert_eq!(outputs.word(2), Some(1 << 5));
/// assert!(outputs.set(240, true).is_err());
/// # Ok::<(), regler_scan_cycle::PointError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Image<const W: usize> {
    #[cfg_attr(feature = "serde", serde(with = "serde_words"))]
    words: [u16; W],
}

impl<const W: usize> Default for Image<W> {
    fn default() -> Self {
        Image::new()
    }
}

impl<const W: usize> Image<W> {
    /// Points in the image.
    pub const POINTS: usize = W * POINTS_PER_WORD;

    /// All points off.
    #[must_use]
    pub const fn new() -> Image<W> {
        Image { words: [0; W] }
    }

    /// An image of these words.
    #[must_use]
    pub const fn from_words(words: [u16; W]) -> Image<W> {
        Image { words }
    }

    /// Point `point`; a point outside the image reads as off (see [`try_get`](Image::try_get)).
    #[must_use]
    pub fn get(&self, point: usize) -> bool {
        self.try_get(point).unwrap_or(false)
    }

    /// Point `point`, or `None` outside the image.
    #[must_use]
    pub fn try_get(&self, point: usize) -> Option<bool> {
        let word = self.words.get(point / POINTS_PER_WORD)?;
        Some(word >> (point % POINTS_PER_WORD) & 1 == 1)
    }

    /// Sets point `point`.
    pub fn set(&mut self, point: usize, on: bool) -> Result<(), PointError> {
        let points = Self::POINTS;
        let word = self
            .words
            .get_mut(point / POINTS_PER_WORD)
            .ok_or(PointError { point, points })?;
        let bit = 1u16 << (point % POINTS_PER_WORD);
        if on {
            *word |= bit;
        } else {
            *word &= !bit;
        }
        Ok(())
    }

    /// Word `index`.
    #[must_use]
    pub fn word(&self, index: usize) -> Option<u16> {
        self.words.get(index).copied()
    }

    /// Sets word `index`.
    pub fn set_word(&mut self, index: usize, value: u16) -> Result<(), WordError> {
        let word = self.words.get_mut(index).ok_or(WordError {
            word: index,
            words: W,
        })?;
        *word = value;
        Ok(())
    }

    /// All words.
    #[must_use]
    pub const fn words(&self) -> &[u16; W] {
        &self.words
    }

    /// All words, to fill.
    pub fn words_mut(&mut self) -> &mut [u16; W] {
        &mut self.words
    }

    /// Points that are on, in order.
    pub fn ones(&self) -> impl Iterator<Item = usize> + '_ {
        (0..Self::POINTS).filter(|&p| self.get(p))
    }
}

#[cfg(feature = "serde")]
mod serde_words {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub(super) fn serialize<S: Serializer, const W: usize>(
        words: &[u16; W],
        s: S,
    ) -> Result<S::Ok, S::Error> {
        words.as_slice().serialize(s)
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>, const W: usize>(
        d: D,
    ) -> Result<[u16; W], D::Error> {
        let v = heapless::Vec::<u16, W>::deserialize(d)?;
        v.into_array()
            .map_err(|_| serde::de::Error::custom("wrong number of image words"))
    }
}

/// Forced points of one image: forced values win over the program and the hardware.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Forcing<const W: usize> {
    mask: Image<W>,
    values: Image<W>,
}

impl<const W: usize> Default for Forcing<W> {
    fn default() -> Self {
        Forcing::new()
    }
}

impl<const W: usize> Forcing<W> {
    /// Nothing forced.
    #[must_use]
    pub const fn new() -> Forcing<W> {
        Forcing {
            mask: Image::new(),
            values: Image::new(),
        }
    }

    /// Forces `point` to `on`.
    pub fn force(&mut self, point: usize, on: bool) -> Result<(), PointError> {
        self.mask.set(point, true)?;
        self.values.set(point, on)
    }

    /// Releases `point`.
    pub fn unforce(&mut self, point: usize) -> Result<(), PointError> {
        self.mask.set(point, false)?;
        self.values.set(point, false)
    }

    /// Releases every point.
    pub fn clear(&mut self) {
        *self = Forcing::new();
    }

    /// The forced value of `point`, if forced.
    #[must_use]
    pub fn forced(&self, point: usize) -> Option<bool> {
        self.mask.get(point).then(|| self.values.get(point))
    }

    /// Whether any point is forced.
    #[must_use]
    pub fn any(&self) -> bool {
        self.mask.words().iter().any(|&w| w != 0)
    }

    /// The forced points and their values.
    pub fn iter(&self) -> impl Iterator<Item = (usize, bool)> + '_ {
        self.mask.ones().map(|p| (p, self.values.get(p)))
    }

    /// Applies the forcing to `image`, word by word.
    #[inline]
    pub fn apply(&self, image: &mut Image<W>) {
        for ((w, m), v) in image
            .words
            .iter_mut()
            .zip(self.mask.words.iter())
            .zip(self.values.words.iter())
        {
            *w = (*w & !m) | (v & m);
        }
    }
}

/// Input conditioning: latching of pulses shorter than a cycle, and debouncing.
///
/// **Latch.** For latched inputs, every [`capture`](Conditioning::capture) of the raw inputs
/// (from a fast clock interrupt, as the 1977 plant's input flip-flops did in hardware) remembers
/// each input that was on; at the next cycle the input reads on even if the pulse is over, and
/// the memory is cleared.
///
/// **Latched or debounced, not both.** A latch says that a pulse shorter than a cycle is an event
/// to be seen; a debounce count of k says that a change shorter than k readings is contact bounce
/// to be ignored. No rule serves both for one input: a latched pulse held on until the debounce
/// accepts it would let every bounce through as well, so the debounce would filter nothing.
/// Which one an input needs is a property of its wiring (a clean sensor pulse, as the source's
/// input flip-flops caught, or a bouncing contact, for which the source asked several equal
/// readings), so the combination is refused with [`DebounceError::Latched`]: a latched point
/// keeps count 1, a debounced point is not latched.
///
/// **Debounce.** A debounced input with count k changes its conditioned value only after k
/// consecutive readings that differ from it (1 = no debounce; at most 15). A count changed while
/// an input is counting applies to the readings already counted: lowered below them, the next
/// differing reading changes the value. The counters are bit-sliced, four bit planes per word,
/// so a cycle costs a few dozen word operations per 16 inputs, whatever the counts. A
/// `Conditioning<W>` is 11 images of `W` words: `22·W` bytes.
///
/// Deserializing checks that every point's debounce count is 1..=15 (a stored count of 0, a
/// corrupt block, is an error, not an input that never debounces), that no latched point is
/// debounced, that no counter holds 15 readings (counters stop at 14) and that no pulse is
/// captured on a point that is not latched. So a restored debounced input with count k changes
/// after at most k consecutive differing readings — after k − c when it had counted c of them,
/// and at the first when c ≥ k — as it would have without the power failure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "RawConditioning<W>"))]
pub struct Conditioning<const W: usize> {
    latched: Image<W>,
    pending: Image<W>,
    stable: Image<W>,
    counters: [Image<W>; 4],
    thresholds: [Image<W>; 4],
}

/// The stored form of a [`Conditioning`], checked on the way in (serde's messages name
/// `Conditioning`: a user reads "expected struct Conditioning").
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
#[serde(expecting = "struct Conditioning")]
struct RawConditioning<const W: usize> {
    latched: Image<W>,
    pending: Image<W>,
    stable: Image<W>,
    counters: [Image<W>; 4],
    thresholds: [Image<W>; 4],
}

#[cfg(feature = "serde")]
impl<const W: usize> TryFrom<RawConditioning<W>> for Conditioning<W> {
    type Error = DebounceError;
    fn try_from(raw: RawConditioning<W>) -> Result<Conditioning<W>, DebounceError> {
        // A point with all four threshold bits clear has count 0.
        let [k0, k1, k2, k3] = &raw.thresholds;
        for (w, (((a, b), c), d)) in k0
            .words
            .iter()
            .zip(&k1.words)
            .zip(&k2.words)
            .zip(&k3.words)
            .enumerate()
        {
            let zero = !(a | b | c | d);
            if zero != 0 {
                let bit = usize::try_from(zero.trailing_zeros()).unwrap_or(0);
                let point = w.saturating_mul(POINTS_PER_WORD).saturating_add(bit);
                return Err(DebounceError::StoredCount { point, count: 0 });
            }
            let latched = raw.latched.words.get(w).copied().unwrap_or(0);
            let both = latched & (!a | b | c | d);
            if both != 0 {
                let bit = usize::try_from(both.trailing_zeros()).unwrap_or(0);
                let point = w.saturating_mul(POINTS_PER_WORD).saturating_add(bit);
                let count = u8::from(a >> bit & 1 == 1)
                    | u8::from(b >> bit & 1 == 1) << 1
                    | u8::from(c >> bit & 1 == 1) << 2
                    | u8::from(d >> bit & 1 == 1) << 3;
                return Err(DebounceError::Latched { point, count });
            }
            // A counter of 15 is never stored: a count is at most 15 and a counter is cleared
            // the cycle it reaches its point's count, so counters stop at 14. Restored, 15 would
            // wrap to 0 at the next differing reading and the input would wait its whole count
            // again.
            let [c0, c1, c2, c3] = &raw.counters;
            let full = c0.words.get(w).copied().unwrap_or(0)
                & c1.words.get(w).copied().unwrap_or(0)
                & c2.words.get(w).copied().unwrap_or(0)
                & c3.words.get(w).copied().unwrap_or(0);
            if full != 0 {
                let bit = usize::try_from(full.trailing_zeros()).unwrap_or(0);
                let point = w.saturating_mul(POINTS_PER_WORD).saturating_add(bit);
                return Err(DebounceError::StoredCounter { point });
            }
            // A pending pulse exists only on a latched point: one elsewhere would read as a
            // phantom input for a cycle.
            let pending = raw.pending.words.get(w).copied().unwrap_or(0);
            let stray = pending & !latched;
            if stray != 0 {
                let bit = usize::try_from(stray.trailing_zeros()).unwrap_or(0);
                let point = w.saturating_mul(POINTS_PER_WORD).saturating_add(bit);
                return Err(DebounceError::PendingNotLatched { point });
            }
        }
        Ok(Conditioning {
            latched: raw.latched,
            pending: raw.pending,
            stable: raw.stable,
            counters: raw.counters,
            thresholds: raw.thresholds,
        })
    }
}

impl<const W: usize> Default for Conditioning<W> {
    fn default() -> Self {
        Conditioning::new()
    }
}

/// A conditioning setting refused: a debounce count outside 1..=15, a point outside the image,
/// or a latched input that would be debounced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DebounceError {
    /// The point is outside the image.
    Point(PointError),
    /// The count is not within 1..=15.
    Count(u8),
    /// Stored conditioning (deserialized) gives a point a count outside 1..=15.
    StoredCount {
        /// The point.
        point: usize,
        /// Its stored count.
        count: u8,
    },
    /// The point would be latched and debounced at once (see [`Conditioning`]): a latched point
    /// keeps count 1.
    Latched {
        /// The point.
        point: usize,
        /// The debounce count it has or was to get (above 1).
        count: u8,
    },
    /// Stored conditioning (deserialized) holds a debounce counter of 15 readings on a point, a
    /// state the conditioning never reaches (a counter is cleared the cycle it reaches the
    /// point's count, at most 15, so counters stop at 14): restored, it would wrap to 0 and the
    /// input would wait its whole count again.
    StoredCounter {
        /// The point.
        point: usize,
    },
    /// Stored conditioning (deserialized) holds a captured pulse on a point that is not
    /// latched: it would read as a phantom input for one cycle.
    PendingNotLatched {
        /// The point.
        point: usize,
    },
}

impl fmt::Display for DebounceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DebounceError::Point(e) => e.fmt(f),
            DebounceError::Count(k) => write!(f, "a debounce count is 1..=15 readings, got {k}"),
            DebounceError::StoredCount { point, count } => write!(
                f,
                "stored conditioning gives point {point} a debounce count of {count}, not 1..=15"
            ),
            DebounceError::Latched { point, count } => write!(
                f,
                "point {point} cannot be latched and debounced (count {count}) at once: \
                 a latch keeps pulses a debounce would drop; latched points keep count 1"
            ),
            DebounceError::StoredCounter { point } => write!(
                f,
                "stored conditioning holds a debounce counter of 15 readings on point {point}: \
                 counters stop at 14"
            ),
            DebounceError::PendingNotLatched { point } => write!(
                f,
                "stored conditioning holds a captured pulse on point {point}, which is not latched"
            ),
        }
    }
}

impl core::error::Error for DebounceError {}

impl<const W: usize> Conditioning<W> {
    /// No latching, no debouncing (every count 1).
    #[must_use]
    pub const fn new() -> Conditioning<W> {
        let mut thresholds = [Image::new(), Image::new(), Image::new(), Image::new()];
        thresholds[0] = Image::from_words([u16::MAX; W]); // count 1 everywhere
        Conditioning {
            latched: Image::new(),
            pending: Image::new(),
            stable: Image::new(),
            counters: [Image::new(), Image::new(), Image::new(), Image::new()],
            thresholds,
        }
    }

    /// Latches (or stops latching) short pulses on `point`. A point whose debounce count is
    /// above 1 is refused with [`DebounceError::Latched`]: it cannot be latched and debounced.
    /// Stopping the latch forgets a pulse captured and not yet read.
    pub fn set_latched(&mut self, point: usize, latched: bool) -> Result<(), DebounceError> {
        if point >= Image::<W>::POINTS {
            return Err(DebounceError::Point(PointError {
                point,
                points: Image::<W>::POINTS,
            }));
        }
        let count = self.debounce(point);
        if latched && count != 1 {
            return Err(DebounceError::Latched { point, count });
        }
        if !latched {
            // A pulse captured while the point was latched is forgotten with the latch: an
            // unlatched point reads only the hardware.
            self.pending
                .set(point, false)
                .map_err(DebounceError::Point)?;
        }
        self.latched
            .set(point, latched)
            .map_err(DebounceError::Point)
    }

    /// Whether `point` is latched.
    #[must_use]
    pub fn latched(&self, point: usize) -> bool {
        self.latched.get(point)
    }

    /// Sets the debounce count of `point` (1..=15 consecutive readings). A count above 1 on a
    /// latched point is refused with [`DebounceError::Latched`].
    pub fn set_debounce(&mut self, point: usize, count: u8) -> Result<(), DebounceError> {
        if !(1..=15).contains(&count) {
            return Err(DebounceError::Count(count));
        }
        if count != 1 && self.latched.get(point) {
            return Err(DebounceError::Latched { point, count });
        }
        for (bit, plane) in self.thresholds.iter_mut().enumerate() {
            plane
                .set(point, count >> bit & 1 == 1)
                .map_err(DebounceError::Point)?;
        }
        Ok(())
    }

    /// The debounce count of `point` (0 for a point outside the image).
    #[must_use]
    pub fn debounce(&self, point: usize) -> u8 {
        (0u8..)
            .zip(self.thresholds.iter())
            .fold(0, |k, (bit, plane)| k | (u8::from(plane.get(point)) << bit))
    }

    /// Remembers which latched inputs are on now (call as often as the hardware allows).
    pub fn capture(&mut self, raw: &[u16; W]) {
        for ((p, r), l) in self
            .pending
            .words
            .iter_mut()
            .zip(raw.iter())
            .zip(self.latched.words.iter())
        {
            *p |= r & l;
        }
    }

    /// One cycle: turns raw readings into the conditioned input image.
    #[inline]
    pub fn condition(&mut self, raw: &[u16; W], out: &mut Image<W>) {
        let [c0, c1, c2, c3] = &mut self.counters;
        let [k0, k1, k2, k3] = &self.thresholds;
        let words = raw
            .iter()
            .zip(self.pending.words.iter_mut())
            .zip(self.stable.words.iter_mut())
            .zip(out.words.iter_mut())
            .zip(
                c0.words
                    .iter_mut()
                    .zip(c1.words.iter_mut())
                    .zip(c2.words.iter_mut().zip(c3.words.iter_mut())),
            )
            .zip(
                k0.words
                    .iter()
                    .zip(k1.words.iter())
                    .zip(k2.words.iter().zip(k3.words.iter())),
            );
        for (((((raw, pending), stable), out), ((c0, c1), (c2, c3))), ((k0, k1), (k2, k3))) in words
        {
            // A latched pulse reads on once, then is forgotten.
            let reading = raw | *pending;
            *pending = 0;
            let diff = reading ^ *stable;
            // Bit-sliced increment of the counters of the differing inputs; others restart at 0.
            let mut carry = diff;
            *c0 ^= carry;
            carry &= !*c0;
            *c1 ^= carry;
            carry &= !*c1;
            *c2 ^= carry;
            carry &= !*c2;
            *c3 ^= carry;
            *c0 &= diff;
            *c1 &= diff;
            *c2 &= diff;
            *c3 &= diff;
            // Counter >= count, bit-sliced from the top bit down. ">=" rather than "==": a count
            // lowered below a running counter must end the wait, not let the counter wrap.
            let (e3, e2, e1) = (!(*c3 ^ k3), !(*c2 ^ k2), !(*c1 ^ k1));
            let above = (*c3 & !k3) | e3 & ((*c2 & !k2) | e2 & ((*c1 & !k1) | e1 & (*c0 & !k0)));
            let equal = e3 & e2 & e1 & !(*c0 ^ k0);
            let reached = diff & (above | equal);
            *stable ^= reached;
            *c0 &= !reached;
            *c1 &= !reached;
            *c2 &= !reached;
            *c3 &= !reached;
            *out = *stable;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn forcing_wins_and_is_visible() {
        let mut f: Forcing<2> = Forcing::new();
        assert!(!f.any());
        f.force(3, true).unwrap();
        assert!(f.any());
        f.force(17, false).unwrap();
        let mut img = Image::from_words([0, 0xFFFF]);
        f.apply(&mut img);
        assert!(img.get(3) && !img.get(17) && img.get(18));
        assert_eq!(f.forced(3), Some(true));
        assert_eq!(f.iter().collect::<Vec<_>>(), [(3, true), (17, false)]);
        f.unforce(3).unwrap();
        assert_eq!(f.forced(3), None);
        assert!(f.any(), "point 17 is still forced");
        f.unforce(17).unwrap();
        assert!(!f.any());
        let e = f.force(32, true).unwrap_err();
        assert_eq!(
            e,
            PointError {
                point: 32,
                points: 32
            }
        );
        assert_eq!(
            e.to_string(),
            "I/O point 32 is outside the image of 32 points"
        );
    }

    #[test]
    fn conditioning_is_eleven_images() {
        assert_eq!(core::mem::size_of::<Conditioning<34>>(), 22 * 34);
    }

    #[test]
    fn set_word_names_the_word() {
        let mut img: Image<2> = Image::new();
        assert_eq!(img.set_word(2, 1), Err(WordError { word: 2, words: 2 }));
        assert_eq!(
            img.set_word(5, 1).unwrap_err().to_string(),
            "I/O word 5 is outside the image of 2 words"
        );
    }

    #[test]
    fn lowering_a_count_mid_count_ends_the_wait() {
        let mut c: Conditioning<1> = Conditioning::new();
        c.set_debounce(0, 15).unwrap();
        let mut out = Image::new();
        for _ in 0..10 {
            c.condition(&[1], &mut out);
        }
        assert!(!out.get(0));
        c.set_debounce(0, 3).unwrap();
        c.condition(&[1], &mut out);
        assert!(
            out.get(0),
            "11 readings counted, 3 needed: no wrap through 15"
        );
    }

    #[test]
    fn debounce_needs_k_consecutive_readings() {
        let mut c: Conditioning<1> = Conditioning::new();
        c.set_debounce(0, 3).unwrap();
        assert_eq!(c.debounce(0), 3);
        assert_eq!(c.debounce(1), 1);
        let mut out = Image::new();
        let mut seen = Vec::new();
        for raw in [1u16, 1, 0, 1, 1, 1, 1, 0, 0, 0] {
            c.condition(&[raw | 0b10], &mut out);
            seen.push((out.get(0), out.get(1)));
        }
        // Point 1 (count 1) follows at once; point 0 needs three in a row.
        let p0: Vec<bool> = seen.iter().map(|s| s.0).collect();
        assert_eq!(
            p0,
            [
                false, false, false, false, false, true, true, true, true, false
            ]
        );
        assert!(seen.iter().all(|s| s.1));
        assert_eq!(c.set_debounce(0, 0), Err(DebounceError::Count(0)));
        assert_eq!(c.set_debounce(0, 16), Err(DebounceError::Count(16)));
    }

    #[test]
    fn every_count_up_to_15_works() {
        for k in 1..=15u8 {
            let mut c: Conditioning<1> = Conditioning::new();
            c.set_debounce(5, k).unwrap();
            let mut out = Image::new();
            let mut n = 0;
            while !out.get(5) {
                c.condition(&[1 << 5], &mut out);
                n += 1;
            }
            assert_eq!(n, k);
        }
    }

    /// Every point, every count above 1, set in either order: a latched input that is also
    /// debounced is refused, or else its short pulse would have to come through.
    #[test]
    #[cfg_attr(
        miri,
        ignore = "exhaustive over 32 points × 14 debounce counts × both orders: hours under Miri; safe code, run natively in every CI run"
    )]
    fn a_latched_input_is_never_a_debounced_one_that_loses_its_pulses() {
        for p in 0..32 {
            for k in 2..=15u8 {
                for latch_first in [false, true] {
                    let mut c: Conditioning<2> = Conditioning::new();
                    let accepted = if latch_first {
                        let latched = c.set_latched(p, true);
                        latched.is_ok() && c.set_debounce(p, k).is_ok()
                    } else {
                        let debounced = c.set_debounce(p, k);
                        debounced.is_ok() && c.set_latched(p, true).is_ok()
                    };
                    if !accepted {
                        continue;
                    }
                    let mut raw = [0u16; 2];
                    raw[p / 16] = 1 << (p % 16);
                    c.capture(&raw); // a pulse shorter than a cycle
                    let mut out = Image::new();
                    let mut seen = false;
                    for _ in 0..16 {
                        c.condition(&[0, 0], &mut out);
                        seen |= out.get(p);
                    }
                    assert!(seen, "point {p}, count {k}: the latched pulse was lost");
                }
            }
        }
    }

    #[test]
    fn latched_pulses_between_cycles_are_seen_once() {
        let mut c: Conditioning<1> = Conditioning::new();
        c.set_latched(4, true).unwrap();
        let mut out = Image::new();
        c.capture(&[1 << 4 | 1 << 6]); // a short pulse on 4 and 6; only 4 is latched
        c.condition(&[0], &mut out);
        assert!(out.get(4) && !out.get(6));
        c.condition(&[0], &mut out);
        assert!(!out.get(4));
    }

    #[test]
    fn an_unlatched_point_never_reads_a_pulse_captured_while_it_was_latched() {
        // Every point of two words: capture while latched, unlatch, then the point reads only
        // the hardware (off), and latching it again does not bring the old pulse back.
        for point in 0..Image::<2>::POINTS {
            let mut c: Conditioning<2> = Conditioning::new();
            assert!(!c.latched(point));
            c.set_latched(point, true).unwrap();
            assert!(c.latched(point));
            assert!((0..Image::<2>::POINTS).all(|p| c.latched(p) == (p == point)));
            c.capture(&[u16::MAX; 2]);
            c.set_latched(point, false).unwrap();
            assert!(!c.latched(point));
            let mut out = Image::new();
            c.condition(&[0; 2], &mut out);
            assert_eq!(out, Image::new(), "point {point}: a phantom pulse");
            c.set_latched(point, true).unwrap();
            c.condition(&[0; 2], &mut out);
            assert_eq!(out, Image::new(), "point {point}: the old pulse came back");
        }
    }
}
