//! The load-step identity: for every kind with integral action, a load step `l` at the process
//! input is rejected with ∫e dt = −Ti/K·l (K = 1 for kinds without P, as the source does) — exact
//! for the forward-difference integral, so it holds here to rounding once the loop has settled.
#![allow(
    clippy::unwrap_used,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "a test may panic: that is how it fails"
)]

use regler_pid::{Action, Config, Kind, Pid};

#[test]
#[cfg_attr(
    miri,
    ignore = "twelve loops of 400 000 samples: hours under Miri; runs natively in every CI run"
)]
fn integral_of_the_error_after_a_load_step_is_minus_ti_over_k_times_the_load() {
    let h = 0.01f64;
    let t = 1.0; // process: y' = (−y + u + l) / t
    let a = (-h / t).exp();
    for kind in [Kind::I, Kind::PI, Kind::ID, Kind::PID] {
        for (k, ti, td, load) in [
            (1.0, 2.0, 0.1, 0.5),
            (0.4, 0.8, 0.05, -1.5),
            (2.5, 5.0, 0.2, 3.0),
        ] {
            let config = Config::<f64> {
                kind,
                action: Action::Direct,
                k,
                ti,
                td,
                n: 10.0,
                h,
                ymin: -1e6,
                ymax: 1e6,
                ..Config::default()
            };
            let mut pid: Pid<f64> = Pid::new(&config).unwrap();
            let r = 1.0;
            let mut y = 0.0;
            // Settle at the set-point first.
            for _ in 0..200_000 {
                let u = pid.update(r, y);
                y = a * y + (1.0 - a) * u;
            }
            assert!((r - y).abs() < 1e-9, "{kind:?} did not settle: {y}");
            // The load step, and the integral of the error from here on.
            let mut integral = 0.0;
            for _ in 0..200_000 {
                let e = r - y;
                integral += e * h;
                let u = pid.update(r, y);
                y = a * y + (1.0 - a) * (u + load);
            }
            assert!(
                (r - y).abs() < 1e-9,
                "{kind:?} did not reject the load: {y}"
            );
            let gain = if kind.has_p() { k } else { 1.0 };
            let expected = -ti / gain * load;
            assert!(
                (integral - expected).abs() <= 1e-6 * expected.abs().max(1.0),
                "{kind:?} K={k} Ti={ti}: ∫e = {integral}, expected {expected}"
            );
        }
    }
}
