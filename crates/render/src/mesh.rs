//! Triangle meshes of a height field sampled on a (possibly decimated) lattice of cells.
//!
//! The lattice and its triangles are the project's one triangulation of a height field
//! ([`snowscape_terrain::lattice`]: every `step`-th column and row plus the last ones, each
//! square split along its south-west to north-east diagonal, a triangle kept when its three
//! corners are usable: valid cells for the terrain, valid cells with snow for the snow mesh);
//! only vertices used by a kept triangle are emitted.
//!
//! Coordinates are glTF's: metres, x east, y up, z south, x and z centred on the grid's
//! centre, `y = (altitude - base) · exaggeration`. Triangles wind counter-clockwise seen from
//! above, so their front faces point up. Normals come from central differences on the lattice
//! (one-sided at borders and next to unusable vertices).

use crate::RenderError;
use snowscape_mesh::{MeshFrame, TriMesh};
use snowscape_terrain::{GridGeometry, operators};

pub use snowscape_terrain::lattice::{lattice_axis, lattice_vertices};

/// The smallest step at least `decimation` whose lattice has at most `budget` vertices.
pub fn choose_step(
    width: usize,
    height: usize,
    decimation: usize,
    budget: Option<usize>,
) -> Result<usize, RenderError> {
    if decimation == 0 {
        return Err(RenderError::InvalidCount {
            name: "decimation",
            value: 0,
            expected: "at least 1 (1 keeps every vertex)",
        });
    }
    let Some(budget) = budget else {
        return Ok(decimation);
    };
    if budget < 4 {
        return Err(RenderError::InvalidCount {
            name: "max_vertices",
            value: budget,
            expected: "at least 4 vertices per mesh",
        });
    }
    let mut step = decimation;
    if lattice_vertices(width, height, step) > budget {
        let ratio = (width as f64 * height as f64 / budget as f64).sqrt();
        step = step.max(ratio.floor() as usize);
        while lattice_vertices(width, height, step) > budget {
            step += 1;
        }
    }
    Ok(step)
}

/// What to mesh: altitude and usability of each grid cell.
pub struct HeightSource<'a> {
    /// The grid's geometry.
    pub geometry: &'a GridGeometry,
    /// Altitude of cell `i`, metres.
    pub altitude: &'a (dyn Fn(usize) -> f32 + Sync),
    /// Whether cell `i` may be a triangle corner.
    pub usable: &'a (dyn Fn(usize) -> bool + Sync),
    /// Name of the surface for error messages ("bedrock altitude", "snow surface altitude").
    pub what: &'static str,
}

/// Meshes `source` on the lattice of `step`, in glTF's frame ([`MeshFrame::Gltf`], module
/// docs) with unit vertex normals and named after `source.what`; `None` when no triangle is
/// usable.
pub fn surface_mesh(
    source: &HeightSource,
    step: usize,
    base: f32,
    exaggeration: f32,
) -> Result<Option<TriMesh>, RenderError> {
    let g = source.geometry;
    let (cols, rows) = (
        lattice_axis(g.width(), step),
        lattice_axis(g.height(), step),
    );
    let (nc, nr) = (cols.len(), rows.len());
    let (dx, dy) = (g.cell_size_x(), g.cell_size_y());
    let (half_w, half_h) = (0.5 * g.width() as f64 * dx, 0.5 * g.height() as f64 * dy);
    let xs: Vec<f32> = cols
        .iter()
        .map(|&c| ((c as f64 + 0.5) * dx - half_w) as f32)
        .collect();
    let zs: Vec<f32> = rows
        .iter()
        .map(|&r| ((r as f64 + 0.5) * dy - half_h) as f32)
        .collect();
    let mut usable = vec![false; nc * nr];
    let mut ys = vec![0.0f32; nc * nr];
    for (b, &r) in rows.iter().enumerate() {
        for (a, &c) in cols.iter().enumerate() {
            let i = g.index(c, r);
            if !(source.usable)(i) {
                continue;
            }
            let altitude = (source.altitude)(i);
            if !altitude.is_finite() {
                return Err(RenderError::NonFinite {
                    what: source.what,
                    col: c,
                    row: r,
                    value: altitude,
                });
            }
            usable[b * nc + a] = true;
            ys[b * nc + a] = (altitude - base) * exaggeration;
        }
    }
    let lattice_triangles = snowscape_terrain::lattice::lattice_triangles(&usable, nc, nr)
        .map_err(|_| RenderError::InvalidCount {
            name: "max_vertices",
            value: nc * nr,
            expected: "fewer than 2^32 lattice vertices per mesh (decimate more)",
        })?;
    if lattice_triangles.is_empty() {
        return Ok(None);
    }
    // Compact: number the used lattice vertices in lattice order.
    let mut new_index = vec![u32::MAX; nc * nr];
    for &v in lattice_triangles.as_flattened() {
        new_index[v as usize] = 0;
    }
    let lattice = Lattice {
        xs: &xs,
        zs: &zs,
        ys: &ys,
        usable: &usable,
    };
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for (v, slot) in new_index.iter_mut().enumerate() {
        if *slot == u32::MAX {
            continue;
        }
        let Ok(next) = u32::try_from(positions.len()) else {
            return Err(RenderError::InvalidCount {
                name: "max_vertices",
                value: positions.len(),
                expected: "fewer than 2^32 vertices per mesh (decimate more)",
            });
        };
        *slot = next;
        let (a, b) = (v % nc, v / nc);
        positions.push([xs[a], ys[v], zs[b]]);
        normals.push(lattice_normal(&lattice, a, b));
    }
    let triangles = lattice_triangles
        .iter()
        .map(|t| t.map(|v| new_index[v as usize]))
        .collect();
    Ok(Some(TriMesh {
        name: source.what.to_string(),
        frame: MeshFrame::Gltf,
        positions,
        normals: Some(normals),
        triangles,
        uvs: None,
    }))
}

/// The lattice's coordinates and usability, for normals.
struct Lattice<'a> {
    xs: &'a [f32],
    zs: &'a [f32],
    ys: &'a [f32],
    usable: &'a [bool],
}

/// Unit normal at lattice vertex `(a, b)` from central differences over usable neighbours.
fn lattice_normal(l: &Lattice, a: usize, b: usize) -> [f32; 3] {
    let nc = l.xs.len();
    let at = |a: usize, b: usize| b * nc + a;
    let here = at(a, b);
    let slope = |lo: Option<usize>, hi: Option<usize>, pos: &dyn Fn(usize) -> f32| {
        let lo = lo.filter(|&v| l.usable[v]).unwrap_or(here);
        let hi = hi.filter(|&v| l.usable[v]).unwrap_or(here);
        let run = pos(hi) - pos(lo);
        if run.abs() > 0.0 {
            (l.ys[hi] - l.ys[lo]) / run
        } else {
            0.0
        }
    };
    let gx = slope(
        a.checked_sub(1).map(|a| at(a, b)),
        (a + 1 < nc).then(|| at(a + 1, b)),
        &|v| l.xs[v % nc],
    );
    let gz = slope(
        b.checked_sub(1).map(|b| at(a, b)),
        (b + 1 < l.zs.len()).then(|| at(a, b + 1)),
        &|v| l.zs[v / nc],
    );
    // The lattice is y up: the upward normal of (x, z) with its last two axes swapped.
    let [nx, nz, ny] = operators::upward_normal(gx, gz);
    [nx, ny, nz]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_meets_the_vertex_budget() {
        let step = choose_step(8192, 8192, 1, Some(2_000_000)).unwrap();
        assert!(lattice_vertices(8192, 8192, step) <= 2_000_000);
        assert!(lattice_vertices(8192, 8192, step - 1) > 2_000_000);
        assert_eq!(choose_step(100, 100, 3, Some(1_000_000)).unwrap(), 3);
        assert!(choose_step(100, 100, 0, None).is_err());
        assert!(choose_step(100, 100, 1, Some(3)).is_err());
    }

    #[test]
    fn a_tilted_plane_has_its_exact_normal_and_upward_triangles() {
        // Altitude rises 0.5 m per metre east; 2 m x 1 m cells.
        let g = GridGeometry::new(5, 4, 2.0, 1.0).unwrap();
        let alt = |i: usize| (i % 5) as f32 * 2.0 * 0.5;
        let mesh = surface_mesh(
            &HeightSource {
                geometry: &g,
                altitude: &alt,
                usable: &|_| true,
                what: "test",
            },
            1,
            0.0,
            1.0,
        )
        .unwrap()
        .unwrap();
        assert_eq!(mesh.positions.len(), 20);
        assert_eq!(mesh.triangles.len(), 4 * 3 * 2);
        assert_eq!(mesh.frame, MeshFrame::Gltf);
        let len = (1.0f32 + 0.25).sqrt();
        for n in mesh.normals.as_ref().unwrap() {
            assert!((n[0] + 0.5 / len).abs() < 1e-6 && (n[1] - 1.0 / len).abs() < 1e-6);
            assert!(n[2].abs() < 1e-6);
        }
        for t in &mesh.triangles {
            let p: [[f32; 3]; 3] = std::array::from_fn(|k| mesh.positions[t[k] as usize]);
            let e1 = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
            let e2 = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
            let up = e1[2] * e2[0] - e1[0] * e2[2];
            assert!(up > 0.0, "triangle {t:?} faces down");
        }
        let b = mesh.bounds().unwrap();
        assert_eq!((b.min[0], b.max[0]), (-4.0, 4.0));
        assert_eq!((b.min[2], b.max[2]), (-1.5, 1.5));
    }
}
