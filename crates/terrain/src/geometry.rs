//! Grid geometry: size, metric cell size, georeferencing and index helpers.
//!
//! Conventions (those of GeoTIFF and ESRI ASCII grids): cells are addressed by `(col, row)`;
//! row 0 is the northern edge; the flat index is `row * width + col`. Map coordinates are in the
//! units of the grid's CRS, and the georeferencing is the north-up affine transform
//! `x = origin_x + col * pixel_width`, `y = origin_y - row * pixel_height` of the cell *corner*.
//!
//! The simulation works in metres. For a projected CRS the metric cell size equals the pixel
//! size; for a geographic CRS (degrees) it is derived from the latitude of the grid's centre
//! with the WGS84 lengths of a degree of latitude and longitude, so slopes are right.

use crate::TerrainError;
use serde::{Deserialize, Serialize};

/// The largest number of cells a grid may hold (4 Gi cells, 16 GiB per f32 layer).
pub const MAX_CELLS: usize = 1 << 32;

/// A coordinate reference system, as read from the input or set by the user.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum Crs {
    /// An EPSG code, e.g. 31287 (MGI / Austria Lambert) or 4326 (WGS84 degrees).
    Epsg(u32),
    /// A WKT definition (from a `.prj` sidecar, say).
    Wkt(String),
}

impl Crs {
    /// Whether this CRS measures positions in degrees of latitude and longitude.
    pub fn is_geographic(&self) -> bool {
        match self {
            // The common geographic 2D codes: WGS84, ETRS89, NAD83, NAD27, GDA94, GDA2020, JGD2000,
            // and the EPSG 4xxx geographic block as a whole (4000..=4999 are geographic CRSs).
            Crs::Epsg(code) => (4000..5000).contains(code),
            Crs::Wkt(wkt) => {
                let head = wkt.trim_start().to_ascii_uppercase();
                head.starts_with("GEOGCS") || head.starts_with("GEOGCRS")
            }
        }
    }

    /// Parse `EPSG:31287`, `epsg:4326`, a bare code `31287`, or a WKT string.
    pub fn parse(text: &str) -> Option<Crs> {
        let t = text.trim();
        if t.is_empty() {
            return None;
        }
        let code = t
            .strip_prefix("EPSG:")
            .or_else(|| t.strip_prefix("epsg:"))
            .unwrap_or(t);
        if let Ok(c) = code.trim().parse::<u32>() {
            return Some(Crs::Epsg(c));
        }
        Some(Crs::Wkt(t.to_string()))
    }
}

impl std::fmt::Display for Crs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Crs::Epsg(c) => write!(f, "EPSG:{c}"),
            Crs::Wkt(w) => {
                let short: String = w.chars().take(60).collect();
                write!(f, "WKT {short}{}", if w.len() > 60 { "..." } else { "" })
            }
        }
    }
}

/// North-up affine georeferencing of the grid's top-left corner, in CRS units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GeoTransform {
    /// Map x of the western edge of column 0.
    pub origin_x: f64,
    /// Map y of the northern edge of row 0.
    pub origin_y: f64,
    /// Width of a cell in CRS units (> 0).
    pub pixel_width: f64,
    /// Height of a cell in CRS units (> 0; y decreases as the row grows).
    pub pixel_height: f64,
}

/// The geometry of a raster: size, metric cell size, georeferencing and CRS.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GridGeometry {
    width: usize,
    height: usize,
    /// Cell size along x (west-east), metres.
    cell_size_x: f64,
    /// Cell size along y (north-south), metres.
    cell_size_y: f64,
    transform: GeoTransform,
    crs: Option<Crs>,
}

fn check_size(width: usize, height: usize) -> Result<(), TerrainError> {
    if width == 0 || height == 0 {
        return Err(TerrainError::InvalidSize {
            width,
            height,
            reason: "a grid needs at least one column and one row",
        });
    }
    match width.checked_mul(height) {
        Some(n) if n <= MAX_CELLS => Ok(()),
        _ => Err(TerrainError::InvalidSize {
            width,
            height,
            reason: "more cells than the 2^32 a grid may hold",
        }),
    }
}

fn check_cell(axis: char, value: f64) -> Result<(), TerrainError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(TerrainError::InvalidCellSize { axis, value })
    }
}

/// Length in metres of one degree of latitude and of longitude at `lat_deg` (WGS84 series).
pub fn metres_per_degree(lat_deg: f64) -> (f64, f64) {
    let p = lat_deg.to_radians();
    let lat = 111_132.954 - 559.822 * (2.0 * p).cos() + 1.175 * (4.0 * p).cos();
    let lon = 111_412.84 * p.cos() - 93.5 * (3.0 * p).cos() + 0.118 * (5.0 * p).cos();
    (lat, lon)
}

impl GridGeometry {
    /// A local metric grid (no CRS) whose south-west corner is at map (0, 0).
    pub fn new(
        width: usize,
        height: usize,
        cell_size_x: f64,
        cell_size_y: f64,
    ) -> Result<Self, TerrainError> {
        check_size(width, height)?;
        check_cell('x', cell_size_x)?;
        check_cell('y', cell_size_y)?;
        Ok(Self {
            width,
            height,
            cell_size_x,
            cell_size_y,
            transform: GeoTransform {
                origin_x: 0.0,
                origin_y: height as f64 * cell_size_y,
                pixel_width: cell_size_x,
                pixel_height: cell_size_y,
            },
            crs: None,
        })
    }

    /// A square-celled local metric grid.
    pub fn square(width: usize, height: usize, cell_size: f64) -> Result<Self, TerrainError> {
        Self::new(width, height, cell_size, cell_size)
    }

    /// A georeferenced grid. The metric cell size is the pixel size, unless the CRS is
    /// geographic, in which case it is derived from the latitude of the grid's centre. Without
    /// a CRS the pixel size is metres, however small.
    pub fn from_transform(
        width: usize,
        height: usize,
        transform: GeoTransform,
        crs: Option<Crs>,
    ) -> Result<Self, TerrainError> {
        check_size(width, height)?;
        for (what, v) in [
            ("origin_x", transform.origin_x),
            ("origin_y", transform.origin_y),
        ] {
            if !v.is_finite() {
                return Err(TerrainError::InvalidTransform { what, value: v });
            }
        }
        check_cell('x', transform.pixel_width)?;
        check_cell('y', transform.pixel_height)?;
        let mut g = Self {
            width,
            height,
            cell_size_x: transform.pixel_width,
            cell_size_y: transform.pixel_height,
            transform,
            crs,
        };
        if g.is_geographic() {
            let (m_lat, m_lon) = metres_per_degree(g.centre_latitude_deg().unwrap_or(0.0));
            g.cell_size_x = transform.pixel_width * m_lon.max(1.0);
            g.cell_size_y = transform.pixel_height * m_lat;
        }
        Ok(g)
    }

    /// Checks that the metric cell sizes are within [`crate::grid::MIN_TERRAIN_CELL_M`] and
    /// [`crate::grid::MAX_TERRAIN_CELL_M`] (what a terrain cell may be).
    pub fn check_terrain_cells(&self) -> Result<(), TerrainError> {
        let (lo, hi) = (
            crate::grid::MIN_TERRAIN_CELL_M,
            crate::grid::MAX_TERRAIN_CELL_M,
        );
        for (axis, value) in [('x', self.cell_size_x), ('y', self.cell_size_y)] {
            if !(lo..=hi).contains(&value) {
                return Err(TerrainError::TerrainCellSize {
                    axis,
                    value,
                    lo,
                    hi,
                });
            }
        }
        Ok(())
    }

    /// Whether positions are in degrees: only when the CRS is geographic. A grid without a
    /// CRS is metric whatever its cell size (a mesh voxelised at 1 cm is not in degrees); a
    /// DEM in degrees without a CRS needs one given (`--crs EPSG:4326`).
    pub fn is_geographic(&self) -> bool {
        self.crs.as_ref().is_some_and(Crs::is_geographic)
    }

    /// Latitude of the grid centre in degrees, when the grid is in degrees.
    pub fn centre_latitude_deg(&self) -> Option<f64> {
        let centre =
            self.transform.origin_y - 0.5 * self.height as f64 * self.transform.pixel_height;
        self.is_geographic().then_some(centre)
    }

    /// Latitude of the grid centre in degrees north, when the georeferencing tells it: a grid
    /// in degrees, or a projected CRS that [`crate::crs_latitude`] can invert.
    pub fn latitude_deg(&self) -> Option<f64> {
        if let Some(lat) = self.centre_latitude_deg() {
            return Some(lat);
        }
        let (x, y) = (
            self.transform.origin_x + 0.5 * self.width as f64 * self.transform.pixel_width,
            self.transform.origin_y - 0.5 * self.height as f64 * self.transform.pixel_height,
        );
        crate::crs_latitude::latitude_deg(self.crs.as_ref()?, x, y)
    }

    /// Number of columns.
    pub fn width(&self) -> usize {
        self.width
    }
    /// Number of rows.
    pub fn height(&self) -> usize {
        self.height
    }
    /// Number of cells.
    pub fn len(&self) -> usize {
        self.width * self.height
    }
    /// Always false: a geometry has at least one cell.
    pub fn is_empty(&self) -> bool {
        false
    }
    /// Cell size along x (west-east), metres.
    pub fn cell_size_x(&self) -> f64 {
        self.cell_size_x
    }
    /// Cell size along y (north-south), metres.
    pub fn cell_size_y(&self) -> f64 {
        self.cell_size_y
    }
    /// Area of one cell, m².
    pub fn cell_area(&self) -> f64 {
        self.cell_size_x * self.cell_size_y
    }
    /// Extent in metres (west-east, north-south).
    pub fn extent_m(&self) -> (f64, f64) {
        (
            self.width as f64 * self.cell_size_x,
            self.height as f64 * self.cell_size_y,
        )
    }
    /// The map rectangle the cells cover (their outer edges), CRS units:
    /// `[x_min, y_min, x_max, y_max]`.
    pub fn map_bounds(&self) -> [f64; 4] {
        let t = &self.transform;
        [
            t.origin_x,
            t.origin_y - self.height as f64 * t.pixel_height,
            t.origin_x + self.width as f64 * t.pixel_width,
            t.origin_y,
        ]
    }
    /// The georeferencing transform.
    pub fn transform(&self) -> &GeoTransform {
        &self.transform
    }
    /// The CRS, when known.
    pub fn crs(&self) -> Option<&Crs> {
        self.crs.as_ref()
    }
    /// The same geometry with another CRS.
    pub fn with_crs(mut self, crs: Option<Crs>) -> Self {
        self.crs = crs;
        self
    }

    /// Flat index of `(col, row)`. Debug-asserts the cell is inside.
    #[inline(always)]
    pub fn index(&self, col: usize, row: usize) -> usize {
        debug_assert!(col < self.width && row < self.height);
        row * self.width + col
    }
    /// `(col, row)` of a flat index.
    #[inline(always)]
    pub fn col_row(&self, index: usize) -> (usize, usize) {
        (index % self.width, index / self.width)
    }
    /// Whether signed `(col, row)` lies inside the grid.
    #[inline(always)]
    pub fn contains(&self, col: isize, row: isize) -> bool {
        col >= 0 && row >= 0 && (col as usize) < self.width && (row as usize) < self.height
    }
    /// Flat index of the neighbour at offset `(dc, dr)`, or `None` outside the grid.
    #[inline(always)]
    pub fn neighbour(&self, col: usize, row: usize, dc: isize, dr: isize) -> Option<usize> {
        let (c, r) = (col as isize + dc, row as isize + dr);
        self.contains(c, r)
            .then(|| r as usize * self.width + c as usize)
    }
    /// Map coordinates (CRS units) of the centre of `(col, row)`.
    pub fn cell_centre(&self, col: usize, row: usize) -> (f64, f64) {
        let t = &self.transform;
        (
            t.origin_x + (col as f64 + 0.5) * t.pixel_width,
            t.origin_y - (row as f64 + 0.5) * t.pixel_height,
        )
    }
    /// Fractional `(col, row)` of a map position, measured so that cell centres are whole
    /// numbers; `None` if the position lies outside the grid's extent.
    pub fn map_to_cell(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let t = &self.transform;
        let c = (x - t.origin_x) / t.pixel_width - 0.5;
        let r = (t.origin_y - y) / t.pixel_height - 0.5;
        let inside =
            c >= -0.5 && r >= -0.5 && c <= self.width as f64 - 0.5 && r <= self.height as f64 - 0.5;
        inside.then_some((c, r))
    }
    /// Local metric position (metres east and south of the north-west corner) of a cell centre.
    pub fn local_metres(&self, col: usize, row: usize) -> (f64, f64) {
        (
            (col as f64 + 0.5) * self.cell_size_x,
            (row as f64 + 0.5) * self.cell_size_y,
        )
    }
    /// The geometry of a `factor`-times coarser (> 1) or finer (< 1) grid over the same extent.
    pub fn resampled(&self, width: usize, height: usize) -> Result<Self, TerrainError> {
        check_size(width, height)?;
        let sx = self.width as f64 / width as f64;
        let sy = self.height as f64 / height as f64;
        Ok(Self {
            width,
            height,
            cell_size_x: self.cell_size_x * sx,
            cell_size_y: self.cell_size_y * sy,
            transform: GeoTransform {
                pixel_width: self.transform.pixel_width * sx,
                pixel_height: self.transform.pixel_height * sy,
                ..self.transform
            },
            crs: self.crs.clone(),
        })
    }
    /// Whether two geometries describe the same cells (size, transform and CRS).
    pub fn same_cells(&self, other: &Self) -> bool {
        self.width == other.width
            && self.height == other.height
            && self.transform == other.transform
            && self.crs == other.crs
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_cell_sizes() {
        for v in [0.0, -5.0, f64::NAN, f64::INFINITY] {
            let e = GridGeometry::new(4, 4, v, 1.0).unwrap_err();
            assert!(matches!(e, TerrainError::InvalidCellSize { axis: 'x', .. }));
        }
        assert!(GridGeometry::new(0, 4, 1.0, 1.0).is_err());
        assert!(GridGeometry::new(100_000, 100_000, 1.0, 1.0).is_err());
    }

    #[test]
    fn index_and_coordinates_round_trip() {
        let g = GridGeometry::from_transform(
            30,
            20,
            GeoTransform {
                origin_x: 1000.0,
                origin_y: 5000.0,
                pixel_width: 10.0,
                pixel_height: 10.0,
            },
            Some(Crs::Epsg(32611)),
        )
        .unwrap();
        let i = g.index(7, 3);
        assert_eq!(g.col_row(i), (7, 3));
        let (x, y) = g.cell_centre(7, 3);
        assert_eq!((x, y), (1075.0, 4965.0));
        let (c, r) = g.map_to_cell(x, y).unwrap();
        assert!((c - 7.0).abs() < 1e-12 && (r - 3.0).abs() < 1e-12);
        assert!(g.map_to_cell(999.0, 4965.0).is_none());
        assert_eq!(g.neighbour(0, 0, -1, 0), None);
        assert_eq!(g.neighbour(0, 0, 1, 1), Some(31));
        assert!(!g.is_geographic());
        assert_eq!(g.cell_size_x(), 10.0);
    }

    #[test]
    fn degrees_get_metric_cells() {
        // 3 arc-second grid at 36.6 N, like the Jacksboro DEM.
        let g = GridGeometry::from_transform(
            403,
            344,
            GeoTransform {
                origin_x: -84.41375,
                origin_y: 36.44625 + 344.0 / 1200.0,
                pixel_width: 1.0 / 1200.0,
                pixel_height: 1.0 / 1200.0,
            },
            Some(Crs::Epsg(4326)),
        )
        .unwrap();
        assert!(g.is_geographic());
        assert!((g.cell_size_y() - 92.5).abs() < 0.5, "{}", g.cell_size_y());
        assert!((g.cell_size_x() - 74.5).abs() < 0.5, "{}", g.cell_size_x());
    }

    #[test]
    fn tiny_cells_without_a_crs_stay_metres() {
        // A mesh voxelised at 1 cm near the origin: once read as degrees (1112 m cells).
        let t = GeoTransform {
            origin_x: 0.0,
            origin_y: 0.64,
            pixel_width: 0.01,
            pixel_height: 0.01,
        };
        let g = GridGeometry::from_transform(64, 64, t, None).unwrap();
        assert!(!g.is_geographic());
        assert_eq!((g.cell_size_x(), g.cell_size_y()), (0.01, 0.01));
        assert_eq!(g.centre_latitude_deg(), None);
        let g = GridGeometry::from_transform(64, 64, t, Some(Crs::Epsg(4326))).unwrap();
        assert!(g.is_geographic() && g.cell_size_y() > 1000.0);
    }

    #[test]
    fn crs_parsing() {
        assert_eq!(Crs::parse("EPSG:31287"), Some(Crs::Epsg(31287)));
        assert_eq!(Crs::parse(" 4326 "), Some(Crs::Epsg(4326)));
        assert!(Crs::parse("GEOGCS[\"WGS 84\"]").unwrap().is_geographic());
        assert!(!Crs::Epsg(31287).is_geographic());
        assert_eq!(Crs::parse(""), None);
    }
}
