//! Every regler crate's code, run where it is deployed: on an emulated Cortex-M4F (hardware
//! single-precision float, 32-bit `usize`) and Cortex-M0 (soft float, no unaligned access, 16 KiB
//! of RAM). Each test prints its name and result over semihosting; the run ends with the plain
//! line "N passed, M failed" and exits with the result, so CI fails on a failure.
//!
//! The crates' own `#[test]`s need `std` (proptest, threads, serde_json); these tests exercise
//! the same public types the way firmware uses them. Host-only: the property tests (they need
//! `std` and a random source), the serde round trips (`serde_json` needs `alloc`) and the
//! cross-thread `Signals` test (no threads here; `Signals` is tested with its real single-core
//! critical section instead).
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use panic_semihosting as _;

mod chain;
mod link;
mod pid;
mod ring;
mod scan;
mod trolley;

/// A test: `Ok` or the first check that failed.
type Outcome = Result<(), &'static str>;

/// A named test.
type Test = (&'static str, fn() -> Outcome);

/// Fails the test with the file, line and condition when `cond` does not hold.
#[macro_export]
macro_rules! check {
    ($cond:expr) => {{
        // Bound first: `!(a < b)` on floats reads as `a >= b`, which a NaN makes false.
        let held: bool = $cond;
        if !held {
            return Err(concat!(file!(), ":", line!(), ": ", stringify!($cond)));
        }
    }};
}

const TESTS: &[Test] = &[
    (
        "link::highway_rejects_every_one_and_two_bit_error",
        link::highway_rejects_every_one_and_two_bit_error,
    ),
    (
        "link::highway_loop_with_noise",
        link::highway_loop_with_noise,
    ),
    ("link::panel_sequence_and_key", link::panel_sequence_and_key),
    (
        "pid::f32_closed_loop_survives_nan_at_power_up",
        pid::f32_closed_loop_survives_nan_at_power_up,
    ),
    (
        "pid::f64_matches_hand_computed_steps",
        pid::f64_matches_hand_computed_steps,
    ),
    ("pid::fixed_point_follows_f32", pid::fixed_point_follows_f32),
    ("pid::relay_autotune_in_f32", pid::relay_autotune_in_f32),
    ("pid::three_point_actuator", pid::three_point_actuator),
    (
        "pid::config_errors_name_the_parameter",
        pid::config_errors_name_the_parameter,
    ),
    ("pid::spike_is_forgotten", pid::spike_is_forgotten),
    (
        "pid::station_commits_at_a_sample_in_f32",
        pid::station_commits_at_a_sample_in_f32,
    ),
    (
        "pid::alarm_blinks_then_steady",
        pid::alarm_blinks_then_steady,
    ),
    (
        "pid::scaling_round_trips_every_count",
        pid::scaling_round_trips_every_count,
    ),
    ("pid::sizes_on_a_32_bit_core", pid::sizes_on_a_32_bit_core),
    (
        "pid::manual_tracking_and_feedforward",
        pid::manual_tracking_and_feedforward,
    ),
    (
        "pid::staged_edits_say_what_was_wrong",
        pid::staged_edits_say_what_was_wrong,
    ),
    (
        "scan::iec_timers_and_pt_changes",
        scan::iec_timers_and_pt_changes,
    ),
    (
        "scan::counters_edges_bistables",
        scan::counters_edges_bistables,
    ),
    (
        "scan::timer_queue_across_wheel_levels",
        scan::timer_queue_across_wheel_levels,
    ),
    (
        "scan::executive_with_debounce_and_forcing",
        scan::executive_with_debounce_and_forcing,
    ),
    (
        "scan::signals_trip_inside_a_cycle",
        scan::signals_trip_inside_a_cycle,
    ),
    (
        "scan::calendar_and_minute_table",
        scan::calendar_and_minute_table,
    ),
    ("scan::sizes_on_a_32_bit_core", scan::sizes_on_a_32_bit_core),
    (
        "scan::step_chain_spool_and_breakpoints",
        scan::step_chain_spool_and_breakpoints,
    ),
    (
        "trolley::decode_all_8192_words",
        trolley::decode_all_8192_words,
    ),
    (
        "trolley::voters_never_invent_a_trolley",
        trolley::voters_never_invent_a_trolley,
    ),
    ("trolley::registry_routes", trolley::registry_routes),
    ("trolley::reader_health_alarm", trolley::reader_health_alarm),
    (
        "chain::correct_is_exact_at_the_extremes",
        chain::correct_is_exact_at_the_extremes,
    ),
    (
        "chain::tracker_with_recalibration",
        chain::tracker_with_recalibration,
    ),
    (
        "chain::snapshot_restore_and_refusal",
        chain::snapshot_restore_and_refusal,
    ),
    (
        "chain::stretch_meter_confirms",
        chain::stretch_meter_confirms,
    ),
    (
        "chain::sizes_on_a_32_bit_core",
        chain::sizes_on_a_32_bit_core,
    ),
    (
        "chain::a_full_chain_hands_the_trolley_back",
        chain::a_full_chain_hands_the_trolley_back,
    ),
    ("ring::ring_pointer_rule", ring::ring_pointer_rule),
    (
        "ring::split_halves_from_a_static",
        ring::split_halves_from_a_static,
    ),
    (
        "ring::frames_and_every_two_bit_error",
        ring::frames_and_every_two_bit_error,
    ),
    (
        "ring::lossy_link_keeps_the_stream",
        ring::lossy_link_keeps_the_stream,
    ),
    (
        "ring::stand_alone_and_back_at_a_row",
        ring::stand_alone_and_back_at_a_row,
    ),
    (
        "ring::capacity_on_a_32_bit_core",
        ring::capacity_on_a_32_bit_core,
    ),
    ("ring::sizes_on_a_32_bit_core", ring::sizes_on_a_32_bit_core),
];

#[entry]
fn main() -> ! {
    let core = if cfg!(target_arch = "arm") && cfg!(target_abi = "eabihf") {
        "Cortex-M4F (thumbv7em-none-eabihf)"
    } else {
        "Cortex-M0 (thumbv6m-none-eabi)"
    };
    hprintln!("regler on-target tests on {}", core);
    let (mut passed, mut failed) = (0u32, 0u32);
    for (name, test) in TESTS {
        match test() {
            Ok(()) => {
                passed += 1;
                hprintln!("test {} ... ok", name);
            }
            Err(why) => {
                failed += 1;
                hprintln!("test {} ... FAILED: {}", name, why);
            }
        }
    }
    hprintln!("{} passed, {} failed", passed, failed);
    debug::exit(if failed == 0 {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}
