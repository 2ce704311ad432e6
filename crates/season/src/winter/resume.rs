//! Checkpoints of a season: writing the whole run state, and resuming from it only when the
//! file is intact (`checkpoint::read` checks lengths and checksum) and was written for the
//! same terrain and scenario. The cheap checks (file, terrain, scenario) run before the
//! environment precompute, so a refused resume costs no time; a refusal names what changed.
//!
//! The checksum detects damage, not nonsense, so every decoded value is then validated as a
//! scenario is ([`validate_state`]): the scheduler's clock finite and within the season (its
//! end plus one event's reach), the timeline indices within their tables, every number of the
//! run state finite and within [`MAX_MAGNITUDE`] (counters within [`MAX_COUNT`]), each
//! avalanche's cell on the grid, the seed and the constant event rates the scenario's, the
//! snow layers finite and ≥ 0 and the other maps finite. A refusal is a
//! [`CheckpointError::Implausible`] naming the field and the value.

use super::{RunState, SeasonError, SnowpackState, Winter};
use crate::avalanches::HazardSources;
use crate::checkpoint::{self, CheckpointError, bedrock_fingerprint};
use crate::forcing::StationForcing;
use crate::scenario::Scenario;
use crate::scheduler::EventKind;
use snowscape_terrain::LayeredTerrain;

/// Extra per-cell maps after the four layers: scour, deposit, the pack's four arrays, rain.
const EXTRA_MAPS: usize = 7;

/// Largest magnitude of any number in a checkpointed run state (volumes in m³, days, metres):
/// 10^15 m³ is a million km³ of snow, beyond any terrain's.
pub const MAX_MAGNITUDE: f64 = 1e15;
/// Largest counter or index in a checkpointed run state (events, draws, skier steps): at a
/// microsecond an event, 10^12 events are eleven days of computing.
pub const MAX_COUNT: u64 = 1_000_000_000_000;

/// Most storms a checkpoint may list (those since the last melt window: a few).
const MAX_STORMS: usize = 10_000;

/// Keys of the run state that are identifiers (any 64-bit value) or checked elsewhere.
const NOT_MAGNITUDES: [&str; 4] = [
    "scenario",
    "fingerprint",
    "scenario_digest",
    "scheduler.seed",
];

/// Every number under `value` (at `key`) finite and within [`MAX_MAGNITUDE`], every integer
/// within [`MAX_COUNT`] (JSON has no NaN: a NaN was refused as a malformed header).
fn check_numbers(key: &str, value: &serde_json::Value) -> Result<(), CheckpointError> {
    use serde_json::Value;
    if NOT_MAGNITUDES.contains(&key) {
        return Ok(());
    }
    let join = |k: &str| {
        if key.is_empty() {
            k.to_string()
        } else {
            format!("{key}.{k}")
        }
    };
    match value {
        Value::Number(n) => {
            if let Some(u) = n.as_u64() {
                if u > MAX_COUNT {
                    return Err(CheckpointError::implausible(
                        key,
                        u,
                        format!("a count or index of at most {MAX_COUNT}"),
                    ));
                }
            } else if let Some(i) = n.as_i64() {
                if i.unsigned_abs() > MAX_COUNT {
                    return Err(CheckpointError::implausible(
                        key,
                        i,
                        format!("a count or index of at most {MAX_COUNT}"),
                    ));
                }
            } else {
                let v = n.as_f64().unwrap_or(f64::NAN);
                if !(v.is_finite() && v.abs() <= MAX_MAGNITUDE) {
                    return Err(CheckpointError::implausible(
                        key,
                        crate::number_for_message(v),
                        format!("a finite number within ±{MAX_MAGNITUDE:e}"),
                    ));
                }
            }
            Ok(())
        }
        Value::Array(a) => a
            .iter()
            .enumerate()
            .try_for_each(|(i, v)| check_numbers(&format!("{key}[{i}]"), v)),
        Value::Object(o) => o.iter().try_for_each(|(k, v)| check_numbers(&join(k), v)),
        _ => Ok(()),
    }
}

/// A number of the state's JSON at `path` (keys), when it is one.
fn number_at(v: &serde_json::Value, path: &[&str]) -> Option<f64> {
    path.iter().try_fold(v, |v, k| v.get(k))?.as_f64()
}

/// The storms of a run state: days within the season (up to `latest`) and a snowfall
/// period's reach past it, a few of them (those since the last melt window), each laid from
/// its start to at most its end.
fn validate_storms(
    storms: &[super::snowpack::StormSpan],
    latest: f64,
) -> Result<(), CheckpointError> {
    let storm_reach = latest + 365.0 * 2.0;
    if storms.len() > MAX_STORMS {
        return Err(CheckpointError::implausible(
            "storms",
            format!("{} storms", storms.len()),
            format!("at most {MAX_STORMS} since the last melt window"),
        ));
    }
    for (k, s) in storms.iter().enumerate() {
        for (field, d) in [
            ("since", s.since),
            ("until", s.until),
            ("delivered_to", s.delivered_to),
        ] {
            if !(d >= 0.0 && d <= storm_reach) {
                return Err(CheckpointError::implausible(
                    format!("storms[{k}].{field}"),
                    d,
                    "a day within the season",
                ));
            }
        }
        if !(s.since <= s.delivered_to && s.delivered_to <= s.until) {
            return Err(CheckpointError::implausible(
                format!("storms[{k}]"),
                format!("{} .. {} laid to {}", s.since, s.until, s.delivered_to),
                "a period laid from its start to at most its end",
            ));
        }
    }
    Ok(())
}

/// The latest day a checkpoint's clocks may show: the season, plus the reach of one event past
/// its end (the last draw comes at most 1 / (the always-active rates) after a time inside the
/// season) and a day for the clock an avalanche or a skier run advances.
fn latest_day(scenario: &Scenario) -> f64 {
    let e = &scenario.events;
    let steady =
        e.melt_and_state.max(0.0) + e.powder_diffusion.max(0.0) + e.wind_transport.max(0.0);
    let reach = if steady > 0.0 {
        1.0 / steady
    } else {
        crate::scenario::MAX_SEASON_DAYS
    };
    scenario.days + reach + 1.0
}

/// A clock `v` (days) at `field` finite and within the season up to `latest`.
fn check_day(field: &str, v: f64, latest: f64) -> Result<(), CheckpointError> {
    if v.is_finite() && (0.0..=latest).contains(&v) {
        Ok(())
    } else {
        Err(CheckpointError::implausible(
            field,
            crate::number_for_message(v),
            format!("a day of the season, within [0, {latest}]"),
        ))
    }
}

/// Validates a decoded run state against the scenario and terrain it resumes (module docs).
fn validate_state(
    state: &RunState,
    scenario: &Scenario,
    terrain: &LayeredTerrain,
) -> Result<(), CheckpointError> {
    let json = serde_json::to_value(state)?;
    check_numbers("", &json)?;
    let latest = latest_day(scenario);
    validate_clocks(state, &json, latest)?;
    validate_storms(&state.storms, latest)?;
    validate_scheduler(&json, scenario)?;
    validate_counters(state, scenario)?;
    validate_terrain(state, terrain, latest)
}

/// The clocks of a run state: the scheduler's, the melt's and the shedding's days within the
/// season (up to `latest`), the snowfall period's end at most two years past it.
fn validate_clocks(
    state: &RunState,
    json: &serde_json::Value,
    latest: f64,
) -> Result<(), CheckpointError> {
    check_day("scheduler.time_days", state.scheduler.time_days(), latest)?;
    check_day("melt_clock_days", state.melt_clock_days, latest)?;
    if let Some(d) = state.shed_clock_days {
        check_day("shed_clock_days", d, latest)?;
    }
    if let Some(d) = number_at(json, &["scheduler", "snowfall_until"]) {
        // A snowfall period may outlast the season; not the clock's reach by a year.
        if !(d >= 0.0 && d <= latest + 365.0 * 2.0) {
            return Err(CheckpointError::implausible(
                "scheduler.snowfall_until",
                crate::number_for_message(d),
                "a day within the season",
            ));
        }
    }
    Ok(())
}

/// The scheduler's draws: a mean snowfall period within a year, the scenario's seed, and the
/// steady kinds at the scenario's frequencies, none negative.
fn validate_scheduler(
    json: &serde_json::Value,
    scenario: &Scenario,
) -> Result<(), CheckpointError> {
    match number_at(json, &["scheduler", "snowfall_mean_days"]) {
        Some(d) if d > 0.0 && d <= 365.0 => {}
        d => {
            return Err(CheckpointError::implausible(
                "scheduler.snowfall_mean_days",
                d.map_or("(none)".into(), crate::number_for_message),
                "a mean snowfall period within (0, 365] days",
            ));
        }
    }
    if json["scheduler"]["seed"].as_u64() != Some(scenario.seed) {
        return Err(CheckpointError::implausible(
            "scheduler.seed",
            &json["scheduler"]["seed"],
            format!("the scenario's seed {}", scenario.seed),
        ));
    }
    let e = &scenario.events;
    let rates = json["scheduler"]["rates"].as_array().map_or(&[][..], |a| a);
    if rates.len() > 16 {
        return Err(CheckpointError::implausible(
            "scheduler.rates",
            format!("{} rates", rates.len()),
            "one per event kind",
        ));
    }
    for (k, r) in rates.iter().enumerate() {
        let per_day = r["per_day"].as_f64().unwrap_or(f64::NAN);
        if per_day.is_nan() || per_day < 0.0 {
            return Err(CheckpointError::implausible(
                format!("scheduler.rates[{k}].per_day"),
                crate::number_for_message(per_day),
                "a rate >= 0 per day",
            ));
        }
        let want = match r["kind"].as_str() {
            Some("melt_and_state_step" | "MeltAndStateStep") => Some(e.melt_and_state),
            Some("powder_diffusion_step" | "PowderDiffusionStep") => Some(e.powder_diffusion),
            Some("wind_transport_step" | "WindTransportStep") => Some(e.wind_transport),
            _ => None,
        };
        if let Some(want) = want
            && per_day != want.max(0.0)
        {
            return Err(CheckpointError::implausible(
                format!("scheduler.rates[{k}].per_day"),
                crate::number_for_message(per_day),
                format!("the scenario's {} per day", want.max(0.0)),
            ));
        }
    }
    Ok(())
}

/// The counters of a run state: the drawn kinds counted once a draw at most, skier runs
/// finished at most those started, and the timeline's indices within the scenario's tables
/// (the weather's is checked against the resolved timeline).
fn validate_counters(state: &RunState, scenario: &Scenario) -> Result<(), CheckpointError> {
    let draws = state.scheduler.draws();
    let drawn: u64 = state
        .event_counts
        .iter()
        .filter(|(k, _)| {
            matches!(
                k,
                EventKind::SnowfallStart
                    | EventKind::SnowfallStep
                    | EventKind::MeltAndStateStep
                    | EventKind::PowderDiffusionStep
                    | EventKind::WindTransportStep
            )
        })
        .map(|(_, &n)| n)
        .sum();
    if drawn > draws {
        return Err(CheckpointError::implausible(
            "event_counts",
            format!("{drawn} drawn events"),
            format!("at most the scheduler's {draws} draws"),
        ));
    }
    if state.ski.finished > state.ski.runs {
        return Err(CheckpointError::implausible(
            "ski.finished",
            state.ski.finished,
            format!("at most the {} runs started", state.ski.runs),
        ));
    }
    for (field, index, len) in [
        (
            "forced_index",
            state.forced_index,
            scenario.snowfall_periods.len(),
        ),
        (
            "user_avalanche_index",
            state.user_avalanche_index,
            scenario.avalanches.len(),
        ),
    ] {
        if index > len {
            return Err(CheckpointError::implausible(
                field,
                index,
                format!("an index within the scenario's {len} entries"),
            ));
        }
    }
    Ok(())
}

/// The terrain of a run state: the summary the fingerprint was taken with, and every avalanche
/// on the grid and on a day of the season (up to `latest`).
fn validate_terrain(
    state: &RunState,
    terrain: &LayeredTerrain,
    latest: f64,
) -> Result<(), CheckpointError> {
    let g = terrain.geometry();
    let summary = terrain_summary(terrain);
    if state.terrain != summary {
        return Err(CheckpointError::implausible(
            "terrain",
            &state.terrain,
            format!("this terrain's `{summary}`"),
        ));
    }
    for (k, a) in state.avalanches.iter().enumerate() {
        if a.cell[0] >= g.width() || a.cell[1] >= g.height() {
            return Err(CheckpointError::implausible(
                format!("avalanches[{k}].cell"),
                format!("{:?}", a.cell),
                format!("a cell of the {}x{} grid", g.width(), g.height()),
            ));
        }
        check_day(&format!("avalanches[{k}].day"), a.day, latest)?;
    }
    Ok(())
}

/// Every snow layer finite and ≥ 0 (0 off the terrain's valid cells, as
/// [`LayeredTerrain::check_invariants`] wants), every other map finite on the valid cells.
fn validate_maps(
    terrain: &LayeredTerrain,
    layers: &[Vec<f32>; 4],
    extra: &[Vec<f32>],
) -> Result<(), CheckpointError> {
    let valid = |i: usize| terrain.mask().is_valid(i);
    const EXTRA_NAMES: [&str; EXTRA_MAPS] = [
        "scour",
        "deposit",
        "surface_age",
        "cold_content",
        "liquid_water",
        "melting",
        "pending_rain",
    ];
    for (k, layer) in layers.iter().enumerate() {
        let ok = |(i, v): (usize, &f32)| v.is_finite() && *v >= 0.0 && (valid(i) || *v == 0.0);
        if let Some(i) = layer.iter().enumerate().position(|c| !ok(c)) {
            return Err(CheckpointError::implausible(
                format!("layer {k} cell {i}"),
                layer[i],
                "a finite snow thickness >= 0 m (0 off the terrain)",
            ));
        }
    }
    for (k, map) in extra.iter().enumerate() {
        if let Some(i) = map
            .iter()
            .enumerate()
            .position(|(i, v)| valid(i) && !v.is_finite())
        {
            return Err(CheckpointError::implausible(
                format!("{} cell {i}", EXTRA_NAMES.get(k).unwrap_or(&"map")),
                map[i],
                "a finite number",
            ));
        }
    }
    Ok(())
}

/// Size and cell size of a terrain, for messages.
pub(super) fn terrain_summary(terrain: &LayeredTerrain) -> String {
    let g = terrain.geometry();
    format!(
        "{}x{} cells of {} x {} m",
        g.width(),
        g.height(),
        g.cell_size_x(),
        g.cell_size_y()
    )
}

/// The first key (dotted path) whose value differs between two JSON documents, with both
/// values; `None` when they are equal.
fn first_difference(
    key: &str,
    old: &serde_json::Value,
    new: &serde_json::Value,
) -> Option<(String, String, String)> {
    use serde_json::Value;
    let path = |k: &str| {
        if key.is_empty() {
            k.to_string()
        } else {
            format!("{key}.{k}")
        }
    };
    match (old, new) {
        (Value::Object(a), Value::Object(b)) => {
            let keys: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
            keys.into_iter().find_map(|k| {
                let null = Value::Null;
                first_difference(
                    &path(k),
                    a.get(k).unwrap_or(&null),
                    b.get(k).unwrap_or(&null),
                )
            })
        }
        (Value::Array(a), Value::Array(b)) if a.len() == b.len() => a
            .iter()
            .zip(b)
            .enumerate()
            .find_map(|(i, (x, y))| first_difference(&format!("{key}[{i}]"), x, y)),
        _ if old == new => None,
        _ => Some((key.to_string(), short(old), short(new))),
    }
}

/// A value for a message, at most 80 characters.
fn short(v: &serde_json::Value) -> String {
    let mut s = match v {
        serde_json::Value::Null => "(unset)".to_string(),
        v => v.to_string(),
    };
    if s.len() > 80 {
        let cut = (0..=77).rev().find(|&i| s.is_char_boundary(i)).unwrap_or(0);
        s.truncate(cut);
        s.push_str("...");
    }
    s
}

impl Winter {
    /// Writes a checkpoint of the whole run state to `w`.
    pub fn write_checkpoint(&self, w: &mut impl std::io::Write) -> Result<(), SeasonError> {
        let m = &self.avalanche_maps;
        let [age, cold, liquid, melting] = self.pack.arrays();
        checkpoint::write(
            w,
            &self.state,
            &self.terrain,
            &[
                &m.scour,
                &m.deposit,
                age,
                cold,
                liquid,
                melting,
                &self.pending_rain,
            ],
        )?;
        Ok(())
    }

    /// Restores a run from a checkpoint written by a run of the same scenario on the same
    /// terrain (anything else is refused).
    pub fn resume(
        scenario: Scenario,
        terrain: LayeredTerrain,
        r: &mut impl std::io::Read,
    ) -> Result<Self, SeasonError> {
        Self::resume_with_forcing(scenario, terrain, None, r)
    }

    /// [`Winter::resume`] for a season driven by station forcing (the same record).
    pub fn resume_with_forcing(
        scenario: Scenario,
        terrain: LayeredTerrain,
        forcing: Option<StationForcing>,
        r: &mut impl std::io::Read,
    ) -> Result<Self, SeasonError> {
        let saved = checkpoint::read::<RunState>(r, terrain.geometry().len(), EXTRA_MAPS)?;
        Self::resume_from(scenario, terrain, forcing, saved)
    }

    /// [`Winter::resume_with_forcing`] from the checkpoint file at `path`: only a regular file
    /// of at most the terrain's largest checkpoint is read ([`checkpoint::read_file`]).
    pub fn resume_from_file(
        scenario: Scenario,
        terrain: LayeredTerrain,
        forcing: Option<StationForcing>,
        path: &std::path::Path,
    ) -> Result<Self, SeasonError> {
        let saved = checkpoint::read_file::<RunState>(path, terrain.geometry().len(), EXTRA_MAPS)?;
        Self::resume_from(scenario, terrain, forcing, saved)
    }

    fn resume_from(
        scenario: Scenario,
        terrain: LayeredTerrain,
        forcing: Option<StationForcing>,
        mut saved: checkpoint::Contents<RunState>,
    ) -> Result<Self, SeasonError> {
        if saved.header.fingerprint != bedrock_fingerprint(&terrain) {
            let now = terrain_summary(&terrain);
            let now = if now == saved.header.terrain {
                format!("{now}, with other altitudes")
            } else {
                now
            };
            return Err(SeasonError::CheckpointTerrain {
                checkpoint: crate::clip_for_message(&saved.header.terrain),
                now,
            });
        }
        let now = serde_json::to_value(&scenario).unwrap_or_default();
        if let Some((key, checkpoint, now)) = first_difference("", &saved.header.scenario, &now) {
            return Err(SeasonError::CheckpointScenario {
                key,
                checkpoint,
                now,
            });
        }
        validate_state(&saved.header, &scenario, &terrain)?;
        validate_maps(&terrain, &saved.layers, &saved.extra)?;
        let mut w = Self::with_forcing(scenario, terrain, forcing)?;
        if saved.header.scenario_digest != w.state.scenario_digest {
            return Err(SeasonError::CheckpointForcing);
        }
        if saved.header.weather_index >= w.weather.len() {
            return Err(CheckpointError::implausible(
                "weather_index",
                saved.header.weather_index,
                format!("an index within the {} weather periods", w.weather.len()),
            )
            .into());
        }
        saved.restore_layers(&mut w.terrain);
        let mut extra = std::mem::take(&mut saved.extra);
        w.pending_rain = extra.pop().unwrap_or_default();
        let pack = extra.split_off(2);
        w.pack = SnowpackState::from_arrays(pack);
        w.avalanche_maps.deposit = extra.pop().unwrap_or_default();
        w.avalanche_maps.scour = extra.pop().unwrap_or_default();
        let state = saved.header;
        let weather_changed = state.weather_index != 0;
        w.state = state;
        if weather_changed {
            w.refresh_weather_maps()?;
        }
        w.refresh_air_temperature();
        // The hazard map of the restored snow (for `avalanche_hazard`; a start recomputes it);
        // the scheduler's rate is the checkpointed one.
        w.hazard.compute(
            &w.scenario.parameters.avalanche,
            &w.terrain,
            &w.slope_deg,
            &HazardSources::default(),
        );
        w.hazard_stale = true;
        Ok(w)
    }

    /// Sets this season to the state of a checkpoint written by it or by a fork of it (the
    /// same scenario and weather on the same terrain) as [`Winter::resume`] restores it, but
    /// without the environment precompute: this season's is kept (the weather period's maps
    /// are refreshed when the checkpoint's period is another). What a checkpoint does not
    /// hold is left as a resume leaves it (no ski area, no painted release rates). The
    /// editor's timeline keeps its snapshots as checkpoints and restores them so.
    pub fn restore_checkpoint(&mut self, r: &mut impl std::io::Read) -> Result<(), SeasonError> {
        let mut saved = checkpoint::read::<RunState>(r, self.terrain.geometry().len(), EXTRA_MAPS)?;
        if saved.header.fingerprint != bedrock_fingerprint(&self.terrain) {
            return Err(SeasonError::CheckpointTerrain {
                checkpoint: saved.header.terrain.clone(),
                now: terrain_summary(&self.terrain),
            });
        }
        if saved.header.scenario_digest != self.state.scenario_digest {
            let now = serde_json::to_value(&self.scenario).unwrap_or_default();
            return Err(match first_difference("", &saved.header.scenario, &now) {
                Some((key, checkpoint, now)) => SeasonError::CheckpointScenario {
                    key,
                    checkpoint,
                    now,
                },
                None => SeasonError::CheckpointForcing,
            });
        }
        let period_changed = saved.header.weather_index != self.state.weather_index;
        saved.restore_layers(&mut self.terrain);
        let mut extra = std::mem::take(&mut saved.extra);
        self.pending_rain = extra.pop().unwrap_or_default();
        let pack = extra.split_off(2);
        self.pack = SnowpackState::from_arrays(pack);
        self.avalanche_maps.deposit = extra.pop().unwrap_or_default();
        self.avalanche_maps.scour = extra.pop().unwrap_or_default();
        self.state = saved.header;
        self.ski_area = None;
        self.painted_release = None;
        self.terminus_stale = false;
        if period_changed {
            self.refresh_weather_maps()?;
        }
        self.refresh_air_temperature();
        self.hazard.compute(
            &self.scenario.parameters.avalanche,
            &self.terrain,
            &self.slope_deg,
            &HazardSources::default(),
        );
        self.hazard_stale = true;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::first_difference;
    use serde_json::json;

    #[test]
    fn the_first_changed_key_is_named_with_both_values() {
        let a = json!({"days": 100.0, "parameters": {"melt": {"k_melt": 0.01}}, "weather": [1, 2]});
        let b = json!({"days": 100.0, "parameters": {"melt": {"k_melt": 0.02}}, "weather": [1, 2]});
        assert_eq!(
            first_difference("", &a, &b),
            Some((
                "parameters.melt.k_melt".into(),
                "0.01".into(),
                "0.02".into()
            ))
        );
        assert_eq!(first_difference("", &a, &a), None);
        let c = json!({"days": 60.0, "parameters": {"melt": {"k_melt": 0.01}}, "weather": [1, 2]});
        assert_eq!(
            first_difference("", &a, &c).map(|d| d.0),
            Some("days".into())
        );
    }
}
