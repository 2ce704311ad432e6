//! The outflow factors of pass 1 on one row, for any lane width, and the per-pipe stencils
//! of pass 1's general code: a pipe's new velocity and volume, its momentum advection, the
//! surface and bed gradients.

use super::*;
use snowscape_terrain::operators;

/// Outflow factors of pass 1 on one row.
#[inline(always)]
pub(super) fn factor_row_lanes<V: Lanes>(
    k: &Consts,
    inp: &Inputs,
    segs: &[[u32; 2]],
    r: usize,
    out: &mut [f64],
) {
    let pw = k.pw;
    let (lo, hi) = if r >= 1 { (1, pw - 2) } else { (1, 0) };
    for (c, visit) in walk(segs, lo, hi, None, V::N) {
        let kk = r * pw + c;
        match visit {
            Visit::Chunk => {
                // SAFETY: `walk` only gives lane visits in the inner region of this pass, where
                // the stencil lies in the padded arrays (all of length `pw·ph`).
                unsafe { factor_lanes::<V>(k, inp, kk, out, c) }
            }
            Visit::Half => {
                // SAFETY: `walk` only gives lane visits in the inner region of this pass, where
                // the stencil lies in the padded arrays (all of length `pw·ph`).
                unsafe { factor_lanes::<V::Half>(k, inp, kk, out, c) }
            }
            Visit::One => {
                // SAFETY: `walk` only gives lane visits in the inner region of this pass, where
                // the stencil lies in the padded arrays (all of length `pw·ph`).
                unsafe { factor_lanes::<f64>(k, inp, kk, out, c) }
            }
            Visit::Border => {
                if inp.h[kk] <= DRY {
                    continue;
                }
                let mut vout = 0.0;
                for d in 0..4 {
                    vout += inp.flux[d][kk - inp.fbase].max(0.0);
                    if let Some(kb) = k.back(c, r, d) {
                        vout += (-inp.flux[d][kb - inp.fbase]).max(0.0);
                    }
                }
                let avail = inp.h[kk] * k.area;
                out[c] = if vout > avail { avail / vout } else { 1.0 };
            }
        }
    }
}

/// Outflow factors of pass 1 on `V::N` cells whose back neighbours exist. Lanes at most `DRY` deep
/// may get a factor too (finite, in [0, 1], never used).
///
/// # Safety
/// Every array of `inp` the kernel reads has the padded length `pw·ph`, and the `V::N` cells
/// from padded index `kk` lie in the pass's inner region (see the `walk` call), so that every
/// cell of the stencil is in the arrays.
#[inline(always)]
unsafe fn factor_lanes<V: Lanes>(k: &Consts, inp: &Inputs, kk: usize, out: &mut [f64], c: usize) {
    // SAFETY: the caller guarantees the stencil lies in the arrays (see `# Safety`).
    unsafe {
        let hk = ld::<V>(inp.h, kk);
        if V::all(hk.le(V::splat(DRY))) {
            return;
        }
        let zero = V::splat(0.0);
        let mut vout = zero;
        for d in 0..4 {
            // (Zeros of either sign add nothing to `vout`, which starts at +0.)
            let kf = kk - inp.fbase;
            vout = vout + ld::<V>(inp.flux[d], kf).max(zero);
            vout = vout + (-ld::<V>(inp.flux[d], kf - k.off[d])).max(zero);
        }
        let avail = hk * V::splat(k.area);
        V::select(vout.gt(avail), avail / vout, V::splat(1.0)).store(out, c);
    }
}

/// The flow depth the Voellmy drag `g·u²/(ξ·h)` of a pipe divides by: the mean of its two
/// cells, at least 1 cm (a film at a front does not stop at once).
#[inline(always)]
pub(super) fn turbulent_depth(hi: f64, hj: f64) -> f64 {
    (0.5 * (hi + hj)).max(MIN_TURBULENT_DEPTH)
}

/// Smallest depth of the Voellmy drag, m.
pub(super) const MIN_TURBULENT_DEPTH: f64 = 0.01;

/// One pipe of the scalar path: from its owner cell to the neighbour in its direction.
#[derive(Debug, Clone, Copy)]
pub(super) struct PipeAt {
    /// The owner cell, padded index.
    pub owner: usize,
    /// The neighbour cell, padded index.
    pub neighbour: usize,
    /// The direction, an index of `DIRS`.
    pub direction: usize,
    /// The owner's column and row in the padded grid.
    pub col: usize,
    pub row: usize,
}

/// One pipe's new velocity and raw (unscaled) volume for a sub-step.
pub(super) fn pipe_update(
    params: &AvalancheParams,
    k: &Consts,
    pg: &PipeGeometry,
    inp: &Inputs,
    at: PipeAt,
) -> (f64, f64) {
    let PipeAt {
        owner: kk,
        neighbour: j,
        direction: d,
        ..
    } = at;
    let (h, bed, vel, vb) = (inp.h, inp.bed, &inp.vel, inp.vbase);
    let dt = k.dt;
    let (hi, hj) = (h[kk], h[j]);
    if hi <= DRY && hj <= DRY {
        return (0.0, 0.0);
    }
    let u0 = inp.pipes[d][kk];
    // The pipe's `cos²θ`: the mean of its cells' (one cell's where the other has none).
    let pipe_mean = |a: usize| match (vel[a][kk - vb].is_nan(), vel[a][j - vb].is_nan()) {
        (false, false) => 0.5 * (vel[a][kk - vb] + vel[a][j - vb]),
        (false, true) => vel[a][kk - vb],
        (true, false) => vel[a][j - vb],
        (true, true) => 1.0,
    };
    let c2 = pipe_mean(C2);
    // The pipe's load factor of the curvature (`pipes::curvature_load`), as its `cos²θ`.
    let cf = pipe_mean(CF);
    let a = if k.projected {
        (c2 * ((bed[j] - bed[kk]) + c2 * (hj - hi))) * pg.neg_g_over_len[d]
    } else {
        ((bed[j] + hj) - (bed[kk] + hi)) * pg.neg_g_over_len[d]
    };
    let vp = [
        0.5 * (vel[VX][kk - vb] + vel[VX][j - vb]),
        0.5 * (vel[VY][kk - vb] + vel[VY][j - vb]),
    ];
    let mut u = u0 + dt * a;
    if params.momentum_advection {
        u += advection(pg, inp, (k.pw, k.curvature), at, dt);
    }
    // Coulomb friction as one vector: the trial velocity at the pipe, `v + δt·(−g∇A)` (cell
    // velocities and surface gradients averaged over the pipe's two cells), is slowed by
    // `g·tanθc·δt` along its own direction and each pipe takes its share `e·v̂`; where the
    // trial speed is below `g·tanθc·δt` the snow is held (static friction: the yield
    // criterion `|∇A| ≤ tanθc` at rest, the same in every direction), and a pipe the force
    // would reverse is set to zero.
    let g = |i: usize| [vel[GX][i - vb], vel[GY][i - vb]];
    let grad = match (vel[GX][kk - vb].is_nan(), vel[GX][j - vb].is_nan()) {
        (false, false) => [
            0.5 * (vel[GX][kk - vb] + vel[GX][j - vb]),
            0.5 * (vel[GY][kk - vb] + vel[GY][j - vb]),
        ],
        (false, true) => g(kk),
        (true, false) => g(j),
        (true, true) => [0.0, 0.0],
    };
    let trial = [vp[0] - k.dtg * grad[0], vp[1] - k.dtg * grad[1]];
    let tnorm = (trial[0] * trial[0] + trial[1] * trial[1]).sqrt();
    // The pipe's μ·g: the law's, or the mean of its cells' (`crate::friction_maps`; the
    // products in the order of `Consts::new`, so a map of the law's μ gives the same bits).
    let mu_g = (!inp.mu.is_empty()).then(|| (0.5 * (inp.mu[kk] + inp.mu[j])) * G);
    let mut yield_dt = match (&k.samos, mu_g) {
        (None, None) => k.yield_dt,
        (None, Some(m)) => k.alpha * m * dt,
        // Rs from the speed at the start of the sub-step (at rest: twice μ, exactly).
        (Some(s), m) => s.yield_dt(
            m.map_or(s.mu_g_dt, |m| m * dt),
            vp[0] * vp[0] + vp[1] * vp[1],
            turbulent_depth(hi, hj),
        ),
    };
    if k.projected {
        // The normal load, and the dry friction with it, is `g cosθ` (times the curvature's
        // `f`); its horizontal share `cosθ` more.
        yield_dt *= c2 * cf;
    }
    let proj = if tnorm > 0.0 {
        ((pg.e[d][0] * trial[0] + pg.e[d][1] * trial[1]) / tnorm).abs()
    } else {
        1.0
    };
    let fric = yield_dt * proj;
    if (k.alpha > 0.0 && tnorm <= yield_dt) || u.abs() <= fric {
        u = 0.0;
    } else {
        u -= fric * u.signum();
    }
    // Viscous term, implicit.
    u /= 1.0 + dt * (1.0 - k.alpha) * params.k_viscous * 0.5 * (hi + hj);
    if k.turb != 0.0 {
        // The drag `g·|v|·v/(ξ·h)` along the pipe: its speed is the flow's (the trial
        // velocity's norm after the dry friction), not the pipe's component, or diagonal
        // pipes would escape it.
        // (Projected: `g u_s²/(ξ h_n)` along the slope is `g u²/(ξ h cos²θ)` on the grid.)
        let depth = if k.projected {
            turbulent_depth(hi, hj) * c2
        } else {
            turbulent_depth(hi, hj)
        };
        let turb = if inp.xi.is_empty() {
            k.turb
        } else {
            k.dtg / (0.5 * (inp.xi[kk] + inp.xi[j]))
        };
        u /= 1.0 + turb * (tnorm - yield_dt).max(0.0) / depth;
    }
    if let Some(s) = &k.samos {
        // (Projected: the drag `dt·|u|/(h·div²)` divided by cos²θ.)
        let den = s.drag_depth(turbulent_depth(hi, hj));
        let den = if k.projected { den * c2 } else { den };
        u = u * den / (den + dt * (tnorm - yield_dt).max(0.0));
    }
    let hup = if u > 0.0 { hi } else { hj };
    if hup <= DRY {
        return (0.0, 0.0);
    }
    (u, pg.width[d] * hup * u * dt)
}

/// Where a gradient reads its cells: the padded nodata flags, and whether nodata cells are
/// walls ([`Border::Closed`]: a wall neighbour is replaced by the cell itself) or open (their
/// bed, and no snow, as the ghost ring's).
#[derive(Clone, Copy)]
pub(super) struct GradientCells<'a> {
    pub nodata: &'a [bool],
    pub walls: bool,
    pub pw: usize,
}

/// Central-difference gradient of the surface `A = B + h` at padded cell `k` (next to a nodata
/// wall the cell itself replaces the wall); `None` on the ghost ring and nodata cells.
pub(super) fn surface_gradient(
    pg: &PipeGeometry,
    h: &[f64],
    bed: &[f64],
    cells: GradientCells,
    k: usize,
) -> Option<[f64; 2]> {
    gradient(pg, |i| bed[i] + h[i], cells, k)
}

/// Central-difference gradient of the bed at padded cell `k`, as [`surface_gradient`].
pub(super) fn bed_gradient(
    pg: &PipeGeometry,
    bed: &[f64],
    cells: GradientCells,
    k: usize,
) -> Option<[f64; 2]> {
    gradient(pg, |i| bed[i], cells, k)
}

/// Central-difference gradient of the field `a` at padded cell `k` (next to a nodata wall the
/// cell itself replaces the wall); `None` on the ghost ring and nodata cells.
#[inline(always)]
fn gradient(
    pg: &PipeGeometry,
    a: impl Fn(usize) -> f64,
    cells: GradientCells,
    k: usize,
) -> Option<[f64; 2]> {
    let GradientCells { nodata, walls, pw } = cells;
    let (r, c) = (k / pw, k % pw);
    if r == 0 || c == 0 || r + 1 >= pg.ph || c + 1 >= pw || nodata[k] {
        return None;
    }
    let ak = a(k);
    let side = |i: usize| if walls && nodata[i] { ak } else { a(i) };
    // The padded grid's rows run south, as its y axis (the flow's frame).
    let gx = operators::interior_difference(side(k - 1), side(k + 1), pg.inv_two_dx);
    let gy = operators::interior_difference(side(k - pw), side(k + pw), pg.inv_two_dy);
    Some([gx, gy])
}

/// Momentum-conservative upwind advection of the pipe velocity (Stelling & Duinmeijer 2003,
/// generalised to the lattice of pipes sharing direction `d`): returns the change of `u` over
/// `dt`, `Σ_f λ_f (u_f − u)` over the lattice neighbours `f` whose face brings momentum in,
/// `λ_f = dt · Q_f / (Δ · h̄)` with `Q_f` the inflowing discharge at the face (mean of the cell
/// discharges `h·v` of the two pipes' end cells), `h̄` the mean depth of the pipe's cells. The
/// `λ` are scaled so that `Σ λ ≤ 1` (a convex combination: no overshoot).
///
/// **Along the bed** (`along_bed`: [`SlopeGravity::Projected`] with the curvature): what the
/// flow carries from cell to cell is its speed along the bed, not its horizontal speed, so
/// `u_f` enters as `u_f·m_f/m`, with `m = sqrt(1 + (v̂·∇B)²)` the flow's length along the bed
/// per horizontal length (`pipes::along_bed`; of a pipe, the mean of its two cells': the
/// flow's direction, not the pipe's, since every pipe carries the projection `e·v` of the one
/// flow velocity). Where the slope eases the horizontal speed grows by the ratio and where it
/// steepens it shrinks, the speed along the bed kept: the horizontal share
/// of the bed's reaction that turns the flow along a curved bed, `−cos²θ (v·H·v) ∇B` (with
/// `u_s = u·m`, `Du/Dt = D(u_s/m)/Dt` gives that term for a steady `u_s`), which AvaFrame
/// com1DFA gets by projecting its particles' velocity back onto the bed. Carried by the
/// upwind advection, it keeps its convex combination: along a path the ratios multiply to
/// `m_start/m_end`, so a flow cannot gain speed going round a hollow, as an explicit
/// `v·H·v` force would on a rough bed.
pub(super) fn advection(
    pg: &PipeGeometry,
    inp: &Inputs,
    (pw, along_bed): (usize, bool),
    at: PipeAt,
    dt: f64,
) -> f64 {
    let PipeAt {
        owner: k,
        neighbour: j,
        direction: d,
        col: c,
        row: r,
    } = at;
    let (h, vel, vb) = (inp.h, &inp.vel, inp.vbase);
    let hbar = 0.5 * (h[k] + h[j]);
    if hbar <= DRY {
        return 0.0;
    }
    let ph = pg.ph;
    let u0 = inp.pipes[d][k];
    let (dc, dr) = DIRS[d];
    let qp = [
        0.5 * (vel[QX][k - vb] + vel[QX][j - vb]),
        0.5 * (vel[QY][k - vb] + vel[QY][j - vb]),
    ];
    // Lattice neighbours: (owner offset, axis, side) with side +1 for the + face.
    let nbs: [(isize, isize, usize, f64); 4] = [
        (-1, 0, 0, -1.0),
        (1, 0, 0, 1.0),
        (0, -1, 1, -1.0),
        (0, 1, 1, 1.0),
    ];
    let mut lam = [0.0f64; 4];
    let mut un = [0.0f64; 4];
    let mut total = 0.0;
    let rate = [dt / (pg.dx * hbar), dt / (pg.dy * hbar)];
    let inv_m = along_bed.then(|| 1.0 / (0.5 * (vel[M][k - vb] + vel[M][j - vb])));
    for (m, &(oc, or, axis, side)) in nbs.iter().enumerate() {
        let (cc, rr) = (c as isize + oc, r as isize + or);
        let (jc, jr) = (cc + dc, rr + dr);
        if cc < 0 || rr < 0 || jc < 0 || jr < 0 {
            continue;
        }
        let (cc, rr, jc, jr) = (cc as usize, rr as usize, jc as usize, jr as usize);
        if cc >= pw || jc >= pw || rr >= ph || jr >= ph {
            continue;
        }
        let (kn, jn) = (rr * pw + cc, jr * pw + jc);
        let qn = 0.5 * (vel[QX + axis][kn - vb] + vel[QX + axis][jn - vb]);
        let q_face = 0.5 * (qp[axis] + qn);
        // Inflow through the + face is q < 0, through the − face q > 0.
        let inflow = -side * q_face;
        if inflow > 0.0 {
            lam[m] = rate[axis] * inflow;
            un[m] = match inv_m {
                Some(inv_m) => {
                    let m_f = 0.5 * (vel[M][kn - vb] + vel[M][jn - vb]);
                    (inp.pipes[d][kn] * m_f) * inv_m
                }
                None => inp.pipes[d][kn],
            };
            total += lam[m];
        }
    }
    let scale = if total > 1.0 { 1.0 / total } else { 1.0 };
    let mut du = 0.0;
    for m in 0..4 {
        du += scale * lam[m] * (un[m] - u0);
    }
    du
}
