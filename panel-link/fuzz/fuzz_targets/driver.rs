//! Arbitrary bytes into a driver that waits on every crate 1..=62, then what a crate sends back
//! for its command (short reply, WAIT, its reply over the SPACE bytes, END) with up to three bits
//! flipped anywhere: no panic, and after the garbage (ended by two WAIT) the driver completes a
//! command only with the reply its crate sent (the README's "the driver completes a command only
//! with a reply whose every byte passed the check, from that command's crate, of the length that
//! command asks for").
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_panel_link::highway::{
    Controller, ControllerConfig, Cycle, Dataway, Driver, DriverConfig, DriverEvent, MAX_MESSAGE,
    Message, WAIT, decode,
};

struct Crate(u32);

impl Dataway for Crate {
    fn cycle(&mut self, _n: u8, _a: u8, f: u8, _write: Option<u32>) -> Cycle {
        Cycle {
            read: self.0,
            x: f != 31,
            q: f % 2 == 0,
        }
    }
}

fn outstanding(address: u8) -> Message {
    let (station, subaddress, function, data) = match (address % 3, address % 2) {
        (2, _) => (address % 32, 3, 0, None),
        (0, _) => (2, 0, 16, Some(0x82_0FFF ^ u32::from(address))),
        (_, 0) => (31, 15, 9, None),
        _ => (0, 7, 26, None),
    };
    Message::Command {
        crate_address: address,
        station,
        subaddress,
        function,
        data,
    }
}

fuzz_target!(|data: &[u8]| {
    // Layout: crate (1), read data (3), three flips (3 × 2), garbage.
    let Some((head, garbage)) = data.split_at_checked(10) else {
        return;
    };
    let mut driver: Driver<62> = Driver::new(DriverConfig {
        timeout: 1_000_000,
        retries: 0,
        gap: 1,
    })
    .unwrap();
    for address in 1..=62 {
        driver.submit(outstanding(address)).unwrap();
    }
    for _ in 0..62 * (MAX_MESSAGE + 1) {
        driver.clock(WAIT);
    }
    for &byte in garbage.iter().chain(&[WAIT; 2]) {
        driver.clock(byte);
    }
    // What crate `address` sends back.
    let address = 1 + head[0] % 62;
    let mut controller = Controller::new(ControllerConfig {
        address,
        demand_repeat: 0,
    })
    .unwrap();
    let mut crate_ = Crate(u32::from_le_bytes([head[1], head[2], head[3], 0]));
    let mut buf = [0u8; MAX_MESSAGE];
    let len = outstanding(address).encode(&mut buf).unwrap();
    // One WAIT first: a fresh controller reads nothing before a clean delimiter.
    let mut segment: Vec<u8> = [WAIT]
        .iter()
        .chain(&buf[..len])
        .chain(&[WAIT; 2])
        .map(|&b| controller.clock(b, &mut crate_))
        .skip(2)
        .collect();
    // The reply it meant: the bytes from its header (at its second occurrence) to its ENDSUM.
    let start = segment.iter().skip(1).position(|&b| b == segment[0]).unwrap() + 1;
    let truth = [3usize, 7]
        .iter()
        .find_map(|&n| segment.get(start..start + n).and_then(|r| decode(r).ok()))
        .unwrap();
    let window = segment.len() * 8;
    for k in 0..3 {
        let bit = usize::from(u16::from_le_bytes([head[4 + 2 * k], head[5 + 2 * k]]));
        if bit < window {
            segment[bit / 8] ^= 1 << (bit % 8);
        }
    }
    for &byte in segment.iter().chain(&[WAIT; 4]) {
        if let Some(DriverEvent::Completed(done)) = driver.clock(byte).event {
            let got = Message::Reply {
                crate_address: done.command.crate_address(),
                status: done.status,
                data: done.data,
            };
            assert_eq!(got, truth, "completed {done:?}");
            assert_eq!(done.command, outstanding(address));
        }
    }
});
