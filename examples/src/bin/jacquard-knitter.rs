//! `jacquard-knitter`: the 1981 FSW-81 two-level system rebuilt on `regler-ring-transfer` — one
//! master feeding jacquard pattern bytes to knitting-machine boards through their refill rings,
//! over a lossy link, in simulated time or over real UDP sockets on 127.0.0.1.

use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, ValueEnum};
use regler_examples::cli::{self, Common, Out, Program, Stop};
use regler_examples::knitter::{self, Config, MAX_MACHINES, MAX_SECONDS, Sim, picture, terminal};
use regler_examples::outln;

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
    #[arg(long, default_value_t = 8, value_parser = cli::whole(1usize, MAX_MACHINES))]
    machines: usize,
    /// Needles per row (8–1000): one pattern byte each.
    #[arg(long, default_value_t = 200, value_parser = cli::whole(8u16, 1000))]
    needles: u16,
    /// Seconds to run (simulated, or real with --transport udp or --interactive; at most a day).
    #[arg(long, default_value_t = 60.0, allow_hyphen_values = true,
          value_parser = cli::real_above(0.0, MAX_SECONDS))]
    seconds: f64,
    /// Link time per byte in nanoseconds (a refill frame is 9 bytes plus its items).
    #[arg(long, default_value_t = 3_000, value_parser = cli::whole(1u64, 1_000_000))]
    byte_ns: u64,
    /// Items per refill frame at most (1: the source's byte per request; up to 64).
    #[arg(long, default_value_t = 1, value_parser = cli::whole(1u32, 64))]
    batch: u32,
    /// Probability that a frame is lost (each direction), 0–0.5.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true, value_parser = cli::real(0.0, 0.5))]
    loss: f64,
    /// Probability that a frame arrives twice, 0–0.5.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true, value_parser = cli::real(0.0, 0.5))]
    duplicate: f64,
    /// The master falls silent at START for SECONDS: `START:SECONDS` (START within the run).
    #[arg(long, value_parser = parse_fault, allow_hyphen_values = true)]
    master_fault: Option<(f64, f64)>,
    /// Needles without a word from the master before a board runs stand-alone (at most
    /// 32 767 − needles − 256: the board's counters must not drift half their range).
    #[arg(long, default_value_t = 100)]
    silence: u32,
    /// The machines' start count (a board keeps it in flash and increments it at every start):
    /// each start gets a boot number different from the one before.
    #[arg(long, default_value_t = 0)]
    start: u32,
    /// Rows per job (1–1000000).
    #[arg(long, default_value_t = 40, value_parser = cli::whole(1u32, knitter::MAX_JOB_ROWS))]
    job_rows: u32,
    /// How master and machines talk.
    #[arg(long, value_enum, default_value_t = Transport::Memory)]
    transport: Transport,
    /// Operator keys, timed: lines `SECONDS KEY` (L, O, S, F, P, T, C M J with a job 0–99, N
    /// for machine N's status, shift N, break), `#` comments; every time within the run.
    #[arg(long, value_name = "FILE")]
    script: Option<PathBuf>,
    /// Answer keys as they come, the run paced in real time (see --speed): typed at a terminal
    /// (no Enter), or one a line from a pipe (as in a script, without the time; the end of the
    /// input is break).
    #[arg(long, conflicts_with = "json")]
    interactive: bool,
    /// With --interactive: simulated seconds per real second (more than 0, at most 10000).
    #[arg(long, default_value_t = 1.0, requires = "interactive", allow_hyphen_values = true,
          value_parser = cli::real_above(0.0, 10_000.0))]
    speed: f64,
    /// Rows shown per machine in the picture (the last ones, 1–100000).
    #[arg(long, default_value_t = 300, value_parser = cli::whole(1usize, 100_000))]
    picture_rows: usize,
    #[command(flatten)]
    common: Common<Knitter>,
}

regler_examples::program!(Knitter, "jacquard-knitter", seed 1981, picture "jacquard-knitter.png", "png");

fn parse_fault(text: &str) -> Result<(f64, f64), String> {
    let (a, b) = text
        .split_once(':')
        .ok_or("expected START:SECONDS, e.g. 20:10")?;
    let start = cli::real(0.0, MAX_SECONDS)(a).map_err(|e| format!("START {e}"))?;
    let length = cli::real_above(0.0, MAX_SECONDS)(b).map_err(|e| format!("SECONDS {e}"))?;
    Ok((start, length))
}

fn main() -> ExitCode {
    cli::finish(Knitter::NAME, run(&Args::parse()))
}

fn run(args: &Args) -> Result<(), Stop> {
    let common = &args.common;
    let config = Config {
        machines: args.machines,
        needles: args.needles,
        seconds: args.seconds,
        seed: common.seed,
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
    let mut out = Out::new();
    let (summary, boards) = match args.transport {
        Transport::Udp => {
            if args.interactive || args.script.is_some() {
                return Err(cli::bad(
                    "--transport udp",
                    "runs the default jobs without a keyboard (no --script or --interactive)",
                ));
            }
            if !common.quiet && !common.json {
                let _ = writeln!(
                    std::io::stderr(),
                    "running {} machines over UDP on 127.0.0.1 for {} s …",
                    config.machines,
                    cli::number(config.seconds)
                );
            }
            knitter::run_udp(&config)?
        }
        Transport::Memory => {
            let script = match &args.script {
                Some(path) => {
                    let text = std::fs::read_to_string(path).map_err(|e| {
                        cli::bad(
                            "--script",
                            format!("cannot read {}: {}", path.display(), cli::io_message(&e)),
                        )
                    })?;
                    knitter::parse_script(&text, &config)
                        .map_err(|e| cli::bad(&format!("--script {}", path.display()), e))?
                }
                None => Vec::new(),
            };
            let mut sim = Sim::new(config.clone(), script)?;
            if args.interactive {
                terminal::run(&mut sim, args.speed, &mut out)?;
            } else {
                simulate(&mut sim, args);
            }
            (sim.summary(), sim.boards)
        }
    };
    if let Some(path) = common.picture() {
        picture::write_png(path, &summary, &boards, args.picture_rows)?;
    }
    if common.json {
        serde_json::to_writer_pretty(out.writer(), &summary)?;
        out.line("")?;
    } else {
        if !common.quiet && !args.interactive {
            for line in &summary.screen {
                out.line(line)?;
            }
        }
        out.line(&summary.table())?;
        if let Some(path) = common.picture() {
            outln!(out, "fabric: {}", path.display())?;
        }
    }
    out.flush()
}

/// The run in simulated time, a second at a time, with the progress bar.
fn simulate(sim: &mut Sim, args: &Args) {
    let seconds = args.seconds.ceil() as u64;
    let bar = cli::progress(
        seconds,
        "knitting",
        "s",
        args.common.quiet || args.common.json,
    );
    let mut second = 0u64;
    while !sim.finished() {
        second += 1;
        sim.run_until(second * 1_000_000_000);
        bar.set_position(second.min(seconds));
    }
    bar.finish_and_clear();
}
