//! Pass 1 (velocities) and pass 2 (pipe momentum and fluxes) on one row, for any lane width.

use super::*;
use snowscape_terrain::operators;

/// Velocities of pass 1 on one row.
#[inline(always)]
pub(super) fn vel_row_lanes<V: Lanes>(
    k: &Consts,
    pg: &PipeGeometry,
    inp: &Inputs,
    segs: &[[u32; 2]],
    r: usize,
    out: &mut [&mut [f64]; 9],
) {
    let pw = k.pw;
    // Lanes where the 3x3 stencil holds no ghost-ring or nodata cell (the bed's curvature is
    // read there only: [`curvature_load`]).
    let (lo, hi) = if r >= 2 && r + 3 <= k.ph {
        (2, pw - 3)
    } else {
        (1, 0)
    };
    let wall = &inp.near_wall[r * pw..(r + 1) * pw];
    for (c, visit) in walk(segs, lo, hi, Some(wall), V::N) {
        let kk = r * pw + c;
        match visit {
            Visit::Chunk => {
                // SAFETY: `walk` only gives lane visits in the inner region of this pass, where
                // the stencil lies in the padded arrays (all of length `pw·ph`).
                unsafe { cell_flow_lanes::<V>(k, inp, kk, out, c) }
            }
            Visit::Half => {
                // SAFETY: `walk` only gives lane visits in the inner region of this pass, where
                // the stencil lies in the padded arrays (all of length `pw·ph`).
                unsafe { cell_flow_lanes::<V::Half>(k, inp, kk, out, c) }
            }
            Visit::One => {
                // SAFETY: `walk` only gives lane visits in the inner region of this pass, where
                // the stencil lies in the padded arrays (all of length `pw·ph`).
                unsafe { cell_flow_lanes::<f64>(k, inp, kk, out, c) }
            }
            Visit::Border => {
                let v = cell_flow_border(k, pg, inp, c, r);
                for (o, x) in out.iter_mut().zip(v) {
                    o[c] = x;
                }
            }
        }
    }
}

/// Velocities of pass 1 on `V::N` cells away from the ghost ring and from nodata cells (their 3x3
/// neighbourhoods hold none).
///
/// # Safety
/// Every array of `inp` the kernel reads has the padded length `pw·ph`, and the `V::N` cells
/// from padded index `kk` lie in the pass's inner region (see the `walk` call), so that every
/// cell of the stencil is in the arrays.
#[inline(always)]
unsafe fn cell_flow_lanes<V: Lanes>(
    k: &Consts,
    inp: &Inputs,
    kk: usize,
    out: &mut [&mut [f64]; 9],
    c: usize,
) {
    // SAFETY: the caller guarantees the stencil lies in the arrays (see `# Safety`).
    unsafe {
        let pw = k.pw;
        let p = &inp.pipes;
        let half = V::splat(0.5);
        let p0 = half * (ld::<V>(p[0], kk) + ld::<V>(p[0], kk - 1));
        let p1 = half * (ld::<V>(p[1], kk) + ld::<V>(p[1], kk - pw));
        let p2 = half * (ld::<V>(p[2], kk) + ld::<V>(p[2], kk - pw - 1));
        let p3 = half * (ld::<V>(p[3], kk) + ld::<V>(p[3], kk - pw + 1));
        let vx_d = (p2 - p3) * V::splat(k.inv_den_x);
        let vy_d = (p2 + p3) * V::splat(k.inv_den_y);
        let vx = half * (p0 + vx_d);
        let vy = half * (p1 + vy_d);
        let a = |i: usize| ld::<V>(inp.bed, i) + ld::<V>(inp.h, i);
        let (inv_two_dx, inv_two_dy) = (V::splat(k.inv_two_dx), V::splat(k.inv_two_dy));
        let mut gx = operators::interior_difference(a(kk - 1), a(kk + 1), inv_two_dx);
        let mut gy = operators::interior_difference(a(kk - pw), a(kk + pw), inv_two_dy);
        let mut c2 = V::splat(1.0);
        let mut cf = V::splat(1.0);
        if k.projected {
            // [`projected_gradient`] in lanes.
            let b = |i: usize| ld::<V>(inp.bed, i);
            let bx = operators::interior_difference(b(kk - 1), b(kk + 1), inv_two_dx);
            let by = operators::interior_difference(b(kk - pw), b(kk + pw), inv_two_dy);
            c2 = V::splat(1.0) / (V::splat(1.0) + (bx * bx + by * by));
            gx = c2 * (bx + c2 * (gx - bx));
            gy = c2 * (by + c2 * (gy - by));
            if k.curvature {
                cf = curvature_load::<V>(k, inp.bed, kk, vx, vy);
                along_bed::<V>(vx, vy, bx, by).store(out[M], c);
            }
        }
        let hk = ld::<V>(inp.h, kk);
        vx.store(out[VX], c);
        vy.store(out[VY], c);
        (hk * vx).store(out[QX], c);
        (hk * vy).store(out[QY], c);
        gx.store(out[GX], c);
        gy.store(out[GY], c);
        c2.store(out[C2], c);
        cf.store(out[CF], c);
    }
}

/// The flow's length along the bed per horizontal length, `m = sqrt(1 + (v̂·∇B)²)`, at
/// horizontal velocity `(vx, vy)` on a bed of gradient `(bx, by)` (1 at rest): the factor from
/// the horizontal speed to the speed along the bed (`update::advection`).
#[inline(always)]
pub(super) fn along_bed<V: Lanes>(vx: V, vy: V, bx: V, by: V) -> V {
    let zero = V::splat(0.0);
    let v2 = vx * vx + vy * vy;
    let vb = vx * bx + vy * by;
    let rise2 = V::select(v2.gt(zero), (vb * vb) / v2, zero);
    (V::splat(1.0) + rise2).sqrt()
}

/// The bed's load factor of the curvature at `V::N` cells from padded index `kk` moving at
/// horizontal velocity `(vx, vy)`: `f = max(0, 1 + v·H·v/g)`, with `H` the Hessian of the bed
/// from the 3x3 stencil by Evans' quadratic fit (Evans 1980, as in Wood 1996's curvatures):
/// `B_xx = (Σ west column + Σ east column − 2 Σ middle column)/(3·dx²)`, `B_yy` the same by
/// rows, `B_xy = ((B_SE − B_SW) − (B_NE − B_NW))/(4·dx·dy)` (x east, y south, as the
/// velocity). It is exact on a quadratic bed and averages the second differences of the three
/// rows (columns), so a DEM's noise loads the friction less than single second differences
/// would (avaKot with the Coulomb law: recall of AvaFrame's footprint 0.64 against 0.59).
///
/// A flow following a bed `z = B(x, y)` at horizontal velocity `v` accelerates normal to it by
/// `cosθ·v·H·v` (differentiate `v·∇B`, the vertical velocity, along the path), so the bed
/// carries `cosθ (g + v·H·v)` per unit mass instead of `g cosθ`: the centrifugal term of
/// Savage-Hutter on a curved bed (Gray, Wieland & Hutter 1999, Proc. R. Soc. A 455; AvaFrame
/// com1DFA's curvature acceleration in the friction, `curvAccInFriction`, its theory
/// documentation's σ₃₃ after Zwinger 2000). Where `v·H·v < −g` the flow lifts off: no load
/// (`f = 0`).
///
/// # Safety
/// The 3x3 stencil of each of the `V::N` cells lies in `bed` (of the padded length `pw·ph`).
#[inline(always)]
pub(super) unsafe fn curvature_load<V: Lanes>(
    k: &Consts,
    bed: &[f64],
    kk: usize,
    vx: V,
    vy: V,
) -> V {
    // SAFETY: the caller guarantees the stencil lies in `bed` (see `# Safety`).
    unsafe {
        let pw = k.pw;
        let b = |i: usize| ld::<V>(bed, i);
        // The 3x3 stencil, rows north (n), middle (m), south (s).
        let (nw, n, ne) = (b(kk - pw - 1), b(kk - pw), b(kk - pw + 1));
        let (w, c, e) = (b(kk - 1), b(kk), b(kk + 1));
        let (sw, s, se) = (b(kk + pw - 1), b(kk + pw), b(kk + pw + 1));
        let (bxx, byy, bxy) = operators::quadratic_fit_hessian(
            [[nw, n, ne], [w, c, e], [sw, s, se]],
            V::splat(2.0),
            V::splat(k.inv_dx2),
            V::splat(k.inv_dy2),
            V::splat(k.inv_four_dxdy),
        );
        let vhv = vx * vx * bxx + (vx + vx) * vy * bxy + vy * vy * byy;
        let f = V::splat(1.0) + vhv * V::splat(1.0 / G);
        let zero = V::splat(0.0);
        V::select(f.lt(zero), zero, f)
    }
}

/// Velocities of pass 1 at any cell (ghost ring and nodata included).
pub(super) fn cell_flow_border(
    k: &Consts,
    pg: &PipeGeometry,
    inp: &Inputs,
    c: usize,
    r: usize,
) -> [f64; 9] {
    let kk = r * k.pw + c;
    let mut p = [0.0; 4];
    for (d, pd) in p.iter_mut().enumerate() {
        let own = inp.pipes[d][kk];
        *pd = match k.back(c, r, d) {
            Some(kb) => 0.5 * (own + inp.pipes[d][kb]),
            None => own,
        };
    }
    let vx_d = (p[2] - p[3]) * k.inv_den_x;
    let vy_d = (p[2] + p[3]) * k.inv_den_y;
    let (vx, vy) = (0.5 * (p[0] + vx_d), 0.5 * (p[1] + vy_d));
    let cells = GradientCells {
        nodata: inp.nodata,
        walls: k.closed,
        pw: k.pw,
    };
    let [gx, gy, c2, cf, m] = match surface_gradient(pg, inp.h, inp.bed, cells, kk) {
        Some([gx, gy]) if k.projected => {
            let [bx, by] =
                bed_gradient(pg, inp.bed, cells, kk).expect("defined where the surface's is");
            // The curvature where the 3x3 stencil holds only valid cells (next to the ghost
            // ring and nodata cells the bed is a copy: its curvature is not the terrain's).
            let inner =
                (2..=k.pw - 3).contains(&c) && (2..=k.ph - 3).contains(&r) && !inp.near_wall[kk];
            let cf = if k.curvature && inner {
                // SAFETY: `inner`: the 3x3 stencil lies in the padded bed.
                unsafe { curvature_load::<f64>(k, inp.bed, kk, vx, vy) }
            } else {
                1.0
            };
            let m = if k.curvature {
                along_bed::<f64>(vx, vy, bx, by)
            } else {
                1.0
            };
            let [gx, gy, c2] = projected_gradient(gx, gy, bx, by);
            [gx, gy, c2, cf, m]
        }
        // (`m` = 1 where the gradient is undefined: the ghost ring and nodata cells.)
        None => [f64::NAN, f64::NAN, f64::NAN, f64::NAN, 1.0],
        Some([gx, gy]) => [gx, gy, 1.0, 1.0, 1.0],
    };
    let hk = inp.h[kk];
    [vx, vy, hk * vx, hk * vy, gx, gy, c2, cf, m]
}

/// The gradient gravity acts on with [`SlopeGravity::Projected`], `cos²θ (∇B + cos²θ ∇h)`, and
/// `cos²θ = 1/(1 + |∇B|²)`, from the surface gradient `(gx, gy)` and the bed's `(bx, by)`.
#[inline(always)]
pub(super) fn projected_gradient(gx: f64, gy: f64, bx: f64, by: f64) -> [f64; 3] {
    let c2 = 1.0 / (1.0 + (bx * bx + by * by));
    [c2 * (bx + c2 * (gx - bx)), c2 * (by + c2 * (gy - by)), c2]
}

/// Pipes of pass 1 on one row.
/// The pipe velocities and volume fluxes a row of pass 1 writes, each per direction.
pub(super) struct PipeRows<'a, 'b> {
    pub pipes: &'a mut [&'b mut [f64]; 4],
    pub fluxes: &'a mut [&'b mut [f64]; 4],
}

#[inline(always)]
pub(super) fn pipes_row_lanes<V: Lanes>(
    params: &AvalancheParams,
    k: &Consts,
    pg: &PipeGeometry,
    inp: &Inputs,
    row: PassRow,
    out: PipeRows,
) {
    let PassRow { row: r, segs } = row;
    let PipeRows {
        pipes: np,
        fluxes: fl,
    } = out;
    let pw = k.pw;
    let (lo, hi) = if r >= 1 && r + 3 <= k.ph && pw >= 5 {
        (2, pw - 3)
    } else {
        (1, 0)
    };
    let wall = &inp.near_wall[r * pw..(r + 1) * pw];
    for (c, visit) in walk(segs, lo, hi, Some(wall), V::N) {
        let kk = r * pw + c;
        match visit {
            Visit::Chunk => {
                // SAFETY: `walk` only gives lane visits in the inner region of this pass, where
                // the stencil lies in the padded arrays (all of length `pw·ph`).
                unsafe { owner_lanes::<V>(k, inp, kk, np, fl, c) }
            }
            Visit::Half => {
                // SAFETY: `walk` only gives lane visits in the inner region of this pass, where
                // the stencil lies in the padded arrays (all of length `pw·ph`).
                unsafe { owner_lanes::<V::Half>(k, inp, kk, np, fl, c) }
            }
            Visit::One => {
                // SAFETY: `walk` only gives lane visits in the inner region of this pass, where
                // the stencil lies in the padded arrays (all of length `pw·ph`).
                unsafe { owner_lanes::<f64>(k, inp, kk, np, fl, c) }
            }
            Visit::Border => {
                let wall_k = k.is_wall(inp.nodata, kk, c, r);
                for d in 0..4 {
                    let (dc, dr) = DIRS[d];
                    let (u, f) = match k.neighbour(c, r, d) {
                        Some(j)
                            if !wall_k
                                && !k.is_wall(
                                    inp.nodata,
                                    j,
                                    (c as isize + dc) as usize,
                                    r + dr as usize,
                                ) =>
                        {
                            let at = PipeAt {
                                owner: kk,
                                neighbour: j,
                                direction: d,
                                col: c,
                                row: r,
                            };
                            pipe_update(params, k, pg, inp, at)
                        }
                        _ => (0.0, 0.0),
                    };
                    np[d][c] = u;
                    fl[d][c] = f;
                }
            }
        }
    }
}

/// Pipes of pass 1 on `V::N` owners whose pipes and advection stencils stay inside the grid (away
/// from the ghost ring) and whose 3x3 neighbourhoods hold no nodata cell: no pipe is a wall and
/// surface gradients are defined at both ends of every pipe.
///
/// # Safety
/// Every array of `inp` the kernel reads has the padded length `pw·ph`, and the `V::N` cells
/// from padded index `kk` lie in the pass's inner region (see the `walk` call), so that every
/// cell of the stencil is in the arrays.
#[inline(always)]
unsafe fn owner_lanes<V: Lanes>(
    k: &Consts,
    inp: &Inputs,
    kk: usize,
    np: &mut [&mut [f64]; 4],
    fl: &mut [&mut [f64]; 4],
    c: usize,
) {
    // SAFETY: the caller guarantees the stencil lies in the arrays (see `# Safety`).
    unsafe {
        let dry = V::splat(DRY);
        let zero = V::splat(0.0);
        let hk = ld::<V>(inp.h, kk);
        let dry_k = hk.le(dry);
        if V::all(dry_k)
            && k.off
                .iter()
                .all(|&o| V::all(ld::<V>(inp.h, kk + o).le(dry)))
        {
            for d in 0..4 {
                zero.store(np[d], c);
                zero.store(fl[d], c);
            }
            return;
        }
        for d in 0..4 {
            let (u, f) = pipe_lanes::<V>(k, inp, d, kk, hk, dry_k);
            u.store(np[d], c);
            f.store(fl[d], c);
        }
    }
}

/// New velocity and raw volume of the pipes `d` of `V::N` owners (the operations of
/// [`pipe_update`] lane by lane; lanes with two dry ends or held by static friction give 0,
/// and when every lane does, the rest is skipped).
///
/// # Safety
/// Every array of `inp` the kernel reads has the padded length `pw·ph`, and the `V::N` cells
/// from padded index `kk` lie in the pass's inner region (see the `walk` call), so that every
/// cell of the stencil is in the arrays.
#[inline(always)]
unsafe fn pipe_lanes<V: Lanes>(
    k: &Consts,
    inp: &Inputs,
    d: usize,
    kk: usize,
    hk: V,
    dry_k: V::M,
) -> (V, V) {
    // SAFETY: the caller guarantees the stencil lies in the arrays (see `# Safety`).
    unsafe {
        let zero = V::splat(0.0);
        let j = kk + k.off[d];
        let hj = ld::<V>(inp.h, j);
        let dead = V::and(dry_k, hj.le(V::splat(DRY)));
        if V::all(dead) {
            return (zero, zero);
        }
        let half = V::splat(0.5);
        let lv = |a: usize, i: usize| ld::<V>(inp.vel[a], i - inp.vbase);
        let dtg = V::splat(k.dtg);
        let (v0, v1) = (
            half * (lv(VX, kk) + lv(VX, j)),
            half * (lv(VY, kk) + lv(VY, j)),
        );
        let t0 = v0 - dtg * (half * (lv(GX, kk) + lv(GX, j)));
        let t1 = v1 - dtg * (half * (lv(GY, kk) + lv(GY, j)));
        let tnorm = (t0 * t0 + t1 * t1).sqrt();
        // [`super::update::turbulent_depth`] lane by lane: the depth both drag laws divide by.
        let mean = half * (hk + hj);
        let depth = V::select(
            mean.lt(V::splat(MIN_TURBULENT_DEPTH)),
            V::splat(MIN_TURBULENT_DEPTH),
            mean,
        );
        // The pipe's μ·g from the friction maps (as in [`super::update::pipe_update`]).
        let mu_g = (!inp.mu.is_empty())
            .then(|| half * (ld::<V>(inp.mu, kk) + ld::<V>(inp.mu, j)) * V::splat(G));
        // The samosAT law's dry friction and drag factor.
        let samos = k.samos.map(|s| {
            // [`Samos::yield_dt`] and [`Samos::drag_depth`] in lanes.
            let start2 = v0 * v0 + v1 * v1;
            let rs0 = V::splat(s.rs0);
            let one = V::splat(1.0);
            let mu_g_dt = mu_g.map_or(V::splat(s.mu_g_dt), |m| m * V::splat(k.dt));
            let rgh = rs0 * (V::splat(G) * depth);
            let y = mu_g_dt * (one + rgh / (rgh + start2));
            let log = super::lanes::ln_at_least_one((depth * V::splat(s.inv_r)).max(V::splat(1.0)));
            let div = log * V::splat(s.inv_kappa) + V::splat(s.b);
            (y, depth * div * div)
        });
        let c2 = half * (lv(C2, kk) + lv(C2, j));
        let cf = half * (lv(CF, kk) + lv(CF, j));
        let yield_dt = match (samos, mu_g) {
            (None, None) => V::splat(k.yield_dt),
            (None, Some(m)) => V::splat(k.alpha) * m * V::splat(k.dt),
            (Some((y, _)), _) => y,
        };
        let yield_dt = if k.projected {
            yield_dt * (c2 * cf)
        } else {
            yield_dt
        };
        let dead = if k.coulomb {
            V::or(dead, tnorm.le(yield_dt))
        } else {
            dead
        };
        if V::all(dead) {
            return (zero, zero);
        }
        let u0 = ld::<V>(inp.pipes[d], kk);
        let a = if k.projected {
            let db = ld::<V>(inp.bed, j) - ld::<V>(inp.bed, kk);
            (c2 * (db + c2 * (hj - hk))) * V::splat(k.neg_g_over_len[d])
        } else {
            let ak = ld::<V>(inp.bed, kk) + hk;
            let aj = ld::<V>(inp.bed, j) + hj;
            (aj - ak) * V::splat(k.neg_g_over_len[d])
        };
        let mut u = u0 + V::splat(k.dt) * a;
        if k.adv {
            u = u + advection_lanes::<V>(k, inp, (d, kk, j), PipeEnds { hk, hj, u0 });
        }
        // `e·trial` (the exact zero components of the axis pipes only change the sign of a zero,
        // which `abs` drops).
        let num = match d {
            0 => t0,
            1 => t1,
            _ => V::splat(k.e[d][0]) * t0 + V::splat(k.e[d][1]) * t1,
        };
        let proj = V::select(tnorm.gt(zero), (num / tnorm).abs(), V::splat(1.0));
        let fric = yield_dt * proj;
        u = V::select(u.abs().le(fric), zero, u - fric * u.signum());
        if k.visc != 0.0 {
            // (With no viscosity the division is by exactly 1.)
            u = u / (V::splat(1.0) + V::splat(k.visc) * (hk + hj));
        }
        if k.turb != 0.0 {
            let speed = V::select(tnorm.gt(yield_dt), tnorm - yield_dt, zero);
            let depth = if k.projected { depth * c2 } else { depth };
            let turb = if inp.xi.is_empty() {
                V::splat(k.turb)
            } else {
                V::splat(k.dtg) / (half * (ld::<V>(inp.xi, kk) + ld::<V>(inp.xi, j)))
            };
            u = u / (V::splat(1.0) + turb * speed / depth);
        }
        if let Some((_, den)) = samos {
            let speed = V::select(tnorm.gt(yield_dt), tnorm - yield_dt, zero);
            let den = if k.projected { den * c2 } else { den };
            u = u * den / (den + V::splat(k.dt) * speed);
        }
        let hup = V::select(u.gt(zero), hk, hj);
        let dead = V::or(dead, hup.le(V::splat(DRY)));
        let f = V::splat(k.width[d]) * hup * u * V::splat(k.dt);
        (V::select(dead, zero, u), V::select(dead, zero, f))
    }
}

/// The lanes' depths at a pipe's owner and neighbour cells and the pipe's velocity.
struct PipeEnds<V> {
    hk: V,
    hj: V,
    u0: V,
}

/// [`advection`] for the owners of [`owner_lanes`] (every lattice neighbour exists), the pipe
/// in direction `d` from the owners at padded index `kk` to the cells at `j`.
///
/// # Safety
/// Every array of `inp` the kernel reads has the padded length `pw·ph`, and the `V::N` cells
/// from padded index `kk` lie in the pass's inner region (see the `walk` call), so that every
/// cell of the stencil is in the arrays.
#[inline(always)]
unsafe fn advection_lanes<V: Lanes>(
    k: &Consts,
    inp: &Inputs,
    (d, kk, j): (usize, usize, usize),
    ends: PipeEnds<V>,
) -> V {
    let PipeEnds { hk, hj, u0 } = ends;
    // SAFETY: the caller guarantees the stencil lies in the arrays (see `# Safety`).
    unsafe {
        let zero = V::splat(0.0);
        let half = V::splat(0.5);
        let hbar = half * (hk + hj);
        let dead = hbar.le(V::splat(DRY));
        if V::all(dead) {
            return zero;
        }
        let (qx, qy) = (inp.vel[QX], inp.vel[QY]);
        let pw = k.pw;
        let jk = j - kk;
        // (Velocity arrays start at padded index `vbase`.)
        let (kv, jv) = (kk - inp.vbase, j - inp.vbase);
        let qp0 = half * (ld::<V>(qx, kv) + ld::<V>(qx, jv));
        let qp1 = half * (ld::<V>(qy, kv) + ld::<V>(qy, jv));
        let dt = V::splat(k.dt);
        let rx = dt / (V::splat(k.dx) * hbar);
        let ry = if k.square {
            rx
        } else {
            dt / (V::splat(k.dy) * hbar)
        };
        let pd = inp.pipes[d];
        // Lattice neighbours (west, east, north, south): owner, discharge component, rate and
        // the sign making the face's inflow positive.
        // (`1·q` is `q` and `−1·q` is `−q`, bit for bit.)
        let nbs = [
            (kk - 1, kv - 1, qx, qp0, rx, false),
            (kk + 1, kv + 1, qx, qp0, rx, true),
            (kk - pw, kv - pw, qy, qp1, ry, false),
            (kk + pw, kv + pw, qy, qp1, ry, true),
        ];
        let mut lam = [zero; 4];
        let mut un = [zero; 4];
        let mut total = zero;
        // With the curvature, the neighbours' velocities along the bed, `u_f·m_f/m`, `m` of a
        // pipe the mean of its cells' ([`super::update::advection`]).
        let mv = inp.vel[M];
        let inv_m = k
            .curvature
            .then(|| V::splat(1.0) / (half * (ld::<V>(mv, kv) + ld::<V>(mv, kv + jk))));
        for (m, &(kn, knv, q, qp, rate, minus)) in nbs.iter().enumerate() {
            let qn = half * (ld::<V>(q, knv) + ld::<V>(q, knv + jk));
            let face = half * (qp + qn);
            let inflow = if minus { -face } else { face };
            lam[m] = V::select(inflow.gt(zero), rate * inflow, zero);
            // (A face without inflow has `λ = 0`: its term below is a zero whatever `u_f`, and
            // zeros leave the sums unchanged.)
            un[m] = match inv_m {
                Some(inv_m) => {
                    let m_f = half * (ld::<V>(mv, knv) + ld::<V>(mv, knv + jk));
                    (ld::<V>(pd, kn) * m_f) * inv_m
                }
                None => ld::<V>(pd, kn),
            };
            total = total + lam[m];
        }
        let one = V::splat(1.0);
        let big = total.gt(one);
        let scale = if V::any(big) {
            V::select(big, one / total, one)
        } else {
            one
        };
        let mut du = zero;
        for m in 0..4 {
            du = du + scale * lam[m] * (un[m] - u0);
        }
        V::select(dead, zero, du)
    }
}
