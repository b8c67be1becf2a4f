//! A simulated loading dock of the 1977 Malmö Ban mailbag sorter (source 000), run on
//! `regler-trolley-id` and `regler-chain-tracker` exactly as its controller would call them.
//!
//! # The plant
//! Each dock has a chain of `chain_m` metres carrying trolleys past `bins` bins; initiators give
//! one pulse per decimetre of chain *as it was new*. The chain stretches linearly by
//! `stretch_m_per_year`, so a pulse stands for a little more chain every day, while the bins
//! stay where they are. Two reference initiators `initiator_span_m` apart let the stretch meter
//! count DIA once per chain revolution; a count is off by one pulse with probability
//! `glitch_rate` (a missed or an extra pulse).
//!
//! At commissioning every reader→tipper distance SA was measured and set `LEAD_PULSES` short, so
//! the tipper is set just before the trolley reaches the bin; the tipper stays set for the
//! source's 6 pulses. A sack falls into bin `j` when its trolley passes bin `j` while that
//! tipper is set, whichever trolley the tracker meant.
//!
//! # The reader
//! A code reader at the chain start takes `readings` scans of each passing trolley. A passage is
//! *disturbed* (the trolley swings) with probability `rate / DISTURBED_SHARE`; in a disturbed
//! passage each scan is wrong with probability `DISTURBED_SHARE`, so a single scan is wrong with
//! probability `rate`, the figure of the source (1 in 1000). Readers differ: reader `i` of `n`
//! has `rate = misread_rate × (1 + reader_spread × (2i/(n−1) − 1))`. A wrong scan has 1, 2 or 3
//! cams flipped (50 %, 35 %, 15 %): parity catches odd counts; two flipped cams are another
//! trolley's number.
//!
//! # The controller
//! *Without voting* it decodes the first scan, as the source did; *with voting* a
//! [`Voter`] combines all scans. Either way the [`Registry`] routes the trolley: delivered if
//! the number read has a destination on this dock, else rejected (to the manual station).
//! *With correction* every accepted DIA recalibrates the tracker; *without* the distances stay
//! as commissioned.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use regler_chain_tracker::{
    DistanceTable, Measurement, SOURCE_HOLD_PULSES, StretchConfig, StretchMeter, TipperEvent,
    Tracker,
};
use regler_trolley_id::{
    AlarmLimits, NoRead, Passage, ReaderHealth, Registry, Route, Strategy, TrolleyId, Verdict,
    Voter, decode, encode,
};
use serde::Serialize;

/// Pulses per metre of new chain (one per decimetre).
pub const PULSES_PER_M: f64 = 10.0;
/// Pulses by which the commissioned distances fall short of the bins.
pub const LEAD_PULSES: u32 = 2;
/// Share of scans that are wrong in a disturbed passage.
pub const DISTURBED_SHARE: f64 = 0.5;
/// Most bins a dock may have.
pub const MAX_BINS: usize = 64;
/// Most trolleys on one chain.
pub const MAX_ON_CHAIN: usize = 2048;
/// Least pulses between two trolleys on the chain: they hang on the chain's dogs at least a
/// metre apart, more than the tipper hold plus the lead, so a set tipper never catches the next
/// trolley when tracking is right.
pub const MIN_GAP_PULSES: u32 = 10;

type Tag = (TrolleyId, u64);
type DockTracker = Tracker<Tag, MAX_ON_CHAIN, MAX_BINS>;

/// Where a sack should go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Destination {
    /// Dock, from 0.
    pub dock: u8,
    /// Bin on that dock, from 0.
    pub bin: u16,
}

/// The simulation's parameters (the example's command line).
#[derive(Clone, Debug, Serialize)]
pub struct Config {
    /// Seed of every random choice.
    pub seed: u64,
    /// Simulated years.
    pub years: f64,
    /// Trolleys through each dock per simulated year (a sample of the real traffic).
    pub trolleys_per_year: u32,
    /// Docks, each with its chain and reader.
    pub docks: u8,
    /// Bins per dock.
    pub bins: u16,
    /// Chain length, metres.
    pub chain_m: f64,
    /// Distance between the reference initiators, metres.
    pub initiator_span_m: f64,
    /// Chain stretch, metres per year.
    pub stretch_m_per_year: f64,
    /// Mean chance that one scan is wrong.
    pub misread_rate: f64,
    /// How uneven the readers are, 0 (equal) to 1.
    pub reader_spread: f64,
    /// Scans per passing trolley.
    pub readings: u8,
    /// Voting strategy when voting.
    #[serde(skip)]
    pub strategy: Strategy,
    /// Mean pulses between entering trolleys.
    pub mean_gap_pulses: u32,
    /// Chance that a DIA measurement is off by one pulse.
    pub glitch_rate: f64,
    /// Reader alarm: passages with two different numbers decoded, per thousand over the last
    /// 1000 passages, above which a reader's alarm goes on.
    pub alarm_disagreement_per_mille: u32,
    /// DIA measurements per year: one per chain revolution in the real plant (an 800 m loop
    /// at 0.5 m/s for 16 hours a day makes about 13 000). The simulation compresses time, so it
    /// spaces the measurements by simulated traffic, not by revolutions.
    pub measurements_per_year: u32,
}

impl Default for Config {
    fn default() -> Config {
        Config {
            seed: 1977,
            years: 5.0,
            trolleys_per_year: 20_000,
            docks: 3,
            bins: 40,
            chain_m: 400.0,
            initiator_span_m: 300.0,
            stretch_m_per_year: 2.0,
            misread_rate: 0.001,
            reader_spread: 0.8,
            readings: 5,
            strategy: Strategy::Majority { min_samples: 3 },
            mean_gap_pulses: 15,
            glitch_rate: 0.02,
            alarm_disagreement_per_mille: 4,
            measurements_per_year: 10_000,
        }
    }
}

impl Config {
    /// Checks every parameter; the message names the one that is wrong.
    pub fn validate(&self) -> Result<(), String> {
        let finite_in = |name: &str, v: f64, lo: f64, hi: f64| {
            if v.is_finite() && v >= lo && v <= hi {
                Ok(())
            } else {
                Err(format!("{name} must be between {lo} and {hi}, got {v}"))
            }
        };
        finite_in("years", self.years, 0.01, 50.0)?;
        finite_in("chain-m", self.chain_m, 50.0, 2000.0)?;
        finite_in(
            "initiator-span-m",
            self.initiator_span_m,
            10.0,
            self.chain_m,
        )?;
        finite_in(
            "stretch-m-per-year",
            self.stretch_m_per_year,
            0.0,
            self.chain_m / 20.0,
        )?;
        finite_in(
            "misread-rate",
            self.misread_rate,
            0.0,
            DISTURBED_SHARE / 2.0,
        )?;
        finite_in("reader-spread", self.reader_spread, 0.0, 1.0)?;
        finite_in("glitch-rate", self.glitch_rate, 0.0, 1.0)?;
        if !(1..=1_000_000).contains(&self.trolleys_per_year) {
            return Err(format!(
                "trolleys-per-year must be between 1 and 1000000, got {}",
                self.trolleys_per_year
            ));
        }
        if !(1..=1_000_000).contains(&self.measurements_per_year) {
            return Err(format!(
                "measurements-per-year must be between 1 and 1000000, got {}",
                self.measurements_per_year
            ));
        }
        if !(1..=8).contains(&self.docks) {
            return Err(format!("docks must be between 1 and 8, got {}", self.docks));
        }
        if !(2..=MAX_BINS as u16).contains(&self.bins) {
            return Err(format!(
                "bins must be between 2 and {MAX_BINS}, got {}",
                self.bins
            ));
        }
        if !(1..=50).contains(&self.readings) {
            return Err(format!(
                "readings must be between 1 and 50, got {}",
                self.readings
            ));
        }
        // The voter needs k readings (with cams, or consecutive): more than a passage has would
        // reject every trolley.
        let k = match self.strategy {
            Strategy::Majority { min_samples } => min_samples,
            Strategy::Consecutive { k } => k,
            _ => 1,
        };
        if k == 0 || k > self.readings {
            return Err(format!(
                "vote-k must be between 1 and readings ({}), got {k}",
                self.readings
            ));
        }
        if !(MIN_GAP_PULSES..=1000).contains(&self.mean_gap_pulses) {
            return Err(format!(
                "mean-gap-pulses must be between {MIN_GAP_PULSES} and 1000, got {}",
                self.mean_gap_pulses
            ));
        }
        Voter::new(self.strategy).map_err(|e| e.to_string())?;
        Ok(())
    }

    /// Pulses each dock runs in the whole simulation.
    #[must_use]
    pub fn pulses_per_dock(&self) -> u64 {
        (self.years * f64::from(self.trolleys_per_year) * f64::from(self.mean_gap_pulses)) as u64
    }

    /// Total pulse steps of a run (every scenario, every dock): the progress bar's length.
    #[must_use]
    pub fn total_steps(&self) -> u64 {
        self.pulses_per_dock() * u64::from(self.docks) * SCENARIOS.len() as u64
    }

    /// Single-scan misread rate of reader `i`.
    #[must_use]
    pub fn reader_rate(&self, i: u8) -> f64 {
        let n = f64::from(self.docks);
        let position = if self.docks > 1 {
            2.0 * f64::from(i) / (n - 1.0) - 1.0
        } else {
            0.0
        };
        self.misread_rate * (1.0 + self.reader_spread * position)
    }

    fn bin_position_m(&self, bin: u16) -> f64 {
        let first = 0.1 * self.chain_m;
        let last = self.chain_m - 0.05 * self.chain_m;
        first + (last - first) * f64::from(bin) / f64::from(self.bins - 1)
    }
}

/// One of the four ways the dock is run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Scenario {
    /// Whether accepted DIA measurements recalibrate the tracker.
    pub correction: bool,
    /// Whether the reader votes over all scans (else: the first scan, parity only).
    pub voting: bool,
}

impl Scenario {
    /// A short name.
    #[must_use]
    pub fn name(&self) -> String {
        format!(
            "{}, {}",
            if self.voting { "voting" } else { "parity only" },
            if self.correction {
                "stretch correction"
            } else {
                "no correction"
            }
        )
    }
}

/// The four scenarios, in report order.
pub const SCENARIOS: [Scenario; 4] = [
    Scenario {
        correction: false,
        voting: false,
    },
    Scenario {
        correction: true,
        voting: false,
    },
    Scenario {
        correction: false,
        voting: true,
    },
    Scenario {
        correction: true,
        voting: true,
    },
];

/// Where sacks ended up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Outcomes {
    /// Trolleys that passed a reader with a sack.
    pub sacks: u64,
    /// Into their own bin.
    pub delivered: u64,
    /// Into another bin.
    pub misdelivered: u64,
    /// Sent to the manual station by the reader (no-read or implausible number).
    pub rejected: u64,
    /// Routed, but never tipped: reached the chain end with the sack.
    pub not_tipped: u64,
    /// Routed and still on the chain when the run ended. The five outcomes add up to `sacks`.
    pub on_chain: u64,
}

impl Outcomes {
    fn add(&mut self, o: &Outcomes) {
        self.sacks += o.sacks;
        self.delivered += o.delivered;
        self.misdelivered += o.misdelivered;
        self.rejected += o.rejected;
        self.not_tipped += o.not_tipped;
        self.on_chain += o.on_chain;
    }
}

/// Tip-position error statistics: where the tracked trolley was when its tipper was set,
/// against where commissioning meant it to be, in metres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct TipError {
    /// Tipper sets measured.
    pub count: u64,
    /// Mean of |error|.
    pub mean_abs_m: f64,
    /// Largest |error|.
    pub max_abs_m: f64,
    #[serde(skip)]
    sum_abs: f64,
}

impl TipError {
    fn record(&mut self, error_m: f64) {
        self.count += 1;
        self.sum_abs += error_m.abs();
        self.max_abs_m = self.max_abs_m.max(error_m.abs());
        self.mean_abs_m = self.sum_abs / self.count as f64;
    }

    fn merge(&mut self, o: &TipError) {
        self.count += o.count;
        self.sum_abs += o.sum_abs;
        self.max_abs_m = self.max_abs_m.max(o.max_abs_m);
        self.mean_abs_m = if self.count == 0 {
            0.0
        } else {
            self.sum_abs / self.count as f64
        };
    }
}

/// One simulated year of one scenario, all docks together.
#[derive(Clone, Debug, Default, Serialize)]
pub struct YearReport {
    /// Year number, from 1 (the last may be partial).
    pub year: u32,
    /// Sack outcomes.
    pub outcomes: Outcomes,
    /// Tip-position error.
    pub tip_error: TipError,
}

/// A scenario's results.
#[derive(Clone, Debug, Serialize)]
pub struct ScenarioReport {
    /// The scenario.
    pub scenario: Scenario,
    /// Its name.
    pub name: String,
    /// Sack outcomes over the whole run.
    pub outcomes: Outcomes,
    /// Misdelivered sacks per million.
    pub misdelivered_per_million: f64,
    /// Tip-position error over the whole run.
    pub tip_error: TipError,
    /// Year by year.
    pub years: Vec<YearReport>,
    /// Tip-position error over `CURVE_POINTS` equal stretches of the run, for the picture.
    pub curve: Vec<CurvePoint>,
    /// Recalibrations of the trackers (all docks).
    pub recalibrations: u64,
}

/// One reader's health (from the voting scenario with correction).
#[derive(Clone, Debug, Serialize)]
pub struct ReaderReport {
    /// Dock (and reader) number, from 1.
    pub dock: u8,
    /// The reader's single-scan misread rate in the simulation.
    pub misread_rate: f64,
    /// Passages.
    pub passages: u32,
    /// Passages with a parity error in any scan.
    pub parity_errors: u32,
    /// Passages that gave no trolley.
    pub no_reads: u32,
    /// Passages that decoded two different numbers.
    pub disagreements: u32,
    /// Times the health alarm was raised.
    pub alarms_raised: u32,
    /// Whether the alarm is on at the end.
    pub alarm_at_end: bool,
}

/// The stretch meter at the end (dock 1 of the run with correction and voting).
#[derive(Clone, Debug, Serialize)]
pub struct StretchReport {
    /// Chain stretch the plant ended with, per mille.
    pub actual_per_mille: f64,
    /// Stretch the meter accepted, per mille.
    pub measured_per_mille: i32,
    /// DIA measurements.
    pub measurements: u32,
    /// Whether the stretch alarm is on.
    pub alarm: bool,
}

/// Everything a run found.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The parameters.
    pub config: Config,
    /// One per scenario, in [`SCENARIOS`] order.
    pub scenarios: Vec<ScenarioReport>,
    /// One per reader.
    pub readers: Vec<ReaderReport>,
    /// The stretch meter.
    pub stretch: StretchReport,
}

/// Points in each scenario's tip-error curve.
pub const CURVE_POINTS: usize = 20;

/// Tip-position error over one stretch of the run.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct CurvePoint {
    /// End of the stretch, years from the start.
    pub years: f64,
    /// The error in that stretch.
    pub tip_error: TipError,
}

struct DockResult {
    years: Vec<YearReport>,
    curve: Vec<TipError>,
    recalibrations: u64,
    health: ReaderHealth<1000>,
    meter: StretchMeter,
}

/// Runs every scenario; `progress(steps)` is called now and then with pulse steps done.
pub fn run(config: &Config, mut progress: impl FnMut(u64)) -> Result<Report, String> {
    config.validate()?;
    let mut scenarios = Vec::new();
    let mut readers = Vec::new();
    let mut stretch = None;
    for scenario in SCENARIOS {
        let mut years: Vec<YearReport> = Vec::new();
        let mut curve: Vec<CurvePoint> = (1..=CURVE_POINTS)
            .map(|i| CurvePoint {
                years: config.years * i as f64 / CURVE_POINTS as f64,
                ..CurvePoint::default()
            })
            .collect();
        let mut recalibrations = 0;
        for dock in 0..config.docks {
            let result = run_dock(config, scenario, dock, &mut progress)?;
            recalibrations += result.recalibrations;
            for (i, y) in result.years.iter().enumerate() {
                if years.len() <= i {
                    years.push(YearReport {
                        year: y.year,
                        ..YearReport::default()
                    });
                }
                years[i].outcomes.add(&y.outcomes);
                years[i].tip_error.merge(&y.tip_error);
            }
            for (point, e) in curve.iter_mut().zip(&result.curve) {
                point.tip_error.merge(e);
            }
            if scenario.voting && scenario.correction {
                let h = result.health.totals();
                readers.push(ReaderReport {
                    dock: dock + 1,
                    misread_rate: config.reader_rate(dock),
                    passages: h.passages,
                    parity_errors: h.parity_errors,
                    no_reads: h.no_reads,
                    disagreements: h.disagreements,
                    alarms_raised: result.health.alarms_raised(),
                    alarm_at_end: result.health.alarm(),
                });
                if dock == 0 {
                    let epsilon = config.stretch_m_per_year * config.years / config.chain_m;
                    stretch = Some(StretchReport {
                        actual_per_mille: 1000.0 * epsilon,
                        measured_per_mille: result.meter.stretch_per_mille(),
                        measurements: result.meter.measurements(),
                        alarm: result.meter.alarm(),
                    });
                }
            }
        }
        let mut outcomes = Outcomes::default();
        let mut tip_error = TipError::default();
        for y in &years {
            outcomes.add(&y.outcomes);
            tip_error.merge(&y.tip_error);
        }
        let misdelivered_per_million = if outcomes.sacks == 0 {
            0.0
        } else {
            1e6 * outcomes.misdelivered as f64 / outcomes.sacks as f64
        };
        scenarios.push(ScenarioReport {
            scenario,
            name: scenario.name(),
            outcomes,
            misdelivered_per_million,
            tip_error,
            years,
            recalibrations,
            curve,
        });
    }
    let stretch = stretch.ok_or("no dock was simulated")?;
    Ok(Report {
        config: config.clone(),
        scenarios,
        readers,
        stretch,
    })
}

/// A trolley physically on the chain.
#[derive(Clone, Copy)]
struct Carried {
    truth: Destination,
    entered: u64,
    has_sack: bool,
    routed: bool,
}

fn run_dock(
    config: &Config,
    scenario: Scenario,
    dock: u8,
    progress: &mut impl FnMut(u64),
) -> Result<DockResult, String> {
    // The same seed for every scenario: the same trolleys, destinations and misreads.
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed ^ (u64::from(dock) << 56));
    let p0 = 1.0 / PULSES_PER_M;
    let sia = (config.initiator_span_m * PULSES_PER_M).round() as u32;
    let bins: Vec<f64> = (0..config.bins).map(|b| config.bin_position_m(b)).collect();
    let sa: Vec<u32> = bins
        .iter()
        .map(|x| ((x / p0).round() as u32).saturating_sub(LEAD_PULSES))
        .collect();
    let table: DistanceTable<MAX_BINS> = DistanceTable::new(sia, &sa).map_err(|e| e.to_string())?;
    let mut tracker: Box<DockTracker> =
        Box::new(Tracker::new(table, SOURCE_HOLD_PULSES).map_err(|e| e.to_string())?);
    let mut meter = StretchMeter::new(StretchConfig::new(sia)).map_err(|e| e.to_string())?;
    let mut voter = Voter::new(config.strategy).map_err(|e| e.to_string())?;
    let mut health: ReaderHealth<1000> = ReaderHealth::new(AlarmLimits {
        disagreement_per_mille: config.alarm_disagreement_per_mille,
        ..AlarmLimits::default()
    })
    .map_err(|e| e.to_string())?;

    // Every trolley in the plant has a destination somewhere: the registry the readers share.
    let mut registry: Registry<Destination> = Registry::new();
    for id in TrolleyId::all() {
        let d = Destination {
            dock: rng.random_range(0..config.docks),
            bin: rng.random_range(0..config.bins),
        };
        registry.assign(id, d);
    }

    let rate = config.reader_rate(dock);
    let disturbed = (rate / DISTURBED_SHARE).min(1.0);
    let pulses_total = config.pulses_per_dock();
    let pulses_per_year = f64::from(config.trolleys_per_year) * f64::from(config.mean_gap_pulses);
    let measure_every =
        ((pulses_per_year / f64::from(config.measurements_per_year)).round() as u64).max(1);
    let chain_pulses = (config.chain_m * PULSES_PER_M) as u64;

    // Trolleys on the chain by entry pulse; at most one enters per pulse.
    let ring_len = (chain_pulses as usize * 2).next_power_of_two();
    let mut on_chain: Vec<Option<Carried>> = vec![None; ring_len];
    let mut set = vec![false; usize::from(config.bins)];
    let mut years: Vec<YearReport> = Vec::new();
    let mut curve = vec![TipError::default(); CURVE_POINTS];
    let mut recalibrations = 0;
    let mut next_entry = 0u64;
    let mut events: Vec<TipperEvent<Tag>> = Vec::new();

    for pulse in 1..=pulses_total {
        let t_years = pulse as f64 / pulses_per_year;
        let year = ((pulse - 1) as f64 / pulses_per_year).floor() as usize;
        while years.len() <= year {
            years.push(YearReport {
                year: years.len() as u32 + 1,
                ..YearReport::default()
            });
        }
        let epsilon = config.stretch_m_per_year * t_years / config.chain_m;
        let pitch = p0 * (1.0 + epsilon);

        // The chain moves one pulse: the tracker hears it.
        events.clear();
        tracker.pulse(|e| events.push(e));
        for e in &events {
            match *e {
                TipperEvent::Set {
                    tipper,
                    trolley: (_, entered),
                } => {
                    set[tipper] = true;
                    // Where was the trolley the tracker meant, against where it should be?
                    let travelled_m = (pulse - entered) as f64 * pitch;
                    let meant_m = bins[tipper] - f64::from(LEAD_PULSES) * p0;
                    years[year].tip_error.record(travelled_m - meant_m);
                    let bin = (pulse.saturating_sub(1) as usize * CURVE_POINTS)
                        / pulses_total.max(1) as usize;
                    if let Some(e) = curve.get_mut(bin) {
                        e.record(travelled_m - meant_m);
                    }
                }
                TipperEvent::Reset { tipper } => set[tipper] = false,
            }
        }

        // Sacks fall wherever a trolley passes a set tipper in the coming pulse: trolley `e` is
        // at (pulse − e)·pitch, so it passes bin x when that crosses x. The pitch grows a
        // little every pulse, so one or two trolleys can cross in one pulse.
        let pitch_next = p0
            * (1.0
                + config.stretch_m_per_year * (pulse + 1) as f64
                    / pulses_per_year
                    / config.chain_m);
        for (bin, _) in set.iter().enumerate().filter(|(_, s)| **s) {
            let first = (pulse as f64 - bins[bin] / pitch).floor() + 1.0;
            let last = ((pulse + 1) as f64 - bins[bin] / pitch_next).floor();
            if last < 0.0 {
                continue;
            }
            for entered in (first.max(0.0) as u64)..=(last as u64) {
                let slot = &mut on_chain[entered as usize % ring_len];
                if let Some(c) = slot.as_mut().filter(|c| c.entered == entered && c.has_sack) {
                    c.has_sack = false;
                    let o = &mut years[year].outcomes;
                    if c.truth.bin == bin as u16 {
                        o.delivered += 1;
                    } else {
                        o.misdelivered += 1;
                    }
                }
            }
        }

        // A trolley leaves the chain end.
        if let Some(left) = pulse.checked_sub(chain_pulses) {
            let slot = &mut on_chain[left as usize % ring_len];
            if let Some(c) = slot.take_if(|c| c.entered == left) {
                if c.has_sack && c.routed {
                    years[year].outcomes.not_tipped += 1;
                }
            }
        }

        // The reference mark passes the second initiator.
        if pulse % measure_every == 0 {
            let true_dia = (config.initiator_span_m / pitch).round() as u32;
            let dia = if rng.random_bool(config.glitch_rate) {
                if rng.random_bool(0.5) {
                    true_dia + 1
                } else {
                    true_dia - 1
                }
            } else {
                true_dia
            };
            if let Measurement::Accepted { dia } = meter.measure(dia) {
                if scenario.correction && tracker.recalibrate(dia).map_err(|e| e.to_string())? {
                    recalibrations += 1;
                }
            }
        }

        // A trolley reaches the reader.
        if pulse >= next_entry {
            let gap = MIN_GAP_PULSES
                + rng.random_range(0..=2 * (config.mean_gap_pulses - MIN_GAP_PULSES));
            next_entry = pulse + u64::from(gap);
            let id = TrolleyId::new(rng.random_range(1..=4095)).ok_or("trolley number")?;
            let truth = Destination {
                dock,
                bin: rng.random_range(0..config.bins),
            };
            registry.assign(id, truth); // keyed at the loading desk
            let scans = scan(&mut rng, encode(id), config.readings, disturbed);
            let passage: Passage = if scenario.voting {
                voter.vote(&scans)
            } else {
                single_read(scans[0])
            };
            health.record(&passage);
            let route = registry.route(&passage.verdict, |d| d.dock == dock);
            let mut carried = Carried {
                truth,
                entered: pulse,
                has_sack: true,
                routed: false,
            };
            years[year].outcomes.sacks += 1;
            match route {
                Route::Deliver {
                    trolley,
                    destination,
                } => match tracker.enter((trolley, pulse), usize::from(destination.bin)) {
                    Ok(()) => carried.routed = true,
                    Err(_) => years[year].outcomes.rejected += 1,
                },
                Route::Reject(_) => years[year].outcomes.rejected += 1,
            }
            // A rejected sack goes to the manual station at the reader: no tipper can drop it.
            carried.has_sack = carried.routed;
            on_chain[pulse as usize % ring_len] = Some(carried);
        }

        if pulse % 65_536 == 0 {
            progress(65_536);
        }
    }
    progress(pulses_total % 65_536);
    // Sacks still riding to their bins when the run ends.
    let still = on_chain
        .iter()
        .flatten()
        .filter(|c| c.has_sack && c.routed)
        .count() as u64;
    if let Some(last) = years.last_mut() {
        last.outcomes.on_chain += still;
    }
    Ok(DockResult {
        years,
        curve,
        recalibrations,
        health,
        meter,
    })
}

/// The scans a reader takes of one passing trolley.
fn scan(rng: &mut ChaCha8Rng, word: u16, readings: u8, disturbed: f64) -> Vec<u16> {
    let swinging = rng.random_bool(disturbed);
    (0..readings)
        .map(|_| {
            if swinging && rng.random_bool(DISTURBED_SHARE) {
                let flips = match rng.random_range(0..100) {
                    0..50 => 1,
                    50..85 => 2,
                    _ => 3,
                };
                let mut w = word;
                let mut flipped = 0;
                while flipped < flips {
                    let bit = 1u16 << rng.random_range(0..13);
                    if (w ^ word) & bit == 0 {
                        w ^= bit;
                        flipped += 1;
                    }
                }
                w
            } else {
                word
            }
        })
        .collect()
}

/// The source's reading: one scan, parity checked, nothing else.
fn single_read(raw: u16) -> Passage {
    let verdict = match decode(raw) {
        Ok(id) => Verdict::Identified(id),
        Err(e) => Verdict::NoRead(NoRead::Undecodable(e)),
    };
    Passage {
        verdict,
        samples: 1,
        no_cams: u16::from(raw == 0),
        parity_errors: u16::from(decode(raw).is_err() && raw != 0),
        faulty_words: 0,
        disagreement: false,
    }
}
