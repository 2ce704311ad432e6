//! Launch sites (Fearing 2000, Section 3.3): every upward-facing triangle of the scene is cut
//! into sub-triangles ("cells"), each the area one launch site is responsible for, with the site
//! at the cell's centroid.
//!
//! The paper uses a constrained Voronoi partition clipped to each triangle; any area-exact,
//! non-overlapping partition serves ("there are numerous other valid meshing possibilities"), and
//! this one is a barycentric grid of k² congruent sub-triangles per triangle (k from the site
//! spacing) refined by midpoint subdivision: a cell splits into four children of a quarter of
//! its area (adaptive refinement, Section 3.1) and four sibling leaves merge back into their
//! parent. The cells of a triangle always tile it exactly, so snow mass is allocated to
//! non-overlapping areas whatever the refinement. Cells live in an arena (ids never reused) and
//! the leaves are the current launch sites; their statistics (flakes shot, sky hits, sky
//! arrivals, snow volume) live with them.

use snowscape_mesh::Scene;

/// "No cell" in parent links.
pub const NONE: u32 = u32::MAX;

/// One cell of the partition (a launch site while it is a leaf).
#[derive(Debug, Clone)]
pub struct Cell {
    /// Corners, scene metres, counter-clockwise seen from above.
    pub corners: [[f64; 3]; 3],
    pub object: u32,
    pub triangle: u32,
    /// Levels of refinement below the initial cell.
    pub level: u8,
    pub parent: u32,
    /// First of the four children (consecutive ids), `NONE` for a leaf.
    pub children: u32,
    /// Whether this cell is a current launch site.
    pub alive: bool,
    /// Flakes shot, sky hits (flakes that reached the sky), in the pass of `pass`.
    pub shots: f64,
    pub sky_hits: f64,
    /// Sky arrivals: (bucket, flake weight) summed per bucket, bilinear splats.
    pub arrivals: Vec<(u32, f32)>,
    /// Accumulation pass the statistics belong to.
    pub pass: u32,
    /// Batches shot in the current pass.
    pub batches: u32,
    /// Snow volume on the site, m³ (its elevation is volume / projected area, Section 3.7).
    pub volume: f64,
}

impl Cell {
    fn new(corners: [[f64; 3]; 3], object: u32, triangle: u32, level: u8, parent: u32) -> Self {
        Self {
            corners,
            object,
            triangle,
            level,
            parent,
            children: NONE,
            alive: true,
            shots: 0.0,
            sky_hits: 0.0,
            arrivals: Vec::new(),
            pass: 0,
            batches: 0,
            volume: 0.0,
        }
    }

    /// The launch site: the cell's centroid on the base surface.
    pub fn centroid(&self) -> [f64; 3] {
        let [a, b, c] = self.corners;
        [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0)
    }

    /// Horizontal (projected) area, m².
    pub fn area_xy(&self) -> f64 {
        let [a, b, c] = self.corners;
        0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs()
    }

    /// Longest edge, metres.
    pub fn size(&self) -> f64 {
        let d = |p: [f64; 3], q: [f64; 3]| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        };
        let [a, b, c] = self.corners;
        d(a, b).max(d(b, c)).max(d(c, a))
    }

    /// Snow depth (vertical), metres.
    pub fn depth(&self) -> f64 {
        let a = self.area_xy();
        if a > 0.0 { self.volume / a } else { 0.0 }
    }

    /// Share of flakes that reached the sky so far (1 before any shot).
    pub fn sky_fraction(&self) -> f64 {
        if self.shots > 0.0 {
            self.sky_hits / self.shots
        } else {
            1.0
        }
    }
}

/// The partition of the scene's upward-facing surface into launch-site cells.
#[derive(Debug, Clone)]
pub struct LaunchSites {
    pub cells: Vec<Cell>,
    /// Initial site spacing, metres.
    pub spacing: f64,
    /// Upward-facing triangles and their total projected area, m².
    pub upward_triangles: usize,
    pub upward_area: f64,
}

/// Unit normal z of triangle corners (0 for a degenerate one).
pub fn normal_z(c: &[[f64; 3]; 3]) -> f64 {
    let e1 = [c[1][0] - c[0][0], c[1][1] - c[0][1], c[1][2] - c[0][2]];
    let e2 = [c[2][0] - c[0][0], c[2][1] - c[0][1], c[2][2] - c[0][2]];
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if l > 0.0 && l.is_finite() {
        n[2] / l
    } else {
        0.0
    }
}

impl LaunchSites {
    /// Cells for every triangle with normal z above `min_normal_z`: spacing `spacing` if given,
    /// else chosen so that about `target` cells cover the upward area (each triangle gets at
    /// least one cell; a triangle of area A is cut into k² cells, k = ceil(2 sqrt(A) / spacing),
    /// at most 256²).
    pub fn build(scene: &Scene, min_normal_z: f64, spacing: Option<f64>, target: usize) -> Self {
        let mut up = Vec::new();
        let (mut area, mut area3_total) = (0.0, 0.0);
        for (oi, o) in scene.objects.iter().enumerate() {
            for t in 0..o.triangles.len() {
                let c = o.corners(t).map(|p| p.map(f64::from));
                if !c.iter().flatten().all(|v| v.is_finite()) {
                    continue;
                }
                if normal_z(&c) > min_normal_z {
                    let a = 0.5
                        * ((c[1][0] - c[0][0]) * (c[2][1] - c[0][1])
                            - (c[1][1] - c[0][1]) * (c[2][0] - c[0][0]))
                            .abs();
                    area += a;
                    area3_total += o.triangle_area(t) as f64;
                    up.push((oi as u32, t as u32, c));
                }
            }
        }
        let spacing =
            spacing.unwrap_or_else(|| (4.0 * area3_total / target.max(1) as f64).sqrt().max(1e-6));
        let mut cells = Vec::new();
        for &(o, t, c) in &up {
            // k² cells of about spacing²/4 each (by 3D area, so slivers are not over-cut).
            let area3 = 0.5 * {
                let e1 = [0, 1, 2].map(|d| c[1][d] - c[0][d]);
                let e2 = [0, 1, 2].map(|d| c[2][d] - c[0][d]);
                let n = [
                    e1[1] * e2[2] - e1[2] * e2[1],
                    e1[2] * e2[0] - e1[0] * e2[2],
                    e1[0] * e2[1] - e1[1] * e2[0],
                ];
                (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
            };
            let k = ((2.0 * area3.sqrt() / spacing).ceil() as usize).clamp(1, 256);
            subdivide(&c, k, |corners| {
                cells.push(Cell::new(corners, o, t, 0, NONE))
            });
        }
        Self {
            cells,
            spacing,
            upward_triangles: up.len(),
            upward_area: area,
        }
    }

    /// Ids of the current launch sites, ascending.
    pub fn leaves(&self) -> Vec<u32> {
        (0..self.cells.len() as u32)
            .filter(|&i| self.cells[i as usize].alive)
            .collect()
    }

    /// Splits leaf `id` into four children (its volume shared by area); returns the first child.
    pub fn split(&mut self, id: u32) -> u32 {
        let cell = &self.cells[id as usize];
        debug_assert!(cell.alive && cell.children == NONE);
        let [a, b, c] = cell.corners;
        let mid = |p: [f64; 3], q: [f64; 3]| [0, 1, 2].map(|k| 0.5 * (p[k] + q[k]));
        let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
        let (o, t, level, volume) = (cell.object, cell.triangle, cell.level + 1, cell.volume);
        let first = self.cells.len() as u32;
        for corners in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
            let mut child = Cell::new(corners, o, t, level, id);
            child.volume = 0.25 * volume;
            self.cells.push(child);
        }
        let cell = &mut self.cells[id as usize];
        cell.alive = false;
        cell.children = first;
        cell.volume = 0.0;
        first
    }

    /// Whether `id`'s four children are all leaves (so they can merge back).
    pub fn can_merge(&self, id: u32) -> bool {
        let c = &self.cells[id as usize];
        c.children != NONE
            && (0..4).all(|k| {
                self.cells[(c.children + k) as usize].alive
                    && self.cells[(c.children + k) as usize].children == NONE
            })
    }

    /// Merges the four leaf children of `id` back into it, keeping their statistics: the
    /// parent's sky record is the area-weighted union of theirs (Section 3.1, merging sites with
    /// identical sky occlusion).
    pub fn merge(&mut self, id: u32) {
        debug_assert!(self.can_merge(id));
        let first = self.cells[id as usize].children;
        let (mut shots, mut hits, mut volume, mut batches) = (0.0, 0.0, 0.0, u32::MAX);
        let mut arrivals: Vec<(u32, f32)> = Vec::new();
        let pass = self.cells[first as usize].pass;
        for k in 0..4 {
            let ch = &mut self.cells[(first + k) as usize];
            ch.alive = false;
            volume += ch.volume;
            ch.volume = 0.0;
            shots += ch.shots;
            batches = batches.min(ch.batches);
            // Each child stands for a quarter of the parent: its flakes keep their share.
            let s = if ch.shots > 0.0 { 0.25 / ch.shots } else { 0.0 };
            hits += 0.25 * ch.sky_fraction();
            for &(b, w) in &ch.arrivals {
                arrivals.push((b, w * s as f32));
            }
        }
        arrivals.sort_by_key(|a| a.0);
        let mut merged: Vec<(u32, f32)> = Vec::with_capacity(arrivals.len());
        for (b, w) in arrivals {
            match merged.last_mut() {
                Some(last) if last.0 == b => last.1 += w * shots as f32,
                _ => merged.push((b, w * shots as f32)),
            }
        }
        let p = &mut self.cells[id as usize];
        p.alive = true;
        p.children = NONE;
        p.shots = shots;
        p.sky_hits = hits * shots;
        p.arrivals = merged;
        p.pass = pass;
        p.batches = batches;
        p.volume = volume;
    }
}

/// Calls `emit` with the k² sub-triangles of a barycentric grid on `c` (same winding).
fn subdivide(c: &[[f64; 3]; 3], k: usize, mut emit: impl FnMut([[f64; 3]; 3])) {
    let kf = k as f64;
    let p = |i: usize, j: usize| {
        let (u, v) = (i as f64 / kf, j as f64 / kf);
        [0, 1, 2].map(|d| c[0][d] + u * (c[1][d] - c[0][d]) + v * (c[2][d] - c[0][d]))
    };
    for j in 0..k {
        for i in 0..k - j {
            emit([p(i, j), p(i + 1, j), p(i, j + 1)]);
            if i + j + 2 <= k {
                emit([p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_mesh::SceneObject;

    #[test]
    fn cells_tile_their_triangles_through_splits_and_merges() {
        let scene = Scene {
            objects: vec![SceneObject {
                frame: Default::default(),
                name: "t".into(),
                positions: vec![[0., 0., 0.], [3., 0., 0.5], [0., 2., 0.], [0., 0., 5.]],
                normals: None,
                // One upward triangle and one vertical one (no sites).
                triangles: vec![[0, 1, 2], [0, 1, 3]],
                uvs: None,
            }],
            ..Default::default()
        };
        let mut s = LaunchSites::build(&scene, 0.05, Some(0.5), 1);
        assert_eq!(s.upward_triangles, 1);
        let total = |s: &LaunchSites| {
            s.leaves()
                .iter()
                .map(|&i| s.cells[i as usize].area_xy())
                .sum::<f64>()
        };
        assert!((total(&s) - 3.0).abs() < 1e-9, "{}", total(&s));
        let n0 = s.leaves().len();
        assert_eq!(n0, 7 * 7, "k = ceil(2 sqrt(3.04) / 0.5)");
        s.cells[0].volume = 2.0;
        let first = s.split(0);
        assert_eq!(s.leaves().len(), n0 + 3);
        assert!((total(&s) - 3.0).abs() < 1e-9);
        assert!((s.cells[first as usize].volume - 0.5).abs() < 1e-12);
        assert!(s.can_merge(0));
        s.merge(0);
        assert_eq!(s.leaves().len(), n0);
        assert!((s.cells[0].volume - 2.0).abs() < 1e-12);
    }
}
