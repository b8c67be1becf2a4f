//! Arbitrary bytes as link frames: the decoder, a slave taking them, and a master taking the
//! reports among them. No panic; a frame that decodes encodes back to the same bytes; the
//! slave's ring never holds more than its capacity and its reports say so; a non-master item is
//! the local pattern's, and a master item comes only from a slave a sync refill placed; the
//! master never owes more than the ring holds, ignores a report of another boot than its
//! session's and a hello of an earlier start (changing nothing but the count of stale reports)
//! and answers it with a session offer, and resumes a session started by a hello of the same
//! or a later start where the newest report left it.
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_ring_transfer::{
    Master, Message, ReportOutcome, Slave, SlaveConfig, SlaveParams, Source, decode, link,
    link::newer_boot,
};

fn link_status(
    status: regler_ring_transfer::SlaveStatus,
    stale_reports: u32,
) -> regler_ring_transfer::SlaveStatus {
    regler_ring_transfer::SlaveStatus {
        stale_reports,
        ..status
    }
}

fuzz_target!(|data: &[u8]| {
    let Ok(mut slave) = Slave::<16>::new(SlaveConfig {
        address: 1,
        row_len: 5,
        silence_limit: 8,
        retry_after: 3,
        boot: 1,
    }) else {
        return;
    };
    let mut master: Master<2> = Master::new();
    if master
        .attach(
            1,
            SlaveParams {
                capacity: 16,
                t0: 3,
            },
        )
        .is_err()
    {
        return;
    }
    let mut buf = [0u8; link::MAX_FRAME];
    // Frames are length-prefixed in the input: [len, bytes...]*
    let mut rest = data;
    let mut now = 0u64;
    while let Some((&len, tail)) = rest.split_first() {
        let len = usize::from(len).min(tail.len());
        let (frame, tail) = tail.split_at(len);
        rest = tail;
        now += 1;
        match decode(frame) {
            Ok(Message::Report(report)) => {
                let n = report.encode(&mut buf).expect("a report fits");
                assert_eq!(&buf[..n], frame, "report re-encodes");
                let before = master.status(1).expect("attached");
                let outcome = master.on_report(now, 1, &report).expect("attached");
                let after = master.status(1).expect("attached");
                assert!(after.owed <= 16);
                let other_boot = before.reports > 0 && report.boot != before.boot;
                let ignored = other_boot && !(report.hello && newer_boot(report.boot, before.boot));
                if ignored {
                    assert_eq!(outcome, ReportOutcome::Stale, "a report of another start");
                    let stale_reports = before.stale_reports + 1;
                    assert_eq!(after.stale_reports, stale_reports);
                    assert_eq!(after, link_status(before, stale_reports));
                    let offer = master.next_refill(now, 4).expect("an offer");
                    assert_eq!((offer.count, offer.sync, offer.boot), (0, true, before.boot));
                } else if report.hello {
                    assert!(!after.linked);
                    assert_eq!(after.consumed, before.consumed, "resumes where it was");
                    assert_eq!(
                        (after.received, after.sent),
                        (after.consumed, after.consumed)
                    );
                }
                let _ = master.next_refill(now, 4);
            }
            Ok(Message::Refill(refill)) => {
                let n = refill.encode(&mut buf).expect("a decoded refill fits");
                assert_eq!(&buf[..n], frame, "refill re-encodes");
            }
            Err(_) => {}
        }
        let _ = slave.on_frame(frame);
        assert!(slave.slack() <= 16);
        let placed = slave.placed();
        let out = slave.step(|_, col| 0xF0 | col as u8);
        if out.source == Source::Master {
            assert!(placed, "a master item from a slave no sync placed");
        }
        // A step from the ring shrinks it; any other source leaves it alone.
        if out.source != Source::Master {
            assert_eq!(out.item, 0xF0 | out.col as u8);
        }
        if let Some(report) = slave.poll_report() {
            // What the slave says of itself is consistent: it never reports more held than
            // its ring has slots.
            let held = report.received.wrapping_sub(report.consumed);
            assert!(usize::from(held) <= 16, "held {held}");
        }
    }
});
