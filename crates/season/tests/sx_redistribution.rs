//! Sx-driven wind redistribution (Winstral et al. 2002's maximum upwind slope, beside the
//! Cordonnier 2018 curvature term) on the real avaMal DEM at its 5 m cells and block-averaged
//! to 50 m: under a westerly, lee (east-facing) slopes end up holding clearly more snow than
//! windward (west-facing) slopes at the same altitude.

use snowscape_environment::{ShelteringParams, WindParams, sheltering_index, wind};
use snowscape_season::wind_transport::{self, WindMaps, WindScratch, WindTransportParams};
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, NodataMask, SnowLayer, surface};
use std::time::Instant;

fn avamal() -> Grid {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/dem/avaframe_avaMal/avaMal.asc"
    );
    assert!(
        std::path::Path::new(path).exists(),
        "real-DEM test input {path} is missing: this test needs /work/shared/data (AvaFrame avaMal)"
    );
    snowscape_io::read_dem(std::path::Path::new(path), &Default::default()).unwrap()
}

/// `grid` averaged over blocks of `k × k` cells (a block with fewer than half its cells
/// valid is nodata; a partial block at the east or south edge is dropped).
fn block_average(grid: &Grid, k: usize) -> Grid {
    let g = grid.geometry();
    let (w, h) = (g.width() / k, g.height() / k);
    let geo = g.resampled(w, h).unwrap();
    let mut data = vec![0.0f32; w * h];
    let mut invalid = vec![false; w * h];
    for r in 0..h {
        for c in 0..w {
            let (mut sum, mut n) = (0.0f64, 0usize);
            for rr in r * k..(r + 1) * k {
                for cc in c * k..(c + 1) * k {
                    let i = g.index(cc, rr);
                    if grid.mask().is_valid(i) {
                        sum += grid.data()[i] as f64;
                        n += 1;
                    }
                }
            }
            if 2 * n >= k * k {
                data[r * w + c] = (sum / n as f64) as f32;
            } else {
                invalid[r * w + c] = true;
            }
        }
    }
    let _ = GridGeometry::square;
    Grid::new(geo, data, NodataMask::from_invalid(invalid)).unwrap()
}

/// What one case measured.
struct Outcome {
    /// Cell-weighted mean over 200 m bands of (lee depth / windward depth).
    ratio: f64,
    /// The same with the paper's term alone (no Sx map).
    paper_ratio: f64,
    exposed_share: f64,
    sheltered_share: f64,
    sx_seconds: f64,
    bands: usize,
}

/// Lee/windward ratio of mean depths within 200 m bands, weighted by the cells of both
/// classes (bands with at least `min_cells` of each).
fn lee_windward_ratio(t: &LayeredTerrain, min_cells: usize) -> (f64, usize) {
    let g = t.geometry();
    let lo = t
        .bedrock
        .iter()
        .enumerate()
        .filter(|&(i, _)| t.mask().is_valid(i))
        .map(|(_, &z)| z)
        .fold(f32::INFINITY, f32::min);
    let mut bands: Vec<[(f64, usize); 2]> = Vec::new();
    for r in 0..g.height() {
        for c in 0..g.width() {
            let i = g.index(c, r);
            if !t.mask().is_valid(i) {
                continue;
            }
            let (gx, gy) = surface::gradient(&t.bedrock, g, t.mask(), c, r);
            let slope = gx.hypot(gy).atan().to_degrees();
            if slope <= 15.0 {
                continue;
            }
            // Aspect: the direction the slope faces (downhill), clockwise from north.
            let aspect = (-gx).atan2(-gy).to_degrees().rem_euclid(360.0);
            let class = if (45.0..=135.0).contains(&aspect) {
                0
            } else if (225.0..=315.0).contains(&aspect) {
                1
            } else {
                continue;
            };
            let band = ((t.bedrock[i] - lo) / 200.0) as usize;
            if bands.len() <= band {
                bands.resize(band + 1, [(0.0, 0); 2]);
            }
            bands[band][class].0 += t.depth_at(i) as f64;
            bands[band][class].1 += 1;
        }
    }
    let (mut num, mut den, mut used) = (0.0, 0.0, 0);
    for [(lee, nl), (wind, nw)] in bands {
        if nl < min_cells || nw < min_cells || wind <= 0.0 {
            continue;
        }
        let ratio = (lee / nl as f64) / (wind / nw as f64);
        let weight = (nl + nw) as f64;
        num += ratio * weight;
        den += weight;
        used += 1;
    }
    (num / den, used)
}

fn run(bed: Grid, min_cells: usize) -> Outcome {
    let mut t = LayeredTerrain::from_bedrock(bed);
    let geo = t.geometry().clone();
    let mask = t.mask().clone();
    let wp = WindParams {
        direction_deg: 270.0,
        ..Default::default()
    };
    let maps = wind(&t.bedrock, &geo, &mask, &wp).unwrap();
    let start = Instant::now();
    // The season's sheltering index: the 100 m and the 1 km searches.
    let sx =
        sheltering_index(&t.bedrock, &geo, &mask, 270.0, &ShelteringParams::default()).unwrap();
    let sx_seconds = start.elapsed().as_secs_f64();
    let p = WindTransportParams::default();
    let valid: Vec<usize> = (0..geo.len()).filter(|&i| mask.is_valid(i)).collect();
    let share = |f: &dyn Fn(f32) -> bool| {
        valid.iter().filter(|&&i| f(sx[i])).count() as f64 / valid.len() as f64
    };
    let exposed_share = share(&|s| (s as f64) < p.sx_redistribution.exposed_below_deg);
    let sheltered_share = share(&|s| (s as f64) > p.sx_redistribution.sheltered_above_deg);
    for &i in &valid {
        t.layer_mut(SnowLayer::Powder)[i] = 0.5;
    }
    let mut paper = t.clone();
    let air = vec![-5.0f32; geo.len()];
    let blow = |t: &mut LayeredTerrain, sx: Option<&[f32]>| {
        let before = t.snow_volume();
        let m = WindMaps {
            u: &maps.u,
            v: &maps.v,
            shadow: &maps.shadow,
            effect_surface: &maps.effect_surface,
            sx,
            terms: None,
            air_temperature: Some(&air),
        };
        let mut scratch = WindScratch::default();
        let (mut out, mut sx_eroded) = (0.0, 0.0);
        for _ in 0..20 {
            let r = wind_transport::step(&p, t, &m, &mut scratch, 0.5).unwrap();
            let moved = r.eroded - r.deposited - r.border_outflow - r.sublimated;
            assert!(moved.abs() <= 1e-6 * before);
            // Border outflow and the drift's sublimation both leave the terrain.
            out += r.border_outflow + r.sublimated;
            sx_eroded += r.sx_eroded;
        }
        t.check_invariants().unwrap();
        assert!(
            (before - out - t.snow_volume()).abs() <= 1e-5 * before,
            "budget: {before} - {out} vs {}",
            t.snow_volume()
        );
        (out, sx_eroded)
    };
    let (out, sx_eroded) = blow(&mut t, Some(&sx));
    assert!(sx_eroded > 0.0);
    blow(&mut paper, None);
    let (ratio, bands) = lee_windward_ratio(&t, min_cells);
    let (paper_ratio, _) = lee_windward_ratio(&paper, min_cells);
    eprintln!(
        "{}x{} cells of {} m: lee/windward {ratio:.3} over {bands} bands (paper term alone \
         {paper_ratio:.3}); Sx exposed {:.1} %, sheltered {:.1} %; Sx in {sx_seconds:.3} s; \
         Sx scour {sx_eroded:.0} m³, border outflow {out:.0} m³",
        geo.width(),
        geo.height(),
        geo.cell_size_x(),
        100.0 * exposed_share,
        100.0 * sheltered_share,
    );
    Outcome {
        ratio,
        paper_ratio,
        exposed_share,
        sheltered_share,
        sx_seconds,
        bands,
    }
}

#[test]
fn lee_slopes_hold_more_snow_than_windward_slopes_at_5_m_and_50_m() {
    let dem = avamal();
    let coarse = block_average(&dem, 10);
    let fine = run(dem, 200);
    let coarse = run(coarse, 10);
    for (name, o) in [("5 m", &fine), ("50 m", &coarse)] {
        assert!(o.bands >= 3, "{name}: only {} bands", o.bands);
        assert!(
            o.ratio >= 1.15,
            "{name}: lee slopes hold {:.3} x the windward depth (paper term alone {:.3})",
            o.ratio,
            o.paper_ratio
        );
        assert!(o.exposed_share > 0.1 && o.sheltered_share > 0.1, "{name}");
        assert!(o.sx_seconds < 60.0);
    }
}
