//! Height-span map: the scene rasterised from above into every depth layer (depth peeling on
//! the CPU), the discretisation of von Festenberg & Gumhold 2011, Section 5: "every point
//! p_ijk is a future snow site. It stores its snow capacity c_ijk in ]0..inf[, that is the free
//! space above itself, its height z_ijk and its indices {ijk}".
//!
//! For each column (cell centre) of a grid laid over the scene, every triangle whose footprint
//! covers the centre gives a crossing at the interpolated height; its facing is the sign of the
//! triangle's normal z. Upward-facing crossings are snow sites (with
//! [`HeightSpanOptions::two_sided`], every crossing is: for open meshes of unreliable winding).
//! A site's capacity is the height up to the next crossing above it, of any facing (the
//! underside of an object, or the next single-sided surface), infinite if there is none. Sites
//! whose capacity is below [`HeightSpanOptions::min_capacity_m`] are covered surfaces (a floor
//! under an object standing on it, coplanar duplicates) and are dropped, so every kept
//! capacity is > 0.
//!
//! Footprints use a top-left fill rule: a column exactly on an edge shared by two triangles
//! of the same facing crosses exactly one of them. Vertical triangles have no footprint and
//! give no crossing. Layout: columns row-major with row 0 the northern one (as
//! [`snowscape_terrain::Grid`]), sites of a column contiguous and sorted by height (CSR).

use crate::MeshError;
use crate::scene::Scene;
use rayon::prelude::*;

/// Most columns a map may have.
pub const MAX_COLUMNS: usize = 1 << 28;

/// How a height-span map is built.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightSpanOptions {
    /// Column spacing, metres (> 0).
    pub cell_size_m: f64,
    /// Horizontal extent `[x_min, y_min, x_max, y_max]` in scene metres; `None` = the scene's
    /// bounds.
    pub extent: Option<[f64; 4]>,
    /// Sites with less free space above are dropped (metres, >= 0).
    pub min_capacity_m: f32,
    /// Every crossing is a site, whatever its facing (for open meshes of unreliable winding).
    pub two_sided: bool,
}

impl Default for HeightSpanOptions {
    /// 10 cm columns over the scene's bounds, 1 mm minimum capacity, upward-facing sites only.
    fn default() -> Self {
        Self {
            cell_size_m: 0.1,
            extent: None,
            min_capacity_m: 1e-3,
            two_sided: false,
        }
    }
}

/// One snow site: a surface point of a column with free space above it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SnowSite {
    /// Height of the surface, metres.
    pub z: f32,
    /// Free space above, metres (> 0; `f32::INFINITY` under the open sky).
    pub capacity: f32,
    /// Object and triangle of the surface.
    pub object: u32,
    pub triangle: u32,
}

/// Every snow site of every column of a grid over the scene.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightSpanMap {
    /// Columns along x and along y.
    pub width: usize,
    pub height: usize,
    /// Column spacing, metres.
    pub cell_size: f64,
    /// Scene (x, y) of the south-west corner of the grid.
    pub origin: [f64; 2],
    /// `sites[offsets[c]..offsets[c + 1]]` are column `c`'s sites, lowest first.
    offsets: Vec<u32>,
    sites: Vec<SnowSite>,
    /// Sites dropped for a capacity below the minimum.
    pub covered_dropped: usize,
}

impl HeightSpanMap {
    /// Scene (x, y) of the centre of column `(col, row)` (row 0 north).
    pub fn column_centre(&self, col: usize, row: usize) -> [f64; 2] {
        [
            self.origin[0] + (col as f64 + 0.5) * self.cell_size,
            self.origin[1] + (self.height as f64 - row as f64 - 0.5) * self.cell_size,
        ]
    }

    /// The sites of column `(col, row)`, lowest first.
    pub fn column(&self, col: usize, row: usize) -> &[SnowSite] {
        let c = row * self.width + col;
        &self.sites[self.offsets[c] as usize..self.offsets[c + 1] as usize]
    }

    /// Every site, column after column.
    pub fn sites(&self) -> &[SnowSite] {
        &self.sites
    }

    /// Number of sites.
    pub fn site_count(&self) -> usize {
        self.sites.len()
    }

    /// The most sites any column holds (the number of depth layers).
    pub fn layer_count(&self) -> usize {
        self.offsets
            .windows(2)
            .map(|w| (w[1] - w[0]) as usize)
            .max()
            .unwrap_or(0)
    }

    /// Builds the map of `scene`.
    pub fn build(scene: &Scene, opts: &HeightSpanOptions) -> Result<Self, MeshError> {
        let bad =
            |name: &'static str, value: String, expected: &'static str| MeshError::InvalidOption {
                name,
                value,
                expected,
            };
        let cs = opts.cell_size_m;
        if !(cs.is_finite() && cs > 0.0) {
            return Err(bad(
                "height-span cell size",
                cs.to_string(),
                "a finite size > 0 m",
            ));
        }
        if opts.min_capacity_m.is_nan() || opts.min_capacity_m < 0.0 {
            return Err(bad(
                "minimum capacity",
                opts.min_capacity_m.to_string(),
                "a height >= 0 m",
            ));
        }
        let extent = match opts.extent {
            Some(e) => e,
            None => {
                let b = scene.bounds().ok_or_else(|| {
                    bad(
                        "height-span scene",
                        "empty".into(),
                        "a scene with triangles",
                    )
                })?;
                [b.min[0], b.min[1], b.max[0], b.max[1]].map(f64::from)
            }
        };
        let [x0, y0, x1, y1] = extent;
        if !(extent.iter().all(|v| v.is_finite()) && x1 >= x0 && y1 >= y0) {
            return Err(bad(
                "height-span extent",
                format!("{extent:?}"),
                "finite [x_min, y_min, x_max, y_max] with min <= max",
            ));
        }
        let width = (((x1 - x0) / cs).ceil() as usize).max(1);
        let height = (((y1 - y0) / cs).ceil() as usize).max(1);
        if width.checked_mul(height).is_none_or(|n| n > MAX_COLUMNS) {
            return Err(bad(
                "height-span resolution",
                format!("{width}x{height} columns at {cs} m"),
                "at most 2^28 columns (a coarser cell size)",
            ));
        }
        let mut map = HeightSpanMap {
            width,
            height,
            cell_size: cs,
            origin: [x0, y0],
            offsets: Vec::new(),
            sites: Vec::new(),
            covered_dropped: 0,
        };
        let footprints = Footprint::all(scene, &map);
        // Triangles binned by the rows their footprint may cover.
        let mut bins: Vec<Vec<u32>> = vec![Vec::new(); height];
        for (i, f) in footprints.iter().enumerate() {
            for bin in &mut bins[f.rows.0..f.rows.1] {
                bin.push(i as u32);
            }
        }
        let rows: Vec<(Vec<u32>, Vec<SnowSite>, usize)> = bins
            .par_iter()
            .enumerate()
            .map(|(row, bin)| map.row_sites(row, bin, &footprints, opts))
            .collect();
        map.offsets.reserve(width * height + 1);
        map.offsets.push(0);
        for (counts, sites, dropped) in rows {
            for c in counts {
                let last = *map.offsets.last().unwrap_or(&0);
                map.offsets.push(last + c);
            }
            map.sites.extend(sites);
            map.covered_dropped += dropped;
        }
        Ok(map)
    }

    /// The sites of one row: per-column counts, sites, and covered sites dropped.
    fn row_sites(
        &self,
        row: usize,
        bin: &[u32],
        footprints: &[Footprint],
        opts: &HeightSpanOptions,
    ) -> (Vec<u32>, Vec<SnowSite>, usize) {
        let mut crossings: Vec<Vec<Crossing>> = vec![Vec::new(); self.width];
        let y = self.column_centre(0, row)[1];
        for &i in bin {
            let f = &footprints[i as usize];
            for (col, column) in crossings
                .iter_mut()
                .enumerate()
                .take(f.cols.1)
                .skip(f.cols.0)
            {
                let x = self.column_centre(col, row)[0];
                if let Some(z) = f.height_at(x, y) {
                    column.push(Crossing {
                        z,
                        up: f.up,
                        object: f.object,
                        triangle: f.triangle,
                    });
                }
            }
        }
        let mut counts = Vec::with_capacity(self.width);
        let mut sites = Vec::new();
        let mut dropped = 0;
        for mut column in crossings {
            column.sort_by(|a, b| a.z.total_cmp(&b.z));
            let before = sites.len();
            for (k, c) in column.iter().enumerate() {
                if !(c.up || opts.two_sided) {
                    continue;
                }
                let capacity = column
                    .get(k + 1)
                    .map_or(f32::INFINITY, |above| (above.z - c.z) as f32);
                if capacity < opts.min_capacity_m || capacity <= 0.0 {
                    dropped += 1;
                    continue;
                }
                sites.push(SnowSite {
                    z: c.z as f32,
                    capacity,
                    object: c.object,
                    triangle: c.triangle,
                });
            }
            counts.push((sites.len() - before) as u32);
        }
        (counts, sites, dropped)
    }
}

#[derive(Debug, Clone, Copy)]
struct Crossing {
    z: f64,
    up: bool,
    object: u32,
    triangle: u32,
}

/// A triangle seen from above, counter-clockwise, with its column range.
struct Footprint {
    p: [[f64; 3]; 3],
    /// Twice the projected area (> 0).
    area2: f64,
    up: bool,
    object: u32,
    triangle: u32,
    /// Half-open column and row ranges its box covers.
    cols: (usize, usize),
    rows: (usize, usize),
}

impl Footprint {
    fn all(scene: &Scene, map: &HeightSpanMap) -> Vec<Footprint> {
        let mut out = Vec::with_capacity(scene.triangle_count());
        for (oi, o) in scene.objects.iter().enumerate() {
            for t in 0..o.triangles.len() {
                let mut p = o.corners(t).map(|q| q.map(f64::from));
                let mut area2 = edge(p[0], p[1], p[2]);
                if area2 == 0.0 || !area2.is_finite() {
                    continue; // vertical: no footprint
                }
                let up = area2 > 0.0;
                if !up {
                    p.swap(1, 2);
                    area2 = -area2;
                }
                let lo = |k: usize| p.iter().map(|q| q[k]).fold(f64::INFINITY, f64::min);
                let hi = |k: usize| p.iter().map(|q| q[k]).fold(f64::NEG_INFINITY, f64::max);
                // Columns whose centres x_c = x0 + (c + 0.5)·cs can fall in [lo, hi].
                let range = |lo: f64, hi: f64, n: usize| {
                    let a = ((lo / map.cell_size - 0.5).ceil().max(0.0) as usize).min(n);
                    let b = (((hi / map.cell_size - 0.5).floor() + 1.0).max(0.0) as usize).min(n);
                    (a, b.max(a))
                };
                let cols = range(lo(0) - map.origin[0], hi(0) - map.origin[0], map.width);
                // Rows count from the north edge.
                let top = map.origin[1] + map.height as f64 * map.cell_size;
                let rows = range(top - hi(1), top - lo(1), map.height);
                if cols.0 < cols.1 && rows.0 < rows.1 {
                    out.push(Footprint {
                        p,
                        area2,
                        up,
                        object: oi as u32,
                        triangle: t as u32,
                        cols,
                        rows,
                    });
                }
            }
        }
        out
    }

    /// Height of the triangle over `(x, y)`, if its footprint covers the point (top-left rule
    /// on edges).
    fn height_at(&self, x: f64, y: f64) -> Option<f64> {
        let q = [x, y, 0.0];
        let [a, b, c] = self.p;
        let w = [edge(b, c, q), edge(c, a, q), edge(a, b, q)];
        let owns =
            |w: f64, from: [f64; 3], to: [f64; 3]| w > 0.0 || (w == 0.0 && top_left(from, to));
        if owns(w[0], b, c) && owns(w[1], c, a) && owns(w[2], a, b) {
            Some((w[0] * a[2] + w[1] * b[2] + w[2] * c[2]) / self.area2)
        } else {
            None
        }
    }
}

/// z of (b - a) x (q - a): > 0 when q is left of a -> b seen from above.
fn edge(a: [f64; 3], b: [f64; 3], q: [f64; 3]) -> f64 {
    (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0])
}

/// Tie-break for points exactly on an edge: antisymmetric in the edge's direction, so of two
/// counter-clockwise triangles sharing an edge (which run it in opposite directions) exactly
/// one owns it.
fn top_left(from: [f64; 3], to: [f64; 3]) -> bool {
    let (dx, dy) = (to[0] - from[0], to[1] - from[1]);
    dy > 0.0 || (dy == 0.0 && dx < 0.0)
}
