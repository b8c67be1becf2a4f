//! The master side (the TRS-80): each machine's job plan and the `regler_ring_transfer::Master`
//! scheduler that grants refills by earliest deadline, turning grants into link frames and
//! reports into keep-alives.

use std::collections::BTreeMap;

use regler_ring_transfer::{Master, Refill, ReportOutcome, SlaveParams, link};

use super::plant::pattern;
use super::{Config, FRAME_OVERHEAD, MAX_MACHINES, RING};

/// The master's job plan for one machine: which job each stream row belongs to.
#[derive(Clone, Debug)]
pub struct Jobs {
    rows: u64,
    starts: BTreeMap<u64, u32>,
    next: Option<u32>,
}

impl Jobs {
    /// Starting with `job`, `rows` rows each.
    #[must_use]
    pub fn new(job: u32, rows: u32) -> Self {
        Self {
            rows: u64::from(rows),
            starts: BTreeMap::from([(0, job)]),
            next: None,
        }
    }

    /// The job and its row for stream row `row`, planning boundaries as they are reached.
    pub fn at(&mut self, row: u64) -> (u32, u64) {
        loop {
            let (&start, &job) = self.starts.last_key_value().unwrap_or((&0, &0));
            if row < start + self.rows {
                break;
            }
            let job = self.next.take().unwrap_or(job);
            self.starts.insert(start + self.rows, job);
        }
        let (&start, &job) = self.starts.range(..=row).next_back().unwrap_or((&0, &0));
        (job, row - start)
    }

    /// The source's C: this job after the current one.
    pub fn change_after_current(&mut self, job: u32) {
        self.next = Some(job);
    }

    /// (current job, queued job) as of stream row `row`.
    #[must_use]
    pub fn shown(&self, row: u64) -> (u32, Option<u32>) {
        let job = self.starts.range(..=row).next_back().map_or(0, |(_, &j)| j);
        (job, self.next)
    }
}

/// The master side: the scheduler, the jobs and the link's counters.
#[derive(Debug)]
pub struct Host {
    /// The scheduler.
    pub master: Box<Master<MAX_MACHINES>>,
    /// Each machine's jobs.
    pub jobs: Vec<Jobs>,
    needles: u16,
    /// Items per refill frame at most.
    pub(super) batch: u32,
    byte_ns: u64,
    /// Refill frames sent.
    pub frames: u64,
    /// Items sent (resends included).
    pub items_sent: u64,
    /// Keep-alives sent.
    pub keep_alives: u64,
    /// Time the refill frames sent hold a link of the run's byte time, nanoseconds: the link's
    /// busy time (in memory it is the simulated link's; over UDP what the same frames would take
    /// on such a link).
    pub link_ns: u64,
}

impl Host {
    /// A master for the boards' speeds.
    ///
    /// # Errors
    /// The master's error, as text.
    pub fn new(config: &Config, t0s: &[u64]) -> Result<Self, String> {
        let mut master: Box<Master<MAX_MACHINES>> = Box::default();
        for (i, &t0) in t0s.iter().enumerate() {
            let t0 = u32::try_from(t0).map_err(|_| "t0 too long")?;
            master
                .attach(
                    i,
                    SlaveParams {
                        capacity: RING as u16,
                        t0,
                    },
                )
                .map_err(|e| e.to_string())?;
        }
        Ok(Self {
            master,
            jobs: (0..t0s.len())
                .map(|i| Jobs::new(i as u32, config.job_rows))
                .collect(),
            needles: config.needles,
            batch: config.batch,
            byte_ns: config.byte_ns,
            frames: 0,
            items_sent: 0,
            keep_alives: 0,
            link_ns: 0,
        })
    }

    /// The master's byte at stream index `k` of machine `m`.
    pub fn byte(&mut self, m: usize, k: u64) -> u8 {
        let needles = u64::from(self.needles);
        let (job, row) = self.jobs[m].at(k / needles);
        pattern(job, row, (k % needles) as u16)
    }

    /// A report from machine `m` at `now`; returns a keep-alive frame when nothing is owed.
    pub fn report(&mut self, now: u64, m: usize, bytes: &[u8]) -> Option<Vec<u8>> {
        let Ok(regler_ring_transfer::Message::Report(report)) = regler_ring_transfer::decode(bytes)
        else {
            return None;
        };
        match self.master.on_report(now, m, &report) {
            Ok(ReportOutcome::Accepted { owed: 0 }) => {
                self.keep_alives += 1;
                let mut frame = vec![0u8; link::MAX_FRAME];
                let n = Refill::keep_alive(report.slave).encode(&mut frame).ok()?;
                frame.truncate(n);
                Some(frame)
            }
            _ => None,
        }
    }

    /// The scheduler's next frame: (machine, frame bytes, items).
    pub fn next_frame(&mut self, now: u64) -> Option<(usize, Vec<u8>, u64)> {
        let grant = self.master.next_refill(now, self.batch)?;
        let items: Vec<u8> = (0..u64::from(grant.count))
            .map(|k| self.byte(grant.slave, grant.first + k))
            .collect();
        let mut frame = vec![0u8; link::MAX_FRAME];
        let n = grant
            .refill(grant.slave as u8, &items)
            .encode(&mut frame)
            .ok()?;
        frame.truncate(n);
        self.frames += 1;
        self.link_ns += (FRAME_OVERHEAD + u64::from(grant.count)) * self.byte_ns;
        self.items_sent += u64::from(grant.count);
        Some((grant.slave, frame, u64::from(grant.count)))
    }
}
