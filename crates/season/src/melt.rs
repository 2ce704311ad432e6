//! Melt: the season's default is the surface energy balance snowpack of [`energy_balance`]
//! (`model = "energy_balance"`: after FSM, Essery 2015, with sublimation and deposition); the
//! enhanced temperature-index model of [`enhanced`] stays available (`model = "enhanced_ti"`:
//! Hock 1999, Pellicciotti et al. 2005, with albedo decay, cold content and refreezing), and
//! `model = "cordonnier"` is the paper's degree-day law below.
//!
//! **Cordonnier et al. 2018, Section 5.2, first equation.**
//!
//! `D(t + δt_m) = D(t) − δt_m · k_melt · max(0, T − T0_melt)`: a degree-day law. The melted
//! depth is taken layer by layer from the top: powder, then unstable, stable and compacted
//! snow (the paper: "from top (unstable) to bottom (compact)"; powder lies above unstable
//! snow, so it goes first). Melt water leaves the model, as in the paper: the step reports the
//! removed volume.

use crate::phenomenon::{
    PhenomenonError, Validity, check_dt, check_map, check_range, with_validity,
};
use crate::{VolumeChange, ordered_sum};
use serde::{Deserialize, Serialize};
use snowscape_terrain::{LayeredTerrain, parallel};

pub mod energy_balance;
pub mod enhanced;
pub use energy_balance::EnergyBalanceParams;
pub use enhanced::{EnhancedMeltParams, HourAir, MeltForcing, MeltHour, MeltReport, SnowpackState};

/// Which melt law a season uses.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum MeltModel {
    /// Surface energy balance per cell and hour with a bulk pack, sublimation and deposition
    /// ([`energy_balance`]). The default.
    #[default]
    EnergyBalance,
    /// Enhanced temperature index with the hour-by-hour sun, albedo, cold content and
    /// refreezing ([`enhanced`]).
    EnhancedTi,
    /// Cordonnier 2018 §5.2: `k_melt · max(0, T − T0_melt)` on the period's temperature map
    /// (which carries the sun as `ki·I`).
    Cordonnier,
}

impl MeltModel {
    /// Whether the model integrates the hourly air and sun in melt windows (the energy
    /// balance and the enhanced temperature index; the paper's law reads the period's map).
    pub fn hourly(self) -> bool {
        self != MeltModel::Cordonnier
    }
}

/// Parameters of melt.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct MeltParams {
    /// The melt law (`energy_balance`, `enhanced_ti` or `cordonnier`).
    pub model: MeltModel,
    /// The energy balance's parameters (`[parameters.melt.energy_balance]`).
    pub energy_balance: EnergyBalanceParams,
    /// The enhanced temperature-index parameters (`[parameters.melt.enhanced]`); its albedo
    /// curves, holding capacity, layer densities and window serve the energy balance too.
    pub enhanced: EnhancedMeltParams,
    /// Melt rate, m of snow per day per °C above `t0_melt`. Cordonnier 2018 Section 5.2 and
    /// Table 2: k_melt = 0.01 m day⁻¹ °C⁻¹.
    pub k_melt: f64,
    /// Temperature above which snow melts, °C. Cordonnier 2018 Table 2: T0_melt = 0 °C.
    pub t0_melt: f64,
}

impl Default for MeltParams {
    fn default() -> Self {
        Self {
            model: MeltModel::default(),
            energy_balance: EnergyBalanceParams::default(),
            enhanced: EnhancedMeltParams::default(),
            k_melt: 0.01,
            t0_melt: 0.0,
        }
    }
}

impl MeltParams {
    /// Checks every field against its range: `k_melt` in [0, 0.1] m/(day·°C) (ten times
    /// Table 2's 0.01), `t0_melt` in [−10, 10] °C, and the other models' fields.
    pub fn validate(&self) -> Result<(), PhenomenonError> {
        self.enhanced.validate()?;
        self.energy_balance.validate()?;
        check_range("melt", "k_melt", self.k_melt, [0.0, 0.1], " m/(day·°C)")?;
        check_range("melt", "t0_melt", self.t0_melt, [-10.0, 10.0], " °C")
    }
}

/// Depth of snow melted over `dt_days` at `temperature` °C, m (degree-day law).
#[inline(always)]
pub fn melt_depth(params: &MeltParams, temperature: f32, dt_days: f64) -> f32 {
    let rate = (dt_days * params.k_melt) as f32;
    rate * (temperature - params.t0_melt as f32).max(0.0)
}

/// Removes up to `depth` metres from the column `layers` (bottom to top: compacted, stable,
/// unstable, powder), top layer first. Returns the depth actually removed. Branch-free.
#[inline(always)]
pub fn remove_top_down(layers: [&mut f32; 4], depth: f32) -> f32 {
    let mut left = depth;
    for layer in layers.into_iter().rev() {
        let take = left.min(*layer);
        *layer -= take;
        left -= take;
    }
    depth - left
}

/// Melts `dt_days` of snow at the per-cell air temperature `temperature` (°C).
pub fn step(
    params: &MeltParams,
    terrain: &mut LayeredTerrain,
    temperature: &[f32],
    dt_days: f64,
) -> Result<VolumeChange, PhenomenonError> {
    params.validate()?;
    check_dt(dt_days)?;
    let geometry = terrain.geometry().clone();
    check_map("temperature", temperature, &geometry)?;
    let mask = terrain.mask().clone();
    let row_removed = with_validity!(mask, |valid| melt_rows(
        params,
        terrain,
        temperature,
        valid,
        dt_days
    ));
    Ok(VolumeChange {
        added: 0.0,
        removed: ordered_sum(&row_removed) * geometry.cell_area(),
    })
}

/// Melts every row; returns the depth removed per row, m.
fn melt_rows<V: Validity>(
    params: &MeltParams,
    terrain: &mut LayeredTerrain,
    temperature: &[f32],
    valid: &V,
    dt_days: f64,
) -> Vec<f64> {
    let w = terrain.geometry().width();
    let [compacted, stable, unstable, powder] = &mut terrain.snow;
    parallel::map_rows_with(
        w,
        (compacted, stable, unstable, powder, temperature),
        || vec![0.0f32; w],
        |removed, row, (c, s, u, p, t)| {
            // A row where nothing is warm enough melts nothing: skip it without touching
            // (and dirtying) its four layer rows, which is most rows in a cold spell.
            let t0 = params.t0_melt as f32;
            if t.iter().all(|&x| x <= t0) {
                return 0.0;
            }
            let (c, s, u, p, t) = (&mut c[..w], &mut s[..w], &mut u[..w], &mut p[..w], &t[..w]);
            let removed = &mut removed[..w];
            for col in 0..w {
                // A nodata cell melts nothing (its temperature may be anything).
                let depth = if valid.at(row * w + col) {
                    melt_depth(params, t[col], dt_days)
                } else {
                    0.0
                };
                let layers = [&mut c[col], &mut s[col], &mut u[col], &mut p[col]];
                removed[col] = remove_top_down(layers, depth);
            }
            crate::row_sum(removed)
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_terrain::{Grid, GridGeometry, NodataMask, SnowLayer};

    fn column(c: f32, s: f32, u: f32, p: f32) -> LayeredTerrain {
        let mut t = LayeredTerrain::from_bedrock(Grid::filled(
            GridGeometry::square(1, 1, 2.0).unwrap(),
            0.0,
        ));
        for (layer, v) in SnowLayer::ALL.into_iter().zip([c, s, u, p]) {
            t.layer_mut(layer)[0] = v;
        }
        t
    }

    fn layers(t: &LayeredTerrain) -> [f32; 4] {
        SnowLayer::ALL.map(|l| t.layer(l)[0])
    }

    #[test]
    fn melt_removes_layers_from_the_top_down() {
        let p = MeltParams::default();
        // 0.01 m/day/°C at 10 °C for 1 day: 0.1 m, all from the 0.1 m of powder.
        let mut t = column(0.2, 0.2, 0.2, 0.1);
        let v = step(&p, &mut t, &[10.0], 1.0).unwrap();
        let l = layers(&t);
        assert!(l[3].abs() < 1e-7 && (l[2] - 0.2).abs() < 1e-7, "{l:?}");
        assert!((v.removed - 0.1 * 4.0).abs() < 1e-6, "{v:?}");
        // Another 0.3 m: the rest of the unstable layer and 0.1 m of stable snow.
        step(&p, &mut t, &[10.0], 3.0).unwrap();
        let l = layers(&t);
        assert!(
            l[2].abs() < 1e-7 && (l[1] - 0.1).abs() < 1e-6 && l[0] == 0.2,
            "{l:?}"
        );
        // Melting more than there is leaves bare ground and reports only what was there.
        let v = step(&p, &mut t, &[20.0], 10.0).unwrap();
        assert_eq!(layers(&t), [0.0; 4]);
        assert!((v.removed - 0.3 * 4.0).abs() < 1e-5, "{v:?}");
        assert!(t.check_invariants().is_ok());
    }

    #[test]
    fn no_melt_at_or_below_the_melt_temperature() {
        let mut t = column(0.1, 0.1, 0.1, 0.1);
        for temp in [0.0, -3.0, -40.0] {
            let v = step(&MeltParams::default(), &mut t, &[temp], 1.0).unwrap();
            assert_eq!(v.removed, 0.0);
        }
        assert_eq!(layers(&t), [0.1; 4]);
        assert!((melt_depth(&MeltParams::default(), 2.5, 0.5) - 0.0125).abs() < 1e-7);
    }

    #[test]
    fn nodata_cells_and_bad_inputs() {
        let geo = GridGeometry::square(2, 1, 1.0).unwrap();
        let bed = Grid::new(
            geo,
            vec![0.0; 2],
            NodataMask::from_invalid(vec![false, true]),
        )
        .unwrap();
        let mut t = LayeredTerrain::from_bedrock(bed);
        t.layer_mut(SnowLayer::Powder)[0] = 0.5;
        let v = step(&MeltParams::default(), &mut t, &[5.0, f32::NAN], 1.0).unwrap();
        assert!((v.removed - 0.05).abs() < 1e-6);
        assert!(t.check_invariants().is_ok());
        let e = step(&MeltParams::default(), &mut t, &[5.0], 1.0).unwrap_err();
        assert!(matches!(
            e,
            PhenomenonError::MapLength {
                actual: 1,
                expected: 2,
                ..
            }
        ));
        let bad = MeltParams {
            k_melt: -1.0,
            ..Default::default()
        };
        assert!(step(&bad, &mut t, &[5.0, 5.0], 1.0).is_err());
        assert!(step(&MeltParams::default(), &mut t, &[5.0, 5.0], f64::NAN).is_err());
    }
}
