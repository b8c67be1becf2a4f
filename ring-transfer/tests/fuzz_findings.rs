//! Regression tests for what the fuzzing campaign (issue 22 §3, `scripts/fuzz`) found.
#![allow(
    clippy::unwrap_used,
    clippy::arithmetic_side_effects,
    reason = "a test may panic: that is how it fails"
)]

use proptest::prelude::{any, prop, prop_assert, prop_assert_eq, proptest};
use regler_ring_transfer::{Master, Report, ReportOutcome, SlaveParams};

proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(if cfg!(miri) { 4 } else { 256 }))]

    /// Any reports, genuine or not (consumed ahead of received, counters anywhere, retries,
    /// hellos, other boots), and any grants in between: the master never owes more than the
    /// ring holds, owes `consumed + capacity − sent` with `sent` never behind `consumed` (it
    /// sends nothing the slave has used), and every grant starts at or after `consumed`.
    /// (`fuzz_targets/decode.rs` found a report with consumed ahead of received that made the
    /// master owe more than the ring.)
    #[test]
    fn no_report_makes_the_master_owe_more_than_the_ring(
        capacity in 1u16..40,
        steps in prop::collection::vec(
            (any::<u16>(), any::<u16>(), any::<bool>(), any::<bool>(), 0u8..3, 0u32..12),
            1..40,
        ),
    ) {
        let mut m: Master<1> = Master::new();
        m.attach(0, SlaveParams { capacity, t0: 3 }).unwrap();
        for (k, &(consumed, received, retry, hello, boot, batch)) in steps.iter().enumerate() {
            let report = Report { slave: 0, consumed, received, standalone: false, retry, boot, hello };
            let outcome = m.on_report(k as u64, 0, &report).unwrap();
            let s = m.status(0).unwrap();
            prop_assert!(s.owed <= u32::from(capacity), "{s:?}");
            prop_assert!(s.sent >= s.consumed, "{s:?}");
            prop_assert_eq!(u64::from(s.owed), (s.consumed + u64::from(capacity)).saturating_sub(s.sent));
            if let ReportOutcome::Accepted { owed } = outcome {
                prop_assert_eq!(owed, s.owed);
            }
            if batch > 0
                && let Some(g) = m.next_refill(k as u64, batch)
            {
                prop_assert!(g.first >= s.consumed, "{g:?} after {s:?}");
                prop_assert!(g.count <= u32::from(capacity));
            }
        }
    }
}
