//! Arbitrary bytes into an L-type crate controller: no panic, never more than 3 bytes held, a
//! dataway cycle only for a command that carried this crate's address, and after one WAIT and a
//! clean command the controller runs it and answers (it always recovers).
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_panel_link::highway::{
    Controller, ControllerConfig, Cycle, Dataway, MAX_MESSAGE, Message, WAIT,
};

struct Crate {
    cycles: u32,
    lam: u8,
}

impl Dataway for Crate {
    fn cycle(&mut self, n: u8, _a: u8, _f: u8, write: Option<u32>) -> Cycle {
        self.cycles += 1;
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

fuzz_target!(|data: &[u8]| {
    let Some((&first, stream)) = data.split_first() else {
        return;
    };
    let mut controller = Controller::new(ControllerConfig {
        address: 1 + first % 62,
        demand_repeat: u32::from(first),
    })
    .unwrap();
    let mut crate_ = Crate {
        cycles: 0,
        lam: first >> 3,
    };
    for &byte in stream {
        controller.clock(byte, &mut crate_);
        assert!(controller.held() <= 3);
    }
    // Liveness.
    crate_.cycles = 0;
    let command = Message::Command {
        crate_address: controller.config().address,
        station: 3,
        subaddress: 1,
        function: 0,
        data: None,
    };
    let mut buf = [0u8; MAX_MESSAGE];
    let len = command.encode(&mut buf).unwrap();
    for &byte in [WAIT].iter().chain(&buf[..len]).chain(&[WAIT; 8]) {
        controller.clock(byte, &mut crate_);
    }
    assert_eq!(crate_.cycles, 1);
});
