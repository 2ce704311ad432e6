//! The validated input surface in the two memory layouts the directional sweeps use.
//!
//! A sweep along a direction walks lines of cells whose main axis is the grid axis closest to
//! that direction. Lines along rows read memory contiguously; lines along columns would not, so
//! the surface, its gradient and its normals are also kept transposed (columns as rows) and the
//! sweeps whose main axis is north-south run on that copy.
//!
//! Nodata cells get the height `-inf` here: the lowest possible terrain, so they never occlude
//! the sky or the sun (they are transparent), and every kernel skips them; their outputs are 0.

use crate::EnvironmentError;
use rayon::prelude::*;
use snowscape_terrain::{GridGeometry, NodataMask, surface};

/// One memory layout of the surface: row-major with `w` cells per row.
#[derive(Debug, Clone)]
pub(crate) struct Layout {
    /// Cells per row of this layout.
    pub w: usize,
    /// Rows of this layout.
    pub h: usize,
    /// Surface height, metres; `-inf` on nodata cells.
    pub z: Vec<f32>,
    /// Height gradient `(∂z/∂x east, ∂z/∂y north)`, dimensionless; 0 on nodata cells.
    pub grad: Vec<[f32; 2]>,
    /// Unit upward normal (east, north, up); zero on nodata cells (so they receive no light).
    pub normal: Vec<[f32; 3]>,
}

/// The surface with its geometry, in the grid's layout and transposed.
#[derive(Debug, Clone)]
pub(crate) struct TerrainField {
    /// Columns of the grid.
    pub width: usize,
    /// Rows of the grid.
    pub height: usize,
    /// Cell size west-east, metres.
    pub csx: f64,
    /// Cell size north-south, metres.
    pub csy: f64,
    /// The grid's own layout (row 0 north).
    pub rows: Layout,
    /// The transposed layout (row `c` holds grid column `c`, north first).
    pub cols: Layout,
}

/// Checks the input lengths and that every valid cell is finite.
pub(crate) fn validate(
    surface: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
) -> Result<(), EnvironmentError> {
    let (w, h) = (geometry.width(), geometry.height());
    let mismatch = |what, actual| EnvironmentError::LengthMismatch {
        what,
        width: w,
        height: h,
        expected: geometry.len(),
        actual,
    };
    if surface.len() != geometry.len() {
        return Err(mismatch("surface", surface.len()));
    }
    if let Some(inv) = mask.invalid_cells()
        && inv.len() != geometry.len()
    {
        return Err(mismatch("nodata mask", inv.len()));
    }
    if let Some(i) = (0..surface.len()).find(|&i| mask.is_valid(i) && !surface[i].is_finite()) {
        let (col, row) = geometry.col_row(i);
        return Err(EnvironmentError::NonFiniteHeight {
            col,
            row,
            value: surface[i],
        });
    }
    Ok(())
}

/// `src` (`h` rows of `w`) transposed into `w` rows of `h`, in parallel tiles.
pub(crate) fn transpose<T: Copy + Send + Sync + Default>(src: &[T], w: usize, h: usize) -> Vec<T> {
    const TILE: usize = 32;
    let mut dst = vec![T::default(); src.len()];
    dst.par_chunks_mut(TILE * h)
        .enumerate()
        .for_each(|(tile, block)| {
            let c0 = tile * TILE;
            let cols = block.len() / h;
            for r in 0..h {
                let line = &src[r * w + c0..r * w + c0 + cols];
                for (dc, &v) in line.iter().enumerate() {
                    block[dc * h + r] = v;
                }
            }
        });
    dst
}

impl TerrainField {
    /// Validates the input and builds both layouts (gradient by central differences,
    /// `snowscape_terrain::surface::gradient`).
    pub fn new(
        surface: &[f32],
        geometry: &GridGeometry,
        mask: &NodataMask,
    ) -> Result<Self, EnvironmentError> {
        validate(surface, geometry, mask)?;
        let (w, h) = (geometry.width(), geometry.height());
        let mut z = vec![0.0f32; w * h];
        let mut grad = vec![[0.0f32; 2]; w * h];
        let mut normal = vec![[0.0f32; 3]; w * h];
        z.par_chunks_mut(w)
            .zip(grad.par_chunks_mut(w))
            .zip(normal.par_chunks_mut(w))
            .enumerate()
            .for_each(|(row, ((zr, gr), nr))| {
                for col in 0..w {
                    let i = row * w + col;
                    if !mask.is_valid(i) {
                        zr[col] = f32::NEG_INFINITY;
                        continue;
                    }
                    zr[col] = surface[i];
                    let (gx, gy) = surface::gradient(surface, geometry, mask, col, row);
                    gr[col] = [gx, gy];
                    let inv = 1.0 / (gx * gx + gy * gy + 1.0).sqrt();
                    nr[col] = [-gx * inv, -gy * inv, inv];
                }
            });
        let cols = Layout {
            w: h,
            h: w,
            z: transpose(&z, w, h),
            grad: transpose(&grad, w, h),
            normal: transpose(&normal, w, h),
        };
        let rows = Layout {
            w,
            h,
            z,
            grad,
            normal,
        };
        Ok(Self {
            width: w,
            height: h,
            csx: geometry.cell_size_x(),
            csy: geometry.cell_size_y(),
            rows,
            cols,
        })
    }

    /// The layout with the given orientation.
    pub fn layout(&self, transposed: bool) -> &Layout {
        if transposed { &self.cols } else { &self.rows }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.width * self.height
    }

    /// Adds a map accumulated in the transposed layout to one in the grid's layout, with
    /// `add(grid-layout value, transposed-layout value)`.
    pub fn add_transposed<T, F>(&self, acc_rows: &mut [T], acc_cols: &[T], add: F)
    where
        T: Copy + Send + Sync + Default,
        F: Fn(&mut T, T) + Sync + Send,
    {
        let back = transpose(acc_cols, self.height, self.width);
        acc_rows
            .par_iter_mut()
            .zip(back.par_iter())
            .for_each(|(a, b)| add(a, *b));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transpose_round_trips() {
        let (w, h) = (37, 70);
        let v: Vec<f32> = (0..w * h).map(|i| i as f32).collect();
        let t = transpose(&v, w, h);
        assert_eq!(t[3 * h + 5], v[5 * w + 3]);
        assert_eq!(transpose(&t, h, w), v);
    }

    #[test]
    fn nodata_is_lowest_terrain_and_nan_is_rejected() {
        let g = GridGeometry::square(3, 2, 1.0).unwrap();
        let mask = NodataMask::from_invalid(vec![false, true, false, false, false, false]);
        let f = TerrainField::new(&[1.0, f32::NAN, 2.0, 3.0, 4.0, 5.0], &g, &mask).unwrap();
        assert_eq!(f.rows.z[1], f32::NEG_INFINITY);
        assert_eq!(f.cols.z[2], f32::NEG_INFINITY);
        assert!(f.rows.grad.iter().flatten().all(|v| v.is_finite()));
        let e = TerrainField::new(
            &[1.0, f32::NAN, 2.0, 3.0, 4.0, 5.0],
            &g,
            &NodataMask::all_valid(),
        )
        .unwrap_err();
        assert!(matches!(
            e,
            EnvironmentError::NonFiniteHeight { col: 1, row: 0, .. }
        ));
    }
}
