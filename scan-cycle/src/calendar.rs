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
#[serde(expecting = "struct DateTime")] // what serde's messages name
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
    /// clock stops at [`DateTime::END`] rather than wrapping into an earlier year; the minute
    /// after it never begins, so it is not counted.
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
                // The minute counted last would be 10000-01-01 00:00, which the clock never
                // enters: it stops in 9999-12-31 23:59.
                *self = DateTime::END;
                return minutes.saturating_sub(1);
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

/// One start handed out by [`MinuteTable::check`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub struct Due<'a, P> {
    /// What to start.
    pub program: &'a P,
    /// Whole minutes between the minute the start was set for and the minute the clock is in
    /// now: 0 when it runs in its own minute.
    pub minutes_late: u64,
    /// Earlier times of the same line that the clock jumped over and that do not run.
    pub missed: u64,
}

/// What one [`MinuteTable::check`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub struct Checked {
    /// Starts handed out in their own minute.
    pub on_time: usize,
    /// Starts handed out late: the clock had jumped over their minute.
    pub late: usize,
    /// Times the clock jumped over that were not handed out (a line runs at most once per
    /// check: these are its earlier times).
    pub missed: u64,
    /// How many minutes the clock stands behind the latest minute already checked (it was set
    /// back); 0 when it is not behind. Nothing runs until it has passed that minute again.
    pub behind_minutes: u64,
}

const MINUTES_PER_DAY: i64 = 1440;
const MINUTES_PER_WEEK: i64 = 7 * MINUTES_PER_DAY;

/// Whole minutes since 0001-01-01 00:00 (the seconds left out); at most about 5.3 · 10⁹.
/// Swaps `items[a]` and `items[b]` for `a < b`; does nothing when either is out of range. No
/// panic path, unlike `slice::swap`.
fn swap_ordered<T>(items: &mut [T], a: usize, b: usize) {
    if let Some((low, high)) = items.split_at_mut_checked(b)
        && let (Some(x), Some(y)) = (low.get_mut(a), high.first_mut())
    {
        core::mem::swap(x, y);
    }
}

/// Heap sort, ascending, O(n log n) and in place. `core`'s sorts keep a panic path (a check for
/// an inconsistent `Ord`) that a no-panic firmware cannot link; this one has none.
fn heap_sort<T: Ord>(items: &mut [T]) {
    // Moves the element at `root` down the max-heap in `items[..end]`.
    fn sift_down<T: Ord>(items: &mut [T], mut root: usize, end: usize) {
        loop {
            let Some(left) = root.checked_mul(2).and_then(|r| r.checked_add(1)) else {
                return;
            };
            if left >= end {
                return;
            }
            let right = left.saturating_add(1);
            let child = match (items.get(left), items.get(right)) {
                (Some(l), Some(r)) if right < end && r > l => right,
                _ => left,
            };
            match (items.get(root), items.get(child)) {
                (Some(r), Some(c)) if c > r => {
                    swap_ordered(items, root, child);
                    root = child;
                }
                _ => return,
            }
        }
    }
    let len = items.len();
    for root in (0..len / 2).rev() {
        sift_down(items, root, len);
    }
    for end in (1..len).rev() {
        swap_ordered(items, 0, end);
        sift_down(items, 0, end);
    }
}

fn minute_number(t: &DateTime) -> i64 {
    day_number(t.year, t.month, t.day)
        .saturating_mul(MINUTES_PER_DAY)
        .saturating_add(i64::from(t.hour).saturating_mul(60))
        .saturating_add(i64::from(t.minute))
}

impl<P> Start<P> {
    /// How many times this line falls in minutes `..= t` (minute numbers from 0, day 0 a
    /// Monday), and the latest of them.
    fn times_up_to(&self, t: i64) -> (i64, Option<i64>) {
        let time_of_day = i64::from(self.hour)
            .saturating_mul(60)
            .saturating_add(i64::from(self.minute));
        let mut count = 0i64;
        let mut latest = None;
        for (day, offset) in (1u8..=7).zip(0i64..) {
            if !self.days.contains(day) {
                continue;
            }
            // The line's first time on this weekday; then one every week.
            let first = offset
                .saturating_mul(MINUTES_PER_DAY)
                .saturating_add(time_of_day);
            let Some(weeks) = t.checked_sub(first).map(|d| d.div_euclid(MINUTES_PER_WEEK)) else {
                continue;
            };
            if weeks < 0 {
                continue;
            }
            count = count.saturating_add(weeks.saturating_add(1));
            let last = first.saturating_add(weeks.saturating_mul(MINUTES_PER_WEEK));
            latest = latest.max(Some(last));
        }
        (count, latest)
    }
}

/// The source's minute table: each whole minute the table is checked for programs to start then
/// (it switched between six sorting schedules and printed statistics at 24:00).
///
/// **What a check hands out.** [`check`](MinuteTable::check) is called with the clock each cycle
/// (or each minute). The table remembers the latest minute it has checked, and hands out every
/// line whose time falls after that minute and up to the minute the clock is in now, once:
/// - *In time*: a line set for the minute the clock is in runs then (`minutes_late` 0).
/// - *Forward jump* (the clock was set forward, or the calendar was set from a real-time clock
///   after an outage): a line whose time the clock jumped over runs once, late, with
///   `minutes_late` saying how late. Starts come out in the order of their times, lines set for
///   the same time in table order.
/// - *Long jump*: a line runs at most once per check, for its latest time in the jump; its earlier
///   times are counted as `missed` (a daily report after a three-day outage runs once, and
///   reports 2 missed), so a check hands out at most `M` starts, whatever the jump.
/// - *Set-back* (a clock corrected backwards, a summer-time change): a start already handed out
///   is not handed out again. The table keeps the latest minute it reached and hands out nothing
///   until the clock has passed it again; [`Checked::behind_minutes`] says how far behind the
///   clock stands. After a wrong clock was corrected backwards by more than that should hold
///   (the plant had run on a date in the future), the operator re-arms the table with
///   [`set_checked_up_to`](MinuteTable::set_checked_up_to).
/// - *First check* (a new table, or after `set_checked_up_to(None)`): only lines set for the
///   minute the clock is in run; nothing is known about earlier minutes.
///
/// The cost of a check is O(M log M) for any jump, with no loop over the minutes jumped.
///
/// **Which clock.** Drive the [`DateTime`] from a wall clock, not from the executive's program
/// time ([`Executive::now_ms`](crate::Executive::now_ms) leaves power outages out, so a calendar
/// advanced from it would stay behind by every outage for good): advance it by the time a
/// free-running hardware counter measured, and after power returns set it afresh from the
/// real-time clock (`DateTime::new` with the RTC's fields). The table then catches up by the rules
/// above. Keep [`checked_up_to`](MinuteTable::checked_up_to) in battery-backed memory to carry
/// the rule over a restart.
///
/// ```
/// use regler_scan_cycle::{DateTime, MinuteTable, Start, Weekdays};
/// let mut table: MinuteTable<&str, 8> = MinuteTable::new();
/// assert!(table.add(Start { hour: 6, minute: 0, days: Weekdays::WORKDAYS, program: "morning schedule" }).is_ok());
/// assert!(table.add(Start { hour: 6, minute: 1, days: Weekdays::ALL, program: "lamp test" }).is_ok());
/// let mut clock = DateTime::new(2026, 11, 23, 5, 59, 30)?; // a Monday
/// let mut started = Vec::new();
/// table.check(&clock, |due| started.push((*due.program, due.minutes_late)));
/// clock.advance(150_000);                                   // a jump to 06:02:00
/// let checked = table.check(&clock, |due| started.push((*due.program, due.minutes_late)));
/// assert_eq!(started, [("morning schedule", 2), ("lamp test", 1)]);
/// assert_eq!((checked.on_time, checked.late, checked.missed), (0, 2, 0));
/// let earlier = DateTime::new(2026, 11, 23, 5, 58, 0)?;      // set back: nothing runs twice
/// let mut reran = 0;
/// assert_eq!(table.check(&earlier, |_| reran += 1).behind_minutes, 4);
/// assert_eq!(reran, 0);
/// # Ok::<(), regler_scan_cycle::InvalidDateTime>(())
/// ```
#[derive(Clone, Debug)]
pub struct MinuteTable<P, const M: usize> {
    starts: Vec<Start<P>, M>,
    /// The latest minute checked, seconds zero.
    checked_up_to: Option<DateTime>,
}

impl<P, const M: usize> Default for MinuteTable<P, M> {
    fn default() -> Self {
        MinuteTable::new()
    }
}

impl<P, const M: usize> MinuteTable<P, M> {
    /// An empty table that has checked no minute yet.
    #[must_use]
    pub const fn new() -> MinuteTable<P, M> {
        MinuteTable {
            starts: Vec::new(),
            checked_up_to: None,
        }
    }

    /// Adds a line; a full table or an impossible time is an error that hands the line back.
    pub fn add(&mut self, start: Start<P>) -> Result<(), AddError<P>> {
        if start.hour > 23 || start.minute > 59 {
            return Err(AddError::InvalidTime(start));
        }
        self.starts.push(start).map_err(AddError::Full)
    }

    /// Checks the table at clock time `now` and hands each start that is due to `start`, by the
    /// rules in the type's documentation: every line whose time falls after the latest minute
    /// checked and up to `now`'s minute runs once, late if the clock jumped over it, earlier
    /// times of the same line counted as missed; nothing runs twice when the clock is set back.
    pub fn check(&mut self, now: &DateTime, mut start: impl FnMut(Due<'_, P>)) -> Checked {
        let mut now_minute = *now;
        now_minute.second = 0;
        now_minute.millis = 0;
        let to = minute_number(&now_minute);
        let from = match self.checked_up_to {
            None => to.saturating_sub(1),
            Some(reached) => {
                let reached = minute_number(&reached);
                if to <= reached {
                    return Checked {
                        behind_minutes: u64::try_from(reached.saturating_sub(to)).unwrap_or(0),
                        ..Checked::default()
                    };
                }
                reached
            }
        };
        self.checked_up_to = Some(now_minute);
        // Each line's latest time in (from, to], and how many of its times fall there.
        let mut due: Vec<(i64, usize, u64), M> = Vec::new();
        let mut checked = Checked::default();
        for (index, line) in self.starts.iter().enumerate() {
            let (count_to, latest) = line.times_up_to(to);
            let (count_from, _) = line.times_up_to(from);
            let times = u64::try_from(count_to.saturating_sub(count_from)).unwrap_or(0);
            if let Some(at) = latest.filter(|_| times > 0) {
                let missed = times.saturating_sub(1);
                checked.missed = checked.missed.saturating_add(missed);
                // At most M lines: the push cannot fail.
                let _ = due.push((at, index, missed));
            }
        }
        heap_sort(&mut due);
        for &(at, index, missed) in &due {
            let Some(line) = self.starts.get(index) else {
                continue;
            };
            let minutes_late = u64::try_from(to.saturating_sub(at)).unwrap_or(0);
            if minutes_late == 0 {
                checked.on_time = checked.on_time.saturating_add(1);
            } else {
                checked.late = checked.late.saturating_add(1);
            }
            start(Due {
                program: &line.program,
                minutes_late,
                missed,
            });
        }
        checked
    }

    /// The latest minute the table has checked (seconds zero): what it will not hand out again.
    /// `None` before the first check.
    #[must_use]
    pub const fn checked_up_to(&self) -> Option<DateTime> {
        self.checked_up_to
    }

    /// Sets the latest minute checked: to carry it over a restart from battery-backed memory, or
    /// to re-arm the table after a clock that ran ahead was corrected backwards (`None`: the
    /// next check runs only the lines of the minute it is in).
    pub fn set_checked_up_to(&mut self, minute: Option<DateTime>) {
        self.checked_up_to = minute.map(|mut m| {
            m.second = 0;
            m.millis = 0;
            m
        });
    }

    /// The lines set for the minute `now` lies in, whether or not they were handed out. A query
    /// for a display: it remembers nothing, so a program driven by it loses the starts of every
    /// minute the clock jumps over and repeats those it is set back across. Start programs with
    /// [`check`](MinuteTable::check).
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
        assert_eq!(
            late.advance(120_000),
            0,
            "no minute begins after the last one"
        );
        assert_eq!(late, DateTime::END, "stops, does not wrap to 9999-01-01");
        assert_eq!(late.advance(u32::MAX), 0);
        assert_eq!(late, DateTime::END);
    }

    #[test]
    #[cfg_attr(
        miri,
        ignore = "21 720 clock advances: hours under Miri; safe code, run natively in every CI run"
    )]
    fn advance_into_the_end_counts_only_the_minutes_the_clock_entered() {
        // Every start second of the last two minutes, every step up to past the end: the count
        // is the minute boundaries crossed up to 23:59, the last minute the clock enters.
        for start in 0..120u32 {
            for step_s in 0..=180u32 {
                let minute = u8::try_from(58 + start / 60).unwrap();
                let second = u8::try_from(start % 60).unwrap();
                let mut t = DateTime::new(9999, 12, 31, 23, minute, second).unwrap();
                let began = t.advance(step_s * 1000);
                let reached = (start + step_s).min(119); // seconds since 23:58:00, capped at END
                let want = reached / 60 - start / 60;
                assert_eq!(began, want, "from 23:{minute}:{second} by {step_s} s");
                if start + step_s > 119 {
                    assert_eq!(t, DateTime::END);
                }
            }
        }
    }

    #[test]
    #[cfg_attr(
        miri,
        ignore = "exhaustive: every slice of up to 6 over 4 values, and slices up to 1 440: hours under Miri; safe code, run natively in every CI run"
    )]
    fn heap_sort_sorts_every_small_slice_like_core() {
        // Every sequence of length 0..=6 over 4 values (ties included), and longer random ones.
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        for len in 0..=6u32 {
            for code in 0..4u32.pow(len) {
                let mut v: std::vec::Vec<(u32, usize)> = (0..len)
                    .map(|i| ((code >> (2 * i)) & 3, i as usize % 2))
                    .collect();
                let mut want = v.clone();
                want.sort_unstable();
                heap_sort(&mut v);
                assert_eq!(v, want);
            }
        }
        for len in [7usize, 31, 64, 257, 1440] {
            let mut v: std::vec::Vec<(i64, usize, u64)> = (0..len)
                .map(|i| {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    ((state % 50) as i64 - 25, i, state % 3)
                })
                .collect();
            let mut want = v.clone();
            want.sort_unstable();
            heap_sort(&mut v);
            assert_eq!(v, want);
        }
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

    /// The milliseconds a stored clock may hold (restored through `checked`): 0 to 999.
    #[test]
    fn stored_milliseconds_stop_at_999() {
        let at = |ms| DateTime::checked(2026, 1, 1, 0, 0, 0, ms);
        assert_eq!(at(999).map(|t| t.millis), Ok(999));
        assert_eq!(at(1000), Err(InvalidDateTime::Millis(1000)));
        assert_eq!(at(u16::MAX), Err(InvalidDateTime::Millis(u16::MAX)));
    }

    #[test]
    fn add_errors_say_what_was_wrong() {
        let at = |hour, minute| Start {
            hour,
            minute,
            days: Weekdays::ALL,
            program: 0u8,
        };
        assert_eq!(
            AddError::Full(at(7, 3)).to_string(),
            "the minute table is full"
        );
        assert_eq!(
            AddError::InvalidTime(at(24, 5)).to_string(),
            "no such time of day: 24:05 (hours 0-23, minutes 0-59)"
        );
        assert_eq!(
            AddError::InvalidTime(at(6, 60)).to_string(),
            "no such time of day: 06:60 (hours 0-23, minutes 0-59)"
        );
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
