//! `autonomous-controller`: the 1985 stand-alone PID controller of Lund on a simulated room or
//! tank, run in simulated time on `regler-pid`, operated through the source's terminal dialogue
//! and keypad (from a script, or typed on stdin with `--interactive`).

use std::io::{BufRead, IsTerminal, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use clap::{Parser, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use regler_examples::autonomous::terminal::Terminal;
use regler_examples::autonomous::{
    self, Input, Interface, ProcessKind, Shown, Sim, SimConfig, SimReport, TracePoint, parse_script,
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
    /// With --interactive: simulated seconds per real second (1 = real time; the default 60
    /// makes a minute of the room pass each second).
    #[arg(long, default_value_t = 60.0)]
    speed: f64,
    /// Seconds between the trace points of --json (at least one sample apart).
    #[arg(long, default_value_t = 60.0)]
    trace_every: f64,
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
    /// Instead of the 1985 controller: tune automatically (relay → Ziegler–Nichols; step
    /// response → AMIGO, SIMC) on Åström and Hägglund's benchmark processes and judge each
    /// tuning (IAE for set-point and load steps, overshoot, Ms); a Markdown table, or --json.
    #[arg(long)]
    tuning_benchmark: bool,
    /// Instead of the 1985 controller: run the relay auto-tuning experiment on the simulated
    /// process (--process), tune a PI by Ziegler–Nichols, hand over bumplessly and answer a
    /// set-point step; the limit cycle and the step in the SVG.
    #[arg(long)]
    autotune: bool,
    /// Drive an increase/decrease (three-point) actuator with this full-stroke run time,
    /// seconds, instead of the 0–10 V output.
    #[arg(long, value_name = "SECONDS")]
    three_point: Option<f64>,
}

fn main() -> ExitCode {
    regler_examples::finish("autonomous-controller", run(&Args::parse()))
}

fn run(args: &Args) -> Result<(), String> {
    if args.autotune {
        let kind = match args.process {
            ProcessArg::Room => ProcessKind::Room,
            ProcessArg::Tank => ProcessKind::Tank,
        };
        let report = autonomous::autotune(kind, args.seed, args.outdoor_mean)?;
        if !args.no_svg {
            std::fs::write(&args.svg, autotune_picture(&report))
                .map_err(|e| format!("cannot write {}: {e}", args.svg.display()))?;
        }
        let text = if args.json {
            serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?
        } else {
            let mut text = autotune_summary(&report);
            if !args.no_svg {
                text.push_str(&format!("\nPicture: {}", args.svg.display()));
            }
            text
        };
        use std::io::Write;
        return match writeln!(std::io::stdout().lock(), "{text}") {
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
                Err(format!("cannot write: {e}"))
            }
            _ => Ok(()),
        };
    }
    if args.tuning_benchmark {
        let found = autonomous::benchmark::evaluate();
        let text = if args.json {
            serde_json::to_string_pretty(&found).map_err(|e| e.to_string())?
        } else {
            autonomous::benchmark::markdown(&found)
        };
        use std::io::Write;
        return match writeln!(std::io::stdout().lock(), "{text}") {
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
                Err(format!("cannot write: {e}"))
            }
            _ => Ok(()),
        };
    }
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
        (None, true) => Vec::new(),
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
        trace_every_s: args.trace_every,
        three_point_s: args.three_point,
        script,
    };
    let report = if args.interactive {
        interactive(args, &config)?
    } else {
        batch(args, &config)?
    };
    if !args.no_svg {
        std::fs::write(&args.svg, picture(&report))
            .map_err(|e| format!("cannot write {}: {e}", args.svg.display()))?;
    }
    if args.json {
        // The trace went out as it was computed; the rest of the report closes the object.
        let Ok(serde_json::Value::Object(fields)) = serde_json::to_value(&report) else {
            return Err("the report did not serialize".into());
        };
        let mut out = std::io::stdout().lock();
        for (key, value) in fields {
            let _ = writeln!(out, ",\n  \"{key}\": {value}");
        }
        let _ = writeln!(out, "}}");
        return Ok(());
    }
    if !args.quiet && !args.interactive {
        print_shown(&report.shown);
        println!();
    }
    print!("{}", summary(&report));
    if !args.no_svg {
        println!("Picture: {}", args.svg.display());
    }
    Ok(())
}

/// Writes trace points as JSON array elements on stdout as they come: `{"trace": [` first,
/// then each point; the caller closes the array and adds the rest of the report.
struct TraceWriter {
    on: bool,
    first: bool,
}

impl TraceWriter {
    fn new(on: bool) -> TraceWriter {
        if on {
            print!("{{\n  \"trace\": [");
        }
        TraceWriter { on, first: true }
    }

    fn point(&mut self, p: &TracePoint) {
        if self.on {
            let sep = if self.first { "\n    " } else { ",\n    " };
            self.first = false;
            print!("{sep}{}", serde_json::to_string(p).unwrap_or_default());
        }
    }

    fn close(&self) {
        if self.on {
            print!("\n  ]");
        }
    }
}

/// The whole run from its script, with a progress bar.
fn batch(args: &Args, config: &SimConfig) -> Result<SimReport, String> {
    let bar = if args.quiet || args.json {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(1000)
    };
    bar.set_style(
        ProgressStyle::with_template("{spinner} simulating [{bar:40}] {percent}%")
            .map_err(|e| e.to_string())?,
    );
    // Checked before the trace array is opened, so a refused run prints only its error.
    if !(args.trace_every.is_finite() && args.trace_every > 0.0) {
        return Err(format!(
            "trace-every must be more than 0 seconds, got {}",
            args.trace_every
        ));
    }
    let mut writer = None;
    let report = autonomous::run(
        config,
        |f| bar.set_position((f * 1000.0) as u64),
        |p| {
            writer
                .get_or_insert_with(|| TraceWriter::new(args.json))
                .point(p)
        },
    );
    bar.finish_and_clear();
    let report = report?;
    writer
        .unwrap_or_else(|| TraceWriter::new(args.json))
        .close();
    Ok(report)
}

/// Prints lines the operator saw, each with its simulated time.
fn print_shown(shown: &[Shown]) {
    for s in shown {
        for (i, line) in s.text.lines().enumerate() {
            if i == 0 {
                println!("[{}] {line}", clock(s.t_s));
            } else {
                println!("        {line}");
            }
        }
    }
}

/// The controller at a terminal: each question, reply, status line and LCD as the operator
/// types, the plant running meanwhile at `--speed` times real time. Plain lines are typed at the
/// terminal; `keys …`, `night on|off` and `outdoor D` as in scripts; `run S` skips S simulated
/// seconds ahead; `quit` (or the end of input) ends the run.
fn interactive(args: &Args, config: &SimConfig) -> Result<SimReport, String> {
    if !(args.speed.is_finite() && args.speed > 0.0 && args.speed <= 1e6) {
        return Err(format!(
            "speed must be more than 0 and at most 1000000, got {}",
            args.speed
        ));
    }
    let (tx, rx) = mpsc::channel::<String>();
    std::thread::spawn(move || {
        for line in std::io::stdin().lock().lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let tty = std::io::stdin().is_terminal();
    let say = |lines: &[String]| {
        let mut out = std::io::stdout().lock();
        for line in lines {
            let _ = writeln!(out, "{line}");
        }
        let _ = out.flush();
    };
    if tty {
        say(&["Answer the start-up questions; then Y (change mode), C (acknowledge), an empty line (status), keys …, night on|off, outdoor D, run SECONDS, quit.".into()]);
    }
    let mut terminal = Terminal::new();
    let mut transcript: Vec<Shown> = Vec::new();
    let startup = match config.interface {
        Interface::Keypad => autonomous::keypad_startup(config.process)?,
        Interface::Terminal => {
            say(&Terminal::banner());
            loop {
                let Ok(line) = rx.recv() else {
                    return Err("input ended before the start-up dialogue was finished".into());
                };
                if line.trim().eq_ignore_ascii_case("quit") {
                    return Err("quit during the start-up dialogue".into());
                }
                if !tty {
                    say(&[format!("> {line}")]);
                }
                transcript.push(Shown {
                    t_s: 0.0,
                    text: format!("> {line}"),
                });
                let (out, done) = terminal.startup_line(&line);
                say(&out);
                transcript.extend(out.into_iter().map(|text| Shown { t_s: 0.0, text }));
                if let Some(startup) = done {
                    break startup;
                }
            }
        }
    };
    let mut sim = Sim::new(config, startup, terminal)?;
    sim.shown = transcript;
    let end = config.hours * 3600.0;
    let started = Instant::now();
    let mut skipped = 0.0;
    let mut writer = TraceWriter::new(args.json);
    let mut trace = |p: &TracePoint| writer.point(p);
    say(&[format!("[{}] {}", clock(sim.now()), sim.status())]);
    while sim.now() < end {
        // The plant runs at `speed` times real time, plus what `run S` skipped.
        let target = (started.elapsed().as_secs_f64() * args.speed + skipped).min(end);
        while sim.now() < target {
            sim.advance(&mut trace);
        }
        let line = match rx.recv_timeout(Duration::from_millis(20)) {
            Ok(line) => line,
            Err(mpsc::RecvTimeoutError::Timeout) => continue,
            Err(mpsc::RecvTimeoutError::Disconnected) => break,
        };
        let trimmed = line.trim();
        if trimmed.eq_ignore_ascii_case("quit") {
            break;
        }
        if let Some(seconds) = trimmed.strip_prefix("run ") {
            match seconds.trim().parse::<f64>() {
                Ok(s) if s.is_finite() && s >= 0.0 => skipped += s,
                _ => say(&[format!("run takes seconds, got '{}'", seconds.trim())]),
            }
            continue;
        }
        let input = match parse_script(&format!("0 {trimmed}"))
            .ok()
            .and_then(|mut e| e.pop())
        {
            Some(e) if !matches!(e.input, Input::Term(_)) => e.input,
            _ => Input::Term(line.clone()),
        };
        let from = sim.shown.len();
        sim.input(&input);
        let mut lines = Vec::new();
        for s in &sim.shown[from..] {
            if tty && s.text.starts_with("> ") {
                continue; // the operator sees what they typed
            }
            for (i, text) in s.text.lines().enumerate() {
                lines.push(if i == 0 {
                    format!("[{}] {text}", clock(s.t_s))
                } else {
                    format!("        {text}")
                });
            }
        }
        lines.push(format!("[{}] {}", clock(sim.now()), sim.status()));
        say(&lines);
    }
    writer.close();
    Ok(sim.report(config))
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
        "Autonomous controller, {} process, {:.1} h simulated, seed {}",
        match r.config.process {
            ProcessKind::Room => "room",
            ProcessKind::Tank => "tank",
        },
        r.config.hours,
        r.config.seed
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
    let points = |f: fn(&autonomous::TracePoint) -> Option<f64>| -> Vec<(f64, f64)> {
        r.picture
            .iter()
            .filter_map(|p| f(p).map(|v| (hours(p.t_s), v)))
            .collect()
    };
    let markers: Vec<f64> = r.commits_s.iter().map(|t| hours(*t)).collect();
    let unit = match r.config.process {
        ProcessKind::Room => "temperature (°C)",
        ProcessKind::Tank => "level (%)",
    };
    let top_series = vec![
        Series {
            label: "set-point",
            colour: "#2c3e50",
            dashed: true,
            points: points(|p| Some(p.setpoint)),
        },
        Series {
            label: "measurement",
            colour: "#c0392b",
            dashed: false,
            points: points(|p| Some(p.measurement)),
        },
    ];
    // The outdoor temperature is what outdoor compensation acts on: a panel of its own when it
    // is on (on the room's axis it would squeeze the room's band flat).
    let outdoor = r.config.outdoor_compensation.then(|| {
        svg::line_chart_fitted(
            "Outdoor temperature (fed forward)",
            "hours",
            "temperature (°C)",
            &[Series {
                label: "outdoor",
                colour: "#7f8c8d",
                dashed: false,
                points: points(|p| p.outdoor),
            }],
            &markers,
            "commit",
        )
    });
    let top = svg::line_chart_fitted(
        "Set-point and measurement",
        "hours",
        unit,
        &top_series,
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
            points: points(|p| Some(p.output)),
        }],
        &markers,
        "commit",
    );
    let (middle, below) = match outdoor {
        Some(chart) => (chart.replacen("<svg ", "<svg y=\"420\" ", 1), 840),
        None => (String::new(), 420),
    };
    let bottom = bottom.replacen("<svg ", &format!("<svg y=\"{below}\" "), 1);
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"720\" height=\"{}\">\n{top}{middle}{bottom}</svg>\n",
        below + 420
    )
}

fn autotune_summary(r: &autonomous::AutotuneReport) -> String {
    let unit = match r.process {
        ProcessKind::Room => "°C",
        ProcessKind::Tank => "%",
    };
    match &r.ultimate {
        Err(e) => format!(
            "relay experiment on the {:?}: failed after {:.0} s: {e}",
            r.process, r.experiment_s
        ),
        Ok((ku, tu)) => format!(
            "relay experiment on the {:?}: output {:.1} ± {:.1} V, hysteresis {} {unit}\n  \
             limit cycle after {:.0} s: Ku = {ku:.3} V/{unit}, Tu = {tu:.0} s\n  \
             Ziegler–Nichols PI: K = {:.3} V/{unit}, Ti = {:.0} s; hand-over jump {:.3} V\n  \
             set-point step of {} {unit}: overshoot {:.0} %, within 5 % after {}",
            r.process,
            r.bias_v,
            r.relay_v,
            r.hysteresis,
            r.experiment_s,
            r.k,
            r.ti,
            r.handover_jump_v,
            r.step,
            r.overshoot_pct,
            r.settling_s
                .map_or("never".to_string(), |s| format!("{s:.0} s")),
        ),
    }
}

fn autotune_picture(r: &autonomous::AutotuneReport) -> String {
    let (scale, unit) = match r.process {
        ProcessKind::Room => (60.0, "minutes"),
        ProcessKind::Tank => (1.0, "seconds"),
    };
    let x = |t: f64| t / scale;
    let marker = [x(r.experiment_s)];
    let pick = |f: fn(&(f64, f64, f64, f64, bool)) -> f64| -> Vec<(f64, f64)> {
        r.trace.iter().map(|p| (x(p.0), f(p))).collect()
    };
    let top = svg::line_chart_fitted(
        "Relay experiment (limit cycle), then the tuned PI answering a set-point step",
        unit,
        match r.process {
            ProcessKind::Room => "temperature (°C)",
            ProcessKind::Tank => "level (%)",
        },
        &[
            Series {
                label: "set-point",
                colour: "#2c3e50",
                dashed: true,
                points: pick(|p| p.1),
            },
            Series {
                label: "measurement",
                colour: "#c0392b",
                dashed: false,
                points: pick(|p| p.2),
            },
        ],
        &marker,
        "hand-over",
    );
    let bottom = svg::line_chart_marked(
        "Output: relay, then PI",
        unit,
        "output (V)",
        &[Series {
            label: "output",
            colour: "#2471a3",
            dashed: false,
            points: pick(|p| p.3),
        }],
        &marker,
        "hand-over",
    )
    .replacen("<svg ", "<svg y=\"420\" ", 1);
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"720\" height=\"840\">\n{top}{bottom}</svg>\n"
    )
}
