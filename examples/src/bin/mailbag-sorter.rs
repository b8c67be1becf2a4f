//! `mailbag-sorter`: the loading docks of the 1977 Malmö Ban mailbag sorter, simulated over
//! years on `regler-trolley-id` and `regler-chain-tracker`, with and without stretch correction
//! and read voting. See `regler_examples::mailbag` for the plant model.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use regler_examples::mailbag::{self, Config, Report};
use regler_examples::svg::{self, Series};
use regler_trolley_id::Strategy;

#[derive(Clone, Copy, Debug, ValueEnum)]
enum StrategyArg {
    /// Bitwise majority over the scans, then decode (needs `--vote-k` scans with cams).
    Majority,
    /// `--vote-k` consecutive identical decodes.
    Consecutive,
}

/// Simulates the dock chains of the 1977 Malmö Ban mailbag sorter for several years: trolleys
/// read at the chain start, tracked by chain pulses to their bins, the chain stretching about
/// 2 m a year. Each run compares four controllers: parity only or voting over several scans,
/// with or without stretch correction (DA = SA·DIA/SIA).
#[derive(Debug, Parser)]
#[command(name = "mailbag-sorter", version, allow_negative_numbers = true)]
struct Args {
    /// Seed of every random choice: the same seed gives the same run.
    #[arg(long, default_value_t = 1977)]
    seed: u64,
    /// Simulated years (0.01 to 50).
    #[arg(long, default_value_t = 5.0)]
    years: f64,
    /// Trolleys through each dock per simulated year (a sample of the real traffic).
    #[arg(long, default_value_t = 20_000)]
    trolleys_per_year: u32,
    /// Docks, each with its own chain and code reader (1 to 8).
    #[arg(long, default_value_t = 3)]
    docks: u8,
    /// Bins (tippers) per dock (2 to 64).
    #[arg(long, default_value_t = 40)]
    bins: u16,
    /// Chain length in metres.
    #[arg(long, default_value_t = 400.0)]
    chain_m: f64,
    /// Chain stretch in metres per year.
    #[arg(long, default_value_t = 2.0)]
    stretch_m_per_year: f64,
    /// Mean chance that one scan of the cams is wrong (the source: 1 in 1000).
    #[arg(long, default_value_t = 0.001)]
    misread_rate: f64,
    /// How uneven the readers are: 0 all equal, 1 from none to twice the mean.
    #[arg(long, default_value_t = 0.8)]
    reader_spread: f64,
    /// Scans a reader takes of each passing trolley.
    #[arg(long, default_value_t = 5)]
    readings: u8,
    /// Voting strategy.
    #[arg(long, value_enum, default_value_t = StrategyArg::Majority)]
    strategy: StrategyArg,
    /// Scans with cams (majority) or consecutive equal decodes (consecutive) needed.
    #[arg(long, default_value_t = 3)]
    vote_k: u8,
    /// Chance that a stretch measurement is off by one pulse.
    #[arg(long, default_value_t = 0.02)]
    glitch_rate: f64,
    /// Reader health alarm: disagreements per thousand passages (last 1000) above which a
    /// reader's alarm goes on.
    #[arg(long, default_value_t = 4)]
    reader_alarm_per_mille: u32,
    /// Print the results as JSON on stdout instead of the summary.
    #[arg(long)]
    json: bool,
    /// Where to write the SVG picture (tip-position error by year, sack outcomes).
    #[arg(long, default_value = "mailbag-sorter.svg")]
    svg: PathBuf,
    /// Do not write the picture.
    #[arg(long)]
    no_svg: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

impl Args {
    fn config(&self) -> Config {
        Config {
            seed: self.seed,
            years: self.years,
            trolleys_per_year: self.trolleys_per_year,
            docks: self.docks,
            bins: self.bins,
            chain_m: self.chain_m,
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

fn main() -> ExitCode {
    regler_examples::finish("mailbag-sorter", run(&Args::parse()))
}

fn run(args: &Args) -> Result<(), String> {
    let config = args.config();
    config.validate()?;
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(config.total_steps())
    };
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} [{bar:40}] {percent}% ({eta} left)")
            .map_err(|e| e.to_string())?
            .progress_chars("=> "),
    );
    bar.set_message("simulating chain pulses");
    let report = mailbag::run(&config, |steps| bar.inc(steps))?;
    bar.finish_and_clear();

    if !args.no_svg {
        std::fs::write(&args.svg, picture(&report))
            .map_err(|e| format!("cannot write {}: {e}", args.svg.display()))?;
    }
    if args.json {
        let json = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        println!("{json}");
    } else {
        print!("{}", summary(&report));
        if !args.no_svg {
            println!("\nPicture: {}", args.svg.display());
        }
    }
    Ok(())
}

fn summary(r: &Report) -> String {
    use std::fmt::Write as _;
    let c = &r.config;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Mailbag sorter, {} dock(s) x {} bins, {:.0} m chains stretching {:.1} m/year, {:.2} years, seed {}",
        c.docks, c.bins, c.chain_m, c.stretch_m_per_year, c.years, c.seed
    );
    let _ = writeln!(
        s,
        "Misread rate {:.4} per scan (readers uneven by {:.0} %), {} scans per trolley when voting\n",
        c.misread_rate,
        100.0 * c.reader_spread,
        c.readings
    );
    let _ = writeln!(
        s,
        "{:<38} {:>9} {:>9} {:>8} {:>8} {:>10} {:>8} {:>11} {:>9}",
        "controller",
        "sacks",
        "delivered",
        "misdeliv",
        "rejected",
        "not tipped",
        "on chain",
        "misdeliv/M",
        "|tip err|"
    );
    for sc in &r.scenarios {
        let o = &sc.outcomes;
        let _ = writeln!(
            s,
            "{:<38} {:>9} {:>9} {:>8} {:>8} {:>10} {:>8} {:>11.1} {:>7.2} m",
            sc.name,
            o.sacks,
            o.delivered,
            o.misdelivered,
            o.rejected,
            o.not_tipped,
            o.on_chain,
            sc.misdelivered_per_million,
            sc.tip_error.mean_abs_m
        );
    }
    let _ = writeln!(
        s,
        "\nTip-position error by year (mean |error|, m): without / with correction"
    );
    let (without, with) = (&r.scenarios[2], &r.scenarios[3]);
    for (a, b) in without.years.iter().zip(&with.years) {
        let _ = writeln!(
            s,
            "  year {:>2}: {:>7.3} / {:>6.3}   (max {:>6.2} / {:>5.2})",
            a.year,
            a.tip_error.mean_abs_m,
            b.tip_error.mean_abs_m,
            a.tip_error.max_abs_m,
            b.tip_error.max_abs_m
        );
    }
    let _ = writeln!(s, "\nReader health (voting, with correction):");
    for rd in &r.readers {
        let _ = writeln!(
            s,
            "  reader {}: rate {:.4}, {} passages, {} with parity errors, {} no-reads, {} disagreements, alarm raised {} time(s){}",
            rd.dock,
            rd.misread_rate,
            rd.passages,
            rd.parity_errors,
            rd.no_reads,
            rd.disagreements,
            rd.alarms_raised,
            if rd.alarm_at_end { ", ALARM ON" } else { "" }
        );
    }
    let st = &r.stretch;
    let _ = writeln!(
        s,
        "\nStretch: chain {:.2} per mille, meter {} per mille after {} measurements{}",
        st.actual_per_mille,
        st.measured_per_mille,
        st.measurements,
        if st.alarm {
            " (stretch alarm: time to shorten the chain)"
        } else {
            ""
        }
    );
    let recal = r
        .scenarios
        .iter()
        .map(|s| s.recalibrations)
        .max()
        .unwrap_or(0);
    let _ = writeln!(s, "Recalibrations with correction: {recal}");
    s
}

fn picture(r: &Report) -> String {
    let colours = ["#c0392b", "#2471a3"];
    // Mean (solid) then maximum (dashed), without and with correction (the voting runs), over
    // twenty stretches of the run.
    let mut series = Vec::new();
    for (dashed, labels) in [
        (false, ["no correction", "with correction"]),
        (true, ["max, without", "max, with"]),
    ] {
        for (sc, colour) in r.scenarios[2..].iter().zip(colours) {
            let stat = |e: &mailbag::TipError| if dashed { e.max_abs_m } else { e.mean_abs_m };
            series.push(Series {
                label: labels[usize::from(sc.scenario.correction)],
                colour,
                dashed,
                points: sc
                    .curve
                    .iter()
                    .filter(|c| c.tip_error.count > 0)
                    .map(|c| (c.years, stat(&c.tip_error)))
                    .collect(),
            });
        }
    }
    let lines = svg::line_chart(
        "Tip-position error as the chain stretches",
        "year",
        "|error| at tipper set (m)",
        &series,
    );
    // The corrected runs hug zero on that scale: the same two lines on a scale of their own.
    let corrected_only: Vec<Series<'_>> = series
        .iter()
        .filter(|s| s.colour == colours[1])
        .cloned()
        .collect();
    let zoom = svg::line_chart(
        "With stretch correction, on its own scale",
        "year",
        "|error| at tipper set (m)",
        &corrected_only,
    );
    // What voting buys shows once the tracking is right: compare the two corrected runs.
    let corrected: Vec<&mailbag::ScenarioReport> = r
        .scenarios
        .iter()
        .filter(|s| s.scenario.correction)
        .collect();
    let per_million = |f: fn(&mailbag::Outcomes) -> u64| -> Vec<f64> {
        corrected
            .iter()
            .map(|s| 1e6 * f(&s.outcomes) as f64 / s.outcomes.sacks.max(1) as f64)
            .collect()
    };
    let names: Vec<String> = corrected
        .iter()
        .map(|s| {
            if s.scenario.voting {
                "voting".into()
            } else {
                "parity only".into()
            }
        })
        .collect();
    let bars = svg::bar_chart(
        "Misdelivered and rejected sacks, stretch correction on",
        "sacks per million",
        &names,
        &[
            ("misdelivered", "#c0392b", per_million(|o| o.misdelivered)),
            ("rejected (manual)", "#f39c12", per_million(|o| o.rejected)),
        ],
    );
    let zoom = zoom.replacen("<svg ", "<svg y=\"420\" ", 1);
    let bars = bars.replacen("<svg ", "<svg y=\"840\" ", 1);
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"720\" height=\"1260\">\n{lines}{zoom}{bars}</svg>\n"
    )
}
