//! Precipitation map (Jubert 2018, Chapter 4 and Section 6.4): snowflakes released above
//! the scene fall through the mean wind; the share of them landing on each column, cleaned
//! of outliers and smoothed, scales the snowfall of the transport (Eq. 5.16).
//!
//! **Flakes** are spheres of radius `r` and density `ρf` (4.1-4.4): gravity `M g`, and the
//! air's drag on the exposed hemisphere `A_p = 2π r²` (4.1). The thesis writes the drag as a
//! wind push `½ ρa |v_wind|² A_p` (4.3) plus a friction `½ ρa |v_t|² C_f A_p` (4.2); these
//! are the two limits (flake at rest, still air) of the drag on the velocity relative to the
//! air, `F = ½ ρa C_f A_p |v_wind − v| (v_wind − v)`, which is used here so that a flake
//! drifts with the wind and falls at its terminal speed `√(g / k)`,
//! `k = ½ ρa C_f A_p / M = 3 ρa C_f / (4 r ρf)`. The update is the Euler scheme of
//! 4.5-4.7 with the drag taken implicitly in `v` (`|v_rel|` lagged), stable for any `Δt`,
//! with `Δt` one voxel of travel.
//!
//! **Launch** (Fig. 6.5): flakes are released uniformly on a plane at height `h` (the
//! user's parameter: here a clearance above the highest surface). The thesis launches them
//! over a window upwind of the domain; here the plane is folded onto the domain's faces
//! ([`launch`]): the plane over the domain, and the upwind side faces below it, through
//! which the inflow carries the snow released upwind, each in proportion to its flux.
//!
//! **Collisions** (4.3): entering a solid voxel through its top (the voxel above is free)
//! lands the flake on that column; entering through a side, the flake slides: the velocity
//! component normal to the face is dropped and it continues along the face. A flake still
//! blocked after sliding drops to the base of the obstacle, on its own column (Section
//! 6.4: "la neige qui frappe un voxel ... tombe directement dans la cellule à sa base").
//!
//! A flake that leaves the domain across a side is lost (the snow entering through the
//! sides is already counted by the launch).
//!
//! **Map** (6.4): counts per column divided by their mean give the ratio map (mean 1).
//! Outliers (IQR rule, `1.5 (Q3 − Q1)` from the mean) are replaced by the mean of their
//! non-outlier 8-neighbours where those are more than half, repeatedly. Only *high*
//! outliers are flagged here: the thesis's aim is the spikes of flakes piled at the foot of
//! walls, and flagging low values too would let the repeated replacement fill the sheltered
//! lee, which must stay thin. Finally an 11 × 11 Gaussian (σ = 2 cells) smooths the map.
//!
//! **Determinism**: flake `n` draws its launch point from the counter-based generator keyed
//! by `(seed, n)`, and counts are integers: the map does not depend on the thread count.

mod launch;

use crate::error::{TransportError, check_positive, check_range};
use crate::physics::GRAVITY;
use crate::wind3d::field::{Centred, Velocity};
use crate::wind3d::voxel::VoxelGrid;
use launch::{Launch, Launcher};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Parameters of the flake simulation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FlakeParams {
    /// Number of flakes released. Section 6.4 uses 10 million for a 1000² map; default
    /// 1 million.
    pub count: usize,
    /// Seed of the launch points.
    pub seed: u64,
    /// Flake radius `r`, mm (4.1). Chosen here: 2 mm.
    pub radius_mm: f64,
    /// Flake density `ρf`, kg m⁻³. Chosen here: 22, which with `r` = 2 mm gives the ≈ 1 m s⁻¹
    /// fall speed of dry snowflakes.
    pub flake_density: f64,
    /// Drag ("friction") coefficient `C_f` (4.2). Section 4.2: 0.47, a sphere.
    pub drag_coefficient: f64,
    /// Air density `ρa`, kg m⁻³ (4.2-4.3). Section 4.2: 1.225.
    pub air_density: f64,
    /// Height of the launch plane above the highest surface of the scene, m (Section 6.4:
    /// "une hauteur h laissée en paramètre"). Chosen here: 50 m; capped at the grid's top.
    pub launch_clearance_m: f64,
    /// Most steps (each about one voxel of travel) of one flake before it is abandoned as
    /// lost. Chosen here: 20 000, twenty times the fall through 80 voxels with a wind ten
    /// times the fall speed; flakes held aloft by updrafts stronger than their fall speed
    /// (over ridges) would otherwise fly on for ever.
    pub max_steps: usize,
}

impl Default for FlakeParams {
    fn default() -> Self {
        Self {
            count: 1_000_000,
            seed: 1,
            radius_mm: 2.0,
            flake_density: 22.0,
            drag_coefficient: 0.47,
            air_density: 1.225,
            launch_clearance_m: 50.0,
            max_steps: 20_000,
        }
    }
}

impl FlakeParams {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), TransportError> {
        check_range("count", self.count as f64, 1.0, 1e10)?;
        check_positive("radius_mm", self.radius_mm)?;
        check_positive("flake_density", self.flake_density)?;
        check_positive("drag_coefficient", self.drag_coefficient)?;
        check_positive("air_density", self.air_density)?;
        check_positive("launch_clearance_m", self.launch_clearance_m)?;
        check_range("max_steps", self.max_steps as f64, 1.0, 1e9)?;
        Ok(())
    }

    /// Drag constant `k = 3 ρa C_f / (4 r ρf)`, m⁻¹.
    pub fn drag_constant(&self) -> f64 {
        3.0 * self.air_density * self.drag_coefficient
            / (4.0 * self.radius_mm * 1e-3 * self.flake_density)
    }

    /// Terminal fall speed in still air `√(g / k)`, m s⁻¹.
    pub fn terminal_speed(&self) -> f64 {
        (GRAVITY / self.drag_constant()).sqrt()
    }
}

/// What became of the flakes of a precipitation map.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct FlakeSummary {
    /// Flakes that landed in the domain.
    pub landed: u64,
    /// Flakes that missed it (blown out across a side) or were abandoned.
    pub lost: u64,
    /// Share of the launched flakes that entered across the upwind sides rather than from
    /// the launch plane over the domain ([`launch`]).
    pub side_share: f64,
}

/// A precipitation map on the voxel columns (`nx × ny`, row 0 at the north).
#[derive(Debug, Clone, PartialEq)]
pub struct PrecipitationMap {
    /// Columns along x.
    pub width: usize,
    /// Columns along y.
    pub height: usize,
    /// Share of the mean snowfall each column receives (mean ≈ 1).
    pub ratio: Vec<f32>,
    /// Flakes landed on each column, before filtering.
    pub counts: Vec<u32>,
    /// What became of the flakes.
    pub flakes: FlakeSummary,
    /// Columns replaced as outliers.
    pub outliers: usize,
}

/// What a flake did.
enum Fate {
    Landed(usize),
    Lost,
}

/// The flake's equation of motion (4.5-4.7): gravity and the drag on the velocity
/// relative to the air, Euler steps of one voxel of travel with the drag implicit in `v`.
#[derive(Debug, Clone, Copy)]
struct Drag {
    /// Drag constant `k`, m⁻¹.
    k: f64,
    /// Terminal speed `√(g / k)`, m s⁻¹.
    vt: f64,
    /// Voxel side, m.
    cell: f64,
}

impl Drag {
    /// Advances `v` (m s⁻¹) by one step in the wind `w`; returns the step's `Δt` per voxel
    /// (s m⁻¹ times the voxel side: the position advances by that times `v`, in voxels).
    #[inline]
    fn step(&self, w: [f64; 3], v: &mut [f64; 3]) -> f64 {
        let rel = [w[0] - v[0], w[1] - v[1], w[2] - v[2]];
        let s = self.k * (rel[0] * rel[0] + rel[1] * rel[1] + rel[2] * rel[2]).sqrt();
        // Δt of one voxel of travel, and Δt in voxels per (m s⁻¹).
        let per_voxel = 1.0 / ((w[0] * w[0] + w[1] * w[1]).sqrt() + self.vt + 1e-3);
        let dt = self.cell * per_voxel;
        let implicit = 1.0 / (1.0 + dt * s);
        let g = [0.0, 0.0, -GRAVITY];
        for a in 0..3 {
            v[a] = (v[a] + dt * (s * w[a] + g[a])) * implicit;
        }
        per_voxel
    }
}

/// What the flakes fly through.
struct Sky<'a> {
    grid: &'a VoxelGrid,
    wind: &'a Centred,
    /// Solid layers of each column (voxelised scenes are solid below their top).
    layers: &'a [u32],
    drag: Drag,
    max_steps: usize,
}

/// One flake from launch to landing (4.5-4.7, 4.3).
fn fly(sky: &Sky, launch: Launch) -> Fate {
    let (grid, wind, layers) = (sky.grid, sky.wind, sky.layers);
    let (nx, ny, nz) = (grid.nx as f64, grid.ny as f64, grid.nz as f64);
    let inside = |x: [f64; 3]| x[0] >= 0.0 && x[1] >= 0.0 && x[0] < nx && x[1] < ny;
    let column = |x: [f64; 3]| (x[1] as usize) * grid.nx + x[0] as usize;
    // Lands where the step x → next crosses the plane z = face, if that is on the domain.
    let land = |x: [f64; 3], next: [f64; 3], face: f64| {
        let f = ((x[2] - face) / (x[2] - next[2])).clamp(0.0, 1.0);
        let at = [
            x[0] + f * (next[0] - x[0]),
            x[1] + f * (next[1] - x[1]),
            face,
        ];
        if inside(at) {
            Fate::Landed(column(at))
        } else {
            Fate::Lost
        }
    };
    let sample = |x: [f64; 3]| {
        let w = wind.sample([x[0] as f32, x[1] as f32, x[2] as f32]);
        [f64::from(w[0]), f64::from(w[1]), f64::from(w[2])]
    };
    let mut x = launch.position; // voxel units
    let mut v = launch.velocity.unwrap_or_else(|| {
        let w = sample(x);
        [w[0], w[1], w[2] - sky.drag.vt]
    });
    for _ in 0..sky.max_steps {
        let per_voxel = sky.drag.step(sample(x), &mut v);
        let advance = |x: [f64; 3], v: [f64; 3]| {
            [
                x[0] + per_voxel * v[0],
                x[1] + per_voxel * v[1],
                x[2] + per_voxel * v[2],
            ]
        };
        let next = advance(x, v);
        if !inside(next) {
            let top = f64::from(layers[column(x)]);
            return if next[2] < top {
                land(x, next, top)
            } else {
                Fate::Lost
            };
        }
        if next[2] < 0.0 {
            return land(x, next, 0.0);
        }
        let (i, j, kk) = (next[0] as usize, next[1] as usize, next[2] as usize);
        if next[2] < nz && grid.is_solid(i, j, kk) {
            let face = (kk + 1) as f64;
            let top_free = kk + 1 >= grid.nz || !grid.is_solid(i, j, kk + 1);
            if top_free && x[2] >= face {
                return land(x, next, face);
            }
            // Slide along the side faces crossed: drop the velocity across them.
            let old = [x[0].floor(), x[1].floor()];
            for a in 0..2 {
                if [i as f64, j as f64][a] != old[a] {
                    v[a] = 0.0;
                }
            }
            let slid = advance(x, v);
            let blocked = !inside(slid)
                || (slid[2] >= 0.0
                    && slid[2] < nz
                    && grid.is_solid(slid[0] as usize, slid[1] as usize, slid[2] as usize));
            if blocked {
                // Drop to the base of the obstacle, on the flake's own column.
                return if inside(x) {
                    Fate::Landed(column(x))
                } else {
                    Fate::Lost
                };
            }
            x = slid;
            continue;
        }
        x = next;
    }
    Fate::Lost
}

/// Simulates the flakes through the mean wind `wind` over `grid` and builds the map;
/// `inflow` is the wind (east, north, m s⁻¹) the wind simulation held on its upwind sides
/// ([`crate::wind3d::Wind3dParams::inflow`]): snow enters across those sides.
pub fn precipitation_map(
    grid: &VoxelGrid,
    wind: &Velocity,
    inflow: [f64; 2],
    params: &FlakeParams,
) -> Result<PrecipitationMap, TransportError> {
    params.validate()?;
    let mut centred = Centred::default();
    centred.update(wind);
    let vt = params.terminal_speed();
    // Launch plane (Fig. 6.5) and the faces it folds onto.
    let highest = grid
        .column_top
        .iter()
        .fold(f32::NEG_INFINITY, |m, &t| m.max(t));
    let top = ((f64::from(highest) - grid.base + params.launch_clearance_m) / grid.cell)
        .min(grid.nz as f64 - 0.5);
    let drag = Drag {
        k: params.drag_constant(),
        vt,
        cell: grid.cell,
    };
    let columns = grid.nx * grid.ny;
    let layers: Vec<u32> = (0..columns)
        .map(|c| grid.ground_layers(c % grid.nx, c / grid.nx) as u32)
        .collect();
    let launcher = Launcher::new(grid, &layers, &centred, &drag, inflow, top);
    let sky = Sky {
        grid,
        wind: &centred,
        layers: &layers,
        drag,
        max_steps: params.max_steps,
    };
    let fly_range = |count: usize| -> Vec<(Vec<u32>, u64)> {
        const CHUNK: usize = 4096;
        (0..count.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut counts = vec![0u32; columns];
                let mut lost = 0u64;
                for n in c * CHUNK..((c + 1) * CHUNK).min(count) {
                    match launcher.start(params.seed, n, count).map(|s| fly(&sky, s)) {
                        Some(Fate::Landed(col)) => counts[col] += 1,
                        _ => lost += 1,
                    }
                }
                (counts, lost)
            })
            .collect()
    };
    let partial = fly_range(params.count);
    let mut counts = vec![0u32; columns];
    let mut lost = 0u64;
    for (c, l) in &partial {
        counts.iter_mut().zip(c).for_each(|(a, b)| *a += b);
        lost += l;
    }
    let landed: u64 = counts.iter().map(|&c| u64::from(c)).sum();
    let mean = landed as f64 / columns as f64;
    // Row 0 at the north.
    let mut ratio = vec![0.0f32; columns];
    let mut counts_north = vec![0u32; columns];
    for j in 0..grid.ny {
        for i in 0..grid.nx {
            let src = j * grid.nx + i;
            let dst = (grid.ny - 1 - j) * grid.nx + i;
            counts_north[dst] = counts[src];
            ratio[dst] = if mean > 0.0 {
                (f64::from(counts[src]) / mean) as f32
            } else {
                0.0
            };
        }
    }
    let outliers = replace_outliers(&mut ratio, grid.nx, grid.ny);
    let ratio = gaussian_11(&ratio, grid.nx, grid.ny, 2.0);
    Ok(PrecipitationMap {
        width: grid.nx,
        height: grid.ny,
        ratio,
        counts: counts_north,
        flakes: FlakeSummary {
            landed,
            lost,
            side_share: launcher.side_share,
        },
        outliers,
    })
}

/// Quartile `q` of `values` (nearest rank).
fn quantile(sorted: &[f32], q: f64) -> f32 {
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

/// Replaces high outliers (IQR rule) by the mean of their valid 8-neighbours where those
/// are more than half of them, repeatedly; returns how many cells were replaced.
pub fn replace_outliers(ratio: &mut [f32], w: usize, h: usize) -> usize {
    let mut sorted = ratio.to_vec();
    sorted.sort_by(f32::total_cmp);
    let (q1, q3) = (quantile(&sorted, 0.25), quantile(&sorted, 0.75));
    let iqr = 1.5 * (q3 - q1);
    let mean = ratio.iter().map(|&r| f64::from(r)).sum::<f64>() / ratio.len() as f64;
    let mut outlier: Vec<bool> = ratio
        .iter()
        .map(|&r| f64::from(r) - mean > f64::from(iqr))
        .collect();
    let flagged = outlier.iter().filter(|&&o| o).count();
    loop {
        let mut changed = Vec::new();
        for r in 0..h {
            for c in 0..w {
                if !outlier[r * w + c] {
                    continue;
                }
                let (mut sum, mut good, mut all) = (0.0f32, 0usize, 0usize);
                for dr in -1isize..=1 {
                    for dc in -1isize..=1 {
                        let (rr, cc) = (r as isize + dr, c as isize + dc);
                        if (dr, dc) == (0, 0)
                            || rr < 0
                            || cc < 0
                            || rr >= h as isize
                            || cc >= w as isize
                        {
                            continue;
                        }
                        let j = rr as usize * w + cc as usize;
                        all += 1;
                        if !outlier[j] {
                            good += 1;
                            sum += ratio[j];
                        }
                    }
                }
                if 2 * good > all {
                    changed.push((r * w + c, sum / good as f32));
                }
            }
        }
        if changed.is_empty() {
            break;
        }
        for (i, v) in changed {
            ratio[i] = v;
            outlier[i] = false;
        }
    }
    flagged - outlier.iter().filter(|&&o| o).count()
}

/// An 11 × 11 Gaussian filter of standard deviation `sigma` cells, renormalised at the
/// borders (separable).
pub fn gaussian_11(values: &[f32], w: usize, h: usize, sigma: f64) -> Vec<f32> {
    let kernel: Vec<f64> = (-5..=5)
        .map(|d: i32| (-(f64::from(d * d)) / (2.0 * sigma * sigma)).exp())
        .collect();
    let pass = |src: &[f32], horizontal: bool| -> Vec<f32> {
        let mut out = vec![0.0f32; w * h];
        out.par_chunks_mut(w).enumerate().for_each(|(r, row)| {
            for (c, o) in row.iter_mut().enumerate() {
                let (mut s, mut n) = (0.0f64, 0.0f64);
                for (t, kv) in kernel.iter().enumerate() {
                    let d = t as isize - 5;
                    let (rr, cc) = if horizontal {
                        (r as isize, c as isize + d)
                    } else {
                        (r as isize + d, c as isize)
                    };
                    if rr >= 0 && cc >= 0 && (rr as usize) < h && (cc as usize) < w {
                        s += kv * f64::from(src[rr as usize * w + cc as usize]);
                        n += kv;
                    }
                }
                *o = (s / n) as f32;
            }
        });
        out
    };
    pass(&pass(values, true), false)
}

#[cfg(test)]
mod tests;
