//! Every error message of `regler-panel-link` in full: each names what was wrong and the value
//! or limit involved (what an operator or integrator reads in a log). The highway's
//! `EncodeError` and `DecodeError` texts are checked where they are made (`highway::tests`), the
//! `embedded-io` adapters' in `io::tests`.
#![allow(
    clippy::unwrap_used,
    clippy::arithmetic_side_effects,
    reason = "a test may panic: that is how it fails"
)]

use regler_panel_link::highway::{
    ConfigError as ControllerConfigError, Controller, ControllerConfig, Driver, DriverConfig,
    DriverError, EncodeError,
};
use regler_panel_link::line::{LineError, Noise, NoiseError};
use regler_panel_link::panel::{
    ConfigError as HostConfigError, KEY_QUEUE, PanelError, RegisterError,
};

#[test]
fn every_error_message_names_what_was_wrong() {
    let queue_full = format!("key 0x2a refused: {KEY_QUEUE} keys are already waiting");
    let rows: Vec<(String, &str)> = vec![
        // line
        (
            LineError::Framing.to_string(),
            "framing error: start bit not 0 or stop bit not 1",
        ),
        (
            LineError::Parity.to_string(),
            "parity error: the parity bit does not match the data",
        ),
        (
            Noise::new(0.75, 1).err().unwrap().to_string(),
            "bit-error rate must be finite and in 0..=0.5, got 0.75",
        ),
        (
            NoiseError::Rate(f64::NAN).to_string(),
            "bit-error rate must be finite and in 0..=0.5, got NaN",
        ),
        // panel
        (
            RegisterError::Index {
                index: 46,
                registers: 46,
            }
            .to_string(),
            "register 46 does not exist (the panel has 46)",
        ),
        (
            RegisterError::Value(128).to_string(),
            "register values are 0..=127 (7 bits), got 128",
        ),
        (
            HostConfigError::KeyTimeout(5).to_string(),
            "key_timeout_polls 5 is below 6: the second key byte of a panel sampling SÄN every \
             20 ms arrives up to 42.3 ms after SÄN rises, and poll 5 may come 40 ms after it \
             (keys lost on a clean line)",
        ),
        (
            HostConfigError::MotStuck(2).to_string(),
            "mot_stuck_polls 2 is below 3: the host keeps SÄN low for 3 polls (over 20 ms) after \
             a key exchange, so that a panel sampling SÄN every 20 ms sees it low",
        ),
        (PanelError::QueueFull(0x2A).to_string(), &queue_full),
        // highway: the crate controller and the driver
        (
            Controller::new(ControllerConfig {
                address: 63,
                demand_repeat: 0,
            })
            .err()
            .unwrap()
            .to_string(),
            "crate address must be 1..=62, got 63",
        ),
        (
            ControllerConfigError::Address(0).to_string(),
            "crate address must be 1..=62, got 0",
        ),
        (
            DriverError::NotACommand.to_string(),
            "only commands can be submitted",
        ),
        (
            DriverError::Encode(EncodeError::Station(32)).to_string(),
            "command cannot be encoded: station number must be 0..=31, got 32",
        ),
        (
            DriverError::NoReplyPossible(63).to_string(),
            "crate address 63 never replies (use 1..=62)",
        ),
        (
            DriverError::CrateBusy(5).to_string(),
            "crate 5 already has a command outstanding",
        ),
        (
            DriverError::WindowFull.to_string(),
            "every slot of the driver's window is taken",
        ),
    ];
    for (got, want) in rows {
        assert_eq!(got, want);
    }
    let least = DriverConfig::for_loop(1).least_timeout();
    let short = Driver::<1>::new(DriverConfig {
        timeout: least - 1,
        ..DriverConfig::for_loop(1)
    });
    assert_eq!(
        short.err().unwrap().to_string(),
        format!(
            "time-out {} byte clocks is shorter than the round trip of a one-controller loop \
             ({least}); a late reply would complete the wrong command (use DriverConfig::for_loop)",
            least - 1
        )
    );
}
