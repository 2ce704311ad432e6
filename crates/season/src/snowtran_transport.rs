//! Physical wind transport as the season's wind phenomenon: the SnowTran-3D mass balance of
//! Jubert 2018 (Section 5.5, Eqs. 5.16-5.17; Liston & Sturm 1998) driving Cordonnier's
//! layers, chosen by the scenario switch `[parameters.wind_transport] model = "snowtran"`.
//!
//! `d(ρs ζ)/dt = −∇·(Qsalt + Qsusp) + Qsubl`
//!
//! over the erodible snow only. Cordonnier's own phenomena keep snowfall and melt (their
//! terms of Eq. 5.16 are switched off here); the wind moves what Figure 10 of Cordonnier
//! 2018 lets it scour, the powder and the unstable snow; stable and compacted snow are the
//! bed. Per wind event:
//!
//! 1. the erodible snow becomes a SnowTran state of water equivalent
//!    `swe = ρe (P + U)` at one erodible density `ρe` (so volumes and masses convert
//!    without a packing term in the season's volume budget);
//! 2. the wind of the environment precompute (Cordonnier §4.2, towards east and north at
//!    the surface) drives [`snowscape_transport::step::step`] in sub-steps of at most
//!    `max_substep_s`, with the hour angle following the simulated time of day, the air
//!    temperature the mean of the temperature map over the snow, and the humidity and cloud
//!    cover of these parameters;
//! 3. the change of `swe` goes back to the layers: a loss takes powder first, then unstable
//!    snow; a gain lands as powder. Sublimation and the net flux across the grid border are
//!    the only volume changes, reported to the season budget.

use crate::VolumeChange;
use crate::phenomenon::{PhenomenonError, check_dt, check_range};
use serde::{Deserialize, Serialize};
use snowscape_terrain::{LayeredTerrain, SnowLayer};
use snowscape_transport::step::{SceneMaps, SnowState, StepScratch, step};
use snowscape_transport::{Phenomena, TransportParams, Weather};

/// Parameters of the physical wind transport in a season.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct SnowTranParams {
    /// Density of the erodible snow (powder and unstable), kg m⁻³. Chosen here: 150, between
    /// Jubert 2018 Eq. 5.18's new snow at −5 °C (≈ 104) and wind-packed snow (Eq. 5.19).
    pub erodible_density: f64,
    /// Relative humidity at `z_rh`, % (Annex I, Eq. I.12). Table 6.I: 25 %; chosen here 70 %,
    /// a winter mean in the Alps.
    pub relative_humidity_pct: f64,
    /// Cloud cover, % (Eq. I.23). Table 6.I: 15 %.
    pub cloud_cover_pct: f64,
    /// Longest transport sub-step, s. Table 6.I steps 300 s; a season's wind events last
    /// hours to days, and the step's positivity limiter keeps any step stable. Chosen here:
    /// 3600 s.
    pub max_substep_s: f64,
    /// The SnowTran-3D parameters (Table 6.I); precipitation and melt are always off here
    /// (Cordonnier's snowfall and melt handle them), the latitude comes from the season.
    pub transport: TransportParams,
}

impl Default for SnowTranParams {
    fn default() -> Self {
        Self {
            erodible_density: snowscape_terrain::SnowLayer::Powder.default_density_kg_m3(),
            relative_humidity_pct: 70.0,
            cloud_cover_pct: 15.0,
            max_substep_s: 3600.0,
            transport: TransportParams::default(),
        }
    }
}

impl SnowTranParams {
    /// Checks the coupling's own values and the transport parameters.
    pub fn validate(&self) -> Result<(), PhenomenonError> {
        let bad = |name, value, reason| PhenomenonError::InvalidParameter {
            phenomenon: "snowtran wind transport",
            name,
            value,
            reason,
        };
        if !(self.erodible_density.is_finite()
            && self.erodible_density >= 1.0
            && self.erodible_density <= 917.0)
        {
            return Err(bad(
                "erodible_density",
                self.erodible_density,
                "a snow density between 1 and 917 kg/m³",
            ));
        }
        for (name, v) in [
            ("relative_humidity_pct", self.relative_humidity_pct),
            ("cloud_cover_pct", self.cloud_cover_pct),
        ] {
            if !(v.is_finite() && (0.0..=100.0).contains(&v)) {
                return Err(bad(name, v, "a percentage in [0, 100]"));
            }
        }
        check_range(
            "snowtran wind transport",
            "max_substep_s",
            self.max_substep_s,
            [60.0, 86_400.0],
            " s",
        )?;
        Ok(self.transport.validate()?)
    }
}

/// What the season's conditions are during a wind event.
#[derive(Debug, Clone, Copy)]
pub struct SnowTranForcing<'a> {
    /// Wind towards the east, m s⁻¹, per cell (the environment precompute).
    pub wind_u: &'a [f32],
    /// Wind towards the north, m s⁻¹, per cell.
    pub wind_v: &'a [f32],
    /// Air temperature, °C, per cell.
    pub temperature: &'a [f32],
    /// Latitude, degrees north.
    pub latitude_deg: f64,
    /// Day of the year at the start of the event.
    pub day_of_year: f64,
    /// Time of the event's start, days from the season's start (for the time of day).
    pub start_day: f64,
}

/// Volumes of one physical wind event, m³ of snow.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SnowTranReport {
    /// Snow removed from cells by the wind (sum of the losses).
    pub eroded: f64,
    /// Snow laid down by the wind (sum of the gains).
    pub deposited: f64,
    /// Lost to sublimation of blowing snow.
    pub sublimated: f64,
    /// Blown out of the grid minus blown in.
    pub border_net_outflow: f64,
    /// Sub-steps taken.
    pub substeps: usize,
}

impl SnowTranReport {
    /// The event's volume budget.
    pub fn volume_change(&self) -> VolumeChange {
        VolumeChange {
            added: (-self.border_net_outflow).max(0.0),
            removed: self.sublimated + self.border_net_outflow.max(0.0),
        }
    }
}

/// Reusable buffers.
#[derive(Debug, Clone, Default)]
pub struct SnowTranScratch {
    step: StepScratch,
}

/// Moves the erodible snow with the physical wind over `dt_days`.
pub fn step_season(
    params: &SnowTranParams,
    terrain: &mut LayeredTerrain,
    forcing: &SnowTranForcing,
    scratch: &mut SnowTranScratch,
    dt_days: f64,
) -> Result<SnowTranReport, PhenomenonError> {
    params.validate()?;
    check_dt(dt_days)?;
    let geometry = terrain.geometry().clone();
    let n = geometry.len();
    for (map, v) in [
        ("wind_u", forcing.wind_u),
        ("wind_v", forcing.wind_v),
        ("temperature", forcing.temperature),
    ] {
        crate::phenomenon::check_map(map, v, &geometry)?;
    }
    let mask = terrain.mask().clone();
    let rho = params.erodible_density as f32;
    let erodible: Vec<f32> = (0..n)
        .map(|i| {
            if mask.is_valid(i) {
                terrain.layer(SnowLayer::Powder)[i] + terrain.layer(SnowLayer::Unstable)[i]
            } else {
                0.0
            }
        })
        .collect();
    let mut state = SnowState {
        swe: erodible.iter().map(|d| d * rho).collect(),
        density: vec![rho; n],
    };
    // Nodata cells hold no snow and no wind.
    let masked = |v: &[f32]| -> Vec<f32> {
        (0..n)
            .map(|i| if mask.is_valid(i) { v[i] } else { 0.0 })
            .collect()
    };
    let (wind_u, wind_v) = (masked(forcing.wind_u), masked(forcing.wind_v));
    let (mut t_sum, mut t_n) = (0.0f64, 0usize);
    for (i, (&d, &t)) in erodible.iter().zip(forcing.temperature).enumerate() {
        if mask.is_valid(i) && d > 0.0 {
            t_sum += f64::from(t);
            t_n += 1;
        }
    }
    let mut transport = params.transport.clone();
    transport.latitude_deg = forcing.latitude_deg;
    transport.phenomena = Phenomena {
        precipitation: false,
        melt: false,
        densification: false,
        ..transport.phenomena
    };
    let scene = SceneMaps {
        geometry: &geometry,
        wind_u: &wind_u,
        wind_v: &wind_v,
        precipitation_ratio: None,
    };
    let total_s = dt_days * 86_400.0;
    let substeps = (total_s / params.max_substep_s).ceil().max(1.0) as usize;
    let dt = total_s / substeps as f64;
    let mut report = SnowTranReport {
        substeps,
        ..Default::default()
    };
    if t_n == 0 || total_s == 0.0 {
        return Ok(report);
    }
    let air = t_sum / t_n as f64;
    let (mut subl, mut border) = (0.0, 0.0);
    for s in 0..substeps {
        let day = forcing.start_day + (s as f64 + 0.5) * dt / 86_400.0;
        let weather = Weather {
            air_temperature_c: air.clamp(-90.0, 60.0),
            relative_humidity_pct: params.relative_humidity_pct,
            cloud_cover_pct: params.cloud_cover_pct,
            hour_angle_deg: 15.0 * ((day.rem_euclid(1.0)) * 24.0 - 12.0),
            day_of_year: (forcing.day_of_year - 1.0 + (day - forcing.start_day)).rem_euclid(365.0)
                + 1.0,
            ..Weather::default()
        };
        let b = step(
            &transport,
            &weather,
            &scene,
            &mut state,
            &mut scratch.step,
            dt,
        )?;
        subl += b.sublimation_out;
        border += b.border_out - b.border_in;
    }
    let area = geometry.cell_area();
    let inv_rho = 1.0 / rho;
    let (mut eroded, mut deposited) = (0.0f64, 0.0f64);
    let (pi, ui) = (SnowLayer::Powder.index(), SnowLayer::Unstable.index());
    for (i, (&swe, &old)) in state.swe.iter().zip(&erodible).enumerate() {
        if !mask.is_valid(i) {
            continue;
        }
        let new_depth = (swe * inv_rho).max(0.0);
        let change = new_depth - old;
        if change >= 0.0 {
            terrain.snow[pi][i] += change;
            deposited += f64::from(change);
        } else {
            let loss = -change;
            let from_powder = loss.min(terrain.snow[pi][i]);
            terrain.snow[pi][i] -= from_powder;
            terrain.snow[ui][i] = (terrain.snow[ui][i] - (loss - from_powder)).max(0.0);
            eroded += f64::from(loss);
        }
    }
    report.eroded = eroded * area;
    report.deposited = deposited * area;
    // The transport budget is in kg; the layers' volumes follow at the erodible density.
    report.sublimated = subl / params.erodible_density;
    report.border_net_outflow = border / params.erodible_density;
    Ok(report)
}
