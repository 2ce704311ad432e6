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
//! The cells are stratified by bands of [`BAND_M`] metres of altitude. A band is used when it
//! holds cells of both classes. The reported ratio pools the cells of the used bands: it is the
//! ratio of the two classes' mean depths, each class mean taken over the bands with the same
//! band weights (the band's class-A plus class-B cell count), i.e.
//!
//! `ratio = Σ_b w_b·mean_A,b / Σ_b w_b·mean_B,b`, `w_b = n_A,b + n_B,b`.
//!
//! Giving both classes the same band weights keeps the altitude gradient of depth out of the
//! aspect, slope and wind contrasts; pooling (a ratio of weighted sums, not a mean of per-band
//! ratios) keeps a nearly bare band, whose class-B mean is close to 0 and whose own ratio may
//! be 20 or 90, from dominating: it adds little depth to either sum. The per-band ratios are
//! reported beside it (with each class's cell count and mean depths) for inspection only.

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
    /// Mean simulated depth of class A and of class B in the band, metres (`None` without cells).
    pub simulated_mean_m: [Option<f64>; 2],
    /// Mean observed depth of class A and of class B in the band, metres.
    pub observed_mean_m: [Option<f64>; 2],
    /// Mean simulated depth of class A over class B in this band alone (`None` when a class has
    /// no cells or the class-B mean is 0). For inspection: the contrast pools the bands.
    pub simulated: Option<f64>,
    /// The same for the observed depth.
    pub observed: Option<f64>,
    /// Whether the band enters the pooled ratio (it holds cells of both classes).
    pub used: bool,
}

/// A contrast over all bands.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContrastRatio {
    pub class_a: &'static str,
    pub class_b: &'static str,
    /// Pooled simulated ratio over the used bands: `Σ w_b·mean_A,b / Σ w_b·mean_B,b` with
    /// `w_b` the band's class-A plus class-B cell count (`None` when no band is used or the
    /// denominator is 0).
    pub simulated: Option<f64>,
    /// The same for the observed depth.
    pub observed: Option<f64>,
    /// The band-weighted mean simulated depth of class A and of class B over the used bands,
    /// metres: the numerator and denominator of `simulated` divided by `Σ w_b`.
    pub simulated_mean_m: [Option<f64>; 2],
    /// The same for the observed depth.
    pub observed_mean_m: [Option<f64>; 2],
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

/// The depth ratio of `contrast`, stratified by elevation bands and pooled over them.
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
        simulated_mean_m: [None; 2],
        observed_mean_m: [None; 2],
        cells_a: 0,
        cells_b: 0,
        cells_used: 0,
        bands: Vec::new(),
    };
    // Σ w_b·mean for class A and B, simulated and observed, and Σ w_b.
    let (mut sim, mut obs, mut w) = ([0.0; 2], [0.0; 2], 0.0);
    for (band, [a, b]) in bands {
        let mean = |sum: f64, n: usize| (n > 0).then(|| sum / n as f64);
        let sim_mean = [mean(a.sim, a.n), mean(b.sim, b.n)];
        let obs_mean = [mean(a.obs, a.n), mean(b.obs, b.n)];
        let ratio = |m: [Option<f64>; 2]| match m {
            [Some(ma), Some(mb)] if mb > 0.0 => Some(ma / mb),
            _ => None,
        };
        let used = a.n > 0 && b.n > 0;
        if used {
            let weight = (a.n + b.n) as f64;
            for k in 0..2 {
                sim[k] += weight * sim_mean[k].unwrap_or(0.0);
                obs[k] += weight * obs_mean[k].unwrap_or(0.0);
            }
            w += weight;
            out.cells_used += a.n + b.n;
        }
        out.cells_a += a.n;
        out.cells_b += b.n;
        out.bands.push(BandRatio {
            from_m: band as f64 * BAND_M,
            cells_a: a.n,
            cells_b: b.n,
            simulated_mean_m: sim_mean,
            observed_mean_m: obs_mean,
            simulated: ratio(sim_mean),
            observed: ratio(obs_mean),
            used,
        });
    }
    if w > 0.0 {
        out.simulated_mean_m = [Some(sim[0] / w), Some(sim[1] / w)];
        out.observed_mean_m = [Some(obs[0] / w), Some(obs[1] / w)];
        out.simulated = (sim[1] > 0.0).then(|| sim[0] / sim[1]);
        out.observed = (obs[1] > 0.0).then(|| obs[0] / obs[1]);
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

    #[test]
    fn a_nearly_bare_band_does_not_dominate_the_pooled_ratio() {
        // Band 0..200 m, nearly bare: 10 north cells at 0.201 m, 10 south cells at 0.01 m
        // (its own ratio 20.1). Band 200..400 m, deep: 10 north cells at 1.0 m, 10 south at
        // 2.0 m (ratio 0.5). Both bands weigh 20 cells.
        // The old mean of per-band ratios: (20·20.1 + 20·0.5) / 40 = 10.3.
        // Pooled: (20·0.201 + 20·1.0) / (20·0.01 + 20·2.0) = 24.02 / 40.2 = 0.597 51...
        let mut terrain = Vec::new();
        let mut sim = Vec::new();
        for (altitude, north, south) in [(100.0, 0.201, 0.01), (300.0, 1.0, 2.0)] {
            for _ in 0..10 {
                terrain.push(cell(altitude, 30.0, 0.0));
                sim.push(north);
                terrain.push(cell(altitude, 30.0, 180.0));
                sim.push(south);
            }
        }
        let obs: Vec<f64> = sim.iter().map(|v| 2.0 * v).collect();
        let r = contrast_ratio(Contrast::NorthSouth, &terrain, &sim, &obs, 270.0);
        let hand: f64 = (20.0 * 0.201 + 20.0 * 1.0) / (20.0 * 0.01 + 20.0 * 2.0);
        assert!((hand - 0.597_512_437_810_945_3).abs() < 1e-12);
        let s = r.simulated.unwrap();
        assert!((s - hand).abs() < 1e-12, "pooled {s}, hand {hand}");
        // Doubling every depth leaves the ratio alone.
        assert!((r.observed.unwrap() - hand).abs() < 1e-12);
        // The class means behind it: (0.201 + 1.0) / 2 and (0.01 + 2.0) / 2.
        let [ma, mb] = r.simulated_mean_m;
        assert!((ma.unwrap() - 0.6005).abs() < 1e-12 && (mb.unwrap() - 1.005).abs() < 1e-12);
        // The per-band table keeps the band ratios and the cell counts of each class.
        assert_eq!(r.bands.len(), 2);
        assert!((r.bands[0].simulated.unwrap() - 20.1).abs() < 1e-9);
        assert!((r.bands[1].simulated.unwrap() - 0.5).abs() < 1e-12);
        assert_eq!((r.bands[0].cells_a, r.bands[0].cells_b), (10, 10));
        assert_eq!((r.cells_a, r.cells_b, r.cells_used), (20, 20, 40));
        // A band whose class B is bare (mean 0) still enters the pooled sums.
        let bare: Vec<f64> = sim
            .iter()
            .zip(&terrain)
            .map(|(&v, t)| {
                if t.altitude_m < 200.0 && t.aspect_deg > 90.0 {
                    0.0
                } else {
                    v
                }
            })
            .collect();
        let r = contrast_ratio(Contrast::NorthSouth, &terrain, &bare, &bare, 270.0);
        assert_eq!(r.bands[0].simulated, None);
        assert!(r.bands[0].used);
        let hand = (20.0 * 0.201 + 20.0 * 1.0) / (20.0 * 2.0);
        assert!((r.simulated.unwrap() - hand).abs() < 1e-12);
    }
}
