//! The in-memory transport: boards, master, link and keyboard as one discrete-event simulation
//! in simulated nanoseconds. The link is shared: a refill frame of `k` items holds it for
//! `(9 + k)` byte times; reports travel on each board's own request line after a latency; both
//! directions lose and duplicate frames from a seeded generator — deterministic for a seed.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use regler_ring_transfer::link;

use super::boards::Board;
use super::keys::{Key, Keyboard, Timed};
use super::master::Host;
use super::plant::speeds;
use super::summary::{Link, Summary, summarise};
use super::{Config, START_NS};

#[derive(Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Event {
    /// The link finished a frame.
    LinkFree,
    /// A refill frame reaches machine m.
    Frame(usize, Vec<u8>),
    /// A report reaches the master.
    Report(usize, Vec<u8>),
    /// Machine m's next needle.
    Needle(usize),
    /// A scripted key.
    Key(usize),
}

/// The in-memory simulation: boards, host, link and keyboard.
#[derive(Debug)]
pub struct Sim {
    /// The configuration.
    pub config: Config,
    /// The boards.
    pub boards: Vec<Board>,
    /// The host.
    pub host: Host,
    /// The keyboard.
    pub keyboard: Keyboard,
    queue: BinaryHeap<Reverse<(u64, u64, Event)>>,
    seq: u64,
    rng: ChaCha8Rng,
    link_busy_until: u64,
    /// Frames lost.
    pub lost: u64,
    /// Frames duplicated.
    pub duplicated: u64,
    script: Vec<Timed>,
    /// Simulated time, ns.
    pub now: u64,
    stopped: bool,
}

impl Sim {
    /// A simulation ready to run.
    ///
    /// # Errors
    /// An invalid configuration.
    pub fn new(config: Config, script: Vec<Timed>) -> Result<Self, String> {
        config.validate()?;
        let boards = speeds(&config)
            .into_iter()
            .enumerate()
            .map(|(i, rpm)| Board::new(i, rpm, &config))
            .collect::<Result<Vec<_>, _>>()?;
        let t0s: Vec<u64> = boards.iter().map(|b| b.t0_ns).collect();
        let host = Host::new(&config, &t0s)?;
        let mut sim = Self {
            rng: ChaCha8Rng::seed_from_u64(config.seed ^ 0x5EED),
            config,
            boards,
            host,
            keyboard: Keyboard::default(),
            queue: BinaryHeap::new(),
            seq: 0,
            link_busy_until: 0,
            lost: 0,
            duplicated: 0,
            script,
            now: 0,
            stopped: false,
        };
        // Machines start at staggered phases, after the master's first fill.
        for i in 0..sim.boards.len() {
            let phase = sim.rng.random_range(0..sim.boards[i].t0_ns);
            sim.push(START_NS + phase, Event::Needle(i));
            // Each board announces itself.
            let mut frame = [0u8; link::REPORT_LEN];
            if let Some(hello) = sim.boards[i].announce() {
                if hello.encode(&mut frame).is_ok() {
                    sim.push(0, Event::Report(i, frame.to_vec()));
                }
            }
        }
        for k in 0..sim.script.len() {
            let at = (sim.script[k].at * 1e9) as u64;
            sim.push(at, Event::Key(k));
        }
        Ok(sim)
    }

    fn push(&mut self, at: u64, event: Event) {
        self.seq += 1;
        self.queue.push(Reverse((at, self.seq, event)));
    }

    fn master_up(&self, now: u64) -> bool {
        self.config.master_fault.is_none_or(|(from, len)| {
            let t = now as f64 / 1e9;
            !(from..from + len).contains(&t)
        })
    }

    /// Sends a frame through the faulty link: lost, once or twice.
    fn deliver(&mut self, at: u64, event: impl Fn() -> Event) {
        if self.rng.random_bool(self.config.loss) {
            self.lost += 1;
            return;
        }
        self.push(at, event());
        if self.rng.random_bool(self.config.duplicate) {
            self.duplicated += 1;
            let later = at + self.rng.random_range(0..2_000_000);
            self.push(later, event());
        }
    }

    fn serve(&mut self, now: u64) {
        if now < self.link_busy_until || !self.master_up(now) {
            return;
        }
        if let Some((m, frame, items)) = self.host.next_frame(now) {
            let done = now + self.config.frame_ns(items);
            self.link_busy_until = done;
            self.push(done, Event::LinkFree);
            self.deliver(done, || Event::Frame(m, frame.clone()));
        }
    }

    /// Runs until `until_ns` (or the end of the run, or Break); `progress` gets simulated
    /// seconds done.
    pub fn run_until(&mut self, until_ns: u64) {
        let end = (self.config.seconds * 1e9) as u64;
        let until = until_ns.min(end);
        while let Some(Reverse((at, _, _))) = self.queue.peek() {
            if *at > until || self.stopped {
                break;
            }
            let Some(Reverse((at, _, event))) = self.queue.pop() else {
                break;
            };
            self.now = at;
            match event {
                Event::LinkFree => self.serve(at),
                Event::Frame(m, frame) => self.boards[m].frame(&frame),
                Event::Report(m, bytes) => {
                    if self.master_up(at) {
                        if let Some(keep_alive) = self.host.report(at, m, &bytes) {
                            // A keep-alive goes out between refills (short: 9 bytes).
                            self.deliver(at + self.config.frame_ns(0), || {
                                Event::Frame(m, keep_alive.clone())
                            });
                        }
                        self.serve(at);
                    }
                }
                Event::Needle(m) => {
                    let host = &mut self.host;
                    let report = self.boards[m].needle(|k| host.byte(m, k));
                    let next = at + self.boards[m].t0_ns;
                    self.push(next, Event::Needle(m));
                    if let Some(report) = report {
                        let mut frame = [0u8; link::REPORT_LEN];
                        if report.encode(&mut frame).is_ok() {
                            let arrive = at + self.config.report_ns;
                            self.deliver(arrive, || Event::Report(m, frame.to_vec()));
                        }
                    }
                }
                Event::Key(k) => {
                    let key = self.script[k].key;
                    self.key(key);
                }
            }
        }
        self.now = self.now.max(until);
    }

    /// Answers an operator key now.
    pub fn key(&mut self, key: Key) {
        let link = self.link();
        if self
            .keyboard
            .key(key, link, &self.boards, &mut self.host, &self.config)
        {
            self.stopped = true;
        }
    }

    /// `true` once Break was pressed or the run's time is up.
    #[must_use]
    pub fn finished(&self) -> bool {
        self.stopped || self.now >= (self.config.seconds * 1e9) as u64
    }

    /// The link's counters so far.
    fn link(&self) -> Link {
        Link {
            lost: self.lost,
            duplicated: self.duplicated,
            elapsed_ns: self.now,
            simulated: true,
        }
    }

    /// The summary.
    #[must_use]
    pub fn summary(&self) -> Summary {
        summarise(
            &self.config,
            "in memory",
            &self.boards,
            &self.host,
            self.link(),
            self.keyboard.screen.clone(),
        )
    }
}
