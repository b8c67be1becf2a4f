//! `autonomous-controller`: the 1985 stand-alone PID controller of Lund on a simulated room or
//! tank, run in simulated time on `regler-pid`, operated through the source's terminal dialogue
//! and keypad (from a script, or typed on stdin with `--interactive`).

use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, ValueEnum};
use regler_examples::autonomous::json::Trace;
use regler_examples::autonomous::{
    self, Interface, ProcessKind, SimConfig, benchmark, interactive, picture, summary,
};
use regler_examples::cli::{self, Common, Out, Program, Stop};

#[derive(Clone, Copy, Debug, ValueEnum)]
enum ProcessArg {
    /// A room heated through a 30 min lag with 2 min dead time; outdoor temperature disturbs it.
    Room,
    /// A tank level, fast; its outflow valve moves every five minutes.
    Tank,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum InterfaceArg {
    /// Start-up questions at the terminal (the script's first `term` lines answer them).
    Terminal,
    /// Keypad only: the source's keypad start-up values.
    Keypad,
}

/// Rebuilds the 1985 autonomous PID controller (8052AH-BASIC, Lund) on a simulated process.
/// Operate it through the source's terminal dialogue or keypad with a timed --script, or type
/// at it with --interactive; without either it runs a built-in demonstration script.
#[derive(Debug, Parser)]
#[command(name = "autonomous-controller", version, allow_negative_numbers = true)]
struct Args {
    /// The simulated process.
    #[arg(long, value_enum, default_value_t = ProcessArg::Room)]
    process: ProcessArg,
    /// Timed input: lines `TIME term TEXT | keys KEYS | night on|off | outdoor DELTA`.
    #[arg(long, conflicts_with = "interactive")]
    script: Option<PathBuf>,
    /// Type terminal lines (or `keys …`, `night on`, `run SECONDS`, `quit`) on stdin; on a
    /// terminal the status line at the top of the screen stays live.
    #[arg(long)]
    interactive: bool,
    /// With --interactive: simulated seconds per real second (1 = real time; the default 60
    /// makes a minute of the room pass each second).
    #[arg(long, requires = "interactive", allow_hyphen_values = true,
          value_parser = cli::real_above(0.0, 1e6))]
    speed: Option<f64>,
    /// Seconds between the trace points of --json (at least one sample apart).
    #[arg(long, default_value_t = 60.0, allow_hyphen_values = true,
          value_parser = cli::real_above(0.0, 8760.0 * 3600.0))]
    trace_every: f64,
    /// How the controller starts.
    #[arg(long, value_enum, default_value_t = InterfaceArg::Terminal)]
    interface: InterfaceArg,
    /// Simulated hours [default: 48 for the room and with --interactive, 1 for the tank, whose
    /// demonstration is over in 30 minutes].
    #[arg(long, allow_hyphen_values = true, value_parser = cli::real_above(0.0, 8760.0))]
    hours: Option<f64>,
    /// Night set-back in scale units, used while the night input is on.
    #[arg(long, default_value_t = 3.0, allow_hyphen_values = true,
          value_parser = cli::real(0.0, 100.0))]
    night_setback: f64,
    /// Outdoor compensation: feed the heat loss forward (room).
    #[arg(long)]
    outdoor_compensation: bool,
    /// Mean outdoor temperature, °C (room).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true,
          value_parser = cli::real(-50.0, 50.0))]
    outdoor_mean: f64,
    /// Instead of the 1985 controller: tune automatically (relay → Ziegler–Nichols; step
    /// response → AMIGO, SIMC) on Åström and Hägglund's benchmark processes and judge each
    /// tuning (IAE for set-point and load steps, overshoot, Ms); a Markdown table, or --json.
    #[arg(long, conflicts_with_all = ["autotune", "interactive", "script", "three_point"])]
    tuning_benchmark: bool,
    /// Instead of the 1985 controller: run the relay auto-tuning experiment on the simulated
    /// process (--process), tune a PI by Ziegler–Nichols, hand over bumplessly and answer a
    /// set-point step; the limit cycle and the step in the picture.
    #[arg(long, conflicts_with_all = ["interactive", "script", "three_point"])]
    autotune: bool,
    /// Drive an increase/decrease (three-point) actuator with this full-stroke run time,
    /// seconds, instead of the 0–10 V output.
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true,
          value_parser = cli::real(5.0, 3600.0))]
    three_point: Option<f64>,
    #[command(flatten)]
    common: Common<Controller>,
}

regler_examples::program!(Controller, "autonomous-controller", seed 1985, picture "autonomous-controller.svg", "svg");

fn main() -> ExitCode {
    cli::finish(Controller::NAME, run(&Args::parse()))
}

fn run(args: &Args) -> Result<(), Stop> {
    let common = &args.common;
    let process = match args.process {
        ProcessArg::Room => ProcessKind::Room,
        ProcessArg::Tank => ProcessKind::Tank,
    };
    if args.tuning_benchmark {
        let found = benchmark::evaluate();
        return if common.json {
            cli::print(&serde_json::to_string_pretty(&found)?)
        } else {
            cli::print(benchmark::markdown(&found).trim_end())
        };
    }
    if args.autotune {
        let report = autonomous::autotune(process, common.seed, args.outdoor_mean)?;
        write_picture(common.picture(), || picture::autotune(&report))?;
        if common.json {
            return cli::print(&serde_json::to_string_pretty(&report)?);
        }
        cli::print(&summary::autotune_summary(&report))?;
        return picture_line(common.picture());
    }
    let interface = match args.interface {
        InterfaceArg::Terminal => Interface::Terminal,
        InterfaceArg::Keypad => Interface::Keypad,
    };
    let script = match (&args.script, args.interactive) {
        (Some(path), _) => {
            let text = std::fs::read_to_string(path).map_err(|e| {
                cli::bad(
                    "--script",
                    format!("cannot read {}: {}", path.display(), cli::io_message(&e)),
                )
            })?;
            autonomous::parse_script(&text)?
        }
        (None, true) => Vec::new(),
        (None, false) => autonomous::parse_script(autonomous::demo_script(process, interface))?,
    };
    let hours = args.hours.unwrap_or(match (process, args.interactive) {
        (ProcessKind::Tank, false) => 1.0,
        _ => 48.0,
    });
    let config = SimConfig {
        process,
        seed: common.seed,
        hours,
        interface,
        night_setback: args.night_setback,
        outdoor_compensation: args.outdoor_compensation,
        outdoor_mean: args.outdoor_mean,
        trace_every_s: args.trace_every,
        three_point_s: args.three_point,
        script,
    };
    let mut out = Out::new();
    let (report, trace) = if args.interactive {
        interactive::run(&config, args.speed.unwrap_or(60.0), common.json, &mut out)?
    } else {
        // Checked before the trace opens, so a refused run prints only its error.
        autonomous::controller::validate(&config)?;
        let bar = common.progress(100, "simulating", "%");
        if common.json {
            bar.finish_and_clear();
        }
        let mut trace = Trace::new(common.json.then_some(&mut out));
        let report = autonomous::run(
            &config,
            |f| bar.set_position((f * 100.0) as u64),
            |p| trace.point(p),
        );
        bar.finish_and_clear();
        (report?, trace)
    };
    for refusal in &report.refused {
        // A warning: the run went on (the question was asked again). Stderr closed: nobody to tell.
        let _ = writeln!(std::io::stderr(), "{}: {refusal}", Controller::NAME);
    }
    write_picture(common.picture(), || picture::run(&report))?;
    if common.json {
        return trace.finish(&report);
    }
    drop(trace);
    if !common.quiet && !args.interactive {
        for line in summary::transcript(&report.shown) {
            out.line(&line)?;
        }
        out.line("")?;
    }
    out.line(&summary::summary(&report))?;
    out.flush()?;
    picture_line(common.picture())
}

/// Writes the picture when there is to be one.
fn write_picture(path: Option<&std::path::Path>, svg: impl FnOnce() -> String) -> Result<(), Stop> {
    if let Some(path) = path {
        cli::write_picture(path, svg())?;
    }
    Ok(())
}

/// Says where the picture went.
fn picture_line(path: Option<&std::path::Path>) -> Result<(), Stop> {
    match path {
        Some(path) => cli::print(&format!("Picture: {}", path.display())),
        None => Ok(()),
    }
}
