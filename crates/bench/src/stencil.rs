//! The roofline reference kernel: one pass of the 5-point Laplacian over an f32 grid.
//!
//! `out = left + right + up + down - 4·centre`. The interior runs without any per-cell index
//! clamping or branch (row slices zipped together, which the compiler vectorises); the four
//! borders are done separately with clamp-to-edge neighbours (`docs/src/architecture.md#performance-and-benchmarks`). It reads 4 and writes 4 bytes per cell: any simple stencil kernel of the
//! simulation should come close to its throughput.

use rayon::prelude::*;

/// The Laplacian at `(col, row)` with clamp-to-edge neighbours (used on the borders).
#[inline]
fn clamped(src: &[f32], width: usize, height: usize, col: usize, row: usize) -> f32 {
    let at = |c: usize, r: usize| src[r * width + c];
    let left = at(col.saturating_sub(1), row);
    let right = at((col + 1).min(width - 1), row);
    let up = at(col, row.saturating_sub(1));
    let down = at(col, (row + 1).min(height - 1));
    left + right + up + down - 4.0 * at(col, row)
}

/// The interior of one row: columns 1..width-1 of `out` from the rows above, at and below.
#[inline]
fn interior_row(up: &[f32], mid: &[f32], down: &[f32], out: &mut [f32]) {
    let n = mid.len();
    let neighbours = mid[..n - 2]
        .iter()
        .zip(&mid[2..])
        .zip(&up[1..n - 1])
        .zip(&down[1..n - 1]);
    for ((o, &c), (((&l, &r), &u), &d)) in
        out[1..n - 1].iter_mut().zip(&mid[1..n - 1]).zip(neighbours)
    {
        *o = l + r + u + d - 4.0 * c;
    }
}

/// One Laplacian pass of the `width` x `height` grid `src` into `out` (same length).
/// Grids narrower or shorter than 3 cells are done entirely with clamped neighbours.
pub fn laplacian(src: &[f32], out: &mut [f32], width: usize, height: usize) {
    debug_assert_eq!(src.len(), width * height);
    debug_assert_eq!(out.len(), width * height);
    if width < 3 || height < 3 {
        for (i, o) in out.iter_mut().enumerate() {
            *o = clamped(src, width, height, i % width, i / width);
        }
        return;
    }
    out.par_chunks_mut(width)
        .enumerate()
        .for_each(|(row, line)| {
            if row == 0 || row == height - 1 {
                for (col, o) in line.iter_mut().enumerate() {
                    *o = clamped(src, width, height, col, row);
                }
                return;
            }
            let up = &src[(row - 1) * width..row * width];
            let mid = &src[row * width..(row + 1) * width];
            let down = &src[(row + 1) * width..(row + 2) * width];
            interior_row(up, mid, down, line);
            line[0] = clamped(src, width, height, 0, row);
            line[width - 1] = clamped(src, width, height, width - 1, row);
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_clamped_definition_everywhere() {
        for (w, h) in [(7, 5), (3, 3), (2, 6), (16, 1)] {
            let src: Vec<f32> = (0..w * h).map(|i| ((i * 37) % 11) as f32 * 0.5).collect();
            let mut out = vec![f32::NAN; w * h];
            laplacian(&src, &mut out, w, h);
            for r in 0..h {
                for c in 0..w {
                    assert_eq!(
                        out[r * w + c],
                        clamped(&src, w, h, c, r),
                        "({c}, {r}) of {w}x{h}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_paraboloid_has_constant_laplacian_inside() {
        let (w, h) = (9, 8);
        let src: Vec<f32> = (0..w * h)
            .map(|i| ((i % w) * (i % w) + (i / w) * (i / w)) as f32)
            .collect();
        let mut out = vec![0.0; w * h];
        laplacian(&src, &mut out, w, h);
        for r in 1..h - 1 {
            for c in 1..w - 1 {
                assert_eq!(out[r * w + c], 4.0);
            }
        }
    }
}
