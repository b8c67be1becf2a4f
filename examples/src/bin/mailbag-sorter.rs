//! `mailbag-sorter`: the whole 1977 Malmö Ban mailbag-sorting plant (`regler_examples::mailbag::plant`),
//! or with `--docks-only` its loading docks simulated over years on `regler-trolley-id` and
//! `regler-chain-tracker`, with and without stretch correction and read voting
//! (`regler_examples::mailbag`).

use std::process::ExitCode;

use clap::{Parser, ValueEnum};
use regler_examples::cli::{self, Common, Program, Stop};
use regler_examples::mailbag::{self, Config, limits::*};
use regler_trolley_id::Strategy;

#[derive(Clone, Copy, Debug, ValueEnum)]
enum StrategyArg {
    /// Bitwise majority over the scans, then decode (needs `--vote-k` scans with cams).
    Majority,
    /// `--vote-k` consecutive identical decodes.
    Consecutive,
}

/// Simulates the whole 1977 Malmö Ban mailbag-sorting plant for --hours: loading desks, code
/// readers and switches, buffer lanes, emptying stations, dock chains and the control program on
/// a 50 ms scan, run twice on the same traffic (parity-only and voting readers), with faults on
/// demand. With --docks-only: the dock chains alone over several years, four controllers (parity
/// only or voting, with or without stretch correction DA = SA·DIA/SIA).
#[derive(Debug, Parser)]
#[command(name = "mailbag-sorter", version, allow_negative_numbers = true)]
struct Args {
    /// Run today's multi-year comparison of the dock chains alone (the options below from
    /// --years to --reader-alarm-per-mille apply only here) instead of the whole plant.
    #[arg(long)]
    docks_only: bool,
    /// Whole plant: simulated hours (0.01 to 1000).
    #[arg(long, default_value_t = 24.0, allow_hyphen_values = true,
          value_parser = cli::real(0.01, 1000.0))]
    hours: f64,
    /// Whole plant: a script of operators' entries, lines `HH:MM[:SS] PANEL COMMAND ARGS`
    /// (`P1 type 3`, `P2 postcode 20211`, `central assign 3 E2`, `central schedule 2|calendar`,
    /// `A emptying D1 A1,A2`, `B emptying E9 B1,C2`, `B lamptest`), `#` comments, and `replace`
    /// alone to leave the seeded traffic out. A line a panel's keyboard would not take (a
    /// command or station not of that panel, a postcode with a bin in no schedule, an extra
    /// word) is refused with its line number.
    #[arg(long, value_name = "FILE")]
    script: Option<std::path::PathBuf>,
    /// Whole plant: a fault at a simulated time, repeatable: `misread@T:READER:RATE`,
    /// `reader-fails@T:READER`, `noise@T:PANEL:BIT_ERROR_RATE`, `stuck@T:INPUT:0|1:SECONDS`,
    /// `chatter@T:INPUT:SECONDS`, `power@T:SECONDS`, `hang@T:SECONDS`,
    /// `pulses@T:DOCK:RATE:SECONDS`; T is always `HH:MM:SS` (hours past 23 for later days),
    /// then exactly the kind's arguments (a missing or extra one is refused); READER R1–R12,
    /// PANEL P1–P3, A, B or central, INPUT a name (full-E3, waiting-D1, present-R5, pulse-1,
    /// ref-end-2) or 0–543, DOCK 1–3, RATE 0 to 0.5, SECONDS 1 to 604800 (7 days; 0 with stuck
    /// and pulses: for good). A power failure (a hang) that starts before the one before it is
    /// over is refused.
    #[arg(long, value_name = "KIND@HH:MM:SS:ARGS", value_parser = parse_fault)]
    fault: Vec<mailbag::plant::faults::Fault>,
    /// Whole plant: trolleys (1 to 4095).
    #[arg(long, default_value_t = 3000, value_parser = cli::whole(1u16, 4095u16))]
    trolleys: u16,
    /// Whole plant: traffic, times the usual day's (0.1 to 10).
    #[arg(long, default_value_t = 1.0, value_parser = cli::real(0.1, 10.0))]
    traffic: f64,
    /// Simulated years (0.01 to 50).
    #[arg(long, default_value_t = 5.0, allow_hyphen_values = true,
          value_parser = cli::real(YEARS.0, YEARS.1))]
    years: f64,
    /// Trolleys through each dock per simulated year, a sample of the real traffic (1 to
    /// 1000000).
    #[arg(long, default_value_t = 20_000, allow_hyphen_values = true,
          value_parser = cli::whole(TROLLEYS_PER_YEAR.0, TROLLEYS_PER_YEAR.1))]
    trolleys_per_year: u32,
    /// Docks, each with its own chain and code reader (1 to 8).
    #[arg(long, default_value_t = 3, allow_hyphen_values = true,
          value_parser = cli::whole(DOCKS.0, DOCKS.1))]
    docks: u8,
    /// Bins (tippers) per dock (2 to 64).
    #[arg(long, default_value_t = 40, allow_hyphen_values = true,
          value_parser = cli::whole(BINS.0, BINS.1))]
    bins: u16,
    /// Chain length in metres (50 to 2000); the reference initiators sit 300 m apart, or ¾ of
    /// a shorter chain.
    #[arg(long, default_value_t = 400.0, allow_hyphen_values = true,
          value_parser = cli::real(CHAIN_M.0, CHAIN_M.1))]
    chain_m: f64,
    /// Chain stretch in metres per year (0 to a twentieth of --chain-m).
    #[arg(long, default_value_t = 2.0, allow_hyphen_values = true,
          value_parser = cli::real(STRETCH_M_PER_YEAR.0, STRETCH_M_PER_YEAR.1))]
    stretch_m_per_year: f64,
    /// Mean chance that one scan of the cams is wrong (0 to 0.25; the source: 1 in 1000).
    #[arg(long, default_value_t = 0.001, allow_hyphen_values = true,
          value_parser = cli::real(MISREAD_RATE.0, MISREAD_RATE.1))]
    misread_rate: f64,
    /// How uneven the readers are: 0 all equal, 1 from none to twice the mean.
    #[arg(long, default_value_t = 0.8, allow_hyphen_values = true,
          value_parser = cli::real(READER_SPREAD.0, READER_SPREAD.1))]
    reader_spread: f64,
    /// Scans a reader takes of each passing trolley (1 to 50).
    #[arg(long, default_value_t = 5, allow_hyphen_values = true,
          value_parser = cli::whole(READINGS.0, READINGS.1))]
    readings: u8,
    /// Voting strategy.
    #[arg(long, value_enum, default_value_t = StrategyArg::Majority, allow_hyphen_values = true)]
    strategy: StrategyArg,
    /// Scans with cams (majority) or consecutive equal decodes (consecutive) needed (1 to
    /// --readings).
    #[arg(long, default_value_t = 3, allow_hyphen_values = true,
          value_parser = cli::whole(1, READINGS.1))]
    vote_k: u8,
    /// Chance that a stretch measurement is off by one pulse (0 to 1).
    #[arg(long, default_value_t = 0.02, allow_hyphen_values = true,
          value_parser = cli::real(GLITCH_RATE.0, GLITCH_RATE.1))]
    glitch_rate: f64,
    /// Reader health alarm: disagreements per thousand passages (last 1000) above which a
    /// reader's alarm goes on (0 to 1000; 1000 never raises it).
    #[arg(long, default_value_t = 4, allow_hyphen_values = true,
          value_parser = cli::whole(ALARM_PER_MILLE.0, ALARM_PER_MILLE.1))]
    reader_alarm_per_mille: u32,
    #[command(flatten)]
    common: Common<Mailbag>,
}

regler_examples::program!(Mailbag, "mailbag-sorter", seed 1977, picture "mailbag-sorter.svg", "svg");

impl Args {
    fn config(&self) -> Config {
        Config {
            seed: self.common.seed,
            years: self.years,
            trolleys_per_year: self.trolleys_per_year,
            docks: self.docks,
            bins: self.bins,
            chain_m: self.chain_m,
            initiator_span_m: Config::initiator_span_for(self.chain_m),
            stretch_m_per_year: self.stretch_m_per_year,
            misread_rate: self.misread_rate,
            reader_spread: self.reader_spread,
            readings: self.readings,
            strategy: match self.strategy {
                StrategyArg::Majority => Strategy::Majority {
                    min_samples: self.vote_k,
                },
                StrategyArg::Consecutive => Strategy::Consecutive { k: self.vote_k },
            },
            glitch_rate: self.glitch_rate,
            alarm_disagreement_per_mille: self.reader_alarm_per_mille,
            ..Config::default()
        }
    }
}

fn parse_fault(s: &str) -> Result<mailbag::plant::faults::Fault, String> {
    mailbag::plant::faults::parse_fault(s)
}

/// Options of the dock comparison alone.
const DOCK_OPTIONS: [&str; 13] = [
    "years",
    "trolleys_per_year",
    "docks",
    "bins",
    "chain_m",
    "stretch_m_per_year",
    "misread_rate",
    "reader_spread",
    "readings",
    "strategy",
    "vote_k",
    "glitch_rate",
    "reader_alarm_per_mille",
];
/// Options of the whole plant alone.
const PLANT_OPTIONS: [&str; 5] = ["hours", "script", "fault", "trolleys", "traffic"];

fn main() -> ExitCode {
    use clap::{CommandFactory, FromArgMatches, parser::ValueSource};
    let matches = Args::command().get_matches();
    let args = match Args::from_arg_matches(&matches) {
        Ok(a) => a,
        Err(e) => e.exit(),
    };
    let given = |id: &str| matches.value_source(id) == Some(ValueSource::CommandLine);
    let wrong = if args.docks_only {
        PLANT_OPTIONS
            .iter()
            .find(|id| given(id))
            .map(|id| (id, "applies to the whole plant, not with --docks-only"))
    } else {
        DOCK_OPTIONS
            .iter()
            .find(|id| given(id))
            .map(|id| (id, "applies only with --docks-only"))
    };
    if let Some((id, why)) = wrong {
        let option = format!("--{}", id.replace('_', "-"));
        let _ = Args::command()
            .error(
                clap::error::ErrorKind::ArgumentConflict,
                format!("{option} {why}"),
            )
            .print();
        return ExitCode::from(2);
    }
    let result = if args.docks_only {
        run(&args)
    } else {
        run_plant(&args)
    };
    cli::finish(Mailbag::NAME, result)
}

fn run_plant(args: &Args) -> Result<(), Stop> {
    use mailbag::plant::{self, panels::Panels};
    plant::faults::check_faults(&args.fault).map_err(|e| cli::bad("--fault", e))?;
    let script = match &args.script {
        None => None,
        Some(path) => {
            let bytes = std::fs::read(path).map_err(|e| {
                cli::bad(
                    "--script",
                    format!("{}: {}", path.display(), cli::io_message(&e)),
                )
            })?;
            Some(
                plant::traffic::parse_script_bytes(&bytes)
                    .map_err(|e| cli::bad("--script", format!("{}: {e}", path.display())))?,
            )
        }
    };
    let config = plant::Config {
        seed: args.common.seed,
        hours: args.hours,
        trolleys: args.trolleys,
        traffic: args.traffic,
        faults: args.fault.clone(),
        script,
        ..plant::Config::default()
    };
    let bar = args
        .common
        .progress(2 * config.minutes(), "simulating the plant", "minutes");
    let report =
        plant::run(&config, || Panels::new(config.seed), &|m| bar.inc(m)).map_err(Stop::Error)?;
    bar.finish_and_clear();
    let picture = args.common.picture();
    if let Some(path) = picture {
        let title = format!(
            "The 1977 mailbag plant, {} h, seed {}",
            cli::number(report.simulated_hours),
            report.seed
        );
        cli::write_picture(
            path,
            plant::map::draw_runs(&report.map, &report.map_parity_only, &title),
        )?;
    }
    if args.common.json {
        cli::print(&serde_json::to_string_pretty(&report)?)
    } else {
        let mut text = plant::summary_text(&report);
        if let Some(path) = picture {
            text.push_str(&format!(
                "\nThe plant map (trolleys per hour on every rail, where sacks went astray), both runs: {}\n",
                path.display()
            ));
        }
        cli::print(&text)
    }
}

fn run(args: &Args) -> Result<(), Stop> {
    let config = args.config();
    config.validate()?;
    let bar = args
        .common
        .progress(config.total_steps(), "simulating chain pulses", "pulses");
    let report = mailbag::run(&config, |steps| bar.inc(steps))?;
    bar.finish_and_clear();
    let picture = args.common.picture();
    if let Some(path) = picture {
        cli::write_picture(path, mailbag::picture(&report))?;
    }
    if args.common.json {
        cli::print(&serde_json::to_string_pretty(&report)?)
    } else {
        cli::print(&mailbag::summary_text(&report, picture))
    }
}
