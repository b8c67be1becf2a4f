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
#[command(name = "microcomputer-plc", version)]
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
    /// With --modbus: seconds to run before stopping.
    #[arg(long, default_value_t = 30.0)]
    seconds: f64,
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
    /// Cycles shown in the timing diagram (the last ones).
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
    reports_run: usize,
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
                "no signal {s:?} (one of: {})",
                SIGNALS.map(|s| s.0).join(", ")
            ));
        }
    }
    if args.window == 0 {
        return Err("window must be at least 1 cycle".into());
    }
    let mut sim = Simulator::new(args.seed);
    let mut log = Vec::new();
    if let Some(address) = &args.modbus {
        if !(args.seconds.is_finite() && args.seconds > 0.0) {
            return Err(format!("seconds must be > 0, got {}", args.seconds));
        }
        serve(&mut sim, address, args.seconds, &mut log)?;
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
            if !execute(&mut sim, line, echo, &mut log)
                .map_err(|e| format!("script line {}: {e}", n + 1))?
            {
                break;
            }
        }
        if args.interactive {
            let stdin = std::io::stdin();
            if stdin.is_terminal() {
                eprintln!(
                    "monitor> (run N, step, cont, break …, force …, show, spool, stats, quit)"
                );
            }
            for line in stdin.lock().lines() {
                let line = line.map_err(|e| e.to_string())?;
                match execute(&mut sim, &line, !args.json, &mut log) {
                    Ok(true) => {}
                    Ok(false) => break,
                    Err(e) => println!("? {e}"),
                }
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
            reports_run: sim.reports.len(),
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
    echo: bool,
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
    if echo {
        println!("> {line}");
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
    ReleaseAll,
}

type Storage = ModbusStorage<1024, 16, 16, 16>;

struct Shared {
    storage: Storage,
    requests: Vec<Request>,
}

const INPUT_COILS: usize = 1000;

/// Runs the PLC in real time for `seconds`, serving its images over Modbus/TCP.
fn serve(
    sim: &mut Simulator,
    address: &str,
    seconds: f64,
    log: &mut Vec<String>,
) -> Result<(), String> {
    let listener =
        TcpListener::bind(address).map_err(|e| format!("cannot listen on {address}: {e}"))?;
    let local = listener.local_addr().map_err(|e| e.to_string())?;
    // On stderr, so that --json output stays clean; a test reads the address from here.
    eprintln!(
        "Modbus/TCP on {local}: discrete inputs 0-15 = inputs, coils 0-15 = outputs, coils 1000-1015 force inputs"
    );
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
                Request::ReleaseAll => {
                    for p in 0..16 {
                        let _ = sim.plc.unforce_input(p);
                        let _ = sim.plc.unforce_output(p);
                    }
                    Ok(())
                }
            };
            log.push(format!(
                "modbus: {r:?}{}",
                result
                    .err()
                    .map(|e| format!(" refused: {e}"))
                    .unwrap_or_default()
            ));
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

/// Copies the images and counters into the Modbus tables.
fn publish(sim: &Simulator, storage: &mut Storage) {
    for p in 0..16 {
        storage.discretes[p] = sim.plc.inputs().get(p);
        storage.coils[p] = sim.plc.outputs().get(p);
        storage.coils[INPUT_COILS + p] = sim.plc.forced_inputs().forced(p).unwrap_or(false);
    }
    let st = sim.plc.stats();
    let t = sim.plant.tally;
    let clip = |v: u64| u16::try_from(v).unwrap_or(u16::MAX);
    let values = [
        clip(u64::from(sim.program.parts().unsigned_abs())),
        clip(u64::from(sim.program.jam_et())),
        clip(st.cycles),
        clip(st.overruns),
        clip(u64::from(st.load_per_mille(sim.plc.config().period_us))),
        clip(sim.program.timers_waiting() as u64),
        clip(u64::from(t.good_passed)),
        clip(u64::from(t.bad_rejected)),
        clip(u64::from(t.bad_passed)),
        clip(u64::from(t.jams)),
    ];
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
        if !(2..=250).contains(&length) {
            return Err(format!("bad MBAP length {length}"));
        }
        stream
            .read_exact(&mut buf[7..6 + length])
            .map_err(|e| e.to_string())?;
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
                let before_hold = s.storage.holdings[0];
                frame
                    .process_write(&mut s.storage)
                    .map_err(|e| format!("{e:?}"))?;
                let mut requests = Vec::new();
                for p in 0..16 {
                    if s.storage.coils[p] != before_coils[p] || frame_writes_coil(&buf, p) {
                        requests.push(Request::ForceOutput(p, s.storage.coils[p]));
                    }
                    let q = INPUT_COILS + p;
                    if s.storage.coils[q] != before_coils[q] || frame_writes_coil(&buf, q) {
                        requests.push(Request::ForceInput(p, s.storage.coils[q]));
                    }
                }
                if s.storage.holdings[0] == 1 && before_hold != 1 {
                    requests.push(Request::ReleaseAll);
                    s.storage.holdings[0] = 0;
                }
                s.requests.extend(requests);
            }
        }
        if frame.response_required {
            frame.finalize_response().map_err(|e| format!("{e:?}"))?;
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

/// A timing diagram of the chosen signals over the last `window` cycles.
fn timing_diagram(sim: &Simulator, signals: &[String], window: usize) -> String {
    let trace = &sim.trace[sim.trace.len().saturating_sub(window)..];
    let (left, row, top) = (80.0, 34.0, 40.0);
    let width = 900.0;
    let plot = width - left - 20.0;
    let height = top + row * signals.len() as f64 + 40.0;
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" font-family=\"monospace\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{}\" y=\"22\" text-anchor=\"middle\" font-size=\"15\" font-family=\"sans-serif\">Timing diagram, cycles {}–{}</text>\n",
        width / 2.0,
        trace.first().map_or(0, |s| s.cycle),
        trace.last().map_or(0, |s| s.cycle)
    );
    let n = trace.len().max(1) as f64;
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
        "<text x=\"{left}\" y=\"{:.1}\" font-family=\"sans-serif\">one column = one {PERIOD_MS} ms cycle; blue inputs, red outputs</text>\n</svg>\n",
        height - 12.0
    ));
    svg
}
