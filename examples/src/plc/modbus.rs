//! The images over Modbus/TCP, in real time: the PLC cycles against the wall clock and a server
//! thread per client answers from tables the cycle publishes; what a client writes becomes a
//! request the cycle carries out before its next scan.
//!
//! Frames are coded by the `rmodbus` crate, behind [`check`], which holds every request to the
//! specification and the map first (an exception answers anything else, and then nothing acts).
//!
//! # What each write function does
//! Every write acts on every point it names, whether or not the value changes:
//! - **5** write single coil, **15** write multiple coils: each coil written forces its point to
//!   the value written — coils 0–15 force output p, coils 1000–1015 force input p. Writing the
//!   value a coil already shows still forces it (a SCADA client writing a block of coils means
//!   every one of them).
//! - **6** write single register, **16** write multiple registers: each register written is a
//!   command, carried out in address order — register 0 ← 1 releases every forced point (← 0 does
//!   nothing), register 1 ← p releases output p, register 2 ← p releases input p (p = 0 included,
//!   so a block write of zeros to 1–2 releases output 0 and input 0). They read as 0.
//!
//! A request is carried out whole or not at all: a block that reaches past the map is exception
//! 2 (ILLEGAL DATA ADDRESS) and a value a register does not take is exception 3 (ILLEGAL DATA
//! VALUE), and then no point of it acts.

use std::io::{ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use rmodbus::server::ModbusFrame;
use rmodbus::server::storage::ModbusStorage;
use rmodbus::{ModbusFrameBuf, ModbusProto};
use serde::Serialize;

use super::PERIOD_MS;
use super::monitor::Transcript;
use super::simulator::Simulator;
use crate::cli::{self, Stop};

/// What a Modbus client asked of the monitor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Request {
    /// Force output p (coil p) to the value.
    ForceOutput(usize, bool),
    /// Force input p (coil 1000 + p) to the value.
    ForceInput(usize, bool),
    /// Release output p (holding register 1 ← p).
    ReleaseOutput(usize),
    /// Release input p (holding register 2 ← p).
    ReleaseInput(usize),
    /// Release every forced point (holding register 0 ← 1).
    ReleaseAll,
}

impl std::fmt::Display for Request {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let on = |v: bool| if v { "on" } else { "off" };
        match *self {
            Request::ForceOutput(p, v) => write!(f, "force output {p} {}", on(v)),
            Request::ForceInput(p, v) => write!(f, "force input {p} {}", on(v)),
            Request::ReleaseOutput(p) => write!(f, "release output {p}"),
            Request::ReleaseInput(p) => write!(f, "release input {p}"),
            Request::ReleaseAll => f.write_str("release all forced points"),
        }
    }
}

type Storage = ModbusStorage<1024, 1024, 32, 32>;

/// The Modbus tables the cycle publishes and the requests clients wrote, shared by the
/// server's threads and the cycle (behind a `Mutex`).
pub struct Shared {
    storage: Storage,
    requests: Vec<Request>,
}

impl Default for Shared {
    fn default() -> Shared {
        Shared::new()
    }
}

impl Shared {
    /// Tables of zeros, no requests.
    #[must_use]
    pub fn new() -> Shared {
        Shared {
            storage: Storage::new(),
            requests: Vec::new(),
        }
    }

    /// Copies `sim`'s images, forcing and counters into the tables (the cycle does it after
    /// every scan).
    pub fn publish(&mut self, sim: &Simulator) {
        publish(sim, &mut self.storage);
    }

    /// The requests written since the last call, in the order they came (the cycle carries
    /// them out before its next scan).
    pub fn take_requests(&mut self) -> Vec<Request> {
        std::mem::take(&mut self.requests)
    }
}

/// The Modbus map (documented in examples/README.md). Every address outside it is answered
/// with exception 2, ILLEGAL DATA ADDRESS.
pub mod map {
    /// Coils 0–15: the output image; writing one forces that output.
    pub const OUTPUT_COILS: u16 = 0;
    /// Coils 1000–1015: the forced value of input p; writing one forces that input.
    pub const INPUT_COILS: u16 = 1000;
    /// Discrete inputs 0–15: the input image.
    pub const INPUTS: u16 = 0;
    /// Discrete inputs 100–115: output p is forced.
    pub const OUTPUT_FORCED: u16 = 100;
    /// Discrete inputs 200–215: input p is forced.
    pub const INPUT_FORCED: u16 = 200;
    /// Input registers 0–18 (32-bit counters take two, high word first).
    pub const INPUT_REGISTERS: u16 = 19;
    /// Holding register 0: write 1 to release every forced point; 1: write p to release output
    /// p; 2: write p to release input p. They read as 0.
    pub const HOLDING_REGISTERS: u16 = 3;
    /// Points per image.
    pub const POINTS: u16 = 16;

    /// Whether `[start, start + count)` lies inside one of `blocks` (start, length).
    pub fn inside(start: u16, count: u16, blocks: &[(u16, u16)]) -> bool {
        let end = u32::from(start) + u32::from(count);
        blocks
            .iter()
            .any(|&(b, n)| start >= b && end <= u32::from(b) + u32::from(n))
    }
}

/// Modbus exception code 1: the function is not served.
pub const ILLEGAL_FUNCTION: u8 = 1;
/// Modbus exception code 2: an address outside the map.
pub const ILLEGAL_DATA_ADDRESS: u8 = 2;
/// Modbus exception code 3: a quantity, byte count or value not taken.
pub const ILLEGAL_DATA_VALUE: u8 = 3;
/// Modbus exception code 0x0B: no device behind that unit id.
pub const GATEWAY_TARGET_FAILED: u8 = 0x0B;

/// The unit ids this server answers: 1 (its own), and 0 and 255, which the Modbus/TCP
/// implementation guide leaves to a server reached by its IP address. Others are answered with
/// exception 0x0B, as a gateway with no device behind that id.
fn answers_unit(unit: u8) -> bool {
    matches!(unit, 0 | 1 | 255)
}

/// Checks a request PDU against the specification and the map; the exception code if it fails.
/// Order as the specification's server state diagrams: function (a function not served is
/// exception 1 whatever its length), then length, quantity and byte count (exception 3), address
/// range (2), value (3).
pub fn check(pdu: &[u8]) -> Result<(), u8> {
    let word = |i: usize| pdu.get(i..i + 2).map(|b| u16::from_be_bytes([b[0], b[1]]));
    // The function first, whatever follows it (even nothing).
    let function = pdu.first().copied().ok_or(ILLEGAL_FUNCTION)?;
    if !matches!(function, 1..=6 | 15 | 16) {
        return Err(ILLEGAL_FUNCTION);
    }
    let address = word(1).ok_or(ILLEGAL_DATA_VALUE)?;
    let coils = [
        (map::OUTPUT_COILS, map::POINTS),
        (map::INPUT_COILS, map::POINTS),
    ];
    let discretes = [
        (map::INPUTS, map::POINTS),
        (map::OUTPUT_FORCED, map::POINTS),
        (map::INPUT_FORCED, map::POINTS),
    ];
    let holding = [(0, map::HOLDING_REGISTERS)];
    let holding_value_ok = |register: u16, value: u16| match register {
        0 => value <= 1,
        _ => value < map::POINTS,
    };
    let quantity = word(3).ok_or(ILLEGAL_DATA_VALUE)?;
    match function {
        1..=4 => {
            let max = if function <= 2 { 2000 } else { 125 };
            if !(1..=max).contains(&quantity) || pdu.len() != 5 {
                return Err(ILLEGAL_DATA_VALUE);
            }
            let ok = match function {
                1 => map::inside(address, quantity, &coils),
                2 => map::inside(address, quantity, &discretes),
                3 => map::inside(address, quantity, &holding),
                _ => map::inside(address, quantity, &[(0, map::INPUT_REGISTERS)]),
            };
            if ok {
                Ok(())
            } else {
                Err(ILLEGAL_DATA_ADDRESS)
            }
        }
        5 => {
            // The value is the "quantity" field here: only 0x0000 and 0xFF00 are coil values.
            if pdu.len() != 5 || !matches!(quantity, 0x0000 | 0xFF00) {
                return Err(ILLEGAL_DATA_VALUE);
            }
            if map::inside(address, 1, &coils) {
                Ok(())
            } else {
                Err(ILLEGAL_DATA_ADDRESS)
            }
        }
        6 => {
            if pdu.len() != 5 {
                return Err(ILLEGAL_DATA_VALUE);
            }
            if !map::inside(address, 1, &holding) {
                return Err(ILLEGAL_DATA_ADDRESS);
            }
            if holding_value_ok(address, quantity) {
                Ok(())
            } else {
                Err(ILLEGAL_DATA_VALUE)
            }
        }
        15 | 16 => {
            let max = if function == 15 { 0x07B0 } else { 0x007B };
            let bytes = usize::from(*pdu.get(5).ok_or(ILLEGAL_DATA_VALUE)?);
            let want = if function == 15 {
                usize::from(quantity).div_ceil(8)
            } else {
                2 * usize::from(quantity)
            };
            if !(1..=max).contains(&quantity) || bytes != want || pdu.len() != 6 + bytes {
                return Err(ILLEGAL_DATA_VALUE);
            }
            let blocks: &[(u16, u16)] = if function == 15 { &coils } else { &holding };
            if !map::inside(address, quantity, blocks) {
                return Err(ILLEGAL_DATA_ADDRESS);
            }
            if function == 16 {
                for k in 0..quantity {
                    let value = word(6 + 2 * usize::from(k)).ok_or(ILLEGAL_DATA_VALUE)?;
                    if !holding_value_ok(address + k, value) {
                        return Err(ILLEGAL_DATA_VALUE);
                    }
                }
            }
            Ok(())
        }
        _ => Err(ILLEGAL_FUNCTION),
    }
}

/// An exception response to the request in `frame` (MBAP header and PDU).
pub fn exception(frame: &[u8], function: u8, code: u8) -> Vec<u8> {
    let mut reply = frame[..4].to_vec(); // transaction id, protocol id
    reply.extend_from_slice(&3u16.to_be_bytes()); // unit id + 2 bytes of PDU
    reply.push(frame[6]);
    reply.push(function | 0x80);
    reply.push(code);
    reply
}

/// What a write request (its PDU, already passed by [`check`]) asks for: one request for every
/// point it names, in address order (see the module's documentation). Reads ask for nothing.
#[must_use]
pub fn requests(pdu: &[u8]) -> Vec<Request> {
    let word = |i: usize| {
        pdu.get(i..i + 2)
            .map_or(0, |b| u16::from_be_bytes([b[0], b[1]]))
    };
    let (function, address, second) = (pdu.first().copied(), word(1), word(3));
    let coil = |a: u16, on: bool| {
        if a >= map::INPUT_COILS {
            Request::ForceInput(usize::from(a - map::INPUT_COILS), on)
        } else {
            Request::ForceOutput(usize::from(a - map::OUTPUT_COILS), on)
        }
    };
    let holding = |register: u16, value: u16| match register {
        0 => (value == 1).then_some(Request::ReleaseAll),
        1 => Some(Request::ReleaseOutput(usize::from(value))),
        _ => Some(Request::ReleaseInput(usize::from(value))),
    };
    match function {
        Some(5) => vec![coil(address, second == 0xFF00)],
        Some(15) => (0..second)
            .map(|k| {
                let byte = pdu.get(6 + usize::from(k / 8)).copied().unwrap_or(0);
                coil(address + k, byte >> (k % 8) & 1 == 1)
            })
            .collect(),
        Some(6) => holding(address, second).into_iter().collect(),
        Some(16) => (0..second)
            .filter_map(|k| holding(address + k, word(6 + 2 * usize::from(k))))
            .collect(),
        _ => Vec::new(),
    }
}

/// Clients served at once; a client that connects while this many are connected is closed at
/// once (and counted).
pub const MAX_CLIENTS: usize = 16;
/// Seconds a client may stay silent (nothing received) before its connection is closed, unless
/// `--idle-timeout` says otherwise; a reply the client does not take within as long closes it
/// too.
pub const IDLE_SECONDS: f64 = 60.0;
/// The largest MBAP length field: the unit id and a PDU of 253 bytes (an ADU of 260 bytes, as
/// the Modbus/TCP implementation guide allows). A frame with a longer (or shorter than 2)
/// length, or a protocol id other than 0, closes the connection: its end cannot be known.
pub const MAX_LENGTH: usize = 254;

/// What the Modbus server did with its clients, for the summary.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ServerReport {
    /// Clients served at once at most ([`MAX_CLIENTS`]).
    pub max_clients: usize,
    /// The idle timeout, seconds.
    pub idle_timeout_s: f64,
    /// Connections accepted (served or not).
    pub clients: u64,
    /// Connections closed at once because [`MAX_CLIENTS`] were connected.
    pub refused_over_cap: u64,
    /// Connections closed after the idle timeout.
    pub closed_idle: u64,
    /// Connections closed at once because no thread could be started for them.
    pub spawn_failures: u64,
    /// Failed accepts, each followed by a pause (100 ms, doubling to 1 s while they go on).
    pub accept_errors: u64,
    /// Why the server stopped listening, if it did before the run's end (the run then stops
    /// and the program exits with status 1).
    pub listener_error: Option<String>,
}

/// The server threads' counts (see [`ServerReport`]).
#[derive(Debug, Default)]
struct Counters {
    active: AtomicUsize,
    clients: AtomicU64,
    refused: AtomicU64,
    idle: AtomicU64,
    spawn_failures: AtomicU64,
    accept_errors: AtomicU64,
}

/// Lowers the count of active clients when a client's thread ends (or its closure is dropped
/// without running, when the thread could not be started).
struct Active(Arc<Counters>);

impl Drop for Active {
    fn drop(&mut self) {
        self.0.active.fetch_sub(1, Ordering::SeqCst);
    }
}

/// A client's work, to be run on a thread of its own.
type Job = Box<dyn FnOnce() + Send>;

/// Whether an accept error means the listening socket itself is broken (no retry helps).
fn fatal(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        ErrorKind::InvalidInput | ErrorKind::Unsupported | ErrorKind::NotConnected
    )
}

/// Accepts clients until `accept` fails for good: each is served on a thread `spawn` starts,
/// unless [`MAX_CLIENTS`] are connected or no thread can be started (then it is closed at
/// once); a passing accept error (out of file descriptors, an aborted connection) is counted
/// and followed by a pause, so the loop never spins.
fn accept_loop(
    mut accept: impl FnMut() -> std::io::Result<TcpStream>,
    spawn: impl Fn(Job) -> std::io::Result<()>,
    state: &Arc<Mutex<Shared>>,
    counters: &Arc<Counters>,
    idle: Duration,
) -> Result<(), String> {
    let mut pause = Duration::from_millis(100);
    loop {
        let stream = match accept() {
            Ok(stream) => stream,
            Err(e) if fatal(&e) => {
                return Err(format!("cannot accept clients: {}", cli::io_message(&e)));
            }
            Err(_) => {
                counters.accept_errors.fetch_add(1, Ordering::SeqCst);
                std::thread::sleep(pause);
                pause = (pause * 2).min(Duration::from_secs(1));
                continue;
            }
        };
        pause = Duration::from_millis(100);
        counters.clients.fetch_add(1, Ordering::SeqCst);
        if counters.active.fetch_add(1, Ordering::SeqCst) >= MAX_CLIENTS {
            counters.active.fetch_sub(1, Ordering::SeqCst);
            counters.refused.fetch_add(1, Ordering::SeqCst);
            drop(stream);
            continue;
        }
        let active = Active(Arc::clone(counters));
        let (state, counters_of_client) = (Arc::clone(state), Arc::clone(counters));
        let job: Job = Box::new(move || {
            let _active = active;
            if let Err(Ended::Idle) = client(stream, &state, idle) {
                counters_of_client.idle.fetch_add(1, Ordering::SeqCst);
            }
        });
        // A job that cannot be started is dropped: its stream closes, `Active` counts down.
        if spawn(job).is_err() {
            counters.spawn_failures.fetch_add(1, Ordering::SeqCst);
        }
    }
}

/// Runs the PLC in real time for `seconds`, serving its images over Modbus/TCP at `address`
/// (announced on stderr, so `--json` stays clean) to at most [`MAX_CLIENTS`] clients at once,
/// each closed after `idle` seconds without a request; every request carried out is noted in
/// `t`. Returns what the server did; if it stopped listening, the run stops there and
/// [`ServerReport::listener_error`] says why.
///
/// # Errors
/// The address cannot be listened on, the server's thread cannot be started, or
/// [`Stop::Closed`] when stdout's reader has gone.
pub fn serve(
    sim: &mut Simulator,
    address: &str,
    seconds: f64,
    idle: f64,
    t: &mut Transcript,
) -> Result<ServerReport, Stop> {
    let listener = TcpListener::bind(address).map_err(|e| {
        cli::bad(
            "--modbus",
            format!("cannot listen on {address}: {}", cli::io_message(&e)),
        )
    })?;
    let local = listener
        .local_addr()
        .map_err(|e| cli::bad("--modbus", cli::io_message(&e)))?;
    let shared = Arc::new(Mutex::new(Shared::new()));
    let counters = Arc::new(Counters::default());
    let idle_time = Duration::from_secs_f64(idle);
    let (state, server_counters) = (Arc::clone(&shared), Arc::clone(&counters));
    let server = std::thread::Builder::new()
        .name("modbus listener".into())
        .spawn(move || {
            accept_loop(
                || listener.accept().map(|(stream, _)| stream),
                |job| {
                    std::thread::Builder::new()
                        .name("modbus client".into())
                        .stack_size(256 * 1024)
                        .spawn(job)
                        .map(drop)
                },
                &state,
                &server_counters,
                idle_time,
            )
        })
        .map_err(|e| format!("cannot start the Modbus server: {}", cli::io_message(&e)))?;
    // A test reads the address from this line.
    let _ = writeln!(
        std::io::stderr(),
        "Modbus/TCP on {local} (unit ids 0, 1, 255): discrete inputs 0-15 = inputs, 100-115 / 200-215 = output / input forced; coils 0-15 = outputs, 1000-1015 force inputs; input registers 0-18; holding 0-2 release forcing"
    );
    sim.plant.use_real_clock();
    let mut listener_error = None;
    let mut server = Some(server);
    let start = Instant::now();
    let period = Duration::from_millis(u64::from(PERIOD_MS));
    let mut next = start;
    while start.elapsed().as_secs_f64() < seconds {
        if server
            .as_ref()
            .is_some_and(std::thread::JoinHandle::is_finished)
            && let Some(handle) = server.take()
        {
            listener_error = Some(match handle.join() {
                Ok(Err(why)) => why,
                Ok(Ok(())) => "the server stopped listening".to_string(),
                Err(panic) => format!(
                    "the server failed: {}",
                    panic
                        .downcast_ref::<&str>()
                        .map(ToString::to_string)
                        .or_else(|| panic.downcast_ref::<String>().cloned())
                        .unwrap_or_else(|| "a panic".to_string())
                ),
            });
            break;
        }
        let requests: Vec<Request> = match shared.lock() {
            Ok(mut s) => s.take_requests(),
            Err(_) => return Err("the Modbus server thread failed".into()),
        };
        for r in requests {
            let line = format!(
                "modbus, cycle {}: {r}{}",
                sim.plc.cycle_count(),
                carry_out(sim, r)
            );
            t.note(line)?;
        }
        sim.run(1);
        if let Ok(mut s) = shared.lock() {
            s.publish(sim);
        }
        next += period;
        if let Some(wait) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
    }
    let count = |c: &AtomicU64| c.load(Ordering::SeqCst);
    Ok(ServerReport {
        max_clients: MAX_CLIENTS,
        idle_timeout_s: idle,
        clients: count(&counters.clients),
        refused_over_cap: count(&counters.refused),
        closed_idle: count(&counters.idle),
        spawn_failures: count(&counters.spawn_failures),
        accept_errors: count(&counters.accept_errors),
        listener_error,
    })
}

/// Carries out one request on the executive: nothing, or ` refused: why`.
pub fn carry_out(sim: &mut Simulator, r: Request) -> String {
    let result = match r {
        Request::ForceOutput(p, v) => sim.plc.force_output(p, v),
        Request::ForceInput(p, v) => sim.plc.force_input(p, v),
        Request::ReleaseOutput(p) => sim.plc.unforce_output(p),
        Request::ReleaseInput(p) => sim.plc.unforce_input(p),
        Request::ReleaseAll => {
            for p in 0..usize::from(map::POINTS) {
                let _ = sim.plc.unforce_input(p);
                let _ = sim.plc.unforce_output(p);
            }
            Ok(())
        }
    };
    result
        .err()
        .map(|e| format!(" refused: {e}"))
        .unwrap_or_default()
}

/// Copies the images, forcing and counters into the Modbus tables.
fn publish(sim: &Simulator, storage: &mut Storage) {
    let points = usize::from(map::POINTS);
    for p in 0..points {
        storage.discretes[usize::from(map::INPUTS) + p] = sim.plc.inputs().get(p);
        storage.discretes[usize::from(map::OUTPUT_FORCED) + p] =
            sim.plc.forced_outputs().forced(p).is_some();
        storage.discretes[usize::from(map::INPUT_FORCED) + p] =
            sim.plc.forced_inputs().forced(p).is_some();
        storage.coils[usize::from(map::OUTPUT_COILS) + p] = sim.plc.outputs().get(p);
        storage.coils[usize::from(map::INPUT_COILS) + p] =
            sim.plc.forced_inputs().forced(p).unwrap_or(false);
    }
    let st = sim.plc.stats();
    let t = sim.plant.tally;
    let clip = |v: u64| u16::try_from(v).unwrap_or(u16::MAX);
    let wide = |v: u64| {
        let v = u32::try_from(v).unwrap_or(u32::MAX);
        [(v >> 16) as u16, v as u16]
    };
    let mut values = Vec::with_capacity(usize::from(map::INPUT_REGISTERS));
    values.extend(wide(u64::from(sim.program.parts().unsigned_abs()))); // 0-1
    values.push(clip(u64::from(sim.program.jam_et()))); // 2
    values.extend(wide(st.cycles)); // 3-4
    values.extend(wide(st.overruns)); // 5-6
    values.push(clip(u64::from(
        st.load_per_mille(sim.plc.config().period_us),
    ))); // 7
    values.push(clip(sim.program.tracked() as u64)); // 8
    values.extend(wide(u64::from(t.good_passed))); // 9-10
    values.extend(wide(u64::from(t.bad_rejected))); // 11-12
    values.extend(wide(u64::from(t.bad_passed))); // 13-14
    values.extend(wide(u64::from(t.jams))); // 15-16
    values.push(clip(u64::from(st.last_us))); // 17
    values.push(clip(u64::from(st.jitter_us))); // 18
    storage.inputs[..values.len()].copy_from_slice(&values);
}

/// Why a client's connection ended.
#[derive(Debug)]
enum Ended {
    /// Nothing came for the idle timeout (or a reply was not taken within it).
    Idle,
    /// The client closed it, sent what is no Modbus/TCP frame, or the connection failed.
    Other,
}

impl From<std::io::Error> for Ended {
    fn from(e: std::io::Error) -> Ended {
        if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) {
            Ended::Idle
        } else {
            Ended::Other
        }
    }
}

/// Serves one Modbus/TCP client: one MBAP frame at a time, until the client closes, sends
/// something that is no Modbus/TCP frame, or stays silent for `idle`.
fn client(mut stream: TcpStream, state: &Mutex<Shared>, idle: Duration) -> Result<(), Ended> {
    stream.set_read_timeout(Some(idle))?;
    stream.set_write_timeout(Some(idle))?;
    // The MBAP header (7 bytes) and the largest PDU (253 bytes).
    let mut buf = [0u8; 6 + MAX_LENGTH];
    loop {
        stream.read_exact(&mut buf[..7])?;
        let Some(length) = frame_length(&buf[..7]) else {
            return Err(Ended::Other);
        };
        stream.read_exact(&mut buf[7..6 + length])?;
        match answer(&buf[..6 + length], state) {
            Answer::Reply(reply) => send(&mut stream, &reply, idle)?,
            Answer::Silent => {}
            Answer::Close => return Err(Ended::Other),
        }
    }
}

/// The length of the frame whose MBAP header (7 bytes) is `header`: the header's length field
/// plus 6, or `None` when it is no Modbus/TCP frame (a length above [`MAX_LENGTH`] or below 2,
/// a protocol id other than 0): the connection is closed, its end cannot be known.
#[must_use]
pub fn frame_length(header: &[u8]) -> Option<usize> {
    let length = usize::from(u16::from_be_bytes([*header.get(4)?, *header.get(5)?]));
    ((2..=MAX_LENGTH).contains(&length) && header.get(2..4)? == [0, 0]).then_some(length)
}

/// What the server does with one frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Answer {
    /// Sends this reply (a response or an exception).
    Reply(Vec<u8>),
    /// Sends nothing (a request that needs no response).
    Silent,
    /// Closes the connection.
    Close,
}

/// Answers one Modbus/TCP frame, `frame` (the MBAP header and the PDU its length field gives,
/// as [`frame_length`] found it): an exception for anything [`check`] refuses or a unit id
/// this server does not answer, else the response, with every point a write names queued for
/// the cycle ([`Shared::take_requests`]).
pub fn answer(frame: &[u8], state: &Mutex<Shared>) -> Answer {
    let (Some(&unit), Some(&function), Some(pdu)) = (frame.get(6), frame.get(7), frame.get(7..))
    else {
        return Answer::Close;
    };
    if frame.len() > 6 + MAX_LENGTH {
        return Answer::Close;
    }
    let verdict = if answers_unit(unit) {
        check(pdu)
    } else {
        Err(GATEWAY_TARGET_FAILED)
    };
    // What passed `check` is short (the map is small); rmodbus takes frames of 256 bytes.
    let mut frame_buf: ModbusFrameBuf = [0; 256];
    let verdict = verdict.and_then(|()| {
        frame_buf
            .get_mut(..frame.len())
            .ok_or(ILLEGAL_DATA_VALUE)?
            .copy_from_slice(frame);
        Ok(())
    });
    if let Err(code) = verdict {
        return Answer::Reply(exception(frame, function, code));
    }
    let asked = requests(pdu);
    // rmodbus answers unit 1; 0 and 255 are ours too (see answers_unit).
    frame_buf[6] = 1;
    let mut response = Vec::new();
    let mut parsed = ModbusFrame::new(1, &frame_buf, ModbusProto::TcpUdp, &mut response);
    if parsed.parse().is_err() {
        return Answer::Close;
    }
    if parsed.processing_required {
        let Ok(mut s) = state.lock() else {
            return Answer::Close;
        };
        let done = if parsed.readonly {
            parsed.process_read(&s.storage).is_ok()
        } else {
            let done = parsed.process_write(&mut s.storage).is_ok();
            // Every point the request names acts (module documentation), then the
            // holding registers, which are commands, read as 0 again.
            s.requests.extend(asked);
            s.storage.holdings[..3].fill(0);
            done
        };
        if !done {
            return Answer::Close;
        }
    }
    if !parsed.response_required {
        return Answer::Silent;
    }
    if parsed.finalize_response().is_err() {
        return Answer::Close;
    }
    if let Some(u) = response.get_mut(6) {
        *u = unit;
    }
    Answer::Reply(response)
}

/// Writes `bytes` within `idle` in all: a client that takes its reply a little at a time is
/// closed when the whole reply has not gone by then (a socket's write timeout alone restarts
/// with every partial write).
fn send(stream: &mut TcpStream, bytes: &[u8], idle: Duration) -> Result<(), Ended> {
    let deadline = Instant::now() + idle;
    let mut sent = 0;
    while sent < bytes.len() {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(Ended::Idle);
        }
        stream.set_write_timeout(Some(left))?;
        match stream.write(&bytes[sent..]) {
            Ok(0) => return Err(Ended::Other),
            Ok(n) => sent += n,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => return Err(e.into()),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> Arc<Mutex<Shared>> {
        Arc::new(Mutex::new(Shared::new()))
    }

    /// A client whose thread cannot be started is closed at once and counted; the loop goes
    /// on, and ends with the reason when accepting fails for good. No panic.
    #[test]
    fn a_client_without_a_thread_is_closed_and_counted() {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let address = listener.local_addr().unwrap();
        let mut peer = TcpStream::connect(address).unwrap();
        peer.set_read_timeout(Some(Duration::from_secs(3))).unwrap();
        let counters = Arc::new(Counters::default());
        let mut accepted = 0;
        let (mut errors, mut fatals) = (0, 0);
        let result = accept_loop(
            || {
                accepted += 1;
                match accepted {
                    1 => listener.accept().map(|(s, _)| s),
                    2 => {
                        errors += 1;
                        Err(std::io::Error::from_raw_os_error(24)) // EMFILE: passes
                    }
                    _ => {
                        fatals += 1;
                        Err(std::io::Error::from(ErrorKind::InvalidInput))
                    }
                }
            },
            |_job| Err(std::io::Error::from(ErrorKind::WouldBlock)),
            &state(),
            &counters,
            Duration::from_secs(1),
        );
        assert_eq!(
            result,
            Err("cannot accept clients: invalid input parameter".to_string())
        );
        assert_eq!((errors, fatals), (1, 1));
        assert_eq!(counters.spawn_failures.load(Ordering::SeqCst), 1);
        assert_eq!(counters.accept_errors.load(Ordering::SeqCst), 1);
        assert_eq!(counters.active.load(Ordering::SeqCst), 0);
        let mut byte = [0u8; 1];
        assert_eq!(peer.read(&mut byte).unwrap(), 0, "closed at once");
    }

    /// Every function not served is exception 1 whatever follows it; lengths decide nothing
    /// before the function does.
    #[test]
    fn the_function_is_checked_first() {
        for f in 0..=255u8 {
            for n in 0..=5 {
                let mut pdu = vec![f];
                pdu.extend_from_slice(&[0, 0, 0, 1, 2][..n]);
                let want = match (f, n) {
                    (1..=4 | 6, 4) => Ok(()),
                    (1..=6 | 15 | 16, _) => Err(ILLEGAL_DATA_VALUE),
                    _ => Err(ILLEGAL_FUNCTION),
                };
                assert_eq!(check(&pdu), want, "function {f:#04x}, {n} bytes");
            }
        }
        assert_eq!(check(&[]), Err(ILLEGAL_FUNCTION));
    }
}
