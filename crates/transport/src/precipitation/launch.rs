//! Where the flakes start: the launch plane of Fig. 6.5, folded onto the domain's faces.
//!
//! The thesis releases flakes uniformly on a plane at height `h` over a window upwind of
//! the domain, wide enough that the extreme winds carry every flake that can land onto it.
//! Upwind of the domain the air is the inflow, horizontally uniform; there, in the steady
//! state, a flake released on the plane falls with a velocity `v(z)` that depends only on
//! its height, and the flakes fill the air below `h` at the density `n(z) = P / |v_z(z)|`
//! (`P` flakes per m² and second released on the plane: the vertical flux is the same at
//! every height). So the flakes crossing into the domain are, per unit time, exactly:
//!
//! - `P` per m² through the launch plane over the domain (the plane itself), and
//! - `n v_n = P v_n(z) / |v_z(z)|` per m² through the upwind side faces below `h` (those
//!   holding the inflow), where `v_n > 0` is the flake velocity into the domain.
//!
//! `v(z)` comes from one flake per boundary column falling from the plane through that
//! column's horizontal wind (upwind air neither rises nor sinks) by the same equation of
//! motion as the flakes proper ([`Drag`]); in a sheared wind a falling flake lags the
//! wind and falls a little slower than `v_t`, and the flux follows.
//!
//! Flakes are launched on those faces, each drawn with a probability proportional to its
//! flux, with the upwind flake's velocity there (on the plane: at rest relative to the
//! vertical, falling at `v_t`). That is the thesis's set-up without its window: no flake
//! flies outside the domain, and none that can land is missed. With a strong wind (the
//! valley: 20-30 m s⁻¹ aloft under a log law) most flakes enter across the upwind side; a
//! window sized by the extreme winds is then tens of kilometres wide and all but a few
//! thousandths of it miss.
//!
//! Air entering across the other sides (an outflow side, zero-gradient in the wind
//! simulation, can draw air in, in a recirculation or around a ridge) comes from beside the
//! domain, where the scene's disturbance of the snowfall is unknown; it carries none here.
//!
//! Sampling is stratified: flake `n` of `N` takes the point `(n + ξ) / N` of the cumulative
//! flux, `ξ` from the counter-based generator keyed by `(seed, n)`, so every face gets its
//! share within one flake, and the launch points do not depend on the thread count.

use super::Drag;
use crate::wind3d::field::Centred;
use crate::wind3d::voxel::VoxelGrid;
use snowscape_terrain::random::uniform;

/// Distance inside the domain of a flake launched on a side face, voxels.
const INSIDE: f64 = 1e-6;

/// Slabs per voxel layer of the side faces: the flux follows the wind the flakes fly
/// through, interpolated between voxel centres, rather than one value per layer.
const SLABS: usize = 8;

/// A rectangle of the launch surface, `origin + a·span[0] + b·span[1]` for `a, b ∈ [0, 1)`
/// in voxel units, and the velocity flakes start with there (`None`: the wind's, falling
/// at `v_t`).
#[derive(Debug, Clone, Copy)]
struct Site {
    origin: [f64; 3],
    span: [[f64; 3]; 2],
    velocity: Option<[f64; 3]>,
}

/// Where and how a flake starts.
pub(super) struct Launch {
    /// Position, voxel units.
    pub position: [f64; 3],
    /// Velocity, m s⁻¹ (`None`: the wind's there, falling at `v_t`).
    pub velocity: Option<[f64; 3]>,
}

/// The launch surface with the cumulative flux of its sites.
#[derive(Debug)]
pub(super) struct Launcher {
    sites: Vec<Site>,
    /// Cumulative flux, in flakes per (flake per voxel face of the launch plane).
    cumulative: Vec<f64>,
    /// Share of the flux entering through the side faces.
    pub side_share: f64,
}

/// Height (voxels) and velocity (m s⁻¹) of a flake falling from the plane `top` through
/// the horizontal wind of the column at `at`, step by step down to `ground`.
fn upwind_fall(
    wind: &Centred,
    drag: &Drag,
    at: [f64; 2],
    top: f64,
    ground: f64,
) -> Vec<(f64, [f64; 3])> {
    let horizontal = |z: f64| {
        let w = wind.sample([at[0] as f32, at[1] as f32, z as f32]);
        [f64::from(w[0]), f64::from(w[1]), 0.0]
    };
    let mut z = top;
    let w = horizontal(z);
    let mut v = [w[0], w[1], -drag.vt];
    let mut path = vec![(z, v)];
    while z > ground {
        let per_voxel = drag.step(horizontal(z), &mut v);
        z += per_voxel * v[2].min(-1e-6);
        path.push((z, v));
    }
    path
}

impl Launcher {
    /// The launch surface for a plane at height `top` (voxel units above the grid's base)
    /// over columns solid up to `layers`
    /// and flakes of motion `drag`, through the voxel-centred wind `wind` the flakes fly
    /// through, whose upwind sides held the inflow `inflow` (east, north; only its signs
    /// matter).
    pub fn new(
        grid: &VoxelGrid,
        layers: &[u32],
        wind: &Centred,
        drag: &Drag,
        inflow: [f64; 2],
        top: f64,
    ) -> Self {
        let (nx, ny) = (grid.nx, grid.ny);
        let mut sites = Vec::new();
        let mut cumulative = Vec::new();
        let mut total = 0.0;
        let mut push = |site: Site, flux: f64, total: &mut f64| {
            if flux > 0.0 {
                *total += flux;
                sites.push(site);
                cumulative.push(*total);
            }
        };
        // The launch plane over the columns it clears.
        for j in 0..ny {
            for i in 0..nx {
                if f64::from(layers[j * nx + i]) < top {
                    let site = Site {
                        origin: [i as f64, j as f64, top],
                        span: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                        velocity: None,
                    };
                    push(site, 1.0, &mut total);
                }
            }
        }
        let plane = total;
        // The upwind side faces below it, in slabs of 1 / SLABS voxel.
        let sides: [(usize, f64, f64); 4] = [
            (0, INSIDE, 1.0),
            (0, nx as f64 - INSIDE, -1.0),
            (1, INSIDE, 1.0),
            (1, ny as f64 - INSIDE, -1.0),
        ];
        let slab = 1.0 / SLABS as f64;
        for (axis, at, inward) in sides {
            if inward * inflow[axis] <= 0.0 {
                continue;
            }
            let along = if axis == 0 { ny } else { nx };
            for l in 0..along {
                let mut origin = [at, at, 0.0];
                origin[1 - axis] = l as f64;
                let (i, j) = (origin[0] as usize, origin[1] as usize);
                let ground = f64::from(layers[j * nx + i]);
                if ground >= top {
                    continue;
                }
                let mut centre = [origin[0], origin[1]];
                centre[1 - axis] += 0.5;
                let path = upwind_fall(wind, drag, centre, top, ground);
                let mut p = 0; // path[p].0 >= z > path[p + 1].0
                let mut z0 = top;
                while z0 > ground {
                    let height = slab.min(z0 - ground);
                    z0 -= height;
                    let mid = z0 + 0.5 * height;
                    while p + 2 < path.len() && path[p + 1].0 >= mid {
                        p += 1;
                    }
                    let ((za, va), (zb, vb)) = (path[p], path[p + 1]);
                    let f = ((za - mid) / (za - zb)).clamp(0.0, 1.0);
                    let v: [f64; 3] = std::array::from_fn(|d| va[d] + f * (vb[d] - va[d]));
                    let flux = inward * v[axis] / -v[2] * height;
                    let mut span = [[0.0; 3], [0.0, 0.0, height]];
                    span[0][1 - axis] = 1.0;
                    let site = Site {
                        origin: [origin[0], origin[1], z0],
                        span,
                        velocity: Some(v),
                    };
                    push(site, flux, &mut total);
                }
            }
        }
        Self {
            sites,
            cumulative,
            side_share: if total > 0.0 {
                1.0 - plane / total
            } else {
                0.0
            },
        }
    }

    /// Launch of flake `n` of `count`, or `None` if no face lets snow in (a plane below
    /// every column with no inflow).
    pub fn start(&self, seed: u64, n: usize, count: usize) -> Option<Launch> {
        let total = *self.cumulative.last()?;
        let key = 3 * n as u64;
        let at = (n as f64 + uniform(seed, key, 0)) / count as f64 * total;
        let s = self
            .cumulative
            .partition_point(|&c| c <= at)
            .min(self.sites.len() - 1);
        let site = &self.sites[s];
        let (a, b) = (uniform(seed, key + 1, 0), uniform(seed, key + 2, 0));
        Some(Launch {
            position: std::array::from_fn(|d| {
                site.origin[d] + a * site.span[0][d] + b * site.span[1][d]
            }),
            velocity: site.velocity,
        })
    }
}
