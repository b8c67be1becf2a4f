//! The 1977 operator-panel link (source 000): the computer refreshes each panel's registers
//! with an endless byte sequence and takes key presses over a MOT/SÄN handshake.
//!
//! # On the wire
//! The host sends, forever, the **reset byte** [`RESET`] (`0xFF`), one byte time of idle line,
//! and one byte per register, in register order: `RESET · r1 … rR RESET · r1 … rR …` (`·` =
//! idle). **Register bytes carry 7 bits** (0–127, bit 8 always 0), so no register value is the
//! reset byte; [`Host::set`] refuses a value above 127 ([`RegisterError::Value`]). On the line
//! each byte is framed with a start bit, 8 data bits, an even parity bit and a stop bit
//! ([`crate::line::Framing::PANEL`]).
//!
//! The panel's counter, zeroed by a reset byte, says which register a byte is for; the panel
//! **stages** the bytes and shows them only when the next reset byte arrives after **exactly
//! `R` clean bytes**. A byte that arrives with a framing or parity error, or with bit 8 set,
//! drops the sequence it falls in; so does a reset byte after fewer or more bytes
//! ([`PanelStats::discarded`]); the display keeps what it showed, and the next reset byte starts
//! afresh. (The source latched each byte at once and let a damaged byte keep its register's old
//! value; see below for why a damaged byte now costs its whole sequence, and the idle byte time
//! is there.)
//!
//! # What the panel shows after a bit error
//! The parity bit catches every odd number of flipped bits in a frame, and a flipped start or
//! stop bit is a framing error; two flips among the data and parity bits pass. So a 2-bit error
//! can turn a register value into the reset byte (`0x7E` → `0xFF`: every value with six or seven
//! ones), the reset byte into a register value, or one register value into another. A flipped
//! start bit, or a flipped idle bit read as a start bit, makes a bit receiver lose character
//! sync: it reads frames that are not the host's until it finds the start bits again, and a
//! second flip can make such a frame pass the parity — or make a fake reset byte: a receiver
//! thrown out of sync can take the closing reset byte's parity bit (0) for a start bit and read
//! its stop bit and the idle ones as `0xFF`; a flipped idle bit makes that frame clean. What is
//! guaranteed, at the level it is tested:
//! - **Frames read in sync** (what a UART gives while it keeps character sync, e.g. one or two
//!   flips among the data and parity bits): after any 1- or 2-bit error, **no register ever
//!   shows a value the host did not send for that register** (in this or an earlier sequence;
//!   before the first sequence, 0): never a shifted display. The one exception the link cannot
//!   see: a register whose own frame took both flips may show a wrong 7-bit value until the
//!   next clean sequence (the link has no checksum).
//! - **At bit level, through a bit receiver** ([`crate::line::BitReceiver`]), start, stop and
//!   idle bits included: after any **1-bit** error no register shows a value the host did not
//!   send for it; after any **1- or 2-bit** error **every register shows the host's value again
//!   within two sequences**: once the reset byte closing the second sequence after the one the
//!   damage fell in has arrived. Until then a 2-bit error that throws the receiver out of
//!   character sync can show wrong 7-bit values (rare: beyond the register whose own frame took
//!   both flips, 16 of 972 400 bit pairs with 7 registers, 160 of 1 566 400 with 1 register,
//!   random values biased to many ones — the test `measure_wrong_values_after_two_flips`).
//!
//! Recovery is bounded because the idle byte time after every reset byte lets a receiver that
//! lost sync find the start bits again, whatever the data, and a damaged byte drops its
//! sequence. Without the idle byte time a receiver out of sync could read every frame as a
//! framing error for as long as the data repeated (one flipped start bit could leave a display
//! stale for good); without dropping a sequence on a damaged byte, frames read out of sync that
//! passed the parity could be shown. The idle time also creates the fake-reset pattern above; a
//! display that recovers within two sequences from every 1- and 2-bit error was chosen over one
//! that can freeze on one flip. The price: one byte time per sequence (`R + 2` byte times), and
//! under noise a damaged byte costs its whole sequence, not one register, for one sequence.
//!
//! Tested, frame level: every value 0–127 at every position of 7, 29 and 46 registers and every
//! 1- and 2-bit change of its frame and of the reset bytes on both sides, and one bit in each of
//! two frames. Bit level: every single bit and every pair of bits from the reset byte opening a
//! sequence through the idle byte time after the reset byte closing the next one (two whole
//! sequences and the idle byte times on both sides), with eight sets of values chosen to be
//! hard (runs of `0x7F`, `0x7E`, 0, single bits, alternating bits) and with random values, new
//! every sequence, for 1, 2 and 7 registers.
//!
//! # The key handshake
//! - The panel has a key: it raises **MOT**.
//! - The host looks at MOT every **10 ms** ([`Host::poll_mot`]) and answers it **between
//!   sequences only**: right after the reset byte that closes a sequence ([`Host::next_byte`]
//!   then returns `None`), it raises **SÄN** and listens. (The source stopped the sequence at
//!   once; a MOT line that chatters could then stop every sequence before its end.)
//! - While SÄN is up the panel sends the key byte at once and again every **20 ms**
//!   ([`Panel::tick_20ms`]).
//! - Two **consecutive identical** clean bytes are the key ([`HostEvent::Key`]); the host drops
//!   SÄN. A damaged byte in between starts the pair again, so a key is never altered by one
//!   damaged byte.
//! - SÄN dropped: the panel drops MOT (for two of its 20 ms ticks) and forgets the key; the host
//!   keeps SÄN low until MOT has read low on a poll since SÄN fell **and** three polls have
//!   passed (or until [`HostConfig::mot_stuck_polls`]), goes on with the registers (the reset
//!   byte went out before the exchange), and sends a whole sequence before it answers MOT
//!   again. The third poll comes more than 20 ms after SÄN fell, so **a panel that samples SÄN
//!   at least every 20 ms sees every key taken before SÄN rises again: no key is ever
//!   delivered twice, whatever the MOT line does** (a MOT line that lies on single polls, or on
//!   many). (Leaving on one poll that read MOT low let a chattering MOT line deliver a key twice.)
//! - The panel must sample SÄN at least every 20 ms (and send the key byte when it sees SÄN
//!   rise, and again every 20 ms while it is up); [`MIN_KEY_TIMEOUT_POLLS`] (6) is what that
//!   takes: the second key byte arrives up to 42.3 ms after SÄN rose.
//!
//! A key waits at most one sequence (`R + 2` byte times) plus a poll and a byte time before
//! SÄN rises.
//!
//! Beyond the source: the host gives up on a key after [`HostConfig::key_timeout_polls`] polls
//! ([`HostEvent::KeyTimedOut`]) and on a MOT line that never drops after
//! [`HostConfig::mot_stuck_polls`] ([`HostEvent::MotStuck`]: it goes back to refreshing and
//! ignores MOT for `mot_stuck_polls` polls more, or until it reads low; a panel holding a key is
//! never ignored for good). So **whatever the MOT line does** (stuck high, stuck
//! low, toggling at every poll, glitching), when the transmitter asks [`Host::next_byte`] once
//! per byte time and MOT is polled every 10 ms, on a clean line **the panel shows a new sequence
//! at least every `R + 3` byte times plus `key_timeout_polls + mot_stuck_polls` polls** (the
//! third byte time: a transmitter that asks once per byte time sees the host sending again up
//! to a byte time after the poll that ends an exchange; with the defaults and 29 registers:
//! 73 ms + 1.1 s), and every `R + 2` byte times while nobody presses a key (71 ms).

use core::fmt;

use heapless::Deque;

use crate::line::LineError;

/// The reset byte: zeroes the panel's register counter. The only byte with bit 8 set.
pub const RESET: u8 = 0xFF;
/// The largest register value (7 bits).
pub const MAX_VALUE: u8 = 0x7F;
/// Registers of a loading desk.
pub const LOADING_DESK: usize = 7;
/// Registers of panel A or B.
pub const LANE_PANEL: usize = 29;
/// Registers of the central desk.
pub const CENTRAL_DESK: usize = 46;
/// Keys a panel holds while the host has not taken them.
pub const KEY_QUEUE: usize = 8;

/// Why a register could not be set.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum RegisterError {
    /// No such register.
    Index {
        /// The index asked for.
        index: usize,
        /// How many registers there are.
        registers: usize,
    },
    /// The value does not fit 7 bits: it could be taken for the reset byte.
    Value(u8),
}

impl fmt::Display for RegisterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Index { index, registers } => {
                write!(
                    f,
                    "register {index} does not exist (the panel has {registers})"
                )
            }
            Self::Value(v) => write!(f, "register values are 0..=127 (7 bits), got {v}"),
        }
    }
}

impl core::error::Error for RegisterError {}

/// The smallest [`HostConfig::key_timeout_polls`]: 6 polls.
///
/// A panel that samples SÄN every 20 ms sends the key byte up to 20 ms after SÄN rises and
/// repeats it 20 ms later; the second byte has arrived one byte time (2.3 ms at 4 800 baud, 11
/// bits) after that: up to 42.3 ms after SÄN rose. The host counts polls from the rise, and
/// its first poll may come at once, so its `n`-th poll may come `(n − 1) · 10` ms after the
/// rise: 5 polls may give up at 40 ms, before the second byte; 6 polls wait at least 50 ms.
pub const MIN_KEY_TIMEOUT_POLLS: u16 = 6;

/// The smallest [`HostConfig::mot_stuck_polls`]: 3 polls, the least the host keeps SÄN low
/// after a key exchange (the third poll comes more than 20 ms after SÄN fell).
pub const MIN_MOT_STUCK_POLLS: u16 = 3;

/// Why a host configuration was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ConfigError {
    /// `key_timeout_polls` below [`MIN_KEY_TIMEOUT_POLLS`]: the host would give up on keys
    /// before a panel sampling SÄN every 20 ms has sent the key byte twice, on a clean line.
    KeyTimeout(u16),
    /// `mot_stuck_polls` below [`MIN_MOT_STUCK_POLLS`]: the host keeps SÄN low for that many
    /// polls after every key exchange, whatever MOT does.
    MotStuck(u16),
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::KeyTimeout(polls) => write!(
                f,
                "key_timeout_polls {polls} is below {MIN_KEY_TIMEOUT_POLLS}: the second key byte \
                 of a panel sampling SÄN every 20 ms arrives up to 42.3 ms after SÄN rises, and \
                 poll 5 may come 40 ms after it (keys lost on a clean line)"
            ),
            Self::MotStuck(polls) => write!(
                f,
                "mot_stuck_polls {polls} is below {MIN_MOT_STUCK_POLLS}: the host keeps SÄN low \
                 for 3 polls (over 20 ms) after a key exchange, so that a panel sampling SÄN \
                 every 20 ms sees it low"
            ),
        }
    }
}

impl core::error::Error for ConfigError {}

/// How long the host waits, in MOT polls (10 ms each).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct HostConfig {
    /// Polls with SÄN up without two equal bytes before the key is given up (default 10 =
    /// 100 ms: five repeats of the key; at least [`MIN_KEY_TIMEOUT_POLLS`]).
    pub key_timeout_polls: u16,
    /// Polls waiting for MOT to drop after a key exchange before the host refreshes again
    /// regardless (default 100; at least [`MIN_MOT_STUCK_POLLS`]); a MOT still high then is
    /// ignored for as many polls more, or until it reads low.
    ///
    /// `key_timeout_polls + mot_stuck_polls` polls is the longest a key exchange lasts, so the
    /// panel shows a new sequence at least every `R + 3` byte times plus that many polls.
    pub mot_stuck_polls: u16,
}

impl Default for HostConfig {
    fn default() -> Self {
        Self {
            key_timeout_polls: 10,
            mot_stuck_polls: 100,
        }
    }
}

/// What the host reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum HostEvent {
    /// A key arrived (two identical clean bytes in a row).
    Key(u8),
    /// SÄN was up for the whole key time-out without two identical bytes; the key is lost.
    KeyTimedOut,
    /// MOT did not drop after SÄN did; the host refreshes again and ignores MOT until it drops.
    MotStuck,
}

/// The host's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct HostStats {
    /// Complete sequences sent: counted when the reset byte that closes one goes out (the panel
    /// shows a sequence when that reset byte arrives).
    pub sequences: u64,
    /// Keys delivered.
    pub keys: u64,
    /// Bytes received with a line error while listening.
    pub line_errors: u64,
    /// Keys given up.
    pub key_timeouts: u64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
enum HostState {
    /// Sending; `next` = 0 is the reset byte, 1 the idle byte time after it (or the key's
    /// turn), k ≥ 2 the register k − 2 (the snapshot is taken at 2).
    Sending { next: usize },
    /// SÄN up, listening.
    AwaitKey { polls: u16, last: Option<u8> },
    /// SÄN dropped `polls` polls ago; `low`: MOT has read low since.
    AwaitMotLow { polls: u16, low: bool },
}

/// The computer's side of one panel's link, with `R` registers (7, 29 or 46 in the source).
///
/// ```
/// use regler_panel_link::panel::{Host, HostConfig, Panel, RESET};
///
/// let mut host: Host<7> = Host::new(HostConfig::default())?;
/// let mut panel: Panel<7> = Panel::new();
/// host.set(2, 99)?;
/// assert_eq!(host.next_byte(), Some(RESET));
/// panel.receive(Ok(RESET));
/// assert_eq!(host.next_byte(), None); // one byte time of idle line after the reset byte
/// for _ in 0..7 {
///     let byte = host.next_byte().unwrap_or(RESET); // the 7 registers
///     panel.receive(Ok(byte));
/// }
/// assert_eq!(panel.registers()[2], 0); // staged: shown when the next reset byte arrives
/// panel.receive(Ok(host.next_byte().unwrap_or(RESET)));
/// assert_eq!(panel.registers()[2], 99);
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct Host<const R: usize> {
    config: HostConfig,
    registers: [u8; R],
    /// The registers as they were when the current sequence began.
    sending: [u8; R],
    state: HostState,
    /// MOT as the last poll saw it (false while a stuck MOT is ignored).
    mot: bool,
    /// Polls a stuck MOT is still ignored for (until it reads low).
    ignore_polls: u16,
    /// The reset byte closing a sequence has just gone out: a waiting key may be taken now.
    between: bool,
    /// The registers of a sequence have gone out: the next reset byte completes it.
    open: bool,
    stats: HostStats,
}

impl<const R: usize> Host<R> {
    /// A host with every register 0, about to send a reset byte.
    ///
    /// # Errors
    /// [`ConfigError`]: a key time-out below [`MIN_KEY_TIMEOUT_POLLS`] or a MOT time-out below
    /// [`MIN_MOT_STUCK_POLLS`], with the value.
    pub const fn new(config: HostConfig) -> Result<Self, ConfigError> {
        const { assert!(R > 0, "a panel has at least one register") };
        if config.key_timeout_polls < MIN_KEY_TIMEOUT_POLLS {
            return Err(ConfigError::KeyTimeout(config.key_timeout_polls));
        }
        if config.mot_stuck_polls < MIN_MOT_STUCK_POLLS {
            return Err(ConfigError::MotStuck(config.mot_stuck_polls));
        }
        Ok(Self {
            config,
            registers: [0; R],
            sending: [0; R],
            state: HostState::Sending { next: 0 },
            mot: false,
            ignore_polls: 0,
            between: false,
            open: false,
            stats: HostStats {
                sequences: 0,
                keys: 0,
                line_errors: 0,
                key_timeouts: 0,
            },
        })
    }

    /// Sets register `index` to `value`; it goes out from the next sequence on.
    ///
    /// # Errors
    /// [`RegisterError`]: no such register, or a value above 127; nothing changes then.
    pub fn set(&mut self, index: usize, value: u8) -> Result<(), RegisterError> {
        if value > MAX_VALUE {
            return Err(RegisterError::Value(value));
        }
        let slot = self.registers.get_mut(index).ok_or(RegisterError::Index {
            index,
            registers: R,
        })?;
        *slot = value;
        Ok(())
    }

    /// The registers as the application last set them.
    #[must_use]
    pub const fn registers(&self) -> &[u8; R] {
        &self.registers
    }

    /// The SÄN line.
    #[must_use]
    pub const fn san(&self) -> bool {
        matches!(self.state, HostState::AwaitKey { .. })
    }

    /// The counters.
    #[must_use]
    pub const fn stats(&self) -> &HostStats {
        &self.stats
    }

    /// The transmitter is ready: the next byte of the stream, or `None`: leave the line idle
    /// for this byte time. Call it once per byte time (one frame) while the transmitter is
    /// ready, also after a `None`.
    ///
    /// `None` comes once per sequence, for one byte time after its reset byte (an idle frame on
    /// the line lets a receiver that lost character sync find the start bits again), and while
    /// the host is not sending (SÄN up, or waiting for MOT to drop).
    ///
    /// Right after a reset byte, if the last MOT poll saw MOT high, the host raises SÄN here
    /// (and returns `None`) instead of starting the next sequence; it never does so inside a
    /// sequence, and after a key exchange it sends a whole sequence before it looks at MOT again.
    pub fn next_byte(&mut self) -> Option<u8> {
        let HostState::Sending { next } = self.state else {
            return None;
        };
        if next == 0 {
            // The reset byte: it closes the sequence before it (the panel shows it now) and
            // opens the next.
            if core::mem::replace(&mut self.open, false) {
                self.stats.sequences = self.stats.sequences.saturating_add(1);
            }
            self.between = true;
            self.state = HostState::Sending { next: 1 };
            return Some(RESET);
        }
        if next == 1 {
            if core::mem::replace(&mut self.between, false) && self.mot {
                self.state = HostState::AwaitKey {
                    polls: 0,
                    last: None,
                };
                return None;
            }
            // One byte time of idle line after the reset byte: a bit receiver that lost
            // character sync (a flipped start bit on back-to-back frames) finds the start bits
            // again before the registers.
            self.state = HostState::Sending { next: 2 };
            return None;
        }
        if next == 2 {
            self.sending = self.registers;
        }
        let byte = self
            .sending
            .get(next.saturating_sub(2))
            .copied()
            .unwrap_or(RESET);
        let next = if next > R {
            self.open = true;
            0
        } else {
            next.saturating_add(1)
        };
        self.state = HostState::Sending { next };
        Some(byte)
    }

    /// The 10 ms MOT poll, with the MOT line's state.
    ///
    /// After a key exchange (a key taken or given up) SÄN stays low until MOT has read low on
    /// some poll since SÄN fell **and** at least [`MIN_MOT_STUCK_POLLS`] (3) polls have passed,
    /// or until [`HostConfig::mot_stuck_polls`] polls have passed; then the host sends a whole
    /// sequence before it can raise SÄN again. The third poll comes more than 20 ms after SÄN
    /// fell, so SÄN stays low for more than 20 ms whatever MOT does: a panel that samples SÄN at
    /// least every 20 ms sees the key taken before SÄN rises again, and **no key is delivered
    /// twice, however the MOT line lies**. A MOT still high after `mot_stuck_polls` is ignored
    /// for `mot_stuck_polls` polls more, or until it reads low.
    pub fn poll_mot(&mut self, mot: bool) -> Option<HostEvent> {
        if mot {
            self.ignore_polls = self.ignore_polls.saturating_sub(1);
            self.mot = self.ignore_polls == 0;
        } else {
            self.ignore_polls = 0;
            self.mot = false;
        }
        match self.state {
            HostState::Sending { .. } => None, // MOT is looked at between sequences only
            HostState::AwaitKey { polls, last } => {
                let polls = polls.saturating_add(1);
                if polls >= self.config.key_timeout_polls {
                    self.stats.key_timeouts = self.stats.key_timeouts.saturating_add(1);
                    self.state = HostState::AwaitMotLow {
                        polls: 0,
                        low: false,
                    };
                    return Some(HostEvent::KeyTimedOut);
                }
                self.state = HostState::AwaitKey { polls, last };
                None
            }
            HostState::AwaitMotLow { polls, low } => {
                let polls = polls.saturating_add(1);
                let low = low || !mot;
                // Back to the registers where they stopped: right after a reset byte, so the
                // next sequence goes out whole before MOT is looked at again.
                if low && polls >= MIN_MOT_STUCK_POLLS {
                    self.state = HostState::Sending { next: 1 };
                    return None;
                }
                if polls >= self.config.mot_stuck_polls {
                    self.ignore_polls = self.config.mot_stuck_polls;
                    self.mot = false;
                    self.state = HostState::Sending { next: 1 };
                    return Some(HostEvent::MotStuck);
                }
                self.state = HostState::AwaitMotLow { polls, low };
                None
            }
        }
    }

    /// A byte (or a line error) arrived from the panel.
    pub fn receive(&mut self, byte: Result<u8, LineError>) -> Option<HostEvent> {
        let HostState::AwaitKey { polls, last } = self.state else {
            return None; // not listening: late repeats and noise are ignored
        };
        match byte {
            Err(_) => {
                self.stats.line_errors = self.stats.line_errors.saturating_add(1);
                self.state = HostState::AwaitKey { polls, last: None };
                None
            }
            Ok(key) if last == Some(key) => {
                self.stats.keys = self.stats.keys.saturating_add(1);
                self.state = HostState::AwaitMotLow {
                    polls: 0,
                    low: false,
                };
                Some(HostEvent::Key(key))
            }
            Ok(key) => {
                self.state = HostState::AwaitKey {
                    polls,
                    last: Some(key),
                };
                None
            }
        }
    }
}

/// Why a key press was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum PanelError {
    /// [`KEY_QUEUE`] keys are already waiting; this one is handed back.
    QueueFull(u8),
}

impl fmt::Display for PanelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::QueueFull(key) => write!(
                f,
                "key {key:#04x} refused: {KEY_QUEUE} keys are already waiting"
            ),
        }
    }
}

impl core::error::Error for PanelError {}

/// The panel's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PanelStats {
    /// Reset bytes received.
    pub resets: u64,
    /// Sequences shown: a reset byte arrived after exactly `R` bytes since the reset before.
    pub shown: u64,
    /// Sequences not shown: a reset byte arrived after 1 to `R − 1` bytes, or after more than
    /// `R`, since the reset before (a byte became a reset byte, or a reset byte was damaged),
    /// or a damaged byte arrived in them.
    pub discarded: u64,
    /// Bytes with a framing or parity error, or with bit 8 set but not the reset byte.
    pub bad_bytes: u64,
    /// Bytes beyond the last register, or before the first reset (ignored).
    pub overruns: u64,
    /// Keys taken by the host.
    pub keys_sent: u64,
}

/// The panel's side: counter, registers, key queue, MOT.
///
/// ```
/// use regler_panel_link::panel::Panel;
///
/// let mut panel: Panel<29> = Panel::new();
/// panel.press(0x41)?;
/// assert!(panel.mot());
/// assert_eq!(panel.set_san(true), Some(0x41)); // sent at once…
/// assert_eq!(panel.tick_20ms(), Some(0x41));   // …and every 20 ms
/// assert_eq!(panel.set_san(false), None);      // taken
/// assert!(!panel.mot());
/// # Ok::<(), regler_panel_link::panel::PanelError>(())
/// ```
#[derive(Clone, Debug)]
pub struct Panel<const R: usize> {
    registers: [u8; R],
    /// The sequence being received: per register its 7-bit value.
    staged: [u8; R],
    /// Bytes received since the last reset byte; `None` until the first reset byte.
    counter: Option<usize>,
    keys: Deque<u8, KEY_QUEUE>,
    san: bool,
    /// Ticks MOT stays low after a key was taken.
    mot_low_ticks: u8,
    stats: PanelStats,
}

impl<const R: usize> Default for Panel<R> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const R: usize> Panel<R> {
    /// A panel with every register 0, waiting for its first reset byte.
    #[must_use]
    pub const fn new() -> Self {
        const { assert!(R > 0, "a panel has at least one register") };
        Self {
            registers: [0; R],
            staged: [0; R],
            counter: None,
            keys: Deque::new(),
            san: false,
            mot_low_ticks: 0,
            stats: PanelStats {
                resets: 0,
                shown: 0,
                discarded: 0,
                bad_bytes: 0,
                overruns: 0,
                keys_sent: 0,
            },
        }
    }

    /// The registers as latched.
    #[must_use]
    pub const fn registers(&self) -> &[u8; R] {
        &self.registers
    }

    /// The counters.
    #[must_use]
    pub const fn stats(&self) -> &PanelStats {
        &self.stats
    }

    /// A byte (or line error) from the host.
    ///
    /// Bytes after a reset byte are staged; the next reset byte shows them, and only if exactly
    /// `R` bytes came in between (a damaged one keeps its register's old value). Otherwise the
    /// staged bytes are dropped and the display keeps what it showed.
    pub fn receive(&mut self, byte: Result<u8, LineError>) {
        if byte == Ok(RESET) {
            self.stats.resets = self.stats.resets.saturating_add(1);
            match self.counter {
                Some(n) if n == R => {
                    self.registers = self.staged;
                    self.stats.shown = self.stats.shown.saturating_add(1);
                }
                // A reset byte right after a reset byte drops nothing.
                Some(0) | None => {}
                Some(_) => self.stats.discarded = self.stats.discarded.saturating_add(1),
            }
            self.counter = Some(0);
            return;
        }
        let Some(at) = self.counter else {
            self.stats.overruns = self.stats.overruns.saturating_add(1);
            return;
        };
        let Ok(value @ 0..=MAX_VALUE) = byte else {
            // A damaged byte (framing or parity error, or bit 8 set): the receiver may have
            // lost character sync, and what it reads until it finds the start bits again is
            // not the host's bytes, yet can pass the parity. Nothing of this sequence is shown;
            // the next reset byte starts afresh.
            self.stats.bad_bytes = self.stats.bad_bytes.saturating_add(1);
            self.stats.discarded = self.stats.discarded.saturating_add(1);
            self.counter = None;
            return;
        };
        self.counter = Some(at.saturating_add(1));
        match self.staged.get_mut(at) {
            Some(slot) => *slot = value,
            None => self.stats.overruns = self.stats.overruns.saturating_add(1),
        }
    }

    /// The operator pressed a key.
    ///
    /// # Errors
    /// [`PanelError::QueueFull`] with the key, when [`KEY_QUEUE`] keys are waiting.
    pub fn press(&mut self, key: u8) -> Result<(), PanelError> {
        self.keys.push_back(key).map_err(PanelError::QueueFull)
    }

    /// Keys waiting.
    #[must_use]
    pub fn keys_waiting(&self) -> usize {
        self.keys.len()
    }

    /// The MOT line: a key is waiting (and the last key's MOT-low time is over).
    #[must_use]
    pub fn mot(&self) -> bool {
        !self.keys.is_empty() && self.mot_low_ticks == 0
    }

    /// The SÄN line changed (or was sampled): on a rise, the key byte to send at once; on a
    /// fall, the key counts as taken.
    pub fn set_san(&mut self, san: bool) -> Option<u8> {
        let was = core::mem::replace(&mut self.san, san);
        match (was, san) {
            (false, true) => self.keys.front().copied(),
            (true, false) => {
                if self.keys.pop_front().is_some() {
                    self.stats.keys_sent = self.stats.keys_sent.saturating_add(1);
                }
                self.mot_low_ticks = 2;
                None
            }
            _ => None,
        }
    }

    /// The 20 ms tick: the key byte again while SÄN is up.
    pub fn tick_20ms(&mut self) -> Option<u8> {
        self.mot_low_ticks = self.mot_low_ticks.saturating_sub(1);
        if self.san {
            self.keys.front().copied()
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn register_values_are_checked() {
        let mut host: Host<7> = Host::new(HostConfig::default()).unwrap();
        assert_eq!(
            host.set(7, 1),
            Err(RegisterError::Index {
                index: 7,
                registers: 7
            })
        );
        assert_eq!(host.set(0, 128), Err(RegisterError::Value(128)));
        assert_eq!(host.set(0, RESET), Err(RegisterError::Value(RESET)));
        assert_eq!(host.set(6, 127), Ok(()));
        assert_eq!(host.registers(), &[0, 0, 0, 0, 0, 0, 127]);
        let config = |key_timeout_polls, mot_stuck_polls| HostConfig {
            key_timeout_polls,
            mot_stuck_polls,
        };
        // The boundaries: 6 polls of key time-out, 2 of MOT time-out.
        for kt in 0..MIN_KEY_TIMEOUT_POLLS {
            let e = Host::<7>::new(config(kt, 100)).unwrap_err();
            assert_eq!(e, ConfigError::KeyTimeout(kt));
            assert!(e.to_string().contains("below 6"), "{e}");
        }
        assert!(Host::<7>::new(config(MIN_KEY_TIMEOUT_POLLS, 100)).is_ok());
        for ms in 0..MIN_MOT_STUCK_POLLS {
            let e = Host::<7>::new(config(10, ms)).unwrap_err();
            assert_eq!(e, ConfigError::MotStuck(ms));
            assert!(e.to_string().contains("sees it low"), "{e}");
        }
        assert!(Host::<7>::new(config(10, MIN_MOT_STUCK_POLLS)).is_ok());
    }

    #[test]
    fn no_register_byte_is_the_reset_byte() {
        for value in 0..=MAX_VALUE {
            assert_ne!(value, RESET);
            assert_eq!(value & 0x80, 0);
        }
    }

    #[test]
    fn a_sequence_never_mixes_two_updates() {
        let mut host: Host<3> = Host::new(HostConfig::default()).unwrap();
        host.set(0, 1).unwrap();
        host.set(2, 1).unwrap();
        assert_eq!(host.next_byte(), Some(RESET));
        assert_eq!(host.next_byte(), None); // the idle byte time after the reset byte
        assert_eq!(host.next_byte(), Some(1));
        host.set(2, 2).unwrap(); // mid-sequence: goes out next time
        assert_eq!(host.next_byte(), Some(0));
        assert_eq!(host.next_byte(), Some(1));
        assert_eq!(host.stats().sequences, 0);
        assert_eq!(host.next_byte(), Some(RESET));
        assert_eq!(host.stats().sequences, 1);
        assert_eq!(host.next_byte(), None);
        assert_eq!(
            [host.next_byte(), host.next_byte(), host.next_byte()],
            [Some(1), Some(0), Some(2)]
        );
    }

    #[test]
    fn a_damaged_byte_drops_its_sequence() {
        let mut panel: Panel<3> = Panel::new();
        panel.receive(Ok(5)); // before any reset: ignored
        assert_eq!(panel.registers(), &[0, 0, 0]);
        for b in [Ok(RESET), Ok(1), Ok(2), Ok(3)] {
            panel.receive(b);
        }
        assert_eq!(panel.registers(), &[0, 0, 0]); // staged until the reset byte after it
        for b in [Ok(RESET), Ok(4), Err(LineError::Parity), Ok(6), Ok(RESET)] {
            panel.receive(b);
        }
        assert_eq!(panel.registers(), &[1, 2, 3]); // the damaged sequence is not shown
        for b in [Ok(7), Err(LineError::Framing), Ok(0x80), Ok(RESET)] {
            panel.receive(b);
        }
        assert_eq!(panel.registers(), &[1, 2, 3]);
        for b in [Ok(4), Ok(5), Ok(6), Ok(RESET)] {
            panel.receive(b);
        }
        assert_eq!(panel.registers(), &[4, 5, 6]); // the next clean sequence is
        assert_eq!(panel.stats().bad_bytes, 2);
        assert_eq!(panel.stats().shown, 2);
        assert_eq!(panel.stats().discarded, 2);
        assert_eq!(panel.stats().overruns, 3);
    }

    #[test]
    fn a_sequence_of_the_wrong_length_is_not_shown() {
        let mut panel: Panel<3> = Panel::new();
        for b in [RESET, 1, 2, 3, RESET] {
            panel.receive(Ok(b));
        }
        // Too short (a byte became a reset byte), too long (a reset byte was damaged): dropped.
        for b in [4, RESET, 5, 6, RESET, 7, 8, 9, 0x7F, 10, 11, 12] {
            panel.receive(Ok(b));
        }
        panel.receive(Ok(RESET));
        assert_eq!(panel.registers(), &[1, 2, 3]);
        assert_eq!(panel.stats().discarded, 3);
        assert_eq!(panel.stats().overruns, 4);
        // A reset right after a reset drops nothing.
        panel.receive(Ok(RESET));
        assert_eq!(panel.stats().discarded, 3);
    }

    #[test]
    fn handshake_delivers_one_key_between_sequences() {
        let mut host: Host<7> = Host::new(HostConfig::default()).unwrap();
        let mut panel: Panel<7> = Panel::new();
        assert_eq!(host.next_byte(), Some(RESET));
        assert_eq!(host.next_byte(), None); // idle
        assert_eq!(host.next_byte(), Some(0));
        panel.press(0x33).unwrap();
        assert_eq!(host.poll_mot(panel.mot()), None);
        // MOT is seen, but the sequence goes out whole first, with the reset byte closing it.
        for _ in 1..7 {
            assert!(!host.san());
            assert_eq!(host.next_byte(), Some(0));
        }
        assert_eq!(host.next_byte(), Some(RESET));
        assert_eq!(host.stats().sequences, 1);
        assert_eq!(host.next_byte(), None);
        assert!(host.san());
        let first = panel.set_san(host.san()).unwrap();
        assert_eq!(host.receive(Ok(first)), None);
        let again = panel.tick_20ms().unwrap();
        assert_eq!(host.receive(Err(LineError::Parity)), None); // noise between: pair restarts
        assert_eq!(host.receive(Ok(again)), None);
        let third = panel.tick_20ms().unwrap();
        assert_eq!(host.receive(Ok(third)), Some(HostEvent::Key(0x33)));
        assert!(!host.san());
        assert_eq!(panel.set_san(false), None);
        // A late repeat is ignored; MOT low lets the host go on with the registers (the reset
        // byte went out before the exchange).
        assert_eq!(host.receive(Ok(0x33)), None);
        assert!(!panel.mot());
        assert_eq!(host.next_byte(), None);
        host.poll_mot(panel.mot());
        assert_eq!(host.next_byte(), None); // SÄN stays low for three polls (over 20 ms)
        host.poll_mot(panel.mot());
        assert_eq!(host.next_byte(), None);
        host.poll_mot(panel.mot());
        assert_eq!(host.next_byte(), None); // idle, then the registers
        assert_eq!(host.next_byte(), Some(0));
        assert_eq!(host.stats().keys, 1);
    }

    #[test]
    fn a_dead_panel_cannot_stop_the_displays() {
        let mut host: Host<7> = Host::new(HostConfig {
            key_timeout_polls: 6,
            mot_stuck_polls: 4,
        })
        .unwrap();
        let mut events = Vec::new();
        host.poll_mot(true);
        assert_eq!(host.next_byte(), Some(RESET));
        assert_eq!(host.next_byte(), None);
        for _ in 0..10 {
            events.extend(host.poll_mot(true)); // 6 polls of key time-out, 4 of MOT time-out
        }
        assert_eq!(events, vec![HostEvent::KeyTimedOut, HostEvent::MotStuck]);
        // The stuck MOT is ignored for `mot_stuck_polls` (4) polls: whole sequences go out.
        for _ in 0..3 {
            assert_eq!(host.poll_mot(true), None);
            assert_eq!(host.next_byte(), None); // idle after the reset byte
            assert!((0..7).all(|_| host.next_byte().is_some()));
            assert_eq!(host.next_byte(), Some(RESET));
            assert!(!host.san());
        }
        // The fourth poll: answered again (a panel holding a key is never ignored for good).
        host.poll_mot(true);
        assert_eq!(host.next_byte(), None);
        assert!(host.san());
        // Given up again, stuck again; this time MOT reads low once: answered at once.
        events.clear();
        for _ in 0..10 {
            events.extend(host.poll_mot(true));
        }
        assert_eq!(events, vec![HostEvent::KeyTimedOut, HostEvent::MotStuck]);
        assert!(!host.san());
        host.poll_mot(false);
        host.poll_mot(true);
        assert_eq!(host.next_byte(), None); // the idle byte time after the reset byte
        assert!((0..7).all(|_| host.next_byte().is_some()));
        assert_eq!(host.next_byte(), Some(RESET));
        assert_eq!(host.next_byte(), None);
        assert!(host.san());
    }

    #[test]
    fn a_full_key_queue_hands_the_key_back() {
        let mut panel: Panel<7> = Panel::new();
        for k in 0..KEY_QUEUE as u8 {
            panel.press(k).unwrap();
        }
        assert_eq!(panel.press(99), Err(PanelError::QueueFull(99)));
        assert_eq!(panel.keys_waiting(), KEY_QUEUE);
    }
}
