//! The configuration, statistics and report types round-trip through serde (here: JSON), so a
//! master can log them and a board can keep its configuration in flash.
#![allow(clippy::unwrap_used, reason = "a test may panic: that is how it fails")]
#![cfg(feature = "serde")]

use regler_ring_transfer::capacity::{LinkSpec, Load, Verdict, check};
use regler_ring_transfer::{Master, Report, Ring, SlaveConfig, SlaveParams, SlaveStatus, Stats};

#[test]
fn value_types_round_trip() {
    let config = SlaveConfig {
        address: 4,
        row_len: 200,
        silence_limit: 100,
        retry_after: 16,
        boot: 200,
    };
    let back: SlaveConfig = serde_json::from_str(&serde_json::to_string(&config).unwrap()).unwrap();
    assert_eq!(back, config);

    let report = Report {
        slave: 4,
        consumed: 65_535,
        received: 7,
        standalone: true,
        retry: false,
        boot: 3,
        hello: true,
    };
    let back: Report = serde_json::from_str(&serde_json::to_string(&report).unwrap()).unwrap();
    assert_eq!(back, report);

    let mut ring: Ring<u8, 4> = Ring::new();
    ring.receive(1).unwrap();
    ring.next();
    ring.next();
    let stats = ring.stats();
    let back: Stats = serde_json::from_str(&serde_json::to_string(&stats).unwrap()).unwrap();
    assert_eq!(back, stats);

    let mut master: Master<2> = Master::new();
    master
        .attach(1, SlaveParams { capacity: 8, t0: 5 })
        .unwrap();
    master
        .on_report(
            3,
            1,
            &Report {
                slave: 1,
                consumed: 0,
                received: 0,
                standalone: false,
                retry: false,
                boot: 9,
                hello: false,
            },
        )
        .unwrap();
    let status = master.status(1).unwrap();
    let back: SlaveStatus = serde_json::from_str(&serde_json::to_string(&status).unwrap()).unwrap();
    assert_eq!(back, status);

    let verdict = check(
        &[Load { t0: 100, ring: 8 }; 3],
        LinkSpec {
            item_time: 10,
            latency: 0,
        },
    )
    .unwrap();
    let back: Verdict = serde_json::from_str(&serde_json::to_string(&verdict).unwrap()).unwrap();
    assert_eq!(back, verdict);
}
