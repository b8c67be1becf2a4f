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
    /// Where in the 20 ms the panel's tick falls (µs).
    tick_phase: u64,
    /// Flipped into the MOT level the host sees, poll by poll (repeating; empty: none).
    mot_glitch: Vec<bool>,
    polls: usize,
    /// The host's transmitter was told to leave the line idle until then (µs).
    idle_until: u64,
    /// The panel samples the SÄN wire only on its 20 ms tick (the slowest the handshake
    /// allows), not at every step.
    san_on_tick: bool,
    /// When SÄN last rose (µs), while it is up.
    san_since: Option<u64>,
    /// The longest time from SÄN rising to the key delivered (µs).
    longest_key_exchange: u64,
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
            mot_glitch: Vec::new(),
            polls: 0,
            idle_until: 0,
            san_on_tick: false,
            san_since: None,
            longest_key_exchange: 0,
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
        // Host transmitter: asked once per byte time while the line is free; `None` leaves the
        // line idle for that byte time.
        if !self.down.busy() && self.now >= self.idle_until {
            match self.host.next_byte() {
                Some(byte) => self.down.queue.push_back(framing.encode(byte)),
                None => self.idle_until = self.now + BYTE_US,
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
                Some(HostEvent::Key(k)) => {
                    self.delivered.push(k);
                    let since = self.san_since.unwrap();
                    self.longest_key_exchange = self.longest_key_exchange.max(self.now - since);
                }
                Some(HostEvent::KeyTimedOut) => self.timeouts += 1,
                _ => {}
            }
        }
        self.san_since = match (self.host.san(), self.san_since) {
            (true, None) => Some(self.now),
            (true, since) => since,
            (false, _) => None,
        };
        // The SÄN wire, sampled by the panel every step (or only on its tick, below).
        if !self.san_on_tick {
            if let Some(key) = self.panel.set_san(self.host.san()) {
                self.up.queue.push_back(framing.encode(key));
            }
        }
        if self.now.is_multiple_of(10_000) {
            let glitch = match self.mot_glitch.len() {
                0 => false,
                n => self.mot_glitch[self.polls % n],
            };
            self.polls += 1;
            if let Some(HostEvent::KeyTimedOut) = self.host.poll_mot(self.panel.mot() ^ glitch) {
                self.timeouts += 1;
            }
        }
        if self.now % 20_000 == self.tick_phase {
            let sampled = if self.san_on_tick {
                self.panel.set_san(self.host.san())
            } else {
                None
            };
            let repeat = self.panel.tick_20ms();
            if let Some(key) = sampled.or(repeat) {
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

// Under Miri each property below draws one case: a case simulates seconds of the line.
proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 1 } else { 300 }))]

    /// Any single damaged byte (any change of its 11-bit frame) in the first sequences: once the
    /// next full sequence is through, every register is right.
    #[test]
    #[cfg_attr(miri, ignore = "four sequences of a 29-register panel in 100 µs steps per case: minutes under Miri; runs natively in every CI run")]
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
    #[cfg_attr(miri, ignore = "2 simulated seconds of the line in 100 µs steps per case: minutes under Miri; runs natively in every CI run")]
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
    #[cfg_attr(miri, ignore = "3 simulated seconds of a noisy line in 100 µs steps per case: minutes under Miri; runs natively in every CI run")]
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

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 1 } else { 100 }))]

    /// A MOT wire that chatters (any level flipped at any poll, repeating): keys are still never
    /// duplicated or altered, and the displays keep being refreshed; once the wire behaves again,
    /// the keys still waiting get through.
    #[test]
    #[cfg_attr(miri, ignore = "6 simulated seconds of the line in 100 µs steps per case: minutes under Miri; runs natively in every CI run")]
    fn a_chattering_mot_never_duplicates_or_alters_a_key(
        keys in proptest::collection::vec(0u8..=255, 1..6),
        glitch in proptest::collection::vec(any::<bool>(), 1..40),
        phase in 0u64..200,
    ) {
        let mut sim: Sim<7> = Sim::new(Damage::None, phase * 100);
        sim.mot_glitch = glitch;
        for &k in &keys {
            sim.panel.press(k).unwrap();
        }
        let before = sim.host.stats().sequences;
        sim.run_ms(3_000);
        let mut rest = keys.iter();
        for d in &sim.delivered {
            prop_assert!(rest.any(|k| k == d), "delivered {:?} from pressed {:?}", sim.delivered, keys);
        }
        // 3 s with at most 1.1 s between sequences (default configuration).
        prop_assert!(sim.host.stats().sequences - before >= 2);
        let (delivered, waiting) = (sim.delivered.len(), sim.panel.keys_waiting());
        sim.mot_glitch.clear();
        sim.run_ms(3_000);
        prop_assert_eq!(sim.panel.keys_waiting(), 0);
        prop_assert_eq!(sim.delivered.len(), delivered + waiting);
    }
}

/// Makes a repeating glitch pattern one where no two consecutive polls lie (the last poll and
/// the first count as consecutive: the pattern repeats).
fn no_two_consecutive(mut glitch: Vec<bool>) -> Vec<bool> {
    for i in 1..glitch.len() {
        if glitch[i - 1] {
            glitch[i] = false;
        }
    }
    let n = glitch.len();
    if n > 0 && glitch[0] && glitch[n - 1] {
        glitch[n - 1] = false;
    }
    glitch
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 1 } else { 150 }))]

    /// Issue 19 (attack, item 2): a MOT line that lies on any polls (any repeating pattern of
    /// lies, and patterns in which no two consecutive polls lie), a panel that samples SÄN only
    /// on its 20 ms tick (the slowest the handshake allows) or at once, 1, 2 or 7 registers: no
    /// key is ever delivered twice, none is altered, they come in the order pressed.
    #[test]
    #[cfg_attr(miri, ignore = "seconds of the simulated line in 100 µs steps per case: minutes under Miri; runs natively in every CI run")]
    fn a_lying_mot_line_never_delivers_a_key_twice(
        n in 1usize..6,
        glitch in proptest::collection::vec(any::<bool>(), 1..40),
        single in any::<bool>(),
        phase in 0u64..200,
        san_on_tick in any::<bool>(),
        registers in 0usize..3,
    ) {
        let glitch = if single { no_two_consecutive(glitch) } else { glitch };
        let keys: Vec<u8> = (0..n as u8).map(|k| 0x41 + k).collect();
        let delivered = match registers {
            0 => mot_lies::<1>(&keys, &glitch, phase, san_on_tick),
            1 => mot_lies::<2>(&keys, &glitch, phase, san_on_tick),
            _ => mot_lies::<7>(&keys, &glitch, phase, san_on_tick),
        };
        // Distinct keys pressed in increasing order: delivered must be strictly increasing.
        prop_assert!(
            delivered.windows(2).all(|w| w[0] < w[1]) && delivered.iter().all(|k| keys.contains(k)),
            "pressed {:?}, delivered {:?}, MOT lies {:?}", keys, delivered, glitch
        );
    }
}

fn mot_lies<const R: usize>(
    keys: &[u8],
    glitch: &[bool],
    phase: u64,
    san_on_tick: bool,
) -> Vec<u8> {
    let mut sim: Sim<R> = Sim::new(Damage::None, phase * 100);
    sim.mot_glitch = glitch.to_vec();
    sim.san_on_tick = san_on_tick;
    for &k in keys {
        sim.panel.press(k).unwrap();
    }
    sim.run_ms(3_000);
    sim.delivered
}

/// Issue 19 (attack, item 5): on a clean line, a panel that samples SÄN only on its 20 ms tick,
/// at phases of that tick (700 µs apart over 20 ms) and of the host's sequences (100 µs apart
/// over 10 ms) against the host's polls, with the smallest key
/// time-out the host accepts: every key is delivered, none times out. And the second key byte
/// does arrive more than 40 ms after SÄN rose at some phase, so 5 polls (the 5th may come 40 ms
/// after the rise) would lose keys: 6 is the least that works.
#[test]
#[cfg_attr(
    miri,
    ignore = "2 900 simulated panels (every phase and start): hours under Miri; runs natively in every CI run"
)]
fn the_smallest_key_time_out_loses_no_key_on_a_clean_line() {
    let config = HostConfig {
        key_timeout_polls: regler_panel_link::panel::MIN_KEY_TIMEOUT_POLLS,
        ..HostConfig::default()
    };
    assert_eq!(config.key_timeout_polls, 6);
    let mut longest = 0;
    for phase in (0..200).step_by(7) {
        for offset in 0..100 {
            let mut sim: Sim<7> = Sim::new(Damage::None, phase * 100);
            sim.host = Host::new(config).unwrap();
            sim.san_on_tick = true;
            sim.idle_until = offset * STEP_US; // the host starts sending then
            let keys = [0x10, 0x11];
            for k in keys {
                sim.panel.press(k).unwrap();
            }
            sim.run_ms(200);
            let at = (phase * 100, offset * 100);
            assert_eq!(sim.delivered, keys, "tick phase, host start (µs): {at:?}");
            assert_eq!(sim.timeouts, 0);
            longest = longest.max(sim.longest_key_exchange);
        }
    }
    assert!(
        (40_000..=40_000 + BYTE_US + 2 * STEP_US).contains(&longest),
        "the second key byte came {longest} µs after SÄN rose"
    );
}

/// The attacker's timed reproducer: one MOT poll reads low while the panel still holds MOT high,
/// the panel samples SÄN on its 20 ms tick. The host used to leave the exchange on that one low
/// poll, send a sequence (shorter than 20 ms for two registers) and raise SÄN again before the
/// panel ever saw it low: the key was delivered twice.
#[test]
fn one_false_mot_low_poll_does_not_deliver_a_key_twice() {
    let mut host: Host<2> = Host::new(HostConfig::default()).unwrap();
    let mut panel: Panel<2> = Panel::new();
    let mut keys = vec![];
    panel.press(0x41).unwrap();
    host.poll_mot(panel.mot()); // t = 0 ms: MOT high
    assert_eq!(host.next_byte(), Some(RESET));
    assert_eq!(host.next_byte(), None); // SÄN rises between sequences
    assert!(host.san());
    let k = panel.set_san(host.san()).unwrap(); // 20 ms tick: SÄN sampled high
    keys.extend(host.receive(Ok(k)));
    let _ = host.poll_mot(panel.mot()); // 30 ms
    let k = panel.tick_20ms().unwrap(); // 40 ms: the repeat (SÄN sampled: still high)
    keys.extend(host.receive(Ok(k)));
    assert_eq!(keys, [HostEvent::Key(0x41)]);
    assert!(!host.san()); // ≈ 42 ms: SÄN dropped
    assert!(panel.mot());
    host.poll_mot(false); // 50 ms: the MOT line lies low for one poll
    for _ in 0..4 {
        let _ = host.next_byte(); // 4 byte times: what a sequence of two registers takes
    }
    host.poll_mot(panel.mot()); // 60 ms: MOT (really high) seen
    let _ = host.next_byte();
    // 60 ms tick: the panel samples SÄN. With the bug it was high again (the panel never saw
    // it low) and the key went out once more.
    let _ = panel.set_san(host.san());
    for poll in 0..20 {
        if let Some(k) = panel.tick_20ms() {
            keys.extend(host.receive(Ok(k)));
        }
        let _ = host.poll_mot(panel.mot());
        for _ in 0..8 {
            let _ = host.next_byte();
        }
        let _ = host.poll_mot(panel.mot());
        if let Some(k) = panel.set_san(host.san()) {
            keys.extend(host.receive(Ok(k)));
        }
        assert!(poll < 19 || panel.keys_waiting() == 0);
    }
    assert_eq!(
        keys,
        [HostEvent::Key(0x41)],
        "one press of 0x41, the host delivered {keys:?}"
    );
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

// ---------------------------------------------------------------------------------------------
// Bit errors in the register stream (issue 19, item 5): what the panel may show.
// ---------------------------------------------------------------------------------------------

use regler_panel_link::line::{BitReceiver, LineError};
use regler_panel_link::panel::{MAX_VALUE, RESET};

/// The host's byte stream, from the host machine itself: sequence `a`, then sequence `b` (the
/// host's registers changed once the first sequence was counted), then `b` again, and so on.
/// Returns the bytes; reset bytes stand at every multiple of `R + 1`.
fn stream<const R: usize>(a: &[u8; R], b: &[u8; R], bytes: usize) -> Vec<u8> {
    let out: Vec<u8> = slots(a, b, bytes).into_iter().flatten().collect();
    for (k, &byte) in out.iter().enumerate() {
        assert_eq!(byte == RESET, k % (R + 1) == 0, "the stream's layout");
    }
    out
}

/// The same stream, byte time by byte time as the host gives it, with `None` where the host
/// leaves the line idle (one byte time after every reset byte), until it holds `bytes` bytes.
fn slots<const R: usize>(a: &[u8; R], b: &[u8; R], bytes: usize) -> Vec<Option<u8>> {
    let mut host: Host<R> = Host::new(HostConfig::default()).unwrap();
    for (i, &v) in a.iter().enumerate() {
        host.set(i, v).unwrap();
    }
    let mut out = Vec::new();
    while out.iter().flatten().count() < bytes {
        out.push(host.next_byte());
        if host.stats().sequences == 1 {
            for (i, &v) in b.iter().enumerate() {
                host.set(i, v).unwrap();
            }
        }
    }
    for (k, slot) in out.iter().enumerate() {
        let place = k % (R + 2);
        let expect = match place {
            0 => Some(RESET),
            1 => None,
            _ => *slot,
        };
        assert_eq!(*slot, expect, "the stream's layout at {k}");
        assert!(slot.is_some_and(|v| v <= MAX_VALUE) || place <= 1);
    }
    out
}

/// Per register, the set of values (bit `v` of a `u128`) the panel may show.
fn allowed<const R: usize>(a: &[u8; R], b: &[u8; R]) -> [u128; R] {
    core::array::from_fn(|i| 1 | (1 << a[i]) | (1 << b[i]))
}

/// Every register shows a value in its allowed set.
fn assert_allowed<const R: usize>(shown: &[u8; R], allowed: &[u128; R], what: &dyn Fn() -> String) {
    for (i, (&v, &set)) in shown.iter().zip(allowed).enumerate() {
        assert!(
            v <= MAX_VALUE && set >> v & 1 == 1,
            "register {i} shows {v}, a value the host never sent for it: display {shown:?}; {}",
            what()
        );
    }
}

/// Every 1- and 2-bit change of an 11-bit panel frame (start, 8 data, parity, stop).
fn masks_1_2() -> Vec<u16> {
    (0..11)
        .flat_map(|i| (i..11).map(move |j| (1u16 << i) | (1 << j)))
        .collect()
}

/// Issue 19 item 5, the example: register 2 = 0x7E with bits 0 and 7 flipped reads as the reset
/// byte (parity still even). The panel must not show `[40, 50, 60, 70, 50, 60, 70]`.
#[test]
fn issue_example_a_2_bit_error_never_shifts_the_display() {
    let values = [10u8, 20, 126, 40, 50, 60, 70];
    let bytes = stream::<7>(&values, &values, 4 * 8 + 1);
    let framing = Framing::PANEL;
    let damaged = 8 + 1 + 2; // the second sequence's register 2
    assert_eq!(
        framing.decode(framing.encode(bytes[damaged]) ^ (0x81 << 1)),
        Ok(RESET)
    );
    let mut panel: Panel<7> = Panel::new();
    for (k, &byte) in bytes.iter().enumerate() {
        let mut frame = framing.encode(byte);
        if k == damaged {
            frame ^= 0x81 << 1;
        }
        panel.receive(framing.decode(frame));
        if k >= 8 {
            assert!(
                panel.registers() == &values,
                "after byte {k}: the panel shows {:?}",
                panel.registers()
            );
        }
    }
}

/// Every 1- and 2-bit error of one frame (data, parity, start and stop bits), for every value
/// 0..=127 of every register and for the reset bytes on both sides of the sequence, and a 1-bit
/// error in each of any two frames from one of those reset bytes to the other: after every
/// byte each register shows a value the host sent for that register — or, only for the register
/// whose own byte took an error that the parity cannot see, that wrong 7-bit value — and once the
/// next clean sequence (with the reset bytes on both sides) is through, every register is right.
fn every_frame_error<const R: usize>() {
    let framing = Framing::PANEL;
    let masks = masks_1_2();
    // Distinct values per register and per sequence, so that a shift shows.
    let a: [u8; R] = core::array::from_fn(|i| (i % 64) as u8);
    let base_b: [u8; R] = core::array::from_fn(|i| (64 + i % 64) as u8);
    let seq = R + 1;
    let mut cases = 0u64;
    // Damage at stream index d: the reset before b (seq), b's registers, the reset after b.
    for d in seq..=2 * seq {
        let register = d.checked_sub(seq + 1).filter(|&r| r < R);
        let values: Vec<u8> = match register {
            Some(_) => (0..=MAX_VALUE).collect(),
            None => vec![base_b[0]],
        };
        for &v in &values {
            let mut b = base_b;
            if let Some(r) = register {
                b[r] = v;
            }
            let bytes = stream::<R>(&a, &b, 5 * seq);
            // The first reset after d starts the next clean sequence.
            let clean_end = (d / seq + 1) * seq + seq;
            let mut prefix: Panel<R> = Panel::new();
            for &byte in &bytes[..d] {
                prefix.receive(Ok(byte));
            }
            let mut outcomes: Vec<Result<u8, LineError>> = masks
                .iter()
                .map(|&m| framing.decode(framing.encode(bytes[d]) ^ m))
                .collect();
            outcomes.sort_by_key(|o| format!("{o:?}"));
            outcomes.dedup();
            for got in outcomes {
                cases += 1;
                let mut allow = allowed(&a, &b);
                if let (Some(r), Ok(w)) = (register, got) {
                    if w <= MAX_VALUE {
                        allow[r] |= 1 << w; // undetectable: the parity sees even flips only
                    }
                }
                let what = || format!("R {R}, byte {d} (value {}) received as {got:?}", bytes[d]);
                let mut panel = prefix.clone();
                panel.receive(got);
                let mut last = *panel.registers();
                assert_allowed(&last, &allow, &what);
                for &byte in &bytes[d + 1..=clean_end] {
                    panel.receive(Ok(byte));
                    if panel.registers() != &last {
                        last = *panel.registers();
                        assert_allowed(&last, &allow, &what);
                    }
                }
                assert_eq!(
                    panel.registers(),
                    &b,
                    "after the next clean sequence: {}",
                    what()
                );
            }
        }
    }
    assert!(cases > (R as u64) * 128 * 30);

    // One flipped bit in each of two frames, anywhere from the reset byte before b to the reset
    // byte after it (a 1-bit error reads the same whatever the value: the outcomes are deduped).
    let bytes = stream::<R>(&a, &base_b, 5 * seq);
    let one_bit = |d: usize| {
        let mut o: Vec<Result<u8, LineError>> = (0..11)
            .map(|k| framing.decode(framing.encode(bytes[d]) ^ (1 << k)))
            .collect();
        o.sort_by_key(|o| format!("{o:?}"));
        o.dedup();
        o
    };
    for d1 in seq..=2 * seq {
        for d2 in d1 + 1..=2 * seq {
            for g1 in one_bit(d1) {
                for g2 in one_bit(d2) {
                    let allow = allowed(&a, &base_b);
                    let what = || format!("R {R}, bytes {d1} and {d2} read as {g1:?}, {g2:?}");
                    let mut panel: Panel<R> = Panel::new();
                    let mut last = *panel.registers();
                    let clean_end = (d2 / seq + 1) * seq + seq;
                    for (k, &byte) in bytes.iter().enumerate().take(clean_end + 1) {
                        panel.receive(match k {
                            _ if k == d1 => g1,
                            _ if k == d2 => g2,
                            _ => Ok(byte),
                        });
                        if panel.registers() != &last {
                            last = *panel.registers();
                            assert_allowed(&last, &allow, &what);
                        }
                    }
                    assert_eq!(panel.registers(), &base_b, "{}", what());
                }
            }
        }
    }
}

#[test]
#[cfg_attr(
    miri,
    ignore = "every one- and two-bit error of every frame of a sequence, every value: hours under Miri; runs natively in every CI run"
)]
fn every_1_and_2_bit_frame_error_loading_desk() {
    every_frame_error::<7>();
}

#[test]
#[cfg_attr(
    miri,
    ignore = "every one- and two-bit error of every frame of a sequence, every value: hours under Miri; runs natively in every CI run"
)]
fn every_1_and_2_bit_frame_error_lane_panel() {
    every_frame_error::<29>();
}

#[test]
#[cfg_attr(
    miri,
    ignore = "every one- and two-bit error of every frame of a sequence, every value: hours under Miri; runs natively in every CI run"
)]
fn every_1_and_2_bit_frame_error_central_desk() {
    every_frame_error::<46>();
}

// ---------------------------------------------------------------------------------------------
// Whatever the MOT line does (issue 19, item 6): the displays keep being refreshed.
// ---------------------------------------------------------------------------------------------

/// The host feeding a panel, the transmitter fed the moment it is ready (one byte per byte
/// time), MOT polled every 10 ms at the level `mot(poll number)` says, no key bytes ever coming
/// back. The last two registers hold a 14-bit counter the application bumps at every event, so
/// every sequence the host sends differs from the one before, and a refresh (a sequence that got
/// through to its last register) shows on the display.
/// Returns the longest time (µs) the display went without changing, from its first change to
/// the end of the run, and the number of changes.
fn longest_refresh_gap<const R: usize>(
    config: HostConfig,
    mut mot: impl FnMut(u64) -> bool,
    run_us: u64,
) -> (u64, u64) {
    const { assert!(R >= 2) };
    let mut host: Host<R> = Host::new(config).unwrap();
    let mut panel: Panel<R> = Panel::new();
    let mut in_flight: Option<(u8, u64)> = None;
    let (mut next_poll, mut poll) = (10_000u64, 0u64);
    let mut last = *panel.registers();
    let (mut last_change, mut longest, mut changes) = (None::<u64>, 0u64, 0u64);
    let mut counter = 0u16;
    let (mut now, mut idle_until) = (0u64, 0u64);
    while now <= run_us {
        counter = (counter + 1) % (1 << 14);
        host.set(R - 2, (counter & 0x7F) as u8).unwrap();
        host.set(R - 1, (counter >> 7) as u8).unwrap();
        if let Some((byte, at)) = in_flight {
            if at == now {
                panel.receive(Ok(byte));
                in_flight = None;
                if panel.registers() != &last {
                    last = *panel.registers();
                    if let Some(t) = last_change {
                        longest = longest.max(now - t);
                    }
                    last_change = Some(now);
                    changes += 1;
                }
            }
        }
        if now == next_poll {
            let _ = host.poll_mot(mot(poll));
            poll += 1;
            next_poll += 10_000;
        }
        if in_flight.is_none() && now >= idle_until {
            match host.next_byte() {
                Some(byte) => in_flight = Some((byte, now + BYTE_US)),
                None => idle_until = now + BYTE_US, // the line idle for a byte time
            }
        }
        now = in_flight.map_or(next_poll.min(idle_until.max(now + 1)), |(_, at)| {
            at.min(next_poll)
        });
    }
    let end_gap = last_change.map_or(run_us, |t| run_us - t);
    (longest.max(end_gap), changes)
}

/// The bound the host's docs state: `R + 3` byte times (the reset byte, the idle byte time,
/// the registers, and a byte time for a transmitter that asks once per byte time to see the
/// host sending again) plus `key_timeout_polls + mot_stuck_polls` polls of 10 ms.
fn refresh_bound<const R: usize>(config: HostConfig) -> u64 {
    (R as u64 + 3) * BYTE_US
        + (u64::from(config.key_timeout_polls) + u64::from(config.mot_stuck_polls)) * 10_000
}

/// Issue 19 item 6, the examples: MOT toggling at every poll, or dropping one poll in twelve,
/// froze the displays (0 sequences in 100 s).
#[test]
#[cfg_attr(
    miri,
    ignore = "200 simulated seconds of a loading desk: hours under Miri; runs natively in every CI run"
)]
fn issue_example_a_chattering_mot_does_not_freeze_the_displays() {
    let config = HostConfig::default();
    for (name, pattern) in [
        (
            "toggling",
            &(|p: u64| p.is_multiple_of(2)) as &dyn Fn(u64) -> bool,
        ),
        ("one poll in twelve low", &|p: u64| p % 12 != 11),
    ] {
        let (gap, changes) = longest_refresh_gap::<29>(config, pattern, 100_000_000);
        assert!(
            gap <= refresh_bound::<29>(config) && changes >= 50,
            "MOT {name}: {changes} refreshes in 100 s, longest gap {gap} µs"
        );
    }
}

/// Every periodic MOT pattern of period 1 to 8 polls (510 patterns: stuck high, stuck low,
/// toggling, short glitches…), two configurations: the display is refreshed at least every
/// bound.
#[test]
#[cfg_attr(
    miri,
    ignore = "510 MOT patterns, 5 simulated seconds each: hours under Miri; runs natively in every CI run"
)]
fn every_short_periodic_mot_pattern_keeps_the_displays_refreshed() {
    for config in [
        HostConfig::default(),
        HostConfig {
            key_timeout_polls: 6,
            mot_stuck_polls: 3,
        },
        HostConfig {
            key_timeout_polls: 7,
            mot_stuck_polls: 5,
        },
    ] {
        let bound = refresh_bound::<7>(config);
        for period in 1..=8u32 {
            for bits in 0..(1u32 << period) {
                let mot = |p: u64| bits >> (p % u64::from(period)) & 1 == 1;
                let (gap, _) = longest_refresh_gap::<7>(config, mot, 5_000_000);
                assert!(
                    gap <= bound,
                    "MOT pattern {bits:0period$b} (period {period}), {config:?}: the display \
                     went {gap} µs without a refresh (bound {bound} µs)",
                    period = period as usize
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 1 } else { 200 }))]

    /// Any MOT pattern (random levels, random run lengths), any accepted configuration: the
    /// display is refreshed at least every bound.
    #[test]
    #[cfg_attr(miri, ignore = "seconds of the simulated line per case: minutes under Miri; runs natively in every CI run")]
    fn any_mot_pattern_keeps_the_displays_refreshed(
        runs in proptest::collection::vec((any::<bool>(), 1u64..150), 1..40),
        key_timeout_polls in 6u16..30,
        mot_stuck_polls in 3u16..150,
    ) {
        let config = HostConfig { key_timeout_polls, mot_stuck_polls };
        let levels: Vec<bool> = runs.iter().flat_map(|&(l, n)| (0..n).map(move |_| l)).collect();
        let (gap, _) = longest_refresh_gap::<29>(config, |p| levels[(p % levels.len() as u64) as usize], 10_000_000);
        prop_assert!(gap <= refresh_bound::<29>(config), "gap {} µs", gap);
    }
}

/// The register stream as bits on the line, frames back to back as a UART sends them when it is
/// fed whenever it is ready — with the idle byte time the host leaves after every reset byte —
/// through a bit receiver (which loses character sync when a start bit is hit). The host's
/// registers are set to `values[k]` before sequence `k` goes out (its reset byte opens it; its
/// idle byte time and registers follow). Every single bit and every pair of bits is flipped in
/// the window from the reset byte opening sequence 2 through the idle byte time after the reset
/// byte closing sequence 3 (two whole sequences and the idle byte times on both sides; start,
/// stop and idle bits included). Checks the guarantee as the module docs state it at bit level:
/// - after a **1-bit** error, no register ever shows a value the host did not send for it (in
///   a sequence that has begun, or 0 before the first);
/// - after a 1- or 2-bit error, once the reset byte closing the second sequence after the one
///   the (last) flip fell in has arrived, every register shows the host's value of that second
///   sequence — and the next sequence's one reset byte later.
///
/// Returns (cases, pairs that showed a value never sent before recovery, not counting pairs
/// that both fell in one register's own frame — for the first register, its frame and the idle
/// byte time before it — which frames read in sync can show too).
fn every_bit_pair_on_the_line<const R: usize>(values: &[[u8; R]]) -> (u64, u64) {
    assert!(values.len() >= 9, "the stream needs nine sequences");
    let framing = Framing::PANEL;
    let mut host: Host<R> = Host::new(HostConfig::default()).unwrap();
    // Byte time by byte time: the slot, and the sequence it belongs to.
    let mut slots: Vec<(Option<u8>, usize)> = Vec::new();
    let mut seq = 0usize;
    while slots.len() < 9 * (R + 2) {
        if slots.len().is_multiple_of(R + 2) {
            seq = slots.len() / (R + 2);
            for (i, &v) in values[seq].iter().enumerate() {
                host.set(i, v).unwrap();
            }
        }
        slots.push((host.next_byte(), seq));
    }
    for (n, (slot, _)) in slots.iter().enumerate() {
        match n % (R + 2) {
            0 => assert_eq!(*slot, Some(RESET), "the stream's layout"),
            1 => assert_eq!(*slot, None, "the stream's layout"),
            _ => assert!(slot.is_some_and(|v| v <= MAX_VALUE), "the stream's layout"),
        }
    }
    let mut bits: Vec<bool> = vec![true; 3]; // the line idle before the host starts
    let mut seq_of_bit: Vec<usize> = vec![0; 3];
    for &(slot, seq) in &slots {
        let frame = slot.map_or(0x7FF, |byte| framing.encode(byte)); // idle: all ones
        bits.extend((0..11).map(|k| frame >> k & 1 == 1));
        seq_of_bit.extend([seq; 11]);
    }
    // One past the last bit of the reset byte opening sequence k.
    let reset_end = |k: usize| 3 + 11 * (k * (R + 2) + 1);
    let first = reset_end(2) - 11;
    let window = first..reset_end(4) + 11;
    let mut rx0 = BitReceiver::new(framing);
    let mut panel0: Panel<R> = Panel::new();
    for &bit in &bits[..first] {
        if let Some(got) = rx0.bit(bit) {
            panel0.receive(got);
        }
    }
    let (mut cases, mut wrong_pairs) = (0, 0);
    for i in window.clone() {
        for j in i..window.end {
            cases += 1;
            let (mut rx, mut panel) = (rx0, panel0.clone());
            let damaged = seq_of_bit[j];
            let (check, last_check) = (reset_end(damaged + 3), reset_end(damaged + 4));
            let mut last = *panel.registers();
            let mut wrong = false;
            for (k, &bit) in bits.iter().enumerate().take(last_check).skip(first) {
                if let Some(got) = rx.bit(bit ^ (k == i || k == j)) {
                    panel.receive(got);
                }
                if panel.registers() != &last {
                    last = *panel.registers();
                    let begun = seq_of_bit[k];
                    for (r, &v) in last.iter().enumerate() {
                        if v != 0 && values[..=begun].iter().all(|s| s[r] != v) {
                            assert!(
                                i != j,
                                "R {R}: one bit ({i}) flipped, register {r} shows {v}, which \
                                 the host never sent for it; values {values:?}"
                            );
                            wrong = true;
                        }
                    }
                }
                if k + 1 == check || k + 1 == last_check {
                    let shown = if k + 1 == check {
                        damaged + 2
                    } else {
                        damaged + 3
                    };
                    assert_eq!(
                        panel.registers(),
                        &values[shown],
                        "R {R}: bits {i} and {j} flipped (sequence {damaged}): not right at the \
                         reset byte closing sequence {shown}; values {values:?}"
                    );
                }
            }
            let (si, sj) = ((i - 3) / 11, (j - 3) / 11);
            let own_frame = (si == sj && si % (R + 2) >= 2) || (si % (R + 2) == 1 && sj == si + 1);
            wrong_pairs += u64::from(wrong && !own_frame);
        }
    }
    (cases, wrong_pairs)
}

#[test]
#[cfg_attr(
    miri,
    ignore = "every pair of bit errors on the line over nine sequences (190 000 runs): hours under Miri; runs natively in every CI run"
)]
fn every_1_and_2_bit_error_on_the_line() {
    let mut cases = 0;
    let issue = [10u8, 20, 126, 40, 50, 60, 70];
    let distinct: [u8; 7] = core::array::from_fn(|i| 100 + i as u8);
    for (a, b) in [
        (distinct, issue),
        (issue, distinct),
        ([0x7F; 7], [0x7E; 7]),
        ([0x7E; 7], [0x7F; 7]),
        ([0; 7], [0x7F; 7]),
        ([0x7F; 7], [0; 7]),
        (
            [0x3F, 0x5F, 0x6F, 0x77, 0x7B, 0x7D, 0x7E],
            [0x7F, 0x3F, 0x5F, 0x6F, 0x77, 0x7B, 0x7D],
        ),
        (
            [1, 2, 4, 8, 16, 32, 64],
            [0x55, 0x2A, 0x55, 0x2A, 0x55, 0x2A, 0x55],
        ),
    ] {
        // `a` for the first two sequences, `b` from the window on (constant data: the case in
        // which a receiver out of sync stayed out of sync before the idle byte time).
        let values: Vec<[u8; 7]> = (0..9).map(|k| if k < 2 { a } else { b }).collect();
        cases += every_bit_pair_on_the_line::<7>(&values).0;
    }
    assert!(cases > 8 * 24_000);
}

/// The attacker's reproducer (issue 19, panel attack item 1): the start bit of the last
/// register and bit 7 of the idle byte time after the reset byte closing the sequence. The
/// receiver, out of sync, reads a frame that passes the parity, then the reset byte's parity
/// bit as a start bit and 0xFF from the stop bit and the idle ones; the flipped idle bit makes
/// that a clean frame: a fake reset byte, and a wrong value is shown. That is the 2-bit case
/// the guarantee leaves open; it must be right two sequences later.
#[test]
fn two_flips_out_of_sync_are_right_within_two_sequences() {
    let values = [0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x73];
    let framing = Framing::PANEL;
    let mut host: Host<7> = Host::new(HostConfig::default()).unwrap();
    for (i, v) in values.iter().enumerate() {
        host.set(i, *v).unwrap();
    }
    let mut rx = BitReceiver::new(framing);
    let mut panel: Panel<7> = Panel::new();
    let (mut resets, mut registers, mut idle_times) = (0, 0, 0);
    let (mut wrong, mut right_again) = (None, None);
    for _ in 0..80 {
        let b = host.next_byte();
        let mut frame = b.map_or(0x7FF, |b| framing.encode(b));
        match b {
            Some(RESET) => {
                resets += 1;
                registers = 0;
            }
            Some(_) => {
                registers += 1;
                if resets == 3 && registers == 7 {
                    frame |= 1; // the start bit of register 7 of sequence 3
                }
            }
            None => {
                idle_times += 1;
                if idle_times == 4 {
                    frame &= !(1 << 7); // bit 7 of the idle byte time closing sequence 3
                }
            }
        }
        for k in 0..11 {
            if let Some(byte) = rx.bit(frame >> k & 1 == 1) {
                panel.receive(byte);
                if *panel.registers() != [0; 7] && *panel.registers() != values {
                    wrong.get_or_insert(*panel.registers());
                }
                if byte == Ok(RESET) && resets == 6 && right_again.is_none() {
                    right_again = Some(*panel.registers());
                }
            }
        }
    }
    assert!(
        wrong.is_some(),
        "the attacker's case shows a wrong value (documented)"
    );
    assert_eq!(
        right_again,
        Some(values),
        "right at the reset byte closing sequence 5"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 1 } else { 6 }))]

    /// The same guarantee with random register values, new ones every sequence, for 1, 2 and 7
    /// registers: every single bit and bit pair over two sequences and the idle byte times on
    /// both sides.
    #[test]
    #[cfg_attr(miri, ignore = "every pair of bit errors on the line for each drawn case: hours under Miri; runs natively in every CI run")]
    fn every_bit_pair_on_the_line_random_values(
        one in proptest::collection::vec(0u8..=127, 9),
        two in proptest::collection::vec(proptest::array::uniform2(0u8..=127), 9),
        seven in proptest::collection::vec(proptest::array::uniform7(0u8..=127), 9),
    ) {
        let one: Vec<[u8; 1]> = one.into_iter().map(|v| [v]).collect();
        every_bit_pair_on_the_line::<1>(&one);
        every_bit_pair_on_the_line::<2>(&two);
        every_bit_pair_on_the_line::<7>(&seven);
    }
}

/// How often a 2-bit error through a bit receiver shows a value the host never sent (beyond
/// the register whose own frame took both flips), with random values (biased to many ones:
/// 0x7F, 0x7E-like values make fake reset bytes likely):
/// a measurement, printed; it asserts only the guarantee. `cargo test --release -- --ignored
/// --nocapture measure`.
#[test]
#[ignore = "a measurement (minutes in debug)"]
fn measure_wrong_values_after_two_flips() {
    let mut seed = 1u64;
    let mut next = move || {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (seed >> 33) as u8
    };
    let mut value = move || match next() % 4 {
        0 => 0x7F ^ (1 << (next() % 7)),
        1 => 0x7F,
        _ => next() & 0x7F,
    };
    let (mut cases, mut wrong) = (0, 0);
    for _ in 0..40 {
        let values: Vec<[u8; 7]> = (0..9).map(|_| core::array::from_fn(|_| value())).collect();
        let (c, w) = every_bit_pair_on_the_line::<7>(&values);
        cases += c;
        wrong += w;
    }
    println!("R = 7: {wrong} of {cases} bit pairs showed a value never sent");
    let (mut cases, mut wrong) = (0, 0);
    for _ in 0..400 {
        let values: Vec<[u8; 1]> = (0..9).map(|_| [value()]).collect();
        let (c, w) = every_bit_pair_on_the_line::<1>(&values);
        cases += c;
        wrong += w;
    }
    println!("R = 1: {wrong} of {cases} bit pairs showed a value never sent");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if cfg!(miri) { 1 } else { 300 }))]

    /// A key pressed at any moment raises SÄN within one sequence (`R + 2` byte times; the
    /// simulation's 100 µs steps add up to one step per byte) plus one MOT poll.
    #[test]
    fn a_key_waits_at_most_one_sequence_and_a_poll(after_us in 0u64..200_000) {
        let mut sim: Sim<29> = Sim::new(Damage::None, 0);
        sim.run_ms(after_us / 1000);
        for _ in 0..(after_us % 1000) / STEP_US {
            sim.step();
        }
        sim.panel.press(0x41).unwrap();
        let pressed = sim.now;
        while !sim.host.san() {
            sim.step();
        }
        let bound = 31 * (BYTE_US + STEP_US) + 10_000;
        prop_assert!(sim.now - pressed <= bound, "{} µs", sim.now - pressed);
    }
}
