//! `jacquard-knitter`: the 1981 FSW-81 two-level system rebuilt on `regler-ring-transfer` — one
//! master feeding jacquard pattern bytes to knitting-machine boards through their refill rings,
//! over a lossy link, in simulated time or over real UDP sockets on 127.0.0.1.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use clap::{Parser, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use regler_examples::knitter::{self, Config, Key, Sim, Summary};

#[derive(Clone, Copy, Debug, ValueEnum)]
enum Transport {
    /// Simulated time, the link modelled byte by byte (deterministic for a seed).
    Memory,
    /// Real time: the master and each machine a thread with its own UDP socket on 127.0.0.1.
    Udp,
}

/// Rebuilds the FSW-81 jacquard system for sock knitting machines (Tsinghua, 1981): a master
/// serving the machines' pattern rings by earliest deadline over a lossy, duplicating link; the
/// boards run on from their ROM pattern when the master falls silent. Operator keys (level 2):
/// L lock, O open, S flow, F jobs, P report, T parameters, C M J change machine M to job J after
/// the current one, 1–8 status, Shift 1–8 (! @ # $ % ^ & *) re-initialise an interface, B break.
#[derive(Debug, Parser)]
#[command(name = "jacquard-knitter", version)]
struct Args {
    /// Knitting machines (1–100).
    #[arg(long, default_value_t = 8)]
    machines: usize,
    /// Needles per row: one pattern byte each.
    #[arg(long, default_value_t = 200)]
    needles: u16,
    /// Seconds to run (simulated, or real with --transport udp or --interactive).
    #[arg(long, default_value_t = 60.0)]
    seconds: f64,
    /// Seed of the machines' speeds (120–140 rpm) and of the link's faults.
    #[arg(long, default_value_t = 1981)]
    seed: u64,
    /// Link time per byte in nanoseconds (a refill frame is 9 bytes plus its items).
    #[arg(long, default_value_t = 3_000)]
    byte_ns: u64,
    /// Items per refill frame at most (1: the source's byte per request).
    #[arg(long, default_value_t = 1)]
    batch: u32,
    /// Probability that a frame is lost (each direction).
    #[arg(long, default_value_t = 0.0)]
    loss: f64,
    /// Probability that a frame arrives twice.
    #[arg(long, default_value_t = 0.0)]
    duplicate: f64,
    /// The master falls silent at START for SECONDS: `START:SECONDS`.
    #[arg(long, value_parser = parse_fault)]
    master_fault: Option<(f64, f64)>,
    /// Needles without a word from the master before a board runs stand-alone (at most
    /// 32 767 − needles − 256: the board's counters must not drift half their range).
    #[arg(long, default_value_t = 100)]
    silence: u32,
    /// The machines' start count (a board keeps it in flash and increments it at every start):
    /// each start gets a boot number different from the one before.
    #[arg(long, default_value_t = 0)]
    start: u32,
    /// Rows per job.
    #[arg(long, default_value_t = 40)]
    job_rows: u32,
    /// How master and machines talk.
    #[arg(long, value_enum, default_value_t = Transport::Memory)]
    transport: Transport,
    /// Operator keys, timed: lines `SECONDS KEY` (L, O, S, F, P, T, C M J, N, shift N, break).
    #[arg(long)]
    script: Option<PathBuf>,
    /// Answer keys as they are typed, the run paced in real time (see --speed).
    #[arg(long)]
    interactive: bool,
    /// With --interactive: simulated seconds per real second.
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
    /// Where to write the fabric picture.
    #[arg(long, default_value = "jacquard-knitter.png")]
    png: PathBuf,
    /// Do not write the picture.
    #[arg(long)]
    no_picture: bool,
    /// Rows shown per machine (the last ones).
    #[arg(long, default_value_t = 300)]
    picture_rows: usize,
    /// No progress bar and no operator screen, only the summary.
    #[arg(long, short)]
    quiet: bool,
}

fn parse_fault(text: &str) -> Result<(f64, f64), String> {
    let (a, b) = text
        .split_once(':')
        .ok_or("expected START:SECONDS, e.g. 20:10")?;
    let a: f64 = a.trim().parse().map_err(|_| format!("bad start '{a}'"))?;
    let b: f64 = b.trim().parse().map_err(|_| format!("bad length '{b}'"))?;
    Ok((a, b))
}

fn main() -> ExitCode {
    regler_examples::finish("jacquard-knitter", run(&Args::parse()))
}

fn run(args: &Args) -> Result<(), String> {
    let config = Config {
        machines: args.machines,
        needles: args.needles,
        seconds: args.seconds,
        seed: args.seed,
        byte_ns: args.byte_ns,
        batch: args.batch,
        loss: args.loss,
        duplicate: args.duplicate,
        report_ns: 20_000,
        master_fault: args.master_fault,
        silence_needles: args.silence,
        job_rows: args.job_rows,
        start: args.start,
    };
    config.validate()?;
    if args.picture_rows == 0 || args.picture_rows > 100_000 {
        return Err(format!(
            "picture rows must be between 1 and 100000, got {}",
            args.picture_rows
        ));
    }
    let (summary, boards) = match args.transport {
        Transport::Udp => {
            if args.interactive || args.script.is_some() {
                return Err("--transport udp runs the default jobs without a keyboard (no --script or --interactive)".into());
            }
            if !args.quiet && !args.json {
                eprintln!(
                    "running {} machines over UDP on 127.0.0.1 for {} s …",
                    config.machines, config.seconds
                );
            }
            knitter::run_udp(&config)?
        }
        Transport::Memory => {
            let script = match &args.script {
                Some(path) => {
                    let text = std::fs::read_to_string(path)
                        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
                    knitter::parse_script(&text)?
                }
                None => Vec::new(),
            };
            let mut sim = Sim::new(config.clone(), script)?;
            if args.interactive {
                interactive(&mut sim, args)?;
            } else {
                simulate(&mut sim, args);
            }
            let summary = sim.summary();
            (summary, sim.boards)
        }
    };
    if !args.no_picture {
        knitter::write_png(&args.png, &boards, args.picture_rows)?;
    }
    report(&summary, args)
}

fn simulate(sim: &mut Sim, args: &Args) {
    let bar = if args.quiet || args.json {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(args.seconds.ceil() as u64)
    };
    if let Ok(style) =
        ProgressStyle::with_template("{spinner} knitting [{bar:40}] {pos}/{len} s ({eta} left)")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    let mut second = 0u64;
    while !sim.finished() {
        second += 1;
        sim.run_until(second * 1_000_000_000);
        bar.set_position(second.min(args.seconds.ceil() as u64));
    }
    bar.finish_and_clear();
}

const HELP: &str = "keys: L lock, O open, S flow, F jobs, P report, T parameters, C change job, 1-8 status, Shift 1-8 (! @ # $ % ^ & *) re-initialise, B break";

fn interactive(sim: &mut Sim, args: &Args) -> Result<(), String> {
    if !(args.speed.is_finite() && args.speed > 0.0 && args.speed <= 10_000.0) {
        return Err(format!(
            "speed must be between 0 and 10000, got {}",
            args.speed
        ));
    }
    let term = console::Term::stdout();
    println!("jacquard-knitter: {} machines; {HELP}", sim.boards.len());
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let term = console::Term::stdout();
        while let Ok(key) = term.read_key() {
            if tx.send(key).is_err() {
                break;
            }
        }
    });
    let start = Instant::now();
    let mut shown = 0;
    let mut pending_c: Vec<char> = Vec::new();
    let mut in_change = false;
    while !sim.finished() {
        let target = (start.elapsed().as_secs_f64() * args.speed * 1e9) as u64;
        sim.run_until(target);
        while let Ok(k) = rx.try_recv() {
            let ch = match k {
                console::Key::Char(c) => c,
                console::Key::Escape => 'b',
                _ => continue,
            };
            if in_change {
                if ch.is_ascii_digit() {
                    pending_c.push(ch);
                    let _ = term.write_str(&ch.to_string());
                }
                if pending_c.len() == 2 {
                    in_change = false;
                    let m = pending_c[0].to_digit(10).unwrap_or(0) as usize;
                    let j = pending_c[1].to_digit(10).unwrap_or(0);
                    pending_c.clear();
                    println!();
                    sim.key(Key::Change(m, j));
                }
                continue;
            }
            let key = match ch.to_ascii_lowercase() {
                'l' => Key::Lock,
                'o' => Key::Open,
                's' => Key::Flow,
                'f' => Key::Jobs,
                'p' => Key::Report,
                't' => Key::Parameters,
                'b' | 'q' => Key::Break,
                'c' => {
                    in_change = true;
                    let _ = term.write_str("C: machine, job (two digits): ");
                    continue;
                }
                d @ '1'..='9' => Key::Status(d.to_digit(10).unwrap_or(0) as usize),
                s => match "!@#$%^&*".find(s) {
                    Some(n) => Key::Reinit(n + 1),
                    None => {
                        println!("unknown key '{s}'; {HELP}");
                        continue;
                    }
                },
            };
            sim.key(key);
        }
        for line in &sim.keyboard.screen[shown..] {
            println!("{line}");
        }
        shown = sim.keyboard.screen.len();
        std::thread::sleep(Duration::from_millis(20));
    }
    Ok(())
}

fn report(summary: &Summary, args: &Args) -> Result<(), String> {
    use std::io::Write;
    let mut text = String::new();
    if args.json {
        text = serde_json::to_string_pretty(summary).map_err(|e| e.to_string())?;
    } else {
        if !args.quiet && !args.interactive {
            for line in &summary.screen {
                text.push_str(line);
                text.push('\n');
            }
        }
        text.push_str(&summary.table());
        if !args.no_picture {
            text.push_str(&format!("\nfabric: {}", args.png.display()));
        }
    }
    // A reader that stops early (`| head`) is not an error of ours.
    match writeln!(std::io::stdout().lock(), "{text}") {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(format!("cannot write: {e}")),
        _ => Ok(()),
    }
}
