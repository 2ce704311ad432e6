//! Surface construction (Fearing 2000, Sections 3.7 and 5).
//!
//! Each launch site is elevated by its snow volume over its projected area. The top snow
//! surface is a fan per site from the elevated site to the corners of its cell (and the
//! T-junction corners of finer neighbours on its edges, so the surface is watertight), with the
//! corner vertices "set to the minimum of adjacent neighbours" (3.7). Vertical closing walls
//! drop from the border corners to the base along every edge-group border. Corners are welded
//! per edge group, so snow of different groups never shares a vertex.
//!
//! Section 5's implicit-function smoothing is optional in the paper; two simpler documented
//! methods stand in for it. [`SnowSurface::smooth`] smooths the finished surface: Taubin's
//! λ|μ passes (λ = 0.5, μ = -0.53; Taubin 1995, "A signal processing approach to fair surface
//! design") on the snow depth of every top-surface vertex over its top-surface neighbours, so
//! the per-site fans (a cone at each site centre, its corners at the minimum of the neighbours,
//! 3.7) that speckle the surface blend, without the shrinkage of plain Laplacian passes (the
//! snow volume under the surface changes by well under 1 %: see the tests). Each depth stays
//! within the range of its vertex's original neighbourhood (no overshoot above the deepest site),
//! wall bottoms stay on the base, and only depth (z) moves. [`smooth_volumes`] is the other: a
//! few Jacobi steps of mass-conserving diffusion of the snow depth between neighbouring sites of
//! a group (each pair exchanges a share of its depth
//! difference times the smaller area, so the total volume is unchanged to rounding).

use crate::edge_groups::Topology;
use crate::launch_sites::LaunchSites;
use crate::tracer::Tag;
use snowscape_mesh::{MeshFrame, SnowObject, TriMesh};
use std::collections::HashMap;

/// The snow surface of all edge groups: the mesh (scene metres, named "snow") with each
/// vertex's depth and each triangle's tag beside it.
#[derive(Debug, Clone, Default)]
pub struct SnowSurface {
    /// Positions (the snow's top, or a wall's base at depth 0) and triangles.
    pub mesh: TriMesh,
    /// Snow depth at each vertex, metres.
    pub depth: Vec<f32>,
    /// What each triangle is: a site's top or a group's wall.
    pub tags: Vec<Tag>,
}

impl SnowSurface {
    /// The surface of the current snow on `sites` (sites thinner than `min_depth` with thin
    /// corners give no triangle).
    #[allow(clippy::needless_range_loop)]
    pub fn build(sites: &LaunchSites, topo: &Topology, min_depth: f64) -> Self {
        let tol = (sites.spacing * 1e-4).max(1e-7);
        let q = |p: [f64; 3]| p.map(|c| (c / tol).round() as i64);
        let mut key_vertex: HashMap<(u32, [i64; 3]), u32> = HashMap::new();
        let mut base: Vec<[f64; 3]> = Vec::new();
        let mut vdepth: Vec<f64> = Vec::new();
        let n = topo.leaves.len();
        let mut polys: Vec<Vec<u32>> = Vec::with_capacity(n);
        let cell = |i: usize| &sites.cells[topo.leaves[i] as usize];
        for i in 0..n {
            let c = cell(i);
            let d = c.depth();
            let mut poly = Vec::with_capacity(3 + topo.t_vertices[i].len());
            for e in 0..3 {
                let (a, b) = (c.corners[e], c.corners[(e + 1) % 3]);
                let mut pts: Vec<(f64, [f64; 3])> = vec![(0.0, a)];
                let len2: f64 = (0..3).map(|k| (b[k] - a[k]).powi(2)).sum();
                for &(te, p) in &topo.t_vertices[i] {
                    if te as usize == e {
                        let s = (0..3).map(|k| (p[k] - a[k]) * (b[k] - a[k])).sum::<f64>()
                            / len2.max(1e-300);
                        pts.push((s, p));
                    }
                }
                pts.sort_by(|x, y| x.0.total_cmp(&y.0));
                for (_, p) in pts {
                    let k = (topo.group[i], q(p));
                    let v = *key_vertex.entry(k).or_insert_with(|| {
                        base.push(p);
                        vdepth.push(f64::INFINITY);
                        (base.len() - 1) as u32
                    });
                    vdepth[v as usize] = vdepth[v as usize].min(d);
                    if poly.last() != Some(&v) && poly.first() != Some(&v) {
                        poly.push(v);
                    }
                }
            }
            polys.push(poly);
        }
        let mut s = SnowSurface {
            mesh: TriMesh {
                name: "snow".into(),
                ..TriMesh::default()
            },
            ..SnowSurface::default()
        };
        let lift = |p: [f64; 3], d: f64| [p[0] as f32, p[1] as f32, (p[2] + d) as f32];
        for (p, &d) in base.iter().zip(&vdepth) {
            s.mesh.positions.push(lift(*p, d));
            s.depth.push(d as f32);
        }
        // Base copies of border corners for the walls, created on demand.
        let mut base_copy: HashMap<u32, u32> = HashMap::new();
        for i in 0..n {
            let c = cell(i);
            let d = c.depth();
            let poly = &polys[i];
            let group = topo.group[i];
            if d >= min_depth || poly.iter().any(|&v| vdepth[v as usize] >= min_depth) {
                let centre = s.mesh.positions.len() as u32;
                s.mesh.positions.push(lift(c.centroid(), d));
                s.depth.push(d as f32);
                for k in 0..poly.len() {
                    s.mesh
                        .triangles
                        .push([centre, poly[k], poly[(k + 1) % poly.len()]]);
                    s.tags.push(Tag::SnowTop {
                        site: i as u32,
                        group,
                    });
                }
            }
            for e in &topo.borders[i] {
                let va = key_vertex[&(group, q(e.a))];
                let vb = key_vertex[&(group, q(e.b))];
                if vdepth[va as usize] < min_depth && vdepth[vb as usize] < min_depth {
                    continue;
                }
                let mut bottom = |v: u32| {
                    *base_copy.entry(v).or_insert_with(|| {
                        let p = base[v as usize];
                        s.mesh.positions.push(lift(p, 0.0));
                        s.depth.push(0.0);
                        (s.mesh.positions.len() - 1) as u32
                    })
                };
                let (ba, bb) = (bottom(va), bottom(vb));
                s.mesh.triangles.push([ba, bb, vb]);
                s.mesh.triangles.push([ba, vb, va]);
                s.tags.push(Tag::SnowWall { group });
                s.tags.push(Tag::SnowWall { group });
            }
        }
        s
    }

    /// `passes` Taubin λ|μ pairs on the depth of the top-surface vertices (module docs).
    pub fn smooth(&mut self, passes: u32) {
        if passes == 0 {
            return;
        }
        let n = self.mesh.positions.len();
        // Edges of the top triangles, as a compressed adjacency (deduplicated).
        let mut edges: Vec<(u32, u32)> = Vec::with_capacity(6 * self.mesh.triangles.len());
        for (t, tag) in self.mesh.triangles.iter().zip(&self.tags) {
            if matches!(tag, Tag::SnowTop { .. }) {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    edges.push((a, b));
                    edges.push((b, a));
                }
            }
        }
        edges.sort_unstable();
        edges.dedup();
        let mut start = vec![0usize; n + 1];
        for &(a, _) in &edges {
            start[a as usize + 1] += 1;
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        let mut depth: Vec<f64> = self.depth.iter().map(|&d| d as f64).collect();
        let step = |depth: &[f64], factor: f64| -> Vec<f64> {
            (0..n)
                .map(|v| {
                    let nb = &edges[start[v]..start[v + 1]];
                    if nb.is_empty() {
                        return depth[v];
                    }
                    let mean =
                        nb.iter().map(|&(_, b)| depth[b as usize]).sum::<f64>() / nb.len() as f64;
                    (depth[v] + factor * (mean - depth[v])).max(0.0)
                })
                .collect()
        };
        // Each vertex stays within the depths of its original neighbourhood: the μ step's
        // overshoot never raises snow above the deepest site around it.
        let range: Vec<(f64, f64)> = (0..n)
            .map(|v| {
                edges[start[v]..start[v + 1]]
                    .iter()
                    .map(|&(_, b)| depth[b as usize])
                    .fold((depth[v], depth[v]), |(lo, hi), d| (lo.min(d), hi.max(d)))
            })
            .collect();
        for _ in 0..passes {
            depth = step(&depth, 0.5);
            depth = step(&depth, -0.53);
            for (d, &(lo, hi)) in depth.iter_mut().zip(&range) {
                *d = d.clamp(lo, hi);
            }
        }
        for v in 0..n {
            if start[v + 1] > start[v] {
                let dz = depth[v] - self.depth[v] as f64;
                self.mesh.positions[v][2] = (self.mesh.positions[v][2] as f64 + dz) as f32;
                self.depth[v] = depth[v] as f32;
            }
        }
    }

    /// Snow volume under the top surface (each top triangle's mean depth times its horizontal
    /// area), m³.
    pub fn top_volume(&self) -> f64 {
        self.mesh
            .triangles
            .iter()
            .zip(&self.tags)
            .filter(|(_, tag)| matches!(tag, Tag::SnowTop { .. }))
            .map(|(t, _)| {
                let [a, b, c] = t.map(|i| self.mesh.positions[i as usize].map(f64::from));
                let area =
                    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])).abs();
                area * t
                    .iter()
                    .map(|&i| self.depth[i as usize] as f64)
                    .sum::<f64>()
                    / 3.0
            })
            .sum()
    }

    /// Triangles with their tags, for the tracer.
    pub fn tagged(&self) -> Vec<([[f32; 3]; 3], Tag)> {
        self.mesh
            .triangles
            .iter()
            .zip(&self.tags)
            .map(|(t, &tag)| (t.map(|i| self.mesh.positions[i as usize]), tag))
            .collect()
    }

    /// The surface as a mesh to write (unused vertices dropped).
    pub fn to_mesh(&self, name: &str) -> SnowObject {
        let mut remap = vec![u32::MAX; self.mesh.positions.len()];
        let mut positions = Vec::new();
        let triangles = self
            .mesh
            .triangles
            .iter()
            .map(|t| {
                t.map(|v| {
                    if remap[v as usize] == u32::MAX {
                        remap[v as usize] = positions.len() as u32;
                        positions.push(self.mesh.positions[v as usize]);
                    }
                    remap[v as usize]
                })
            })
            .collect();
        SnowObject::new(TriMesh {
            name: name.into(),
            frame: MeshFrame::Scene,
            positions,
            triangles,
            ..TriMesh::default()
        })
    }
}

/// `iterations` Jacobi steps of mass-conserving depth diffusion between neighbouring sites
/// (pairs where either site saw no sky are left alone, so occlusion boundaries stay sharp).
pub fn smooth_volumes(sites: &mut LaunchSites, topo: &Topology, iterations: u32) {
    let n = topo.leaves.len();
    for _ in 0..iterations {
        let depth: Vec<f64> = topo
            .leaves
            .iter()
            .map(|&c| sites.cells[c as usize].depth())
            .collect();
        let area: Vec<f64> = topo
            .leaves
            .iter()
            .map(|&c| sites.cells[c as usize].area_xy())
            .collect();
        let frac: Vec<f64> = topo
            .leaves
            .iter()
            .map(|&c| sites.cells[c as usize].sky_fraction())
            .collect();
        let mut delta = vec![0.0f64; n];
        for i in 0..n {
            for nb in &topo.neighbours[i] {
                let j = nb.site as usize;
                // Never smooth into a site no flake could reach from the sky (a roof's shadow).
                if j <= i || frac[i] == 0.0 || frac[j] == 0.0 {
                    continue;
                }
                let deg = topo.neighbours[i].len().max(topo.neighbours[j].len()) as f64;
                let flux = 0.5 / (deg + 1.0) * (depth[i] - depth[j]) * area[i].min(area[j]);
                delta[i] -= flux;
                delta[j] += flux;
            }
        }
        for (&leaf, d) in topo.leaves.iter().zip(&delta) {
            let c = &mut sites.cells[leaf as usize];
            c.volume = (c.volume + d).max(0.0);
        }
    }
}
