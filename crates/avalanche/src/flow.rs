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
//! `δt ≤ C · min(dx, dy) / max_i (|u|_i + sqrt(g · h_i))` (`|u|_i` the largest speed of the 8
//! pipes touching cell `i`: the fastest wave of each cell, not the largest speed plus the
//! deepest cell's celerity, which may lie far apart) and `δt ≤ C · sqrt(min(dx, dy)/g)` (the
//! latter bounds the first sub-step from rest on steep beds), `C` = [`AvalancheParams::courant`].
//!
//! **Borders.** Nodata cells are walls (pipes to them carry nothing). [`Border::Closed`] makes
//! the ghost ring walls; [`Border::Open`] gives the ghost ring the bed of the nearest grid cell
//! and no snow: snow that flows into it leaves the grid and is counted as `border_outflow`.
//!
//! **Cost.** Only an *active set* is visited. The padded grid is cut into tiles of 16x16
//! cells; each tile keeps the box of its *content* cells (flowing snow or a moving owned pipe),
//! refreshed by the last pass of every sub-step. Snow moves at most one cell per sub-step, so a
//! sub-step only changes cells within 1 of the content and only reads cells within 3: its passes
//! visit, row by row, the union of the tile boxes grown by 3 cells (velocities and pipes) or 2
//! cells (thickness). A branching avalanche thus costs its footprint, not its bounding box, and
//! the cost of a sub-step does not depend on the grid size. Pipes with two dry ends and pipes
//! held by static friction are skipped early. A sub-step makes two passes: (1) in blocks of
//! 16 rows, row by row, the cell velocities, discharges and surface gradients (kept in the
//! block's own rows, never written to a grid-sized array), the new pipes and raw volumes, and
//! the outflow factors (a block also computes the pipes of the next block's first row, for the
//! factors of its last row); (2) in one sweep of each row, the thickness, the pipes scaled by
//! the outflow factors, the content per tile and the CFL maxima of the next sub-step. Away
//! from the ghost ring and nodata cells the kernels run on four consecutive cells at a time
//! (AVX, when the CPU has it), with the IEEE operations of the one-cell code and in the same
//! order, so the lanes change no result.
//!
//! **Determinism.** Every pass is a gather over rows (rayon), each row writes only its own
//! cells, and per-row sums are added in row order (within a row, cell by cell), so results are
//! bit-identical for any thread count and with or without the four-lane kernels.

mod footprint;
mod lanes;
mod settle;
mod tiles;

pub use footprint::BedSource;

use lanes::{Lanes, ld};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use snowscape_terrain::{GridGeometry, NodataMask};
use std::cell::RefCell;
use std::sync::atomic::AtomicBool;
use thiserror::Error;
use tiles::{Segments, TILE, TileSet};

/// Gravitational acceleration, m/s² (the paper's `g = 9.81`).
pub const G: f64 = 9.81;

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
    /// A state that reads its bed from the terrain was stepped without one.
    #[error("this avalanche state reads its bed from the terrain: step it with `step_on`")]
    BedSourceMissing,
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
    /// Cells visited in the last sub-step (the active set: tile boxes grown by 3 cells, ghost
    /// ring included).
    pub active_cells: usize,
    /// Grid cells holding flowing snow after the step.
    pub flowing_cells: usize,
    /// Number of sub-steps.
    pub substeps: usize,
    /// Smallest sub-step, s (0 when no sub-step ran).
    pub dt_min: f64,
    /// Largest sub-step, s.
    pub dt_max: f64,
    /// Simulated time the sub-steps covered, s (the step's `dt`, or less when the flow came
    /// to rest; with [`step_at_least`] up to its `max_dt`).
    pub simulated_s: f64,
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
}

/// Cells of the active set (grown by 3) from which a sub-step runs its passes on all worker
/// threads (measured on the 2-core development machine: a sub-step costs ~0.2 µs per cell,
/// a fork and join of both passes ~20-50 µs).
const PARALLEL_MIN_CELLS: usize = 8192;

/// Rows per block of the pipe pass.
const BLOCK: usize = 16;

/// Per worker thread, the rows of the block of the pipe pass it works on: velocities,
/// discharges and gradients ([`VX`]..[`GY`]), and the pipes and volumes of the next block's
/// first row (the volumes after a copy of the block's last row).
#[derive(Default)]
struct BlockRows {
    vel: [Vec<f64>; 6],
    np: [Vec<f64>; 4],
    fl: [Vec<f64>; 4],
}

thread_local! {
    static BLOCK_ROWS: RefCell<BlockRows> = RefCell::new(Default::default());
}

/// Forces the one-lane kernels (a test compares them with the four-lane ones).
pub(crate) static FORCE_SCALAR: AtomicBool = AtomicBool::new(false);

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
    /// Padded thickness of the films that came to rest during the run (see `settle_films`), m.
    pub(crate) settled: Vec<f64>,
    /// Padded pipe velocities, one array per owned direction (east, south, south-east,
    /// south-west), m/s.
    pub(crate) pipes: [Vec<f64>; 4],
    /// Box holding all snow and moving pipes, grown by one cell; `None` when nothing flows.
    pub(crate) active: Option<ActiveBox>,
    /// The active set: per tile, the box of its cells with snow or a moving owned pipe.
    tiles: TileSet,
    /// Largest pipe speed and largest wave speed `sqrt(g·h) + |u|` over the cells (`|u|` the
    /// largest speed of the 8 pipes touching the cell), m/s: the CFL step.
    maxima: (f64, f64),
    /// Padded flags: the cell or one of its 8 neighbours is a nodata cell.
    near_wall: Vec<bool>,
    /// Pipe lengths, widths and directions of the grid.
    pg: PipeGeometry,
    /// The tiles this run touched; whether the bed is read lazily.
    pub(crate) footprint: footprint::Footprint,
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
        let mut near_wall = vec![false; pw * ph];
        for r in 0..ph {
            for c in 0..pw {
                if nodata[r * pw + c] {
                    for rr in r.saturating_sub(1)..=(r + 1).min(ph - 1) {
                        for cc in c.saturating_sub(1)..=(c + 1).min(pw - 1) {
                            near_wall[rr * pw + cc] = true;
                        }
                    }
                }
            }
        }
        Ok(Self {
            geometry: geometry.clone(),
            pw,
            ph,
            nodata,
            bed: pbed,
            h: vec![0.0; pw * ph],
            settled: vec![0.0; pw * ph],
            pipes: std::array::from_fn(|_| vec![0.0; pw * ph]),
            active: None,
            tiles: TileSet::new(pw, ph),
            maxima: (0.0, 0.0),
            near_wall,
            pg: PipeGeometry::new(geometry, ph),
            footprint: footprint::Footprint::new(pw.div_ceil(TILE) * ph.div_ceil(TILE), false),
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
        self.pipes.iter_mut().for_each(|p| p.fill(0.0));
        self.h.fill(0.0);
        self.settled.fill(0.0);
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
        self.mark_content(k);
        Ok(())
    }

    /// Adds padded cell `k`, which received snow, to the active set (its tile touched) and
    /// to the CFL maxima.
    pub(crate) fn mark_content(&mut self, k: usize) {
        self.maxima.1 = self.maxima.1.max(self.wave_speed(k));
        let (r, c) = (k / self.pw, k % self.pw);
        self.tiles.add(r, c, c);
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
        self.touch_tile((r / TILE) * self.tiles.ntx() + c / TILE);
    }

    /// Flowing volume on the grid, m³ (rows summed in order).
    pub fn flowing_volume(&self) -> f64 {
        let area = self.geometry.cell_area();
        let Some(bx) = self.active else {
            return 0.0;
        };
        // Only the box can hold snow; the cells outside would add zeros to the row-major sum.
        let (w, hgt) = (self.geometry.width(), self.geometry.height());
        let (r0, r1) = (bx.r0.max(1), bx.r1.min(hgt));
        let (c0, c1) = (bx.c0.max(1), bx.c1.min(w));
        (r0..=r1)
            .flat_map(|r| self.h[r * self.pw + c0..=r * self.pw + c1].iter())
            .sum::<f64>()
            * area
    }

    /// Largest pipe speed, m/s.
    pub fn max_speed(&self) -> f64 {
        self.maxima.0
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
    #[inline(always)]
    pub fn velocity_at(&self, col: usize, row: usize) -> [f64; 2] {
        let (k, pw) = (self.pad(col, row), self.pw);
        let p = &self.pipes;
        // (The owners of the pipes reaching the cell: west, north, north-west, north-east.)
        let p0 = 0.5 * (p[0][k] + p[0][k - 1]);
        let p1 = 0.5 * (p[1][k] + p[1][k - pw]);
        let p2 = 0.5 * (p[2][k] + p[2][k - pw - 1]);
        let p3 = 0.5 * (p[3][k] + p[3][k - pw + 1]);
        let vx_d = (p2 - p3) / (2.0 * self.pg.e[2][0]);
        let vy_d = (p2 + p3) / (2.0 * self.pg.e[2][1]);
        [0.5 * (p0 + vx_d), 0.5 * (p1 + vy_d)]
    }

    /// Whether a grid cell and all 8 pipes touching it are at rest.
    #[inline(always)]
    pub fn at_rest(&self, col: usize, row: usize) -> bool {
        let (k, pw) = (self.pad(col, row), self.pw);
        let p = &self.pipes;
        // (Row above, from the north-west to the north-east neighbour; the cell's row, from the
        // west neighbour to the cell.)
        let (up, here) = (k - pw - 1..k - pw + 2, k - 1..k + 1);
        let (n0, n1, n2, n3) = (
            &p[0][here.clone()],
            &p[1][up.clone()],
            &p[2][up.clone()],
            &p[3][up],
        );
        let (h1, h2, h3) = (&p[1][here.clone()], &p[2][here.clone()], &p[3][here]);
        n0[0] == 0.0
            && n0[1] == 0.0
            && h1[1] == 0.0
            && n1[1] == 0.0
            && h2[1] == 0.0
            && n2[0] == 0.0
            && h3[1] == 0.0
            && n3[2] == 0.0
    }

    /// `sqrt(g·h) + |u|` at padded cell `k`, `|u|` the largest speed of the 8 pipes touching it.
    fn wave_speed(&self, k: usize) -> f64 {
        let (c, r) = (k % self.pw, k / self.pw);
        let mut umax = 0.0f64;
        for (d, &(dc, dr)) in DIRS.iter().enumerate() {
            umax = umax.max(self.pipes[d][k].abs());
            let (cc, rr) = (c as isize - dc, r as isize - dr);
            if cc >= 0 && rr >= 0 && (cc as usize) < self.pw {
                umax = umax.max(self.pipes[d][rr as usize * self.pw + cc as usize].abs());
            }
        }
        (G * self.h[k]).sqrt() + umax
    }

    /// Recomputes the active set, the active box and the CFL maxima by scanning the whole grid
    /// (after external edits).
    ///
    /// The largest wave speed over all cells is the larger of the wet cells' and the largest
    /// pipe speed (a dry cell's `|u|` is the speed of a pipe, and the cell at either end of the
    /// fastest pipe reaches it), so dry cells cost one look at their pipes.
    pub(crate) fn refresh_active(&mut self) {
        self.refresh_active_over(&[(0, self.ph - 1, 0, self.pw - 1)]);
    }

    /// [`AvalancheState::refresh_active`] over the padded boxes `(r0, r1, c0, c1)` only (all
    /// snow and motion must lie in them), each scanned row by row.
    pub(crate) fn refresh_active_over(&mut self, boxes: &[(usize, usize, usize, usize)]) {
        self.tiles.clear();
        let (mut umax, mut wave) = (0.0f64, 0.0f64);
        for &(r0, r1, c0, c1) in boxes {
            for r in r0..=r1 {
                let mut run: Option<(usize, usize)> = None;
                for c in c0..=c1 {
                    let k = r * self.pw + c;
                    let mut moving = false;
                    for p in &self.pipes {
                        umax = umax.max(p[k].abs());
                        moving |= p[k] != 0.0;
                    }
                    let wet = self.h[k] > 0.0;
                    if wet {
                        wave = wave.max(self.wave_speed(k));
                    }
                    if wet || moving {
                        run = match run {
                            Some((a, _)) if a / TILE == c / TILE => Some((a, c)),
                            Some((a, b)) => {
                                self.tiles.add(r, a, b);
                                Some((c, c))
                            }
                            None => Some((c, c)),
                        };
                    }
                }
                if let Some((a, b)) = run {
                    self.tiles.add(r, a, b);
                }
            }
        }
        self.maxima = (umax, wave.max(umax));
        self.active = self.tiles.bbox().map(|b| b.grown(self.pw, self.ph));
        for o in 0..self.tiles.occupied().len() {
            self.touch_tile(self.tiles.occupied()[o] as usize);
        }
    }
}

/// The per-cell quantities of a sub-step the pipes read, one array each: velocity (vx, vy)
/// reconstructed from the 8 pipes, discharge (h·vx, h·vy) and surface gradient (∂A/∂x, ∂A/∂y;
/// NaN on the ghost ring and nodata cells).
const VX: usize = 0;
const VY: usize = 1;
const QX: usize = 2;
const QY: usize = 3;
const GX: usize = 4;
const GY: usize = 5;

/// Reusable work buffers for [`step`] (allocated on first use).
#[derive(Debug, Clone, Default)]
pub struct AvalancheScratch {
    /// New pipe velocities and raw (unscaled) volumes, per owned direction.
    new_pipes: [Vec<f64>; 4],
    flux: [Vec<f64>; 4],
    /// Outflow scaling factor of every wet cell.
    factor: Vec<f64>,
    /// Per padded row, the content column range of each tile the row touches.
    row_tiles: Vec<[u32; 2]>,
    /// The active tiles grown by 3 cells (velocities, pipes) and by 2 cells (thickness).
    seg3: Segments,
    seg2: Segments,
}

/// Pipe geometry: length, width and unit vector (x east, y south) per owned direction.
#[derive(Debug, Clone, PartialEq)]
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

/// Advances the flowing snow by `dt` seconds in CFL-limited sub-steps.
///
/// Pure apart from `state` and `scratch`; deterministic for any rayon thread count.
pub fn step(
    params: &AvalancheParams,
    state: &mut AvalancheState,
    scratch: &mut AvalancheScratch,
    dt: f64,
) -> Result<AvalancheReport, AvalancheError> {
    step_on(params, state, scratch, dt, None)
}

/// [`step`] on a state that reads its bed from `bed` where the flow goes (a season's
/// persistent state; `None` for a state that holds its whole bed).
pub fn step_on(
    params: &AvalancheParams,
    state: &mut AvalancheState,
    scratch: &mut AvalancheScratch,
    dt: f64,
    bed: Option<&dyn BedSource>,
) -> Result<AvalancheReport, AvalancheError> {
    advance_flow(params, state, scratch, dt, dt, bed)
}

/// Advances the flowing snow by whole CFL sub-steps until at least `dt` seconds have passed
/// (the last sub-step is not shortened to end at `dt`), but never past `max_dt`; the time
/// advanced is the report's `simulated_s`. A run that samples records from the sub-steps
/// instead of cutting sub-steps at each record takes the fewest sub-steps the CFL condition
/// allows.
pub fn step_at_least(
    params: &AvalancheParams,
    state: &mut AvalancheState,
    scratch: &mut AvalancheScratch,
    dt: f64,
    max_dt: f64,
    bed: Option<&dyn BedSource>,
) -> Result<AvalancheReport, AvalancheError> {
    if !(max_dt.is_finite() && max_dt >= dt) {
        return Err(AvalancheError::InvalidTimeStep(max_dt));
    }
    advance_flow(params, state, scratch, dt, max_dt, bed)
}

/// Sub-steps until `dt` has passed, the last one ending at most at `max_dt`.
fn advance_flow(
    params: &AvalancheParams,
    state: &mut AvalancheState,
    scratch: &mut AvalancheScratch,
    dt: f64,
    max_dt: f64,
    bed: Option<&dyn BedSource>,
) -> Result<AvalancheReport, AvalancheError> {
    params.validate()?;
    if !(dt.is_finite() && dt >= 0.0) {
        return Err(AvalancheError::InvalidTimeStep(dt));
    }
    let n = state.pw * state.ph;
    if scratch.factor.len() != n {
        let zeros = || vec![0.0; n];
        scratch.new_pipes = std::array::from_fn(|_| zeros());
        scratch.flux = std::array::from_fn(|_| zeros());
        // Factors stay finite and in [0, 1] (the thickness pass relies on it).
        scratch.factor = vec![1.0; n];
    }
    let nt = state.ph * state.tiles.ntx();
    if scratch.row_tiles.len() != nt {
        scratch.row_tiles = vec![[0; 2]; nt];
    }
    let pg = state.pg.clone();
    let dmin = pg.dx.min(pg.dy);
    let mut report = AvalancheReport::default();
    let mut elapsed = 0.0;
    while elapsed < dt {
        if state.active.is_none() {
            break;
        }
        if report.substeps >= params.max_substeps {
            return Err(AvalancheError::TooManySubsteps {
                done: report.substeps,
                remaining: dt - elapsed,
                dt,
            });
        }
        let speed = state.maxima.1;
        if speed == 0.0 {
            break;
        }
        let mut sub = (params.courant * dmin / speed)
            .min(params.courant * (dmin / G).sqrt())
            .min(max_dt - elapsed);
        // Avoid a sliver of a last sub-step.
        if max_dt - elapsed - sub < 1e-9 * max_dt {
            sub = max_dt - elapsed;
        }
        state.touch_around_content(bed)?;
        let s = substep(params, &pg, state, scratch, sub);
        report.moved_volume += s.moved;
        report.border_outflow += s.outflow;
        report.max_speed = report.max_speed.max(s.max_speed);
        report.active_cells = s.visited;
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
    report.simulated_s = elapsed;
    if report.substeps == 0 {
        report.flowing_cells = state
            .content_cells()
            .map(|(r0, r1, c0, c1)| {
                (r0..=r1)
                    .map(|r| {
                        (c0..=c1)
                            .filter(|&c| state.thickness_at(c, r) > 0.0)
                            .count()
                    })
                    .sum::<usize>()
            })
            .sum();
    }
    Ok(report)
}

/// The sub-step [`step`] would take next from this state (0 when nothing flows), s.
pub fn cfl_dt(params: &AvalancheParams, state: &AvalancheState) -> f64 {
    if state.active.is_none() {
        return 0.0;
    }
    let speed = state.maxima.1;
    if speed == 0.0 {
        return 0.0;
    }
    let dmin = state
        .geometry
        .cell_size_x()
        .min(state.geometry.cell_size_y());
    (params.courant * dmin / speed).min(params.courant * (dmin / G).sqrt())
}

struct SubReport {
    moved: f64,
    outflow: f64,
    max_speed: f64,
    flowing: usize,
    visited: usize,
}

/// Constants of one sub-step.
struct Consts {
    dt: f64,
    /// `dt·g`.
    dtg: f64,
    /// Coulomb yield speed change `α·g·tanθc·dt`.
    yield_dt: f64,
    coulomb: bool,
    /// Viscous coefficient `dt·(1 − α)·kv/2` (0: no viscous term).
    visc: f64,
    adv: bool,
    closed: bool,
    alpha: f64,
    pw: usize,
    ph: usize,
    len: [f64; 4],
    width: [f64; 4],
    e: [[f64; 2]; 4],
    dx: f64,
    dy: f64,
    square: bool,
    area: f64,
    /// `2·e_SE,x`, `2·e_SE,y`, `2·dx`, `2·dy`: divisors of the velocity and gradient.
    den_x: f64,
    den_y: f64,
    two_dx: f64,
    two_dy: f64,
    /// Padded index offset of the neighbour of each owned pipe.
    off: [usize; 4],
}

impl Consts {
    fn new(params: &AvalancheParams, pg: &PipeGeometry, pw: usize, ph: usize, dt: f64) -> Self {
        let mu_g = params.rest_angle_deg.to_radians().tan() * G;
        Self {
            dt,
            dtg: dt * G,
            yield_dt: params.alpha * mu_g * dt,
            coulomb: params.alpha > 0.0,
            visc: dt * (1.0 - params.alpha) * params.k_viscous * 0.5,
            adv: params.momentum_advection,
            closed: params.border == Border::Closed,
            alpha: params.alpha,
            pw,
            ph,
            len: pg.len,
            width: pg.width,
            e: pg.e,
            dx: pg.dx,
            dy: pg.dy,
            square: pg.dx == pg.dy,
            area: pg.area,
            den_x: 2.0 * pg.e[2][0],
            den_y: 2.0 * pg.e[2][1],
            two_dx: 2.0 * pg.dx,
            two_dy: 2.0 * pg.dy,
            off: [1, pw, pw + 1, pw - 1],
        }
    }

    fn is_wall(&self, nodata: &[bool], k: usize, c: usize, r: usize) -> bool {
        nodata[k] || (self.closed && (r == 0 || c == 0 || r == self.ph - 1 || c == self.pw - 1))
    }

    /// Padded index of the neighbour of `(c, r)` along owned direction `d`.
    fn neighbour(&self, c: usize, r: usize, d: usize) -> Option<usize> {
        let (dc, dr) = DIRS[d];
        let cc = c as isize + dc;
        let rr = r as isize + dr;
        if cc < 0 || rr < 0 || cc >= self.pw as isize || rr >= self.ph as isize {
            None
        } else {
            Some(rr as usize * self.pw + cc as usize)
        }
    }

    /// Padded index of the owner of the pipe reaching `(c, r)` along direction `d`.
    fn back(&self, c: usize, r: usize, d: usize) -> Option<usize> {
        let (dc, dr) = DIRS[d];
        let cc = c as isize - dc;
        let rr = r as isize - dr;
        if cc < 0 || rr < 0 || cc >= self.pw as isize || rr >= self.ph as isize {
            None
        } else {
            Some(rr as usize * self.pw + cc as usize)
        }
    }
}

/// Read-only arrays of a pass (the ones a pass does not read are empty).
#[derive(Clone, Copy)]
struct Inputs<'a> {
    h: &'a [f64],
    bed: &'a [f64],
    nodata: &'a [bool],
    near_wall: &'a [bool],
    pipes: [&'a [f64]; 4],
    /// Velocities, discharges and gradients of the padded cells from index `vbase` on.
    vel: [&'a [f64]; 6],
    vbase: usize,
    new_pipes: [&'a [f64]; 4],
    /// Raw volumes of the padded cells from index `fbase` on (0 outside the pipe pass).
    flux: [&'a [f64]; 4],
    fbase: usize,
    factor: &'a [f64],
}

/// Per-row results of the final pass of a sub-step.
#[derive(Clone, Copy, Default)]
struct RowStats {
    moved: f64,
    umax: f64,
    outflow: f64,
    wave: f64,
    flowing: usize,
    /// Entries of the row in `row_tiles`.
    tiles: usize,
}

/// The chunks of `len` values (the last one may be shorter) of `N` arrays, one entry per chunk.
fn rows_of<const N: usize>(arrays: [&mut [f64]; N], len: usize) -> Vec<[&mut [f64]; N]> {
    let rows = arrays[0].len().div_ceil(len);
    let mut its = arrays.map(|a| a.chunks_mut(len));
    (0..rows)
        .map(|_| std::array::from_fn(|i| its[i].next().expect("row")))
        .collect()
}

/// A block of the pipe pass: its index, its new pipes and raw volumes (4 directions each), its
/// outflow factors.
type BlockItem<'a, 'b> = (
    usize,
    (
        (&'a mut [&'b mut [f64]; 4], &'a mut [&'b mut [f64]; 4]),
        &'a mut [&'b mut [f64]; 1],
    ),
);

/// A row of the thickness pass: its index, thickness, pipes (4 directions) and tile ranges.
type RowItem<'a> = (
    usize,
    ((&'a mut [f64], [&'a mut [f64]; 4]), &'a mut [[u32; 2]]),
);

/// One sub-step over the active set.
///
/// Regions (`C` = the cells with snow or a moving owned pipe, `C+m` grown by `m` cells): new
/// snow and moving pipes lie in `C+1`, and a pipe with a wet end has its owner in `C+1`, so
/// pipes are updated on `C+2` (read: velocities on `C+3`), thickness on `C+1`. The active set
/// visits `seg3 ⊇ C+3` for velocities and pipes (pipes with two dry ends come out 0 without
/// reading velocities) and `seg2 ⊇ C+2` for thickness (reading fluxes on `seg3`).
fn substep(
    params: &AvalancheParams,
    pg: &PipeGeometry,
    state: &mut AvalancheState,
    scratch: &mut AvalancheScratch,
    dt: f64,
) -> SubReport {
    let (pw, ph) = (state.pw, state.ph);
    let k = Consts::new(params, pg, pw, ph, dt);
    let simd = lanes::simd_available();
    scratch.seg3.build(&state.tiles, 3, pw, ph);
    scratch.seg2.build(&state.tiles, 2, pw, ph);
    let AvalancheScratch {
        new_pipes,
        flux,
        factor,
        row_tiles,
        seg3,
        seg2,
    } = scratch;
    let (seg3, seg2) = (&*seg3, &*seg2);
    // A small flow runs on the calling thread: below this many cells the fork and join of
    // the two passes cost more than the second core saves.
    let parallel = seg3.cells >= PARALLEL_MIN_CELLS;
    let (r0, nr) = (seg3.r0, seg3.rows());
    let rows = r0 * pw..(r0 + nr) * pw;
    let empty: &[f64] = &[];
    let none = Inputs {
        h: &state.h,
        bed: &state.bed,
        nodata: &state.nodata,
        near_wall: &state.near_wall,
        pipes: [empty; 4],
        vel: [empty; 6],
        vbase: 0,
        new_pipes: [empty; 4],
        flux: [empty; 4],
        fbase: 0,
        factor: empty,
    };

    // Pass 1: new pipe velocities, raw volumes and outflow factors, by blocks of rows. Row by
    // row, a block computes the cell velocities, discharges and surface gradients its pipes
    // read (its rows, one row above and two below) into rows of its own, its pipes, and the
    // outflow factors of the row above (those of its first row need the block above). Then
    // it computes the pipes of the next block's first row (into rows of its own) for the
    // factors of its last row. (The factors of the first row of the active set are never
    // used: no snow lies within 3 rows of it.)
    {
        let pipes = state.pipes.each_ref().map(|p| p.as_slice());
        let inp1 = Inputs { pipes, ..none };
        let end = r0 + nr;
        let nb = nr.div_ceil(BLOCK);
        let mut np = rows_of(
            new_pipes.each_mut().map(|v| &mut v[rows.clone()]),
            BLOCK * pw,
        );
        let mut fl = rows_of(flux.each_mut().map(|v| &mut v[rows.clone()]), BLOCK * pw);
        // Block `b` holds the factors of its rows shifted down by one.
        let frows = (r0 + 1).min(ph) * pw..(end + 1).min(ph) * pw;
        let mut fac = rows_of([&mut factor[frows]], BLOCK * pw);
        fac.resize_with(nb, || [&mut []]);
        let block = |(bi, ((np, fl), [fac])): BlockItem| {
            let b0 = r0 + bi * BLOCK;
            let b1 = b0 + np[0].len() / pw;
            // Pipes of row `b1` too, but in the last block.
            let halo = b1 < end;
            let v0 = b0.saturating_sub(1);
            let v1 = (b1 + 1 + halo as usize).min(ph - 1);
            let len = (v1 - v0 + 1) * pw;
            BLOCK_ROWS.with_borrow_mut(|bb| {
                let BlockRows {
                    vel,
                    np: np_h,
                    fl: fl_h,
                } = bb;
                for a in vel.iter_mut() {
                    if a.len() < len {
                        a.resize(len, 0.0);
                    }
                }
                for a in np_h.iter_mut().chain(fl_h.iter_mut()) {
                    if a.len() < 2 * pw {
                        a.resize(2 * pw, 0.0);
                    }
                }
                let vel_of = |x: usize, vel: &mut [Vec<f64>; 6]| {
                    let lr = (x - v0) * pw;
                    let mut row = vel.each_mut().map(|a| &mut a[lr..lr + pw]);
                    vel_row(simd, &k, pg, &inp1, seg3.row(x), x, &mut row);
                };
                for x in v0..=(b0 + 1).min(v1) {
                    vel_of(x, vel);
                }
                for r in b0..b1 + halo as usize {
                    if r + 2 <= v1 {
                        vel_of(r + 2, vel);
                    }
                    let inp = Inputs {
                        pipes,
                        vel: vel.each_ref().map(|a| &a[..len]),
                        vbase: v0 * pw,
                        ..none
                    };
                    let segs = seg3.row(r);
                    if r < b1 {
                        let lr = (r - b0) * pw..(r - b0 + 1) * pw;
                        let mut np_r = np.each_mut().map(|a| &mut a[lr.clone()]);
                        let mut fl_r = fl.each_mut().map(|a| &mut a[lr.clone()]);
                        pipes_row(simd, params, &k, pg, &inp, segs, r, &mut np_r, &mut fl_r);
                    } else {
                        // The next block's first row, after a copy of this block's last
                        // row of volumes (the factors read both).
                        let last = (b1 - 1 - b0) * pw..(b1 - b0) * pw;
                        for (h, f) in fl_h.iter_mut().zip(fl.iter()) {
                            h[..pw].copy_from_slice(&f[last.clone()]);
                        }
                        let mut np_r = np_h.each_mut().map(|a| &mut a[..pw]);
                        let mut fl_r = fl_h.each_mut().map(|a| &mut a[pw..2 * pw]);
                        pipes_row(simd, params, &k, pg, &inp, segs, r, &mut np_r, &mut fl_r);
                    }
                    // The factors of the row (the block's first row: the block above).
                    if r > b0 {
                        let inp = if r < b1 {
                            Inputs {
                                flux: fl.each_ref().map(|a| &**a),
                                fbase: b0 * pw,
                                ..none
                            }
                        } else {
                            Inputs {
                                flux: fl_h.each_ref().map(|a| &a[..2 * pw]),
                                fbase: (r - 1) * pw,
                                ..none
                            }
                        };
                        let lr = (r - b0 - 1) * pw..(r - b0) * pw;
                        factor_row(simd, &k, &inp, segs, r, &mut fac[lr]);
                    }
                }
            });
        };
        if parallel {
            np.par_iter_mut()
                .zip(fl.par_iter_mut())
                .zip(fac.par_iter_mut())
                .enumerate()
                .for_each(block);
        } else {
            np.iter_mut()
                .zip(fl.iter_mut())
                .zip(fac.iter_mut())
                .enumerate()
                .for_each(block);
        }
    }

    // Pass 2: thickness update (seg2), pipes scaled by the upwind cell's factor (seg3), the
    // content of each row per tile, the CFL maxima.
    let ntx = state.tiles.ntx();
    let stats: Vec<RowStats> = {
        let inp = Inputs {
            h: empty,
            bed: empty,
            nodata: &[],
            near_wall: &[],
            pipes: [empty; 4],
            vel: [empty; 6],
            vbase: 0,
            new_pipes: new_pipes.each_ref().map(|v| v.as_slice()),
            flux: flux.each_ref().map(|v| v.as_slice()),
            fbase: 0,
            factor,
        };
        let (h, pipes) = (&mut state.h, &mut state.pipes);
        let prows = rows_of(pipes.each_mut().map(|v| &mut v[rows.clone()]), pw);
        let row = |(ri, ((hrow, mut prow), trow)): RowItem| {
            let r = r0 + ri;
            update_row(
                simd,
                &k,
                &inp,
                seg2.row(r),
                seg3.row(r),
                r,
                hrow,
                &mut prow,
                trow,
            )
        };
        let (hr, tr) = (
            &mut h[rows.clone()],
            &mut row_tiles[r0 * ntx..(r0 + nr) * ntx],
        );
        if parallel {
            hr.par_chunks_mut(pw)
                .zip(prows)
                .zip(tr.par_chunks_mut(ntx))
                .enumerate()
                .map(row)
                .collect()
        } else {
            hr.chunks_mut(pw)
                .zip(prows)
                .zip(tr.chunks_mut(ntx))
                .enumerate()
                .map(row)
                .collect()
        }
    };

    let mut out = SubReport {
        moved: 0.0,
        outflow: 0.0,
        max_speed: 0.0,
        flowing: 0,
        visited: seg3.cells,
    };
    let mut wave = 0.0f64;
    state.tiles.clear();
    for (ri, st) in stats.iter().enumerate() {
        let r = r0 + ri;
        out.moved += st.moved;
        out.max_speed = out.max_speed.max(st.umax);
        out.outflow += st.outflow;
        out.flowing += st.flowing;
        wave = wave.max(st.wave);
        for &[a, b] in &row_tiles[r * ntx..r * ntx + st.tiles] {
            state.tiles.add(r, a as usize, b as usize);
        }
    }
    state.maxima = (out.max_speed, wave);
    state.active = state.tiles.bbox().map(|b| b.grown(pw, ph));
    out
}

/// How a pass visits a cell.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Visit {
    /// `V::N` cells from this one, all away from the ghost ring and walls: the lane kernel.
    Chunk,
    /// One such cell: the lane kernel on one lane.
    One,
    /// A cell near the ghost ring or a wall: the general code.
    Border,
}

/// The cells of `segs` and how to visit them: columns `lo..=hi` not flagged in `wall` run
/// the lane kernels (in chunks of `lanes`), the others the general code. (An iterator, not a
/// callback, so that the kernels are compiled inside the caller, with its target features.)
struct Walk<'a> {
    segs: &'a [[u32; 2]],
    /// Next segment, next column, last column of the current segment.
    si: usize,
    c: usize,
    b: usize,
    lo: usize,
    hi: usize,
    wall: Option<&'a [bool]>,
    lanes: usize,
}

#[inline(always)]
fn walk<'a>(
    segs: &'a [[u32; 2]],
    lo: usize,
    hi: usize,
    wall: Option<&'a [bool]>,
    lanes: usize,
) -> Walk<'a> {
    Walk {
        segs,
        si: 0,
        c: 1,
        b: 0,
        lo,
        hi,
        wall,
        lanes,
    }
}

impl Walk<'_> {
    #[inline(always)]
    fn clear(&self, c: usize) -> bool {
        self.wall.is_none_or(|w| !w[c])
    }
}

impl Iterator for Walk<'_> {
    type Item = (usize, Visit);

    #[inline(always)]
    fn next(&mut self) -> Option<(usize, Visit)> {
        if self.c > self.b {
            let &[a, b] = self.segs.get(self.si)?;
            self.si += 1;
            self.c = a as usize;
            self.b = b as usize;
        }
        let c = self.c;
        if c >= self.lo && c <= self.hi && self.clear(c) {
            let n = self.lanes;
            if n > 1 && c + n - 1 <= self.b.min(self.hi) && (c + 1..c + n).all(|i| self.clear(i)) {
                self.c += n;
                return Some((c, Visit::Chunk));
            }
            self.c += 1;
            return Some((c, Visit::One));
        }
        self.c += 1;
        Some((c, Visit::Border))
    }
}

/// Defines `$name(simd, args..)`, running `$generic::<F4>` compiled for AVX when `simd` is
/// set (the caller checked the CPU), else `$generic::<f64>`.
macro_rules! lanes_dispatch {
    ($name:ident, $avx:ident, $generic:ident, ($($arg:ident : $ty:ty),* $(,)?) -> $ret:ty $(,)?) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx")]
        #[allow(clippy::too_many_arguments)]
        fn $avx($($arg: $ty),*) -> $ret {
            $generic::<lanes::F4>($($arg),*)
        }

        #[allow(clippy::too_many_arguments)]
        fn $name(simd: bool, $($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            if simd {
                // SAFETY: `simd` is only set when the CPU has AVX (`lanes::simd_available`).
                return unsafe { $avx($($arg),*) };
            }
            let _ = simd;
            $generic::<f64>($($arg),*)
        }
    };
}

lanes_dispatch!(
    vel_row,
    vel_row_avx,
    vel_row_lanes,
    (
        k: &Consts,
        pg: &PipeGeometry,
        inp: &Inputs,
        segs: &[[u32; 2]],
        r: usize,
        out: &mut [&mut [f64]; 6],
    ) -> ()
);
lanes_dispatch!(
    pipes_row,
    pipes_row_avx,
    pipes_row_lanes,
    (
        params: &AvalancheParams,
        k: &Consts,
        pg: &PipeGeometry,
        inp: &Inputs,
        segs: &[[u32; 2]],
        r: usize,
        np: &mut [&mut [f64]; 4],
        fl: &mut [&mut [f64]; 4],
    ) -> ()
);
lanes_dispatch!(
    factor_row,
    factor_row_avx,
    factor_row_lanes,
    (
        k: &Consts,
        inp: &Inputs,
        segs: &[[u32; 2]],
        r: usize,
        out: &mut [f64],
    ) -> ()
);
lanes_dispatch!(
    update_row,
    update_row_avx,
    update_row_lanes,
    (
        k: &Consts,
        inp: &Inputs,
        seg2: &[[u32; 2]],
        seg3: &[[u32; 2]],
        r: usize,
        hrow: &mut [f64],
        prow: &mut [&mut [f64]; 4],
        trow: &mut [[u32; 2]],
    ) -> RowStats
);

/// Velocities of pass 1 on one row.
#[inline(always)]
fn vel_row_lanes<V: Lanes>(
    k: &Consts,
    pg: &PipeGeometry,
    inp: &Inputs,
    segs: &[[u32; 2]],
    r: usize,
    out: &mut [&mut [f64]; 6],
) {
    let pw = k.pw;
    let (lo, hi) = if r >= 1 && r + 2 <= k.ph {
        (1, pw - 2)
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
    out: &mut [&mut [f64]; 6],
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
        let vx_d = (p2 - p3) / V::splat(k.den_x);
        let vy_d = (p2 + p3) / V::splat(k.den_y);
        let vx = half * (p0 + vx_d);
        let vy = half * (p1 + vy_d);
        let a = |i: usize| ld::<V>(inp.bed, i) + ld::<V>(inp.h, i);
        let gx = (a(kk + 1) - a(kk - 1)) / V::splat(k.two_dx);
        let gy = (a(kk + pw) - a(kk - pw)) / V::splat(k.two_dy);
        let hk = ld::<V>(inp.h, kk);
        vx.store(out[VX], c);
        vy.store(out[VY], c);
        (hk * vx).store(out[QX], c);
        (hk * vy).store(out[QY], c);
        gx.store(out[GX], c);
        gy.store(out[GY], c);
    }
}

/// Velocities of pass 1 at any cell (ghost ring and nodata included).
fn cell_flow_border(k: &Consts, pg: &PipeGeometry, inp: &Inputs, c: usize, r: usize) -> [f64; 6] {
    let kk = r * k.pw + c;
    let mut p = [0.0; 4];
    for (d, pd) in p.iter_mut().enumerate() {
        let own = inp.pipes[d][kk];
        *pd = match k.back(c, r, d) {
            Some(kb) => 0.5 * (own + inp.pipes[d][kb]),
            None => own,
        };
    }
    let vx_d = (p[2] - p[3]) / k.den_x;
    let vy_d = (p[2] + p[3]) / k.den_y;
    let (vx, vy) = (0.5 * (p[0] + vx_d), 0.5 * (p[1] + vy_d));
    let [gx, gy] =
        surface_gradient(pg, inp.h, inp.bed, inp.nodata, k.pw, kk).unwrap_or([f64::NAN, f64::NAN]);
    let hk = inp.h[kk];
    [vx, vy, hk * vx, hk * vy, gx, gy]
}

/// Pipes of pass 1 on one row.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn pipes_row_lanes<V: Lanes>(
    params: &AvalancheParams,
    k: &Consts,
    pg: &PipeGeometry,
    inp: &Inputs,
    segs: &[[u32; 2]],
    r: usize,
    np: &mut [&mut [f64]; 4],
    fl: &mut [&mut [f64]; 4],
) {
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
                            pipe_update(params, k, pg, inp, kk, j, d, c, r)
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
        let t0 = half * (lv(VX, kk) + lv(VX, j)) - dtg * (half * (lv(GX, kk) + lv(GX, j)));
        let t1 = half * (lv(VY, kk) + lv(VY, j)) - dtg * (half * (lv(GY, kk) + lv(GY, j)));
        let tnorm = (t0 * t0 + t1 * t1).sqrt();
        let yield_dt = V::splat(k.yield_dt);
        let dead = if k.coulomb {
            V::or(dead, tnorm.le(yield_dt))
        } else {
            dead
        };
        if V::all(dead) {
            return (zero, zero);
        }
        let u0 = ld::<V>(inp.pipes[d], kk);
        let ak = ld::<V>(inp.bed, kk) + hk;
        let aj = ld::<V>(inp.bed, j) + hj;
        let a = V::splat(-G) * (aj - ak) / V::splat(k.len[d]);
        let mut u = u0 + V::splat(k.dt) * a;
        if k.adv {
            u = u + advection_lanes::<V>(k, inp, d, kk, j, hk, hj, u0);
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
        let hup = V::select(u.gt(zero), hk, hj);
        let dead = V::or(dead, hup.le(V::splat(DRY)));
        let f = V::splat(k.width[d]) * hup * u * V::splat(k.dt);
        (V::select(dead, zero, u), V::select(dead, zero, f))
    }
}

/// [`advection`] for the owners of [`owner_lanes`] (every lattice neighbour exists).
///
/// # Safety
/// Every array of `inp` the kernel reads has the padded length `pw·ph`, and the `V::N` cells
/// from padded index `kk` lie in the pass's inner region (see the `walk` call), so that every
/// cell of the stencil is in the arrays.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
unsafe fn advection_lanes<V: Lanes>(
    k: &Consts,
    inp: &Inputs,
    d: usize,
    kk: usize,
    j: usize,
    hk: V,
    hj: V,
    u0: V,
) -> V {
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
        for (m, &(kn, knv, q, qp, rate, minus)) in nbs.iter().enumerate() {
            let qn = half * (ld::<V>(q, knv) + ld::<V>(q, knv + jk));
            let face = half * (qp + qn);
            let inflow = if minus { -face } else { face };
            lam[m] = V::select(inflow.gt(zero), rate * inflow, zero);
            // (A face without inflow has `λ = 0`: its term below is a zero whatever `u_f`, and
            // zeros leave the sums unchanged.)
            un[m] = ld::<V>(pd, kn);
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

/// Outflow factors of pass 1 on one row.
#[inline(always)]
fn factor_row_lanes<V: Lanes>(
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

/// Lane accumulators of pass 2 (maxima and counts: any order gives the same result).
struct Acc<V> {
    umax: V,
    wave: V,
    flowing: usize,
}

/// Pass 2 on one row.
#[allow(clippy::needless_range_loop)]
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn update_row_lanes<V: Lanes>(
    k: &Consts,
    inp: &Inputs,
    seg2: &[[u32; 2]],
    seg3: &[[u32; 2]],
    r: usize,
    hrow: &mut [f64],
    prow: &mut [&mut [f64]; 4],
    trow: &mut [[u32; 2]],
) -> RowStats {
    let (pw, ph) = (k.pw, k.ph);
    let mut st = RowStats::default();
    let zero = V::splat(0.0);
    let mut acc = Acc {
        umax: zero,
        wave: zero,
        flowing: 0,
    };
    let mut acc1 = Acc {
        umax: 0.0,
        wave: 0.0,
        flowing: 0,
    };
    // The row's moved volume, summed cell by cell, pipe by pipe.
    let mut moved = 0.0;
    let (lo, hi) = if r >= 1 && r + 2 <= ph {
        (1, pw - 2)
    } else {
        (1, 0)
    };
    let ghost_row = r == 0 || r == ph - 1;
    let mut run: Option<(usize, usize)> = None;
    let mut content = |c: usize, st: &mut RowStats| {
        run = match run {
            Some((a, _)) if a / TILE == c / TILE => Some((a, c)),
            Some((a, b)) => {
                trow[st.tiles] = [a as u32, b as u32];
                st.tiles += 1;
                Some((c, c))
            }
            None => Some((c, c)),
        };
    };
    // Cells of seg3 in column order; those of seg2 also get their thickness. `next2` is the
    // first segment of seg2 not left of the current cell.
    let mut next2 = 0;
    let mut in2 = |c: usize| {
        while next2 < seg2.len() && (seg2[next2][1] as usize) < c {
            next2 += 1;
        }
        match seg2.get(next2) {
            Some(&[a, b]) if a as usize <= c => (true, b as usize),
            Some(&[a, _]) => (false, a as usize),
            None => (false, usize::MAX),
        }
    };
    for (c, visit) in walk(seg3, lo, hi, None, V::N) {
        let kk = r * pw + c;
        let bits = match visit {
            Visit::Chunk | Visit::One => {
                let (inside, edge) = in2(c);
                let n = if visit == Visit::Chunk { V::N } else { 1 };
                // SAFETY (the three calls): `walk` only gives lane visits in the inner region
                // of this pass, where the stencil lies in the padded arrays (all of length
                // `pw·ph`).
                if n == 1 {
                    unsafe {
                        update_lanes::<f64>(
                            k, inp, kk, hrow, prow, c, &mut acc1, &mut moved, inside,
                        )
                    }
                } else if (inside && c + n - 1 <= edge) || (!inside && c + n - 1 < edge) {
                    // All lanes in seg2, or none.
                    unsafe {
                        update_lanes::<V>(k, inp, kk, hrow, prow, c, &mut acc, &mut moved, inside)
                    }
                } else {
                    let mut bits = 0;
                    for i in 0..n {
                        let inside = in2(c + i).0;
                        let b = unsafe {
                            update_lanes::<f64>(
                                k,
                                inp,
                                kk + i,
                                hrow,
                                prow,
                                c + i,
                                &mut acc1,
                                &mut moved,
                                inside,
                            )
                        };
                        bits |= b << i;
                    }
                    bits
                }
            }
            Visit::Border => {
                if in2(c).0 {
                    let mut dv = 0.0;
                    for d in 0..4 {
                        dv -= scaled_flux(k, inp, kk, c, r, d);
                        if let Some(kb) = k.back(c, r, d) {
                            let (dc, dr) = DIRS[d];
                            dv += scaled_flux(
                                k,
                                inp,
                                kb,
                                (c as isize - dc) as usize,
                                r - dr as usize,
                                d,
                            );
                        }
                    }
                    let mut hn = hrow[c] + dv / k.area;
                    if hn < 0.0 {
                        hn = 0.0;
                    }
                    if ghost_row || c == 0 || c == pw - 1 {
                        st.outflow += hn * k.area;
                        hn = 0.0;
                    } else if hn > 0.0 {
                        acc1.flowing += 1;
                    }
                    let mut umax = 0.0f64;
                    for d in 0..4 {
                        umax = umax.max(scaled_pipe(k, inp, kk, c, r, d).abs());
                        if let Some(kb) = k.back(c, r, d) {
                            let (dc, dr) = DIRS[d];
                            let u = scaled_pipe(
                                k,
                                inp,
                                kb,
                                (c as isize - dc) as usize,
                                r - dr as usize,
                                d,
                            );
                            umax = umax.max(u.abs());
                        }
                    }
                    acc1.wave = acc1.wave.max((G * hn).sqrt() + umax);
                    hrow[c] = hn;
                }
                let mut moving = false;
                for d in 0..4 {
                    let mut u = inp.new_pipes[d][kk];
                    let mut f = inp.flux[d][kk];
                    if f != 0.0 {
                        let src = if f > 0.0 {
                            kk
                        } else {
                            k.neighbour(c, r, d).unwrap_or(kk)
                        };
                        let s = inp.factor[src];
                        f *= s;
                        u *= s;
                    }
                    prow[d][c] = u;
                    moved += f.abs();
                    acc1.umax = acc1.umax.max(u.abs());
                    moving |= u != 0.0;
                }
                (moving || hrow[c] > 0.0) as u32
            }
        };
        let mut b = bits;
        while b != 0 {
            content(c + b.trailing_zeros() as usize, &mut st);
            b &= b - 1;
        }
    }
    if let Some((a, b)) = run {
        trow[st.tiles] = [a as u32, b as u32];
        st.tiles += 1;
    }
    st.moved = moved;
    st.flowing = acc.flowing + acc1.flowing;
    st.umax = acc1.umax;
    st.wave = acc1.wave;
    for i in 0..V::N {
        st.umax = st.umax.max(acc.umax.lane(i));
        st.wave = st.wave.max(acc.wave.lane(i));
    }
    st
}

/// A pipe's new velocity scaled by its upwind cell's factor (general code).
fn scaled_pipe(k: &Consts, inp: &Inputs, kk: usize, c: usize, r: usize, d: usize) -> f64 {
    let u = inp.new_pipes[d][kk];
    let f = inp.flux[d][kk];
    if f != 0.0 {
        let src = if f > 0.0 {
            kk
        } else {
            k.neighbour(c, r, d).unwrap_or(kk)
        };
        u * inp.factor[src]
    } else {
        u
    }
}

/// A pipe's volume scaled by its upwind cell's factor (general code).
fn scaled_flux(k: &Consts, inp: &Inputs, kk: usize, c: usize, r: usize, d: usize) -> f64 {
    let f = inp.flux[d][kk];
    if f != 0.0 {
        let src = if f > 0.0 {
            kk
        } else {
            k.neighbour(c, r, d).unwrap_or(kk)
        };
        f * inp.factor[src]
    } else {
        f
    }
}

/// Pass 2 on `V::N` cells away from the ghost ring: the pipes they own scaled by their upwind
/// cell's factor (volume moved, largest speed) and, with `thick`, their new thickness (and
/// wave speed). A volume `f` scaled by the factor `s` is `f·s` even for a zero `f` (`s` is
/// finite and ≥ 0), so the product needs no branch. Returns the lanes with content (snow or a
/// moving pipe).
///
/// # Safety
/// Every array of `inp` the kernel reads has the padded length `pw·ph`, and the `V::N` cells
/// from padded index `kk` lie in the pass's inner region (see the `walk` call), so that every
/// cell of the stencil is in the arrays.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
unsafe fn update_lanes<V: Lanes>(
    k: &Consts,
    inp: &Inputs,
    kk: usize,
    hrow: &mut [f64],
    prow: &mut [&mut [f64]; 4],
    c: usize,
    acc: &mut Acc<V>,
    moved: &mut f64,
    thick: bool,
) -> u32 {
    // SAFETY: the caller guarantees the stencil lies in the arrays (see `# Safety`).
    unsafe {
        let zero = V::splat(0.0);
        let fac = |i: usize| ld::<V>(inp.factor, i);
        let mut dv = zero;
        // Largest speed of the 8 pipes touching the cells.
        let mut ucell = zero;
        let mut moving = zero.ne(zero);
        let mut absf = [zero; 4];
        for d in 0..4 {
            let off = k.off[d];
            let f = ld::<V>(inp.flux[d], kk);
            let s = V::select(f.gt(zero), fac(kk), fac(kk + off));
            let u = ld::<V>(inp.new_pipes[d], kk);
            let u = V::select(f.ne(zero), u * s, u);
            let fs = f * s;
            absf[d] = fs.abs();
            u.store(prow[d], c);
            acc.umax = acc.umax.max(u.abs());
            moving = V::or(moving, u.ne(zero));
            if thick {
                dv = dv - fs;
                ucell = ucell.max(u.abs());
                let kb = kk - off;
                let f = ld::<V>(inp.flux[d], kb);
                let s = V::select(f.gt(zero), fac(kb), fac(kk));
                dv = dv + f * s;
                let u = ld::<V>(inp.new_pipes[d], kb);
                ucell = ucell.max(V::select(f.ne(zero), u * s, u).abs());
            }
        }
        // The row's volume in the order of the general code: cell by cell, pipe by pipe.
        for i in 0..V::N {
            for a in &absf {
                *moved += a.lane(i);
            }
        }
        if thick {
            let hn = ld::<V>(hrow, c) + dv / V::splat(k.area);
            let hn = V::select(hn.lt(zero), zero, hn);
            hn.store(hrow, c);
            acc.flowing += V::bits(hn.gt(zero)).count_ones() as usize;
            acc.wave = acc.wave.max((V::splat(G) * hn).sqrt() + ucell);
        }
        V::bits(V::or(moving, ld::<V>(hrow, c).gt(zero)))
    }
}

/// One pipe's new velocity and raw (unscaled) volume for a sub-step.
#[allow(clippy::too_many_arguments)]
fn pipe_update(
    params: &AvalancheParams,
    k: &Consts,
    pg: &PipeGeometry,
    inp: &Inputs,
    kk: usize,
    j: usize,
    d: usize,
    c: usize,
    r: usize,
) -> (f64, f64) {
    let (h, bed, vel, vb) = (inp.h, inp.bed, &inp.vel, inp.vbase);
    let dt = k.dt;
    let (hi, hj) = (h[kk], h[j]);
    if hi <= DRY && hj <= DRY {
        return (0.0, 0.0);
    }
    let u0 = inp.pipes[d][kk];
    let a = -G * ((bed[j] + hj) - (bed[kk] + hi)) / pg.len[d];
    let vp = [
        0.5 * (vel[VX][kk - vb] + vel[VX][j - vb]),
        0.5 * (vel[VY][kk - vb] + vel[VY][j - vb]),
    ];
    let mut u = u0 + dt * a;
    if params.momentum_advection {
        u += advection(pg, inp, k.pw, kk, j, d, c, r, dt);
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
    let yield_dt = k.yield_dt;
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
fn advection(
    pg: &PipeGeometry,
    inp: &Inputs,
    pw: usize,
    k: usize,
    j: usize,
    d: usize,
    c: usize,
    r: usize,
    dt: f64,
) -> f64 {
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
            un[m] = inp.pipes[d][kn];
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::Ordering;

    /// The four-lane kernels give the bits of the one-lane (scalar) ones: random bed and
    /// depths, nodata cells, both borders, dry, wet and mixed snow, square and oblong cells.
    #[test]
    fn lanes_match_scalar() {
        let hash = |i: usize, seed: u64| {
            let mut x = (i as u64 ^ seed.wrapping_mul(0x9E37_79B9_7F4A_7C15))
                .wrapping_add(0x632B_E59B_D9B4_E019);
            x ^= x >> 30;
            x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
            x ^= x >> 27;
            x = x.wrapping_mul(0x94D0_49BB_1331_11EB);
            x ^= x >> 31;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        let cases = [
            (70, 50, 2.0, 2.0, Border::Open, 1.0),
            (61, 43, 3.0, 2.0, Border::Closed, 0.4),
            (40, 64, 5.0, 5.0, Border::Open, 0.0),
        ];
        for (case, &(w, h, dx, dy, border, alpha)) in cases.iter().enumerate() {
            let seed = case as u64 + 11;
            let g = GridGeometry::new(w, h, dx, dy).unwrap();
            let bed: Vec<f64> = (0..w * h)
                .map(|i| 4.0 * hash(i, seed) + 0.9 * (i / w) as f64 + 0.2 * (i % w) as f64)
                .collect();
            let mask =
                NodataMask::from_invalid((0..w * h).map(|i| hash(i, seed ^ 7) < 0.02).collect());
            let mut s = AvalancheState::new(&g, &mask, &bed).unwrap();
            let depth: Vec<f64> = (0..w * h)
                .map(|i| {
                    let v = hash(i, seed ^ 3);
                    if v < 0.4 { 0.0 } else { 2.0 * v }
                })
                .collect();
            s.set_thickness(&depth).unwrap();
            let params = AvalancheParams {
                border,
                alpha,
                k_viscous: 0.02,
                ..AvalancheParams::default()
            };
            let run = |scalar: bool| {
                FORCE_SCALAR.store(scalar, Ordering::Relaxed);
                let mut st = s.clone();
                let mut scratch = AvalancheScratch::default();
                let reports: Vec<AvalancheReport> = (0..12)
                    .map(|_| step(&params, &mut st, &mut scratch, 0.3).unwrap())
                    .collect();
                FORCE_SCALAR.store(false, Ordering::Relaxed);
                (st, reports)
            };
            let (a, ra) = run(true);
            let (b, rb) = run(false);
            assert!(ra.iter().map(|r| r.substeps).sum::<usize>() > 20);
            assert_eq!(a, b, "case {case}");
            assert_eq!(ra, rb, "case {case}");
        }
    }
}
