//! A season run: the scenario's weather timeline, the environment precompute, the Poisson
//! scheduler and the Section 5 phenomena, stepped event by event (Cordonnier 2018, §3-5).
//!
//! The environment (sun, sky, bounce, temperature, wind) is computed on the bedrock, as the
//! paper does (§4.1: `A = B` "allows precomputation"): sun, sky and bounce once for the season's
//! dates, temperature and wind again at each weather change. The state that evolves — the snow
//! layers and the [`SeasonState`]: scheduler, budget, per-cell maps, paint, ski area — is plain
//! data, so a checkpoint captures a run exactly and a resumed run ends bit-identical to an
//! uninterrupted one. The scratch buffers and caches live in a workspace apart
//! ([`Winter::drop_workspace`]), rebuilt when dropped.

use crate::avalanches::{self, AvalancheMaps, AvalancheRecord, HazardSources, Trigger};
use crate::checkpoint::CheckpointError;
use crate::forcing::StationForcing;
use crate::melt::SnowpackState;
use crate::phenomenon::PhenomenonError;
use crate::scenario::{Scenario, WeatherPeriod, day_of_year};
use crate::scheduler::{Event, EventKind, SECONDS_PER_DAY, Scheduler};
use crate::skiing::SkiStats;
use crate::weather::Air;
use serde::{Deserialize, Serialize};
use snowscape_avalanche::AvalancheWorkspace;
use snowscape_avalanche::release_area::rupture_at_point;
use snowscape_environment::{EnvironmentError, EnvironmentMaps, EnvironmentParams, precompute};
use snowscape_skiers::SkiArea;
use snowscape_terrain::{LayeredTerrain, TerrainError};
use std::collections::BTreeMap;
use std::time::Instant;
use thiserror::Error;

/// Why a season could not run.
#[derive(Debug, Error)]
pub enum SeasonError {
    #[error("environment precompute: {0}")]
    Environment(#[from] EnvironmentError),
    /// The terrain cannot carry a season (its cells are beyond what a terrain cell may be).
    #[error("terrain: {0}")]
    Terrain(#[source] TerrainError),
    #[error("{phenomenon} at day {day:.3}: {source}")]
    Phenomenon {
        phenomenon: &'static str,
        day: f64,
        #[source]
        source: PhenomenonError,
    },
    #[error("invariant broken after {phenomenon} at day {day:.3}: {source}")]
    Invariant {
        phenomenon: &'static str,
        day: f64,
        #[source]
        source: TerrainError,
    },
    #[error("avalanche at day {day:.3}: {source}")]
    Avalanche {
        day: f64,
        #[source]
        source: snowscape_avalanche::AvalancheError,
    },
    #[error("skier at day {day:.3}: {reason}")]
    Skier { day: f64, reason: String },
    #[error("avalanche at map position ({x}, {y}): {reason}")]
    AvalanchePosition { x: f64, y: f64, reason: String },
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    #[error(
        "the checkpoint was written on another terrain ({checkpoint}); this run's terrain is {now}: resume with the same --dem and reader options"
    )]
    CheckpointTerrain { checkpoint: String, now: String },
    #[error(
        "the checkpoint was written with {key} = {checkpoint}; this run has {key} = {now}: resume with the same scenario and options (or start again)"
    )]
    CheckpointScenario {
        key: String,
        checkpoint: String,
        now: String,
    },
    #[error(
        "the checkpoint was written with another weather timeline or station forcing record: resume with the same --forcing file"
    )]
    CheckpointForcing,
}

mod budget;
mod phenomena;
use phenomena::PHENOMENA;
mod resume;
mod setup;
mod skier_runs;
mod snowpack;
mod workspace;

pub use budget::{SeasonBudget, WaterBudget};

/// The evolving state, checkpointed as the header of a checkpoint file.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct RunState {
    scheduler: Scheduler,
    budget: SeasonBudget,
    event_counts: BTreeMap<EventKind, u64>,
    weather_index: usize,
    forced_index: usize,
    fingerprint: u64,
    scenario_digest: u64,
    /// The resolved scenario, to name what changed when a resume is refused.
    scenario: serde_json::Value,
    /// The terrain's size and cell size, for the same purpose.
    terrain: String,
    /// Every avalanche so far.
    avalanches: Vec<AvalancheRecord>,
    /// Next scenario avalanche to trigger.
    user_avalanche_index: usize,
    /// What the skiers did.
    ski: SkiStats,
    /// End of the last melt window, days (the next window starts here).
    #[serde(default)]
    melt_clock_days: f64,
    /// Day of the last slope-shedding step (none yet: `None`).
    #[serde(default)]
    shed_clock_days: Option<f64>,
    /// The snowfall periods the next melt window may reach, and the running one.
    #[serde(default)]
    storms: Vec<snowpack::StormSpan>,
    /// Precipitation and peak SWE per altitude band.
    #[serde(default)]
    bands: crate::bands::BandRecord,
    /// Whether snowfall or melt changed the snow since the ski area's distance map was
    /// computed (the next skier refreshes it).
    #[serde(default)]
    terminus_stale: bool,
}

/// Everything a checkpoint holds besides the terrain's snow layers, as plain data: the run
/// state (scheduler, budget, counters, clocks, avalanche records), the snowpack's and the
/// avalanches' per-cell maps, the rain to melt, the painted release rates and the ski area.
/// The rest of a [`Winter`] is its scenario and inputs, the environment precompute and the
/// workspace of scratch buffers and caches ([`Winter::drop_workspace`]).
#[derive(Debug, Clone)]
pub struct SeasonState {
    run: RunState,
    /// Surface age, cold content and liquid water per cell.
    pack: SnowpackState,
    /// Rain since the last melt window, m of water per cell.
    pending_rain: Vec<f32>,
    /// Snow the season's avalanches scoured and deposited, per cell.
    avalanche_maps: AvalancheMaps,
    /// Painted release rates, 1/day per cell ([`Winter::set_painted_release`]).
    painted_release: Option<Vec<f32>>,
    /// The ski area, made at the first skier (see [`crate::skiing`]).
    ski_area: Option<SkiArea>,
}

impl SeasonState {
    /// Simulated time, days since the season start.
    pub fn day(&self) -> f64 {
        self.run.scheduler.time_days()
    }
    /// The snow budget so far.
    pub fn budget(&self) -> &SeasonBudget {
        &self.run.budget
    }
    /// Every avalanche of the season so far, in order.
    pub fn avalanches(&self) -> &[AvalancheRecord] {
        &self.run.avalanches
    }
    /// The snowpack's surface state.
    pub fn snowpack(&self) -> &SnowpackState {
        &self.pack
    }
    /// Rain since the last melt window, m of water per cell.
    pub fn pending_rain(&self) -> &[f32] {
        &self.pending_rain
    }
    /// Snow the season's avalanches scoured and deposited so far, per cell, m.
    pub fn avalanche_maps(&self) -> &AvalancheMaps {
        &self.avalanche_maps
    }
    /// The painted release rates, 1/day per cell (`None`: no paint).
    pub fn painted_release(&self) -> Option<&[f32]> {
        self.painted_release.as_deref()
    }
    /// The ski area, once a skier has come.
    pub fn ski_area(&self) -> Option<&SkiArea> {
        self.ski_area.as_ref()
    }
}

/// Where the season's latitude came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LatitudeSource {
    /// The scenario's `latitude_deg` (or the command line's `--latitude`).
    Scenario,
    /// The DEM's georeferencing.
    Georeferencing,
    /// Neither: the sun and the climatology run at the default latitude (a warning).
    Assumed,
}

/// A season in progress. Cloning it forks the run (the clone continues identically).
#[derive(Debug, Clone)]
pub struct Winter {
    scenario: Scenario,
    weather: Vec<WeatherPeriod>,
    /// The terrain and its snow layers.
    pub terrain: LayeredTerrain,
    /// What a checkpoint holds besides the snow layers.
    state: SeasonState,
    environment: EnvironmentMaps,
    base_environment: EnvironmentParams,
    /// Wall-clock seconds per phenomenon (not part of the state: it differs between runs).
    pub wall_seconds: BTreeMap<&'static str, f64>,
    /// Scratch buffers and caches, dropped and rebuilt at will ([`Winter::drop_workspace`]).
    workspace: workspace::SeasonWorkspace,
    avalanche_workspace: AvalancheWorkspace,
    /// The hourly air, sun and precipitation factors.
    air: Air,
    latitude_source: LatitudeSource,
    /// The altitude band of each cell.
    bands: crate::bands::Bands,
}

fn scenario_digest(
    s: &Scenario,
    weather: &[WeatherPeriod],
    forcing: Option<&StationForcing>,
) -> u64 {
    let text = serde_json::to_string(&(s, weather)).unwrap_or_default();
    let h = text.bytes().fold(0x243f_6a88_85a3_08d3, |h, b| {
        snowscape_terrain::random::mix64(h ^ b as u64)
    });
    forcing.map_or(h, |f| {
        f.records.iter().fold(h, |h, r| {
            let v =
                (r.air_temperature_c.to_bits() as u64) << 32 | r.precipitation_mm.to_bits() as u64;
            snowscape_terrain::random::mix64(h ^ v)
        })
    })
}

impl Winter {
    /// Prepares a season on `terrain`: resolves the weather timeline (the default winter when
    /// the scenario has none) and latitude, and precomputes the environment for day 0.
    pub fn new(scenario: Scenario, terrain: LayeredTerrain) -> Result<Self, SeasonError> {
        Self::with_forcing(scenario, terrain, None)
    }

    /// A season driven by a station's record (`forcing`): its hourly air temperature and
    /// precipitation, distributed over the terrain by the lapse rate and the orographic
    /// gradient from the station's altitude; season day 0 is the record's first hour.
    pub fn with_forcing(
        scenario: Scenario,
        terrain: LayeredTerrain,
        forcing: Option<StationForcing>,
    ) -> Result<Self, SeasonError> {
        terrain
            .geometry()
            .check_terrain_cells()
            .map_err(SeasonError::Terrain)?;
        let mut env = scenario.parameters.environment.clone();
        let (latitude, latitude_source) =
            setup::resolve_latitude(&scenario, &terrain, env.sun.latitude_deg);
        env.sun.latitude_deg = latitude;
        let weather = setup::resolve_weather(&scenario, &terrain, forcing.as_ref(), latitude);
        env.sun.start_day = day_of_year(&scenario.start_date).unwrap_or(env.sun.start_day);
        env.sun.num_days = (scenario.days.ceil() as u32).clamp(1, 365);
        let state = setup::initial_state(&scenario, &terrain, &weather, forcing.as_ref());
        let t = Instant::now();
        let params = weather_params(&env, &weather[0]);
        let environment = precompute(
            &terrain.bedrock,
            terrain.geometry(),
            terrain.mask(),
            &params,
        )?;
        let (season_sun, hourly_sun_s) =
            setup::hourly_sun(&scenario, &terrain, &env, &environment)?;
        let air = setup::season_air(
            &scenario, forcing, &weather, latitude, &env, &terrain, season_sun,
        );
        let mut w = Self::assemble(setup::SeasonStart {
            scenario,
            weather,
            terrain,
            state,
            environment,
            base_environment: env,
            air,
            latitude_source,
        });
        w.wall_seconds
            .insert("environment", t.elapsed().as_secs_f64());
        w.wall_seconds.insert("hourly_sun", hourly_sun_s);
        w.ready()?;
        Ok(w)
    }

    /// Everything a checkpoint holds besides the snow layers ([`SeasonState`]).
    pub fn state(&self) -> &SeasonState {
        &self.state
    }
    /// The scenario being run.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }
    /// The resolved weather timeline.
    pub fn weather(&self) -> &[WeatherPeriod] {
        &self.weather
    }
    /// The current environment maps.
    pub fn environment(&self) -> &EnvironmentMaps {
        &self.environment
    }
    /// Latitude the sun was computed for, degrees north.
    pub fn latitude_deg(&self) -> f64 {
        self.base_environment.sun.latitude_deg
    }
    /// Where the latitude came from ([`LatitudeSource::Assumed`] deserves a warning).
    pub fn latitude_source(&self) -> LatitudeSource {
        self.latitude_source
    }
    /// The snowpack's surface state (age, cold content, liquid water).
    pub fn snowpack(&self) -> &SnowpackState {
        &self.state.pack
    }
    /// The hourly weather of the season.
    pub fn air(&self) -> &Air {
        &self.air
    }
    /// Simulated time, days since the season start.
    pub fn day(&self) -> f64 {
        self.state.run.scheduler.time_days()
    }
    /// The snow budget so far.
    pub fn budget(&self) -> &SeasonBudget {
        &self.state.run.budget
    }
    /// Number of events of each kind so far.
    pub fn event_counts(&self) -> &BTreeMap<EventKind, u64> {
        &self.state.run.event_counts
    }
    /// Every avalanche of the season so far, in order.
    pub fn avalanches(&self) -> &[AvalancheRecord] {
        &self.state.run.avalanches
    }
    /// Snow thickness the season's avalanches scoured and deposited so far, per cell, m.
    pub fn avalanche_maps(&self) -> &AvalancheMaps {
        &self.state.avalanche_maps
    }
    /// The ski area (tracks, texture), once a skier has come.
    pub fn ski_area(&self) -> Option<&SkiArea> {
        self.state.ski_area.as_ref()
    }
    /// What the season's skiers did.
    pub fn ski_stats(&self) -> &SkiStats {
        &self.state.run.ski
    }
    /// The current avalanche hazard per cell, 1/day (Σ is the Avalanche-Start rate).
    pub fn avalanche_hazard(&self) -> &[f64] {
        &self.workspace.hazard.lambda
    }
    /// The season by 200 m altitude band so far: precipitation, rain share and peak SWE
    /// ([`crate::bands`]; the peak counts the snow now as well as the daily samples).
    pub fn altitude_bands(&self) -> Vec<crate::bands::BandSummary> {
        let mut record = self.state.run.bands.clone();
        record.raise_peaks(&self.band_mean_swe());
        self.bands.summary(&record)
    }
    /// Whether the season is over.
    pub fn finished(&self) -> bool {
        self.day() >= self.scenario.days
    }

    /// Runs events until the clock reaches `day` (or the season ends).
    pub fn run_until(&mut self, day: f64) -> Result<(), SeasonError> {
        self.run_until_unless(day, &std::sync::atomic::AtomicBool::new(false))
    }

    /// [`Winter::run_until`], stopping early (between two events, where a checkpoint is
    /// consistent) as soon as `stop` is set: how a front end honours Ctrl-C or a cancel.
    pub fn run_until_unless(
        &mut self,
        day: f64,
        stop: &std::sync::atomic::AtomicBool,
    ) -> Result<(), SeasonError> {
        let end = day.min(self.scenario.days);
        self.ensure_workspace()?;
        while self.day() < end && !stop.load(std::sync::atomic::Ordering::Relaxed) {
            self.apply_timeline()?;
            let Some(event) = self.state.run.scheduler.next_event() else {
                break;
            };
            self.apply(event)?;
        }
        Ok(())
    }

    /// Starts weather periods and forced snowfall periods whose day has come.
    fn apply_timeline(&mut self) -> Result<(), SeasonError> {
        let now = self.day();
        let next = self.state.run.weather_index + 1;
        if next < self.weather.len() && now >= self.weather[next].from_day {
            self.state.run.weather_index = next;
            let w = self.weather[next].clone();
            self.state.run.scheduler.set_rate(
                EventKind::SnowfallStart,
                w.snowfall_per_week / 7.0,
                true,
            );
            self.refresh_weather_maps()?;
        }
        while let Some(p) = self
            .scenario
            .snowfall_periods
            .get(self.state.run.forced_index)
        {
            if now < p.start_day {
                break;
            }
            let until = p.start_day + p.days;
            if until > now {
                self.state.run.scheduler.force_snowfall(p.start_day, until);
                self.follow_storms();
            }
            self.state.run.forced_index += 1;
        }
        while let Some(a) = self
            .scenario
            .avalanches
            .get(self.state.run.user_avalanche_index)
            .cloned()
        {
            if now < a.day {
                break;
            }
            self.state.run.user_avalanche_index += 1;
            match self.trigger_avalanche(a.x, a.y) {
                Ok(_) | Err(SeasonError::AvalanchePosition { .. }) => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }

    /// The recent-skier map the hazard reads, when skiers run.
    fn recent_skier_map(&self) -> Option<Vec<f32>> {
        self.state
            .ski_area
            .as_ref()
            .map(|a| a.recent_skiers(&self.scenario.skiers.ski))
    }

    /// Recomputes the avalanche hazard and the Avalanche-Start rate.
    fn update_avalanche_rate(&mut self) {
        let skiers = self.recent_skier_map();
        let sources = HazardSources {
            skiers: skiers.as_deref(),
            painted: self.state.painted_release.as_deref(),
        };
        let total = self.workspace.hazard.compute(
            &self.scenario.parameters.avalanche,
            &self.terrain,
            &self.workspace.slope_deg,
            &sources,
        );
        self.workspace.hazard_stale = false;
        self.state
            .run
            .scheduler
            .set_rate(EventKind::AvalancheStart, total, total > 0.0);
    }

    /// The painted release rate of `cell`, 1/day (0 without paint).
    pub(super) fn painted_rate(&self, cell: usize) -> f64 {
        self.state
            .painted_release
            .as_ref()
            .map_or(0.0, |p| f64::from(p[cell]))
    }

    /// Per-cell friction of the season's avalanches (μ and, under the Voellmy law, ξ;
    /// [`snowscape_avalanche::FrictionMaps::from_rasters`] matches rasters onto the grid):
    /// every later avalanche runs with it. Not checkpointed (a resumed season is given it
    /// again). An error names the mismatch: maps of another grid, or a ξ map under a law
    /// that reads none.
    pub fn set_friction_maps(
        &mut self,
        maps: snowscape_avalanche::FrictionMaps,
    ) -> Result<(), SeasonError> {
        maps.check_for(
            self.terrain.geometry(),
            &self.scenario.parameters.avalanche.flow,
        )
        .map_err(|source| SeasonError::Avalanche {
            day: self.day(),
            source,
        })?;
        self.avalanche_workspace.set_friction_maps(maps);
        Ok(())
    }

    /// The per-cell friction of the season's avalanches ([`Winter::set_friction_maps`]).
    pub fn friction_maps(&self) -> &snowscape_avalanche::FrictionMaps {
        self.avalanche_workspace.friction_maps()
    }

    /// Paints where avalanches start (the editor's avalanche brush): `probability_per_day`
    /// per cell, in [0, 1], the chance that a release zone of `site_spacing_m` × `site_spacing_m`
    /// around the cell releases on a given day. Each cell becomes a release rate of
    /// `−ln(1 − min(p, 0.99)) · cell area / site area` per day, added to the hazard map the
    /// scheduler draws its Avalanche-Start events from
    /// ([`crate::avalanches::HazardSources::painted`]), so the painted releases happen during
    /// the season's days, at the times the scheduler draws, wherever unstable snow lies; they
    /// are recorded with [`Trigger::Painted`]. `None` (or a map of zeros) removes the paint.
    /// An error names the first value out of range.
    pub fn set_painted_release(
        &mut self,
        probability_per_day: Option<&[f32]>,
        site_spacing_m: f64,
    ) -> Result<(), SeasonError> {
        let g = self.terrain.geometry();
        let rates = match probability_per_day {
            None => None,
            Some(p) => {
                let bad = |name: &'static str, value: f64, reason: &'static str| {
                    SeasonError::Phenomenon {
                        phenomenon: "painted release",
                        day: self.day(),
                        source: crate::phenomenon::PhenomenonError::InvalidParameter {
                            phenomenon: "painted release",
                            name,
                            value,
                            reason,
                        },
                    }
                };
                if p.len() != g.len() {
                    return Err(bad("cells", p.len() as f64, "one value per grid cell"));
                }
                if !(site_spacing_m.is_finite() && site_spacing_m > 0.0) {
                    return Err(bad("site_spacing_m", site_spacing_m, "must be > 0 m"));
                }
                if let Some(&v) = p.iter().find(|v| !(0.0..=1.0).contains(*v)) {
                    return Err(bad(
                        "probability_per_day",
                        f64::from(v),
                        "must be in [0, 1]",
                    ));
                }
                let share = g.cell_area() / (site_spacing_m * site_spacing_m);
                // A certain release (p = 1) has no finite rate: p counts up to 0.99 (4.6
                // releases a day per zone).
                let rate = |p: f32| (-(1.0 - f64::from(p).min(0.99)).ln() * share) as f32;
                p.iter().any(|&v| v > 0.0).then(|| {
                    p.iter()
                        .map(|&v| if v > 0.0 { rate(v) } else { 0.0 })
                        .collect()
                })
            }
        };
        if rates != self.state.painted_release {
            self.ensure_workspace()?;
            self.state.painted_release = rates;
            self.update_avalanche_rate();
        }
        Ok(())
    }

    /// Triggers an avalanche now at a map position (the user's rupture point, §3.2): the
    /// unstable snow within reach and down-slope of it runs to rest and deposits as stable
    /// snow. An error names the position when it lies outside the grid or holds no unstable
    /// snow (scenario avalanches that find no snow are skipped).
    pub fn trigger_avalanche(&mut self, x: f64, y: f64) -> Result<AvalancheRecord, SeasonError> {
        let g = self.terrain.geometry();
        let Some((c, r)) = g.map_to_cell(x, y) else {
            return Err(SeasonError::AvalanchePosition {
                x,
                y,
                reason: "outside the grid".into(),
            });
        };
        let cell = g.index(c.round() as usize, r.round() as usize);
        self.ensure_workspace()?;
        let t = Instant::now();
        let rec = self.start_avalanche(cell, Trigger::User);
        *self.wall_seconds.entry("avalanche").or_default() += t.elapsed().as_secs_f64();
        rec
    }

    /// Ruptures at `cell`, runs the avalanche to rest (temporal zoom) and records it.
    fn start_avalanche(
        &mut self,
        cell: usize,
        trigger: Trigger,
    ) -> Result<AvalancheRecord, SeasonError> {
        let day = self.day();
        let params = &self.scenario.parameters.avalanche;
        let (col, row) = self.terrain.geometry().col_row(cell);
        let err = |source| SeasonError::Avalanche { day, source };
        let (x, y) = self.terrain.geometry().cell_centre(col, row);
        let cells = match rupture_at_point(&self.terrain, x, y, &params.rupture) {
            Ok(r) => r.cells,
            Err(e) => {
                return Err(SeasonError::AvalanchePosition {
                    x,
                    y,
                    reason: e.to_string(),
                });
            }
        };
        let (rec, entrained) = avalanches::run_avalanche(
            params,
            &mut self.terrain,
            &self.environment.temperature,
            avalanches::Release {
                cells: &cells,
                day,
                trigger,
                cell,
            },
            &mut self.state.avalanche_maps,
            &mut self.avalanche_workspace,
        )
        .map_err(err)?;
        self.state.run.budget.avalanche_outflow += rec.outflow_m3;
        self.state.run.budget.avalanche_entrained += rec.entrained_m3;
        self.state
            .run
            .scheduler
            .advance_clock(rec.simulated_s / SECONDS_PER_DAY);
        *self
            .state
            .run
            .event_counts
            .entry(EventKind::AvalancheStep)
            .or_default() += rec.steps;
        self.state.run.avalanches.push(rec.clone());
        // Only the released and entrained cells' unstable snow changed (the debris is stable
        // snow).
        let mut changed = cells;
        if !entrained.is_empty() {
            changed.extend(entrained);
            changed.sort_unstable();
            changed.dedup();
        }
        let skiers = self.recent_skier_map();
        let sources = HazardSources {
            skiers: skiers.as_deref(),
            painted: self.state.painted_release.as_deref(),
        };
        let total = self.workspace.hazard.update_cells(
            &self.scenario.parameters.avalanche,
            &self.terrain,
            &self.workspace.slope_deg,
            &sources,
            &changed,
        );
        self.state
            .run
            .scheduler
            .set_rate(EventKind::AvalancheStart, total, total > 0.0);
        Ok(rec)
    }

    /// Recomputes temperature and wind for the current weather period (sun, sky and bounce do
    /// not depend on the weather and are kept).
    fn refresh_weather_maps(&mut self) -> Result<(), SeasonError> {
        let t = Instant::now();
        let w = &self.weather[self.state.run.weather_index];
        let params = weather_params(&self.base_environment, w);
        let g = self.terrain.geometry();
        self.environment.temperature = snowscape_environment::temperature(
            &self.terrain.bedrock,
            &self.environment.irradiance,
            self.terrain.mask(),
            &params.temperature,
        )?;
        let wind = snowscape_environment::wind(
            &self.terrain.bedrock,
            g,
            self.terrain.mask(),
            &params.wind,
        )?;
        self.environment.wind_u = wind.u;
        self.environment.wind_v = wind.v;
        self.environment.wind_shadow = wind.shadow;
        self.environment.wind_effect_surface = wind.effect_surface;
        self.environment.wind_stats = wind.stats;
        self.refresh_wind_terms()?;
        self.refresh_air_temperature();
        self.environment.store(&mut self.terrain)?;
        *self.wall_seconds.entry("environment").or_default() += t.elapsed().as_secs_f64();
        Ok(())
    }

    fn apply(&mut self, event: Event) -> Result<(), SeasonError> {
        let t = Instant::now();
        let day = event.time_days;
        self.follow_storms();
        self.sample_band_swe(day);
        // An avalanche runs inside its start event: its time is the avalanche's.
        let name = match event.kind {
            EventKind::AvalancheStart => phenomenon_name(EventKind::AvalancheStep),
            EventKind::SkierStart => phenomenon_name(EventKind::SkierStep),
            kind => phenomenon_name(kind),
        };
        let depth_before = (self.state.ski_area.is_some()
            && matches!(
                event.kind,
                EventKind::SnowfallStep | EventKind::WindTransportStep
            ))
        .then(|| self.terrain.total_depth());
        // Each step of the event, timed under its own name (the rest of the event's upkeep
        // under the event's).
        let mut steps_s = 0.0;
        for &(_, step_name, step) in PHENOMENA.iter().filter(|p| p.0 == event.kind) {
            let ts = Instant::now();
            step(self, &event)?;
            let s = ts.elapsed().as_secs_f64();
            *self.wall_seconds.entry(step_name).or_default() += s;
            steps_s += s;
        }
        self.fade_tracks(depth_before)?;
        if matches!(
            event.kind,
            EventKind::MeltAndStateStep | EventKind::SnowfallStep
        ) {
            self.state.run.terminus_stale = true;
        }
        if matches!(
            event.kind,
            EventKind::MeltAndStateStep | EventKind::SnowfallStep
        ) {
            self.update_avalanche_rate();
        } else if !matches!(
            event.kind,
            // Powder diffusion moves powder only (tested); an avalanche updates the map
            // itself; a snowfall start changes no snow.
            EventKind::PowderDiffusionStep | EventKind::AvalancheStart | EventKind::SnowfallStart
        ) {
            // Wind erodes unstable snow where the powder is gone; skiers change the
            // recent-skier map.
            self.workspace.hazard_stale = true;
        }
        *self.state.run.event_counts.entry(event.kind).or_default() += 1;
        if cfg!(debug_assertions) || event.index.is_multiple_of(64) {
            self.terrain
                .check_invariants()
                .map_err(|source| SeasonError::Invariant {
                    phenomenon: name,
                    day,
                    source,
                })?;
        }
        *self.wall_seconds.entry(name).or_default() += t.elapsed().as_secs_f64() - steps_s;
        Ok(())
    }
}

/// Random stream of the avalanche start cells.
const STREAM_AVALANCHE_CELL: u64 = 0xa7a1_a4c3;
/// Random stream of the painted-or-natural draw of an avalanche start on a painted cell.
const STREAM_PAINTED_TRIGGER: u64 = 0xa7a1_9a17;

/// The environment parameters of one weather period.
fn weather_params(base: &EnvironmentParams, w: &WeatherPeriod) -> EnvironmentParams {
    let mut p = base.clone();
    p.temperature.t0_c = w.sea_level_temperature_c;
    p.wind.direction_deg = w.wind_from_deg;
    p.wind.speed_m_s = w.wind_speed_m_s;
    p
}

/// Stable names of the phenomena, for timings and reports.
pub fn phenomenon_name(kind: EventKind) -> &'static str {
    match kind {
        EventKind::SnowfallStart => "snowfall_start",
        EventKind::SnowfallStep => "snowfall",
        EventKind::MeltAndStateStep => "melt_and_stability",
        EventKind::PowderDiffusionStep => "powder_diffusion",
        EventKind::WindTransportStep => "wind_transport",
        EventKind::AvalancheStart => "avalanche_start",
        EventKind::AvalancheStep => "avalanche",
        EventKind::SkierStart => "skier_start",
        EventKind::SkierStep => "skier",
    }
}
