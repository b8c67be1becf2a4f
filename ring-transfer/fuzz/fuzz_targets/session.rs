//! A master and a board on a link the fuzzer drives: it chooses which frame arrives next, which
//! is lost, repeated or held back for any time, when the board steps and when it reboots. Every
//! frame is genuine (built by the master or the board), so the checks are the crate's promises
//! at the level the plant meets them: an item labelled `Source::Master` is the master's item at
//! the stream index the board stands at; a rebooted board is placed at or before the furthest
//! point any earlier board reached (nothing skipped); a board never holds more than its ring.
//! At the end every frame still held back arrives (late frames of earlier starts among them),
//! then the link is clean: the board must be placed within `retry_after + 1` steps, the
//! master's session must be the board's start, and both must say linked within
//! `retry_after + 2·row_len + 2` steps, whatever happened before. Boot numbers increase by one
//! at every start (the firmware's rule), up to 121 starts (inside the window of 128 in which
//! `link::newer_boot` orders them).
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_ring_transfer::{
    Master, Refill, ReportOutcome, Slave, SlaveConfig, SlaveParams, Source, link,
};

const RING: usize = 8;

fn stream(k: u64) -> u8 {
    (k.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 56) as u8 % 251
}

fn extend(known: u64, wire: u16) -> u64 {
    let diff = wire.wrapping_sub(known as u16) as i16;
    known.wrapping_add_signed(i64::from(diff))
}

fn config(boot: u8) -> SlaveConfig {
    SlaveConfig {
        address: 2,
        row_len: 3,
        silence_limit: 5,
        retry_after: 2,
        boot,
    }
}

fuzz_target!(|data: &[u8]| {
    let mut boot = 1u8;
    let mut slave: Slave<RING> = Slave::new(config(boot)).expect("valid");
    let mut master: Master<1> = Master::new();
    master
        .attach(
            0,
            SlaveParams {
                capacity: RING as u16,
                t0: 1,
            },
        )
        .expect("valid");
    let mut up: Vec<Vec<u8>> = Vec::new();
    let mut down: Vec<Vec<u8>> = Vec::new();
    let mut frame = [0u8; link::MAX_FRAME];
    let mut items = [0u8; link::MAX_REFILL];
    let (mut now, mut abs, mut furthest) = (0u64, 0u64, 0u64);
    let mut bytes = data.iter().copied();
    while let Some(op) = bytes.next() {
        let arg = usize::from(bytes.next().unwrap_or(0));
        match op % 8 {
            0 => {
                now += 1;
                let placed = slave.placed();
                let out = slave.step(|_, col| 251 + col as u8);
                match out.source {
                    Source::Master => {
                        assert!(placed);
                        assert_eq!(out.item, stream(abs), "index {abs}");
                    }
                    _ => assert_eq!(out.item, 251 + out.col as u8),
                }
                if placed && out.source != Source::Local {
                    abs += 1;
                    furthest = furthest.max(abs);
                }
                assert!(slave.slack() <= RING);
                if let Some(r) = slave.poll_report() {
                    let n = r.encode(&mut frame).expect("fits");
                    up.push(frame[..n].to_vec());
                }
            }
            1 if !up.is_empty() => {
                let f = up.remove(arg % up.len());
                let Ok(link::Message::Report(r)) = link::decode(&f) else {
                    panic!("a genuine report decodes");
                };
                let outcome = master.on_report(now, 0, &r).expect("attached");
                if outcome == (ReportOutcome::Accepted { owed: 0 }) {
                    let n = Refill::keep_alive(2).encode(&mut frame).expect("fits");
                    down.push(frame[..n].to_vec());
                }
                let batch = u32::from(bytes.next().unwrap_or(0) % 16) + 1;
                while let Some(g) = master.next_refill(now, batch) {
                    let n = g.count as usize;
                    for (k, item) in items[..n].iter_mut().enumerate() {
                        *item = stream(g.first + k as u64);
                    }
                    let len = g.refill(2, &items[..n]).encode(&mut frame).expect("fits");
                    down.push(frame[..len].to_vec());
                }
                assert!(master.status(0).expect("attached").owed <= RING as u32);
            }
            2 if !down.is_empty() => {
                let f = down.remove(arg % down.len());
                let was_placed = slave.placed();
                slave.on_frame(&f).expect("a genuine refill for this board");
                if !was_placed && slave.placed() {
                    abs = extend(
                        master.status(0).expect("attached").consumed,
                        slave.report(false).consumed,
                    );
                    assert!(
                        abs <= furthest,
                        "placed at {abs}, beyond {furthest}: items skipped"
                    );
                }
            }
            3 if !up.is_empty() => {
                up.remove(arg % up.len());
            }
            4 if !down.is_empty() => {
                down.remove(arg % down.len());
            }
            5 if !up.is_empty() => {
                let f = up[arg % up.len()].clone();
                up.push(f);
            }
            6 if !down.is_empty() => {
                let f = down[arg % down.len()].clone();
                down.push(f);
            }
            7 if boot < 121 => {
                boot += 1;
                slave = Slave::new(config(boot)).expect("valid");
            }
            _ => {}
        }
        // Keep the queues short: a frame held back for ever is a frame lost.
        up.truncate(64);
        down.truncate(256);
    }
    // Everything still on the link arrives, in the order the fuzzer left it.
    let mut serve = |master: &mut Master<1>, slave: &mut Slave<RING>, now: u64, r: &link::Report| {
        let outcome = master.on_report(now, 0, r).expect("attached");
        let mut frames = Vec::new();
        if outcome == (ReportOutcome::Accepted { owed: 0 }) {
            let n = Refill::keep_alive(2).encode(&mut frame).expect("fits");
            frames.push(frame[..n].to_vec());
        }
        while let Some(g) = master.next_refill(now, link::MAX_REFILL as u32) {
            let n = g.count as usize;
            for (k, item) in items[..n].iter_mut().enumerate() {
                *item = stream(g.first + k as u64);
            }
            let len = g.refill(2, &items[..n]).encode(&mut frame).expect("fits");
            frames.push(frame[..len].to_vec());
        }
        for f in frames {
            let was_placed = slave.placed();
            slave.on_frame(&f).expect("a genuine refill for this board");
            if !was_placed && slave.placed() {
                return Some(extend(
                    master.status(0).expect("attached").consumed,
                    slave.report(false).consumed,
                ));
            }
        }
        None
    };
    for f in up.drain(..) {
        let Ok(link::Message::Report(r)) = link::decode(&f) else {
            panic!("a genuine report decodes");
        };
        if let Some(at) = serve(&mut master, &mut slave, now, &r) {
            abs = at;
            assert!(abs <= furthest, "placed at {abs}, beyond {furthest}");
        }
    }
    for f in down.drain(..) {
        let was_placed = slave.placed();
        slave.on_frame(&f).expect("a genuine refill for this board");
        if !was_placed && slave.placed() {
            abs = extend(
                master.status(0).expect("attached").consumed,
                slave.report(false).consumed,
            );
            assert!(abs <= furthest, "placed at {abs}, beyond {furthest}");
        }
    }
    // A clean link (every frame delivered at once) from here.
    let c = config(boot);
    let placed_by = u64::from(c.retry_after) + 1;
    let linked_by = u64::from(c.retry_after) + 2 * u64::from(c.row_len) + 2;
    for step in 1..=linked_by {
        now += 1;
        let placed = slave.placed();
        let out = slave.step(|_, col| 251 + col as u8);
        match out.source {
            Source::Master => assert_eq!(out.item, stream(abs), "index {abs}"),
            _ => assert_eq!(out.item, 251 + out.col as u8),
        }
        if placed && out.source != Source::Local {
            abs += 1;
            furthest = furthest.max(abs);
        }
        if let Some(r) = slave.poll_report()
            && let Some(at) = serve(&mut master, &mut slave, now, &r)
        {
            abs = at;
            assert!(abs <= furthest, "placed at {abs}, beyond {furthest}");
        }
        if step == placed_by {
            assert!(slave.placed(), "not placed {placed_by} clean steps after the faults");
        }
    }
    let status = master.status(0).expect("attached");
    assert_eq!(status.boot, slave.boot(), "the master serves another start");
    assert!(status.linked, "the master does not say linked: {status:?}");
    assert_eq!(slave.mode(), regler_ring_transfer::Mode::Linked, "the board is not linked");
});
