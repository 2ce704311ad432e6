//! Per-cell friction of a run: the μ and ξ rasters a user names (`--mu-raster`,
//! `--xi-raster` of `snowscape avalanche` and `snowscape run`) matched onto the DEM's cells by
//! map coordinates ([`FrictionMaps::from_rasters`]), and what report.json says of them.

use super::report::{FrictionRasterReport, FrictionReport};
use snowscape_avalanche::{AvalancheError, AvalancheParams, FrictionMaps, MapMatch};
use snowscape_io::ReadOptions;
use snowscape_terrain::Grid;
use std::path::{Path, PathBuf};

/// The friction rasters a run names (either may be absent).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrictionRasters {
    /// Per-cell dry-friction coefficient μ, in [0, 2].
    pub mu: Option<PathBuf>,
    /// Per-cell Voellmy ξ, m/s², in [10, 100 000] (the Voellmy law only).
    pub xi: Option<PathBuf>,
}

/// Why the friction rasters were refused.
#[derive(Debug, thiserror::Error)]
pub enum FrictionRasterError {
    /// A raster cannot be read (`which`: `mu` or `xi`).
    #[error("{which} raster {path}: {source}")]
    Read {
        which: &'static str,
        path: PathBuf,
        #[source]
        source: Box<snowscape_io::RasterError>,
    },
    /// The rasters do not fit the run: a ξ map under another law than Voellmy, a raster that
    /// covers none of the DEM's cells, a value out of range.
    #[error("friction rasters: {0}")]
    Match(#[source] AvalancheError),
}

/// The μ and ξ rasters matched onto `dem`'s cells, and what report.json says of them (`None`
/// without either). Cells a raster does not cover keep the law's value (a warning counts
/// them).
pub fn friction_maps(
    rasters: &FrictionRasters,
    dem: &Grid,
    params: &AvalancheParams,
) -> Result<(FrictionMaps, Option<FrictionReport>), FrictionRasterError> {
    if rasters.mu.is_none() && rasters.xi.is_none() {
        return Ok((FrictionMaps::default(), None));
    }
    let read = |which: &'static str, path: Option<&Path>| {
        path.map(|p| {
            snowscape_io::read_dem(p, &ReadOptions::default()).map_err(|source| {
                FrictionRasterError::Read {
                    which,
                    path: p.to_path_buf(),
                    source: Box::new(source),
                }
            })
        })
        .transpose()
    };
    let mu = read("mu", rasters.mu.as_deref())?;
    let xi = read("xi", rasters.xi.as_deref())?;
    let (maps, mu_match, xi_match) =
        FrictionMaps::from_rasters(dem.geometry(), dem.mask(), params, mu.as_ref(), xi.as_ref())
            .map_err(FrictionRasterError::Match)?;
    for (flag, m) in [("--mu-raster", &mu_match), ("--xi-raster", &xi_match)] {
        if let Some(m) = m
            && m.defaulted_cells > 0
        {
            tracing::warn!(
                "{flag}: {} of the DEM's cells lie outside the raster or under its nodata and keep the law's value",
                m.defaulted_cells
            );
        }
    }
    let entry = |path: &Option<PathBuf>, m: Option<MapMatch>| {
        m.map(|matched| FrictionRasterReport {
            file: path.as_ref().map(|p| p.display().to_string()),
            matched,
        })
    };
    let report = FrictionReport {
        mu: entry(&rasters.mu, mu_match),
        xi: entry(&rasters.xi, xi_match),
    };
    Ok((maps, Some(report)))
}
