//! `microcomputer-plc`: the 1989 Maribor / Metalna controller rebuilt as a soft-PLC on
//! `regler-scan-cycle`, running a conveyor section against a simulated plant. Drive it like the
//! source's simulator (run N cycles, step, continuous with breakpoints, show and force I/O,
//! spool, statistics) from a script, stdin, or over Modbus/TCP.

use std::io::{BufRead, IsTerminal, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use clap::Parser;
use regler_examples::plc::{self, PERIOD_MS, SIGNALS, Simulator};
use rmodbus::server::ModbusFrame;
use rmodbus::server::storage::ModbusStorage;
use rmodbus::{ModbusFrameBuf, ModbusProto};
use serde::Serialize;

/// Rebuilds the 1989 industrial microcomputer controller as a soft-PLC running a conveyor section
/// (start/stop, jam detector, part counter, reject gate from the timer register) against a
/// simulated plant. Monitor commands: run N, step, cont, break cycle N, break in|out POINT on|off,
/// clear breaks, force in|out POINT 0|1, unforce in|out POINT, show, spool, stats, quit. Points
/// are numbers or names (start, stop, part, bad, reset; motor, jam, gate, run).
#[derive(Debug, Parser)]
#[command(name = "microcomputer-plc", version, allow_negative_numbers = true)]
struct Args {
    /// Monitor commands, one a line (default: a built-in demonstration).
    #[arg(long)]
    script: Option<PathBuf>,
    /// Read monitor commands from stdin.
    #[arg(long)]
    interactive: bool,
    /// Serve the images over Modbus/TCP at this address (e.g. 127.0.0.1:5020) and run in real
    /// time: discrete inputs 0.. = inputs, coils 0.. = outputs (writing one forces it), coils
    /// 1000.. force inputs, input registers = counters, holding register 0 ← 1 releases all forces.
    #[arg(long)]
    modbus: Option<String>,
    /// With --modbus: seconds to run before stopping (it is an error without --modbus).
    #[arg(long)]
    seconds: Option<f64>,
    /// Seed of the plant.
    #[arg(long, default_value_t = 1989)]
    seed: u64,
    /// Print a JSON summary instead of the monitor's output.
    #[arg(long)]
    json: bool,
    /// Where to write the timing diagram.
    #[arg(long, default_value = "microcomputer-plc.svg")]
    svg: PathBuf,
    /// Do not write the picture.
    #[arg(long)]
    no_svg: bool,
    /// Signals in the timing diagram.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "start,part,bad,motor,jam,gate"
    )]
    signals: Vec<String>,
    /// Cycles shown in the timing diagram (the last ones, at most 100000).
    #[arg(long, default_value_t = 400)]
    window: usize,
    /// Only the summary.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Serialize)]
struct Summary {
    seed: u64,
    cycles: u64,
    parts: i32,
    tally: plc::Tally,
    stats: regler_scan_cycle::CycleStats,
    load_per_mille: u32,
    reports_run: u64,
    spool_waiting: usize,
    forced_inputs: Vec<(usize, bool)>,
    forced_outputs: Vec<(usize, bool)>,
    log: Vec<String>,
}

fn main() -> ExitCode {
    regler_examples::finish("microcomputer-plc", run(&Args::parse()))
}

fn run(args: &Args) -> Result<(), String> {
    for s in &args.signals {
        if !SIGNALS.iter().any(|(name, ..)| name == s) {
            return Err(format!(
                "no signal '{s}' (one of: {})",
                SIGNALS.map(|s| s.0).join(", ")
            ));
        }
    }
    if !(1..=plc::TRACE_CAP).contains(&args.window) {
        return Err(format!(
            "window must be between 1 and {} cycles, got {}",
            plc::TRACE_CAP,
            args.window
        ));
    }
    if args.seconds.is_some() && args.modbus.is_none() {
        return Err("--seconds only applies with --modbus (the real-time server)".into());
    }
    let mut sim = Simulator::new(args.seed);
    let mut log = Vec::new();
    if let Some(address) = &args.modbus {
        let seconds = args.seconds.unwrap_or(30.0);
        if !(seconds.is_finite() && seconds > 0.0 && seconds <= 86_400.0) {
            return Err(format!(
                "seconds must be between 0 and 86400, got {seconds}"
            ));
        }
        serve(
            &mut sim,
            address,
            seconds,
            &mut log,
            !args.quiet && !args.json,
        )?;
    } else {
        let commands: Vec<String> = match (&args.script, args.interactive) {
            (Some(_), true) => return Err("--script and --interactive exclude each other".into()),
            (Some(path), false) => std::fs::read_to_string(path)
                .map_err(|e| format!("cannot read {}: {e}", path.display()))?
                .lines()
                .map(str::to_string)
                .collect(),
            (None, false) => plc::DEMO_SCRIPT.lines().map(str::to_string).collect(),
            (None, true) => Vec::new(),
        };
        let echo = !args.quiet && !args.json;
        for (n, line) in commands.iter().enumerate() {
            if !execute(&mut sim, line, echo, true, &mut log)
                .map_err(|e| format!("script line {}: {e}", n + 1))?
            {
                break;
            }
        }
        if args.interactive {
            let stdin = std::io::stdin();
            // At a terminal the operator sees what they typed: no echo, a prompt instead.
            let terminal = stdin.is_terminal();
            let prompt = || {
                if terminal {
                    eprint!("monitor> ");
                    let _ = std::io::stderr().flush();
                }
            };
            if terminal {
                eprintln!("microcomputer-plc monitor: 'help' lists the commands, 'quit' ends.");
            }
            prompt();
            for line in stdin.lock().lines() {
                let line = line.map_err(|e| e.to_string())?;
                match execute(&mut sim, &line, !args.json, !terminal, &mut log) {
                    Ok(true) => {}
                    Ok(false) => break,
                    Err(e) => println!("? {e}"),
                }
                prompt();
            }
        }
    }
    if !args.no_svg {
        std::fs::write(&args.svg, timing_diagram(&sim, &args.signals, args.window))
            .map_err(|e| format!("cannot write {}: {e}", args.svg.display()))?;
    }
    let st = *sim.plc.stats();
    if args.json {
        let summary = Summary {
            seed: args.seed,
            cycles: sim.plc.cycle_count(),
            parts: sim.program.parts(),
            tally: sim.plant.tally,
            stats: st,
            load_per_mille: st.load_per_mille(sim.plc.config().period_us),
            reports_run: sim.reports_run,
            spool_waiting: sim.program.spool.len(),
            forced_inputs: sim.plc.forced_inputs().iter().collect(),
            forced_outputs: sim.plc.forced_outputs().iter().collect(),
            log,
        };
        println!(
            "{}",
            serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?
        );
    } else {
        print!("{}", sim.stats());
        if !args.no_svg {
            println!("Timing diagram: {}", args.svg.display());
        }
    }
    Ok(())
}

/// Runs one monitor command; `Ok(false)` for quit.
fn execute(
    sim: &mut Simulator,
    line: &str,
    print: bool,
    echo_command: bool,
    log: &mut Vec<String>,
) -> Result<bool, String> {
    let line = line.split('#').next().unwrap_or("").trim();
    if line.is_empty() {
        return Ok(true);
    }
    if line == "quit" {
        return Ok(false);
    }
    let out = sim.command(line)?;
    if print {
        if echo_command {
            println!("> {line}");
        }
        print!("{out}");
    }
    log.push(format!("> {line}"));
    log.extend(out.lines().map(str::to_string));
    Ok(true)
}

/// What a Modbus client asked of the monitor.
#[derive(Clone, Copy, Debug)]
enum Request {
    ForceOutput(usize, bool),
    ForceInput(usize, bool),
    ReleaseOutput(usize),
    ReleaseInput(usize),
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

struct Shared {
    storage: Storage,
    requests: Vec<Request>,
}

/// The Modbus map (documented in examples/README.md). Every address outside it is answered
/// with exception 2, ILLEGAL DATA ADDRESS.
mod map {
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

/// Modbus exception codes.
const ILLEGAL_FUNCTION: u8 = 1;
const ILLEGAL_DATA_ADDRESS: u8 = 2;
const ILLEGAL_DATA_VALUE: u8 = 3;
const GATEWAY_TARGET_FAILED: u8 = 0x0B;

/// The unit ids this server answers: 1 (its own), and 0 and 255, which the Modbus/TCP
/// implementation guide leaves to a server reached by its IP address. Others are answered with
/// exception 0x0B, as a gateway with no device behind that id.
fn answers_unit(unit: u8) -> bool {
    matches!(unit, 0 | 1 | 255)
}

/// Checks a request PDU against the specification and the map; the exception code if it fails.
/// Order as the specification's server state diagrams: function, quantity and byte count,
/// address range, value.
fn check(pdu: &[u8]) -> Result<(), u8> {
    let word = |i: usize| pdu.get(i..i + 2).map(|b| u16::from_be_bytes([b[0], b[1]]));
    let (Some(&function), Some(address)) = (pdu.first(), word(1)) else {
        return Err(ILLEGAL_DATA_VALUE);
    };
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
fn exception(frame: &[u8], function: u8, code: u8) -> Vec<u8> {
    let mut reply = frame[..4].to_vec(); // transaction id, protocol id
    reply.extend_from_slice(&3u16.to_be_bytes()); // unit id + 2 bytes of PDU
    reply.push(frame[6]);
    reply.push(function | 0x80);
    reply.push(code);
    reply
}

/// Runs the PLC in real time for `seconds`, serving its images over Modbus/TCP.
fn serve(
    sim: &mut Simulator,
    address: &str,
    seconds: f64,
    log: &mut Vec<String>,
    echo: bool,
) -> Result<(), String> {
    let listener =
        TcpListener::bind(address).map_err(|e| format!("cannot listen on {address}: {e}"))?;
    let local = listener.local_addr().map_err(|e| e.to_string())?;
    // On stderr, so that --json output stays clean; a test reads the address from here.
    eprintln!(
        "Modbus/TCP on {local} (unit ids 0, 1, 255): discrete inputs 0-15 = inputs, 100-115 / 200-215 = output / input forced; coils 0-15 = outputs, 1000-1015 force inputs; input registers 0-18; holding 0-2 release forcing"
    );
    sim.plant.use_real_clock();
    let shared = Arc::new(Mutex::new(Shared {
        storage: Storage::new(),
        requests: Vec::new(),
    }));
    let server_state = Arc::clone(&shared);
    std::thread::spawn(move || {
        for stream in listener.incoming().flatten() {
            let state = Arc::clone(&server_state);
            std::thread::spawn(move || {
                let _ = client(stream, &state);
            });
        }
    });
    let start = Instant::now();
    let period = Duration::from_millis(u64::from(PERIOD_MS));
    let mut next = start;
    while start.elapsed().as_secs_f64() < seconds {
        let requests: Vec<Request> = match shared.lock() {
            Ok(mut s) => std::mem::take(&mut s.requests),
            Err(_) => return Err("the Modbus server thread failed".into()),
        };
        for r in requests {
            let result = match r {
                Request::ForceOutput(p, v) => sim.plc.force_output(p, v).map_err(|e| e.to_string()),
                Request::ForceInput(p, v) => sim.plc.force_input(p, v).map_err(|e| e.to_string()),
                Request::ReleaseOutput(p) => sim.plc.unforce_output(p).map_err(|e| e.to_string()),
                Request::ReleaseInput(p) => sim.plc.unforce_input(p).map_err(|e| e.to_string()),
                Request::ReleaseAll => {
                    for p in 0..usize::from(map::POINTS) {
                        let _ = sim.plc.unforce_input(p);
                        let _ = sim.plc.unforce_output(p);
                    }
                    Ok(())
                }
            };
            let line = format!(
                "modbus, cycle {}: {r}{}",
                sim.plc.cycle_count(),
                result
                    .err()
                    .map(|e| format!(" refused: {e}"))
                    .unwrap_or_default()
            );
            if echo {
                println!("{line}");
            }
            log.push(line);
        }
        sim.run(1);
        if let Ok(mut s) = shared.lock() {
            publish(sim, &mut s.storage);
        }
        next += period;
        if let Some(wait) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
    }
    Ok(())
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
    values.push(clip(sim.program.timers_waiting() as u64)); // 8
    values.extend(wide(u64::from(t.good_passed))); // 9-10
    values.extend(wide(u64::from(t.bad_rejected))); // 11-12
    values.extend(wide(u64::from(t.bad_passed))); // 13-14
    values.extend(wide(u64::from(t.jams))); // 15-16
    values.push(clip(u64::from(st.last_us))); // 17
    values.push(clip(u64::from(st.jitter_us))); // 18
    storage.inputs[..values.len()].copy_from_slice(&values);
}

/// Serves one Modbus/TCP client: one MBAP frame at a time.
fn client(mut stream: TcpStream, state: &Mutex<Shared>) -> Result<(), String> {
    loop {
        let mut buf: ModbusFrameBuf = [0; 256];
        stream
            .read_exact(&mut buf[..7])
            .map_err(|e| e.to_string())?;
        let length = usize::from(u16::from_be_bytes([buf[4], buf[5]]));
        if !(2..=250).contains(&length) || buf[2..4] != [0, 0] {
            return Err(format!("not a Modbus/TCP frame (length {length})"));
        }
        stream
            .read_exact(&mut buf[7..6 + length])
            .map_err(|e| e.to_string())?;
        let unit = buf[6];
        let function = buf[7];
        let verdict = if answers_unit(unit) {
            check(&buf[7..6 + length])
        } else {
            Err(GATEWAY_TARGET_FAILED)
        };
        if let Err(code) = verdict {
            stream
                .write_all(&exception(&buf, function, code))
                .map_err(|e| e.to_string())?;
            continue;
        }
        // rmodbus answers unit 1; 0 and 255 are ours too (see answers_unit).
        buf[6] = 1;
        let mut response = Vec::new();
        let mut frame = ModbusFrame::new(1, &buf, ModbusProto::TcpUdp, &mut response);
        frame.parse().map_err(|e| format!("{e:?}"))?;
        if frame.processing_required {
            let mut s = state.lock().map_err(|_| "poisoned".to_string())?;
            if frame.readonly {
                frame
                    .process_read(&s.storage)
                    .map_err(|e| format!("{e:?}"))?;
            } else {
                let before_coils = s.storage.coils;
                frame
                    .process_write(&mut s.storage)
                    .map_err(|e| format!("{e:?}"))?;
                let mut requests = Vec::new();
                for p in 0..usize::from(map::POINTS) {
                    let out = usize::from(map::OUTPUT_COILS) + p;
                    if s.storage.coils[out] != before_coils[out] || frame_writes_coil(&buf, out) {
                        requests.push(Request::ForceOutput(p, s.storage.coils[out]));
                    }
                    let q = usize::from(map::INPUT_COILS) + p;
                    if s.storage.coils[q] != before_coils[q] || frame_writes_coil(&buf, q) {
                        requests.push(Request::ForceInput(p, s.storage.coils[q]));
                    }
                }
                // Holding registers are commands: act on what was written, then read as 0.
                if writes_holding(&buf, 0) && s.storage.holdings[0] == 1 {
                    requests.push(Request::ReleaseAll);
                }
                if writes_holding(&buf, 1) {
                    requests.push(Request::ReleaseOutput(usize::from(s.storage.holdings[1])));
                }
                if writes_holding(&buf, 2) {
                    requests.push(Request::ReleaseInput(usize::from(s.storage.holdings[2])));
                }
                s.storage.holdings[..3].fill(0);
                s.requests.extend(requests);
            }
        }
        if frame.response_required {
            frame.finalize_response().map_err(|e| format!("{e:?}"))?;
            if let Some(u) = response.get_mut(6) {
                *u = unit;
            }
            stream.write_all(&response).map_err(|e| e.to_string())?;
        }
    }
}

/// Whether a write-single-coil request (function 5) addresses `coil` (so that writing the value
/// a coil already has still forces it).
fn frame_writes_coil(buf: &[u8], coil: usize) -> bool {
    buf.get(7) == Some(&5)
        && buf
            .get(8..10)
            .map(|b| usize::from(u16::from_be_bytes([b[0], b[1]])))
            == Some(coil)
}

/// Whether a write request (function 6 or 16) writes holding register `register`.
fn writes_holding(buf: &[u8], register: u16) -> bool {
    let word = |i: usize| buf.get(i..i + 2).map(|b| u16::from_be_bytes([b[0], b[1]]));
    match (buf.get(7), word(8), word(10)) {
        (Some(6), Some(a), _) => a == register,
        (Some(16), Some(a), Some(n)) => {
            register >= a && u32::from(register) < u32::from(a) + u32::from(n)
        }
        _ => false,
    }
}

/// A timing diagram of the chosen signals over the last `window` cycles.
fn timing_diagram(sim: &Simulator, signals: &[String], window: usize) -> String {
    // The reject gate is what the program is for: the window ends a quarter of its width after
    // the last time the gate opened, so the bad part, the gate and its timing are in the picture.
    let gate = SIGNALS
        .iter()
        .find(|(name, ..)| *name == "gate")
        .map_or(2, |&(_, _, p)| p);
    let opened =
        |a: &plc::Sample, b: &plc::Sample| a.outputs >> gate & 1 == 0 && b.outputs >> gate & 1 == 1;
    let all: Vec<plc::Sample> = sim.trace.iter().copied().collect();
    let last_opening = all
        .windows(2)
        .rposition(|w| opened(&w[0], &w[1]))
        .map(|i| i + 1);
    let end = match last_opening {
        Some(i) => (i + window / 4 + 1)
            .min(all.len())
            .max(window.min(all.len())),
        None => all.len(),
    };
    let trace = &all[end.saturating_sub(window)..end];
    let caption = match last_opening.map(|i| all[i].cycle) {
        Some(c) => format!(
            "Timing diagram, cycles {}–{} (the reject gate last opened in cycle {c})",
            trace.first().map_or(0, |s| s.cycle),
            trace.last().map_or(0, |s| s.cycle)
        ),
        None => format!(
            "Timing diagram, cycles {}–{} (the reject gate did not open)",
            trace.first().map_or(0, |s| s.cycle),
            trace.last().map_or(0, |s| s.cycle)
        ),
    };
    let (left, row, top) = (80.0, 34.0, 40.0);
    let width = 900.0;
    let plot = width - left - 20.0;
    let height = top + row * signals.len() as f64 + 52.0;
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" font-family=\"monospace\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{}\" y=\"22\" text-anchor=\"middle\" font-size=\"15\" font-family=\"sans-serif\">{caption}</text>\n",
        width / 2.0,
    );
    let n = trace.len().max(1) as f64;
    // Cycle ticks: about eight, at round cycle numbers.
    if let (Some(first), Some(last)) = (trace.first(), trace.last()) {
        let span = (last.cycle - first.cycle).max(1);
        let raw = span as f64 / 8.0;
        let magnitude = 10f64.powf(raw.log10().floor());
        let step = [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|m| m * magnitude)
            .find(|s| *s >= raw)
            .unwrap_or(raw)
            .max(1.0) as u64;
        let axis = top + row * signals.len() as f64 + 4.0;
        let mut c = first.cycle.div_ceil(step) * step;
        while c <= last.cycle {
            let x = left + plot * (c - first.cycle) as f64 / n;
            svg.push_str(&format!(
                "<line x1=\"{x:.1}\" x2=\"{x:.1}\" y1=\"{top}\" y2=\"{axis:.1}\" stroke=\"#eee\"/><text x=\"{x:.1}\" y=\"{:.1}\" text-anchor=\"middle\" font-size=\"10\">{c}</text>\n",
                axis + 12.0
            ));
            c += step;
        }
    }
    for (k, name) in signals.iter().enumerate() {
        let Some(&(_, input, point)) = SIGNALS.iter().find(|(s, ..)| s == name) else {
            continue;
        };
        let base = top + row * (k as f64 + 1.0) - 8.0;
        svg.push_str(&format!(
            "<text x=\"8\" y=\"{base:.1}\">{}{name}</text>\n",
            if input { "in  " } else { "out " }
        ));
        let mut path = String::new();
        for (i, s) in trace.iter().enumerate() {
            let word = if input { s.inputs } else { s.outputs };
            let y = if word >> point & 1 == 1 {
                base - 18.0
            } else {
                base
            };
            let x0 = left + plot * i as f64 / n;
            let x1 = left + plot * (i + 1) as f64 / n;
            path.push_str(&format!(
                "{}{x0:.1},{y:.1} L{x1:.1},{y:.1} ",
                if i == 0 { "M" } else { "L" }
            ));
        }
        let colour = if input { "#2471a3" } else { "#c0392b" };
        svg.push_str(&format!(
            "<path d=\"{path}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"1.6\"/>\n"
        ));
        svg.push_str(&format!(
            "<line x1=\"{left}\" x2=\"{:.1}\" y1=\"{:.1}\" y2=\"{:.1}\" stroke=\"#eee\"/>\n",
            left + plot,
            base + 4.0,
            base + 4.0
        ));
    }
    svg.push_str(&format!(
        "<text x=\"{left}\" y=\"{:.1}\" font-family=\"sans-serif\">x: cycle number ({PERIOD_MS} ms each, {} cycles shown); blue inputs, red outputs; high = on</text>\n</svg>\n",
        height - 8.0,
        trace.len()
    ));
    svg
}
