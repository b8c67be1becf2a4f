//! The serial-highway driver: sends commands round the loop, matches replies, retries.

use core::fmt;

use heapless::Vec;

use super::{
    DecodeError, EncodeError, Framer, MAX_DECODE, MAX_MESSAGE, Message, NON_ADDRESSED, Seen,
    Status, WAIT, decode, is_read,
};

/// How a [`Driver`] works the loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DriverConfig {
    /// Byte clocks after a command's last byte before it counts as lost. It must be longer than
    /// the loop's round trip — 4 byte clocks per controller (one of delay, three held behind a
    /// demand) plus two messages of [`MAX_MESSAGE`] bytes and the gap; [`DriverConfig::for_loop`]
    /// computes that. [`Driver::new`] refuses a time-out below what the shortest loop (one
    /// controller) needs ([`DriverConfig::least_timeout`]), but it cannot know how many
    /// controllers are on the loop: **a time-out shorter than the actual loop's round trip gives
    /// wrong answers, not only retries** — the command is sent again while its reply is still on
    /// the way, and that late reply (replies carry no tag, only the crate address) completes the
    /// resend, or the crate's next command, with the data of an earlier cycle.
    pub timeout: u32,
    /// How many times a command is sent again before it fails. A resend waits for the attempt's
    /// deadline even after an ERR reply or an unanswered return (see [`Driver`]).
    pub retries: u8,
    /// WAIT bytes after each command (room for the controllers' demands; 0 is allowed: a
    /// controller also sends a demand right after a message).
    pub gap: u8,
}

impl DriverConfig {
    /// The least time-out [`Driver::new`] accepts with this configuration's gap: the round trip of
    /// a loop of one controller — two messages of [`MAX_MESSAGE`] bytes, the gap and 4 byte clocks
    /// of delay.
    #[must_use]
    pub const fn least_timeout(&self) -> u32 {
        Self::round_trip(1, self.gap)
    }

    /// A configuration for a loop of `controllers` crate controllers (1–62; more are counted as
    /// 62, none as one): the time-out is the loop's longest round trip, 4 byte clocks per
    /// controller plus two messages of [`MAX_MESSAGE`] bytes and the gap; 3 retries, a gap of 1.
    ///
    /// ```
    /// use regler_panel_link::highway::{Driver, DriverConfig};
    ///
    /// let config = DriverConfig::for_loop(20);
    /// assert_eq!(config.timeout, 4 * 20 + 2 * 15 + 1);
    /// let _driver: Driver<4> = Driver::new(config)?;
    /// assert!(Driver::<4>::new(regler_panel_link::highway::DriverConfig { timeout: 1, ..config }).is_err());
    /// # Ok::<(), Box<dyn core::error::Error>>(())
    /// ```
    #[must_use]
    pub const fn for_loop(controllers: u8) -> Self {
        let gap = 1;
        Self {
            timeout: Self::round_trip(controllers, gap),
            retries: 3,
            gap,
        }
    }

    const fn round_trip(controllers: u8, gap: u8) -> u32 {
        let controllers = if controllers == 0 {
            1
        } else if controllers > 62 {
            62
        } else {
            controllers
        };
        // MAX_MESSAGE is 15.
        const TWO_MESSAGES: u32 = 2 * 15;
        const { assert!(MAX_MESSAGE == 15) };
        // At most 4 * 62 + 30 + 255: no overflow.
        (controllers as u32)
            .saturating_mul(4)
            .saturating_add(TWO_MESSAGES)
            .saturating_add(gap as u32)
    }
}

impl Default for DriverConfig {
    fn default() -> Self {
        Self {
            timeout: 512,
            retries: 3,
            gap: 1,
        }
    }
}

/// Why [`Driver::submit`] refused a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DriverError {
    /// Only commands are submitted.
    NotACommand,
    /// A field does not fit (see [`EncodeError`]).
    Encode(EncodeError),
    /// Crate 0 is the driver and crate 63 answers nobody: there would be no reply to wait for.
    NoReplyPossible(u8),
    /// A command to this crate is still outstanding: replies carry no tag, only the crate address,
    /// so one command per crate is in flight at a time.
    CrateBusy(u8),
    /// Every slot of the window is taken.
    WindowFull,
    /// [`DriverConfig::timeout`] is shorter than the round trip of even a one-controller loop
    /// ([`DriverConfig::least_timeout`]): late replies would complete the wrong command.
    TimeoutTooShort {
        /// The time-out given.
        timeout: u32,
        /// The least accepted with that gap.
        least: u32,
    },
}

impl fmt::Display for DriverError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotACommand => f.write_str("only commands can be submitted"),
            Self::Encode(e) => write!(f, "command cannot be encoded: {e}"),
            Self::NoReplyPossible(a) => write!(f, "crate address {a} never replies (use 1..=62)"),
            Self::CrateBusy(a) => write!(f, "crate {a} already has a command outstanding"),
            Self::WindowFull => f.write_str("every slot of the driver's window is taken"),
            Self::TimeoutTooShort { timeout, least } => write!(
                f,
                "time-out {timeout} byte clocks is shorter than the round trip of a one-controller loop ({least}); a late reply would complete the wrong command (use DriverConfig::for_loop)"
            ),
        }
    }
}

impl core::error::Error for DriverError {}

/// Why a command failed for good.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum Failure {
    /// The crate answered ERR every time (it saw a damaged command).
    Err,
    /// The command came back round the loop unanswered: no crate has that address.
    NoResponse,
    /// No reply within the time-out.
    Timeout,
}

/// A finished command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Completion {
    /// The tag [`Driver::submit`] gave.
    pub tag: u32,
    /// The command.
    pub command: Message,
    /// The reply's status (ERR clear).
    pub status: Status,
    /// Read data (F0–F7).
    pub data: Option<u32>,
    /// Sends it took (1 = no retry).
    pub attempts: u8,
}

/// What the driver reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum DriverEvent {
    /// A command was answered cleanly.
    Completed(Completion),
    /// A command failed after every retry.
    Failed {
        /// The tag [`Driver::submit`] gave.
        tag: u32,
        /// The command.
        command: Message,
        /// The last reason.
        failure: Failure,
    },
    /// A crate asked for attention.
    Demand {
        /// The crate.
        crate_address: u8,
        /// Its graded LAM.
        sgl: u8,
    },
}

/// What one byte clock of the driver gave.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Step {
    /// The byte to send into the loop.
    pub transmit: u8,
    /// An event, if one happened.
    pub event: Option<DriverEvent>,
}

/// The driver's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DriverStats {
    /// Commands sent, retries included.
    pub sent: u64,
    /// Commands completed.
    pub completed: u64,
    /// Commands failed for good.
    pub failed: u64,
    /// Commands sent again.
    pub retries: u64,
    /// Replies with ERR (the crate saw a damaged command).
    pub err_replies: u64,
    /// Byte sequences that failed [`decode`] (detected errors on the way back).
    pub garbled: u64,
    /// Time-outs.
    pub timeouts: u64,
    /// Commands that came back unanswered.
    pub no_response: u64,
    /// Short replies (header + END) seen.
    pub short_replies: u64,
    /// Replies no command was waiting for (late or duplicated).
    pub unexpected: u64,
    /// Demands received.
    pub demands: u64,
    /// Byte clocks.
    pub clocks: u64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
enum SlotState {
    Queued,
    InFlight { deadline: u64 },
}

#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct Slot {
    tag: u32,
    command: Message,
    state: SlotState,
    attempts: u8,
    /// ERR or an unanswered return seen for the attempt in flight: the reason it is resent
    /// when its deadline passes.
    noted: Option<Failure>,
}

/// The driver (SC0) as a byte machine: `W` commands outstanding at most, one per crate.
///
/// [`submit`](Self::submit) queues a command and gives it a tag; every [`clock`](Self::clock)
/// takes the byte arriving from the last crate and gives the byte to send, and at most one
/// [`DriverEvent`]. It follows message boundaries as the crate controllers do (a delimiter where
/// the layout allows no end makes junk up to the next clean delimiter), and completes a command
/// only with a reply whose every byte passed the checks, whose header names that command's crate
/// and whose length is the one that command's function asks for. A reply with ERR,
/// a command that came back unanswered and a time-out send the command again, up to
/// [`DriverConfig::retries`] times. Execution is at least once: a reply lost on the way back
/// means the command runs again (the highway has no sequence numbers), so a non-idempotent
/// function such as read-and-clear can run twice; never, though, after its command completed.
///
/// ```
/// use regler_panel_link::highway::{Driver, DriverConfig, DriverEvent, Message};
///
/// let mut driver: Driver<4> = Driver::new(DriverConfig::default())?;
/// let tag = driver.submit(Message::Command { crate_address: 9, station: 1, subaddress: 0, function: 0, data: None })?;
/// // An empty loop: the command comes straight back, unanswered, every time.
/// let mut line = 0xE0;
/// let failed = loop {
///     let step = driver.clock(line);
///     line = step.transmit;
///     if let Some(DriverEvent::Failed { tag: t, .. }) = step.event { break t; }
/// };
/// assert_eq!(failed, tag);
/// assert_eq!(driver.stats().sent, 4); // first send + 3 retries
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct Driver<const W: usize> {
    config: DriverConfig,
    slots: Vec<Slot, W>,
    tx: [u8; MAX_MESSAGE],
    tx_len: u8,
    tx_pos: u8,
    gap_left: u8,
    rx: [u8; MAX_DECODE],
    rx_len: usize,
    framer: Framer,
    /// In junk already counted as garbled.
    junk: bool,
    next_tag: u32,
    stats: DriverStats,
}

impl<const W: usize> Driver<W> {
    /// A driver with nothing outstanding. It starts as after a break: it reads nothing as a
    /// message before the first clean delimiter (an idle line gives one at once), so after a
    /// restart the tail of a reply on its way back is never taken for a reply.
    ///
    /// # Errors
    /// [`DriverError::TimeoutTooShort`] when `config.timeout` is below
    /// [`DriverConfig::least_timeout`].
    pub const fn new(config: DriverConfig) -> Result<Self, DriverError> {
        const { assert!(W > 0, "a driver needs a window of at least one command") };
        let least = config.least_timeout();
        if config.timeout < least {
            return Err(DriverError::TimeoutTooShort {
                timeout: config.timeout,
                least,
            });
        }
        Ok(Self {
            config,
            slots: Vec::new(),
            tx: [WAIT; MAX_MESSAGE],
            tx_len: 0,
            tx_pos: 0,
            // One WAIT before the first message: crate controllers that start with the driver
            // read nothing before a clean delimiter.
            gap_left: 1,
            rx: [WAIT; MAX_DECODE],
            rx_len: 0,
            framer: Framer::new(),
            // It starts in junk (see `Framer::new`), which is not a detected error.
            junk: true,
            next_tag: 0,
            stats: DriverStats {
                sent: 0,
                completed: 0,
                failed: 0,
                retries: 0,
                err_replies: 0,
                garbled: 0,
                timeouts: 0,
                no_response: 0,
                short_replies: 0,
                unexpected: 0,
                demands: 0,
                clocks: 0,
            },
        })
    }

    /// The counters.
    #[must_use]
    pub const fn stats(&self) -> &DriverStats {
        &self.stats
    }

    /// Commands submitted and not yet completed or failed.
    #[must_use]
    pub fn outstanding(&self) -> usize {
        self.slots.len()
    }

    /// True when a command to `crate_address` is outstanding.
    #[must_use]
    pub fn busy(&self, crate_address: u8) -> bool {
        self.slots
            .iter()
            .any(|s| s.command.crate_address() == crate_address)
    }

    /// Queues `command` and returns its tag.
    ///
    /// # Errors
    /// See [`DriverError`]; nothing is queued then.
    pub fn submit(&mut self, command: Message) -> Result<u32, DriverError> {
        let Message::Command { crate_address, .. } = command else {
            return Err(DriverError::NotACommand);
        };
        command.validate().map_err(DriverError::Encode)?;
        if crate_address == 0 || crate_address >= NON_ADDRESSED {
            return Err(DriverError::NoReplyPossible(crate_address));
        }
        if self.busy(crate_address) {
            return Err(DriverError::CrateBusy(crate_address));
        }
        let tag = self.next_tag;
        let slot = Slot {
            tag,
            command,
            state: SlotState::Queued,
            attempts: 0,
            noted: None,
        };
        self.slots.push(slot).map_err(|_| DriverError::WindowFull)?;
        self.next_tag = self.next_tag.wrapping_add(1);
        Ok(tag)
    }

    /// One byte clock: `input` is the byte arriving from the loop.
    pub fn clock(&mut self, input: u8) -> Step {
        self.stats.clocks = self.stats.clocks.saturating_add(1);
        let transmit = self.transmit();
        let mut event = self.receive(input);
        if event.is_none() {
            event = self.expire();
        }
        Step { transmit, event }
    }

    fn transmit(&mut self) -> u8 {
        if self.tx_pos >= self.tx_len {
            if self.gap_left > 0 {
                self.gap_left = self.gap_left.saturating_sub(1);
                return WAIT;
            }
            self.load_next();
            if self.tx_pos >= self.tx_len {
                return WAIT; // nothing to send
            }
        }
        let byte = self
            .tx
            .get(usize::from(self.tx_pos))
            .copied()
            .unwrap_or(WAIT);
        self.tx_pos = self.tx_pos.saturating_add(1);
        if self.tx_pos == self.tx_len {
            self.gap_left = self.config.gap;
        }
        byte
    }

    fn load_next(&mut self) {
        let now = self.stats.clocks;
        let Some(slot) = self.slots.iter_mut().find(|s| s.state == SlotState::Queued) else {
            return;
        };
        let Ok(len) = slot.command.encode(&mut self.tx) else {
            return; // validated in submit
        };
        slot.attempts = slot.attempts.saturating_add(1);
        slot.noted = None;
        // The deadline counts from the last byte sent.
        let deadline = now
            .saturating_add(len as u64)
            .saturating_add(u64::from(self.config.timeout));
        slot.state = SlotState::InFlight { deadline };
        self.tx_len = u8::try_from(len).unwrap_or(0);
        self.tx_pos = 0;
        self.stats.sent = self.stats.sent.saturating_add(1);
    }

    fn receive(&mut self, input: u8) -> Option<DriverEvent> {
        // Message boundaries as every crate controller follows them: a message ends only with a
        // clean delimiter where its layout allows an end; after a break the stream is junk up
        // to the next clean delimiter, so a damaged message's tail is never taken for a reply.
        let seen = self.framer.push(input);
        if seen == Seen::Junk {
            if !self.junk {
                self.junk = true;
                self.stats.garbled = self.stats.garbled.saturating_add(1);
            }
            self.rx_len = 0;
            return None;
        }
        self.junk = false;
        match seen {
            Seen::Gap | Seen::Junk => return None,
            Seen::Header => self.rx_len = 0,
            Seen::Text | Seen::End => {}
        }
        if let Some(slot) = self.rx.get_mut(self.rx_len) {
            *slot = input;
            self.rx_len = self.rx_len.saturating_add(1);
        }
        if seen != Seen::End {
            return None;
        }
        let len = core::mem::take(&mut self.rx_len);
        let bytes = self.rx.get(..len).unwrap_or(&[]);
        match decode(bytes) {
            Ok(Message::Reply {
                crate_address,
                status,
                data,
            }) => self.on_reply(crate_address, status, data),
            Ok(Message::Demand { crate_address, sgl }) => {
                self.stats.demands = self.stats.demands.saturating_add(1);
                Some(DriverEvent::Demand { crate_address, sgl })
            }
            Ok(command @ Message::Command { .. }) => {
                let index = self.in_flight(command.crate_address())?;
                if self.slots.get(index).map(|s| s.command) != Some(command) {
                    return None;
                }
                self.stats.no_response = self.stats.no_response.saturating_add(1);
                self.note(index, Failure::NoResponse);
                None
            }
            Err(DecodeError::Truncated { .. }) => {
                self.stats.short_replies = self.stats.short_replies.saturating_add(1);
                None
            }
            Err(_) => {
                // Detected damage. Which command it belonged to is not trusted (the header may be
                // what was hit): the time-out resends it.
                self.stats.garbled = self.stats.garbled.saturating_add(1);
                None
            }
        }
    }

    fn in_flight(&self, crate_address: u8) -> Option<usize> {
        self.slots.iter().position(|s| {
            s.command.crate_address() == crate_address
                && matches!(s.state, SlotState::InFlight { .. })
        })
    }

    fn on_reply(
        &mut self,
        crate_address: u8,
        status: Status,
        data: Option<u32>,
    ) -> Option<DriverEvent> {
        let Some(index) = self.in_flight(crate_address) else {
            self.stats.unexpected = self.stats.unexpected.saturating_add(1);
            return None;
        };
        let slot = *self.slots.get(index)?;
        if status.err {
            self.stats.err_replies = self.stats.err_replies.saturating_add(1);
            self.note(index, Failure::Err);
            return None;
        }
        let Message::Command { function, .. } = slot.command else {
            return None;
        };
        if is_read(function) != data.is_some() {
            // A clean reply of the wrong shape: not an answer to this command.
            self.stats.unexpected = self.stats.unexpected.saturating_add(1);
            return None;
        }
        self.slots.remove(index);
        self.stats.completed = self.stats.completed.saturating_add(1);
        Some(DriverEvent::Completed(Completion {
            tag: slot.tag,
            command: slot.command,
            status,
            data,
            attempts: slot.attempts,
        }))
    }

    /// Resending at once would be unsafe: the highway carries no sequence numbers, and an ERR
    /// reply may be a damaged message's ghost while the attempt is still on its way. So the
    /// attempt is resent only when its deadline has passed and nothing of it can still be on the
    /// loop; a good reply meanwhile still completes it.
    fn note(&mut self, index: usize, failure: Failure) {
        if let Some(slot) = self.slots.get_mut(index) {
            slot.noted = Some(failure);
        }
    }

    fn retry(&mut self, index: usize, failure: Failure) -> Option<DriverEvent> {
        let retries = self.config.retries;
        let slot = self.slots.get_mut(index)?;
        if slot.attempts > retries {
            let (tag, command) = (slot.tag, slot.command);
            self.slots.remove(index);
            self.stats.failed = self.stats.failed.saturating_add(1);
            return Some(DriverEvent::Failed {
                tag,
                command,
                failure,
            });
        }
        slot.state = SlotState::Queued;
        self.stats.retries = self.stats.retries.saturating_add(1);
        None
    }

    fn expire(&mut self) -> Option<DriverEvent> {
        let now = self.stats.clocks;
        let index = self
            .slots
            .iter()
            .position(|s| matches!(s.state, SlotState::InFlight { deadline } if now >= deadline))?;
        let noted = self.slots.get(index).and_then(|s| s.noted);
        if noted.is_none() {
            self.stats.timeouts = self.stats.timeouts.saturating_add(1);
        }
        self.retry(index, noted.unwrap_or(Failure::Timeout))
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Controller, ControllerConfig, Cycle, Dataway, MAX_MESSAGE};
    use super::*;

    struct Echo;
    impl Dataway for Echo {
        fn cycle(&mut self, n: u8, a: u8, _f: u8, write: Option<u32>) -> Cycle {
            Cycle {
                read: write.unwrap_or(u32::from(n) << 8 | u32::from(a)),
                x: true,
                q: true,
            }
        }
    }

    #[test]
    fn submit_refuses_what_cannot_be_answered() {
        let mut d: Driver<1> = Driver::new(DriverConfig::default()).unwrap();
        let cmd = |crate_address| Message::Command {
            crate_address,
            station: 1,
            subaddress: 0,
            function: 0,
            data: None,
        };
        assert_eq!(
            d.submit(Message::Demand {
                crate_address: 1,
                sgl: 1
            }),
            Err(DriverError::NotACommand)
        );
        assert_eq!(d.submit(cmd(0)), Err(DriverError::NoReplyPossible(0)));
        assert_eq!(d.submit(cmd(63)), Err(DriverError::NoReplyPossible(63)));
        assert!(matches!(d.submit(cmd(64)), Err(DriverError::Encode(_))));
        assert_eq!(d.submit(cmd(1)), Ok(0));
        assert_eq!(d.submit(cmd(1)), Err(DriverError::CrateBusy(1)));
        assert_eq!(d.submit(cmd(2)), Err(DriverError::WindowFull));
    }

    #[test]
    fn the_driver_sends_each_command_at_once_then_its_gap_and_nothing_else() {
        // A write (the longest command) and then a read (shorter), on a line that answers
        // nothing: byte for byte, the one WAIT a new driver starts with (controllers that start
        // with it read nothing before a clean delimiter), the write, `gap` WAIT, the read, then
        // WAIT until the time-out resends them: never a byte left over in the buffer from the
        // longer message.
        let gap = 2;
        let mut config = DriverConfig {
            gap,
            ..DriverConfig::for_loop(1)
        };
        config.timeout = config.least_timeout();
        let mut d: Driver<2> = Driver::new(config).unwrap();
        let write = Message::Command {
            crate_address: 3,
            station: 1,
            subaddress: 0,
            function: 16,
            data: Some(0xABCDEF),
        };
        let read = Message::Command {
            crate_address: 4,
            station: 1,
            subaddress: 0,
            function: 0,
            data: None,
        };
        let bytes = |m: Message| {
            let mut buf = [0u8; MAX_MESSAGE];
            let len = m.encode(&mut buf).unwrap();
            buf[..len].to_vec()
        };
        d.submit(write).unwrap();
        d.submit(read).unwrap();
        let mut expected = std::vec![WAIT];
        expected.extend(bytes(write));
        expected.extend(core::iter::repeat_n(WAIT, usize::from(gap)));
        expected.extend(bytes(read));
        let sent: std::vec::Vec<u8> = (0..config.timeout)
            .map(|_| d.clock(WAIT).transmit)
            .collect();
        assert_eq!(sent[..expected.len()], expected[..]);
        assert!(
            sent[expected.len()..].iter().all(|&b| b == WAIT),
            "after the read only WAIT until the time-out: {sent:02X?}"
        );
    }

    #[test]
    fn a_loop_of_three_crates_answers_every_command() {
        let mut d: Driver<3> = Driver::new(DriverConfig::default()).unwrap();
        let mut crates: std::vec::Vec<Controller> = (1..=3)
            .map(|a| {
                Controller::new(ControllerConfig {
                    address: a,
                    demand_repeat: 0,
                })
                .unwrap()
            })
            .collect();
        for a in 1..=3 {
            d.submit(Message::Command {
                crate_address: a,
                station: a,
                subaddress: 2,
                function: 0,
                data: None,
            })
            .unwrap();
        }
        let mut line = WAIT;
        let mut done = std::vec::Vec::new();
        for _ in 0..200 {
            let step = d.clock(line);
            line = crates
                .iter_mut()
                .fold(step.transmit, |b, c| c.clock(b, &mut Echo));
            if let Some(DriverEvent::Completed(c)) = step.event {
                done.push((c.command.crate_address(), c.data, c.attempts));
            }
        }
        done.sort_unstable();
        assert_eq!(
            done,
            std::vec![
                (1, Some(0x102), 1),
                (2, Some(0x202), 1),
                (3, Some(0x302), 1)
            ]
        );
        assert_eq!(d.stats().short_replies, 3);
        assert_eq!(d.outstanding(), 0);
    }

    /// An ERR reply may be the ghost of a damaged message while the real attempt is still on the
    /// loop: the driver must not resend before the attempt's deadline, and the real reply that
    /// follows still completes the command, once.
    #[test]
    fn an_err_reply_does_not_resend_before_the_deadline() {
        let mut d: Driver<2> = Driver::new(DriverConfig {
            timeout: 100,
            retries: 3,
            gap: 1,
        })
        .unwrap();
        let cmd = Message::Command {
            crate_address: 2,
            station: 1,
            subaddress: 0,
            function: 0,
            data: None,
        };
        d.submit(cmd).unwrap();
        let feed = |d: &mut Driver<2>, m: Message| {
            let mut buf = [0u8; MAX_MESSAGE];
            let len = m.encode(&mut buf).unwrap();
            buf[..len]
                .iter()
                .map(|&b| d.clock(b).event)
                .fold(None, |a, e| a.or(e))
        };
        for _ in 0..20 {
            d.clock(WAIT);
        }
        assert_eq!(d.stats().sent, 1);
        let ghost = Message::Reply {
            crate_address: 2,
            status: Status {
                err: true,
                ..Status::default()
            },
            data: None,
        };
        assert_eq!(feed(&mut d, ghost), None);
        for _ in 0..20 {
            assert_eq!(d.clock(WAIT).event, None);
        }
        assert_eq!(
            d.stats().sent,
            1,
            "resent while the attempt could still be on the loop"
        );
        let real = Message::Reply {
            crate_address: 2,
            status: Status {
                x: true,
                q: true,
                ..Status::default()
            },
            data: Some(7),
        };
        match feed(&mut d, real) {
            Some(DriverEvent::Completed(c)) => assert_eq!((c.data, c.attempts), (Some(7), 1)),
            other => panic!("{other:?}"),
        }
        // Without a good reply, the resend comes at the deadline, for the noted reason.
        d.submit(cmd).unwrap();
        for _ in 0..20 {
            d.clock(WAIT);
        }
        feed(&mut d, ghost);
        let mut clocks = 0;
        while d.stats().sent < 3 {
            assert_eq!(d.clock(WAIT).event, None);
            clocks += 1;
        }
        assert!(clocks > 50, "resent after {clocks} clocks");
        assert_eq!(
            d.stats().timeouts,
            0,
            "an ERR-noted attempt is not a time-out"
        );
    }

    /// A command to a crate that is not on the loop comes back round unanswered: the driver
    /// retries it and then reports it failed with `NoResponse` (not a time-out, not garbled).
    #[test]
    fn a_command_to_a_crate_not_on_the_loop_fails_with_no_response() {
        let config = DriverConfig {
            retries: 2,
            ..DriverConfig::for_loop(2)
        };
        let mut d: Driver<1> = Driver::new(config).unwrap();
        let mut crates: std::vec::Vec<Controller> = (1..=2)
            .map(|a| {
                Controller::new(ControllerConfig {
                    address: a,
                    demand_repeat: 0,
                })
                .unwrap()
            })
            .collect();
        let cmd = Message::Command {
            crate_address: 7,
            station: 1,
            subaddress: 0,
            function: 16,
            data: Some(9),
        };
        let tag = d.submit(cmd).unwrap();
        let mut line = WAIT;
        let mut events = std::vec::Vec::new();
        for _ in 0..400 {
            let step = d.clock(line);
            line = crates
                .iter_mut()
                .fold(step.transmit, |b, c| c.clock(b, &mut Echo));
            events.extend(step.event);
        }
        assert_eq!(
            events,
            std::vec![DriverEvent::Failed {
                tag,
                command: cmd,
                failure: Failure::NoResponse
            }]
        );
        let stats = d.stats();
        assert_eq!((stats.sent, stats.retries, stats.failed), (3, 2, 1));
        assert_eq!(
            (stats.no_response, stats.garbled, stats.timeouts),
            (3, 0, 0)
        );
    }
}
