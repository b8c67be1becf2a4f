//! regler-ring-transfer on the core: the ring, the split halves in a `static` (as firmware holds
//! them), the frames and their CRC, the lossy-link protocol, stand-alone mode, the master's EDF
//! and the capacity check's 128-bit arithmetic on a 32-bit core.

use regler_ring_transfer::capacity::{self, LinkSpec, Load, Verdict};
use regler_ring_transfer::{
    Master, Message, Mode, Refill, Report, Ring, SharedRing, Slave, SlaveConfig, SlaveParams,
    Source, decode, link,
};

use crate::{Outcome, check};

pub fn ring_pointer_rule() -> Outcome {
    let mut ring: Ring<u8, 16> = Ring::new();
    for b in 0..16 {
        check!(ring.receive(b).is_ok());
    }
    check!(ring.receive(99) == Err(99));
    check!(ring.next() == Some(0));
    check!(ring.requests() == 1 && ring.slack() == 15);
    check!(ring.deadline(2_308) == 15 * 2_308);
    for _ in 0..15 {
        check!(ring.next().is_some());
    }
    check!(ring.next().is_none());
    let stats = ring.stats();
    check!(stats.underruns == 1 && stats.least_slack == 0 && stats.most_requests == 16);
    Ok(())
}

pub fn split_halves_from_a_static() -> Outcome {
    // Firmware keeps the ring in a static and hands the halves to the link interrupt and the
    // machine loop; cortex-m's singleton gives the `&'static mut` once.
    let shared = cortex_m::singleton!(: SharedRing<u8, 64> = SharedRing::new()).ok_or("twice")?;
    let (mut filler, mut drainer) = shared.split();
    let (mut sent, mut got) = (0u32, 0u32);
    for round in 0..1000u32 {
        // The link delivers in bursts, the machine takes one per round.
        if round % 7 == 0 {
            while filler.requests() > 0 {
                check!(filler.receive(sent as u8).is_ok());
                sent += 1;
            }
        }
        if let Some(item) = drainer.next() {
            check!(item == got as u8);
            got += 1;
        }
    }
    let c = filler.counters();
    check!(c.received == sent && c.consumed == got && drainer.underruns() == 0);
    check!(filler.stats().least_slack <= 64);
    Ok(())
}

pub fn frames_and_every_two_bit_error() -> Outcome {
    let report = Report {
        slave: 3,
        consumed: 0xBEEF,
        received: 0xBF00,
        standalone: true,
        retry: true,
        boot: 7,
        hello: false,
    };
    let mut frame = [0u8; link::MAX_FRAME];
    let n = report.encode(&mut frame).map_err(|_| "encode")?;
    check!(decode(&frame[..n]) == Ok(Message::Report(report)));
    check!(link::crc16(b"123456789") == 0x29B1);
    let bits = n * 8;
    for i in 0..bits {
        for j in i..bits {
            let mut damaged = frame;
            damaged[i / 8] ^= 1 << (i % 8);
            if j != i {
                damaged[j / 8] ^= 1 << (j % 8);
            }
            check!(decode(&damaged[..n]).is_err());
        }
    }
    Ok(())
}

fn pattern(k: u64) -> u8 {
    (k % 251) as u8
}

pub fn lossy_link_keeps_the_stream() -> Outcome {
    let config = SlaveConfig {
        address: 2,
        row_len: 8,
        silence_limit: 30_000, // never silent in this run; with row 8 and ring 32 within MAX_DRIFT
        retry_after: 5,
        boot: 1,
    };
    let mut slave: Slave<32> = Slave::new(config).map_err(|_| "slave")?;
    let mut master: Master<4> = Master::new();
    master
        .attach(
            2,
            SlaveParams {
                capacity: 32,
                t0: 2,
            },
        )
        .map_err(|_| "attach")?;
    let mut frame = [0u8; link::MAX_FRAME];
    let mut items = [0u8; 8];
    let mut lost = 0u32;
    for now in 0..4_000u64 {
        if let Some(report) = slave.poll_report() {
            // Every fifth report is lost.
            if now % 5 != 1 {
                master.on_report(now, 2, &report).map_err(|_| "report")?;
            }
        }
        while let Some(g) = master.next_refill(now, 8) {
            let n = g.count as usize;
            for (k, item) in items[..n].iter_mut().enumerate() {
                *item = pattern(g.first + k as u64);
            }
            let len = g
                .refill(2, &items[..n])
                .encode(&mut frame)
            .map_err(|_| "refill")?;
            // Every third refill is lost, every fourth arrives twice.
            if g.first % 3 == 1 {
                lost += 1;
                continue;
            }
            let _ = slave.on_frame(&frame[..len]);
            if g.first % 4 == 0 {
                let _ = slave.on_frame(&frame[..len]);
            }
        }
        if now % 2 == 0 {
            // The stream index the slave takes next: its consumed count (no wrap in this run).
            let index = u64::from(slave.report(false).consumed);
            let out = slave.step(|_, _| 0xFF);
            if out.source == Source::Master {
                check!(out.item == pattern(index));
            }
        }
    }
    check!(lost > 0 && slave.stats().duplicates > 0 && slave.stats().retries > 0);
    Ok(())
}

pub fn stand_alone_and_back_at_a_row() -> Outcome {
    let config = SlaveConfig {
        address: 0,
        row_len: 10,
        silence_limit: 12,
        retry_after: 4,
        boot: 1,
    };
    let mut slave: Slave<32> = Slave::new(config).map_err(|_| "slave")?;
    let mut master: Master<1> = Master::new();
    master
        .attach(
            0,
            SlaveParams {
                capacity: 32,
                t0: 1,
            },
        )
        .map_err(|_| "attach")?;
    let mut frame = [0u8; link::MAX_FRAME];
    let mut items = [0u8; link::MAX_REFILL];
    let (mut row_source, mut mixed_rows, mut local_rows) = (None, 0u32, 0u32);
    for now in 0..3_000u64 {
        let up = !(1_000..1_500).contains(&now);
        let report = slave.poll_report().filter(|_| up);
        let outcome = report.map(|r| master.on_report(now, 0, &r));
        if let Some(Ok(regler_ring_transfer::ReportOutcome::Accepted { owed: 0 })) = outcome {
            let n = Refill::keep_alive(0)
                .encode(&mut frame)
                .map_err(|_| "keep-alive")?;
            let _ = slave.on_frame(&frame[..n]);
        }
        while let Some(g) = master
            .next_refill(now, link::MAX_REFILL as u32)
            .filter(|_| up)
        {
            let n = g.count as usize;
            for (k, item) in items[..n].iter_mut().enumerate() {
                *item = pattern(g.first + k as u64);
            }
            let len = g
                .refill(0, &items[..n])
                .encode(&mut frame)
            .map_err(|_| "refill")?;
            let _ = slave.on_frame(&frame[..len]);
        }
        let out = slave.step(|_, _| 0xFF);
        let source = if out.source == Source::Local { 1 } else { 0 };
        if out.col == 0 {
            row_source = Some(source);
        } else if row_source != Some(source) {
            mixed_rows += 1;
        }
        if out.col == 9 && source == 1 && row_source == Some(1) {
            local_rows += 1;
        }
    }
    check!(slave.mode() == Mode::Linked);
    check!(mixed_rows == 0);
    check!((40..=50).contains(&local_rows));
    check!(slave.stats().underruns == 0 && slave.stats().standalone_entries == 1);
    Ok(())
}

pub fn capacity_on_a_32_bit_core() -> Outcome {
    let machine = Load {
        t0: 2_308,
        ring: 256,
    };
    let link = LinkSpec {
        item_time: 28,
        latency: 100,
    };
    check!(capacity::max_slaves(machine, link, 1_000) == Ok(82));
    check!(capacity::check(&[machine; 8], link).map(|v| v.is_schedulable()) == Ok(true));
    check!(capacity::min_ring(&[machine; 8], link, 0, 1024) == Ok(Some(3)));
    let tight = [Load { t0: 1000, ring: 10 }, Load { t0: 18, ring: 2 }];
    check!(
        capacity::check(
            &tight,
            LinkSpec {
                item_time: 10,
                latency: 0
            }
        ) == Ok(Verdict::DeadlineMiss {
            interval: 18,
            demand: 19
        })
    );
    Ok(())
}

pub fn sizes_on_a_32_bit_core() -> Outcome {
    // What a board and a master cost in RAM.
    check!(core::mem::size_of::<Ring<u8, 256>>() <= 256 + 32);
    check!(core::mem::size_of::<Slave<256>>() <= 256 + 128);
    // 8 slaves: per slave its state (counters, statistics, session and a pending offer) plus
    // two u16 heap indices and an `Option<u64>` key (148 bytes a slave on a 64-bit host).
    check!(core::mem::size_of::<Master<8>>() <= 8 * 160);
    Ok(())
}
