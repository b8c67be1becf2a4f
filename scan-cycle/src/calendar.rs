//! The plant calendar: a clock advanced by the cycle, and a minute table of program starts.

use core::fmt;

use heapless::Vec;

/// A date and time of day (proleptic Gregorian calendar, no time zone). Deserializing checks
/// every field as [`DateTime::new`] does: a stored 31 February is an error, not a clock.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "RawDateTime"))]
pub struct DateTime {
    year: u16,
    month: u8,
    day: u8,
    hour: u8,
    minute: u8,
    second: u8,
    millis: u16,
}

/// A date or time that does not exist, naming the field that is wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum InvalidDateTime {
    /// The year is not within 1..=9999.
    Year(u16),
    /// The month is not within 1..=12.
    Month(u8),
    /// The month has no such day.
    Day {
        /// The day asked for.
        day: u8,
        /// Days in that month of that year.
        days_in_month: u8,
    },
    /// The hour is not within 0..=23.
    Hour(u8),
    /// The minute is not within 0..=59.
    Minute(u8),
    /// The second is not within 0..=59.
    Second(u8),
    /// Stored milliseconds not within 0..=999.
    Millis(u16),
}

impl fmt::Display for InvalidDateTime {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            InvalidDateTime::Year(y) => write!(f, "the year must be 1..=9999, got {y}"),
            InvalidDateTime::Month(m) => write!(f, "the month must be 1..=12, got {m}"),
            InvalidDateTime::Day { day, days_in_month } => {
                write!(
                    f,
                    "the day must be 1..={days_in_month} in that month, got {day}"
                )
            }
            InvalidDateTime::Hour(h) => write!(f, "the hour must be 0..=23, got {h}"),
            InvalidDateTime::Minute(m) => write!(f, "the minute must be 0..=59, got {m}"),
            InvalidDateTime::Second(s) => write!(f, "the second must be 0..=59, got {s}"),
            InvalidDateTime::Millis(ms) => write!(f, "the milliseconds must be 0..=999, got {ms}"),
        }
    }
}

impl core::error::Error for InvalidDateTime {}

/// The stored form of a [`DateTime`], checked on the way in.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct RawDateTime {
    year: u16,
    month: u8,
    day: u8,
    hour: u8,
    minute: u8,
    second: u8,
    millis: u16,
}

#[cfg(feature = "serde")]
impl TryFrom<RawDateTime> for DateTime {
    type Error = InvalidDateTime;
    fn try_from(r: RawDateTime) -> Result<DateTime, InvalidDateTime> {
        DateTime::checked(r.year, r.month, r.day, r.hour, r.minute, r.second, r.millis)
    }
}

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
        DateTime::checked(year, month, day, hour, minute, second, 0)
    }

    fn checked(
        year: u16,
        month: u8,
        day: u8,
        hour: u8,
        minute: u8,
        second: u8,
        millis: u16,
    ) -> Result<DateTime, InvalidDateTime> {
        if !(1..=9999).contains(&year) {
            return Err(InvalidDateTime::Year(year));
        }
        if !(1..=12).contains(&month) {
            return Err(InvalidDateTime::Month(month));
        }
        let days = days_in_month(year, month);
        if day < 1 || day > days {
            return Err(InvalidDateTime::Day {
                day,
                days_in_month: days,
            });
        }
        if hour > 23 {
            return Err(InvalidDateTime::Hour(hour));
        }
        if minute > 59 {
            return Err(InvalidDateTime::Minute(minute));
        }
        if second > 59 {
            return Err(InvalidDateTime::Second(second));
        }
        if millis > 999 {
            return Err(InvalidDateTime::Millis(millis));
        }
        Ok(DateTime {
            year,
            month,
            day,
            hour,
            minute,
            second,
            millis,
        })
    }

    /// The last moment the calendar holds: 9999-12-31 23:59:59.999, where
    /// [`advance`](DateTime::advance) stops.
    pub const END: DateTime = DateTime {
        year: 9999,
        month: 12,
        day: 31,
        hour: 23,
        minute: 59,
        second: 59,
        millis: 999,
    };

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

    /// Advances by `ms` milliseconds; returns how many whole minutes began on the way. The
    /// clock stops at [`DateTime::END`] rather than wrapping into an earlier year.
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
            if self.year >= 9999 {
                *self = DateTime::END;
                return minutes;
            }
            self.month = 1;
            self.year = self.year.saturating_add(1);
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

/// Why [`MinuteTable::add`] refused a line; the line is handed back.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AddError<P> {
    /// The table has no room for another line.
    Full(Start<P>),
    /// The hour is above 23 or the minute above 59.
    InvalidTime(Start<P>),
}

impl<P> AddError<P> {
    /// The line that was refused.
    pub fn into_start(self) -> Start<P> {
        match self {
            AddError::Full(s) | AddError::InvalidTime(s) => s,
        }
    }
}

impl<P> fmt::Display for AddError<P> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AddError::Full(_) => f.write_str("the minute table is full"),
            AddError::InvalidTime(s) => write!(
                f,
                "no such time of day: {:02}:{:02} (hours 0-23, minutes 0-59)",
                s.hour, s.minute
            ),
        }
    }
}

impl<P: fmt::Debug> core::error::Error for AddError<P> {}

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

    /// Adds a line; a full table or an impossible time is an error that hands the line back.
    pub fn add(&mut self, start: Start<P>) -> Result<(), AddError<P>> {
        if start.hour > 23 || start.minute > 59 {
            return Err(AddError::InvalidTime(start));
        }
        self.starts.push(start).map_err(AddError::Full)
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
    fn errors_name_the_field_and_the_clock_stops_at_the_end() {
        assert_eq!(
            DateTime::new(2026, 2, 29, 0, 0, 0),
            Err(InvalidDateTime::Day {
                day: 29,
                days_in_month: 28
            })
        );
        assert_eq!(
            DateTime::new(0, 1, 1, 0, 0, 0),
            Err(InvalidDateTime::Year(0))
        );
        assert_eq!(
            DateTime::new(2026, 13, 1, 0, 0, 0),
            Err(InvalidDateTime::Month(13))
        );
        assert_eq!(
            DateTime::new(2026, 1, 1, 24, 0, 0),
            Err(InvalidDateTime::Hour(24))
        );
        assert_eq!(
            DateTime::new(2026, 1, 1, 0, 60, 0),
            Err(InvalidDateTime::Minute(60))
        );
        assert_eq!(
            DateTime::new(2026, 1, 1, 0, 0, 60).unwrap_err().to_string(),
            "the second must be 0..=59, got 60"
        );
        let mut late = DateTime::new(9999, 12, 31, 23, 59, 0).unwrap();
        assert_eq!(late.advance(120_000), 1, "one minute began before the end");
        assert_eq!(late, DateTime::END, "stops, does not wrap to 9999-01-01");
        late.advance(u32::MAX);
        assert_eq!(late, DateTime::END);
    }

    #[test]
    fn minute_table_says_why_it_refused() {
        let mut table: MinuteTable<u8, 1> = MinuteTable::new();
        let start = |hour, program| Start {
            hour,
            minute: 0,
            days: Weekdays::ALL,
            program,
        };
        assert_eq!(
            table.add(start(24, 1)),
            Err(AddError::InvalidTime(start(24, 1)))
        );
        table.add(start(6, 2)).unwrap();
        let full = table.add(start(7, 3)).unwrap_err();
        assert_eq!(full, AddError::Full(start(7, 3)));
        assert_eq!(full.into_start().program, 3);
    }

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
