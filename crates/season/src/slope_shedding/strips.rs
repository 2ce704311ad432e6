//! Strips of rows, swept in parallel (see the parent module's documentation, "Parallel
//! strips"): each strip owns its rows and sees one halo row of each neighbouring strip, a copy
//! taken between phases; snow a strip sends into its halo waits in its outbox for the next phase.

use super::cascade::{self, SweepTotals};
use super::*;
use std::ops::Range;

/// Fewest rows of a strip.
const MIN_STRIP_ROWS: usize = 16;

/// Strips of a grid: its two halves. The strips depend on the grid alone, never on the number
/// of threads, so the results do not either. Each boundary costs phases (a debris flow crosses
/// it once per phase, and zigzags where it runs along it), so more strips cost more than they
/// gain: on the benchmark's 1024² terrain, a step after 2 cm of powder on 1 m of settled snow
/// took 73 ms in one strip, 48 ms in two, 61 ms in four and 77 ms in eight (2 cores; 80 ms in
/// the single sweep before the strips).
const STRIPS: usize = 2;

/// The strips' own rows: `ceil(height / STRIPS)` rows each, at least [`MIN_STRIP_ROWS`].
pub(super) fn strip_rows(height: usize) -> Vec<Range<usize>> {
    let rows = height.div_ceil(STRIPS).max(MIN_STRIP_ROWS);
    (0..height)
        .step_by(rows)
        .map(|r| r..(r + rows).min(height))
        .collect()
}

/// One strip of rows and its sweep's state.
#[derive(Debug, Clone)]
pub(super) struct Strip {
    /// The rows of the grid the strip owns.
    pub(super) rows: Range<usize>,
    /// The strip's window: its rows and a halo row above and below where the grid has them.
    /// Cells are indexed in the window from here on.
    pub(super) window: Range<usize>,
    /// The window as a grid of its own (its border is the grid's, its halo rows are cells).
    pub(super) geometry: GridGeometry,
    /// The strip's valid cells, each after its neighbours in the strip that lie above it
    /// ([`upslope_first_order`] of the strip's rows).
    pub(super) order: Vec<u32>,
    /// The window's cells: the strip's own (`rank` their position in `order`) and the halo's
    /// (flagged [`HALO`], copies of the neighbouring strips' cells).
    pub(super) cells: Vec<CellState>,
    /// One bit per rank: the cells the sweep has still to visit.
    pub(super) pending: Vec<u64>,
    /// Passed receivers waiting for a visit.
    pub(super) queue: BinaryHeap<u64>,
    /// Own cells whose surface (or expected surface) changed in this phase.
    pub(super) dirty: Vec<u32>,
    /// Snow sent into the halo in this phase: grid index and depth, m.
    pub(super) outbox: Vec<(u32, f32)>,
    /// Visits of passed cells in this step (bounded by the revisit budget).
    pub(super) revisits: usize,
}

impl Strip {
    /// The strip of rows `rows` of a grid: its order and its cells' fixed fields (`rank`,
    /// `interior`, `bedrock_tan` from `bedrock_tan`, per grid cell).
    pub(super) fn new<V: Validity>(
        rows: Range<usize>,
        bedrock: &[f32],
        geometry: &GridGeometry,
        valid: &V,
        bedrock_tan: &[f32],
    ) -> Result<Self, PhenomenonError> {
        let (w, h) = (geometry.width(), geometry.height());
        let window_rows = rows.start.saturating_sub(1)..(rows.end + 1).min(h);
        let grid = |height: usize| {
            GridGeometry::new(w, height, geometry.cell_size_x(), geometry.cell_size_y()).map_err(
                |_| PhenomenonError::InvalidParameter {
                    phenomenon: NAME,
                    name: "rows",
                    value: height as f64,
                    reason: "a strip of rows of the grid is not a grid",
                },
            )
        };
        let own = rows.start * w..rows.end * w;
        let own_order = upslope_first_order(
            &bedrock[own.clone()],
            &grid(rows.len())?,
            &valid.window(own),
        );
        let shift = ((rows.start - window_rows.start) * w) as u32;
        let order: Vec<u32> = own_order.iter().map(|&i| i + shift).collect();
        let window = window_rows.start * w..window_rows.end * w;
        let mut cells: Vec<CellState> = window
            .clone()
            .map(|g| {
                let (col, row) = (g % w, g / w);
                CellState {
                    interior: col > 0 && row > 0 && col + 1 < w && row + 1 < h,
                    bedrock_tan: bedrock_tan[g],
                    ..CellState::default()
                }
            })
            .collect();
        for (p, &i) in order.iter().enumerate() {
            cells[i as usize].rank = p as u32;
        }
        Ok(Self {
            rows,
            geometry: grid(window_rows.len())?,
            window,
            order,
            cells,
            pending: Vec::new(),
            queue: BinaryHeap::new(),
            dirty: Vec::new(),
            outbox: Vec::new(),
            revisits: 0,
        })
    }

    /// The window index of grid cell `g` (one of the strip's own).
    #[inline]
    pub(super) fn local(&self, g: usize) -> usize {
        g - self.window.start
    }

    /// The window indices of the strip's own cells.
    pub(super) fn own(&self, width: usize) -> Range<usize> {
        let start = self.rows.start * width - self.window.start;
        start..start + self.rows.len() * width
    }

    /// Ready for a step: nothing pending, queued, changed or sent.
    pub(super) fn clear(&mut self) {
        self.pending.clear();
        self.pending.resize(self.order.len().div_ceil(64), 0);
        self.queue.clear();
        self.dirty.clear();
        self.outbox.clear();
        self.revisits = 0;
    }

    /// After a phase's sweep every cell rests: what a later phase sees of a cell it has not
    /// reached is its current surface.
    pub(super) fn settle(&mut self) {
        for &i in &self.dirty {
            let cell = &mut self.cells[i as usize];
            cell.surface0 = cell.surface;
            cell.flags &= !DIRTY;
        }
        self.dirty.clear();
    }

    /// Lists own cell `i` as changed in this phase.
    #[inline]
    pub(super) fn mark_dirty(&mut self, i: usize) {
        let cell = &mut self.cells[i];
        if cell.flags & DIRTY == 0 {
            cell.flags |= DIRTY;
            self.dirty.push(i as u32);
        }
    }

    /// Marks own cell `i` (window index) to be visited.
    #[inline]
    pub(super) fn mark_pending(&mut self, i: usize) {
        set_pending(&mut self.pending, self.cells[i].rank);
    }

    /// Whether any cell waits for a visit.
    pub(super) fn has_pending(&self) -> bool {
        self.pending.iter().any(|&b| b != 0)
    }
}

/// Sets the pending bit of `rank`.
#[inline]
pub(super) fn set_pending(pending: &mut [u64], rank: u32) {
    let p = rank as usize;
    pending[p / 64] |= 1 << (p % 64);
}

/// What a strip sees of a neighbouring strip's cell in its halo: the surface it is expected to
/// keep (`surface0` if that strip has set the cell up in this step, else its snow surface) and
/// its bed.
fn halo_cell(
    strips: &[Strip],
    owner: usize,
    g: usize,
    generation: u32,
    bedrock: &[f32],
    snow: &[Vec<f32>; 4],
) -> CellState {
    let strip = &strips[owner];
    let mut cell = strip.cells[strip.local(g)];
    if cell.stamp != generation {
        (cell.bed, cell.surface0) = bed_and_surface(column(bedrock, g, snow, g));
    }
    // Seen as a cell the sweep has not reached (the largest rank): the surface it is expected
    // to keep, whatever it receives (in transit), and no limit on what is sent.
    CellState {
        surface: cell.surface0,
        rank: u32::MAX,
        stamp: generation,
        flags: HALO,
        ..cell
    }
}

/// Copies into the halo of each strip in `which` the cells of its neighbours, as they are
/// expected to rest (see [`halo_cell`]).
pub(super) fn refresh_halos(
    strips: &mut [Strip],
    which: &[usize],
    generation: u32,
    bedrock: &[f32],
    snow: &[Vec<f32>; 4],
    width: usize,
) {
    let halos: Vec<Vec<(usize, CellState)>> = which
        .iter()
        .map(|&s| {
            let strip = &strips[s];
            let mut halo = Vec::new();
            let mut row = |owner: usize, r: usize| {
                for g in r * width..(r + 1) * width {
                    let cell = halo_cell(strips, owner, g, generation, bedrock, snow);
                    halo.push((strip.local(g), cell));
                }
            };
            if s > 0 {
                row(s - 1, strip.rows.start - 1);
            }
            if s + 1 < strips.len() {
                row(s + 1, strip.rows.end);
            }
            halo
        })
        .collect();
    for (&s, halo) in which.iter().zip(halos) {
        for (i, cell) in halo {
            strips[s].cells[i] = cell;
        }
    }
}

/// Most phases of one step: what still crosses between strips after them is left where it
/// landed (reported as unsettled; the next step moves it on).
const MAX_PHASES: usize = 1024;

/// Sheds the `active` cells' excess (grid index, slope tan, excess m; in index order): every
/// strip sweeps its own cells in parallel, then, phase after phase, the strips that received
/// snow from a neighbour sweep again from those receivers, until none crosses.
pub(super) fn shed_in_phases<V: Validity>(
    tables: &Tables,
    terrain: &mut LayeredTerrain,
    strips: &mut [Strip],
    valid: &V,
    active: &[(u32, f32, f32)],
    generation: u32,
) -> SheddingReport {
    let w = terrain.geometry().width();
    let area = terrain.geometry().cell_area();
    let deposit = tables.params.deposit_layer.index();
    let (bedrock, snow) = (&terrain.bedrock, &terrain.snow);
    // What the neighbours above expect a cell to keep: its surface less its own excess.
    parallel::for_each_row(1, PerRow(&mut *strips), |_, strip| {
        strip.clear();
        let lo = active.partition_point(|a| (a.0 as usize) < strip.rows.start * w);
        let hi = active.partition_point(|a| (a.0 as usize) < strip.rows.end * w);
        for &(g, tan, excess) in &active[lo..hi] {
            let (g, i) = (g as usize, strip.local(g as usize));
            set_up(i, generation, &mut strip.cells, || {
                column(bedrock, g, snow, g)
            });
            let cell = &mut strip.cells[i];
            cell.flags = ACTIVE | PENDING;
            cell.tan_slope = tan;
            cell.surface0 -= excess;
            strip.mark_pending(i);
            strip.mark_dirty(i);
        }
    });
    let mut totals = SweepTotals::default();
    let mut unsettled = 0;
    for phase in 0.. {
        if phase > 0 {
            let inbox: Vec<(u32, f32)> = strips
                .iter_mut()
                .flat_map(|s| std::mem::take(&mut s.outbox))
                .collect();
            if inbox.is_empty() {
                break;
            }
            parallel::for_each_row(1, PerRow(&mut *strips), |_, strip| strip.settle());
            let snow = &mut terrain.snow;
            for &(g, share) in &inbox {
                let g = g as usize;
                let s = (g / w) / strips[0].rows.len();
                let strip = &mut strips[s];
                let i = strip.local(g);
                set_up(i, generation, &mut strip.cells, || {
                    column(&terrain.bedrock, g, snow, g)
                });
                strip.mark_dirty(i);
                snow[deposit][g] += share;
                let cell = &mut strip.cells[i];
                cell.surface += share;
                cell.flags |= RECEIVED;
                if phase == MAX_PHASES {
                    unsettled += 1;
                } else if cell.flags & PENDING == 0 {
                    cell.flags |= PENDING;
                    strip.mark_pending(i);
                }
            }
            if phase == MAX_PHASES {
                break;
            }
        }
        let which: Vec<usize> = (0..strips.len())
            .filter(|&s| phase == 0 || strips[s].has_pending())
            .collect();
        refresh_halos(
            strips,
            &which,
            generation,
            &terrain.bedrock,
            &terrain.snow,
            w,
        );
        let swept: Vec<SweepTotals> = {
            let mut layers = terrain.snow.each_mut().map(|l| l.as_mut_slice());
            let mut parts: Vec<(&mut Strip, [&mut [f32]; 4])> = Vec::with_capacity(strips.len());
            for strip in strips.iter_mut() {
                let len = strip.rows.len() * w;
                let own = layers.each_mut().map(|l| {
                    let (head, tail) = std::mem::take(l).split_at_mut(len);
                    *l = tail;
                    head
                });
                parts.push((strip, own));
            }
            // Only the strips in `which` sweep; their totals in strip order.
            parallel::map_rows(1, PerRow(parts), |s, (strip, own)| {
                which.binary_search(&s).is_ok().then(|| {
                    cascade::sweep(tables, &terrain.bedrock, strip, own, valid, generation)
                })
            })
            .into_iter()
            .flatten()
            .collect()
        };
        for t in swept {
            totals.moved += t.moved;
            totals.received += t.received;
            totals.border += t.border;
            totals.cells_shed += t.cells_shed;
            totals.unsettled += t.unsettled;
        }
    }
    SheddingReport {
        moved_m3: totals.moved * area,
        received_m3: totals.received * area,
        border_outflow_m3: totals.border * area,
        cells_shed: totals.cells_shed,
        revisits: strips.iter().map(|s| s.revisits).sum(),
        unsettled_cells: totals.unsettled + unsettled,
    }
}
