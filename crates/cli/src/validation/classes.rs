//! Terrain classes of the compared cells and the depth ratios between them, within
//! elevation bands, for the simulated and the observed depth.
//!
//! Slope and aspect come from the run's bedrock by central differences
//! ([`snowscape_terrain::surface::gradient`]); aspect is the compass direction a slope faces
//! (downhill), degrees clockwise from north; northness is cos(aspect)·sin(slope).
//!
//! | ratio | class A | class B |
//! |---|---|---|
//! | north/south | aspect within ±45° of north, slope > 15° | aspect within ±45° of south, slope > 15° |
//! | steep/moderate | slope > 60° | slope 20..=35° |
//! | lee/windward | aspect within ±45° of the direction the wind blows TO, slope > 15° | aspect within ±45° of the direction it blows FROM, slope > 15° |
//!
//! Within each band of [`BAND_M`] metres of altitude, the ratio is the mean depth of class A
//! over the mean depth of class B. A band counts when it holds cells of both classes and both
//! the simulated and the observed class-B means are positive (so the simulated and observed
//! ratios average over the same bands); the reported ratio is the mean of the per-band ratios
//! weighted by the band's class-A plus class-B cell count. Comparing within bands keeps the
//! altitude gradient of depth out of the aspect, slope and wind contrasts.

use serde::Serialize;
use snowscape_terrain::{Grid, surface};

/// Height of an elevation band, metres.
pub const BAND_M: f64 = 200.0;
/// Slope above which a cell has an aspect class, degrees.
pub const ASPECT_MIN_SLOPE_DEG: f64 = 15.0;
/// Half-width of an aspect class, degrees.
pub const ASPECT_HALF_WIDTH_DEG: f64 = 45.0;
/// Slope above which a cell is steep, degrees.
pub const STEEP_SLOPE_DEG: f64 = 60.0;
/// Slopes of the moderate class, degrees.
pub const MODERATE_SLOPE_DEG: (f64, f64) = (20.0, 35.0);

/// Altitude, slope, aspect and northness of one cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellTerrain {
    pub altitude_m: f64,
    pub slope_deg: f64,
    /// Degrees clockwise from north, 0..360; 0 on flat ground (slope 0).
    pub aspect_deg: f64,
    /// cos(aspect)·sin(slope), −1..1.
    pub northness: f64,
}

/// The terrain attributes of the cell at flat index `i` of `bedrock`.
pub fn cell_terrain(bedrock: &Grid, i: usize) -> CellTerrain {
    let g = bedrock.geometry();
    let (col, row) = g.col_row(i);
    let (gx, gy) = surface::gradient(bedrock.data(), g, bedrock.mask(), col, row);
    let (gx, gy) = (f64::from(gx), f64::from(gy));
    let steepness = (gx * gx + gy * gy).sqrt();
    // The downhill direction (-gx east, -gy north) as a compass bearing.
    let aspect_deg = if steepness > 0.0 {
        (-gx).atan2(-gy).to_degrees().rem_euclid(360.0)
    } else {
        0.0
    };
    CellTerrain {
        altitude_m: f64::from(bedrock.data()[i]),
        slope_deg: steepness.atan().to_degrees(),
        aspect_deg,
        // cos(aspect) = -gy / |g| and sin(slope) = |g| / √(1 + |g|²).
        northness: -gy / (1.0 + steepness * steepness).sqrt(),
    }
}

/// The angle between two compass bearings, 0..=180 degrees.
pub fn bearing_difference(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

/// A pair of classes whose depth ratio is reported.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Contrast {
    NorthSouth,
    SteepModerate,
    LeeWindward,
}

impl Contrast {
    /// Whether the cell is in class A (`Some(true)`), class B (`Some(false)`) or neither.
    pub fn class(self, t: &CellTerrain, wind_from_deg: f64) -> Option<bool> {
        let facing = |bearing: f64| {
            t.slope_deg > ASPECT_MIN_SLOPE_DEG
                && bearing_difference(t.aspect_deg, bearing) <= ASPECT_HALF_WIDTH_DEG
        };
        let (a, b) = match self {
            Contrast::NorthSouth => (facing(0.0), facing(180.0)),
            Contrast::SteepModerate => (
                t.slope_deg > STEEP_SLOPE_DEG,
                (MODERATE_SLOPE_DEG.0..=MODERATE_SLOPE_DEG.1).contains(&t.slope_deg),
            ),
            Contrast::LeeWindward => (facing(wind_from_deg + 180.0), facing(wind_from_deg)),
        };
        match (a, b) {
            (true, _) => Some(true),
            (false, true) => Some(false),
            _ => None,
        }
    }
}

/// One elevation band of a contrast.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BandRatio {
    /// Lower edge of the band, metres.
    pub from_m: f64,
    pub cells_a: usize,
    pub cells_b: usize,
    /// Mean simulated depth of class A over class B.
    pub simulated: Option<f64>,
    /// Mean observed depth of class A over class B.
    pub observed: Option<f64>,
    /// Whether the band enters the weighted means.
    pub used: bool,
}

/// A contrast over all bands.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContrastRatio {
    pub class_a: &'static str,
    pub class_b: &'static str,
    /// Count-weighted mean over the used bands of the simulated per-band ratio.
    pub simulated: Option<f64>,
    /// The same for the observed depth.
    pub observed: Option<f64>,
    /// Cells of class A, all bands.
    pub cells_a: usize,
    /// Cells of class B, all bands.
    pub cells_b: usize,
    /// Cells of both classes in the bands used.
    pub cells_used: usize,
    pub bands: Vec<BandRatio>,
}

#[derive(Default, Clone, Copy)]
struct Sums {
    n: usize,
    sim: f64,
    obs: f64,
}

/// The depth ratio of `contrast` within elevation bands.
pub fn contrast_ratio(
    contrast: Contrast,
    terrain: &[CellTerrain],
    simulated: &[f64],
    observed: &[f64],
    wind_from_deg: f64,
) -> ContrastRatio {
    let (class_a, class_b) = match contrast {
        Contrast::NorthSouth => ("north", "south"),
        Contrast::SteepModerate => ("steep", "moderate"),
        Contrast::LeeWindward => ("lee", "windward"),
    };
    let mut bands: std::collections::BTreeMap<i64, [Sums; 2]> = Default::default();
    for ((t, &s), &o) in terrain.iter().zip(simulated).zip(observed) {
        let Some(is_a) = contrast.class(t, wind_from_deg) else {
            continue;
        };
        let band = (t.altitude_m / BAND_M).floor() as i64;
        let sums = &mut bands.entry(band).or_default()[usize::from(!is_a)];
        sums.n += 1;
        sums.sim += s;
        sums.obs += o;
    }
    let mut out = ContrastRatio {
        class_a,
        class_b,
        simulated: None,
        observed: None,
        cells_a: 0,
        cells_b: 0,
        cells_used: 0,
        bands: Vec::new(),
    };
    let (mut ws, mut wo, mut w) = (0.0, 0.0, 0.0);
    for (band, [a, b]) in bands {
        let mean_ratio = |sa: f64, sb: f64| {
            (a.n > 0 && b.n > 0 && sb > 0.0).then(|| (sa / a.n as f64) / (sb / b.n as f64))
        };
        let simulated = mean_ratio(a.sim, b.sim);
        let observed = mean_ratio(a.obs, b.obs);
        let used = simulated.is_some() && observed.is_some();
        if let (Some(s), Some(o)) = (simulated, observed) {
            let weight = (a.n + b.n) as f64;
            ws += weight * s;
            wo += weight * o;
            w += weight;
            out.cells_used += a.n + b.n;
        }
        out.cells_a += a.n;
        out.cells_b += b.n;
        out.bands.push(BandRatio {
            from_m: band as f64 * BAND_M,
            cells_a: a.n,
            cells_b: b.n,
            simulated,
            observed,
            used,
        });
    }
    if w > 0.0 {
        out.simulated = Some(ws / w);
        out.observed = Some(wo / w);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_terrain::GridGeometry;

    #[test]
    fn aspect_and_northness_of_planes() {
        // A plane falling to the north by 1 m per 10 m: aspect 0, slope atan(0.1).
        let g = GridGeometry::square(3, 3, 10.0).unwrap();
        let north = Grid::from_fn(g.clone(), |_, r| 100.0 + r as f32); // row 0 is north
        let t = cell_terrain(&north, 4);
        assert!(t.aspect_deg.abs() < 1e-9 || (t.aspect_deg - 360.0).abs() < 1e-9);
        assert!((t.slope_deg - 0.1f64.atan().to_degrees()).abs() < 1e-5);
        assert!((t.northness - 0.1 / 1.01f64.sqrt()).abs() < 1e-6);
        // Falling to the east: aspect 90, northness 0.
        let east = Grid::from_fn(g, |c, _| 100.0 - 2.0 * c as f32);
        let t = cell_terrain(&east, 4);
        assert!((t.aspect_deg - 90.0).abs() < 1e-6, "{}", t.aspect_deg);
        assert!(t.northness.abs() < 1e-9);
        assert_eq!(bearing_difference(350.0, 20.0), 30.0);
        assert_eq!(bearing_difference(90.0, 270.0), 180.0);
    }

    fn cell(altitude_m: f64, slope_deg: f64, aspect_deg: f64) -> CellTerrain {
        CellTerrain {
            altitude_m,
            slope_deg,
            aspect_deg,
            northness: 0.0,
        }
    }

    #[test]
    fn ratios_are_count_weighted_over_bands() {
        // Band 0..200: 1 north cell (depth 2) and 1 south cell (1): ratio 2, weight 2.
        // Band 200..400: 3 north cells (3 each), 1 south (1): ratio 3, weight 4.
        // Band 400..600: north only: not used. Weighted mean (2·2 + 3·4) / 6 = 8/3.
        let terrain = [
            cell(100.0, 30.0, 10.0),
            cell(150.0, 30.0, 170.0),
            cell(250.0, 30.0, 350.0),
            cell(260.0, 30.0, 0.0),
            cell(270.0, 30.0, 44.0),
            cell(300.0, 30.0, 200.0),
            cell(450.0, 30.0, 0.0),
            cell(120.0, 10.0, 0.0),  // too flat for an aspect class
            cell(120.0, 30.0, 90.0), // east-facing: neither
        ];
        let sim = [2.0, 1.0, 3.0, 3.0, 3.0, 1.0, 9.0, 5.0, 5.0];
        let obs: Vec<f64> = sim.iter().map(|v| v * 0.5).collect();
        let r = contrast_ratio(Contrast::NorthSouth, &terrain, &sim, &obs, 270.0);
        assert!((r.simulated.unwrap() - 8.0 / 3.0).abs() < 1e-12);
        assert!((r.observed.unwrap() - 8.0 / 3.0).abs() < 1e-12);
        assert_eq!((r.cells_a, r.cells_b, r.cells_used), (5, 2, 6));
        assert_eq!(r.bands.len(), 3);
        assert!(!r.bands[2].used);
        // Lee of a westerly wind faces east.
        let r = contrast_ratio(Contrast::LeeWindward, &terrain, &sim, &obs, 270.0);
        assert_eq!((r.cells_a, r.cells_b), (1, 0));
        assert_eq!(r.simulated, None);
        let c = Contrast::SteepModerate;
        assert_eq!(c.class(&cell(0.0, 61.0, 0.0), 0.0), Some(true));
        assert_eq!(c.class(&cell(0.0, 35.0, 0.0), 0.0), Some(false));
        assert_eq!(c.class(&cell(0.0, 40.0, 0.0), 0.0), None);
    }
}
