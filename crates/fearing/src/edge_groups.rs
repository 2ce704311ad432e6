//! Neighbours and edge groups of the launch sites (Fearing 2000, Section 3.3).
//!
//! Two leaf cells are neighbours when an edge of one and an edge of the other are collinear and
//! overlap (found geometrically, so mesh seams with duplicated vertices and the T-junctions of
//! adaptive refinement connect like shared edges). The edge groups are the connected components
//! of that graph: pieces of upward-facing surface bounded by XY silhouette edges (where the
//! surface turns away from the sky), open mesh edges and holes; neighbour links never cross
//! them. A cell edge that no neighbour covers is a group border, where snow can leave the
//! group over an edge (Section 4.3) and where the snow surface gets its closing wall (3.7).
//! Corners of neighbours lying inside a cell's edge (T-junctions) are recorded so the snow
//! surface stays watertight.

use crate::launch_sites::LaunchSites;
use rayon::prelude::*;
use std::collections::HashMap;

/// A neighbour of a site.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Neighbour {
    /// Index into [`Topology::leaves`].
    pub site: u32,
    /// Horizontal distance between the two sites, metres.
    pub distance: f64,
}

/// A border edge of a site: its cell edge `edge` (corners `edge`, `edge + 1`), no neighbour there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BorderEdge {
    pub edge: u8,
    pub a: [f64; 3],
    pub b: [f64; 3],
}

/// Site adjacency, edge groups and borders of one state of the launch sites.
#[derive(Debug, Clone, Default)]
pub struct Topology {
    /// Cell ids of the sites, ascending.
    pub leaves: Vec<u32>,
    /// Neighbours of each site (sorted by site).
    pub neighbours: Vec<Vec<Neighbour>>,
    /// Border edges of each site.
    pub borders: Vec<Vec<BorderEdge>>,
    /// Corners of neighbours inside each edge of each site: (edge, point).
    pub t_vertices: Vec<Vec<(u8, [f64; 3])>>,
    /// Edge group of each site, numbered from 0 in order of their first site.
    pub group: Vec<u32>,
    pub group_count: usize,
}

/// Edge pairs closer than this share a line, metres (relative to the scene size).
fn tolerance(sites: &LaunchSites) -> f64 {
    (sites.spacing * 1e-4).max(1e-7)
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Overlap length of segment (q0, q1) with segment (p0, p1) when collinear within `tol`, and the
/// q endpoints strictly inside (p0, p1).
fn overlap(
    p0: [f64; 3],
    p1: [f64; 3],
    q0: [f64; 3],
    q1: [f64; 3],
    tol: f64,
) -> Option<(f64, [bool; 2])> {
    let d = sub(p1, p0);
    let len = dot(d, d).sqrt();
    if len <= tol {
        return None;
    }
    let u = d.map(|c| c / len);
    let off = |q: [f64; 3]| {
        let w = sub(q, p0);
        let s = dot(w, u);
        let perp = sub(w, u.map(|c| c * s));
        (s, dot(perp, perp).sqrt())
    };
    let ((s0, e0), (s1, e1)) = (off(q0), off(q1));
    if e0 > tol || e1 > tol {
        return None;
    }
    let o = s0.max(s1).min(len) - s0.min(s1).max(0.0);
    (o > tol).then_some((o, [s0 > tol && s0 < len - tol, s1 > tol && s1 < len - tol]))
}

impl Topology {
    /// The adjacency of the current leaves of `sites`.
    pub fn build(sites: &LaunchSites) -> Self {
        let leaves = sites.leaves();
        let n = leaves.len();
        let tol = tolerance(sites);
        let cell = |i: usize| &sites.cells[leaves[i] as usize];
        // Hash grid over the cells' boxes, bucket size = initial spacing.
        let h = sites.spacing.max(tol * 10.0);
        let key = |p: [f64; 3]| p.map(|c| (c / h).floor() as i64);
        let boxes: Vec<([i64; 3], [i64; 3])> = (0..n)
            .map(|i| {
                let c = cell(i).corners;
                let lo = [0, 1, 2].map(|k| c[0][k].min(c[1][k]).min(c[2][k]) - tol);
                let hi = [0, 1, 2].map(|k| c[0][k].max(c[1][k]).max(c[2][k]) + tol);
                (key(lo), key(hi))
            })
            .collect();
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (i, (lo, hi)) in boxes.iter().enumerate() {
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        grid.entry([x, y, z]).or_default().push(i as u32);
                    }
                }
            }
        }
        // Pairs (a < b) with their shared lengths per edge and T-vertices, per a in parallel.
        type Pair = (
            u32,
            u32,
            [f64; 3],
            [f64; 3],
            Vec<(u8, [f64; 3])>,
            Vec<(u8, [f64; 3])>,
        );
        let pairs: Vec<Vec<Pair>> = (0..n)
            .into_par_iter()
            .with_min_len(64)
            .map(|a| {
                let (lo, hi) = boxes[a];
                let mut cand = Vec::new();
                for x in lo[0]..=hi[0] {
                    for y in lo[1]..=hi[1] {
                        for z in lo[2]..=hi[2] {
                            if let Some(v) = grid.get(&[x, y, z]) {
                                cand.extend(v.iter().copied().filter(|&b| b as usize > a));
                            }
                        }
                    }
                }
                cand.sort_unstable();
                cand.dedup();
                let ca = cell(a).corners;
                let mut out = Vec::new();
                for b in cand {
                    let cb = cell(b as usize).corners;
                    let (mut la, mut lb) = ([0.0; 3], [0.0; 3]);
                    let (mut ta, mut tb) = (Vec::new(), Vec::new());
                    let mut any = false;
                    for ea in 0..3 {
                        let (p0, p1) = (ca[ea], ca[(ea + 1) % 3]);
                        for eb in 0..3 {
                            let (q0, q1) = (cb[eb], cb[(eb + 1) % 3]);
                            if let Some((o, inside)) = overlap(p0, p1, q0, q1, tol) {
                                any = true;
                                la[ea] += o;
                                lb[eb] += o;
                                for (k, q) in [q0, q1].into_iter().enumerate() {
                                    if inside[k] {
                                        ta.push((ea as u8, q));
                                    }
                                }
                                if let Some((_, inside_b)) = overlap(q0, q1, p0, p1, tol) {
                                    for (k, p) in [p0, p1].into_iter().enumerate() {
                                        if inside_b[k] {
                                            tb.push((eb as u8, p));
                                        }
                                    }
                                }
                            }
                        }
                    }
                    if any {
                        out.push((a as u32, b, la, lb, ta, tb));
                    }
                }
                out
            })
            .collect();
        let mut covered = vec![[0.0f64; 3]; n];
        let mut neighbours = vec![Vec::new(); n];
        let mut t_vertices = vec![Vec::new(); n];
        let mut uf = UnionFind::new(n);
        for (a, b, la, lb, ta, tb) in pairs.into_iter().flatten() {
            let (a, b) = (a as usize, b as usize);
            let (pa, pb) = (cell(a).centroid(), cell(b).centroid());
            let distance = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt();
            neighbours[a].push(Neighbour {
                site: b as u32,
                distance,
            });
            neighbours[b].push(Neighbour {
                site: a as u32,
                distance,
            });
            for k in 0..3 {
                covered[a][k] += la[k];
                covered[b][k] += lb[k];
            }
            t_vertices[a].extend(ta);
            t_vertices[b].extend(tb);
            uf.union(a, b);
        }
        for v in &mut neighbours {
            v.sort_by_key(|nb: &Neighbour| nb.site);
        }
        let borders = (0..n)
            .map(|i| {
                let c = cell(i).corners;
                (0..3)
                    .filter_map(|e| {
                        let (a, b) = (c[e], c[(e + 1) % 3]);
                        let len = dot(sub(b, a), sub(b, a)).sqrt();
                        (covered[i][e] < 0.5 * len).then_some(BorderEdge {
                            edge: e as u8,
                            a,
                            b,
                        })
                    })
                    .collect()
            })
            .collect();
        let mut group = vec![u32::MAX; n];
        let mut root_group = HashMap::new();
        for (i, g) in group.iter_mut().enumerate() {
            let r = uf.find(i);
            let next = root_group.len() as u32;
            *g = *root_group.entry(r).or_insert(next);
        }
        Self {
            leaves,
            neighbours,
            borders,
            t_vertices,
            group,
            group_count: root_group.len(),
        }
    }

    /// Site index of each cell id (`u32::MAX` for cells that are not sites).
    pub fn site_of_cell(&self, cells: usize) -> Vec<u32> {
        let mut s = vec![u32::MAX; cells];
        for (i, &c) in self.leaves.iter().enumerate() {
            s[c as usize] = i as u32;
        }
        s
    }
}

struct UnionFind(Vec<usize>);

impl UnionFind {
    fn new(n: usize) -> Self {
        Self((0..n).collect())
    }
    fn find(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }
    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.0[ra.max(rb)] = ra.min(rb);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_mesh::{Scene, SceneObject};

    fn square(x0: f32, z: f32, split_vertices: bool) -> SceneObject {
        let mut positions = vec![[x0, 0., z], [x0 + 1., 0., z], [x0 + 1., 1., z], [x0, 1., z]];
        let triangles = if split_vertices {
            positions.extend([[x0, 0., z], [x0 + 1., 1., z]]);
            vec![[0, 1, 2], [4, 5, 3]]
        } else {
            vec![[0, 1, 2], [0, 2, 3]]
        };
        SceneObject {
            frame: Default::default(),
            name: "sq".into(),
            positions,
            normals: None,
            triangles,
            uvs: None,
        }
    }

    #[test]
    fn seams_join_groups_split_and_borders_ring_the_outside() {
        // A square with a seam (duplicated vertices) and a separate raised square.
        let scene = Scene {
            objects: vec![square(0.0, 0.0, true), square(3.0, 1.0, false)],
            ..Default::default()
        };
        let mut sites = LaunchSites::build(&scene, 0.05, Some(0.5), 1);
        let t = Topology::build(&sites);
        assert_eq!(t.group_count, 2);
        // Each square is 2 triangles of 4 cells (k = ceil(1.41/0.5) = 3 → 9 cells each).
        assert_eq!(t.leaves.len(), 36);
        // Border length of the first square is its perimeter, 4 m.
        let border_len: f64 = (0..t.leaves.len())
            .filter(|&i| t.group[i] == 0)
            .flat_map(|i| t.borders[i].iter())
            .map(|e| dot(sub(e.b, e.a), sub(e.b, e.a)).sqrt())
            .sum();
        assert!((border_len - 4.0).abs() < 1e-9, "{border_len}");
        // Refining one cell keeps it connected and adds T-vertices to its neighbours.
        sites.split(t.leaves[4]);
        let t2 = Topology::build(&sites);
        assert_eq!(t2.group_count, 2);
        assert!(t2.t_vertices.iter().any(|v| !v.is_empty()));
        let border2: f64 = (0..t2.leaves.len())
            .filter(|&i| t2.group[i] == 0)
            .flat_map(|i| t2.borders[i].iter())
            .map(|e| dot(sub(e.b, e.a), sub(e.b, e.a)).sqrt())
            .sum();
        assert!((border2 - 4.0).abs() < 1e-9, "{border2}");
    }
}
