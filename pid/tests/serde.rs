//! Stored configurations through serde: they come back as they were, and stored data that
//! breaks an invariant is an error.
#![allow(clippy::unwrap_used, reason = "a test may panic: that is how it fails")]
#![cfg(feature = "serde")]

use regler_pid::{Config, Pid, Scaling};

#[test]
fn configs_round_trip_and_bad_scales_are_refused() {
    let config = Config {
        k: 2.5,
        tt: Some(3.0),
        dymax: Some(0.5),
        ..Config::default()
    };
    let back: Config = serde_json::from_str(&serde_json::to_string(&config).unwrap()).unwrap();
    assert_eq!(back, config);
    let f32_config: Config<f32> =
        serde_json::from_str(&serde_json::to_string(&config).unwrap()).unwrap();
    assert!(Pid::<f32>::new(&f32_config).is_ok());

    let scale = Scaling::new(0.0, 40.0).unwrap();
    let text = serde_json::to_string(&scale).unwrap();
    assert_eq!(serde_json::from_str::<Scaling>(&text).unwrap(), scale);
    let reversed = text.replace("40.0", "-5.0");
    let err = serde_json::from_str::<Scaling>(&reversed)
        .unwrap_err()
        .to_string();
    assert!(err.contains("SCALEMAX must exceed SCALEMIN"), "{err}");
}
