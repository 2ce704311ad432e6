//! The distance-to-terminus map (Cordonnier et al. 2018, Section 6.2, "Global path search").
//!
//! The paper pre-computes, with "a simple cellular automaton that finds minima on the terrain
//! and propagates the distance to them", the distance from each cell to a down-slope end point,
//! used to weight where skiers spawn and to keep them out of dead-ends.
//!
//! **Termini** ([`Terminus`]) have distance 0: the paper's local minima and terrain edge, every
//! cell at or below a valley-floor altitude, caller-given cells, or one map point.
//!
//! **Automaton.** A cell is *skiable* when it holds data and more than
//! [`SkiParams::min_snow_depth_m`] of snow. A skiable, non-terminus cell `c` may move to a
//! neighbour `n` of its 8-neighbourhood when `n` is skiable or a terminus and does not lie
//! higher, `A_n ≤ A_c` (`A` = bedrock + snow). The rule of the automaton is
//!
//! ```text
//! D(c) ← min( D(c), min over allowed n of D(n) + ℓ(c, n) )
//! ```
//!
//! with `ℓ` the horizontal distance between cell centres (m), starting from `D = 0` at termini
//! and `∞` elsewhere. Its fixed point is unique: `D(c)` is the length of the shortest
//! never-climbing snow-covered route from `c` to a terminus, `∞` where there is none (a
//! dead-end). We read the paper's "farthest down-slope end point" as this shortest route: with
//! flats and ties (`A_n = A_c`) routes can loop, and the shortest route is the quantity such a
//! relaxation converges to; far from every end point still means the start of a long run.
//!
//! The GPU applies the rule to all cells at once, one ring per iteration (hundreds of passes
//! on a 1024² grid). On the CPU the same rule is applied in place, sweeping the grid in the
//! four raster orders in turn (an asynchronous automaton, Gauss–Seidel style), until a sweep
//! changes nothing. Because the fixed point is unique and each value is the sum along its
//! route taken from the terminus outwards, the result is bit-identical to the synchronous
//! automaton ([`TerminusMap::compute_synchronous`], kept as the reference for tests) and does
//! not depend on the order.

use crate::frame::{SnowView, map_to_local};
use crate::{SkiError, SkiParams};
use serde::{Deserialize, Serialize};
use snowscape_terrain::LayeredTerrain;

/// Which cells end a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Terminus {
    /// The paper's end points: skiable cells with no lower skiable neighbour (local minima of
    /// the snow surface, snow-line ends included), and skiable cells on the terrain's edge
    /// (the grid border or next to nodata).
    LocalMinima,
    /// Every valid cell whose surface lies at or below this altitude, m (a valley floor).
    BelowAltitude(f64),
    /// The given cells (row-major indices).
    Cells(Vec<usize>),
    /// The cell holding this map point (CRS units).
    Point {
        /// Map x.
        x: f64,
        /// Map y.
        y: f64,
    },
}

/// Distance from every cell to a terminus, m, with the weights skiers spawn by.
#[derive(Debug, Clone, PartialEq)]
pub struct TerminusMap {
    width: usize,
    height: usize,
    distance: Vec<f32>,
    spawn_cdf: Vec<f64>,
    sweeps: usize,
    rule: Terminus,
}

/// The 8 neighbour offsets.
const N8: [(isize, isize); 8] = [
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

/// Per-cell inputs of the automaton.
struct Field {
    width: usize,
    height: usize,
    surface: Vec<f32>,
    /// Skiable or terminus: a cell a route may enter.
    enterable: Vec<bool>,
    /// Skiable and not a terminus: a cell whose distance the rule updates.
    updated: Vec<bool>,
    /// `ℓ` per neighbour offset, m.
    lengths: [f32; 8],
}

impl Field {
    /// One application of the rule at cell `i`: the relaxed distance, reading `d`.
    #[inline(always)]
    fn relaxed(&self, d: &[f32], col: usize, row: usize) -> f32 {
        let i = row * self.width + col;
        let a = self.surface[i];
        let mut best = d[i];
        if col > 0 && row > 0 && col + 1 < self.width && row + 1 < self.height {
            // Interior: no bounds tests.
            let w = self.width as isize;
            for (k, &(dc, dr)) in N8.iter().enumerate() {
                let j = (i as isize + dr * w + dc) as usize;
                if self.enterable[j] && self.surface[j] <= a {
                    let cand = d[j] + self.lengths[k];
                    if cand < best {
                        best = cand;
                    }
                }
            }
            return best;
        }
        for (k, &(dc, dr)) in N8.iter().enumerate() {
            let (c, r) = (col as isize + dc, row as isize + dr);
            if c < 0 || r < 0 || c as usize >= self.width || r as usize >= self.height {
                continue;
            }
            let j = r as usize * self.width + c as usize;
            if self.enterable[j] && self.surface[j] <= a {
                let cand = d[j] + self.lengths[k];
                if cand < best {
                    best = cand;
                }
            }
        }
        best
    }
}

fn terminus_cells(
    rule: &Terminus,
    view: &SnowView,
    surface: &[f32],
) -> Result<Vec<bool>, SkiError> {
    let (w, h) = (view.width, view.height);
    let n = w * h;
    let mut t = vec![false; n];
    match rule {
        Terminus::LocalMinima => {
            for (i, ti) in t.iter_mut().enumerate() {
                if !view.skiable(i) {
                    continue;
                }
                let (col, row) = (i % w, i / w);
                let mut edge = false;
                let mut lower = false;
                for &(dc, dr) in &N8 {
                    let (c, r) = (col as isize + dc, row as isize + dr);
                    if c < 0 || r < 0 || c as usize >= w || r as usize >= h {
                        edge = true;
                        continue;
                    }
                    let j = r as usize * w + c as usize;
                    if !view.mask.is_valid(j) {
                        edge = true;
                    } else if view.skiable(j) && surface[j] < surface[i] {
                        lower = true;
                    }
                }
                *ti = edge || !lower;
            }
        }
        Terminus::BelowAltitude(alt) => {
            if !alt.is_finite() {
                return Err(SkiError::InvalidParameter {
                    name: "terminus altitude",
                    value: *alt,
                    expected: "finite",
                });
            }
            for (i, ti) in t.iter_mut().enumerate() {
                *ti = view.mask.is_valid(i) && f64::from(surface[i]) <= *alt;
            }
        }
        Terminus::Cells(cells) => {
            for &i in cells {
                if i >= n {
                    return Err(SkiError::CellOutOfRange {
                        what: "terminus",
                        index: i,
                        cells: n,
                    });
                }
                if !view.mask.is_valid(i) {
                    return Err(SkiError::OnNodata {
                        what: "terminus",
                        col: i % w,
                        row: i / w,
                    });
                }
                t[i] = true;
            }
        }
        Terminus::Point { x, y } => {
            let (_, (col, row)) = map_to_local(view.terrain.geometry(), "terminus point", *x, *y)?;
            let i = row * w + col;
            if !view.mask.is_valid(i) {
                return Err(SkiError::OnNodata {
                    what: "terminus point",
                    col,
                    row,
                });
            }
            t[i] = true;
        }
    }
    if !t.iter().any(|&b| b) {
        return Err(SkiError::NoTerminus(format!("{rule:?} selects no cell")));
    }
    Ok(t)
}

/// The automaton's inputs and its starting distances (0 at termini, ∞ elsewhere).
fn prepare(
    params: &SkiParams,
    terrain: &LayeredTerrain,
    rule: &Terminus,
) -> Result<(Field, Vec<f32>), SkiError> {
    params.validate()?;
    let view = SnowView::new(terrain, params.min_snow_depth_m);
    let (w, h) = (view.width, view.height);
    let surface: Vec<f32> = (0..w * h).map(|i| view.surface(i)).collect();
    let term = terminus_cells(rule, &view, &surface)?;
    let skiable: Vec<bool> = (0..w * h).map(|i| view.skiable(i)).collect();
    let enterable = skiable.iter().zip(&term).map(|(&s, &t)| s || t).collect();
    let updated = skiable.iter().zip(&term).map(|(&s, &t)| s && !t).collect();
    let distance = term
        .iter()
        .map(|&t| if t { 0.0 } else { f32::INFINITY })
        .collect();
    let lengths = N8.map(|(dc, dr)| (dc as f64 * view.dx).hypot(dr as f64 * view.dy) as f32);
    Ok((
        Field {
            width: w,
            height: h,
            surface,
            enterable,
            updated,
            lengths,
        },
        distance,
    ))
}

impl TerminusMap {
    /// The distance map of `terrain` for the termini `rule`, by in-place sweeps of the
    /// automaton until a sweep changes nothing (see the module docs).
    pub fn compute(
        params: &SkiParams,
        terrain: &LayeredTerrain,
        rule: &Terminus,
    ) -> Result<Self, SkiError> {
        let (field, mut d) = prepare(params, terrain, rule)?;
        let (w, h) = (field.width, field.height);
        let mut sweeps = 0;
        loop {
            let (rev_rows, rev_cols) = (sweeps & 1 == 1, sweeps & 2 == 2);
            sweeps += 1;
            let mut changed = false;
            for rr in 0..h {
                let row = if rev_rows { h - 1 - rr } else { rr };
                for cc in 0..w {
                    let col = if rev_cols { w - 1 - cc } else { cc };
                    let i = row * w + col;
                    if !field.updated[i] {
                        continue;
                    }
                    let v = field.relaxed(&d, col, row);
                    if v < d[i] {
                        d[i] = v;
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        Ok(Self::from_distance(w, h, d, sweeps, rule.clone()))
    }

    /// The same map by the synchronous automaton (every cell updated from the previous
    /// iteration's values, as on the GPU), iterated until nothing changes. Slow (one ring per
    /// iteration); the reference the swept [`Self::compute`] is tested against.
    pub fn compute_synchronous(
        params: &SkiParams,
        terrain: &LayeredTerrain,
        rule: &Terminus,
    ) -> Result<Self, SkiError> {
        let (field, mut d) = prepare(params, terrain, rule)?;
        let (w, h) = (field.width, field.height);
        let mut next = d.clone();
        let mut iterations = 0;
        loop {
            iterations += 1;
            let mut changed = false;
            for row in 0..h {
                for col in 0..w {
                    let i = row * w + col;
                    next[i] = if field.updated[i] {
                        field.relaxed(&d, col, row)
                    } else {
                        d[i]
                    };
                    changed |= next[i] < d[i];
                }
            }
            std::mem::swap(&mut d, &mut next);
            if !changed {
                break;
            }
        }
        Ok(Self::from_distance(w, h, d, iterations, rule.clone()))
    }

    /// A map of `width`×`height` cells from its distances (the automaton's, or a
    /// checkpoint's). Spawn weight: the distance itself, on cells with a route (finite) that
    /// are not termini (0): a cell the automaton does not update keeps its start, 0 (a
    /// terminus) or +∞ (no snow), which add nothing, so one rule serves both.
    pub fn from_distance(
        width: usize,
        height: usize,
        distance: Vec<f32>,
        sweeps: usize,
        rule: Terminus,
    ) -> Self {
        let mut acc = 0.0f64;
        let spawn_cdf = distance
            .iter()
            .map(|&d| {
                if d.is_finite() {
                    acc += f64::from(d);
                }
                acc
            })
            .collect();
        Self {
            width,
            height,
            distance,
            spawn_cdf,
            sweeps,
            rule,
        }
    }

    /// Distance to the terminus per cell, m (`f32::INFINITY`: no route, a dead-end or a cell
    /// without snow).
    pub fn distance(&self) -> &[f32] {
        &self.distance
    }
    /// Distance of cell `i`, m.
    #[inline(always)]
    pub fn distance_at(&self, i: usize) -> f32 {
        self.distance[i]
    }
    /// Whether cell `i` is a terminus.
    #[inline(always)]
    pub fn is_terminus(&self, i: usize) -> bool {
        self.distance[i] == 0.0
    }
    /// Grid size `(width, height)` the map was computed on.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }
    /// Sweeps (or synchronous iterations) the automaton needed, the last one changing nothing.
    pub fn sweeps(&self) -> usize {
        self.sweeps
    }
    /// The termini rule the map was computed for.
    pub fn rule(&self) -> &Terminus {
        &self.rule
    }
    /// Sum of the spawn weights (the distances of skiable cells with a route), m.
    pub fn spawn_weight_total(&self) -> f64 {
        self.spawn_cdf.last().copied().unwrap_or(0.0)
    }
    /// The cell a uniform draw `u ∈ [0, 1)` selects with probability proportional to its
    /// distance to the terminus; `None` when no cell has a positive weight.
    pub fn spawn_cell(&self, u: f64) -> Option<usize> {
        let total = self.spawn_weight_total();
        if total <= 0.0 {
            return None;
        }
        let target = u.clamp(0.0, 1.0) * total;
        let i = self.spawn_cdf.partition_point(|&c| c <= target);
        if i < self.spawn_cdf.len() {
            Some(i)
        } else {
            // `u·total` rounded up to the total: the last cell with a positive weight.
            Some(self.spawn_cdf.partition_point(|&c| c < total))
        }
    }
}
