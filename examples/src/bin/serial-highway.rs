//! `serial-highway`: the CAMAC serial highway (source 004) rebuilt on `regler-panel-link` — a
//! driver and up to 62 L-type crate controllers on a noisy loop, or a driver and one crate over
//! two real serial ports. The highway itself is `regler_examples::highway`.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, ValueEnum};
use regler_examples::cli::{self, Common, Program, Stop};
use regler_examples::highway::{
    self, Config, LineKind, MAX_BER, MAX_CRATES, MAX_MESSAGES, MAX_RATE, MIN_RATE, WINDOW,
};

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
    /// Crate controllers on the loop (1 to 62).
    #[arg(long, default_value_t = 62, allow_hyphen_values = true,
          value_parser = cli::whole(1, MAX_CRATES))]
    crates: u8,
    /// Commands to run to completion or failure (1 to 100000000).
    #[arg(long, default_value_t = 1_000_000, allow_hyphen_values = true,
          value_parser = cli::whole(1, MAX_MESSAGES))]
    messages: u64,
    /// Bit-error rate of every link (0 to 0.1).
    #[arg(long, default_value_t = 1e-5, allow_hyphen_values = true,
          value_parser = cli::real(0.0, MAX_BER))]
    ber: f64,
    /// Line encoding the noise acts on.
    #[arg(long, value_enum, default_value_t = Line::ByteSerial, allow_hyphen_values = true)]
    line: Line,
    /// Commands in flight at most: one per crate, so 1 to 16 and at most --crates [default: 16,
    /// or --crates when fewer]
    #[arg(long, allow_hyphen_values = true, value_parser = cli::whole(1, WINDOW))]
    window: Option<usize>,
    /// Retries per command, 0 to 255 (each waits for the attempt's deadline: the highway has no
    /// sequence numbers, so nothing may be resent while a copy could still be on the loop).
    #[arg(long, default_value_t = 5, allow_hyphen_values = true,
          value_parser = cli::whole(0, u8::MAX))]
    retries: u8,
    /// A scripted workload instead of the random one: lines `CRATE STATION SUBADDRESS FUNCTION
    /// [DATA]` (e.g. `5 1 0 16 0x1234` writes, `5 1 0 0` reads back), run in order, over and over.
    #[arg(long, allow_hyphen_values = true)]
    script: Option<PathBuf>,
    /// Bit-serial bit rate in bit/s for the throughput figure (1000 to 100000000).
    #[arg(long, default_value_t = 5e6, allow_hyphen_values = true,
          value_parser = cli::real(MIN_RATE, MAX_RATE))]
    bit_rate: f64,
    /// Run the driver and one crate over these two serial ports instead (e.g. the two ends of
    /// `socat -d -d pty,raw,echo=0 pty,raw,echo=0`): DRIVER_PORT CRATE_PORT. Takes --messages,
    /// --seed and --json; the loop's options and the picture do not apply and are refused.
    #[arg(long, num_args = 2, value_names = ["DRIVER_PORT", "CRATE_PORT"],
          conflicts_with_all = ["crates", "ber", "line", "window", "retries", "script",
                                "bit_rate", "picture"])]
    ports: Option<Vec<String>>,
    /// With --ports: run the 1977 panel link (host and a 29-register panel) over the ports
    /// instead of the highway (five keys chosen by --seed; --messages does not apply).
    #[arg(long, requires = "ports", conflicts_with = "messages")]
    panel: bool,
    #[command(flatten)]
    common: Common<Highway>,
}

regler_examples::program!(Highway, "serial-highway", seed 1976, picture "serial-highway.svg", "svg");

fn main() -> ExitCode {
    cli::finish(Highway::NAME, run(&Args::parse()))
}

fn run(args: &Args) -> Result<(), Stop> {
    if let Some(ports) = &args.ports {
        return over_ports(args, ports);
    }
    let window = match args.window {
        Some(w) if w > usize::from(args.crates) => {
            return Err(cli::bad(
                "--window",
                format!(
                    "one command in flight per crate, so at most --crates ({}), got {w}",
                    args.crates
                ),
            ));
        }
        Some(w) => w,
        None => Config::default_window(args.crates),
    };
    let config = Config {
        crates: args.crates,
        messages: args.messages,
        ber: args.ber,
        seed: args.common.seed,
        line: match args.line {
            Line::ByteSerial => LineKind::ByteSerial,
            Line::BitSerial => LineKind::BitSerial,
        },
        window,
        retries: args.retries,
        bit_rate_hz: args.bit_rate,
        ..Config::default()
    };
    let script = match &args.script {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| {
                format!(
                    "--script: cannot read {}: {}",
                    path.display(),
                    cli::io_message(&e)
                )
            })?;
            Some(highway::parse_script(&text, args.crates)?)
        }
        None => None,
    };
    let bar = args.common.progress(args.messages, "commands", "");
    let summary = highway::run(config, script, |done| bar.set_position(done))?;
    bar.finish_and_clear();
    if let Some(path) = args.common.picture() {
        cli::write_picture(path, highway::picture(&summary))?;
    }
    if args.common.json {
        cli::print(&serde_json::to_string_pretty(&summary)?)
    } else {
        cli::print(&highway::summary_text(&summary, args.common.picture()))
    }
}

/// `--ports`: the driver and one crate, or with `--panel` the panel link, over two real ports.
fn over_ports(args: &Args, ports: &[String]) -> Result<(), Stop> {
    let [driver_port, crate_port] = ports else {
        return Err(cli::bad("--ports", "needs two paths"));
    };
    if args.panel {
        let keys: Vec<u8> = (0..5u64)
            .map(|k| ((args.common.seed.wrapping_add(k) * 37) % 128) as u8)
            .collect();
        let summary = highway::ports::run_panel(driver_port, crate_port, &keys)?;
        let list = |keys: &[u8]| keys.iter().map(u8::to_string).collect::<Vec<_>>().join(" ");
        cli::print(&if args.common.json {
            serde_json::to_string_pretty(&summary)?
        } else {
            format!(
                "panel link over real ports: host on {driver_port}, panel on {crate_port}\n  \
                 keys pressed {}, delivered {}\n  \
                 {} register sequences in {:.2} s; the panel shows the host's registers: {}",
                list(&summary.keys_pressed),
                list(&summary.keys_delivered),
                summary.sequences,
                summary.seconds,
                if summary.registers_match { "yes" } else { "NO" }
            )
        })?;
        return if summary.registers_match && summary.keys_delivered == summary.keys_pressed {
            Ok(())
        } else {
            Err("the panel link over the ports lost or altered something".into())
        };
    }
    let summary = highway::ports::run(driver_port, crate_port, args.messages, args.common.seed)?;
    cli::print(&if args.common.json {
        serde_json::to_string_pretty(&summary)?
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
    })?;
    if summary.undetected_errors == 0 {
        Ok(())
    } else {
        Err("undetected errors over the ports".into())
    }
}
