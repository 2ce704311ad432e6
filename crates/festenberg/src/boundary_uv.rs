//! Texture coordinates near the snow boundary (von Festenberg & Gumhold 2011, Section 5.4.2,
//! Figs. 9 and 10): `u` runs along the boundary, `v` across it, so that a boundary alpha mask
//! ([`crate::mask`]) can be laid along every snow edge.
//!
//! Initialisation on each boundary loop (edges used by one triangle, walked in the triangles'
//! counter-clockwise order, so the snow is on the left):
//! - the loop is smoothed by "four convolutions of the boundary with the mask 1/4·(1 2 1)"
//!   into points `q_i`; `T_i` is the tangent by the mask `(-1 0 1)`; the reference direction
//!   `n_i × T_i / |n_i × T_i|` (vertex normal `n_i`) points into the snow, and
//!   `v_{i,s} = <ref, p_i - q_i>` is the signed distance of Fig. 9a;
//! - `v_{i,γ} = γ_max / π` with `γ` the angle between the snow surface and the ground along
//!   each mesh edge leaving the vertex (Fig. 9b), the largest kept: 0 for thin snow, 1/2 for
//!   snow standing at right angles to the ground;
//! - `u` is the arc length of the smoothed loop, scaled so a loop covers `[0, k]` with `k` a
//!   whole number of mask repeats.
//!
//! Coordinates are kept "proportional to distances" (metres, `v_{i,γ}` scaled by the mask
//! length `L`) and divided by `L` at the end ("an affine texture transformation").
//!
//! Propagation into the mesh (the marching method of Fig. 10): a priority queue of triangles
//! with exactly two processed vertices `p1, p2`; the candidate for the third, `p3`, is
//! `v3 = min over t in [0, 1] of v1 + t (v2 - v1) + |p1 + t (p2 - p1) - p3|` (the roots of the
//! quadratic `a t² + 2 b t + c = 0` of Fig. 10, pruned to [0, 1], plus the interval ends), and
//! `u3 = u1 + t*·(u2 - u1)` taken the short way round the loop's period. The lowest candidate
//! is processed first; propagation stops when the queue is empty or the lowest `v` exceeds
//! `L` (texture `v` = 1), and every vertex left gets `v = 1`.
//!
//! Seams: a triangle whose `u` values straddle the loop's wrap-around (a spread over `k / 2`)
//! gets copies of its high-`u` vertices with `u - k`, which sample the same texels of the
//! `u`-periodic mask.

use snowscape_mesh::TriMesh;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// What [`texture`] did to a mesh (its vertices may have been duplicated at seams).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct UvStats {
    /// Boundary loops found.
    pub loops: usize,
    /// Vertices given coordinates by propagation.
    pub propagated: usize,
    /// Vertices duplicated at `u` seams.
    pub seam_copies: usize,
}

/// Rows of the mask image, so `v` can be kept on texel centres (no wrap-around bleeding).
pub const MASK_ROWS: f32 = 256.0;

/// Gives `mesh` (scene frame, its unit vertex normals set) its boundary texture coordinates
/// (glTF convention: `u` along the boundary, where the mask repeats, `v` in [0, 1] across it),
/// with `ground` points under its vertices and mask length `scale` metres; vertices are
/// duplicated where a triangle straddles a loop's `u` seam.
///
/// # Panics
/// If the mesh has no normals (the cover pipeline computes them first).
pub fn texture(mesh: &mut TriMesh, ground: &[[f32; 3]], scale: f32) -> UvStats {
    let positions = &mesh.positions;
    let triangles = &mesh.triangles;
    let normals = mesh
        .normals
        .as_deref()
        .expect("the boundary texture needs the mesh's vertex normals");
    let n = positions.len();
    // (u, v in metres, period k); k = 0 for vertices not yet processed.
    let mut coord: Vec<Option<(f32, f32, f32)>> = vec![None; n];
    let loops = boundary_loops(triangles, n);
    let gamma = boundary_angles(positions, ground, triangles, n);
    for lp in &loops {
        init_loop(lp, positions, normals, &gamma, scale, &mut coord);
    }
    let propagated = propagate(positions, triangles, scale, &mut coord);
    let rows = MASK_ROWS;
    mesh.uvs = Some(
        coord
            .iter()
            .map(|c| {
                let (u, v) = c.map_or((0.0, scale), |(u, v, _)| (u, v));
                // Never a NaN or infinity in a file: a coordinate the arithmetic could not
                // give (f32 overflow on absurd geometry, which the readers refuse) is the
                // seam (u = 0) and the far side of the mask (v = 1).
                let u = if u.is_finite() { u } else { 0.0 };
                let v = if (v / scale).is_finite() {
                    v / scale
                } else {
                    1.0
                };
                [u, v.clamp(0.5 / rows, 1.0 - 0.5 / rows)]
            })
            .collect(),
    );
    let period: Vec<f32> = coord.iter().map(|c| c.map_or(0.0, |c| c.2)).collect();
    UvStats {
        loops: loops.len(),
        propagated,
        seam_copies: fix_seams(mesh, &period),
    }
}

/// Boundary loops: directed edges used by one triangle, chained head to tail.
pub fn boundary_loops(triangles: &[[u32; 3]], n: usize) -> Vec<Vec<u32>> {
    let mut edges: Vec<(u32, u32, u32, u32)> = Vec::with_capacity(triangles.len() * 3);
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.push((a.min(b), a.max(b), a, b));
        }
    }
    edges.sort_unstable();
    let mut out_edges: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && (edges[j].0, edges[j].1) == (edges[i].0, edges[i].1) {
            j += 1;
        }
        if j == i + 1 {
            out_edges[edges[i].2 as usize].push(edges[i].3);
        }
        i = j;
    }
    let mut loops = Vec::new();
    for start in 0..n {
        while let Some(mut next) = out_edges[start].pop() {
            let mut lp = vec![start as u32];
            while next as usize != start {
                lp.push(next);
                match out_edges[next as usize].pop() {
                    Some(nn) => next = nn,
                    None => break, // an open chain (non-manifold input): keep what we have
                }
            }
            loops.push(lp);
        }
    }
    loops
}

/// The largest angle between snow surface and ground along the edges at each vertex.
fn boundary_angles(p: &[[f32; 3]], g: &[[f32; 3]], triangles: &[[u32; 3]], n: usize) -> Vec<f32> {
    let mut gamma = vec![0.0f32; n];
    for t in triangles {
        for k in 0..3 {
            for (a, b) in [(t[k], t[(k + 1) % 3]), (t[(k + 1) % 3], t[k])] {
                let (a, b) = (a as usize, b as usize);
                let snow = sub(p[b], p[a]);
                let ground = sub(g[b], g[a]);
                let (ls, lg) = (len(snow), len(ground));
                if ls > 0.0 && lg > 0.0 {
                    let c = (dot(snow, ground) / (ls * lg)).clamp(-1.0, 1.0);
                    gamma[a] = gamma[a].max(c.acos());
                }
            }
        }
    }
    gamma
}

fn init_loop(
    lp: &[u32],
    p: &[[f32; 3]],
    normals: &[[f32; 3]],
    gamma: &[f32],
    scale: f32,
    coord: &mut [Option<(f32, f32, f32)>],
) {
    let m = lp.len();
    let pts: Vec<[f32; 3]> = lp.iter().map(|&i| p[i as usize]).collect();
    let mut q = pts.clone();
    if m >= 3 {
        for _ in 0..4 {
            q = (0..m)
                .map(|i| {
                    let (a, b, c) = (q[(i + m - 1) % m], q[i], q[(i + 1) % m]);
                    [0, 1, 2].map(|k| 0.25 * (a[k] + 2.0 * b[k] + c[k]))
                })
                .collect();
        }
    }
    let mut arc = vec![0.0f32; m + 1];
    for i in 0..m {
        arc[i + 1] = arc[i] + len(sub(q[(i + 1) % m], q[i]));
    }
    let total = arc[m];
    let k = (total / scale).round().max(1.0);
    for (i, &vi) in lp.iter().enumerate() {
        let vi = vi as usize;
        let t = sub(q[(i + 1) % m], q[(i + m - 1) % m]);
        let r = cross(normals[vi], t);
        let lr = len(r);
        let vs = if lr > 0.0 {
            dot(r, sub(pts[i], q[i])) / lr
        } else {
            0.0
        };
        let v = vs + gamma[vi] / std::f32::consts::PI * scale;
        let u = if total > 0.0 { arc[i] / total * k } else { 0.0 };
        coord[vi] = Some((u, v, k));
    }
}

/// Marching propagation (Fig. 10); returns the number of vertices it reached.
fn propagate(
    p: &[[f32; 3]],
    triangles: &[[u32; 3]],
    scale: f32,
    coord: &mut [Option<(f32, f32, f32)>],
) -> usize {
    let n = p.len();
    let mut around: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (ti, t) in triangles.iter().enumerate() {
        for &v in t {
            around[v as usize].push(ti as u32);
        }
    }
    let mut heap = BinaryHeap::new();
    let push = |heap: &mut BinaryHeap<Candidate>, coord: &[Option<(f32, f32, f32)>], ti: usize| {
        let t = triangles[ti];
        let done: Vec<usize> = (0..3).filter(|&k| coord[t[k] as usize].is_some()).collect();
        if done.len() != 2 {
            return;
        }
        let k3 = 3 - done[0] - done[1];
        let (i1, i2, i3) = (t[done[0]] as usize, t[done[1]] as usize, t[k3] as usize);
        let (c1, c2) = (coord[i1].unwrap_or_default(), coord[i2].unwrap_or_default());
        let (ts, v3) = march(p[i1], p[i2], p[i3], c1.1, c2.1);
        let period = c1.2;
        let mut du = c2.0 - c1.0;
        if period > 0.0 && c2.2 == period {
            if du > 0.5 * period {
                du -= period;
            } else if du < -0.5 * period {
                du += period;
            }
        }
        let mut u3 = c1.0 + ts * du;
        if period > 0.0 {
            u3 = u3.rem_euclid(period);
        }
        heap.push(Candidate {
            v: v3,
            triangle: ti as u32,
            vertex: i3 as u32,
            u: u3,
            period,
        });
    };
    for ti in 0..triangles.len() {
        push(&mut heap, coord, ti);
    }
    let mut reached = 0;
    while let Some(c) = heap.pop() {
        if c.v > scale {
            break;
        }
        if coord[c.vertex as usize].is_some() {
            continue;
        }
        coord[c.vertex as usize] = Some((c.u, c.v, c.period));
        reached += 1;
        for &ti in &around[c.vertex as usize] {
            push(&mut heap, coord, ti as usize);
        }
    }
    reached
}

/// A queued update: lowest `v` first, ties by triangle then vertex (deterministic).
#[derive(Debug, Clone, Copy)]
struct Candidate {
    v: f32,
    triangle: u32,
    vertex: u32,
    u: f32,
    period: f32,
}

impl PartialEq for Candidate {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Candidate {}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Candidate {
    fn cmp(&self, o: &Self) -> Ordering {
        // BinaryHeap is a max-heap: reverse so the lowest v comes out first.
        o.v.total_cmp(&self.v)
            .then(o.triangle.cmp(&self.triangle))
            .then(o.vertex.cmp(&self.vertex))
    }
}

/// The update step of Fig. 10: `(t*, v3)` minimising `v1 + t Δv + |p1 + t Δp - p3|`.
pub fn march(p1: [f32; 3], p2: [f32; 3], p3: [f32; 3], v1: f32, v2: f32) -> (f32, f32) {
    let dp = sub(p2, p1);
    let d = sub(p3, p1);
    let dv = (v2 - v1) as f64;
    let pp = dot(dp, dp) as f64;
    let pd = dot(dp, d) as f64;
    let dd = dot(d, d) as f64;
    let f = |t: f64| v1 as f64 + t * dv + (t * t * pp - 2.0 * t * pd + dd).max(0.0).sqrt();
    let mut best = (0.0, f(0.0));
    let mut consider = |t: f64| {
        if (0.0..=1.0).contains(&t) {
            let ft = f(t);
            if ft < best.1 {
                best = (t, ft);
            }
        }
    };
    consider(1.0);
    // (t·pp - pd)² = dv² (t² pp - 2 t pd + dd): a t² + 2 b t + c = 0.
    let a = pp * (pp - dv * dv);
    let b = pd * (dv * dv - pp);
    let c = pd * pd - dv * dv * dd;
    if a.abs() > 1e-30 {
        let disc = b * b - a * c;
        if disc >= 0.0 {
            let s = disc.sqrt();
            consider((-b + s) / a);
            consider((-b - s) / a);
        }
    } else if b.abs() > 1e-30 {
        consider(-c / (2.0 * b));
    }
    (best.0 as f32, best.1 as f32)
}

/// Duplicates the high-`u` corners of every triangle straddling its loop's seam (period `k`)
/// with `u - k`; returns the number of copies.
fn fix_seams(m: &mut TriMesh, period: &[f32]) -> usize {
    let (Some(normals), Some(uvs)) = (m.normals.as_mut(), m.uvs.as_mut()) else {
        return 0;
    };
    let mut copy: std::collections::HashMap<u32, u32> = std::collections::HashMap::new();
    for ti in 0..m.triangles.len() {
        let t = m.triangles[ti];
        let k = t.iter().map(|&i| period[i as usize]).fold(0.0f32, f32::max);
        if k <= 0.0 {
            continue;
        }
        let us = t.map(|i| uvs[i as usize][0]);
        let lo = us.iter().copied().fold(f32::INFINITY, f32::min);
        let hi = us.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        if hi - lo <= 0.5 * k {
            continue;
        }
        for s in 0..3 {
            let i = t[s];
            if us[s] > lo + 0.5 * k {
                let j = *copy.entry(i).or_insert_with(|| {
                    let j = m.positions.len() as u32;
                    m.positions.push(m.positions[i as usize]);
                    normals.push(normals[i as usize]);
                    let [u, v] = uvs[i as usize];
                    uvs.push([u - k, v]);
                    j
                });
                m.triangles[ti][s] = j;
            }
        }
    }
    copy.len()
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn len(a: [f32; 3]) -> f32 {
    dot(a, a).sqrt()
}
fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn marching_reproduces_the_distance_to_a_straight_boundary() {
        // Boundary along the x axis: v = y. p1, p2 at y = 1 and 2, p3 at y = 3.
        let (t, v3) = march([0.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 3.0, 0.0], 1.0, 2.0);
        assert!((v3 - 3.0).abs() < 1e-5, "{v3} at t = {t}");
        // Equal v on both: the nearest point of the edge.
        let (t, v3) = march([0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 1.0, 0.0], 0.0, 0.0);
        assert!((t - 0.5).abs() < 1e-5 && (v3 - 1.0).abs() < 1e-5);
    }

    #[test]
    fn a_square_has_one_counter_clockwise_boundary_loop() {
        let tris = [[0, 1, 2], [0, 2, 3]];
        let loops = boundary_loops(&tris, 4);
        assert_eq!(loops.len(), 1);
        assert_eq!(loops[0].len(), 4);
    }
}
