//! The alpine landform: the height of every cell, composed from a coarse eroded relief and
//! fine eroded-looking detail.
//!
//! 1. **Drainage network.** A coarse grid (about one coarse cell per 8 fine cells, 24..=256
//!    cells per side) covers the terrain plus a margin of 1/8 of the extent on every side, so
//!    its fixed outlets lie outside the terrain. A mountain-range uplift field (fBm with one or
//!    two ranges across the extent) over a hilly initial surface is eroded by
//!    [`super::erosion`]: dendritic valleys, concave river profiles, rounded divides. The
//!    normalised result is raised to a power > 1, which widens and flattens valley floors and
//!    steepens the upper slopes, as glaciers did.
//! 2. **Plateaus.** Where a low-frequency mask is high, the coarse relief is cut by a soft
//!    minimum, leaving flat tablelands whose edges the cliff pass steepens. The mask of rock
//!    bands used by [`super::cliffs`] is also computed on the coarse grid (both vary over
//!    kilometres, so sampling them per cell would waste time).
//! 3. **Detail.** Swiss turbulence ([`super::noise::SwissTurbulence`]), first wavelength 4
//!    coarse cells, octaves down to about 4 fine cells: sharp arêtes, couloirs and rock ribs
//!    running down the slopes. It fades out towards the valley floors so they stay smooth.
//!
//! Heights are relative (0 at the lowest valley floor, about 1 at the highest summit) until
//! [`super::alpine`] scales them by the relief.

use super::AlpineParams;
use super::erosion::{self, StreamPower};
use super::noise::{Fbm, SwissTurbulence};
use crate::random::uniform;

/// Noise layer numbers: each feature draws its own independent layers.
mod layer {
    pub const UPLIFT: u64 = 0;
    pub const PLATEAUS: u64 = 10;
    pub const ROCK_BANDS: u64 = 15;
    pub const INITIAL: u64 = 20;
    pub const DETAIL: u64 = 100;
    /// Random stream of the initial roughness of the coarse grid.
    pub const ROUGHNESS: u64 = 300;
}

/// Largest side of the coarse erosion grid, cells.
const COARSE_MAX_SIDE: usize = 256;
/// Smallest side of the coarse erosion grid, cells.
const COARSE_MIN_SIDE: usize = 24;
/// Fine cells per coarse cell, when the coarse grid is not at its largest or smallest.
const FINE_PER_COARSE: usize = 8;
/// Margin of the coarse grid beyond the terrain on every side, as a share of the extent.
const MARGIN: f64 = 0.125;
/// Finest noise wavelength, in fine cells.
const FINEST_WAVELENGTH_CELLS: f64 = 4.0;
/// Most octaves of detail.
const MAX_OCTAVES: usize = 10;
/// Relief of the initial surface, in uplift steps: the drainage inherits its irregular
/// layout instead of growing only from the grid edges.
const INITIAL_RELIEF: f64 = 15.0;
/// Largest wavelength of the mountain ranges (the uplift field), m: a larger extent holds
/// several ranges instead of one stretched range.
const RANGE_WAVELENGTH: f64 = 16_000.0;
/// Range-field level below which the coarse grid is lowland held at base level: these nodes
/// are outlets inside the terrain, so a large extent drains to several main valleys.
const LOWLAND_LEVEL: f64 = -0.45;
/// Gradient of the detail (metres of detail amplitude per metre of its wavelength).
const DETAIL_STEEPNESS: f64 = 0.27;
/// Largest detail amplitude, as a share of the relief.
const MAX_DETAIL_SHARE: f64 = 0.25;

/// Exponent applied to the normalised eroded relief: > 1 flattens valley floors.
const VALLEY_FLATTENING: f64 = 1.4;

/// The erosion that shapes the drainage network (dimensionless; tuned by eye and by the slope
/// distribution of the result).
const EROSION: StreamPower = StreamPower {
    iterations: 100,
    erodibility: 0.25,
    area_exponent: 0.45,
    diffusivity: 0.12,
};

/// Level (share of the relief) at which plateaus cut the summits.
const PLATEAU_LEVEL: f64 = 0.55;
/// Width of the soft minimum that rounds plateau edges, as a share of the relief.
const PLATEAU_SOFTNESS: f64 = 0.05;

/// Hermite smoothstep of `x` between `edge0` and `edge1`.
#[inline(always)]
fn smoothstep(edge0: f64, edge1: f64, x: f64) -> f64 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Polynomial soft minimum of `a` and `b` with blending width `k` (Quilez).
#[inline(always)]
fn soft_min(a: f64, b: f64, k: f64) -> f64 {
    let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
    b + (a - b) * h - k * h * (1.0 - h)
}

/// Catmull-Rom weights of the four taps around fractional offset `t` in [0, 1).
#[inline(always)]
fn catmull_rom(t: f64) -> [f64; 4] {
    let (t2, t3) = (t * t, t * t * t);
    [
        0.5 * (-t3 + 2.0 * t2 - t),
        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
        0.5 * (t3 - t2),
    ]
}

/// Side of the coarse erosion grid for a terrain of `size` cells per side.
pub fn coarse_side(size: usize) -> usize {
    (size / FINE_PER_COARSE).clamp(COARSE_MIN_SIDE, COARSE_MAX_SIDE)
}

/// The number of detail octaves from wavelength `first` (m) down to about 4 cells.
pub fn detail_octaves(first: f64, cell_size: f64) -> usize {
    let ratio = first / (FINEST_WAVELENGTH_CELLS * cell_size);
    if ratio <= 1.0 {
        1
    } else {
        (ratio.log2().floor() as usize + 1).min(MAX_OCTAVES)
    }
}

/// The eroded relief on the coarse grid, normalised to [0, 1].
#[derive(Debug, Clone)]
struct CoarseRelief {
    side: usize,
    /// Coarse cell size, m.
    cell: f64,
    /// Metres from the coarse grid's west/north edge to the terrain's.
    margin: f64,
    heights: Vec<f64>,
    /// Rock-band outcrop weight in [0, 0.7] (about a third of the area is non-zero).
    rock_bands: Vec<f64>,
}

/// The plateau mask in [0, 1] for an fBm value (roughly normal, σ ≈ 0.3) and a target share.
fn plateau_mask(value: f64, share: f64) -> f64 {
    let threshold = 0.3 * (1.0 - 2.0 * share) * 1.5;
    smoothstep(threshold - 0.04, threshold + 0.04, value)
}

/// The rock-band weight for an fBm value.
fn rock_band_weight(value: f64) -> f64 {
    0.7 * ((value - 0.1) * 4.0).clamp(0.0, 1.0)
}

impl CoarseRelief {
    /// Uplifts and erodes the coarse grid of `params`.
    fn new(params: &AlpineParams) -> Self {
        let side = coarse_side(params.size);
        let extent = params.size as f64 * params.cell_size;
        let margin = MARGIN * extent;
        let cell = (extent + 2.0 * margin) / side as f64;
        let ranges = Fbm::new(params.seed, layer::UPLIFT, 3);
        let initial = Fbm::new(params.seed, layer::INITIAL, 5);
        let range_scale = 1.0 / (0.5 * (extent + 2.0 * margin).min(RANGE_WAVELENGTH));
        let mut uplift = vec![0.0; side * side];
        let mut heights = vec![0.0; side * side];
        for (i, (u, h)) in uplift.iter_mut().zip(heights.iter_mut()).enumerate() {
            let (col, row) = (i % side, i / side);
            let (x, y) = (
                (col as f64 + 0.5) * cell * range_scale,
                (row as f64 + 0.5) * cell * range_scale,
            );
            let range = ranges.value(x, y);
            *u = if range < LOWLAND_LEVEL {
                0.0
            } else {
                0.3 + 0.7 * smoothstep(-0.4, 0.4, range)
            };
            let hills = 0.5 + 0.5 * initial.value(3.0 * x, 3.0 * y);
            *h = INITIAL_RELIEF * hills * *u
                + 0.5 * uniform(params.seed, layer::ROUGHNESS, i as u64);
        }
        erosion::erode(&mut heights, &uplift, side, &EROSION, params.seed);
        let max = heights.iter().cloned().fold(f64::MIN_POSITIVE, f64::max);
        heights
            .iter_mut()
            .for_each(|h| *h = (h.max(0.0) / max).powf(VALLEY_FLATTENING));
        let plateaus = Fbm::new(params.seed, layer::PLATEAUS, 2);
        let bands = Fbm::new(params.seed, layer::ROCK_BANDS, 2);
        let mask_scale = 1.0 / (0.35 * extent);
        let mut rock_bands = vec![0.0; side * side];
        for (i, (h, band)) in heights.iter_mut().zip(rock_bands.iter_mut()).enumerate() {
            let (col, row) = (i % side, i / side);
            let x = ((col as f64 + 0.5) * cell - margin) * mask_scale;
            let y = ((row as f64 + 0.5) * cell - margin) * mask_scale;
            let mask = plateau_mask(plateaus.value(x + 17.0, y - 5.0), params.plateau_share);
            if params.plateau_share > 0.0 && mask > 0.0 {
                *h += mask * (soft_min(*h, PLATEAU_LEVEL, PLATEAU_SOFTNESS) - *h);
            }
            *band = rock_band_weight(bands.value(x + 3.0, y - 7.0));
        }
        Self {
            side,
            cell,
            margin,
            heights,
            rock_bands,
        }
    }

    /// Bilinear rock-band weight at `(x, y)` metres from the terrain's north-west corner.
    #[inline]
    fn rock_band(&self, x: f64, y: f64) -> f64 {
        let last = self.side - 1;
        let cx = ((x + self.margin) / self.cell - 0.5).clamp(0.0, last as f64);
        let cy = ((y + self.margin) / self.cell - 0.5).clamp(0.0, last as f64);
        let (c0, r0) = (cx.floor() as usize, cy.floor() as usize);
        let (c1, r1) = ((c0 + 1).min(last), (r0 + 1).min(last));
        let (fx, fy) = (cx - c0 as f64, cy - r0 as f64);
        let at = |c: usize, r: usize| self.rock_bands[r * self.side + c];
        let top = at(c0, r0) + fx * (at(c1, r0) - at(c0, r0));
        let bottom = at(c0, r1) + fx * (at(c1, r1) - at(c0, r1));
        top + fy * (bottom - top)
    }

    /// Bicubic (Catmull-Rom) height at `(x, y)` metres from the terrain's north-west corner.
    #[inline]
    fn height(&self, x: f64, y: f64) -> f64 {
        let cx = (x + self.margin) / self.cell - 0.5;
        let cy = (y + self.margin) / self.cell - 0.5;
        let (x0, y0) = (cx.floor(), cy.floor());
        let (wx, wy) = (catmull_rom(cx - x0), catmull_rom(cy - y0));
        let last = self.side as isize - 1;
        let mut sum = 0.0;
        for (j, wyj) in wy.iter().enumerate() {
            let r = (y0 as isize + j as isize - 1).clamp(0, last) as usize;
            let line = &self.heights[r * self.side..(r + 1) * self.side];
            let mut acc = 0.0;
            for (k, wxk) in wx.iter().enumerate() {
                let c = (x0 as isize + k as isize - 1).clamp(0, last) as usize;
                acc += wxk * line[c];
            }
            sum += wyj * acc;
        }
        sum
    }
}

/// The alpine height function of one seed and parameter set.
#[derive(Debug, Clone)]
pub struct AlpineLandform {
    coarse: CoarseRelief,
    detail: SwissTurbulence,
    detail_max: f64,
    /// Metres per lattice unit of the first detail octave.
    detail_wavelength: f64,
    /// Detail amplitude, as a share of the relief.
    detail_amplitude: f64,
}

impl AlpineLandform {
    /// The landform of `params` (already validated); erodes the coarse grid.
    pub fn new(params: &AlpineParams) -> Self {
        let coarse = CoarseRelief::new(params);
        let detail_wavelength = 4.0 * coarse.cell;
        let octaves = detail_octaves(detail_wavelength, params.cell_size);
        let detail = SwissTurbulence::new(params.seed, layer::DETAIL, octaves);
        Self {
            coarse,
            detail_max: detail.max_value(),
            detail,
            detail_wavelength,
            detail_amplitude: (DETAIL_STEEPNESS * detail_wavelength / params.effective_relief())
                .min(MAX_DETAIL_SHARE),
        }
    }

    /// Relative height at `(x, y)` metres (x east, y south of the north-west corner), about
    /// [0, 1].
    #[inline]
    pub fn height(&self, x: f64, y: f64) -> f64 {
        let base = self.coarse.height(x, y);
        let rock = smoothstep(0.02, 0.3, base);
        let (u, v) = (x / self.detail_wavelength, y / self.detail_wavelength);
        let ridges = self.detail.value(u, v) / self.detail_max - 0.5;
        base + self.detail_amplitude * rock * ridges
    }

    /// Rock-band outcrop weight in [0, 0.7] at `(x, y)` metres (the cliff pass's mask).
    #[inline]
    pub fn rock_band(&self, x: f64, y: f64) -> f32 {
        self.coarse.rock_band(x, y) as f32
    }
}
