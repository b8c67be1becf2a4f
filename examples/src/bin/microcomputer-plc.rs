//! `microcomputer-plc`: the 1989 Maribor / Metalna controller rebuilt as a soft-PLC on
//! `regler-scan-cycle`, running a conveyor section against a simulated plant. Drive it like the
//! source's simulator (run N cycles, step, continuous with breakpoints, show and force I/O,
//! spool, statistics) from a script, stdin, or over Modbus/TCP. The system is in
//! `regler_examples::plc`; this binary parses the arguments, runs it and prints.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use clap::builder::PossibleValuesParser;
use regler_examples::cli::{self, Common, Program, Stop};
use regler_examples::plc::monitor::{self, Transcript};
use regler_examples::plc::summary::{self, Summary};
use regler_examples::plc::{DEMO_SCRIPT, SIGNALS, Simulator, TRACE_CAP, modbus, picture};

/// Rebuilds the 1989 industrial microcomputer controller as a soft-PLC running a conveyor section
/// (start/stop, jam detector, part counter, reject gate set by bad parts tracked by the belt
/// encoder's pulses) against a simulated plant. Monitor commands: run N, step, cont, break cycle N, break in|out POINT on|off,
/// clear breaks, force in|out POINT 0|1, unforce in|out POINT, powerfail MS, show, spool, stats,
/// help, quit.
/// Points are numbers or names (start, stop, part, bad, reset; motor, jam, gate, run).
#[derive(Debug, Parser)]
#[command(
    name = "microcomputer-plc",
    version,
    allow_negative_numbers = true,
    mut_arg("quiet", |a| a.help(
        "Only the summary: the script's (or demonstration's) output and the Modbus requests are \
         not printed (the interactive monitor still answers)"
    ))
)]
struct Args {
    /// Monitor commands, one a line (default: a built-in demonstration).
    #[arg(long, value_name = "FILE", conflicts_with = "interactive")]
    script: Option<PathBuf>,
    /// Read monitor commands from stdin.
    #[arg(long)]
    interactive: bool,
    /// Serve the images over Modbus/TCP at this address (e.g. 127.0.0.1:5020) and run in real
    /// time: discrete inputs 0.. = inputs, coils 0.. = outputs, coils 1000.. = forced inputs
    /// (functions 5 and 15 force every coil they write), input registers = counters, holding
    /// registers 0-2 release forcing (functions 6 and 16: each register written acts).
    #[arg(long, value_name = "ADDRESS", conflicts_with_all = ["script", "interactive"])]
    modbus: Option<String>,
    /// With --modbus: seconds to run before stopping (more than 0, at most 86400; default 30).
    #[arg(long, value_parser = cli::real_above(0.0, 86_400.0))]
    seconds: Option<f64>,
    /// With --modbus: close a client's connection after this many seconds in which nothing
    /// came from it (more than 0, at most 86400; default 60). At most 16 clients are served at
    /// once: one more is closed at once.
    #[arg(long, value_name = "SECONDS", value_parser = cli::real_above(0.0, 86_400.0))]
    idle_timeout: Option<f64>,
    /// Signals in the timing diagram, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "start,part,bad,motor,jam,gate",
        value_parser = PossibleValuesParser::new(SIGNALS.map(|s| s.0)),
        conflicts_with = "no_picture"
    )]
    signals: Vec<String>,
    /// Cycles in the timing diagram (1 to 100000): the window ends a quarter of its width after
    /// the reject gate last opened (the last cycles if it never opened, or if the run is shorter
    /// than the window).
    #[arg(long, default_value_t = 400, value_parser = cli::whole(1, TRACE_CAP),
          conflicts_with = "no_picture")]
    window: usize,
    #[command(flatten)]
    common: Common<Plc>,
}

regler_examples::program!(Plc, "microcomputer-plc", seed 1989, picture "microcomputer-plc.svg", "svg");

fn main() -> ExitCode {
    cli::finish(Plc::NAME, run(&Args::parse()))
}

fn run(args: &Args) -> Result<(), Stop> {
    if args.seconds.is_some() && args.modbus.is_none() {
        return Err(cli::bad(
            "--seconds",
            "only applies with --modbus (the real-time server)",
        ));
    }
    if args.idle_timeout.is_some() && args.modbus.is_none() {
        return Err(cli::bad(
            "--idle-timeout",
            "only applies with --modbus (the real-time server)",
        ));
    }
    let seed = args.common.seed;
    let mut sim = Simulator::new(seed);
    let json = args.common.json;
    if let Some(address) = &args.modbus {
        let mut t = Transcript::new(!args.common.quiet && !json);
        let idle = args.idle_timeout.unwrap_or(modbus::IDLE_SECONDS);
        let report = modbus::serve(
            &mut sim,
            address,
            args.seconds.unwrap_or(30.0),
            idle,
            &mut t,
        )?;
        let stopped = report.listener_error.clone();
        finish(args, &sim, t, Some(report))?;
        match stopped {
            Some(why) => Err(Stop::Error(format!(
                "the Modbus server stopped early: {why}"
            ))),
            None => Ok(()),
        }
    } else if args.interactive {
        // The monitor answers whatever --quiet says: it is a dialogue.
        let mut t = Transcript::new(!json);
        let stdin = std::io::stdin();
        let terminal = stdin.is_terminal();
        monitor::run_stdin(&mut sim, stdin.lock(), terminal, &mut t)?;
        finish(args, &sim, t, None)
    } else {
        let mut t = Transcript::new(!args.common.quiet && !json);
        let script = match &args.script {
            Some(path) => std::fs::read(path).map_err(|e| {
                cli::bad(
                    "--script",
                    format!("cannot read {}: {}", path.display(), cli::io_message(&e)),
                )
            })?,
            None => DEMO_SCRIPT.as_bytes().to_vec(),
        };
        monitor::run_script(&mut sim, &script, &mut t)?;
        finish(args, &sim, t, None)
    }
}

/// The picture, then the JSON summary or the closing text.
fn finish(
    args: &Args,
    sim: &Simulator,
    mut t: Transcript,
    server: Option<modbus::ServerReport>,
) -> Result<(), Stop> {
    let picture = args.common.picture();
    if let Some(path) = picture {
        let svg = picture::timing_diagram(sim, &args.signals, args.window, args.common.seed);
        cli::write_picture(path, svg)?;
    }
    if args.common.json {
        let mut summary = Summary::new(sim, args.common.seed, std::mem::take(&mut t.log));
        summary.modbus = server;
        let text = serde_json::to_string_pretty(&summary)?;
        t.out().line(&text)?;
    } else {
        let text = summary::closing(sim, &t, server.as_ref(), picture);
        t.out().text(&text)?;
    }
    t.out().flush()
}
