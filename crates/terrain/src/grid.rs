//! [`Grid`]: a georeferenced f32 raster with a nodata mask and bilinear sampling.

use crate::{GridGeometry, TerrainError};

/// The largest altitude magnitude a terrain may hold, metres. Earth's relief spans -11 km to
/// +9 km; the limit leaves room for synthetic scenes but refuses spikes (1e30) and wrong units.
pub const MAX_ABS_ALTITUDE_M: f32 = 1e5;

/// The smallest metric cell a terrain may have, m: 1 mm, the scale of a snow grain, below
/// which the model's layers and slopes mean nothing (and a DEM in degrees without a CRS has
/// cells of ~1e-4 to 1e-2 "m").
pub const MIN_TERRAIN_CELL_M: f64 = 1e-3;

/// The largest metric cell a terrain may have, m: 100 km (a whole-Earth grid of 400 cells).
pub const MAX_TERRAIN_CELL_M: f64 = 1e5;

/// Which cells hold data. Nodata cells (outside a real DEM's footprint) carry no snow and are
/// skipped by every kernel; their stored value is kept finite (0) so it can never spread a NaN.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct NodataMask {
    /// `None` when every cell is valid (the common case costs no memory).
    invalid: Option<Vec<bool>>,
}

impl NodataMask {
    /// A mask where every cell is valid.
    pub fn all_valid() -> Self {
        Self { invalid: None }
    }
    /// A mask from a per-cell "is nodata" vector.
    pub fn from_invalid(invalid: Vec<bool>) -> Self {
        if invalid.iter().any(|&b| b) {
            Self {
                invalid: Some(invalid),
            }
        } else {
            Self::all_valid()
        }
    }
    /// Whether cell `index` holds data.
    #[inline(always)]
    pub fn is_valid(&self, index: usize) -> bool {
        match &self.invalid {
            None => true,
            Some(m) => !m[index],
        }
    }
    /// Whether any cell is nodata.
    pub fn has_nodata(&self) -> bool {
        self.invalid.is_some()
    }
    /// Number of nodata cells.
    pub fn count_nodata(&self) -> usize {
        self.invalid
            .as_ref()
            .map_or(0, |m| m.iter().filter(|&&b| b).count())
    }
    /// The per-cell "is nodata" slice, if any cell is nodata.
    pub fn invalid_cells(&self) -> Option<&[bool]> {
        self.invalid.as_deref()
    }
}

/// A georeferenced raster of f32 values that owns its geometry and nodata mask.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    geometry: GridGeometry,
    data: Vec<f32>,
    mask: NodataMask,
}

impl Grid {
    /// A grid over `geometry` holding `data` (row-major, row 0 north). Nodata cells must be
    /// flagged in `mask`; valid cells must be finite.
    pub fn new(
        geometry: GridGeometry,
        data: Vec<f32>,
        mask: NodataMask,
    ) -> Result<Self, TerrainError> {
        if data.len() != geometry.len() {
            return Err(TerrainError::LengthMismatch {
                width: geometry.width(),
                height: geometry.height(),
                expected: geometry.len(),
                actual: data.len(),
            });
        }
        if let Some(inv) = mask.invalid_cells()
            && inv.len() != data.len()
        {
            return Err(TerrainError::LengthMismatch {
                width: geometry.width(),
                height: geometry.height(),
                expected: geometry.len(),
                actual: inv.len(),
            });
        }
        let mut g = Self {
            geometry,
            data,
            mask,
        };
        g.zero_nodata();
        Ok(g)
    }

    /// A grid filled with `value`, every cell valid.
    pub fn filled(geometry: GridGeometry, value: f32) -> Self {
        let data = vec![value; geometry.len()];
        Self {
            geometry,
            data,
            mask: NodataMask::all_valid(),
        }
    }

    /// A grid whose value at `(col, row)` is `f(col, row)`, every cell valid.
    pub fn from_fn(geometry: GridGeometry, mut f: impl FnMut(usize, usize) -> f32) -> Self {
        let (w, h) = (geometry.width(), geometry.height());
        let mut data = Vec::with_capacity(w * h);
        for r in 0..h {
            for c in 0..w {
                data.push(f(c, r));
            }
        }
        Self {
            geometry,
            data,
            mask: NodataMask::all_valid(),
        }
    }

    fn zero_nodata(&mut self) {
        if let Some(inv) = self.mask.invalid_cells() {
            for (v, &bad) in self.data.iter_mut().zip(inv) {
                if bad {
                    *v = 0.0;
                }
            }
        }
    }

    /// The grid's geometry.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }
    /// The values, row-major, row 0 north.
    pub fn data(&self) -> &[f32] {
        &self.data
    }
    /// The values, mutably. Callers keep nodata cells at 0 and valid cells finite.
    pub fn data_mut(&mut self) -> &mut [f32] {
        &mut self.data
    }
    /// The values, consuming the grid.
    pub fn into_data(self) -> Vec<f32> {
        self.data
    }
    /// The nodata mask.
    pub fn mask(&self) -> &NodataMask {
        &self.mask
    }
    /// Value at `(col, row)`, `None` outside the grid or on nodata.
    pub fn get(&self, col: usize, row: usize) -> Option<f32> {
        if col >= self.geometry.width() || row >= self.geometry.height() {
            return None;
        }
        let i = self.geometry.index(col, row);
        self.mask.is_valid(i).then(|| self.data[i])
    }

    /// Checks that every valid cell is finite; the error names the first offending cell.
    pub fn check_finite(&self, what: &str) -> Result<(), TerrainError> {
        for (i, &v) in self.data.iter().enumerate() {
            if !v.is_finite() && self.mask.is_valid(i) {
                let (col, row) = self.geometry.col_row(i);
                return Err(TerrainError::NonFinite {
                    what: what.to_string(),
                    col,
                    row,
                    value: v,
                });
            }
        }
        Ok(())
    }

    /// Checks that the grid can be a terrain, before any work is done on it: at least 2x2
    /// cells of [`MIN_TERRAIN_CELL_M`] to [`MAX_TERRAIN_CELL_M`] metres each way, every valid
    /// altitude finite and within +-[`MAX_ABS_ALTITUDE_M`], and at least
    /// one 2x2 block of cells of which three or more are valid (a surface with a slope).
    /// The error names the size, the cell and the value.
    pub fn check_terrain(&self) -> Result<(), TerrainError> {
        self.geometry.check_terrain_cells()?;
        let (w, h) = (self.geometry.width(), self.geometry.height());
        if w < 2 || h < 2 {
            return Err(TerrainError::TerrainTooSmall {
                width: w,
                height: h,
            });
        }
        for (i, &v) in self.data.iter().enumerate() {
            if self.mask.is_valid(i) && (v.is_nan() || v.abs() > MAX_ABS_ALTITUDE_M) {
                let (col, row) = self.geometry.col_row(i);
                return Err(TerrainError::AltitudeOutOfRange {
                    col,
                    row,
                    value: v,
                    limit: MAX_ABS_ALTITUDE_M,
                });
            }
        }
        let Some(invalid) = self.mask.invalid_cells() else {
            return Ok(());
        };
        let valid = |c: usize, r: usize| usize::from(!invalid[r * w + c]);
        let has_surface = (0..h - 1).any(|r| {
            (0..w - 1)
                .any(|c| valid(c, r) + valid(c + 1, r) + valid(c, r + 1) + valid(c + 1, r + 1) >= 3)
        });
        if has_surface {
            Ok(())
        } else {
            Err(TerrainError::NoTerrainSurface {
                width: w,
                height: h,
                valid: self.geometry.len() - self.mask.count_nodata(),
            })
        }
    }

    /// Minimum and maximum over valid cells (`None` if every cell is nodata).
    pub fn value_range(&self) -> Option<(f32, f32)> {
        let mut range: Option<(f32, f32)> = None;
        for (i, &v) in self.data.iter().enumerate() {
            if self.mask.is_valid(i) {
                range = Some(match range {
                    None => (v, v),
                    Some((lo, hi)) => (lo.min(v), hi.max(v)),
                });
            }
        }
        range
    }

    /// Mean over valid cells.
    pub fn mean(&self) -> Option<f64> {
        let (mut s, mut n) = (0.0f64, 0usize);
        for (i, &v) in self.data.iter().enumerate() {
            if self.mask.is_valid(i) {
                s += v as f64;
                n += 1;
            }
        }
        (n > 0).then(|| s / n as f64)
    }

    /// Bilinear sample at fractional `(col, row)` (cell centres at whole numbers). Positions
    /// beyond the outer cell centres clamp to the border; nodata corners are left out and the
    /// remaining weights renormalised. `None` outside the grid or where all four corners are
    /// nodata.
    pub fn sample(&self, col: f64, row: f64) -> Option<f32> {
        let (w, h) = (self.geometry.width(), self.geometry.height());
        if !(col >= -0.5 && row >= -0.5 && col <= w as f64 - 0.5 && row <= h as f64 - 0.5) {
            return None;
        }
        let c = col.clamp(0.0, (w - 1) as f64);
        let r = row.clamp(0.0, (h - 1) as f64);
        let (c0, r0) = (c.floor() as usize, r.floor() as usize);
        let (c1, r1) = ((c0 + 1).min(w - 1), (r0 + 1).min(h - 1));
        let (fc, fr) = (c - c0 as f64, r - r0 as f64);
        let mut acc = 0.0f64;
        let mut wsum = 0.0f64;
        for (cc, rr, wt) in [
            (c0, r0, (1.0 - fc) * (1.0 - fr)),
            (c1, r0, fc * (1.0 - fr)),
            (c0, r1, (1.0 - fc) * fr),
            (c1, r1, fc * fr),
        ] {
            let i = self.geometry.index(cc, rr);
            if wt > 0.0 && self.mask.is_valid(i) {
                acc += wt * self.data[i] as f64;
                wsum += wt;
            }
        }
        (wsum > 0.0).then(|| (acc / wsum) as f32)
    }

    /// Bilinear sample at map coordinates (CRS units).
    pub fn sample_map(&self, x: f64, y: f64) -> Option<f32> {
        let (c, r) = self.geometry.map_to_cell(x, y)?;
        self.sample(c, r)
    }

    /// This grid bilinearly resampled onto `geometry` (same extent, another resolution).
    pub fn resample(&self, geometry: GridGeometry) -> Grid {
        let sx = self.geometry.width() as f64 / geometry.width() as f64;
        let sy = self.geometry.height() as f64 / geometry.height() as f64;
        let mut invalid = vec![false; geometry.len()];
        let mut data = vec![0.0f32; geometry.len()];
        for r in 0..geometry.height() {
            for c in 0..geometry.width() {
                let i = geometry.index(c, r);
                match self.sample((c as f64 + 0.5) * sx - 0.5, (r as f64 + 0.5) * sy - 0.5) {
                    Some(v) => data[i] = v,
                    None => invalid[i] = true,
                }
            }
        }
        Grid {
            geometry,
            data,
            mask: NodataMask::from_invalid(invalid),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> Grid {
        let g = GridGeometry::square(4, 3, 2.0).unwrap();
        Grid::from_fn(g, |c, r| (c + 10 * r) as f32)
    }

    #[test]
    fn bilinear_is_exact_on_a_plane() {
        let g = ramp();
        assert_eq!(g.sample(1.0, 1.0), Some(11.0));
        let v = g.sample(1.25, 0.5).unwrap();
        assert!((v - 6.25).abs() < 1e-5);
        assert_eq!(g.sample(-0.4, 0.0), Some(0.0));
        assert_eq!(g.sample(-0.6, 0.0), None);
        assert_eq!(g.sample(f64::NAN, 0.0), None);
    }

    #[test]
    fn nodata_is_skipped_and_zeroed() {
        let geo = GridGeometry::square(2, 1, 1.0).unwrap();
        let g = Grid::new(
            geo,
            vec![f32::NAN, 4.0],
            NodataMask::from_invalid(vec![true, false]),
        )
        .unwrap();
        assert_eq!(g.data()[0], 0.0);
        assert_eq!(g.sample(0.5, 0.0), Some(4.0));
        assert_eq!(g.get(0, 0), None);
        assert_eq!(g.value_range(), Some((4.0, 4.0)));
        assert!(g.check_finite("test").is_ok());
    }

    #[test]
    fn non_finite_is_reported_with_its_cell() {
        let geo = GridGeometry::square(3, 2, 1.0).unwrap();
        let mut d = vec![1.0; 6];
        d[4] = f32::INFINITY;
        let g = Grid::new(geo, d, NodataMask::all_valid()).unwrap();
        let e = g.check_finite("heights").unwrap_err();
        assert_eq!(
            e,
            TerrainError::NonFinite {
                what: "heights".into(),
                col: 1,
                row: 1,
                value: f32::INFINITY
            }
        );
    }

    fn terrain(w: usize, h: usize, data: Vec<f32>, invalid: Option<Vec<bool>>) -> Grid {
        let geo = GridGeometry::square(w, h, 10.0).unwrap();
        let mask = invalid.map_or_else(NodataMask::all_valid, NodataMask::from_invalid);
        Grid::new(geo, data, mask).unwrap()
    }

    #[test]
    fn terrain_needs_two_by_two_cells() {
        for (w, h) in [(1, 1), (1, 7), (7, 1)] {
            let e = terrain(w, h, vec![100.0; w * h], None)
                .check_terrain()
                .unwrap_err();
            assert_eq!(
                e,
                TerrainError::TerrainTooSmall {
                    width: w,
                    height: h
                }
            );
            assert!(e.to_string().contains(&format!("{w}x{h}")), "{e}");
        }
        assert!(terrain(2, 2, vec![1.0; 4], None).check_terrain().is_ok());
    }

    #[test]
    fn terrain_needs_a_surface_of_valid_cells() {
        let all_nodata = terrain(3, 3, vec![0.0; 9], Some(vec![true; 9]));
        let e = all_nodata.check_terrain().unwrap_err();
        assert!(matches!(e, TerrainError::NoTerrainSurface { valid: 0, .. }));
        let mut one = vec![true; 9];
        one[4] = false;
        let e = terrain(3, 3, vec![5.0; 9], Some(one)).check_terrain();
        assert!(matches!(
            e,
            Err(TerrainError::NoTerrainSurface { valid: 1, .. })
        ));
        // A chequerboard has valid cells everywhere but no block with three of them.
        let chequer: Vec<bool> = (0..16).map(|i| (i % 4 + i / 4) % 2 == 0).collect();
        let e = terrain(4, 4, vec![5.0; 16], Some(chequer)).check_terrain();
        assert!(matches!(
            e,
            Err(TerrainError::NoTerrainSurface { valid: 8, .. })
        ));
        // Three valid corners make a triangle with a slope.
        let three = vec![false, false, false, true];
        assert!(
            terrain(2, 2, vec![1.0; 4], Some(three))
                .check_terrain()
                .is_ok()
        );
    }

    #[test]
    fn altitudes_beyond_the_limit_name_the_cell_and_value() {
        let mut d = vec![1500.0; 12];
        d[7] = 1e30;
        let e = terrain(4, 3, d, None).check_terrain().unwrap_err();
        assert_eq!(
            e,
            TerrainError::AltitudeOutOfRange {
                col: 3,
                row: 1,
                value: 1e30,
                limit: MAX_ABS_ALTITUDE_M
            }
        );
        let text = e.to_string();
        assert!(
            text.contains("1e30") && text.contains("col 3, row 1"),
            "{text}"
        );
        let mut d = vec![0.0; 4];
        d[0] = -1.5e5;
        let e = terrain(2, 2, d, None).check_terrain().unwrap_err();
        assert!(e.to_string().contains("-150000"), "{e}");
        let mut d = vec![0.0; 4];
        d[1] = f32::NAN;
        assert!(terrain(2, 2, d, None).check_terrain().is_err());
        let mut d = vec![0.0; 4];
        d[2] = -1e5;
        assert!(terrain(2, 2, d, None).check_terrain().is_ok());
    }

    #[test]
    fn length_mismatch_is_an_error() {
        let geo = GridGeometry::square(3, 2, 1.0).unwrap();
        assert!(Grid::new(geo, vec![0.0; 5], NodataMask::all_valid()).is_err());
    }
}
