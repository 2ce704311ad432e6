//! Spatially varying friction: a dry-friction coefficient μ and a Voellmy turbulence
//! coefficient ξ per cell, as RAMMS and AvaFrame com1DFA take them from rasters (forest, open
//! slope and gully classes; AvaFrame issues #1046 and #1312).
//!
//! **What a map replaces.** μ replaces the run's dry-friction coefficient cell by cell, whatever
//! the law: `tanθc` of [`FrictionLaw::Coulomb`] (the yield `α·g·μ`; the viscous term keeps its
//! `kv`), `voellmy_mu` of [`FrictionLaw::Voellmy`], `samos_at.mu` of [`FrictionLaw::SamosAt`]
//! (its speed-dependent factor `1 + Rs0/(Rs0 + Rs)` still applies). ξ replaces `voellmy_xi_m_s2`
//! and only exists for the Voellmy law (a map that no term would read is refused).
//!
//! **On a pipe.** The flow's pipes join two cells; a pipe's μ and ξ are the arithmetic means of
//! its two cells' values, as its depth and velocity are. With a map whose every cell holds the
//! law's scalar the run is bit-identical to the run without the map (tested).
//!
//! **Matching by map coordinates.** [`FrictionMaps::from_rasters`] samples each raster at the
//! centres of the run's cells by map coordinates (bilinear, nodata corners left out; any cell
//! size, any extent overlapping the DEM). Cells the raster does not cover, or covers with nodata,
//! keep the law's scalar and are counted ([`MapMatch::defaulted_cells`]); a raster that covers
//! none of the DEM's valid cells, or holds a value out of range (checked on the raster's own
//! cells, before sampling), is an error naming the value, the cell and its map coordinates.

use crate::flow::{AvalancheError, AvalancheParams, FrictionLaw};
use serde::Serialize;
use snowscape_terrain::{Grid, GridGeometry, NodataMask};

/// Range of a μ value (as `voellmy_mu` and `samos_at.mu`).
pub const MU_RANGE: (f64, f64) = (0.0, 2.0);
/// Range of a ξ value, m/s² (as `voellmy_xi_m_s2`).
pub const XI_RANGE: (f64, f64) = (10.0, 1e5);

/// The range of a map's values and its words.
fn range_of(what: &str) -> (f64, f64, &'static str) {
    if what == "xi map" {
        (XI_RANGE.0, XI_RANGE.1, "in [10, 100000] m/s²")
    } else {
        (MU_RANGE.0, MU_RANGE.1, "in [0, 2]")
    }
}

/// Per-cell μ and ξ of a grid (row-major, one value per cell; `None`: the law's scalar).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FrictionMaps {
    width: usize,
    height: usize,
    mu: Option<Vec<f64>>,
    xi: Option<Vec<f64>>,
}

/// How a raster was matched onto the run's cells.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MapMatch {
    /// Valid cells that took their value from the raster.
    pub raster_cells: usize,
    /// Valid cells outside the raster or under its nodata, which keep the law's scalar.
    pub defaulted_cells: usize,
    /// Smallest and largest value over the valid cells (raster and default).
    pub min: f64,
    pub max: f64,
}

impl FrictionMaps {
    /// Maps of a `geometry`-sized grid: every value is checked (finite, μ in [0, 2], ξ in
    /// [10, 100000] m/s²; the error names the map and the cell).
    pub fn new(
        geometry: &GridGeometry,
        mu: Option<Vec<f64>>,
        xi: Option<Vec<f64>>,
    ) -> Result<Self, AvalancheError> {
        for (what, map) in [("mu map", &mu), ("xi map", &xi)] {
            let Some(map) = map else { continue };
            let (lo, hi, expected) = range_of(what);
            if map.len() != geometry.len() {
                return Err(AvalancheError::LengthMismatch {
                    what,
                    got: map.len(),
                    expected: geometry.len(),
                });
            }
            if let Some((index, &value)) = map
                .iter()
                .enumerate()
                .find(|(_, v)| !(v.is_finite() && **v >= lo && **v <= hi))
            {
                let (x, y) =
                    geometry.cell_centre(index % geometry.width(), index / geometry.width());
                return Err(AvalancheError::FrictionMapValue {
                    what,
                    index,
                    x,
                    y,
                    value,
                    expected,
                });
            }
        }
        Ok(Self {
            width: geometry.width(),
            height: geometry.height(),
            mu,
            xi,
        })
    }

    /// Maps sampled from rasters onto the cells of `geometry` by map coordinates (module
    /// documentation): a cell with no raster value takes `params`' scalar. Returns the maps and,
    /// per raster given, how it matched.
    pub fn from_rasters(
        geometry: &GridGeometry,
        mask: &NodataMask,
        params: &AvalancheParams,
        mu: Option<&Grid>,
        xi: Option<&Grid>,
    ) -> Result<(Self, Option<MapMatch>, Option<MapMatch>), AvalancheError> {
        if xi.is_some() && params.friction != FrictionLaw::Voellmy {
            return Err(AvalancheError::FrictionMapUnused {
                what: "xi map",
                law: params.friction,
            });
        }
        let sample = |what: &'static str, raster: &Grid, default: f64| {
            // The raster's own values first: an out-of-range value is named where it is
            // written, not blended into its neighbours by the sampling.
            let (lo, hi, expected) = range_of(what);
            let rg = raster.geometry();
            if let Some((index, value)) = raster
                .data()
                .iter()
                .enumerate()
                .filter(|&(i, _)| raster.mask().is_valid(i))
                .map(|(i, &v)| (i, f64::from(v)))
                .find(|&(_, v)| !(v.is_finite() && v >= lo && v <= hi))
            {
                let (x, y) = rg.cell_centre(index % rg.width(), index / rg.width());
                return Err(AvalancheError::FrictionMapValue {
                    what,
                    index,
                    x,
                    y,
                    value,
                    expected,
                });
            }
            let mut raster_cells = 0;
            let values: Vec<f64> = (0..geometry.len())
                .map(|i| {
                    if !mask.is_valid(i) {
                        return default;
                    }
                    let (x, y) = geometry.cell_centre(i % geometry.width(), i / geometry.width());
                    match raster.sample_map(x, y) {
                        Some(v) => {
                            raster_cells += 1;
                            f64::from(v)
                        }
                        None => default,
                    }
                })
                .collect();
            if raster_cells == 0 {
                return Err(AvalancheError::FrictionMapOutside { what });
            }
            Ok((values, raster_cells))
        };
        let valid = (0..geometry.len()).filter(|&i| mask.is_valid(i)).count();
        let summary = |values: &[f64], raster_cells: usize| {
            let (min, max) = (0..values.len())
                .filter(|&i| mask.is_valid(i))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), i| {
                    (a.min(values[i]), b.max(values[i]))
                });
            MapMatch {
                raster_cells,
                defaulted_cells: valid - raster_cells,
                min,
                max,
            }
        };
        let mu = mu
            .map(|r| sample("mu map", r, params.dry_friction()))
            .transpose()?;
        let xi = xi
            .map(|r| sample("xi map", r, params.voellmy_xi_m_s2))
            .transpose()?;
        let mu_match = mu.as_ref().map(|(v, n)| summary(v, *n));
        let xi_match = xi.as_ref().map(|(v, n)| summary(v, *n));
        let maps = Self::new(geometry, mu.map(|(v, _)| v), xi.map(|(v, _)| v))?;
        Ok((maps, mu_match, xi_match))
    }

    /// Whether neither map is set.
    pub fn is_empty(&self) -> bool {
        self.mu.is_none() && self.xi.is_none()
    }

    /// Grid size `(width, height)` the maps were built for.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// μ per cell, if set.
    pub fn mu(&self) -> Option<&[f64]> {
        self.mu.as_deref()
    }

    /// ξ per cell, m/s², if set.
    pub fn xi(&self) -> Option<&[f64]> {
        self.xi.as_deref()
    }

    /// Checks that the maps fit `geometry` and that the law of `params` reads every map set.
    pub fn check_for(
        &self,
        geometry: &GridGeometry,
        params: &AvalancheParams,
    ) -> Result<(), AvalancheError> {
        if self.is_empty() {
            return Ok(());
        }
        if (self.width, self.height) != (geometry.width(), geometry.height()) {
            return Err(AvalancheError::GeometryMismatch {
                width: geometry.width(),
                height: geometry.height(),
                terrain_width: self.width,
                terrain_height: self.height,
            });
        }
        if self.xi.is_some() && params.friction != FrictionLaw::Voellmy {
            return Err(AvalancheError::FrictionMapUnused {
                what: "xi map",
                law: params.friction,
            });
        }
        Ok(())
    }
}
