//! Instructions per operation on the Cortex-M4F and the Cortex-M0: each hot path runs N times,
//! then 2N times, between calls of `marker`; `on-target/cycles` runs this single-stepped under
//! QEMU, counts the instructions between markers and reports (count(2N) − count(N)) / N, which
//! cancels the set-up and leaves the operation and its loop. On the M0 (no FPU) `f32` is soft
//! float: the rows of `Pid<I16F16>` against `Pid<f32>` there are the reason fixed point exists.
#![no_std]
#![no_main]

use core::hint::black_box;

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use fixed::types::I16F16;
use panic_semihosting as _;
use regler_panel_link::highway::{
    Controller, ControllerConfig, Cycle, Dataway, MAX_MESSAGE, Message, WAIT,
};
use regler_pid::{Config, Kind, Pid, Scalar};
use regler_trolley_id::decode;

/// Operations per pass: a multiple of 256, so that both passes of an operation with work done
/// once per 256 calls (the timer queue moves the next 256-tick block's timers down once per
/// block; the highway traffic below repeats every 256 bytes) hold it in proportion.
const N: u32 = 256;

/// Where the trace is cut; `on-target/cycles` finds its address with `llvm-nm`.
#[unsafe(no_mangle)]
#[inline(never)]
pub extern "C" fn regler_marker(phase: u32) {
    black_box(phase);
}

fn twice(name: &str, mut op: impl FnMut()) {
    hprintln!("op {}", name);
    regler_marker(0);
    for _ in 0..N {
        op();
    }
    regler_marker(1);
    for _ in 0..2 * N {
        op();
    }
    regler_marker(2);
}

/// No controller, out of line: the output is the error.
#[inline(never)]
fn no_controller(y: f32) -> f32 {
    1.0 - y
}

/// One regler sample out of line.
#[inline(never)]
fn regler_sample(pid: &mut Pid<f32>, y: f32) -> f32 {
    pid.update(1.0, y)
}

/// One regler sample in fixed point out of line.
#[inline(never)]
fn fixed_sample(pid: &mut Pid<I16F16>, y: I16F16) -> I16F16 {
    pid.update(I16F16::ONE, y)
}

/// No controller in fixed point, out of line: the output is the error.
#[inline(never)]
fn no_controller_fixed(y: I16F16) -> I16F16 {
    Scalar::sub(I16F16::ONE, y)
}

/// One `pid` crate sample out of line.
#[inline(never)]
fn anchor_sample(pid: &mut pid::Pid<f32>, y: f32) -> f32 {
    pid.next_control_output(y).output
}

/// Ends the run with a failure (a configuration refused: it never is).
fn fail() -> ! {
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}

#[entry]
fn main() -> ! {
    hprintln!("n {}", N);
    // One function per section, out of line, so that their states do not share one stack
    // frame. The M0 (micro:bit) has 16 KiB of RAM: the 256-entry timer queue and tracker do not
    // fit beside the rest, so its table has the controllers and the decoder.
    pid_rows();
    #[cfg(not(micro_bit))]
    timer_queue_rows();
    #[cfg(not(micro_bit))]
    tracker_rows();
    decode_rows();
    highway_rows();
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::wfi();
    }
}

/// The controllers: regler's in `f32` and `I16F16`, and the `pid` crate.
#[inline(never)]
#[allow(
    clippy::field_reassign_with_default,
    reason = "the contract's own spelling for an f32 config"
)]
fn pid_rows() {
    // The benches' loop: a controller with everything on and a first-order plant.
    let mut c = Config::<f32>::default();
    c.kind = Kind::PID;
    c.k = black_box(2.0);
    c.ti = black_box(1.0);
    // Td as in benches/src/pid_loop.rs: the `pid` crate's unfiltered derivative leaves its loop
    // stable (at 0.2 s it rings between the limits).
    c.td = black_box(0.02);
    c.n = 10.0;
    c.tt = Some(0.05);
    c.h = 0.01;
    c.ymin = -5.0;
    c.ymax = 5.0;
    c.dymax = Some(0.5);
    let Ok(mut regler) = Pid::<f32>::new(&c) else {
        fail()
    };
    let mut y = 0.0f32;
    twice("regler Pid<f32>::update + plant", || {
        let u = regler.update(1.0, black_box(y));
        y += 0.05 * (u - y);
    });
    // The anchor as its docs configure it and as `benches/src/pid_shapes.rs` does: the gains of
    // the configuration above (kp = K, ki = K·h/Ti, kd = K·Td/h) and every limit the output's.
    let mut anchor = pid::Pid::new(1.0f32, 5.0);
    anchor.p(black_box(2.0f32), 5.0).i(0.02, 5.0).d(4.0, 5.0);
    let mut y = 0.0f32;
    twice("pid crate Pid<f32>::next_control_output + plant", || {
        let u = anchor.next_control_output(black_box(y)).output;
        y += 0.05 * (u - y);
    });
    // The loop and plant alone (the output is the error): subtract it for a controller's cost.
    let mut y = 0.0f32;
    twice("plant alone", || {
        let u = 1.0 - black_box(y);
        y += 0.05 * (u - y);
    });
    let mut y = 0.0f32;
    twice("plant alone, one call per sample", || {
        let u = no_controller(black_box(y));
        y += 0.05 * (u - y);
    });
    // The same two, called out of line once per sample, as a timer interrupt calls them.
    regler.reset();
    let mut y = 0.0f32;
    twice(
        "regler Pid<f32>::update + plant, one call per sample",
        || {
            let u = regler_sample(&mut regler, black_box(y));
            y += 0.05 * (u - y);
        },
    );
    anchor.reset_integral_term();
    let mut y = 0.0f32;
    twice(
        "pid crate Pid<f32>::next_control_output + plant, one call per sample",
        || {
            let u = anchor_sample(&mut anchor, black_box(y));
            y += 0.05 * (u - y);
        },
    );
    // The same controller in fixed point (same configuration, the plant in I16F16 too), one
    // call per sample; with the plant alone in I16F16 the difference is one update.
    let Ok(mut fixed) = Pid::<I16F16>::new(&c) else {
        fail()
    };
    let plant = I16F16::from_num(0.05);
    let mut y = I16F16::ZERO;
    twice(
        "regler Pid<I16F16>::update + plant, one call per sample",
        || {
            let u = fixed_sample(&mut fixed, black_box(y));
            y = Scalar::add(y, Scalar::mul(plant, Scalar::sub(u, y)));
        },
    );
    let mut y = I16F16::ZERO;
    twice("plant alone in I16F16, one call per sample", || {
        let u = no_controller_fixed(black_box(y));
        y = Scalar::add(y, Scalar::mul(plant, Scalar::sub(u, y)));
    });
}

/// The timer queue.
#[cfg(not(micro_bit))]
#[inline(never)]
fn timer_queue_rows() {
    use regler_scan_cycle::TimerQueue;
    let mut queue: TimerQueue<u16, 256> = TimerQueue::new();
    for n in 0..256u16 {
        let _ = queue.insert(u32::from(n) + 1, n);
    }
    twice(
        "TimerQueue<u16, 256>::tick, one expiry re-armed per tick",
        || {
            let mut fired = None;
            queue.tick(|a| fired = Some(a));
            if let Some(a) = fired {
                let _ = queue.insert(256, a);
            }
        },
    );
}

/// The chain tracker.
#[cfg(not(micro_bit))]
#[inline(never)]
fn tracker_rows() {
    use regler_chain_tracker::{DistanceTable, Tracker};
    let Ok(table) = DistanceTable::<8>::new(1000, &[100, 200, 300, 400, 500, 600, 700, 800]) else {
        fail()
    };
    let Ok(mut tracker) = Tracker::<u16, 256, 8>::new(table, 6) else {
        fail()
    };
    let mut k = 0u32;
    twice(
        "Tracker<u16, 256, 8>::pulse, a trolley entering every 4 pulses",
        || {
            if k.is_multiple_of(4) {
                let _ = tracker.enter(k as u16, (k % 8) as usize);
            }
            tracker.pulse(|e| {
                black_box(e);
            });
            k = k.wrapping_add(1);
        },
    );
}

/// The trolley code.
#[inline(never)]
fn decode_rows() {
    let mut word = 0u16;
    twice("decode", || {
        black_box(decode(black_box(word)).is_ok());
        word = word.wrapping_add(1) & 0x1FFF;
    });
}

/// The serial highway's crate controller, one byte clock per call.
#[inline(never)]
fn highway_rows() {
    // The serial highway's crate controller (crate 7), one byte clock per call, on 256 bytes of
    // mixed traffic repeated: commands (a third to crate 7, which runs a dataway cycle and
    // answers), replies and demands made as `benches/src/highway.rs` makes them, back to back,
    // WAIT after the last whole message.
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
    let mut traffic = [WAIT; 256];
    let (mut at, mut x, mut k) = (0usize, 0x2545_F491_4F6C_DD1Du64, 0u32);
    loop {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let f = (x % 32) as u8;
        let crate_address = if k % 3 == 0 {
            7
        } else {
            1 + (x >> 8) as u8 % 62
        };
        let message = match k % 4 {
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
                status: regler_panel_link::highway::Status::from_bits((x >> 40) as u8),
                data: (x & 1 == 0).then_some((x >> 12) as u32 & 0xFF_FFFF),
            },
            _ => Message::Demand {
                crate_address,
                sgl: 1 + (x >> 20) as u8 % 31,
            },
        };
        let mut buf = [0u8; MAX_MESSAGE];
        let Ok(len) = message.encode(&mut buf) else {
            fail()
        };
        if at + len > traffic.len() {
            break;
        }
        traffic[at..at + len].copy_from_slice(&buf[..len]);
        at += len;
        k += 1;
    }
    let Ok(mut controller) = Controller::new(ControllerConfig {
        address: 7,
        demand_repeat: 0,
    }) else {
        fail()
    };
    let mut crate_ = Registers([0; 32]);
    let mut byte = 0usize;
    twice(
        "highway Controller::clock, one byte of mixed traffic",
        || {
            black_box(controller.clock(black_box(traffic[byte]), &mut crate_));
            byte = (byte + 1) % traffic.len();
        },
    );
}
