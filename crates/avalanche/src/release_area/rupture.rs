//! A rupture at a point: the release zone a slab grows into from an unstable cell.

use super::*;
use snowscape_terrain::operators;

/// Parameters of the rupture at a point (module docs, *Rupture at a point*).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
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
        if !(self.reach_per_unstable_m.is_finite()
            && (0.0..=10_000.0).contains(&self.reach_per_unstable_m))
        {
            return bad(
                "reach_per_unstable_m",
                self.reach_per_unstable_m,
                "in [0, 10000] m per m",
            );
        }
        if !(self.min_unstable_m.is_finite()
            && self.min_unstable_m > 0.0
            && self.min_unstable_m <= 100.0)
        {
            return bad("min_unstable_m", self.min_unstable_m, "in (0, 100] m");
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
    let slab = Slab::new(terrain, params);
    let (col, row, fc, fr) = slab.rupture_cell(x, y)?;
    let i0 = row * slab.w + col;
    let u0 = slab.unstable[i0] as f64;
    let reach = params.reach_per_unstable_m * u0;
    // Point in local metres (east, south of the north-west corner).
    let (px, py) = ((fc + 0.5) * slab.dx, (fr + 0.5) * slab.dy);
    let (mut cells, mut zone) = slab.rupture_zone(i0, (px, py), reach);
    let zone_cells = zone.len();
    let downslope_cells = slab.downslope_reach(&mut cells, &mut zone);
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

/// The snow a rupture runs through: the terrain, its unstable layer and the grid's measures.
struct Slab<'a> {
    terrain: &'a LayeredTerrain,
    g: &'a GridGeometry,
    mask: &'a NodataMask,
    unstable: &'a [f32],
    params: &'a RuptureParams,
    w: usize,
    h: usize,
    dx: f64,
    dy: f64,
}

impl<'a> Slab<'a> {
    fn new(terrain: &'a LayeredTerrain, params: &'a RuptureParams) -> Self {
        let g = terrain.geometry();
        Slab {
            terrain,
            g,
            mask: terrain.mask(),
            unstable: terrain.layer(SnowLayer::Unstable),
            params,
            w: g.width(),
            h: g.height(),
            dx: g.cell_size_x(),
            dy: g.cell_size_y(),
        }
    }

    /// The rupture cell of map point `(x, y)` (col, row) with its fractional cell position
    /// (fc, fr): on the DEM, on a valid cell, with unstable snow of at least the minimum.
    fn rupture_cell(&self, x: f64, y: f64) -> Result<(usize, usize, f64, f64), ReleaseAreaError> {
        let (g, w, h) = (self.g, self.w, self.h);
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
        if !self.mask.is_valid(i0) {
            return Err(ReleaseAreaError::PointOnNodata { x, y, col, row });
        }
        let u0 = self.unstable[i0] as f64;
        if u0.is_nan() || u0 < self.params.min_unstable_m {
            return Err(ReleaseAreaError::NoUnstableSnow {
                x,
                y,
                col,
                row,
                unstable_m: u0,
                min_unstable_m: self.params.min_unstable_m,
            });
        }
        Ok((col, row, fc, fr))
    }

    /// Whether cell `i` is valid and holds unstable snow.
    fn has_unstable(&self, i: usize) -> bool {
        self.mask.is_valid(i) && self.unstable[i] as f64 >= self.params.min_unstable_m
    }

    /// The snow surface of a cell (the sums of `LayeredTerrain::surface`).
    fn surface(&self, i: usize) -> f64 {
        (self.terrain.bedrock[i] + self.terrain.depth_at(i)) as f64
    }

    /// Step 3, the rupture zone: a flood fill from cell `i0` through unstable snow within
    /// `reach` m of the point `p` (local metres). Returns the flags of the cells taken and
    /// the cells in the order taken.
    fn rupture_zone(&self, i0: usize, p: (f64, f64), reach: f64) -> (Vec<bool>, Vec<usize>) {
        let (g, w) = (self.g, self.w);
        let (px, py) = p;
        let mut cells = vec![false; w * self.h];
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
                    if cells[j] || !self.has_unstable(j) {
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
        (cells, zone)
    }

    /// The snow surface's gradient at cell (c, r) (x east, y south):
    /// [`operators::gradient_south`], one-sided next to nodata.
    fn gradient(&self, c: usize, r: usize) -> [f64; 2] {
        let at = |dc: isize, dr: isize| {
            self.g
                .neighbour(c, r, dc, dr)
                .filter(|&j| self.mask.is_valid(j))
                .map(|j| self.surface(j))
        };
        let (gx, gy) =
            operators::gradient_south(self.surface(r * self.w + c), at, self.dx, self.dy);
        [gx, gy]
    }

    /// The bilinear gradient at local position (x, y) (metres); the nearest cell's when a
    /// corner is nodata.
    fn gradient_at(&self, x: f64, y: f64) -> [f64; 2] {
        let (w, h, dx, dy) = (self.w, self.h, self.dx, self.dy);
        let (fcx, fry) = (x / dx - 0.5, y / dy - 0.5);
        let c0 = fcx.floor().clamp(0.0, (w - 1) as f64) as usize;
        let r0 = fry.floor().clamp(0.0, (h - 1) as f64) as usize;
        let (c1, r1) = ((c0 + 1).min(w - 1), (r0 + 1).min(h - 1));
        let (tx, ty) = (
            (fcx - c0 as f64).clamp(0.0, 1.0),
            (fry - r0 as f64).clamp(0.0, 1.0),
        );
        let corners = [(c0, r0), (c1, r0), (c0, r1), (c1, r1)];
        if corners.iter().any(|&(c, r)| !self.mask.is_valid(r * w + c)) {
            let c = (x / dx).floor().clamp(0.0, (w - 1) as f64) as usize;
            let r = (y / dy).floor().clamp(0.0, (h - 1) as f64) as usize;
            return self.gradient(c, r);
        }
        let [g00, g10, g01, g11] = corners.map(|(c, r)| self.gradient(c, r));
        let lerp = |k: usize| {
            (1.0 - ty) * ((1.0 - tx) * g00[k] + tx * g10[k])
                + ty * ((1.0 - tx) * g01[k] + tx * g11[k])
        };
        [lerp(0), lerp(1)]
    }

    /// Step 4, the downslope reach: a fall line from every cell of the rupture zone (the
    /// first entries of `zone`), through unstable snow that does not rise and is at least the
    /// minimum slope; the cells it adds are flagged in `cells` and appended to `zone`. Returns
    /// their number.
    fn downslope_reach(&self, cells: &mut [bool], zone: &mut Vec<usize>) -> usize {
        let (w, h, dx, dy) = (self.w, self.h, self.dx, self.dy);
        let tan_min = self.params.min_slope_deg.to_radians().tan();
        let step_len = 0.5 * dx.min(dy);
        let max_steps = 4 * (w + h) * ((dx.max(dy) / dx.min(dy)).ceil() as usize);
        let mut downslope_cells = 0;
        let zone_cells = zone.len();
        for z in 0..zone_cells {
            let start = zone[z];
            let (sc, sr) = (start % w, start / w);
            let (mut x, mut y) = self.g.local_metres(sc, sr);
            let mut last = start;
            for _ in 0..max_steps {
                let [gx, gy] = self.gradient_at(x, y);
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
                if !self.has_unstable(i) || self.surface(i) > self.surface(last) {
                    break;
                }
                let [cgx, cgy] = self.gradient(c, r);
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
        downslope_cells
    }
}
