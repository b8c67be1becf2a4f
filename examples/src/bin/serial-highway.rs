//! `serial-highway`: the CAMAC serial highway (source 004) rebuilt on `regler-panel-link` — a
//! driver and up to 62 L-type crate controllers on a noisy loop, or a driver and one crate over
//! two real serial ports.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use regler_examples::cli::{self, Common, Program, Stop};
use regler_examples::highway::{self, Config, LineKind, Sim, Summary};
use regler_examples::svg;

#[derive(Clone, Copy, Debug, ValueEnum)]
enum Line {
    /// Eight lines and a clock (noise on the 8 bits of each byte).
    ByteSerial,
    /// Start bit, 8 bits LSB first, stop bit (noise on all 10).
    BitSerial,
}

/// Rebuilds the CAMAC serial highway: a driver sends commands round a loop of L-type crate
/// controllers; each controller takes its commands off the loop, checks row and column parity,
/// runs the dataway cycle only when the command is clean and writes its reply over the SPACE
/// bytes; a counter module raises a LAM and its crate sends a demand between messages. Every link
/// flips bits at the given rate; the run counts what was detected and — the figure that
/// matters — what was not.
#[derive(Debug, Parser)]
#[command(name = "serial-highway", version)]
struct Args {
    /// Crate controllers on the loop (1–62).
    #[arg(long, default_value_t = 62)]
    crates: u8,
    /// Commands to run to completion (or failure).
    #[arg(long, default_value_t = 1_000_000)]
    messages: u64,
    /// Bit-error rate of every link.
    #[arg(long, default_value_t = 1e-5)]
    ber: f64,
    /// Line encoding the noise acts on.
    #[arg(long, value_enum, default_value_t = Line::ByteSerial)]
    line: Line,
    /// Commands in flight at most (1–16, one per crate).
    #[arg(long, default_value_t = 16)]
    window: usize,
    /// Retries per command (each waits for the attempt's deadline: the highway has no sequence
    /// numbers, so nothing may be resent while a copy could still be on the loop).
    #[arg(long, default_value_t = 5)]
    retries: u8,
    /// A scripted workload instead of the random one: lines `CRATE STATION SUBADDRESS FUNCTION
    /// [DATA]` (e.g. `5 1 0 16 0x1234` writes, `5 1 0 0` reads back), run in order, over and over.
    #[arg(long)]
    script: Option<PathBuf>,
    /// Bit-serial bit rate (bit/s) for the throughput figure.
    #[arg(long, default_value_t = 5e6)]
    bit_rate: f64,
    /// Run the driver and one crate over these two serial ports instead (e.g. the two ends of
    /// `socat -d -d pty,raw,echo=0 pty,raw,echo=0`): DRIVER_PORT CRATE_PORT.
    #[arg(long, num_args = 2, value_names = ["DRIVER_PORT", "CRATE_PORT"])]
    ports: Option<Vec<String>>,
    /// With --ports: run the 1977 panel link (host and a 29-register panel) over the ports
    /// instead of the highway.
    #[arg(long, requires = "ports")]
    panel: bool,
    #[command(flatten)]
    common: Common<Highway>,
}

/// The program's name and defaults for the shared options.
#[derive(Debug, Clone)]
struct Highway;

impl Program for Highway {
    const NAME: &'static str = "serial-highway";
    const SEED: u64 = 1976;
    const PICTURE: &'static str = "serial-highway.svg";
    const FORMAT: &'static str = "svg";
    const NO_FORMAT: &'static str = "no-svg";
}

fn main() -> ExitCode {
    cli::finish(Highway::NAME, run(&Args::parse()))
}

fn run(args: &Args) -> Result<(), Stop> {
    if let Some(ports) = &args.ports {
        let [driver_port, crate_port] = ports.as_slice() else {
            return Err("--ports needs two paths".into());
        };
        if args.panel {
            let keys: Vec<u8> = (0..5u64)
                .map(|k| ((args.common.seed.wrapping_add(k) * 37) % 128) as u8)
                .collect();
            let summary = highway::ports::run_panel(driver_port, crate_port, &keys)?;
            let text = if args.common.json {
                serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?
            } else {
                format!(
                    "panel link over real ports: host on {driver_port}, panel on {crate_port}\n  \
                     keys pressed {:?}, delivered {:?}\n  \
                     {} register sequences in {:.2} s; the panel shows the host's registers: {}",
                    summary.keys_pressed,
                    summary.keys_delivered,
                    summary.sequences,
                    summary.seconds,
                    if summary.registers_match { "yes" } else { "NO" }
                )
            };
            cli::print(&text)?;
            return if summary.registers_match && summary.keys_delivered == summary.keys_pressed {
                Ok(())
            } else {
                Err("the panel link over the ports lost or altered something".into())
            };
        }
        let summary =
            highway::ports::run(driver_port, crate_port, args.messages, args.common.seed)?;
        let text = if args.common.json {
            serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?
        } else {
            format!(
                "serial-highway over real ports: driver on {driver_port}, crate 1 on {crate_port}\n  \
                 {} commands completed, {} failed, undetected errors: {}\n  \
                 {} byte clocks in {:.2} s ({:.0} byte round trips per second through the ports)",
                summary.completed,
                summary.failed,
                summary.undetected_errors,
                summary.clocks,
                summary.seconds,
                summary.clocks as f64 / summary.seconds.max(1e-9)
            )
        };
        cli::print(&text)?;
        return if summary.undetected_errors == 0 {
            Ok(())
        } else {
            Err("undetected errors over the ports".into())
        };
    }
    let config = Config {
        crates: args.crates,
        messages: args.messages,
        ber: args.ber,
        seed: args.common.seed,
        line: match args.line {
            Line::ByteSerial => LineKind::ByteSerial,
            Line::BitSerial => LineKind::BitSerial,
        },
        window: args.window,
        retries: args.retries,
        bit_rate_hz: args.bit_rate,
        ..Config::default()
    };
    let crates = config.crates;
    let mut sim = Sim::new(config)?;
    if let Some(path) = &args.script {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        sim.set_script(highway::parse_script(&text, crates)?);
    }
    let bar = if args.common.quiet || args.common.json {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(args.messages)
    };
    if let Ok(style) = ProgressStyle::with_template(
        "{spinner} commands [{bar:40}] {human_pos}/{human_len} ({eta} left)",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    let chunk = (args.messages / 200).max(1);
    while !sim.finished() {
        sim.run_until_done(sim.done() + chunk);
        bar.set_position(sim.done());
    }
    bar.finish_and_clear();
    let summary = sim.summary();
    if let Some(path) = args.common.picture() {
        std::fs::write(path, picture(&summary))
            .map_err(|e| format!("cannot write {}: {}", path.display(), cli::io_message(&e)))?;
    }
    let text = if args.common.json {
        serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?
    } else {
        summary_text(&summary, args)
    };
    cli::print(&text)
}

fn summary_text(s: &Summary, args: &Args) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    // Writing to a String cannot fail.
    macro_rules! println {
        ($($t:tt)*) => { let _ = writeln!(out, $($t)*); };
    }
    let c = &s.config;
    println!(
        "serial-highway: {} crates, {} commands, bit-error rate {:e} per link ({:?}), seed {}",
        c.crates, c.messages, c.ber, c.line, c.seed
    );
    println!(
        "  completed {}, failed {}, retries {}, time-outs {}",
        s.completed, s.failed, s.retries, s.timeouts
    );
    println!(
        "  bits flipped {}; detected at the crates {}, at the driver {}",
        s.bits_flipped, s.detected_at_crates, s.garbled_at_driver
    );
    println!(
        "  undetected errors: {} (wrong cycles run {}, wrong answers accepted {}, phantom demands {})",
        s.undetected_errors,
        s.undetected.wrong_cycles,
        s.undetected.wrong_answers,
        s.undetected.phantom_demands
    );
    println!("  demands {}, served {}", s.demands, s.demands_served);
    println!(
        "  throughput: {:.0} commands/s at {} MHz byte-serial, {:.0} commands/s at {} Mbit/s bit-serial",
        s.messages_per_s_byte_serial,
        c.byte_rate_hz / 1e6,
        s.messages_per_s_bit_serial,
        c.bit_rate_hz / 1e6
    );
    println!("  crate  messages  replies  detected  retries  failed  demands  served");
    let show: Vec<_> = if s.crates.len() > 12 {
        // The first and last few, and the busiest with errors.
        let mut picked: Vec<_> = s
            .crates
            .iter()
            .take(4)
            .chain(s.crates.iter().rev().take(4))
            .collect();
        picked.sort_by_key(|c| c.address);
        picked.dedup_by_key(|c| c.address);
        picked
    } else {
        s.crates.iter().collect()
    };
    for k in show {
        println!(
            "  {:>5}  {:>8}  {:>7}  {:>8}  {:>7}  {:>6}  {:>7}  {:>6}",
            k.address,
            k.messages,
            k.replies,
            k.detected_errors,
            k.retries,
            k.failed,
            k.demands,
            k.demands_served
        );
    }
    if s.crates.len() > 12 {
        println!("  (all {} crates: --json, or the picture)", s.crates.len());
    }
    if let Some(path) = args.common.picture() {
        println!("  picture: {}", path.display());
    }
    out.trim_end().to_string()
}

fn picture(s: &Summary) -> String {
    let per_thousand = |f: fn(&highway::CrateSummary) -> u64| -> Vec<(f64, f64)> {
        s.crates
            .iter()
            .map(|c| {
                (
                    f64::from(c.address),
                    1000.0 * f(c) as f64 / c.messages.max(1) as f64,
                )
            })
            .collect()
    };
    let series = [
        svg::Series {
            label: "retries",
            colour: "#1f77b4",
            dashed: false,
            points: per_thousand(|c| c.retries),
        },
        svg::Series {
            label: "errors caught by the crate",
            colour: "#d62728",
            dashed: false,
            points: per_thousand(|c| c.detected_errors),
        },
        svg::Series {
            label: "demands served",
            colour: "#2ca02c",
            dashed: true,
            points: per_thousand(|c| c.demands_served),
        },
    ];
    svg::line_chart(
        &format!(
            "Serial highway, {} crates, BER {:e}: undetected {}",
            s.config.crates, s.config.ber, s.undetected_errors
        ),
        "crate address (position on the loop)",
        "per 1000 commands to the crate",
        &series,
    )
}
