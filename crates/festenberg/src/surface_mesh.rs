//! The snow surface as a triangle mesh (von Festenberg & Gumhold 2011, Section 5.4.1).
//!
//! "All symmetric pairs {p, p'} which are direct neighbours in i or j direction within the
//! height span map are connected to a quad mesh" ([`crate::links`]), at the sites' world
//! positions "including the accumulated snow height and potential overhangs". "Concave corners
//! of the boundary of the quad mesh are smoothed by adding a triangle cutting the concave
//! corner short": where three sites of a 2x2 block are linked in an L but the fourth is not,
//! the L gets a triangle. "Each remaining quad is subdivided into two triangles by locally
//! minimizing the largest interior angle of the resulting triangles." Faces whose corners all
//! hold no snow are left out. Triangles are counter-clockwise seen from above (normals up).
//! Vertex normals are area-weighted triangle normals (computed by the writer,
//! [`snowscape_mesh::write::vertex_normals`]).

use crate::links::SiteLinks;
use crate::sites::SiteField;
use snowscape_mesh::TriMesh;

/// A snow surface mesh over the sites, as built: the mesh (scene frame, named "snow", no
/// normals yet) with each vertex's site and ground point beside it, which the texture and the
/// bridges need; [`crate::pipeline::plain_mesh`] makes the object to write of it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SiteMesh {
    /// The snow surface: positions (scene metres, z up) and counter-clockwise triangles seen
    /// from above.
    pub mesh: TriMesh,
    /// The ground point under each vertex (the site without snow and offset).
    pub ground: Vec<[f32; 3]>,
    /// The site of each vertex.
    pub site: Vec<u32>,
    /// Quads split into two triangles.
    pub quads: usize,
    /// Triangles cutting concave corners.
    pub corner_triangles: usize,
}

/// Snow heights below this share of h0 count as no snow when faces are chosen.
pub const NO_SNOW: f32 = 1e-4;

/// Builds the mesh of `heights` (metres per site) with optional horizontal `offsets`
/// (overhangs, metres per site).
pub fn build(
    field: &SiteField,
    links: &[SiteLinks],
    heights: &[f32],
    offsets: Option<&[[f32; 2]]>,
) -> SiteMesh {
    let mut m = SiteMesh {
        mesh: TriMesh {
            name: "snow".into(),
            ..TriMesh::default()
        },
        ..SiteMesh::default()
    };
    let mut vertex = vec![u32::MAX; field.len()];
    let eps = NO_SNOW * field.depth;
    let (w, h) = (field.width, field.height);
    let east = |i: usize| links[i][0].site();
    let south = |i: usize| links[i][1].site();
    let west = |i: usize| links[i][2].site();
    let north = |i: usize| links[i][3].site();
    let mut add = |m: &mut SiteMesh, corners: &[usize]| -> Option<Vec<u32>> {
        if corners.iter().all(|&i| heights[i] <= eps) {
            return None;
        }
        Some(
            corners
                .iter()
                .map(|&i| {
                    if vertex[i] == u32::MAX {
                        vertex[i] = m.mesh.positions.len() as u32;
                        let [x, y] = field.column_xy(field.column[i] as usize);
                        let off = offsets.map_or([0.0; 2], |o| o[i]);
                        let g = [x as f32, y as f32, field.z[i]];
                        m.ground.push(g);
                        m.mesh
                            .positions
                            .push([g[0] + off[0], g[1] + off[1], g[2] + heights[i]]);
                        m.site.push(i as u32);
                    }
                    vertex[i]
                })
                .collect(),
        )
    };
    for row in 0..h.saturating_sub(1) {
        for col in 0..w.saturating_sub(1) {
            let c = row * w + col;
            // Corners a (this column), b (east), c (south-east), d (south).
            for a in field.column_sites(c) {
                match (east(a), south(a)) {
                    (Some(b), Some(d)) => {
                        let c1 = south(b);
                        if c1.is_some() && c1 == east(d) {
                            if let Some(v) = add(&mut m, &[a, b, c1.unwrap_or(0), d]) {
                                let t = split_quad(&m.mesh.positions, [v[0], v[1], v[2], v[3]]);
                                m.mesh.triangles.extend(t);
                                m.quads += 1;
                            }
                        } else if let Some(v) = add(&mut m, &[a, d, b]) {
                            m.mesh.triangles.push([v[0], v[1], v[2]]);
                            m.corner_triangles += 1;
                        }
                    }
                    (Some(b), None) => {
                        if let Some(cc) = south(b)
                            && let Some(v) = add(&mut m, &[a, cc, b])
                        {
                            m.mesh.triangles.push([v[0], v[1], v[2]]);
                            m.corner_triangles += 1;
                        }
                    }
                    (None, Some(d)) => {
                        if let Some(cc) = east(d)
                            && let Some(v) = add(&mut m, &[a, d, cc])
                        {
                            m.mesh.triangles.push([v[0], v[1], v[2]]);
                            m.corner_triangles += 1;
                        }
                    }
                    (None, None) => {}
                }
            }
            // The L with its corner at c and no a linked to b or d.
            for cc in field.column_sites(c + w + 1) {
                if let (Some(d), Some(b)) = (west(cc), north(cc))
                    && north(d).is_none()
                    && west(b).is_none()
                    && let Some(v) = add(&mut m, &[b, d, cc])
                {
                    m.mesh.triangles.push([v[0], v[1], v[2]]);
                    m.corner_triangles += 1;
                }
            }
        }
    }
    m
}

/// The two triangles of quad `[a, b, c, d]` (a north-west, b north-east, c south-east, d
/// south-west) whose largest interior angle is smaller.
fn split_quad(p: &[[f32; 3]], [a, b, c, d]: [u32; 4]) -> [[u32; 3]; 2] {
    let along_ac = [[a, d, c], [a, c, b]];
    let along_bd = [[a, d, b], [b, d, c]];
    let worst = |ts: &[[u32; 3]; 2]| {
        ts.iter()
            .map(|t| max_angle(t.map(|i| p[i as usize])))
            .fold(0.0f32, f32::max)
    };
    if worst(&along_bd) < worst(&along_ac) {
        along_bd
    } else {
        along_ac
    }
}

/// The largest interior angle of a triangle, radians.
pub fn max_angle(t: [[f32; 3]; 3]) -> f32 {
    let sub = |a: [f32; 3], b: [f32; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let angle = |u: [f32; 3], v: [f32; 3]| {
        let dot = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
        let lu = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
        let lv = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if lu * lv > 0.0 {
            (dot / (lu * lv)).clamp(-1.0, 1.0).acos()
        } else {
            std::f32::consts::PI
        }
    };
    (0..3)
        .map(|k| {
            let (o, u, v) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            angle(sub(u, o), sub(v, o))
        })
        .fold(0.0, f32::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quads_split_along_the_diagonal_that_avoids_the_obtuse_angle() {
        // A rhombus squashed along b-d: the a-c diagonal gives obtuse triangles.
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.2, 0.0],
            [1.2, 1.2, 0.0],
            [0.2, 1.0, 0.0],
        ];
        let t = split_quad(&p, [0, 1, 2, 3]);
        assert_eq!(t, [[0, 3, 1], [1, 3, 2]]);
        let right = max_angle([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        assert!((right - std::f32::consts::FRAC_PI_2).abs() < 1e-5);
    }
}
