//! The start of a season ([`Winter::with_forcing`]): the latitude and the weather timeline it
//! resolves, the run state it starts from, the hourly air it draws on, and the readying of the
//! maps and rates before the first event.

use super::{
    LatitudeSource, RunState, SeasonBudget, SeasonError, SeasonState, Winter, resume,
    scenario_digest,
};
use crate::avalanches::{self, AvalancheMaps};
use crate::forcing::StationForcing;
use crate::melt::SnowpackState;
use crate::scenario::{Scenario, WeatherPeriod};
use crate::scheduler::{EventKind, Scheduler};
use crate::skiing::SkiStats;
use crate::weather::{Air, AirSource};
use snowscape_avalanche::AvalancheWorkspace;
use snowscape_environment::{EnvironmentMaps, EnvironmentParams, SeasonSun};
use snowscape_terrain::LayeredTerrain;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

/// The season's latitude, degrees north, and where it came from: the scenario's, else the
/// DEM's georeferencing, else `assumed_deg` (the environment's default).
pub(super) fn resolve_latitude(
    scenario: &Scenario,
    terrain: &LayeredTerrain,
    assumed_deg: f64,
) -> (f64, LatitudeSource) {
    match (scenario.latitude_deg, terrain.geometry().latitude_deg()) {
        (Some(l), _) => (l, LatitudeSource::Scenario),
        (None, Some(l)) => (l, LatitudeSource::Georeferencing),
        (None, None) => (assumed_deg, LatitudeSource::Assumed),
    }
}

/// The weather timeline: the station's winter when a record forces the season, else the
/// scenario's periods (the default winter over the valid cells' altitudes when it has none).
pub(super) fn resolve_weather(
    scenario: &Scenario,
    terrain: &LayeredTerrain,
    forcing: Option<&StationForcing>,
    latitude: f64,
) -> Vec<WeatherPeriod> {
    match forcing {
        Some(f) => crate::climate::station_winter(f, scenario.days),
        None => {
            let valid: Vec<f32> = terrain
                .bedrock
                .iter()
                .enumerate()
                .filter(|(i, _)| terrain.mask().is_valid(*i))
                .map(|(_, &z)| z)
                .collect();
            scenario.weather_or_default(&valid, latitude)
        }
    }
}

/// The run state at day 0: the scheduler seeded with the first period's snowfall rate, the
/// budget holding the terrain's snow, and the fingerprints a checkpoint is checked against.
pub(super) fn initial_state(
    scenario: &Scenario,
    terrain: &LayeredTerrain,
    weather: &[WeatherPeriod],
    forcing: Option<&StationForcing>,
) -> RunState {
    let mut scheduler = Scheduler::new(scenario.seed, &scenario.events);
    let digest = scenario_digest(scenario, weather, forcing);
    scheduler.set_rate(
        EventKind::SnowfallStart,
        weather[0].snowfall_per_week / 7.0,
        true,
    );
    RunState {
        scheduler,
        budget: SeasonBudget {
            initial_store: terrain.snow_volume(),
            ..SeasonBudget::default()
        },
        event_counts: BTreeMap::new(),
        weather_index: 0,
        forced_index: 0,
        fingerprint: crate::checkpoint::bedrock_fingerprint(terrain),
        scenario_digest: digest,
        scenario: serde_json::to_value(scenario).unwrap_or_default(),
        terrain: resume::terrain_summary(terrain),
        avalanches: Vec::new(),
        user_avalanche_index: 0,
        ski: SkiStats::default(),
        melt_clock_days: 0.0,
        shed_clock_days: None,
        storms: Vec::new(),
        bands: crate::bands::BandRecord::default(),
        terminus_stale: false,
    }
}

/// The hourly sun of the season's dates when the melt model is hourly (else none), with the
/// wall-clock seconds it took.
pub(super) fn hourly_sun(
    scenario: &Scenario,
    terrain: &LayeredTerrain,
    env: &EnvironmentParams,
    environment: &EnvironmentMaps,
) -> Result<(SeasonSun, f64), SeasonError> {
    if scenario.parameters.melt.model.hourly() {
        let t = Instant::now();
        let sun = snowscape_environment::season_sun(
            &terrain.bedrock,
            terrain.geometry(),
            terrain.mask(),
            env,
            &environment.sky_view_factor,
        )?;
        Ok((sun, t.elapsed().as_secs_f64()))
    } else {
        Ok((SeasonSun::default(), 0.0))
    }
}

/// The hourly air of the season: from the station's record, the climatology (the default
/// winter of a scenario without periods) or the weather periods, with the storm rates of the
/// timeline and the scenario's forced snowfall.
pub(super) fn season_air(
    scenario: &Scenario,
    forcing: Option<StationForcing>,
    weather: &[WeatherPeriod],
    latitude: f64,
    env: &EnvironmentParams,
    terrain: &LayeredTerrain,
    season_sun: SeasonSun,
) -> Air {
    let source = match forcing {
        Some(f) => AirSource::Station(Arc::new(f)),
        None if scenario.weather.is_empty()
            && scenario.parameters.climate.default_winter
                == crate::climate::DefaultWinter::Climatology =>
        {
            AirSource::Climatology
        }
        None => AirSource::Periods,
    };
    let storm_rates = crate::storms::StormRates::new(
        &scenario.parameters.climate,
        &crate::storms::SeasonStorms {
            weather,
            forced: &scenario.snowfall_periods,
            mean_storm_days: scenario.events.snowfall_mean_days,
            start_day_of_year: env.sun.start_day,
            days: scenario.days,
        },
    );
    Air::new(
        &scenario.parameters.climate,
        source,
        weather,
        latitude,
        env.sun.start_day,
        terrain,
        Arc::new(season_sun),
    )
    .with_storm_rates(storm_rates)
}

/// What a season is made of at its start, before [`Winter::ready`].
pub(super) struct SeasonStart {
    pub scenario: Scenario,
    pub weather: Vec<WeatherPeriod>,
    pub terrain: LayeredTerrain,
    pub state: RunState,
    pub environment: EnvironmentMaps,
    pub base_environment: EnvironmentParams,
    pub air: Air,
    pub latitude_source: LatitudeSource,
}

impl Winter {
    /// The season of `start` with empty scratch, maps and caches.
    pub(super) fn assemble(start: SeasonStart) -> Self {
        let SeasonStart {
            scenario,
            weather,
            terrain,
            state,
            environment,
            base_environment,
            air,
            latitude_source,
        } = start;
        let n_cells = terrain.geometry().len();
        let bands = crate::bands::Bands::new(&terrain);
        Self {
            bands,
            air,
            latitude_source,
            scenario,
            weather,
            terrain,
            state: SeasonState {
                run: state,
                pack: SnowpackState::new(n_cells),
                pending_rain: vec![0.0; n_cells],
                avalanche_maps: AvalancheMaps::default(),
                painted_release: None,
                ski_area: None,
            },
            environment,
            base_environment,
            wall_seconds: BTreeMap::new(),
            workspace: Default::default(),
            avalanche_workspace: AvalancheWorkspace::default(),
        }
    }

    /// Readies a freshly assembled season for its first event: the first period's wind terms
    /// and air temperature, the environment stored on the terrain, no drawn snowfall when a
    /// station's record brings it, the band record, the bedrock slopes, empty avalanche maps,
    /// the avalanche rate and the skiers' rate.
    pub(super) fn ready(&mut self) -> Result<(), SeasonError> {
        self.refresh_wind_terms()?;
        self.refresh_air_temperature();
        self.environment.store(&mut self.terrain)?;
        if self.air.from_station() {
            self.state
                .run
                .scheduler
                .set_rate(EventKind::SnowfallStart, 0.0, false);
        }
        self.state.run.bands.ensure(self.bands.len());
        self.workspace.slope_deg = avalanches::bedrock_slopes_deg(&self.terrain);
        self.workspace.built = true;
        let n = self.terrain.geometry().len();
        self.state.avalanche_maps = AvalancheMaps {
            scour: vec![0.0; n],
            deposit: vec![0.0; n],
        };
        self.update_avalanche_rate();
        let per_day = self.scenario.skiers.per_day;
        self.state
            .run
            .scheduler
            .set_rate(EventKind::SkierStart, per_day, per_day > 0.0);
        Ok(())
    }
}
