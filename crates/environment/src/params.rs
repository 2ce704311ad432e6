//! Parameters of the environment precompute, one struct per phenomenon, with units and cited
//! defaults. A scenario file maps onto them 1:1, e.g.
//!
//! ```toml
//! [environment.sun]
//! latitude_deg = 46.5
//! start_day = 1
//! [environment.wind]
//! direction_deg = 300.0
//! ```
//!
//! Cordonnier et al. 2018 Table 2 is misaligned in the text extraction; the values below follow
//! `docs/src/model.md#sources-and-the-reading-of-table-2`, which reads it by units. Constants the paper leaves open are marked as our
//! choices, with the reason.

use crate::error::check_param;
use crate::{DeclinationModel, EnvironmentError};
use serde::{Deserialize, Serialize};

/// Direct sunlight (Cordonnier 2018, Section 4.1, `I_sun = k_sun Σ_h s_h n·i_h`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct SunParams {
    /// Latitude, degrees north (negative south), in [-90, 90]. Default 45: between the paper's
    /// sites, Steens Mountain (42.6° N) and Glacier National Park (48.7° N) (Section 8).
    pub latitude_deg: f64,
    /// First day of the sampled period, day of year in 1..=365. Default 335 (1 December): our
    /// choice, the start of the winter the simulation covers.
    pub start_day: u32,
    /// Number of days in the period (>= 1). Default 120 (December to March): our choice.
    pub num_days: u32,
    /// Sample every `day_step`-th day of the period (>= 1). Default 15: the sun path changes
    /// little in two weeks; our choice, it keeps the precompute within its time budget.
    pub day_step: u32,
    /// Sun positions per hour of solar time (1..=60). Default 1: the paper's hourly positions
    /// ("sun position at hour h", Section 4.1).
    pub samples_per_hour: u32,
    /// Declination formula. Default Spencer 1971.
    pub declination: DeclinationModel,
    /// Amount of direct illumination, dimensionless (>= 0). Default 0.9: Cordonnier 2018
    /// Table 2 (`k_sun`, printed "0.9 h"; our sum already carries the hours).
    pub k_sun: f64,
}

impl Default for SunParams {
    fn default() -> Self {
        Self {
            latitude_deg: 45.0,
            start_day: 335,
            num_days: 120,
            day_step: 15,
            samples_per_hour: 1,
            declination: DeclinationModel::Spencer,
            k_sun: 0.9,
        }
    }
}

/// Ambient (sky) light (Cordonnier 2018, Section 4.1, `I_sky = k_sky π/N Σ cos² φ_i`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct SkyParams {
    /// Number of horizon directions N (4..=360), evenly spaced clockwise from north.
    /// Default 16: the issue's default (16 or 32); SAGA's Sky View Factor uses 8.
    pub directions: u32,
    /// Amount of ambient illumination, hours per day per unit projected solid angle (>= 0);
    /// an open flat cell gets `k_sky·π`. Default 0.1: Cordonnier 2018 Table 2 (`k_sky`).
    pub k_sky: f64,
}

impl Default for SkyParams {
    fn default() -> Self {
        Self {
            directions: 16,
            k_sky: 0.1,
        }
    }
}

/// One indirect bounce of sunlight (Cordonnier 2018, Section 4.1, `I_ind`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct BounceParams {
    /// Amount of indirect illumination, dimensionless (0..=1: the senders' albedo). Default
    /// 0.9: Cordonnier 2018 Table 2 (`k_ind`), the albedo of fresh snow. The sum is divided by
    /// π (Lambertian form factor), which the paper's formula leaves out.
    pub k_ind: f64,
    /// Polar sample directions per cell (1..=64). Default 8: our choice (bounded cost).
    pub directions: u32,
    /// Sample radii per direction (1..=16), spaced geometrically. Default 4: our choice.
    pub radii: u32,
    /// Smallest sample radius, metres (> 0; raised to one cell size). Default 10 m: our choice.
    pub min_radius_m: f64,
    /// Largest sample radius `r_max`, metres (>= min_radius_m). Default 200 m: our choice, a
    /// valley side; the paper leaves `r_max` open.
    pub max_radius_m: f64,
    /// Seed of the per-cell rotation of the sample directions ("random directions θ_i").
    pub seed: u64,
}

impl Default for BounceParams {
    fn default() -> Self {
        Self {
            k_ind: 0.9,
            directions: 8,
            radii: 4,
            min_radius_m: 10.0,
            max_radius_m: 200.0,
            seed: 0,
        }
    }
}

/// Temperature (Cordonnier 2018, Section 4.1, `T = T0 + kt·A + ki·I`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct TemperatureParams {
    /// Sea-level temperature T0, °C. Default 0 °C: user-set in the paper (Table 2 gives none).
    pub t0_c: f64,
    /// Temperature change with altitude kt, °C per m. Default -0.01: Cordonnier 2018 Table 2.
    pub kt: f64,
    /// Temperature increase per daylight hour of sun ki, °C per (h/day). Default 0.41:
    /// Cordonnier 2018 Table 2 (10 °C for 24 h of sun, Section 4.1).
    pub ki: f64,
}

impl Default for TemperatureParams {
    fn default() -> Self {
        Self {
            t0_c: 0.0,
            kt: -0.01,
            ki: 0.41,
        }
    }
}

/// Wind (Cordonnier 2018, Section 4.2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct WindParams {
    /// Direction the dominant wind blows FROM, degrees clockwise from north (meteorological
    /// convention: 270 = westerly, blowing towards the east). Default 270: our choice, the
    /// prevailing mid-latitude westerlies.
    pub direction_deg: f64,
    /// Wind strength at sea level |Wd|, m/s (>= 0). Default 10: Cordonnier 2018 Table 2.
    pub speed_m_s: f64,
    /// Venturi speed-up with altitude kventuri, per m. Default 1e-3: Cordonnier 2018 Table 2.
    pub k_venturi: f64,
    /// Altitude at which the wind blows at `|Wd|`, metres: the Venturi term is
    /// `1 + kventuri·(A − venturi_base_m)`. The paper measures from sea level (`0`); the
    /// default (unset) is the lowest valid altitude of the terrain, chosen here because on high
    /// terrain the paper's kventuri triples the wind at 2000 m, and the wind-effect surface
    /// then detaches at almost every convexity (its curvature threshold is c/|W|²): on the
    /// avaMal DEM (1330-2900 m) sea level puts 98 % of the cells in wind shadow.
    pub venturi_base_m: Option<f64>,
    /// Topography effect on wind kterrain, dimensionless. Default 0.5: Cordonnier 2018 Table 2.
    pub k_terrain: f64,
    /// Decrease of the wind-effect surface's vertical speed c, m/s² (> 0). The paper sets it
    /// "experimentally" to 0.7 (Cordonnier 2018 §4.2, Table 2) on its own terrains; the cap
    /// behind a crest reattaches after a distance ∝ |W|²/c, and with the Venturi speed-up on
    /// real alpine DEMs 0.7 puts 88 % of avaMal (5 m cells, 1330-2900 m, wind from 300°) in wind
    /// shadow, leaving almost no windward surface to scour. Default chosen here: 3.0, which
    /// shadows about half of avaMal — its lee-facing share — so crests are scoured and
    /// cornices form just past them.
    pub c_m_s2: f64,
    /// Wind shadow where the wind-effect surface is more than this above the ground, metres
    /// (>= 0). Default 0.05 m: our choice, above f32 round-off of altitudes up to 9 km.
    pub shadow_epsilon_m: f64,
    /// Gauss-Seidel sweeps in wind order run before the red-black iterations, cycling through
    /// the four row/column orders starting with the one that follows the wind (0 = start from
    /// the paper's `Wz = A`, `Wsz = W·∇A`). Default 1: our choice; the transport is along the
    /// dominant wind, so one sweep in its order solves the upwind system exactly
    /// (`wind::effect_surface`) and red-black then confirms it in one iteration.
    pub ordered_sweeps: u32,
    /// Most red-black Gauss-Seidel iterations (one red and one black half-sweep each).
    /// Default 2000: our choice; from the paper's start red-black needs about as many
    /// iterations as the longest chain of detached cells along the wind.
    pub max_iterations: u32,
    /// Stop when an iteration changes Wz by less than this anywhere, metres (> 0).
    /// Default 1e-3 m: our choice.
    pub tolerance_m: f64,
}

impl Default for WindParams {
    fn default() -> Self {
        Self {
            direction_deg: 270.0,
            speed_m_s: 10.0,
            k_venturi: 1e-3,
            venturi_base_m: None,
            k_terrain: 0.5,
            c_m_s2: 3.0,
            shadow_epsilon_m: 0.05,
            ordered_sweeps: 1,
            max_iterations: 2000,
            tolerance_m: 1e-3,
        }
    }
}

/// All parameters of the environment precompute.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct EnvironmentParams {
    /// Direct sunlight and the sampling schedule.
    pub sun: SunParams,
    /// Ambient sky light.
    pub sky: SkyParams,
    /// One indirect bounce.
    pub bounce: BounceParams,
    /// Temperature.
    pub temperature: TemperatureParams,
    /// Wind.
    pub wind: WindParams,
    /// Wind sheltering and exposure: the maximum upwind slope `Sx` (Winstral et al. 2002),
    /// computed for each weather period's wind.
    pub sheltering: crate::wind::ShelteringParams,
}

impl SunParams {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), EnvironmentError> {
        let lat = self.latitude_deg;
        check_param(
            "sun.latitude_deg",
            lat,
            lat.abs() <= 90.0,
            "must be in [-90, 90]",
        )?;
        let d = self.start_day as f64;
        check_param(
            "sun.start_day",
            d,
            (1.0..=365.0).contains(&d),
            "must be in 1..=365",
        )?;
        let n = self.num_days as f64;
        check_param(
            "sun.num_days",
            n,
            (1.0..=3660.0).contains(&n),
            "must be in 1..=3660",
        )?;
        let s = self.day_step as f64;
        check_param(
            "sun.day_step",
            s,
            (1.0..=366.0).contains(&s),
            "must be in 1..=366",
        )?;
        let p = self.samples_per_hour as f64;
        check_param(
            "sun.samples_per_hour",
            p,
            (1.0..=60.0).contains(&p),
            "must be in 1..=60",
        )?;
        check_param(
            "sun.k_sun",
            self.k_sun,
            (0.0..=10.0).contains(&self.k_sun),
            "must be in [0, 10]",
        )
    }
}

impl SkyParams {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), EnvironmentError> {
        let n = self.directions as f64;
        check_param(
            "sky.directions",
            n,
            (4.0..=360.0).contains(&n),
            "must be in 4..=360",
        )?;
        check_param(
            "sky.k_sky",
            self.k_sky,
            (0.0..=10.0).contains(&self.k_sky),
            "must be in [0, 10]",
        )
    }
}

impl BounceParams {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), EnvironmentError> {
        let k = self.k_ind;
        check_param(
            "bounce.k_ind",
            k,
            (0.0..=1.0).contains(&k),
            "must be in [0, 1]",
        )?;
        let n = self.directions as f64;
        check_param(
            "bounce.directions",
            n,
            (1.0..=64.0).contains(&n),
            "must be in 1..=64",
        )?;
        let r = self.radii as f64;
        check_param(
            "bounce.radii",
            r,
            (1.0..=16.0).contains(&r),
            "must be in 1..=16",
        )?;
        let r0 = self.min_radius_m;
        check_param(
            "bounce.min_radius_m",
            r0,
            r0 > 0.0 && r0 <= 1e4,
            "must be in (0, 10000] m",
        )?;
        let r1 = self.max_radius_m;
        check_param(
            "bounce.max_radius_m",
            r1,
            r1 >= r0 && r1 <= 1e4,
            "must be in [min_radius_m, 10000] m",
        )
    }
}

impl TemperatureParams {
    /// Checks every field is finite.
    pub fn validate(&self) -> Result<(), EnvironmentError> {
        check_param(
            "temperature.t0_c",
            self.t0_c,
            self.t0_c.abs() <= 80.0,
            "must be in [-80, 80] °C",
        )?;
        check_param(
            "temperature.kt",
            self.kt,
            self.kt.abs() <= 0.1,
            "must be in [-0.1, 0.1] °C/m",
        )?;
        check_param(
            "temperature.ki",
            self.ki,
            self.ki.abs() <= 100.0,
            "must be in [-100, 100] °C per unit of insolation",
        )
    }
}

impl WindParams {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), EnvironmentError> {
        check_param(
            "wind.direction_deg",
            self.direction_deg,
            true,
            "must be finite",
        )?;
        let s = self.speed_m_s;
        check_param(
            "wind.speed_m_s",
            s,
            (0.0..=100.0).contains(&s),
            "must be in [0, 100] m/s",
        )?;
        check_param(
            "wind.k_venturi",
            self.k_venturi,
            self.k_venturi.abs() <= 0.1,
            "must be in [-0.1, 0.1] per m",
        )?;
        if let Some(base) = self.venturi_base_m {
            check_param(
                "wind.venturi_base_m",
                base,
                base.abs() <= 1e5,
                "must be a plausible altitude (|z| <= 100000 m)",
            )?;
        }
        check_param(
            "wind.k_terrain",
            self.k_terrain,
            self.k_terrain.abs() <= 100.0,
            "must be in [-100, 100]",
        )?;
        check_param(
            "wind.c_m_s2",
            self.c_m_s2,
            self.c_m_s2 > 0.0 && self.c_m_s2 <= 1000.0,
            "must be in (0, 1000] m/s²",
        )?;
        let e = self.shadow_epsilon_m;
        check_param(
            "wind.shadow_epsilon_m",
            e,
            (0.0..=1000.0).contains(&e),
            "must be in [0, 1000] m",
        )?;
        let o = self.ordered_sweeps as f64;
        check_param(
            "wind.ordered_sweeps",
            o,
            self.ordered_sweeps <= 16,
            "must be in 0..=16",
        )?;
        let m = self.max_iterations as f64;
        check_param(
            "wind.max_iterations",
            m,
            (1..=100_000).contains(&self.max_iterations),
            "must be in 1..=100000",
        )?;
        let t = self.tolerance_m;
        check_param(
            "wind.tolerance_m",
            t,
            t > 0.0 && t <= 100.0,
            "must be in (0, 100] m",
        )
    }
}

impl EnvironmentParams {
    /// Checks every parameter; the error names the first offending one.
    pub fn validate(&self) -> Result<(), EnvironmentError> {
        self.sun.validate()?;
        self.sky.validate()?;
        self.bounce.validate()?;
        self.temperature.validate()?;
        self.sheltering.validate()?;
        self.wind.validate()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_round_trip_through_json() {
        let p = EnvironmentParams::default();
        p.validate().unwrap();
        let text = serde_json::to_string(&p).unwrap();
        let back: EnvironmentParams = serde_json::from_str(&text).unwrap();
        assert_eq!(back, p);
        // Partial documents fill in defaults; unknown keys are rejected.
        let partial: EnvironmentParams =
            serde_json::from_str(r#"{"wind": {"direction_deg": 300.0}}"#).unwrap();
        assert_eq!(partial.wind.direction_deg, 300.0);
        assert_eq!(partial.wind.speed_m_s, 10.0);
        assert!(serde_json::from_str::<EnvironmentParams>(r#"{"wind": {"sped": 1}}"#).is_err());
    }

    #[test]
    fn bad_values_name_the_parameter() {
        let mut p = EnvironmentParams::default();
        p.sun.latitude_deg = 91.0;
        assert!(matches!(
            p.validate(),
            Err(EnvironmentError::InvalidParameter { name: "sun.latitude_deg", value, .. }) if value == 91.0
        ));
        let mut p = EnvironmentParams::default();
        p.wind.c_m_s2 = f64::NAN;
        assert!(matches!(
            p.validate(),
            Err(EnvironmentError::InvalidParameter {
                name: "wind.c_m_s2",
                ..
            })
        ));
        let mut p = EnvironmentParams::default();
        p.bounce.max_radius_m = 1.0;
        assert!(p.validate().is_err());
    }
}
