//! The driver and one crate over two real serial ports (e.g. the two ends of a `socat` pty
//! pair), each in its own thread, through `regler_panel_link::io` on the `serialport` crate; and
//! the 1977 panel link (host and panel) over the same two ports.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use embedded_io_adapters::std::FromStd;
use regler_panel_link::highway::{
    Controller, ControllerConfig, Driver, DriverConfig, DriverEvent, Message,
};
use regler_panel_link::io::{ControllerLink, DriverLink, IoError, clock_controller, clock_driver};
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

fn open(path: &str, timeout: Duration) -> Result<FromStd<Box<dyn serialport::SerialPort>>, String> {
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
pub fn run_panel(host_port: &str, panel_port: &str, keys: &[u8]) -> Result<PanelSummary, String> {
    use regler_panel_link::io::{Transmit, host_transmit, panel_receive, read_byte, write_byte};
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
    let mut host: Host<LANE_PANEL> = Host::new(HostConfig::default()).map_err(|e| e.to_string())?;
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
            let _sent_or_idle: Transmit =
                host_transmit(&mut host_side, &mut host).map_err(|e| format!("host port: {e}"))?;
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
