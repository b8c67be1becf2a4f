//! The CAMAC serial highway of source 004 rebuilt on `regler-panel-link`: one driver and up to
//! 62 L-type crate controllers on a loop of one-way links, each link flipping bits at a set rate;
//! simulated crates with register modules and a counter that raises a LAM. The simulation is the
//! loop a firmware would run: one byte clock at a time, every machine called exactly as on a
//! real highway.
//!
//! The harness knows the truth the protocol does not: which command the driver issued to each
//! crate and what each dataway cycle read. An **undetected error** is a cycle that ran a command
//! the driver did not issue, or a completed command whose answer (data, X, Q) no run of it gave.

use std::collections::BTreeSet;

use regler_panel_link::highway::{
    Controller, ControllerConfig, Cycle, Dataway, Driver, DriverConfig, DriverEvent, Message, WAIT,
    is_read,
};
use regler_panel_link::line::{Framing, Noise};
use serde::Serialize;

/// The driver's window: commands in flight at most (one per crate).
pub const WINDOW: usize = 16;
/// The counter module's station.
pub const COUNTER_STATION: u8 = 20;
/// Register modules sit at stations 1..=REGISTER_STATIONS.
pub const REGISTER_STATIONS: u8 = 4;

/// How the bytes travel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LineKind {
    /// Eight lines and a clock: noise hits the 8 bits of each byte.
    ByteSerial,
    /// Start 0, 8 bits LSB first, stop 1: noise hits all 10 bits; a frame with a broken start or
    /// stop bit reaches the controller as a byte with even parity (a detected error).
    BitSerial,
}

/// One run's parameters.
#[derive(Clone, Debug, Serialize)]
pub struct Config {
    /// Crate controllers on the loop (1–62).
    pub crates: u8,
    /// Commands to complete (or fail).
    pub messages: u64,
    /// Bit-error rate of every link.
    pub ber: f64,
    /// Seed of the workload and of the noise.
    pub seed: u64,
    /// Line encoding.
    pub line: LineKind,
    /// Commands in flight at most (1–16).
    pub window: usize,
    /// Retries per command.
    pub retries: u8,
    /// Counter counts before it raises its LAM.
    pub lam_preset: u32,
    /// Byte clocks per counter count.
    pub count_period: u32,
    /// Byte-serial clock (Hz) for the throughput figure.
    pub byte_rate_hz: f64,
    /// Bit-serial bit rate (bit/s) for the throughput figure.
    pub bit_rate_hz: f64,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            crates: 62,
            messages: 1_000_000,
            ber: 1e-5,
            seed: 1976,
            line: LineKind::ByteSerial,
            window: WINDOW,
            retries: 5,
            lam_preset: 5_000,
            count_period: 7,
            byte_rate_hz: 5e6,
            bit_rate_hz: 5e6,
        }
    }
}

impl Config {
    /// Checks every parameter.
    ///
    /// # Errors
    /// The first bad one, named.
    pub fn validate(&self) -> Result<(), String> {
        if !(1..=62).contains(&self.crates) {
            return Err(format!("crates must be 1..=62, got {}", self.crates));
        }
        if self.messages == 0 {
            return Err("messages must be at least 1".into());
        }
        if !(self.ber.is_finite() && (0.0..=0.1).contains(&self.ber)) {
            return Err(format!(
                "bit-error rate must be in 0..=0.1, got {}",
                self.ber
            ));
        }
        if !(1..=WINDOW).contains(&self.window) {
            return Err(format!("window must be 1..={WINDOW}, got {}", self.window));
        }
        if self.lam_preset == 0 || self.count_period == 0 {
            return Err("lam preset and count period must be at least 1".into());
        }
        for (name, v) in [
            ("byte rate", self.byte_rate_hz),
            ("bit rate", self.bit_rate_hz),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name} must be positive, got {v}"));
            }
        }
        Ok(())
    }

    /// Byte clocks a reply may take at most: every controller may hold 3 bytes behind a demand
    /// on top of its one byte of delay, and a command and its reply must pass.
    #[must_use]
    pub fn timeout(&self) -> u32 {
        4 * (u32::from(self.crates) + 1) + 64
    }
}

/// One dataway cycle as the crate ran it: (N, A, F, write data, read data, X, Q).
pub type CycleRecord = (u8, u8, u8, Option<u32>, u32, bool, bool);

/// A cycle a module took (X and Q set), nothing to read.
const ACCEPTED: Cycle = Cycle {
    read: 0,
    x: true,
    q: true,
};
/// No module answers this N·F: X and Q clear.
const NO_MODULE: Cycle = Cycle {
    read: 0,
    x: false,
    q: false,
};

/// The modules of one simulated crate.
#[derive(Clone, Debug)]
pub struct SimCrate {
    /// Register modules: 16 registers of 24 bits each.
    pub registers: [[u32; 16]; REGISTER_STATIONS as usize],
    /// The counter's count.
    pub count: u32,
    /// The counter's LAM is enabled.
    pub lam_enabled: bool,
    /// The LAM preset.
    pub preset: u32,
    /// Cycles run since the harness last cleared the log: (N, A, F, write, read, X, Q).
    pub log: Vec<CycleRecord>,
}

impl SimCrate {
    fn new(preset: u32) -> Self {
        Self {
            registers: [[0; 16]; REGISTER_STATIONS as usize],
            count: 0,
            lam_enabled: true,
            preset,
            log: Vec::new(),
        }
    }

    /// The counter's LAM.
    #[must_use]
    pub fn lam(&self) -> bool {
        self.lam_enabled && self.count >= self.preset
    }
}

impl Dataway for SimCrate {
    fn cycle(&mut self, n: u8, a: u8, f: u8, write: Option<u32>) -> Cycle {
        let result = match (n, f) {
            (1..=REGISTER_STATIONS, _) => {
                let reg = &mut self.registers[usize::from(n - 1)][usize::from(a & 15)];
                match f {
                    0 => Cycle {
                        read: *reg,
                        ..ACCEPTED
                    },
                    9 => {
                        *reg = 0;
                        ACCEPTED
                    }
                    16 => {
                        *reg = write.unwrap_or(0) & 0xFF_FFFF;
                        ACCEPTED
                    }
                    _ => NO_MODULE,
                }
            }
            (COUNTER_STATION, 0) => Cycle {
                read: self.count,
                ..ACCEPTED
            },
            (COUNTER_STATION, 2) => Cycle {
                read: core::mem::take(&mut self.count),
                ..ACCEPTED
            },
            (COUNTER_STATION, 8) => Cycle {
                q: self.lam(),
                ..ACCEPTED
            },
            (COUNTER_STATION, 24) => {
                self.lam_enabled = false;
                ACCEPTED
            }
            (COUNTER_STATION, 26) => {
                self.lam_enabled = true;
                ACCEPTED
            }
            _ => NO_MODULE,
        };
        let read = if is_read(f) {
            result.read & 0xFF_FFFF
        } else {
            0
        };
        self.log.push((n, a, f, write, read, result.x, result.q));
        result
    }

    fn graded_lam(&mut self) -> u8 {
        u8::from(self.lam())
    }
}

/// Per-crate figures.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CrateSummary {
    /// Crate address.
    pub address: u8,
    /// Commands the driver issued to it.
    pub messages: u64,
    /// Commands completed.
    pub replies: u64,
    /// Errors its controller detected (ERR replies, truncated commands).
    pub detected_errors: u64,
    /// Re-sends of its commands.
    pub retries: u64,
    /// Commands that failed after every retry.
    pub failed: u64,
    /// Demands received from it.
    pub demands: u64,
    /// Demands served (its counter read and cleared).
    pub demands_served: u64,
    /// Cycles run.
    pub cycles: u64,
}

/// What a run gives.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// The configuration.
    pub config: Config,
    /// Byte clocks run.
    pub clocks: u64,
    /// Commands completed.
    pub completed: u64,
    /// Commands failed.
    pub failed: u64,
    /// Commands re-sent.
    pub retries: u64,
    /// Messages damaged on the way back to the driver (rejected by `decode`).
    pub garbled_at_driver: u64,
    /// Errors the controllers detected.
    pub detected_at_crates: u64,
    /// Time-outs at the driver.
    pub timeouts: u64,
    /// Bits the noise flipped.
    pub bits_flipped: u64,
    /// The figure that matters: wrong cycles run plus wrong answers accepted.
    pub undetected_errors: u64,
    /// The same, by kind.
    pub undetected: Undetected,
    /// Demands received.
    pub demands: u64,
    /// Demands served.
    pub demands_served: u64,
    /// Completed commands per second of line time, byte-serial.
    pub messages_per_s_byte_serial: f64,
    /// Completed commands per second of line time, bit-serial.
    pub messages_per_s_bit_serial: f64,
    /// Per crate.
    pub crates: Vec<CrateSummary>,
}

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

/// Parses a workload script: one command per line, `CRATE STATION SUBADDRESS FUNCTION [DATA]`
/// (data for F16–F23, decimal or 0x-hex); `#` starts a comment.
///
/// # Errors
/// The line and what is wrong with it.
pub fn parse_script(text: &str, crates: u8) -> Result<Vec<Message>, String> {
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let at = |e: String| format!("script line {}: {e}", k + 1);
        let number = |t: &str| -> Result<u32, String> {
            match t.strip_prefix("0x") {
                Some(hex) => u32::from_str_radix(hex, 16),
                None => t.parse(),
            }
            .map_err(|_| format!("'{t}' is not a number"))
        };
        let fields: Vec<&str> = line.split_whitespace().collect();
        if !(4..=5).contains(&fields.len()) {
            return Err(at(format!(
                "expected CRATE STATION SUBADDRESS FUNCTION [DATA], got '{line}'"
            )));
        }
        let small = |t: &str| -> Result<u8, String> {
            u8::try_from(number(t)?).map_err(|_| format!("'{t}' is too large"))
        };
        let command = Message::Command {
            crate_address: small(fields[0]).map_err(at)?,
            station: small(fields[1]).map_err(at)?,
            subaddress: small(fields[2]).map_err(at)?,
            function: small(fields[3]).map_err(at)?,
            data: fields.get(4).map(|t| number(t)).transpose().map_err(at)?,
        };
        command.validate().map_err(|e| at(e.to_string()))?;
        if !(1..=crates).contains(&command.crate_address()) {
            return Err(at(format!(
                "crate {} is not on the loop (1..={crates})",
                command.crate_address()
            )));
        }
        out.push(command);
    }
    if out.is_empty() {
        return Err("the script has no commands".into());
    }
    Ok(out)
}

/// The undetected errors by kind.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Undetected {
    /// A crate ran a cycle that was not the command issued to it.
    pub wrong_cycles: u64,
    /// The driver accepted an answer no run of the command gave.
    pub wrong_answers: u64,
    /// A demand arrived from a crate address not on the loop.
    pub phantom_demands: u64,
}

impl Undetected {
    /// All of them.
    #[must_use]
    pub fn total(&self) -> u64 {
        self.wrong_cycles + self.wrong_answers + self.phantom_demands
    }
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

/// The driver and one crate over two real serial ports (e.g. the two ends of a `socat` pty
/// pair), each in its own thread, through `regler_panel_link::io` on the `serialport` crate.
pub mod ports {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::time::{Duration, Instant};

    use embedded_io_adapters::std::FromStd;
    use regler_panel_link::highway::{
        Controller, ControllerConfig, Driver, DriverConfig, DriverEvent, Message,
    };
    use regler_panel_link::io::{
        ControllerLink, DriverLink, IoError, clock_controller, clock_driver,
    };
    use serde::Serialize;

    use super::{REGISTER_STATIONS, SimCrate};

    /// What the run over the ports gave.
    #[derive(Clone, Debug, Serialize)]
    pub struct PortSummary {
        /// The driver's port.
        pub driver_port: String,
        /// The crate's port.
        pub crate_port: String,
        /// Commands completed.
        pub completed: u64,
        /// Commands failed.
        pub failed: u64,
        /// Answers that did not match what the crate did.
        pub undetected_errors: u64,
        /// Byte clocks.
        pub clocks: u64,
        /// Wall-clock seconds.
        pub seconds: f64,
    }

    fn open(
        path: &str,
        timeout: Duration,
    ) -> Result<FromStd<Box<dyn serialport::SerialPort>>, String> {
        let port = serialport::new(path, 115_200)
            .timeout(timeout)
            .open()
            .map_err(|e| format!("cannot open {path}: {e}"))?;
        Ok(FromStd::new(port))
    }

    /// Writes then reads back `messages` registers of crate 1 over the two ports.
    ///
    /// # Errors
    /// A port that cannot be opened, or fails or stalls mid-run.
    pub fn run(
        driver_port: &str,
        crate_port: &str,
        messages: u64,
        seed: u64,
    ) -> Result<PortSummary, String> {
        let mut crate_side = open(crate_port, Duration::from_millis(100))?;
        let mut driver_side = open(driver_port, Duration::from_secs(3))?;
        let stop = Arc::new(AtomicBool::new(false));
        let crate_stop = Arc::clone(&stop);
        let crate_thread = std::thread::spawn(move || -> Result<SimCrate, String> {
            let mut controller = Controller::new(ControllerConfig {
                address: 1,
                demand_repeat: 0,
            })
            .map_err(|e| e.to_string())?;
            let mut dataway = SimCrate::new(u32::MAX);
            let mut link = ControllerLink::default();
            // A read that times out is a quiet line; the run ends when the driver says so.
            while !crate_stop.load(Ordering::Relaxed) {
                match clock_controller(&mut crate_side, &mut controller, &mut dataway, &mut link) {
                    Ok(()) | Err(IoError::Port(_)) => {}
                    Err(e) => return Err(format!("crate port: {e}")),
                }
            }
            Ok(dataway)
        });
        let start = Instant::now();
        let mut driver: Driver<1> = Driver::new(DriverConfig {
            timeout: 64,
            retries: 3,
            gap: 1,
        })
        .map_err(|e| e.to_string())?;
        let mut rng = regler_panel_link::line::Noise::new(0.0, seed).map_err(|e| e.to_string())?;
        let mut link = DriverLink::default();
        let (mut completed, mut failed, mut undetected) = (0u64, 0u64, 0u64);
        let mut expected: Option<(Message, Option<u32>)> = None;
        let mut written = [[0u32; 16]; REGISTER_STATIONS as usize];
        let mut issued = 0u64;
        while completed + failed < messages {
            if driver.outstanding() == 0 && issued < messages {
                let r = rng.next_u64();
                let n = 1 + (r % u64::from(REGISTER_STATIONS)) as u8;
                let a = ((r >> 8) % 16) as u8;
                let (function, data) = if issued.is_multiple_of(2) {
                    (16, Some(((r >> 16) & 0xFF_FFFF) as u32))
                } else {
                    (0, None)
                };
                let command = Message::Command {
                    crate_address: 1,
                    station: n,
                    subaddress: a,
                    function,
                    data,
                };
                let answer = match data {
                    Some(d) => {
                        written[usize::from(n - 1)][usize::from(a)] = d;
                        None
                    }
                    None => Some(written[usize::from(n - 1)][usize::from(a)]),
                };
                driver.submit(command).map_err(|e| e.to_string())?;
                expected = Some((command, answer));
                issued += 1;
            }
            match clock_driver(&mut driver_side, &mut driver, &mut link)
                .map_err(|e| format!("driver port: {e}"))?
            {
                Some(DriverEvent::Completed(done)) => {
                    completed += 1;
                    if expected != Some((done.command, done.data)) {
                        undetected += 1;
                    }
                }
                Some(DriverEvent::Failed { .. }) => failed += 1,
                _ => {}
            }
        }
        let clocks = driver.stats().clocks;
        let seconds = start.elapsed().as_secs_f64();
        stop.store(true, Ordering::Relaxed);
        drop(driver_side);
        let dataway = crate_thread
            .join()
            .map_err(|_| "crate thread panicked".to_string())??;
        // The crate's registers are what the driver wrote.
        if dataway.registers != written {
            undetected += 1;
        }
        Ok(PortSummary {
            driver_port: driver_port.into(),
            crate_port: crate_port.into(),
            completed,
            failed,
            undetected_errors: undetected,
            clocks,
            seconds,
        })
    }

    /// What the panel link over the ports gave.
    #[derive(Clone, Debug, Serialize)]
    pub struct PanelSummary {
        /// The host's port.
        pub host_port: String,
        /// The panel's port.
        pub panel_port: String,
        /// Keys pressed at the panel.
        pub keys_pressed: Vec<u8>,
        /// Keys the host took, in order.
        pub keys_delivered: Vec<u8>,
        /// Register sequences the host sent.
        pub sequences: u64,
        /// The panel shows the host's registers at the end.
        pub registers_match: bool,
        /// Wall-clock seconds.
        pub seconds: f64,
    }

    /// The 1977 panel link over two real ports: the host (29 registers, updated every 50 ms as
    /// in the source) on one, a panel on the other, its operator pressing `keys` 100 ms apart.
    /// Data bytes go over the ports at the source's 4800-baud pace (one per 2.3 ms); MOT and
    /// SÄN, separate wires in the source, are two shared flags here (a pty pair has no modem
    /// lines; on a real port they map to RTS/CTS).
    ///
    /// # Errors
    /// A port that cannot be opened or fails.
    pub fn run_panel(
        host_port: &str,
        panel_port: &str,
        keys: &[u8],
    ) -> Result<PanelSummary, String> {
        use regler_panel_link::io::{
            Transmit, host_transmit, panel_receive, read_byte, write_byte,
        };
        use regler_panel_link::panel::{Host, HostConfig, HostEvent, LANE_PANEL, Panel};

        let mut host_side = open(host_port, Duration::from_millis(1))?;
        let mut panel_side = open(panel_port, Duration::from_millis(1))?;
        let mot = Arc::new(AtomicBool::new(false));
        let san = Arc::new(AtomicBool::new(false));
        let stop = Arc::new(AtomicBool::new(false));
        let (panel_mot, panel_san, panel_stop) =
            (Arc::clone(&mot), Arc::clone(&san), Arc::clone(&stop));
        let pressed = keys.to_vec();
        let start = Instant::now();
        let panel_thread = std::thread::spawn(move || -> Result<Panel<LANE_PANEL>, String> {
            let mut panel: Panel<LANE_PANEL> = Panel::new();
            let mut next_key = 0usize;
            let mut next_tick = Duration::from_millis(20);
            while !panel_stop.load(Ordering::Relaxed) {
                match panel_receive(&mut panel_side, &mut panel) {
                    // A time-out: a quiet line (the panel is not told); another port error:
                    // the panel was told its byte slot was damaged.
                    Ok(()) | Err(IoError::Port(_)) => {}
                    Err(e) => return Err(format!("panel port: {e}")),
                }
                let now = start.elapsed();
                if next_key < pressed.len()
                    && now >= Duration::from_millis(100 * (next_key as u64 + 1))
                    && panel.press(pressed[next_key]).is_ok()
                {
                    next_key += 1;
                }
                let mut send = panel.set_san(panel_san.load(Ordering::Relaxed));
                if now >= next_tick {
                    next_tick += Duration::from_millis(20);
                    send = send.or(panel.tick_20ms());
                }
                if let Some(key) = send {
                    write_byte(&mut panel_side, key).map_err(|e| format!("panel port: {e}"))?;
                }
                panel_mot.store(panel.mot(), Ordering::Relaxed);
            }
            Ok(panel)
        });
        let mut host: Host<LANE_PANEL> =
            Host::new(HostConfig::default()).map_err(|e| e.to_string())?;
        let mut delivered = Vec::new();
        let byte_time = Duration::from_micros(11 * 1_000_000 / 4800);
        let (mut next_byte, mut next_poll, mut next_update) =
            (Duration::ZERO, Duration::ZERO, Duration::ZERO);
        let mut update = 0u8;
        let keys_done_by = Duration::from_millis(100 * (keys.len() as u64 + 1) + 500);
        let mut settle_from: Option<u64> = None;
        loop {
            let now = start.elapsed();
            // The display data, refreshed from the live lists every 50 ms — until the end.
            if now >= next_update && now < keys_done_by {
                next_update += Duration::from_millis(50);
                update = update.wrapping_add(1);
                for i in 0..LANE_PANEL {
                    host.set(i, (update.wrapping_mul(7).wrapping_add(i as u8)) & 0x7F)
                        .map_err(|e| e.to_string())?;
                }
            }
            if now >= next_byte {
                // Once per byte time, whatever it returns: after `LeaveIdle` the line stays
                // idle until the next byte time.
                next_byte += byte_time;
                let _sent_or_idle: Transmit = host_transmit(&mut host_side, &mut host)
                    .map_err(|e| format!("host port: {e}"))?;
            }
            if now >= next_poll {
                next_poll += Duration::from_millis(10);
                host.poll_mot(mot.load(Ordering::Relaxed));
                san.store(host.san(), Ordering::Relaxed);
            }
            match read_byte(&mut host_side) {
                Ok(byte) => {
                    if let Some(HostEvent::Key(key)) = host.receive(Ok(byte)) {
                        delivered.push(key);
                    }
                    san.store(host.san(), Ordering::Relaxed);
                }
                Err(IoError::Port(_)) => {}
                Err(e) => return Err(format!("host port: {e}")),
            }
            // After the last update: three more full sequences, then compare (the first may
            // hold older values; the panel shows the second when its closing reset byte arrives,
            // and the third leaves that byte time to get there).
            if now >= keys_done_by && !host.san() {
                let base = *settle_from.get_or_insert(host.stats().sequences);
                if host.stats().sequences >= base + 3 {
                    break;
                }
            }
            if now > keys_done_by + Duration::from_secs(10) {
                return Err("the panel link did not settle within 10 s".into());
            }
        }
        let seconds = start.elapsed().as_secs_f64();
        stop.store(true, Ordering::Relaxed);
        let panel = panel_thread
            .join()
            .map_err(|_| "panel thread panicked".to_string())??;
        Ok(PanelSummary {
            host_port: host_port.into(),
            panel_port: panel_port.into(),
            keys_pressed: keys.to_vec(),
            keys_delivered: delivered,
            sequences: host.stats().sequences,
            registers_match: panel.registers() == host.registers(),
            seconds,
        })
    }
}
