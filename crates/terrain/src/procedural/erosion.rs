//! Fluvial erosion on a coarse grid: the drainage network that makes terrain look like mountains.
//!
//! The stream-power law with uplift and hillslope diffusion,
//! `∂h/∂t = U - K·A^m·S + D·∇²h` (A: drainage area, S: slope along the flow). Incision uses the
//! implicit O(n) scheme of Braun & Willett (2013, Geomorphology 180-181, "A very efficient
//! O(n), implicit and parallel method to solve the stream power equation"): steepest-descent
//! receivers (D8), a stack ordering from the outlets upwards, drainage area accumulated down
//! the stack, then each node updated after its receiver. Diffusion is an explicit 5-point step
//! (stable for `D ≤ 0.25`); it rounds divides and sets the spacing of valleys, which would
//! otherwise form at every cell. Grid-edge nodes are fixed outlets; interior pits rise with the
//! uplift until they spill.
//!
//! All quantities are dimensionless: cell size 1, uplift share ≤ 1 per step; the caller
//! rescales heights. Every pass runs in a fixed order, so the result is exactly reproducible.

use crate::random::{hash3, uniform};
use rayon::prelude::*;

/// Parameters of the dimensionless stream-power erosion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StreamPower {
    /// Number of time steps (each uplifts by at most 1).
    pub iterations: usize,
    /// Erodibility K per step (drainage area in cells).
    pub erodibility: f64,
    /// Drainage-area exponent m (the slope exponent n is 1); 0.4..0.5 in nature.
    pub area_exponent: f64,
    /// Hillslope diffusivity D, cells² per step (≤ 0.25 for stability).
    pub diffusivity: f64,
}

/// The random stream of the stochastic flow directions.
const FLOW_STREAM: u64 = 0x666c_6f77;

/// Offsets and lengths (in cells) of the 8 neighbours.
const NEIGHBOURS: [(isize, isize, f64); 8] = [
    (-1, -1, std::f64::consts::SQRT_2),
    (0, -1, 1.0),
    (1, -1, std::f64::consts::SQRT_2),
    (-1, 0, 1.0),
    (1, 0, 1.0),
    (-1, 1, std::f64::consts::SQRT_2),
    (0, 1, 1.0),
    (1, 1, std::f64::consts::SQRT_2),
];

/// Whether `(col, row)` lies on the edge of a `side`² grid.
#[inline(always)]
fn on_edge(col: usize, row: usize, side: usize) -> bool {
    col == 0 || row == 0 || col + 1 == side || row + 1 == side
}

/// The receiver of every node and the distance to it in cells, drawn among the lower
/// neighbours with probability proportional to the slope towards each (a stochastic multiple-
/// flow-direction rule: over many steps flow spreads like a multiple-flow model and channels
/// meander instead of following the grid axes). `draw(node)` is a uniform number in [0, 1).
/// A node that is on the edge or has no lower neighbour is its own receiver.
fn receivers(h: &[f64], side: usize, draw: impl Fn(usize) -> f64 + Sync) -> (Vec<u32>, Vec<f64>) {
    let mut rec: Vec<u32> = (0..h.len() as u32).collect();
    let mut dist = vec![1.0; h.len()];
    rec.par_chunks_mut(side)
        .zip(dist.par_chunks_mut(side))
        .enumerate()
        .filter(|(row, _)| *row > 0 && *row + 1 < side)
        .for_each(|(row, (rec_row, dist_row))| {
            for col in 1..side - 1 {
                if let Some((j, len)) = draw_receiver(h, side, col, row, draw(row * side + col)) {
                    rec_row[col] = j as u32;
                    dist_row[col] = len;
                }
            }
        });
    (rec, dist)
}

/// The receiver (index, distance in cells) of interior node `(col, row)` for the uniform
/// number `u`, or `None` when no neighbour is lower.
#[inline]
fn draw_receiver(h: &[f64], side: usize, col: usize, row: usize, u: f64) -> Option<(usize, f64)> {
    let i = row * side + col;
    let neighbour =
        |dc: isize, dr: isize| (row as isize + dr) as usize * side + (col as isize + dc) as usize;
    let mut slopes = [0.0f64; 8];
    let mut total = 0.0;
    for (k, &(dc, dr, len)) in NEIGHBOURS.iter().enumerate() {
        slopes[k] = ((h[i] - h[neighbour(dc, dr)]) / len).max(0.0);
        total += slopes[k];
    }
    if total <= 0.0 {
        return None;
    }
    let mut pick = u * total;
    let mut chosen = None;
    for (k, &(dc, dr, len)) in NEIGHBOURS.iter().enumerate() {
        if slopes[k] <= 0.0 {
            continue;
        }
        chosen = Some((neighbour(dc, dr), len));
        pick -= slopes[k];
        if pick < 0.0 {
            break;
        }
    }
    chosen
}

/// Nodes ordered so that every node comes after its receiver (outlets and pits first).
fn stack_order(rec: &[u32]) -> Vec<u32> {
    let n = rec.len();
    let mut first_donor = vec![0u32; n + 1];
    for (i, &r) in rec.iter().enumerate() {
        if r as usize != i {
            first_donor[r as usize + 1] += 1;
        }
    }
    for i in 0..n {
        first_donor[i + 1] += first_donor[i];
    }
    let mut fill = first_donor.clone();
    let mut donors = vec![0u32; first_donor[n] as usize];
    for (i, &r) in rec.iter().enumerate() {
        if r as usize != i {
            donors[fill[r as usize] as usize] = i as u32;
            fill[r as usize] += 1;
        }
    }
    let mut stack = Vec::with_capacity(n);
    let mut pending = Vec::new();
    for (base, &r) in rec.iter().enumerate() {
        if r as usize != base {
            continue;
        }
        pending.push(base as u32);
        while let Some(node) = pending.pop() {
            stack.push(node);
            let (a, b) = (first_donor[node as usize], first_donor[node as usize + 1]);
            pending.extend_from_slice(&donors[a as usize..b as usize]);
        }
    }
    stack
}

/// Drainage area (cells) of every node: itself plus everything upstream.
fn drainage_area(stack: &[u32], rec: &[u32]) -> Vec<f64> {
    let mut area = vec![1.0; rec.len()];
    for &node in stack.iter().rev() {
        let (i, r) = (node as usize, rec[node as usize] as usize);
        if r != i {
            area[r] += area[i];
        }
    }
    area
}

/// One explicit diffusion step of the interior of `h` into `out`; edges and nodes with a zero
/// uplift share (base levels) are copied unchanged.
fn diffuse(h: &[f64], uplift: &[f64], out: &mut [f64], side: usize, diffusivity: f64) {
    out.par_chunks_mut(side)
        .enumerate()
        .for_each(|(row, line)| {
            let start = row * side;
            line.copy_from_slice(&h[start..start + side]);
            if row == 0 || row + 1 == side {
                return;
            }
            for (col, out) in line.iter_mut().enumerate().take(side - 1).skip(1) {
                let i = start + col;
                if uplift[i] > 0.0 {
                    let laplacian = h[i - 1] + h[i + 1] + h[i - side] + h[i + side] - 4.0 * h[i];
                    *out = h[i] + diffusivity * laplacian;
                }
            }
        });
}

/// Runs `params.iterations` steps of uplift, implicit stream-power incision and hillslope
/// diffusion on the `side`² height field `h`, with per-node uplift share `uplift` (0..=1).
/// Nodes with a zero uplift share, like the grid edges, are fixed base levels (outlets).
/// `seed` keys the stochastic choice of flow directions.
pub fn erode(h: &mut [f64], uplift: &[f64], side: usize, params: &StreamPower, seed: u64) {
    let diffusivity = params.diffusivity.clamp(0.0, 0.25);
    let mut scratch = vec![0.0; h.len()];
    // Drainage areas are whole cell counts: their powers are looked up, not recomputed.
    let area_power: Vec<f64> = (0..=h.len())
        .map(|a| (a as f64).powf(params.area_exponent))
        .collect();
    for step in 0..params.iterations {
        let key = hash3(seed, FLOW_STREAM, step as u64);
        let (rec, dist) = receivers(h, side, |node| uniform(key, 0, node as u64));
        let stack = stack_order(&rec);
        let area = drainage_area(&stack, &rec);
        for &node in &stack {
            let i = node as usize;
            if on_edge(i % side, i / side, side) || uplift[i] <= 0.0 {
                continue;
            }
            let r = rec[i] as usize;
            let raised = h[i] + uplift[i];
            h[i] = if r == i {
                raised
            } else {
                let f = params.erodibility * area_power[area[i] as usize] / dist[i];
                (raised + f * h[r]) / (1.0 + f)
            };
        }
        diffuse(h, uplift, &mut scratch, side, diffusivity);
        h.copy_from_slice(&scratch);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stack_puts_receivers_first_and_area_sums_upstream() {
        // A 1D chain 3 -> 2 -> 1 -> 0 (0 is its own receiver) plus 4 -> 1.
        let rec = vec![0u32, 0, 1, 2, 1];
        let stack = stack_order(&rec);
        assert_eq!(stack.len(), 5);
        let pos = |n: u32| stack.iter().position(|&s| s == n).unwrap();
        for (i, &r) in rec.iter().enumerate() {
            assert!(pos(r) <= pos(i as u32));
        }
        assert_eq!(drainage_area(&stack, &rec), vec![5.0, 4.0, 2.0, 1.0, 1.0]);
    }

    #[test]
    fn uplift_builds_relief_that_drains_to_the_edges() {
        let side = 32;
        let mut h = vec![0.0; side * side];
        let uplift = vec![1.0; side * side];
        let params = StreamPower {
            iterations: 200,
            erodibility: 0.2,
            area_exponent: 0.45,
            diffusivity: 0.1,
        };
        for (i, v) in h.iter_mut().enumerate() {
            let (col, row) = (i % side, i / side);
            if !on_edge(col, row, side) {
                *v = crate::random::uniform(1, 2, i as u64);
            }
        }
        erode(&mut h, &uplift, side, &params, 1);
        let max = h.iter().cloned().fold(0.0, f64::max);
        assert!(max > 5.0, "no relief: {max}");
        // After erosion every interior node drains to an edge: no pits remain.
        let (rec, _) = receivers(&h, side, |_| 0.5);
        for row in 1..side - 1 {
            for col in 1..side - 1 {
                let i = row * side + col;
                assert_ne!(rec[i] as usize, i, "pit at ({col}, {row})");
            }
        }
        // The edges stay at base level.
        assert!((0..side).all(|c| h[c] == 0.0 && h[(side - 1) * side + c] == 0.0));
    }
}
