//! The serial-highway workload the `panel_link` bench and the `highway-codec` instruction counter
//! share: 1 024 messages of every kind and shape, their encoded bytes, and a crate that answers.

use regler_panel_link::highway::{
    Controller, ControllerConfig, Cycle, Dataway, MAX_MESSAGE, Message, Status, decode,
};

/// 1 024 messages of every kind and shape from a fixed xorshift generator; every third command
/// is addressed to crate 7 (the controller bench's own crate).
#[must_use]
pub fn workload() -> Vec<Message> {
    let mut x = 0x2545_F491_4F6C_DD1Du64;
    (0..1024)
        .map(|k| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let f = (x % 32) as u8;
            let crate_address = if k % 3 == 0 {
                7
            } else {
                1 + (x >> 8) as u8 % 62
            };
            match k % 4 {
                0 | 1 => Message::Command {
                    crate_address,
                    station: (x >> 16) as u8 % 32,
                    subaddress: (x >> 24) as u8 % 16,
                    function: f,
                    data: (16..=23)
                        .contains(&f)
                        .then_some((x >> 32) as u32 & 0xFF_FFFF),
                },
                2 => Message::Reply {
                    crate_address,
                    status: Status::from_bits((x >> 40) as u8),
                    data: (x & 1 == 0).then_some((x >> 12) as u32 & 0xFF_FFFF),
                },
                _ => Message::Demand {
                    crate_address,
                    sgl: 1 + (x >> 20) as u8 % 31, // SGL 0 is no demand
                },
            }
        })
        .collect()
}

/// The workload's messages of its shortest encoded length (`longest` false) or of its longest:
/// the decoder's cost per byte is compared between the two (`docs/PERFORMANCE.md`, "Cost
/// statements").
#[must_use]
pub fn of_extreme_length(longest: bool) -> Vec<Message> {
    let messages = workload();
    let (_, lens) = encoded(&messages);
    let pick = if longest {
        lens.iter().max()
    } else {
        lens.iter().min()
    };
    let Some(&pick) = pick else {
        return Vec::new();
    };
    messages
        .into_iter()
        .zip(lens)
        .filter(|&(_, len)| len == pick)
        .map(|(m, _)| m)
        .collect()
}

/// The messages' bytes back to back, and each message's length.
#[must_use]
pub fn encoded(messages: &[Message]) -> (Vec<u8>, Vec<usize>) {
    let mut bytes = Vec::new();
    let mut lens = Vec::new();
    let mut buf = [0u8; MAX_MESSAGE];
    for m in messages {
        let len = m.encode(&mut buf).unwrap_or(0);
        bytes.extend_from_slice(&buf[..len]);
        lens.push(len);
    }
    (bytes, lens)
}

/// A crate of 32 registers, one per station.
pub struct Registers(pub [u32; 32]);

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

/// Encodes every message into `out`; returns the bytes written.
pub fn encode_all(messages: &[Message], out: &mut [u8]) -> usize {
    let mut at = 0;
    for m in messages {
        at += m.encode(&mut out[at..]).unwrap_or(0);
    }
    at
}

/// Decodes every message; returns how many decoded.
#[must_use]
pub fn decode_all(bytes: &[u8], lens: &[usize]) -> usize {
    let mut at = 0;
    let mut ok = 0;
    for &len in lens {
        ok += usize::from(decode(&bytes[at..at + len]).is_ok());
        at += len;
    }
    ok
}

/// Copies every message's bytes, message by message: the practical limit of any codec.
pub fn copy_all(bytes: &[u8], lens: &[usize], out: &mut [u8]) -> usize {
    let mut at = 0;
    for &len in lens {
        out[at..at + len].copy_from_slice(&bytes[at..at + len]);
        at += len;
    }
    at
}

/// Runs `rounds` passes of `which` (`encode`, `decode`, `copy`, `controller`, `delay`) over the
/// workload, or of `decode-shortest` / `decode-longest` over its messages of the shortest /
/// longest encoded length ([`of_extreme_length`]), and returns a checksum, or `None` for an
/// unknown `which`.
#[must_use]
pub fn run(which: &str, rounds: u64) -> Option<u64> {
    let messages = match which {
        "decode-shortest" => of_extreme_length(false),
        "decode-longest" => of_extreme_length(true),
        _ => workload(),
    };
    let (bytes, lens) = encoded(&messages);
    let mut out = vec![0u8; bytes.len()];
    let mut sum = 0u64;
    let mut controller = Controller::new(ControllerConfig {
        address: 7,
        demand_repeat: 0,
    })
    .ok()?;
    let mut crate_ = Registers([0; 32]);
    for _ in 0..rounds {
        sum += match which {
            "encode" => encode_all(std::hint::black_box(&messages), &mut out) as u64,
            "decode" | "decode-shortest" | "decode-longest" => {
                decode_all(std::hint::black_box(&bytes), &lens) as u64
            }
            "copy" => copy_all(std::hint::black_box(&bytes), &lens, &mut out) as u64,
            "controller" => {
                for (o, &i) in out.iter_mut().zip(std::hint::black_box(&bytes)) {
                    *o = controller.clock(i, &mut crate_);
                }
                u64::from(out[0])
            }
            // The controller's anchor: each byte passed on one clock later.
            "delay" => {
                let mut held = 0xE0u8;
                for (o, &i) in out.iter_mut().zip(std::hint::black_box(&bytes)) {
                    *o = held;
                    held = i;
                }
                u64::from(out[0])
            }
            _ => return None,
        };
    }
    Some(sum)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shortest_and_longest_messages_decode_and_are_of_one_length_each() {
        let (short, long) = (of_extreme_length(false), of_extreme_length(true));
        let (short_bytes, short_lens) = encoded(&short);
        let (long_bytes, long_lens) = encoded(&long);
        assert!(!short.is_empty() && !long.is_empty());
        let all = encoded(&workload()).1;
        assert!(short_lens.iter().all(|&l| Some(&l) == all.iter().min()));
        assert!(long_lens.iter().all(|&l| Some(&l) == all.iter().max()));
        assert!(short_lens[0] < long_lens[0]);
        // Every one of them decodes: the counters time real decodes, not early refusals.
        assert_eq!(decode_all(&short_bytes, &short_lens), short.len());
        assert_eq!(decode_all(&long_bytes, &long_lens), long.len());
        assert_eq!(run("decode-shortest", 1), Some(short.len() as u64));
        assert_eq!(run("decode-longest", 1), Some(long.len() as u64));
    }
}
