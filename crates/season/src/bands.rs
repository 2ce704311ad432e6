//! The season by altitude band, for a user to check against what they know of their range:
//! per 200 m band of the bedrock's altitude, the precipitation that fell (mm of water over
//! the band's cells), the share of it that fell as rain, and the peak over the season of the
//! band's mean snow water equivalent.
//!
//! Bands start at a multiple of 200 m below the lowest valid cell; a terrain of more than
//! [`MAX_BANDS`] such bands gets bands of a multiple of 200 m wide enough to keep to it. The
//! precipitation is summed where it is laid ([`crate::snowfall::add_precipitation`], the
//! orographic snowfall: the paper's snowfall adds depth, not water, and is not counted), so
//! the bands' snow water and rain add up to the water budget's `snowfall_water` and `rain`.
//! The SWE is the layers' depths at their densities plus the liquid water the pack holds,
//! averaged over the band once a day (at the first event of each season day), so its peak is
//! that of the daily samples. Every sum is over rows in order, each row's per band in four
//! interleaved partial sums added in a fixed order, so the table does not depend on the
//! thread count.

use serde::{Deserialize, Serialize};
use snowscape_terrain::{LayeredTerrain, parallel};

/// Width of a band, m.
pub const BAND_WIDTH_M: f64 = 200.0;
/// Most bands a terrain is split into (40 km of relief at 200 m).
pub const MAX_BANDS: usize = 200;
/// The band index of a cell in no band (nodata).
pub const NO_BAND: u16 = u16::MAX;
/// Interleaved partial sums per band and row, added in a fixed order.
const LANES: usize = 4;

/// The band of each cell of a terrain.
#[derive(Debug, Clone, Default)]
pub struct Bands {
    /// Lower edge of the first band, m.
    base_m: f64,
    /// Width of each band, m.
    width_m: f64,
    /// Per cell: its band, or [`NO_BAND`].
    band_of: Vec<u16>,
    /// Valid cells per band.
    cells: Vec<u64>,
}

/// What a season recorded per band (checkpointed with the run's state).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct BandRecord {
    /// Per band: snow water and rain summed over its cells, m of water.
    pub water_m: Vec<[f64; 2]>,
    /// Per band: the highest daily mean SWE so far, m of water.
    pub peak_swe_m: Vec<f64>,
    /// The last season day whose SWE was sampled (`None`: none yet).
    pub sampled_day: Option<u64>,
}

/// One row of the band table (`report.json`'s `bands`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BandSummary {
    /// Lower edge, m.
    pub from_m: f64,
    /// Upper edge, m.
    pub to_m: f64,
    /// Valid cells in the band.
    pub cells: u64,
    /// Precipitation over the season, mm of water (the band's mean).
    pub precipitation_mm: f64,
    /// Share of that precipitation that fell as rain, 0..1 (0 without precipitation).
    pub rain_share: f64,
    /// Peak over the season of the band's mean SWE, mm of water.
    pub peak_swe_mm: f64,
}

impl Bands {
    /// The bands of `terrain`'s valid bedrock cells.
    pub fn new(terrain: &LayeredTerrain) -> Self {
        let mask = terrain.mask();
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (i, &z) in terrain.bedrock.iter().enumerate() {
            if mask.is_valid(i) && z.is_finite() {
                lo = lo.min(z as f64);
                hi = hi.max(z as f64);
            }
        }
        if lo > hi {
            return Self::default();
        }
        let base_m = (lo / BAND_WIDTH_M).floor() * BAND_WIDTH_M;
        let raw = ((hi - base_m) / BAND_WIDTH_M).floor() + 1.0;
        let widen = (raw / MAX_BANDS as f64).ceil().max(1.0);
        let width_m = BAND_WIDTH_M * widen;
        let n = (((hi - base_m) / width_m).floor() as usize + 1).min(MAX_BANDS);
        let mut cells = vec![0u64; n];
        let band_of: Vec<u16> = terrain
            .bedrock
            .iter()
            .enumerate()
            .map(|(i, &z)| {
                if !(mask.is_valid(i) && z.is_finite()) {
                    return NO_BAND;
                }
                let b = (((z as f64 - base_m) / width_m).floor() as usize).min(n - 1);
                cells[b] += 1;
                b as u16
            })
            .collect();
        Self {
            base_m,
            width_m,
            band_of,
            cells,
        }
    }

    /// Number of bands.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Whether the terrain has no valid cell.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// Per cell: its band, or [`NO_BAND`].
    pub fn band_of(&self) -> &[u16] {
        &self.band_of
    }

    /// Per band: the mean SWE of its cells now, m of water (`liquid_m`: the pack's liquid
    /// water per cell; `densities_kg_m3`: the layers', compacted to powder).
    pub fn mean_swe_m(
        &self,
        terrain: &LayeredTerrain,
        liquid_m: &[f32],
        densities_kg_m3: [f64; 4],
    ) -> Vec<f64> {
        let w = terrain.geometry().width();
        let n = self.len();
        let per_water = densities_kg_m3.map(|d| (d / 1000.0) as f32);
        let [c, s, u, p] = &terrain.snow;
        let rows: Vec<Vec<f64>> = parallel::map_rows(w, &self.band_of, |row, bands| {
            // Per band, `SUM_LANES` interleaved partial sums (no chain of additions).
            let mut sums = vec![0.0f64; n * LANES];
            let at = row * w;
            for (col, &b) in bands.iter().enumerate() {
                let i = at + col;
                if let Some(sum) = sums.get_mut(b as usize * LANES + col % LANES) {
                    let swe = c[i] * per_water[0]
                        + s[i] * per_water[1]
                        + u[i] * per_water[2]
                        + p[i] * per_water[3]
                        + liquid_m.get(i).copied().unwrap_or(0.0);
                    *sum += swe as f64;
                }
            }
            sums.chunks_exact(LANES)
                .map(|l| (l[0] + l[1]) + (l[2] + l[3]))
                .collect()
        });
        let mut total = vec![0.0f64; n];
        for r in rows {
            for (t, v) in total.iter_mut().zip(r) {
                *t += v;
            }
        }
        for (t, &k) in total.iter_mut().zip(&self.cells) {
            *t /= k.max(1) as f64;
        }
        total
    }

    /// The table of `record`.
    pub fn summary(&self, record: &BandRecord) -> Vec<BandSummary> {
        (0..self.len())
            .map(|b| {
                let [snow, rain] = record.water_m.get(b).copied().unwrap_or([0.0; 2]);
                let cells = self.cells[b];
                let total = snow + rain;
                BandSummary {
                    from_m: self.base_m + b as f64 * self.width_m,
                    to_m: self.base_m + (b + 1) as f64 * self.width_m,
                    cells,
                    precipitation_mm: total / cells.max(1) as f64 * 1000.0,
                    rain_share: if total > 0.0 { rain / total } else { 0.0 },
                    peak_swe_mm: record.peak_swe_m.get(b).copied().unwrap_or(0.0) * 1000.0,
                }
            })
            .collect()
    }
}

impl BandRecord {
    /// Sized for `n` bands (a record from before the bands existed starts empty).
    pub fn ensure(&mut self, n: usize) {
        self.water_m.resize(n, [0.0; 2]);
        self.peak_swe_m.resize(n, 0.0);
    }

    /// Raises each band's peak to `mean_swe_m` where it is higher.
    pub fn raise_peaks(&mut self, mean_swe_m: &[f64]) {
        for (peak, &v) in self.peak_swe_m.iter_mut().zip(mean_swe_m) {
            *peak = peak.max(v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_terrain::{Grid, GridGeometry};

    fn ramp(w: usize, h: usize, z0: f32, dz: f32) -> LayeredTerrain {
        let g = GridGeometry::square(w, h, 10.0).unwrap();
        LayeredTerrain::from_bedrock(Grid::from_fn(g, |_, r| z0 + dz * r as f32))
    }

    #[test]
    fn bands_are_200_m_from_a_multiple_of_200_m() {
        // Rows at 1130, 1230, ..., 2030 m: bands 1000-1200, ..., 2000-2200.
        let t = ramp(4, 10, 1130.0, 100.0);
        let b = Bands::new(&t);
        assert_eq!(b.len(), 6);
        let s = b.summary(&BandRecord::default());
        assert_eq!(
            (s[0].from_m, s[0].to_m, s[5].to_m),
            (1000.0, 1200.0, 2200.0)
        );
        let cells: Vec<u64> = s.iter().map(|r| r.cells).collect();
        assert_eq!(cells, [4, 8, 8, 8, 8, 4]);
        // A huge relief widens the bands to keep to the cap.
        let huge = ramp(2, 3, 0.0, 1.0e6);
        let b = Bands::new(&huge);
        assert!(b.len() <= MAX_BANDS);
        let s = b.summary(&BandRecord::default());
        assert_eq!(s.iter().map(|r| r.cells).sum::<u64>(), 6);
        assert!((s[0].to_m - s[0].from_m) % BAND_WIDTH_M == 0.0);
    }
}
