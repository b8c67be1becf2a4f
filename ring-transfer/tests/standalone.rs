//! Stand-alone mode: a master that falls silent, for any time, any number of times, never
//! leaves a mixed row behind it when it returns, and the pattern resumes where it paused.
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "a test may panic: that is how it fails"
)]

use proptest::prelude::*;
use regler_ring_transfer::{
    Master, Mode, Refill, ReportOutcome, Slave, SlaveConfig, SlaveParams, Source, link,
};

const RING: usize = 32;

/// The master's stream: item k of the job.
fn stream(k: u64) -> u8 {
    (k % 251) as u8
}

/// The board's local pattern (never equal to a stream byte: those are < 251).
fn local(_row: u32, col: u16) -> u8 {
    251 + (col % 5) as u8
}

struct Run {
    rows: Vec<Vec<(u8, Source)>>,
    master_saw_standalone: bool,
    slave: Slave<RING>,
}

fn run(row_len: u16, silences: &[(u64, u64)], steps: u64) -> Run {
    let config = SlaveConfig {
        address: 5,
        row_len,
        silence_limit: 12,
        retry_after: 4,
        boot: 1,
    };
    let mut slave: Slave<RING> = Slave::new(config).unwrap();
    let mut master: Master<8> = Master::new();
    master
        .attach(
            5,
            SlaveParams {
                capacity: RING as u16,
                t0: 1,
            },
        )
        .unwrap();
    let mut frame = [0u8; link::MAX_FRAME];
    let mut items = [0u8; link::MAX_REFILL];
    let mut rows: Vec<Vec<(u8, Source)>> = Vec::new();
    let mut master_saw_standalone = false;
    for now in 0..steps {
        let up = !silences.iter().any(|&(from, to)| (from..to).contains(&now));
        if let Some(report) = slave.poll_report() {
            if up {
                let outcome = master.on_report(now, 5, &report).unwrap();
                master_saw_standalone |= report.standalone;
                if let ReportOutcome::Accepted { owed: 0 } = outcome {
                    let n = Refill::keep_alive(5).encode(&mut frame).unwrap();
                    slave.on_frame(&frame[..n]).unwrap();
                }
            }
        }
        while let Some(g) = master
            .next_refill(now, link::MAX_REFILL as u32)
            .filter(|_| up)
        {
            let n = g.count as usize;
            for (k, item) in items[..n].iter_mut().enumerate() {
                *item = stream(g.first + k as u64);
            }
            let len = g.refill(5, &items[..n]).encode(&mut frame).unwrap();
            slave.on_frame(&frame[..len]).unwrap();
        }
        let out = slave.step(local);
        if out.col == 0 {
            rows.push(Vec::new());
        }
        rows.last_mut().unwrap().push((out.item, out.source));
    }
    Run {
        rows,
        master_saw_standalone,
        slave,
    }
}

fn silences() -> impl Strategy<Value = Vec<(u64, u64)>> {
    proptest::collection::vec((100u64..3_000, 1u64..600), 0..4).prop_map(|v| {
        v.into_iter()
            .map(|(from, len)| (from, from + len))
            .collect()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 4 } else { 128 }))]

    /// Every row is whole from one source — master or local — except that a row the master's
    /// failure cut short may end in fallback items; the master's rows are consecutive rows of
    /// its stream (the pattern resumes where it paused, nothing skipped or repeated); a long
    /// silence puts the slave in stand-alone mode and the master hears of it; and the slave is
    /// linked again at the end.
    #[test]
    #[cfg_attr(miri, ignore = "4 000 simulated steps of the ring per case: minutes under Miri, a simulated ring steps in tens of milliseconds under Miri; runs natively in every CI run")]
    fn rows_stay_whole_across_master_faults(row_len in 3u16..80, silences in silences()) {
        let r = run(row_len, &silences, 4_000);
        let mut next_stream_row = 0u64;
        for (i, row) in r.rows.iter().enumerate() {
            let master_items = row.iter().take_while(|(_, s)| *s == Source::Master).count();
            let rest = &row[master_items..];
            let rest_source = rest.first().map(|(_, s)| *s);
            prop_assert!(rest.iter().all(|(_, s)| Some(*s) == rest_source), "row {i}: {row:?}");
            prop_assert_ne!(rest_source, Some(Source::Underrun), "row {}", i);
            if master_items > 0 {
                prop_assert!(rest_source.is_none() || rest_source == Some(Source::Fallback), "row {i}: {row:?}");
                for (col, (item, _)) in row[..master_items].iter().enumerate() {
                    prop_assert_eq!(*item, stream(next_stream_row * u64::from(row_len) + col as u64), "row {}", i);
                }
                next_stream_row += 1;
            } else {
                prop_assert_eq!(rest_source, Some(Source::Local), "row {}: {:?}", i, row);
            }
        }
        let longest = silences.iter().map(|(a, b)| b - a).max().unwrap_or(0);
        let stats = r.slave.stats();
        if longest > 12 + 2 * u64::from(row_len) + RING as u64 {
            prop_assert!(stats.standalone_entries > 0);
            prop_assert!(r.master_saw_standalone);
        }
        prop_assert_eq!(stats.underruns, 0);
        prop_assert_eq!(r.slave.mode(), Mode::Linked);
    }
}

#[test]
#[cfg_attr(
    miri,
    ignore = "2 000 simulated steps of the ring: minutes under Miri, a simulated ring steps in tens of milliseconds under Miri; runs natively in every CI run"
)]
fn a_silence_is_visible_as_local_rows() {
    let r = run(10, &[(500, 900)], 2_000);
    let local_rows = r
        .rows
        .iter()
        .filter(|row| row.iter().all(|(_, s)| *s == Source::Local))
        .count();
    // 400 steps of silence, less the ring's 32 items and the 12-step limit, in rows of 10.
    assert!((30..=40).contains(&local_rows), "{local_rows}");
    assert_eq!(r.slave.stats().standalone_rows as usize, local_rows);
}
