//! Faults on demand: the `--fault KIND@HH:MM:SS:ARGS` syntax ([`FAULT_SYNTAX`], [`parse_fault`]:
//! the time always with its seconds, then exactly the kind's arguments; durations at most
//! [`MAX_FAULT_SECONDS`]), the check that power failures and hangs do not overlap
//! ([`check_faults`]), and what each kind does to the run (`run.rs` applies them; a power
//! failure or hang that comes while one is on is ignored there, which is why the binary refuses
//! them first).

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

/// The longest a fault may last: 7 days (604 800 seconds). Longer is refused.
pub const MAX_FAULT_SECONDS: u64 = 7 * 24 * 3600;

/// The `--fault` syntax, for `--help` and errors.
pub const FAULT_SYNTAX: &str = "KIND@HH:MM:SS:ARGS (the time always with its seconds, then \
exactly the kind's arguments), one of: misread@T:READER:RATE, reader-fails@T:READER, \
noise@T:PANEL:BIT_ERROR_RATE, stuck@T:INPUT:0|1:SECONDS, chatter@T:INPUT:SECONDS, \
power@T:SECONDS, hang@T:SECONDS, pulses@T:DOCK:RATE:SECONDS (READER R1–R12, PANEL P1–P3/A/B/\
central, INPUT a name like full-E3, present-R5, pulse-1 or a number 0–543, DOCK 1–3, RATE 0 to \
0.5, SECONDS 1 to 604800, or 0 for good with stuck and pulses; a power failure or a hang must \
start after the one before it is over)";

fn parse_reader(s: &str) -> Result<usize, String> {
    (0..READERS)
        .find(|&r| READER_NAMES[r].eq_ignore_ascii_case(s))
        .ok_or_else(|| format!("reader must be R1 to R12, got '{s}'"))
}

fn rate(s: &str) -> Result<f64, String> {
    let r: f64 = num(Some(&s), "rate")?;
    if (0.0..=0.5).contains(&r) {
        Ok(r)
    } else {
        Err(format!("rate must be from 0 to 0.5, got {r}"))
    }
}

/// Seconds from `min` to [`MAX_FAULT_SECONDS`].
fn seconds(s: &str, min: u64) -> Result<u64, String> {
    match s.parse::<u64>() {
        Ok(n) if (min..=MAX_FAULT_SECONDS).contains(&n) => Ok(n),
        _ => Err(format!(
            "seconds must be a whole number from {min} to {MAX_FAULT_SECONDS} (7 days), got '{s}'"
        )),
    }
}

fn input(s: &str) -> Result<usize, String> {
    input_point(s).ok_or_else(|| format!("no input named '{s}'"))
}

/// Parses one `--fault`: `KIND@HH:MM:SS` and then exactly the kind's arguments, each after a
/// `:` (see [`FAULT_SYNTAX`]). A missing or extra argument, or a time without its seconds, is
/// refused.
///
/// # Errors
/// What is wrong, with the syntax.
pub fn parse_fault(s: &str) -> Result<Fault, String> {
    let (kind, rest) = s
        .split_once('@')
        .ok_or_else(|| format!("no '@' in '{s}'; expected {FAULT_SYNTAX}"))?;
    let parts: Vec<&str> = rest.split(':').collect();
    let wanted = match kind {
        "reader-fails" | "power" | "hang" => 1,
        "misread" | "noise" | "chatter" => 2,
        "stuck" | "pulses" => 3,
        other => return Err(format!("unknown fault '{other}'; expected {FAULT_SYNTAX}")),
    };
    if parts.len() != 3 + wanted {
        return Err(format!(
            "'{s}': {kind} takes the time HH:MM:SS and then {wanted} argument{}: {} parts after \
             the '@' separated by ':', got {}; expected {FAULT_SYNTAX}",
            if wanted == 1 { "" } else { "s" },
            3 + wanted,
            parts.len(),
        ));
    }
    let at_ms = parse_time(&parts[..3].join(":")).map_err(|e| format!("'{s}': {e}"))?;
    let a = &parts[3..];
    let kind = match kind {
        "misread" => FaultKind::Misread {
            reader: parse_reader(a[0])?,
            rate: rate(a[1])?,
        },
        "reader-fails" => FaultKind::ReaderFails {
            reader: parse_reader(a[0])?,
        },
        "noise" => FaultKind::Noise {
            panel: parse_panel(a[0])?,
            rate: rate(a[1])?,
        },
        "stuck" => FaultKind::Stuck {
            point: input(a[0])?,
            on: match a[1] {
                "1" => true,
                "0" => false,
                other => return Err(format!("stuck needs 0 or 1 after the input, got '{other}'")),
            },
            secs: seconds(a[2], 0)?,
        },
        "chatter" => FaultKind::Chatter {
            point: input(a[0])?,
            secs: seconds(a[1], 1)?,
        },
        "power" => FaultKind::Power {
            secs: seconds(a[0], 1)?,
        },
        "hang" => FaultKind::Hang {
            secs: seconds(a[0], 1)?,
        },
        _ => {
            let dock: usize = num(Some(&a[0]), "dock")?;
            if !(1..=3).contains(&dock) {
                return Err(format!("dock must be 1 to 3, got {dock}"));
            }
            FaultKind::MissedPulses {
                dock: dock - 1,
                rate: rate(a[1])?,
                secs: seconds(a[2], 0)?,
            }
        }
    };
    Ok(Fault { at_ms, kind })
}

/// Checks the faults of one run together: a power failure may not start before the one before
/// it is over (the power back), nor a hang before the one before it (the program restarted).
///
/// # Errors
/// The two faults that overlap.
pub fn check_faults(faults: &[Fault]) -> Result<(), String> {
    let mut sorted: Vec<&Fault> = faults.iter().collect();
    sorted.sort_by_key(|f| f.at_ms);
    for what in ["power", "hang"] {
        let mut over: Option<u64> = None;
        for f in &sorted {
            let secs = match (what, f.kind) {
                ("power", FaultKind::Power { secs }) | ("hang", FaultKind::Hang { secs }) => secs,
                _ => continue,
            };
            if over.is_some_and(|end| f.at_ms <= end) {
                return Err(format!(
                    "a {what} fault at {} starts before the one before it is over (at {}); \
                     give the next one a later time",
                    hms(f.at_ms),
                    hms(over.unwrap_or(0)),
                ));
            }
            over = Some(f.at_ms.saturating_add(secs.saturating_mul(1000)));
        }
    }
    Ok(())
}

fn hms(ms: u64) -> String {
    let s = ms / 1000;
    format!("{:02}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faults_parse_and_bad_ones_are_refused() {
        assert_eq!(
            parse_fault("power@06:30:00:20").unwrap(),
            Fault {
                at_ms: 23_400_000,
                kind: FaultKind::Power { secs: 20 }
            }
        );
        assert_eq!(
            parse_fault("misread@01:00:00:R5:0.01").unwrap().kind,
            FaultKind::Misread {
                reader: 4,
                rate: 0.01
            }
        );
        assert_eq!(
            parse_fault("stuck@01:00:30:full-E3:1:0").unwrap().at_ms,
            3_630_000
        );
        assert_eq!(
            parse_fault("stuck@00:10:00:15:1:0").unwrap().kind,
            FaultKind::Stuck {
                point: 15,
                on: true,
                secs: 0
            }
        );
        for bad in [
            "nonsense",
            "misread@01:00:00:R13:0.1",
            "stuck@01:00:00:nowhere:1:0",
            "power@06:30:20",      // no seconds in the time
            "hang@00:10:00",       // no duration
            "power@00:10:00:0",    // no power failure of 0 s
            "power@00:10:20:10:5", // an extra argument
            "reader-fails@00:00:00:R1:junk",
            "stuck@00:10:00:15:1", // the duration missing
            "chatter@00:00:00:pulse-1:604801",
            "hang@00:10:00:18446744073709551615",
        ] {
            assert!(parse_fault(bad).is_err(), "{bad}");
        }
        assert!(parse_fault("chatter@00:00:00:pulse-1:604800").is_ok());
    }

    #[test]
    fn overlapping_power_failures_and_hangs_are_refused() {
        let f = |s: &str| parse_fault(s).unwrap();
        let ok = [
            f("power@00:10:00:20"),
            f("power@00:10:21:5"),
            f("hang@00:10:05:5"),
        ];
        assert_eq!(check_faults(&ok), Ok(()));
        for second in ["power@00:10:00:5", "power@00:10:20:5"] {
            let e = check_faults(&[f("power@00:10:00:20"), f(second)]).unwrap_err();
            assert!(e.contains("power fault at 00:10:"), "{e}");
        }
        assert!(check_faults(&[f("hang@00:10:00:20"), f("hang@00:10:19:5")]).is_err());
    }
}
