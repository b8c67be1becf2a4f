//! The results: the JSON summary for machines (`--json`) and the closing text for a person.

use serde::Serialize;

use super::modbus::ServerReport;
use super::plant::Tally;
use super::simulator::Simulator;
use super::{SIGNALS, monitor::Transcript};

/// A forced point in the JSON summary.
#[derive(Clone, Debug, Serialize)]
pub struct Forced {
    /// The point's number.
    pub point: usize,
    /// Its name, if the conveyor uses it (`""` otherwise).
    pub name: &'static str,
    /// The value it is forced to.
    pub value: bool,
}

/// What `--json` prints.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// The plant's seed.
    pub seed: u64,
    /// Cycles run.
    pub cycles: u64,
    /// Parts counted by the program.
    pub parts: i32,
    /// What happened to the parts.
    pub tally: Tally,
    /// The executive's cycle statistics.
    pub stats: regler_scan_cycle::CycleStats,
    /// Busy time over the period, ‰.
    pub load_per_mille: u32,
    /// Reports run in the reserve.
    pub reports_run: u64,
    /// Power failures survived.
    pub power_failures: u32,
    /// Reports waiting in the spool.
    pub spool_waiting: usize,
    /// Inputs forced at the end.
    pub forced_inputs: Vec<Forced>,
    /// Outputs forced at the end.
    pub forced_outputs: Vec<Forced>,
    /// Every command and its output, and every Modbus request.
    pub log: Vec<String>,
    /// With `--modbus`: what the server did with its clients (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modbus: Option<ServerReport>,
}

fn forced(points: impl Iterator<Item = (usize, bool)>, input: bool) -> Vec<Forced> {
    points
        .map(|(point, value)| Forced {
            point,
            name: SIGNALS
                .iter()
                .find(|&&(_, i, p)| i == input && p == point)
                .map_or("", |&(name, ..)| name),
            value,
        })
        .collect()
}

impl Summary {
    /// The summary of a finished run.
    #[must_use]
    pub fn new(sim: &Simulator, seed: u64, log: Vec<String>) -> Summary {
        let st = *sim.plc.stats();
        Summary {
            seed,
            cycles: sim.plc.cycle_count(),
            parts: sim.program.parts(),
            tally: sim.plant.tally,
            stats: st,
            load_per_mille: st.load_per_mille(sim.plc.config().period_us),
            reports_run: sim.reports_run,
            power_failures: sim.power_failures,
            spool_waiting: sim.program.spool.len(),
            forced_inputs: forced(sim.plc.forced_inputs().iter(), true),
            forced_outputs: forced(sim.plc.forced_outputs().iter(), false),
            log,
            modbus: None,
        }
    }
}

/// The closing text: the statistics (unless the monitor's last command printed exactly them)
/// and where the picture went.
#[must_use]
pub fn closing(
    sim: &Simulator,
    transcript: &Transcript,
    server: Option<&ServerReport>,
    picture: Option<&std::path::Path>,
) -> String {
    let stats = sim.stats();
    let mut text = if transcript.printed_last(&stats) {
        String::new()
    } else {
        stats
    };
    if let Some(r) = server {
        text.push_str(&server_line(r));
    }
    if let Some(path) = picture {
        text.push_str(&format!("Timing diagram: {}\n", path.display()));
    }
    text
}

/// The Modbus server's line in the closing text.
fn server_line(r: &ServerReport) -> String {
    let mut line = format!(
        "Modbus: {} client{} (at most {} at once), {} closed over that cap, {} closed idle after {} s",
        r.clients,
        if r.clients == 1 { "" } else { "s" },
        r.max_clients,
        r.refused_over_cap,
        r.closed_idle,
        crate::cli::number(r.idle_timeout_s),
    );
    if r.spawn_failures > 0 {
        line.push_str(&format!(
            ", {} closed for want of a thread",
            r.spawn_failures
        ));
    }
    if r.accept_errors > 0 {
        line.push_str(&format!(", {} failed accepts", r.accept_errors));
    }
    line.push('\n');
    if let Some(why) = &r.listener_error {
        line.push_str(&format!("Modbus server stopped early: {why}\n"));
    }
    line
}
