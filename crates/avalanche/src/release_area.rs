//! Where an avalanche starts: release areas as practitioners give them, and the paper's
//! rupture at a point.
//!
//! Every entry point returns a [`ReleaseMask`] in the grid of the DEM: one flag per cell
//! (row-major, row 0 north) and, optionally, a release thickness per cell. A mask feeds the flow
//! in one of two ways:
//! - on a bare DEM (the practitioners' case: AvaFrame's com1DFA puts `d0` metres of snow in the
//!   release area), [`ReleaseMask::thickness_field`] gives the flowing thickness to hand to
//!   [`AvalancheState::set_thickness`];
//! - on a [`LayeredTerrain`] (the season's case), [`ReleaseMask::release`] moves snow out of the
//!   layers into the flow, as [`crate::convert::release`] does: all unstable snow and powder of
//!   the masked cells, or up to the mask's per-cell thickness from the top of the pack down.
//!
//! ## Shapefile polygons ([`release_from_shapefile`])
//!
//! ESRI shapefiles of type Polygon, PolygonZ or PolygonM (Z and M are ignored), any number of
//! records, each with any number of rings. A cell is released when its **centre** lies inside a
//! record's polygon by the **even-odd rule** over all the record's rings (so holes, and parts
//! that overlap, need no ring orientation); cells inside several records take the largest
//! thickness. Null records are skipped with a warning.
//!
//! **Thickness.** AvaFrame reads the release thickness of each polygon from the attribute table
//! (`thickness`, or `d0` in older files; the avaWog and avaKot release files both carry
//! `thickness = 1.000`). When the `.dbf` has such a field (case-insensitive) every record must
//! hold a finite positive value, and [`ReleaseMask::thickness`] carries it per cell; without the
//! field (or without a `.dbf`) the thickness is left to the caller.
//!
//! **Checks**, each a [`ReleaseAreaError`] naming the file: the file cannot be read; a record is
//! not a polygon; a record lies entirely outside the DEM (both extents named); a record covers
//! no cell centre (a sliver smaller than a cell); no cell is released at all (every covered
//! cell is nodata). A polygon partly outside the DEM is clipped, with a warning. The `.prj`
//! beside the `.shp`, when present, is compared with the DEM's CRS: a clear disagreement (two
//! different EPSG codes, a geographic against a projected CRS, or WKT names of two different
//! known CRSs) is [`ReleaseAreaError::CrsMismatch`]; a comparison that cannot be decided (a DEM
//! without CRS, or WKT names that are not recognised) is a warning in
//! [`ReleaseMask::warnings`].
//!
//! ## Raster masks ([`release_from_raster`])
//!
//! Any raster [`snowscape_io::read_dem`] reads, in the DEM's grid: same size, same
//! georeferencing (origin within 1/1000 of a cell, pixel size to 1 ppm) and no clearly different
//! CRS, else [`ReleaseAreaError::RasterGridMismatch`] naming both grids. With
//! [`RasterRelease::Mask`] every valid nonzero cell is released; with
//! [`RasterRelease::Thickness`] the value is also the release thickness (m; negative values are
//! an error, zero is "not released").
//!
//! ## Rupture at a point ([`release_at_point`], Cordonnier et al. 2018, Section 6.1)
//!
//! The paper keeps a boolean **"Snow Moving"** layer: snow is initially still; "a rupture point
//! can then be triggered either automatically or by the user. If the unstable layer U is
//! non-empty, then the avalanche rapidly propagates to neighboring areas, with reach
//! proportional to the thickness of U. All unstable snow in the rupture zone is immediately set
//! into motion, as well as all unstable snow in the downslope reach of the avalanche." Only U
//! (and the powder on top) is released: stable and compacted snow are "too strongly fused"
//! (surface-layer avalanches). The paper gives no more detail; the design here:
//!
//! 1. **Rupture cell.** The cell containing the point `(x, y)` (map coordinates). A point
//!    outside the DEM or on nodata is an error. Its unstable thickness `U0` must reach
//!    [`RuptureParams::min_unstable_m`], else [`ReleaseAreaError::NoUnstableSnow`]: snow-free or
//!    stable-only snow does not release (the paper's "if the unstable layer U is non-empty").
//! 2. **Reach** `R = k_reach · U0` ([`RuptureParams::reach_per_unstable_m`], m of fracture
//!    propagation per m of unstable snow: "reach proportional to the thickness of U").
//! 3. **Rupture zone** (the slab that fractures): the cells connected to the rupture cell
//!    through 8-neighbour steps over cells holding unstable snow (`U ≥ min_unstable_m`) whose
//!    centres lie within horizontal distance `R` of the point. The fracture runs through the
//!    weak layer in every direction, across and up the slope too, but never farther than `R`.
//! 4. **Downslope reach** (the unstable snow the moving slab runs over and sets in motion): from
//!    the centre of every rupture-zone cell a *fall line* is traced down the snow surface
//!    `A = B + D` (steps of half a cell along `−∇A`, the gradient interpolated bilinearly from
//!    the cells' central differences); every cell it crosses joins the mask. A fall line ends
//!    where the unstable snow ends (`U < min_unstable_m`), where the slope eases below
//!    [`RuptureParams::min_slope_deg`] (unstable snow does not form nor release on gentler
//!    slopes: the snowfall model's critical slope `s_U`, 25°), at a flat or a pit, at nodata or
//!    at the grid's edge. The swept band has the rupture zone's width and follows the fall
//!    lines, converging in gullies: the mask extends downslope as far as continuous unstable
//!    snow on a steep enough slope goes, but never upslope beyond `R`.
//!
//! The mask carries no thickness: [`ReleaseMask::release`] then takes all unstable snow and
//! powder of the masked cells. The [`Rupture`] also reports the rupture cell, `U0`, `R` and the
//! sizes of the two parts.

use crate::flow::{AvalancheError, AvalancheState};
use snowscape_io::vector::VectorError;
use snowscape_io::{RasterError, ReadOptions};
use snowscape_terrain::{Crs, GridGeometry, LayeredTerrain, NodataMask, SnowLayer};
use std::collections::VecDeque;
use std::fmt;
use std::path::{Path, PathBuf};
use thiserror::Error;

mod polygons;
mod rupture;

pub use polygons::release_from_shapefile;
use polygons::*;
pub use rupture::{Rupture, RuptureCells, RuptureParams, release_at_point, rupture_at_point};
use snowscape_terrain::crs_facts::same_crs;

/// An axis-aligned extent in map coordinates (CRS units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapExtent {
    /// Western edge.
    pub x_min: f64,
    /// Southern edge.
    pub y_min: f64,
    /// Eastern edge.
    pub x_max: f64,
    /// Northern edge.
    pub y_max: f64,
}

impl MapExtent {
    /// The extent of a grid (cell edges).
    pub fn of_grid(g: &GridGeometry) -> Self {
        let [x_min, y_min, x_max, y_max] = g.map_bounds();
        Self {
            x_min,
            x_max,
            y_min,
            y_max,
        }
    }

    fn of_points(points: impl Iterator<Item = (f64, f64)>) -> Option<Self> {
        let mut e: Option<Self> = None;
        for (x, y) in points {
            e = Some(match e {
                None => Self {
                    x_min: x,
                    y_min: y,
                    x_max: x,
                    y_max: y,
                },
                Some(e) => Self {
                    x_min: e.x_min.min(x),
                    y_min: e.y_min.min(y),
                    x_max: e.x_max.max(x),
                    y_max: e.y_max.max(y),
                },
            });
        }
        e
    }

    fn intersects(&self, o: &Self) -> bool {
        self.x_min < o.x_max && o.x_min < self.x_max && self.y_min < o.y_max && o.y_min < self.y_max
    }

    fn contains_extent(&self, o: &Self) -> bool {
        o.x_min >= self.x_min
            && o.x_max <= self.x_max
            && o.y_min >= self.y_min
            && o.y_max <= self.y_max
    }
}

impl fmt::Display for MapExtent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "x {:.3}..{:.3}, y {:.3}..{:.3}",
            self.x_min, self.x_max, self.y_min, self.y_max
        )
    }
}

/// Why a release area could not be made. Every variant names the file or point and the
/// offending values.
#[derive(Debug, Error)]
pub enum ReleaseAreaError {
    /// The shapefile, its attribute table or its `.prj` cannot be read.
    #[error(transparent)]
    Vector(#[from] VectorError),
    /// A record is not a polygon.
    #[error(
        "{path}: record {record} is a {shape_type}, a release area must be a Polygon, PolygonZ or PolygonM"
    )]
    NotPolygons {
        /// The `.shp` path.
        path: PathBuf,
        /// Record index (0-based).
        record: usize,
        /// The record's shape type.
        shape_type: String,
    },
    /// The shapefile holds no polygon at all.
    #[error("{path}: the shapefile holds no polygon ({records} records, all null)")]
    NoPolygons {
        /// The `.shp` path.
        path: PathBuf,
        /// Number of records.
        records: usize,
    },
    /// A polygon lies entirely outside the DEM.
    #[error("{path}: release polygon {record} ({polygon}) lies entirely outside the DEM ({dem})")]
    PolygonOutsideDem {
        /// The `.shp` path.
        path: PathBuf,
        /// Record index (0-based).
        record: usize,
        /// The polygon's extent.
        polygon: MapExtent,
        /// The DEM's extent.
        dem: MapExtent,
    },
    /// A polygon covers no cell centre of the DEM.
    #[error(
        "{path}: release polygon {record} ({polygon}) contains no cell centre of the DEM \
         (cells of {cell_x} x {cell_y} CRS units): it is smaller than a cell"
    )]
    NoCellInside {
        /// The `.shp` path.
        path: PathBuf,
        /// Record index (0-based).
        record: usize,
        /// The polygon's extent.
        polygon: MapExtent,
        /// Pixel width.
        cell_x: f64,
        /// Pixel height.
        cell_y: f64,
    },
    /// No valid cell is released (every covered cell is nodata, or a raster mask is all zero).
    #[error(
        "{path}: the release area covers no valid DEM cell ({covered} cells covered, all nodata or zero)"
    )]
    EmptyRelease {
        /// The input path.
        path: PathBuf,
        /// Cells covered before dropping nodata.
        covered: usize,
    },
    /// The input's CRS clearly differs from the DEM's.
    #[error(
        "{path}: the release area is in {file_crs}, the DEM in {dem_crs}: reproject one of them"
    )]
    CrsMismatch {
        /// The input (or its `.prj`).
        path: PathBuf,
        /// The input's CRS.
        file_crs: String,
        /// The DEM's CRS.
        dem_crs: String,
    },
    /// A thickness attribute is missing, not a number, or not positive.
    #[error(
        "{path}: record {record} has {field} = {value}, a release thickness must be a finite number > 0 (m)"
    )]
    BadThickness {
        /// The `.dbf` path.
        path: PathBuf,
        /// Record index (0-based).
        record: usize,
        /// The field name.
        field: String,
        /// The value as read.
        value: String,
    },
    /// A raster mask cannot be read.
    #[error("cannot read release raster: {0}")]
    Raster(#[from] RasterError),
    /// A raster mask is not in the DEM's grid.
    #[error("{path}: the release raster ({raster}) is not in the DEM's grid ({dem})")]
    RasterGridMismatch {
        /// The raster path.
        path: PathBuf,
        /// The raster's size and georeferencing.
        raster: String,
        /// The DEM's size and georeferencing.
        dem: String,
    },
    /// A release-thickness raster holds a negative value.
    #[error("{path}: release thickness {value} m at cell (col {col}, row {row}) is negative")]
    BadRasterValue {
        /// The raster path.
        path: PathBuf,
        /// Column.
        col: usize,
        /// Row.
        row: usize,
        /// The value.
        value: f64,
    },
    /// A rupture point outside the DEM.
    #[error("rupture point ({x}, {y}) lies outside the DEM ({dem})")]
    PointOutsideDem {
        /// Map x.
        x: f64,
        /// Map y.
        y: f64,
        /// The DEM's extent.
        dem: MapExtent,
    },
    /// A rupture point on a nodata cell.
    #[error("rupture point ({x}, {y}) falls on nodata cell (col {col}, row {row})")]
    PointOnNodata {
        /// Map x.
        x: f64,
        /// Map y.
        y: f64,
        /// Column.
        col: usize,
        /// Row.
        row: usize,
    },
    /// Nothing to release at the rupture point.
    #[error(
        "rupture point ({x}, {y}), cell (col {col}, row {row}): {unstable_m} m of unstable snow, \
         below the {min_unstable_m} m needed to release (stable snow does not release)"
    )]
    NoUnstableSnow {
        /// Map x.
        x: f64,
        /// Map y.
        y: f64,
        /// Column.
        col: usize,
        /// Row.
        row: usize,
        /// Unstable thickness there, m.
        unstable_m: f64,
        /// The threshold, m.
        min_unstable_m: f64,
    },
    /// A parameter or argument out of range.
    #[error("release parameter {name} = {value} must be {expected}")]
    InvalidParameter {
        /// Name.
        name: &'static str,
        /// Value.
        value: f64,
        /// The valid range.
        expected: &'static str,
    },
    /// A per-cell input of the wrong length.
    #[error("{what} has {got} values, the grid has {expected} cells")]
    LengthMismatch {
        /// What was passed.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The number of grid cells.
        expected: usize,
    },
}

/// Released cells in a DEM's grid, with an optional release thickness per cell.
#[derive(Debug, Clone, PartialEq)]
pub struct ReleaseMask {
    /// One flag per grid cell (row-major, row 0 north): released or not.
    pub cells: Vec<bool>,
    /// Release thickness per cell, m (0 outside the mask), when the input gives one.
    pub thickness: Option<Vec<f64>>,
    /// Grid width, cells.
    pub width: usize,
    /// Grid height, cells.
    pub height: usize,
    /// Area of one cell, m².
    pub cell_area_m2: f64,
    /// Things the caller should know (clipped polygons, CRS that could not be compared...).
    pub warnings: Vec<String>,
}

impl ReleaseMask {
    /// A mask from per-cell flags (and thicknesses, m) over `geometry`; nodata cells of `mask`
    /// are cleared.
    pub fn from_cells(
        geometry: &GridGeometry,
        mask: &NodataMask,
        mut cells: Vec<bool>,
        thickness: Option<Vec<f64>>,
    ) -> Result<Self, ReleaseAreaError> {
        let n = geometry.len();
        if cells.len() != n {
            return Err(ReleaseAreaError::LengthMismatch {
                what: "release cells",
                got: cells.len(),
                expected: n,
            });
        }
        let mut thickness = thickness;
        if let Some(t) = &mut thickness {
            if t.len() != n {
                return Err(ReleaseAreaError::LengthMismatch {
                    what: "release thickness",
                    got: t.len(),
                    expected: n,
                });
            }
            for (i, v) in t.iter_mut().enumerate() {
                if cells[i] && !(v.is_finite() && *v > 0.0) {
                    return Err(ReleaseAreaError::InvalidParameter {
                        name: "release thickness",
                        value: *v,
                        expected: "finite and > 0 in released cells",
                    });
                }
                if !cells[i] {
                    *v = 0.0;
                }
            }
        }
        for (i, c) in cells.iter_mut().enumerate() {
            if !mask.is_valid(i) {
                *c = false;
            }
        }
        if let Some(t) = &mut thickness {
            for (v, &c) in t.iter_mut().zip(&cells) {
                if !c {
                    *v = 0.0;
                }
            }
        }
        Ok(Self {
            cells,
            thickness,
            width: geometry.width(),
            height: geometry.height(),
            cell_area_m2: geometry.cell_area(),
            warnings: Vec::new(),
        })
    }

    /// Number of released cells.
    pub fn count(&self) -> usize {
        self.cells.iter().filter(|&&c| c).count()
    }

    /// Released area, m².
    pub fn area_m2(&self) -> f64 {
        self.count() as f64 * self.cell_area_m2
    }

    /// Flowing thickness per cell (m, row-major) for a bare DEM: the mask's thickness where it
    /// has one, else `default_m` in released cells, 0 elsewhere. Hand it to
    /// [`AvalancheState::set_thickness`].
    pub fn thickness_field(&self, default_m: f64) -> Result<Vec<f64>, ReleaseAreaError> {
        if !(default_m.is_finite() && default_m >= 0.0) {
            return Err(ReleaseAreaError::InvalidParameter {
                name: "default release thickness",
                value: default_m,
                expected: "finite and >= 0 (m)",
            });
        }
        Ok(match &self.thickness {
            Some(t) => t.clone(),
            None => self
                .cells
                .iter()
                .map(|&c| if c { default_m } else { 0.0 })
                .collect(),
        })
    }

    /// Volume of [`ReleaseMask::thickness_field`], m³.
    pub fn volume_m3(&self, default_m: f64) -> Result<f64, ReleaseAreaError> {
        Ok(self.thickness_field(default_m)?.iter().sum::<f64>() * self.cell_area_m2)
    }

    /// Moves snow of the masked cells from the terrain's layers into the flow, as
    /// [`crate::convert::release`] does: without a per-cell thickness all unstable snow and
    /// powder; with one, up to that many metres from the top of the pack down (powder,
    /// unstable, stable, compacted; taking stable or compacted snow lowers the bed). Returns
    /// the released volume, m³.
    pub fn release(
        &self,
        terrain: &mut LayeredTerrain,
        state: &mut AvalancheState,
    ) -> Result<f64, AvalancheError> {
        let n = terrain.bedrock.len();
        if self.cells.len() != n {
            return Err(AvalancheError::LengthMismatch {
                what: "release mask",
                got: self.cells.len(),
                expected: n,
            });
        }
        let Some(th) = &self.thickness else {
            return crate::convert::release(terrain, state, &self.cells, None);
        };
        let (g, t) = (state.geometry(), terrain.geometry());
        if g.width() != t.width() || g.height() != t.height() {
            return Err(AvalancheError::GeometryMismatch {
                width: g.width(),
                height: g.height(),
                terrain_width: t.width(),
                terrain_height: t.height(),
            });
        }
        // The per-cell form of `convert::release(.., Some(t))`: up to `th[i]` metres from the
        // top of the pack down; taking stable or compacted snow lowers the bed.
        let w = self.width;
        let area = terrain.geometry().cell_area();
        let mut volume = 0.0;
        for (i, &want) in th.iter().enumerate().take(n) {
            if !self.cells[i] || !terrain.mask().is_valid(i) {
                continue;
            }
            if !(want.is_finite() && want >= 0.0) {
                return Err(AvalancheError::BadValue {
                    what: "release thickness",
                    index: i,
                    value: want,
                });
            }
            let k = state.pad(i % w, i / w);
            state.touch_around_cell(k, Some(&*terrain))?;
            let taken = crate::convert::take_from_top(terrain, i, |_, have, so_far| {
                have.min(want - so_far).max(0.0)
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
}

// ---------------------------------------------------------------------------------------------
// CRS comparison.

/// How the values of a release raster are read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RasterRelease {
    /// Every valid nonzero cell is released; the thickness is left to the caller.
    #[default]
    Mask,
    /// Valid cells with a value > 0 are released with that thickness (m).
    Thickness,
}

fn describe_grid(g: &GridGeometry) -> String {
    let t = g.transform();
    format!(
        "{}x{} cells of {} x {}, origin ({}, {}), CRS {}",
        g.width(),
        g.height(),
        t.pixel_width,
        t.pixel_height,
        t.origin_x,
        t.origin_y,
        g.crs()
            .map_or_else(|| "none".to_string(), |c| c.to_string())
    )
}

/// Reads a release raster in the DEM's grid (any format [`snowscape_io::read_dem`] reads, with
/// `options`); see the module docs for the grid check and [`RasterRelease`] for the values.
pub fn release_from_raster(
    path: &Path,
    geometry: &GridGeometry,
    mask: &NodataMask,
    options: &ReadOptions,
    values: RasterRelease,
) -> Result<ReleaseMask, ReleaseAreaError> {
    let grid = snowscape_io::read_dem(path, options)?;
    let g = grid.geometry();
    let (a, b) = (g.transform(), geometry.transform());
    let same = g.width() == geometry.width()
        && g.height() == geometry.height()
        && (a.pixel_width - b.pixel_width).abs() <= 1e-6 * b.pixel_width
        && (a.pixel_height - b.pixel_height).abs() <= 1e-6 * b.pixel_height
        && (a.origin_x - b.origin_x).abs() <= 1e-3 * b.pixel_width
        && (a.origin_y - b.origin_y).abs() <= 1e-3 * b.pixel_height;
    let crs_clash = match (g.crs(), geometry.crs()) {
        (Some(f), Some(d)) => same_crs(f, d) == Some(false),
        _ => false,
    };
    if !same || crs_clash {
        return Err(ReleaseAreaError::RasterGridMismatch {
            path: path.to_path_buf(),
            raster: describe_grid(g),
            dem: describe_grid(geometry),
        });
    }
    let mut warnings = Vec::new();
    check_crs(path, g.crs(), geometry.crs(), &mut warnings)?;
    let w = g.width();
    let data = grid.data();
    let mut cells = vec![false; data.len()];
    let mut th = (values == RasterRelease::Thickness).then(|| vec![0.0; data.len()]);
    for (i, &v) in data.iter().enumerate() {
        if !grid.mask().is_valid(i) {
            continue;
        }
        match values {
            RasterRelease::Mask => cells[i] = v != 0.0,
            RasterRelease::Thickness => {
                if v < 0.0 {
                    return Err(ReleaseAreaError::BadRasterValue {
                        path: path.to_path_buf(),
                        col: i % w,
                        row: i / w,
                        value: v as f64,
                    });
                }
                if v > 0.0 {
                    cells[i] = true;
                    if let Some(t) = th.as_mut() {
                        t[i] = v as f64;
                    }
                }
            }
        }
    }
    finish(path, geometry, mask, cells, th, warnings)
}

// ---------------------------------------------------------------------------------------------
// Rupture at a point (Section 6.1).

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rasterise_even_odd_with_hole() {
        let g = GridGeometry::square(10, 10, 1.0).unwrap();
        // Outer square 1..9, hole 4..6 (cell centres at .5).
        let rings = vec![
            vec![(1.0, 1.0), (9.0, 1.0), (9.0, 9.0), (1.0, 9.0)],
            vec![(4.0, 4.0), (4.0, 6.0), (6.0, 6.0), (6.0, 4.0)],
        ];
        let mut cells = [false; 100];
        let n = rasterise(&rings, &g, |i| cells[i] = true);
        assert_eq!(n, 64 - 4);
        assert_eq!(cells.iter().filter(|&&c| c).count(), 60);
        // Cell (col 4, row 4): centre (4.5, 10 - 4.5 = 5.5) is in the hole.
        assert!(!cells[4 * 10 + 4]);
        assert!(cells[10 + 1]);
        assert!(!cells[0]);
    }
}
