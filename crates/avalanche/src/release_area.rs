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
use shapefile::Shape;
use shapefile::dbase::FieldValue;
use snowscape_io::{RasterError, ReadOptions};
use snowscape_terrain::{Crs, GridGeometry, LayeredTerrain, NodataMask, SnowLayer};
use std::collections::VecDeque;
use std::fmt;
use std::path::{Path, PathBuf};
use thiserror::Error;

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
        let t = g.transform();
        Self {
            x_min: t.origin_x,
            x_max: t.origin_x + g.width() as f64 * t.pixel_width,
            y_min: t.origin_y - g.height() as f64 * t.pixel_height,
            y_max: t.origin_y,
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
    /// The shapefile (`.shp`/`.shx`) cannot be read.
    #[error("cannot read release shapefile {path}: {source}")]
    Shapefile {
        /// The `.shp` path.
        path: PathBuf,
        /// The reader's error.
        #[source]
        source: shapefile::Error,
    },
    /// The attribute table (`.dbf`) cannot be read.
    #[error("cannot read the attribute table {path} of the release shapefile: {source}")]
    Dbf {
        /// The `.dbf` path.
        path: PathBuf,
        /// The reader's error.
        #[source]
        source: shapefile::dbase::Error,
    },
    /// The attribute table has another number of records than the shapefile.
    #[error("{path}: {records} attribute records for {shapes} shapes")]
    DbfRecordCount {
        /// The `.dbf` path.
        path: PathBuf,
        /// Records in the `.dbf`.
        records: usize,
        /// Shapes in the `.shp`.
        shapes: usize,
    },
    /// The `.prj` sidecar cannot be read.
    #[error("cannot read the projection file {path}: {source}")]
    Prj {
        /// The `.prj` path.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
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

/// What a CRS says about itself: an EPSG code (given or recognised from the name), a
/// normalised name, and whether it is geographic.
struct CrsFacts {
    code: Option<u32>,
    name: Option<String>,
    geographic: bool,
}

fn normalise_name(s: &str) -> String {
    s.chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .map(|c| c.to_ascii_lowercase())
        .collect()
}

/// EPSG codes of a few CRS names as EPSG and ESRI spell them (normalised: lower-case
/// alphanumerics), for the grids avalanche practitioners use.
fn code_of_name(n: &str) -> Option<u32> {
    let fixed: &[(&str, u32)] = &[
        ("mgiaustrialambert", 31287),
        ("mgiaustriagkwest", 31254),
        ("mgiaustriagkcentral", 31255),
        ("mgiaustriagkeast", 31256),
        ("mgiaustriagkm28", 31257),
        ("mgiaustriagkm31", 31258),
        ("mgiaustriagkm34", 31259),
        ("wgs84", 4326),
        ("gcswgs1984", 4326),
        ("etrs89", 4258),
        ("gcsetrs1989", 4258),
        ("ch1903lv03", 21781),
        ("ch1903lv95", 2056),
        ("etrs89laea", 3035),
        ("etrs89extendedlaeaeurope", 3035),
        ("etrs1989laea", 3035),
    ];
    if let Some(&(_, c)) = fixed.iter().find(|(k, _)| *k == n) {
        return Some(c);
    }
    // UTM: "wgs84utmzone32n", "wgs1984utmzone32n", "etrs89utmzone32n", "etrs1989utmzone32n".
    for (prefix, north, south) in [
        ("wgs84utmzone", 32600, Some(32700)),
        ("wgs1984utmzone", 32600, Some(32700)),
        ("etrs89utmzone", 25800, None),
        ("etrs1989utmzone", 25800, None),
    ] {
        if let Some(rest) = n.strip_prefix(prefix) {
            let (zone, hemi) = rest.split_at(rest.len().saturating_sub(1));
            let zone: u32 = zone.parse().ok()?;
            if !(1..=60).contains(&zone) {
                return None;
            }
            return match hemi {
                "n" => Some(north + zone),
                "s" => south.map(|s| s + zone),
                _ => None,
            };
        }
    }
    None
}

/// The root keyword, root name and root EPSG authority of a WKT string (WKT1 `AUTHORITY`,
/// WKT2 `ID`, at bracket depth 1).
fn wkt_facts(wkt: &str) -> CrsFacts {
    let t = wkt.trim();
    let open = t.find(['[', '(']);
    let head = open.map_or(t, |o| &t[..o]).trim().to_ascii_uppercase();
    let geographic = matches!(head.as_str(), "GEOGCS" | "GEOGCRS" | "GEODCRS");
    let name = open.and_then(|o| {
        let rest = &t[o + 1..];
        let q0 = rest.find('"')?;
        let q1 = rest[q0 + 1..].find('"')?;
        Some(normalise_name(&rest[q0 + 1..q0 + 1 + q1]))
    });
    // Root-level authority: scan keywords at depth 1.
    let mut code = None;
    let bytes = t.as_bytes();
    let mut depth = 0i32;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'[' | b'(' => depth += 1,
            b']' | b')' => depth -= 1,
            b'"' => {
                // Skip quoted text.
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' {
                    i += 1;
                }
            }
            _ if depth == 1 => {
                let rest = t[i..].to_ascii_uppercase();
                for kw in ["AUTHORITY[", "ID["] {
                    if rest.starts_with(kw) && (i == 0 || !bytes[i - 1].is_ascii_alphabetic()) {
                        let inner = &rest[kw.len()..];
                        let end = inner.find(']').unwrap_or(inner.len());
                        let parts: Vec<&str> = inner[..end]
                            .split(',')
                            .map(|p| p.trim().trim_matches('"').trim())
                            .collect();
                        if parts.len() >= 2 && parts[0] == "EPSG" {
                            code = parts[1].parse().ok();
                        }
                    }
                }
            }
            _ => {}
        }
        i += 1;
    }
    let code = code.or_else(|| name.as_deref().and_then(code_of_name));
    CrsFacts {
        code,
        name,
        geographic,
    }
}

fn crs_facts(crs: &Crs) -> CrsFacts {
    match crs {
        Crs::Epsg(c) => CrsFacts {
            code: Some(*c),
            name: None,
            geographic: crs.is_geographic(),
        },
        Crs::Wkt(w) => wkt_facts(w),
    }
}

/// `Some(true)`: the same CRS; `Some(false)`: clearly different; `None`: cannot tell.
fn same_crs(a: &Crs, b: &Crs) -> Option<bool> {
    let (fa, fb) = (crs_facts(a), crs_facts(b));
    if let (Some(ca), Some(cb)) = (fa.code, fb.code) {
        return Some(ca == cb);
    }
    if fa.geographic != fb.geographic {
        return Some(false);
    }
    match (fa.name, fb.name) {
        (Some(na), Some(nb)) if na == nb => Some(true),
        _ => None,
    }
}

/// Compares the input's CRS with the DEM's: an error when clearly different, a warning when
/// undecidable.
fn check_crs(
    path: &Path,
    file_crs: Option<&Crs>,
    dem_crs: Option<&Crs>,
    warnings: &mut Vec<String>,
) -> Result<(), ReleaseAreaError> {
    match (file_crs, dem_crs) {
        (Some(f), Some(d)) => match same_crs(f, d) {
            Some(true) => Ok(()),
            Some(false) => Err(ReleaseAreaError::CrsMismatch {
                path: path.to_path_buf(),
                file_crs: f.to_string(),
                dem_crs: d.to_string(),
            }),
            None => {
                warnings.push(format!(
                    "{}: cannot tell whether its CRS ({f}) is the DEM's ({d}); assuming it is",
                    path.display()
                ));
                Ok(())
            }
        },
        (Some(f), None) => {
            warnings.push(format!(
                "{}: the release area is in {f}, the DEM declares no CRS; assuming they agree",
                path.display()
            ));
            Ok(())
        }
        _ => Ok(()),
    }
}

// ---------------------------------------------------------------------------------------------
// Shapefiles.

/// One record's rings as (x, y) vertex lists.
type Rings = Vec<Vec<(f64, f64)>>;

fn rings_of(shape: &Shape) -> Option<Rings> {
    fn xy<P>(rings: &[shapefile::PolygonRing<P>], f: impl Fn(&P) -> (f64, f64)) -> Rings {
        rings
            .iter()
            .map(|r| r.points().iter().map(&f).collect())
            .collect()
    }
    match shape {
        Shape::Polygon(p) => Some(xy(p.rings(), |q| (q.x, q.y))),
        Shape::PolygonM(p) => Some(xy(p.rings(), |q| (q.x, q.y))),
        Shape::PolygonZ(p) => Some(xy(p.rings(), |q| (q.x, q.y))),
        _ => None,
    }
}

/// Marks the cells of `geometry` whose centres lie inside `rings` (even-odd rule); returns the
/// number of cell centres inside.
fn rasterise(rings: &Rings, geometry: &GridGeometry, mut mark: impl FnMut(usize)) -> usize {
    let t = geometry.transform();
    let (w, h) = (geometry.width(), geometry.height());
    let Some(e) = MapExtent::of_points(rings.iter().flatten().copied()) else {
        return 0;
    };
    // Rows whose centre y lies within the polygon's y range.
    let row_of = |y: f64| (t.origin_y - y) / t.pixel_height - 0.5;
    let r0 = row_of(e.y_max).ceil().max(0.0);
    let r1 = row_of(e.y_min).floor().min(h as f64 - 1.0);
    if r1 < r0 {
        return 0;
    }
    let mut count = 0;
    let mut xs: Vec<f64> = Vec::new();
    for row in r0 as usize..=r1 as usize {
        let yc = t.origin_y - (row as f64 + 0.5) * t.pixel_height;
        xs.clear();
        for ring in rings {
            let n = ring.len();
            if n < 3 {
                continue;
            }
            for k in 0..n {
                let (x1, y1) = ring[k];
                let (x2, y2) = ring[(k + 1) % n];
                if (y1 <= yc) != (y2 <= yc) {
                    xs.push(x1 + (yc - y1) * (x2 - x1) / (y2 - y1));
                }
            }
        }
        xs.sort_by(f64::total_cmp);
        for pair in xs.chunks_exact(2) {
            // Columns whose centre x lies in [pair[0], pair[1]).
            let c0 = ((pair[0] - t.origin_x) / t.pixel_width - 0.5)
                .ceil()
                .max(0.0);
            let c1 =
                (((pair[1] - t.origin_x) / t.pixel_width - 0.5).ceil() - 1.0).min(w as f64 - 1.0);
            if c1 < c0 {
                continue;
            }
            for col in c0 as usize..=c1 as usize {
                mark(row * w + col);
                count += 1;
            }
        }
    }
    count
}

/// A release thickness attribute (`thickness` or `d0`, any case) of one record.
fn thickness_field_name(names: &[String]) -> Option<String> {
    for want in ["thickness", "d0"] {
        if let Some(n) = names.iter().find(|n| n.eq_ignore_ascii_case(want)) {
            return Some(n.clone());
        }
    }
    None
}

fn field_number(v: &FieldValue) -> Result<f64, String> {
    match v {
        FieldValue::Numeric(Some(x)) | FieldValue::Double(x) | FieldValue::Currency(x) => Ok(*x),
        FieldValue::Float(Some(x)) => Ok(*x as f64),
        FieldValue::Integer(x) => Ok(*x as f64),
        FieldValue::Character(Some(s)) => s.trim().parse().map_err(|_| format!("{s:?}")),
        FieldValue::Numeric(None) | FieldValue::Float(None) | FieldValue::Character(None) => {
            Err("empty".into())
        }
        other => Err(format!("{other:?}")),
    }
}

/// Per-record release thickness from the `.dbf` beside `shp`, `None` when it has no thickness
/// field (or there is no `.dbf`).
fn read_thickness(
    shp: &Path,
    records: usize,
    warnings: &mut Vec<String>,
) -> Result<Option<Vec<f64>>, ReleaseAreaError> {
    let dbf = shp.with_extension("dbf");
    if !dbf.is_file() {
        warnings.push(format!(
            "{}: no attribute table {}: release thickness left to the caller",
            shp.display(),
            dbf.display()
        ));
        return Ok(None);
    }
    let dbf_err = |source| ReleaseAreaError::Dbf {
        path: dbf.clone(),
        source,
    };
    let mut reader = shapefile::dbase::Reader::from_path(&dbf).map_err(dbf_err)?;
    let names: Vec<String> = reader
        .fields()
        .iter()
        .map(|f| f.name().to_string())
        .collect();
    let Some(field) = thickness_field_name(&names) else {
        return Ok(None);
    };
    let rows = reader.read().map_err(dbf_err)?;
    if rows.len() != records {
        return Err(ReleaseAreaError::DbfRecordCount {
            path: dbf,
            records: rows.len(),
            shapes: records,
        });
    }
    let mut out = Vec::with_capacity(rows.len());
    for (k, rec) in rows.iter().enumerate() {
        let bad = |value: String| ReleaseAreaError::BadThickness {
            path: dbf.clone(),
            record: k,
            field: field.clone(),
            value,
        };
        let v = rec.get(&field).ok_or_else(|| bad("missing".into()))?;
        let x = field_number(v).map_err(bad)?;
        if !(x.is_finite() && x > 0.0) {
            return Err(bad(x.to_string()));
        }
        out.push(x);
    }
    Ok(Some(out))
}

/// The CRS of the `.prj` beside `path`, if there is one: its WKT, or the EPSG code at its root.
fn read_prj(path: &Path) -> Result<Option<Crs>, ReleaseAreaError> {
    let prj = path.with_extension("prj");
    if !prj.is_file() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&prj).map_err(|source| ReleaseAreaError::Prj {
        path: prj.clone(),
        source,
    })?;
    let t = text.trim().trim_start_matches('\u{feff}');
    if t.is_empty() {
        return Ok(None);
    }
    Ok(Crs::parse(t).map(|c| match &c {
        Crs::Wkt(w) => wkt_facts(w).code.map_or(c.clone(), Crs::Epsg),
        Crs::Epsg(_) => c,
    }))
}

/// Rasterises the polygons of an ESRI shapefile into the DEM's grid (see the module docs: cell
/// centres inside by the even-odd rule, per-record thickness from a `thickness`/`d0` field, CRS
/// from the `.prj`). Nodata cells of `mask` are never released.
pub fn release_from_shapefile(
    path: &Path,
    geometry: &GridGeometry,
    mask: &NodataMask,
) -> Result<ReleaseMask, ReleaseAreaError> {
    let shp_err = |source| ReleaseAreaError::Shapefile {
        path: path.to_path_buf(),
        source,
    };
    let shapes = shapefile::ShapeReader::from_path(path)
        .and_then(|r| r.read())
        .map_err(shp_err)?;
    let mut warnings = Vec::new();
    check_crs(
        path,
        read_prj(path)?.as_ref(),
        geometry.crs(),
        &mut warnings,
    )?;
    let thickness = read_thickness(path, shapes.len(), &mut warnings)?;
    let dem = MapExtent::of_grid(geometry);
    let n = geometry.len();
    let mut cells = vec![false; n];
    let mut th = thickness.as_ref().map(|_| vec![0.0f64; n]);
    let mut polygons = 0;
    for (k, shape) in shapes.iter().enumerate() {
        if matches!(shape, Shape::NullShape) {
            warnings.push(format!(
                "{}: record {k} is a null shape, skipped",
                path.display()
            ));
            continue;
        }
        let rings = rings_of(shape).ok_or_else(|| ReleaseAreaError::NotPolygons {
            path: path.to_path_buf(),
            record: k,
            shape_type: shape.shapetype().to_string(),
        })?;
        let Some(ext) = MapExtent::of_points(rings.iter().flatten().copied()) else {
            warnings.push(format!(
                "{}: record {k} has no vertex, skipped",
                path.display()
            ));
            continue;
        };
        polygons += 1;
        if !ext.intersects(&dem) {
            return Err(ReleaseAreaError::PolygonOutsideDem {
                path: path.to_path_buf(),
                record: k,
                polygon: ext,
                dem,
            });
        }
        if !dem.contains_extent(&ext) {
            warnings.push(format!(
                "{}: release polygon {k} ({ext}) reaches beyond the DEM ({dem}): clipped",
                path.display()
            ));
        }
        let value = thickness.as_ref().map(|t| t[k]);
        let inside = rasterise(&rings, geometry, |i| {
            cells[i] = true;
            if let (Some(t), Some(v)) = (th.as_mut(), value) {
                t[i] = t[i].max(v);
            }
        });
        if inside == 0 {
            let t = geometry.transform();
            return Err(ReleaseAreaError::NoCellInside {
                path: path.to_path_buf(),
                record: k,
                polygon: ext,
                cell_x: t.pixel_width,
                cell_y: t.pixel_height,
            });
        }
    }
    if polygons == 0 {
        return Err(ReleaseAreaError::NoPolygons {
            path: path.to_path_buf(),
            records: shapes.len(),
        });
    }
    finish(path, geometry, mask, cells, th, warnings)
}

/// Drops nodata cells (with a warning), checks something is left.
fn finish(
    path: &Path,
    geometry: &GridGeometry,
    mask: &NodataMask,
    cells: Vec<bool>,
    th: Option<Vec<f64>>,
    mut warnings: Vec<String>,
) -> Result<ReleaseMask, ReleaseAreaError> {
    let covered = cells.iter().filter(|&&c| c).count();
    let mut out = ReleaseMask::from_cells(geometry, mask, cells, th)?;
    let kept = out.count();
    if kept == 0 {
        return Err(ReleaseAreaError::EmptyRelease {
            path: path.to_path_buf(),
            covered,
        });
    }
    if kept < covered {
        warnings.push(format!(
            "{}: {} of {covered} covered cells are nodata in the DEM and do not release",
            path.display(),
            covered - kept
        ));
    }
    out.warnings = warnings;
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// Raster masks.

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

/// Parameters of the rupture at a point (module docs, *Rupture at a point*).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RuptureParams {
    /// Reach of the fracture per metre of unstable snow at the rupture point, m/m: `R = k·U0`.
    /// Default 50 (chosen here: a 0.5 m slab breaks over a 25 m radius, a 50 m wide crown, the
    /// size of a common dry-slab release; the paper gives only the proportionality).
    pub reach_per_unstable_m: f64,
    /// Unstable thickness below which a cell counts as holding no unstable snow, m. Default
    /// 0.01 (chosen here: 1 cm, the footprint threshold of peak-thickness maps).
    pub min_unstable_m: f64,
    /// Slope below which the downslope reach stops, degrees. Default 25 (the snowfall model's
    /// critical slope of unstable snow `s_U`, Cordonnier et al. 2018 Table 2).
    pub min_slope_deg: f64,
}

impl Default for RuptureParams {
    fn default() -> Self {
        Self {
            reach_per_unstable_m: 50.0,
            min_unstable_m: 0.01,
            min_slope_deg: 25.0,
        }
    }
}

impl RuptureParams {
    /// Checks every field, naming the offending one.
    pub fn validate(&self) -> Result<(), ReleaseAreaError> {
        let bad = |name, value, expected| {
            Err(ReleaseAreaError::InvalidParameter {
                name,
                value,
                expected,
            })
        };
        if !(self.reach_per_unstable_m.is_finite() && self.reach_per_unstable_m >= 0.0) {
            return bad(
                "reach_per_unstable_m",
                self.reach_per_unstable_m,
                "finite and >= 0",
            );
        }
        if !(self.min_unstable_m.is_finite() && self.min_unstable_m > 0.0) {
            return bad("min_unstable_m", self.min_unstable_m, "finite and > 0");
        }
        if !(self.min_slope_deg.is_finite() && (0.0..90.0).contains(&self.min_slope_deg)) {
            return bad("min_slope_deg", self.min_slope_deg, "in [0, 90)");
        }
        Ok(())
    }
}

/// A rupture at a point: the released cells and how they came about.
#[derive(Debug, Clone, PartialEq)]
pub struct Rupture {
    /// The released cells (no per-cell thickness: all unstable snow and powder go).
    pub mask: ReleaseMask,
    /// The rupture cell (col, row).
    pub cell: (usize, usize),
    /// Unstable thickness at the rupture cell, m.
    pub unstable_m: f64,
    /// Reach of the fracture, m.
    pub reach_m: f64,
    /// Cells of the rupture zone (within the reach).
    pub zone_cells: usize,
    /// Cells added by the downslope reach (outside the rupture zone).
    pub downslope_cells: usize,
}

/// The rupture of Cordonnier et al. 2018, Section 6.1, at map point `(x, y)` of `terrain`:
/// the "Snow Moving" mask of the rupture zone (unstable snow within a reach proportional to
/// the unstable thickness at the point) and of the unstable snow down the fall lines below it.
/// See the module docs for the design.
pub fn release_at_point(
    terrain: &LayeredTerrain,
    x: f64,
    y: f64,
    params: &RuptureParams,
) -> Result<Rupture, ReleaseAreaError> {
    let r = rupture_at_point(terrain, x, y, params)?;
    Ok(Rupture {
        mask: ReleaseMask::from_cells(terrain.geometry(), terrain.mask(), r.flags, None)?,
        cell: r.cell,
        unstable_m: r.unstable_m,
        reach_m: r.reach_m,
        zone_cells: r.zone_cells,
        downslope_cells: r.downslope_cells,
    })
}

/// The cells of a rupture at a point (see [`release_at_point`]), without a grid-sized mask.
#[derive(Debug, Clone, PartialEq)]
pub struct RuptureCells {
    /// The released cells, row-major indices in ascending order (all valid).
    pub cells: Vec<usize>,
    /// One flag per grid cell: released or not.
    pub flags: Vec<bool>,
    /// The rupture cell (col, row).
    pub cell: (usize, usize),
    /// Unstable thickness at the rupture cell, m.
    pub unstable_m: f64,
    /// Reach of the fracture, m.
    pub reach_m: f64,
    /// Cells of the rupture zone (within the reach).
    pub zone_cells: usize,
    /// Cells added by the downslope reach (outside the rupture zone).
    pub downslope_cells: usize,
}

/// [`release_at_point`] as a list of cells: its cost follows the rupture, not the grid.
pub fn rupture_at_point(
    terrain: &LayeredTerrain,
    x: f64,
    y: f64,
    params: &RuptureParams,
) -> Result<RuptureCells, ReleaseAreaError> {
    params.validate()?;
    let g = terrain.geometry();
    let mask = terrain.mask();
    let (w, h) = (g.width(), g.height());
    let (dx, dy) = (g.cell_size_x(), g.cell_size_y());
    let (fc, fr) = g
        .map_to_cell(x, y)
        .filter(|_| x.is_finite() && y.is_finite())
        .ok_or(ReleaseAreaError::PointOutsideDem {
            x,
            y,
            dem: MapExtent::of_grid(g),
        })?;
    let col = (fc.round().max(0.0) as usize).min(w - 1);
    let row = (fr.round().max(0.0) as usize).min(h - 1);
    let i0 = row * w + col;
    if !mask.is_valid(i0) {
        return Err(ReleaseAreaError::PointOnNodata { x, y, col, row });
    }
    let unstable = terrain.layer(SnowLayer::Unstable);
    let u0 = unstable[i0] as f64;
    if u0.is_nan() || u0 < params.min_unstable_m {
        return Err(ReleaseAreaError::NoUnstableSnow {
            x,
            y,
            col,
            row,
            unstable_m: u0,
            min_unstable_m: params.min_unstable_m,
        });
    }
    let has_unstable = |i: usize| mask.is_valid(i) && unstable[i] as f64 >= params.min_unstable_m;
    let reach = params.reach_per_unstable_m * u0;
    // Point in local metres (east, south of the north-west corner).
    let (px, py) = ((fc + 0.5) * dx, (fr + 0.5) * dy);

    // 3. Rupture zone: flood fill through unstable snow within the reach.
    let mut cells = vec![false; w * h];
    let mut zone = Vec::new();
    let mut queue = VecDeque::from([i0]);
    cells[i0] = true;
    while let Some(i) = queue.pop_front() {
        zone.push(i);
        let (c, r) = (i % w, i / w);
        for dr in -1isize..=1 {
            for dc in -1isize..=1 {
                let Some(j) = g.neighbour(c, r, dc, dr) else {
                    continue;
                };
                if cells[j] || !has_unstable(j) {
                    continue;
                }
                let (jx, jy) = g.local_metres(j % w, j / w);
                if (jx - px).hypot(jy - py) <= reach {
                    cells[j] = true;
                    queue.push_back(j);
                }
            }
        }
    }
    let zone_cells = zone.len();

    // 4. Downslope reach: fall lines from every rupture-zone cell.
    // The snow surface of a cell (the sums of `LayeredTerrain::surface`).
    let surface = |i: usize| (terrain.bedrock[i] + terrain.depth_at(i)) as f64;
    let tan_min = params.min_slope_deg.to_radians().tan();
    // Per-cell gradient (x east, y south), central differences, one-sided next to nodata.
    let grad = |c: usize, r: usize| -> [f64; 2] {
        let i = r * w + c;
        let at = |dc: isize, dr: isize| match g.neighbour(c, r, dc, dr) {
            Some(j) if mask.is_valid(j) => (surface(j), 1.0),
            _ => (surface(i), 0.0),
        };
        let ((zw, ww), (ze, we)) = (at(-1, 0), at(1, 0));
        let ((zn, wn), (zs, ws)) = (at(0, -1), at(0, 1));
        let gx = if ww + we > 0.0 {
            (ze - zw) / ((ww + we) * dx)
        } else {
            0.0
        };
        let gy = if wn + ws > 0.0 {
            (zs - zn) / ((wn + ws) * dy)
        } else {
            0.0
        };
        [gx, gy]
    };
    // Bilinear gradient at local position (metres); nearest cell's when a corner is nodata.
    let grad_at = |x: f64, y: f64| -> [f64; 2] {
        let (fcx, fry) = (x / dx - 0.5, y / dy - 0.5);
        let c0 = fcx.floor().clamp(0.0, (w - 1) as f64) as usize;
        let r0 = fry.floor().clamp(0.0, (h - 1) as f64) as usize;
        let (c1, r1) = ((c0 + 1).min(w - 1), (r0 + 1).min(h - 1));
        let (tx, ty) = (
            (fcx - c0 as f64).clamp(0.0, 1.0),
            (fry - r0 as f64).clamp(0.0, 1.0),
        );
        let corners = [(c0, r0), (c1, r0), (c0, r1), (c1, r1)];
        if corners.iter().any(|&(c, r)| !mask.is_valid(r * w + c)) {
            let c = (x / dx).floor().clamp(0.0, (w - 1) as f64) as usize;
            let r = (y / dy).floor().clamp(0.0, (h - 1) as f64) as usize;
            return grad(c, r);
        }
        let [g00, g10, g01, g11] = corners.map(|(c, r)| grad(c, r));
        let lerp = |k: usize| {
            (1.0 - ty) * ((1.0 - tx) * g00[k] + tx * g10[k])
                + ty * ((1.0 - tx) * g01[k] + tx * g11[k])
        };
        [lerp(0), lerp(1)]
    };
    let step_len = 0.5 * dx.min(dy);
    let max_steps = 4 * (w + h) * ((dx.max(dy) / dx.min(dy)).ceil() as usize);
    let mut downslope_cells = 0;
    // (The fall lines start from the rupture zone, its first `zone_cells` entries; the cells
    // they add are appended.)
    for z in 0..zone_cells {
        let start = zone[z];
        let (sc, sr) = (start % w, start / w);
        let (mut x, mut y) = g.local_metres(sc, sr);
        let mut last = start;
        for _ in 0..max_steps {
            let [gx, gy] = grad_at(x, y);
            let norm = gx.hypot(gy);
            if norm < 1e-9 {
                break;
            }
            x -= step_len * gx / norm;
            y -= step_len * gy / norm;
            if x < 0.0 || y < 0.0 || x >= w as f64 * dx || y >= h as f64 * dy {
                break;
            }
            let (c, r) = ((x / dx) as usize, (y / dy) as usize);
            let i = r * w + c;
            if i == last {
                continue;
            }
            if !has_unstable(i) || surface(i) > surface(last) {
                break;
            }
            let [cgx, cgy] = grad(c, r);
            if cgx.hypot(cgy) < tan_min {
                break;
            }
            if !cells[i] {
                cells[i] = true;
                zone.push(i);
                downslope_cells += 1;
            }
            last = i;
        }
    }
    zone.sort_unstable();
    Ok(RuptureCells {
        cells: zone,
        flags: cells,
        cell: (col, row),
        unstable_m: u0,
        reach_m: reach,
        zone_cells,
        downslope_cells,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wkt_root_authority_and_names() {
        let wkt = r#"PROJCS["MGI / Austria Lambert",GEOGCS["MGI",AUTHORITY["EPSG","4312"]],UNIT["metre",1],AUTHORITY["EPSG","31287"]]"#;
        assert_eq!(wkt_facts(wkt).code, Some(31287));
        let esri =
            r#"PROJCS["MGI_Austria_Lambert",GEOGCS["GCS_MGI",DATUM["D_MGI"]],UNIT["Meter",1.0]]"#;
        let f = wkt_facts(esri);
        assert_eq!(f.code, Some(31287));
        assert!(!f.geographic);
        assert_eq!(
            same_crs(&Crs::Wkt(esri.into()), &Crs::Epsg(31287)),
            Some(true)
        );
        assert_eq!(
            same_crs(&Crs::Wkt(esri.into()), &Crs::Epsg(32632)),
            Some(false)
        );
        let utm = r#"PROJCS["WGS_1984_UTM_Zone_32N",GEOGCS["GCS_WGS_1984"]]"#;
        assert_eq!(wkt_facts(utm).code, Some(32632));
        let unknown = r#"PROJCS["My_Local_Grid",GEOGCS["GCS_WGS_1984"]]"#;
        assert_eq!(same_crs(&Crs::Wkt(unknown.into()), &Crs::Epsg(31287)), None);
        let geo = r#"GEOGCS["Some datum",DATUM["x"]]"#;
        assert_eq!(
            same_crs(&Crs::Wkt(geo.into()), &Crs::Wkt(unknown.into())),
            Some(false)
        );
    }

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
