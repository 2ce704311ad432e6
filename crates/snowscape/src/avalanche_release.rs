//! One avalanche's release on a DEM, the path `snowscape avalanche` and the Python package's
//! `snowscape.avalanche` share: what the user names (a file, a mask, a rupture point) becomes
//! the bare terrain carrying the release's unstable snow and the released cells, which
//! [`snowscape_avalanche::AvalancheWorkspace::run_to_rest`] then runs to rest.

use snowscape_avalanche::release_area::{
    RasterRelease, ReleaseAreaError, ReleaseMask, RuptureParams, release_at_point,
    release_from_raster, release_from_shapefile,
};
use snowscape_avalanche::validation::ThicknessConvention;
use snowscape_io::ReadOptions;
use snowscape_terrain::{Grid, LayeredTerrain, SnowLayer};

/// What a release names.
#[derive(Debug, Clone, PartialEq)]
pub enum ReleaseSpec {
    /// A map position (CRS units): the rupture point.
    Point(f64, f64),
    /// A shapefile polygon or a raster mask in the DEM's grid.
    File(std::path::PathBuf),
    /// A mask of the DEM's cells (row-major, row 0 north; true = released).
    Mask(Vec<bool>),
}

/// The terrain to release from (the bare DEM carrying the release's unstable snow), the
/// release cells and their mask.
///
/// A file gives the cells (and, from a shapefile's `thickness` field, their thickness;
/// `--thickness` overrides it, 1 m by default). A point covers the DEM with `--thickness` of
/// unstable snow and breaks it there (Cordonnier 2018 §6.1 rupture: the unstable snow within a
/// reach proportional to its thickness, and everything down the fall lines below).
///
/// `snow_cover_m` metres of loose snow (powder, fully entrainable: AvaFrame's entrainment
/// thickness) are laid on every valid cell outside the release. The thickness must be in
/// (0, 50] m and the cover in [0, 50] m (checked before any work, for every front end), and a
/// release that holds no snow is refused.
pub fn release_terrain(
    dem: &Grid,
    spec: &ReleaseSpec,
    thickness: Option<f64>,
    convention: ThicknessConvention,
    dem_options: &ReadOptions,
    snow_cover_m: f64,
) -> Result<(LayeredTerrain, Vec<usize>, ReleaseMask), ReleaseError> {
    check_release_values(thickness, snow_cover_m)?;
    let (mut terrain, cells, area) = release_only(dem, spec, thickness, convention, dem_options)?;
    if snow_cover_m > 0.0 {
        // The cover the flow can entrain, outside the release (whose snow it releases).
        let mask = dem.mask().clone();
        for (i, v) in terrain.layer_mut(SnowLayer::Powder).iter_mut().enumerate() {
            if mask.is_valid(i) && !area.cells[i] {
                *v = snow_cover_m as f32;
            }
        }
    }
    let unstable = terrain.layer(SnowLayer::Unstable);
    if !cells.iter().any(|&i| unstable[i] > 0.0) {
        return Err(ReleaseError::NoSnow);
    }
    Ok((terrain, cells, area))
}

/// Largest release thickness and snow cover, m.
pub const MAX_THICKNESS_M: f64 = 50.0;

/// Checks a release thickness ((0, 50] m) and a snow cover ([0, 50] m).
pub fn check_release_values(
    thickness_m: Option<f64>,
    snow_cover_m: f64,
) -> Result<(), ReleaseError> {
    if let Some(t) = thickness_m
        && !(t.is_finite() && t > 0.0 && t <= MAX_THICKNESS_M)
    {
        return Err(ReleaseError::Thickness(t));
    }
    if !(snow_cover_m.is_finite() && (0.0..=MAX_THICKNESS_M).contains(&snow_cover_m)) {
        return Err(ReleaseError::SnowCover(snow_cover_m));
    }
    Ok(())
}

impl ReleaseSpec {
    /// A release as the command line names it: `X,Y` map coordinates (finite) as a rupture
    /// point, anything else as the path of an existing file.
    pub fn parse(text: &str) -> Result<Self, ReleaseError> {
        let parts: Vec<&str> = text.split(',').collect();
        if parts.len() == 2
            && let (Ok(x), Ok(y)) = (
                parts[0].trim().parse::<f64>(),
                parts[1].trim().parse::<f64>(),
            )
        {
            if !(x.is_finite() && y.is_finite()) {
                return Err(ReleaseError::NonFinitePoint(text.to_string()));
            }
            return Ok(Self::Point(x, y));
        }
        let path = std::path::PathBuf::from(text);
        if !path.exists() {
            return Err(ReleaseError::NotPointOrFile(text.to_string()));
        }
        Ok(Self::File(path))
    }
}

/// Why a release was refused.
#[derive(Debug, thiserror::Error)]
pub enum ReleaseError {
    #[error(transparent)]
    Area(#[from] ReleaseAreaError),
    #[error("release thickness {0} m must be in (0, 50]")]
    Thickness(f64),
    #[error("snow cover {0} m must be in [0, 50]")]
    SnowCover(f64),
    #[error("the release holds no snow (released volume 0 m³)")]
    NoSnow,
    #[error("{0:?}: the coordinates must be finite")]
    NonFinitePoint(String),
    #[error("{0:?} is neither X,Y map coordinates nor an existing file")]
    NotPointOrFile(String),
}

/// The release's terrain, cells and mask, before the cover and the checks.
fn release_only(
    dem: &Grid,
    spec: &ReleaseSpec,
    thickness: Option<f64>,
    convention: ThicknessConvention,
    dem_options: &ReadOptions,
) -> Result<(LayeredTerrain, Vec<usize>, ReleaseMask), ReleaseAreaError> {
    let g = dem.geometry();
    let mut terrain = LayeredTerrain::from_bedrock(dem.clone());
    let mask = terrain.mask().clone();
    let area = match spec {
        ReleaseSpec::Point(x, y) => {
            let mut h = vec![thickness.unwrap_or(1.0); g.len()];
            convention.to_vertical(&mut h, dem);
            for (i, v) in terrain
                .layer_mut(SnowLayer::Unstable)
                .iter_mut()
                .enumerate()
            {
                if mask.is_valid(i) {
                    *v = h[i] as f32;
                }
            }
            release_at_point(&terrain, *x, *y, &RuptureParams::default())?.mask
        }
        ReleaseSpec::File(_) | ReleaseSpec::Mask(_) => {
            let mut area = match spec {
                ReleaseSpec::File(path) => {
                    let is_shp = path
                        .extension()
                        .and_then(|e| e.to_str())
                        .is_some_and(|e| e.eq_ignore_ascii_case("shp"));
                    let area = if is_shp {
                        release_from_shapefile(path, g, dem.mask())?
                    } else {
                        release_from_raster(path, g, dem.mask(), dem_options, RasterRelease::Mask)?
                    };
                    let name = path.display().to_string();
                    for w in &area.warnings {
                        // The readers' warnings name the file already (they go into report.json
                        // as they are): it is said once.
                        if w.contains(&name) {
                            tracing::warn!("{w}");
                        } else {
                            tracing::warn!("{name}: {w}");
                        }
                    }
                    area
                }
                _ => {
                    let ReleaseSpec::Mask(cells) = spec else {
                        unreachable!("matched above")
                    };
                    ReleaseMask::from_cells(g, dem.mask(), cells.clone(), None)?
                }
            };
            if thickness.is_some() {
                area.thickness = None;
            }
            let mut h = area.thickness_field(thickness.unwrap_or(1.0))?;
            convention.to_vertical(&mut h, dem);
            for (i, v) in terrain
                .layer_mut(SnowLayer::Unstable)
                .iter_mut()
                .enumerate()
            {
                if area.cells[i] && mask.is_valid(i) {
                    *v = h[i] as f32;
                }
            }
            area
        }
    };
    let cells = (0..area.cells.len()).filter(|&i| area.cells[i]).collect();
    Ok((terrain, cells, area))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn release_points_and_files_are_told_apart() {
        assert_eq!(
            ReleaseSpec::parse("631500.5, 212300").unwrap(),
            ReleaseSpec::Point(631500.5, 212300.0)
        );
        assert!(ReleaseSpec::parse("nan,3").is_err());
        let e = ReleaseSpec::parse("no/such/file.shp")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no/such/file.shp"), "{e}");
    }
}
