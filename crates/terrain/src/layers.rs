//! The layered terrain of Cordonnier et al. 2018, Section 3: bedrock plus four snow layers.
//!
//! From bottom to top: compacted snow (hard, old, does not move), stable snow, unstable snow
//! (can release as an avalanche), and powder (fresh, light, moved by wind and diffusion).
//! Every layer is a thickness in metres of snow per cell; the surface altitude is
//! `A = bedrock + Σ layers`. Auxiliary maps (sun exposure, temperature, wind...) are named f32
//! layers over the same geometry, added by the phenomena that compute them.

use crate::{Grid, GridGeometry, NodataMask, TerrainError};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The four snow layers, bottom to top.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Hash,
    PartialOrd,
    Ord,
    Serialize,
    Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum SnowLayer {
    /// Old snow compacted under its own weight; the bed avalanches slide on.
    Compacted,
    /// Snow bonded to the layer below.
    Stable,
    /// Snow that can release as an avalanche.
    Unstable,
    /// Fresh, light snow: moved by wind and diffusion.
    Powder,
}

impl SnowLayer {
    /// All layers, bottom to top.
    pub const ALL: [SnowLayer; 4] = [
        SnowLayer::Compacted,
        SnowLayer::Stable,
        SnowLayer::Unstable,
        SnowLayer::Powder,
    ];
    /// Lower-case name, used for file names (`layers_<name>.tif`) and channels.
    pub fn name(self) -> &'static str {
        match self {
            SnowLayer::Compacted => "compacted",
            SnowLayer::Stable => "stable",
            SnowLayer::Unstable => "unstable",
            SnowLayer::Powder => "powder",
        }
    }
    /// Position in [`SnowLayer::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// Bedrock and snow layers over one geometry, as flat f32 vectors (struct of arrays).
#[derive(Debug, Clone, PartialEq)]
pub struct LayeredTerrain {
    geometry: GridGeometry,
    mask: NodataMask,
    /// Bedrock altitude, metres.
    pub bedrock: Vec<f32>,
    /// Snow thickness per layer (indexed by [`SnowLayer::index`]), metres.
    pub snow: [Vec<f32>; 4],
    /// Named auxiliary maps over the same geometry.
    pub maps: BTreeMap<String, Vec<f32>>,
}

impl LayeredTerrain {
    /// A snow-free terrain on a bedrock grid.
    pub fn from_bedrock(bedrock: Grid) -> Self {
        let geometry = bedrock.geometry().clone();
        let mask = bedrock.mask().clone();
        let n = geometry.len();
        Self {
            geometry,
            mask,
            bedrock: bedrock.into_data(),
            snow: std::array::from_fn(|_| vec![0.0; n]),
            maps: BTreeMap::new(),
        }
    }

    /// The geometry shared by every layer.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }
    /// The nodata mask shared by every layer.
    pub fn mask(&self) -> &NodataMask {
        &self.mask
    }
    /// Thickness of one snow layer, metres.
    pub fn layer(&self, layer: SnowLayer) -> &[f32] {
        &self.snow[layer.index()]
    }
    /// Thickness of one snow layer, mutably.
    pub fn layer_mut(&mut self, layer: SnowLayer) -> &mut [f32] {
        &mut self.snow[layer.index()]
    }
    /// Total snow depth of cell `i`, metres.
    #[inline(always)]
    pub fn depth_at(&self, i: usize) -> f32 {
        self.snow[0][i] + self.snow[1][i] + self.snow[2][i] + self.snow[3][i]
    }
    /// Total snow depth per cell, metres.
    pub fn total_depth(&self) -> Vec<f32> {
        (0..self.geometry.len()).map(|i| self.depth_at(i)).collect()
    }
    /// Surface altitude per cell (bedrock + snow), metres.
    pub fn surface(&self) -> Vec<f32> {
        (0..self.geometry.len())
            .map(|i| self.bedrock[i] + self.depth_at(i))
            .collect()
    }
    /// Total snow volume over valid cells, m³.
    pub fn snow_volume(&self) -> f64 {
        let a = self.geometry.cell_area();
        (0..self.geometry.len())
            .filter(|&i| self.mask.is_valid(i))
            .map(|i| self.depth_at(i) as f64)
            .sum::<f64>()
            * a
    }
    /// A layer (or any per-cell vector) as a [`Grid`] carrying this terrain's geometry and mask.
    pub fn to_grid(&self, values: Vec<f32>) -> Result<Grid, TerrainError> {
        Grid::new(self.geometry.clone(), values, self.mask.clone())
    }
    /// Adds or replaces a named auxiliary map.
    pub fn set_map(&mut self, name: &str, values: Vec<f32>) -> Result<(), TerrainError> {
        if values.len() != self.geometry.len() {
            return Err(TerrainError::LengthMismatch {
                width: self.geometry.width(),
                height: self.geometry.height(),
                expected: self.geometry.len(),
                actual: values.len(),
            });
        }
        self.maps.insert(name.to_string(), values);
        Ok(())
    }
    /// Checks the invariants every phenomenon must keep: no negative or non-finite snow, no
    /// snow on nodata cells. The error names the layer and cell.
    pub fn check_invariants(&self) -> Result<(), TerrainError> {
        for layer in SnowLayer::ALL {
            for (i, &v) in self.layer(layer).iter().enumerate() {
                let bad = !v.is_finite() || v < 0.0 || (!self.mask.is_valid(i) && v != 0.0);
                if bad {
                    let (col, row) = self.geometry.col_row(i);
                    return Err(TerrainError::NonFinite {
                        what: format!("{} snow layer", layer.name()),
                        col,
                        row,
                        value: v,
                    });
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_sum_to_depth_and_surface() {
        let geo = GridGeometry::square(2, 2, 10.0).unwrap();
        let mut t = LayeredTerrain::from_bedrock(Grid::filled(geo, 100.0));
        t.layer_mut(SnowLayer::Powder)[0] = 0.5;
        t.layer_mut(SnowLayer::Stable)[0] = 0.25;
        assert_eq!(t.depth_at(0), 0.75);
        assert_eq!(t.surface()[0], 100.75);
        assert!((t.snow_volume() - 75.0).abs() < 1e-9);
        assert!(t.check_invariants().is_ok());
        t.layer_mut(SnowLayer::Unstable)[3] = -0.1;
        assert!(t.check_invariants().is_err());
    }

    #[test]
    fn names_are_stable() {
        let names: Vec<_> = SnowLayer::ALL.iter().map(|l| l.name()).collect();
        assert_eq!(names, ["compacted", "stable", "unstable", "powder"]);
    }
}
