//! The four controllers — parity only or voting, with or without stretch correction — each
//! run over every dock on the same trolleys and misreads, and their results gathered.

use super::Config;
use super::docks::run_dock;
use super::report::{
    CURVE_POINTS, CurvePoint, Outcomes, ReaderReport, Report, ScenarioReport, StretchReport,
    TipError, YearReport,
};
use serde::Serialize;

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
