//! Plumbing shared by the Section 5 phenomena (melt, stability, powder diffusion, wind
//! transport): typed input errors, the nodata view that lets kernels compile a branch-free
//! interior for mask-free grids, and the surface-gradient row stencil.
//!
//! Kernels are written once over a [`Validity`] and instantiated twice: with [`AllValid`]
//! (every validity test folds to `true`, so interior loops carry no mask branch) and with
//! [`Masked`] (the terrain's per-cell nodata flags).

use snowscape_terrain::{GridGeometry, LayeredTerrain, NodataMask, operators, parallel, surface};
use thiserror::Error;

/// A bad input to a phenomenon step: a map of the wrong size, a parameter out of range or a
/// bad time step. Each variant carries the offending value.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PhenomenonError {
    /// A per-cell input map whose length does not match the terrain.
    #[error("{map} map has {actual} values but the {width}x{height} terrain needs {expected}")]
    MapLength {
        map: &'static str,
        width: usize,
        height: usize,
        expected: usize,
        actual: usize,
    },
    /// A parameter outside its valid range.
    #[error("invalid {phenomenon} parameter {name} = {value}: {reason}")]
    InvalidParameter {
        phenomenon: &'static str,
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// A parameter outside its documented range `[min, max]`.
    #[error("invalid {phenomenon} parameter {name} = {value}: must be within [{min}, {max}]{unit}")]
    OutOfRange {
        phenomenon: &'static str,
        name: &'static str,
        value: f64,
        min: f64,
        max: f64,
        /// The unit, with a leading space (or empty).
        unit: &'static str,
    },
    /// A time step that is negative, NaN or infinite.
    #[error("invalid time step {dt_days} days: it must be finite and non-negative")]
    InvalidTimeStep { dt_days: f64 },
    /// The physical wind transport (Jubert 2018) rejected a parameter or met a bad value.
    #[error("snowtran wind transport: {0}")]
    Transport(#[from] snowscape_transport::TransportError),
}

/// Checks that a per-cell map covers the grid.
pub(crate) fn check_map<T>(
    map: &'static str,
    values: &[T],
    geometry: &GridGeometry,
) -> Result<(), PhenomenonError> {
    if values.len() == geometry.len() {
        Ok(())
    } else {
        Err(PhenomenonError::MapLength {
            map,
            width: geometry.width(),
            height: geometry.height(),
            expected: geometry.len(),
            actual: values.len(),
        })
    }
}

/// Checks a time step.
pub(crate) fn check_dt(dt_days: f64) -> Result<(), PhenomenonError> {
    if dt_days.is_finite() && dt_days >= 0.0 {
        Ok(())
    } else {
        Err(PhenomenonError::InvalidTimeStep { dt_days })
    }
}

/// Checks that a parameter is finite and not below `min`.
pub(crate) fn check_at_least(
    phenomenon: &'static str,
    name: &'static str,
    value: f64,
    min: f64,
) -> Result<(), PhenomenonError> {
    if value.is_finite() && value >= min {
        Ok(())
    } else {
        Err(PhenomenonError::InvalidParameter {
            phenomenon,
            name,
            value,
            reason: if value.is_finite() {
                "below its minimum"
            } else {
                "not a finite number"
            },
        })
    }
}

/// Checks that a parameter is a finite number.
pub(crate) fn check_finite(
    phenomenon: &'static str,
    name: &'static str,
    value: f64,
) -> Result<(), PhenomenonError> {
    check_at_least(phenomenon, name, value, f64::MIN)
}

/// Checks that a parameter is a finite number within `[min, max]` (`unit` with a leading
/// space, for the message).
pub(crate) fn check_range(
    phenomenon: &'static str,
    name: &'static str,
    value: f64,
    [min, max]: [f64; 2],
    unit: &'static str,
) -> Result<(), PhenomenonError> {
    if value.is_finite() && value >= min && value <= max {
        Ok(())
    } else {
        Err(PhenomenonError::OutOfRange {
            phenomenon,
            name,
            value,
            min,
            max,
            unit,
        })
    }
}

/// Which cells hold data, as seen by a kernel.
pub(crate) trait Validity: Sync {
    /// Whether cell `i` holds data.
    fn at(&self, i: usize) -> bool;
    /// The validity of the cells `cells` of the grid, indexed from the window's first cell
    /// (a block of whole rows is a grid of its own).
    fn window(&self, cells: std::ops::Range<usize>) -> Self
    where
        Self: Sized;
}

/// Every cell holds data: the test folds away.
pub(crate) struct AllValid;

impl Validity for AllValid {
    #[inline(always)]
    fn at(&self, _i: usize) -> bool {
        true
    }
    fn window(&self, _cells: std::ops::Range<usize>) -> Self {
        AllValid
    }
}

/// Per-cell nodata flags (`true` = nodata).
pub(crate) struct Masked<'a>(pub &'a [bool]);

impl Validity for Masked<'_> {
    #[inline(always)]
    fn at(&self, i: usize) -> bool {
        !self.0[i]
    }
    fn window(&self, cells: std::ops::Range<usize>) -> Self {
        Masked(&self.0[cells])
    }
}

/// Runs `kernel` with the cheapest [`Validity`] for `mask`.
macro_rules! with_validity {
    ($mask:expr, |$v:ident| $body:expr) => {
        match $mask.invalid_cells() {
            None => {
                let $v = &$crate::phenomenon::AllValid;
                $body
            }
            Some(flags) => {
                let $v = &$crate::phenomenon::Masked(flags);
                $body
            }
        }
    };
}
pub(crate) use with_validity;

/// Writes the snow-surface altitude `A = B + C + S + U + P` of every cell into `out`
/// (row-parallel, reusing `out`'s allocation; the same sum, in the same order, as
/// [`LayeredTerrain::surface`]).
pub(crate) fn fill_surface(terrain: &LayeredTerrain, out: &mut Vec<f32>) {
    let w = terrain.geometry().width();
    out.resize(terrain.geometry().len(), 0.0);
    let [c, s, u, p] = &terrain.snow;
    parallel::for_each_row(
        w,
        (&mut out[..], &terrain.bedrock, c, s, u, p),
        |_, (a, b, c, s, u, p)| {
            for (k, a) in a.iter_mut().enumerate() {
                *a = b[k] + (c[k] + s[k] + u[k] + p[k]);
            }
        },
    );
}

/// Norm of the surface gradient `‖∇A‖` (tan of the slope) along one row, into `out`.
///
/// Central differences in the interior ([`operators::interior_difference`]: the stencil of
/// [`surface::gradient`] without per-cell clamping); border cells and cells next to nodata use [`surface::gradient`]'s
/// one-sided rule. Nodata cells get 0.
pub(crate) fn row_gradient_norm<V: Validity>(
    a: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    valid: &V,
    row: usize,
    out: &mut [f32],
) {
    row_gradient_norm_in(a, geometry, mask, valid, row, 0..geometry.width(), out);
}

/// [`row_gradient_norm`] of the columns `cols` of the row, into `out[..cols.len()]`.
pub(crate) fn row_gradient_norm_in<V: Validity>(
    a: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    valid: &V,
    row: usize,
    cols: std::ops::Range<usize>,
    out: &mut [f32],
) {
    let w = geometry.width();
    let h = geometry.height();
    let half_inv_dx = (0.5 / geometry.cell_size_x()) as f32;
    let half_inv_dy = (0.5 / geometry.cell_size_y()) as f32;
    let slow = |col: usize| -> f32 {
        let (gx, gy) = surface::gradient(a, geometry, mask, col, row);
        operators::slope_tangent(gx, gy)
    };
    let base = row * w;
    let first = cols.start;
    let out = &mut out[..cols.len()];
    let edge = |col: usize| if valid.at(base + col) { slow(col) } else { 0.0 };
    if row == 0 || row + 1 == h || w < 3 {
        for (k, o) in out.iter_mut().enumerate() {
            *o = edge(first + k);
        }
        return;
    }
    let up = &a[base - w..base];
    let mid = &a[base..base + w];
    let dn = &a[base + w..base + 2 * w];
    // The border columns in the range, then its interior columns.
    for col in [0, w - 1] {
        if cols.contains(&col) {
            out[col - first] = edge(col);
        }
    }
    let (lo, hi) = (cols.start.max(1), cols.end.min(w - 1));
    for col in lo..hi {
        let i = base + col;
        out[col - first] = if !valid.at(i) {
            0.0
        } else if valid.at(i - 1) && valid.at(i + 1) && valid.at(i - w) && valid.at(i + w) {
            let gx = operators::interior_difference(mid[col - 1], mid[col + 1], half_inv_dx);
            let gy = operators::interior_difference(dn[col], up[col], half_inv_dy);
            operators::slope_tangent(gx, gy)
        } else {
            slow(col)
        };
    }
}

/// Snow depths, and loads of snow in transit, below this are no snow, m. Melt, the snow state
/// changes and wind transport set what their transfers leave below it to 0: shares of shares
/// of such residues decay into subnormal floats, each operation on which costs a microcode
/// assist of a hundred cycles or more on Intel cores (a calm 1024² season on a 2-core Xeon VM:
/// wind transport 1.65 -> 1.38 s, melt and stability 1.49 -> 1.42 s). What the flush takes
/// is outside the volume budget and negligible: at most this depth per cell and step, about
/// 1e-9 m³ over a 100-day season on 1024² cells of 10 m, where the budget closes to 1e-5 of
/// ~1e8 m³.
pub const NEGLIGIBLE_DEPTH_M: f32 = 1e-20;

/// `x`, or 0 when it is below `floor` (branch-free: a select in vector loops).
#[inline(always)]
pub(crate) fn flush_below(x: f32, floor: f32) -> f32 {
    if x < floor { 0.0 } else { x }
}

/// A depth `d`, or 0 when it is below [`NEGLIGIBLE_DEPTH_M`].
#[inline(always)]
pub(crate) fn flush_negligible(d: f32) -> f32 {
    flush_below(d, NEGLIGIBLE_DEPTH_M)
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_terrain::{Grid, GridGeometry};

    #[test]
    fn row_gradient_matches_the_terrain_stencil_everywhere() {
        let geo = GridGeometry::new(7, 5, 2.0, 3.0).unwrap();
        let mut invalid = vec![false; geo.len()];
        invalid[geo.index(3, 2)] = true;
        let g = Grid::new(
            geo.clone(),
            (0..geo.len())
                .map(|i| ((i * 37) % 11) as f32 * 0.7)
                .collect(),
            NodataMask::from_invalid(invalid),
        )
        .unwrap();
        let mask = g.mask();
        for row in 0..geo.height() {
            let mut out = vec![0.0; geo.width()];
            with_validity!(mask, |v| row_gradient_norm(
                g.data(),
                &geo,
                mask,
                v,
                row,
                &mut out
            ));
            for (col, &o) in out.iter().enumerate() {
                let expect = if mask.is_valid(geo.index(col, row)) {
                    let (gx, gy) = surface::gradient(g.data(), &geo, mask, col, row);
                    (gx * gx + gy * gy).sqrt()
                } else {
                    0.0
                };
                assert!((o - expect).abs() < 1e-5, "({col},{row}) {o} vs {expect}");
            }
            // Any range of columns gives the bits of the whole row.
            for cols in [0..3, 2..7, 3..4, 0..7, 6..7] {
                let mut part = vec![-1.0; cols.len()];
                with_validity!(mask, |v| row_gradient_norm_in(
                    g.data(),
                    &geo,
                    mask,
                    v,
                    row,
                    cols.clone(),
                    &mut part
                ));
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&part), bits(&out[cols]));
            }
        }
    }

    #[test]
    fn fill_surface_matches_the_terrain() {
        let geo = GridGeometry::square(5, 3, 1.0).unwrap();
        let mut t = LayeredTerrain::from_bedrock(Grid::from_fn(geo, |c, r| (c * r) as f32));
        for (k, layer) in snowscape_terrain::SnowLayer::ALL.into_iter().enumerate() {
            t.layer_mut(layer)[k + 3] = 0.1 * (k + 1) as f32;
        }
        let mut out = vec![9.0; 2];
        fill_surface(&t, &mut out);
        assert_eq!(out, t.surface());
    }

    #[test]
    fn errors_carry_the_offending_values() {
        let geo = GridGeometry::square(4, 3, 1.0).unwrap();
        let e = check_map("temperature", &[0.0; 5], &geo).unwrap_err();
        assert_eq!(
            e.to_string(),
            "temperature map has 5 values but the 4x3 terrain needs 12"
        );
        assert!(check_dt(-1.0).is_err() && check_dt(f64::NAN).is_err());
        assert!(check_dt(0.0).is_ok());
        let e = check_at_least("melt", "k_melt", -0.5, 0.0).unwrap_err();
        assert!(e.to_string().contains("k_melt = -0.5"), "{e}");
    }
}
