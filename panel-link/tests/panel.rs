//! The 1977 panel link in simulated time: host and panel on a 4800-baud line with start, parity
//! and stop bits, MOT polled every 10 ms, the key repeated every 20 ms.
//!
//! Properties: after any single damaged byte the panel's registers are right again once the next
//! full sequence is through; a key is never delivered twice or altered, whatever the noise.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::unreachable,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "a test may panic: that is how it fails"
)]

use std::collections::VecDeque;

use proptest::prelude::*;
use regler_panel_link::line::{Framing, Noise};
use regler_panel_link::panel::{Host, HostConfig, HostEvent, Panel};

/// One byte at 4800 baud with 11 bits: 2292 µs.
const BYTE_US: u64 = 11 * 1_000_000 / 4800;
const STEP_US: u64 = 100;

/// A one-way line: frames queue at the transmitter and arrive a byte-time after they start.
#[derive(Default)]
struct Line {
    queue: VecDeque<u16>,
    in_flight: Option<(u16, u64)>,
    sent: u64,
}

impl Line {
    fn busy(&self) -> bool {
        self.in_flight.is_some() || !self.queue.is_empty()
    }

    /// Advances to `now`; returns a frame that finished arriving.
    fn step(&mut self, now: u64) -> Option<u16> {
        let mut arrived = None;
        if let Some((frame, at)) = self.in_flight {
            if now >= at {
                arrived = Some(frame);
                self.in_flight = None;
            }
        }
        if self.in_flight.is_none() {
            if let Some(frame) = self.queue.pop_front() {
                self.in_flight = Some((frame, now + BYTE_US));
            }
        }
        arrived
    }
}

/// What can damage the line.
enum Damage {
    None,
    /// Host → panel byte number `index` gets its frame XORed with `mask`.
    DownByte {
        index: u64,
        mask: u16,
    },
    /// Panel → host byte number `index` gets `mask`.
    UpByte {
        index: u64,
        mask: u16,
    },
    /// Random bit errors both ways.
    Noise(Noise),
}

struct Sim<const R: usize> {
    host: Host<R>,
    panel: Panel<R>,
    down: Line,
    up: Line,
    now: u64,
    damage: Damage,
    delivered: Vec<u8>,
    timeouts: u64,
    /// Sequences completed as the panel sees them (reset bytes that arrived).
    tick_phase: u64,
}

impl<const R: usize> Sim<R> {
    fn new(damage: Damage, tick_phase: u64) -> Self {
        Self {
            host: Host::new(HostConfig::default()).unwrap(),
            panel: Panel::new(),
            down: Line::default(),
            up: Line::default(),
            now: 0,
            damage,
            delivered: Vec::new(),
            timeouts: 0,
            tick_phase: tick_phase % 20_000,
        }
    }

    fn damage(&mut self, frame: u16, down: bool, index: u64) -> u16 {
        match &mut self.damage {
            Damage::None => frame,
            Damage::DownByte { index: i, mask } if down && *i == index => frame ^ *mask,
            Damage::UpByte { index: i, mask } if !down && *i == index => frame ^ *mask,
            Damage::DownByte { .. } | Damage::UpByte { .. } => frame,
            Damage::Noise(noise) => noise.corrupt(frame, Framing::PANEL.bits()),
        }
    }

    fn step(&mut self) {
        let framing = Framing::PANEL;
        self.now += STEP_US;
        // Host transmitter.
        if !self.down.busy() {
            if let Some(byte) = self.host.next_byte() {
                self.down.queue.push_back(framing.encode(byte));
            }
        }
        if let Some(frame) = self.down.step(self.now) {
            let index = self.down.sent;
            self.down.sent += 1;
            let frame = self.damage(frame, true, index);
            self.panel.receive(framing.decode(frame));
        }
        if let Some(frame) = self.up.step(self.now) {
            let index = self.up.sent;
            self.up.sent += 1;
            let frame = self.damage(frame, false, index);
            match self.host.receive(framing.decode(frame)) {
                Some(HostEvent::Key(k)) => self.delivered.push(k),
                Some(HostEvent::KeyTimedOut) => self.timeouts += 1,
                _ => {}
            }
        }
        // The SÄN wire, sampled by the panel every step.
        if let Some(key) = self.panel.set_san(self.host.san()) {
            self.up.queue.push_back(framing.encode(key));
        }
        if self.now.is_multiple_of(10_000) {
            if let Some(HostEvent::KeyTimedOut) = self.host.poll_mot(self.panel.mot()) {
                self.timeouts += 1;
            }
        }
        if self.now % 20_000 == self.tick_phase {
            if let Some(key) = self.panel.tick_20ms() {
                self.up.queue.push_back(framing.encode(key));
            }
        }
    }

    /// Runs until the host has completed `n` more sequences and the last one has arrived.
    fn run_sequences(&mut self, n: u64) {
        let target = self.host.stats().sequences + n;
        while self.host.stats().sequences < target || self.down.busy() {
            self.step();
        }
    }

    fn run_ms(&mut self, ms: u64) {
        for _ in 0..ms * 1000 / STEP_US {
            self.step();
        }
    }
}

fn registers<const R: usize>(values: &[u8]) -> Host<R> {
    let mut host: Host<R> = Host::new(HostConfig::default()).unwrap();
    for (i, &v) in values.iter().enumerate().take(R) {
        host.set(i, v).unwrap();
    }
    host
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Any single damaged byte (any change of its 11-bit frame) in the first sequences: once the
    /// next full sequence is through, every register is right.
    #[test]
    fn registers_are_right_after_the_next_full_sequence(
        values in proptest::collection::vec(0u8..=127, 29),
        index in 0u64..90,
        mask in 1u16..(1 << 11),
    ) {
        let mut sim: Sim<29> = Sim::new(Damage::DownByte { index, mask }, 0);
        sim.host = registers(&values);
        // The damaged byte is within the first three sequences (30 bytes each)…
        sim.run_sequences(3);
        // …the next full sequence sets everything right.
        sim.run_sequences(1);
        prop_assert_eq!(sim.panel.registers(), sim.host.registers());
    }

    /// Updates while sending: the panel shows the newest values after one more full sequence.
    #[test]
    fn updates_at_any_time_arrive(
        first in proptest::collection::vec(0u8..=127, 7),
        second in proptest::collection::vec(0u8..=127, 7),
        after_ms in 0u64..40,
    ) {
        let mut sim: Sim<7> = Sim::new(Damage::None, 0);
        sim.host = registers(&first);
        sim.run_ms(after_ms);
        for (i, &v) in second.iter().enumerate() {
            sim.host.set(i, v).unwrap();
        }
        sim.run_sequences(2);
        prop_assert_eq!(&sim.panel.registers()[..], &second[..]);
    }

    /// Any single damaged byte on the key line: every key arrives, once, unaltered, in order.
    #[test]
    fn a_damaged_key_byte_costs_nothing(
        keys in proptest::collection::vec(0u8..=255, 1..6),
        index in 0u64..12,
        mask in 1u16..(1 << 11),
        phase in 0u64..200,
    ) {
        let mut sim: Sim<7> = Sim::new(Damage::UpByte { index, mask }, phase * 100);
        for &k in &keys {
            sim.panel.press(k).unwrap();
        }
        sim.run_ms(2_000);
        prop_assert_eq!(&sim.delivered, &keys);
        prop_assert_eq!(sim.timeouts, 0);
        prop_assert_eq!(sim.panel.keys_waiting(), 0);
    }

    /// Random bit errors both ways, up to 1 in 100 bits: what arrives is always a key pressed,
    /// in the order pressed, never twice; the displays keep being refreshed.
    #[test]
    fn noise_never_duplicates_or_alters_a_key(
        keys in proptest::collection::vec(0u8..=255, 1..8),
        rate in 0.0f64..0.01,
        seed in any::<u64>(),
        phase in 0u64..200,
    ) {
        let mut sim: Sim<7> = Sim::new(Damage::Noise(Noise::new(rate, seed).unwrap()), phase * 100);
        for &k in &keys {
            sim.panel.press(k).unwrap();
        }
        sim.run_ms(3_000);
        // `delivered` must be a subsequence of `keys`, taken in order, each at most once.
        let mut rest = keys.iter();
        for d in &sim.delivered {
            prop_assert!(rest.any(|k| k == d), "delivered {:?} from pressed {:?}", sim.delivered, keys);
        }
        prop_assert_eq!(sim.delivered.len() as u64 + sim.timeouts, keys.len() as u64);
        prop_assert!(sim.host.stats().sequences > 50);
    }
}

#[test]
fn a_panel_that_was_off_is_right_after_the_next_full_sequence() {
    // The panel powers up in the middle of a sequence: it ignores bytes until the first reset.
    let mut sim: Sim<46> = Sim::new(Damage::None, 0);
    sim.host = registers(&(0..46).map(|v| v as u8 + 1).collect::<Vec<_>>());
    for _ in 0..5 {
        sim.host.next_byte(); // five bytes went out before the panel listened
    }
    sim.run_sequences(1); // the rest of the broken sequence: ignored, the counter is not set
    assert_eq!(sim.panel.registers(), &[0; 46]);
    sim.run_sequences(1);
    assert_eq!(sim.panel.registers(), sim.host.registers());
}
