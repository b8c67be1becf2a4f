//! The text summary: the four controllers side by side, the tip-position error year by year,
//! the readers' health and the stretch meter.

use std::fmt::Write as _;
use std::path::Path;

use super::Report;

/// The summary of `r` for the terminal; `picture` is named at the end when one was written.
#[must_use]
pub fn summary_text(r: &Report, picture: Option<&Path>) -> String {
    let c = &r.config;
    let mut s = String::new();
    // Writing to a String cannot fail.
    macro_rules! line {
        ($($t:tt)*) => { let _ = writeln!(s, $($t)*); };
    }
    line!(
        "Mailbag sorter, {} dock(s) x {} bins, {:.0} m chains stretching {:.1} m/year, {:.2} years, seed {}",
        c.docks,
        c.bins,
        c.chain_m,
        c.stretch_m_per_year,
        c.years,
        c.seed
    );
    line!(
        "Misread rate {:.4} per scan (readers uneven by {:.0} %), {} scans per trolley when voting\n",
        c.misread_rate,
        100.0 * c.reader_spread,
        c.readings
    );
    line!(
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
        line!(
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
    line!("\nTip-position error by year (mean |error|, m): without / with correction");
    let (without, with) = (&r.scenarios[2], &r.scenarios[3]);
    for (a, b) in without.years.iter().zip(&with.years) {
        line!(
            "  year {:>2}: {:>7.3} / {:>6.3}   (max {:>6.2} / {:>5.2})",
            a.year,
            a.tip_error.mean_abs_m,
            b.tip_error.mean_abs_m,
            a.tip_error.max_abs_m,
            b.tip_error.max_abs_m
        );
    }
    line!("\nReader health (voting, with correction):");
    for rd in &r.readers {
        line!(
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
    line!(
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
    line!("Recalibrations with correction: {recal}");
    if let Some(path) = picture {
        line!("\nPicture: {}", path.display());
    }
    s.trim_end().to_string()
}
