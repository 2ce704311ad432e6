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
    let n = terrain.bedrock.len();
    if cells.len() != n {
        return Err(AvalancheError::LengthMismatch {
            what: "release cells",
            got: cells.len(),
            expected: n,
        });
    }
    let list: Vec<usize> = (0..n).filter(|&i| cells[i]).collect();
    release_cells(terrain, state, &list, thickness)
}

/// [`release`] of a list of grid cells (row-major indices; nodata cells are skipped): the
/// cost follows the list, not the grid. Returns the released volume, m³.
pub fn release_cells(
    terrain: &mut LayeredTerrain,
    state: &mut AvalancheState,
    cells: &[usize],
    thickness: Option<f64>,
) -> Result<f64, AvalancheError> {
    check_terrain(terrain, state)?;
    if let Some(t) = thickness
        && !(t.is_finite() && t >= 0.0)
    {
        return Err(AvalancheError::BadValue {
            what: "release thickness",
            index: 0,
            value: t,
        });
    }
    let n = terrain.bedrock.len();
    if let Some(&i) = cells.iter().find(|&&i| i >= n) {
        return Err(AvalancheError::LengthMismatch {
            what: "release cell index",
            got: i,
            expected: n,
        });
    }
    let w = terrain.geometry().width();
    let area = terrain.geometry().cell_area();
    let mut volume = 0.0;
    for &i in cells {
        if !terrain.mask().is_valid(i) {
            continue;
        }
        let k = state.pad(i % w, i / w);
        // A state that reads its bed from the terrain reads it here, before the release
        // lowers it.
        state.touch_around_cell(k, Some(&*terrain))?;
        let taken = take_from_top(terrain, i, |layer, have, so_far| match thickness {
            None if matches!(layer, SnowLayer::Powder | SnowLayer::Unstable) => have,
            None => 0.0,
            Some(t) => have.min(t - so_far).max(0.0),
        });
        state.bed[k] -= taken.from_bed;
        state.h[k] += taken.total;
        volume += taken.total * area;
        if state.h[k] > 0.0 {
            state.mark_content(k);
        }
    }
    Ok(volume)
}

/// Snow taken from a column: in all, and from its stable and compacted layers (the bed).
pub(crate) struct Taken {
    pub(crate) total: f64,
    pub(crate) from_bed: f64,
}

/// Takes snow from the top of column `i` down (powder, unstable, stable, compacted):
/// `take(layer, have, taken_so_far)` metres of each layer (f32 layers, f64 sums).
pub(crate) fn take_from_top(
    terrain: &mut LayeredTerrain,
    i: usize,
    mut take: impl FnMut(SnowLayer, f64, f64) -> f64,
) -> Taken {
    let mut taken = Taken {
        total: 0.0,
        from_bed: 0.0,
    };
    for layer in [
        SnowLayer::Powder,
        SnowLayer::Unstable,
        SnowLayer::Stable,
        SnowLayer::Compacted,
    ] {
        let have = terrain.layer(layer)[i] as f64;
        let take = take(layer, have, taken.total);
        if take <= 0.0 {
            continue;
        }
        let left = (have - take).max(0.0) as f32;
        terrain.layer_mut(layer)[i] = left;
        let took = have - left as f64;
        taken.total += took;
        if matches!(layer, SnowLayer::Stable | SnowLayer::Compacted) {
            taken.from_bed += took;
        }
    }
    taken
}

/// Turns flowing snow (and settled films) into `layer`. With `at_rest_only`, only cells whose
/// 8 pipes are all at rest deposit; otherwise every cell does and all motion stops. Visits the
/// touched tiles only (all of the avalanche's snow lies in them). Returns the deposited
/// volume, m³.
pub fn deposit(
    terrain: &mut LayeredTerrain,
    state: &mut AvalancheState,
    layer: SnowLayer,
    at_rest_only: bool,
) -> Result<f64, AvalancheError> {
    check_terrain(terrain, state)?;
    let g = terrain.geometry().clone();
    let w = g.width();
    let raises_bed = matches!(layer, SnowLayer::Stable | SnowLayer::Compacted);
    let mut volume = 0.0;
    let boxes: Vec<_> = state.touched_cells().collect();
    for &(r0, r1, c0, c1) in &boxes {
        for row in r0..=r1 {
            for col in c0..=c1 {
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
    }
    if at_rest_only {
        state.refresh_active_touched();
    } else {
        state.stop_all();
    }
    Ok(volume)
}
