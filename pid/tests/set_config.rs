//! `Pid::set_config` as its docs state it: a change of kind moves the derivative state the new
//! kind lacks into the integral (where there is one), and a change of weights after an absurd
//! set-point starts the next sample afresh — in either mode, which the change keeps.
#![allow(
    clippy::unwrap_used,
    clippy::float_cmp,
    reason = "a test may panic: that is how it fails"
)]

use regler_pid::{Config, Kind, Mode, Pid};

fn pid_config(kind: Kind) -> Config<f64> {
    Config {
        kind,
        k: 2.0,
        ti: 10.0,
        td: 4.0,
        n: 8.0,
        h: 0.5,
        ymin: -100.0,
        ymax: 100.0,
        ..Config::default()
    }
}

/// "A derivative state that the new kind lacks is dropped, into the integral where there is
/// one": after a ramp of the measurement (so that D is well away from 0), a change from every
/// kind with D to every kind without it (with P as the old kind has or lacks it, so that P does
/// not move) leaves D at 0 and the integral at I + D; a change to a kind with D keeps both.
#[test]
fn a_kind_without_d_takes_the_derivative_into_the_integral() {
    for from in Kind::ALL.into_iter().filter(|k| k.has_d()) {
        // With P on both sides: a P term that appears or goes moves the integral too
        // (bumpless), which is another rule.
        for to in Kind::ALL.into_iter().filter(|k| k.has_p() == from.has_p()) {
            let mut pid = Pid::<f64>::new(&pid_config(from)).unwrap();
            for n in 0..6 {
                pid.update(10.0, f64::from(n) * 0.5);
            }
            let (i, d) = (pid.integral(), pid.derivative());
            assert!(d.abs() > 0.1, "{from}: D {d}");
            pid.set_config(&pid_config(to)).unwrap();
            let (want_i, want_d) = match (to.has_d(), to.has_i()) {
                (true, _) => (i, d),
                (false, true) => (i + d, 0.0),
                (false, false) => (i, 0.0),
            };
            assert_eq!(pid.derivative(), want_d, "{from} -> {to}: D");
            assert!(
                (pid.integral() - want_i).abs() <= 1e-12 * (i.abs() + d.abs()),
                "{from} -> {to}: I {} for {want_i}",
                pid.integral()
            );
        }
    }
}

/// After an absurd set-point that the new weights cannot carry (b·r or c·r overflows), the
/// change starts the next sample afresh — and keeps the mode: a controller in manual stays in
/// manual with its output, one in automatic stays in automatic.
#[test]
fn a_change_that_restarts_the_controller_keeps_its_mode() {
    for kind in Kind::ALL {
        for manual in [false, true] {
            let base = Config {
                c: 0.0,
                ..pid_config(kind)
            };
            let mut pid = Pid::<f64>::new(&base).unwrap();
            pid.update(5.0, 5.0);
            if manual {
                pid.set_manual(12.5).unwrap();
            }
            pid.update(1e307, 5.0);
            pid.set_config(&Config { c: 100.0, ..base }).unwrap();
            let want = if manual { Mode::Manual } else { Mode::Auto };
            assert_eq!(pid.mode(), want, "{kind}, manual {manual}");
            pid.clear_faults();
            for n in 0..20 {
                let u = pid.update(5.0, 4.0);
                assert_eq!(pid.mode(), want, "{kind}, manual {manual}: sample {n}");
                assert!(
                    !pid.faults().any(),
                    "{kind}, manual {manual}: sample {n} held"
                );
                if manual {
                    assert_eq!(u, 12.5, "{kind}: the operator's output");
                }
            }
        }
    }
}
