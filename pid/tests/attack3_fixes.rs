//! Regression tests from the attack on the fast paths (issue 23 §2): a tracking value held as
//! the output outside the limits, and a change of weights after an absurd set-point that parked
//! the controller for good. Both predate the fast paths; each test failed before its fix.

#[cfg(feature = "fixed")]
use fixed::types::I16F16;
use regler_pid::{Config, Inputs, Kind, Pid};

fn pi() -> Config<f64> {
    Config {
        kind: Kind::PI,
        k: 2.0,
        ti: 10.0,
        h: 0.5,
        ymin: 0.0,
        ymax: 10.0,
        ..Config::default()
    }
}

fn tracking(track: f32) -> Inputs<f32> {
    Inputs {
        feedforward: 0.0,
        track: Some(track),
    }
}

/// Manual mode: the output is the operator's. A tracking value, however large, moves I only;
/// the operator's output stands on every later sample.
#[test]
fn a_tracking_value_never_replaces_the_operators_output() {
    for track in [1e30f32, -1e30, 7.0, f32::MAX] {
        let mut pid = Pid::<f32>::new(&pi()).unwrap();
        pid.update(5.0, 5.0);
        pid.set_manual(3.0).unwrap();
        assert_eq!(pid.update_with(5.0, 5.0, tracking(track)), 3.0);
        assert_eq!(pid.update(5.0, 5.0), 3.0, "track {track}");
        assert_eq!(pid.update(5.0, f32::NAN), 3.0, "held, track {track}");
    }
}

/// Automatic mode: a held output (after a non-finite input) and the rate limit's start are the
/// tracking value within the limits, in f32 and in fixed point.
#[test]
fn a_held_output_after_tracking_stays_within_the_limits() {
    for (track, want) in [(-1e30f32, 0.0f32), (1e30, 10.0), (4.0, 4.0)] {
        let mut pid = Pid::<f32>::new(&pi()).unwrap();
        pid.update(5.0, 5.0);
        pid.update_with(5.0, 5.0, tracking(track));
        let u = pid.update(5.0, f32::NAN);
        assert!(pid.faults().non_finite_input());
        assert_eq!(u, want, "track {track}");
    }
    #[cfg(feature = "fixed")]
    {
        let f = I16F16::from_num;
        let mut fixed = Pid::<I16F16>::new(&pi()).unwrap();
        fixed.update(f(5), f(5));
        fixed.update_with(
            f(5),
            f(5),
            Inputs {
                feedforward: f(0),
                track: Some(I16F16::MAX),
            },
        );
        assert_eq!(fixed.output(), f(10));
    }
}

/// An absurd but finite set-point, then a change of the weights: every kind, in f32 and f64,
/// runs again on the next sane samples (no sample held with a fault), the derivative starting
/// afresh.
#[test]
fn a_change_of_weights_after_an_absurd_setpoint_never_parks_the_controller() {
    for kind in Kind::ALL {
        for (huge, c, b) in [
            (1e38f32, 10.0f32, 1.0f32),
            (1e38, 0.0, 10.0),
            (3e38, 2.0, 2.0),
        ] {
            let base = Config::<f32> {
                kind,
                k: 1.0,
                ti: 10.0,
                td: 1.0,
                h: 0.5,
                ymin: 0.0,
                ymax: 10.0,
                c: 0.0,
                ..Config::default()
            };
            let mut pid = Pid::<f32>::new(&base).unwrap();
            pid.update(5.0, 5.0);
            pid.update(huge, 5.0);
            pid.set_config(&Config { c, b, ..base }).unwrap();
            pid.clear_faults();
            for n in 0..100 {
                let u = pid.update(5.0, 4.0);
                assert!(!pid.faults().any(), "{kind:?} c {c} b {b}: sample {n} held");
                assert!((0.0..=10.0).contains(&u));
            }
        }
        let base = Config::<f64> {
            kind,
            k: 1.0,
            ti: 10.0,
            td: 1.0,
            h: 0.5,
            ymin: 0.0,
            ymax: 10.0,
            c: 0.0,
            ..Config::default()
        };
        let mut pid = Pid::<f64>::new(&base).unwrap();
        pid.update(5.0, 5.0);
        pid.update(1e307, 5.0);
        pid.set_config(&Config { c: 100.0, ..base }).unwrap();
        pid.clear_faults();
        for n in 0..100 {
            pid.update(5.0, 4.0);
            assert!(!pid.faults().any(), "f64 {kind:?}: sample {n} held");
        }
    }
}

mod properties {
    use proptest::prelude::*;
    use regler_pid::{Config, Inputs, Kind, Pid};

    fn kind() -> impl Strategy<Value = Kind> {
        proptest::sample::select(Kind::ALL.to_vec())
    }

    proptest! {
        /// Any finite set-point, however absurd, then any accepted change of the weights b and
        /// c: the next sane samples run, none held with a fault, the output within the limits.
        #[test]
        fn no_change_of_weights_parks_the_controller(
            kind in kind(),
            r in prop_oneof![-f32::MAX..f32::MAX, 1e30f32..f32::MAX, -f32::MAX..-1e30f32],
            b in 0.0f32..100.0,
            c in 0.0f32..100.0,
        ) {
            let base = Config::<f32> {
                kind, k: 1.0, ti: 10.0, td: 1.0, h: 0.5, ymin: 0.0, ymax: 10.0, c: 0.0,
                ..Config::default()
            };
            let mut pid = Pid::<f32>::new(&base).unwrap();
            pid.update(5.0, 5.0);
            pid.update(r, 5.0);
            if pid.set_config(&Config { b, c, ..base }).is_ok() {
                pid.clear_faults();
                for _ in 0..3 {
                    let u = pid.update(5.0, 4.0);
                    prop_assert!(!pid.faults().any(), "{:?}", pid.faults());
                    prop_assert!((0.0..=10.0).contains(&u));
                }
            }
        }

        /// Any finite tracking value: in manual mode the output stays the operator's; in
        /// automatic the held output (after a non-finite measurement) is within the limits.
        #[test]
        fn a_tracking_value_is_held_within_the_limits_and_never_overrides_manual(
            track in -f32::MAX..f32::MAX,
            manual in 0.0f32..=10.0,
        ) {
            let cfg = Config::<f32> {
                kind: Kind::PI, k: 2.0, ti: 10.0, h: 0.5, ymin: 0.0, ymax: 10.0,
                ..Config::default()
            };
            let inputs = Inputs { feedforward: 0.0, track: Some(track) };
            let mut pid = Pid::<f32>::new(&cfg).unwrap();
            pid.update(5.0, 5.0);
            pid.update_with(5.0, 5.0, inputs);
            let held = pid.update(5.0, f32::NAN);
            prop_assert_eq!(held, track.clamp(0.0, 10.0));
            let mut pid = Pid::<f32>::new(&cfg).unwrap();
            pid.update(5.0, 5.0);
            pid.set_manual(manual).unwrap();
            pid.update_with(5.0, 5.0, inputs);
            prop_assert_eq!(pid.update(5.0, 5.0), manual);
        }
    }
}
