//! Diffusion of powdery snow (Cordonnier et al. 2018, Section 5.3).
//!
//! The paper moves powder across each of the 4 faces of a cell by
//! `m_d = δt_d · k_m · max(0, s_d − s_d0)` (or `min(0, s_d + s_d0)` for negative slopes),
//! with `s_d = (A(p) − A(p_n)) / ‖p − p_n‖` the surface slope towards the neighbour, and
//! scales a cell's outflow down when it would take more powder than the cell holds.
//!
//! **Units.** The paper calls `m_d` a "proportion" without saying of what. We read it as the
//! share of the *excess slope* relaxed: moving a thickness `h` across a face of length `ℓ`
//! changes the slope between the two cells by `2h/ℓ`, so the thickness moved is
//! `m_d = (δt · k_m / 2) · ℓ · max(0, |s_d| − s_d0)`, signed like `s_d` (positive: out of
//! `p`). `k_m` is then the rate, per day, at which an isolated step above the rest slope
//! relaxes; `ℓ` is `cell_size_x` across east/west faces and `cell_size_y` across north/south
//! faces.
//!
//! **Conservation (gather form).** Each face flux is a function of the two surfaces in a
//! canonical order (west→east, north→south), so both cells compute the same value and one
//! negates it exactly. The paper's `(i + P)/o` limiter depends on the neighbours' limited
//! inflow, which is circular in a parallel update; we scale a cell's outgoing fluxes by
//! `min(1, P/o)` (its own powder only), computed in a first pass, and apply every scaled face
//! flux to both sides in a second pass. Volume is conserved to f32 rounding and no cell goes
//! negative, whatever the thread count. The limiter is stricter than the paper's (a cell
//! cannot pass on in the same sub-step what it receives); sub-steps make the difference small.
//!
//! **Stability (CFL).** Linearised, one sub-step is `A_p ← A_p − (f/2) Σ_n (A_p − A_n)` with
//! `f = k_m δt_sub`: the checkerboard mode is multiplied by `1 − 4f`, so `f ≤ 1/4` keeps every
//! mode decaying without oscillation (the threshold and the limiter only reduce fluxes). A
//! step is split into `⌈k_m δt / 0.25⌉` sub-steps; the defaults (`k_m` = 0.5/day, two events
//! per day) need one.
//!
//! **Borders.** Nodata cells are walls (no flux). At the grid border the default
//! [`DiffusionBorder::Open`] lets powder leave where the terrain keeps descending outwards: the
//! ghost cell beyond the border continues the bedrock linearly and carries the border cell's
//! snow depth, so the outward slope is the bedrock slope `(B_inner − B_p)/ℓ`; powder above the
//! rest slope flows out (never in) and is reported as `border_outflow`.
//! [`DiffusionBorder::Closed`] has no flux across the border.

use crate::VolumeChange;
use crate::phenomenon::{
    PhenomenonError, Validity, check_dt, check_range, fill_surface, with_validity,
};
use serde::{Deserialize, Serialize};
use snowscape_terrain::{LayeredTerrain, SnowLayer, parallel};

/// Largest share `f = k_m · δt_sub` of the excess slope relaxed in one sub-step (see the
/// module documentation: `1 − 4f ≥ 0`).
pub const MAX_RELAXATION_PER_SUBSTEP: f64 = 0.25;

/// What happens to powder at the grid border.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum DiffusionBorder {
    /// Powder leaves where the bedrock descends out of the grid steeper than the rest slope;
    /// counted as border outflow.
    #[default]
    Open,
    /// No flux across the border.
    Closed,
}

/// Parameters of powder diffusion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct DiffusionParams {
    /// Rest slope `s_d0` (rise over run, dimensionless) below which powder does not move.
    /// Cordonnier 2018 Table 2 (read by units, `docs/src/model.md#sources-and-the-reading-of-table-2`): 0.5.
    pub rest_slope: f64,
    /// Shift rate `k_m`, 1/day: share of the excess slope relaxed per day.
    /// Cordonnier 2018 Table 2: 0.5 day⁻¹.
    pub k_m: f64,
    /// Border condition. Chosen here: open, so powder spilling off a cut-out DEM leaves it.
    pub border: DiffusionBorder,
}

impl Default for DiffusionParams {
    fn default() -> Self {
        Self {
            rest_slope: 0.5,
            k_m: 0.5,
            border: DiffusionBorder::Open,
        }
    }
}

impl DiffusionParams {
    /// Checks the rest slope is in [0, 10] (rise over run) and the rate in [0, 100] 1/day
    /// (two hundred times Table 2's 0.5; the sub-step count grows with it).
    pub fn validate(&self) -> Result<(), PhenomenonError> {
        const P: &str = "powder diffusion";
        check_range(P, "rest_slope", self.rest_slope, [0.0, 10.0], "")?;
        check_range(P, "k_m", self.k_m, [0.0, 100.0], " 1/day")
    }

    /// Number of sub-steps a step of `dt_days` is split into (0 when nothing moves).
    pub fn substeps(&self, dt_days: f64) -> u32 {
        let f = self.k_m * dt_days;
        if f <= 0.0 {
            0
        } else {
            (f / MAX_RELAXATION_PER_SUBSTEP).ceil().max(1.0) as u32
        }
    }
}

/// Volumes moved by one diffusion step, m³ of snow.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DiffusionReport {
    /// Powder moved across interior faces (each face counted once per sub-step).
    pub moved: f64,
    /// Powder that left the grid across its border.
    pub border_outflow: f64,
    /// Sub-steps taken.
    pub substeps: u32,
}

impl DiffusionReport {
    /// The step's volume budget: border outflow is the only volume removed.
    pub fn volume_change(&self) -> VolumeChange {
        VolumeChange {
            added: 0.0,
            removed: self.border_outflow,
        }
    }
}

/// Reusable buffers of the diffusion step.
#[derive(Debug, Clone, Default)]
pub struct DiffusionScratch {
    surface: Vec<f32>,
    surface_next: Vec<f32>,
    scale: Vec<f32>,
}

/// Thickness moved across one face from the cell of surface `a_from` to the cell of
/// surface `a_to` (negative: the other way), m. `threshold = s_d0 · ℓ` is the rise at rest,
/// `c = k_m δt / 2` (see the module documentation).
#[inline(always)]
pub fn face_flux(a_from: f32, a_to: f32, threshold: f32, c: f32) -> f32 {
    let d = a_from - a_to;
    c * (d.abs() - threshold).max(0.0).copysign(d)
}

/// Sub-step constants and read-only maps.
struct Stencil<'a, V> {
    a: &'a [f32],
    bedrock: &'a [f32],
    valid: &'a V,
    w: usize,
    h: usize,
    /// Rest rise across east/west and north/south faces, m.
    tx: f32,
    ty: f32,
    c: f32,
    open: bool,
}

/// Face order of the per-cell flux arrays: east, west, north, south.
const EAST: usize = 0;
const WEST: usize = 1;
const NORTH: usize = 2;
const SOUTH: usize = 3;

impl<V: Validity> Stencil<'_, V> {
    /// Outward fluxes (E, W, N, S) of the interior cell `col` (in `1..w-1`) of a row, from
    /// the surface rows above, at and below it; `i` is its flat index. All zero for a nodata
    /// cell.
    #[inline(always)]
    fn interior(&self, [up, mid, dn]: [&[f32]; 3], col: usize, i: usize) -> [f32; 4] {
        let w = self.w;
        let ap = mid[col];
        let own = self.valid.at(i);
        let face = |j: usize, f: f32| if own && self.valid.at(j) { f } else { 0.0 };
        [
            face(i + 1, face_flux(ap, mid[col + 1], self.tx, self.c)),
            face(i - 1, -face_flux(mid[col - 1], ap, self.tx, self.c)),
            face(i - w, -face_flux(up[col], ap, self.ty, self.c)),
            face(i + w, face_flux(ap, dn[col], self.ty, self.c)),
        ]
    }

    /// The surface rows above, at and below interior row `row`, each `w` long.
    #[inline(always)]
    fn rows(&self, row: usize) -> [&[f32]; 3] {
        let (w, base) = (self.w, row * self.w);
        [
            &self.a[base - w..base],
            &self.a[base..base + w],
            &self.a[base + w..base + 2 * w],
        ]
    }

    /// Outward fluxes (E, W, N, S) of any cell, and which of them cross the grid border.
    fn general(&self, col: usize, row: usize) -> ([f32; 4], [bool; 4]) {
        let (a, w, h) = (self.a, self.w, self.h);
        let i = row * w + col;
        let ap = a[i];
        let inside = [col + 1 < w, col > 0, row > 0, row + 1 < h];
        let nb = |k: usize| match k {
            EAST => i + 1,
            WEST => i - 1,
            NORTH => i - w,
            _ => i + w,
        };
        let opposite = [WEST, EAST, SOUTH, NORTH];
        let mut flux = [0.0f32; 4];
        for k in 0..4 {
            let t = if k < 2 { self.tx } else { self.ty };
            flux[k] = if inside[k] {
                let j = nb(k);
                match (self.valid.at(j), k) {
                    (false, _) => 0.0,
                    (true, EAST | SOUTH) => face_flux(ap, a[j], t, self.c),
                    (true, _) => -face_flux(a[j], ap, t, self.c),
                }
            } else if self.open && inside[opposite[k]] && self.valid.at(nb(opposite[k])) {
                // Ghost cell: bedrock continued linearly, same snow depth.
                let inner = self.bedrock[nb(opposite[k])];
                face_flux(inner, self.bedrock[i], t, self.c).max(0.0)
            } else {
                0.0
            };
        }
        (flux, inside.map(|x| !x))
    }
}

/// Rows whose cells `1..w-1` take the interior fast path (`None`: the whole row is border).
#[inline(always)]
fn interior_span(w: usize, h: usize, row: usize) -> Option<std::ops::Range<usize>> {
    (row > 0 && row + 1 < h && w >= 3).then(|| 1..w - 1)
}

/// The share `min(1, P/o)` of its outgoing fluxes `f` a cell holding `p` can afford.
#[inline(always)]
fn limiter(f: [f32; 4], p: f32) -> f32 {
    let out = f[0].max(0.0) + f[1].max(0.0) + f[2].max(0.0) + f[3].max(0.0);
    if out > p { p / out } else { 1.0 }
}

/// Pass 1: every cell's limiter.
fn limiter_pass<V: Validity>(st: &Stencil<V>, powder: &[f32], scale: &mut [f32]) {
    let w = st.w;
    parallel::for_each_row(w, scale, |row, line| {
        let base = row * w;
        let p = &powder[base..base + w];
        let general = |col: usize| {
            if st.valid.at(base + col) {
                limiter(st.general(col, row).0, p[col])
            } else {
                0.0
            }
        };
        match interior_span(w, st.h, row) {
            Some(span) => {
                line[0] = general(0);
                line[w - 1] = general(w - 1);
                let rows = st.rows(row);
                for col in span {
                    let s = limiter(st.interior(rows, col, base + col), p[col]);
                    line[col] = if st.valid.at(base + col) { s } else { 0.0 };
                }
            }
            None => {
                for (col, s) in line.iter_mut().enumerate() {
                    *s = general(col);
                }
            }
        }
    });
}

/// Pass 2: applies the scaled face fluxes; returns per-row (moved, border outflow) in metres.
fn update_pass<V: Validity>(
    st: &Stencil<V>,
    scale: &[f32],
    powder: &mut [f32],
    a_next: &mut [f32],
) -> Vec<(f64, f64)> {
    let w = st.w;
    parallel::map_rows_with(
        w,
        (powder, a_next),
        || vec![0.0f32; w],
        |moved_row, row, (p_line, a_line)| {
            let base = row * w;
            let a = &st.a[base..base + w];
            let mut border = 0.0f64;
            let mut general = |col: usize, p: &mut f32, a_new: &mut f32, moved: &mut f32| {
                let i = base + col;
                if !st.valid.at(i) {
                    (*a_new, *moved) = (a[col], 0.0);
                    return;
                }
                let (f, ghost) = st.general(col, row);
                let sp = scale[i];
                let (mut out, mut inflow, mut ghost_out) = (0.0f32, 0.0f32, 0.0f32);
                for k in 0..4 {
                    if f[k] > 0.0 {
                        *(if ghost[k] { &mut ghost_out } else { &mut out }) += f[k] * sp;
                    } else if f[k] < 0.0 {
                        let j = match k {
                            EAST => i + 1,
                            WEST => i - 1,
                            NORTH => i - w,
                            _ => i + w,
                        };
                        inflow += -f[k] * scale[j];
                    }
                }
                let p_new = (*p - out - ghost_out + inflow).max(0.0);
                *a_new = a[col] + (p_new - *p);
                *p = p_new;
                *moved = out;
                border += ghost_out as f64;
            };
            match interior_span(w, st.h, row) {
                Some(span) => {
                    general(0, &mut p_line[0], &mut a_line[0], &mut moved_row[0]);
                    let last = w - 1;
                    general(
                        last,
                        &mut p_line[last],
                        &mut a_line[last],
                        &mut moved_row[last],
                    );
                    let s_up = &scale[base - w..base];
                    let s_mid = &scale[base..base + w];
                    let s_dn = &scale[base + w..base + 2 * w];
                    let (p_line, a_line) = (&mut p_line[..w], &mut a_line[..w]);
                    let moved_row = &mut moved_row[..w];
                    let rows = st.rows(row);
                    for col in span {
                        let f = st.interior(rows, col, base + col);
                        let sp = s_mid[col];
                        let out = f.iter().map(|f| f.max(0.0)).sum::<f32>() * sp;
                        let inflow = (-f[EAST]).max(0.0) * s_mid[col + 1]
                            + (-f[WEST]).max(0.0) * s_mid[col - 1]
                            + (-f[NORTH]).max(0.0) * s_up[col]
                            + (-f[SOUTH]).max(0.0) * s_dn[col];
                        let p_old = p_line[col];
                        let p_new = (p_old - out + inflow).max(0.0);
                        p_line[col] = p_new;
                        a_line[col] = a[col] + (p_new - p_old);
                        moved_row[col] = out;
                    }
                }
                None => {
                    for col in 0..w {
                        general(col, &mut p_line[col], &mut a_line[col], &mut moved_row[col]);
                    }
                }
            }
            let moved = crate::row_sum(moved_row);
            (moved, border)
        },
    )
}

/// Diffuses the powder layer over `dt_days`.
pub fn step(
    params: &DiffusionParams,
    terrain: &mut LayeredTerrain,
    scratch: &mut DiffusionScratch,
    dt_days: f64,
) -> Result<DiffusionReport, PhenomenonError> {
    params.validate()?;
    check_dt(dt_days)?;
    let substeps = params.substeps(dt_days);
    let mut report = DiffusionReport {
        substeps,
        ..Default::default()
    };
    if substeps == 0 {
        return Ok(report);
    }
    let geometry = terrain.geometry().clone();
    let mask = terrain.mask().clone();
    let n = geometry.len();
    fill_surface(terrain, &mut scratch.surface);
    scratch.surface_next.resize(n, 0.0);
    scratch.scale.resize(n, 0.0);
    let c = (params.k_m * dt_days / substeps as f64 / 2.0) as f32;
    let mut rows = Vec::with_capacity(geometry.height() * substeps as usize);
    for _ in 0..substeps {
        with_validity!(mask, |valid| {
            let st = Stencil {
                a: &scratch.surface,
                bedrock: &terrain.bedrock,
                valid,
                w: geometry.width(),
                h: geometry.height(),
                tx: (params.rest_slope * geometry.cell_size_x()) as f32,
                ty: (params.rest_slope * geometry.cell_size_y()) as f32,
                c,
                open: params.border == DiffusionBorder::Open,
            };
            limiter_pass(
                &st,
                &terrain.snow[SnowLayer::Powder.index()],
                &mut scratch.scale,
            );
            let powder = &mut terrain.snow[SnowLayer::Powder.index()];
            rows.extend(update_pass(
                &st,
                &scratch.scale,
                powder,
                &mut scratch.surface_next,
            ));
        });
        std::mem::swap(&mut scratch.surface, &mut scratch.surface_next);
    }
    let area = geometry.cell_area();
    report.moved = rows.iter().map(|r| r.0).sum::<f64>() * area;
    report.border_outflow = rows.iter().map(|r| r.1).sum::<f64>() * area;
    Ok(report)
}

#[cfg(test)]
mod tests;
