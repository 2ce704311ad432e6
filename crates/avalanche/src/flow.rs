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
//! momentum advection the paper omits (needed for Ritter's dam-break front, `docs/src/model.md#flow-model`): each
//! pipe direction forms a regular lattice, `u` is advected by the velocity `v` at the pipe (mean
//! of the two cells' velocities, reconstructed from their 8 pipes) with first-order upwind
//! differences on that lattice. The third is the Coulomb yield force of norm `g·tanθc`,
//! applied as one vector: the trial velocity at the pipe `v + δt·(−g∇A)` (mean of the two
//! cells' reconstructed velocities and central-difference surface gradients) is slowed by
//! `g·tanθc·δt` along its own direction and each pipe takes its projection `e·v̂`. As in the
//! paper, where the flow is null or the force would reverse it, the velocity is set to zero
//! (static friction): snow at rest holds while `|∇A| ≤ tanθc`, the same criterion in every
//! direction, and a sheet on a plane of slope `tanθ > tanθc` accelerates at `g·(tanθ − tanθc)`
//! (tests/validation.rs). With [`SlopeGravity::Projected`] (Savage & Hutter 1989; Mangeney et
//! al. 2000; see its docs) gravity acts as Savage-Hutter's projected on the horizontal grid:
//! the first term becomes `−g c² ((B_j − B_i) + c² (h_j − h_i))/L`, the trial gradient
//! `c² (∇B + c² ∇h)` and the yield `c²·g·tanθc`, with `c² = cos²θ = 1/(1 + |∇B|²)` the mean
//! of the pipe's two cells (central differences of the bed), and the Voellmy and samosAT drags
//! are divided by `c²`; a sheet on a plane then accelerates at `g cos²θ (tanθ − tanθc)`
//! (tests/avaframe_analytic.rs). With [`AvalancheParams::curvature`] (the default) the yield
//! is `c²·f·g·tanθc` with the pipe's load factor `f = max(0, 1 + v·H·v/g)` of the bed's
//! curvature (`pipes::curvature_load`, mean of the two cells) and the advection carries the
//! speed along the bed (`update::advection`). The fourth is the viscous term `−kv·U·φ` of the paper written for the velocity (`h_face` = mean depth of the two
//! cells), applied implicitly. `α ∈ [0, 1]` mixes dry (Coulomb) and wet (viscous) snow.
//!
//! **Mass (per cell).** The volume through a pipe in a sub-step is `F = w · h_up · u · δt`, with
//! `h_up` the depth of the upwind cell: the *face cross-section* is `w·h_up`, not the paper's
//! constant `dx²`, which makes waves travel at `sqrt(g·h)` instead of `sqrt(g·dx)` (`docs/src/model.md#flow-model`). The widths `w` make the 8-pipe stencil consistent with `∂h/∂t + ∇·(h v) = 0` and
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
//! **Borders.** The ghost ring and the nodata cells (the outline of a clipped DEM, and holes in
//! it) are the two edges of the terrain, and [`AvalancheParams::border`] sets the condition of
//! both:
//!
//! - [`Border::Open`] (the default, and the season's natural avalanches): an open boundary.
//!   The ghost ring takes the bed of the nearest grid cell, a nodata cell the bed of the
//!   nearest valid cell (`state::nearest_valid`: by 8-neighbour steps, an edge neighbour
//!   before a corner one, ties in row-major order; found once at setup, O(cells), from the
//!   mask alone, so a lazily read bed takes the same), and both hold no snow: their pipes are
//!   computed as any other, the snow that flows into them in a sub-step leaves the terrain at
//!   its end and is counted as `border_outflow` (the volume budget closes with it), and the
//!   surface gradient of a cell next to them reads their surface, their bed. Their own surface
//!   gradient is undefined: a pipe to them takes the valid cell's. The bed is copied when it is
//!   read (at setup, or per tile in a lazy state): bed the flow scours from a valid cell during
//!   a run is not scoured from its copies.
//! - [`Border::Closed`]: walls. Pipes to the ghost ring and to nodata cells carry nothing, and
//!   the surface gradient next to a nodata cell replaces it by the cell itself.
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
//! from the ghost ring and nodata cells the kernels run on eight consecutive cells at a time
//! (AVX-512, when the CPU has it; four at a segment's end) or four (AVX), with the IEEE
//! operations of the one-cell code and in the same order, so the lanes change no result. The
//! constant divisors (`2·dx`, `2·dy`, `L`, `dx·dy`) are applied as multiplications by their
//! reciprocals.
//!
//! **Threads.** A large flow runs its passes through the project's one dispatch point
//! ([`snowscape_terrain::parallel`]: blocks of rows, then rows); a small one (below
//! [`PARALLEL_MIN_CELLS`] visited cells) on the calling thread, or, during a run to rest on a
//! pool of two threads or more, shared with the run's helper thread (`team`: the first blocks or
//! rows on the caller, the rest on the helper, split where half the visited cells lie).
//!
//! **Determinism.** Every pass is a gather over rows, each row writes only its own cells, and
//! per-row sums are added in row order (within a row, cell by cell), so results are
//! bit-identical for any thread count, any split and any lane width.

mod consts;
mod footprint;
mod lanes;
mod params;
mod peaks;
mod pipes;
mod rows;
mod settle;
mod state;
mod substep;
mod team;
mod thickness;
mod tiles;
mod update;
mod walk;

use consts::Consts;
pub use params::{
    AvalancheError, AvalancheParams, AvalancheReport, Border, FrictionLaw, SamosAtParams,
    SlopeGravity,
};
pub(crate) use peaks::{Peaks, Recorded};
use peaks::{RecordRow, record_row_lanes};
use pipes::*;
use rows::Rows;
use substep::substep;
use thickness::*;
use update::*;
use walk::*;

pub use footprint::BedSource;

use crate::friction_maps::FrictionMaps;
use lanes::{Lanes, Simd, ld};
use serde::{Deserialize, Serialize};
use snowscape_terrain::parallel::{self, PerRow};
use snowscape_terrain::{GridGeometry, NodataMask};
use std::sync::Mutex;
pub(crate) use team::Team;
use team::TeamHandle;
use thiserror::Error;
use tiles::{Segments, TILE, TileSet};

/// Gravitational acceleration, m/s²: the paper's `g = 9.81`, the model's one value.
pub const G: f64 = snowscape_terrain::materials::GRAVITY_M_S2;

/// A depth below which a cell is treated as dry for the upwind face cross-section, m.
const DRY: f64 = 1e-12;

/// Pipe directions owned by a cell, as (column step, row step): east, south, south-east,
/// south-west (rows grow southwards).
pub const DIRS: [(isize, isize); 4] = [(1, 0), (0, 1), (1, 1), (-1, 1)];

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

/// The rows of the block of the pipe pass a worker works on: velocities, discharges and
/// gradients ([`VX`]..[`GY`]), and the pipes and volumes of the next block's first row (the
/// volumes after a copy of the block's last row).
#[derive(Default)]
struct BlockRows {
    vel: [Vec<f64>; 9],
    np: [Vec<f64>; 4],
    fl: [Vec<f64>; 4],
}

/// One [`BlockRows`] per worker thread of the pool running the step, owned by the scratch: a
/// block takes its worker's (a block never waits on other work while it holds it, so the
/// lock is never contended within a pool).
#[derive(Default)]
struct BlockRowsPool(Vec<Mutex<BlockRows>>);

impl BlockRowsPool {
    /// Makes room for every worker of the current pool (and the two of a [`Team`]).
    fn reserve_workers(&mut self) {
        let n = snowscape_terrain::parallel::workers().max(2);
        if self.0.len() < n {
            self.0.resize_with(n, Default::default);
        }
    }

    /// The rows of worker `worker` (a dispatch worker's index, or a [`Team`]'s 0 and 1).
    fn of_worker(&self, worker: usize) -> std::sync::MutexGuard<'_, BlockRows> {
        let i = worker % self.0.len().max(1);
        // A panic in another block poisons nothing we rely on: the rows are overwritten
        // before they are read.
        self.0[i].lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl Clone for BlockRowsPool {
    /// Work buffers are not state: a clone starts empty.
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl std::fmt::Debug for BlockRowsPool {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "BlockRowsPool({} workers)", self.0.len())
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
    /// Per grid cell, the valid cell whose bed it takes (`state::nearest_valid`; empty: every
    /// cell its own).
    bed_from: Vec<u32>,
    /// Pipe lengths, widths and directions of the grid.
    pg: PipeGeometry,
    /// The tiles this run touched; whether the bed is read lazily.
    pub(crate) footprint: footprint::Footprint,
    /// Padded per-cell dry-friction coefficient μ (`crate::friction_maps`; empty: the law's).
    pub(crate) mu: Vec<f64>,
    /// Padded per-cell Voellmy ξ, m/s² (empty: the law's).
    pub(crate) xi: Vec<f64>,
}

/// The per-cell quantities of a sub-step the pipes read, one array each: velocity (vx, vy)
/// reconstructed from the 8 pipes, discharge (h·vx, h·vy), the gradient gravity acts on
/// (∂A/∂x, ∂A/∂y; with [`SlopeGravity::Projected`] `cos²θ (∇B + cos²θ ∇h)`; NaN on the ghost
/// ring and nodata cells), the bed's `cos²θ` (1 with [`SlopeGravity::Shallow`]; NaN where
/// the gradient is), the bed's load factor `f = max(0, 1 + v·H·v/g)` of the curvature
/// (`pipes::curvature_load`; 1 with [`SlopeGravity::Shallow`] or without
/// [`AvalancheParams::curvature`]; NaN where the gradient is) and, with the curvature, the
/// flow's length along the bed per horizontal length `m = sqrt(1 + (v̂·∇B)²)` (`v̂` the
/// direction of the cell's velocity; 1 at rest and where the gradient is undefined; not
/// written without the curvature). Nine arrays (a named constant as the array length trips
/// the compiler).
const VX: usize = 0;
const VY: usize = 1;
const QX: usize = 2;
const QY: usize = 3;
const GX: usize = 4;
const GY: usize = 5;
const C2: usize = 6;
const CF: usize = 7;
const M: usize = 8;

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
    /// Per visited row of the thickness pass, its sums and maxima.
    row_stats: Vec<RowStats>,
    /// The active tiles grown by 3 cells (velocities, pipes) and by 2 cells (thickness).
    seg3: Segments,
    seg2: Segments,
    /// The pipe pass's rows, per worker.
    block_rows: BlockRowsPool,
    /// The widest kernels to run, lanes (1, 4 or 8; 0: the widest the CPU has). Every width
    /// gives the same bits (for the tests and the benchmark that compare them).
    max_lanes: usize,
    /// The helper thread of the run to rest going on (small flows split their passes with it).
    team: TeamHandle,
}

impl AvalancheScratch {
    /// Runs the one-lane kernels even where the CPU has AVX (`true`), or the fastest the CPU
    /// has (`false`, the default). Both give the same bits.
    pub fn set_scalar_kernels(&mut self, scalar: bool) {
        self.max_lanes = if scalar { 1 } else { 0 };
    }

    /// Runs kernels at most `lanes` wide (1: one cell at a time; 4: AVX; 8: AVX-512; 0: the
    /// widest the CPU has, the default), never wider than the CPU has. Every width gives the
    /// same bits.
    pub fn set_max_lanes(&mut self, lanes: usize) {
        self.max_lanes = lanes;
    }

    /// Splits small flows' passes with `team`'s helper from now on (a default handle: none).
    pub(crate) fn set_team(&mut self, team: TeamHandle) {
        self.team = team;
    }

    /// The kernels a sub-step runs.
    fn simd(&self) -> Simd {
        let cpu = Simd::detect();
        match self.max_lanes {
            0 => cpu,
            1..=3 => Simd::Scalar,
            4..=7 => cpu.min(Simd::Avx),
            _ => cpu,
        }
    }
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
    /// `1/(dx·dy)`, `1/(2·dx)`, `1/(2·dy)` and `−g/L` per direction: constant divisors as
    /// factors.
    inv_area: f64,
    inv_two_dx: f64,
    inv_two_dy: f64,
    neg_g_over_len: [f64; 4],
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
            inv_area: 1.0 / (dx * dy),
            inv_two_dx: 1.0 / (2.0 * dx),
            inv_two_dy: 1.0 / (2.0 * dy),
            neg_g_over_len: [-G / dx, -G / dy, -G / ld, -G / ld],
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

/// Read-only arrays of a pass (the ones a pass does not read are empty).
#[derive(Clone, Copy)]
struct Inputs<'a> {
    h: &'a [f64],
    bed: &'a [f64],
    nodata: &'a [bool],
    near_wall: &'a [bool],
    pipes: [&'a [f64]; 4],
    /// Velocities, discharges and gradients of the padded cells from index `vbase` on.
    vel: [&'a [f64]; 9],
    vbase: usize,
    new_pipes: [&'a [f64]; 4],
    /// Raw volumes of the padded cells from index `fbase` on (0 outside the pipe pass).
    flux: [&'a [f64]; 4],
    fbase: usize,
    factor: &'a [f64],
    /// Padded per-cell μ and ξ (empty: the law's scalars in [`Consts`]).
    mu: &'a [f64],
    xi: &'a [f64],
}

/// Per-row results of the final pass of a sub-step.
#[derive(Debug, Clone, Copy, Default)]
struct RowStats {
    moved: f64,
    umax: f64,
    outflow: f64,
    wave: f64,
    flowing: usize,
    /// Entries of the row in `row_tiles`.
    tiles: usize,
}

/// A block of the pipe pass: its new pipes and raw volumes (4 directions each) and its
/// outflow factors.
type BlockItem<'a> = [&'a mut [f64]; 9];

/// A row of the thickness pass: its thickness and pipes (4 directions).
type RowItem<'a> = [&'a mut [f64]; 5];

/// A row of pass 1: its index and the segments of cells it visits.
#[derive(Debug, Clone, Copy)]
struct PassRow<'a> {
    row: usize,
    segs: &'a [[u32; 2]],
}

/// Defines `$name(simd, args..)`, running `$generic::<F8>` compiled for AVX-512 or
/// `$generic::<F4>` compiled for AVX as `simd` says (the caller checked the CPU), else
/// `$generic::<f64>`.
macro_rules! lanes_dispatch {
    ($name:ident, $avx:ident, $avx512:ident, $generic:ident, ($($arg:ident : $ty:ty),* $(,)?) -> $ret:ty $(,)?) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx")]
        fn $avx($($arg: $ty),*) -> $ret {
            $generic::<lanes::F4>($($arg),*)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx,avx512f,avx512dq")]
        fn $avx512($($arg: $ty),*) -> $ret {
            $generic::<lanes::F8>($($arg),*)
        }

        fn $name(simd: Simd, $($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            match simd {
                // SAFETY: `simd` names only what the CPU has (`Simd::detect`).
                Simd::Avx512 => return unsafe { $avx512($($arg),*) },
                Simd::Avx => return unsafe { $avx($($arg),*) },
                Simd::Scalar => {}
            }
            let _ = simd;
            $generic::<f64>($($arg),*)
        }
    };
}

lanes_dispatch!(
    vel_row,
    vel_row_avx,
    vel_row_avx512,
    vel_row_lanes,
    (
        k: &Consts,
        pg: &PipeGeometry,
        inp: &Inputs,
        segs: &[[u32; 2]],
        r: usize,
        out: &mut [&mut [f64]; 9],
    ) -> ()
);
lanes_dispatch!(
    pipes_row,
    pipes_row_avx,
    pipes_row_avx512,
    pipes_row_lanes,
    (
        params: &AvalancheParams,
        k: &Consts,
        pg: &PipeGeometry,
        inp: &Inputs,
        row: PassRow,
        out: PipeRows,
    ) -> ()
);
lanes_dispatch!(
    factor_row,
    factor_row_avx,
    factor_row_avx512,
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
    update_row_avx512,
    update_row_lanes,
    (
        k: &Consts,
        inp: &Inputs,
        segs: UpdateSegs,
        hrow: &mut [f64],
        prow: &mut [&mut [f64]; 4],
        trow: &mut [[u32; 2]],
    ) -> RowStats
);

lanes_dispatch!(
    record_row,
    record_row_avx,
    record_row_avx512,
    record_row_lanes,
    (
        s: &AvalancheState,
        row: RecordRow,
        consts: (f64, [f64; 2]),
        peaks: (&mut [f64], &mut [f64]),
        out: &mut Recorded,
    ) -> (),
);

#[cfg(test)]
mod tests;
