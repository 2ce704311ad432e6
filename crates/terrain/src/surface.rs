//! Surface derivatives of a height field on its grid: gradient, slope and normals per cell,
//! the stencils of [`crate::operators`] read through the grid's nodata mask.
//!
//! Central differences `∂z/∂x ≈ (z[c+1] - z[c-1]) / 2dx` in the interior, one-sided at the
//! borders and next to nodata cells (a missing neighbour is replaced by the cell itself).
//! x points east, y points north (row 0 is north, so `∂z/∂y = (z[r-1] - z[r+1]) / 2dy`).

use crate::{GridGeometry, NodataMask, operators};
use rayon::prelude::*;

/// The height gradient `(∂z/∂x, ∂z/∂y)` at `(col, row)`, x east and y north
/// ([`operators::gradient`]: nodata neighbours and the border make it one-sided).
#[inline]
pub fn gradient(
    z: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    col: usize,
    row: usize,
) -> (f32, f32) {
    let at = |dc: isize, dr: isize| {
        geometry
            .neighbour(col, row, dc, dr)
            .filter(|&j| mask.is_valid(j))
            .map(|j| z[j])
    };
    operators::gradient(
        z[geometry.index(col, row)],
        at,
        geometry.cell_size_x() as f32,
        geometry.cell_size_y() as f32,
    )
}

/// Slope angle in radians at `(col, row)`.
#[inline]
pub fn slope(z: &[f32], geometry: &GridGeometry, mask: &NodataMask, col: usize, row: usize) -> f32 {
    let (gx, gy) = gradient(z, geometry, mask, col, row);
    operators::slope_angle(gx, gy)
}

/// Unit upward normal `(nx, ny, nz)` (x east, y north, z up) of every cell.
pub fn normals(z: &[f32], geometry: &GridGeometry, mask: &NodataMask) -> Vec<[f32; 3]> {
    let w = geometry.width();
    let mut out = vec![[0.0f32, 0.0, 1.0]; geometry.len()];
    out.par_chunks_mut(w).enumerate().for_each(|(row, line)| {
        for (col, n) in line.iter_mut().enumerate() {
            let (gx, gy) = gradient(z, geometry, mask, col, row);
            *n = operators::upward_normal(gx, gy);
        }
    });
    out
}

/// Slope angle in radians of every cell.
pub fn slopes(z: &[f32], geometry: &GridGeometry, mask: &NodataMask) -> Vec<f32> {
    let w = geometry.width();
    let mut out = vec![0.0f32; geometry.len()];
    out.par_chunks_mut(w).enumerate().for_each(|(row, line)| {
        for (col, s) in line.iter_mut().enumerate() {
            *s = slope(z, geometry, mask, col, row);
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Grid;

    #[test]
    fn plane_has_exact_gradient_and_normal() {
        // z rises 0.5 m per metre eastwards and 0.25 per metre northwards; 2 m x 4 m cells.
        let geo = GridGeometry::new(5, 4, 2.0, 4.0).unwrap();
        let g = Grid::from_fn(geo.clone(), |c, r| {
            let (x, y) = (c as f32 * 2.0, -(r as f32) * 4.0);
            0.5 * x + 0.25 * y
        });
        for (c, r) in [(0, 0), (2, 1), (4, 3)] {
            let (gx, gy) = gradient(g.data(), &geo, g.mask(), c, r);
            assert!(
                (gx - 0.5).abs() < 1e-5 && (gy - 0.25).abs() < 1e-5,
                "{gx} {gy}"
            );
        }
        let n = normals(g.data(), &geo, g.mask());
        let expect = [-0.5f32, -0.25, 1.0];
        let len = (expect.iter().map(|v| v * v).sum::<f32>()).sqrt();
        for k in 0..3 {
            assert!((n[7][k] - expect[k] / len).abs() < 1e-5);
        }
        let s = slope(g.data(), &geo, g.mask(), 2, 2);
        assert!((s - (0.3125f32).sqrt().atan()).abs() < 1e-5);
    }
}
