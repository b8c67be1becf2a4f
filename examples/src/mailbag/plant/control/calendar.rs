//! The calendar's sorting schedules: the minute table's lines and the schedule in force at a
//! time.

use regler_scan_cycle::{DateTime, Weekdays};

/// The minute table's statistics line.
pub(super) const STATISTICS: u8 = 255;

/// The calendar's schedule starts: (hour, schedule, days).
pub const SCHEDULE_STARTS: [(u8, u8, Weekdays); 7] = [
    (0, 0, Weekdays::WORKDAYS),
    (5, 1, Weekdays::WORKDAYS),
    (10, 2, Weekdays::WORKDAYS),
    (15, 3, Weekdays::WORKDAYS),
    (20, 4, Weekdays::WORKDAYS),
    (0, 5, Weekdays::WEEKEND),
    (12, 4, Weekdays::WEEKEND),
];

/// The schedule the calendar has in force at `t`: the latest start at or before it, looking
/// back up to a week.
#[must_use]
pub fn schedule_for(t: &DateTime) -> u8 {
    const WEEK: u32 = 7 * 24;
    let now = (u32::from(t.weekday()).clamp(1, 7) - 1) * 24 + u32::from(t.hour());
    for back in 0..=WEEK {
        let h = (now + WEEK - back) % WEEK;
        let (day, hour) = ((h / 24) as u8 + 1, (h % 24) as u8);
        if let Some(&(_, s, _)) = SCHEDULE_STARTS
            .iter()
            .find(|(sh, _, days)| *sh == hour && days.contains(day))
        {
            return s;
        }
    }
    0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_schedule_in_force_follows_the_starts_by_time_and_weekday() {
        // 1977-03-07 is a Monday.
        let at = |day, hour, minute| {
            schedule_for(&DateTime::new(1977, 3, day, hour, minute, 0).unwrap())
        };
        assert_eq!(at(7, 0, 30), 0);
        assert_eq!(at(7, 4, 59), 0);
        assert_eq!(at(7, 5, 0), 1);
        assert_eq!(at(7, 14, 59), 2);
        assert_eq!(at(11, 23, 0), 4); // Friday night
        assert_eq!(at(12, 1, 0), 5); // Saturday
        assert_eq!(at(13, 13, 0), 4); // Sunday afternoon
        assert_eq!(at(14, 0, 0), 0); // Monday again
    }
}
