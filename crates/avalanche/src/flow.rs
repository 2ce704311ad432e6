//! The flowing snow and one pure time step of the avalanche pipe model.
//!
//! **State.** Per cell the flowing thickness `h` (m) on a bed `B` that does not move
//! (bedrock + compacted + stable snow, m); per *pipe* (the link between a cell and one of its 8
//! neighbours) a velocity `u` (m/s) along the pipe. Every cell owns the four pipes towards east,
//! south, south-east and south-west, so each link is stored once. The surface is `A = B + h`.
//! The state is padded by a ghost ring of cells around the grid (see *Borders*).
//!
//! **Momentum (per pipe, from cell `i` to neighbour `j`, length `L`, unit vector `e`).**
//!
//! ```text
//! ∂u/∂t = −g (A_j − A_i)/L  −  (v·∇) u  −  α · g·tanθc · (e·v̂)  −  (1 − α) · kv · h_face · u
//! ```
//!
//! The first term is the paper's `ΔP/(ρ·dx)` (ρ cancels: `ΔP = ρ g ΔA`); the second is the
//! momentum advection the paper omits (needed for Ritter's dam-break front, DESIGN.md §4): each
//! pipe direction forms a regular lattice, `u` is advected by the velocity `v` at the pipe (mean
//! of the two cells' velocities, reconstructed from their 8 pipes) with first-order upwind
//! differences on that lattice. The third is the Coulomb yield force of norm `g·tanθc`,
//! applied as one vector: the trial velocity at the pipe `v + δt·(−g∇A)` (mean of the two
//! cells' reconstructed velocities and central-difference surface gradients) is slowed by
//! `g·tanθc·δt` along its own direction and each pipe takes its projection `e·v̂`. As in the
//! paper, where the flow is null or the force would reverse it, the velocity is set to zero
//! (static friction): snow at rest holds while `|∇A| ≤ tanθc`, the same criterion in every
//! direction, and a sheet on a plane of slope `tanθ > tanθc` accelerates at `g·(tanθ − tanθc)`
//! (tests/validation.rs). The fourth is the viscous term `−kv·U·φ` of the paper written for the velocity (`h_face` = mean depth of the two
//! cells), applied implicitly. `α ∈ [0, 1]` mixes dry (Coulomb) and wet (viscous) snow.
//!
//! **Mass (per cell).** The volume through a pipe in a sub-step is `F = w · h_up · u · δt`, with
//! `h_up` the depth of the upwind cell: the *face cross-section* is `w·h_up`, not the paper's
//! constant `dx²`, which makes waves travel at `sqrt(g·h)` instead of `sqrt(g·dx)` (DESIGN.md
//! §4). The widths `w` make the 8-pipe stencil consistent with `∂h/∂t + ∇·(h v) = 0` and
//! isotropic: with `Ld = sqrt(dx² + dy²)`, east pipes have `w = dy·dy²/Ld²`, south pipes
//! `w = dx·dx²/Ld²`, diagonal pipes `w = dx·dy/(2·Ld)` (square cells: `dx/2` and `dx/(2√2)`;
//! a pipe velocity is the projection `e·v` of the flow velocity, and the 4 pipe directions then
//! sum to `∇·(h v)` with no cross term). Then `h_i ← h_i − Σ F_out/(dx·dy) + Σ F_in/(dx·dy)`.
//!
//! **Positivity (gather form).** A cell's total outflow `V_out` is scaled by the paper's
//! `min(V_out, dx·dy·h)/V_out`; the factor of the *upwind* cell scales the pipe's volume and
//! velocity once, and both cells read the same scaled value, so volume is conserved to round-off
//! and `h ≥ 0` (round-off negatives, `~1e-17 m`, are clamped to 0).
//!
//! **Time step (CFL).** A call to [`step`] of length `dt` is split into sub-steps
//! `δt ≤ C · min(dx, dy) / (max|u| + sqrt(g · max h))` and `δt ≤ C · sqrt(min(dx, dy)/g)` (the
//! latter bounds the first sub-step from rest on steep beds), `C` = [`AvalancheParams::courant`].
//!
//! **Borders.** Nodata cells are walls (pipes to them carry nothing). [`Border::Closed`] makes
//! the ghost ring walls; [`Border::Open`] gives the ghost ring the bed of the nearest grid cell
//! and no snow: snow that flows into it leaves the grid and is counted as `border_outflow`.
//!
//! **Cost.** Only a box around the flowing snow is visited: every cell with snow and every
//! moving pipe lies inside the box shrunk by one cell, and snow moves at most one cell per
//! sub-step, so the box grows by at most one cell per sub-step and shrinks with the snow. The
//! cost of a sub-step is proportional to the box area (the footprint), not to the grid.
//!
//! **Determinism.** Every pass is a gather over rows (rayon), each row writes only its own
//! cells, and per-row sums are added in row order, so results are bit-identical for any thread
//! count.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use snowscape_terrain::{GridGeometry, NodataMask};
use thiserror::Error;

/// Gravitational acceleration, m/s² (the paper's `g = 9.81`).
pub const G: f64 = 9.81;

/// Per-cell flow quantities of a sub-step: `[vx, vy, h·vx, h·vy, ∂A/∂x, ∂A/∂y]`.
type CellFlow = [f64; 6];

/// A depth below which a cell is treated as dry for the upwind face cross-section, m.
const DRY: f64 = 1e-12;

/// Pipe directions owned by a cell, as (column step, row step): east, south, south-east,
/// south-west (rows grow southwards).
pub const DIRS: [(isize, isize); 4] = [(1, 0), (0, 1), (1, 1), (-1, 1)];

/// What happens at the edge of the grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Border {
    /// Snow leaves the grid (counted in [`AvalancheReport::border_outflow`]).
    #[default]
    Open,
    /// The border is a wall.
    Closed,
}

/// Parameters of the avalanche flow (Cordonnier et al. 2018, Table 2 via DESIGN.md §4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AvalancheParams {
    /// Snow density ρ, kg/m³. Default 500 (Table 2). It cancels out of every acceleration
    /// (`ΔP/ρ = g·ΔA`) and is kept for reports and mass conversions.
    pub density: f64,
    /// Rest angle θc of the snow, degrees: Coulomb friction `g·tanθc`. Default 30 (Table 2).
    pub rest_angle_deg: f64,
    /// Viscous coefficient kv of the term `−kv·h·u`, 1/(m·s). Default 5e-4 (Table 2, which
    /// gives no unit; DESIGN.md §4 writes /s²).
    pub k_viscous: f64,
    /// Dry/wet mix α ∈ [0, 1]: weight of the Coulomb term, `1 − α` weighs the viscous term.
    /// The paper makes it proportional to snow temperature; here it is an input. Default 1
    /// (chosen here: dry granular snow, the case the rest-angle validation checks).
    pub alpha: f64,
    /// Courant number C of the automatic sub-step, in (0, 1]. Default 0.4 (chosen here: the
    /// explicit pipe update is stable below ~0.5 on the 8-neighbour stencil).
    pub courant: f64,
    /// Include momentum advection `(v·∇)u`. Default true (DESIGN.md §4: needed for Ritter's
    /// front); false gives the paper's hydrostatic pipe model with a depth cross-section.
    pub momentum_advection: bool,
    /// Grid border condition. Default open.
    pub border: Border,
    /// Upper bound on the number of sub-steps in one call to [`step`]. Default 1 000 000.
    pub max_substeps: usize,
}

impl Default for AvalancheParams {
    fn default() -> Self {
        Self {
            density: 500.0,
            rest_angle_deg: 30.0,
            k_viscous: 5e-4,
            alpha: 1.0,
            courant: 0.4,
            momentum_advection: true,
            border: Border::Open,
            max_substeps: 1_000_000,
        }
    }
}

impl AvalancheParams {
    /// Checks every field, naming the offending one.
    pub fn validate(&self) -> Result<(), AvalancheError> {
        let bad = |name: &'static str, value: f64, expected: &'static str| {
            Err(AvalancheError::InvalidParameter {
                name,
                value,
                expected,
            })
        };
        if !(self.density.is_finite() && self.density > 0.0) {
            return bad("density", self.density, "finite and > 0");
        }
        if !(self.rest_angle_deg.is_finite() && (0.0..90.0).contains(&self.rest_angle_deg)) {
            return bad("rest_angle_deg", self.rest_angle_deg, "in [0, 90)");
        }
        if !(self.k_viscous.is_finite() && self.k_viscous >= 0.0) {
            return bad("k_viscous", self.k_viscous, "finite and >= 0");
        }
        if !(0.0..=1.0).contains(&self.alpha) {
            return bad("alpha", self.alpha, "in [0, 1]");
        }
        if !(self.courant > 0.0 && self.courant <= 1.0) {
            return bad("courant", self.courant, "in (0, 1]");
        }
        if self.max_substeps == 0 {
            return bad("max_substeps", 0.0, ">= 1");
        }
        Ok(())
    }
}

/// Errors of the avalanche module, carrying the offending values.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum AvalancheError {
    /// A parameter is out of range.
    #[error("avalanche parameter {name} = {value} must be {expected}")]
    InvalidParameter {
        /// Field name.
        name: &'static str,
        /// Offending value.
        value: f64,
        /// The valid range.
        expected: &'static str,
    },
    /// The time step is negative or not finite.
    #[error("avalanche time step {0} s must be finite and >= 0")]
    InvalidTimeStep(f64),
    /// A per-cell input has the wrong length.
    #[error("{what} has {got} values, the grid has {expected} cells")]
    LengthMismatch {
        /// What was passed.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The number of grid cells.
        expected: usize,
    },
    /// A value that must be finite and non-negative is not.
    #[error("{what} at cell {index} is {value}, must be finite and >= 0")]
    BadValue {
        /// What was passed.
        what: &'static str,
        /// Cell index (row-major, unpadded).
        index: usize,
        /// Offending value.
        value: f64,
    },
    /// The terrain does not have the state's geometry.
    #[error("terrain is {terrain_width}x{terrain_height}, the avalanche state {width}x{height}")]
    GeometryMismatch {
        /// State width.
        width: usize,
        /// State height.
        height: usize,
        /// Terrain width.
        terrain_width: usize,
        /// Terrain height.
        terrain_height: usize,
    },
    /// The sub-step limit was reached before the step was done.
    #[error("avalanche step stopped after {done} sub-steps with {remaining} s of {dt} s left")]
    TooManySubsteps {
        /// Sub-steps done.
        done: usize,
        /// Time left, s.
        remaining: f64,
        /// Requested step, s.
        dt: f64,
    },
}

/// What one call to [`step`] did.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct AvalancheReport {
    /// Volume that crossed pipes, summed over pipes and sub-steps, m³.
    pub moved_volume: f64,
    /// Volume that left the grid across its border, m³.
    pub border_outflow: f64,
    /// Largest pipe speed at the end of any sub-step, m/s.
    pub max_speed: f64,
    /// Cells visited in the last sub-step (the active box, ghost ring included).
    pub active_cells: usize,
    /// Grid cells holding flowing snow after the step.
    pub flowing_cells: usize,
    /// Number of sub-steps.
    pub substeps: usize,
    /// Smallest sub-step, s (0 when no sub-step ran).
    pub dt_min: f64,
    /// Largest sub-step, s.
    pub dt_max: f64,
}

/// An inclusive box of padded cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ActiveBox {
    pub r0: usize,
    pub r1: usize,
    pub c0: usize,
    pub c1: usize,
}

impl ActiveBox {
    fn grown(self, pw: usize, ph: usize) -> Self {
        Self {
            r0: self.r0.saturating_sub(1),
            r1: (self.r1 + 1).min(ph - 1),
            c0: self.c0.saturating_sub(1),
            c1: (self.c1 + 1).min(pw - 1),
        }
    }
    fn area(self) -> usize {
        (self.r1 - self.r0 + 1) * (self.c1 - self.c0 + 1)
    }
}

/// Flowing snow over a grid: thickness per cell, velocity per pipe, the fixed bed.
#[derive(Debug, Clone, PartialEq)]
pub struct AvalancheState {
    pub(crate) geometry: GridGeometry,
    pub(crate) pw: usize,
    pub(crate) ph: usize,
    /// Padded nodata flags (ghost ring false).
    pub(crate) nodata: Vec<bool>,
    /// Padded bed altitude, m.
    pub(crate) bed: Vec<f64>,
    /// Padded flowing thickness, m.
    pub(crate) h: Vec<f64>,
    /// Padded pipe velocities (east, south, south-east, south-west), m/s.
    pub(crate) pipes: Vec<[f64; 4]>,
    /// Box holding all snow and moving pipes, grown by one cell; `None` when nothing flows.
    pub(crate) active: Option<ActiveBox>,
}

impl AvalancheState {
    /// A state with no flowing snow on `bed` (m, row-major, one value per grid cell).
    pub fn new(
        geometry: &GridGeometry,
        mask: &NodataMask,
        bed: &[f64],
    ) -> Result<Self, AvalancheError> {
        let (w, hgt) = (geometry.width(), geometry.height());
        if bed.len() != w * hgt {
            return Err(AvalancheError::LengthMismatch {
                what: "bed",
                got: bed.len(),
                expected: w * hgt,
            });
        }
        let (pw, ph) = (w + 2, hgt + 2);
        let mut nodata = vec![false; pw * ph];
        let mut pbed = vec![0.0; pw * ph];
        for r in 0..ph {
            for c in 0..pw {
                let ic = c.clamp(1, w) - 1;
                let ir = r.clamp(1, hgt) - 1;
                let i = ir * w + ic;
                let inside = c >= 1 && c <= w && r >= 1 && r <= hgt;
                if inside && !mask.is_valid(i) {
                    nodata[r * pw + c] = true;
                    continue;
                }
                let b = bed[i];
                if mask.is_valid(i) && !b.is_finite() {
                    return Err(AvalancheError::BadValue {
                        what: "bed",
                        index: i,
                        value: b,
                    });
                }
                pbed[r * pw + c] = if b.is_finite() { b } else { 0.0 };
            }
        }
        Ok(Self {
            geometry: geometry.clone(),
            pw,
            ph,
            nodata,
            bed: pbed,
            h: vec![0.0; pw * ph],
            pipes: vec![[0.0; 4]; pw * ph],
            active: None,
        })
    }

    /// A state on the avalanche bed of a layered terrain: bedrock + compacted + stable snow.
    pub fn from_terrain(
        terrain: &snowscape_terrain::LayeredTerrain,
    ) -> Result<Self, AvalancheError> {
        use snowscape_terrain::SnowLayer;
        let bed: Vec<f64> = (0..terrain.bedrock.len())
            .map(|i| {
                terrain.bedrock[i] as f64
                    + terrain.layer(SnowLayer::Compacted)[i] as f64
                    + terrain.layer(SnowLayer::Stable)[i] as f64
            })
            .collect();
        Self::new(terrain.geometry(), terrain.mask(), &bed)
    }

    /// The grid geometry.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    #[inline]
    pub(crate) fn pad(&self, col: usize, row: usize) -> usize {
        (row + 1) * self.pw + col + 1
    }

    /// Flowing thickness at a grid cell, m.
    pub fn thickness_at(&self, col: usize, row: usize) -> f64 {
        self.h[self.pad(col, row)]
    }

    /// Bed altitude at a grid cell, m.
    pub fn bed_at(&self, col: usize, row: usize) -> f64 {
        self.bed[self.pad(col, row)]
    }

    /// Flowing thickness of every grid cell (row-major), m.
    pub fn thickness(&self) -> Vec<f64> {
        let (w, hgt) = (self.geometry.width(), self.geometry.height());
        let mut out = Vec::with_capacity(w * hgt);
        for r in 0..hgt {
            let k = self.pad(0, r);
            out.extend_from_slice(&self.h[k..k + w]);
        }
        out
    }

    /// Sets the flowing thickness of every grid cell (m, row-major) and stops all motion.
    pub fn set_thickness(&mut self, h: &[f64]) -> Result<(), AvalancheError> {
        let (w, hgt) = (self.geometry.width(), self.geometry.height());
        if h.len() != w * hgt {
            return Err(AvalancheError::LengthMismatch {
                what: "thickness",
                got: h.len(),
                expected: w * hgt,
            });
        }
        for (i, &v) in h.iter().enumerate() {
            if !(v.is_finite() && v >= 0.0) {
                return Err(AvalancheError::BadValue {
                    what: "thickness",
                    index: i,
                    value: v,
                });
            }
        }
        self.pipes.iter_mut().for_each(|p| *p = [0.0; 4]);
        self.h.iter_mut().for_each(|v| *v = 0.0);
        for r in 0..hgt {
            for c in 0..w {
                let k = self.pad(c, r);
                if !self.nodata[k] {
                    self.h[k] = h[r * w + c];
                }
            }
        }
        self.refresh_active();
        Ok(())
    }

    /// Adds `dh` metres of flowing snow (at rest) to one grid cell, keeping the motion elsewhere.
    pub fn add_thickness(&mut self, col: usize, row: usize, dh: f64) -> Result<(), AvalancheError> {
        let k = self.pad(col, row);
        if !(dh.is_finite() && dh >= 0.0) {
            return Err(AvalancheError::BadValue {
                what: "added thickness",
                index: row * self.geometry.width() + col,
                value: dh,
            });
        }
        if self.nodata[k] || dh == 0.0 {
            return Ok(());
        }
        self.h[k] += dh;
        let (r, c) = (k / self.pw, k % self.pw);
        let cell = ActiveBox {
            r0: r,
            r1: r,
            c0: c,
            c1: c,
        }
        .grown(self.pw, self.ph);
        self.active = Some(match self.active {
            None => cell,
            Some(b) => ActiveBox {
                r0: b.r0.min(cell.r0),
                r1: b.r1.max(cell.r1),
                c0: b.c0.min(cell.c0),
                c1: b.c1.max(cell.c1),
            },
        });
        Ok(())
    }

    /// Flowing volume on the grid, m³ (rows summed in order).
    pub fn flowing_volume(&self) -> f64 {
        let area = self.geometry.cell_area();
        self.thickness().iter().sum::<f64>() * area
    }

    /// Largest pipe speed, m/s.
    pub fn max_speed(&self) -> f64 {
        self.pipes
            .iter()
            .flat_map(|p| p.iter())
            .fold(0.0f64, |m, u| m.max(u.abs()))
    }

    /// The "snow moving" layer: a grid cell is active if it or one of its 8 neighbours holds
    /// flowing snow.
    pub fn moving_mask(&self) -> Vec<bool> {
        let (w, hgt) = (self.geometry.width(), self.geometry.height());
        let mut out = vec![false; w * hgt];
        for r in 0..hgt {
            for c in 0..w {
                let k = self.pad(c, r);
                out[r * w + c] = (-1isize..=1).any(|dr| {
                    (-1isize..=1).any(|dc| {
                        let kk = (k as isize + dr * self.pw as isize + dc) as usize;
                        self.h[kk] > 0.0
                    })
                });
            }
        }
        out
    }

    /// Velocity of the snow in a grid cell (m/s; x east, y south), reconstructed from its 8
    /// pipes as in the advection step.
    pub fn velocity_at(&self, col: usize, row: usize) -> [f64; 2] {
        let pg = PipeGeometry::new(&self.geometry, self.ph);
        let k = self.pad(col, row);
        let mut p = [0.0; 4];
        for (d, pd) in p.iter_mut().enumerate() {
            let (dc, dr) = DIRS[d];
            let kb = (k as isize - dr * self.pw as isize - dc) as usize;
            *pd = 0.5 * (self.pipes[k][d] + self.pipes[kb][d]);
        }
        let vx_d = (p[2] - p[3]) / (2.0 * pg.e[2][0]);
        let vy_d = (p[2] + p[3]) / (2.0 * pg.e[2][1]);
        [0.5 * (p[0] + vx_d), 0.5 * (p[1] + vy_d)]
    }

    /// Whether a grid cell and all 8 pipes touching it are at rest.
    pub fn at_rest(&self, col: usize, row: usize) -> bool {
        let k = self.pad(col, row);
        self.pipes[k].iter().all(|&u| u == 0.0)
            && DIRS.iter().enumerate().all(|(d, &(dc, dr))| {
                let kb = (k as isize - dr * self.pw as isize - dc) as usize;
                self.pipes[kb][d] == 0.0
            })
    }

    /// Recomputes the active box by scanning the whole grid (after external edits).
    pub(crate) fn refresh_active(&mut self) {
        let mut b: Option<ActiveBox> = None;
        for r in 0..self.ph {
            for c in 0..self.pw {
                let k = r * self.pw + c;
                if self.h[k] > 0.0 || self.pipes[k].iter().any(|&u| u != 0.0) {
                    b = Some(match b {
                        None => ActiveBox {
                            r0: r,
                            r1: r,
                            c0: c,
                            c1: c,
                        },
                        Some(b) => ActiveBox {
                            r0: b.r0.min(r),
                            r1: b.r1.max(r),
                            c0: b.c0.min(c),
                            c1: b.c1.max(c),
                        },
                    });
                }
            }
        }
        self.active = b.map(|b| b.grown(self.pw, self.ph));
    }
}

/// Reusable work buffers for [`step`] (allocated on first use).
#[derive(Debug, Clone, Default)]
pub struct AvalancheScratch {
    /// Per padded cell: velocity (vx, vy), discharge (h·vx, h·vy) and surface gradient
    /// (∂A/∂x, ∂A/∂y; NaN on the ghost ring and nodata cells).
    vel: Vec<CellFlow>,
    new_pipes: Vec<[f64; 4]>,
    flux: Vec<[f64; 4]>,
    factor: Vec<f64>,
}

/// Pipe geometry: length, width and unit vector (x east, y south) per owned direction.
struct PipeGeometry {
    len: [f64; 4],
    width: [f64; 4],
    e: [[f64; 2]; 4],
    dx: f64,
    dy: f64,
    area: f64,
    /// Padded height of the grid, cells.
    ph: usize,
}

impl PipeGeometry {
    fn new(geometry: &GridGeometry, ph: usize) -> Self {
        let (dx, dy) = (geometry.cell_size_x(), geometry.cell_size_y());
        let ld = (dx * dx + dy * dy).sqrt();
        Self {
            len: [dx, dy, ld, ld],
            width: [
                dy * dy * dy / (ld * ld),
                dx * dx * dx / (ld * ld),
                dx * dy / (2.0 * ld),
                dx * dy / (2.0 * ld),
            ],
            e: [
                [1.0, 0.0],
                [0.0, 1.0],
                [dx / ld, dy / ld],
                [-dx / ld, dy / ld],
            ],
            dx,
            dy,
            area: dx * dy,
            ph,
        }
    }
}

/// Per-row results of the final pass of a sub-step.
#[derive(Clone, Copy, Default)]
struct RowStats {
    outflow: f64,
    flowing: usize,
    cols: Option<(usize, usize)>,
}

/// Advances the flowing snow by `dt` seconds in CFL-limited sub-steps.
///
/// Pure apart from `state` and `scratch`; deterministic for any rayon thread count.
pub fn step(
    params: &AvalancheParams,
    state: &mut AvalancheState,
    scratch: &mut AvalancheScratch,
    dt: f64,
) -> Result<AvalancheReport, AvalancheError> {
    params.validate()?;
    if !(dt.is_finite() && dt >= 0.0) {
        return Err(AvalancheError::InvalidTimeStep(dt));
    }
    let n = state.pw * state.ph;
    if scratch.vel.len() != n {
        scratch.vel = vec![[0.0; 6]; n];
        scratch.new_pipes = vec![[0.0; 4]; n];
        scratch.flux = vec![[0.0; 4]; n];
        scratch.factor = vec![1.0; n];
    }
    let pg = PipeGeometry::new(&state.geometry, state.ph);
    let dmin = pg.dx.min(pg.dy);
    let mut report = AvalancheReport::default();
    let mut elapsed = 0.0;
    while elapsed < dt {
        let Some(bx) = state.active else { break };
        if report.substeps >= params.max_substeps {
            return Err(AvalancheError::TooManySubsteps {
                done: report.substeps,
                remaining: dt - elapsed,
                dt,
            });
        }
        let (umax, hmax) = cfl_maxima(state, bx);
        let speed = umax + (G * hmax).sqrt();
        if speed == 0.0 {
            break;
        }
        let mut sub = (params.courant * dmin / speed)
            .min(params.courant * (dmin / G).sqrt())
            .min(dt - elapsed);
        // Avoid a sliver of a last sub-step.
        if dt - elapsed - sub < 1e-9 * dt {
            sub = dt - elapsed;
        }
        let s = substep(params, &pg, state, scratch, bx, sub);
        report.moved_volume += s.moved;
        report.border_outflow += s.outflow;
        report.max_speed = report.max_speed.max(s.max_speed);
        report.active_cells = bx.grown(state.pw, state.ph).area();
        report.flowing_cells = s.flowing;
        report.dt_min = if report.substeps == 0 {
            sub
        } else {
            report.dt_min.min(sub)
        };
        report.dt_max = report.dt_max.max(sub);
        report.substeps += 1;
        elapsed += sub;
    }
    if report.substeps == 0 {
        report.flowing_cells = state.h.iter().filter(|&&v| v > 0.0).count();
    }
    Ok(report)
}

/// The sub-step [`step`] would take next from this state (0 when nothing flows), s.
pub fn cfl_dt(params: &AvalancheParams, state: &AvalancheState) -> f64 {
    let Some(bx) = state.active else { return 0.0 };
    let (umax, hmax) = cfl_maxima(state, bx);
    let speed = umax + (G * hmax).sqrt();
    if speed == 0.0 {
        return 0.0;
    }
    let dmin = state
        .geometry
        .cell_size_x()
        .min(state.geometry.cell_size_y());
    (params.courant * dmin / speed).min(params.courant * (dmin / G).sqrt())
}

fn cfl_maxima(state: &AvalancheState, bx: ActiveBox) -> (f64, f64) {
    let pw = state.pw;
    let rows: Vec<(f64, f64)> = (bx.r0..=bx.r1)
        .into_par_iter()
        .map(|r| {
            let mut um = 0.0f64;
            let mut hm = 0.0f64;
            for c in bx.c0..=bx.c1 {
                let k = r * pw + c;
                hm = hm.max(state.h[k]);
                for u in state.pipes[k] {
                    um = um.max(u.abs());
                }
            }
            (um, hm)
        })
        .collect();
    rows.iter().fold((0.0, 0.0), |(a, b), &(u, h)| {
        (f64::max(a, u), f64::max(b, h))
    })
}

struct SubReport {
    moved: f64,
    outflow: f64,
    max_speed: f64,
    flowing: usize,
}

#[allow(clippy::needless_range_loop)]
fn substep(
    params: &AvalancheParams,
    pg: &PipeGeometry,
    state: &mut AvalancheState,
    scratch: &mut AvalancheScratch,
    bx: ActiveBox,
    dt: f64,
) -> SubReport {
    let (pw, ph) = (state.pw, state.ph);
    let closed = params.border == Border::Closed;
    let p1 = bx.grown(pw, ph);
    let p2 = p1.grown(pw, ph);
    let mu_g = params.rest_angle_deg.to_radians().tan() * G;
    let is_wall = |nodata: &[bool], k: usize, c: usize, r: usize| {
        nodata[k] || (closed && (r == 0 || c == 0 || r == ph - 1 || c == pw - 1))
    };
    let neighbour = |c: usize, r: usize, d: usize| -> Option<usize> {
        let (dc, dr) = DIRS[d];
        let cc = c as isize + dc;
        let rr = r as isize + dr;
        if cc < 0 || rr < 0 || cc >= pw as isize || rr >= ph as isize {
            None
        } else {
            Some(rr as usize * pw + cc as usize)
        }
    };
    let back = |c: usize, r: usize, d: usize| -> Option<usize> {
        let (dc, dr) = DIRS[d];
        let cc = c as isize - dc;
        let rr = r as isize - dr;
        if cc < 0 || rr < 0 || cc >= pw as isize || rr >= ph as isize {
            None
        } else {
            Some(rr as usize * pw + cc as usize)
        }
    };

    // Pass 1: cell velocities from the 8 pipes touching each cell (box grown by 2).
    {
        let pipes = &state.pipes;
        let (hh, bed, nodata) = (&state.h, &state.bed, &state.nodata);
        let e = &pg.e;
        scratch.vel[p2.r0 * pw..(p2.r1 + 1) * pw]
            .par_chunks_mut(pw)
            .enumerate()
            .for_each(|(ri, row)| {
                let r = p2.r0 + ri;
                for (c, v) in row.iter_mut().enumerate().take(p2.c1 + 1).skip(p2.c0) {
                    let k = r * pw + c;
                    let mut p = [0.0; 4];
                    for (d, pd) in p.iter_mut().enumerate() {
                        let own = pipes[k][d];
                        *pd = match back(c, r, d) {
                            Some(kb) => 0.5 * (own + pipes[kb][d]),
                            None => own,
                        };
                    }
                    let vx_d = (p[2] - p[3]) / (2.0 * e[2][0]);
                    let vy_d = (p[2] + p[3]) / (2.0 * e[2][1]);
                    let (vx, vy) = (0.5 * (p[0] + vx_d), 0.5 * (p[1] + vy_d));
                    let [gx, gy] = surface_gradient(pg, hh, bed, nodata, pw, k)
                        .unwrap_or([f64::NAN, f64::NAN]);
                    *v = [vx, vy, hh[k] * vx, hh[k] * vy, gx, gy];
                }
            });
    }

    // Pass 2: new pipe velocities and raw volumes (owners in the box grown by 1).
    {
        let (h, bed, pipes, nodata, vel) = (
            &state.h,
            &state.bed,
            &state.pipes,
            &state.nodata,
            &scratch.vel,
        );
        let range = p1.r0 * pw..(p1.r1 + 1) * pw;
        scratch.new_pipes[range.clone()]
            .par_chunks_mut(pw)
            .zip(scratch.flux[range].par_chunks_mut(pw))
            .enumerate()
            .for_each(|(ri, (urow, frow))| {
                let r = p1.r0 + ri;
                for c in p1.c0..=p1.c1 {
                    let k = r * pw + c;
                    let wall_k = is_wall(nodata, k, c, r);
                    for d in 0..4 {
                        let (dc, dr) = DIRS[d];
                        let (u, f) = match neighbour(c, r, d) {
                            Some(j)
                                if !wall_k
                                    && !is_wall(
                                        nodata,
                                        j,
                                        (c as isize + dc) as usize,
                                        r + dr as usize,
                                    ) =>
                            {
                                pipe_update(
                                    params, pg, mu_g, dt, pw, k, j, d, c, r, h, bed, pipes, vel,
                                )
                            }
                            _ => (0.0, 0.0),
                        };
                        urow[c][d] = u;
                        frow[c][d] = f;
                    }
                }
            });
    }

    // Pass 3: outflow scaling factor of every cell that can hold snow (the box).
    {
        let (h, flux) = (&state.h, &scratch.flux);
        let area = pg.area;
        scratch.factor[bx.r0 * pw..(bx.r1 + 1) * pw]
            .par_chunks_mut(pw)
            .enumerate()
            .for_each(|(ri, row)| {
                let r = bx.r0 + ri;
                for (c, fac) in row.iter_mut().enumerate().take(bx.c1 + 1).skip(bx.c0) {
                    let k = r * pw + c;
                    let mut vout = 0.0;
                    for d in 0..4 {
                        vout += flux[k][d].max(0.0);
                        if let Some(kb) = back(c, r, d) {
                            vout += (-flux[kb][d]).max(0.0);
                        }
                    }
                    let avail = h[k] * area;
                    *fac = if vout > avail { avail / vout } else { 1.0 };
                }
            });
    }

    // Pass 4: scale volumes and velocities by the upwind cell's factor; store the velocities.
    let rows4: Vec<(f64, f64)> = {
        let (factor, new_pipes) = (&scratch.factor, &scratch.new_pipes);
        let range = p1.r0 * pw..(p1.r1 + 1) * pw;
        state.pipes[range.clone()]
            .par_chunks_mut(pw)
            .zip(scratch.flux[range].par_chunks_mut(pw))
            .enumerate()
            .map(|(ri, (urow, frow))| {
                let r = p1.r0 + ri;
                let mut moved = 0.0;
                let mut umax = 0.0f64;
                for c in p1.c0..=p1.c1 {
                    let k = r * pw + c;
                    for d in 0..4 {
                        let mut u = new_pipes[k][d];
                        let mut f = frow[c][d];
                        if f != 0.0 {
                            let src = if f > 0.0 {
                                k
                            } else {
                                neighbour(c, r, d).unwrap_or(k)
                            };
                            let s = factor[src];
                            f *= s;
                            u *= s;
                        }
                        frow[c][d] = f;
                        urow[c][d] = u;
                        moved += f.abs();
                        umax = umax.max(u.abs());
                    }
                }
                (moved, umax)
            })
            .collect()
    };

    // Pass 5: thickness update (cells of the box), border outflow, next box.
    let rows5: Vec<RowStats> = {
        let (flux, pipes) = (&scratch.flux, &state.pipes);
        let area = pg.area;
        state.h[bx.r0 * pw..(bx.r1 + 1) * pw]
            .par_chunks_mut(pw)
            .enumerate()
            .map(|(ri, row)| {
                let r = bx.r0 + ri;
                let mut st = RowStats::default();
                let ghost_row = r == 0 || r == ph - 1;
                for (c, hv) in row.iter_mut().enumerate().take(bx.c1 + 1).skip(bx.c0) {
                    let k = r * pw + c;
                    let mut dv = 0.0;
                    for d in 0..4 {
                        dv -= flux[k][d];
                        if let Some(kb) = back(c, r, d) {
                            dv += flux[kb][d];
                        }
                    }
                    let mut hn = *hv + dv / area;
                    if hn < 0.0 {
                        hn = 0.0;
                    }
                    if ghost_row || c == 0 || c == pw - 1 {
                        st.outflow += hn * area;
                        hn = 0.0;
                    } else if hn > 0.0 {
                        st.flowing += 1;
                    }
                    *hv = hn;
                    if hn > 0.0 || pipes[k].iter().any(|&u| u != 0.0) {
                        st.cols = Some(match st.cols {
                            None => (c, c),
                            Some((a, b)) => (a.min(c), b.max(c)),
                        });
                    }
                }
                st
            })
            .collect()
    };

    let mut out = SubReport {
        moved: 0.0,
        outflow: 0.0,
        max_speed: 0.0,
        flowing: 0,
    };
    for (m, u) in rows4 {
        out.moved += m;
        out.max_speed = out.max_speed.max(u);
    }
    let mut next: Option<ActiveBox> = None;
    for (ri, st) in rows5.iter().enumerate() {
        out.outflow += st.outflow;
        out.flowing += st.flowing;
        if let Some((a, b)) = st.cols {
            let r = bx.r0 + ri;
            next = Some(match next {
                None => ActiveBox {
                    r0: r,
                    r1: r,
                    c0: a,
                    c1: b,
                },
                Some(nb) => ActiveBox {
                    r0: nb.r0.min(r),
                    r1: nb.r1.max(r),
                    c0: nb.c0.min(a),
                    c1: nb.c1.max(b),
                },
            });
        }
    }
    state.active = next.map(|b| b.grown(pw, ph));
    out
}

/// One pipe's new velocity and raw (unscaled) volume for a sub-step.
#[allow(clippy::too_many_arguments)]
#[inline]
fn pipe_update(
    params: &AvalancheParams,
    pg: &PipeGeometry,
    mu_g: f64,
    dt: f64,
    pw: usize,
    k: usize,
    j: usize,
    d: usize,
    c: usize,
    r: usize,
    h: &[f64],
    bed: &[f64],
    pipes: &[[f64; 4]],
    vel: &[CellFlow],
) -> (f64, f64) {
    let (hi, hj) = (h[k], h[j]);
    if hi <= DRY && hj <= DRY {
        return (0.0, 0.0);
    }
    let u0 = pipes[k][d];
    let a = -G * ((bed[j] + hj) - (bed[k] + hi)) / pg.len[d];
    let vp = [0.5 * (vel[k][0] + vel[j][0]), 0.5 * (vel[k][1] + vel[j][1])];
    let mut u = u0 + dt * a;
    if params.momentum_advection {
        u += advection(pg, pipes, vel, h, pw, k, j, d, c, r, dt);
    }
    // Coulomb friction as one vector: the trial velocity at the pipe, `v + δt·(−g∇A)` (cell
    // velocities and surface gradients averaged over the pipe's two cells), is slowed by
    // `g·tanθc·δt` along its own direction and each pipe takes its share `e·v̂`; where the
    // trial speed is below `g·tanθc·δt` the snow is held (static friction: the yield
    // criterion `|∇A| ≤ tanθc` at rest, the same in every direction), and a pipe the force
    // would reverse is set to zero.
    let grad = match (vel[k][4].is_nan(), vel[j][4].is_nan()) {
        (false, false) => [0.5 * (vel[k][4] + vel[j][4]), 0.5 * (vel[k][5] + vel[j][5])],
        (false, true) => [vel[k][4], vel[k][5]],
        (true, false) => [vel[j][4], vel[j][5]],
        (true, true) => [0.0, 0.0],
    };
    let trial = [vp[0] - dt * G * grad[0], vp[1] - dt * G * grad[1]];
    let tnorm = (trial[0] * trial[0] + trial[1] * trial[1]).sqrt();
    let yield_dt = params.alpha * mu_g * dt;
    let proj = if tnorm > 0.0 {
        ((pg.e[d][0] * trial[0] + pg.e[d][1] * trial[1]) / tnorm).abs()
    } else {
        1.0
    };
    let fric = yield_dt * proj;
    if (params.alpha > 0.0 && tnorm <= yield_dt) || u.abs() <= fric {
        u = 0.0;
    } else {
        u -= fric * u.signum();
    }
    // Viscous term, implicit.
    u /= 1.0 + dt * (1.0 - params.alpha) * params.k_viscous * 0.5 * (hi + hj);
    let hup = if u > 0.0 { hi } else { hj };
    if hup <= DRY {
        return (0.0, 0.0);
    }
    (u, pg.width[d] * hup * u * dt)
}

/// Central-difference gradient of the surface `A = B + h` at padded cell `k` (one-sided next
/// to nodata cells); `None` on the ghost ring.
fn surface_gradient(
    pg: &PipeGeometry,
    h: &[f64],
    bed: &[f64],
    nodata: &[bool],
    pw: usize,
    k: usize,
) -> Option<[f64; 2]> {
    let (r, c) = (k / pw, k % pw);
    if r == 0 || c == 0 || r + 1 >= pg.ph || c + 1 >= pw || nodata[k] {
        return None;
    }
    let a = |i: usize| bed[i] + h[i];
    let ak = a(k);
    let side = |i: usize| if nodata[i] { ak } else { a(i) };
    let gx = (side(k + 1) - side(k - 1)) / (2.0 * pg.dx);
    let gy = (side(k + pw) - side(k - pw)) / (2.0 * pg.dy);
    Some([gx, gy])
}

/// Momentum-conservative upwind advection of the pipe velocity (Stelling & Duinmeijer 2003,
/// generalised to the lattice of pipes sharing direction `d`): returns the change of `u` over
/// `dt`, `Σ_f λ_f (u_f − u)` over the lattice neighbours `f` whose face brings momentum in,
/// `λ_f = dt · Q_f / (Δ · h̄)` with `Q_f` the inflowing discharge at the face (mean of the cell
/// discharges `h·v` of the two pipes' end cells), `h̄` the mean depth of the pipe's cells. The
/// `λ` are scaled so that `Σ λ ≤ 1` (a convex combination: no overshoot).
#[allow(clippy::too_many_arguments)]
#[inline]
fn advection(
    pg: &PipeGeometry,
    pipes: &[[f64; 4]],
    vel: &[CellFlow],
    h: &[f64],
    pw: usize,
    k: usize,
    j: usize,
    d: usize,
    c: usize,
    r: usize,
    dt: f64,
) -> f64 {
    let hbar = 0.5 * (h[k] + h[j]);
    if hbar <= DRY {
        return 0.0;
    }
    let ph = pg.ph;
    let u0 = pipes[k][d];
    let (dc, dr) = DIRS[d];
    let qp = [0.5 * (vel[k][2] + vel[j][2]), 0.5 * (vel[k][3] + vel[j][3])];
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
    let interior = c >= 2 && c + 2 < pw && r >= 1 && r + 2 < ph;
    let jk = j as isize - k as isize;
    for (m, &(oc, or, axis, side)) in nbs.iter().enumerate() {
        let (kn, jn) = if interior {
            let kn = (k as isize + oc + or * pw as isize) as usize;
            (kn, (kn as isize + jk) as usize)
        } else {
            let (cc, rr) = (c as isize + oc, r as isize + or);
            let (jc, jr) = (cc + dc, rr + dr);
            if cc < 0 || rr < 0 || jc < 0 || jr < 0 {
                continue;
            }
            let (cc, rr, jc, jr) = (cc as usize, rr as usize, jc as usize, jr as usize);
            if cc >= pw || jc >= pw || rr >= ph || jr >= ph {
                continue;
            }
            (rr * pw + cc, jr * pw + jc)
        };
        let qn = 0.5 * (vel[kn][2 + axis] + vel[jn][2 + axis]);
        let q_face = 0.5 * (qp[axis] + qn);
        // Inflow through the + face is q < 0, through the − face q > 0.
        let inflow = -side * q_face;
        if inflow > 0.0 {
            lam[m] = rate[axis] * inflow;
            un[m] = pipes[kn][d];
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
