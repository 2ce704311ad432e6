//! The season's snowpack beyond the paper, as [`Winter`] runs it: the hourly air
//! ([`crate::weather`]), the storms and their orographic precipitation ([`crate::storms`]),
//! the enhanced melt windows, the altitude bands' record ([`crate::bands`]) and the Sx
//! sheltering of each weather period.

use super::{SeasonError, Winter};
use crate::melt::{self, MeltForcing, MeltModel};
use crate::phenomenon::PhenomenonError;
use crate::snowfall::{self, PrecipitationMaps, SnowfallModel};
use crate::wind_transport::{WindMaps, WindModel, WindTerms};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// A snowfall period of the scheduler, and how much of its precipitation has been laid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(super) struct StormSpan {
    /// Start, season days.
    pub since: f64,
    /// End, season days (the running period's may still grow).
    pub until: f64,
    /// Its precipitation is laid up to here, season days.
    pub delivered_to: f64,
}

/// The `(since, until)` days of the storms a run state lists (the melt and drift humidity
/// windows read them).
pub(super) fn storm_windows(storms: &[StormSpan]) -> Vec<(f64, f64)> {
    storms.iter().map(|s| (s.since, s.until)).collect()
}

impl Winter {
    /// What the current period's wind field gives wind transport: the sheltering index (the
    /// short- and long-range maximum upwind slopes, when the Sx redistribution is on), then the
    /// field's snow-independent terms.
    pub(super) fn refresh_wind_terms(&mut self) -> Result<(), SeasonError> {
        let p = &self.scenario.parameters.wind_transport;
        if p.sx_redistribution.enabled {
            let t = Instant::now();
            let w = &self.weather[self.state.run.weather_index];
            self.workspace.sx = snowscape_environment::sheltering_index(
                &self.terrain.bedrock,
                self.terrain.geometry(),
                self.terrain.mask(),
                w.wind_from_deg,
                &self.base_environment.sheltering,
            )?;
            *self.wall_seconds.entry("sheltering").or_default() += t.elapsed().as_secs_f64();
        } else {
            self.workspace.sx.clear();
        }
        self.workspace.wind_terms = if p.model == WindModel::Cordonnier {
            let maps = wind_maps(&self.environment, &self.workspace.sx, None);
            let terms = WindTerms::new(self.terrain.geometry(), self.terrain.mask(), &maps)
                .map_err(|source| SeasonError::Phenomenon {
                    phenomenon: "wind_transport",
                    day: self.day(),
                    source,
                })?;
            Some(terms)
        } else {
            None
        };
        Ok(())
    }

    /// Under the hourly melts, the temperature map the phenomena read (snowfall split,
    /// stability, avalanche α) is the daily-mean air temperature at the end of the last melt
    /// window (the paper's map carries the sun as `ki·I`, which these melts count themselves).
    pub(super) fn refresh_air_temperature(&mut self) {
        if self.scenario.parameters.melt.model.hourly() {
            self.air.daily_temperature_map(
                self.state.run.melt_clock_days,
                self.terrain.mask(),
                &mut self.environment.temperature,
            );
        }
    }

    /// Follows the scheduler's snowfall period: a new one is recorded, the running one's end
    /// kept up to date (a forced period may lengthen it).
    pub(super) fn follow_storms(&mut self) {
        let Some((since, until)) = self.state.run.scheduler.snowfall_period() else {
            return;
        };
        match self.state.run.storms.last_mut() {
            Some(s) if s.since == since => s.until = until,
            _ => self.state.run.storms.push(StormSpan {
                since,
                until,
                delivered_to: since,
            }),
        }
    }

    /// The default snowfall: lays the storms' precipitation, hour by hour, up to `day` (a
    /// Snowfall-Step), or only that of the storms that ended by `day` (`ended_only`: a melt
    /// event, for the hours since a storm's last step). The paper's snowfall lays none of it
    /// here (its steps add their own).
    pub(super) fn deliver_storms(
        &mut self,
        day: f64,
        ended_only: bool,
    ) -> Result<(), PhenomenonError> {
        let orographic = self.scenario.parameters.snowfall.model == SnowfallModel::Orographic;
        for k in 0..self.state.run.storms.len() {
            let s = self.state.run.storms[k];
            let to = s.until.min(day);
            if to <= s.delivered_to || (ended_only && s.until > day) {
                continue;
            }
            if orographic {
                let table = self.air.storm_precipitation(s.delivered_to, to);
                self.add_precipitation(&table)?;
            }
            self.state.run.storms[k].delivered_to = to;
        }
        Ok(())
    }

    /// Forgets the storms whose precipitation is laid and that ended before `day` (the
    /// start of the next melt window).
    pub(super) fn forget_storms(&mut self, day: f64) {
        self.state
            .run
            .storms
            .retain(|s| s.until > day || s.delivered_to < s.until);
    }

    /// Samples each altitude band's mean SWE at the first event of each season day.
    pub(super) fn sample_band_swe(&mut self, day: f64) {
        let today = day.max(0.0).floor() as u64;
        if self.state.run.bands.sampled_day.is_some_and(|d| d >= today) {
            return;
        }
        let t = Instant::now();
        let mean = self.band_mean_swe();
        self.state.run.bands.raise_peaks(&mean);
        self.state.run.bands.sampled_day = Some(today);
        *self.wall_seconds.entry("altitude_bands").or_default() += t.elapsed().as_secs_f64();
    }

    /// Each altitude band's mean SWE now, m of water.
    pub(super) fn band_mean_swe(&self) -> Vec<f64> {
        self.bands.mean_swe_m(
            &self.terrain,
            &self.state.pack.liquid_water_m,
            self.scenario.parameters.melt.enhanced.layer_density_kg_m3,
        )
    }

    /// Adds a precipitation table's snow to the layers and its rain to the pending rain.
    pub(super) fn add_precipitation(
        &mut self,
        table: &snowfall::PrecipitationTable,
    ) -> Result<(), PhenomenonError> {
        let p = &self.scenario.parameters;
        let maps = PrecipitationMaps {
            temperature: &self.environment.temperature,
            lapse_offset_c: &self.air.lapse_offset_c,
            orographic: &self.air.orographic,
        };
        let r = snowfall::add_precipitation(
            &p.snowfall,
            &mut self.terrain,
            &maps,
            table,
            snowfall::PrecipitationTargets {
                densities_kg_m3: p.melt.enhanced.layer_density_kg_m3,
                surface_age: &mut self.state.pack.surface_age_days,
                reset_swe_m: p.melt.enhanced.reset_swe_m,
                rain_out: &mut self.state.pending_rain,
                bands: (self.bands.band_of(), &mut self.state.run.bands.water_m),
            },
            &mut self.workspace.snowfall,
        )?;
        let b = &mut self.state.run.budget;
        b.snowfall += r.snow_m3;
        b.water.snowfall_water += r.snow_water_m3;
        b.water.rain += r.rain_m3;
        b.water.pending += r.rain_m3;
        Ok(())
    }

    /// One window of the hourly melt (the energy balance or the enhanced temperature index),
    /// from the last melt event to `day`. Returns whether it ran, leaving the snow surface in
    /// the stability scratch ([`crate::stability::step_on_filled_surface`]).
    pub(super) fn snowpack_melt(&mut self, day: f64) -> Result<bool, PhenomenonError> {
        let t0 = self.state.run.melt_clock_days;
        let min_window = self.scenario.parameters.melt.enhanced.min_window_hours / 24.0;
        if day - t0 < min_window && day < self.scenario.days {
            return Ok(false);
        }
        if let Some(table) = self.air.station_precipitation(t0, day) {
            self.add_precipitation(&table)?;
        }
        let storms = storm_windows(&self.state.run.storms);
        let hours = self.air.melt_hours(t0, day, &storms);
        let reflected: Vec<&[f32]> = self
            .air
            .sun
            .months
            .iter()
            .map(|m| m.reflected.as_slice())
            .collect();
        let svf = &self.air.sun.sky_view_factor;
        let forcing = MeltForcing {
            hours: &hours,
            lapse_offset_c: &self.air.lapse_offset_c,
            sky_view_factor: svf,
            reflected: &reflected,
            rain_m: &self.state.pending_rain,
            window_days: (day - t0) as f32,
        };
        let p = &self.scenario.parameters.melt;
        let surface = self.workspace.stability.surface_to_fill();
        let r = if p.model == MeltModel::EnergyBalance {
            melt::energy_balance::step_filling_surface(
                &p.energy_balance,
                &p.enhanced,
                &mut self.terrain,
                &mut self.state.pack,
                &forcing,
                surface,
            )?
        } else {
            melt::enhanced::step_filling_surface(
                &p.enhanced,
                &mut self.terrain,
                &mut self.state.pack,
                &forcing,
                surface,
            )?
        };
        self.state.pending_rain.fill(0.0);
        let a = self.terrain.geometry().cell_area();
        let b = &mut self.state.run.budget;
        b.melt += r.melted_snow_m3;
        b.refreeze += r.refrozen_snow_m3;
        b.sublimation += r.sublimated_snow_m3;
        b.deposition += r.deposited_snow_m3;
        b.sublimation_water += r.sublimated_water_m3;
        b.deposition_water += r.deposited_water_m3;
        b.water.melt += r.melt_water_m3;
        b.water.refrozen += r.refrozen_water_m3;
        b.water.runoff += r.runoff_m3;
        b.water.pending = 0.0;
        b.water.store = self.state.pack.liquid_volume(a);
        self.state.run.melt_clock_days = day;
        self.refresh_air_temperature();
        Ok(true)
    }
}

/// The wind maps of wind transport: the environment's wind field and air temperature, the
/// `sx` map (none when empty) and the field's `terms`.
pub(super) fn wind_maps<'a>(
    e: &'a snowscape_environment::EnvironmentMaps,
    sx: &'a [f32],
    terms: Option<&'a WindTerms>,
) -> WindMaps<'a> {
    WindMaps {
        u: &e.wind_u,
        v: &e.wind_v,
        shadow: &e.wind_shadow,
        effect_surface: &e.wind_effect_surface,
        sx: (!sx.is_empty()).then_some(sx),
        terms,
        air_temperature: Some(&e.temperature),
    }
}
