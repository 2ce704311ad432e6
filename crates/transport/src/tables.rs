//! Lookup tables that take the expensive, cell-independent parts out of the per-cell work.
//!
//! - When a surface saltates, `u*` solves Eqs. 5.26 and 5.29 for the wind `u_r` alone (the
//!   roughness `0.12 u*²/2g` is a function of `u*`), so the Newton-Raphson solution
//!   (Eqs. 5.30-5.36) is tabulated once per `z_r` over `u_r ∈ [0, W_max]`, `W_max` the
//!   strongest wind below 80 m s⁻¹ for which the system has a solution (about 50 m s⁻¹ at
//!   `z_r = 5 m`); stronger winds are clamped to it.
//! - Over a saltating surface `z0` and `h*` are functions of `u*`, so the suspension and
//!   sublimation integrals per unit saltation flux (Eqs. 5.40-5.47) depend on `u*` and the
//!   weather alone: `Qsusp = Qsalt / u_p · S(u*)` and
//!   `Qsubl = Qsalt / u_p · (V(u*) + ψs(u*, u*t))` with `S = ∫(φt/φr) u dz / h*`,
//!   `V = ∫ψt (φt/φr) dz / h*`; `V + ψs` (`ψs`: Annex I at `h*/2`) is tabulated over
//!   `(u*, u*t)` on the `u*` sampling of `S`, so one location of `u*` serves both.
//!
//! Tables are rebuilt only when the parameters or the weather they depend on change.
//! Linear interpolation keeps them within 0.5 % of the direct evaluation (tested).

use crate::float_ops::truncate;
use crate::params::{TransportParams, Weather};
use crate::physics::shear::saltating_friction_velocity;
use crate::physics::shear::saltation_height;
use crate::physics::sublimation::{Atmosphere, sin_solar_elevation, surface_irradiance};
use crate::physics::suspension::{blowing_snow_profile, saltation_layer_loss_rate};

/// Highest wind considered for the table, m s⁻¹.
pub const MAX_WIND: f64 = 80.0;
const SHEAR_SAMPLES: usize = 2048;
const PROFILE_SAMPLES: usize = 512;
const THRESHOLD_SAMPLES: usize = 64;
/// Lowest tabulated friction velocity, m s⁻¹ (below the lowest threshold, 0.1 m s⁻¹).
const MIN_U_STAR: f64 = 0.09;
/// Highest tabulated threshold friction velocity, m s⁻¹ (ρs ≈ 490 kg m⁻³).
const MAX_U_STAR_T: f64 = 3.0;

/// A uniform grid of `n` samples from `lo`: where a point falls on it, clamped at both ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Axis {
    lo: f32,
    inv_step: f32,
    /// Index of the last sample, `n − 1`.
    last: f32,
    /// Index of the last segment, `n − 2`.
    last_segment: u32,
}

/// A point on an [`Axis`]: the segment it falls in and its weight towards the segment's end.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Point {
    segment: usize,
    weight: f32,
}

impl Axis {
    fn new(lo: f64, step: f64, n: usize) -> Self {
        Self {
            lo: lo as f32,
            inv_step: (1.0 / step) as f32,
            last: (n - 1) as f32,
            last_segment: (n - 2) as u32,
        }
    }

    #[inline(always)]
    pub(crate) fn locate(&self, x: f32) -> Point {
        // Clamped to [0, last] with comparisons that keep NaN (one instruction each).
        let t = (x - self.lo) * self.inv_step;
        let t = if t < 0.0 { 0.0 } else { t };
        let t = if t > self.last { self.last } else { t };
        // The last sample falls at the end of the last segment, and so does NaN (whose
        // weight stays NaN).
        let segment = truncate(t).min(self.last_segment);
        Point {
            segment: segment as usize,
            weight: t - segment as f32,
        }
    }
}

/// A uniformly sampled function with linear interpolation, clamped at both ends. Each
/// segment keeps its start value and its rise, so an evaluation is one load and one
/// multiply-add.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Table1 {
    axis: Axis,
    segments: Vec<[f32; 2]>,
}

impl Table1 {
    pub(crate) fn new(lo: f64, hi: f64, n: usize, f: impl Fn(f64) -> f64) -> Self {
        let step = (hi - lo) / (n - 1) as f64;
        let values: Vec<f32> = (0..n).map(|i| f(lo + i as f64 * step) as f32).collect();
        Self {
            axis: Axis::new(lo, step, n),
            segments: values.windows(2).map(|v| [v[0], v[1] - v[0]]).collect(),
        }
    }

    /// The sampling of the table, to locate a point once for tables that share it.
    #[inline(always)]
    pub(crate) fn axis(&self) -> &Axis {
        &self.axis
    }

    /// The value at a point located on [`Table1::axis`].
    #[inline(always)]
    pub(crate) fn at_point(&self, p: Point) -> f32 {
        let [value, rise] = self.segments[p.segment];
        value + p.weight * rise
    }

    #[inline(always)]
    pub(crate) fn at(&self, x: f32) -> f32 {
        self.at_point(self.axis.locate(x))
    }
}

/// Functions of one variable sampled on one axis, their segments stored one row after the
/// other, so that a point located once evaluates any row with one load.
#[derive(Debug, Clone, PartialEq)]
struct TableRows {
    axis: Axis,
    per_row: usize,
    segments: Vec<[f32; 2]>,
}

impl TableRows {
    fn new(lo: f64, hi: f64, n: usize, rows: usize, f: impl Fn(usize, f64) -> f64) -> Self {
        let tables: Vec<Table1> = (0..rows)
            .map(|k| Table1::new(lo, hi, n, |x| f(k, x)))
            .collect();
        Self {
            axis: tables[0].axis,
            per_row: n - 1,
            segments: tables.into_iter().flat_map(|t| t.segments).collect(),
        }
    }

    /// Row `row` at a point located on `self.axis`.
    #[inline(always)]
    fn at(&self, row: usize, p: Point) -> f32 {
        let [value, rise] = self.segments[row * self.per_row + p.segment];
        value + p.weight * rise
    }
}

/// The Newton-Raphson `u*` of a saltating surface as a function of the wind at `z_r`.
#[derive(Debug, Clone, PartialEq)]
pub struct ShearTable {
    key: (f64, f64),
    table: Table1,
    max_wind: f64,
}

impl ShearTable {
    /// Tabulates `u*(u_r)` for the parameters' `z_r` (Eqs. 5.30-5.36).
    pub fn new(params: &TransportParams) -> Self {
        let z_r = params.reference_height_m;
        let z0 = params.snow_roughness_m;
        // The strongest wind (to 0.1 m/s) with a solution: solutions exist below a limit.
        let mut max_wind = MAX_WIND;
        while max_wind > 0.1 && saltating_friction_velocity(max_wind, z_r, z0).is_none() {
            max_wind -= 0.1;
        }
        let solve = |w: f64| saltating_friction_velocity(w, z_r, z0).map_or(0.0, |s| s.0);
        Self {
            key: (z_r, z0),
            table: Table1::new(0.0, max_wind, SHEAR_SAMPLES, solve),
            max_wind,
        }
    }

    /// The strongest tabulated wind, m s⁻¹.
    pub fn max_wind(&self) -> f64 {
        self.max_wind
    }

    /// Saltating friction velocity for a wind `u_r`, m s⁻¹.
    #[inline(always)]
    pub fn saltating_u_star(&self, u_r: f32) -> f32 {
        self.table.at(u_r)
    }

    fn fresh_for(&self, params: &TransportParams) -> bool {
        self.key == (params.reference_height_m, params.snow_roughness_m)
    }
}

/// The atmosphere of a weather period at the parameters' latitude (Annex I).
pub fn atmosphere(params: &TransportParams, weather: &Weather) -> Atmosphere {
    let sin_elev = sin_solar_elevation(
        params.latitude_deg,
        weather.day_of_year,
        weather.hour_angle_deg,
    );
    Atmosphere {
        t_k: weather.air_temperature_k(),
        rh: weather.relative_humidity_pct / 100.0,
        z_rh: params.humidity_height_m,
        irradiance: surface_irradiance(sin_elev, weather.cloud_cover_pct / 100.0),
    }
}

/// Suspension and sublimation per unit saltation flux, for one weather period, on one
/// `u*` sampling, so a lookup locates `u*` once.
#[derive(Debug, Clone, PartialEq)]
pub struct BlowingSnowTable {
    key: (Atmosphere, f64, usize, f64),
    suspension: Table1,
    /// `V(u*) + ψs(u*, u*t)` over `(u*, u*t)`, one row per sampled `u*t`, on the sampling
    /// of `suspension`.
    sublimation: TableRows,
    u_star_t_axis: Axis,
}

impl BlowingSnowTable {
    /// Tabulates `S(u*)` and `V(u*) + ψs(u*, u*t)` (Eqs. 5.40-5.47, Annex I).
    pub fn new(params: &TransportParams, weather: &Weather, max_u_star: f64) -> Self {
        let atm = atmosphere(params, weather);
        let s = params.settling_velocity;
        let n = params.integration_samples;
        let hi = max_u_star.max(MIN_U_STAR + 0.1);
        let step = (hi - MIN_U_STAR) / (PROFILE_SAMPLES - 1) as f64;
        let profiles: Vec<_> = (0..PROFILE_SAMPLES)
            .map(|i| {
                let u = MIN_U_STAR + i as f64 * step;
                let p = blowing_snow_profile(u, s, n, &atm);
                let h = saltation_height(u);
                (p.suspension / h, p.sublimation / h)
            })
            .collect();
        // The samples of `Table1::new` and `TableRows::new` fall at these same `u*`.
        let sample = |u: f64| (((u - MIN_U_STAR) / step).round() as usize).min(PROFILE_SAMPLES - 1);
        let suspension = Table1::new(MIN_U_STAR, hi, PROFILE_SAMPLES, |u| profiles[sample(u)].0);
        let t_step = MAX_U_STAR_T / (THRESHOLD_SAMPLES - 1) as f64;
        let sublimation = TableRows::new(
            MIN_U_STAR,
            hi,
            PROFILE_SAMPLES,
            THRESHOLD_SAMPLES,
            |k, u| profiles[sample(u)].1 + saltation_layer_loss_rate(u, k as f64 * t_step, &atm),
        );
        Self {
            key: (atm, s, n, hi),
            suspension,
            sublimation,
            u_star_t_axis: Axis::new(0.0, t_step, THRESHOLD_SAMPLES),
        }
    }

    /// `S(u*) = Qsusp u_p / Qsalt`, m s⁻¹, and `V(u*) + ψs(u*, u*t) = Qsubl u_p / Qsalt`,
    /// s⁻¹ (≤ 0).
    #[inline(always)]
    pub fn per_flux(&self, u_star: f32, u_star_t: f32) -> (f32, f32) {
        let p = self.suspension.axis().locate(u_star);
        let t = self.u_star_t_axis.locate(u_star_t);
        let a = self.sublimation.at(t.segment, p);
        let b = self.sublimation.at(t.segment + 1, p);
        (self.suspension.at_point(p), a + t.weight * (b - a))
    }

    fn fresh_for(&self, params: &TransportParams, weather: &Weather, max_u_star: f64) -> bool {
        let hi = max_u_star.max(MIN_U_STAR + 0.1);
        self.key
            == (
                atmosphere(params, weather),
                params.settling_velocity,
                params.integration_samples,
                hi,
            )
    }
}

/// Both tables, rebuilt lazily.
#[derive(Debug, Clone, Default)]
pub struct Tables {
    shear: Option<ShearTable>,
    blowing: Option<BlowingSnowTable>,
}

impl Tables {
    /// The tables for these parameters and weather, rebuilding what is stale.
    pub fn update(
        &mut self,
        params: &TransportParams,
        weather: &Weather,
    ) -> (&ShearTable, &BlowingSnowTable) {
        if !self.shear.as_ref().is_some_and(|t| t.fresh_for(params)) {
            self.shear = Some(ShearTable::new(params));
        }
        let shear = self.shear.as_ref().expect("just built");
        let max_u = f64::from(shear.saltating_u_star(shear.max_wind() as f32));
        if !self
            .blowing
            .as_ref()
            .is_some_and(|t| t.fresh_for(params, weather, max_u))
        {
            self.blowing = Some(BlowingSnowTable::new(params, weather, max_u));
        }
        (shear, self.blowing.as_ref().expect("just built"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::suspension::{blowing_snow_fluxes, particle_speed};

    #[test]
    fn shear_table_matches_newton_raphson() {
        let p = TransportParams::default();
        let t = ShearTable::new(&p);
        assert!(
            t.max_wind() > 45.0 && t.max_wind() < 55.0,
            "{}",
            t.max_wind()
        );
        for w in [1.0, 3.3, 7.0, 11.0, 25.0, 40.0] {
            let direct = saltating_friction_velocity(w, 5.0, p.snow_roughness_m)
                .unwrap()
                .0;
            let tab = f64::from(t.saltating_u_star(w as f32));
            assert!(
                (tab / direct - 1.0).abs() < 2e-3,
                "W {w}: {tab} vs {direct}"
            );
        }
    }

    #[test]
    fn blowing_snow_table_matches_direct_integrals() {
        let p = TransportParams::default();
        let w = Weather {
            relative_humidity_pct: 40.0,
            ..Default::default()
        };
        let mut tables = Tables::default();
        let (_, b) = tables.update(&p, &w);
        let atm = atmosphere(&p, &w);
        for (u, ut) in [(0.3, 0.15), (0.5, 0.25), (0.9, 0.3), (1.5, 0.5)] {
            let (qs, qv) = blowing_snow_fluxes(0.01, u, ut, 0.3, 40, &atm);
            let up = particle_speed(ut);
            let (s, v) = b.per_flux(u as f32, ut as f32);
            let (qs_tab, qv_tab) = (0.01 / up * f64::from(s), 0.01 / up * f64::from(v));
            assert!((qs_tab / qs - 1.0).abs() < 5e-3, "u* {u}: {qs_tab} vs {qs}");
            assert!((qv_tab / qv - 1.0).abs() < 5e-3, "u* {u}: {qv_tab} vs {qv}");
        }
    }

    #[test]
    fn tables_are_rebuilt_when_the_weather_changes() {
        let p = TransportParams::default();
        let mut tables = Tables::default();
        let dry = tables
            .update(&p, &Weather::default())
            .1
            .per_flux(0.5, 0.2)
            .1;
        let wet_weather = Weather {
            relative_humidity_pct: 100.0,
            cloud_cover_pct: 100.0,
            hour_angle_deg: 180.0,
            ..Default::default()
        };
        let wet = tables.update(&p, &wet_weather).1.per_flux(0.5, 0.2).1;
        assert!(dry < 0.0);
        assert_eq!(wet, 0.0);
    }
}
