//! `max_slaves` and `min_ring` against the obvious linear scans, the monotonicity the binary
//! search relies on, and limits up to the integers' maximum answered at once.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "a test may panic: that is how it fails"
)]

mod promptly;

use std::time::{Duration, Instant};

use promptly::promptly;
use proptest::prelude::*;
use regler_ring_transfer::capacity::{self, CapacityError, LinkSpec, Load, Verdict};

fn schedulable(loads: &[Load], link: LinkSpec) -> Result<bool, CapacityError> {
    Ok(capacity::check(loads, link)?.is_schedulable())
}

fn with_ring(loads: &[Load], slave: usize, ring: u32) -> Vec<Load> {
    let mut v = loads.to_vec();
    v[slave].ring = ring;
    v
}

fn sets() -> impl Strategy<Value = (Vec<Load>, LinkSpec)> {
    (1usize..5, 1u64..30, 0u64..60).prop_flat_map(|(n, item_time, latency)| {
        (
            proptest::collection::vec(
                (5u64..200, 2u32..40).prop_map(|(t0, ring)| Load { t0, ring }),
                n,
            ),
            Just(LinkSpec { item_time, latency }),
        )
    })
}

// One case under Miri: a case runs dozens of capacity checks (128-bit arithmetic, interpreted).
proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 1 } else { 300 }))]

    /// The largest n ≤ limit whose n copies pass `check`, found by scanning every n.
    #[test]
    fn max_slaves_is_the_linear_scan(
        t0 in 1u64..300, ring in 1u32..12, item_time in 1u64..60, latency in 0u64..200, limit in 0usize..40,
    ) {
        let load = Load { t0, ring };
        let link = LinkSpec { item_time, latency };
        let mut model = 0;
        for n in 1..=limit {
            if schedulable(&vec![load; n], link).unwrap() {
                model = n;
            }
        }
        prop_assert_eq!(capacity::max_slaves(load, link, limit), Ok(model));
    }

    /// A ring one slot longer never turns a schedulable set into a refused one.
    #[test]
    fn a_longer_ring_never_hurts((loads, link) in sets(), pick in any::<prop::sample::Index>(), ring in 2u32..120) {
        let slave = pick.index(loads.len());
        let shorter = schedulable(&with_ring(&loads, slave, ring), link).unwrap();
        let longer = schedulable(&with_ring(&loads, slave, ring + 1), link).unwrap();
        prop_assert!(!shorter || longer, "{:?} {:?} slave {} ring {}", loads, link, slave, ring);
    }

    /// The utilisation a verdict reports is Σ C/Tᵢ in parts per million, rounded up (it was
    /// rounded down: 0.5363157… was reported as 536 315 ppm).
    #[test]
    fn the_utilisation_is_the_exact_sum_rounded_up((loads, link) in sets()) {
        let (mut num, mut den) = (0u128, 1u128);
        for l in &loads {
            num = num * u128::from(l.t0) + u128::from(link.item_time) * den;
            den *= u128::from(l.t0);
        }
        let want = (num * 1_000_000).div_ceil(den) as u64;
        match capacity::check(&loads, link).unwrap() {
            Verdict::Schedulable { utilisation_ppm } | Verdict::Overloaded { utilisation_ppm } => {
                prop_assert_eq!(utilisation_ppm, want, "{:?} {:?}", loads, link);
            }
            _ => {}
        }
    }

    /// The smallest ring in 2..=max_ring that passes `check`, found by scanning every ring.
    #[test]
    fn min_ring_is_the_linear_scan((loads, link) in sets(), pick in any::<prop::sample::Index>(), max_ring in 0u32..150) {
        let slave = pick.index(loads.len());
        let model = (2..=max_ring).find(|&r| schedulable(&with_ring(&loads, slave, r), link).unwrap());
        let search = loads.clone();
        let found = promptly(move || capacity::min_ring(&search, link, slave, max_ring));
        prop_assert_eq!(found, Ok(model));
    }
}

/// The largest limits return at once (the search was linear in the limit: 1.4 s for 10⁷,
/// `usize::MAX` never).
#[test]
#[cfg_attr(
    miri,
    ignore = "times capacity checks at the largest limits against the wall clock (2 s): an interpreter is hundreds of times slower; runs natively in every CI run"
)]
fn the_largest_limits_return_at_once() {
    let started = Instant::now();
    let link = LinkSpec {
        item_time: 1,
        latency: 0,
    };
    let load = Load {
        t0: u64::MAX / 4,
        ring: 2,
    };
    let most = capacity::max_slaves(load, link, usize::MAX).unwrap();
    assert_eq!(most as u64, u64::MAX / 4);
    assert_eq!(capacity::max_slaves(load, link, 10_000_000), Ok(10_000_000));
    // No ring fits (the link is overloaded): every ring up to u32::MAX is "searched".
    let overloaded = [Load { t0: 10, ring: 4 }; 2];
    let slow = LinkSpec {
        item_time: 6,
        latency: 0,
    };
    assert_eq!(
        promptly(move || capacity::min_ring(&overloaded, slow, 0, u32::MAX)),
        Ok(None)
    );
    // A ring that fits only far up: the slave's deadline must cover a long latency.
    let far = [Load { t0: 1, ring: 2 }];
    let late = LinkSpec {
        item_time: 1,
        latency: 3_000_000_000,
    };
    assert_eq!(
        promptly(move || capacity::min_ring(&far, late, 0, u32::MAX)),
        Ok(Some(3_000_000_002))
    );
    assert!(
        started.elapsed() < Duration::from_secs(2),
        "{:?}",
        started.elapsed()
    );
}
