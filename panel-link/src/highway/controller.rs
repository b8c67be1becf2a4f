//! The L-type crate controller: one byte in, one byte out, one byte of delay.

use core::fmt;

use heapless::Deque;

use super::{
    COLUMNS, END, Framer, M1, M2, NON_ADDRESSED, SPACE, STATION_MARK, Seen, WAIT, data_bytes,
    endsum_byte, guard_len, is_clean_delimiter, is_delimiter, is_read, is_write, row_parity_ok,
    with_parity,
};

/// What a CAMAC dataway cycle answered.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Cycle {
    /// The read lines (24 bits used; sent back for F0–F7).
    pub read: u32,
    /// X: the module accepted the command.
    pub x: bool,
    /// Q: the module's answer (e.g. "LAM was set", "data valid").
    pub q: bool,
}

/// The crate behind a controller: the modules on its dataway.
pub trait Dataway {
    /// Runs one dataway cycle N·A·F, with the write data for F16–F23.
    fn cycle(&mut self, station: u8, subaddress: u8, function: u8, write: Option<u32>) -> Cycle;

    /// The graded LAM (5 bits, 0 = no request) the controller reports in a demand.
    fn graded_lam(&mut self) -> u8 {
        0
    }
}

/// How a [`Controller`] is set up.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ControllerConfig {
    /// The crate address, 1–62.
    pub address: u8,
    /// Send the demand again after this many byte clocks while the graded LAM stays the same and
    /// non-zero (a demand lost on the loop is not lost for good); 0 = only when it changes.
    pub demand_repeat: u32,
}

impl Default for ControllerConfig {
    fn default() -> Self {
        Self {
            address: 1,
            demand_repeat: 4096,
        }
    }
}

/// Why a configuration was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ConfigError {
    /// Crate addresses are 1–62 (0 is the driver, 63 addresses no crate).
    Address(u8),
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Address(a) => write!(f, "crate address must be 1..=62, got {a}"),
        }
    }
}

impl core::error::Error for ConfigError {}

/// What a controller has seen and done.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ControllerStats {
    /// Commands addressed to this crate.
    pub commands: u64,
    /// Dataway cycles run (clean commands).
    pub executed: u64,
    /// Addressed commands refused for an error (answered with ERR).
    pub errors: u64,
    /// Addressed commands that ended before their reply room (no reply possible).
    pub truncated: u64,
    /// Demands sent.
    pub demands: u64,
    /// Messages for other crates passed on.
    pub passed: u64,
}

/// Where the receiver stands in the incoming stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
enum Rx {
    /// Following message boundaries: between messages, passing others' messages on, or junk.
    Framing,
    /// A header with our address arrived; the second byte tells whether a command for us begins.
    Second { header: u8 },
    /// Taking a command addressed to this crate.
    Command,
    /// Our command broke (a delimiter where its layout allows none): its bytes up to the next
    /// clean delimiter are taken off the loop too, so no crate downstream sees its tail.
    Consume,
}

/// The L-type crate controller as a byte machine on the loop.
///
/// Each [`clock`](Self::clock) takes the byte arriving from upstream and returns the byte for
/// downstream, one byte late. A command with this crate's address is taken off the loop: the
/// controller answers the short reply (header + END) at once, puts WAIT in place of the rest of
/// the command text, checks row parity, layout, the column sum and that every byte after SUM up
/// to the reply's status byte is SPACE (the guard, see the [module docs](super)), runs the
/// dataway cycle only if all are clean, and writes its reply (header, status with ERR/SX/SQ/DERR,
/// data for reads, ENDSUM) over the reply room. Between messages it may send a demand (header,
/// SGL, ENDSUM), holding up to 3 bytes of a following message meanwhile; the WAIT bytes of the
/// next gap give the time back.
///
/// It follows every message's layout, its own and those it passes on: a delimiter where the
/// layout allows no end is a break, and everything up to the next clean delimiter is junk —
/// passed on unread, or, in a command for this crate, replaced by WAIT (no reply, DERR in the
/// next one). So the tail of a damaged message is never read as a command. A new controller
/// (after power-up or a reset) starts the same way, as after a break: it reads nothing before the
/// first clean delimiter — on an idle line the first WAIT — so the tail of a command that was
/// passing when it restarted is never read as a command either.
///
/// ```
/// use regler_panel_link::highway::{decode, Controller, ControllerConfig, Cycle, Dataway, Message, Status, MAX_MESSAGE};
///
/// struct Register(u32);
/// impl Dataway for Register {
///     fn cycle(&mut self, _n: u8, _a: u8, f: u8, write: Option<u32>) -> Cycle {
///         if let Some(w) = write { self.0 = w; }
///         Cycle { read: if f == 0 { self.0 } else { 0 }, x: true, q: true }
///     }
/// }
///
/// let mut crate_ = Register(0);
/// let mut controller = Controller::new(ControllerConfig { address: 3, ..Default::default() })?;
/// let write = Message::Command { crate_address: 3, station: 1, subaddress: 0, function: 16, data: Some(0x1234) };
/// let mut buf = [0u8; MAX_MESSAGE];
/// let len = write.encode(&mut buf)?;
/// // A fresh controller reads nothing before the first clean delimiter: an idle line's WAIT.
/// let line = [0xE0].iter().chain(&buf[..len]).chain(&[0xE0]);
/// let out: Vec<u8> = line.map(|&b| controller.clock(b, &mut crate_)).collect();
/// // One byte late: header, END (the short reply), WAITs, then the reply over the SPACEs.
/// assert_eq!(&out[2..4], &[buf[0], 0xE0]);
/// assert_eq!(decode(&out[11..14]), Ok(Message::Reply { crate_address: 3, status: Status { x: true, q: true, ..Status::default() }, data: None }));
/// assert_eq!(crate_.0, 0x1234);
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct Controller {
    config: ControllerConfig,
    /// The one-byte delay register: the byte that goes out next clock.
    delayed: u8,
    /// Up to 3 bytes held behind a demand.
    held: Deque<u8, 3>,
    rx: Rx,
    framer: Framer,
    // The addressed command being taken.
    pos: u8,
    columns: u8,
    error: bool,
    subaddress: u8,
    function: u8,
    station: u8,
    data: u32,
    sum_at: u8,
    /// Where the reply's header goes (the first byte of the reply room).
    room_at: u8,
    reply: [u8; 7],
    /// The reply's length once the command is answered (at the reply's status byte); 0 before.
    reply_len: u8,
    reply_sent: u8,
    /// The last command had an error (reported as DERR in the next reply).
    last_error: bool,
    // Demands.
    last_sgl: u8,
    since_demand: u32,
    stats: ControllerStats,
}

impl Controller {
    /// A controller for the crate at `config.address`. It reads nothing as a message before the
    /// first clean delimiter it receives (see above).
    ///
    /// # Errors
    /// [`ConfigError::Address`] unless the address is 1–62.
    pub const fn new(config: ControllerConfig) -> Result<Self, ConfigError> {
        if config.address == 0 || config.address >= NON_ADDRESSED {
            return Err(ConfigError::Address(config.address));
        }
        Ok(Self {
            config,
            delayed: WAIT,
            held: Deque::new(),
            rx: Rx::Framing,
            framer: Framer::new(),
            pos: 0,
            columns: 0,
            error: false,
            subaddress: 0,
            function: 0,
            station: 0,
            data: 0,
            sum_at: 0,
            room_at: 0,
            reply: [WAIT; 7],
            reply_len: 0,
            reply_sent: 0,
            last_error: false,
            last_sgl: 0,
            since_demand: 0,
            stats: ControllerStats {
                commands: 0,
                executed: 0,
                errors: 0,
                truncated: 0,
                demands: 0,
                passed: 0,
            },
        })
    }

    /// The configuration.
    #[must_use]
    pub const fn config(&self) -> &ControllerConfig {
        &self.config
    }

    /// What this controller has seen and done.
    #[must_use]
    pub const fn stats(&self) -> &ControllerStats {
        &self.stats
    }

    /// Bytes held back beyond the one-byte delay (0–3, non-zero after a demand).
    #[must_use]
    pub fn held(&self) -> usize {
        self.held.len()
    }

    /// One byte clock: takes the byte from upstream, returns the byte for downstream.
    pub fn clock<D: Dataway + ?Sized>(&mut self, input: u8, dataway: &mut D) -> u8 {
        let out = self.delayed;
        let decided = self.take(input, dataway);
        let byte = decided.unwrap_or(WAIT);
        self.since_demand = self.since_demand.saturating_add(1);
        if let Some(next) = self.held.pop_front() {
            // Bytes are held behind a demand: they go first. A gap byte is dropped meanwhile:
            // that is how the delay shrinks back to one byte.
            self.delayed = next;
            if decided.is_some() {
                let _ = self.held.push_back(byte); // one out, at most one in: never full
            }
            return out;
        }
        self.delayed = byte;
        if self.rx == Rx::Framing && self.framer.between() {
            if let Some(sgl) = self.demand_due(dataway) {
                let header = with_parity(self.config.address);
                let sgl_byte = with_parity(M2 | sgl);
                let demand = [header, sgl_byte, endsum_byte(&[header, sgl_byte])];
                // In place of a gap byte, or right after the delimiter that ended a message.
                let rest = if decided.is_none() {
                    self.delayed = header;
                    demand.get(1..).unwrap_or(&[])
                } else {
                    &demand[..]
                };
                for &b in rest {
                    let _ = self.held.push_back(b); // at most 3 into an empty queue of 3
                }
                self.stats.demands = self.stats.demands.saturating_add(1);
            }
        }
        out
    }

    fn demand_due<D: Dataway + ?Sized>(&mut self, dataway: &mut D) -> Option<u8> {
        let sgl = dataway.graded_lam() & 0x1F;
        if sgl == 0 {
            self.last_sgl = 0;
            return None;
        }
        let repeat =
            self.config.demand_repeat != 0 && self.since_demand >= self.config.demand_repeat;
        if sgl != self.last_sgl || repeat {
            self.last_sgl = sgl;
            self.since_demand = 0;
            return Some(sgl);
        }
        None
    }

    /// Decides the byte that goes out in the place of `input`; `None` for gap filler.
    fn take<D: Dataway + ?Sized>(&mut self, input: u8, dataway: &mut D) -> Option<u8> {
        match self.rx {
            Rx::Framing => {
                let seen = self.framer.push(input);
                if seen == Seen::Gap {
                    return None;
                }
                if seen == Seen::Header {
                    if row_parity_ok(input) && input & COLUMNS == self.config.address {
                        self.rx = Rx::Second { header: input };
                    } else {
                        self.stats.passed = self.stats.passed.saturating_add(1);
                    }
                }
                Some(input)
            }
            Rx::Second { header } => {
                self.rx = Rx::Framing;
                // A reply or demand with our header cannot be for us: only commands are. A
                // damaged second byte of a command to us makes an ERR reply.
                let command = !row_parity_ok(input) || input & (M1 | M2) == 0;
                if command && !is_delimiter(input) {
                    self.start_command(header, input);
                    return Some(END);
                }
                // Header + END (the short reply), or not a command: followed like any message.
                self.stats.passed = self.stats.passed.saturating_add(1);
                self.framer.push(input);
                Some(input)
            }
            Rx::Command => Some(self.command_byte(input, dataway)),
            Rx::Consume => {
                if is_clean_delimiter(input) {
                    self.rx = Rx::Framing;
                    self.framer.reset();
                }
                Some(WAIT)
            }
        }
    }

    fn start_command(&mut self, header: u8, sa: u8) {
        self.rx = Rx::Command;
        self.stats.commands = self.stats.commands.saturating_add(1);
        self.pos = 2;
        self.columns = (header ^ sa) & COLUMNS;
        self.error = !row_parity_ok(sa);
        self.subaddress = sa & 0x0F;
        self.function = 0;
        self.station = 0;
        self.data = 0;
        self.sum_at = 4;
        self.room_at = u8::MAX;
        self.reply_len = 0;
        self.reply_sent = 0;
    }

    /// The command broke: no reply (or the rest of it) can be placed; the rest of the command is
    /// taken off the loop up to the next clean delimiter.
    fn break_command(&mut self) -> u8 {
        if self.reply_len == 0 {
            self.stats.truncated = self.stats.truncated.saturating_add(1);
        }
        self.last_error = true;
        // The delimiter that broke it is not the end: the junk runs to the next clean one.
        self.rx = Rx::Consume;
        WAIT
    }

    fn command_byte<D: Dataway + ?Sized>(&mut self, input: u8, dataway: &mut D) -> u8 {
        let pos = self.pos;
        self.pos = self.pos.saturating_add(1);
        let answered = self.reply_len != 0;
        if is_clean_delimiter(input) {
            // END ends the command only once the whole reply went out over the SPACE bytes;
            // anywhere else a clean delimiter is a break: the bytes after it are this damaged
            // command's tail, never a message of their own.
            if answered && self.reply_sent >= self.reply_len && input == END {
                self.rx = Rx::Framing;
                self.framer.reset();
                return END;
            }
            return self.break_command();
        }
        if answered {
            // The rest of the reply, then WAIT for any SPACE beyond it.
            if self.reply_sent < self.reply_len {
                let byte = self
                    .reply
                    .get(usize::from(self.reply_sent))
                    .copied()
                    .unwrap_or(WAIT);
                self.reply_sent = self.reply_sent.saturating_add(1);
                return byte;
            }
            return WAIT;
        }
        if is_delimiter(input) {
            // A damaged delimiter: an error in the command, not its end.
            self.error = true;
        }
        if pos <= self.sum_at {
            self.error |= !row_parity_ok(input);
            self.columns ^= input & COLUMNS;
        }
        match pos {
            2 => {
                self.function = input & 0x1F;
                if input & 0x20 != 0 {
                    self.error = true;
                }
                self.sum_at = if is_write(self.function) { 8 } else { 4 };
                let guard = u8::try_from(guard_len(self.function)).unwrap_or(u8::MAX);
                self.room_at = self.sum_at.saturating_add(1).saturating_add(guard);
            }
            3 => {
                self.station = input & 0x1F;
                if input & STATION_MARK == 0 {
                    self.error = true;
                }
            }
            p if p < self.sum_at => {
                self.data = (self.data << 6) | u32::from(input & COLUMNS);
            }
            p if p == self.sum_at => {
                if self.columns != 0 {
                    self.error = true;
                }
            }
            p => {
                // Guard and reply room up to the status byte: every byte must be SPACE. For a
                // non-write that covers positions 5–8, where a write's d2, d3, d4 and SUM stand.
                if input != SPACE {
                    self.error = true;
                }
                if p == self.room_at {
                    // The reply's header does not depend on the status: it goes out now.
                    return with_parity(self.config.address);
                }
                if p > self.room_at {
                    // The status byte: everything up to here was checked.
                    self.answer(dataway);
                    self.reply_sent = 2;
                    return self.reply.get(1).copied().unwrap_or(WAIT);
                }
            }
        }
        WAIT
    }

    fn answer<D: Dataway + ?Sized>(&mut self, dataway: &mut D) {
        let error = self.error;
        let mut status = if error { 1 } else { 0 };
        if self.last_error {
            status |= 8;
        }
        self.last_error = error;
        let mut read = None;
        if error {
            self.stats.errors = self.stats.errors.saturating_add(1);
        } else {
            self.stats.executed = self.stats.executed.saturating_add(1);
            let write = if is_write(self.function) {
                Some(self.data)
            } else {
                None
            };
            let cycle = dataway.cycle(self.station, self.subaddress, self.function, write);
            status |= u8::from(cycle.x) << 1 | u8::from(cycle.q) << 2;
            if is_read(self.function) {
                read = Some(cycle.read & 0xFF_FFFF);
            }
        }
        let header = with_parity(self.config.address);
        let status = with_parity(M1 | status);
        self.reply = [WAIT; 7];
        let len = match read {
            Some(word) => {
                let [d0, d1, d2, d3] = data_bytes(word);
                let text = [header, status, d0, d1, d2, d3];
                self.reply = [header, status, d0, d1, d2, d3, endsum_byte(&text)];
                7
            }
            None => {
                self.reply[0] = header;
                self.reply[1] = status;
                self.reply[2] = endsum_byte(&[header, status]);
                3
            }
        };
        self.reply_len = len;
    }
}

#[cfg(test)]
mod tests {
    use super::super::{MAX_MESSAGE, Message, Status, decode};
    use super::*;

    #[derive(Default)]
    struct Crate {
        regs: [u32; 4],
        cycles: Vec<(u8, u8, u8, Option<u32>)>,
        lam: u8,
    }

    impl Dataway for Crate {
        fn cycle(&mut self, n: u8, a: u8, f: u8, write: Option<u32>) -> Cycle {
            self.cycles.push((n, a, f, write));
            let reg = usize::from(a & 3);
            if let Some(w) = write {
                self.regs[reg] = w;
            }
            Cycle {
                read: self.regs[reg],
                x: true,
                q: f < 8,
            }
        }
        fn graded_lam(&mut self) -> u8 {
            self.lam
        }
    }

    /// A fresh controller that has seen one WAIT (a fresh controller reads nothing before the
    /// first clean delimiter).
    fn synced(config: ControllerConfig) -> Controller {
        let mut c = Controller::new(config).unwrap();
        c.clock(WAIT, &mut Crate::default());
        c
    }

    fn run(c: &mut Controller, crate_: &mut Crate, input: &[u8]) -> Vec<u8> {
        input
            .iter()
            .chain(&[WAIT; 8])
            .map(|&b| c.clock(b, crate_))
            .collect()
    }

    fn encode(m: Message) -> Vec<u8> {
        let mut buf = [0u8; MAX_MESSAGE];
        let len = m.encode(&mut buf).unwrap();
        buf[..len].to_vec()
    }

    /// The messages in an output stream (skipping gap delimiters).
    fn messages(stream: &[u8]) -> Vec<Vec<u8>> {
        let mut out = Vec::new();
        let mut cur = Vec::new();
        for &b in stream {
            if cur.is_empty() && is_delimiter(b) {
                continue;
            }
            cur.push(b);
            if is_delimiter(b) {
                out.push(std::mem::take(&mut cur));
            }
        }
        out
    }

    #[test]
    fn config_is_checked() {
        for bad in [0, 63, 64, 255] {
            assert_eq!(
                Controller::new(ControllerConfig {
                    address: bad,
                    demand_repeat: 0
                })
                .err(),
                Some(ConfigError::Address(bad))
            );
        }
    }

    #[test]
    fn read_is_answered_over_the_spaces_with_one_byte_of_delay() {
        let mut c = synced(ControllerConfig {
            address: 7,
            demand_repeat: 0,
        });
        let mut crate_ = Crate {
            regs: [0x12_3456, 0, 0, 0],
            ..Crate::default()
        };
        let cmd = encode(Message::Command {
            crate_address: 7,
            station: 2,
            subaddress: 0,
            function: 0,
            data: None,
        });
        let out = run(&mut c, &mut crate_, &cmd);
        assert_eq!(out.len(), cmd.len() + 8);
        assert_eq!(out[0], WAIT);
        let found = messages(&out);
        assert_eq!(found.len(), 2, "{out:x?}");
        assert_eq!(
            decode(&found[0]),
            Err(super::super::DecodeError::Truncated { crate_address: 7 })
        );
        assert_eq!(
            decode(&found[1]),
            Ok(Message::Reply {
                crate_address: 7,
                status: Status {
                    x: true,
                    q: true,
                    ..Status::default()
                },
                data: Some(0x12_3456)
            })
        );
        assert_eq!(crate_.cycles, vec![(2, 0, 0, None)]);
        // The reply sits exactly where the SPACE bytes after the two guard bytes were (one byte
        // late).
        assert_eq!(&out[8..15], &found[1][..]);
    }

    #[test]
    fn other_crates_messages_pass_unchanged_one_byte_late() {
        let mut c = synced(ControllerConfig {
            address: 7,
            demand_repeat: 0,
        });
        let mut crate_ = Crate::default();
        let mut stream = encode(Message::Command {
            crate_address: 8,
            station: 2,
            subaddress: 0,
            function: 16,
            data: Some(5),
        });
        stream.extend(encode(Message::Reply {
            crate_address: 7,
            status: Status::default(),
            data: None,
        }));
        stream.extend(encode(Message::Demand {
            crate_address: 7,
            sgl: 3,
        }));
        let out = run(&mut c, &mut crate_, &stream);
        assert_eq!(&out[1..=stream.len()], &stream[..]);
        assert!(crate_.cycles.is_empty());
        assert_eq!(c.stats().passed, 3);
    }

    #[test]
    fn a_command_without_its_station_mark_is_not_run_even_with_good_parity_and_sum() {
        let mut c = synced(ControllerConfig {
            address: 7,
            demand_repeat: 0,
        });
        let mut crate_ = Crate::default();
        let mut cmd = encode(Message::Command {
            crate_address: 7,
            station: 2,
            subaddress: 1,
            function: 0,
            data: None,
        });
        // The station byte without its mark, its row parity and the SUM made good again: only
        // the mark says it is wrong (as `decode` says).
        cmd[3] = with_parity(2);
        cmd[4] = super::super::sum_byte(&cmd[..4]);
        assert!(decode(&cmd).is_err());
        let found = messages(&run(&mut c, &mut crate_, &cmd));
        assert_eq!(
            decode(&found[1]),
            Ok(Message::Reply {
                crate_address: 7,
                status: Status {
                    err: true,
                    ..Status::default()
                },
                data: None
            })
        );
        assert!(crate_.cycles.is_empty());
        assert_eq!((c.stats().errors, c.stats().executed), (1, 0));
    }

    /// `demand_repeat`: while the graded LAM stays the same the demand goes out again every
    /// `demand_repeat` byte clocks on an idle line, and with 0 only once.
    #[test]
    fn a_steady_lam_repeats_its_demand_every_demand_repeat_clocks() {
        for repeat in [0, 1, 2, 50, 100] {
            let mut c = synced(ControllerConfig {
                address: 7,
                demand_repeat: repeat,
            });
            let mut crate_ = Crate {
                lam: 5,
                ..Crate::default()
            };
            let mut at = Vec::new();
            for clock in 0..1000u32 {
                let before = c.stats().demands;
                c.clock(WAIT, &mut crate_);
                if c.stats().demands > before {
                    at.push(clock);
                }
            }
            if repeat == 0 {
                assert_eq!(at, [0], "repeat 0: one demand");
                continue;
            }
            // A demand takes 3 bytes of the line; the count starts when it is decided.
            assert_eq!(at[0], 0, "repeat {repeat}");
            for pair in at.windows(2) {
                assert_eq!(pair[1] - pair[0], repeat.max(3), "repeat {repeat}: {at:?}");
            }
            assert_eq!(at.len() as u32, 1 + 999 / repeat.max(3), "repeat {repeat}");
        }
    }

    #[test]
    fn a_corrupt_command_is_answered_with_err_and_not_run_then_derr() {
        let mut c = synced(ControllerConfig {
            address: 7,
            demand_repeat: 0,
        });
        let mut crate_ = Crate::default();
        let mut cmd = encode(Message::Command {
            crate_address: 7,
            station: 2,
            subaddress: 1,
            function: 16,
            data: Some(77),
        });
        cmd[5] ^= 0x03; // two column bits: row parity holds, the sum does not
        let out = run(&mut c, &mut crate_, &cmd);
        let found = messages(&out);
        let err = Status {
            err: true,
            ..Status::default()
        };
        assert_eq!(
            decode(&found[1]),
            Ok(Message::Reply {
                crate_address: 7,
                status: err,
                data: None
            })
        );
        assert!(crate_.cycles.is_empty());
        // The next, clean command runs and reports the earlier error as DERR.
        let cmd = encode(Message::Command {
            crate_address: 7,
            station: 2,
            subaddress: 1,
            function: 16,
            data: Some(77),
        });
        let found = messages(&run(&mut c, &mut crate_, &cmd));
        let derr = Status {
            derr: true,
            x: true,
            ..Status::default()
        };
        assert_eq!(
            decode(&found[1]),
            Ok(Message::Reply {
                crate_address: 7,
                status: derr,
                data: None
            })
        );
        assert_eq!(crate_.cycles, vec![(2, 1, 16, Some(77))]);
        assert_eq!(c.stats().errors, 1);
        assert_eq!(c.stats().executed, 1);
    }

    #[test]
    fn demand_goes_out_between_messages_and_the_delay_shrinks_back() {
        let mut c = synced(ControllerConfig {
            address: 5,
            demand_repeat: 0,
        });
        let mut crate_ = Crate::default();
        let passing = encode(Message::Reply {
            crate_address: 9,
            status: Status::default(),
            data: Some(1),
        });
        let mut stream = passing.clone();
        stream.extend(&passing); // back to back: no gap
        crate_.lam = 0;
        let mut out = Vec::new();
        let mut max_held = 0;
        for (k, &b) in stream.iter().chain(&[WAIT; 10]).enumerate() {
            if k == 3 {
                crate_.lam = 4; // LAM raised in the middle of a passing message
            }
            out.push(c.clock(b, &mut crate_));
            assert!(c.held() <= 3);
            max_held = max_held.max(c.held());
        }
        // The demand went out right after the first message's ENDSUM: its three bytes were
        // held, and the second message behind them.
        assert_eq!(max_held, 3);
        let found = messages(&out);
        assert_eq!(found.len(), 3, "{out:x?}");
        assert_eq!(found[0], passing);
        assert_eq!(
            decode(&found[1]),
            Ok(Message::Demand {
                crate_address: 5,
                sgl: 4
            })
        );
        assert_eq!(found[2], passing);
        assert_eq!(c.held(), 0);
        assert_eq!(c.stats().demands, 1);
    }

    /// Messages may follow each other without a gap byte: a command to this crate right after
    /// one it answered, or right after the junk of one that broke, is answered too.
    #[test]
    fn a_command_right_after_one_it_took_is_answered() {
        let mut c = synced(ControllerConfig {
            address: 5,
            demand_repeat: 0,
        });
        let mut crate_ = Crate::default();
        let write = |data| {
            encode(Message::Command {
                crate_address: 5,
                station: 1,
                subaddress: 2,
                function: 16,
                data: Some(data),
            })
        };
        let read = encode(Message::Command {
            crate_address: 5,
            station: 1,
            subaddress: 2,
            function: 0,
            data: None,
        });
        // Answered, then straight on; broken (END in its text), its junk up to the next clean
        // delimiter, then straight on.
        let mut stream = write(0x11);
        stream.extend(&read);
        stream.extend(&read[..3]);
        stream.extend([END, END]);
        stream.extend(write(0x22));
        stream.extend(&read);
        let out = run(&mut c, &mut crate_, &stream);
        assert_eq!(
            crate_.cycles,
            vec![
                (1, 2, 16, Some(0x11)),
                (1, 2, 0, None),
                (1, 2, 16, Some(0x22)),
                (1, 2, 0, None)
            ]
        );
        let replies: Vec<_> = messages(&out)
            .iter()
            .filter_map(|m| decode(m).ok())
            .collect();
        let reply = |derr, data: Option<u32>| Message::Reply {
            crate_address: 5,
            status: Status {
                x: true,
                q: data.is_some(),
                derr,
                ..Status::default()
            },
            data,
        };
        assert_eq!(
            replies,
            vec![
                reply(false, None),
                reply(false, Some(0x11)),
                reply(true, None),
                reply(false, Some(0x22))
            ]
        );
        assert_eq!(c.stats().commands, 5);
        assert_eq!(c.stats().executed, 4);
        assert_eq!(c.stats().truncated, 1);
    }

    /// A delimiter other than WAIT between messages is a break: junk up to the next clean
    /// delimiter, and only that far — the command after it is answered.
    #[test]
    fn a_stray_delimiter_between_messages_is_junk_up_to_the_next_clean_delimiter() {
        let mut c = synced(ControllerConfig {
            address: 5,
            demand_repeat: 0,
        });
        let mut crate_ = Crate::default();
        // ENDSUM (a clean delimiter, not WAIT), a header, END: junk, to be passed on as it is.
        let junk = [endsum_byte(&[]), with_parity(9), END];
        let mut stream = junk.to_vec();
        stream.extend(encode(Message::Command {
            crate_address: 5,
            station: 1,
            subaddress: 2,
            function: 16,
            data: Some(0x33),
        }));
        let out = run(&mut c, &mut crate_, &stream);
        assert_eq!(&out[1..4], &junk[..]);
        assert_eq!(crate_.cycles, vec![(1, 2, 16, Some(0x33))]);
        assert_eq!(c.stats().executed, 1);
        assert_eq!(c.stats().passed, 0); // junk is no message
    }

    /// A message is at most `MAX_DECODE` (75) bytes: a command whose SPACE run goes on past that
    /// is junk from its 76th byte, so the next clean delimiter — here a demand's ENDSUM, where a
    /// command may not end — ends it, and the command after it is answered.
    #[test]
    fn a_space_run_past_the_longest_message_is_junk_up_to_the_next_clean_delimiter() {
        let mut c = synced(ControllerConfig {
            address: 5,
            demand_repeat: 0,
        });
        let mut crate_ = Crate::default();
        let other = encode(Message::Command {
            crate_address: 9,
            station: 1,
            subaddress: 2,
            function: 0,
            data: None,
        });
        // 4 text bytes, SUM and 71 SPACE: 76 bytes without a delimiter.
        let mut stream = other[..5].to_vec();
        stream.extend([SPACE; 71]);
        stream.push(endsum_byte(&[]));
        stream.extend(encode(Message::Command {
            crate_address: 5,
            station: 1,
            subaddress: 2,
            function: 16,
            data: Some(0x44),
        }));
        run(&mut c, &mut crate_, &stream);
        assert_eq!(crate_.cycles, vec![(1, 2, 16, Some(0x44))]);
        assert_eq!(c.stats().passed, 1);
    }

    /// A command to another crate cut short by END (before its SPACE run) is broken: the stream
    /// is junk up to the next clean delimiter after that END, so a message following without a
    /// gap — which may be the damaged command's own tail — is not taken; after a gap it is.
    #[test]
    fn an_end_inside_another_crates_command_makes_junk_up_to_the_next_clean_delimiter() {
        let mut c = synced(ControllerConfig {
            address: 5,
            demand_repeat: 0,
        });
        let mut crate_ = Crate::default();
        let other = encode(Message::Command {
            crate_address: 9,
            station: 1,
            subaddress: 2,
            function: 0,
            data: None,
        });
        let ours = encode(Message::Command {
            crate_address: 5,
            station: 1,
            subaddress: 2,
            function: 16,
            data: Some(0x55),
        });
        // 4 text bytes, SUM, 2 SPACE and END: 9 SPACE short.
        let mut stream = other[..7].to_vec();
        stream.push(END);
        stream.extend(&ours);
        run(&mut c, &mut crate_, &stream);
        assert_eq!(crate_.cycles, vec![]);
        assert_eq!(c.stats().commands, 0);
        // The END of the junk ends it: the same command again, after a gap, is answered.
        run(&mut c, &mut crate_, &ours);
        assert_eq!(crate_.cycles, vec![(1, 2, 16, Some(0x55))]);
    }

    /// A byte other than SPACE after another crate's command's SUM is a break: junk from there,
    /// so the next clean delimiter — here a demand's ENDSUM, where a command may not end — ends
    /// it, and the command after it is answered.
    #[test]
    fn a_text_byte_in_another_crates_reply_room_is_a_break() {
        let mut c = synced(ControllerConfig {
            address: 5,
            demand_repeat: 0,
        });
        let mut crate_ = Crate::default();
        let other = encode(Message::Command {
            crate_address: 9,
            station: 1,
            subaddress: 2,
            function: 0,
            data: None,
        });
        // 4 text bytes, SUM, 2 SPACE, a text byte that is not SPACE, ENDSUM.
        let mut stream = other[..7].to_vec();
        stream.extend([with_parity(1), endsum_byte(&[])]);
        stream.extend(encode(Message::Command {
            crate_address: 5,
            station: 1,
            subaddress: 2,
            function: 16,
            data: Some(0x66),
        }));
        run(&mut c, &mut crate_, &stream);
        assert_eq!(crate_.cycles, vec![(1, 2, 16, Some(0x66))]);
    }

    /// A reply longer than 7 bytes breaks at its 7th byte (where ENDSUM belongs): junk from
    /// there, so its ENDSUM ends the junk and the command right after it is answered.
    #[test]
    fn a_reply_one_byte_too_long_is_junk_up_to_its_endsum() {
        let mut c = synced(ControllerConfig {
            address: 5,
            demand_repeat: 0,
        });
        let mut crate_ = Crate::default();
        let reply = encode(Message::Reply {
            crate_address: 9,
            status: Status::default(),
            data: Some(0x77),
        });
        // Header, status, 4 data bytes, one more text byte, ENDSUM.
        let mut stream = reply[..6].to_vec();
        stream.extend([with_parity(1), endsum_byte(&[])]);
        stream.extend(encode(Message::Command {
            crate_address: 5,
            station: 1,
            subaddress: 2,
            function: 16,
            data: Some(0x77),
        }));
        run(&mut c, &mut crate_, &stream);
        assert_eq!(crate_.cycles, vec![(1, 2, 16, Some(0x77))]);
    }

    /// A dataway that does not report a graded LAM (the trait's default) makes no demand.
    #[test]
    fn a_dataway_without_graded_lam_makes_no_demand() {
        struct Plain;
        impl Dataway for Plain {
            fn cycle(&mut self, _: u8, _: u8, _: u8, _: Option<u32>) -> Cycle {
                Cycle {
                    read: 0,
                    x: true,
                    q: true,
                }
            }
        }
        let mut c = Controller::new(ControllerConfig {
            address: 5,
            demand_repeat: 1,
        })
        .unwrap();
        let out: Vec<u8> = (0..50).map(|_| c.clock(WAIT, &mut Plain)).collect();
        assert_eq!(out, vec![WAIT; 50]);
        assert_eq!(c.stats().demands, 0);
    }
}
