//! Faults on demand: the `--fault KIND@TIME[:ARGS]` syntax and what each kind does to the run
//! (`run.rs` applies them).

use super::layout::{READER_NAMES, READERS, input_point};
use super::operator::PanelId;
use super::traffic::{num, parse_panel, parse_time};

/// A fault on demand (the fields are named in [`FAULT_SYNTAX`]).
#[allow(
    missing_docs,
    reason = "the fields are the syntax's arguments, documented there"
)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FaultKind {
    /// Reader's single-scan misread rate from then on.
    Misread { reader: usize, rate: f64 },
    /// The reader reads nothing (no cams) from then on.
    ReaderFails { reader: usize },
    /// Bit error rate on a panel's line.
    Noise { panel: PanelId, rate: f64 },
    /// An input stuck at a value, for `secs` (0: for good).
    Stuck { point: usize, on: bool, secs: u64 },
    /// An input that toggles at every read, for `secs`.
    Chatter { point: usize, secs: u64 },
    /// The power fails for `secs`.
    Power { secs: u64 },
    /// The program hangs for `secs`; the watchdog trips, then the operator restarts it.
    Hang { secs: u64 },
    /// A chain's pulse initiator misses pulses at `rate`, for `secs`.
    MissedPulses { dock: usize, rate: f64, secs: u64 },
}

/// A fault at a time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fault {
    /// Milliseconds from the start.
    pub at_ms: u64,
    /// What.
    pub kind: FaultKind,
}

/// The `--fault` syntax, for `--help` and errors.
pub const FAULT_SYNTAX: &str = "KIND@HH:MM[:SS][:ARGS], KIND one of: misread@T:READER:RATE, \
reader-fails@T:READER, noise@T:PANEL:BIT_ERROR_RATE, stuck@T:INPUT:0|1[:SECONDS], \
chatter@T:INPUT[:SECONDS], power@T:SECONDS, hang@T[:SECONDS], pulses@T:DOCK:RATE[:SECONDS] \
(READER R1–R12, PANEL P1–P3/A/B/central, INPUT a name like full-E3, present-R5, pulse-1 or a \
number 0–543, DOCK 1–3)";

fn parse_reader(s: &str) -> Result<usize, String> {
    (0..READERS)
        .find(|&r| READER_NAMES[r].eq_ignore_ascii_case(s))
        .ok_or_else(|| format!("reader must be R1 to R12, got '{s}'"))
}

fn rate(s: Option<&&str>) -> Result<f64, String> {
    let r: f64 = num(s, "rate")?;
    if (0.0..=0.5).contains(&r) {
        Ok(r)
    } else {
        Err(format!("rate must be from 0 to 0.5, got {r}"))
    }
}

/// Parses one `--fault`.
///
/// # Errors
/// What is wrong, with the syntax.
pub fn parse_fault(s: &str) -> Result<Fault, String> {
    let (kind, rest) = s
        .split_once('@')
        .ok_or_else(|| format!("no '@' in '{s}'; expected {FAULT_SYNTAX}"))?;
    let parts: Vec<&str> = rest.split(':').collect();
    // The time is the first two or three parts that are all digits.
    let time_parts = if parts.len() >= 3
        && parts[2].chars().all(|c| c.is_ascii_digit())
        && parts[2].len() == 2
        && !matches!(kind, "power" | "hang")
    {
        3
    } else {
        2
    }
    .min(parts.len());
    let at_ms = parse_time(&parts[..time_parts].join(":")).map_err(|e| format!("'{s}': {e}"))?;
    let a = &parts[time_parts..];
    let secs = |i: usize| -> Result<u64, String> {
        match a.get(i) {
            None => Ok(0),
            Some(x) => x
                .parse()
                .map_err(|_| format!("seconds must be a whole number, got '{x}'")),
        }
    };
    let kind = match kind {
        "misread" => FaultKind::Misread {
            reader: parse_reader(a.first().ok_or("reader missing")?)?,
            rate: rate(a.get(1))?,
        },
        "reader-fails" => FaultKind::ReaderFails {
            reader: parse_reader(a.first().ok_or("reader missing")?)?,
        },
        "noise" => FaultKind::Noise {
            panel: parse_panel(a.first().ok_or("panel missing")?)?,
            rate: rate(a.get(1))?,
        },
        "stuck" => {
            let name = a.first().ok_or("input missing")?;
            let point = input_point(name).ok_or_else(|| format!("no input named '{name}'"))?;
            let on = match a.get(1).copied() {
                Some("1") => true,
                Some("0") => false,
                _ => return Err("stuck needs 0 or 1 after the input".into()),
            };
            FaultKind::Stuck {
                point,
                on,
                secs: secs(2)?,
            }
        }
        "chatter" => {
            let name = a.first().ok_or("input missing")?;
            let point = input_point(name).ok_or_else(|| format!("no input named '{name}'"))?;
            FaultKind::Chatter {
                point,
                secs: secs(1)?.max(1),
            }
        }
        "power" => FaultKind::Power {
            secs: secs(0)?.max(1),
        },
        "hang" => FaultKind::Hang {
            secs: secs(0)?.max(1),
        },
        "pulses" => {
            let dock: usize = num(a.first(), "dock")?;
            if !(1..=3).contains(&dock) {
                return Err(format!("dock must be 1 to 3, got {dock}"));
            }
            FaultKind::MissedPulses {
                dock: dock - 1,
                rate: rate(a.get(1))?,
                secs: secs(2)?,
            }
        }
        other => return Err(format!("unknown fault '{other}'; expected {FAULT_SYNTAX}")),
    };
    Ok(Fault { at_ms, kind })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faults_parse_and_bad_ones_are_refused() {
        assert_eq!(
            parse_fault("power@06:30:20").unwrap(),
            Fault {
                at_ms: 23_400_000,
                kind: FaultKind::Power { secs: 20 }
            }
        );
        assert_eq!(
            parse_fault("misread@01:00:R5:0.01").unwrap().kind,
            FaultKind::Misread {
                reader: 4,
                rate: 0.01
            }
        );
        assert_eq!(
            parse_fault("stuck@01:00:30:full-E3:1").unwrap().at_ms,
            3_630_000
        );
        assert!(parse_fault("nonsense").is_err());
        assert!(parse_fault("misread@01:00:R13:0.1").is_err());
        assert!(parse_fault("stuck@01:00:nowhere:1").is_err());
    }
}
