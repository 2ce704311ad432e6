//! Snowfall. The season's default (`model = "orographic"`, [`add_precipitation`]) takes the
//! precipitation at a reference altitude, scales it by the orographic factor of
//! [`crate::climate`], splits rain from snow by the cell's air temperature and adds the snow
//! water at each layer's density; the paper's law (`model = "cordonnier"`, [`step`]) is below.
//! Both share the layer split.
//!
//! **Cordonnier et al. 2018, Section 5.1.** Depth added per precipitation step (Foehn rule):
//! `ΔD = δt_p · k_snow · max(0, A − A0_precip)`, with `A = B + D` the snow-surface altitude.
//!
//! The new snow is split between layers:
//! - powder share `x_P = k_powdery (‖∇A‖ − s_c)`, clamped to [0, 1], with the critical slope
//!   rising as the ground gets colder: `s_c = s_c0 + k_sc · max(0, T0_powdery − T)`;
//! - of the rest, the unstable share `x_U = k_unstable (s − s_U)`, clamped to [0, 1], where `s`
//!   is the slope angle; the remainder is stable snow.
//!
//! The paper leaves `k_powdery`, `s_c0`, `k_sc`, `k_unstable` and `s_U` to the user; the
//! defaults below are ours, chosen so that snow bonds on slopes up to ~35° at −10 °C
//! (steeper faces hold mostly powder that later diffuses and blows away), and that new snow
//! on slopes between 25° and 45° is increasingly unstable — the slopes where slab avalanches
//! start in practice. The tests check the behaviour these values produce.

use crate::phenomenon::{
    PhenomenonError, Validity, check_dt, check_map, check_range, fill_surface, row_gradient_norm,
    with_validity,
};
use crate::{VolumeChange, ordered_sum};
use serde::{Deserialize, Serialize};
use snowscape_terrain::{LayeredTerrain, parallel};

/// Which snowfall law a season uses.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum SnowfallModel {
    /// Precipitation with an orographic gradient and a temperature phase ([`add_precipitation`]).
    #[default]
    Orographic,
    /// Cordonnier 2018 §5.1: `k_snow · max(0, A − A0_precip)`.
    Cordonnier,
}

/// Parameters of snowfall.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct SnowfallParams {
    /// The snowfall law (`orographic` or `cordonnier`).
    pub model: SnowfallModel,
    /// Snowfall rate per metre of altitude above `a0_precip`, m of snow per day per m
    /// (1/day). Cordonnier 2018 Table 2: k_snow = 1e-4.
    pub k_snow: f64,
    /// Rain-snow limit: altitude below which precipitation falls as rain, m. User-set in the
    /// paper (Table 2, A0precip); our default puts it at a typical mid-winter 800 m.
    pub a0_precip: f64,
    /// Powder share per unit of surface gradient above the critical slope (dimensionless).
    /// Chosen here: 1.0 (all powder once the gradient exceeds s_c by 1, i.e. ~35° → ~60°).
    pub k_powdery: f64,
    /// Critical gradient ‖∇A‖ above which new snow stays powder, at or above T0_powdery
    /// (dimensionless, tan of the slope). Chosen here: 0.7 (35°).
    pub sc0: f64,
    /// Rise of the critical gradient per °C below T0_powdery, 1/°C. Chosen here: 0.02.
    pub k_sc_powdery: f64,
    /// Temperature below which the critical slope rises, °C. Cordonnier 2018 Table 2: −10.
    pub t0_powdery: f64,
    /// Unstable share per degree of slope above `s_u`, 1/degree. Chosen here: 1/20.
    pub k_unstable: f64,
    /// Slope below which new snow is stable, degrees. Chosen here: 25.
    pub s_u_deg: f64,
}

impl Default for SnowfallParams {
    fn default() -> Self {
        Self {
            model: SnowfallModel::default(),
            k_snow: 1e-4,
            a0_precip: 800.0,
            k_powdery: 1.0,
            sc0: 0.7,
            k_sc_powdery: 0.02,
            t0_powdery: -10.0,
            k_unstable: 1.0 / 20.0,
            s_u_deg: 25.0,
        }
    }
}

impl SnowfallParams {
    /// Checks every field against its range (the message states it): `k_snow` in
    /// [0, 0.01] 1/day (a hundred times Table 2's 1e-4), `a0_precip` in [−1000, 9000] m,
    /// `k_powdery` in [0, 100], `sc0` in [0, 10], `k_sc_powdery` in [0, 1] 1/°C,
    /// `t0_powdery` in [−50, 10] °C, `k_unstable` in [0, 1] 1/°, `s_u_deg` in [0, 90] °.
    pub fn validate(&self) -> Result<(), PhenomenonError> {
        const P: &str = "snowfall";
        check_range(P, "k_snow", self.k_snow, [0.0, 0.01], " 1/day")?;
        check_range(P, "a0_precip", self.a0_precip, [-1000.0, 9000.0], " m")?;
        check_range(P, "k_powdery", self.k_powdery, [0.0, 100.0], "")?;
        check_range(P, "sc0", self.sc0, [0.0, 10.0], "")?;
        check_range(P, "k_sc_powdery", self.k_sc_powdery, [0.0, 1.0], " 1/°C")?;
        check_range(P, "t0_powdery", self.t0_powdery, [-50.0, 10.0], " °C")?;
        check_range(P, "k_unstable", self.k_unstable, [0.0, 1.0], " 1/°")?;
        check_range(P, "s_u_deg", self.s_u_deg, [0.0, 90.0], " °")
    }
}

/// Reusable buffers of the snowfall step.
#[derive(Debug, Clone, Default)]
pub struct SnowfallScratch {
    surface: Vec<f32>,
}

/// How new snow at one cell is shared between layers: (powder, unstable, stable), summing to 1.
pub fn layer_shares(
    params: &SnowfallParams,
    gradient_norm: f64,
    temperature: f64,
) -> (f64, f64, f64) {
    let (p, u, s) = ShareCoefficients::new(params).shares(gradient_norm as f32, temperature as f32);
    (p as f64, u as f64, s as f64)
}

/// The parameters of [`layer_shares`] in the f32 form the per-cell loop uses.
#[derive(Debug, Clone, Copy)]
struct ShareCoefficients {
    sc0: f32,
    k_sc: f32,
    t0_powdery: f32,
    k_powdery: f32,
    k_unstable: f32,
    s_u_deg: f32,
    /// Surface gradients (tan) at or below which the unstable fraction is surely 0, and at or
    /// above which it is surely 1: 0.01° inside the ramp's ends, a hundred times the f32
    /// error of the slope in degrees, so that the `atan` is only evaluated on the ramp and
    /// the shares keep their bits.
    flat_below: f32,
    steep_above: f32,
}

impl ShareCoefficients {
    fn new(p: &SnowfallParams) -> Self {
        Self {
            sc0: p.sc0 as f32,
            k_sc: p.k_sc_powdery as f32,
            t0_powdery: p.t0_powdery as f32,
            k_powdery: p.k_powdery as f32,
            k_unstable: p.k_unstable as f32,
            s_u_deg: p.s_u_deg as f32,
            // (k_u = 0 keeps the formula, whose −0 the shortcut would not reproduce.)
            flat_below: if p.k_unstable >= 1e-6 {
                tan_deg(p.s_u_deg - 0.01)
            } else {
                -1.0
            },
            steep_above: if p.k_unstable >= 1e-6 {
                tan_deg(p.s_u_deg + 1.0 / p.k_unstable + 0.01)
            } else {
                f32::INFINITY
            },
        }
    }

    #[inline(always)]
    fn shares(&self, gradient_norm: f32, temperature: f32) -> (f32, f32, f32) {
        let sc = self.sc0 + self.k_sc * (self.t0_powdery - temperature).max(0.0);
        let x_p = (self.k_powdery * (gradient_norm - sc)).clamp(0.0, 1.0);
        let x_u = if gradient_norm <= self.flat_below {
            0.0
        } else if gradient_norm >= self.steep_above {
            1.0
        } else {
            let slope_deg = gradient_norm.atan().to_degrees();
            (self.k_unstable * (slope_deg - self.s_u_deg)).clamp(0.0, 1.0)
        };
        let rest = 1.0 - x_p;
        (x_p, rest * x_u, rest * (1.0 - x_u))
    }
}

/// `tan` of a slope in degrees as f32: −1 below 0° (no gradient is that low), infinite from
/// 90° (none is that high).
fn tan_deg(deg: f64) -> f32 {
    if deg < 0.0 {
        -1.0
    } else if deg >= 90.0 {
        f32::INFINITY
    } else {
        deg.to_radians().tan() as f32
    }
}

/// Adds `dt_days` of snowfall. `temperature` is the per-cell air temperature, °C.
pub fn step(
    params: &SnowfallParams,
    terrain: &mut LayeredTerrain,
    temperature: &[f32],
    scratch: &mut SnowfallScratch,
    dt_days: f64,
) -> Result<VolumeChange, PhenomenonError> {
    params.validate()?;
    check_dt(dt_days)?;
    let geometry = terrain.geometry().clone();
    check_map("temperature", temperature, &geometry)?;
    let mask = terrain.mask().clone();
    let w = geometry.width();
    fill_surface(terrain, &mut scratch.surface);
    let surf = &scratch.surface;
    let rate = (dt_days * params.k_snow) as f32;
    let a0 = params.a0_precip as f32;
    let k = ShareCoefficients::new(params);
    let [_, stable, unstable, powder] = &mut terrain.snow;
    let row_added: Vec<f64> = with_validity!(mask, |valid| {
        parallel::map_rows_with(
            w,
            (stable, unstable, powder),
            || vec![0.0f32; w],
            |gradient, row, (st, un, pw)| {
                row_gradient_norm(surf, &geometry, &mask, valid, row, gradient);
                let mut added = 0.0f64;
                for col in 0..w {
                    let i = row * w + col;
                    let depth = rate * (surf[i] - a0).max(0.0);
                    if depth <= 0.0 || !valid.at(i) {
                        continue;
                    }
                    let (xp, xu, _) = k.shares(gradient[col], temperature[i]);
                    let (dp, du) = (depth * xp, depth * xu);
                    // The stable share takes the remainder (never below 0 after rounding).
                    let ds = (depth - dp - du).max(0.0);
                    pw[col] += dp;
                    un[col] += du;
                    st[col] += ds;
                    added += dp as f64 + du as f64 + ds as f64;
                }
                added
            },
        )
    });
    Ok(VolumeChange {
        added: ordered_sum(&row_added) * geometry.cell_area(),
        removed: 0.0,
    })
}

/// One hour (or part of one) of precipitation, as the phase table reads it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrecipitationHour {
    /// Sea-level air temperature, °C (a cell's is this plus its lapse offset).
    pub sea_level_c: f32,
    /// Precipitation at the reference altitude, m of water.
    pub water_m: f32,
    /// Relative humidity of the air, 0..1 (the same at every altitude).
    pub relative_humidity: f32,
}

/// Precipitation of a window at the reference altitude as a function of a cell's lapse
/// offset (its air temperature minus the sea-level one), split into snow and rain by the
/// phase of each hour: a table, so the per-cell cost does not grow with the hours.
#[derive(Debug, Clone, PartialEq)]
pub struct PrecipitationTable {
    offset_min: f32,
    step: f32,
    /// Snow water per offset sample, m.
    snow_m: Vec<f32>,
    /// Rain per offset sample, m.
    rain_m: Vec<f32>,
}

impl PrecipitationTable {
    /// Offsets sampled every 0.05 °C (the phase ramp is linear between samples, so the table
    /// is exact for hours whose ramp corners fall on samples and within 0.05 °C otherwise).
    pub const STEP_C: f32 = 0.05;

    /// The table for precipitation `hours` over lapse offsets in `[offset_min, offset_max]`.
    pub fn new(
        climate: &crate::climate::ClimateParams,
        hours: &[PrecipitationHour],
        offset_min: f32,
        offset_max: f32,
    ) -> Self {
        let n = (((offset_max - offset_min) / Self::STEP_C).ceil() as usize + 2).min(1 << 16);
        let (mut snow_m, mut rain_m) = (vec![0.0f32; n], vec![0.0f32; n]);
        for k in 0..n {
            let offset = offset_min + k as f32 * Self::STEP_C;
            for h in hours {
                let share = climate.snow_share(h.sea_level_c + offset, h.relative_humidity);
                snow_m[k] += h.water_m * share;
                rain_m[k] += h.water_m * (1.0 - share);
            }
        }
        Self {
            offset_min,
            step: Self::STEP_C,
            snow_m,
            rain_m,
        }
    }

    /// (snow, rain) m of water at the reference altitude for a cell of lapse offset `offset`.
    #[inline]
    pub fn at(&self, offset: f32) -> (f32, f32) {
        let x = ((offset - self.offset_min) / self.step).max(0.0);
        let k = (x as usize).min(self.snow_m.len() - 2);
        let f = (x - k as f32).min(1.0);
        (
            self.snow_m[k] + f * (self.snow_m[k + 1] - self.snow_m[k]),
            self.rain_m[k] + f * (self.rain_m[k + 1] - self.rain_m[k]),
        )
    }

    /// Whether the window brought any precipitation.
    pub fn is_dry(&self) -> bool {
        self.snow_m.iter().chain(&self.rain_m).all(|&v| v <= 0.0)
    }
}

/// What [`add_precipitation`] added.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PrecipitationReport {
    /// Snow added, m³ of snow (at the layers' densities).
    pub snow_m3: f64,
    /// Water equivalent of that snow, m³.
    pub snow_water_m3: f64,
    /// Rain on every valid cell, m³ of water (returned per cell in `rain_out`).
    pub rain_m3: f64,
}

/// Per-cell inputs of [`add_precipitation`].
#[derive(Debug, Clone, Copy)]
pub struct PrecipitationMaps<'a> {
    /// Air temperature for the layer split, °C.
    pub temperature: &'a [f32],
    /// Lapse offset of each cell, °C (the phase table's argument).
    pub lapse_offset_c: &'a [f32],
    /// Orographic factor of each cell.
    pub orographic: &'a [f32],
}

/// Where a window's precipitation goes besides the snow layers, and how the snow is laid.
pub struct PrecipitationTargets<'a> {
    /// Density of new snow in each layer (compacted, stable, unstable, powder), kg/m³.
    pub densities_kg_m3: [f64; 4],
    /// Age of the snow surface per cell, days: reset where at least `reset_swe_m` fell.
    pub surface_age: &'a mut [f32],
    /// Snow water that resets the surface age, m.
    pub reset_swe_m: f64,
    /// Rain per cell, m of water, added to (the melt's liquid water).
    pub rain_out: &'a mut [f32],
    /// The altitude band of each cell ([`crate::bands::Bands::band_of`]) and the snow water
    /// and rain summed per band, m of water over its cells, added to.
    pub bands: (&'a [u16], &'a mut [[f64; 2]]),
}

/// Adds a window's precipitation (the orographic model): snow water `s · f_oro` by the
/// layer split of [`layer_shares`], each share at its layer's density; the surface age is
/// reset where at least `reset_swe_m` fell; the rain `r · f_oro` is added to `rain_out`
/// (m of water per cell, for the melt's liquid water).
pub fn add_precipitation(
    params: &SnowfallParams,
    terrain: &mut LayeredTerrain,
    maps: &PrecipitationMaps,
    table: &PrecipitationTable,
    targets: PrecipitationTargets,
    scratch: &mut SnowfallScratch,
) -> Result<PrecipitationReport, PhenomenonError> {
    let PrecipitationTargets {
        densities_kg_m3,
        surface_age,
        reset_swe_m,
        rain_out,
        bands: (band_of, band_water),
    } = targets;
    params.validate()?;
    let geometry = terrain.geometry().clone();
    check_map("temperature", maps.temperature, &geometry)?;
    check_map("lapse offset", maps.lapse_offset_c, &geometry)?;
    check_map("orographic factor", maps.orographic, &geometry)?;
    check_map("surface age", surface_age, &geometry)?;
    check_map("rain", rain_out, &geometry)?;
    check_map("altitude band", band_of, &geometry)?;
    if table.is_dry() {
        return Ok(PrecipitationReport::default());
    }
    let mask = terrain.mask().clone();
    let w = geometry.width();
    fill_surface(terrain, &mut scratch.surface);
    let surf = &scratch.surface;
    let k = ShareCoefficients::new(params);
    let depth_per_water = densities_kg_m3.map(|d| (1000.0 / d) as f32);
    let reset = reset_swe_m as f32;
    let [_, stable, unstable, powder] = &mut terrain.snow;
    let n_bands = band_water.len();
    let rows: Vec<([f64; 3], Vec<[f64; 2]>)> = with_validity!(mask, |valid| {
        parallel::map_rows_with(
            w,
            (stable, unstable, powder, surface_age, rain_out),
            || vec![0.0f32; w],
            |gradient, row, (st, un, pw, age, rain)| {
                row_gradient_norm(surf, &geometry, &mask, valid, row, gradient);
                // Four interleaved partial sums of each term (as `crate::row_sum`).
                let mut sums = [[0.0f64; crate::SUM_LANES]; 3];
                // Per band and lane: snow water and rain.
                let mut by_band = vec![[0.0f64; 2]; n_bands * crate::SUM_LANES];
                for col in 0..w {
                    let i = row * w + col;
                    let lane = col % crate::SUM_LANES;
                    if !valid.at(i) {
                        continue;
                    }
                    let (s_ref, r_ref) = table.at(maps.lapse_offset_c[i]);
                    let oro = maps.orographic[i];
                    let (swe, r) = (s_ref * oro, r_ref * oro);
                    rain[col] += r;
                    sums[2][lane] += r as f64;
                    let band = by_band.get_mut(band_of[i] as usize * crate::SUM_LANES + lane);
                    if swe <= 0.0 {
                        if let Some(b) = band {
                            b[1] += r as f64;
                        }
                        continue;
                    }
                    let (xp, xu, _) = k.shares(gradient[col], maps.temperature[i]);
                    let (wp, wu) = (swe * xp, swe * xu);
                    let ws = (swe - wp - wu).max(0.0);
                    let (dp, du, ds) = (
                        wp * depth_per_water[3],
                        wu * depth_per_water[2],
                        ws * depth_per_water[1],
                    );
                    pw[col] += dp;
                    un[col] += du;
                    st[col] += ds;
                    if swe >= reset {
                        age[col] = 0.0;
                    }
                    sums[0][lane] += dp as f64 + du as f64 + ds as f64;
                    sums[1][lane] += (wp + wu + ws) as f64;
                    if let Some(b) = band {
                        b[0] += (wp + wu + ws) as f64;
                        b[1] += r as f64;
                    }
                }
                (sums.map(crate::lane_total), by_band)
            },
        )
    });
    let a = geometry.cell_area();
    let mut r = PrecipitationReport::default();
    for (s, by_band) in rows {
        r.snow_m3 += s[0] * a;
        r.snow_water_m3 += s[1] * a;
        r.rain_m3 += s[2] * a;
        for (total, lanes) in band_water
            .iter_mut()
            .zip(by_band.chunks_exact(crate::SUM_LANES))
        {
            total[0] += crate::lane_total(std::array::from_fn(|l| lanes[l][0]));
            total[1] += crate::lane_total(std::array::from_fn(|l| lanes[l][1]));
        }
    }
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_terrain::{Grid, GridGeometry, SnowLayer};

    fn plane(alt: f32) -> LayeredTerrain {
        LayeredTerrain::from_bedrock(Grid::filled(GridGeometry::square(8, 8, 10.0).unwrap(), alt))
    }

    #[test]
    fn shares_skip_the_atan_off_the_ramp_without_changing_a_bit() {
        for (s_u, k_u) in [
            (30.0, 0.05),
            (0.0, 0.05),
            (85.0, 0.01),
            (40.0, 0.0),
            (10.0, 1.0),
        ] {
            let p = SnowfallParams {
                s_u_deg: s_u,
                k_unstable: k_u,
                ..SnowfallParams::default()
            };
            let k = ShareCoefficients::new(&p);
            let mut g = 0.0f32;
            while g < 40.0 {
                let (xp, xu, xs) = k.shares(g, -5.0);
                let deg = g.atan().to_degrees();
                let sc = k.sc0 + k.k_sc * (k.t0_powdery + 5.0).max(0.0);
                let want_p = (k.k_powdery * (g - sc)).clamp(0.0, 1.0);
                let want_u = (k.k_unstable * (deg - k.s_u_deg)).clamp(0.0, 1.0);
                let rest = 1.0 - want_p;
                assert_eq!(
                    (xp.to_bits(), xu.to_bits(), xs.to_bits()),
                    (
                        want_p.to_bits(),
                        (rest * want_u).to_bits(),
                        (rest * (1.0 - want_u)).to_bits()
                    ),
                    "s_u {s_u} k_u {k_u} gradient {g}"
                );
                // Fine steps near the ramp's ends, coarser beyond.
                g = if g < 3.0 { g + 1e-4 } else { g * 1.001 };
            }
        }
    }

    #[test]
    fn flat_plane_gets_uniform_stable_snow_above_the_rain_limit() {
        let p = SnowfallParams::default();
        let mut t = plane(1800.0);
        let temp = vec![-8.0f32; 64];
        let v = step(&p, &mut t, &temp, &mut SnowfallScratch::default(), 1.0).unwrap();
        let expect = 1e-4 * 1000.0;
        for i in 0..64 {
            assert!((t.layer(SnowLayer::Stable)[i] as f64 - expect).abs() < 1e-6);
            assert_eq!(t.layer(SnowLayer::Powder)[i], 0.0);
            assert_eq!(t.layer(SnowLayer::Unstable)[i], 0.0);
        }
        assert!(
            (v.added - expect * 6400.0).abs() < 1e-6 * expect * 6400.0,
            "{}",
            v.added
        );
    }

    #[test]
    fn no_snow_below_the_rain_limit() {
        let mut t = plane(500.0);
        let v = step(
            &SnowfallParams::default(),
            &mut t,
            &[0.0; 64],
            &mut SnowfallScratch::default(),
            1.0,
        )
        .unwrap();
        assert_eq!(v.added, 0.0);
        assert_eq!(t.total_depth().iter().sum::<f32>(), 0.0);
    }

    #[test]
    fn steep_slopes_get_powder_and_unstable_snow() {
        let p = SnowfallParams::default();
        let (xp_flat, xu_flat, _) = layer_shares(&p, 0.0, -5.0);
        assert_eq!((xp_flat, xu_flat), (0.0, 0.0));
        let (_, xu_40, _) = layer_shares(&p, 40f64.to_radians().tan(), -5.0);
        assert!(xu_40 > 0.5, "{xu_40}");
        let (xp_60, _, _) = layer_shares(&p, 60f64.to_radians().tan(), -5.0);
        assert!(xp_60 > 0.9, "{xp_60}");
        // Colder ground holds snow on steeper slopes.
        let (xp_cold, _, _) = layer_shares(&p, 45f64.to_radians().tan(), -30.0);
        let (xp_mild, _, _) = layer_shares(&p, 45f64.to_radians().tan(), -5.0);
        assert!(xp_cold < xp_mild);
        let (a, b, c) = layer_shares(&p, 0.9, -12.0);
        assert!((a + b + c - 1.0).abs() < 1e-6);
    }
}
