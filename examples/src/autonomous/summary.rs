//! The text a user reads: the operator's transcript with its simulated times, the run's summary
//! (what was simulated, IAE, overshoot, settling, alarms, commits), and the autotune result.

use std::fmt::Write as _;

use super::{AutotuneReport, Shown, SimReport};

/// Simulated seconds as a clock from the start, `hh:mm:ss` (hours past 24 go on counting).
#[must_use]
pub fn clock(t: f64) -> String {
    let s = t.round() as u64;
    format!("{:02}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

/// Lines the operator saw, each with its simulated time (the lines of an LCD picture indented
/// under the first).
#[must_use]
pub fn transcript(shown: &[Shown]) -> Vec<String> {
    let mut lines = Vec::new();
    for s in shown {
        for (i, line) in s.text.lines().enumerate() {
            lines.push(if i == 0 {
                format!("[{}] {line}", clock(s.t_s))
            } else {
                format!("        {line}")
            });
        }
    }
    lines
}

/// The run's summary, a line a figure, the LCD at the end last.
#[must_use]
pub fn summary(r: &SimReport) -> String {
    let mut s = String::new();
    let unit = r.config.process.unit();
    // What was simulated, and when the operator quit before the end asked for, that too.
    let asked = r.config.hours;
    let simulated = if r.simulated_h + 1e-6 < asked {
        format!(
            "{:.1} h simulated (ended before the {} h asked for)",
            r.simulated_h,
            crate::cli::number(asked)
        )
    } else {
        format!("{:.1} h simulated", r.simulated_h)
    };
    let _ = writeln!(
        s,
        "Autonomous controller, {} process, {simulated}, seed {}",
        r.config.process.name(),
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
    if r.commits_s.is_empty() {
        let _ = writeln!(s, "  commits            0");
    } else {
        let commits: Vec<String> = r.commits_s.iter().map(|t| clock(*t)).collect();
        let _ = writeln!(
            s,
            "  commits            {} at {}",
            commits.len(),
            commits.join(", ")
        );
    }
    if r.commit_pending_at_end {
        let _ = writeln!(
            s,
            "  (a commit was keyed but the run ended before the next sample put it into force)"
        );
    }
    let _ = writeln!(s, "  samples            {}", r.samples);
    let _ = writeln!(s, "  controller faults  {}", r.faults);
    let _ = write!(s, "LCD at the end:\n{}", r.final_lcd);
    s
}

/// The autotune result: the relay experiment, the tuning, the hand-over and the step.
#[must_use]
pub fn autotune_summary(r: &AutotuneReport) -> String {
    let unit = r.process.unit();
    let process = r.process.name();
    match &r.ultimate {
        Err(e) => format!(
            "relay experiment on the {process}: failed after {:.0} s: {e}",
            r.experiment_s
        ),
        Ok((ku, tu)) => format!(
            "relay experiment on the {process}: output {:.1} ± {:.1} V, hysteresis {} {unit}\n  \
             limit cycle after {:.0} s: Ku = {ku:.3} V/{unit}, Tu = {tu:.0} s\n  \
             Ziegler–Nichols PI: K = {:.3} V/{unit}, Ti = {:.0} s; hand-over jump {:.3} V\n  \
             set-point step of {} {unit}: overshoot {:.0} %, within 5 % after {}",
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
