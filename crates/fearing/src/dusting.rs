//! Flake dusting (Fearing 2000, Section 3.8): where the snow is too thin to be a surface, the
//! already-computed sky-occlusion percentages become procedural noise textures of matching
//! density on semi-transparent polygons floating slightly in front of the model.
//!
//! Every launch site thinner than the surface threshold that saw the sky gets its cell as a
//! dusting triangle, lifted along its normal by a thousandth of the site spacing. The texture
//! is one 256 x 256 atlas of [`LEVELS`] horizontal bands; band k holds keyed white noise whose
//! alpha is opaque on a share (k + 1) / LEVELS of its texels, and a site's triangle maps into
//! the band of its sky-hit share, in one of four slots chosen by a keyed draw (so neighbours do
//! not repeat one pattern). The alpha is a mask (cut at 0.5) in the GLB and the OBJ's `map_d`.

use crate::edge_groups::Topology;
use crate::launch_sites::LaunchSites;
use image::{Rgba, RgbaImage};
use snowscape_mesh::{MeshFrame, SnowObject, TriMesh};
use snowscape_terrain::random::{hash3, uniform};

/// Density levels of the atlas.
pub const LEVELS: u32 = 8;
/// Atlas size, texels.
pub const SIZE: u32 = 256;

/// The dusting atlas: band k (rows k·SIZE/LEVELS..) opaque on (k + 1)/LEVELS of its texels.
pub fn atlas(seed: u64) -> RgbaImage {
    let band = SIZE / LEVELS;
    RgbaImage::from_fn(SIZE, SIZE, |x, y| {
        let k = (y / band).min(LEVELS - 1);
        // 2 x 2 texel flakes.
        let u = uniform(seed, 0xd057, ((y / 2) as u64) << 16 | (x / 2) as u64);
        let on = u < (k + 1) as f64 / LEVELS as f64;
        Rgba([250, 252, 255, if on { 255 } else { 0 }])
    })
}

/// The dusting mesh of the sites thinner than `min_depth` that saw the sky, `None` if none.
pub fn dusting_mesh(
    sites: &LaunchSites,
    topo: &Topology,
    min_depth: f64,
    seed: u64,
) -> Option<SnowObject> {
    let lift = sites.spacing * 1e-3;
    let (mut positions, mut uvs, mut triangles) = (Vec::new(), Vec::new(), Vec::new());
    let band = 1.0 / LEVELS as f32;
    for &id in &topo.leaves {
        let c = &sites.cells[id as usize];
        let share = c.sky_fraction();
        if c.depth() >= min_depth || c.shots == 0.0 || share <= 0.0 {
            continue;
        }
        let k = ((share * LEVELS as f64).ceil() as u32).clamp(1, LEVELS) - 1;
        let slot = (hash3(seed, 0xd058, id as u64) % 4) as f32;
        let e1 = [0, 1, 2].map(|d| c.corners[1][d] - c.corners[0][d]);
        let e2 = [0, 1, 2].map(|d| c.corners[2][d] - c.corners[0][d]);
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt().max(1e-300);
        let base = positions.len() as u32;
        for p in c.corners {
            positions.push([0, 1, 2].map(|d| (p[d] + n[d] / l * lift) as f32));
        }
        let (u0, v0) = (slot * 0.25, k as f32 * band);
        uvs.extend([
            [u0 + 0.02, v0 + 0.9 * band],
            [u0 + 0.23, v0 + 0.9 * band],
            [u0 + 0.125, v0 + 0.1 * band],
        ]);
        triangles.push([base, base + 1, base + 2]);
    }
    (!triangles.is_empty()).then(|| {
        SnowObject::textured(
            TriMesh {
                name: "dusting".into(),
                frame: MeshFrame::Scene,
                positions,
                normals: None,
                uvs: Some(uvs),
                triangles,
            },
            atlas(seed),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atlas_bands_grow_denser() {
        let img = atlas(3);
        let band = SIZE / LEVELS;
        let share = |k: u32| {
            let rows = k * band..(k + 1) * band;
            let on = rows
                .clone()
                .flat_map(|y| (0..SIZE).map(move |x| (x, y)))
                .filter(|&(x, y)| img.get_pixel(x, y).0[3] == 255)
                .count();
            on as f64 / (band * SIZE) as f64
        };
        for k in 0..LEVELS {
            let want = (k + 1) as f64 / LEVELS as f64;
            assert!(
                (share(k) - want).abs() < 0.05,
                "band {k}: {} vs {want}",
                share(k)
            );
        }
    }
}
