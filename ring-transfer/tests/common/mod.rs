//! A board and its master on a link that delays, loses, repeats and reorders frames, run step
//! by step as firmware would: the harness the reboot and relink properties share.
#![allow(
    dead_code,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "a test may panic: that is how it fails"
)]

use regler_ring_transfer::{
    Master, Mode, Output, Report, ReportOutcome, Slave, SlaveConfig, SlaveParams, Source, link,
};

/// Item `k` of the master's stream: a hash, so that an item taken for the wrong index is
/// caught (255 times in 256 per item).
pub(crate) fn stream(k: u64) -> u8 {
    let x = k.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    ((x >> 56) as u8) % 251
}

/// The board's local pattern (never a stream byte: those are < 251).
pub(crate) fn local(_row: u32, col: u16) -> u8 {
    251 + (col % 5) as u8
}

/// The 64-bit count nearest to `known` whose low 16 bits are `wire`.
pub(crate) fn extend(known: u64, wire: u16) -> u64 {
    let diff = wire.wrapping_sub(known as u16) as i16;
    known.wrapping_add_signed(i64::from(diff))
}

/// One direction of the link.
pub(crate) struct Wire {
    in_flight: Vec<(u64, Vec<u8>)>,
    rng: u64,
    /// Steps every frame takes (≥ 1).
    pub(crate) delay: u64,
    /// Chances in 256 that a frame is lost, repeated, or delayed by up to `jitter` more steps.
    pub(crate) loss: u8,
    pub(crate) duplicate: u8,
    pub(crate) late: u8,
    pub(crate) jitter: u64,
    /// Frames lost so far.
    pub(crate) lost: u64,
}

impl Wire {
    pub(crate) fn new(seed: u64, delay: u64) -> Self {
        Self {
            in_flight: Vec::new(),
            rng: seed | 1,
            delay: delay.max(1),
            loss: 0,
            duplicate: 0,
            late: 0,
            jitter: 0,
            lost: 0,
        }
    }
    fn roll(&mut self) -> u8 {
        self.rng ^= self.rng >> 12;
        self.rng ^= self.rng << 25;
        self.rng ^= self.rng >> 27;
        (self.rng.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 56) as u8
    }
    pub(crate) fn send(&mut self, now: u64, frame: &[u8], faulty: bool) {
        if faulty && self.roll() < self.loss {
            self.lost += 1;
            return;
        }
        let copies = if faulty && self.roll() < self.duplicate {
            2
        } else {
            1
        };
        for _ in 0..copies {
            let extra = if faulty && self.jitter > 0 && self.roll() < self.late {
                1 + u64::from(self.roll()) % self.jitter
            } else {
                0
            };
            self.in_flight
                .push((now + self.delay + extra, frame.to_vec()));
        }
    }
    pub(crate) fn arrived(&mut self, now: u64) -> Vec<Vec<u8>> {
        let (due, later): (Vec<_>, Vec<_>) = self.in_flight.drain(..).partition(|(t, _)| *t <= now);
        self.in_flight = later;
        due.into_iter().map(|(_, f)| f).collect()
    }
}

pub(crate) const ADDRESS: u8 = 3;

/// One step's record.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Step {
    pub(crate) now: u64,
    pub(crate) boot: u8,
    /// The stream index the board's consumed count stood at before the step (once placed).
    pub(crate) index: Option<u64>,
    pub(crate) out: Output,
    pub(crate) mode_after: Mode,
}

pub(crate) struct Sim<const N: usize> {
    pub(crate) config: SlaveConfig,
    pub(crate) master: Master<1>,
    pub(crate) slave: Slave<N>,
    pub(crate) up: Wire,
    pub(crate) down: Wire,
    /// The board's consumed count as a 64-bit stream index (meaningful once placed).
    pub(crate) abs_consumed: u64,
    /// The newest consumed count (64-bit) of a report of the current session's board that
    /// reached the master before the current board's first hello did — where the board before
    /// it stopped, as far as the master can know.
    pub(crate) newest_of_previous: u64,
    newest_of_current: u64,
    hello_delivered: bool,
    /// Where each board was placed (its consumed count at the sync), by boot number.
    pub(crate) placements: Vec<(u8, u64)>,
    pub(crate) steps: Vec<Step>,
    /// The master is up (answers reports, sends refills).
    pub(crate) master_up: bool,
    pub(crate) faulty: bool,
    pub(crate) stale_standalone: u32,
    /// Items per refill frame at most.
    pub(crate) batch: u32,
}

impl<const N: usize> Sim<N> {
    /// A master whose counters stand at `offset` (a board that had been running reported them
    /// before this one started: boot 0), and a new board with boot number 1.
    pub(crate) fn new(config: SlaveConfig, offset: u64, delay: u64, seed: u64) -> Self {
        let mut master: Master<1> = Master::new();
        master
            .attach(
                0,
                SlaveParams {
                    capacity: N as u16,
                    t0: 1,
                },
            )
            .unwrap();
        let running = Report {
            slave: ADDRESS,
            consumed: offset as u16,
            received: offset as u16,
            standalone: false,
            retry: false,
            boot: config.boot.wrapping_sub(1),
            hello: false,
        };
        master.on_report(0, 0, &running).unwrap();
        // The master's stream index is the 16-bit count extended from 0: move it to `offset`
        // by reports of the running board in steps below half the range.
        let mut at = offset as u16 as u64;
        while at < offset {
            at = (at + 0x4000).min(offset);
            let r = Report {
                consumed: at as u16,
                received: at as u16,
                ..running
            };
            master.on_report(0, 0, &r).unwrap();
        }
        assert_eq!(master.status(0).unwrap().consumed, offset);
        Self {
            config,
            master,
            slave: Slave::new(config).unwrap(),
            up: Wire::new(seed, delay),
            down: Wire::new(seed.rotate_left(23) ^ 0xA5A5, delay),
            abs_consumed: 0,
            newest_of_previous: offset,
            newest_of_current: offset,
            hello_delivered: false,
            placements: Vec::new(),
            steps: Vec::new(),
            master_up: true,
            faulty: false,
            stale_standalone: 0,
            batch: link::MAX_REFILL as u32,
        }
    }

    /// The board restarts: a new `Slave` with the next boot number.
    pub(crate) fn reboot(&mut self) {
        self.config.boot = self.config.boot.wrapping_add(1);
        self.slave = Slave::new(self.config).unwrap();
        self.hello_delivered = false;
    }

    pub(crate) fn step(&mut self, now: u64) {
        for f in self.up.arrived(now) {
            let Ok(link::Message::Report(r)) = link::decode(&f) else {
                panic!("a report frame");
            };
            if !self.master_up {
                continue;
            }
            let session = self.master.status(0).unwrap().boot;
            let previous = self.config.boot.wrapping_sub(1);
            if r.boot == self.config.boot && r.hello && !self.hello_delivered {
                self.hello_delivered = true;
                self.newest_of_previous = self.newest_of_current;
            }
            // The model of "where the board stopped": the newest count the master heard from
            // the live board, or from the board before it until the new one's hello came.
            let live = r.boot == self.config.boot || (!self.hello_delivered && r.boot == previous);
            if !r.hello && live {
                let c = extend(self.newest_of_current, r.consumed);
                self.newest_of_current = self.newest_of_current.max(c);
            }
            let outcome = self.master.on_report(now, 0, &r).unwrap();
            if r.standalone && !r.hello && r.boot == session && outcome == ReportOutcome::Stale {
                let s = self.master.status(0).unwrap();
                if extend(s.consumed, r.consumed) == s.consumed
                    && extend(s.received, r.received) == s.received
                {
                    self.stale_standalone += 1;
                }
            }
            if let ReportOutcome::Accepted { owed: 0 } = outcome {
                let mut frame = [0u8; link::MAX_FRAME];
                let n = regler_ring_transfer::Refill::keep_alive(ADDRESS)
                    .encode(&mut frame)
                    .unwrap();
                self.down.send(now, &frame[..n], self.faulty);
            }
        }
        if self.master_up {
            let mut items = [0u8; link::MAX_REFILL];
            let mut frame = [0u8; link::MAX_FRAME];
            while let Some(g) = self.master.next_refill(now, self.batch) {
                let n = g.count as usize;
                for (k, item) in items[..n].iter_mut().enumerate() {
                    *item = stream(g.first + k as u64);
                }
                let len = g.refill(ADDRESS, &items[..n]).encode(&mut frame).unwrap();
                self.down.send(now, &frame[..len], self.faulty);
            }
        }
        for f in self.down.arrived(now) {
            let was_placed = self.slave.placed();
            self.slave.on_frame(&f).unwrap();
            if !was_placed && self.slave.placed() {
                let wire = self.slave.report(false).consumed;
                self.abs_consumed = extend(self.newest_of_previous, wire);
                self.placements.push((self.config.boot, self.abs_consumed));
            }
        }
        let index = self.slave.placed().then_some(self.abs_consumed);
        let out = self.slave.step(local);
        if self.slave.placed() {
            let wire = self.slave.report(false).consumed;
            self.abs_consumed = extend(self.abs_consumed, wire);
        }
        self.steps.push(Step {
            now,
            boot: self.config.boot,
            index,
            out,
            mode_after: self.slave.mode(),
        });
        if let Some(r) = self.slave.poll_report() {
            let mut frame = [0u8; link::MAX_FRAME];
            let n = r.encode(&mut frame).unwrap();
            self.up.send(now, &frame[..n], self.faulty);
        }
    }

    /// Every item labelled `Source::Master` is the master's item at the index the board's
    /// counters stood at; every other item is the local pattern's; a placed board in linked
    /// mode moves one index per step, a stand-alone one none.
    pub(crate) fn check_items(&self) {
        for w in self.steps.windows(2) {
            let (a, b) = (w[0], w[1]);
            if a.boot == b.boot {
                if let (Some(i), Some(j)) = (a.index, b.index) {
                    let moved = j - i;
                    let expected = u64::from(a.out.source != Source::Local);
                    assert_eq!(moved, expected, "step {}: {:?}", a.now, a);
                }
            }
        }
        for s in &self.steps {
            match s.out.source {
                Source::Master => {
                    let i = s.index.expect("a master item only from a placed board");
                    assert_eq!(s.out.item, stream(i), "step {}: index {i}", s.now);
                }
                _ => assert_eq!(s.out.item, local(s.out.row, s.out.col), "step {}", s.now),
            }
        }
    }
}
