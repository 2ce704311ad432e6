//! Calendar times of a forcing series: parsing the ISO 8601 subset the readers accept, and the
//! proleptic Gregorian day count that checks the spacing of the records.
//!
//! Accepted: `YYYY-MM-DD` (midnight), `YYYY-MM-DDTHH:MM`, `YYYY-MM-DD HH:MM`, each optionally
//! with `:SS` where the seconds are `00`. No time-zone suffix: times are the station's clock,
//! whatever it is (the snobal file is MST), and only their spacing matters to the readers.
//! The day count is Howard Hinnant's `days_from_civil` (public-domain algorithm,
//! <https://howardhinnant.github.io/date_algorithms.html>).

use std::fmt;

/// A calendar time to the minute (no time zone: the station's clock).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ForcingTime {
    pub year: i32,
    /// 1..=12.
    pub month: u32,
    /// 1..=31 (checked against the month and leap years).
    pub day: u32,
    /// 0..=23.
    pub hour: u32,
    /// 0..=59 (0 for hourly and daily series).
    pub minute: u32,
}

/// Whether `year` is a Gregorian leap year.
pub fn is_leap_year(year: i32) -> bool {
    (year % 4 == 0 && year % 100 != 0) || year % 400 == 0
}

/// Days in `month` (1..=12) of `year`.
pub fn days_in_month(year: i32, month: u32) -> u32 {
    match month {
        1 | 3 | 5 | 7 | 8 | 10 | 12 => 31,
        4 | 6 | 9 | 11 => 30,
        2 if is_leap_year(year) => 29,
        2 => 28,
        _ => 0,
    }
}

/// Days from 1970-01-01 to `year-month-day` (negative before), Hinnant's `days_from_civil`.
fn days_from_civil(year: i32, month: u32, day: u32) -> i64 {
    let y = i64::from(year) - i64::from(month <= 2);
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let m = i64::from(month);
    let doy = (153 * (if m > 2 { m - 3 } else { m + 9 }) + 2) / 5 + i64::from(day) - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// The calendar date of `days` since 1970-01-01, Hinnant's `civil_from_days`.
fn civil_from_days(days: i64) -> (i32, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let year = (yoe + era * 400 + i64::from(month <= 2)) as i32;
    (year, month, day)
}

impl ForcingTime {
    /// Midnight of a date.
    pub fn date(year: i32, month: u32, day: u32) -> Self {
        Self {
            year,
            month,
            day,
            hour: 0,
            minute: 0,
        }
    }

    /// Parses the accepted ISO 8601 forms (module docs); the error says what is wrong.
    pub fn parse(text: &str) -> Result<Self, &'static str> {
        let t = text.trim();
        let (date, clock) = match t.find(['T', ' ']) {
            Some(at) => (&t[..at], Some(t[at + 1..].trim_start())),
            None => (t, None),
        };
        let num = |s: &str, digits: usize| -> Option<u32> {
            (s.len() == digits && s.bytes().all(|b| b.is_ascii_digit()))
                .then(|| s.parse().ok())
                .flatten()
        };
        const DATE: &str = "a date YYYY-MM-DD, optionally with a time THH:MM or ' HH:MM'";
        let mut parts = date.split('-');
        let (Some(y), Some(m), Some(d), None) =
            (parts.next(), parts.next(), parts.next(), parts.next())
        else {
            return Err(DATE);
        };
        let (Some(year), Some(month), Some(day)) = (num(y, 4), num(m, 2), num(d, 2)) else {
            return Err(DATE);
        };
        if !(1..=12).contains(&month) {
            return Err("a month 01..12");
        }
        if day == 0 || day > days_in_month(year as i32, month) {
            return Err("a day that exists in that month");
        }
        let (mut hour, mut minute) = (0, 0);
        if let Some(clock) = clock {
            const CLOCK: &str = "a time of day HH:MM (or HH:MM:00), without a time zone";
            let mut parts = clock.split(':');
            let (Some(h), Some(mi), s, None) =
                (parts.next(), parts.next(), parts.next(), parts.next())
            else {
                return Err(CLOCK);
            };
            let (Some(h), Some(mi)) = (num(h, 2), num(mi, 2)) else {
                return Err(CLOCK);
            };
            if s.is_some_and(|s| num(s, 2) != Some(0)) {
                return Err("whole minutes (seconds :00)");
            }
            if h > 23 || mi > 59 {
                return Err("an hour 00..23 and minutes 00..59");
            }
            (hour, minute) = (h, mi);
        }
        Ok(Self {
            year: year as i32,
            month,
            day,
            hour,
            minute,
        })
    }

    /// Minutes since 1970-01-01T00:00 (negative before).
    pub fn minutes_since_epoch(&self) -> i64 {
        days_from_civil(self.year, self.month, self.day) * 1440
            + i64::from(self.hour) * 60
            + i64::from(self.minute)
    }

    /// The time `minutes` (may be negative) after 1970-01-01T00:00.
    pub fn from_minutes_since_epoch(minutes: i64) -> Self {
        let (year, month, day) = civil_from_days(minutes.div_euclid(1440));
        let m = minutes.rem_euclid(1440);
        Self {
            year,
            month,
            day,
            hour: (m / 60) as u32,
            minute: (m % 60) as u32,
        }
    }

    /// The time `hours` later (rounded to the minute).
    pub fn plus_hours(&self, hours: f64) -> Self {
        Self::from_minutes_since_epoch(self.minutes_since_epoch() + (hours * 60.0).round() as i64)
    }

    /// Day of the year, 1 on 1 January.
    pub fn day_of_year(&self) -> u32 {
        (days_from_civil(self.year, self.month, self.day) - days_from_civil(self.year, 1, 1)) as u32
            + 1
    }
}

impl fmt::Display for ForcingTime {
    /// ISO 8601, `YYYY-MM-DDTHH:MM`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:04}-{:02}-{:02}T{:02}:{:02}",
            self.year, self.month, self.day, self.hour, self.minute
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_three_forms() {
        let t = ForcingTime::parse("1983-10-01").unwrap();
        assert_eq!(t, ForcingTime::date(1983, 10, 1));
        let t = ForcingTime::parse("1984-02-29T13:30").unwrap();
        assert_eq!((t.day, t.hour, t.minute), (29, 13, 30));
        assert_eq!(ForcingTime::parse("1984-02-29 13:30:00").unwrap(), t);
        for bad in [
            "1983-02-29",
            "1983-13-01",
            "83-10-01",
            "1983-10-01T24:00",
            "1983-10-01 12",
            "1983-10-01T12:00:30",
            "1983-10-01T12:00Z",
            "",
        ] {
            assert!(ForcingTime::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn epoch_minutes_round_trip_across_leap_years_and_centuries() {
        assert_eq!(ForcingTime::date(1970, 1, 1).minutes_since_epoch(), 0);
        assert_eq!(ForcingTime::date(1969, 12, 31).minutes_since_epoch(), -1440);
        // Water year 1984 is 366 days (29 February 1984).
        let a = ForcingTime::date(1983, 10, 1).minutes_since_epoch();
        let b = ForcingTime::date(1984, 10, 1).minutes_since_epoch();
        assert_eq!(b - a, 366 * 1440);
        for m in [-5_000_000_000i64, -1, 0, 59, 1_000_000, 16_000_000_123] {
            let t = ForcingTime::from_minutes_since_epoch(m);
            assert_eq!(t.minutes_since_epoch(), m, "{t}");
        }
        assert_eq!(
            ForcingTime::from_minutes_since_epoch(
                ForcingTime::date(2000, 3, 1).minutes_since_epoch() - 1
            )
            .to_string(),
            "2000-02-29T23:59"
        );
        assert_eq!(ForcingTime::date(1984, 12, 31).day_of_year(), 366);
        assert_eq!(ForcingTime::date(1983, 12, 31).day_of_year(), 365);
        assert_eq!(
            ForcingTime::date(1983, 10, 1)
                .plus_hours(8783.0)
                .to_string(),
            "1984-09-30T23:00"
        );
    }
}
