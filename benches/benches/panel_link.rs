//! Serial-highway `encode` and `decode`, and a crate controller passing a stream on, each beside a
//! plain byte copy of the same bytes — the practical limit of any codec. Throughput is in bytes of
//! encoded messages, so the figure to read is the ratio to the copy.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use regler_panel_link::highway::{
    Controller, ControllerConfig, Cycle, Dataway, MAX_MESSAGE, Message, Status, decode,
};

/// 1024 messages of every kind and shape, from a fixed generator.
fn workload() -> Vec<Message> {
    let mut x = 0x2545_F491_4F6C_DD1Du64;
    (0..1024)
        .map(|k| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let f = (x % 32) as u8;
            match k % 4 {
                0 | 1 => Message::Command {
                    crate_address: 1 + (x >> 8) as u8 % 62,
                    station: (x >> 16) as u8 % 32,
                    subaddress: (x >> 24) as u8 % 16,
                    function: f,
                    data: (16..=23)
                        .contains(&f)
                        .then_some((x >> 32) as u32 & 0xFF_FFFF),
                },
                2 => Message::Reply {
                    crate_address: 1 + (x >> 8) as u8 % 62,
                    status: Status::from_bits((x >> 40) as u8),
                    data: (x & 1 == 0).then_some((x >> 12) as u32 & 0xFF_FFFF),
                },
                _ => Message::Demand {
                    crate_address: 1 + (x >> 8) as u8 % 62,
                    sgl: (x >> 20) as u8 % 32,
                },
            }
        })
        .collect()
}

fn encoded(messages: &[Message]) -> (Vec<u8>, Vec<usize>) {
    let mut bytes = Vec::new();
    let mut lens = Vec::new();
    let mut buf = [0u8; MAX_MESSAGE];
    for m in messages {
        let len = m.encode(&mut buf).expect("valid message");
        bytes.extend_from_slice(&buf[..len]);
        lens.push(len);
    }
    (bytes, lens)
}

fn codec(c: &mut Criterion) {
    let messages = workload();
    let (bytes, lens) = encoded(&messages);
    let mut out = vec![0u8; bytes.len()];

    let mut group = c.benchmark_group("highway_encode_1024_messages");
    group.throughput(Throughput::Bytes(bytes.len() as u64));
    group.bench_function("regler_encode", |b| {
        b.iter(|| {
            let mut at = 0;
            for m in black_box(&messages) {
                at += m.encode(&mut out[at..]).unwrap_or(0);
            }
            at
        });
    });
    group.bench_function("plain_copy", |b| {
        b.iter(|| {
            let mut at = 0;
            for &len in black_box(&lens) {
                out[at..at + len].copy_from_slice(&bytes[at..at + len]);
                at += len;
            }
            at
        });
    });
    group.finish();

    let mut group = c.benchmark_group("highway_decode_1024_messages");
    group.throughput(Throughput::Bytes(bytes.len() as u64));
    group.bench_function("regler_decode", |b| {
        b.iter(|| {
            let mut at = 0;
            let mut ok = 0;
            for &len in black_box(&lens) {
                ok += usize::from(decode(&bytes[at..at + len]).is_ok());
                at += len;
            }
            ok
        });
    });
    group.bench_function("plain_copy", |b| {
        b.iter(|| {
            let mut at = 0;
            for &len in black_box(&lens) {
                out[at..at + len].copy_from_slice(&bytes[at..at + len]);
                at += len;
            }
            at
        });
    });
    group.finish();
}

struct Registers([u32; 32]);

impl Dataway for Registers {
    fn cycle(&mut self, n: u8, _a: u8, f: u8, write: Option<u32>) -> Cycle {
        let reg = &mut self.0[usize::from(n & 31)];
        if let Some(w) = write {
            *reg = w;
        }
        Cycle {
            read: *reg,
            x: true,
            q: f < 8,
        }
    }
}

fn controller(c: &mut Criterion) {
    // The loop's traffic as one crate sees it: commands for it and for others, replies, demands.
    let mut messages = workload();
    for (k, m) in messages.iter_mut().enumerate() {
        if let Message::Command { crate_address, .. } = m {
            if k % 3 == 0 {
                *crate_address = 7;
            }
        }
    }
    let (bytes, _) = encoded(&messages);
    let mut out = vec![0u8; bytes.len()];
    let mut group = c.benchmark_group("controller_stream");
    group.throughput(Throughput::Bytes(bytes.len() as u64));
    let mut crate_ = Registers([0; 32]);
    let mut ctl = Controller::new(ControllerConfig {
        address: 7,
        demand_repeat: 0,
    })
    .expect("valid address");
    group.bench_function("regler_controller_clock", |b| {
        b.iter(|| {
            for (o, &i) in out.iter_mut().zip(black_box(&bytes)) {
                *o = ctl.clock(i, &mut crate_);
            }
        });
    });
    group.bench_function("plain_copy_with_one_byte_delay", |b| {
        b.iter(|| {
            let mut held = 0xE0u8;
            for (o, &i) in out.iter_mut().zip(black_box(&bytes)) {
                *o = held;
                held = i;
            }
        });
    });
    group.finish();
}

criterion_group!(benches, codec, controller);
criterion_main!(benches);
