//! Conversions between snow layers and flowing snow.
//!
//! [`release`] turns snow into flowing snow: by default the unstable layer and the powder on top
//! (Cordonnier et al. 2018, Section 6.1: "only the unstable layer U and the powdery snow P on
//! top are subject to avalanche redistribution"), or a given thickness taken from the top of the
//! snow pack down (powder, unstable, stable, compacted; taking stable or compacted snow lowers
//! the avalanche bed). [`deposit`] turns flowing snow back into a snow layer. The layer is the
//! caller's choice; avalanche debris is dense, sintered snow, so [`SnowLayer::Stable`] is the
//! natural target (chosen here: it no longer releases, and becomes part of the bed of later
//! avalanches); depositing into stable or compacted snow raises the bed by the deposit.
//! Terrain layers are f32, the flow state f64: a round trip is exact to f32 rounding.

use crate::flow::{AvalancheError, AvalancheState};
use snowscape_terrain::{LayeredTerrain, SnowLayer};

fn check_terrain(terrain: &LayeredTerrain, state: &AvalancheState) -> Result<(), AvalancheError> {
    let (g, t) = (state.geometry(), terrain.geometry());
    if g.width() != t.width() || g.height() != t.height() {
        return Err(AvalancheError::GeometryMismatch {
            width: g.width(),
            height: g.height(),
            terrain_width: t.width(),
            terrain_height: t.height(),
        });
    }
    Ok(())
}

/// Releases snow of the cells where `cells` is true (row-major, one flag per grid cell) into
/// flowing snow. `thickness: None` releases all unstable snow and powder; `Some(t)` releases up
/// to `t` metres taken from the top of the snow pack. Returns the released volume, m³.
pub fn release(
    terrain: &mut LayeredTerrain,
    state: &mut AvalancheState,
    cells: &[bool],
    thickness: Option<f64>,
) -> Result<f64, AvalancheError> {
    check_terrain(terrain, state)?;
    let n = terrain.bedrock.len();
    if cells.len() != n {
        return Err(AvalancheError::LengthMismatch {
            what: "release cells",
            got: cells.len(),
            expected: n,
        });
    }
    if let Some(t) = thickness
        && !(t.is_finite() && t >= 0.0)
    {
        return Err(AvalancheError::BadValue {
            what: "release thickness",
            index: 0,
            value: t,
        });
    }
    let w = terrain.geometry().width();
    let area = terrain.geometry().cell_area();
    let mut volume = 0.0;
    let mask = terrain.mask().clone();
    for (i, _) in cells
        .iter()
        .enumerate()
        .filter(|(i, c)| **c && mask.is_valid(*i))
    {
        let (col, row) = (i % w, i / w);
        let k = state.pad(col, row);
        let mut taken = 0.0f64;
        let top_down = [
            SnowLayer::Powder,
            SnowLayer::Unstable,
            SnowLayer::Stable,
            SnowLayer::Compacted,
        ];
        for layer in top_down {
            let have = terrain.layer(layer)[i] as f64;
            let take = match thickness {
                None => {
                    if matches!(layer, SnowLayer::Powder | SnowLayer::Unstable) {
                        have
                    } else {
                        0.0
                    }
                }
                Some(t) => have.min(t - taken).max(0.0),
            };
            if take <= 0.0 {
                continue;
            }
            let left = (have - take).max(0.0) as f32;
            terrain.layer_mut(layer)[i] = left;
            let took = have - left as f64;
            taken += took;
            if matches!(layer, SnowLayer::Stable | SnowLayer::Compacted) {
                state.bed[k] -= took;
            }
        }
        state.h[k] += taken;
        volume += taken * area;
    }
    state.refresh_active();
    Ok(volume)
}

/// Turns flowing snow (and settled films) into `layer`. With `at_rest_only`, only cells whose 8 pipes are all at
/// rest deposit; otherwise every cell does and all motion stops. Returns the deposited
/// volume, m³.
pub fn deposit(
    terrain: &mut LayeredTerrain,
    state: &mut AvalancheState,
    layer: SnowLayer,
    at_rest_only: bool,
) -> Result<f64, AvalancheError> {
    check_terrain(terrain, state)?;
    let g = terrain.geometry().clone();
    let (w, hgt) = (g.width(), g.height());
    let raises_bed = matches!(layer, SnowLayer::Stable | SnowLayer::Compacted);
    let mut volume = 0.0;
    for row in 0..hgt {
        for col in 0..w {
            let k = state.pad(col, row);
            // Settled films are at rest by definition.
            let mut hv = std::mem::take(&mut state.settled[k]);
            if !at_rest_only || state.at_rest(col, row) {
                hv += std::mem::take(&mut state.h[k]);
            }
            if hv <= 0.0 {
                continue;
            }
            let i = row * w + col;
            terrain.layer_mut(layer)[i] += hv as f32;
            if raises_bed {
                state.bed[k] += hv;
            }
            volume += hv * g.cell_area();
        }
    }
    if !at_rest_only {
        state.pipes.iter_mut().for_each(|p| p.fill(0.0));
    }
    state.refresh_active();
    Ok(volume)
}
