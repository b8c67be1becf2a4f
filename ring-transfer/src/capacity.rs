//! How many slaves can one master serve? A schedulability test for the refill link.
//!
//! **The model.** Slave `i` consumes one item every `t0ᵢ` (at most that often) and has a ring of
//! `Nᵢ` slots. Every consumption is a request for one item with the source's deadline: with the
//! ring otherwise full it must arrive within `(Nᵢ − 1)·t0ᵢ`, less the `latency` before the master
//! hears of it. The link carries one item at a time, `item_time` each, without pre-emption
//! (a byte on the wire is not interrupted), and the master always sends the item with the
//! earliest deadline ([`crate::Master::next_refill`] with `max` = 1). All times are integers in
//! one unit.
//!
//! **The test** is the processor-demand criterion for non-pre-emptive EDF (George, Rivierre &
//! Spuri, 1996): with `Dᵢ = (Nᵢ − 1)·t0ᵢ − latency`, `Tᵢ = t0ᵢ` and `C = item_time`, the set is
//! schedulable if the utilisation `Σ C/Tᵢ ≤ 1` and, at every deadline point `L` below the
//! largest `D`,
//!
//! `Σᵢ max(0, ⌊(L − Dᵢ)/Tᵢ⌋ + 1)·C + (C − 1) ≤ L`,
//!
//! the last term being the longest time an item already on the wire for a later deadline can
//! hold the link (integer time). Points at or beyond the largest `D` need no check: when every
//! `Dᵢ ≥ Tᵢ` the demand there is at most `U·L`. A ring so short that `Dᵢ < Tᵢ` is refused as
//! [`Verdict::RingTooShort`] — a safe simplification (such a slave leaves the master less than
//! one consumption period and is never what a plant wants).
//!
//! **Exact or safe?** Safe always: a set called schedulable meets every deadline under these
//! rules, whatever the phases of the machines (the property tests run the [`crate::Master`]
//! against simulated slaves and find no miss or underrun). Exact for identical slaves — the
//! source's case of one master and many like machines — where it reduces to `U ≤ 1`; for mixed
//! sets the blocking term can be one tick pessimistic. The utilisation is summed as an exact
//! fraction; only if its denominator outgrows 128 bits does the sum fall back to 64-bit fixed
//! point rounded up (a set within 2⁻⁶⁴·n of `U = 1` may then be refused).
//!
//! ```
//! use regler_ring_transfer::capacity::{check, max_slaves, min_ring, LinkSpec, Load, Verdict};
//!
//! // A sock machine at 130 rpm with 200 needles takes a byte every ≈2 308 µs.
//! let machine = Load { t0: 2_308, ring: 256 };
//! // A link that delivers a byte in 28 µs (service included), requests seen within 100 µs.
//! let link = LinkSpec { item_time: 28, latency: 100 };
//! assert_eq!(max_slaves(machine, link, 1_000)?, 82); // "one master can serve 80+"
//! let eight = [machine; 8];
//! assert!(matches!(check(&eight, link)?, Verdict::Schedulable { .. }));
//! // Eight machines hardly load the link: a 3-byte ring would do (2 leaves less than t0 after
//! // the latency).
//! assert_eq!(min_ring(&eight, link, 0, 1024)?, Some(3));
//! # Ok::<(), regler_ring_transfer::capacity::CapacityError>(())
//! ```

use core::fmt;

/// One slave's demand on the link.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Load {
    /// Shortest time between two consumptions (≥ 1).
    pub t0: u64,
    /// Ring slots.
    pub ring: u32,
}

/// The link.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LinkSpec {
    /// Time the link is busy per item delivered, the master's handling of the request included
    /// (≥ 1).
    pub item_time: u64,
    /// Longest time from a consumption until the master has the request.
    pub latency: u64,
}

/// The answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum Verdict {
    /// Every request meets its deadline.
    Schedulable {
        /// Link utilisation in parts per million (rounded up).
        utilisation_ppm: u64,
    },
    /// The link is asked for more items than it can carry.
    Overloaded {
        /// Link utilisation in parts per million (rounded up).
        utilisation_ppm: u64,
    },
    /// In some interval of length `interval` the requests due add up to more link time than it
    /// has.
    DeadlineMiss {
        /// The interval.
        interval: u64,
        /// Link time the requests due in it need (blocking included).
        demand: u64,
    },
    /// This slave's ring leaves the master less than one consumption period `t0` after the
    /// latency: `(ring − 1)·t0 − latency < t0`.
    RingTooShort {
        /// The slave.
        slave: usize,
    },
}

impl Verdict {
    /// `true` for [`Verdict::Schedulable`].
    #[must_use]
    pub fn is_schedulable(&self) -> bool {
        matches!(self, Self::Schedulable { .. })
    }
}

/// Why the question could not be answered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum CapacityError {
    /// No slaves given.
    NoSlaves,
    /// A slave with `t0` = 0.
    ZeroRate {
        /// The slave.
        slave: usize,
    },
    /// `item_time` = 0.
    ZeroItemTime,
    /// The slave index for [`min_ring`] is not in the set.
    UnknownSlave(usize),
    /// A deadline does not fit in 64 bits.
    Overflow,
    /// The test would evaluate the demand of every slave at more than [`MAX_POINTS`] deadline
    /// points in all (points × slaves: rates or rings many orders of magnitude apart, or very
    /// many slaves beside one fast one).
    TooComplex {
        /// Deadline points × slaves the test would need (saturating).
        points: u64,
    },
}

impl fmt::Display for CapacityError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::NoSlaves => write!(f, "no slaves to check"),
            Self::ZeroRate { slave } => write!(f, "slave {slave}: t0 must be at least 1"),
            Self::ZeroItemTime => write!(f, "item_time must be at least 1"),
            Self::UnknownSlave(i) => write!(f, "slave {i} is not in the set"),
            Self::Overflow => write!(f, "a deadline does not fit in 64 bits"),
            Self::TooComplex { points } => {
                write!(
                    f,
                    "{points} deadline points x slaves to check (at most {MAX_POINTS})"
                )
            }
        }
    }
}

impl core::error::Error for CapacityError {}

/// The most work one [`check`] does: deadline points × slaves (each point sums the demand of
/// every slave). A set that needs more is refused with [`CapacityError::TooComplex`] before any
/// point is evaluated, so a check costs O(n) plus at most this many demand terms.
pub const MAX_POINTS: u64 = 10_000_000;

/// Whether `loads` can share `link`. Cost: O(n + n·P), P the deadline points below the
/// largest deadline (none for identical slaves), with n·P at most [`MAX_POINTS`] (a set that
/// needs more is refused).
///
/// # Errors
/// [`CapacityError`] for an empty set, a zero rate or item time, an overflow, or too many
/// points.
pub fn check(loads: &[Load], link: LinkSpec) -> Result<Verdict, CapacityError> {
    check_by(loads.len(), |i| loads.get(i).copied(), link)
}

/// The smallest ring for slave `slave` (the others as given) that keeps the set schedulable,
/// searching `2..=max_ring`; `None` if none is. Cost: O(log r) checks, r the answer (or
/// `max_ring` when there is none) — `u32::MAX` returns as promptly as 1 000.
///
/// The search relies on the verdict being monotone in the ring: a ring one slot longer never
/// turns [`Verdict::Schedulable`] into a refusal. Why: a longer ring raises only this slave's
/// deadline `D`. Its own demand `⌊(L − D)/T⌋ + 1` falls at every `L`; the blocking term `C − 1`
/// (one item time, the same for every slave) may newly appear at an `L` between the old and the
/// new `D` — but only where this slave's own demand drops from at least `C` to 0, so the sum
/// falls there too; the utilisation and the other slaves' terms do not change. (The property
/// tests check this and compare the search with a linear scan.)
///
/// # Errors
/// As [`check`] for any ring the search tries (it tries rings from 2 upwards in doubling steps,
/// none above `max(2·r, max_ring)`), and [`CapacityError::UnknownSlave`].
pub fn min_ring(
    loads: &[Load],
    link: LinkSpec,
    slave: usize,
    max_ring: u32,
) -> Result<Option<u32>, CapacityError> {
    let own = *loads.get(slave).ok_or(CapacityError::UnknownSlave(slave))?;
    let fits = |ring: u32| -> Result<bool, CapacityError> {
        let verdict = check_by(
            loads.len(),
            |i| {
                if i == slave {
                    Some(Load { ring, ..own })
                } else {
                    loads.get(i).copied()
                }
            },
            link,
        )?;
        Ok(verdict.is_schedulable())
    };
    if max_ring < 2 {
        return Ok(None);
    }
    // Galloping from the bottom, so that no ring far above the answer is tried (a check's cost
    // grows with the ring): `bad` does not fit, `good` does.
    let (mut bad, mut step) = (1u32, 1u32);
    let mut good = loop {
        let probe = bad.saturating_add(step).min(max_ring);
        if fits(probe)? {
            break probe;
        }
        if probe == max_ring {
            return Ok(None);
        }
        bad = probe;
        step = step.saturating_mul(2);
    };
    while good.saturating_sub(bad) > 1 {
        let mid = bad.saturating_add(good.saturating_sub(bad) >> 1);
        if fits(mid)? {
            good = mid;
        } else {
            bad = mid;
        }
    }
    Ok(Some(good))
}

/// The most identical slaves (`load` each, up to `limit`) one link can serve: the source's
/// "one master can serve 80+". The largest `n ≤ limit` for which [`check`] of `n` copies of
/// `load` is schedulable (0 if none is). O(1): for identical slaves every deadline is the same,
/// so the test reduces to the ring check and `n·item_time ≤ t0`.
///
/// # Errors
/// As [`check`] of one such slave (none for `limit` = 0).
pub fn max_slaves(load: Load, link: LinkSpec, limit: usize) -> Result<usize, CapacityError> {
    if limit == 0 {
        return Ok(0);
    }
    if link.item_time == 0 {
        return Err(CapacityError::ZeroItemTime);
    }
    if load.t0 == 0 {
        return Err(CapacityError::ZeroRate { slave: 0 });
    }
    if deadline(load, link)?.is_none() {
        return Ok(0);
    }
    // n·C ≤ T: the exact utilisation bound (no deadline points: all deadlines are equal).
    let most = load.t0.checked_div(link.item_time).unwrap_or(0);
    Ok(usize::try_from(most).map_or(limit, |m| m.min(limit)))
}

/// A non-negative fraction in lowest terms.
#[derive(Clone, Copy)]
struct Fraction {
    num: u128,
    den: u128,
}

impl Fraction {
    const ZERO: Self = Self { num: 0, den: 1 };

    fn add(self, num: u128, den: u128) -> Option<Self> {
        let g = gcd(self.den, den);
        let scale = den.checked_div(g)?;
        let den_total = self.den.checked_mul(scale)?;
        let num_total = self
            .num
            .checked_mul(scale)?
            .checked_add(num.checked_mul(self.den.checked_div(g)?)?)?;
        let g = gcd(num_total, den_total);
        Some(Self {
            num: num_total.checked_div(g)?,
            den: den_total.checked_div(g)?,
        })
    }
}

/// `⌈a/b⌉`, `a` for `b` = 0 (never asked: rates are checked first). `u128::div_ceil` would
/// keep a division-by-zero panic path in the firmware.
fn div_ceil(a: u128, b: u128) -> u128 {
    let q = a.checked_div(b).unwrap_or(a);
    let r = a.checked_rem(b).unwrap_or(0);
    q.saturating_add(u128::from(r != 0))
}

fn gcd(mut a: u128, mut b: u128) -> u128 {
    while b != 0 {
        (a, b) = (b, a.checked_rem(b).unwrap_or(0));
    }
    a
}

fn deadline(load: Load, link: LinkSpec) -> Result<Option<u64>, CapacityError> {
    let periods = u64::from(load.ring.saturating_sub(1));
    let window = periods
        .checked_mul(load.t0)
        .ok_or(CapacityError::Overflow)?;
    Ok(window.checked_sub(link.latency).filter(|&d| d >= load.t0))
}

fn check_by(
    n: usize,
    load: impl Fn(usize) -> Option<Load>,
    link: LinkSpec,
) -> Result<Verdict, CapacityError> {
    if n == 0 {
        return Err(CapacityError::NoSlaves);
    }
    if link.item_time == 0 {
        return Err(CapacityError::ZeroItemTime);
    }
    let c = link.item_time;
    let mut rounded_up: u128 = 0; // Σ C/Tᵢ in units of 2⁻⁶⁴, each term rounded up
    let mut exact = Some(Fraction::ZERO);
    let mut d_max = 0u64;
    for i in 0..n {
        let l = load(i).ok_or(CapacityError::UnknownSlave(i))?;
        if l.t0 == 0 {
            return Err(CapacityError::ZeroRate { slave: i });
        }
        let share = div_ceil(u128::from(c) << 64, u128::from(l.t0));
        rounded_up = rounded_up.saturating_add(share);
        exact = exact.and_then(|sum| sum.add(u128::from(c), u128::from(l.t0)));
        match deadline(l, link)? {
            Some(d) => d_max = d_max.max(d),
            None => return Ok(Verdict::RingTooShort { slave: i }),
        }
    }
    // For display, rounded up: from the exact sum when it fits in 128 bits, else from the
    // rounded-up sum (within n·2⁻⁶⁴ above the truth).
    let ppm = exact
        .and_then(|sum| Some(div_ceil(sum.num.checked_mul(1_000_000)?, sum.den)))
        .unwrap_or_else(|| div_ceil(rounded_up.saturating_mul(1_000_000), 1 << 64));
    let ppm = u64::try_from(ppm).unwrap_or(u64::MAX);
    // Exact when the sum of fractions fits in 128 bits, rounded up (safe) when it does not.
    let overloaded = exact.map_or(rounded_up > 1 << 64, |sum| sum.num > sum.den);
    if overloaded {
        return Ok(Verdict::Overloaded {
            utilisation_ppm: ppm,
        });
    }
    // Count the points first, so that an absurd set is refused rather than ground through.
    let mut points = 0u64;
    for i in 0..n {
        let l = load(i).ok_or(CapacityError::UnknownSlave(i))?;
        let d = deadline(l, link)?.ok_or(CapacityError::Overflow)?;
        let periods = div_ceil(u128::from(d_max.saturating_sub(d)), u128::from(l.t0));
        points = points.saturating_add(u64::try_from(periods).unwrap_or(u64::MAX));
    }
    // Each point sums the demand of all n slaves: the cap bounds that work, not the points.
    let work = points.saturating_mul(u64::try_from(n).unwrap_or(u64::MAX));
    if work > MAX_POINTS {
        return Err(CapacityError::TooComplex { points: work });
    }
    let blocking = c.saturating_sub(1);
    for i in 0..n {
        let l = load(i).ok_or(CapacityError::UnknownSlave(i))?;
        let mut at = deadline(l, link)?.ok_or(CapacityError::Overflow)?;
        while at < d_max {
            let mut demand = blocking;
            for j in 0..n {
                let other = load(j).ok_or(CapacityError::UnknownSlave(j))?;
                let dj = deadline(other, link)?.ok_or(CapacityError::Overflow)?;
                if let Some(after) = at.checked_sub(dj) {
                    let jobs = after.checked_div(other.t0).unwrap_or(0).saturating_add(1);
                    demand = demand.saturating_add(jobs.saturating_mul(c));
                }
            }
            if demand > at {
                return Ok(Verdict::DeadlineMiss {
                    interval: at,
                    demand,
                });
            }
            at = at.saturating_add(l.t0);
        }
    }
    Ok(Verdict::Schedulable {
        utilisation_ppm: ppm,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `f()` on its own thread; fails if it has not returned within 5 s (a search or a capped
    /// check that never ends is a failure, not a hang). Under Miri `f` simply runs.
    fn promptly<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
        if cfg!(miri) {
            return f();
        }
        let (done, result) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let _ = done.send(f());
        });
        result
            .recv_timeout(std::time::Duration::from_secs(5))
            .expect("returned within 5 s")
    }

    const LINK: LinkSpec = LinkSpec {
        item_time: 10,
        latency: 0,
    };

    #[test]
    fn identical_slaves_fit_while_the_link_keeps_up() {
        let load = Load { t0: 100, ring: 8 };
        assert_eq!(max_slaves(load, LINK, 1000), Ok(10));
        assert!(check(&[load; 10], LINK).unwrap().is_schedulable());
        assert_eq!(
            check(&[load; 11], LINK),
            Ok(Verdict::Overloaded {
                utilisation_ppm: 1_100_000
            })
        );
    }

    #[test]
    fn a_short_ring_beside_long_ones() {
        promptly(|| {
            let link = LinkSpec {
                item_time: 10,
                latency: 0,
            };
            let loads = [
                Load { t0: 30, ring: 40 },
                Load { t0: 30, ring: 40 },
                Load { t0: 60, ring: 2 },
            ];
            let verdict = check(&loads, link).unwrap();
            assert!(verdict.is_schedulable(), "{verdict:?}");
            assert_eq!(min_ring(&loads, link, 2, 100), Ok(Some(2)));
            // The smallest ring is searched for too when it is all that is allowed.
            assert_eq!(min_ring(&loads, link, 2, 2), Ok(Some(2)));
            assert_eq!(min_ring(&loads, link, 2, 1), Ok(None));
        });
    }

    #[test]
    fn blocking_counts_below_the_largest_deadline() {
        promptly(|| {
            // Slave 1 has a deadline of 10 = one item time; an item for slave 0 may have just
            // started, so 10 + 9 > 10.
            let loads = [Load { t0: 1000, ring: 10 }, Load { t0: 10, ring: 2 }];
            let link = LinkSpec {
                item_time: 10,
                latency: 0,
            };
            assert!(matches!(
                check(&loads, link),
                Ok(Verdict::Overloaded { .. } | Verdict::DeadlineMiss { .. })
            ));
            let loads = [Load { t0: 1000, ring: 10 }, Load { t0: 40, ring: 2 }];
            assert_eq!(
                check(&loads, link),
                Ok(Verdict::Schedulable {
                    utilisation_ppm: 260_000
                })
            );
            let loads = [Load { t0: 1000, ring: 10 }, Load { t0: 18, ring: 2 }];
            assert_eq!(
                check(&loads, link),
                Ok(Verdict::DeadlineMiss {
                    interval: 18,
                    demand: 19
                })
            );
        });
    }

    #[test]
    fn errors_and_short_rings() {
        promptly(|| {
            assert_eq!(check(&[], LINK), Err(CapacityError::NoSlaves));
            assert_eq!(
                check(&[Load { t0: 0, ring: 4 }], LINK),
                Err(CapacityError::ZeroRate { slave: 0 })
            );
            assert_eq!(
                check(
                    &[Load { t0: 1, ring: 4 }],
                    LinkSpec {
                        item_time: 0,
                        latency: 0
                    }
                ),
                Err(CapacityError::ZeroItemTime)
            );
            assert_eq!(
                check(&[Load { t0: 100, ring: 1 }], LINK),
                Ok(Verdict::RingTooShort { slave: 0 })
            );
            assert_eq!(
                check(
                    &[Load { t0: 100, ring: 3 }],
                    LinkSpec {
                        item_time: 10,
                        latency: 150
                    }
                ),
                Ok(Verdict::RingTooShort { slave: 0 })
            );
            assert_eq!(
                check(
                    &[Load {
                        t0: u64::MAX,
                        ring: 3
                    }],
                    LINK
                ),
                Err(CapacityError::Overflow)
            );
            assert_eq!(
                min_ring(&[], LINK, 0, 10),
                Err(CapacityError::UnknownSlave(0))
            );
            let absurd = [
                Load { t0: 1, ring: 4 },
                Load {
                    t0: 1_000_000_000,
                    ring: 30_000,
                },
            ];
            assert!(matches!(
                check(
                    &absurd,
                    LinkSpec {
                        item_time: 1,
                        latency: 0
                    }
                ),
                Ok(Verdict::Overloaded { .. })
            ));
            let absurd = [
                Load { t0: 2, ring: 4 },
                Load {
                    t0: 1_000_000_000,
                    ring: 30_000,
                },
            ];
            assert!(matches!(
                check(
                    &absurd,
                    LinkSpec {
                        item_time: 1,
                        latency: 0
                    }
                ),
                Err(CapacityError::TooComplex { .. })
            ));
        });
    }

    #[test]
    fn demand_equal_to_the_interval_fits() {
        // At L = 19 the short-ringed slave's one item and the longest blocking (9) need exactly
        // 19: the link just makes it (the test is demand ≤ L). U = 1/100 + 10/19 = 0.5363157…,
        // reported rounded up.
        let loads = [Load { t0: 1000, ring: 10 }, Load { t0: 19, ring: 2 }];
        assert_eq!(
            check(&loads, LINK),
            Ok(Verdict::Schedulable {
                utilisation_ppm: 536_316
            })
        );
    }

    #[test]
    fn sums_past_128_bits_fall_back_to_the_rounded_up_utilisation() {
        // Three pairwise coprime periods near 3·2⁶²: the exact sum of C/Tᵢ needs a denominator
        // of ~2¹⁹⁰, so the 2⁻⁶⁴ fixed-point sum (each term rounded up) decides.
        let ts = [(3 << 62) + 1, (3 << 62) + 3, (3 << 62) - 1];
        let loads = ts.map(|t0| Load { t0, ring: 2 });
        // C = 2⁶²: the rounded-up sum is exactly 2⁶⁴ (U just below 1): accepted.
        let at_one = LinkSpec {
            item_time: 1 << 62,
            latency: 0,
        };
        assert_eq!(
            check(&loads, at_one),
            Ok(Verdict::Schedulable {
                utilisation_ppm: 1_000_000
            })
        );
        // C = 2⁶³: U just below 2 (1.99999999…, reported rounded up): overloaded.
        let at_two = LinkSpec {
            item_time: 1 << 63,
            latency: 0,
        };
        assert_eq!(
            check(&loads, at_two),
            Ok(Verdict::Overloaded {
                utilisation_ppm: 2_000_000
            })
        );
    }

    #[test]
    fn error_messages_name_the_problem() {
        let cases = [
            (CapacityError::NoSlaves, "no slaves to check"),
            (
                CapacityError::ZeroRate { slave: 3 },
                "slave 3: t0 must be at least 1",
            ),
            (CapacityError::ZeroItemTime, "item_time must be at least 1"),
            (CapacityError::UnknownSlave(7), "slave 7 is not in the set"),
            (
                CapacityError::Overflow,
                "a deadline does not fit in 64 bits",
            ),
            (
                CapacityError::TooComplex { points: 12 },
                "12 deadline points x slaves to check (at most 10000000)",
            ),
        ];
        for (error, message) in cases {
            assert_eq!(error.to_string(), message);
        }
    }
}
