//! User parameters of the transport model (Jubert 2018, Table 6.I) and the weather that
//! drives it, as plain structs with units and cited defaults. Scenario files (TOML) map
//! 1:1 onto them; unknown keys are errors.
//!
//! Table 6.I swaps two symbols with respect to Section 5.4: it calls the latitude η and the
//! curvature length ν, while Eq. 5.9 uses η for the curvature length. The names here are
//! in words (`latitude_deg`, `curvature_length_m`), so the clash disappears. The table also
//! prints the precipitation rate as "1.5 m s⁻¹", which cannot be a snowfall rate; Table 7.I
//! gives 0.75 cm h⁻¹. Here `P` is a water-equivalent rate in mm h⁻¹ (Eq. 5.16 multiplies it
//! by the density of water ρw).

use crate::error::{TransportError, check_positive, check_range};
use serde::{Deserialize, Serialize};
use snowscape_terrain::timeline::{
    TimeUnit, TimelinePeriod, check_timeline, next_start_after, period_index_at,
};

/// Which phenomena of Eq. 5.16 take part, so the ablations of Figs. 7.6-7.8 can be run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct Phenomena {
    /// Snowfall `ρw P` (Eq. 5.16).
    pub precipitation: bool,
    /// Saltation transport (Section 5.5.3). When off, saltation still sets the reference
    /// concentration of suspension and sublimation (Section 7.1.2: "la saltation détermine
    /// le taux de suspension ainsi que le taux de sublimation"); only its own divergence is
    /// left out of the mass balance.
    pub saltation: bool,
    /// Suspension transport (Section 5.5.4).
    pub suspension: bool,
    /// Sublimation of blowing snow (Section 5.5.5, Annex I).
    pub sublimation: bool,
    /// Degree-day melt (Section 5.5.6).
    pub melt: bool,
    /// Density evolution without snowfall (Eq. 5.21).
    pub densification: bool,
}

impl Default for Phenomena {
    fn default() -> Self {
        Self {
            precipitation: true,
            saltation: true,
            suspension: true,
            sublimation: true,
            melt: true,
            densification: true,
        }
    }
}

/// Static parameters of a transport run (Table 6.I and the constants of Section 5.5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct TransportParams {
    /// Height above the ground at which the wind is measured, `z_r`, m. Table 6.I: 5 m.
    pub reference_height_m: f64,
    /// Weight of the slope on the wind, `γp` (Eq. 5.11). Table 6.I: 0.45.
    pub slope_weight: f64,
    /// Weight of the curvature on the wind, `γc` (Eq. 5.11). Table 6.I: 0.55. Eq. 5.12 asks
    /// `γp + γc = 1`; it is not enforced (Liston's MicroMet uses 0.5 and 0.5 too).
    pub curvature_weight: f64,
    /// Curvature length scale `η` of Eq. 5.9 (ν in Table 6.I), m: the typical distance
    /// between a crest and the next valley bottom. Table 6.I: 50 m.
    pub curvature_length_m: f64,
    /// Latitude of the scene, degrees north (Annex I, Eq. I.21). Table 6.I: 45.5°.
    pub latitude_deg: f64,
    /// Degree-day melt factor `C_M`, mm of snow depth per °C per day (Eq. 5.48).
    /// Table 6.I: 1.6 (Table 7.I uses 3.2).
    pub melt_factor_mm_per_degc_day: f64,
    /// Melt reference temperature `T_b`, °C (Eq. 5.48). Table 6.I: 0 °C.
    pub melt_base_temperature_c: f64,
    /// Snow depth held by the vegetation `C_v`, m (Eq. 5.27): snow below it cannot blow.
    /// Table 6.I: 0.05 m.
    pub vegetation_snow_depth_m: f64,
    /// Roughness length of the vegetation `z0_veg`, m (Eq. 5.28). Table 6.I: 0.05 m.
    pub vegetation_roughness_m: f64,
    /// Roughness length of a snow surface without saltation `z0_neige`, m (Eq. 5.28).
    /// Not in the thesis's tables; chosen here: 0.001 m, smooth snow.
    pub snow_roughness_m: f64,
    /// Height of the relative-humidity observation `z_rh`, m (Eqs. I.12-I.13).
    /// Not in the thesis's tables; chosen here: 2 m, a screen-level observation.
    pub humidity_height_m: f64,
    /// Equilibrium fetch `f`, m (Eq. 5.39). Section 5.5.3 after Liston & Sturm 1998: 300 m.
    pub fetch_m: f64,
    /// Fetch scaling constant `μ` (Eq. 5.39). Section 5.5.3: 3.
    pub fetch_scale: f64,
    /// Air density `ρa`, kg m⁻³ (Eq. 5.37). Liston & Sturm 1998: 1.275.
    pub air_density: f64,
    /// Settling velocity of suspended snow `s`, m s⁻¹ (Eq. 5.41). Section 5.5.4: 0.3.
    pub settling_velocity: f64,
    /// Number of samples of the Riemann sums of Eqs. 5.40 and 5.46 (Eqs. 6.3-6.4).
    /// Not given in the thesis; chosen here: 40.
    pub integration_samples: usize,
    /// Whether enough snow lies outside the domain to enter it at saturation (Section
    /// 5.5.3: "l'utilisateur peut spécifier si il y a assez de neige en dehors du domaine").
    /// `true`: saltation enters upwind borders at `Qs_max`; `false`: at 0.
    pub saturated_inflow: bool,
    /// Time step `Δt`, s (Eq. 5.17). Table 6.I: 300 s.
    pub time_step_s: f64,
    /// Switches of the phenomena.
    pub phenomena: Phenomena,
}

impl Default for TransportParams {
    fn default() -> Self {
        Self {
            reference_height_m: 5.0,
            slope_weight: 0.45,
            curvature_weight: 0.55,
            curvature_length_m: 50.0,
            latitude_deg: 45.5,
            melt_factor_mm_per_degc_day: 1.6,
            melt_base_temperature_c: 0.0,
            vegetation_snow_depth_m: 0.05,
            vegetation_roughness_m: 0.05,
            snow_roughness_m: 0.001,
            humidity_height_m: 2.0,
            fetch_m: 300.0,
            fetch_scale: 3.0,
            air_density: 1.275,
            settling_velocity: 0.3,
            integration_samples: 40,
            saturated_inflow: false,
            time_step_s: 300.0,
            phenomena: Phenomena::default(),
        }
    }
}

impl TransportParams {
    /// Checks every parameter is finite and in its physical range.
    pub fn validate(&self) -> Result<(), TransportError> {
        check_positive("reference_height_m", self.reference_height_m)?;
        check_range("slope_weight", self.slope_weight, 0.0, 10.0)?;
        check_range("curvature_weight", self.curvature_weight, 0.0, 10.0)?;
        check_positive("curvature_length_m", self.curvature_length_m)?;
        check_range("latitude_deg", self.latitude_deg, -90.0, 90.0)?;
        check_range(
            "melt_factor_mm_per_degc_day",
            self.melt_factor_mm_per_degc_day,
            0.0,
            1000.0,
        )?;
        check_range(
            "melt_base_temperature_c",
            self.melt_base_temperature_c,
            -50.0,
            50.0,
        )?;
        check_range(
            "vegetation_snow_depth_m",
            self.vegetation_snow_depth_m,
            0.0,
            100.0,
        )?;
        check_positive("vegetation_roughness_m", self.vegetation_roughness_m)?;
        check_positive("snow_roughness_m", self.snow_roughness_m)?;
        if self.snow_roughness_m >= self.reference_height_m
            || self.vegetation_roughness_m >= self.reference_height_m
        {
            return Err(TransportError::InvalidParameter {
                name: "reference_height_m",
                value: self.reference_height_m,
                reason: "must be above the roughness lengths",
            });
        }
        check_positive("humidity_height_m", self.humidity_height_m)?;
        check_positive("fetch_m", self.fetch_m)?;
        check_positive("fetch_scale", self.fetch_scale)?;
        check_positive("air_density", self.air_density)?;
        check_positive("settling_velocity", self.settling_velocity)?;
        check_range(
            "integration_samples",
            self.integration_samples as f64,
            1.0,
            10_000.0,
        )?;
        check_positive("time_step_s", self.time_step_s)?;
        Ok(())
    }
}

/// The weather of one period of the timeline (Tables 6.I and 7.I).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Weather {
    /// Start of this period in the timeline, hours from the start of the run.
    pub from_hour: f64,
    /// Water-equivalent precipitation rate `P`, mm h⁻¹ (Eq. 5.16). Table 7.I: 0.75 cm h⁻¹
    /// during 12 h, then 0; default 0.
    pub precipitation_mm_per_h: f64,
    /// Air temperature `T_a`, °C. Table 7.I: −5 °C during 12 h, then +10 °C; default −5.
    pub air_temperature_c: f64,
    /// Relative humidity `RH` at `z_rh`, % (Eq. I.12). Table 6.I: 25 % (Table 7.I: 40 %).
    pub relative_humidity_pct: f64,
    /// Cloud cover `σc`, % (Eq. I.23). Table 6.I: 15 % (Table 7.I: 0 %).
    pub cloud_cover_pct: f64,
    /// Solar hour angle `τ`, degrees (Eq. I.21), 0 at solar noon. Table 6.I: −35°.
    pub hour_angle_deg: f64,
    /// Day of the year `d` (Eq. I.22). Table 6.I: 1st January, 1.
    pub day_of_year: f64,
    /// Wind speed at `z_r` where no wind field is given, m s⁻¹ (inflow of the 3D wind).
    /// Table 7.I: 11 m s⁻¹ (castle); default 0.
    pub wind_speed_m_s: f64,
    /// Direction the wind blows from, degrees clockwise from north (θ of Eqs. 5.1-5.4).
    /// Table 7.I: a west wind, 270°.
    pub wind_from_deg: f64,
}

impl Default for Weather {
    fn default() -> Self {
        Self {
            from_hour: 0.0,
            precipitation_mm_per_h: 0.0,
            air_temperature_c: -5.0,
            relative_humidity_pct: 25.0,
            cloud_cover_pct: 15.0,
            hour_angle_deg: -35.0,
            day_of_year: 1.0,
            wind_speed_m_s: 0.0,
            wind_from_deg: 270.0,
        }
    }
}

impl Weather {
    /// Checks every field is finite and in its physical range.
    pub fn validate(&self) -> Result<(), TransportError> {
        check_range("from_hour", self.from_hour, 0.0, f64::MAX)?;
        check_range(
            "precipitation_mm_per_h",
            self.precipitation_mm_per_h,
            0.0,
            1000.0,
        )?;
        check_range("air_temperature_c", self.air_temperature_c, -90.0, 60.0)?;
        check_range(
            "relative_humidity_pct",
            self.relative_humidity_pct,
            0.0,
            100.0,
        )?;
        check_range("cloud_cover_pct", self.cloud_cover_pct, 0.0, 100.0)?;
        check_range("hour_angle_deg", self.hour_angle_deg, -180.0, 180.0)?;
        check_range("day_of_year", self.day_of_year, 1.0, 366.0)?;
        check_range("wind_speed_m_s", self.wind_speed_m_s, 0.0, 100.0)?;
        check_range("wind_from_deg", self.wind_from_deg, -360.0, 360.0)?;
        Ok(())
    }

    /// Air temperature in kelvin.
    pub fn air_temperature_k(&self) -> f64 {
        self.air_temperature_c + crate::physics::FREEZING_K
    }

    /// Precipitation as a water-equivalent rate in m s⁻¹ (the `P` of Eq. 5.16).
    pub fn precipitation_m_per_s(&self) -> f64 {
        self.precipitation_mm_per_h * 1e-3 / 3600.0
    }
}

/// A piecewise-constant weather timeline: each period lasts until the next one starts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Timeline(pub Vec<Weather>);

impl TimelinePeriod for Weather {
    const UNIT: TimeUnit = TimeUnit::Hours;
    const START_KEY: &'static str = "from_hour";
    fn start(&self) -> f64 {
        self.from_hour
    }
}

impl Timeline {
    /// Checks the periods are valid and form a timeline: they start at hour 0 and at strictly
    /// increasing hours (`snowscape_terrain::timeline`, the rule a season's weather follows).
    pub fn validate(&self) -> Result<(), TransportError> {
        for w in &self.0 {
            w.validate()?;
        }
        check_timeline(&self.0, false).map_err(|e| TransportError::Timeline {
            index: e.index,
            from_hour: e.start,
            reason: e.reason,
        })
    }

    /// The weather in force at `hour` (the last period starting at or before it).
    pub fn at(&self, hour: f64) -> &Weather {
        &self.0[period_index_at(&self.0, hour).unwrap_or(0)]
    }

    /// Start of the next period after `hour`, h (`None` in the last one).
    pub fn next_start_after(&self, hour: f64) -> Option<f64> {
        next_start_after(&self.0, hour)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_table_6_1_and_valid() {
        let p = TransportParams::default();
        p.validate().unwrap();
        assert_eq!(p.reference_height_m, 5.0);
        assert_eq!(p.slope_weight + p.curvature_weight, 1.0); // Eq. 5.12
        assert_eq!(p.time_step_s, 300.0);
        Weather::default().validate().unwrap();
    }

    #[test]
    fn unknown_keys_are_rejected_with_their_name() {
        let err = toml::from_str::<TransportParams>("reference_hieght_m = 3.0").unwrap_err();
        assert!(err.to_string().contains("reference_hieght_m"), "{err}");
        let ok: TransportParams =
            toml::from_str("fetch_m = 150.0\n[phenomena]\nmelt = false").unwrap();
        assert_eq!(ok.fetch_m, 150.0);
        assert!(!ok.phenomena.melt && ok.phenomena.saltation);
    }

    #[test]
    fn invalid_values_name_the_parameter() {
        let p = TransportParams {
            fetch_m: -1.0,
            ..Default::default()
        };
        match p.validate() {
            Err(TransportError::InvalidParameter { name, value, .. }) => {
                assert_eq!((name, value), ("fetch_m", -1.0));
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn timeline_picks_the_period_in_force() {
        let t = Timeline(vec![
            Weather::default(),
            Weather {
                from_hour: 12.0,
                air_temperature_c: 10.0,
                ..Default::default()
            },
        ]);
        t.validate().unwrap();
        assert_eq!(t.at(0.0).air_temperature_c, -5.0);
        assert_eq!(t.at(11.99).air_temperature_c, -5.0);
        assert_eq!(t.at(12.0).air_temperature_c, 10.0);
        assert_eq!(t.at(100.0).air_temperature_c, 10.0);
        let unsorted = Timeline(vec![t.0[1].clone(), t.0[0].clone()]);
        assert!(unsorted.validate().is_err());
    }
}
