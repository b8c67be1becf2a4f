//! What happens to the plant over the day: sacks arriving at the desks (seeded), the
//! operators' settings, and the `--script` that replaces or adds to them.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::layout::BINS;
use super::operator::{BUFFER_LANES, Command, POST_TYPES, PanelId, SCHEDULES};

/// Postcodes in the plant's catalogue (each schedule gives a bin to 150 of them).
pub const POSTCODES: u32 = 300;
const FIRST_POSTCODE: u32 = 20_000;
const POSTCODE_STEP: u32 = 211;

/// The `i`-th postcode of the catalogue.
#[must_use]
pub fn postcode(i: u32) -> u32 {
    FIRST_POSTCODE + POSTCODE_STEP * (i % POSTCODES)
}

/// The bin of `code` in sorting schedule `schedule`, or `None` when the schedule has none
/// (the entry is refused). Schedule `s` sorts postcodes `50·s … 50·s + 149` of the catalogue
/// (wrapping), over the 150 bins in a schedule-specific order.
#[must_use]
pub fn bin_for(schedule: u8, code: u32) -> Option<u8> {
    let offset = code.checked_sub(FIRST_POSTCODE)?;
    if offset % POSTCODE_STEP != 0 || offset / POSTCODE_STEP >= POSTCODES {
        return None;
    }
    let i = offset / POSTCODE_STEP;
    let k = (i + POSTCODES - 50 * u32::from(schedule % SCHEDULES)) % POSTCODES;
    (k < BINS as u32).then(|| ((k * 7 + u32::from(schedule) * 11) % BINS as u32) as u8)
}

/// One thing an operator keys, at a time of the run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Keyed {
    /// Milliseconds from the start of the run.
    pub at_ms: u64,
    /// The panel.
    pub panel: PanelId,
    /// What is keyed.
    pub command: Command,
}

/// The start-up settings the operators key at 00:00: post types to lanes (letters 0–9 on
/// D1–D4 and E1–E6, parcels 10–13 on E7–E10), lanes to emptying stations (letters' lanes two
/// A stations each, parcels' lanes on B and C).
#[must_use]
pub fn start_up_settings() -> Vec<Keyed> {
    let mut out = Vec::new();
    let key = |panel, command| Keyed {
        at_ms: 0,
        panel,
        command,
    };
    for t in 0..POST_TYPES {
        out.push(key(
            PanelId::Central,
            Command::AssignType {
                post_type: t,
                lane: t,
            },
        ));
    }
    for lane in 0..BUFFER_LANES {
        let (panel, stations) = match lane {
            0..10 => (PanelId::A, 0b111 & !(1 << (lane % 3))),
            10 | 11 => (PanelId::B, 0b0011000),
            _ => (PanelId::B, 0b1100000),
        };
        out.push(key(panel, Command::Emptying { lane, stations }));
    }
    out
}

/// A sack at a desk: what the operator will key for it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SackArrival {
    /// Milliseconds from the start.
    pub at_ms: u64,
    /// Desk 0–2.
    pub desk: u8,
    /// What it is: a post type, or a postcode (P1 and P2 only).
    pub entry: Command,
}

/// Sacks per hour over the three desks at the day's peak.
pub const PEAK_SACKS_PER_HOUR: f64 = 1_200.0;

/// The traffic's share of the peak at `hour` of the day: night post from 04, peaks at 07 and
/// 17, quiet after 22.
#[must_use]
pub fn day_profile(hour: u64) -> f64 {
    const PROFILE: [f64; 24] = [
        0.15, 0.1, 0.1, 0.1, 0.4, 0.7, 0.9, 1.0, 0.9, 0.7, 0.6, 0.6, 0.6, 0.6, 0.7, 0.8, 0.9, 1.0,
        0.9, 0.7, 0.5, 0.4, 0.3, 0.2,
    ];
    PROFILE[(hour % 24) as usize]
}

/// The seeded day(s) of sacks and of the operators' changes: `hours` of traffic, `scale` times
/// the usual rate. The schedule of the sorted post is drawn from when each sack comes (a few
/// postcodes have no bin in it: refused).
#[must_use]
pub fn workload(
    seed: u64,
    hours: f64,
    scale: f64,
    schedule_at: impl Fn(u64) -> u8,
) -> (Vec<SackArrival>, Vec<Keyed>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5AC5);
    let end_ms = (hours * 3_600_000.0) as u64;
    let mut sacks = Vec::new();
    let mut t = 0u64;
    loop {
        let rate_per_ms = PEAK_SACKS_PER_HOUR * scale * day_profile(t / 3_600_000) / 3_600_000.0;
        let gap = -(1.0 - rng.random::<f64>()).ln() / rate_per_ms.max(1e-9);
        t += gap.ceil() as u64;
        if t >= end_ms {
            break;
        }
        let desk = rng.random_range(0..3u8);
        let sorted = desk < 2 && rng.random_bool(0.35);
        let entry = if sorted {
            let s = u32::from(schedule_at(t));
            let i = if rng.random_bool(0.03) {
                50 * s + 150 + rng.random_range(0..150) // none in this schedule
            } else {
                50 * s + rng.random_range(0..150)
            };
            Command::Postcode(postcode(i))
        } else if rng.random_bool(0.75) {
            Command::PostType(rng.random_range(0..10))
        } else {
            Command::PostType(rng.random_range(10..14))
        };
        sacks.push(SackArrival {
            at_ms: t,
            desk,
            entry,
        });
    }
    // Now and then the central desk moves a post type, panel A a lane's stations.
    let mut changes = Vec::new();
    let mut t = 0u64;
    loop {
        t += rng.random_range(1_800_000..7_200_000);
        if t >= end_ms {
            break;
        }
        if rng.random_bool(0.5) {
            let post_type = rng.random_range(0..10);
            let lane = rng.random_range(0..10);
            changes.push(Keyed {
                at_ms: t,
                panel: PanelId::Central,
                command: Command::AssignType { post_type, lane },
            });
        } else {
            let lane = rng.random_range(0..10);
            let stations = rng.random_range(1..8u8);
            changes.push(Keyed {
                at_ms: t,
                panel: PanelId::A,
                command: Command::Emptying { lane, stations },
            });
        }
    }
    (sacks, changes)
}

/// What a `--script` file holds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Script {
    /// Sacks to add.
    pub sacks: Vec<SackArrival>,
    /// Operators' commands.
    pub keyed: Vec<Keyed>,
    /// `replace` was given: the seeded workload is left out.
    pub replace: bool,
}

/// `HH:MM[:SS]` (hours may pass 23 for later days) to milliseconds.
///
/// # Errors
/// A message saying what is wrong.
pub fn parse_time(s: &str) -> Result<u64, String> {
    let parts: Vec<&str> = s.split(':').collect();
    let bad = || format!("time must be HH:MM or HH:MM:SS, got '{s}'");
    if !(2..=3).contains(&parts.len()) {
        return Err(bad());
    }
    let n: Vec<u64> = parts
        .iter()
        .map(|p| p.parse::<u64>().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    if n[0] > 10_000 || n[1] > 59 || n.get(2).is_some_and(|&s| s > 59) {
        return Err(bad());
    }
    Ok(((n[0] * 60 + n[1]) * 60 + n.get(2).copied().unwrap_or(0)) * 1000)
}

pub(super) fn parse_panel(s: &str) -> Result<PanelId, String> {
    Ok(match s.to_ascii_uppercase().as_str() {
        "P1" => PanelId::Desk(0),
        "P2" => PanelId::Desk(1),
        "P3" => PanelId::Desk(2),
        "A" => PanelId::A,
        "B" => PanelId::B,
        "CENTRAL" => PanelId::Central,
        _ => {
            return Err(format!(
                "panel must be P1, P2, P3, A, B or central, got '{s}'"
            ));
        }
    })
}

pub(super) fn num<T: std::str::FromStr>(s: Option<&&str>, what: &str) -> Result<T, String> {
    let s = s.ok_or_else(|| format!("{what} missing"))?;
    s.parse()
        .map_err(|_| format!("{what} must be a number, got '{s}'"))
}

/// Parses a script. Lines: `HH:MM[:SS] PANEL COMMAND ARGS`, `#` comments, blank lines, and
/// `replace` alone (the seeded workload is left out). Commands, each with exactly the
/// arguments shown (an extra word is refused), at the panels whose keyboards take them (the
/// same rules as [`super::panels::keyboard`]):
/// - `P1|P2|P3 type N` (a sack of post type 0–13), `P1|P2 postcode NNNNN` (a postcode that has
///   a bin in at least one sorting schedule: one of the catalogue's 300);
/// - `central assign TYPE LANE` (lane D1–D4 or E1–E11), `central schedule N|calendar` (N 1–6);
/// - `A emptying LANE STATIONS` (stations of panel A: `A1,A3`), `B emptying LANE STATIONS`
///   (stations of panel B: B1, B2, C1, C2);
/// - any panel: `lamptest`.
///
/// # Errors
/// `line N: …` for the first bad line.
pub fn parse_script(text: &str) -> Result<Script, String> {
    parse_lines(text)
}

/// [`parse_script`] on a file's bytes: text that is not UTF-8 is refused naming the first line
/// that is not.
///
/// # Errors
/// `line N: …` for the first bad line.
pub fn parse_script_bytes(bytes: &[u8]) -> Result<Script, String> {
    match std::str::from_utf8(bytes) {
        Ok(text) => parse_lines(text),
        Err(e) => {
            let line = bytes[..e.valid_up_to()]
                .iter()
                .filter(|&&b| b == b'\n')
                .count()
                + 1;
            Err(format!("line {line}: not UTF-8 text"))
        }
    }
}

fn parse_lines(text: &str) -> Result<Script, String> {
    let mut script = Script::default();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        if line.eq_ignore_ascii_case("replace") {
            script.replace = true;
            continue;
        }
        parse_line(line, &mut script).map_err(|e| format!("line {}: {e}", i + 1))?;
    }
    Ok(script)
}

fn lane_number(s: &str) -> Result<u8, String> {
    (0..BUFFER_LANES)
        .find(|&l| super::operator::lane_name(l).eq_ignore_ascii_case(s))
        .ok_or_else(|| format!("lane must be D1–D4 or E1–E11, got '{s}'"))
}

fn parse_line(line: &str, script: &mut Script) -> Result<(), String> {
    let words: Vec<&str> = line.split_whitespace().collect();
    let at_ms = parse_time(words[0])?;
    let panel = parse_panel(words.get(1).ok_or("panel missing")?)?;
    let command = words.get(2).ok_or("command missing")?.to_ascii_lowercase();
    let args = &words[3..];
    let wanted = match command.as_str() {
        "lamptest" => 0,
        "type" | "postcode" | "schedule" => 1,
        "assign" | "emptying" => 2,
        _ => args.len(), // no such command: refused below
    };
    if args.len() > wanted {
        return Err(format!(
            "too many words: '{command}' takes {wanted}, got '{}'",
            args.join(" ")
        ));
    }
    let keyed = |command| Keyed {
        at_ms,
        panel,
        command,
    };
    match (panel, command.as_str()) {
        (PanelId::Desk(d), "type") => {
            let t: u8 = num(args.first(), "post type")?;
            if t >= POST_TYPES {
                return Err(format!("post type must be 0 to 13, got {t}"));
            }
            script.sacks.push(SackArrival {
                at_ms,
                desk: d,
                entry: Command::PostType(t),
            });
        }
        (PanelId::Desk(d), "postcode") if d < 2 => {
            let code: u32 = num(args.first(), "postcode")?;
            if !(10_000..=99_999).contains(&code) {
                return Err(format!("postcode must have five digits, got {code}"));
            }
            if (0..SCHEDULES).all(|s| bin_for(s, code).is_none()) {
                return Err(format!("postcode {code} has a bin in no sorting schedule"));
            }
            script.sacks.push(SackArrival {
                at_ms,
                desk: d,
                entry: Command::Postcode(code),
            });
        }
        (PanelId::Central, "assign") => {
            let t: u8 = num(args.first(), "post type")?;
            let lane = lane_number(args.get(1).ok_or("lane missing")?)?;
            if t >= POST_TYPES {
                return Err(format!("post type must be 0 to 13, got {t}"));
            }
            script
                .keyed
                .push(keyed(Command::AssignType { post_type: t, lane }));
        }
        (PanelId::Central, "schedule") => {
            let arg = args.first().ok_or("schedule missing")?;
            let s = if arg.eq_ignore_ascii_case("calendar") {
                None
            } else {
                let n: u8 = num(Some(arg), "schedule")?;
                if !(1..=SCHEDULES).contains(&n) {
                    return Err(format!("schedule must be 1 to 6 or calendar, got {n}"));
                }
                Some(n - 1)
            };
            script.keyed.push(keyed(Command::Schedule(s)));
        }
        (PanelId::A | PanelId::B, "emptying") => {
            let lane = lane_number(args.first().ok_or("lane missing")?)?;
            let (mine, names) = if panel == PanelId::A {
                (0..3, "A1–A3")
            } else {
                (3..7, "B1, B2, C1 or C2")
            };
            let mut stations = 0u8;
            for name in args.get(1).ok_or("stations missing")?.split(',') {
                let s = mine
                    .clone()
                    .find(|&s| super::operator::station_name(s).eq_ignore_ascii_case(name))
                    .ok_or_else(|| {
                        format!(
                            "a station of panel {} must be {names}, got '{name}'",
                            panel.name()
                        )
                    })?;
                stations |= 1 << s;
            }
            script
                .keyed
                .push(keyed(Command::Emptying { lane, stations }));
        }
        (_, "lamptest") => script.keyed.push(keyed(Command::LampTest)),
        (p, c) => return Err(format!("'{c}' is not a command of panel {}", p.name())),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_schedule_gives_150_postcodes_distinct_bins() {
        for s in 0..SCHEDULES {
            let mut bins: Vec<u8> = (0..POSTCODES)
                .filter_map(|i| bin_for(s, postcode(i)))
                .collect();
            assert_eq!(bins.len(), BINS);
            bins.sort_unstable();
            bins.dedup();
            assert_eq!(bins.len(), BINS);
        }
        assert_eq!(bin_for(0, 12_345), None);
    }

    #[test]
    fn scripts_name_the_bad_line() {
        let s = parse_script("# a comment\n06:00 P1 type 3\n06:01 central schedule 2\n").unwrap();
        assert_eq!(s.sacks.len(), 1);
        assert_eq!(s.keyed[0].command, Command::Schedule(Some(1)));
        let e = parse_script("06:00 P1 type 3\n06:00 P3 postcode 20000\n").unwrap_err();
        assert!(e.starts_with("line 2:"), "{e}");
        for (bad, why) in [
            ("A emptying D1 C2", "station of panel A"),
            ("B emptying E9 A1", "station of panel B"),
            ("P1 postcode 12345", "no sorting schedule"),
            ("P1 type 3 4", "too many words"),
            ("central schedule 2 x", "too many words"),
            ("B lamptest now", "too many words"),
        ] {
            let e = parse_script(&format!("# ok\n06:00 {bad}\n")).unwrap_err();
            assert!(e.starts_with("line 2:") && e.contains(why), "{bad}: {e}");
        }
        let e = parse_script_bytes(b"06:00 P1 type 3\n06:01 P1 type \xff\n").unwrap_err();
        assert_eq!(e, "line 2: not UTF-8 text");
        assert!(parse_script("06:00 B emptying E9 B1,C2\n06:00 P2 postcode 20211\n").is_ok());
    }
}
