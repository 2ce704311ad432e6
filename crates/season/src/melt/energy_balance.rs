//! Surface energy balance snowpack: the season's default melt (`[parameters.melt] model =
//! "energy_balance"`; beyond Cordonnier 2018), after the energy balance of FSM (Essery 2015,
//! Geosci. Model Dev. 8, 3867-3876) with a bulk pack as in UEB (Tarboton & Luce 1996).
//!
//! Per cell and hour of the window (the hours since the previous melt event, as the enhanced
//! melt integrates them; dark hours in steps of several, below), on cells with snow, the
//! energy into the pack is
//!
//! `Q = (1 − α) S + L↓ − ε σ T_s⁴ + H + LE + G`, W/m², with
//!
//! - **shortwave** `S = V·I_dif + b·I_dir + r·I_refl`: the hour's diffuse, direct and
//!   terrain-reflected irradiance with the precompute's sky view `V`, beam factor `b`
//!   (shadow × incidence) and reflected share `r` ([`snowscape_environment::insolation`]), every
//!   hour with sun; `α` the aging albedo of the enhanced melt (USACE 1956, [`super::enhanced`]);
//! - **incoming longwave** `L↓ = V·L_sky + (1 − V) σ T_a⁴` (the terrain the cell sees emits as
//!   a black body at the air temperature), with the sky's
//!   `L_sky = (1 − 0.84 N) ε_clr σ T_a⁴ + 0.84 N σ T_a⁴` (cloud cover `N`: Unsworth & Monteith
//!   1975, Q. J. R. Meteorol. Soc. 101) and the clear-sky emissivity of Prata 1996 (Q. J. R.
//!   Meteorol. Soc. 122, Eq. 21): `ε_clr = 1 − (1 + w) exp(−(1.2 + 3 w)^½)`,
//!   `w = 46.5 e_a / T_a` (cm; `e_a` in hPa, `T_a` in K); `e_a = RH · e_w(T_a)`. A station's
//!   recorded incoming longwave replaces `L_sky`;
//! - **outgoing longwave** from the surface temperature `T_s`, `ε` = 0.99 (Warren 1982, Rev.
//!   Geophys. 20(1): snow's thermal-infrared emissivity 0.98-0.99);
//! - **sensible and latent heat** by the bulk method `H = ρ c_p C_H U (T_a − T_s)`,
//!   `E = C_H U (e_s(T_s) − e_a) / (R_v T_a)` (kg m⁻² s⁻¹, `ρ q = e / (R_v T)`), `LE = −L_s E`,
//!   with the neutral coefficient `C_H = κ² / (ln(z_U/z_0) ln(z_T/z_0h))`, `z_0h = z_0/10`,
//!   and Louis et al. 1982's stability correction as FSM writes it (its `SURF_EXCH`):
//!   `Ri_B = g (T_a − T_s) z_U² / (z_T T_a U²)`; `f_h = 1 / (1 + 3b Ri_B (1 + b Ri_B)^½)` when
//!   stable, `1 − 3b Ri_B / (1 + 3b² C_D (−Ri_B z_U/z_0)^½)` when not, `C_D = (κ / ln(z_U/z_0))²`,
//!   `b` = 5. The vapour flux is sublimation (E > 0) or deposition (E < 0) of the snow with
//!   the latent heat of sublimation `L_s`, as in FSM whenever snow lies: at a melting surface
//!   condensation onto ice and the melt of that ice release `L_s − L_f = L_v` together.
//!   `e_s` is the saturation vapour pressure over ice and `e_w` over water (Magnus with
//!   Sonntag 1990's coefficients, WMO-No. 8 2008, Annex 4.B); air density from the
//!   barometric pressure at the cell's altitude (scale height 8.43 km) and the window's mean
//!   air temperature;
//! - **ground heat** `G`, a constant flux from the soil.
//!
//! **Surface temperature.** `T_s` balances `Q(T_s)` against conduction into the pack,
//! `K (T_s − T_p)`, with `K = k_s / d` (`d` half the depth, at most the diurnal damping depth
//! `(κ_s P/π)^½` ≈ 0.1 m of snow of `k_s` = 0.24 W m⁻¹ K⁻¹) and the pack's bulk temperature
//! `T_p = −H_cc L_f / (c_i SWE)` from its cold content `H_cc`. `Q` is linearised around the
//! previous step's `T_s` (FSM's `SURF_EBAL`: one Newton step a step, the exchange coefficient
//! at the previous `T_s`; two in the first step of a window, which starts from `min(T_a, 0)`),
//! and the pack's temperature is taken at the end of the step (implicit: `K` in series with the
//! pack's heat capacity `c_i ρ_w SWE / Δt`, so a thin pack follows its surface without
//! overshoot). `T_s` is capped at 0 °C; the energy of the step `Q(T_s) Δt` (every term at the
//! solved `T_s` in the linearisation, so they sum to it exactly) goes into the pack.
//!
//! **The pack** per hour, in m of water equivalent: the energy pays the cold content first
//! and what is left melts snow (a negative energy adds to the cold content); liquid water
//! refreezes against the cold content; the vapour flux removes or adds snow; liquid water
//! beyond `θ_max · SWE` runs off. At the end of the window the layers change once: refrozen
//! and deposited ice join the compacted layer, then sublimation and melt take snow from the
//! top layer down (powder, unstable, stable, compacted, each at its density) as in the
//! enhanced melt, whose albedo curves, holding capacity, layer densities, surface-age reset
//! and window length (`[parameters.melt.enhanced]`) this model shares. Rain joins the liquid
//! water with its heat `P c_w max(0, T̄)` at the start of the window.
//!
//! **Steps and numerics.** Consecutive hours without sun are integrated together, up to
//! `dark_step_hours` (8 h: the night's forcing varies slowly), hours with sun two at a time
//! (`sun_step_hours` = 2). Each step linearises the balance about a predicted surface
//! temperature: the previous step's surface moved by the change of the radiative and ground
//! gains since that step times the balance's compliance there, `1 / (−dQ/dT_s + K_eff)` (a
//! window's first step: twice about the previous surface). Without the predictor two-hour
//! steps lag the surface behind the sun (−7 % of a sunny slope's loss in the slope test);
//! with it the slope days lose what hourly steps lose within 3 % (south) and 10 % (north),
//! at half the steps. The air-side terms that depend on a cell only through its
//! air temperature (`e_a`, `L_sky`) are interpolated per step by a degree-4 polynomial in the
//! cell's lapse offset (Chebyshev nodes over the terrain's range) and `e_i` by a degree-6
//! polynomial over [−60, 0] °C, so the per-cell loop has no transcendental function. Cells go
//! through the steps in groups of sixteen without data-dependent branches, step after step
//! over every group of a row that has snow; every sum is per cell in a fixed order and rows run
//! in parallel, so results are identical for any thread count and vector width.

use super::enhanced::{
    self, EnhancedMeltParams, MeltForcing, MeltReport, SnowpackState, albedo_table,
};
use crate::phenomenon::{PhenomenonError, check_range};
use serde::{Deserialize, Serialize};
use snowscape_terrain::LayeredTerrain;
use snowscape_terrain::parallel::{self, PerRow};

mod kernel;
mod steps;
#[cfg(test)]
mod tests;

use kernel::{Kernel, RowInputs, RowState};
use steps::Step;

/// Parameters of the energy-balance snowpack (`[parameters.melt.energy_balance]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct EnergyBalanceParams {
    /// Roughness length of snow for momentum z_0, m. Essery 2015 (FSM's `z0sn`): 0.01.
    pub roughness_length_m: f64,
    /// Height of the wind speed z_U, m. Essery 2015 (FSM's `zU`): 10 (the WMO wind height).
    pub wind_height_m: f64,
    /// Height of the air temperature and humidity z_T, m. Essery 2015 (FSM's `zT`): 2.
    pub temperature_height_m: f64,
    /// Slope b of Louis et al. 1982's stability functions. Essery 2015 (FSM's `bstb`): 5.
    pub stability_slope: f64,
    /// Thermal-infrared emissivity of snow ε. Warren 1982: 0.99.
    pub emissivity: f64,
    /// Thermal conductivity of snow k_s, W m⁻¹ K⁻¹. Essery 2015 (FSM's `kfix`): 0.24.
    pub snow_conductivity_w_m_k: f64,
    /// Largest conduction length d between the surface and the pack, m. Chosen here: 0.1,
    /// the diurnal damping depth `(κ_s P/π)^½` of snow of k_s 0.24 W m⁻¹ K⁻¹ and 300 kg/m³.
    pub conduction_depth_m: f64,
    /// Heat flux from the ground into the pack G, W/m². Chosen here: 2 (a few W/m² reach the
    /// base of seasonal snow from the unfrozen soil; small beside the radiation).
    pub ground_heat_w_m2: f64,
    /// Longest step with sun, hours: consecutive sunny hours of a window are integrated
    /// together up to this length. Chosen here: 2 (with the predicted surface temperature,
    /// module docs; behaviour test: the slope days lose what hourly steps lose within 3 %
    /// south and 10 % north; 3 h steps: −4 % south, +34 % north).
    pub sun_step_hours: f64,
    /// Longest step without sun, hours: consecutive dark hours are integrated together up
    /// to this length. Chosen here: 8 (the night's forcing varies slowly; behaviour test:
    /// the slope days lose what hourly steps lose within 3 %; a night in two steps).
    pub dark_step_hours: f64,
}

impl Default for EnergyBalanceParams {
    fn default() -> Self {
        Self {
            roughness_length_m: 0.01,
            wind_height_m: 10.0,
            temperature_height_m: 2.0,
            stability_slope: 5.0,
            emissivity: 0.99,
            snow_conductivity_w_m_k: 0.24,
            conduction_depth_m: 0.1,
            ground_heat_w_m2: 2.0,
            sun_step_hours: 2.0,
            dark_step_hours: 8.0,
        }
    }
}

impl EnergyBalanceParams {
    /// Checks every field's range (the heights above the roughness length).
    pub fn validate(&self) -> Result<(), PhenomenonError> {
        const P: &str = "melt.energy_balance";
        check_range(
            P,
            "roughness_length_m",
            self.roughness_length_m,
            [1e-5, 0.5],
            " m",
        )?;
        let z0 = self.roughness_length_m;
        check_range(
            P,
            "wind_height_m",
            self.wind_height_m,
            [z0 * 2.0, 100.0],
            " m",
        )?;
        check_range(
            P,
            "temperature_height_m",
            self.temperature_height_m,
            [z0 * 20.0, 100.0],
            " m",
        )?;
        check_range(P, "stability_slope", self.stability_slope, [0.0, 20.0], "")?;
        check_range(P, "emissivity", self.emissivity, [0.5, 1.0], "")?;
        check_range(
            P,
            "snow_conductivity_w_m_k",
            self.snow_conductivity_w_m_k,
            [0.01, 3.0],
            " W/(m·K)",
        )?;
        check_range(
            P,
            "conduction_depth_m",
            self.conduction_depth_m,
            [0.01, 2.0],
            " m",
        )?;
        check_range(
            P,
            "ground_heat_w_m2",
            self.ground_heat_w_m2,
            [-50.0, 50.0],
            " W/m²",
        )?;
        check_range(P, "sun_step_hours", self.sun_step_hours, [1.0, 6.0], " h")?;
        check_range(
            P,
            "dark_step_hours",
            self.dark_step_hours,
            [1.0, 12.0],
            " h",
        )
    }
}

/// Integrates one window of the energy balance on every valid cell (module docs).
pub fn step(
    params: &EnergyBalanceParams,
    shared: &EnhancedMeltParams,
    terrain: &mut LayeredTerrain,
    pack: &mut SnowpackState,
    forcing: &MeltForcing,
) -> Result<MeltReport, PhenomenonError> {
    step_and_surface(params, shared, terrain, pack, forcing, None)
}

/// [`step`], also writing the snow surface it leaves (`bedrock + Σ layers`) into `surface`,
/// as [`super::enhanced::step_filling_surface`] does, for the stability step that follows.
pub(crate) fn step_filling_surface(
    params: &EnergyBalanceParams,
    shared: &EnhancedMeltParams,
    terrain: &mut LayeredTerrain,
    pack: &mut SnowpackState,
    forcing: &MeltForcing,
    surface: &mut Vec<f32>,
) -> Result<MeltReport, PhenomenonError> {
    step_and_surface(params, shared, terrain, pack, forcing, Some(surface))
}

/// Per-row partial sums of the report, m (depth or water) summed over the row's cells.
#[derive(Default, Clone, Copy)]
struct RowSums([f64; SUMS]);

/// The report's sums per cell: melted depth and water, refrozen depth and water, rain on
/// snow, runoff, sublimated depth and water, deposited depth and water.
const SUMS: usize = 10;

fn step_and_surface(
    params: &EnergyBalanceParams,
    shared: &EnhancedMeltParams,
    terrain: &mut LayeredTerrain,
    pack: &mut SnowpackState,
    forcing: &MeltForcing,
    surface: Option<&mut Vec<f32>>,
) -> Result<MeltReport, PhenomenonError> {
    params.validate()?;
    shared.validate()?;
    enhanced::check_inputs("melt.energy_balance", terrain, pack, forcing)?;
    let geometry = terrain.geometry().clone();
    let w = geometry.width();
    let mask = terrain.mask().clone();
    let invalid = mask.invalid_cells();
    let offsets = steps::OffsetRange::of(forcing.lapse_offset_c);
    let steps = Step::of_window(
        forcing,
        &offsets,
        (params.sun_step_hours as f32, params.dark_step_hours as f32),
    );
    let kernel = Kernel::new(params, shared, forcing, &offsets);
    let albedo = albedo_table(shared);
    let surface_rows = super::enhanced::surface_rows(surface, &geometry);
    let bedrock = &terrain.bedrock;
    let [c, s, u, p] = &mut terrain.snow;
    let rows: Vec<RowSums> = parallel::map_rows_with(
        w,
        (
            c,
            s,
            u,
            p,
            &mut pack.surface_age_days,
            &mut pack.cold_content_m,
            &mut pack.liquid_water_m,
            &mut pack.melting,
            PerRow(surface_rows),
        ),
        || kernel::Scratch::new(w),
        |scratch, row, (c, s, u, p, age, cold, liquid, melting, surface)| {
            let base = row * w;
            let inputs = RowInputs {
                base,
                altitude: &bedrock[base..base + w],
                offset: &forcing.lapse_offset_c[base..base + w],
                sky_view: &forcing.sky_view_factor[base..base + w],
                rain: (!forcing.rain_m.is_empty()).then(|| &forcing.rain_m[base..base + w]),
                invalid: invalid.map(|v| &v[base..base + w]),
                albedo: &albedo,
            };
            let state = RowState {
                layers: [&mut *c, &mut *s, &mut *u, &mut *p],
                age,
                cold,
                liquid,
                melting,
            };
            kernel.row(&steps, &inputs, state, scratch);
            if let Some(a) = surface {
                let b = &bedrock[base..base + w];
                for (k, a) in a.iter_mut().enumerate() {
                    *a = b[k] + (c[k] + s[k] + u[k] + p[k]);
                }
            }
            RowSums(std::array::from_fn(|k| crate::row_sum(&scratch.sums[k])))
        },
    );
    let a = geometry.cell_area();
    let mut t = [0.0f64; SUMS];
    for r in rows {
        for (t, v) in t.iter_mut().zip(r.0) {
            *t += v * a;
        }
    }
    Ok(MeltReport {
        melted_snow_m3: t[0],
        melt_water_m3: t[1],
        refrozen_snow_m3: t[2],
        refrozen_water_m3: t[3],
        rain_on_snow_m3: t[4],
        runoff_m3: t[5],
        sublimated_snow_m3: t[6],
        sublimated_water_m3: t[7],
        deposited_snow_m3: t[8],
        deposited_water_m3: t[9],
    })
}

/// The physical constants of the balance (module docs), SI units.
mod constants {
    /// Stefan-Boltzmann constant, W m⁻² K⁻⁴ (CODATA 2018).
    pub const STEFAN_BOLTZMANN: f64 = 5.670_374e-8;
    /// von Kármán's constant κ (FSM's `vkman`).
    pub const VON_KARMAN: f64 = 0.4;
    /// Specific heat of dry air at constant pressure, J kg⁻¹ K⁻¹.
    pub const AIR_HEAT_CAPACITY: f64 = 1005.0;
    /// Gas constant of dry air, J kg⁻¹ K⁻¹.
    pub const DRY_AIR_GAS_CONSTANT: f64 = 287.05;
    /// Gas constant of water vapour, J kg⁻¹ K⁻¹.
    pub const VAPOUR_GAS_CONSTANT: f64 = 461.5;
    /// Sea-level pressure, Pa (ICAO standard atmosphere).
    pub const SEA_LEVEL_PRESSURE: f64 = 101_325.0;
    /// Scale height of the barometric pressure, m: `R_d T_0 / g` at the standard atmosphere's
    /// 288.15 K.
    pub const PRESSURE_SCALE_HEIGHT: f64 = 8431.0;
    /// 0 °C in K.
    pub const MELTING_POINT_K: f64 = 273.15;
}
