//! The loop, one byte clock at a time: the driver, every link's noise, every crate controller
//! and its dataway, and the harness that checks each cycle and each answer against the truth.

use std::collections::BTreeSet;

use regler_panel_link::highway::{
    Controller, ControllerConfig, Driver, DriverConfig, DriverEvent, Message, WAIT,
};
use regler_panel_link::line::{Framing, Noise};

use super::{
    COUNTER_STATION, Config, CrateSummary, LineKind, REGISTER_STATIONS, SimCrate, Summary,
    Undetected, WINDOW,
};

/// The highway and its harness.
pub struct Sim {
    /// The configuration.
    pub config: Config,
    driver: Driver<WINDOW>,
    /// Controllers and their crates, in loop order (addresses 1..=crates).
    pub crates: Vec<(Controller, SimCrate)>,
    links: Vec<Noise>,
    rng: Noise,
    /// The last command issued to each crate (index = address).
    issued: Vec<Option<Message>>,
    per_crate: Vec<CrateSummary>,
    /// Crates whose demand waits for a free slot.
    demand_waiting: BTreeSet<u8>,
    line_in: u8,
    submitted: u64,
    done: u64,
    undetected: Undetected,
    demands: u64,
    demands_served: u64,
    /// A scripted workload (run in order, over and over), or empty for the random one.
    script: Vec<Message>,
    script_next: usize,
}

impl Sim {
    /// A highway with every crate idle.
    ///
    /// # Errors
    /// A bad configuration.
    pub fn new(config: Config) -> Result<Self, String> {
        config.validate()?;
        let mut crates = Vec::new();
        for address in 1..=config.crates {
            let controller = Controller::new(ControllerConfig {
                address,
                demand_repeat: 4 * config.timeout(),
            })
            .map_err(|e| e.to_string())?;
            crates.push((controller, SimCrate::new(config.lam_preset)));
        }
        // One noise source per link (driver → crate 1, …, last crate → driver), each seeded from
        // one generator so that no two links' streams are related.
        let mut seeds = Noise::new(0.0, config.seed).map_err(|e| e.to_string())?;
        let links = (0..=u64::from(config.crates))
            .map(|_| Noise::new(config.ber, seeds.next_u64()))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| e.to_string())?;
        let driver = Driver::new(DriverConfig {
            timeout: config.timeout(),
            retries: config.retries,
            gap: 1,
        })
        .map_err(|e| e.to_string())?;
        let per_crate = (0..=config.crates)
            .map(|a| CrateSummary {
                address: a,
                ..CrateSummary::default()
            })
            .collect();
        Ok(Self {
            rng: Noise::new(0.0, seeds.next_u64()).map_err(|e| e.to_string())?,
            issued: vec![None; usize::from(config.crates) + 1],
            config,
            driver,
            crates,
            links,
            per_crate,
            demand_waiting: BTreeSet::new(),
            line_in: WAIT,
            submitted: 0,
            done: 0,
            undetected: Undetected::default(),
            demands: 0,
            demands_served: 0,
            script: Vec::new(),
            script_next: 0,
        })
    }

    /// Runs `script` (in order, over and over) instead of the random workload.
    pub fn set_script(&mut self, script: Vec<Message>) {
        self.script = script;
        self.script_next = 0;
    }

    /// Commands completed or failed so far.
    #[must_use]
    pub fn done(&self) -> u64 {
        self.done
    }

    /// True when the run is over.
    #[must_use]
    pub fn finished(&self) -> bool {
        self.done >= self.config.messages
    }

    fn submit(&mut self, command: Message) {
        let address = command.crate_address();
        if self.driver.submit(command).is_ok() {
            self.issued[usize::from(address)] = Some(command);
            self.crates[usize::from(address) - 1].1.log.clear();
            self.per_crate[usize::from(address)].messages += 1;
            self.submitted += 1;
        }
    }

    /// The random workload: reads, writes and controls of the register modules and reads of the
    /// counters; demands first.
    fn feed(&mut self) {
        if self.submitted >= self.config.messages || self.driver.outstanding() >= self.config.window
        {
            return;
        }
        let waiting: Option<u8> = self
            .demand_waiting
            .iter()
            .copied()
            .find(|&c| !self.driver.busy(c));
        if let Some(c) = waiting {
            self.demand_waiting.remove(&c);
            self.submit(Message::Command {
                crate_address: c,
                station: COUNTER_STATION,
                subaddress: 0,
                function: 2,
                data: None,
            });
            return;
        }
        if let Some(&command) = self.script.get(self.script_next) {
            // In order: the next line waits until its crate is free.
            if !self.driver.busy(command.crate_address()) {
                self.submit(command);
                self.script_next = (self.script_next + 1) % self.script.len();
            }
            return;
        }
        let r = self.rng.next_u64();
        let c = 1 + (r % u64::from(self.config.crates)) as u8;
        if self.driver.busy(c) {
            return;
        }
        let n = 1 + ((r >> 8) % u64::from(REGISTER_STATIONS)) as u8;
        let a = ((r >> 16) % 16) as u8;
        let command = match (r >> 24) % 20 {
            0..=8 => Message::Command {
                crate_address: c,
                station: n,
                subaddress: a,
                function: 0,
                data: None,
            },
            9..=15 => Message::Command {
                crate_address: c,
                station: n,
                subaddress: a,
                function: 16,
                data: Some(((r >> 32) & 0xFF_FFFF) as u32),
            },
            16 => Message::Command {
                crate_address: c,
                station: n,
                subaddress: a,
                function: 9,
                data: None,
            },
            17 => Message::Command {
                crate_address: c,
                station: COUNTER_STATION,
                subaddress: 0,
                function: 8,
                data: None,
            },
            _ => Message::Command {
                crate_address: c,
                station: COUNTER_STATION,
                subaddress: 0,
                function: 0,
                data: None,
            },
        };
        self.submit(command);
    }

    fn carry(&mut self, byte: u8, link: usize) -> u8 {
        let noise = &mut self.links[link];
        match self.config.line {
            LineKind::ByteSerial => noise.corrupt_byte(byte),
            LineKind::BitSerial => {
                let frame =
                    noise.corrupt(Framing::BIT_SERIAL.encode(byte), Framing::BIT_SERIAL.bits());
                // A framing error: the receiver has no byte; it passes one that fails row parity.
                Framing::BIT_SERIAL.decode(frame).unwrap_or(0)
            }
        }
    }

    /// One byte clock of the whole loop.
    pub fn clock(&mut self) {
        self.feed();
        let step = self.driver.clock(self.line_in);
        let mut byte = step.transmit;
        let count_tick = self.driver.stats().clocks % u64::from(self.config.count_period) == 0;
        for k in 0..self.crates.len() {
            byte = self.carry(byte, k);
            let (controller, dataway) = &mut self.crates[k];
            if count_tick {
                dataway.count = (dataway.count + 1) & 0xFF_FFFF;
            }
            let before = dataway.log.len();
            byte = controller.clock(byte, dataway);
            if dataway.log.len() > before {
                let address = controller.config().address;
                self.per_crate[usize::from(address)].cycles += 1;
                // Every cycle must be the command last issued to this crate.
                let ok = match self.issued[usize::from(address)] {
                    Some(Message::Command {
                        station,
                        subaddress,
                        function,
                        data,
                        ..
                    }) => dataway.log.last().is_some_and(|e| {
                        (e.0, e.1, e.2, e.3) == (station, subaddress, function, data)
                    }),
                    _ => false,
                };
                if !ok {
                    self.undetected.wrong_cycles += 1;
                }
            }
        }
        let last = self.crates.len();
        self.line_in = self.carry(byte, last);
        match step.event {
            Some(DriverEvent::Completed(done)) => self.completed(done),
            Some(DriverEvent::Failed { command, .. }) => {
                let address = command.crate_address();
                self.per_crate[usize::from(address)].failed += 1;
                self.done += 1;
            }
            Some(DriverEvent::Demand { crate_address, .. }) => {
                self.demands += 1;
                match self.per_crate.get_mut(usize::from(crate_address)) {
                    Some(stats) if crate_address >= 1 => {
                        stats.demands += 1;
                        self.demand_waiting.insert(crate_address);
                    }
                    // A demand from a crate that is not on the loop: a damaged header got through.
                    _ => self.undetected.phantom_demands += 1,
                }
            }
            None => {}
        }
    }

    fn completed(&mut self, done: regler_panel_link::highway::Completion) {
        self.done += 1;
        let address = done.command.crate_address();
        let stats = &mut self.per_crate[usize::from(address)];
        stats.replies += 1;
        stats.retries += u64::from(done.attempts.saturating_sub(1));
        let log = &self.crates[usize::from(address) - 1].1.log;
        // The answer must be what some run of this command gave.
        let matches = log.iter().any(|e| {
            (done.data.is_none() || done.data == Some(e.4))
                && e.5 == done.status.x
                && e.6 == done.status.q
        });
        if !matches || self.issued[usize::from(address)] != Some(done.command) {
            self.undetected.wrong_answers += 1;
        }
        if let Message::Command {
            station: COUNTER_STATION,
            function: 2,
            ..
        } = done.command
        {
            stats.demands_served += 1;
            self.demands_served += 1;
        }
    }

    /// Runs until `done` reaches `target` (or the run's end).
    pub fn run_until_done(&mut self, target: u64) {
        let target = target.min(self.config.messages);
        while self.done < target {
            self.clock();
        }
    }

    /// The figures so far.
    #[must_use]
    pub fn summary(&self) -> Summary {
        let stats = self.driver.stats();
        let line_s_byte = stats.clocks as f64 / self.config.byte_rate_hz;
        let line_s_bit = stats.clocks as f64 * 10.0 / self.config.bit_rate_hz;
        let mut crates: Vec<CrateSummary> = self.per_crate.iter().skip(1).cloned().collect();
        for (c, (controller, _)) in crates.iter_mut().zip(&self.crates) {
            c.detected_errors = controller.stats().errors + controller.stats().truncated;
        }
        let retries = crates.iter().map(|c| c.retries).sum::<u64>();
        Summary {
            config: self.config.clone(),
            clocks: stats.clocks,
            completed: stats.completed,
            failed: stats.failed,
            retries: retries.max(stats.retries),
            garbled_at_driver: stats.garbled,
            detected_at_crates: crates.iter().map(|c| c.detected_errors).sum(),
            timeouts: stats.timeouts,
            bits_flipped: self.links.iter().map(Noise::flips).sum(),
            undetected_errors: self.undetected.total(),
            undetected: self.undetected,
            demands: self.demands,
            demands_served: self.demands_served,
            messages_per_s_byte_serial: if line_s_byte > 0.0 {
                stats.completed as f64 / line_s_byte
            } else {
                0.0
            },
            messages_per_s_bit_serial: if line_s_bit > 0.0 {
                stats.completed as f64 / line_s_bit
            } else {
                0.0
            },
            crates,
        }
    }
}

/// A whole run: the loop from idle until `config.messages` commands completed or failed, the
/// `script` (if any) instead of the random workload; `progress(done)` is called about 200 times
/// with the commands done so far.
///
/// # Errors
/// A bad configuration (named as its command-line option).
pub fn run(
    config: Config,
    script: Option<Vec<Message>>,
    mut progress: impl FnMut(u64),
) -> Result<Summary, String> {
    let chunk = (config.messages / 200).max(1);
    let mut sim = Sim::new(config)?;
    if let Some(script) = script {
        sim.set_script(script);
    }
    while !sim.finished() {
        sim.run_until_done(sim.done() + chunk);
        progress(sim.done());
    }
    Ok(sim.summary())
}
