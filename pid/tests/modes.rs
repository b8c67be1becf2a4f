//! `set_manual` / `set_auto` as their docs state them: the return to automatic is bumpless
//! ("the integral is set so that the next output starts from the manual one"), also straight
//! after the switch to manual with no sample between; a `set_auto` in automatic changes nothing.
#![allow(
    clippy::unwrap_used,
    clippy::float_cmp,
    reason = "a test may panic: that is how it fails"
)]

use regler_pid::{Config, Kind, Mode, Pid};

fn config(kind: Kind) -> Config<f64> {
    Config {
        kind,
        k: 2.0,
        ti: 10.0,
        td: 1.0,
        h: 0.5,
        ymin: -20.0,
        ymax: 20.0,
        ..Config::default()
    }
}

/// Manual with an output, then automatic at once (no sample in manual): the next sample's
/// output starts from the manual one — it moves only by what one sample's I and D add at
/// unchanged inputs, never jumps to where the controller stood before manual.
#[test]
fn back_to_automatic_straight_after_manual_starts_from_the_manual_output() {
    for kind in Kind::ALL.into_iter().filter(|k| k.has_i()) {
        for manual in [-15.0, 0.0, 7.5] {
            let mut pid = Pid::<f64>::new(&config(kind)).unwrap();
            for _ in 0..10 {
                pid.update(5.0, 3.0);
            }
            let before = pid.output();
            pid.set_manual(manual).unwrap();
            assert_eq!(pid.output(), manual);
            pid.set_auto();
            assert_eq!(pid.mode(), Mode::Auto);
            let u = pid.update(5.0, 3.0);
            // One sample's integral step at this error is bi·2 = K·h/Ti·2 = 0.2 (less without P).
            assert!(
                (u - manual).abs() <= 0.25,
                "{kind}: {u} after manual {manual} (it stood at {before})"
            );
        }
    }
}

/// `set_auto` in automatic (started or not, the output at a limit or not) changes nothing: the
/// integral and the next output are what they would have been without it.
#[test]
fn set_auto_in_automatic_changes_nothing() {
    for kind in Kind::ALL {
        // (set-point, measurement): inside the limits, then far beyond them (output at 20).
        for (r, y) in [(5.0, 3.0), (500.0, 0.0)] {
            let mut pid = Pid::<f64>::new(&config(kind)).unwrap();
            let mut twin = Pid::<f64>::new(&config(kind)).unwrap();
            pid.set_auto();
            for n in 0..8 {
                let u = pid.update(r, y);
                let want = twin.update(r, y);
                assert_eq!(u, want, "{kind} ({r}, {y}): sample {n}");
                assert_eq!(pid.integral(), twin.integral(), "{kind}: sample {n}");
                pid.set_auto();
                assert_eq!(pid.integral(), twin.integral(), "{kind}: set_auto moved I");
            }
        }
    }
}
