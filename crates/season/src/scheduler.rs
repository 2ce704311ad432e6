//! The Poisson stochastic scheduler of Cordonnier et al. 2018, Section 3.1.
//!
//! Each phenomenon is a Poisson process of mean frequency `f_e` (events per day). The waiting
//! time to the next event of type `e` is exponential, so the next event of the superposed
//! process is of type `e` with probability `P(e) = f_e / Σ_i f_i` (paper Eq. 1). The paper
//! advances the clock by a mean step rather than a sampled one; we advance it by the mean
//! waiting time of the superposed process, `1 / Σ_i f_i`, so each phenomenon fires `f_e` times
//! per simulated day on average, and each event integrates its phenomenon over its own mean
//! period `δt_e = 1 / f_e`. High-frequency events (avalanche steps at 10 per second) dominate
//! `Σ f` while active, which shrinks the clock step to fractions of a second: the paper's
//! temporal zoom falls out of the same rule.
//!
//! Start/stop events gate phenomena that come in periods (a snowfall lasts a few days): a
//! start event activates the gated step events, and the period ends after a duration drawn
//! from an exponential law of the period's mean length.
//!
//! Determinism: the k-th draw uses the counter-based generator keyed by (seed, k), so the
//! event sequence is a pure function of the seed and the scheduler state, which is plain data
//! (`Serialize`) and can be checkpointed and resumed bit-identically.

use crate::phenomenon::{PhenomenonError, check_range};
use serde::{Deserialize, Serialize};
use snowscape_terrain::random;

/// The kinds of events the season is made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EventKind {
    /// Starts a snowfall period (Cordonnier: once a week on average).
    SnowfallStart,
    /// One precipitation step during a snowfall period (twice a day).
    SnowfallStep,
    /// Melt and snow-state changes (twice a day).
    MeltAndStateStep,
    /// Powder diffusion (twice a day).
    PowderDiffusionStep,
    /// Wind transport (twice a day).
    WindTransportStep,
    /// Starts an avalanche somewhere (rare; also triggered by the user).
    AvalancheStart,
    /// One avalanche flow step (10 per second while an avalanche runs).
    AvalancheStep,
    /// Starts a skier (also triggered by the user).
    SkierStart,
    /// One skier step while skiers are on the slopes.
    SkierStep,
}

/// Seconds per day.
pub const SECONDS_PER_DAY: f64 = 86_400.0;

/// Mean frequency of one event kind and whether it is currently active.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EventRate {
    pub kind: EventKind,
    /// Mean number of events per simulated day.
    pub per_day: f64,
    /// Inactive kinds (e.g. snowfall steps outside a snowfall period) are never drawn.
    pub active: bool,
}

/// One drawn event.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Event {
    pub kind: EventKind,
    /// Simulated time at which it happens, days since the season start.
    pub time_days: f64,
    /// The period the event integrates its phenomenon over, days (`1 / f_e`).
    pub dt_days: f64,
    /// Sequence number of this draw (0, 1, 2, ...): a key for the event's own random numbers.
    pub index: u64,
}

/// The scheduler's whole state: plain data, checkpointed as is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scheduler {
    seed: u64,
    draws: u64,
    time_days: f64,
    rates: Vec<EventRate>,
    /// End of the current snowfall period, days, when one is running.
    snowfall_until: Option<f64>,
    /// Start of the current snowfall period, days, when one is running.
    #[serde(default)]
    snowfall_since: Option<f64>,
    /// Mean length of a snowfall period, days (Cordonnier: three days).
    snowfall_mean_days: f64,
}

/// Default frequencies of Cordonnier 2018 Section 3.2, events per day.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EventFrequencies {
    /// Snowfall-Start, per day. Paper: once a week.
    pub snowfall_start: f64,
    /// Snowfall-Step during a period, per day. Paper: twice a day.
    pub snowfall_step: f64,
    /// Mean snowfall period, days. Paper: three days.
    pub snowfall_mean_days: f64,
    /// Snow-Melting-Step (melt and state changes), per day. Paper: twice a day.
    pub melt_and_state: f64,
    /// Powder diffusion, per day. Paper §8: about as often as melt (200 events in 100 days).
    pub powder_diffusion: f64,
    /// Wind-Transport-Step, per day. Paper: twice a day.
    pub wind_transport: f64,
}

/// Most events of one kind per day (every ~15 minutes): the season's work grows with it.
pub const MAX_EVENTS_PER_DAY: f64 = 100.0;

impl EventFrequencies {
    /// Checks every frequency: within [0, 100] per day (`snowfall_start` within [0, 10]),
    /// and the mean snowfall period within [0.01, 365] days.
    pub fn validate(&self) -> Result<(), PhenomenonError> {
        const P: &str = "events";
        check_range(
            P,
            "snowfall_start",
            self.snowfall_start,
            [0.0, 10.0],
            " per day",
        )?;
        for (name, v) in [
            ("snowfall_step", self.snowfall_step),
            ("melt_and_state", self.melt_and_state),
            ("powder_diffusion", self.powder_diffusion),
            ("wind_transport", self.wind_transport),
        ] {
            check_range(P, name, v, [0.0, MAX_EVENTS_PER_DAY], " per day")?;
        }
        check_range(
            P,
            "snowfall_mean_days",
            self.snowfall_mean_days,
            [0.01, 365.0],
            " days",
        )
    }
}

impl Default for EventFrequencies {
    fn default() -> Self {
        Self {
            snowfall_start: 1.0 / 7.0,
            snowfall_step: 2.0,
            snowfall_mean_days: 3.0,
            melt_and_state: 2.0,
            powder_diffusion: 2.0,
            wind_transport: 2.0,
        }
    }
}

/// Random-number streams of the scheduler (distinct from the phenomena's streams).
const STREAM_KIND: u64 = 0x5c4e_d01e;
const STREAM_PERIOD: u64 = 0x5c4e_d01f;

impl Scheduler {
    /// A scheduler for the snow-cover events, at time 0.
    pub fn new(seed: u64, f: &EventFrequencies) -> Self {
        let rate = |kind, per_day: f64, active| EventRate {
            kind,
            per_day: per_day.max(0.0),
            active,
        };
        Self {
            seed,
            draws: 0,
            time_days: 0.0,
            rates: vec![
                rate(EventKind::SnowfallStart, f.snowfall_start, true),
                rate(EventKind::SnowfallStep, f.snowfall_step, false),
                rate(EventKind::MeltAndStateStep, f.melt_and_state, true),
                rate(EventKind::PowderDiffusionStep, f.powder_diffusion, true),
                rate(EventKind::WindTransportStep, f.wind_transport, true),
            ],
            snowfall_until: None,
            snowfall_since: None,
            snowfall_mean_days: f.snowfall_mean_days.max(1e-6),
        }
    }

    /// Simulated time, days.
    pub fn time_days(&self) -> f64 {
        self.time_days
    }
    /// Number of events drawn so far.
    pub fn draws(&self) -> u64 {
        self.draws
    }
    /// Whether a snowfall period is running.
    pub fn snowing(&self) -> bool {
        self.snowfall_until.is_some()
    }

    /// The running snowfall period: its start and end, days.
    pub fn snowfall_period(&self) -> Option<(f64, f64)> {
        let until = self.snowfall_until?;
        Some((
            self.snowfall_since.unwrap_or(self.time_days).min(until),
            until,
        ))
    }

    /// Adds or updates the rate of an event kind (e.g. avalanche steps while one runs).
    pub fn set_rate(&mut self, kind: EventKind, per_day: f64, active: bool) {
        match self.rates.iter_mut().find(|r| r.kind == kind) {
            Some(r) => {
                r.per_day = per_day.max(0.0);
                r.active = active;
            }
            None => self.rates.push(EventRate {
                kind,
                per_day: per_day.max(0.0),
                active,
            }),
        }
    }

    /// Advances the clock by `days` without drawing an event: the temporal zoom of a phenomenon
    /// that runs to its end inside one event (an avalanche, §3.1 Fig. 4).
    pub fn advance_clock(&mut self, days: f64) {
        self.time_days += days.max(0.0);
    }

    /// Starts a snowfall period of `days` now.
    fn start_snowfall(&mut self, days: f64) {
        self.force_snowfall(self.time_days, self.time_days + days.max(0.0));
    }

    /// Runs a snowfall period scheduled from `since` until `until`, days (scenario-forced
    /// snowfall, started at the first event at or after `since`): a running period that has
    /// not ended is extended, else one starts, dated `since`.
    pub fn force_snowfall(&mut self, since: f64, until: f64) {
        match self.snowfall_until {
            Some(u) if u > self.time_days => self.snowfall_until = Some(u.max(until)),
            _ => {
                self.snowfall_until = Some(until);
                self.snowfall_since = Some(since.min(self.time_days));
            }
        }
        self.set_active(EventKind::SnowfallStep, true);
    }

    fn set_active(&mut self, kind: EventKind, active: bool) {
        if let Some(r) = self.rates.iter_mut().find(|r| r.kind == kind) {
            r.active = active;
        }
    }

    fn total_rate(&self) -> f64 {
        self.rates
            .iter()
            .filter(|r| r.active)
            .map(|r| r.per_day)
            .sum()
    }

    /// Draws the next event and advances the clock; `None` when no event kind is active.
    pub fn next_event(&mut self) -> Option<Event> {
        if let Some(until) = self.snowfall_until
            && self.time_days >= until
        {
            self.snowfall_until = None;
            self.snowfall_since = None;
            self.set_active(EventKind::SnowfallStep, false);
        }
        let total = self.total_rate();
        if total <= 0.0 {
            return None;
        }
        let index = self.draws;
        let u = random::uniform(self.seed, STREAM_KIND, index) * total;
        let mut drawable = self.rates.iter().filter(|r| r.active && r.per_day > 0.0);
        let mut acc = 0.0;
        let mut chosen = None;
        for r in drawable.by_ref() {
            acc += r.per_day;
            chosen = Some(r);
            if u < acc {
                break;
            }
        }
        // `total > 0` guarantees one drawable rate; rounding may leave `u` past the last sum.
        let chosen = chosen?;
        let kind = chosen.kind;
        let dt_days = 1.0 / chosen.per_day;
        self.draws += 1;
        self.time_days += 1.0 / total;
        if kind == EventKind::SnowfallStart && self.snowfall_until.is_none() {
            let v = random::uniform(self.seed, STREAM_PERIOD, index).max(f64::MIN_POSITIVE);
            let length = -self.snowfall_mean_days * v.ln();
            self.start_snowfall(length);
        }
        Some(Event {
            kind,
            time_days: self.time_days,
            dt_days,
            index,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn counts(seed: u64, days: f64) -> BTreeMap<EventKind, usize> {
        let mut s = Scheduler::new(seed, &EventFrequencies::default());
        let mut c = BTreeMap::new();
        while s.time_days() < days {
            let e = s.next_event().unwrap();
            *c.entry(e.kind).or_insert(0) += 1;
        }
        c
    }

    #[test]
    fn a_hundred_days_has_the_papers_event_counts() {
        // Cordonnier §8: ≈200 wind, 200 diffusion, 200 melt/state, 100 snowfall events.
        let c = counts(7, 100.0);
        for k in [
            EventKind::WindTransportStep,
            EventKind::PowderDiffusionStep,
            EventKind::MeltAndStateStep,
        ] {
            let n = c[&k] as f64;
            assert!((150.0..=250.0).contains(&n), "{k:?}: {n}");
        }
        let snow = c[&EventKind::SnowfallStep] as f64;
        assert!((40.0..=160.0).contains(&snow), "snowfall steps {snow}");
    }

    #[test]
    fn probabilities_follow_the_rates() {
        let mut s = Scheduler::new(1, &EventFrequencies::default());
        s.set_rate(EventKind::AvalancheStep, 6.0, true);
        let mut n_av = 0;
        let n = 20_000;
        for _ in 0..n {
            if s.next_event().unwrap().kind == EventKind::AvalancheStep {
                n_av += 1;
            }
        }
        // Σf ≈ 6 + 6 + 1/7 + (2 while snowing): the avalanche share is about one half.
        let share = n_av as f64 / n as f64;
        assert!((0.40..0.52).contains(&share), "{share}");
    }

    #[test]
    fn temporal_zoom_shrinks_the_clock_step() {
        let mut s = Scheduler::new(3, &EventFrequencies::default());
        s.set_rate(EventKind::AvalancheStep, 10.0 * SECONDS_PER_DAY, true);
        let t0 = s.time_days();
        for _ in 0..100 {
            s.next_event();
        }
        let seconds = (s.time_days() - t0) * SECONDS_PER_DAY;
        assert!(
            (9.0..11.0).contains(&seconds),
            "100 avalanche-time events took {seconds} s"
        );
    }

    #[test]
    fn same_seed_same_sequence_and_resume_is_identical() {
        let mut a = Scheduler::new(11, &EventFrequencies::default());
        let mut b = a.clone();
        let mut seq_a = Vec::new();
        for _ in 0..500 {
            seq_a.push(a.next_event().unwrap());
        }
        for _ in 0..200 {
            b.next_event();
        }
        let saved = serde_json::to_string(&b).unwrap();
        let mut c: Scheduler = serde_json::from_str(&saved).unwrap();
        let rest: Vec<Event> = (0..300).map(|_| c.next_event().unwrap()).collect();
        assert_eq!(&seq_a[200..], &rest[..]);
        let mut d = Scheduler::new(12, &EventFrequencies::default());
        let other: Vec<EventKind> = (0..500).map(|_| d.next_event().unwrap().kind).collect();
        assert_ne!(seq_a.iter().map(|e| e.kind).collect::<Vec<_>>(), other);
    }

    #[test]
    fn snowfall_steps_only_inside_periods() {
        let mut s = Scheduler::new(5, &EventFrequencies::default());
        let mut steps = 0;
        for _ in 0..3000 {
            let e = s.next_event().unwrap();
            if e.kind == EventKind::SnowfallStep {
                assert!(
                    s.snowing(),
                    "snowfall step at day {} outside a period",
                    e.time_days
                );
                steps += 1;
            }
        }
        assert!(steps > 0);
    }
}
