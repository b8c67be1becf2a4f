//! One panel link: the computer's [`Host`] and the far end's [`Panel`] on a simulated 4 800-baud
//! line, with the handshake lines, the noise, and the counters the operator subsystem reports.
//!
//! # Timing
//! A character is 11 bits (start, 8 data, parity, stop), so the line carries 4 800 / 11 byte
//! times a second. Every 10 ms tick adds 48 bits to the link's budget and runs one byte time per
//! 11 bits in it (4 or 5 a tick, exactly 4 800 / 11 a second over any whole number of
//! ticks). In each byte time the computer's transmitter asks [`Host::next_byte`]: a byte goes to
//! the panel, `None` leaves the line idle. Then the tick polls MOT ([`Host::poll_mot`]), the panel
//! samples SÄN ([`Panel::set_san`]: on a rise it sends its key byte at once), and every second
//! tick is the panel's 20 ms tick ([`Panel::tick_20ms`]: the key byte again while SÄN is up). A
//! key byte reaches the computer within the tick it is sent in (2.3 ms, less than a tick).
//!
//! # The line
//! Each byte is framed with [`Framing::PANEL`] and each of its 11 bits flipped with the link's
//! bit-error rate by a [`Noise`] (one for each direction); the receiver decodes the damaged
//! frame, so a flipped bit shows as a parity or framing error, or as a wrong byte when two flips
//! keep the parity. A clean link (rate 0) skips the framing: the byte goes straight across.
//! With noise, one draw of [`Noise::corrupt`] per frame says whether the frame is hit and
//! where; only a hit frame is encoded and decoded. The model is at frame level: a receiver
//! keeps character sync, and bits of the idle byte times are not disturbed (the crate's own
//! tests cover a bit receiver losing sync and finding it again).
//!
//! # Checking the displays after a corrupted byte
//! After every byte the noise changed on the way to the panel, the link compares the panel's
//! registers with what the computer sent once the **next whole sequence** has arrived: the one
//! opened by the reset byte after the damaged byte's sequence, closed by the reset byte after
//! that. Registers that differ then are counted in
//! [`LinkStats::displays_wrong_after_next_sequence`]. If that next sequence is hit too (a byte of
//! it, or its closing reset byte), the check moves to the sequence after the latest hit one and
//! [`LinkStats::checks_postponed`] counts it; one check then covers every hit before it.
//!
//! At this frame-level model the check finds 0 by the crate's design, not by luck: the panel
//! drops every sequence a detected error fell in, and shows a sequence only when its closing
//! reset byte arrives after exactly `R` clean bytes, so a clean sequence shows exactly what the
//! computer sent. A 2-bit error that keeps the parity shows a wrong value in its own register
//! until then (the link has no checksum). The counter is there to catch a panel that latched
//! damaged bytes, as the 1977 panel did. At a bit-error rate of 10⁻³ about one frame in 90 is
//! hit and the central desk's 47-byte sequence is hit two times in five, so postponed checks
//! are common: a display is right again after the first clean sequence, however long that takes.
//!
//! # Cost
//! A clean link's byte is [`Host::next_byte`], [`Panel::receive`] and a counter: about 75
//! instructions a byte for the whole subsystem (callgrind, release, a simulated hour), of which
//! the crate's two machines take about 41 and this file about 17; 1.3 s of CPU for a simulated
//! day of the six links (210 M bytes). Noise on a link adds [`Noise::corrupt`] (about 40
//! instructions a frame).

use regler_panel_link::line::{Framing, Noise};
use regler_panel_link::panel::{Host, HostConfig, HostEvent, Panel, RESET};

/// Line bits in one 10 ms tick at 4 800 baud.
pub const BITS_PER_TICK: u32 = 48;
/// Bits of one character on the line.
pub const BITS_PER_BYTE: u32 = 11;

/// The host's time-outs: the crate's defaults (a key given up after 10 polls, a stuck MOT after
/// 100).
const HOST_CONFIG: HostConfig = HostConfig {
    key_timeout_polls: 10,
    mot_stuck_polls: 100,
};

/// What one link counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct LinkStats {
    /// Bytes the computer sent (reset bytes and registers).
    pub bytes_sent: u64,
    /// Of those, bytes the noise changed on the line.
    pub bytes_corrupted: u64,
    /// Key bytes the panel sent.
    pub key_bytes_sent: u64,
    /// Of those, bytes the noise changed.
    pub key_bytes_corrupted: u64,
    /// Line errors detected: bad bytes at the panel (parity, framing, bit 8 set) and line
    /// errors at the computer while it listened for a key.
    pub errors_detected: u64,
    /// Sequences the panel showed.
    pub sequences_shown: u64,
    /// Sequences the panel dropped (a damaged byte in them, or the wrong length).
    pub sequences_dropped: u64,
    /// Checks made one whole sequence after a corrupted byte.
    pub checks: u64,
    /// Checks moved on because the next sequence was hit too.
    pub checks_postponed: u64,
    /// Registers wrong at a check.
    pub displays_wrong_after_next_sequence: u64,
    /// Keys the computer took.
    pub keys_taken: u64,
    /// Keys the computer gave up waiting for (the key is lost).
    pub keys_lost: u64,
    /// Times the computer found MOT stuck high.
    pub mot_stuck: u64,
}

/// The simulated link to one panel with `R` registers.
#[derive(Clone, Debug)]
pub struct Link<const R: usize> {
    host: Host<R>,
    panel: Panel<R>,
    /// Line bits of the budget not yet spent on byte times.
    bits: u32,
    to_panel: Option<Noise>,
    to_host: Option<Noise>,
    /// Bytes go through the watched path: noise on the line, a fault to inject or a check
    /// pending. A clean link skips the framing and the bookkeeping below.
    watched: bool,
    /// The registers the host sent in the current sequence, as they went out (watched only).
    sent: [u8; R],
    /// Sequence position of the last byte sent: 0 the reset byte, `k` register `k − 1`;
    /// `None` until the watched path has seen a reset byte.
    position: Option<usize>,
    /// Reset bytes sent on the watched path.
    resets: u64,
    /// Check the display when the reset byte with this number has arrived clean.
    check_at: Option<u64>,
    /// Fault injection: flip these frame bits of the byte sent at this sequence position.
    inject: Option<(usize, u16)>,
    /// Fault injection: the MOT line as the computer reads it, stuck at this level.
    mot_stuck_at: Option<bool>,
    /// Keys taken off panels that restarted since (their own counters started again at 0).
    keys_popped_before: u64,

    stats: LinkStats,
}

impl<const R: usize> Link<R> {
    /// The host as powered up; evaluated at compile time, so a refused configuration is a
    /// build error, never a run-time panic.
    const HOST: Host<R> = match Host::new(HOST_CONFIG) {
        Ok(host) => host,
        Err(_) => panic!("the crate's default host configuration is valid"),
    };

    /// A clean link, both ends just powered up.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            host: Self::HOST,
            panel: Panel::new(),
            bits: 0,
            to_panel: None,
            to_host: None,
            watched: false,
            sent: [0; R],
            position: None,
            resets: 0,
            check_at: None,
            inject: None,
            mot_stuck_at: None,
            keys_popped_before: 0,
            stats: LinkStats {
                bytes_sent: 0,
                bytes_corrupted: 0,
                key_bytes_sent: 0,
                key_bytes_corrupted: 0,
                errors_detected: 0,
                sequences_shown: 0,
                sequences_dropped: 0,
                checks: 0,
                checks_postponed: 0,
                displays_wrong_after_next_sequence: 0,
                keys_taken: 0,
                keys_lost: 0,
                mot_stuck: 0,
            },
        }
    }

    /// Bit-error rate `rate` in both directions from now on (0: a clean line), seeded.
    pub fn set_noise(&mut self, rate: f64, seed: u64) {
        let noise = |seed| Noise::new(rate, seed).ok().filter(|_| rate > 0.0);
        self.to_panel = noise(seed);
        self.to_host = noise(seed ^ 0x5A5A_5A5A_5A5A_5A5A);
        self.watch();
    }

    /// Takes the watched path if anything needs it; entering it, the sequence position is
    /// unknown until the next reset byte.
    fn watch(&mut self) {
        let watched = self.to_panel.is_some() || self.inject.is_some() || self.check_at.is_some();
        if watched && !self.watched {
            self.position = None;
        }
        self.watched = watched;
    }

    /// The next byte sent at sequence position `position` (0: a reset byte, `k`: register
    /// `k − 1`) has the frame bits in `mask` flipped (bit 0 is the start bit).
    pub fn inject(&mut self, position: usize, mask: u16) {
        self.inject = Some((position, mask & 0x7FF));
        self.watch();
    }

    /// The MOT line as the computer reads it is stuck at `level` (`None`: the panel's MOT).
    pub fn stick_mot(&mut self, level: Option<bool>) {
        self.mot_stuck_at = level;
    }

    /// The panel restarts: registers 0, no keys, waiting for a reset byte (its power failed and
    /// came back). The computer is not told. Returns how many of the keys the panel held the
    /// computer had not taken (a key taken just before, whose SÄN fall the panel had not seen
    /// yet, was held but is not lost).
    pub fn restart_panel(&mut self) -> usize {
        let popped = self.keys_popped_before + self.panel.stats().keys_sent;
        let taken_not_popped = self.host.stats().keys.saturating_sub(popped);
        let waiting = self.panel.keys_waiting() as u64;
        self.keys_popped_before = popped + taken_not_popped.min(waiting);
        self.panel = Panel::new();
        usize::try_from(waiting.saturating_sub(taken_not_popped)).unwrap_or(usize::MAX)
    }

    /// The registers the computer holds for the panel.
    #[must_use]
    pub fn registers(&self) -> &[u8] {
        self.host.registers()
    }

    /// The registers the panel shows.
    #[must_use]
    pub fn display(&self) -> &[u8] {
        self.panel.registers()
    }

    /// The computer's registers from `values` (values above 127 are refused by the crate and
    /// counted as detected errors; a layout never makes one).
    pub fn set_registers(&mut self, values: &[u8; R]) {
        for (index, &value) in values.iter().enumerate() {
            if self.host.set(index, value).is_err() {
                self.stats.errors_detected += 1;
            }
        }
    }

    /// The operator pressed `key` on the panel; `false` when the panel's key queue is full.
    pub fn press(&mut self, key: u8) -> bool {
        self.panel.press(key).is_ok()
    }

    /// Keys pressed on the panel and not yet taken by the computer.
    #[must_use]
    pub fn keys_waiting(&self) -> usize {
        self.panel.keys_waiting()
    }

    /// The counters, with the crate's own counters folded in.
    #[must_use]
    pub fn stats(&self) -> LinkStats {
        let panel = self.panel.stats();
        let host = self.host.stats();
        LinkStats {
            errors_detected: self.stats.errors_detected + panel.bad_bytes + host.line_errors,
            sequences_shown: panel.shown,
            sequences_dropped: panel.discarded,
            keys_taken: host.keys,
            keys_lost: host.key_timeouts,
            ..self.stats
        }
    }

    /// One 10 ms tick (`twenty_ms`: also the panel's 20 ms tick); the host's events go to `on`.
    pub fn tick(&mut self, twenty_ms: bool, on: &mut impl FnMut(HostEvent)) {
        self.bits += BITS_PER_TICK;
        while self.bits >= BITS_PER_BYTE {
            self.bits -= BITS_PER_BYTE;
            self.byte_time();
        }
        let mot = self.mot_stuck_at.unwrap_or(self.panel.mot());
        if let Some(event) = self.host.poll_mot(mot) {
            self.event(event, on);
        }
        if let Some(key) = self.panel.set_san(self.host.san()) {
            self.key_byte(key, on);
        }
        if twenty_ms {
            if let Some(key) = self.panel.tick_20ms() {
                self.key_byte(key, on);
            }
        }
    }

    fn event(&mut self, event: HostEvent, on: &mut impl FnMut(HostEvent)) {
        if event == HostEvent::MotStuck {
            self.stats.mot_stuck += 1;
        }
        on(event);
    }

    /// A key byte from the panel to the computer.
    fn key_byte(&mut self, key: u8, on: &mut impl FnMut(HostEvent)) {
        self.stats.key_bytes_sent += 1;
        let mask = self
            .to_host
            .as_mut()
            .map_or(0, |n| n.corrupt(0, BITS_PER_BYTE));
        let received = if mask == 0 {
            Ok(key)
        } else {
            self.stats.key_bytes_corrupted += 1;
            Framing::PANEL.decode(Framing::PANEL.encode(key) ^ mask)
        };
        if let Some(event) = self.host.receive(received) {
            self.event(event, on);
        }
    }

    /// One byte time of the computer's transmitter.
    fn byte_time(&mut self) {
        let Some(byte) = self.host.next_byte() else {
            return;
        };
        self.stats.bytes_sent += 1;
        if self.watched {
            self.watched_byte(byte);
        } else {
            self.panel.receive(Ok(byte));
        }
    }

    /// A byte on the watched path: its position, the noise, an injected fault, the check.
    fn watched_byte(&mut self, byte: u8) {
        if byte == RESET {
            self.resets += 1;
            self.position = Some(0);
        } else if let Some(position) = self.position {
            if let Some(slot) = self.sent.get_mut(position) {
                *slot = byte;
            }
            self.position = Some(position + 1);
        }
        let mut mask = self
            .to_panel
            .as_mut()
            .map_or(0, |n| n.corrupt(0, BITS_PER_BYTE));
        if let Some((at, flip)) = self.inject {
            if Some(at) == self.position {
                mask ^= flip;
                self.inject = None;
            }
        }
        if mask == 0 {
            self.panel.receive(Ok(byte));
            if byte == RESET && self.check_at == Some(self.resets) {
                self.check();
            }
        } else {
            self.stats.bytes_corrupted += 1;
            if self.check_at.is_some() {
                self.stats.checks_postponed += 1;
            }
            // The next whole sequence is opened by the next reset byte and closed by the one
            // after.
            self.check_at = Some(self.resets + 2);
            self.panel
                .receive(Framing::PANEL.decode(Framing::PANEL.encode(byte) ^ mask));
        }
        self.watch();
    }

    /// The next whole sequence after a corrupted byte has arrived: count registers still wrong.
    fn check(&mut self) {
        self.check_at = None;
        self.stats.checks += 1;
        let wrong = self
            .panel
            .registers()
            .iter()
            .zip(&self.sent)
            .filter(|(shown, sent)| shown != sent)
            .count();
        self.stats.displays_wrong_after_next_sequence += wrong as u64;
    }
}

impl<const R: usize> Default for Link<R> {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_line_carries_4800_over_11_bytes_a_second() {
        let mut link: Link<7> = Link::new();
        for _ in 0..1100 {
            link.tick(false, &mut |_| {});
        }
        // 11 s: 4 800 byte times; 533 sequences of 9 (reset, idle, 7 registers) and 3 more
        // byte times (reset, idle, one register).
        assert_eq!(link.stats().bytes_sent, 533 * 8 + 2);
        assert_eq!(link.bits, 0);
    }

    #[test]
    fn any_rate_is_taken_without_a_panic() {
        for rate in [f64::NAN, -1.0, 0.0, 1e-300, 0.5, 0.6, f64::INFINITY] {
            let mut link: Link<7> = Link::new();
            link.set_noise(rate, 1);
            for _ in 0..100 {
                link.tick(true, &mut |_| {});
            }
            assert_eq!(link.watched, rate > 0.0 && rate <= 0.5, "{rate}");
        }
    }

    #[test]
    fn every_flip_of_a_register_frame_is_fixed_by_the_next_sequence() {
        for position in 0..=7 {
            for bit in 0..11 {
                let mut link: Link<7> = Link::new();
                let mut values = [0u8; 7];
                for (k, v) in values.iter_mut().enumerate() {
                    *v = 0x7E - k as u8;
                }
                link.set_registers(&values);
                for _ in 0..10 {
                    link.tick(false, &mut |_| {});
                }
                link.inject(position, 1 << bit);
                for _ in 0..10 {
                    link.tick(false, &mut |_| {});
                }
                let stats = link.stats();
                assert_eq!(
                    (stats.bytes_corrupted, stats.checks),
                    (1, 1),
                    "{position} {bit}"
                );
                assert_eq!(stats.displays_wrong_after_next_sequence, 0);
                assert_eq!(link.display(), &values);
            }
        }
    }
}
