//! Arbitrary operator input to the 1985 controller example (`autonomous-controller`): the
//! start-up dialogue typed line by line (`Terminal::startup_line`; a valid dialogue finishes it
//! if the input did not), then keypad keys (`Keypad::press`), terminal lines
//! (`Terminal::running_line`) and samples of the process, interleaved as the input says, on the
//! run's `Station<Number>`.
//!
//! What the example's and `regler-pid`'s documentation promise:
//! - the start-up checks each answer as it is typed: what it starts, the station takes
//!   (`Station::new` accepts it, YMAX above YMIN); a refused answer asks again or goes back;
//! - the LCD's two lines never exceed 24 characters;
//! - nothing keyed or typed goes into force before a sample: the active parameters change only
//!   at a sample after a commit, and then to the set committed (or not at all, the commit
//!   refused with the reason);
//! - what is staged is always a set the controller can run (`startup::try_on`), YMAX above
//!   YMIN, whatever was keyed or typed;
//! - the output is finite and within the active YMIN..YMAX (as the controller's `f32` holds
//!   them).
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_examples::autonomous::keypad::{KeyEffect, Keypad, LCD_WIDTH};
use regler_examples::autonomous::startup::{self, Number, Question};
use regler_examples::autonomous::terminal::Terminal;
use regler_pid::{OperatorLimits, Station};

/// A start-up that the dialogue accepts (the example's tests' PI controller).
const VALID: [&str; 13] = [
    "PI", "10", "0", "10", "0", "3", "60", "0", "100", "DIR", "5", "50", "",
];

/// Keys of the keypad, most of the time; any character sometimes.
const KEYS: &[u8] = b"0123456789.-*ACDPI";

fn runnable(station: &Station<Number>) {
    let staged = station.staged();
    for (what, p) in [("active", staged.active()), ("staged", staged.shadow())] {
        assert!(
            startup::try_on::<Number>(*p, staged.scaling(), staged.limits()).is_ok(),
            "the {what} set cannot run: {p:?}"
        );
        assert!(
            p.config.ymax > p.config.ymin,
            "the {what} set has YMAX <= YMIN: {p:?}"
        );
    }
}

fuzz_target!(|data: &[u8]| {
    let mut lines = data.split(|&b| b == b'\n');
    let mut terminal = Terminal::new();
    let mut started = None;
    let mut valid = VALID.iter();
    for _ in 0..60 {
        let typed = match lines.next() {
            Some(raw) => String::from_utf8_lossy(raw).into_owned(),
            None => match valid.next() {
                Some(line) => (*line).to_string(),
                None => break,
            },
        };
        let before = terminal.question();
        let answer = terminal.startup_line(&typed);
        if let Some(s) = answer.started {
            started = Some(s);
            break;
        }
        let now = terminal.question();
        if answer.refused.is_some() {
            assert!(
                now <= before,
                "a refused answer moved on from {before:?} to {now:?}"
            );
        }
        if before == Some(Question::Start) {
            // A dialogue the input does not finish: start over with the valid answers.
            valid = VALID.iter();
            terminal = Terminal::new();
        }
    }
    let Some(startup) = started else { return };
    let station =
        Station::<Number>::new(startup.params, startup.scaling, OperatorLimits::default());
    let Ok(mut station) = station else {
        panic!(
            "the start-up started what the station refuses: {startup:?}: {station:?}",
            station = station.err()
        );
    };
    runnable(&station);
    let mut pad = Keypad::new();
    // What was committed and not yet sampled: the set that must come into force.
    let mut committed: Option<regler_pid::Parameters> = None;
    let rest: Vec<u8> = lines
        .flat_map(|l| l.iter().copied().chain([b'\n']))
        .collect();
    let mut rest = rest.as_slice();
    let (min, max) = (startup.scaling.min(), startup.scaling.max());
    for _ in 0..400 {
        let Some((&op, tail)) = rest.split_first() else {
            break;
        };
        rest = tail;
        let active = *station.staged().active();
        match op % 4 {
            0 | 1 => {
                let key = if op & 0x80 == 0 {
                    char::from(KEYS[usize::from(op >> 2) % KEYS.len()])
                } else {
                    char::from(op & 0x7F)
                };
                if pad.press(key, &mut station) == KeyEffect::Committed {
                    committed = Some(*station.staged().shadow());
                }
                assert!(
                    pad.lcd().top.chars().count() <= LCD_WIDTH,
                    "{:?}",
                    pad.lcd()
                );
                assert!(
                    pad.lcd().bottom.chars().count() <= LCD_WIDTH,
                    "{:?}",
                    pad.lcd()
                );
            }
            2 => {
                let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
                let line = String::from_utf8_lossy(&rest[..end]).into_owned();
                rest = rest.get(end + 1..).unwrap_or(&[]);
                let out = terminal.running_line(&line, &mut station);
                if out.iter().any(|l| l == "PARAMETERS COMMITTED") {
                    committed = Some(*station.staged().shadow());
                }
            }
            _ => {
                let xin = match rest.split_first() {
                    Some((&b, tail)) => {
                        rest = tail;
                        if b == 0xFF {
                            f64::NAN
                        } else {
                            min + (max - min) * f64::from(b) / 254.0
                        }
                    }
                    None => min,
                };
                let pending = station.staged().commit_pending();
                let y = station.sample(xin);
                let now = *station.staged().active();
                assert!(y.is_finite(), "output {y}");
                // The limits as the controller's number type holds them (YMIN 3.01 is
                // 3.0099999904… in f32), as the crate's own property test states it.
                let (lo, hi) = (
                    f64::from(now.config.ymin as Number),
                    f64::from(now.config.ymax as Number),
                );
                assert!(y >= lo && y <= hi, "output {y} outside {lo}..{hi}");
                if pending {
                    if station.refused_commit().is_none() {
                        let want = committed.take().expect("a commit was keyed or typed");
                        assert_eq!(now, want, "the set in force is not the one committed");
                    } else {
                        assert_eq!(now, active, "a refused commit changed the set in force");
                    }
                } else {
                    assert_eq!(now, active, "the set in force changed without a commit");
                }
                committed = None;
                runnable(&station);
                continue;
            }
        }
        assert_eq!(
            *station.staged().active(),
            active,
            "in force before a sample"
        );
        runnable(&station);
    }
});
