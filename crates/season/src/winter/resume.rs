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
//! snow layers finite and ≥ 0, the painted release rates finite and ≥ 0 and the other maps
//! finite, and the ski area as [`SkiArea::restore`] checks it (tile indices within the
//! texture, texels in [0, 1], skiers and track cells on the grid, ids below the next id) with
//! its seed and termini rule the scenario's and its clock within the season. A refusal is a
//! [`CheckpointError::Implausible`] naming the field and the value.
//!
//! Besides the run state, a checkpoint holds the painted release rates (a map, and whether
//! there is paint) and the ski area (its scalars in the header, three maps, the tracks and
//! the texture's tiles in sections of their own), so a resumed season with skiers and paint
//! ends bit-identical to an uninterrupted one.

use super::{RunState, SeasonError, SnowpackState, Winter};
use crate::checkpoint::{self, CheckpointError, bedrock_fingerprint};
use crate::forcing::StationForcing;
use crate::scenario::Scenario;
use crate::scheduler::{EventKind, SECONDS_PER_DAY};
use serde::{Deserialize, Serialize};
use snowscape_skiers::{SkiArea, SkiAreaHeader, SkiAreaMaps, SkiError, SkiTracks, TrackTexture};
use snowscape_terrain::LayeredTerrain;

/// Extra per-cell maps after the four layers: scour, deposit, the pack's four arrays, rain,
/// the painted release rates, and the ski area's distance to the terminus, recent-skier count
/// and time (zeros where there is no paint or no ski area).
const EXTRA_MAPS: usize = 11;

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
        "painted_release",
        "ski distance",
        "recent skiers",
        "recent skier time",
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
    // The ski area's maps are validated with the area ([`SkiArea::restore`]).
    for (k, map) in extra.iter().enumerate().take(PAINT) {
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
    let paint = extra.get(PAINT).map_or(&[][..], |m| m);
    if let Some(i) = paint.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
        return Err(CheckpointError::implausible(
            format!("painted_release cell {i}"),
            paint[i],
            "a finite release rate >= 0 per day",
        ));
    }
    Ok(())
}

/// Index of the painted release rates among the extra maps.
const PAINT: usize = 7;

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

/// The header a checkpoint file holds: the run state and what says which of the ski area's
/// and the paint's sections hold something.
#[derive(Serialize)]
struct SavedRef<'a> {
    #[serde(flatten)]
    run: &'a RunState,
    /// The ski area's scalars (`None`: no skier has come).
    ski_area: Option<SkiAreaHeader>,
    /// Whether painted release rates are set (the map is written either way).
    painted: bool,
}

/// [`SavedRef`], read back.
#[derive(Deserialize)]
struct Saved {
    #[serde(flatten)]
    run: RunState,
    ski_area: Option<SkiAreaHeader>,
    painted: bool,
}

/// What bounds a checkpoint of `scenario` on `terrain`: its cells, the extra maps, the tiles
/// of the track texture at the scenario's resolution.
fn bounds(scenario: &Scenario, terrain: &LayeredTerrain) -> checkpoint::Bounds {
    let g = terrain.geometry();
    checkpoint::Bounds {
        cells: g.len(),
        extra: EXTRA_MAPS,
        tiles: TrackTexture::tile_count(g.width(), g.height(), scenario.skiers.ski.texels_per_cell),
    }
}

/// A refusal of the ski area's values as a checkpoint's.
fn ski_refusal(e: SkiError) -> CheckpointError {
    match e {
        SkiError::Implausible {
            field,
            value,
            expected,
        } => CheckpointError::implausible(field, value, expected),
        e => CheckpointError::implausible("ski_area", e, "a ski area of this scenario"),
    }
}

/// The ski area of a checkpoint (`None` when no skier had come), validated against the
/// scenario and the season's clock (`latest`, days).
fn restore_ski_area(
    header: Option<SkiAreaHeader>,
    maps: SkiAreaMaps,
    tracks: &[u8],
    tiles: Vec<(usize, Vec<f32>)>,
    scenario: &Scenario,
    terrain: &LayeredTerrain,
) -> Result<Option<SkiArea>, CheckpointError> {
    let Some(header) = header else {
        if !tracks.is_empty() || !tiles.is_empty() {
            return Err(CheckpointError::implausible(
                "ski tracks",
                format!("{} bytes and {} tiles", tracks.len(), tiles.len()),
                "none without a ski area",
            ));
        }
        return Ok(None);
    };
    if header.seed != scenario.seed {
        return Err(CheckpointError::implausible(
            "ski_area.seed",
            header.seed,
            format!("the scenario's seed {}", scenario.seed),
        ));
    }
    if header.rule != scenario.skiers.terminus {
        return Err(CheckpointError::implausible(
            "ski_area.rule",
            format!("{:?}", header.rule),
            format!("the scenario's terminus {:?}", scenario.skiers.terminus),
        ));
    }
    let latest_s = latest_day(scenario) * SECONDS_PER_DAY;
    // NaN and negative times are refused with the area's other values.
    if header.time_s > latest_s {
        return Err(CheckpointError::implausible(
            "ski_area.time_s",
            header.time_s,
            format!("a time within the season's {latest_s} s"),
        ));
    }
    if header.sweeps as u64 > MAX_COUNT {
        return Err(CheckpointError::implausible(
            "ski_area.sweeps",
            header.sweeps,
            format!("at most {MAX_COUNT} sweeps"),
        ));
    }
    let tracks: SkiTracks = serde_json::from_slice(tracks).map_err(|e| {
        CheckpointError::implausible("ski tracks", e, "the JSON of the skiers and their tracks")
    })?;
    SkiArea::restore(
        &scenario.skiers.ski,
        terrain.geometry().clone(),
        header,
        maps,
        tracks,
        tiles,
    )
    .map(Some)
    .map_err(ski_refusal)
}

impl Winter {
    /// Writes a checkpoint of the whole run state to `w`: the snow, the pack, the maps, the
    /// painted release rates and the ski area with its tracks.
    pub fn write_checkpoint(&self, w: &mut impl std::io::Write) -> Result<(), SeasonError> {
        let m = &self.state.avalanche_maps;
        let [age, cold, liquid, melting] = self.state.pack.arrays();
        let n = self.terrain.geometry().len();
        let zeros = vec![0.0f32; n];
        let paint = self.state.painted_release.as_deref().unwrap_or(&zeros);
        let area = self.state.ski_area.as_ref();
        let [distance, recent_value, recent_time] = area.map_or([&zeros[..]; 3], |a| a.maps());
        let tracks = match area {
            Some(a) => a.tracks_json().map_err(CheckpointError::Header)?,
            None => Vec::new(),
        };
        let tiles: Vec<(usize, &[f32])> =
            area.map_or_else(Vec::new, |a| a.texture().allocated().collect());
        let header = SavedRef {
            run: &self.state.run,
            ski_area: area.map(SkiArea::header),
            painted: self.state.painted_release.is_some(),
        };
        let extra: [&[f32]; EXTRA_MAPS] = [
            &m.scour,
            &m.deposit,
            age,
            cold,
            liquid,
            melting,
            &self.state.pending_rain,
            paint,
            distance,
            recent_value,
            recent_time,
        ];
        let payload = checkpoint::Payload {
            extra: &extra,
            tracks: &tracks,
            tiles: &tiles,
        };
        checkpoint::write(w, &header, &self.terrain, payload)?;
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
        let saved = checkpoint::read::<Saved>(r, bounds(&scenario, &terrain))?;
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
        let saved = checkpoint::read_file::<Saved>(path, bounds(&scenario, &terrain))?;
        Self::resume_from(scenario, terrain, forcing, saved)
    }

    fn resume_from(
        scenario: Scenario,
        terrain: LayeredTerrain,
        forcing: Option<StationForcing>,
        saved: checkpoint::Contents<Saved>,
    ) -> Result<Self, SeasonError> {
        let run = &saved.header.run;
        if run.fingerprint != bedrock_fingerprint(&terrain) {
            let now = terrain_summary(&terrain);
            let now = if now == run.terrain {
                format!("{now}, with other altitudes")
            } else {
                now
            };
            return Err(SeasonError::CheckpointTerrain {
                checkpoint: crate::clip_for_message(&run.terrain),
                now,
            });
        }
        let now = serde_json::to_value(&scenario).unwrap_or_default();
        if let Some((key, checkpoint, now)) = first_difference("", &run.scenario, &now) {
            return Err(SeasonError::CheckpointScenario {
                key,
                checkpoint,
                now,
            });
        }
        validate_state(run, &scenario, &terrain)?;
        validate_maps(&terrain, &saved.layers, &saved.extra)?;
        let mut w = Self::with_forcing(scenario, terrain, forcing)?;
        if saved.header.run.scenario_digest != w.state.run.scenario_digest {
            return Err(SeasonError::CheckpointForcing);
        }
        if saved.header.run.weather_index >= w.weather.len() {
            return Err(CheckpointError::implausible(
                "weather_index",
                saved.header.run.weather_index,
                format!("an index within the {} weather periods", w.weather.len()),
            )
            .into());
        }
        w.restore_saved(saved)?;
        Ok(w)
    }

    /// Sets the season's state to a checkpoint's (checked against this season's terrain and
    /// scenario): the snow, the maps, the run state, the paint and the ski area; then the
    /// weather period's maps when the period is another, the air temperature and the hazard.
    fn restore_saved(&mut self, saved: checkpoint::Contents<Saved>) -> Result<(), SeasonError> {
        let checkpoint::Contents {
            header,
            layers,
            extra,
            tracks,
            tiles,
        } = saved;
        let mut extra = extra.into_iter();
        let mut next = || extra.next().unwrap_or_default();
        let (scour, deposit) = (next(), next());
        let pack = vec![next(), next(), next(), next()];
        let pending_rain = next();
        let paint = next();
        let ski_maps = SkiAreaMaps {
            distance: next(),
            recent_value: next(),
            recent_time: next(),
        };
        let Saved {
            run,
            ski_area,
            painted,
        } = header;
        let ski_area = restore_ski_area(
            ski_area,
            ski_maps,
            &tracks,
            tiles,
            &self.scenario,
            &self.terrain,
        )?;
        let period_changed = run.weather_index != self.state.run.weather_index;
        for (layer, saved) in self.terrain.snow.iter_mut().zip(layers) {
            *layer = saved;
        }
        self.state.avalanche_maps.scour = scour;
        self.state.avalanche_maps.deposit = deposit;
        self.state.pack = SnowpackState::from_arrays(pack);
        self.state.pending_rain = pending_rain;
        self.state.painted_release = painted.then_some(paint);
        self.state.ski_area = ski_area;
        self.state.run = run;
        if period_changed {
            self.refresh_weather_maps()?;
        }
        self.refresh_air_temperature();
        // The hazard map of the restored snow (for `avalanche_hazard`); the scheduler's rate
        // is the checkpointed one, and the next start recomputes the map.
        self.ensure_workspace()?;
        self.recompute_hazard();
        Ok(())
    }

    /// Sets this season to the state of a checkpoint written by it or by a fork of it (the
    /// same scenario and weather on the same terrain) as [`Winter::resume`] restores it, but
    /// without the environment precompute: this season's is kept (the weather period's maps
    /// are refreshed when the checkpoint's period is another). The ski area and the painted
    /// release rates are the checkpoint's. The editor's timeline keeps its snapshots as
    /// checkpoints and restores them so.
    pub fn restore_checkpoint(&mut self, r: &mut impl std::io::Read) -> Result<(), SeasonError> {
        let saved = checkpoint::read::<Saved>(r, bounds(&self.scenario, &self.terrain))?;
        let run = &saved.header.run;
        if run.fingerprint != bedrock_fingerprint(&self.terrain) {
            return Err(SeasonError::CheckpointTerrain {
                checkpoint: run.terrain.clone(),
                now: terrain_summary(&self.terrain),
            });
        }
        if run.scenario_digest != self.state.run.scenario_digest {
            let now = serde_json::to_value(&self.scenario).unwrap_or_default();
            return Err(match first_difference("", &run.scenario, &now) {
                Some((key, checkpoint, now)) => SeasonError::CheckpointScenario {
                    key,
                    checkpoint,
                    now,
                },
                None => SeasonError::CheckpointForcing,
            });
        }
        self.restore_saved(saved)
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
