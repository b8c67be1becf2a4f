//! A slave board: the ring, the link protocol and the stand-alone fallback in one.

use core::fmt;

use crate::link::{DecodeError, Message, Report, decode, newer_boot};
use crate::ring::Ring;

/// How a slave is set up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SlaveConfig {
    /// The slave's address on the link.
    pub address: u8,
    /// Items per row of the pattern (≥ 1): the slave changes source only at a row boundary.
    /// With `silence_limit` and the ring's `N`, at most [`MAX_DRIFT`] (see there).
    pub row_len: u16,
    /// Steps without a frame from the master after which it counts as silent (≥ 1). Every step
    /// of an outage before that is an underrun that moves the board's counters on, so
    /// `silence_limit + row_len + N` must be at most [`MAX_DRIFT`] (32 767).
    pub silence_limit: u32,
    /// Steps a slave owed items waits without a refill before it reports again with the retry
    /// flag (≥ 1); also the period of its reports while stand-alone or saying hello.
    pub retry_after: u32,
    /// The board's boot number: the firmware adds 1 at every start (a counter kept in flash or
    /// a backup register, wrapping). The master tells a rebooted board by it and ignores every
    /// report and hello of an earlier start ([`newer_boot`](crate::link::newer_boot): the 128
    /// numbers behind the session's), so no late frame of the board before a reboot moves the
    /// new board's session. A board whose number went back or jumped (a lost counter, a random
    /// byte) is still placed again: the master names its session's number and the board takes
    /// the next one ([`Slave::boot`]), one round trip later; but until then a late frame of an
    /// earlier start may be taken for the current one. A board that starts with the same number
    /// as before is placed again too, with the same caveat.
    pub boot: u8,
}

/// The most `silence_limit + row_len + N` a [`Slave`] accepts: 32 767, the largest count the
/// master's 16-bit counter extension reads as "ahead".
///
/// While no report of the board reaches the master (a link outage), the board's `consumed`
/// count moves at most `max(2·d + silence_limit + 1, N) + row_len − 1` past the newest report
/// the master holds, for a master that grants the board at most `N` items ahead and a link whose
/// round trip (a report out, the master's answer back) takes at most `2·d` steps: `2·d` steps
/// until the master's last answer arrives, `silence_limit + 1` steps of underruns before the
/// master counts as silent (or up to the `N` items the master had granted, taken from the
/// ring), and the rest of the row cut short (`row_len − 1` [`Source::Fallback`] items); then the
/// board is stand-alone and its count stands still. With `silence_limit + row_len + N ≤ 32 767`
/// and a ring of at least `4·d` slots (the relink bound's condition) that is at most 32 767, so
/// the master takes the board's first report after any outage, however long.
pub const MAX_DRIFT: u64 = 0x7FFF;

/// Why a [`SlaveConfig`] was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SlaveConfigError {
    /// `row_len` = 0.
    ZeroRow,
    /// `silence_limit` = 0: every step would count as silence.
    ZeroSilenceLimit,
    /// `retry_after` = 0: every step would be a retry.
    ZeroRetry,
    /// `silence_limit + row_len + N` exceeds [`MAX_DRIFT`]: during an outage the board's
    /// 16-bit `consumed` count could run half its range or more past the newest report the
    /// master holds, and the master would take every later report for an old one (the board
    /// would stay stand-alone for good). The fields: `silence_limit`, `row_len`, `N`.
    Drift {
        /// `silence_limit` as given.
        silence_limit: u32,
        /// `row_len` as given.
        row_len: u16,
        /// The ring's slots.
        capacity: usize,
    },
    /// The ring has 0 slots or more than 32 767 (the 16-bit counters need half their range).
    Capacity(usize),
}

impl fmt::Display for SlaveConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::ZeroRow => write!(f, "row_len must be at least 1 item"),
            Self::ZeroSilenceLimit => write!(f, "silence_limit must be at least 1 step"),
            Self::ZeroRetry => write!(f, "retry_after must be at least 1 step"),
            Self::Capacity(n) => write!(f, "ring must have 1..=32767 slots, got {n}"),
            Self::Drift {
                silence_limit,
                row_len,
                capacity,
            } => write!(
                f,
                "silence_limit + row_len + ring slots must be at most {MAX_DRIFT}, got \
                 {silence_limit} + {row_len} + {capacity}"
            ),
        }
    }
}

impl core::error::Error for SlaveConfigError {}

/// Why a frame was not taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FrameError {
    /// The frame is damaged or malformed.
    Decode(DecodeError),
    /// A refill for another slave (a shared line).
    NotForMe(u8),
    /// A report: slaves take refills only.
    NotARefill,
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Decode(e) => write!(f, "bad frame: {e}"),
            Self::NotForMe(a) => write!(f, "refill addressed to slave {a}"),
            Self::NotARefill => write!(f, "a report, not a refill"),
        }
    }
}

impl core::error::Error for FrameError {}

/// Where the slave gets its items.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Mode {
    /// From the master, through the ring.
    Linked,
    /// From the local pattern (the source's ROM or tape): the master was silent too long, or
    /// has not yet placed this new slave in its stream.
    StandAlone,
}

/// Where one output item came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Source {
    /// The master's stream, on time.
    Master,
    /// The local pattern, in stand-alone mode.
    Local,
    /// The local pattern standing in for the master's items from the needle where the ring ran
    /// dry while the master was silent too long to the end of that row (the row the master's
    /// failure cut short; the master's items for it are skipped, so the rows stay aligned).
    Fallback,
    /// The local pattern standing in for a master item that was late although the master was
    /// not silent: an **underrun**. The master's item is skipped when it comes, so the rows
    /// stay aligned.
    Underrun,
}

/// One step's output.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Output {
    /// The item for the machine.
    pub item: u8,
    /// Where it came from.
    pub source: Source,
    /// The row (counting from 0 at start, wrapping) and the position in it.
    pub row: u32,
    /// Position in the row.
    pub col: u16,
}

/// A slave's statistics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SlaveStats {
    /// Master items that were late while the master was not silent.
    pub underruns: u32,
    /// Items taken from the local pattern because the master had fallen silent mid-row.
    pub fallbacks: u32,
    /// Fewest items left in the ring after a step in linked mode (0 after an underrun).
    pub least_slack: u16,
    /// Rows made in stand-alone mode.
    pub standalone_rows: u32,
    /// Switches to stand-alone mode.
    pub standalone_entries: u32,
    /// Items that arrived again and were dropped.
    pub duplicates: u32,
    /// Refills that started beyond the next expected item (an earlier one was lost).
    pub gaps: u32,
    /// Items dropped because the ring was full (a master that sent more than owed).
    pub overflows: u32,
    /// Frames refused as damaged or malformed.
    pub bad_frames: u32,
    /// Reports sent with the retry flag.
    pub retries: u32,
}

/// A slave board of source 001: its ring, the cumulative-counter protocol, and the stand-alone
/// fallback.
///
/// * [`on_frame`](Self::on_frame) takes a frame from the link (a refill, or a keep-alive);
/// * [`step`](Self::step) hands the machine its next item — from the ring, or, when the master
///   has been silent longer than the limit, from a local pattern the caller supplies;
/// * [`poll_report`](Self::poll_report) says when to send a request: at once whenever the ring
///   has a free slot and something was consumed since the last report (the source's
///   "RP ≠ SP"), again with the retry flag after `retry_after` steps without a refill, and
///   every `retry_after` steps while stand-alone, so the master can answer.
///
/// **Starting (and restarting).** A new slave has no place in the master's stream: it runs
/// stand-alone and its reports say **hello** (at once, then every `retry_after` steps) until a
/// sync refill for its boot number arrives, whose first index becomes its counters. The master
/// answers a hello where the board before it stopped (see [`Master`](crate::Master)), so a
/// board that was power-cycled resumes the stream there. A slave that receives a sync refill
/// for another boot number (a session offer: the master serves another start of this board)
/// says hello again, keeping its ring and counters; if that number is a later start than its
/// own, it first takes the number after it ([`Slave::boot`]).
///
/// **Stand-alone and back.** At a row boundary, a linked slave whose master is silent and whose
/// ring cannot cover the next row switches to its local pattern (`min(row_len, N)` items cover a
/// row: with a ring shorter than a row, a full ring). A stand-alone slave switches back at the
/// first row boundary at which it has heard the master (any valid frame for it, a keep-alive
/// too) since it went stand-alone and the ring covers the next row. Once the master answers
/// again, with frames delayed by at most `d` steps each way and none lost, the slave is linked
/// again within `retry_after + 4·d + row_len + 1` steps, for every configuration
/// [`Slave::new`] accepts (its next report, the answer — twice, when the outage ate refills the
/// master had counted as sent and the board must ask again for the gap — and the rest of the
/// row), given a ring of at least `4·d` slots (a ring shorter than the link's round trip underruns, outage or not). The master's
/// stream pauses meanwhile, so the rows around a fault are whole rows of one source or the
/// other, never a mixture. The one exception: if the ring runs dry mid-row after the master has
/// gone silent, the rest of that row comes from the local pattern ([`Source::Fallback`]) — there
/// is nothing else to give the machine.
///
/// ```
/// use regler_ring_transfer::{link, Mode, Refill, Slave, SlaveConfig};
///
/// let config = SlaveConfig { address: 3, row_len: 4, silence_limit: 6, retry_after: 4, boot: 1 };
/// let mut slave: Slave<8> = Slave::new(config)?;
/// let rom = |_row: u32, col: u16| 0xF0 | (col as u8); // the local pattern
///
/// // The new board says hello; the master's answer places it in the stream and fills the ring.
/// let hello = slave.poll_report().ok_or("a new board says hello")?;
/// assert!(hello.hello);
/// let mut frame = [0; link::MAX_FRAME];
/// let items = [1, 2, 3, 4, 5, 6, 7, 8];
/// let sync = Refill { slave: 3, first: 0, items: &items, boot: 1, sync: true };
/// let n = sync.encode(&mut frame)?;
/// assert_eq!(slave.on_frame(&frame[..n]), Ok(8));
/// assert_eq!(slave.step(rom).item, 1);
/// let report = slave.poll_report().ok_or("one consumed: a report is due")?;
/// assert_eq!((report.consumed, report.received), (1, 8));
///
/// // The master falls silent; the ring covers two whole rows, then the slave runs stand-alone.
/// let items: Vec<u8> = (0..12).map(|_| slave.step(rom).item).collect();
/// assert_eq!(items, [2, 3, 4, 5, 6, 7, 8, 0xF0, 0xF1, 0xF2, 0xF3, 0xF0]);
/// assert_eq!(slave.mode(), Mode::StandAlone);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct Slave<const N: usize> {
    config: SlaveConfig,
    ring: Ring<u8, N>,
    consumed: u16,
    received: u16,
    mode: Mode,
    row: u32,
    col: u16,
    silent: u32,
    since_report: u32,
    reported: Option<u16>,
    gap: bool,
    cut_short: bool,
    /// The counters are stream positions (a sync refill for this boot has arrived).
    placed: bool,
    /// The master's session is this boot's (no hello needed).
    synced: bool,
    /// A hello has been sent since the slave last lost its session.
    hello_sent: bool,
    /// A valid frame for this slave arrived since it last went stand-alone.
    heard: bool,
    /// The boot number in its reports: `config.boot`, or the one after the master's session
    /// if the master named a later start.
    boot: u8,
    stats: SlaveStats,
}

impl<const N: usize> Slave<N> {
    /// A slave with an empty ring, stand-alone, saying hello until the master places it in the
    /// stream.
    ///
    /// # Errors
    /// The [`SlaveConfigError`] naming the bad field.
    pub const fn new(config: SlaveConfig) -> Result<Self, SlaveConfigError> {
        if config.row_len == 0 {
            return Err(SlaveConfigError::ZeroRow);
        }
        if config.silence_limit == 0 {
            return Err(SlaveConfigError::ZeroSilenceLimit);
        }
        if config.retry_after == 0 {
            return Err(SlaveConfigError::ZeroRetry);
        }
        if N == 0 || N > 0x7FFF {
            return Err(SlaveConfigError::Capacity(N));
        }
        #[allow(clippy::cast_possible_truncation, reason = "N <= 0x7FFF was checked")]
        let sum = (config.silence_limit as u64)
            .saturating_add(config.row_len as u64)
            .saturating_add(N as u64);
        if sum > MAX_DRIFT {
            return Err(SlaveConfigError::Drift {
                silence_limit: config.silence_limit,
                row_len: config.row_len,
                capacity: N,
            });
        }
        Ok(Self {
            config,
            ring: Ring::new(),
            consumed: 0,
            received: 0,
            mode: Mode::StandAlone,
            row: 0,
            col: 0,
            silent: 0,
            since_report: 0,
            reported: None,
            gap: false,
            cut_short: false,
            placed: false,
            synced: false,
            hello_sent: false,
            heard: false,
            boot: config.boot,
            stats: SlaveStats {
                underruns: 0,
                fallbacks: 0,
                #[allow(clippy::cast_possible_truncation, reason = "N <= 0x7FFF was checked")]
                least_slack: N as u16,
                standalone_rows: 0,
                standalone_entries: 0,
                duplicates: 0,
                gaps: 0,
                overflows: 0,
                bad_frames: 0,
                retries: 0,
            },
        })
    }

    /// Takes one frame from the link; returns how many items went into the ring. Any valid
    /// frame for this slave — a keep-alive too — tells it the master is there.
    ///
    /// Before a sync refill for this slave's boot number has placed it in the stream, only
    /// such a refill (with items) is taken; a sync refill for another boot number makes a slave
    /// the master had synced say hello again, and one of a later start
    /// ([`newer_boot`](crate::link::newer_boot)) makes it take the boot number after that one.
    ///
    /// Items are taken only in stream order: one whose index is behind the next expected is a
    /// duplicate and dropped; one beyond it means something was lost — it and the rest of the
    /// frame are dropped and the next report asks for a resend.
    ///
    /// # Errors
    /// [`FrameError`] for a damaged frame, a refill for another slave, or a report. Nothing is
    /// changed but the count of bad frames.
    pub fn on_frame(&mut self, bytes: &[u8]) -> Result<usize, FrameError> {
        let refill = match decode(bytes) {
            Ok(Message::Refill(refill)) => refill,
            Ok(Message::Report(_)) => return Err(FrameError::NotARefill),
            Err(e) => {
                self.stats.bad_frames = self.stats.bad_frames.saturating_add(1);
                return Err(FrameError::Decode(e));
            }
        };
        if refill.slave != self.config.address {
            return Err(FrameError::NotForMe(refill.slave));
        }
        self.silent = 0;
        self.heard = true;
        if refill.sync {
            if refill.boot == self.boot {
                // A session offer (no items) never places a board: only the sync grant that
                // starts the session does.
                if !self.placed && !refill.items.is_empty() {
                    self.placed = true;
                    self.consumed = refill.first;
                    self.received = refill.first;
                    self.reported = None;
                }
                self.synced = self.placed;
            } else {
                if newer_boot(refill.boot, self.boot) {
                    // The master serves a later start than this one: this board's boot number
                    // went back (a counter lost, a random byte). Take the next one after it.
                    self.boot = refill.boot.wrapping_add(1);
                    self.hello_sent = false;
                }
                if self.synced {
                    // The master serves another start of this board: say hello again.
                    self.synced = false;
                    self.hello_sent = false;
                }
            }
        }
        if !self.placed {
            return Ok(0);
        }
        let mut taken = 0usize;
        let mut index = refill.first;
        for &item in refill.items {
            let ahead = index.wrapping_sub(self.received);
            if ahead == 0 {
                if self.ring.receive(item).is_err() {
                    self.stats.overflows = self.stats.overflows.saturating_add(1);
                    break;
                }
                self.received = self.received.wrapping_add(1);
                taken = taken.saturating_add(1);
            } else if ahead >= 0x8000 {
                self.stats.duplicates = self.stats.duplicates.saturating_add(1);
            } else {
                self.stats.gaps = self.stats.gaps.saturating_add(1);
                self.gap = true;
                break;
            }
            index = index.wrapping_add(1);
        }
        if taken > 0 && self.synced {
            self.since_report = 0;
        }
        Ok(taken)
    }

    fn master_silent(&self) -> bool {
        self.silent > self.config.silence_limit
    }

    fn ring_covers_a_row(&self) -> bool {
        self.ring.len() >= usize::from(self.config.row_len).min(N)
    }

    /// The machine's next item. `local(row, col)` is the local pattern, asked only when the
    /// item does not come from the master.
    pub fn step(&mut self, local: impl FnOnce(u32, u16) -> u8) -> Output {
        if self.col == 0 {
            match self.mode {
                Mode::Linked if self.master_silent() && !self.ring_covers_a_row() => {
                    self.mode = Mode::StandAlone;
                    self.heard = false;
                    self.stats.standalone_entries = self.stats.standalone_entries.saturating_add(1);
                }
                // "Heard since it went stand-alone", not "heard within the silence limit": the
                // master's answers to the periodic reports may come anywhere in a row.
                Mode::StandAlone if self.placed && self.heard && self.ring_covers_a_row() => {
                    self.mode = Mode::Linked;
                }
                _ => {}
            }
        }
        let (row, col) = (self.row, self.col);
        let (item, source) = match self.mode {
            Mode::StandAlone => (local(row, col), Source::Local),
            Mode::Linked if self.cut_short => {
                // The rest of a row the master's failure cut short: local items; the master's
                // items for these needles are skipped (taken from the ring if they are there).
                self.consumed = self.consumed.wrapping_add(1);
                if self.ring.next().is_none() {
                    self.received = self.received.wrapping_add(1);
                }
                self.stats.fallbacks = self.stats.fallbacks.saturating_add(1);
                (local(row, col), Source::Fallback)
            }
            Mode::Linked => {
                if let Some(item) = self.ring.next() {
                    self.consumed = self.consumed.wrapping_add(1);
                    let slack = u16::try_from(self.ring.len()).unwrap_or(u16::MAX);
                    self.stats.least_slack = self.stats.least_slack.min(slack);
                    (item, Source::Master)
                } else {
                    // Nothing to give: skip the master's item (taken as received and consumed,
                    // so it is dropped as a duplicate when it comes) and keep the row aligned.
                    self.consumed = self.consumed.wrapping_add(1);
                    self.received = self.received.wrapping_add(1);
                    let source = if self.master_silent() {
                        self.stats.fallbacks = self.stats.fallbacks.saturating_add(1);
                        self.cut_short = true;
                        Source::Fallback
                    } else {
                        self.stats.underruns = self.stats.underruns.saturating_add(1);
                        self.stats.least_slack = 0;
                        Source::Underrun
                    };
                    (local(row, col), source)
                }
            }
        };
        self.col = self.col.saturating_add(1);
        if self.col >= self.config.row_len {
            self.col = 0;
            self.cut_short = false;
            self.row = self.row.wrapping_add(1);
            if self.mode == Mode::StandAlone {
                self.stats.standalone_rows = self.stats.standalone_rows.saturating_add(1);
            }
        }
        self.silent = self.silent.saturating_add(1);
        self.since_report = self.since_report.saturating_add(1);
        Output {
            item,
            source,
            row,
            col,
        }
    }

    /// A report to send now, if one is due (see the type's docs).
    pub fn poll_report(&mut self) -> Option<Report> {
        if !self.synced {
            if self.hello_sent && self.since_report < self.config.retry_after {
                return None;
            }
            self.hello_sent = true;
            self.since_report = 0;
            return Some(self.report(false));
        }
        let owed = self.ring.requests() > 0;
        let fresh = self.reported != Some(self.consumed);
        let waited = self.since_report >= self.config.retry_after;
        let standalone = self.mode == Mode::StandAlone;
        let retry = self.gap || (owed && waited && !fresh);
        if !(retry || (owed && fresh) || (standalone && waited)) {
            return None;
        }
        if retry {
            self.stats.retries = self.stats.retries.saturating_add(1);
        }
        self.gap = false;
        self.reported = Some(self.consumed);
        self.since_report = 0;
        Some(self.report(retry))
    }

    /// The report this slave would send now (for a status request, the source's keys 1–8).
    /// Its counters are stream positions once the slave is placed in the stream.
    #[must_use]
    pub fn report(&self, retry: bool) -> Report {
        Report {
            slave: self.config.address,
            consumed: self.consumed,
            received: self.received,
            standalone: self.mode == Mode::StandAlone,
            retry,
            boot: self.boot,
            hello: !self.synced,
        }
    }

    /// The boot number this slave's reports carry: [`SlaveConfig::boot`], unless a sync refill
    /// named a later start ([`newer_boot`](crate::link::newer_boot)), in which case the number
    /// after that one (the firmware may store it as the last boot number used).
    #[must_use]
    pub fn boot(&self) -> u8 {
        self.boot
    }

    /// `true` once a sync refill has placed this slave in the master's stream.
    #[must_use]
    pub fn placed(&self) -> bool {
        self.placed
    }

    /// Linked or stand-alone.
    #[must_use]
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The row being made and the position in it.
    #[must_use]
    pub fn position(&self) -> (u32, u16) {
        (self.row, self.col)
    }

    /// Items in the ring.
    #[must_use]
    pub fn slack(&self) -> usize {
        self.ring.len()
    }

    /// Refills owed (free slots).
    #[must_use]
    pub fn requests(&self) -> usize {
        self.ring.requests()
    }

    /// Statistics.
    #[must_use]
    pub fn stats(&self) -> SlaveStats {
        self.stats
    }

    /// The configuration.
    #[must_use]
    pub fn config(&self) -> SlaveConfig {
        self.config
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::{MAX_FRAME, Refill};

    const CONFIG: SlaveConfig = SlaveConfig {
        address: 1,
        row_len: 4,
        silence_limit: 6,
        retry_after: 3,
        boot: 9,
    };

    fn refill(slave: &mut Slave<8>, first: u16, items: &[u8]) -> Result<usize, FrameError> {
        let mut buf = [0; MAX_FRAME];
        let n = Refill {
            slave: 1,
            first,
            items,
            boot: 9,
            sync: !slave.placed(),
        }
        .encode(&mut buf)
        .unwrap();
        slave.on_frame(&buf[..n])
    }

    #[test]
    fn config_is_checked() {
        assert_eq!(
            Slave::<8>::new(SlaveConfig {
                row_len: 0,
                ..CONFIG
            })
            .err(),
            Some(SlaveConfigError::ZeroRow)
        );
        assert_eq!(
            Slave::<8>::new(SlaveConfig {
                silence_limit: 0,
                ..CONFIG
            })
            .err(),
            Some(SlaveConfigError::ZeroSilenceLimit)
        );
        assert_eq!(
            Slave::<8>::new(SlaveConfig {
                retry_after: 0,
                ..CONFIG
            })
            .err(),
            Some(SlaveConfigError::ZeroRetry)
        );
        assert_eq!(
            Slave::<40_000>::new(CONFIG).err(),
            Some(SlaveConfigError::Capacity(40_000))
        );
    }

    #[test]
    fn duplicates_and_gaps() {
        let mut s: Slave<8> = Slave::new(CONFIG).unwrap();
        assert_eq!(refill(&mut s, 0, &[0, 1, 2]), Ok(3));
        assert_eq!(refill(&mut s, 1, &[1, 2, 3]), Ok(1)); // 1, 2 again; 3 new
        assert_eq!(refill(&mut s, 6, &[6]), Ok(0)); // 4, 5 lost
        assert_eq!(s.stats().duplicates, 2);
        assert_eq!(s.stats().gaps, 1);
        let r = s.poll_report().unwrap();
        assert!(r.retry);
        assert_eq!(r.received, 4);
        assert_eq!(refill(&mut s, 4, &[4, 5, 6, 7, 8, 9]), Ok(4)); // the ring holds 8
        assert_eq!(s.stats().overflows, 1);
        let items: Vec<u8> = (0..8).map(|_| s.step(|_, _| 0xEE).item).collect();
        assert_eq!(items, [0, 1, 2, 3, 4, 5, 6, 7]);
    }

    #[test]
    fn an_underrun_skips_the_late_item() {
        let mut s: Slave<8> = Slave::new(CONFIG).unwrap();
        refill(&mut s, 0, &[10, 11, 12, 13]).unwrap();
        for item in 10..14 {
            assert_eq!(
                s.step(|_, _| 0xEE),
                Output {
                    item,
                    source: Source::Master,
                    row: 0,
                    col: item as u16 - 10
                }
            );
        }
        let out = s.step(|_, _| 0xEE);
        assert_eq!((out.item, out.source), (0xEE, Source::Underrun));
        // Item 4 comes late: dropped; item 5 is used.
        assert_eq!(refill(&mut s, 4, &[14, 15]), Ok(1));
        assert_eq!(s.step(|_, _| 0xEE).item, 15);
        assert_eq!(s.stats().underruns, 1);
    }

    #[test]
    fn other_frames_are_refused_without_effect() {
        let mut s: Slave<8> = Slave::new(CONFIG).unwrap();
        let mut buf = [0; MAX_FRAME];
        let n = Refill {
            slave: 2,
            first: 0,
            items: &[1],
            boot: 9,
            sync: true,
        }
        .encode(&mut buf)
        .unwrap();
        assert_eq!(s.on_frame(&buf[..n]), Err(FrameError::NotForMe(2)));
        let n = s.report(false).encode(&mut buf).unwrap();
        assert_eq!(s.on_frame(&buf[..n]), Err(FrameError::NotARefill));
        assert!(matches!(s.on_frame(&[0x5A, 1]), Err(FrameError::Decode(_))));
        assert_eq!(s.slack(), 0);
        assert_eq!(s.stats().bad_frames, 1);
        assert!(!s.placed());
    }

    #[test]
    fn a_new_slave_says_hello_until_a_sync_for_its_boot_places_it() {
        let mut s: Slave<8> = Slave::new(CONFIG).unwrap();
        let hello = s.poll_report().unwrap();
        assert!(hello.hello && hello.standalone);
        assert_eq!(hello.boot, 9);
        assert_eq!(
            s.poll_report(),
            None,
            "the next hello after retry_after steps"
        );
        let mut buf = [0; MAX_FRAME];
        // A plain refill, or a sync for another boot, does not place it.
        for (boot, sync) in [(9, false), (8, true)] {
            let n = Refill {
                slave: 1,
                first: 100,
                items: &[1, 2, 3, 4],
                boot,
                sync,
            }
            .encode(&mut buf)
            .unwrap();
            assert_eq!(s.on_frame(&buf[..n]), Ok(0));
            assert!(!s.placed());
        }
        for _ in 0..3 {
            assert_eq!(s.step(|_, _| 0xEE).source, Source::Local);
        }
        assert!(s.poll_report().unwrap().hello);
        let n = Refill {
            slave: 1,
            first: 100,
            items: &[1, 2, 3, 4],
            boot: 9,
            sync: true,
        }
        .encode(&mut buf)
        .unwrap();
        assert_eq!(s.on_frame(&buf[..n]), Ok(4));
        assert!(s.placed());
        // The rest of the local row, then the master's items from index 100.
        assert_eq!(s.step(|_, _| 0xEE).source, Source::Local);
        assert_eq!(
            s.step(|_, _| 0xEE),
            Output {
                item: 1,
                source: Source::Master,
                row: 1,
                col: 0
            }
        );
        let r = s.poll_report().unwrap();
        assert!(!r.hello);
        assert_eq!((r.consumed, r.received), (101, 104));
        // A sync for another boot: hello again, ring and counters kept.
        let n = Refill {
            slave: 1,
            first: 0,
            items: &[],
            boot: 7,
            sync: true,
        }
        .encode(&mut buf)
        .unwrap();
        assert_eq!(s.on_frame(&buf[..n]), Ok(0));
        let r = s.poll_report().unwrap();
        assert!(r.hello);
        assert_eq!((r.consumed, r.received, s.slack()), (101, 104, 3));
    }

    #[test]
    fn stand_alone_reports_and_comes_back_at_a_row_boundary() {
        let mut s: Slave<8> = Slave::new(CONFIG).unwrap();
        let _ = s.poll_report();
        refill(&mut s, 0, &[0, 1, 2, 3, 4, 5, 6, 7]).unwrap();
        let mut sources = Vec::new();
        for _ in 0..20 {
            sources.push(s.step(|_, _| 0xEE).source);
            let _ = s.poll_report();
        }
        assert_eq!(s.mode(), Mode::StandAlone);
        assert!(sources[..8].iter().all(|&x| x == Source::Master));
        assert!(sources[8..].iter().all(|&x| x == Source::Local));
        // The stand-alone slave keeps reporting so that a returning master can answer.
        let mut hail = None;
        for _ in 0..3 {
            s.step(|_, _| 0);
            hail = hail.or(s.poll_report());
        }
        assert!(hail.unwrap().standalone);
        // The master is back mid-row: the rest of the row stays local.
        let (_, col) = s.position();
        assert_ne!(col, 0);
        refill(&mut s, 8, &[8, 9, 10, 11, 12, 13, 14, 15]).unwrap();
        for _ in col..4 {
            assert_eq!(s.step(|_, _| 0xEE).source, Source::Local);
        }
        assert_eq!(s.position().1, 0, "the row ended");
        let next: Vec<u8> = (0..4).map(|_| s.step(|_, _| 0xEE).item).collect();
        assert_eq!(next, [8, 9, 10, 11]);
        assert_eq!(s.mode(), Mode::Linked);
    }

    /// A report at once when the ring has a free slot and something was consumed since the
    /// last one; none while the ring is full, none again before the next consumption.
    #[test]
    fn a_report_when_a_slot_is_free_and_something_was_consumed() {
        let mut s: Slave<8> = Slave::new(CONFIG).unwrap();
        assert!(s.poll_report().unwrap().hello);
        assert_eq!(refill(&mut s, 0, &[0, 1, 2, 3, 4, 5, 6, 7]), Ok(8));
        assert_eq!(s.poll_report(), None, "a full ring asks for nothing");
        assert_eq!((s.slack(), s.requests()), (8, 0));
        assert_eq!(s.step(|_, _| 0xEE).item, 0);
        assert_eq!((s.slack(), s.requests()), (7, 1), "one free slot");
        let r = s.poll_report().unwrap();
        assert_eq!((r.consumed, r.received, r.retry), (1, 8, false));
        assert_eq!(s.poll_report(), None, "nothing consumed since");
        s.step(|_, _| 0xEE);
        assert_eq!(s.poll_report().map(|r| r.consumed), Some(2));
    }

    /// A refill that brings items restarts the count of steps to the next report (the board
    /// heard from the master); one that brings none (a keep-alive, duplicates) does not.
    #[test]
    fn only_a_refill_that_brings_items_restarts_the_report_countdown() {
        // Stand-alone, reports every `retry_after` = 3 steps when polled every step.
        let stand_alone = || {
            let mut s: Slave<8> = Slave::new(CONFIG).unwrap();
            let _ = s.poll_report();
            refill(&mut s, 0, &[0, 1, 2, 3, 4, 5, 6, 7]).unwrap();
            for _ in 0..20 {
                s.step(|_, _| 0xEE);
                let _ = s.poll_report();
            }
            assert_eq!(s.mode(), Mode::StandAlone);
            // Just after a report, at the start of a row.
            // (Reports every 3 steps, rows of 4: within 12 steps.)
            let mut steps = 0;
            while !(s.position().1 == 0 && s.poll_report().is_some()) {
                assert!(steps < 12, "no report at the start of a row");
                s.step(|_, _| 0xEE);
                steps += 1;
            }
            s
        };
        // Steps (polled after each) until the next report.
        let next_report = |s: &mut Slave<8>| {
            (1..=10)
                .find(|_| {
                    s.step(|_, _| 0xEE);
                    s.poll_report().is_some()
                })
                .unwrap()
        };
        let mut s = stand_alone();
        assert_eq!(next_report(&mut s), 3, "undisturbed");
        // One step, then a refill with items: three more steps to the next report.
        let mut s = stand_alone();
        s.step(|_, _| 0xEE);
        assert!(s.poll_report().is_none());
        assert_eq!(refill(&mut s, 8, &[8, 9, 10]), Ok(3));
        assert_eq!(next_report(&mut s), 3, "after a refill with items");
        // One step, then a refill of items already held: the countdown goes on.
        let mut s = stand_alone();
        s.step(|_, _| 0xEE);
        assert!(s.poll_report().is_none());
        assert_eq!(refill(&mut s, 0, &[0, 1, 2]), Ok(0));
        assert_eq!(next_report(&mut s), 2, "after a refill of duplicates");
        // A refill that fills the ring mid-row: the board stays stand-alone to the row's end,
        // asks for nothing (no free slot, nothing consumed), and still reports after
        // `retry_after` steps, as stand-alone, so the master hears it.
        let mut s = stand_alone();
        s.step(|_, _| 0xEE);
        assert!(s.poll_report().is_none());
        assert_eq!(refill(&mut s, 8, &[8, 9, 10, 11, 12, 13, 14, 15]), Ok(8));
        assert_eq!(next_report(&mut s), 3, "stand-alone with a full ring");
        assert_eq!(s.mode(), Mode::StandAlone);
    }

    fn sync(s: &mut Slave<8>, first: u16, items: &[u8], boot: u8) -> Result<usize, FrameError> {
        let mut buf = [0; MAX_FRAME];
        let n = Refill {
            slave: 1,
            first,
            items,
            boot,
            sync: true,
        }
        .encode(&mut buf)
        .unwrap();
        s.on_frame(&buf[..n])
    }

    /// A session offer (a sync of no items) never places a board, of its own boot or another.
    #[test]
    fn an_offer_never_places() {
        // Under Miri the ends and the middle of the boot numbers.
        let boots: Vec<u8> = if cfg!(miri) {
            vec![0, 1, 9, 127, 128, 255]
        } else {
            (0..=255).collect()
        };
        for boot in boots {
            let mut s: Slave<8> = Slave::new(CONFIG).unwrap();
            assert!(s.poll_report().unwrap().hello);
            assert_eq!(sync(&mut s, 100, &[], boot), Ok(0));
            assert!(!s.placed());
            for _ in 0..3 {
                s.step(|_, _| 0xEE);
            }
            assert!(s.poll_report().unwrap().hello, "still saying hello");
        }
    }

    /// Every boot number an offer can name: a placed board says hello again for any other
    /// number; for a later start than its own (1..=127 ahead) it takes the number after it,
    /// which the master then takes as a later start than its session.
    #[test]
    fn an_offer_of_another_start_makes_the_board_say_hello() {
        // Under Miri the board's own number 9, one behind and one ahead, the last later start
        // (127 ahead), the first earlier one (128 ahead) and the ends.
        let offers: Vec<u8> = if cfg!(miri) {
            vec![0, 8, 9, 10, 136, 137, 255]
        } else {
            (0..=255).collect()
        };
        for offered in offers {
            let mut s: Slave<8> = Slave::new(CONFIG).unwrap();
            let _ = s.poll_report();
            assert_eq!(sync(&mut s, 100, &[1, 2, 3, 4], 9), Ok(4));
            s.step(|_, _| 0xEE);
            assert!(!s.poll_report().unwrap().hello);
            assert_eq!(sync(&mut s, 0, &[], offered), Ok(0));
            let r = s.poll_report();
            if offered == 9 {
                assert!(r.is_none_or(|r| !r.hello));
                continue;
            }
            let r = r.unwrap();
            assert!(r.hello, "offer {offered}");
            assert_eq!((r.consumed, r.received, s.slack()), (101, 104, 3));
            let later = crate::link::newer_boot(offered, 9);
            assert_eq!(r.boot, if later { offered.wrapping_add(1) } else { 9 });
            assert!(crate::link::newer_boot(r.boot, offered) || !later);
            assert_eq!(s.boot(), r.boot);
            // The master's answer for the board's number places nothing anew: the ring and
            // counters stay, only the missing items are taken.
            assert_eq!(sync(&mut s, 101, &[2, 3, 4, 5], r.boot), Ok(1));
            assert!(!s.report(false).hello, "synced again");
        }
    }
}
