//! Arbitrary bytes from a Modbus/TCP client of the PLC example (`microcomputer-plc --modbus`),
//! framed as the server frames them (`modbus::frame_length`), each frame answered by
//! `modbus::answer` against tables published from a running simulator; the requests a write
//! queued are carried out and a cycle runs between frames, as the server's cycle does.
//!
//! What the module's documentation promises, checked for every frame:
//! - a header with a length outside 2..=254 or a protocol id other than 0 closes the connection;
//! - every reply echoes the transaction and protocol ids and the unit id, and its length field
//!   is its length; an exception is the function | 0x80 with code 1, 2, 3 or 0x0B;
//! - a request `check` refuses, or one to a unit other than 0, 1 and 255, is answered with an
//!   exception and nothing acts; a request `check` passes is answered (never a closed
//!   connection) with the function's own response;
//! - a write acts on every point it names, in address order (coil p forces output p, coil
//!   1000 + p input p; holding register 0 ← 1 releases all, 1 ← p output p, 2 ← p input p), and
//!   carried out, the forcing is what it asked;
//! - holding registers read as 0; discrete inputs read the images and the forced flags as the
//!   last cycle published them; a read's byte count is what its quantity asks.
#![no_main]

use std::sync::Mutex;

use libfuzzer_sys::fuzz_target;
use regler_examples::plc::Simulator;
use regler_examples::plc::modbus::{
    self, Answer, GATEWAY_TARGET_FAILED, ILLEGAL_DATA_ADDRESS, ILLEGAL_DATA_VALUE,
    ILLEGAL_FUNCTION, Request, Shared,
};

fn word(pdu: &[u8], i: usize) -> u16 {
    u16::from_be_bytes([pdu[i], pdu[i + 1]])
}

/// What a write that passed the check asks for, from the module's documentation.
fn model_requests(pdu: &[u8]) -> Vec<Request> {
    let coil = |a: u16, on: bool| {
        if a >= 1000 {
            Request::ForceInput(usize::from(a - 1000), on)
        } else {
            Request::ForceOutput(usize::from(a), on)
        }
    };
    let holding = |register: u16, value: u16| match (register, value) {
        (0, 1) => Some(Request::ReleaseAll),
        (0, _) => None,
        (1, p) => Some(Request::ReleaseOutput(usize::from(p))),
        (_, p) => Some(Request::ReleaseInput(usize::from(p))),
    };
    let (address, second) = (word(pdu, 1), word(pdu, 3));
    match pdu[0] {
        5 => vec![coil(address, second == 0xFF00)],
        15 => (0..second)
            .map(|k| coil(address + k, pdu[6 + usize::from(k / 8)] >> (k % 8) & 1 == 1))
            .collect(),
        6 => holding(address, second).into_iter().collect(),
        16 => (0..second)
            .filter_map(|k| holding(address + k, word(pdu, 6 + 2 * usize::from(k))))
            .collect(),
        _ => Vec::new(),
    }
}

fn forced(sim: &Simulator) -> Vec<(Option<bool>, Option<bool>)> {
    (0..16)
        .map(|p| {
            (
                sim.plc.forced_outputs().forced(p),
                sim.plc.forced_inputs().forced(p),
            )
        })
        .collect()
}

fuzz_target!(|data: &[u8]| {
    let mut sim = Simulator::new(3);
    sim.run(3);
    let state = Mutex::new(Shared::new());
    state.lock().unwrap().publish(&sim);
    let mut rest = data;
    for _ in 0..64 {
        let Some(header) = rest.get(..7) else { break };
        let length = usize::from(word(header, 4));
        let Some(length_checked) = modbus::frame_length(header) else {
            assert!(
                !(2..=254).contains(&length) || header[2..4] != [0, 0],
                "header {header:?} closes the connection"
            );
            break;
        };
        assert_eq!(length_checked, length);
        let Some(frame) = rest.get(..6 + length) else {
            break;
        };
        rest = &rest[6 + length..];
        let (unit, function, pdu) = (frame[6], frame[7], &frame[7..]);
        let verdict = if matches!(unit, 0 | 1 | 255) {
            modbus::check(pdu)
        } else {
            Err(GATEWAY_TARGET_FAILED)
        };
        let before = forced(&sim);
        let answer = modbus::answer(frame, &state);
        let queued = state.lock().unwrap().take_requests();
        let Answer::Reply(reply) = answer else {
            panic!("{answer:?} for {frame:?} (check says {verdict:?})");
        };
        assert!(reply.len() >= 9, "reply {reply:?}");
        assert_eq!(
            reply[..4],
            frame[..4],
            "transaction and protocol ids echoed"
        );
        assert_eq!(
            usize::from(word(&reply, 4)),
            reply.len() - 6,
            "length field"
        );
        assert_eq!(reply[6], unit, "unit id echoed");
        match verdict {
            Err(code) => {
                assert!(
                    matches!(
                        code,
                        ILLEGAL_FUNCTION
                            | ILLEGAL_DATA_ADDRESS
                            | ILLEGAL_DATA_VALUE
                            | GATEWAY_TARGET_FAILED
                    ),
                    "code {code}"
                );
                assert_eq!(
                    reply[7..],
                    [function | 0x80, code],
                    "exception for {frame:?}"
                );
                assert!(queued.is_empty(), "a refused request queued {queued:?}");
            }
            Ok(()) => {
                assert_eq!(reply[7], function, "response to {frame:?}: {reply:?}");
                let quantity = word(pdu, 3);
                match function {
                    1 | 2 => assert_eq!(usize::from(reply[8]), usize::from(quantity).div_ceil(8)),
                    3 | 4 => assert_eq!(usize::from(reply[8]), 2 * usize::from(quantity)),
                    _ => {}
                }
                // Reads: MBAP, function, byte count, data; writes echo address and quantity.
                let want_len = if function <= 4 {
                    9 + usize::from(reply[8])
                } else {
                    12
                };
                assert_eq!(reply.len(), want_len, "reply {reply:?}");
                if function == 3 {
                    assert!(
                        reply[9..].iter().all(|&b| b == 0),
                        "holding registers read as 0"
                    );
                }
                if function == 2 {
                    let address = word(pdu, 1);
                    for k in 0..quantity {
                        let a = address + k;
                        let bit = reply[9 + usize::from(k / 8)] >> (k % 8) & 1 == 1;
                        let p = usize::from(a % 100);
                        let want = match a {
                            0..=15 => sim.plc.inputs().get(p),
                            100..=115 => sim.plc.forced_outputs().forced(p).is_some(),
                            _ => sim.plc.forced_inputs().forced(p).is_some(),
                        };
                        assert_eq!(bit, want, "discrete input {a}");
                    }
                }
                assert_eq!(queued, model_requests(pdu), "requests of {pdu:?}");
            }
        }
        // The cycle carries the requests out, in order, then runs and publishes.
        let mut want = before;
        for &r in &queued {
            assert_eq!(modbus::carry_out(&mut sim, r), "", "{r} refused");
            match r {
                Request::ForceOutput(p, v) => want[p].0 = Some(v),
                Request::ForceInput(p, v) => want[p].1 = Some(v),
                Request::ReleaseOutput(p) => want[p].0 = None,
                Request::ReleaseInput(p) => want[p].1 = None,
                Request::ReleaseAll => want.iter_mut().for_each(|w| *w = (None, None)),
            }
        }
        assert_eq!(forced(&sim), want, "forcing after {queued:?}");
        sim.run(1);
        state.lock().unwrap().publish(&sim);
    }
});
