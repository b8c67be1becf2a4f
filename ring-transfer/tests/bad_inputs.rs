//! Bad inputs (issue 22 §5): every public constructor and operation of `regler-ring-transfer`
//! fed the extremes — rings of 1, 2, 3, 4 and 5 slots full and empty, NaN items, frames empty,
//! one byte long, one byte short and long, with a count of 65 and 255, reserved flags and a bad
//! CRC, buffers one byte short, counters at their 16-bit wrap, boot numbers over all 65 536
//! pairs, slave indices at `S` and `usize::MAX`, capacities 0, 32 768 and `u16::MAX`, rates 0
//! and MAX — with the exact error or documented result.
//!
//! Each test is a table: one row per (operation, extreme input, expected outcome). A refused
//! call is checked to have changed nothing.
#![allow(
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    clippy::type_complexity,
    clippy::float_cmp,
    reason = "a test may panic: that is how it fails"
)]

mod promptly;

use promptly::promptly;
use regler_ring_transfer::capacity::{
    CapacityError, LinkSpec, Load, Verdict, check, max_slaves, min_ring,
};
use regler_ring_transfer::link::{
    DecodeError, EncodeError, MAX_FRAME, MAX_REFILL, REPORT_LEN, crc16, newer_boot,
};
use regler_ring_transfer::{
    Counters, FrameError, Master, MasterError, Message, Refill, Report, ReportOutcome, Ring,
    SharedRing, Slave, SlaveConfig, SlaveConfigError, SlaveParams, Stats, decode,
};

/// A ring of `N` slots from empty to full and past, and through its slots' wrap: a full ring
/// hands the item back and changes nothing; an empty one counts an underrun and hands out
/// nothing (never the blank).
fn ring_at_its_ends<const N: usize>() {
    let mut ring: Ring<u8, N> = Ring::new();
    // (what, len, requests, slack, empty, full)
    let empty = (0, N, 0, true, false);
    let state = |r: &Ring<u8, N>| (r.len(), r.requests(), r.slack(), r.is_empty(), r.is_full());
    assert_eq!(state(&ring), empty, "Ring<{N}> new");
    assert_eq!(
        ring.stats(),
        Stats {
            underruns: 0,
            least_slack: N,
            most_requests: 0
        }
    );
    assert_eq!(
        (ring.deadline(0), ring.deadline(u32::MAX)),
        (0, 0),
        "Ring<{N}> empty deadline"
    );
    assert_eq!(ring.next(), None, "Ring<{N}> empty: an underrun");
    assert_eq!(
        ring.stats(),
        Stats {
            underruns: 1,
            least_slack: 0,
            most_requests: N
        }
    );
    ring.reset_stats();
    for k in 0..N {
        assert_eq!(ring.receive(k as u8), Ok(()), "Ring<{N}> item {k}");
    }
    assert_eq!(state(&ring), (N, 0, N, false, true), "Ring<{N}> full");
    assert_eq!(
        ring.deadline(u32::MAX),
        N as u64 * u64::from(u32::MAX),
        "Ring<{N}> full deadline, t0 MAX"
    );
    let counters = ring.counters();
    assert_eq!(ring.receive(0xEE), Err(0xEE), "Ring<{N}> full: handed back");
    assert_eq!(
        (ring.counters(), state(&ring)),
        (counters, (N, 0, N, false, true)),
        "a refused receive changed the ring"
    );
    // Through the wrap of the slots, several times: first in, first out.
    let mut expect = 0u8;
    let mut next_in = N as u8;
    for _ in 0..(3 * N + 7) {
        assert_eq!(ring.next(), Some(expect), "Ring<{N}> order");
        expect = expect.wrapping_add(1);
        assert_eq!(ring.receive(next_in), Ok(()));
        next_in = next_in.wrapping_add(1);
    }
    assert_eq!(ring.stats().least_slack, N - 1);
    ring.clear();
    assert_eq!(state(&ring), empty, "Ring<{N}> cleared");
    assert_eq!(
        ring.counters().received,
        ring.counters().consumed + N as u32,
        "clear drops, does not consume"
    );
    assert_eq!(ring.next(), None);
}

#[test]
fn rings_of_one_to_five_slots_at_their_ends() {
    ring_at_its_ends::<1>();
    ring_at_its_ends::<2>();
    ring_at_its_ends::<3>();
    ring_at_its_ends::<4>();
    ring_at_its_ends::<5>();
}

/// Items are carried as they are: NaN, −0.0 and the other float extremes come out bit for bit;
/// an `Option` item `None` comes out as `Some(None)`, never as an underrun.
#[test]
fn items_at_their_extremes_come_out_as_they_went_in() {
    let floats = [
        f32::NAN,
        -f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        -0.0,
        f32::from_bits(1),
        f32::MAX,
        f32::MIN,
    ];
    let mut ring: Ring<f32, 3> = Ring::new();
    for x in floats {
        ring.receive(x).unwrap();
        assert_eq!(ring.next().map(f32::to_bits), Some(x.to_bits()), "{x}");
    }
    let mut options: Ring<Option<u8>, 2> = Ring::new();
    options.receive(None).unwrap();
    options.receive(Some(u8::MAX)).unwrap();
    assert_eq!(
        (options.next(), options.next(), options.next()),
        (Some(None), Some(Some(255)), None)
    );
}

/// The split halves at 1 and 2 slots (`S` = 1 and 2; a ring of `S` holds `S`): full hands the
/// item back, empty counts an underrun.
#[test]
fn shared_rings_of_one_and_two_slots() {
    fn check<const S: usize>() {
        let mut shared: SharedRing<u8, S> = SharedRing::new();
        assert_eq!(shared.capacity(), S);
        let (mut filler, mut drainer) = shared.split();
        assert_eq!(drainer.next(), None);
        assert_eq!((drainer.underruns(), drainer.consumed()), (1, 0));
        assert_eq!((filler.requests(), filler.slack()), (S, 0));
        for k in 0..S {
            assert_eq!(filler.receive(k as u8), Ok(()));
        }
        assert_eq!(filler.receive(0xEE), Err(0xEE), "SharedRing<{S}> full");
        assert_eq!((filler.requests(), filler.slack()), (0, S));
        assert_eq!(
            filler.counters(),
            Counters {
                received: S as u32,
                consumed: 0
            }
        );
        for k in 0..S {
            assert_eq!(drainer.next(), Some(k as u8));
        }
        assert_eq!(drainer.next(), None);
        assert_eq!((drainer.underruns(), drainer.consumed()), (2, S as u32));
    }
    check::<1>();
    check::<2>();
}

fn report(consumed: u16, received: u16) -> Report {
    Report {
        slave: 1,
        consumed,
        received,
        standalone: false,
        retry: false,
        boot: 0,
        hello: false,
    }
}

/// A frame with a valid CRC over `body`.
fn sealed(body: &[u8]) -> Vec<u8> {
    let mut f = body.to_vec();
    f.extend_from_slice(&crc16(body).to_le_bytes());
    f
}

/// `decode` of every malformed frame shape: the first rule broken is the error.
#[test]
#[rustfmt::skip]
fn decode_at_the_extremes() {
    let mut good_report = [0u8; REPORT_LEN];
    report(u16::MAX, u16::MAX).encode(&mut good_report).unwrap();
    let mut bad_crc = good_report;
    bad_crc[2] ^= 1;
    let carried = u16::from_le_bytes([good_report[8], good_report[9]]);
    let mut full_refill = [0u8; MAX_FRAME];
    let items = [0xAB; MAX_REFILL];
    let n = Refill { slave: 255, first: u16::MAX, items: &items, boot: 255, sync: true }.encode(&mut full_refill).unwrap();
    assert_eq!(n, MAX_FRAME);
    let rows: Vec<(&str, Vec<u8>, Result<(), DecodeError>)> = vec![
        ("empty", vec![], Err(DecodeError::Empty)),
        ("tag 0x00", vec![0x00], Err(DecodeError::UnknownTag(0x00))),
        ("tag 0xFF", vec![0xFF; 10], Err(DecodeError::UnknownTag(0xFF))),
        ("report tag alone", vec![0xA5], Err(DecodeError::Length { expected: 10, got: 1 })),
        ("report one byte short", good_report[..9].to_vec(), Err(DecodeError::Length { expected: 10, got: 9 })),
        ("report one byte long", [&good_report[..], &[0]].concat(), Err(DecodeError::Length { expected: 10, got: 11 })),
        ("report, counters at u16::MAX", good_report.to_vec(), Ok(())),
        ("report, one bit flipped", bad_crc.to_vec(), Err(DecodeError::Checksum { carried, computed: crc16(&bad_crc[..8]) })),
        ("report, reserved flag 0x08", sealed(&[0xA5, 1, 0, 0, 0, 0, 0x08, 0]), Err(DecodeError::ReservedFlags(0x08))),
        ("report, every flag bit", sealed(&[0xA5, 1, 0, 0, 0, 0, 0xFF, 0]), Err(DecodeError::ReservedFlags(0xFF))),
        ("refill tag alone", vec![0x5A], Err(DecodeError::Length { expected: 9, got: 1 })),
        ("refill header short of its count", vec![0x5A, 1, 0, 0, 0, 0], Err(DecodeError::Length { expected: 9, got: 6 })),
        ("refill count 65", vec![0x5A, 1, 0, 0, 0, 0, 65], Err(DecodeError::TooManyItems(65))),
        ("refill count 255", vec![0x5A, 1, 0, 0, 0, 0, 255, 0, 0], Err(DecodeError::TooManyItems(255))),
        ("refill count 1, no item", sealed(&[0x5A, 1, 0, 0, 0, 0, 1]), Err(DecodeError::Length { expected: 10, got: 9 })),
        ("refill of 0 items", sealed(&[0x5A, 1, 0, 0, 0, 0, 0]), Ok(())),
        ("refill of 64 items, all fields at MAX", full_refill.to_vec(), Ok(())),
        ("refill of 64 items, one byte long", [&full_refill[..], &[0]].concat(), Err(DecodeError::Length { expected: MAX_FRAME, got: MAX_FRAME + 1 })),
        ("refill, reserved flag 0x02", sealed(&[0x5A, 1, 0, 0, 0x02, 0, 0]), Err(DecodeError::ReservedFlags(0x02))),
    ];
    for (what, frame, want) in rows {
        assert_eq!(decode(&frame).map(|_| ()), want, "{what}");
    }
    match decode(&full_refill) {
        Ok(Message::Refill(r)) => assert_eq!((r.slave, r.first, r.items.len(), r.boot, r.sync), (255, u16::MAX, 64, 255, true)),
        other => panic!("{other:?}"),
    }
    assert_eq!(decode(&good_report), Ok(Message::Report(report(u16::MAX, u16::MAX))));
    assert_eq!(crc16(&[]), 0xFFFF, "the CRC of nothing is the initial value");
}

/// `encode` into buffers of 0, one byte short, exactly, and longer; refills of 0, 64, 65 items.
#[test]
#[rustfmt::skip]
fn encode_at_the_extremes() {
    let r = report(0, 0);
    // (buffer length, result)
    let rows: [(usize, Result<usize, EncodeError>); 4] = [
        (0, Err(EncodeError::BufferTooSmall { needed: 10, got: 0 })),
        (9, Err(EncodeError::BufferTooSmall { needed: 10, got: 9 })),
        (10, Ok(10)),
        (11, Ok(10)),
    ];
    for (len, want) in rows {
        let mut out = vec![0x77; len];
        assert_eq!(r.encode(&mut out), want, "report into {len} bytes");
        if want.is_err() {
            assert!(out.iter().all(|&b| b == 0x77), "a refused encode wrote into the buffer");
        }
    }
    let items = [1u8; 65];
    // (items, buffer length, result)
    let rows: [(usize, usize, Result<usize, EncodeError>); 6] = [
        (0, 9, Ok(9)),
        (0, 8, Err(EncodeError::BufferTooSmall { needed: 9, got: 8 })),
        (64, MAX_FRAME, Ok(MAX_FRAME)),
        (64, MAX_FRAME - 1, Err(EncodeError::BufferTooSmall { needed: MAX_FRAME, got: MAX_FRAME - 1 })),
        (65, 200, Err(EncodeError::TooManyItems(65))),
        (65, 0, Err(EncodeError::TooManyItems(65))),
    ];
    for (n, len, want) in rows {
        let mut out = vec![0x77; len];
        let refill = Refill { slave: 1, first: 0, items: &items[..n], boot: 0, sync: false };
        assert_eq!(refill.encode(&mut out), want, "refill of {n} into {len} bytes");
        if want.is_err() {
            assert!(out.iter().all(|&b| b == 0x77), "a refused encode wrote into the buffer");
        }
    }
    assert_eq!(Refill::keep_alive(u8::MAX).items.len(), 0);
}

/// `newer_boot` over every pair of boot numbers (exhaustive): later exactly when 1..=127 ahead,
/// wrapping.
#[test]
fn newer_boot_over_every_pair() {
    // Every pair; under Miri every 7th candidate (the function has no unsafe code to check).
    let step = if cfg!(miri) { 7 } else { 1 };
    for candidate in (0..=u8::MAX).step_by(step) {
        for than in 0..=u8::MAX {
            let ahead = candidate.wrapping_sub(than);
            assert_eq!(
                newer_boot(candidate, than),
                (1..=127).contains(&ahead),
                "{candidate} vs {than}"
            );
        }
    }
}

fn config() -> SlaveConfig {
    SlaveConfig {
        address: 1,
        row_len: 4,
        silence_limit: 10,
        retry_after: 5,
        boot: 0,
    }
}

/// `Slave::new` with each field at 0, 1 and MAX and the drift sum at and one past its limit.
#[test]
#[rustfmt::skip]
fn slave_config_at_the_extremes() {
    let c = config();
    let drift = |s, r, n| Err(SlaveConfigError::Drift { silence_limit: s, row_len: r, capacity: n });
    // (what, config, Slave<4>::new)
    let rows: [(&str, SlaveConfig, Result<(), SlaveConfigError>); 9] = [
        ("good", c, Ok(())),
        ("row_len 0", SlaveConfig { row_len: 0, ..c }, Err(SlaveConfigError::ZeroRow)),
        ("silence_limit 0", SlaveConfig { silence_limit: 0, ..c }, Err(SlaveConfigError::ZeroSilenceLimit)),
        ("retry_after 0", SlaveConfig { retry_after: 0, ..c }, Err(SlaveConfigError::ZeroRetry)),
        ("all 1", SlaveConfig { row_len: 1, silence_limit: 1, retry_after: 1, ..c }, Ok(())),
        ("retry_after MAX, address and boot MAX", SlaveConfig { retry_after: u32::MAX, address: 255, boot: 255, ..c }, Ok(())),
        ("silence_limit MAX", SlaveConfig { silence_limit: u32::MAX, ..c }, drift(u32::MAX, 4, 4)),
        ("row_len MAX", SlaveConfig { row_len: u16::MAX, ..c }, drift(10, u16::MAX, 4)),
        ("drift sum 32 767 exactly", SlaveConfig { silence_limit: 32_767 - 4 - 4, ..c }, Ok(())),
    ];
    for (what, config, want) in rows {
        assert_eq!(Slave::<4>::new(config).map(|_| ()), want, "{what}");
    }
    assert_eq!(Slave::<4>::new(SlaveConfig { silence_limit: 32_767 - 4 - 4 + 1, ..config() }).map(|_| ()), drift(32_760, 4, 4), "drift sum one past");
    assert_eq!(Slave::<32_767>::new(SlaveConfig { silence_limit: 0, ..config() }).map(|_| ()), Err(SlaveConfigError::ZeroSilenceLimit));
    assert_eq!(Slave::<32_768>::new(config()).map(|_| ()), Err(SlaveConfigError::Capacity(32_768)));
    assert_eq!(Slave::<1>::new(SlaveConfig { silence_limit: 32_765, row_len: 1, ..config() }).map(|_| ()), Ok(()));
}

/// `Slave::on_frame` with every kind of bad frame: the error, and nothing changed but the count
/// of bad frames (damaged frames only).
#[test]
#[rustfmt::skip]
fn slave_frames_at_the_extremes() {
    let slave: Slave<4> = Slave::new(config()).unwrap();
    let mut report_frame = [0u8; REPORT_LEN];
    report(0, 0).encode(&mut report_frame).unwrap();
    let mut other = [0u8; 16];
    let n = Refill { slave: 2, first: 0, items: &[1, 2], boot: 0, sync: true }.encode(&mut other).unwrap();
    let mut damaged = other;
    damaged[3] ^= 0x80;
    // (what, frame, result, bad frames counted)
    let rows: Vec<(&str, Vec<u8>, Result<usize, FrameError>, u32)> = vec![
        ("empty", vec![], Err(FrameError::Decode(DecodeError::Empty)), 1),
        ("one byte", vec![0x5A], Err(FrameError::Decode(DecodeError::Length { expected: 9, got: 1 })), 1),
        ("damaged", damaged[..n].to_vec(), Err(FrameError::Decode(decode(&damaged[..n]).unwrap_err())), 1),
        ("for another slave", other[..n].to_vec(), Err(FrameError::NotForMe(2)), 0),
        ("a report", report_frame.to_vec(), Err(FrameError::NotARefill), 0),
        ("a keep-alive before being placed", {
            let mut f = [0u8; 9];
            Refill::keep_alive(1).encode(&mut f).unwrap();
            f.to_vec()
        }, Ok(0), 0),
    ];
    for (what, frame, want, bad) in rows {
        let mut s = slave.clone();
        let r = s.on_frame(&frame);
        assert_eq!(r, want, "{what}");
        assert_eq!(s.stats().bad_frames, bad, "{what}");
        if r.is_err() {
            let mut expect = format!("{slave:?}");
            if bad > 0 {
                expect = expect.replace("bad_frames: 0", "bad_frames: 1");
            }
            assert_eq!(format!("{s:?}"), expect, "{what}: a refused frame changed the slave");
        }
    }
}

/// The master at `S` = 1 and 2: slave indices at `S` and `usize::MAX`, capacities 0, 1,
/// 32 767, 32 768 and `u16::MAX`, rates 0, 1 and MAX; calls on a slave not attached. A refused
/// call changes nothing.
#[test]
#[rustfmt::skip]
fn master_at_the_extremes() {
    fn check<const S: usize>() {
        let p = |capacity, t0| SlaveParams { capacity, t0 };
        // (what, slave, params, result)
        let rows: [(&str, usize, SlaveParams, Result<(), MasterError>); 9] = [
            ("slave S", S, p(4, 10), Err(MasterError::UnknownSlave(S))),
            ("slave usize::MAX", usize::MAX, p(4, 10), Err(MasterError::UnknownSlave(usize::MAX))),
            ("capacity 0", 0, p(0, 10), Err(MasterError::Capacity(0))),
            ("capacity 32 768", 0, p(32_768, 10), Err(MasterError::Capacity(32_768))),
            ("capacity u16::MAX", 0, p(u16::MAX, 10), Err(MasterError::Capacity(u16::MAX))),
            ("t0 0", 0, p(4, 0), Err(MasterError::ZeroRate)),
            ("capacity 1, t0 1", 0, p(1, 1), Ok(())),
            ("capacity 32 767, t0 MAX", S - 1, p(32_767, u32::MAX), Ok(())),
            ("re-attach", 0, p(4, 10), Ok(())),
        ];
        let mut m: Master<S> = Master::new();
        for (what, slave, params, want) in rows {
            let before = (m.attached(), (0..S).map(|i| m.status(i)).collect::<Vec<_>>());
            let r = m.attach(slave, params);
            assert_eq!(r, want, "Master<{S}>::attach {what}");
            if r.is_err() {
                assert_eq!((m.attached(), (0..S).map(|i| m.status(i)).collect::<Vec<_>>()), before, "{what}");
            }
        }
        assert_eq!(m.attached(), S.min(2));
        // Calls on slaves out of range and not attached.
        let mut fresh: Master<S> = Master::new();
        let r = report(0, 0);
        assert_eq!(fresh.on_report(0, 0, &r), Err(MasterError::NotAttached(0)));
        assert_eq!(fresh.on_report(0, S, &r), Err(MasterError::UnknownSlave(S)));
        assert_eq!(fresh.reinit(0), Err(MasterError::NotAttached(0)));
        assert_eq!(fresh.reinit(usize::MAX), Err(MasterError::UnknownSlave(usize::MAX)));
        assert_eq!(fresh.detach(0), Ok(()), "detaching a slave never attached is harmless");
        assert_eq!(fresh.detach(S), Err(MasterError::UnknownSlave(S)));
        assert_eq!(fresh.status(0), Err(MasterError::NotAttached(0)));
        assert_eq!((fresh.next_refill(u64::MAX, u32::MAX), fresh.earliest()), (None, None), "nothing attached, nothing owed");
        // After detach: not attached again.
        m.detach(0).unwrap();
        assert_eq!(m.status(0), Err(MasterError::NotAttached(0)));
        assert_eq!(m.on_report(0, 0, &r), Err(MasterError::NotAttached(0)));
    }
    check::<1>();
    check::<2>();
}

/// What the master owes over a sequence of reports does not depend on where the 16-bit
/// counters stand: the same reports shifted to straddle the wrap at 65 535 → 0 give the same
/// outcomes and grants (relative to the start), at `now` 0 and near `u64::MAX`.
#[test]
#[rustfmt::skip]
fn master_counters_across_their_wrap() {
    fn run(offset: u16, now0: u64) -> Vec<(ReportOutcome, Option<(u64, u32, bool)>)> {
        let mut m: Master<1> = Master::new();
        m.attach(0, SlaveParams { capacity: 8, t0: 10 }).unwrap();
        // (consumed, received) relative to the offset
        let steps: [(u16, u16); 6] = [(0, 8), (3, 8), (3, 11), (9, 11), (9, 17), (17, 25)];
        let mut out = Vec::new();
        let mut base = None;
        for (k, (c, r)) in steps.into_iter().enumerate() {
            let now = now0.saturating_add(k as u64 * 10);
            let outcome = m.on_report(now, 0, &report(c.wrapping_add(offset), r.wrapping_add(offset))).unwrap();
            let grant = m.next_refill(now, 64).map(|g| {
                let b = *base.get_or_insert(g.first.wrapping_sub(u64::from(8u16)));
                (g.first.wrapping_sub(b), g.count, g.late)
            });
            out.push((outcome, grant));
        }
        out
    }
    let reference = run(0, 0);
    for offset in [u16::MAX - 2, u16::MAX, 1 << 15] {
        assert_eq!(run(offset, 0), reference, "offset {offset}");
    }
    let late = run(u16::MAX - 2, u64::MAX - 100);
    assert_eq!(late.iter().map(|(o, g)| (*o, g.map(|g| (g.0, g.1)))).collect::<Vec<_>>(),
               reference.iter().map(|(o, g)| (*o, g.map(|g| (g.0, g.1)))).collect::<Vec<_>>(), "now near u64::MAX");
    // A report older than the newest (behind by one, and by 32 768) is stale.
    let mut m: Master<1> = Master::new();
    m.attach(0, SlaveParams { capacity: 8, t0: 10 }).unwrap();
    m.on_report(0, 0, &report(5, 5)).unwrap();
    m.on_report(1, 0, &report(6, 13)).unwrap();
    assert_eq!(m.on_report(2, 0, &report(5, 13)), Ok(ReportOutcome::Stale), "one behind");
    assert_eq!(m.on_report(3, 0, &report(6u16.wrapping_sub(1 << 15), 13)), Ok(ReportOutcome::Stale), "half the range behind");
}

/// The capacity check: no slaves, zero rates and item times, rings of 0, 1 and `u32::MAX`,
/// times at `u64::MAX`, an unknown slave, limits 0 and 1.
#[test]
#[rustfmt::skip]
fn capacity_check_at_the_extremes() {
    let link = LinkSpec { item_time: 10, latency: 100 };
    let load = |t0, ring| Load { t0, ring };
    let ok = |r: Result<Verdict, CapacityError>| r.map(|v| core::mem::discriminant(&v));
    let schedulable = ok(Ok(Verdict::Schedulable { utilisation_ppm: 0 }));
    // (what, loads, link, result: Err, or the verdict's variant)
    let rows: Vec<(&str, Vec<Load>, LinkSpec, Result<core::mem::Discriminant<Verdict>, CapacityError>)> = vec![
        ("no slaves", vec![], link, Err(CapacityError::NoSlaves)),
        ("t0 0", vec![load(1000, 8), load(0, 8)], link, Err(CapacityError::ZeroRate { slave: 1 })),
        ("item_time 0", vec![load(1000, 8)], LinkSpec { item_time: 0, ..link }, Err(CapacityError::ZeroItemTime)),
        ("one slave, ring 8", vec![load(1000, 8)], link, schedulable),
        ("t0 MAX, ring MAX", vec![load(u64::MAX, u32::MAX)], link, Err(CapacityError::Overflow)),
        ("latency MAX", vec![load(1000, 8)], LinkSpec { latency: u64::MAX, ..link }, ok(Ok(Verdict::RingTooShort { slave: 0 }))),
        ("item_time MAX", vec![load(1000, 8)], LinkSpec { item_time: u64::MAX, ..link }, ok(Ok(Verdict::Overloaded { utilisation_ppm: 0 }))),
    ];
    for (what, loads, link, want) in rows {
        assert_eq!(ok(check(&loads, link)), want, "check: {what}");
    }
    // Rings of 0 and 1 leave no time at all: refused by name (the slave).
    for ring in [0, 1] {
        assert!(matches!(check(&[load(1000, ring)], link), Ok(Verdict::RingTooShort { slave: 0, .. })), "ring {ring}");
    }
    // min_ring: (slave, max_ring, result)
    let set = [load(1000, 8), load(2000, 8)];
    let rows: [(usize, u32, Result<Option<u32>, CapacityError>); 7] = [
        (2, 100, Err(CapacityError::UnknownSlave(2))),
        (usize::MAX, 100, Err(CapacityError::UnknownSlave(usize::MAX))),
        (0, 0, Ok(None)),
        (0, 1, Ok(None)),
        (0, 2, Ok(None)),
        (0, 3, Ok(Some(3))),
        (0, u32::MAX, Ok(Some(3))),
    ];
    for (slave, max_ring, want) in rows {
        // A search that never ends is a failure, not a hang (`promptly`).
        assert_eq!(promptly(move || min_ring(&set, link, slave, max_ring)), want, "min_ring slave {slave}, max {max_ring}");
    }
    // max_slaves: (limit, result)
    for (limit, want) in [(0, Ok(0)), (1, Ok(1))] {
        assert_eq!(max_slaves(load(1000, 8), link, limit), want, "max_slaves limit {limit}");
    }
    assert_eq!(max_slaves(load(0, 8), link, 5), Err(CapacityError::ZeroRate { slave: 0 }));
}

proptest::proptest! {
    /// The first report after attach (or reinit) is read the same wherever the slave's 16-bit
    /// counters stand: for any offset, ring size and fill level, the master owes exactly the
    /// ring's free slots (never more than its capacity) and its first grant starts at the slave's
    /// `received` count. Before the fix a pair straddling the wrap (received past 65 535,
    /// consumed not) read received 65 536 behind, and the master owed 65 536 items for good.
    #[test]
    fn the_first_report_reads_the_same_at_any_offset(
        offset in proptest::prelude::any::<u16>(),
        capacity in 1u16..=300,
        fill in 0u16..=300,
    ) {
        let held = fill.min(capacity);
        let mut m: Master<1> = Master::new();
        m.attach(0, SlaveParams { capacity, t0: 10 }).unwrap();
        let r = report(offset, offset.wrapping_add(held));
        let owed = u32::from(capacity - held);
        proptest::prop_assert_eq!(m.on_report(0, 0, &r), Ok(ReportOutcome::Accepted { owed }));
        let grant = m.next_refill(0, u32::MAX);
        proptest::prop_assert_eq!(grant.map(|g| (g.first_wire(), g.count)), (owed > 0).then_some((offset.wrapping_add(held), owed)));
        m.reinit(0).unwrap();
        proptest::prop_assert_eq!(m.on_report(1, 0, &r), Ok(ReportOutcome::Accepted { owed }));
    }
}

fn refill_frame(first: u16, items: &[u8], sync: bool) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME];
    let n = Refill {
        slave: 1,
        first,
        items,
        boot: 0,
        sync,
    }
    .encode(&mut out)
    .unwrap();
    out[..n].to_vec()
}

/// A slave placed just below the 16-bit wrap takes items across it in order: a duplicate
/// (behind the next index, across the wrap) is dropped, a gap (ahead of it) is dropped and asks
/// for a resend; its report's counters wrap.
#[test]
#[rustfmt::skip]
fn a_slave_across_the_counters_wrap() {
    let mut s: Slave<8> = Slave::new(config()).unwrap();
    // (what, frame, items taken, (consumed, received) reported)
    let rows: Vec<(&str, Vec<u8>, usize, (u16, u16))> = vec![
        ("sync at 65 534, four items", refill_frame(65_534, &[1, 2, 3, 4], true), 4, (65_534, 2)),
        ("the same again: duplicates", refill_frame(65_534, &[1, 2, 3, 4], false), 0, (65_534, 2)),
        ("behind across the wrap: duplicates", refill_frame(65_535, &[2, 3], false), 0, (65_534, 2)),
        ("ahead: a gap", refill_frame(4, &[7], false), 0, (65_534, 2)),
        ("next in order", refill_frame(2, &[5, 6], false), 2, (65_534, 4)),
        ("a keep-alive", refill_frame(0, &[], false), 0, (65_534, 4)),
    ];
    for (what, frame, taken, (consumed, received)) in rows {
        assert_eq!(s.on_frame(&frame), Ok(taken), "{what}");
        let r = s.report(false);
        assert_eq!((r.consumed, r.received), (consumed, received), "{what}");
    }
    assert_eq!((s.stats().duplicates, s.stats().gaps), (6, 1));
    // The items come out in stream order across the wrap.
    let out: Vec<u8> = (0..6).map(|_| s.step(|_, _| 0xEE).item).collect();
    assert_eq!(out, [1, 2, 3, 4, 5, 6]);
    assert_eq!(s.report(false).consumed, 4, "consumed wrapped past 65 535");
}

/// `next_refill` with `max` 0 (counts as 1), 1 and `u32::MAX`, at `now` 0 and `u64::MAX`:
/// never more than is owed, the deadline saturating, a grant at `u64::MAX` late.
#[test]
#[rustfmt::skip]
fn master_grants_at_the_extremes() {
    let fresh = |t0| {
        let mut m: Master<1> = Master::new();
        m.attach(0, SlaveParams { capacity: 8, t0 }).unwrap();
        m.on_report(0, 0, &report(0, 0)).unwrap();
        while m.next_refill(0, u32::MAX).is_some() {}
        m.on_report(10, 0, &report(5, 8)).unwrap(); // five consumed: five owed, three left
        m
    };
    // (what, t0, now, max, (count, deadline, late))
    let rows: [(&str, u32, u64, u32, (u32, u64, bool)); 5] = [
        ("max 0 counts as 1", 10, 10, 0, (1, 10 + 3 * 10, false)),
        ("max 1", 10, 10, 1, (1, 40, false)),
        ("max MAX: what is owed", 10, 10, u32::MAX, (5, 40, false)),
        ("now MAX: late", 10, u64::MAX, u32::MAX, (5, 40, true)),
        ("t0 MAX", u32::MAX, 10, u32::MAX, (5, 10 + 3 * u64::from(u32::MAX), false)),
    ];
    for (what, t0, now, max, want) in rows {
        let mut m = fresh(t0);
        let g = m.next_refill(now, max).unwrap();
        assert_eq!((g.count, g.deadline, g.late), want, "{what}");
        assert_eq!(g.first, 8, "{what}");
        if want.2 {
            assert_eq!((m.status(0).unwrap().missed, m.status(0).unwrap().worst_lateness), (1, u64::MAX - 40), "{what}");
        }
    }
}
