//! The minute table against a model that walks the clock minute by minute, over forward jumps,
//! set-backs and outages (the calendar set afresh from a real-time clock).
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects,
    clippy::cast_possible_truncation,
    reason = "a test may panic: that is how it fails"
)]

use proptest::prelude::{prop, prop_assert_eq, proptest};
use regler_scan_cycle::{
    Checked, CycleConfig, DateTime, Executive, Io, MinuteTable, Restart, Start, Weekdays,
};

/// What one check handed out: (line, minutes late, missed), in order, and the totals.
type Outcome = (Vec<(usize, u64, u64)>, usize, usize, u64, u64);

fn minute_of(t: &DateTime) -> DateTime {
    DateTime::new(t.year(), t.month(), t.day(), t.hour(), t.minute(), 0).unwrap()
}

fn falls_in(line: &Start<usize>, t: &DateTime) -> bool {
    line.hour == t.hour() && line.minute == t.minute() && line.days.contains(t.weekday())
}

/// The rule as the documentation states it, the slow way: walk every minute after the latest
/// one checked up to now's, note which lines fall in each; a line runs once, for its latest time,
/// the earlier ones are missed; a clock behind the latest minute checked runs nothing.
struct Model {
    reached: Option<DateTime>,
}

impl Model {
    fn check(&mut self, lines: &[Start<usize>], now: &DateTime) -> Outcome {
        let now = minute_of(now);
        let mut seen: Vec<Vec<u64>> = vec![Vec::new(); lines.len()];
        let mut steps = 0u64;
        match self.reached {
            None => {
                for (i, line) in lines.iter().enumerate() {
                    if falls_in(line, &now) {
                        seen[i].push(0);
                    }
                }
            }
            Some(reached) if now <= reached => {
                let mut t = now;
                let mut behind = 0;
                while t < reached {
                    t.advance(60_000);
                    behind += 1;
                }
                return (Vec::new(), 0, 0, 0, behind);
            }
            Some(reached) => {
                let mut t = reached;
                while t < now {
                    t.advance(60_000);
                    steps += 1;
                    for (i, line) in lines.iter().enumerate() {
                        if falls_in(line, &t) {
                            seen[i].push(steps);
                        }
                    }
                }
            }
        }
        self.reached = Some(now);
        let mut out: Vec<(u64, usize, u64)> = seen
            .iter()
            .enumerate()
            .filter_map(|(i, times)| Some((*times.last()?, i, times.len() as u64 - 1)))
            .collect();
        out.sort();
        let starts: Vec<(usize, u64, u64)> = out
            .iter()
            .map(|&(at, i, missed)| (i, steps - at, missed))
            .collect();
        let on_time = starts.iter().filter(|s| s.1 == 0).count();
        let missed = starts.iter().map(|s| s.2).sum();
        (starts.clone(), on_time, starts.len() - on_time, missed, 0)
    }
}

fn run(table: &mut MinuteTable<usize, 6>, now: &DateTime) -> Outcome {
    let mut starts = Vec::new();
    let c: Checked = table.check(now, |due| {
        starts.push((*due.program, due.minutes_late, due.missed));
    });
    (starts, c.on_time, c.late, c.missed, c.behind_minutes)
}

#[derive(Clone, Debug)]
enum Move {
    /// The clock advanced by this many ms (a cycle, or a jump).
    Advance(u32),
    /// The clock set back to a time it showed before (an index into the times seen), plus ms.
    SetBack(usize, u32),
    /// Power off for this many ms: no checks meanwhile; then the calendar is set afresh from the
    /// real-time clock's fields.
    Outage(u32),
}

fn moves() -> impl proptest::strategy::Strategy<Value = Move> {
    use proptest::prelude::{Strategy, any, prop_oneof};
    prop_oneof![
        4 => prop_oneof![1u32..2_000, 1u32..180_000].prop_map(Move::Advance),
        2 => (1u32..3 * 86_400_000).prop_map(Move::Advance),
        2 => (any::<usize>(), 0u32..120_000).prop_map(|(i, ms)| Move::SetBack(i, ms)),
        1 => (1u32..9 * 86_400_000).prop_map(Move::Outage),
    ]
}

fn lines() -> impl proptest::strategy::Strategy<Value = Vec<Start<usize>>> {
    use proptest::prelude::{Strategy, any, prop_oneof};
    let minute = prop_oneof![0u8..3, 0u8..60];
    prop::collection::vec((0u8..24, minute, any::<u8>()), 0..=6).prop_map(|v| {
        v.into_iter()
            .enumerate()
            .map(|(program, (hour, minute, days))| Start {
                hour,
                minute,
                days: Weekdays(days),
                program,
            })
            .collect()
    })
}

proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(if cfg!(miri) { 4 } else { 96 }))]

    /// Every start the clock reaches runs once — late if the clock jumped over it, in the order
    /// of its time —, a line runs at most once per check with its earlier times counted missed,
    /// nothing runs again when the clock is set back, and after an outage the calendar set from
    /// the real-time clock catches up by the same rule.
    #[test]
    #[cfg_attr(
        miri,
        ignore = "a model walked minute by minute over jumps and outages of up to 9 days, 24 moves a case: many minutes interpreted; runs natively in every CI run"
    )]
    fn minute_table_matches_a_minute_by_minute_walk(
        lines in lines(),
        (year, month, day, hour, minute, second) in
            (1999u16..2030, 1u8..=12, 1u8..=31, 0u8..24, 0u8..60, 0u8..60),
        moves in prop::collection::vec(moves(), 1..24),
    ) {
        let mut table: MinuteTable<usize, 6> = MinuteTable::new();
        for line in &lines {
            table.add(*line).unwrap();
        }
        let mut model = Model { reached: None };
        let day = day.min(28);
        let mut now = DateTime::new(year, month, day, hour, minute, second).unwrap();
        let mut seen = vec![now];
        prop_assert_eq!(run(&mut table, &now), model.check(&lines, &now));
        for m in moves {
            match m {
                Move::Advance(ms) => {
                    now.advance(ms);
                }
                Move::SetBack(i, ms) => {
                    now = seen[i % seen.len()];
                    now.advance(ms);
                }
                Move::Outage(ms) => {
                    let mut rtc = now;
                    rtc.advance(ms);
                    now = DateTime::new(
                        rtc.year(), rtc.month(), rtc.day(), rtc.hour(), rtc.minute(), rtc.second(),
                    ).unwrap();
                }
            }
            seen.push(now);
            prop_assert_eq!(run(&mut table, &now), model.check(&lines, &now), "at {}", now);
            prop_assert_eq!(table.checked_up_to(), model.reached);
        }
    }
}

#[test]
#[cfg_attr(
    miri,
    ignore = "443 simulated days of a calendar, day by day: a minute under Miri; runs natively in every CI run"
)]
fn a_jump_longer_than_a_week_runs_each_line_once() {
    let lines = [
        Start {
            hour: 6,
            minute: 0,
            days: Weekdays::ALL,
            program: 0,
        },
        Start {
            hour: 0,
            minute: 0,
            days: Weekdays::WORKDAYS,
            program: 1,
        },
        Start {
            hour: 23,
            minute: 59,
            days: Weekdays(0b100_0000),
            program: 2,
        },
        Start {
            hour: 12,
            minute: 30,
            days: Weekdays::WEEKEND,
            program: 3,
        },
        Start {
            hour: 12,
            minute: 30,
            days: Weekdays(0),
            program: 4,
        },
    ];
    // 8 days, 5 weeks, and over a leap day and a year end: 400 days.
    for days in [8u32, 35, 400] {
        let mut table: MinuteTable<usize, 6> = MinuteTable::new();
        let mut model = Model { reached: None };
        for line in lines {
            table.add(line).unwrap();
        }
        let mut now = DateTime::new(2027, 12, 30, 5, 59, 59).unwrap();
        assert_eq!(run(&mut table, &now), model.check(&lines, &now));
        for _ in 0..days {
            now.advance(86_400_000);
        }
        let got = run(&mut table, &now);
        assert_eq!(got, model.check(&lines, &now));
        assert_eq!(got.0.len(), 4, "each line that falls in the jump runs once");
        assert!(got.3 > 0, "the rest are reported missed");
    }
}

#[test]
fn the_issue_s_jump_runs_06_00_and_06_01_late_and_a_set_back_runs_nothing_twice() {
    let mut table: MinuteTable<&str, 4> = MinuteTable::new();
    for (minute, program) in [(0, "06:00"), (1, "06:01"), (2, "06:02"), (3, "06:03")] {
        table
            .add(Start {
                hour: 6,
                minute,
                days: Weekdays::ALL,
                program,
            })
            .unwrap();
    }
    let mut clock = DateTime::new(2026, 11, 23, 5, 59, 30).unwrap();
    let mut ran = Vec::new();
    table.check(&clock, |d| ran.push((*d.program, d.minutes_late)));
    assert_eq!(clock.advance(150_000), 3);
    let c = table.check(&clock, |d| ran.push((*d.program, d.minutes_late)));
    assert_eq!(ran, [("06:00", 2), ("06:01", 1), ("06:02", 0)]);
    assert_eq!(
        (c.on_time, c.late, c.missed, c.behind_minutes),
        (1, 2, 0, 0)
    );
    // Set back to 05:59:50: 06:00 to 06:02 have run and do not run again; 06:03 still does.
    let mut back = DateTime::new(2026, 11, 23, 5, 59, 50).unwrap();
    assert_eq!(
        table.check(&back, |_| panic!("ran twice")).behind_minutes,
        3
    );
    for _ in 0..4 {
        back.advance(60_000);
        table.check(&back, |d| ran.push((*d.program, d.minutes_late)));
    }
    assert_eq!(ran.last(), Some(&("06:03", 0)));
    assert_eq!(ran.len(), 4);
}

/// The plant: a wall clock in µs that keeps counting through an outage (as the real-time clock
/// does), and the executive's program time, which leaves the outage out.
struct Plant {
    wall_us: u64,
}

impl Io<1, 1> for Plant {
    fn read_inputs(&mut self, raw: &mut [u16; 1]) {
        *raw = [0];
    }
    fn write_outputs(&mut self, _: &[u16; 1]) {}
    fn now_us(&mut self) -> u32 {
        self.wall_us as u32
    }
}

#[test]
#[cfg_attr(
    miri,
    ignore = "outages of every length over a week of calendar checks: minutes interpreted; runs natively in every CI run"
)]
fn after_an_outage_a_calendar_set_from_the_real_time_clock_is_right_and_catches_up() {
    let start = DateTime::new(2026, 11, 23, 5, 55, 0).unwrap();
    let mut table: MinuteTable<&str, 2> = MinuteTable::new();
    table
        .add(Start {
            hour: 6,
            minute: 0,
            days: Weekdays::ALL,
            program: "shift",
        })
        .unwrap();
    let mut plc: Executive<1, 1> = Executive::new(CycleConfig::source());
    let mut plant = Plant { wall_us: 0 };
    let (mut calendar, mut from_program_time) = (start, start);
    let mut last_ms = 0u32;
    let mut ran = Vec::new();
    let rtc = |plant: &Plant| {
        let mut t = start;
        t.advance((plant.wall_us / 1000) as u32);
        DateTime::new(
            t.year(),
            t.month(),
            t.day(),
            t.hour(),
            t.minute(),
            t.second(),
        )
        .unwrap()
    };
    let mut cycles = |plc: &mut Executive<1, 1>,
                      plant: &mut Plant,
                      n: u32,
                      calendar: &mut DateTime,
                      ran: &mut Vec<(&str, u64)>,
                      from_program_time: &mut DateTime,
                      last_ms: &mut u32| {
        for _ in 0..n {
            let before = plant.wall_us;
            plant.wall_us += 50_000;
            plc.cycle(plant, |_| {}).unwrap();
            // As documented: the calendar goes by the wall clock's elapsed time.
            calendar.advance(((plant.wall_us - before) / 1000) as u32);
            table.check(calendar, |d| ran.push((*d.program, d.minutes_late)));
            // As not to do it: by the executive's program time.
            from_program_time.advance(plc.now_ms().wrapping_sub(*last_ms));
            *last_ms = plc.now_ms();
        }
    };
    cycles(
        &mut plc,
        &mut plant,
        60 * 20,
        &mut calendar,
        &mut ran,
        &mut from_program_time,
        &mut last_ms,
    ); // to 05:56
    plc.power_fail(&mut plant);
    plant.wall_us += 10 * 60 * 1_000_000; // 10 minutes without power: 06:00 passes
    plc.resume(Restart::Inhibit);
    calendar = rtc(&plant); // set afresh from the real-time clock
    cycles(
        &mut plc,
        &mut plant,
        20,
        &mut calendar,
        &mut ran,
        &mut from_program_time,
        &mut last_ms,
    );
    assert_eq!(
        calendar,
        rtc(&plant),
        "the calendar is right after the outage"
    );
    assert_eq!(
        ran,
        [("shift", 6)],
        "the start the outage jumped over ran once, 6 minutes late"
    );
    let slow = calendar.hour() as u32 * 60 + calendar.minute() as u32
        - (from_program_time.hour() as u32 * 60 + from_program_time.minute() as u32);
    assert!(
        slow >= 9,
        "program time leaves the outage out: {slow} min slow"
    );
}

#[test]
fn checked_up_to_carries_the_rule_over_a_restart_and_none_re_arms() {
    let line = |minute, program| Start {
        hour: 6,
        minute,
        days: Weekdays::ALL,
        program,
    };
    let mut table: MinuteTable<u8, 2> = MinuteTable::new();
    table.add(line(0, 0)).unwrap();
    table.add(line(1, 1)).unwrap();
    // Restored from battery-backed memory after a restart: 05:59 was the latest minute checked.
    table.set_checked_up_to(Some(DateTime::new(2026, 11, 23, 5, 59, 40).unwrap()));
    assert_eq!(
        table.checked_up_to(),
        Some(DateTime::new(2026, 11, 23, 5, 59, 0).unwrap()),
        "seconds zero"
    );
    let now = DateTime::new(2026, 11, 23, 6, 1, 10).unwrap();
    let mut ran = Vec::new();
    table.check(&now, |d| ran.push((*d.program, d.minutes_late)));
    assert_eq!(ran, [(0, 1), (1, 0)]);
    // Re-armed after a wrong clock was corrected back: only the minute it is in runs.
    table.set_checked_up_to(None);
    ran.clear();
    let back = DateTime::new(2026, 11, 23, 6, 0, 5).unwrap();
    let c = table.check(&back, |d| ran.push((*d.program, d.minutes_late)));
    assert_eq!((ran.as_slice(), c.behind_minutes), ([(0, 0)].as_slice(), 0));
}

#[test]
#[cfg_attr(
    miri,
    ignore = "a week of calendar minutes: a minute interpreted; runs natively in every CI run"
)]
fn the_first_week_of_the_calendar_counts_too() {
    // 0001-01-01, a Monday, is the first day the calendar holds.
    let mut table: MinuteTable<u8, 1> = MinuteTable::new();
    table
        .add(Start {
            hour: 0,
            minute: 5,
            days: Weekdays::ALL,
            program: 7,
        })
        .unwrap();
    let mut model = Model { reached: None };
    let lines = [Start {
        hour: 0,
        minute: 5,
        days: Weekdays::ALL,
        program: 0,
    }];
    let mut now = DateTime::new(1, 1, 1, 0, 4, 30).unwrap();
    let mut got = Vec::new();
    for _ in 0..3 {
        let mut ran = Vec::new();
        let c = table.check(&now, |d| ran.push((*d.program, d.minutes_late, d.missed)));
        let (want, ..) = model.check(&lines, &now);
        assert_eq!(ran.len(), want.len());
        got.push((ran, c.missed));
        now.advance(2 * 86_400_000);
    }
    assert_eq!(
        got[1],
        (vec![(7, 1439, 1)], 1),
        "two days on: the second 00:05 runs 1 439 min late, the first is missed"
    );
}
