//! Piecewise-constant timelines: the one rule for a weather timeline, shared by a season
//! (`snowscape-season`'s `[[weather]]` periods, in days) and a transport run
//! (`snowscape-transport`'s weather periods, in hours).
//!
//! A timeline is a list of periods, each in force from its start until the next one starts
//! (the last one until the end of the run). Its starts are finite, the first is 0 and each
//! is later than the one before it; its clock's unit is part of the period's type
//! ([`TimelinePeriod::UNIT`]) and of its start's name in a file (`from_day`, `from_hour`).

/// The unit of a timeline's clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeUnit {
    /// Hours since the start of the run.
    Hours,
    /// Days since the start of the season.
    Days,
}

impl TimeUnit {
    /// Hours in one unit.
    pub fn hours(self) -> f64 {
        match self {
            TimeUnit::Hours => 1.0,
            TimeUnit::Days => 24.0,
        }
    }

    /// The unit's name, singular ("hour", "day").
    pub fn name(self) -> &'static str {
        match self {
            TimeUnit::Hours => "hour",
            TimeUnit::Days => "day",
        }
    }
}

/// A period of a piecewise-constant timeline.
pub trait TimelinePeriod {
    /// The unit of [`TimelinePeriod::start`].
    const UNIT: TimeUnit;
    /// Name of the start in a file (`from_day`, `from_hour`), for messages.
    const START_KEY: &'static str;
    /// Start of the period, in [`TimelinePeriod::UNIT`]s since the start of the timeline.
    fn start(&self) -> f64;
}

/// Why a list of periods is not a timeline: which period, its start and the rule it breaks.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("period {index}: {key} = {start}: {reason}")]
pub struct TimelineError {
    /// Position of the period in the list.
    pub index: usize,
    /// Name of the start in a file (`from_day`, `from_hour`).
    pub key: &'static str,
    /// The offending start (NaN for an empty timeline).
    pub start: f64,
    /// The rule it breaks.
    pub reason: String,
}

/// Checks that `periods` is a timeline (module docs); an empty list is one only when
/// `allow_empty` (a season without `[[weather]]` makes its own).
pub fn check_timeline<P: TimelinePeriod>(
    periods: &[P],
    allow_empty: bool,
) -> Result<(), TimelineError> {
    let error = |index: usize, start: f64, reason: String| TimelineError {
        index,
        key: P::START_KEY,
        start,
        reason,
    };
    let unit = P::UNIT.name();
    let Some(first) = periods.first() else {
        return if allow_empty {
            Ok(())
        } else {
            Err(error(0, f64::NAN, "no weather period".into()))
        };
    };
    let mut last = f64::NEG_INFINITY;
    for (index, p) in periods.iter().enumerate() {
        let start = p.start();
        if !start.is_finite() || start < 0.0 {
            return Err(error(
                index,
                start,
                format!("a period starts at a finite {unit} >= 0"),
            ));
        }
        if start <= last {
            return Err(error(
                index,
                start,
                format!("periods must start at strictly increasing {unit}s"),
            ));
        }
        last = start;
    }
    if first.start() != 0.0 {
        return Err(error(
            0,
            first.start(),
            format!("the first period must start at {unit} 0"),
        ));
    }
    Ok(())
}

/// Index of the period in force at `time` (the last one starting at or before it; the
/// first one before the timeline starts); `None` for an empty timeline.
pub fn period_index_at<P: TimelinePeriod>(periods: &[P], time: f64) -> Option<usize> {
    if periods.is_empty() {
        return None;
    }
    Some(
        periods
            .partition_point(|p| p.start() <= time)
            .saturating_sub(1),
    )
}

/// Start of the first period that starts after `time`, if any.
pub fn next_start_after<P: TimelinePeriod>(periods: &[P], time: f64) -> Option<f64> {
    let k = periods.partition_point(|p| p.start() <= time);
    periods.get(k).map(P::start)
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Hourly(f64);
    impl TimelinePeriod for Hourly {
        const UNIT: TimeUnit = TimeUnit::Hours;
        const START_KEY: &'static str = "from_hour";
        fn start(&self) -> f64 {
            self.0
        }
    }

    fn line(starts: &[f64]) -> Vec<Hourly> {
        starts.iter().map(|&s| Hourly(s)).collect()
    }

    #[test]
    fn a_timeline_starts_at_zero_and_increases() {
        assert!(check_timeline(&line(&[0.0, 12.0, 30.5]), false).is_ok());
        assert!(check_timeline(&line(&[]), true).is_ok());
        let e = check_timeline(&line(&[]), false).unwrap_err();
        assert_eq!(e.index, 0);
        let e = check_timeline(&line(&[1.0, 2.0]), false).unwrap_err();
        assert_eq!((e.index, e.start), (0, 1.0));
        assert!(e.reason.contains("hour 0"), "{e}");
        let e = check_timeline(&line(&[0.0, 5.0, 5.0]), false).unwrap_err();
        assert_eq!((e.index, e.start, e.key), (2, 5.0, "from_hour"));
        for bad in [f64::NAN, f64::INFINITY, -1.0] {
            let e = check_timeline(&line(&[0.0, bad]), false).unwrap_err();
            assert_eq!(e.index, 1, "{e}");
        }
        assert_eq!(TimeUnit::Days.hours(), 24.0);
    }

    #[test]
    fn the_period_in_force_is_the_last_started() {
        let t = line(&[0.0, 12.0, 30.0]);
        assert_eq!(period_index_at(&t, -1.0), Some(0));
        assert_eq!(period_index_at(&t, 0.0), Some(0));
        assert_eq!(period_index_at(&t, 11.9), Some(0));
        assert_eq!(period_index_at(&t, 12.0), Some(1));
        assert_eq!(period_index_at(&t, 1e9), Some(2));
        assert_eq!(period_index_at(&line(&[]), 3.0), None);
        assert_eq!(next_start_after(&t, 0.0), Some(12.0));
        assert_eq!(next_start_after(&t, 12.0), Some(30.0));
        assert_eq!(next_start_after(&t, 30.0), None);
    }
}
