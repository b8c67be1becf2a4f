//! The machine side: each knitting machine's board (the Z-80 single-board computer) with its
//! `regler_ring_transfer::Slave` ring, knitting one byte per needle and recording the fabric
//! row by row: from the master's stream, from its ROM (stand-alone), or patched.

use regler_ring_transfer::{Mode, Report, Slave, SlaveConfig, Source};
use serde::Serialize;

use super::plant::rom_pattern;
use super::{Config, RING};

/// The boot number of machine `machine` at its start number `start` in the run seeded `seed`:
/// a hash of seed and machine plus the start count, so two consecutive starts of a machine
/// always differ (a board must never start with the previous start's number: a late sync of
/// that start could place it behind the master's stream, ignored for good).
#[must_use]
pub fn boot_number(seed: u64, machine: usize, start: u32) -> u8 {
    let mut x = seed ^ (machine as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^= x >> 31;
    x.to_le_bytes()[0].wrapping_add(start.to_le_bytes()[0])
}

/// A board's mode as the operator reads it: `linked` (knitting the master's stream) or
/// `stand-alone` (its ROM pattern).
#[must_use]
pub fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::Linked => "linked",
        Mode::StandAlone => "stand-alone",
    }
}

/// What a knitted row was made from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum RowSource {
    /// Stream row `n` from the master, whole.
    Master(u64),
    /// The board's ROM pattern (stand-alone).
    Local,
    /// A row with items that were not the master's (an underrun or a fallback).
    Patched,
}

/// One knitted row.
#[derive(Clone, Debug)]
pub struct Row {
    /// Source of the row.
    pub source: RowSource,
    /// Colours, with bit 7 set for a needle that did not get the master's item.
    pub needles: Vec<u8>,
}

/// The machine side: a board with its slave and the fabric it knitted.
#[derive(Debug)]
pub struct Board {
    /// Index (0-based; the operator's keys number them from 1).
    pub index: usize,
    /// Revolutions per minute.
    pub rpm: u32,
    /// Nanoseconds per needle.
    pub t0_ns: u64,
    slave: Slave<RING>,
    needles: u16,
    stream_index: u64,
    /// Rows knitted.
    pub rows: Vec<Row>,
    current: Vec<u8>,
    current_stream_row: Option<u64>,
    current_patched: bool,
    current_local: bool,
    /// Master items that were not the right byte for their stream position (must stay 0).
    pub wrong_items: u64,
    /// Master rows that were not the next stream row (must stay 0).
    pub rows_out_of_order: u64,
    next_stream_row: u64,
    /// Needles knitted in stand-alone mode.
    pub standalone_needles: u64,
}

impl Board {
    /// A board at `rpm` with `needles` needles.
    ///
    /// # Errors
    /// The slave's configuration error, as text.
    pub fn new(index: usize, rpm: u32, config: &Config) -> Result<Self, String> {
        let slave = Slave::new(SlaveConfig {
            address: u8::try_from(index).map_err(|_| "too many machines")?,
            row_len: config.needles,
            silence_limit: config.silence_needles,
            retry_after: 16,
            boot: boot_number(config.seed, index, config.start),
        })
        .map_err(|e| e.to_string())?;
        Ok(Self {
            index,
            rpm,
            t0_ns: 60_000_000_000 / (u64::from(rpm) * u64::from(config.needles)),
            slave,
            needles: config.needles,
            stream_index: 0,
            rows: Vec::new(),
            current: Vec::new(),
            current_stream_row: None,
            current_patched: false,
            current_local: false,
            wrong_items: 0,
            rows_out_of_order: 0,
            next_stream_row: 0,
            standalone_needles: 0,
        })
    }

    /// A frame from the link.
    pub fn frame(&mut self, bytes: &[u8]) {
        let _ = self.slave.on_frame(bytes);
    }

    /// One needle; `expected(stream_index)` is the master's byte there (for the check).
    /// Returns a report to send, if one is due.
    pub fn needle(&mut self, expected: impl FnOnce(u64) -> u8) -> Option<Report> {
        let out = self.slave.step(rom_pattern);
        if out.col == 0 {
            self.current.clear();
            self.current_stream_row = None;
            self.current_patched = false;
            self.current_local = false;
        }
        let mut colour = out.item & 0x03;
        match out.source {
            Source::Master => {
                if out.item != expected(self.stream_index) {
                    self.wrong_items += 1;
                }
                if out.col == 0 {
                    self.current_stream_row = Some(self.stream_index / u64::from(self.needles));
                }
                self.stream_index += 1;
            }
            Source::Underrun | Source::Fallback => {
                colour |= 0x80;
                self.current_patched = true;
                self.stream_index += 1;
            }
            Source::Local => {
                self.current_local = true;
                self.standalone_needles += 1;
            }
        }
        self.current.push(colour);
        if usize::from(out.col) + 1 == usize::from(self.needles) {
            let source = if self.current_local {
                RowSource::Local
            } else if self.current_patched {
                RowSource::Patched
            } else {
                RowSource::Master(self.current_stream_row.unwrap_or(u64::MAX))
            };
            if let RowSource::Master(n) = source {
                if n != self.next_stream_row {
                    self.rows_out_of_order += 1;
                }
                self.next_stream_row = n + 1;
            } else if source == RowSource::Patched {
                self.next_stream_row = self.stream_index.div_ceil(u64::from(self.needles));
            }
            self.rows.push(Row {
                source,
                needles: std::mem::take(&mut self.current),
            });
        }
        self.slave.poll_report()
    }

    /// The board's first report (a hello: it has no place in the stream until the master
    /// answers).
    pub fn announce(&mut self) -> Option<Report> {
        self.slave.poll_report()
    }

    /// Needles per row.
    #[must_use]
    pub fn needles(&self) -> u16 {
        self.needles
    }

    /// The slave (statistics, mode).
    #[must_use]
    pub fn slave(&self) -> &Slave<RING> {
        &self.slave
    }

    /// The source's keys 1–8: the board's status line.
    #[must_use]
    pub fn status_line(&self) -> String {
        let s = self.slave.stats();
        let (row, col) = self.slave.position();
        format!(
            "machine {}: {} rpm, {:?}, row {row} needle {col}, ring {}/{RING}, underruns {}, least slack {}, stand-alone {:.1} s",
            self.index + 1,
            self.rpm,
            mode_name(self.slave.mode()),
            self.slave.slack(),
            s.underruns,
            s.least_slack,
            self.standalone_needles as f64 * self.t0_ns as f64 / 1e9
        )
    }
}
