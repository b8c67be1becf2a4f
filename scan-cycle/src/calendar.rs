//! The plant calendar: a clock advanced by the cycle, and a minute table of program starts.

use core::fmt;

use heapless::Vec;

/// A date and time of day (proleptic Gregorian calendar, no time zone).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DateTime {
    year: u16,
    month: u8,
    day: u8,
    hour: u8,
    minute: u8,
    second: u8,
    millis: u16,
}

/// A date or time that does not exist.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct InvalidDateTime;

impl fmt::Display for InvalidDateTime {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("no such date or time (year 1..=9999, month 1..=12, a day of that month, 00:00:00 to 23:59:59)")
    }
}

impl core::error::Error for InvalidDateTime {}

fn leap(year: u16) -> bool {
    (year.is_multiple_of(4) && !year.is_multiple_of(100)) || year.is_multiple_of(400)
}

fn days_in_month(year: u16, month: u8) -> u8 {
    match month {
        1 | 3 | 5 | 7 | 8 | 10 | 12 => 31,
        4 | 6 | 9 | 11 => 30,
        2 if leap(year) => 29,
        2 => 28,
        _ => 0,
    }
}

/// Days since 0001-01-01 (day 0), a Monday.
fn day_number(year: u16, month: u8, day: u8) -> i64 {
    let y = i64::from(year).saturating_sub(1);
    let mut days = y
        .saturating_mul(365)
        .saturating_add(y / 4)
        .saturating_sub(y / 100)
        .saturating_add(y / 400);
    for m in 1..month {
        days = days.saturating_add(i64::from(days_in_month(year, m)));
    }
    days.saturating_add(i64::from(day)).saturating_sub(1)
}

impl DateTime {
    /// A date and time, checked.
    pub fn new(
        year: u16,
        month: u8,
        day: u8,
        hour: u8,
        minute: u8,
        second: u8,
    ) -> Result<DateTime, InvalidDateTime> {
        let ok = (1..=9999).contains(&year)
            && (1..=12).contains(&month)
            && day >= 1
            && day <= days_in_month(year, month)
            && hour < 24
            && minute < 60
            && second < 60;
        if ok {
            Ok(DateTime {
                year,
                month,
                day,
                hour,
                minute,
                second,
                millis: 0,
            })
        } else {
            Err(InvalidDateTime)
        }
    }

    /// Year.
    #[must_use]
    pub const fn year(&self) -> u16 {
        self.year
    }
    /// Month, 1–12.
    #[must_use]
    pub const fn month(&self) -> u8 {
        self.month
    }
    /// Day of the month, from 1.
    #[must_use]
    pub const fn day(&self) -> u8 {
        self.day
    }
    /// Hour, 0–23.
    #[must_use]
    pub const fn hour(&self) -> u8 {
        self.hour
    }
    /// Minute, 0–59.
    #[must_use]
    pub const fn minute(&self) -> u8 {
        self.minute
    }
    /// Second, 0–59.
    #[must_use]
    pub const fn second(&self) -> u8 {
        self.second
    }

    /// ISO weekday: 1 = Monday … 7 = Sunday.
    #[must_use]
    pub fn weekday(&self) -> u8 {
        u8::try_from(day_number(self.year, self.month, self.day).rem_euclid(7))
            .unwrap_or(0)
            .saturating_add(1)
    }

    /// ISO 8601 week number, 1–53 (weeks start on Monday; week 1 holds the year's first Thursday).
    #[must_use]
    pub fn iso_week(&self) -> u8 {
        // Day numbers are below 4 million: none of this can overflow an i64.
        let ordinal =
            day_number(self.year, self.month, self.day).saturating_sub(day_number(self.year, 1, 1));
        let week = ordinal
            .saturating_add(11)
            .saturating_sub(i64::from(self.weekday()))
            / 7;
        let weeks_in = |year: u16| {
            let jan1 = DateTime {
                year,
                month: 1,
                day: 1,
                hour: 0,
                minute: 0,
                second: 0,
                millis: 0,
            }
            .weekday();
            if jan1 == 4 || (jan1 == 3 && leap(year)) {
                53i64
            } else {
                52
            }
        };
        let week = if week < 1 {
            weeks_in(self.year.saturating_sub(1))
        } else if week > weeks_in(self.year) {
            1
        } else {
            week
        };
        u8::try_from(week).unwrap_or(1)
    }

    /// Advances by `ms` milliseconds; returns how many whole minutes began on the way.
    pub fn advance(&mut self, ms: u32) -> u32 {
        let mut minutes = 0u32;
        let total = u32::from(self.millis).saturating_add(ms % 1000);
        self.millis = u16::try_from(total % 1000).unwrap_or(0);
        let mut seconds = (ms / 1000).saturating_add(total / 1000);
        while seconds > 0 {
            let step = seconds.min(60u32.saturating_sub(u32::from(self.second)));
            seconds = seconds.saturating_sub(step);
            let s = u32::from(self.second).saturating_add(step);
            if s < 60 {
                self.second = u8::try_from(s).unwrap_or(0);
                continue;
            }
            self.second = 0;
            minutes = minutes.saturating_add(1);
            self.minute = self.minute.saturating_add(1);
            if self.minute < 60 {
                continue;
            }
            self.minute = 0;
            self.hour = self.hour.saturating_add(1);
            if self.hour < 24 {
                continue;
            }
            self.hour = 0;
            self.day = self.day.saturating_add(1);
            if self.day <= days_in_month(self.year, self.month) {
                continue;
            }
            self.day = 1;
            self.month = self.month.saturating_add(1);
            if self.month <= 12 {
                continue;
            }
            self.month = 1;
            self.year = self.year.saturating_add(1).min(9999);
        }
        minutes
    }
}

impl fmt::Display for DateTime {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:04}-{:02}-{:02} {:02}:{:02}:{:02}",
            self.year, self.month, self.day, self.hour, self.minute, self.second
        )
    }
}

/// Weekdays as a bit set: bit 0 = Monday … bit 6 = Sunday.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Weekdays(pub u8);

impl Weekdays {
    /// Every day.
    pub const ALL: Weekdays = Weekdays(0x7F);
    /// Monday to Friday.
    pub const WORKDAYS: Weekdays = Weekdays(0x1F);
    /// Saturday and Sunday.
    pub const WEEKEND: Weekdays = Weekdays(0x60);

    /// Whether ISO weekday `day` (1–7) is in the set.
    #[must_use]
    pub fn contains(self, day: u8) -> bool {
        (1..=7).contains(&day) && self.0 >> day.saturating_sub(1) & 1 == 1
    }
}

/// One line of the minute table: start `program` at `hour:minute` on `days`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Start<P> {
    /// Hour, 0–23.
    pub hour: u8,
    /// Minute, 0–59.
    pub minute: u8,
    /// Weekdays.
    pub days: Weekdays,
    /// What to start (a sorting schedule, a statistics printout).
    pub program: P,
}

/// The source's minute table: each whole minute the table is checked for programs to start then
/// (it switched between six sorting schedules and printed statistics at 24:00).
///
/// ```
/// use regler_scan_cycle::{DateTime, MinuteTable, Start, Weekdays};
/// let mut table: MinuteTable<&str, 8> = MinuteTable::new();
/// assert!(table.add(Start { hour: 6, minute: 0, days: Weekdays::WORKDAYS, program: "morning schedule" }).is_ok());
/// assert!(table.add(Start { hour: 0, minute: 0, days: Weekdays::ALL, program: "print statistics" }).is_ok());
/// let mut clock = DateTime::new(2026, 11, 23, 5, 59, 30)?; // a Monday
/// assert_eq!(clock.advance(30_000), 1);                     // 06:00:00
/// assert_eq!(table.due(&clock).collect::<Vec<_>>(), [&"morning schedule"]);
/// # Ok::<(), regler_scan_cycle::InvalidDateTime>(())
/// ```
#[derive(Clone, Debug)]
pub struct MinuteTable<P, const M: usize> {
    starts: Vec<Start<P>, M>,
}

impl<P, const M: usize> Default for MinuteTable<P, M> {
    fn default() -> Self {
        MinuteTable::new()
    }
}

impl<P, const M: usize> MinuteTable<P, M> {
    /// An empty table.
    #[must_use]
    pub const fn new() -> MinuteTable<P, M> {
        MinuteTable { starts: Vec::new() }
    }

    /// Adds a line; a full table or an impossible time hands it back.
    pub fn add(&mut self, start: Start<P>) -> Result<(), Start<P>> {
        if start.hour > 23 || start.minute > 59 {
            return Err(start);
        }
        self.starts.push(start)
    }

    /// The programs to start in the minute `now` lies in.
    pub fn due<'a>(&'a self, now: &DateTime) -> impl Iterator<Item = &'a P> + 'a {
        let (h, m, d) = (now.hour(), now.minute(), now.weekday());
        self.starts
            .iter()
            .filter(move |s| s.hour == h && s.minute == m && s.days.contains(d))
            .map(|s| &s.program)
    }

    /// The lines.
    pub fn iter(&self) -> impl Iterator<Item = &Start<P>> {
        self.starts.iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weekdays_and_iso_weeks() {
        let d = |y, m, dd| DateTime::new(y, m, dd, 0, 0, 0).unwrap();
        assert_eq!(d(1977, 5, 2).weekday(), 1); // a Monday
        assert_eq!(d(2026, 11, 22).weekday(), 7);
        assert_eq!(d(2000, 2, 29).weekday(), 2);
        assert_eq!(d(2026, 1, 1).iso_week(), 1);
        assert_eq!(d(2021, 1, 3).iso_week(), 53); // belongs to 2020's week 53
        assert_eq!(d(2024, 12, 30).iso_week(), 1); // belongs to 2025's week 1
        assert_eq!(d(2020, 12, 31).iso_week(), 53);
        assert!(DateTime::new(2023, 2, 29, 0, 0, 0).is_err());
        assert!(DateTime::new(2024, 2, 29, 0, 0, 0).is_ok());
        assert!(DateTime::new(2024, 1, 1, 24, 0, 0).is_err());
    }

    #[test]
    fn advance_rolls_over_minutes_days_months_years() {
        let mut t = DateTime::new(1999, 12, 31, 23, 59, 58).unwrap();
        assert_eq!(t.advance(1_500), 0);
        assert_eq!(t.advance(600), 1);
        assert_eq!(t.to_string(), "2000-01-01 00:00:00");
        let mut t = DateTime::new(2024, 2, 28, 23, 0, 0).unwrap();
        assert_eq!(t.advance(2 * 3_600_000), 120);
        assert_eq!(t.to_string(), "2024-02-29 01:00:00");
        for _ in 0..1200 {
            t.advance(50); // the source's 50 ms cycle
        }
        assert_eq!(t.to_string(), "2024-02-29 01:01:00");
    }

    #[test]
    fn minute_table_by_weekday() {
        let mut table: MinuteTable<u8, 2> = MinuteTable::new();
        table
            .add(Start {
                hour: 22,
                minute: 0,
                days: Weekdays::WEEKEND,
                program: 1,
            })
            .unwrap();
        table
            .add(Start {
                hour: 22,
                minute: 0,
                days: Weekdays::WORKDAYS,
                program: 2,
            })
            .unwrap();
        assert!(
            table
                .add(Start {
                    hour: 1,
                    minute: 0,
                    days: Weekdays::ALL,
                    program: 3
                })
                .is_err()
        );
        let sat = DateTime::new(2026, 11, 21, 22, 0, 0).unwrap();
        let mon = DateTime::new(2026, 11, 23, 22, 0, 0).unwrap();
        assert_eq!(table.due(&sat).copied().collect::<std::vec::Vec<_>>(), [1]);
        assert_eq!(table.due(&mon).copied().collect::<std::vec::Vec<_>>(), [2]);
        let mut t2: MinuteTable<u8, 4> = MinuteTable::new();
        assert!(
            t2.add(Start {
                hour: 24,
                minute: 0,
                days: Weekdays::ALL,
                program: 0
            })
            .is_err()
        );
    }
}
