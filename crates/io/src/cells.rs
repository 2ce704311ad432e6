//! Turning decoded samples into a [`Grid`]: the one place where the nodata rule is enforced.
//!
//! The rule, the same for every reader:
//! - a value equal to the file's declared nodata value (ESRI ASCII `NODATA_value`, GeoTIFF
//!   `GDAL_NODATA`, the PNG16/RAW16 sidecar's `nodata` code) is nodata;
//! - NaN is nodata only in binary float files that cannot or did not declare a nodata value
//!   (NPY, EXR, float GeoTIFF without `GDAL_NODATA`): NumPy and GDAL use NaN that way. In a text
//!   grid or a file that declares a nodata value (unless the declared value is NaN) a NaN is a
//!   mistake and an error naming the cell;
//! - an infinite value, or a finite value beyond the f32 range, is always an error.

use crate::error::{RasterError, Result, geometry_err};
use snowscape_terrain::{Grid, GridGeometry, NodataMask};
use std::path::Path;

/// Which values of a file mean "no data".
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct NodataRule {
    /// The declared nodata value, if the file declares one.
    pub declared: Option<f64>,
    /// Whether NaN means nodata (see the module docs).
    pub nan_is_nodata: bool,
}

impl NodataRule {
    /// A file with a declared nodata value (or none, for a text format): NaN is an error
    /// unless the declared value is itself NaN.
    pub fn declared(value: Option<f64>) -> Self {
        Self {
            declared: value,
            nan_is_nodata: value.is_some_and(f64::is_nan),
        }
    }
    /// A binary float file without a nodata declaration: NaN is nodata.
    pub fn nan() -> Self {
        Self {
            declared: None,
            nan_is_nodata: true,
        }
    }
    /// A binary file whose declared value (if any) is the only nodata; for an integer file
    /// NaN cannot occur.
    pub fn for_binary(declared: Option<f64>) -> Self {
        match declared {
            Some(v) => Self::declared(Some(v)),
            None => Self::nan(),
        }
    }
}

/// Collects cells row by row (row 0 north), classifying each as data or nodata.
pub(crate) struct CellSink<'p> {
    path: &'p Path,
    width: usize,
    /// Column and row of the file the first cell lies in (a window or a chunk of the file),
    /// for error messages.
    first_col: usize,
    first_row: usize,
    rule: NodataRule,
    declared_f32: Option<f32>,
    data: Vec<f32>,
    invalid: Vec<bool>,
}

impl<'p> CellSink<'p> {
    /// A sink for `width * height` cells. The caller has checked the cell count already.
    pub fn new(path: &'p Path, width: usize, height: usize, rule: NodataRule) -> Self {
        Self::with_capacity(path, width, width.saturating_mul(height), rule)
    }

    /// A sink for rows of `width` cells that reserves room for `n` cells up front (it grows
    /// as cells arrive), for readers whose header may promise more than the file holds.
    pub fn with_capacity(path: &'p Path, width: usize, n: usize, rule: NodataRule) -> Self {
        Self {
            path,
            width: width.max(1),
            first_col: 0,
            first_row: 0,
            rule,
            declared_f32: rule.declared.map(|v| v as f32),
            data: Vec::with_capacity(n),
            invalid: Vec::with_capacity(n),
        }
    }

    /// The same sink for a window of the file whose first cell is at `(col, row)`.
    pub fn starting_at(mut self, col: usize, row: usize) -> Self {
        (self.first_col, self.first_row) = (col, row);
        self
    }

    /// Adds a cell already classified as data, finite (a chunk's cell moved into a window).
    pub fn push_data(&mut self, v: f32) {
        debug_assert!(v.is_finite());
        self.data.push(v);
        self.invalid.push(false);
    }

    /// Whether `v` is nodata under the file's rule (the declared value, or NaN where NaN
    /// means nodata).
    pub fn is_nodata(&self, v: f64) -> bool {
        self.rule.declared.is_some_and(|d| d == v) || (v.is_nan() && self.rule.nan_is_nodata)
    }

    /// Number of cells pushed so far.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// Adds a nodata cell (for formats that flag nodata by a code, not a value).
    pub fn push_nodata(&mut self) {
        self.data.push(0.0);
        self.invalid.push(true);
    }

    fn push_valid(&mut self, raw: f64, v: f32) -> Result<()> {
        if v.is_finite() {
            self.data.push(v);
            self.invalid.push(false);
            Ok(())
        } else {
            let i = self.data.len();
            Err(RasterError::NonFinite {
                path: self.path.to_path_buf(),
                col: self.first_col + i % self.width,
                row: self.first_row + i / self.width,
                value: raw,
            })
        }
    }

    /// Adds a value decoded as f64 (text, f64 or integer samples).
    #[inline]
    pub fn push_f64(&mut self, v: f64) -> Result<()> {
        if self.is_nodata(v) {
            self.push_nodata();
            Ok(())
        } else {
            self.push_valid(v, v as f32)
        }
    }

    /// Adds an f32 sample; the declared nodata value is compared in f32 precision.
    #[inline]
    pub fn push_f32(&mut self, v: f32) -> Result<()> {
        if self.declared_f32.is_some_and(|d| d == v) || (v.is_nan() && self.rule.nan_is_nodata) {
            self.push_nodata();
            Ok(())
        } else {
            self.push_valid(v as f64, v)
        }
    }

    /// The cells pushed: values (0 where nodata) and which are nodata.
    pub fn into_parts(self) -> (Vec<f32>, Vec<bool>) {
        (self.data, self.invalid)
    }

    /// The grid over `geometry`; the caller has pushed exactly `geometry.len()` cells.
    pub fn finish(self, geometry: GridGeometry) -> Result<Grid> {
        Grid::new(geometry, self.data, NodataMask::from_invalid(self.invalid))
            .map_err(geometry_err(self.path))
    }
}

/// Fails with [`RasterError::TooManyCells`] when `width x height` exceeds `max` (or overflows),
/// before anything is allocated. Returns the cell count.
pub(crate) fn check_cells(path: &Path, width: u64, height: u64, max: usize) -> Result<usize> {
    let too_many = || RasterError::TooManyCells {
        path: path.to_path_buf(),
        width,
        height,
        max,
    };
    let n = width.checked_mul(height).ok_or_else(too_many)?;
    let n = usize::try_from(n).map_err(|_| too_many())?;
    if n > max {
        return Err(too_many());
    }
    Ok(n)
}

/// Fails with [`RasterError::InvalidCellSize`] unless `value` is finite and positive.
pub(crate) fn check_cell_size(path: &Path, value: f64, source_of: &str) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(RasterError::InvalidCellSize {
            path: path.to_path_buf(),
            value,
            source_of: source_of.to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn declared_value_is_nodata_and_nan_is_an_error() {
        let p = Path::new("x.asc");
        let mut s = CellSink::new(p, 2, 1, NodataRule::declared(Some(-9999.0)));
        s.push_f64(-9999.0).unwrap();
        let e = s.push_f64(f64::NAN).unwrap_err();
        assert!(
            matches!(e, RasterError::NonFinite { col: 1, row: 0, .. }),
            "{e}"
        );
        assert!(e.to_string().contains("x.asc"));
    }

    #[test]
    fn nan_is_nodata_without_declaration_but_inf_is_not() {
        let p = Path::new("x.npy");
        let mut s = CellSink::new(p, 3, 1, NodataRule::nan());
        s.push_f32(f32::NAN).unwrap();
        s.push_f32(1.5).unwrap();
        let e = s.push_f32(f32::NEG_INFINITY).unwrap_err();
        assert!(matches!(e, RasterError::NonFinite { col: 2, .. }));
        let mut s = CellSink::new(p, 2, 1, NodataRule::nan());
        s.push_f32(f32::NAN).unwrap();
        s.push_f32(1.5).unwrap();
        let g = s.finish(GridGeometry::square(2, 1, 1.0).unwrap()).unwrap();
        assert_eq!(g.mask().count_nodata(), 1);
        assert_eq!(g.get(1, 0), Some(1.5));
    }

    #[test]
    fn f64_beyond_f32_range_is_an_error() {
        let mut s = CellSink::new(Path::new("a"), 1, 1, NodataRule::nan());
        let e = s.push_f64(1e300).unwrap_err();
        assert!(
            matches!(e, RasterError::NonFinite { value, .. } if value == 1e300),
            "{e}"
        );
    }

    #[test]
    fn f32_nodata_compares_in_f32() {
        let mut s = CellSink::new(Path::new("a"), 1, 1, NodataRule::declared(Some(0.1)));
        s.push_f32(0.1).unwrap();
        assert_eq!(s.invalid, vec![true]);
    }

    #[test]
    fn cell_limit_and_cell_size() {
        let p = Path::new("big.asc");
        let e = check_cells(p, 100_000, 100_000, 1 << 28).unwrap_err();
        assert!(e.to_string().contains("100000x100000"), "{e}");
        assert!(check_cells(p, u64::MAX, 3, usize::MAX).is_err());
        assert_eq!(check_cells(p, 4, 5, 20).unwrap(), 20);
        for v in [0.0, -1.0, f64::NAN] {
            assert!(matches!(
                check_cell_size(p, v, "cellsize"),
                Err(RasterError::InvalidCellSize { .. })
            ));
        }
    }
}
