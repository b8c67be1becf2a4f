//! Arbitrary frames at the master's end of the link: a master of four slave places (three
//! attached, rings of 1, 5 and 300 slots, one place left empty) takes whatever decodes as a
//! report, for the slave the report's address names (addresses past the places included),
//! and the input decides when the scheduler is asked for a refill and with what batch.
//!
//! Checked, from the master's documentation:
//! - a report for a place beyond the master or not attached is refused and changes nothing;
//! - the master never owes more than the slave's ring holds, owes exactly what the newest report
//!   leaves room for (`consumed + capacity − sent`), and says so in `Accepted { owed }`; the
//!   consumed count never goes back (older reports are stale);
//! - a report ignored as stale changes nothing but the count of stale reports; a report of
//!   another boot than the session's, but a hello of a later start, is ignored so;
//! - a grant is a session offer (no items, sync, the session's boot, nothing sent) or
//!   1..=min(batch, owed) items starting exactly where the last grant to that slave ended.
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_ring_transfer::{
    Master, MasterError, Message, ReportOutcome, SlaveParams, SlaveStatus, decode, link::newer_boot,
};

const CAPACITY: [u16; 4] = [1, 5, 300, 0];

fn statuses(master: &Master<4>) -> Vec<Result<SlaveStatus, MasterError>> {
    (0..5).map(|s| master.status(s)).collect()
}

fn owed_by_rule(s: &SlaveStatus, slave: usize) -> u32 {
    let room = s.consumed + u64::from(CAPACITY[slave]);
    u32::try_from(room.saturating_sub(s.sent)).unwrap_or(u32::MAX)
}

fuzz_target!(|data: &[u8]| {
    let mut master: Master<4> = Master::new();
    for (slave, &capacity) in CAPACITY.iter().enumerate().take(3) {
        master
            .attach(
                slave,
                SlaveParams {
                    capacity,
                    t0: 1 + slave as u32 * 7,
                },
            )
            .unwrap();
    }
    let mut rest = data;
    let mut now = 0u64;
    while let Some((&head, tail)) = rest.split_first() {
        now += u64::from(head >> 4);
        if head & 1 == 1 {
            // Ask the scheduler.
            let batch = u32::from(head >> 1 & 7);
            let before = statuses(&master);
            match master.next_refill(now, batch) {
                None => {}
                Some(g) => {
                    let Ok(was) = before[g.slave] else {
                        panic!("a grant for place {}", g.slave)
                    };
                    let after = master.status(g.slave).unwrap();
                    if g.count == 0 {
                        assert!(g.sync && g.boot == was.boot, "{g:?}");
                        assert_eq!(after.sent, was.sent, "an offer sent items");
                    } else {
                        assert!(
                            g.count <= batch.max(1) && g.count <= was.owed,
                            "{g:?} of {was:?}"
                        );
                        assert_eq!(g.first, was.sent, "a grant not where the last ended");
                        assert_eq!(after.sent, was.sent + u64::from(g.count));
                    }
                    for (s, st) in statuses(&master).iter().enumerate() {
                        if s != g.slave {
                            assert_eq!(*st, before[s], "a grant to {} changed {s}", g.slave);
                        }
                    }
                }
            }
            rest = tail;
            continue;
        }
        // A frame: [len, bytes…].
        let Some((&len, tail)) = tail.split_first() else {
            break;
        };
        let len = usize::from(len).min(tail.len());
        let (frame, tail) = tail.split_at(len);
        rest = tail;
        let Ok(Message::Report(report)) = decode(frame) else {
            continue;
        };
        let slave = usize::from(report.slave % 5);
        let before = statuses(&master);
        let outcome = master.on_report(now, slave, &report);
        let after = statuses(&master);
        let Ok(was) = before[slave] else {
            assert!(outcome.is_err(), "a report for place {slave} taken");
            assert_eq!(after, before, "a refused report changed something");
            continue;
        };
        for s in (0..5).filter(|&s| s != slave) {
            assert_eq!(after[s], before[s], "a report for {slave} changed {s}");
        }
        let now_status = after[slave].unwrap();
        let outcome = outcome.expect("an attached place");
        assert!(
            now_status.owed <= u32::from(CAPACITY[slave]),
            "{now_status:?}"
        );
        assert_eq!(
            now_status.owed,
            owed_by_rule(&now_status, slave),
            "{now_status:?}"
        );
        assert!(
            now_status.consumed >= was.consumed,
            "consumed went back: {was:?} → {now_status:?}"
        );
        let other_boot = was.reports > 0 && report.boot != was.boot;
        if other_boot && !(report.hello && newer_boot(report.boot, was.boot)) {
            assert_eq!(outcome, ReportOutcome::Stale, "{report:?} of another start");
        }
        match outcome {
            ReportOutcome::Accepted { owed } => assert_eq!(owed, now_status.owed),
            ReportOutcome::Stale => {
                let counted = SlaveStatus {
                    stale_reports: was.stale_reports + 1,
                    ..was
                };
                assert_eq!(
                    now_status, counted,
                    "a stale report changed more than its count"
                );
            }
        }
    }
});
