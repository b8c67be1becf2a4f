//! `autonomous-controller`: the 1985 stand-alone PID controller of Lund on a simulated room or
//! tank, run in simulated time on `regler-pid`, operated through the source's terminal dialogue
//! and keypad (from a script, or typed on stdin with `--interactive`).

use std::io::{BufRead, IsTerminal};
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use regler_examples::autonomous::{
    self, Event, Input, Interface, ProcessKind, SimConfig, SimReport, parse_script,
};
use regler_examples::svg::{self, Series};

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
    #[arg(long)]
    script: Option<PathBuf>,
    /// Type terminal lines (or `keys …`, `night on`, `run SECONDS`, `quit`) on stdin.
    #[arg(long)]
    interactive: bool,
    /// Simulated seconds each interactive line advances the clock.
    #[arg(long, default_value_t = 600.0)]
    step_s: f64,
    /// How the controller starts.
    #[arg(long, value_enum, default_value_t = InterfaceArg::Terminal)]
    interface: InterfaceArg,
    /// Simulated hours.
    #[arg(long, default_value_t = 48.0)]
    hours: f64,
    /// Seed of the disturbances.
    #[arg(long, default_value_t = 1985)]
    seed: u64,
    /// Night set-back in scale units, used while the night input is on.
    #[arg(long, default_value_t = 3.0)]
    night_setback: f64,
    /// Outdoor compensation: feed the heat loss forward (room).
    #[arg(long)]
    outdoor_compensation: bool,
    /// Mean outdoor temperature, °C (room).
    #[arg(long, default_value_t = 0.0)]
    outdoor_mean: f64,
    /// Print the results as JSON.
    #[arg(long)]
    json: bool,
    /// Where to write the SVG picture.
    #[arg(long, default_value = "autonomous-controller.svg")]
    svg: PathBuf,
    /// Do not write the picture.
    #[arg(long)]
    no_svg: bool,
    /// No progress bar, and only the summary (not the operator's screen).
    #[arg(long, short)]
    quiet: bool,
}

fn main() -> ExitCode {
    regler_examples::finish("autonomous-controller", run(&Args::parse()))
}

fn run(args: &Args) -> Result<(), String> {
    let process = match args.process {
        ProcessArg::Room => ProcessKind::Room,
        ProcessArg::Tank => ProcessKind::Tank,
    };
    let interface = match args.interface {
        InterfaceArg::Terminal => Interface::Terminal,
        InterfaceArg::Keypad => Interface::Keypad,
    };
    let script = match (&args.script, args.interactive) {
        (Some(_), true) => return Err("--script and --interactive exclude each other".into()),
        (Some(path), false) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
            parse_script(&text)?
        }
        (None, true) => interactive_script(args)?,
        (None, false) => parse_script(autonomous::demo_script(process, interface))?,
    };
    let config = SimConfig {
        process,
        seed: args.seed,
        hours: args.hours,
        interface,
        night_setback: args.night_setback,
        outdoor_compensation: args.outdoor_compensation,
        outdoor_mean: args.outdoor_mean,
        script,
    };
    let bar = if args.quiet || args.json {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(1000)
    };
    bar.set_style(
        ProgressStyle::with_template("{spinner} simulating [{bar:40}] {percent}%")
            .map_err(|e| e.to_string())?,
    );
    let report = autonomous::run(&config, |f| bar.set_position((f * 1000.0) as u64))?;
    bar.finish_and_clear();
    if !args.no_svg {
        std::fs::write(&args.svg, picture(&report))
            .map_err(|e| format!("cannot write {}: {e}", args.svg.display()))?;
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?
        );
        return Ok(());
    }
    if !args.quiet {
        for s in &report.shown {
            for (i, line) in s.text.lines().enumerate() {
                if i == 0 {
                    println!("[{}] {line}", clock(s.t_s));
                } else {
                    println!("        {line}");
                }
            }
        }
        println!();
    }
    print!("{}", summary(&report));
    if !args.no_svg {
        println!("Picture: {}", args.svg.display());
    }
    Ok(())
}

/// Reads stdin lines as timed inputs, each `--step-s` after the one before: plain text is typed
/// at the terminal; `keys …`, `night on|off`, `outdoor D` as in scripts; `run S` only advances.
fn interactive_script(args: &Args) -> Result<Vec<Event>, String> {
    if !(args.step_s.is_finite() && args.step_s > 0.0) {
        return Err(format!("step-s must be > 0, got {}", args.step_s));
    }
    let stdin = std::io::stdin();
    if stdin.is_terminal() {
        eprintln!(
            "Type the answers to the start-up questions, then commands (Y, C, keys …, night on, run 3600, quit)."
        );
        for line in autonomous::terminal::Terminal::banner() {
            eprintln!("{line}");
        }
    }
    let mut events = Vec::new();
    let mut t = 0.0;
    let mut started = false;
    for line in stdin.lock().lines() {
        let line = line.map_err(|e| e.to_string())?;
        let trimmed = line.trim();
        if trimmed.eq_ignore_ascii_case("quit") {
            break;
        }
        if let Some(seconds) = trimmed.strip_prefix("run ") {
            t += seconds
                .trim()
                .parse::<f64>()
                .map_err(|_| format!("run takes seconds, got {seconds:?}"))?;
            continue;
        }
        let parsed = parse_script(&format!("0 {trimmed}"));
        let input = match parsed.ok().and_then(|mut e| e.pop()) {
            Some(e) if !matches!(e.input, Input::Term(_)) => e.input,
            _ => Input::Term(line.clone()),
        };
        events.push(Event { t_s: t, input });
        // Start-up answers all land at 0; the clock runs once the regulator has started.
        if started {
            t += args.step_s;
        } else if line.is_empty() {
            started = true;
        }
    }
    Ok(events)
}

fn clock(t: f64) -> String {
    let s = t.round() as u64;
    format!("{:02}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

fn summary(r: &SimReport) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let unit = match r.config.process {
        ProcessKind::Room => "°C",
        ProcessKind::Tank => "%",
    };
    let _ = writeln!(
        s,
        "Autonomous controller, {:?} process, {:.1} h simulated, seed {}",
        r.config.process, r.config.hours, r.config.seed
    );
    let _ = writeln!(s, "  IAE                {:.2} {unit}·h", r.iae_unit_hours);
    let _ = writeln!(
        s,
        "  overshoot          {:.1} % of the first step",
        r.overshoot_percent
    );
    match r.settling_time_s {
        Some(t) => {
            let _ = writeln!(s, "  settling time      {:.0} s ({})", t, clock(t));
        }
        None => {
            let _ = writeln!(s, "  settling time      not settled");
        }
    }
    let _ = writeln!(s, "  alarms             {}", r.alarms);
    let commits: Vec<String> = r.commits_s.iter().map(|t| clock(*t)).collect();
    let _ = writeln!(
        s,
        "  commits            {} at {}",
        commits.len(),
        commits.join(", ")
    );
    let _ = writeln!(s, "  samples            {}", r.samples);
    let _ = writeln!(s, "  controller faults  {}", r.faults);
    let _ = writeln!(s, "LCD at the end:\n{}", r.final_lcd);
    s
}

fn picture(r: &SimReport) -> String {
    let hours = |t: f64| t / 3600.0;
    let step = (r.trace.len() / 1500).max(1);
    let points = |f: fn(&autonomous::TracePoint) -> f64| -> Vec<(f64, f64)> {
        r.trace
            .iter()
            .step_by(step)
            .map(|p| (hours(p.t_s), f(p)))
            .collect()
    };
    let markers: Vec<f64> = r.commits_s.iter().map(|t| hours(*t)).collect();
    let unit = match r.config.process {
        ProcessKind::Room => "temperature (°C)",
        ProcessKind::Tank => "level (%)",
    };
    let top = svg::line_chart_marked(
        "Set-point and measurement",
        "hours",
        unit,
        &[
            Series {
                label: "set-point",
                colour: "#2c3e50",
                dashed: true,
                points: points(|p| p.setpoint),
            },
            Series {
                label: "measurement",
                colour: "#c0392b",
                dashed: false,
                points: points(|p| p.measurement),
            },
        ],
        &markers,
        "commit",
    );
    let bottom = svg::line_chart_marked(
        "Controller output",
        "hours",
        "output (V)",
        &[Series {
            label: "output Y",
            colour: "#2471a3",
            dashed: false,
            points: points(|p| p.output),
        }],
        &markers,
        "commit",
    );
    let bottom = bottom.replacen("<svg ", "<svg y=\"420\" ", 1);
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"720\" height=\"840\">\n{top}{bottom}</svg>\n"
    )
}
