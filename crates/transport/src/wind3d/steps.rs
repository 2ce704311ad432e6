//! The stages of a wind iteration: boundary set-up, RK4 semi-Lagrangian advection,
//! implicit viscosity, divergence and gradient subtraction (see the module docs).

use super::field::{Component, Velocity};
use super::project::Poisson;
use super::voxel::VoxelGrid;
use super::{Face, WindParams, WindSolver};
use rayon::prelude::*;

/// Face kinds of the three components.
pub(super) fn face_kinds(g: &VoxelGrid, p: &WindParams) -> [Vec<Face>; 3] {
    let [ux, uy] = p.inflow();
    let v = Velocity::zeros(g.nx, g.ny, g.nz);
    let boundary = |solid: bool, inflow_here: bool| match (solid, inflow_here) {
        (true, _) => Face::Closed,
        (false, true) => Face::Inflow,
        (false, false) => Face::Outflow,
    };
    let mut ku = vec![Face::Fluid; v.u.data.len()];
    let mut kv = vec![Face::Fluid; v.v.data.len()];
    let mut kw = vec![Face::Fluid; v.w.data.len()];
    for k in 0..g.nz {
        for j in 0..g.ny {
            for i in 0..=g.nx {
                ku[v.u.index(i, j, k)] = if i == 0 {
                    boundary(g.is_solid(0, j, k), ux > 0.0)
                } else if i == g.nx {
                    boundary(g.is_solid(g.nx - 1, j, k), ux < 0.0)
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
                    boundary(g.is_solid(i, 0, k), uy > 0.0)
                } else if j == g.ny {
                    boundary(g.is_solid(i, g.ny - 1, k), uy < 0.0)
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

/// The Poisson operator of the projection for these faces.
pub(super) fn poisson(g: &VoxelGrid, kinds: &[Vec<Face>; 3]) -> Poisson {
    let v = Velocity::zeros(g.nx, g.ny, g.nz);
    let mut diag = vec![0u8; g.len()];
    let mut couple = vec![0u8; g.len()];
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
                for (d, f) in faces.iter().enumerate() {
                    match f {
                        Face::Fluid => {
                            diag[c] += 1;
                            couple[c] |= 1 << d;
                        }
                        Face::Outflow => diag[c] += 1,
                        Face::Closed | Face::Inflow => {}
                    }
                }
            }
        }
    }
    Poisson {
        nx: g.nx,
        slice: g.nx * g.ny,
        multigrid: super::multigrid::Multigrid::new([g.nx, g.ny, g.nz], &diag, &couple),
        diag,
        couple,
    }
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

/// Semi-Lagrangian advection with an RK4 back-trace (3.12-3.14, Fig. 3.1). The trace
/// runs through the velocity averaged to the voxel centres; the advected value is then
/// interpolated on the face's own staggered grid.
pub(super) fn advect(s: &mut WindSolver) {
    for (dst, src) in [
        (&mut s.previous.u, &s.velocity.u),
        (&mut s.previous.v, &s.velocity.v),
        (&mut s.previous.w, &s.velocity.w),
    ] {
        dst.data.copy_from_slice(&src.data);
    }
    s.centred.update(&s.previous);
    let h = (s.dt / s.grid.cell) as f32; // voxels per (m/s)
    let centred = &s.centred;
    let trace = |p: [f32; 3]| {
        let at =
            |q: [f32; 3], k: [f32; 3], f: f32| [q[0] - f * k[0], q[1] - f * k[1], q[2] - f * k[2]];
        let k1 = centred.sample(p);
        let k2 = centred.sample(at(p, k1, 0.5 * h));
        let k3 = centred.sample(at(p, k2, 0.5 * h));
        let k4 = centred.sample(at(p, k3, h));
        let mean: [f32; 3] =
            std::array::from_fn(|a| (k1[a] + 2.0 * k2[a] + 2.0 * k3[a] + k4[a]) / 6.0);
        at(p, mean, h)
    };
    let prev = &s.previous;
    let comps = [&mut s.velocity.u, &mut s.velocity.v, &mut s.velocity.w];
    for (axis, c) in comps.into_iter().enumerate() {
        let src = prev.components()[axis];
        let kinds = &s.kinds[axis];
        let (dims, offset) = (c.dims, c.offset);
        let slice = dims[0] * dims[1];
        c.data
            .par_chunks_mut(slice)
            .enumerate()
            .for_each(|(k, out)| {
                for j in 0..dims[1] {
                    for i in 0..dims[0] {
                        let o = j * dims[0] + i;
                        if matches!(kinds[k * slice + o], Face::Fluid | Face::Outflow) {
                            let p = [
                                (i as f64 + offset[0]) as f32,
                                (j as f64 + offset[1]) as f32,
                                (k as f64 + offset[2]) as f32,
                            ];
                            let b = trace(p);
                            out[o] = src.sample([f64::from(b[0]), f64::from(b[1]), f64::from(b[2])])
                                as f32;
                        }
                    }
                }
            });
    }
    extrapolate_outflow(s);
}

/// Outflow faces copy the face just inside the domain (zero gradient).
fn extrapolate_outflow(s: &mut WindSolver) {
    let comps = [&mut s.velocity.u, &mut s.velocity.v, &mut s.velocity.w];
    for (axis, c) in comps.into_iter().enumerate() {
        let d = c.dims;
        let stride = [1, d[0], d[0] * d[1]][axis];
        for k in 0..d[2] {
            for j in 0..d[1] {
                for i in 0..d[0] {
                    let id = c.index(i, j, k);
                    if s.kinds[axis][id] != Face::Outflow {
                        continue;
                    }
                    let at_min = [i, j, k][axis] == 0;
                    let inner = if at_min { id + stride } else { id - stride };
                    if d[axis] > 1 {
                        c.data[id] = c.data[inner];
                    }
                }
            }
        }
    }
}

/// Implicit viscosity `(I − α ∇²) u_new = u`, `α = ν Δt / Δ²` (3.15-3.16), by Jacobi sweeps
/// until the largest update is below 1e-6 of the wind speed (at most 50 sweeps).
pub(super) fn diffuse(s: &mut WindSolver) {
    let alpha = s.params.viscosity_m2_s * s.dt / (s.grid.cell * s.grid.cell);
    if alpha == 0.0 {
        return;
    }
    let tol = 1e-6 * s.params.speed_m_s.max(1e-6);
    let comps = [&mut s.velocity.u, &mut s.velocity.v, &mut s.velocity.w];
    let bufs = [&mut s.previous.u, &mut s.previous.v, &mut s.previous.w];
    for (axis, (c, buf)) in comps.into_iter().zip(bufs).enumerate() {
        let rhs = c.data.clone();
        let kinds = &s.kinds[axis];
        let d = c.dims;
        let slice = d[0] * d[1];
        for _ in 0..50 {
            let x = &c.data;
            let change = buf
                .data
                .par_chunks_mut(slice)
                .enumerate()
                .map(|(k, out)| {
                    let mut change = 0.0f64;
                    for j in 0..d[1] {
                        for i in 0..d[0] {
                            let id = k * slice + j * d[0] + i;
                            let o = j * d[0] + i;
                            if !matches!(kinds[id], Face::Fluid | Face::Outflow) {
                                out[o] = x[id];
                                continue;
                            }
                            let mut sum = 0.0f64;
                            let mut n = 0.0f64;
                            let mut add = |ok: bool, nb: usize| {
                                if ok {
                                    sum += f64::from(x[nb]);
                                    n += 1.0;
                                }
                            };
                            add(i > 0, id.wrapping_sub(1));
                            add(i + 1 < d[0], id + 1);
                            add(j > 0, id.wrapping_sub(d[0]));
                            add(j + 1 < d[1], id + d[0]);
                            add(k > 0, id.wrapping_sub(slice));
                            add(k + 1 < d[2], id + slice);
                            let new = (f64::from(rhs[id]) + alpha * sum) / (1.0 + alpha * n);
                            change = change.max((new - f64::from(x[id])).abs());
                            out[o] = new as f32;
                        }
                    }
                    change
                })
                .reduce(|| 0.0, f64::max);
            std::mem::swap(&mut c.data, &mut buf.data);
            if change < tol {
                break;
            }
        }
    }
}

/// Divergence of every fluid voxel into `s.rhs`, s⁻¹ (0 in solids).
pub(super) fn divergence(s: &mut WindSolver) {
    let g = &s.grid;
    let v = &s.velocity;
    let inv = 1.0 / g.cell;
    let slice = g.nx * g.ny;
    s.rhs
        .par_chunks_mut(slice)
        .enumerate()
        .for_each(|(k, out)| {
            for j in 0..g.ny {
                for i in 0..g.nx {
                    let o = j * g.nx + i;
                    out[o] = if g.solid[k * slice + o] {
                        0.0
                    } else {
                        let du = f64::from(v.u.data[v.u.index(i + 1, j, k)])
                            - f64::from(v.u.data[v.u.index(i, j, k)]);
                        let dv = f64::from(v.v.data[v.v.index(i, j + 1, k)])
                            - f64::from(v.v.data[v.v.index(i, j, k)]);
                        let dw = f64::from(v.w.data[v.w.index(i, j, k + 1)])
                            - f64::from(v.w.data[v.w.index(i, j, k)]);
                        (du + dv + dw) * inv
                    };
                }
            }
        });
}

/// `u −= ∇φ / Δ` on fluid and outflow faces (`φ = 0` beyond outflow faces).
pub(super) fn subtract_gradient(s: &mut WindSolver) {
    let g = &s.grid;
    let phi = &s.phi;
    let inv = 1.0 / g.cell;
    let comps = [&mut s.velocity.u, &mut s.velocity.v, &mut s.velocity.w];
    for (axis, c) in comps.into_iter().enumerate() {
        let d = c.dims;
        let kinds = &s.kinds[axis];
        let slice = d[0] * d[1];
        c.data
            .par_chunks_mut(slice)
            .enumerate()
            .for_each(|(k, out)| {
                for j in 0..d[1] {
                    for i in 0..d[0] {
                        let o = j * d[0] + i;
                        let kind = kinds[k * slice + o];
                        if !matches!(kind, Face::Fluid | Face::Outflow) {
                            continue;
                        }
                        let pos = [i, j, k];
                        let cell = |q: [usize; 3]| phi[g.index(q[0], q[1], q[2])];
                        let n = [g.nx, g.ny, g.nz][axis];
                        let plus = (pos[axis] < n).then(|| cell(pos));
                        let minus = (pos[axis] > 0).then(|| {
                            let mut q = pos;
                            q[axis] -= 1;
                            cell(q)
                        });
                        let grad = (plus.unwrap_or(0.0) - minus.unwrap_or(0.0)) * inv;
                        out[o] -= grad as f32;
                    }
                }
            });
    }
}
