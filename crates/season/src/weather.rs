//! The season's weather, hour by hour, as the default melt and snowfall read it: the
//! sea-level air temperature of each hour (climatology, `[[weather]]` periods or station
//! forcing, plus the diurnal cycle of [`crate::climate`], damped and colder in the hours of
//! snowfall periods, [`crate::storms`]), per-cell lapse offsets and orographic factors, the
//! hours of a melt window with their sun, and the phase table of a window's precipitation.

use crate::climate::ClimateParams;
use crate::forcing::StationForcing;
use crate::melt::MeltHour;
use crate::scenario::WeatherPeriod;
use crate::snowfall::{PrecipitationHour, PrecipitationTable};
use crate::storms::StormRates;
use snowscape_environment::SeasonSun;
use snowscape_environment::insolation::clear_sky;
use snowscape_terrain::{LayeredTerrain, NodataMask, parallel};
use std::sync::Arc;

/// Longwave emission of a melting snow surface, `σ · 273.15⁴`, W/m² (emissivity 1).
pub const MELTING_SURFACE_LONGWAVE_W_M2: f32 = 315.6;

/// Where the hourly air comes from.
#[derive(Debug, Clone)]
pub enum AirSource {
    /// The climatology of [`crate::climate::climatology_sea_level_c`] with the diurnal cycle.
    Climatology,
    /// The `[[weather]]` periods' sea-level temperatures with the diurnal cycle.
    Periods,
    /// A station's record (its own diurnal cycle), moved to sea level with the lapse rate.
    Station(Arc<StationForcing>),
}

/// The hourly weather of a season over one terrain (cheap to clone: the maps are shared).
#[derive(Debug, Clone)]
pub struct Air {
    climate: ClimateParams,
    source: AirSource,
    periods: Vec<WeatherPeriod>,
    latitude_deg: f64,
    start_day_of_year: u32,
    /// Per cell: lapse rate × altitude, °C.
    pub lapse_offset_c: Arc<Vec<f32>>,
    /// Per cell: the orographic precipitation factor.
    pub orographic: Arc<Vec<f32>>,
    offset_range: (f32, f32),
    /// Altitude of the precipitation reference (the climate's or the station's), m.
    pub reference_altitude_m: f64,
    /// Altitude the clear-sky air mass is computed at (the terrain's median), m.
    radiation_altitude_m: f64,
    /// The hourly sun of the season's months.
    pub sun: Arc<SeasonSun>,
    /// The storm rates of a season total, when the climate sets one.
    storm_rates: Option<StormRates>,
}

/// Whether season time `day` lies in one of the snowfall periods `storms` (start, end), days.
pub fn in_storm(storms: &[(f64, f64)], day: f64) -> bool {
    storms
        .iter()
        .any(|&(from, until)| from <= day && day < until)
}

impl Air {
    /// The air over the bedrock of `terrain` (nodata cells get offset 0 and factor 0).
    pub fn new(
        climate: &ClimateParams,
        source: AirSource,
        periods: &[WeatherPeriod],
        latitude_deg: f64,
        start_day_of_year: u32,
        terrain: &LayeredTerrain,
        sun: Arc<SeasonSun>,
    ) -> Self {
        let (bedrock, mask) = (&terrain.bedrock, terrain.mask());
        let lapse = climate.lapse_c_per_m() as f32;
        let reference_altitude_m = match &source {
            AirSource::Station(s) => s.station_altitude_m.unwrap_or(climate.reference_altitude_m),
            _ => climate.reference_altitude_m,
        };
        let lapse_offset_c: Vec<f32> = bedrock
            .iter()
            .enumerate()
            .map(|(i, &z)| if mask.is_valid(i) { lapse * z } else { 0.0 })
            .collect();
        let orographic: Vec<f32> = bedrock
            .iter()
            .enumerate()
            .map(|(i, &z)| {
                if mask.is_valid(i) {
                    climate.orographic_factor(z, reference_altitude_m)
                } else {
                    0.0
                }
            })
            .collect();
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        let mut valid: Vec<f32> = Vec::new();
        for (i, &o) in lapse_offset_c.iter().enumerate() {
            if mask.is_valid(i) {
                lo = lo.min(o);
                hi = hi.max(o);
                valid.push(bedrock[i]);
            }
        }
        if lo > hi {
            (lo, hi) = (0.0, 0.0);
        }
        valid.sort_by(f32::total_cmp);
        let radiation_altitude_m = valid.get(valid.len() / 2).copied().unwrap_or(0.0) as f64;
        Self {
            climate: climate.clone(),
            source,
            periods: periods.to_vec(),
            latitude_deg,
            start_day_of_year,
            lapse_offset_c: Arc::new(lapse_offset_c),
            orographic: Arc::new(orographic),
            offset_range: (lo, hi),
            reference_altitude_m,
            radiation_altitude_m,
            sun,
            storm_rates: None,
        }
    }

    /// The same air with the storm rates of a season total ([`crate::storms`]).
    pub fn with_storm_rates(mut self, rates: Option<StormRates>) -> Self {
        self.storm_rates = rates;
        self
    }

    /// The storm rates of a season total, when the climate sets one.
    pub fn storm_rates(&self) -> Option<&StormRates> {
        self.storm_rates.as_ref()
    }

    /// The climate parameters.
    pub fn climate(&self) -> &ClimateParams {
        &self.climate
    }

    /// Day of year (1..=365, fractional) of season day `day`.
    pub fn day_of_year(&self, day: f64) -> f64 {
        (self.start_day_of_year as f64 - 1.0 + day).rem_euclid(365.0) + 1.0
    }

    fn period_at(&self, day: f64) -> Option<&WeatherPeriod> {
        let k = snowscape_terrain::timeline::period_index_at(&self.periods, day)?;
        let p = &self.periods[k];
        (p.from_day <= day).then_some(p)
    }

    /// The station record covering season day `day`.
    fn station_record(&self, day: f64) -> Option<&crate::forcing::ForcingRecord> {
        match &self.source {
            AirSource::Station(s) => Some(s.at_hour(day * 24.0)),
            _ => None,
        }
    }

    /// Daily-mean sea-level air temperature at season day `day`, °C (no diurnal term).
    pub fn sea_level_daily_c(&self, day: f64) -> f64 {
        match &self.source {
            AirSource::Climatology => {
                crate::climate::climatology_sea_level_c(self.latitude_deg, self.day_of_year(day))
                    + self.climate.temperature_offset_c
            }
            AirSource::Periods => self
                .period_at(day)
                .map_or(0.0, |p| p.sea_level_temperature_c),
            AirSource::Station(s) => {
                // The mean of the 24 records around `day`.
                let lapse = self.climate.lapse_c_per_m();
                let z = s.station_altitude_m.unwrap_or(self.reference_altitude_m);
                let start = (day.floor() * 24.0) as i64;
                let sum: f64 = (0..24)
                    .map(|h| s.at_hour((start + h) as f64 + 0.5).air_temperature_c as f64)
                    .sum();
                sum / 24.0 - lapse * z
            }
        }
    }

    /// Sea-level air temperature at season time `day` (with the diurnal cycle), °C: the
    /// storm cycle of [`crate::storms`] when `storm` (a snowfall period), except under a
    /// station's record.
    pub fn sea_level_c(&self, day: f64, storm: bool) -> f64 {
        if let Some(r) = self.station_record(day) {
            return r.air_temperature_c as f64
                - self.climate.lapse_c_per_m() * self.reference_altitude_m;
        }
        let hour = day.rem_euclid(1.0) * 24.0;
        let cycle = if storm {
            self.climate.storm_diurnal_c(hour)
        } else {
            self.climate.diurnal_c(hour)
        };
        self.sea_level_daily_c(day) + cycle
    }

    /// Precipitation during snowfall periods at the reference altitude, m of water per day
    /// (climatology and periods): the period's rate, else a season total's, else the
    /// climate's ([`crate::storms`]).
    pub fn storm_precipitation_m_per_day(&self, day: f64) -> f64 {
        let mm = match self.period_at(day).and_then(|p| p.precipitation_mm_per_day) {
            Some(mm) => mm,
            None => match &self.storm_rates {
                Some(r) => r.at(day),
                None => self.climate.storm_precipitation_mm_per_day(),
            },
        };
        mm * 1e-3
    }

    /// The phase table of the storm hours `[t0, t1]` (season days): each hour's storm air
    /// and rate, at the storm humidity (a station's, when it records one).
    pub fn storm_precipitation(&self, t0: f64, t1: f64) -> PrecipitationTable {
        let storm_rh = self.climate.storm_relative_humidity as f32;
        let hours: Vec<PrecipitationHour> = Self::slots(t0, t1)
            .into_iter()
            .filter(|&(_, w)| w > 0.0)
            .map(|(t, w)| {
                let mid = t + 0.5 * w as f64 / 24.0;
                PrecipitationHour {
                    sea_level_c: self.sea_level_c(mid, true) as f32,
                    water_m: (self.storm_precipitation_m_per_day(mid) * w as f64 / 24.0) as f32,
                    relative_humidity: self
                        .station_record(mid)
                        .and_then(|r| r.relative_humidity)
                        .unwrap_or(storm_rh),
                }
            })
            .filter(|h| h.water_m > 0.0)
            .collect();
        self.precipitation_table(&hours)
    }

    /// Whether precipitation comes from a station record (then the Poisson snowfall is off).
    pub fn from_station(&self) -> bool {
        matches!(self.source, AirSource::Station(_))
    }

    /// The daily-mean air temperature map at season day `day`, °C (0 on nodata).
    pub fn daily_temperature_map(&self, day: f64, mask: &NodataMask, out: &mut Vec<f32>) {
        let t = self.sea_level_daily_c(day) as f32;
        out.resize(self.lapse_offset_c.len(), 0.0);
        const BLOCK: usize = 1 << 14;
        parallel::for_each_block(
            BLOCK,
            (&mut out[..], &self.lapse_offset_c[..]),
            |b, (out, offsets)| match mask.invalid_cells() {
                None => out.iter_mut().zip(offsets).for_each(|(o, &d)| *o = t + d),
                Some(invalid) => {
                    let invalid = &invalid[b * BLOCK..b * BLOCK + out.len()];
                    for ((o, &d), &bad) in out.iter_mut().zip(offsets).zip(invalid) {
                        *o = if bad { 0.0 } else { t + d };
                    }
                }
            },
        );
    }

    /// The hour slots of the window `[t0, t1]` (season days): (start day, weight in hours).
    fn slots(t0: f64, t1: f64) -> Vec<(f64, f32)> {
        let mut out = Vec::new();
        let mut t = t0;
        // At most a year of hours in one window.
        while t < t1 && out.len() < 24 * 366 {
            let next = ((t * 24.0).floor() + 1.0) / 24.0;
            let end = next.min(t1);
            out.push((t, ((end - t) * 24.0) as f32));
            t = end;
        }
        out
    }

    /// The hour-weighted mean relative humidity (0..1, with respect to water) of `[t0, t1]`
    /// (season days): the climate's storm humidity in the hours inside the snowfall periods
    /// `storms`, its fair humidity outside them, a station's recorded humidity where it has
    /// one. An empty interval reads the humidity at `t0`.
    pub fn mean_relative_humidity(&self, t0: f64, t1: f64, storms: &[(f64, f64)]) -> f64 {
        let at = |day: f64| {
            let climate = self
                .climate
                .hour_air(in_storm(storms, day))
                .relative_humidity;
            let recorded = self.station_record(day).and_then(|r| r.relative_humidity);
            f64::from(recorded.unwrap_or(climate))
        };
        let (mut sum, mut hours) = (0.0, 0.0);
        for (t, weight) in Self::slots(t0, t1) {
            let w = f64::from(weight);
            sum += w * at(t + 0.5 * w / 24.0);
            hours += w;
        }
        if hours > 0.0 { sum / hours } else { at(t0) }
    }

    /// The hours of the melt window `[t0, t1]`: sea-level temperature, sun and clouds, of a
    /// storm in the hours inside the snowfall periods `storms` (start, end), days (station
    /// shortwave, when recorded, sets the clouds instead).
    pub fn melt_hours(&self, t0: f64, t1: f64, storms: &[(f64, f64)]) -> Vec<MeltHour<'_>> {
        Self::slots(t0, t1)
            .into_iter()
            .filter(|&(_, w)| w > 0.0)
            .map(|(t, weight)| {
                let mid = t + 0.5 * weight as f64 / 24.0;
                let storm = in_storm(storms, mid);
                let clouds = if storm {
                    self.climate.storm_cloud_factor
                } else {
                    self.climate.fair_cloud_factor
                };
                let doy = self.day_of_year(mid);
                let hour = (mid.rem_euclid(1.0) * 24.0).floor() as u32;
                let month_index = self
                    .sun
                    .month_for(doy as u32)
                    .and_then(|m| self.sun.months.iter().position(|x| x.month == m.month))
                    .unwrap_or(0);
                let sun_hour = self.sun.months.get(month_index).and_then(|m| m.hour(hour));
                let mut air = self.climate.hour_air(storm);
                let (beam, direct, diffuse, reflected) = match sun_hour {
                    Some(h) => {
                        let (dir, dif) = clear_sky(
                            &self.climate.clear_sky,
                            doy as u32,
                            h.sin_elevation as f64,
                            self.radiation_altitude_m,
                        );
                        let recorded =
                            self.recorded_cloud_factor(mid, dir, dif, h.sin_elevation as f64);
                        if let Some(c) = recorded {
                            air.cloud_cover = crate::climate::cloud_cover_of_factor(c) as f32;
                        }
                        let c = recorded.unwrap_or(clouds);
                        (
                            Some(h.beam.as_slice()),
                            (dir * c) as f32,
                            (dif * c) as f32,
                            (dir * h.sin_elevation as f64 * c) as f32,
                        )
                    }
                    None => (None, 0.0, 0.0, 0.0),
                };
                let record = self.station_record(mid);
                if let Some(r) = record {
                    air.relative_humidity = r.relative_humidity.unwrap_or(air.relative_humidity);
                    air.wind_speed_m_s = r.wind_speed_m_s;
                    air.longwave_in_w_m2 = r.longwave_in_w_m2;
                }
                let longwave_balance_w_m2 = record
                    .and_then(|r| r.longwave_in_w_m2)
                    .map_or(0.0, |l| l - MELTING_SURFACE_LONGWAVE_W_M2);
                MeltHour {
                    air,
                    longwave_balance_w_m2,
                    weight,
                    sea_level_c: self.sea_level_c(mid, storm) as f32,
                    beam,
                    direct_w_m2: direct,
                    diffuse_w_m2: diffuse,
                    reflected_w_m2: reflected,
                    month: month_index,
                }
            })
            .collect()
    }

    /// The shortwave share of the clear sky at `day`: a station's measured shortwave over
    /// the clear-sky global irradiance on flat ground when it records one (incoming, or net
    /// over the fresh-snow absorptance when only net shortwave is given), else `None` (the
    /// climate's share).
    fn recorded_cloud_factor(&self, day: f64, dir: f64, dif: f64, sin_e: f64) -> Option<f64> {
        let r = self.station_record(day)?;
        let clear = dir * sin_e + dif;
        if clear < 20.0 {
            return None;
        }
        if let Some(sw) = r.shortwave_in_w_m2 {
            return Some((sw as f64 / clear).clamp(0.0, 1.2));
        }
        // Net shortwave over a mid-season snow absorptance (1 − 0.75).
        r.net_shortwave_w_m2
            .map(|net| (net as f64 / (0.25 * clear)).clamp(0.0, 1.2))
    }

    /// The precipitation table of a station window `[t0, t1]` (snow and rain at the
    /// reference altitude by each record's temperature and relative humidity, the storm
    /// humidity where none is recorded), or `None` without a station.
    pub fn station_precipitation(&self, t0: f64, t1: f64) -> Option<PrecipitationTable> {
        let AirSource::Station(_) = &self.source else {
            return None;
        };
        let lapse = self.climate.lapse_c_per_m();
        let storm_rh = self.climate.storm_relative_humidity as f32;
        let hours: Vec<PrecipitationHour> = Self::slots(t0, t1)
            .into_iter()
            .filter_map(|(t, w)| {
                let r = self.station_record(t + 0.5 * w as f64 / 24.0)?;
                let per_hour = r.precipitation_mm as f64 * 1e-3 / self.station_step_hours();
                Some(PrecipitationHour {
                    sea_level_c: (r.air_temperature_c as f64 - lapse * self.reference_altitude_m)
                        as f32,
                    water_m: (per_hour * w as f64) as f32,
                    relative_humidity: r.relative_humidity.unwrap_or(storm_rh),
                })
            })
            .filter(|h| h.water_m > 0.0)
            .collect();
        Some(self.precipitation_table(&hours))
    }

    fn station_step_hours(&self) -> f64 {
        match &self.source {
            AirSource::Station(s) => s.step_hours.max(1e-6),
            _ => 1.0,
        }
    }

    /// The phase table of precipitation `hours` over this terrain's lapse offsets.
    pub fn precipitation_table(&self, hours: &[PrecipitationHour]) -> PrecipitationTable {
        PrecipitationTable::new(
            &self.climate,
            hours,
            self.offset_range.0,
            self.offset_range.1,
        )
    }
}
