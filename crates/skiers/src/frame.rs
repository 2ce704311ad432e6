//! The local metric frame skiers move in, and its link to map coordinates.
//!
//! Positions are metres east (`x`) and south (`y`) of the grid's north-west corner, so cell
//! `(col, row)` spans `[col·dx, (col+1)·dx) × [row·dy, (row+1)·dy)` and its centre is at
//! `((col+½)·dx, (row+½)·dy)`. Map coordinates (CRS units) follow the grid's north-up affine
//! transform: `X = origin_x + x/dx · pixel_width`, `Y = origin_y − y/dy · pixel_height`, which
//! is exact for projected and geographic grids alike.

use crate::SkiError;
use snowscape_terrain::{GridGeometry, LayeredTerrain, NodataMask, operators};

/// Map coordinates `(X, Y)` of the local position `(x, y)` (m).
pub fn local_to_map(geometry: &GridGeometry, x: f64, y: f64) -> (f64, f64) {
    let t = geometry.transform();
    (
        t.origin_x + x / geometry.cell_size_x() * t.pixel_width,
        t.origin_y - y / geometry.cell_size_y() * t.pixel_height,
    )
}

/// The map extent `(x_min, x_max, y_min, y_max)` of the grid, CRS units.
pub fn map_extent(geometry: &GridGeometry) -> (f64, f64, f64, f64) {
    let t = geometry.transform();
    let x_max = t.origin_x + geometry.width() as f64 * t.pixel_width;
    let y_min = t.origin_y - geometry.height() as f64 * t.pixel_height;
    (t.origin_x, x_max, y_min, t.origin_y)
}

/// A local position (m) and the cell `(col, row)` holding it.
pub type LocalPoint = ((f64, f64), (usize, usize));

/// The local position (m) and cell `(col, row)` of the map point `(X, Y)`; the error names
/// `what` and the grid's extent when the point lies outside.
pub fn map_to_local(
    geometry: &GridGeometry,
    what: &'static str,
    x: f64,
    y: f64,
) -> Result<LocalPoint, SkiError> {
    let t = geometry.transform();
    let cx = (x - t.origin_x) / t.pixel_width;
    let cy = (t.origin_y - y) / t.pixel_height;
    let (w, h) = (geometry.width() as f64, geometry.height() as f64);
    if !(cx >= 0.0 && cy >= 0.0 && cx < w && cy < h) {
        let (x_min, x_max, y_min, y_max) = map_extent(geometry);
        return Err(SkiError::OutsideGrid {
            what,
            x,
            y,
            x_min,
            x_max,
            y_min,
            y_max,
        });
    }
    let cell = (cx.floor() as usize, cy.floor() as usize);
    Ok((
        (cx * geometry.cell_size_x(), cy * geometry.cell_size_y()),
        cell,
    ))
}

/// Read-only per-cell view of the terrain the skiers need: surface altitude, snow depth,
/// validity. Computed on demand (four layer reads per cell), so a step costs nothing per grid
/// cell.
#[derive(Clone, Copy)]
pub(crate) struct SnowView<'a> {
    pub terrain: &'a LayeredTerrain,
    pub mask: &'a NodataMask,
    pub width: usize,
    pub height: usize,
    pub dx: f64,
    pub dy: f64,
    pub min_depth: f32,
}

impl<'a> SnowView<'a> {
    pub fn new(terrain: &'a LayeredTerrain, min_depth: f64) -> Self {
        let g = terrain.geometry();
        Self {
            terrain,
            mask: terrain.mask(),
            width: g.width(),
            height: g.height(),
            dx: g.cell_size_x(),
            dy: g.cell_size_y(),
            min_depth: min_depth as f32,
        }
    }
    /// Surface altitude (bedrock + snow), m.
    #[inline(always)]
    pub fn surface(&self, i: usize) -> f32 {
        self.terrain.bedrock[i] + self.terrain.depth_at(i)
    }
    /// Whether the cell holds data and more snow than the skiing threshold.
    #[inline(always)]
    pub fn skiable(&self, i: usize) -> bool {
        self.mask.is_valid(i) && self.terrain.depth_at(i) > self.min_depth
    }
    /// The cell holding local position `(x, y)`, `None` outside the grid.
    #[inline(always)]
    pub fn cell_of(&self, x: f64, y: f64) -> Option<(usize, usize)> {
        let (c, r) = ((x / self.dx).floor(), (y / self.dy).floor());
        (c >= 0.0 && r >= 0.0 && c < self.width as f64 && r < self.height as f64)
            .then_some((c as usize, r as usize))
    }
    /// Centre of a cell, local metres.
    #[inline(always)]
    pub fn centre(&self, col: usize, row: usize) -> (f64, f64) {
        ((col as f64 + 0.5) * self.dx, (row as f64 + 0.5) * self.dy)
    }
    /// Surface gradient `(∂A/∂x, ∂A/∂y)` at a cell in the local frame (x east, y south):
    /// [`operators::gradient_south`], one-sided at borders and next to nodata.
    pub fn gradient(&self, col: usize, row: usize) -> (f64, f64) {
        let at = |dc: isize, dr: isize| {
            let (c, r) = (col as isize + dc, row as isize + dr);
            if c < 0 || r < 0 || c as usize >= self.width || r as usize >= self.height {
                return None;
            }
            let j = r as usize * self.width + c as usize;
            self.mask.is_valid(j).then(|| self.surface(j) as f64)
        };
        let a = self.surface(row * self.width + col) as f64;
        operators::gradient_south(a, at, self.dx, self.dy)
    }
    /// Surface slope angle of a cell, radians.
    pub fn slope(&self, col: usize, row: usize) -> f64 {
        let (gx, gy) = self.gradient(col, row);
        operators::slope_angle(gx, gy)
    }
}
