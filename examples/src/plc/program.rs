//! The PLC program: the conveyor section's control logic as IEC 61131-3 function blocks (SR, TON,
//! CTU, R_TRIG) and a `regler_chain_tracker::Tracker` that follows each bad part from the quality
//! sensor to the reject gate by the belt encoder's pulses, scanned by the executive on its input
//! and output images.
//!
//! The tracker is source 000's dock-chain tracking with one tipper (the gate) on a belt that does
//! not stretch: each scan reads the encoder's counter from the input image, hands the pulses
//! since the last scan to [`Tracker::advance`] (a stalled or stopped belt gives none, so the parts
//! and their countdowns stand still together), then enters the bad part the quality sensor
//! flagged in this scan.

use regler_chain_tracker::{DistanceTable, Snapshot, TipperEvent, Tracker, TrackerError};
use regler_scan_cycle::{Ctu, RTrig, Scan, Spool, Sr, Ton};

use super::{IW, OW, input, output};

/// A one-shot job for the reserve: a printout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Report {
    /// Every tenth part: the batch count.
    Batch(u32),
    /// A shift change from the minute table: the hour.
    Shift(u8),
}

impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Report::Batch(n) => write!(f, "batch of 10 parts, {n} parts in all"),
            Report::Shift(h) => write!(f, "shift report at {h:02}:00"),
        }
    }
}

/// Bad parts the tracker holds at once (between the sensor and the gate there is room for five).
const TRACKED: usize = 16;

/// The tracker: bad parts, numbered in the order they were flagged, to one gate.
pub type GateTracker = Tracker<u32, TRACKED, 1>;

/// The application program and its function blocks.
pub struct Conveyor {
    motor: Sr,
    jam_timer: Ton,
    jammed: Sr,
    parts: Ctu,
    part_edge: RTrig,
    bad_edge: RTrig,
    /// Parts counted before the last power failure (the CTU restarts from 0).
    parts_before: i32,
    tracker: GateTracker,
    /// The encoder count read in the last scan (`None` before the first).
    encoder: Option<u16>,
    bad_flagged: u32,
    /// Bad parts the tracker could not take (full): they go through.
    pub untracked: u32,
    gate: bool,
    /// Reports waiting for the reserve.
    pub spool: Spool<Report, 8>,
    /// Reports refused by a full spool.
    pub spool_refused: u32,
}

/// Encoder pulses from the quality sensor to the reject gate: 2 m of belt at 10 mm a pulse (the
/// part enters the gate's photo eye there).
pub const GATE_PULSES: u32 = 200;
/// Encoder pulses the gate stays open (0.3 m of belt): the bad part has left the section 150 mm
/// past the gate, and the next part, at least 400 mm behind it, has not.
pub const HOLD_PULSES: u32 = 30;

/// What the program keeps through a power failure (its battery-backed memory): the tracker's
/// [`Snapshot`] — the bad parts on their way to the gate and the gate's hold —, the edges'
/// memories (a part under a sensor when the power went is not counted or flagged twice), the
/// counts and the spool. The rest starts from power-on: the motor's latch (off until START: the
/// executive restarts with `Restart::Inhibit`), the jam detector, and the encoder count last read
/// (the counter card restarts from 0 with the power, so the first scan takes a new reference; the
/// belt cannot move without power, so no travel is missed).
#[derive(Clone, Debug)]
pub struct Retained {
    /// The tracker's snapshot.
    pub tracker: Snapshot<u32, TRACKED, 1>,
    part_edge: RTrig,
    bad_edge: RTrig,
    parts: i32,
    bad_flagged: u32,
    untracked: u32,
    spool: Spool<Report, 8>,
    spool_refused: u32,
}

impl Default for Conveyor {
    fn default() -> Self {
        Conveyor::new()
    }
}

impl Conveyor {
    /// The program at power-on.
    #[must_use]
    pub fn new() -> Conveyor {
        Conveyor {
            motor: Sr::new(),
            jam_timer: Ton::new(3_000),
            jammed: Sr::new(),
            parts: Ctu::new(i32::MAX),
            part_edge: RTrig::new(),
            bad_edge: RTrig::new(),
            parts_before: 0,
            tracker: gate_tracker(),
            encoder: None,
            bad_flagged: 0,
            untracked: 0,
            gate: false,
            spool: Spool::new(),
            spool_refused: 0,
        }
    }

    /// Parts counted (CTU's CV, plus what it had counted before the last power failure).
    #[must_use]
    pub fn parts(&self) -> i32 {
        self.parts_before.saturating_add(self.parts.cv())
    }

    /// What a power failure must keep (see [`Retained`]).
    #[must_use]
    pub fn retain(&self) -> Retained {
        Retained {
            tracker: self.tracker.snapshot(),
            part_edge: self.part_edge,
            bad_edge: self.bad_edge,
            parts: self.parts(),
            bad_flagged: self.bad_flagged,
            untracked: self.untracked,
            spool: self.spool.clone(),
            spool_refused: self.spool_refused,
        }
    }

    /// The program after a power failure: from power-on, with what [`retain`](Self::retain)
    /// kept, so the bad parts in flight are tracked on from where they stood and the gate is
    /// open again if it was holding.
    ///
    /// # Errors
    /// The tracker refused the snapshot (another program's, or corrupt).
    pub fn power_on(retained: &Retained) -> Result<Conveyor, TrackerError> {
        let mut program = Conveyor::new();
        program.tracker.restore(&retained.tracker)?;
        program.gate = program.tracker.is_set(0);
        program.part_edge = retained.part_edge;
        program.bad_edge = retained.bad_edge;
        program.parts_before = retained.parts;
        program.bad_flagged = retained.bad_flagged;
        program.untracked = retained.untracked;
        program.spool = retained.spool.clone();
        program.spool_refused = retained.spool_refused;
        Ok(program)
    }

    /// The jam timer's elapsed time, ms.
    #[must_use]
    pub fn jam_et(&self) -> u32 {
        self.jam_timer.et()
    }

    /// Bad parts on their way to the gate.
    #[must_use]
    pub fn tracked(&self) -> usize {
        self.tracker.in_flight().count()
    }

    /// Bad parts the quality sensor flagged.
    #[must_use]
    pub fn bad_flagged(&self) -> u32 {
        self.bad_flagged
    }

    /// One scan of the program.
    pub fn scan(&mut self, s: &mut Scan<'_, IW, OW>) {
        let i = s.inputs;
        let part = i.get(input::PART);
        let jam = self
            .jam_timer
            .call(part && s.previous.get(output::MOTOR), s.now_ms);
        let jammed = self.jammed.call(jam, i.get(input::RESET) && !part);
        let motor = self
            .motor
            .call(i.get(input::START) && !jammed, i.get(input::STOP) || jammed);
        if self.part_edge.call(part) {
            self.parts.call(true, false);
            if self.parts() % 10 == 0
                && self
                    .spool
                    .push(Report::Batch(self.parts().unsigned_abs()))
                    .is_err()
            {
                self.spool_refused += 1;
            }
        } else {
            self.parts.call(false, false);
        }
        // The belt's travel since the last scan, from the encoder's counter (it wraps at 2^16;
        // a scan sees at most 5 pulses at full speed).
        let count = i.word(input::ENCODER_WORD).unwrap_or(0);
        let pulses = count.wrapping_sub(self.encoder.unwrap_or(count));
        self.encoder = Some(count);
        let mut gate = self.gate;
        self.tracker
            .advance(u32::from(pulses), |event| match event {
                TipperEvent::Set { .. } => gate = true,
                TipperEvent::Reset { .. } => gate = false,
            });
        // A bad part flagged now is tracked from here, motor on or off: it is on the belt.
        if self.bad_edge.call(i.get(input::BAD)) {
            self.bad_flagged = self.bad_flagged.wrapping_add(1);
            if self.tracker.enter(self.bad_flagged, 0).is_err() {
                self.untracked += 1;
            }
        }
        self.gate = gate;
        let _ = s.outputs.set(output::MOTOR, motor);
        let _ = s.outputs.set(output::JAM, jammed);
        let _ = s.outputs.set(output::GATE, gate);
        let _ = s.outputs.set(output::RUN, motor && !jammed);
    }
}

/// The tracker at power-on: one gate [`GATE_PULSES`] from the sensor, open for [`HOLD_PULSES`].
fn gate_tracker() -> GateTracker {
    DistanceTable::new(GATE_PULSES, &[GATE_PULSES])
        .ok()
        .and_then(|table| Tracker::new(table, HOLD_PULSES).ok())
        .unwrap_or_else(|| unreachable!("a one-gate table with a nonzero hold is valid"))
}
