//! Enhanced temperature-index melt with albedo, cold content, liquid water and refreezing
//! (beyond Cordonnier 2018: the season's default melt, `[parameters.melt] model = "enhanced_ti"`).
//!
//! Per cell and hour `h` of the window an event integrates (the hours since the previous melt
//! event, so windows tile the season without gaps):
//!
//! - **melt energy** (Pellicciotti et al. 2005, J. Glaciol. 51(175), Eq. 4; Hock 1999,
//!   J. Glaciol. 45(149)), in m of water:
//!   `E = Σ_h [T_h > T_T] · (f_T · T_h + f_R · (1 − α) · I_sw,h) · Δt_h`
//!   with `T_h` the cell's air temperature at that hour (the diurnal cycle of
//!   [`crate::climate`]), `I_sw,h` the incoming shortwave with topographic shadows, sky view
//!   and terrain reflection ([`snowscape_environment::insolation`]), `f_T` = 0.05 mm w.e.
//!   h⁻¹ °C⁻¹, `f_R` = 0.0094 mm w.e. h⁻¹ W⁻¹ m², `T_T` = 1 °C (Pellicciotti 2005, Table 2,
//!   Haut Glacier d'Arolla); plus the heat rain brings, `P_rain · c_w · T / L_f`;
//! - **cooling** (the heat deficit of SNOW-17, Anderson 1976, NOAA Tech. Memo. NWS HYDRO-17,
//!   §2.4, with its negative melt factor): `C = k_cc · Σ_h max(0, −T_h) · Δt_h`, m of water,
//!   the deficit `H` capped by the cold content of the whole pack at the window's mean air
//!   temperature, `SWE · c_i · max(0, −T̄) / L_f`.
//! - **longwave**, when station forcing records the incoming longwave `L_in`: the balance of
//!   a melting surface `Σ_h (L_in,h − σ 273.15⁴) Δt_h / (ρ_w L_f)` joins the melt energy (the
//!   net-radiation index of Kustas et al. 1994, Water Resour. Res. 30(5)); a negative total
//!   cools the pack instead. Dry, clear spells then melt nothing even above 0 °C, as an energy
//!   balance says; without the record the temperature factor stands for the longwave.
//!
//! The update, in this order: `H ← min(H + C, H_max)`; liquid water refreezes against the
//! deficit (`r = min(L, H)`, into the compacted layer, which gains `r ρ_w/ρ_C` of depth);
//! the melt energy pays the deficit first, and what is left melts snow from the top layer down
//! (powder, unstable, stable, compacted, each at its density); melt water and rain join the
//! liquid water `L`, which the pack holds up to `θ_max · SWE` (Anderson 1976's liquid-water
//! holding capacity, 5 %); the rest runs off. A cell that melts out releases its water.
//! Layer depths left below [`crate::phenomenon::NEGLIGIBLE_DEPTH_M`] (1e-20 m) are set to 0.
//!
//! **Albedo** decays with the age `t` (days) of the snow surface and is reset by snowfall
//! (U.S. Army Corps of Engineers 1956, "Snow Hydrology", as fitted in the form used by e.g.
//! the UEB and SNOWPACK literature): `α = max(α_min, α0 · 0.94^(t^0.58))` while the pack is cold and
//! `α = max(α_min, α0 · 0.82^(t^0.46))` once it is ripe (no cold content left and wet: the
//! melt-season curve), `α0` = 0.85,
//! `α_min` = 0.4.
//!
//! Every sum is per cell in a fixed order and rows run in parallel, so results are identical
//! for any thread count.

use crate::phenomenon::{PhenomenonError, check_range};
use serde::{Deserialize, Serialize};
use snowscape_terrain::LayeredTerrain;
use snowscape_terrain::parallel::{self, PerRow};

use snowscape_terrain::materials::{
    LATENT_HEAT_FUSION_J_KG as LATENT_HEAT_FUSION, LAYER_DENSITY_KG_M3,
    SPECIFIC_HEAT_ICE_J_KG_K as SPECIFIC_HEAT_ICE,
    SPECIFIC_HEAT_WATER_J_KG_K as SPECIFIC_HEAT_WATER, WATER_DENSITY_KG_M3 as WATER_DENSITY,
};

/// Parameters of the enhanced temperature-index melt.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct EnhancedMeltParams {
    /// Temperature factor f_T, mm w.e. per hour per °C. Pellicciotti et al. 2005, Table 2: 0.05.
    pub f_t_mm_per_h_c: f64,
    /// Shortwave radiation factor f_R, mm w.e. per hour per W/m² absorbed.
    /// Pellicciotti et al. 2005, Table 2: 0.0094.
    pub f_r_mm_per_h_w_m2: f64,
    /// Threshold temperature T_T above which snow melts, °C. Pellicciotti et al. 2005: 1 °C.
    pub threshold_c: f64,
    /// Negative melt factor k_cc: heat deficit gained per hour per °C below 0, mm w.e.
    /// Anderson 1976 (SNOW-17): NMF 0.05-0.5 mm per 6 h per °C; 0.3 mm per 6 h (0.05 mm/h/°C,
    /// the value of f_T) chosen here, as clear nights cool the surface below the air.
    pub cold_content_mm_per_h_c: f64,
    /// Liquid water the pack holds, as a share of its water equivalent θ_max.
    /// Anderson 1976 (SNOW-17 PLWHC): 0.05.
    pub liquid_holding_capacity: f64,
    /// Albedo of fresh snow α0. U.S. Army Corps of Engineers 1956: 0.85.
    pub fresh_albedo: f64,
    /// Lowest albedo of old snow α_min. Chosen here: 0.4 (old wet snow, Cuffey & Paterson 2010
    /// Table 5.3: 0.4-0.7 for old snow).
    pub min_albedo: f64,
    /// Base of the accumulation-season decay per day^0.58. USACE 1956: 0.94.
    pub cold_decay: f64,
    /// Base of the melt-season decay per day^0.46. USACE 1956: 0.82.
    pub melt_decay: f64,
    /// New snow water equivalent that resets the surface age, m w.e. Chosen here: 0.001
    /// (1 mm w.e., about 1 cm of fresh snow; a dusting renews the surface).
    pub reset_swe_m: f64,
    /// Shortest window a melt event integrates, hours: a Melt-And-State event sooner than
    /// this after the last window leaves the melt to the next one. Default 24: whole diurnal
    /// cycles, whose cooling and warming the window nets as the cold content would overnight
    /// (and half the cost of the paper's twice-daily events). 0 integrates every event.
    pub min_window_hours: f64,
    /// Density of each layer (compacted, stable, unstable, powder), kg/m³, to turn melt water
    /// into snow depth. Default: the shared layer densities
    /// ([`snowscape_terrain::materials::LAYER_DENSITY_KG_M3`]: compacted 500, Cordonnier 2018
    /// Table 2's ρ; stable 300, the 0.6 ratio of [`crate::stability`]; unstable 250 and powder
    /// 150, our choice within Cuffey & Paterson 2010 Table 2.1).
    pub layer_density_kg_m3: [f64; 4],
}

impl Default for EnhancedMeltParams {
    fn default() -> Self {
        Self {
            f_t_mm_per_h_c: 0.05,
            f_r_mm_per_h_w_m2: 0.0094,
            threshold_c: 1.0,
            cold_content_mm_per_h_c: 0.05,
            liquid_holding_capacity: 0.05,
            fresh_albedo: 0.85,
            min_albedo: 0.4,
            cold_decay: 0.94,
            melt_decay: 0.82,
            reset_swe_m: 0.001,
            min_window_hours: 24.0,
            layer_density_kg_m3: LAYER_DENSITY_KG_M3,
        }
    }
}

impl EnhancedMeltParams {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), PhenomenonError> {
        const P: &str = "melt.enhanced";
        let in_range =
            |name: &'static str, v: f64, lo: f64, hi: f64| check_range(P, name, v, [lo, hi], "");
        in_range("f_t_mm_per_h_c", self.f_t_mm_per_h_c, 0.0, 10.0)?;
        in_range("f_r_mm_per_h_w_m2", self.f_r_mm_per_h_w_m2, 0.0, 1.0)?;
        check_range(P, "threshold_c", self.threshold_c, [-10.0, 10.0], " °C")?;
        in_range(
            "cold_content_mm_per_h_c",
            self.cold_content_mm_per_h_c,
            0.0,
            10.0,
        )?;
        in_range(
            "liquid_holding_capacity",
            self.liquid_holding_capacity,
            0.0,
            0.5,
        )?;
        in_range("fresh_albedo", self.fresh_albedo, 0.0, 1.0)?;
        in_range("min_albedo", self.min_albedo, 0.0, self.fresh_albedo)?;
        in_range("cold_decay", self.cold_decay, 0.0, 1.0)?;
        in_range("melt_decay", self.melt_decay, 0.0, 1.0)?;
        check_range(P, "reset_swe_m", self.reset_swe_m, [0.0, 1.0], " m")?;
        in_range("min_window_hours", self.min_window_hours, 0.0, 240.0)?;
        for (k, d) in self.layer_density_kg_m3.iter().enumerate() {
            in_range(
                [
                    "layer_density_kg_m3[0]",
                    "layer_density_kg_m3[1]",
                    "layer_density_kg_m3[2]",
                    "layer_density_kg_m3[3]",
                ][k],
                *d,
                10.0,
                917.0,
            )?;
        }
        Ok(())
    }

    /// Albedo of a surface `age_days` old; `melting` selects the melt-season curve.
    #[inline]
    pub fn albedo(&self, age_days: f32, melting: bool) -> f32 {
        let (base, exponent) = if melting {
            (self.melt_decay, 0.46f32)
        } else {
            (self.cold_decay, 0.58f32)
        };
        let a = self.fresh_albedo as f32 * (base as f32).powf(age_days.max(0.0).powf(exponent));
        a.max(self.min_albedo as f32)
    }
}

/// The per-cell state of the snowpack's surface energy, checkpointed with the run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SnowpackState {
    /// Days since the last snowfall renewed the surface.
    pub surface_age_days: Vec<f32>,
    /// Heat deficit (cold content), m of water equivalent of melt energy.
    pub cold_content_m: Vec<f32>,
    /// Liquid water held in the pack, m of water.
    pub liquid_water_m: Vec<f32>,
    /// 1 where the pack ended the last window ripe (no cold content, wet): it then ages on
    /// the melt-season albedo curve.
    pub melting: Vec<f32>,
}

impl SnowpackState {
    /// A fresh state for `n` cells (new snow, no deficit, dry).
    pub fn new(n: usize) -> Self {
        Self {
            surface_age_days: vec![0.0; n],
            cold_content_m: vec![0.0; n],
            liquid_water_m: vec![0.0; n],
            melting: vec![0.0; n],
        }
    }

    /// The four per-cell arrays, for checkpoints (age, cold content, liquid water, melting).
    pub fn arrays(&self) -> [&[f32]; 4] {
        [
            &self.surface_age_days,
            &self.cold_content_m,
            &self.liquid_water_m,
            &self.melting,
        ]
    }

    /// Rebuilds a state from [`SnowpackState::arrays`].
    pub fn from_arrays(mut a: Vec<Vec<f32>>) -> Self {
        let melting = a.pop().unwrap_or_default();
        let liquid_water_m = a.pop().unwrap_or_default();
        let cold_content_m = a.pop().unwrap_or_default();
        let surface_age_days = a.pop().unwrap_or_default();
        Self {
            surface_age_days,
            cold_content_m,
            liquid_water_m,
            melting,
        }
    }

    /// Total liquid water, m³.
    pub fn liquid_volume(&self, cell_area: f64) -> f64 {
        // Fixed blocks summed in parallel, then in order: the same bits for any thread count.
        let blocks: Vec<f64> =
            parallel::map_rows(1 << 14, &self.liquid_water_m, |_, b| crate::row_sum(b));
        blocks.iter().sum::<f64>() * cell_area
    }
}

/// One hour (or part of one) of the window, the same for every cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeltHour<'a> {
    /// Fraction of the hour inside the window, (0, 1].
    pub weight: f32,
    /// Air temperature at sea level, °C (a cell's is this plus its lapse offset).
    pub sea_level_c: f32,
    /// Direct-beam factors of the hour (shadow × incidence, /255), `None` at night.
    pub beam: Option<&'a [u8]>,
    /// Direct normal irradiance times the cloud factor, W/m².
    pub direct_w_m2: f32,
    /// Diffuse horizontal irradiance times the cloud factor, W/m².
    pub diffuse_w_m2: f32,
    /// Reflected light per unit of the reflected share (flat direct irradiance), W/m².
    pub reflected_w_m2: f32,
    /// Index of the month's reflected-share map in [`MeltForcing::reflected`].
    pub month: usize,
    /// Longwave balance of a melting surface, `L_in − σ·273.15⁴`, W/m², when the forcing
    /// records the incoming longwave (0 otherwise: the temperature factor stands for it).
    pub longwave_balance_w_m2: f32,
    /// Humidity, cloud, wind and recorded longwave of the hour (the energy balance reads them).
    pub air: HourAir,
}

/// The air of one hour beyond its temperature, as the energy-balance melt reads it
/// ([`super::energy_balance`]): the same for every cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HourAir {
    /// Relative humidity with respect to water at the cell's air temperature, 0..=1.
    pub relative_humidity: f32,
    /// Cloud cover, 0 (clear) to 1 (overcast).
    pub cloud_cover: f32,
    /// Wind speed at the wind measurement height, m/s.
    pub wind_speed_m_s: f32,
    /// Incoming longwave radiation recorded by a station, W/m² (`None`: from the air's
    /// temperature, humidity and cloud).
    pub longwave_in_w_m2: Option<f32>,
}

impl Default for HourAir {
    /// Fair weather of the default climate ([`crate::climate::ClimateParams`]).
    fn default() -> Self {
        crate::climate::ClimateParams::default().hour_air(false)
    }
}

/// What a window of melt reads besides the terrain.
#[derive(Debug, Clone, Copy)]
pub struct MeltForcing<'a> {
    /// The hours of the window.
    pub hours: &'a [MeltHour<'a>],
    /// Per cell: air temperature minus the sea-level temperature (the lapse term), °C.
    pub lapse_offset_c: &'a [f32],
    /// Per cell: the sky view factor.
    pub sky_view_factor: &'a [f32],
    /// Per month: the reflected share per cell.
    pub reflected: &'a [&'a [f32]],
    /// Per cell: the rain of the window, m of water (empty: none). Its heat,
    /// `P · c_w · max(0, T̄) / L_f` at the window's mean air temperature, melts snow.
    pub rain_m: &'a [f32],
    /// Length of the window, days (ages the surface).
    pub window_days: f32,
}

impl MeltForcing<'_> {
    /// The hour-weighted mean sea-level temperature of the window, °C (0 without hours).
    pub fn mean_sea_level_c(&self) -> f32 {
        let weight: f32 = self.hours.iter().map(|h| h.weight).sum();
        if weight > 0.0 {
            self.hours
                .iter()
                .map(|h| h.weight * h.sea_level_c)
                .sum::<f32>()
                / weight
        } else {
            0.0
        }
    }
}

/// Per row of `geometry`, where a melt writes its snow surface: the rows of `surface` (sized
/// to the grid), or none without a surface to fill.
pub(super) fn surface_rows<'a>(
    surface: Option<&'a mut Vec<f32>>,
    geometry: &snowscape_terrain::GridGeometry,
) -> Vec<Option<&'a mut [f32]>> {
    match surface {
        Some(a) => {
            a.resize(geometry.len(), 0.0);
            a.chunks_mut(geometry.width()).map(Some).collect()
        }
        None => (0..geometry.height()).map(|_| None).collect(),
    }
}

/// What a window of melt did, m³ (snow volume) and m³ of water.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MeltReport {
    /// Snow volume melted, m³ of snow.
    pub melted_snow_m3: f64,
    /// Melt water, m³ of water.
    pub melt_water_m3: f64,
    /// Snow volume refrozen from liquid water (added to the compacted layer), m³ of snow.
    pub refrozen_snow_m3: f64,
    /// Water refrozen, m³ of water.
    pub refrozen_water_m3: f64,
    /// Rain that fell on snow and joined its liquid water, m³ of water (rain on bare ground
    /// runs off at once).
    pub rain_on_snow_m3: f64,
    /// Water that left the pack (runoff), m³.
    pub runoff_m3: f64,
    /// Snow volume lost to vapour (sublimation; the energy balance only), m³ of snow.
    pub sublimated_snow_m3: f64,
    /// Its water equivalent, m³ of water.
    pub sublimated_water_m3: f64,
    /// Snow volume gained from vapour (deposition, laid on the compacted layer), m³ of snow.
    pub deposited_snow_m3: f64,
    /// Its water equivalent, m³ of water.
    pub deposited_water_m3: f64,
}

/// Per-cell partial sums of one row.
#[derive(Default, Clone, Copy)]
struct RowSums {
    melted_snow: f64,
    melt_water: f64,
    refrozen_snow: f64,
    refrozen_water: f64,
    rain: f64,
    runoff: f64,
}

/// Integrates one window of melt on every valid cell (module docs).
pub fn step(
    params: &EnhancedMeltParams,
    terrain: &mut LayeredTerrain,
    pack: &mut SnowpackState,
    forcing: &MeltForcing,
) -> Result<MeltReport, PhenomenonError> {
    step_and_surface(params, terrain, pack, forcing, None)
}

/// [`step`], also writing the snow surface it leaves, `A = bedrock + Σ layers` cell by cell
/// (the same operations as the other steps' surface), into `surface` (resized to the grid):
/// each row while its layers are still in cache, for the stability step that follows
/// ([`crate::stability::step_on_filled_surface`]) instead of a pass of its own.
pub(crate) fn step_filling_surface(
    params: &EnhancedMeltParams,
    terrain: &mut LayeredTerrain,
    pack: &mut SnowpackState,
    forcing: &MeltForcing,
    surface: &mut Vec<f32>,
) -> Result<MeltReport, PhenomenonError> {
    step_and_surface(params, terrain, pack, forcing, Some(surface))
}

fn step_and_surface(
    params: &EnhancedMeltParams,
    terrain: &mut LayeredTerrain,
    pack: &mut SnowpackState,
    forcing: &MeltForcing,
    surface: Option<&mut Vec<f32>>,
) -> Result<MeltReport, PhenomenonError> {
    params.validate()?;
    check_inputs("melt.enhanced", terrain, pack, forcing)?;
    let geometry = terrain.geometry().clone();
    let w = geometry.width();
    let mask = terrain.mask().clone();
    let invalid = mask.invalid_cells();
    let k = Coefficients::new(params, forcing);
    let surface_rows = surface_rows(surface, &geometry);
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
        || RowScratch::new(w),
        |scratch, row, (c, s, u, p, age, cold, liquid, melting, surface)| {
            let base = row * w;
            let snowy = (0..w).any(|k| c[k] + s[k] + u[k] + p[k] > 0.0);
            if snowy {
                row_shortwave(k.threshold, forcing, base, &mut scratch.shortwave);
            } else {
                scratch.shortwave.fill(0.0);
            }
            let valid = invalid.map(|v| &v[base..base + w]);
            let rain = if forcing.rain_m.is_empty() {
                None
            } else {
                Some(&forcing.rain_m[base..base + w])
            };
            let sums = k.row(
                forcing,
                base,
                RowState {
                    layers: [&mut *c, &mut *s, &mut *u, &mut *p],
                    age,
                    cold,
                    liquid,
                    melting,
                },
                rain,
                valid,
                scratch,
            );
            if let Some(a) = surface {
                let b = &bedrock[base..base + w];
                for (k, a) in a.iter_mut().enumerate() {
                    *a = b[k] + (c[k] + s[k] + u[k] + p[k]);
                }
            }
            sums
        },
    );
    let a = geometry.cell_area();
    let mut r = MeltReport::default();
    for s in rows {
        r.melted_snow_m3 += s.melted_snow * a;
        r.melt_water_m3 += s.melt_water * a;
        r.refrozen_snow_m3 += s.refrozen_snow * a;
        r.refrozen_water_m3 += s.refrozen_water * a;
        r.rain_on_snow_m3 += s.rain * a;
        r.runoff_m3 += s.runoff * a;
    }
    Ok(r)
}

/// Checks that every per-cell input of a melt window has the terrain's length and every sunny
/// hour's maps exist (`phenomenon` names the model in the error).
pub(super) fn check_inputs(
    phenomenon: &'static str,
    terrain: &LayeredTerrain,
    pack: &SnowpackState,
    forcing: &MeltForcing,
) -> Result<(), PhenomenonError> {
    let geometry = terrain.geometry();
    let n = geometry.len();
    for (name, v) in [
        ("lapse offset", forcing.lapse_offset_c.len()),
        ("sky view factor", forcing.sky_view_factor.len()),
        ("surface age", pack.surface_age_days.len()),
        ("cold content", pack.cold_content_m.len()),
        ("liquid water", pack.liquid_water_m.len()),
        ("melting", pack.melting.len()),
    ] {
        if v != n {
            return Err(PhenomenonError::MapLength {
                map: name,
                width: geometry.width(),
                height: geometry.height(),
                expected: n,
                actual: v,
            });
        }
    }
    if !forcing.rain_m.is_empty() && forcing.rain_m.len() != n {
        return Err(PhenomenonError::MapLength {
            map: "rain",
            width: geometry.width(),
            height: geometry.height(),
            expected: n,
            actual: forcing.rain_m.len(),
        });
    }
    if let Some(h) = forcing.hours.iter().find(|h| {
        h.beam.is_some_and(|b| {
            b.len() != n || forcing.reflected.get(h.month).is_none_or(|r| r.len() != n)
        })
    }) {
        return Err(PhenomenonError::InvalidParameter {
            phenomenon,
            name: "hour.month",
            value: h.month as f64,
            reason: "no sun maps for this month or beam map of the wrong size",
        });
    }
    Ok(())
}

/// Per-row buffers: the melting hours' shortwave, the table lookups, and each cell's
/// contributions to the sums (reduced in cell order).
struct RowScratch {
    shortwave: Vec<f32>,
    absorbed: Vec<f32>,
    cooling: Vec<f32>,
    warm: Vec<f32>,
    /// Zeros: the rain of a window without any.
    no_rain: Vec<f32>,
    /// 1 on valid cells, 0 on nodata (all ones without a mask).
    keep: Vec<f32>,
    /// refrozen depth, refrozen water, melted depth, melt water, rain on snow, runoff.
    sums: [Vec<f32>; 6],
}

impl RowScratch {
    fn new(w: usize) -> Self {
        Self {
            shortwave: vec![0.0; w],
            no_rain: vec![0.0; w],
            keep: vec![1.0; w],
            absorbed: vec![0.0; w],
            cooling: vec![0.0; w],
            warm: vec![0.0; w],
            sums: std::array::from_fn(|_| vec![0.0; w]),
        }
    }
}

/// The parameters in the units the per-cell loop uses.
struct Coefficients {
    /// Melt threshold T_T, °C.
    threshold: f32,
    /// Albedo by surface age in steps of [`ALBEDO_STEP_DAYS`]: the cold curve's
    /// [`ALBEDO_ENTRIES`], then the melting curve's.
    albedo: Vec<f32>,
    /// Cooling and melting degree-hours of the window by lapse offset.
    degree_hours: DegreeHours,
    /// The scalars of [`column_updates`].
    scalars: Scalars,
}

/// `Σ_h w_h max(0, −T_h)` and `Σ_h w_h [T_h > T_T] T_h` for `T_h = T_sl,h + offset`, tabulated
/// every [`DegreeHours::STEP_C`] of offset: both are piecewise linear in the offset with kinks
/// where an hour crosses 0 or `T_T`, so linear interpolation is exact between kinks and off by
/// at most one hour-weight × step near them (the threshold jump of the melt sum is smeared
/// over one step).
struct DegreeHours {
    offset_min: f32,
    cooling: Vec<f32>,
    warm: Vec<f32>,
}

impl DegreeHours {
    const STEP_C: f32 = 0.02;

    fn new(hours: &[MeltHour], threshold: f32, offsets: &[f32]) -> Self {
        // (Minimum and maximum are exact in any order: the same range for any thread count.)
        let (lo, hi) = parallel::range(offsets).unwrap_or((0.0, 0.0));
        let n = (((hi - lo) / Self::STEP_C).ceil() as usize + 2).min(1 << 20);
        let (mut cooling, mut warm) = (vec![0.0f32; n], vec![0.0f32; n]);
        for k in 0..n {
            let o = lo + k as f32 * Self::STEP_C;
            for h in hours {
                let t = h.sea_level_c + o;
                cooling[k] += h.weight * (-t).max(0.0);
                if t > threshold {
                    warm[k] += h.weight * t;
                }
            }
        }
        Self {
            offset_min: lo,
            cooling,
            warm,
        }
    }

    /// The sums at `offset` (linear between entries). Indices are converted as `u32` (the
    /// table holds at most 2^20 entries): the vector unit converts eight lanes at once, where
    /// `usize` went through a scalar conversion per cell (melt and stability of the calm
    /// 1024² season 1.46-1.48 -> 1.33-1.39 s).
    #[inline(always)]
    fn at(&self, offset: f32) -> (f32, f32) {
        let (cooling, warm) = (&self.cooling[..], &self.warm[..self.cooling.len()]);
        let x = ((offset - self.offset_min) * (1.0 / Self::STEP_C)).max(0.0);
        let k = (x as u32).min(cooling.len() as u32 - 2) as usize;
        let f = (x - k as f32).min(1.0);
        (
            cooling[k] + f * (cooling[k + 1] - cooling[k]),
            warm[k] + f * (warm[k + 1] - warm[k]),
        )
    }
}

/// The albedo by surface age in steps of [`ALBEDO_STEP_DAYS`]: the cold curve's
/// [`ALBEDO_ENTRIES`], then the melting curve's.
pub(super) fn albedo_table(p: &EnhancedMeltParams) -> Vec<f32> {
    [false, true]
        .iter()
        .flat_map(|&melting| {
            (0..ALBEDO_ENTRIES).map(move |k| p.albedo(k as f32 * ALBEDO_STEP_DAYS, melting))
        })
        .collect()
}

/// [`EnhancedMeltParams::albedo`] from [`albedo_table`]'s `table` (linear between entries).
/// Indices as in [`DegreeHours::at`].
#[inline(always)]
pub(super) fn albedo_from_table(table: &[f32], age_days: f32, melting: bool) -> f32 {
    const N: usize = ALBEDO_ENTRIES;
    let t = &table[..2 * N];
    let x = (age_days.max(0.0) * (1.0 / ALBEDO_STEP_DAYS)).min((N - 1) as f32);
    let k = (x as u32).min(N as u32 - 2) as usize;
    let f = x - k as f32;
    let k = k + if melting { N } else { 0 };
    t[k] + f * (t[k + 1] - t[k])
}

/// Age step of the albedo table, days.
const ALBEDO_STEP_DAYS: f32 = 0.05;
/// Ages beyond this use the last entry, days (both curves reach α_min well before).
const ALBEDO_MAX_DAYS: f32 = 400.0;
/// Entries of each albedo curve's table.
const ALBEDO_ENTRIES: usize = (ALBEDO_MAX_DAYS / ALBEDO_STEP_DAYS) as usize + 1;

impl Coefficients {
    fn new(p: &EnhancedMeltParams, f: &MeltForcing) -> Self {
        let mean_sea_level = f.mean_sea_level_c();
        let longwave_wh: f32 = f
            .hours
            .iter()
            .map(|h| h.weight * h.longwave_balance_w_m2)
            .sum();
        let longwave_m =
            (longwave_wh as f64 * 3600.0 / (LATENT_HEAT_FUSION * WATER_DENSITY)) as f32;
        let scalars = Scalars {
            f_t: (p.f_t_mm_per_h_c * 1e-3) as f32,
            f_r: (p.f_r_mm_per_h_w_m2 * 1e-3) as f32,
            longwave_m,
            rain_heat: (SPECIFIC_HEAT_WATER / LATENT_HEAT_FUSION) as f32,
            mean_sea_level,
            cold_per_c: (SPECIFIC_HEAT_ICE / LATENT_HEAT_FUSION) as f32,
            k_cc: (p.cold_content_mm_per_h_c * 1e-3) as f32,
            holding: p.liquid_holding_capacity as f32,
            water_per_depth: p.layer_density_kg_m3.map(|d| (d / WATER_DENSITY) as f32),
            depth_per_water: p.layer_density_kg_m3.map(|d| (WATER_DENSITY / d) as f32),
            window_days: f.window_days,
        };
        Self {
            scalars,
            degree_hours: DegreeHours::new(f.hours, p.threshold_c as f32, f.lapse_offset_c),
            threshold: p.threshold_c as f32,
            albedo: albedo_table(p),
        }
    }

    /// [`EnhancedMeltParams::albedo`] from the table (linear between entries).
    #[inline(always)]
    fn albedo_at(&self, age_days: f32, melting: bool) -> f32 {
        albedo_from_table(&self.albedo, age_days, melting)
    }

    /// Per cell of a row with lapse offsets `off`: the absorbed share `1 − α` of its surface
    /// (of its age, on the curve `melting` selects) and the window's cooling and melting
    /// degree-hours, from the tables: eight cells at a time with AVX2 gathers where the build
    /// has AVX2 (`gathers.rs`, the same bits), the rest cell by cell
    /// ([`Coefficients::lookups_scalar`]).
    fn lookups(
        &self,
        off: &[f32],
        (age, melting): (&[f32], &[f32]),
        (absorbed, cooling, warm): (&mut [f32], &mut [f32], &mut [f32]),
    ) {
        let w = off.len();
        let (age, melting) = (&age[..w], &melting[..w]);
        let (absorbed, cooling, warm) = (&mut absorbed[..w], &mut cooling[..w], &mut warm[..w]);
        #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
        let done = self.lookups_avx2(off, (age, melting), (absorbed, cooling, warm));
        #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
        let done = 0;
        self.lookups_scalar(
            &off[done..],
            (&age[done..], &melting[done..]),
            (
                &mut absorbed[done..],
                &mut cooling[done..],
                &mut warm[done..],
            ),
        );
    }

    /// [`Coefficients::lookups`] cell by cell.
    fn lookups_scalar(
        &self,
        off: &[f32],
        (age, melting): (&[f32], &[f32]),
        (absorbed, cooling, warm): (&mut [f32], &mut [f32], &mut [f32]),
    ) {
        for col in 0..off.len() {
            absorbed[col] = 1.0 - self.albedo_at(age[col], melting[col] > 0.5);
        }
        for col in 0..off.len() {
            (cooling[col], warm[col]) = self.degree_hours.at(off[col]);
        }
    }

    /// The window on one row starting at cell `base` (module docs), in two passes: the
    /// table lookups, then the column updates written without data-dependent branches, so
    /// the cells of a row overlap in the pipeline (and vectorise) instead of waiting on one
    /// another's long dependency chains.
    fn row(
        &self,
        f: &MeltForcing,
        base: usize,
        st: RowState,
        rain: Option<&[f32]>,
        invalid: Option<&[bool]>,
        sc: &mut RowScratch,
    ) -> RowSums {
        let w = sc.shortwave.len();
        let off = &f.lapse_offset_c[base..base + w];
        self.lookups(
            off,
            (&st.age[..w], &st.melting[..w]),
            (&mut sc.absorbed, &mut sc.cooling, &mut sc.warm),
        );
        // Without a mask `keep` stays all ones, and without rain the zeros of `no_rain` are
        // read (no per-row copies).
        if let Some(v) = invalid {
            for (k, &bad) in sc.keep.iter_mut().zip(&v[..w]) {
                *k = if bad { 0.0 } else { 1.0 };
            }
        }
        let rain = rain.unwrap_or(&sc.no_rain);
        let sums = column_updates(
            &self.scalars,
            Columns {
                off,
                shortwave: &sc.shortwave,
                absorbed: &sc.absorbed,
                cooling: &sc.cooling,
                warm: &sc.warm,
                rain,
                keep: &sc.keep,
            },
            st,
            &mut sc.sums,
        );
        let [s_rd, s_rw, s_md, s_mw, s_rain, s_ro] = sums;
        let total = |v: &[f32]| crate::row_sum(v);
        let [s_rd, s_rw, s_md, s_mw, s_rain, s_ro] =
            [s_rd, s_rw, s_md, s_mw, s_rain, s_ro].map(|v| &**v);
        RowSums {
            refrozen_snow: total(s_rd),
            refrozen_water: total(s_rw),
            melted_snow: total(s_md),
            melt_water: total(s_mw),
            rain: total(s_rain),
            runoff: total(s_ro),
        }
    }
}

/// `Σ_h w_h [T_h > T_T] I_sw,h` (W h/m²) of the cells of one row starting at cell `base`
/// (`threshold` = `T_T`), hour by hour over the row (vectorised: AVX2 where the CPU has it, the
/// same bits as SSE since Rust does not fuse multiply-adds), skipping hours too cold anywhere
/// in the row.
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn row_shortwave(threshold: f32, f: &MeltForcing, base: usize, out: &mut [f32]) {
    out.fill(0.0);
    let w = out.len();
    let off = &f.lapse_offset_c[base..base + w];
    let svf = &f.sky_view_factor[base..base + w];
    let warmest_offset = off.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let thr = threshold;
    for h in f.hours {
        if h.sea_level_c + warmest_offset <= thr {
            continue;
        }
        let (t0, wt) = (h.sea_level_c, h.weight);

        match h.beam {
            Some(beam) => {
                let beam = &beam[base..base + w];
                let refl = &f.reflected[h.month][base..base + w];
                let (direct, diffuse, reflected) = (
                    wt * h.direct_w_m2 * (1.0 / 255.0),
                    wt * h.diffuse_w_m2,
                    wt * h.reflected_w_m2,
                );
                for ((((o, &b), &r), &v), &z) in
                    out.iter_mut().zip(beam).zip(refl).zip(svf).zip(off)
                {
                    let sw = diffuse * v + direct * b as f32 + reflected * r;
                    *o += if t0 + z > thr { sw } else { 0.0 };
                }
            }
            None if h.diffuse_w_m2 > 0.0 => {
                let diffuse = wt * h.diffuse_w_m2;
                for ((o, &v), &z) in out.iter_mut().zip(svf).zip(off) {
                    *o += if t0 + z > thr { diffuse * v } else { 0.0 };
                }
            }
            None => {}
        }
    }
}

mod columns;
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
mod gathers;
use columns::{Columns, RowState, Scalars, column_updates};

#[cfg(test)]
mod tests;
