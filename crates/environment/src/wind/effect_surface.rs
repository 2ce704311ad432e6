//! The wind-effect surface `Wz` and its vertical speed `Wsz` (Cordonnier et al. 2018,
//! Section 4.2, Figure 7): the lowest altitude above which the wind blows at full strength.
//!
//! ```text
//! W·∇Wsz = −c        if Wz > A        (detached: the surface sinks along a parabola)
//! Wsz    = W·∇A      otherwise        (attached: it follows the ground)
//! W·∇Wz  = Wsz,      Wz >= A
//! ```
//!
//! Discretisation: first-order upwind differences along the transport wind `W = (Wx, Wy)`,
//! `W·∇f ≈ ax (f − f_x) + ay (f − f_y)` with `ax = |Wx|/dx`, `ay = |Wy|/dy` and `f_x`, `f_y` the
//! upwind neighbours. Solving each equation for the cell gives the local update
//! (`relax`), applied exactly as the paper orders it: `Wsz` first (as if detached), then `Wz`
//! from the new `Wsz`, then, if `Wz <= A`, the cell is attached: `Wz = A` and `Wsz = W·∇A`
//! (the same upwind differences of `A`, so a planar slope stays attached exactly).
//!
//! The caller chooses the transport wind; [`crate::wind`](mod@crate::wind) passes Eq. 2's wind projected on the
//! dominant direction, so every cell's upwind neighbours lie on the same side and the system
//! is triangular in wind order (see there for why).
//!
//! Solver: Gauss-Seidel. A sweep that visits rows and columns in wind order solves a
//! triangular upwind system exactly; `ordered_sweeps` such sweeps run first (cycling through
//! the four row/column orders, the fast-sweeping idea of Zhao 2005, "A fast sweeping method for
//! Eikonal equations", Math. Comp. 74, for transport winds that are not one-signed). They are
//! sequential. Then the paper's red-black (checkerboard) Gauss-Seidel iterates to the
//! tolerance: every neighbour of a red cell is black, so each half-step updates one colour in
//! parallel from the other, with a result independent of the thread count; the residual is the
//! largest change of `Wz` in an iteration (a maximum, exact in any order). With
//! `ordered_sweeps = 0` it starts from the paper's `Wz = A`, `Wsz = W·∇A` and converges in at
//! most as many iterations as the longest upwind chain of detached cells.
//!
//! Boundaries: a missing upwind neighbour (outside the grid, or nodata: nodata cells act as
//! border) drops its term, i.e. a zero derivative across the border; a cell with no upwind
//! neighbour left (the inflow corner) or no wind (`W = 0`, the paper's undefined case) is
//! attached (`Wz = A`, `Wsz = W·∇A`). Nodata cells get 0.

use rayon::prelude::*;

/// Per-cell coefficients of the update, fixed during the solve.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Cell {
    /// Altitude A, m.
    a: f32,
    /// `1/(ax + ay)`, s; 0 where the wind is calm.
    inv_sum: f32,
    /// `ax/(ax + ay)`.
    wx: f32,
    /// `ay/(ax + ay)`.
    wy: f32,
    /// `W·∇A` by upwind differences, m/s.
    ground: f32,
    /// Column step to the x-upwind neighbour (−1 west, +1 east, 0 none).
    up_x: i8,
    /// Row step to the y-upwind neighbour (−1 north, +1 south, 0 none).
    up_y: i8,
    /// Bit 0: valid cell; bit 1: x-upwind neighbour present; bit 2: y-upwind neighbour present.
    flags: u8,
}

const VALID: u8 = 1;
const HAS_X: u8 = 2;
const HAS_Y: u8 = 4;

/// Statistics of one solve.
#[derive(Debug, Clone, PartialEq)]
pub struct WindSolveStats {
    /// Ordered Gauss-Seidel sweeps run before the red-black iterations.
    pub ordered_sweeps: u32,
    /// Red-black iterations run.
    pub iterations: u32,
    /// Largest change of `Wz` (m) in each red-black iteration, in order.
    pub residual_history: Vec<f32>,
    /// Whether the last residual is below the tolerance.
    pub converged: bool,
}

/// The result of a solve, in the grid's layout (0 on nodata cells).
#[derive(Debug, Clone)]
pub(crate) struct EffectSurface {
    /// Wind-effect surface altitude `Wz`, m.
    pub wz: Vec<f32>,
    /// Its vertical speed `Wsz`, m/s.
    pub wsz: Vec<f32>,
    /// Solver statistics.
    pub stats: WindSolveStats,
}

/// The paper's local update of one cell from its upwind neighbours `(Wz, Wsz)`:
/// `Wsz = (−c + ax·Wsz_x + ay·Wsz_y)/(ax + ay)`, then `Wz = (Wsz + ax·Wz_x + ay·Wz_y)/(ax + ay)`,
/// then attach if `Wz <= A`. Returns `(Wz, Wsz)`.
#[inline(always)]
pub(crate) fn relax(cell: &Cell, nx: (f32, f32), ny: (f32, f32), c: f32) -> (f32, f32) {
    if cell.inv_sum == 0.0 {
        return (cell.a, cell.ground);
    }
    let s = -c * cell.inv_sum + cell.wx * nx.1 + cell.wy * ny.1;
    let z = s * cell.inv_sum + cell.wx * nx.0 + cell.wy * ny.0;
    if z <= cell.a {
        (cell.a, cell.ground)
    } else {
        (z, s)
    }
}

/// Builds the per-cell coefficients from altitudes (`-inf` on nodata), gradients and the
/// transport winds.
pub(crate) fn build_cells(
    z: &[f32],
    grad: &[[f32; 2]],
    wind: &[[f32; 2]],
    w: usize,
    h: usize,
    csx: f32,
    csy: f32,
) -> Vec<Cell> {
    let valid = |c: isize, r: isize| {
        c >= 0
            && r >= 0
            && (c as usize) < w
            && (r as usize) < h
            && z[r as usize * w + c as usize] != f32::NEG_INFINITY
    };
    let mut cells = vec![Cell::default(); w * h];
    cells.par_chunks_mut(w).enumerate().for_each(|(row, line)| {
        for (col, cell) in line.iter_mut().enumerate() {
            let i = row * w + col;
            if z[i] == f32::NEG_INFINITY {
                continue;
            }
            let a = z[i];
            let [we, wn] = wind[i];
            let (ax, ay) = (we.abs() / csx, wn.abs() / csy);
            let up_x: i8 = if we > 0.0 {
                -1
            } else if we < 0.0 {
                1
            } else {
                0
            };
            // Wind blowing north comes from the south, the next row.
            let up_y: i8 = if wn > 0.0 {
                1
            } else if wn < 0.0 {
                -1
            } else {
                0
            };
            let (cx, ry) = (col as isize + up_x as isize, row as isize + up_y as isize);
            let has_x = up_x != 0 && valid(cx, row as isize);
            let has_y = up_y != 0 && valid(col as isize, ry);
            // A missing upwind neighbour drops its term (zero derivative across the border).
            let (ex, ey) = (if has_x { ax } else { 0.0 }, if has_y { ay } else { 0.0 });
            let sum = ex + ey;
            *cell = if sum > 1e-6 * (ax + ay) && sum > 0.0 {
                let zx = if has_x { z[row * w + cx as usize] } else { a };
                let zy = if has_y { z[ry as usize * w + col] } else { a };
                Cell {
                    a,
                    inv_sum: 1.0 / sum,
                    wx: ex / sum,
                    wy: ey / sum,
                    ground: ex * (a - zx) + ey * (a - zy),
                    up_x,
                    up_y,
                    flags: VALID | if has_x { HAS_X } else { 0 } | if has_y { HAS_Y } else { 0 },
                }
            } else {
                // Calm, or inflow with no upwind neighbour: attached, Wsz = W·∇A.
                let [gx, gy] = grad[i];
                Cell {
                    a,
                    ground: we * gx + wn * gy,
                    flags: VALID,
                    ..Cell::default()
                }
            };
        }
    });
    cells
}

/// `(Wz, Wsz)` and coefficients split by checkerboard colour: cell `(x, y)` has colour
/// `(x + y) % 2` and index `y·hw + x/2` in its colour's arrays.
struct Checkerboard {
    w: usize,
    h: usize,
    hw: usize,
    z: [Vec<f32>; 2],
    s: [Vec<f32>; 2],
    cells: [Vec<Cell>; 2],
}

impl Checkerboard {
    fn new(cells: &[Cell], w: usize, h: usize) -> Self {
        let hw = w.div_ceil(2);
        let mut split: [Vec<Cell>; 2] =
            [vec![Cell::default(); hw * h], vec![Cell::default(); hw * h]];
        for y in 0..h {
            for x in 0..w {
                split[(x + y) & 1][y * hw + x / 2] = cells[y * w + x];
            }
        }
        // The paper's initial state: Wz = A, Wsz = W·∇A.
        let init = |f: fn(&Cell) -> f32| -> [Vec<f32>; 2] {
            [
                split[0].iter().map(f).collect(),
                split[1].iter().map(f).collect(),
            ]
        };
        let z = init(|c| if c.flags & VALID != 0 { c.a } else { 0.0 });
        let s = init(|c| if c.flags & VALID != 0 { c.ground } else { 0.0 });
        Self {
            w,
            h,
            hw,
            z,
            s,
            cells: split,
        }
    }

    /// Upwind neighbour values `(x-neighbour, y-neighbour)` of cell `(x, y)` read from the
    /// other colour's arrays.
    #[inline(always)]
    fn neighbours(
        cell: &Cell,
        x: usize,
        y: usize,
        hw: usize,
        z: &[f32],
        s: &[f32],
    ) -> ((f32, f32), (f32, f32)) {
        // A missing neighbour has weight 0: its value is never used.
        let nx = if cell.flags & HAS_X != 0 {
            let j = y * hw + (x as isize + cell.up_x as isize) as usize / 2;
            (z[j], s[j])
        } else {
            (0.0, 0.0)
        };
        let ny = if cell.flags & HAS_Y != 0 {
            let j = (y as isize + cell.up_y as isize) as usize * hw + x / 2;
            (z[j], s[j])
        } else {
            (0.0, 0.0)
        };
        (nx, ny)
    }

    /// One sequential Gauss-Seidel sweep, columns in `x_ascending` order and rows in
    /// `y_ascending` order.
    fn ordered_sweep(&mut self, x_ascending: bool, y_ascending: bool, c: f32) {
        let (w, h, hw) = (self.w, self.h, self.hw);
        for yy in 0..h {
            let y = if y_ascending { yy } else { h - 1 - yy };
            for xx in 0..w {
                let x = if x_ascending { xx } else { w - 1 - xx };
                let col = (x + y) & 1;
                let i = y * hw + x / 2;
                let cell = self.cells[col][i];
                if cell.flags & VALID == 0 {
                    continue;
                }
                let (nx, ny) =
                    Self::neighbours(&cell, x, y, hw, &self.z[1 - col], &self.s[1 - col]);
                let (z, s) = relax(&cell, nx, ny, c);
                self.z[col][i] = z;
                self.s[col][i] = s;
            }
        }
    }

    /// One parallel red-black half-step on `colour`; returns the largest change of `Wz`.
    fn half_step(&mut self, colour: usize, c: f32) -> f32 {
        let (w, hw) = (self.w, self.hw);
        let [z0, z1] = &mut self.z;
        let [s0, s1] = &mut self.s;
        let (own_z, other_z, own_s, other_s) = if colour == 0 {
            (z0, &*z1, s0, &*s1)
        } else {
            (z1, &*z0, s1, &*s0)
        };
        let cells = &self.cells[colour];
        own_z
            .par_chunks_mut(hw)
            .zip(own_s.par_chunks_mut(hw))
            .zip(cells.par_chunks(hw))
            .enumerate()
            .map(|(y, ((zr, sr), cr))| {
                let off = (colour + y) & 1;
                let mut change = 0.0f32;
                for (i, cell) in cr.iter().enumerate() {
                    let x = 2 * i + off;
                    if x >= w || cell.flags & VALID == 0 {
                        continue;
                    }
                    let (nx, ny) = Self::neighbours(cell, x, y, hw, other_z, other_s);
                    let (z, s) = relax(cell, nx, ny, c);
                    change = change.max((z - zr[i]).abs());
                    zr[i] = z;
                    sr[i] = s;
                }
                change
            })
            .reduce(|| 0.0, f32::max)
    }

    /// Back to the grid's layout.
    fn unsplit(&self, field: &[Vec<f32>; 2]) -> Vec<f32> {
        let (w, hw) = (self.w, self.hw);
        let mut out = vec![0.0f32; w * self.h];
        out.par_chunks_mut(w).enumerate().for_each(|(y, line)| {
            for (x, o) in line.iter_mut().enumerate() {
                *o = field[(x + y) & 1][y * hw + x / 2];
            }
        });
        out
    }
}

/// Solver settings.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SolveSettings {
    /// Vertical deceleration c, m/s².
    pub c: f32,
    /// Ordered sweeps before red-black.
    pub ordered_sweeps: u32,
    /// Most red-black iterations.
    pub max_iterations: u32,
    /// Stop when the largest change of Wz is below this, m.
    pub tolerance_m: f32,
    /// Dominant wind `[east, north]`, to order the first sweep.
    pub dominant: [f32; 2],
}

/// Solves for `Wz`, `Wsz` on a `w`×`h` grid of prepared cells.
pub(crate) fn solve(cells: &[Cell], w: usize, h: usize, settings: &SolveSettings) -> EffectSurface {
    let mut board = Checkerboard::new(cells, w, h);
    // Blowing east: west (low x) is upwind, so x ascends; blowing north: rows descend.
    let x_asc = settings.dominant[0] >= 0.0;
    let y_asc = settings.dominant[1] < 0.0;
    let orders = [
        (x_asc, y_asc),
        (x_asc, !y_asc),
        (!x_asc, y_asc),
        (!x_asc, !y_asc),
    ];
    for k in 0..settings.ordered_sweeps as usize {
        let (xa, ya) = orders[k % 4];
        board.ordered_sweep(xa, ya, settings.c);
    }
    let mut history = Vec::new();
    let mut converged = false;
    for _ in 0..settings.max_iterations {
        let red = board.half_step(0, settings.c);
        let black = board.half_step(1, settings.c);
        let residual = red.max(black);
        history.push(residual);
        if residual < settings.tolerance_m {
            converged = true;
            break;
        }
    }
    EffectSurface {
        wz: board.unsplit(&board.z),
        wsz: board.unsplit(&board.s),
        stats: WindSolveStats {
            ordered_sweeps: settings.ordered_sweeps,
            iterations: history.len() as u32,
            residual_history: history,
            converged,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cells_1d(z: &[f32], speed: f32, dx: f32) -> Vec<Cell> {
        let n = z.len();
        let grad: Vec<[f32; 2]> = (0..n)
            .map(|i| {
                let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
                [(z[b] - z[a]) / ((b - a) as f32 * dx), 0.0]
            })
            .collect();
        build_cells(z, &grad, &vec![[speed, 0.0]; n], n, 1, dx, dx)
    }

    #[test]
    fn a_step_down_makes_a_parabolic_cap() {
        // Plateau at 100 m, then a drop to 0 m; wind 10 m/s east, 1 m cells.
        let z: Vec<f32> = (0..400)
            .map(|i| if i < 100 { 100.0 } else { 0.0 })
            .collect();
        let cells = cells_1d(&z, 10.0, 1.0);
        let settings = SolveSettings {
            c: 0.7,
            ordered_sweeps: 1,
            max_iterations: 10,
            tolerance_m: 1e-4,
            dominant: [10.0, 0.0],
        };
        let out = solve(&cells, z.len(), 1, &settings);
        assert!(out.stats.converged && out.stats.iterations == 1);
        // Past the edge, Wsz falls by c·dx/|W| per metre and Wz follows it down: after s metres
        // Wz ≈ 100 − c s²/(2|W|²) (first-order upwind adds O(dx) terms).
        for s in [10usize, 50, 100] {
            let expect = 100.0 - 0.7 * (s * s) as f32 / 200.0;
            let got = out.wz[99 + s];
            assert!(
                (got - expect).abs() < 0.05 * (100.0 - expect) + 0.5,
                "s={s} {got} vs {expect}"
            );
        }
        // The cap lands at s = sqrt(2·100·|W|²/c) ≈ 169 m; beyond it the surface is attached.
        assert!(out.wz[99 + 150] > 1.0);
        assert_eq!(out.wz[99 + 200], 0.0);
        // Upwind of the edge the surface hugs the plateau.
        assert!(out.wz[..100].iter().all(|&v| v == 100.0));
    }

    #[test]
    fn red_black_alone_reaches_the_ordered_solution() {
        let z: Vec<f32> = (0..120)
            .map(|i| 50.0 - (i as f32 - 40.0).abs().min(30.0))
            .collect();
        let cells = cells_1d(&z, 10.0, 2.0);
        let base = SolveSettings {
            c: 0.7,
            ordered_sweeps: 1,
            max_iterations: 500,
            tolerance_m: 1e-5,
            dominant: [10.0, 0.0],
        };
        let ordered = solve(&cells, z.len(), 1, &base);
        let rb = solve(
            &cells,
            z.len(),
            1,
            &SolveSettings {
                ordered_sweeps: 0,
                ..base
            },
        );
        assert!(rb.stats.converged, "{:?}", rb.stats.residual_history);
        assert!(rb.stats.iterations > 5);
        for (a, b) in ordered.wz.iter().zip(&rb.wz) {
            assert!((a - b).abs() < 1e-3, "{a} {b}");
        }
    }
}
