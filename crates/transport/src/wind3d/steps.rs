//! The stages of a wind iteration: boundary set-up, RK4 semi-Lagrangian advection,
//! implicit viscosity, divergence and gradient subtraction (see the module docs).

use super::field::{Centred, Component, Lattice, Velocity};
use super::project::Poisson;
use super::stencil::{apply_row, rows};
use super::voxel::VoxelGrid;
use super::{Face, Wind3dParams, WindSolver};
use rayon::prelude::*;

/// Face kinds of the three components.
pub(super) fn face_kinds(g: &VoxelGrid, p: &Wind3dParams) -> [Vec<Face>; 3] {
    let [ux, uy] = p.inflow();
    let v = Velocity::zeros(g.nx, g.ny, g.nz);
    // A side's faces by the inflow's component into the domain across it: closed where
    // the wind runs parallel to the side (a symmetry plane) or the voxel is solid.
    let boundary = |solid: bool, inward: f64| {
        if solid || inward == 0.0 {
            Face::Closed
        } else if inward > 0.0 {
            Face::Inflow
        } else {
            Face::Outflow
        }
    };
    let mut ku = vec![Face::Fluid; v.u.data.len()];
    let mut kv = vec![Face::Fluid; v.v.data.len()];
    let mut kw = vec![Face::Fluid; v.w.data.len()];
    for k in 0..g.nz {
        for j in 0..g.ny {
            for i in 0..=g.nx {
                ku[v.u.index(i, j, k)] = if i == 0 {
                    boundary(g.is_solid(0, j, k), ux)
                } else if i == g.nx {
                    boundary(g.is_solid(g.nx - 1, j, k), -ux)
                } else if g.is_solid(i - 1, j, k) || g.is_solid(i, j, k) {
                    Face::Closed
                } else {
                    Face::Fluid
                };
            }
        }
        for j in 0..=g.ny {
            for i in 0..g.nx {
                kv[v.v.index(i, j, k)] = if j == 0 {
                    boundary(g.is_solid(i, 0, k), uy)
                } else if j == g.ny {
                    boundary(g.is_solid(i, g.ny - 1, k), -uy)
                } else if g.is_solid(i, j - 1, k) || g.is_solid(i, j, k) {
                    Face::Closed
                } else {
                    Face::Fluid
                };
            }
        }
    }
    for k in 0..=g.nz {
        for j in 0..g.ny {
            for i in 0..g.nx {
                kw[v.w.index(i, j, k)] =
                    if k == 0 || k == g.nz || g.is_solid(i, j, k - 1) || g.is_solid(i, j, k) {
                        Face::Closed
                    } else {
                        Face::Fluid
                    };
            }
        }
    }
    [ku, kv, kw]
}

/// The Poisson operator of the projection for these faces: each fluid voxel's count of
/// open (fluid or outflow) faces.
pub(super) fn poisson(g: &VoxelGrid, kinds: &[Vec<Face>; 3]) -> Poisson {
    let v = Velocity::zeros(g.nx, g.ny, g.nz);
    let mut diag = vec![0.0f32; g.len()];
    for k in 0..g.nz {
        for j in 0..g.ny {
            for i in 0..g.nx {
                let c = g.index(i, j, k);
                if g.solid[c] {
                    continue;
                }
                let faces = [
                    kinds[0][v.u.index(i, j, k)],
                    kinds[0][v.u.index(i + 1, j, k)],
                    kinds[1][v.v.index(i, j, k)],
                    kinds[1][v.v.index(i, j + 1, k)],
                    kinds[2][v.w.index(i, j, k)],
                    kinds[2][v.w.index(i, j, k + 1)],
                ];
                diag[c] = faces
                    .iter()
                    .filter(|f| matches!(f, Face::Fluid | Face::Outflow))
                    .count() as f32;
            }
        }
    }
    Poisson::new([g.nx, g.ny, g.nz], diag)
}

/// Outflow faces and the face just inside the domain each copies, per component.
pub(super) fn outflow_faces(g: &VoxelGrid, kinds: &[Vec<Face>; 3]) -> [Vec<(usize, usize)>; 3] {
    let v = Velocity::zeros(g.nx, g.ny, g.nz);
    std::array::from_fn(|axis| {
        let c = v.components()[axis];
        let d = c.dims;
        let stride = [1, d[0], d[0] * d[1]][axis];
        let mut faces = Vec::new();
        if d[axis] < 2 {
            return faces;
        }
        for k in 0..d[2] {
            for j in 0..d[1] {
                for i in 0..d[0] {
                    let id = c.index(i, j, k);
                    if kinds[axis][id] == Face::Outflow {
                        let inner = if [i, j, k][axis] == 0 {
                            id + stride
                        } else {
                            id - stride
                        };
                        faces.push((id, inner));
                    }
                }
            }
        }
        faces
    })
}

/// Inflow profile value of the horizontal component `comp` at a face of component `c`.
fn inflow_value(s: &WindSolver, c: &Component, comp: f64, i: usize, j: usize, k: usize) -> f32 {
    let g = &s.grid;
    let ci = i.min(g.nx - 1);
    let cj = j.min(g.ny - 1);
    let z = g.base + c.position(i, j, k)[2] * g.cell;
    let above = z - f64::from(g.column_top[cj * g.nx + ci]).max(g.base);
    let z0 = s.params.inflow_roughness_m;
    let factor = if above <= 0.0 {
        0.0
    } else if z0 == 0.0 {
        1.0
    } else {
        (above.max(z0) / z0).ln() / (s.params.reference_height_m / z0).ln()
    };
    (comp * factor) as f32
}

/// Sets every open face to the inflow profile and closed faces to 0.
pub(super) fn initialise(s: &mut WindSolver) {
    let [ux, uy] = s.params.inflow();
    let mut vel = s.velocity.clone();
    for (axis, comp) in [(0usize, ux), (1, uy)] {
        let c = if axis == 0 { &mut vel.u } else { &mut vel.v };
        let snapshot = c.clone();
        for k in 0..c.dims[2] {
            for j in 0..c.dims[1] {
                for i in 0..c.dims[0] {
                    let id = c.index(i, j, k);
                    c.data[id] = match s.kinds[axis][id] {
                        Face::Closed => 0.0,
                        _ => inflow_value(s, &snapshot, comp, i, j, k),
                    };
                }
            }
        }
    }
    vel.w.data.iter_mut().for_each(|w| *w = 0.0);
    s.velocity = vel;
}

/// Whether a face's velocity is computed (advected, diffused, projected).
#[inline(always)]
fn free(kind: Face) -> bool {
    matches!(kind, Face::Fluid | Face::Outflow)
}

/// Voxel centres back-traced together: independent traces interleave, hiding the latency
/// of each trace's chain of dependent samples.
const LANES: usize = 8;

/// RK4 displacement over `h` voxels per (m s⁻¹) of `LANES` voxel centres `p` whose
/// velocities are `k1` (3.13-3.14): `h (k1 + 2 k2 + 2 k3 + k4) / 6`, the departure point
/// being `p` minus it.
#[inline(always)]
fn displacement(
    centred: &Centred,
    p: &[[f32; 4]; LANES],
    k1: &[[f32; 4]; LANES],
    h: f32,
) -> [[f32; 4]; LANES] {
    // Four-lane arithmetic (the fourth lane is padding) so that each step is one vector op.
    #[inline(always)]
    fn axpy(q: [f32; 4], k: [f32; 4], f: f32) -> [f32; 4] {
        [
            q[0] + f * k[0],
            q[1] + f * k[1],
            q[2] + f * k[2],
            q[3] + f * k[3],
        ]
    }
    let mut sum = *k1;
    let mut q = [[0.0f32; 4]; LANES];
    for l in 0..LANES {
        q[l] = axpy(p[l], k1[l], -0.5 * h);
    }
    for (weight, reach) in [(2.0, 0.5), (2.0, 1.0), (1.0, 0.0)] {
        let mut k = [[0.0f32; 4]; LANES];
        for l in 0..LANES {
            k[l] = centred.sample4(q[l]);
        }
        for l in 0..LANES {
            sum[l] = axpy(sum[l], k[l], weight);
            q[l] = axpy(p[l], k[l], -reach * h);
        }
    }
    let f = h / 6.0;
    let mut out = [[0.0f32; 4]; LANES];
    for l in 0..LANES {
        out[l] = [f * sum[l][0], f * sum[l][1], f * sum[l][2], 0.0];
    }
    out
}

/// The RK4 displacement `x − x_departure` of every voxel centre, voxel units.
fn trace_centres(centred: &Centred, h: f32, out: &mut Vec<[f32; 4]>) {
    let [nx, ny, nz] = centred.dims;
    out.resize(nx * ny * nz, [0.0; 4]);
    out.par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(k, slice)| {
            let z = k as f32 + 0.5;
            for j in 0..ny {
                let start = (k * ny + j) * nx;
                let row = &mut slice[j * nx..(j + 1) * nx];
                for i0 in (0..nx).step_by(LANES) {
                    let lanes = LANES.min(nx - i0);
                    let mut p = [[0.5, j as f32 + 0.5, z, 0.0]; LANES];
                    let mut k1 = [[0.0f32; 4]; LANES];
                    for l in 0..lanes {
                        p[l][0] = (i0 + l) as f32 + 0.5;
                        k1[l] = centred.data[start + i0 + l];
                    }
                    let d = displacement(centred, &p, &k1, h);
                    row[i0..i0 + lanes].copy_from_slice(&d[..lanes]);
                }
            }
        });
}

/// Semi-Lagrangian advection with an RK4 back-trace (3.12-3.14, Fig. 3.1). The trace
/// runs from each voxel centre through the velocity averaged to the voxel centres; a
/// face's departure point is its position minus the mean displacement of the two voxels it
/// separates (the one voxel at a domain side), and the advected value is interpolated
/// there on the face's own staggered grid.
pub(super) fn advect(s: &mut WindSolver) {
    // The advected field overwrites every free face; the other faces hold the same fixed
    // values in both buffers (0 or the inflow profile), so a swap replaces a copy.
    std::mem::swap(&mut s.previous, &mut s.velocity);
    s.centred.update(&s.previous);
    let h = (s.dt / s.grid.cell) as f32; // voxels per (m/s)
    trace_centres(&s.centred, h, &mut s.displacement);
    let disp = &s.displacement;
    let g = &s.grid;
    let (nx, ny, nz) = (g.nx, g.ny, g.nz);
    let prev = &s.previous;
    let comps = [&mut s.velocity.u, &mut s.velocity.v, &mut s.velocity.w];
    for (axis, c) in comps.into_iter().enumerate() {
        let src = prev.components()[axis];
        let lattice = Lattice::new(src.dims, src.offset);
        let kinds = &s.kinds[axis];
        let (dims, offset) = (c.dims, c.offset.map(|o| o as f32));
        let slice = dims[0] * dims[1];
        c.data
            .par_chunks_mut(slice)
            .enumerate()
            .for_each(|(k, out)| {
                let z = k as f32 + offset[2];
                for j in 0..dims[1] {
                    let y = j as f32 + offset[1];
                    let row = j * dims[0];
                    let krow = &kinds[k * slice + row..k * slice + row + dims[0]];
                    let orow = &mut out[row..row + dims[0]];
                    // The voxel rows on the − and + sides of this row of faces.
                    let centre_row = |jj: usize, kk: usize| {
                        let s = (kk.min(nz - 1) * ny + jj.min(ny - 1)) * nx;
                        &disp[s..s + nx]
                    };
                    let (minus, plus) = match axis {
                        0 => (centre_row(j, k), centre_row(j, k)),
                        1 => (centre_row(j.saturating_sub(1), k), centre_row(j, k)),
                        _ => (centre_row(j, k.saturating_sub(1)), centre_row(j, k)),
                    };
                    for (i, (o, kind)) in orow.iter_mut().zip(krow).enumerate() {
                        if !free(*kind) {
                            continue;
                        }
                        let (a, b) = if axis == 0 {
                            (minus[i.saturating_sub(1)], plus[i.min(nx - 1)])
                        } else {
                            (minus[i], plus[i])
                        };
                        let p = [
                            i as f32 + offset[0] - 0.5 * (a[0] + b[0]),
                            y - 0.5 * (a[1] + b[1]),
                            z - 0.5 * (a[2] + b[2]),
                        ];
                        *o = lattice.sample(&src.data, p);
                    }
                }
            });
    }
    for (c, faces) in [&mut s.velocity.u, &mut s.velocity.v, &mut s.velocity.w]
        .into_iter()
        .zip(&s.outflow)
    {
        // Outflow faces copy the face just inside the domain (zero gradient).
        for &(id, inner) in faces {
            c.data[id] = c.data[inner];
        }
    }
}

/// Implicit viscosity `(I − α ∇²) u_new = u`, `α = ν Δt / Δ²` (3.15-3.16), by Jacobi sweeps
/// until the error is below 1e-6 of the wind speed (at most 50 sweeps). Each face averages
/// with its neighbours on its own staggered grid (those beyond the grid are left out).
/// Jacobi contracts the error by `q = 6α / (1 + 6α)` per sweep, so after a sweep that
/// changed no value by more than `δ` the error is at most `δ q / (1 − q)`: for the small
/// `α` of a wind one sweep is usually enough.
pub(super) fn diffuse(s: &mut WindSolver) {
    let alpha = (s.params.viscosity_m2_s * s.dt / (s.grid.cell * s.grid.cell)) as f32;
    if alpha == 0.0 {
        return;
    }
    let tol = (1e-6 * s.params.speed_m_s.max(1e-6)) as f32;
    let q = 6.0 * alpha / (1.0 + 6.0 * alpha);
    let error_bound = q / (1.0 - q);
    let comps = [&mut s.velocity.u, &mut s.velocity.v, &mut s.velocity.w];
    let bufs = [&mut s.previous.u, &mut s.previous.v, &mut s.previous.w];
    for (axis, (c, buf)) in comps.into_iter().zip(bufs).enumerate() {
        let kinds = &s.kinds[axis];
        let d = c.dims;
        let slice = d[0] * d[1];
        let zeros = vec![0.0f32; d[0]];
        // The right-hand side: the advected field, kept aside only if a second sweep runs.
        let mut rhs: Option<Vec<f32>> = None;
        for sweep in 0..50 {
            let x = &c.data;
            let rhs_now: &[f32] = rhs.as_deref().unwrap_or(x);
            let change = buf
                .data
                .par_chunks_mut(slice)
                .enumerate()
                .map(|(k, out)| {
                    let mut change = 0.0f32;
                    for j in 0..d[1] {
                        let start = k * slice + j * d[0];
                        let r = rows(x, d, j, k, &zeros);
                        // Neighbours inside the grid: two along the row (one at its ends).
                        let across = [j > 0, j + 1 < d[1], k > 0, k + 1 < d[2]]
                            .iter()
                            .filter(|&&b| b)
                            .count() as f32;
                        let orow = &mut out[j * d[0]..(j + 1) * d[0]];
                        let (krow, brow) =
                            (&kinds[start..start + d[0]], &rhs_now[start..start + d[0]]);
                        let xrow = r.centre;
                        apply_row(&zeros, None, &r, orow);
                        let last = d[0] - 1;
                        for (i, ((o, x), (b, kind))) in orow
                            .iter_mut()
                            .zip(xrow)
                            .zip(brow.iter().zip(krow))
                            .enumerate()
                        {
                            // −Σ neighbours is in `o`; two neighbours along the row
                            // (one at its ends).
                            let along = if i == 0 || i == last { 1.0 } else { 2.0 };
                            let n = across + along - if last == 0 { 1.0 } else { 0.0 };
                            let new = (b - alpha * *o) / (1.0 + alpha * n);
                            let keep = free(*kind);
                            if keep {
                                change = change.max((new - x).abs());
                            }
                            *o = if keep { new } else { *x };
                        }
                    }
                    change
                })
                .reduce(|| 0.0, f32::max);
            std::mem::swap(&mut c.data, &mut buf.data);
            if change * error_bound < tol {
                break;
            }
            if sweep == 0 {
                rhs = Some(buf.data.clone());
            }
        }
    }
}

/// `scale` times the divergence of `vel` in every fluid voxel into `out`, s⁻¹ (0 in solids).
pub(super) fn divergence(g: &VoxelGrid, vel: &Velocity, scale: f64, out: &mut [f64]) {
    let (u, v, w) = (&vel.u, &vel.v, &vel.w);
    let inv = scale / g.cell;
    let (nx, ny) = (g.nx, g.ny);
    out.par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(k, out)| {
            for j in 0..ny {
                let cells = g.index(0, j, k);
                let solid = &g.solid[cells..cells + nx];
                let ur = &u.data[u.index(0, j, k)..u.index(0, j, k) + nx + 1];
                let vs = &v.data[v.index(0, j, k)..v.index(0, j, k) + nx];
                let vn = &v.data[v.index(0, j + 1, k)..v.index(0, j + 1, k) + nx];
                let wd = &w.data[w.index(0, j, k)..w.index(0, j, k) + nx];
                let wu = &w.data[w.index(0, j, k + 1)..w.index(0, j, k + 1) + nx];
                for (i, o) in out[j * nx..(j + 1) * nx].iter_mut().enumerate() {
                    let du = f64::from(ur[i + 1]) - f64::from(ur[i]);
                    let dv = f64::from(vn[i]) - f64::from(vs[i]);
                    let dw = f64::from(wu[i]) - f64::from(wd[i]);
                    *o = if solid[i] { 0.0 } else { (du + dv + dw) * inv };
                }
            }
        });
}

/// `u −= ∇φ / Δ` on fluid and outflow faces (`φ = 0` beyond outflow faces).
pub(super) fn subtract_gradient(
    g: &VoxelGrid,
    kinds: &[Vec<Face>; 3],
    phi: &[f64],
    vel: &mut Velocity,
) {
    let inv = 1.0 / g.cell;
    let (nx, ny, nz) = (g.nx, g.ny, g.nz);
    let zeros = vec![0.0f64; nx];
    // The φ row of cell row (j, k), or zeros beyond the grid.
    let phi_row = |j: usize, k: usize| -> &[f64] {
        if j < ny && k < nz {
            &phi[g.index(0, j, k)..g.index(0, j, k) + nx]
        } else {
            &zeros
        }
    };
    let comps = [&mut vel.u, &mut vel.v, &mut vel.w];
    for (axis, c) in comps.into_iter().enumerate() {
        let d = c.dims;
        let kinds = &kinds[axis];
        let slice = d[0] * d[1];
        c.data
            .par_chunks_mut(slice)
            .enumerate()
            .for_each(|(k, out)| {
                for j in 0..d[1] {
                    let start = k * slice + j * d[0];
                    let krow = &kinds[start..start + d[0]];
                    let orow = &mut out[j * d[0]..(j + 1) * d[0]];
                    // φ on the + and − side of each face of the row.
                    let (plus, minus): (&[f64], &[f64]) = match axis {
                        0 => (phi_row(j, k), phi_row(j, k)),
                        1 => (
                            phi_row(j, k),
                            j.checked_sub(1).map_or(&zeros[..], |jm| phi_row(jm, k)),
                        ),
                        _ => (
                            phi_row(j, k),
                            k.checked_sub(1).map_or(&zeros[..], |km| phi_row(j, km)),
                        ),
                    };
                    for (i, o) in orow.iter_mut().enumerate() {
                        if !free(krow[i]) {
                            continue;
                        }
                        let grad = if axis == 0 {
                            let p = if i < nx { plus[i] } else { 0.0 };
                            let m = if i > 0 { minus[i - 1] } else { 0.0 };
                            p - m
                        } else {
                            plus[i] - minus[i]
                        };
                        *o -= (grad * inv) as f32;
                    }
                }
            });
    }
}
