//! Arbitrary bytes into an L-type crate controller, then a command with up to three bits flipped
//! anywhere in it, the gap around it and the next command's first bytes: no panic, never more
//! than 3 bytes held, and after the garbage (ended by two WAIT) the only cycles run are the
//! command sent or the next command, each at most once, never another (the README's "no 1-, 2-
//! or 3-bit error makes any controller run a cycle other than the one sent"); after one more gap
//! a clean command runs (the controller always resynchronises).
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_panel_link::highway::{
    Controller, ControllerConfig, Cycle, Dataway, MAX_MESSAGE, Message, WAIT,
};

struct Crate {
    cycles: Vec<(u8, u8, u8, Option<u32>)>,
    lam: u8,
}

impl Dataway for Crate {
    fn cycle(&mut self, n: u8, a: u8, f: u8, write: Option<u32>) -> Cycle {
        self.cycles.push((n, a, f, write));
        assert!(n < 32);
        assert!(write.is_none_or(|w| w < 1 << 24));
        Cycle {
            read: 0x00AB_CDEF,
            x: true,
            q: false,
        }
    }
    fn graded_lam(&mut self) -> u8 {
        self.lam
    }
}

fn fields(m: &Message) -> (u8, u8, u8, Option<u32>) {
    match *m {
        Message::Command {
            station,
            subaddress,
            function,
            data,
            ..
        } => (station, subaddress, function, data),
        _ => unreachable!(),
    }
}

fn encode(m: &Message) -> Vec<u8> {
    let mut buf = [0u8; MAX_MESSAGE];
    let len = m.encode(&mut buf).unwrap();
    buf[..len].to_vec()
}

fuzz_target!(|data: &[u8]| {
    // Layout of the input: config (1), command fields (7), three flips (3 × 2), garbage.
    let Some((head, garbage)) = data.split_at_checked(14) else {
        return;
    };
    let address = 1 + head[0] % 62;
    let mut controller = Controller::new(ControllerConfig {
        address,
        demand_repeat: u32::from(head[0]),
    })
    .unwrap();
    let mut crate_ = Crate {
        cycles: Vec::new(),
        lam: head[0] >> 3,
    };
    for &byte in garbage {
        controller.clock(byte, &mut crate_);
        assert!(controller.held() <= 3);
    }
    for _ in 0..2 {
        controller.clock(WAIT, &mut crate_);
    }
    crate_.cycles.clear();
    // The command: to this crate or another, any fields.
    let function = head[4] % 32;
    let sent = Message::Command {
        crate_address: if head[1] & 1 == 0 { address } else { 1 + head[1] / 2 % 62 },
        station: head[2] % 32,
        subaddress: head[3] % 16,
        function,
        data: (16..=23)
            .contains(&function)
            .then(|| u32::from_le_bytes([head[5], head[6], head[7], 0])),
    };
    let next = Message::Command {
        crate_address: address,
        station: 9,
        subaddress: 1,
        function: 9,
        data: None,
    };
    let mut stream = vec![WAIT];
    stream.extend(encode(&sent));
    stream.push(WAIT);
    let next_bytes = encode(&next);
    stream.extend(&next_bytes[..2]);
    let window = stream.len() * 8;
    let mut flipped = Vec::new();
    for k in 0..3 {
        let bit = usize::from(u16::from_le_bytes([head[8 + 2 * k], head[9 + 2 * k]]));
        if bit < window && !flipped.contains(&bit) {
            flipped.push(bit);
            stream[bit / 8] ^= 1 << (bit % 8);
        }
    }
    stream.extend(&next_bytes[2..]);
    stream.extend([WAIT; 4]);
    for &byte in &stream {
        controller.clock(byte, &mut crate_);
        assert!(controller.held() <= 3);
    }
    let mut allowed = vec![fields(&next)];
    if sent.crate_address() == address {
        allowed.push(fields(&sent));
    }
    // Each command sent may run once: take it off the list when it does.
    for cycle in &crate_.cycles {
        let at = allowed.iter().position(|a| a == cycle);
        assert!(
            at.is_some(),
            "crate {address} ran {cycle:?}; sent {sent:?}, bits {flipped:?}"
        );
        if let Some(at) = at {
            allowed.swap_remove(at);
        }
    }
    // Liveness.
    crate_.cycles.clear();
    let probe = Message::Command {
        crate_address: address,
        station: 3,
        subaddress: 1,
        function: 0,
        data: None,
    };
    for &byte in [WAIT].iter().chain(&encode(&probe)).chain(&[WAIT; 8]) {
        controller.clock(byte, &mut crate_);
    }
    assert_eq!(crate_.cycles, vec![fields(&probe)]);
});
