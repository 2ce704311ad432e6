//! Shared by the real-terrain behaviour tests: the real DEMs (a missing file fails the test
//! loudly), block resampling, slope and aspect classes, and depth ratios compared within
//! 200 m elevation bands (so altitude does not masquerade as aspect or slope).
#![allow(dead_code)]

use snowscape_terrain::{Grid, GridGeometry, NodataMask};
use std::path::PathBuf;

/// A DEM under `../shared/data/dem/` (relative to the repository root).
pub fn shared_dem(relative: &str) -> Grid {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/dem")
        .join(relative);
    assert!(
        path.exists(),
        "{} is missing: these tests need the shared data folder beside the checkout",
        path.display()
    );
    snowscape_io::read_dem(&path, &snowscape_io::ReadOptions::default())
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
}

/// The mean of each `k × k` block of valid cells (nodata where a block has none), on a grid
/// with the same origin and CRS and `k` times the cell size.
pub fn block_average(grid: &Grid, k: usize) -> Grid {
    let g = grid.geometry();
    let (w, h) = (g.width() / k, g.height() / k);
    let geo = g.resampled(w, h).unwrap();
    let mut values = vec![0.0f32; w * h];
    let mut invalid = vec![false; w * h];
    for r in 0..h {
        for c in 0..w {
            let (mut sum, mut n) = (0.0f64, 0usize);
            for dr in 0..k {
                for dc in 0..k {
                    let i = g.index(c * k + dc, r * k + dr);
                    if grid.mask().is_valid(i) {
                        sum += grid.data()[i] as f64;
                        n += 1;
                    }
                }
            }
            if n * 2 > k * k {
                values[r * w + c] = (sum / n as f64) as f32;
            } else {
                invalid[r * w + c] = true;
            }
        }
    }
    Grid::new(geo, values, NodataMask::from_invalid(invalid)).unwrap()
}

/// Slope (degrees) and aspect (degrees clockwise from north, the direction the slope faces)
/// of every valid interior cell with valid neighbours; `None` elsewhere.
pub fn slope_aspect(grid: &Grid) -> Vec<Option<(f32, f32)>> {
    let g: &GridGeometry = grid.geometry();
    let (w, h) = (g.width(), g.height());
    let z = grid.data();
    let ok = |i: usize| grid.mask().is_valid(i);
    (0..w * h)
        .map(|i| {
            let (c, r) = (i % w, i / w);
            if c == 0 || r == 0 || c + 1 == w || r + 1 == h {
                return None;
            }
            if ![i, i - 1, i + 1, i - w, i + w].into_iter().all(ok) {
                return None;
            }
            let dzdx = (z[i + 1] - z[i - 1]) as f64 / (2.0 * g.cell_size_x());
            // Row 0 is north: north is row − 1.
            let dzdn = (z[i - w] - z[i + w]) as f64 / (2.0 * g.cell_size_y());
            let slope = dzdx.hypot(dzdn).atan().to_degrees();
            // The slope faces down the gradient.
            let aspect = (-dzdx).atan2(-dzdn).to_degrees().rem_euclid(360.0);
            Some((slope as f32, aspect as f32))
        })
        .collect()
}

/// Whether `aspect` lies within `half` degrees of `centre`.
pub fn facing(aspect: f32, centre: f32, half: f32) -> bool {
    let d = (aspect - centre).rem_euclid(360.0);
    d.min(360.0 - d) <= half
}

/// Mean depth of class `a` over class `b` compared within 200 m elevation bands: the ratio of
/// the band means of `a` and of `b`, each averaged over the bands with at least `min_cells`
/// cells of both classes with the same weights (the smaller count), so a band where `b` is
/// bare counts; and the per-band (band floor, ratio, cells a, cells b).
pub fn band_ratio(
    depth: &[f32],
    bedrock: &Grid,
    classes: &[Option<(f32, f32)>],
    a: impl Fn(f32, f32) -> bool,
    b: impl Fn(f32, f32) -> bool,
    min_cells: usize,
) -> (f64, Vec<(i32, f64, usize, usize)>) {
    band_ratio_of(depth, bedrock, classes, a, b, min_cells, false)
}

/// [`band_ratio`] with the band medians instead of the means (robust to the few metres-deep
/// sluff and avalanche cones at the foot of faces, which dominate a band's mean).
pub fn band_median_ratio(
    depth: &[f32],
    bedrock: &Grid,
    classes: &[Option<(f32, f32)>],
    a: impl Fn(f32, f32) -> bool,
    b: impl Fn(f32, f32) -> bool,
    min_cells: usize,
) -> (f64, Vec<(i32, f64, usize, usize)>) {
    band_ratio_of(depth, bedrock, classes, a, b, min_cells, true)
}

fn band_ratio_of(
    depth: &[f32],
    bedrock: &Grid,
    classes: &[Option<(f32, f32)>],
    a: impl Fn(f32, f32) -> bool,
    b: impl Fn(f32, f32) -> bool,
    min_cells: usize,
    median: bool,
) -> (f64, Vec<(i32, f64, usize, usize)>) {
    use std::collections::BTreeMap;
    let mut bands: BTreeMap<i32, [Vec<f32>; 2]> = BTreeMap::new();
    for (i, cls) in classes.iter().enumerate() {
        let Some((s, asp)) = *cls else { continue };
        let band = (bedrock.data()[i] / 200.0).floor() as i32 * 200;
        let e = bands.entry(band).or_default();
        if a(s, asp) {
            e[0].push(depth[i]);
        }
        if b(s, asp) {
            e[1].push(depth[i]);
        }
    }
    let stat = |v: &mut Vec<f32>| -> f64 {
        if median {
            v.sort_by(f32::total_cmp);
            v[v.len() / 2] as f64
        } else {
            v.iter().map(|&d| d as f64).sum::<f64>() / v.len() as f64
        }
    };
    let mut detail = Vec::new();
    let (mut num, mut den) = (0.0, 0.0);
    for (band, [mut va, mut vb]) in bands {
        let (na, nb) = (va.len(), vb.len());
        if na < min_cells || nb < min_cells {
            continue;
        }
        let (ma, mb) = (stat(&mut va), stat(&mut vb));
        let weight = na.min(nb) as f64;
        num += ma * weight;
        den += mb * weight;
        detail.push((band, ma / mb, na, nb));
    }
    (if den > 0.0 { num / den } else { f64::NAN }, detail)
}

/// One stratum of [`band_slope_ratio`]: band floor (m), slope class floor (°), ratio, cells of
/// each aspect.
pub type Stratum = (i32, i32, f64, usize, usize);

/// [`band_ratio`] within strata of elevation band × slope class (15-30°, 30-45°, 45-60°): the
/// aspect contrast at the same altitude *and* slope. On real terrain the faces of one aspect
/// are often steeper than those of the other (avaMal's north faces are), and steeper faces
/// hold less snow whatever their aspect, so the band means alone mix slope into aspect.
pub fn band_slope_ratio(
    depth: &[f32],
    bedrock: &Grid,
    classes: &[Option<(f32, f32)>],
    a_aspect: f32,
    b_aspect: f32,
    min_cells: usize,
) -> (f64, Vec<Stratum>) {
    use std::collections::BTreeMap;
    let mut strata: BTreeMap<(i32, i32), [Vec<f32>; 2]> = BTreeMap::new();
    for (i, cls) in classes.iter().enumerate() {
        let Some((s, asp)) = *cls else { continue };
        if !(15.0..60.0).contains(&s) {
            continue;
        }
        let band = (bedrock.data()[i] / 200.0).floor() as i32 * 200;
        let class = 15 + 15 * ((s - 15.0) / 15.0).floor() as i32;
        let e = strata.entry((band, class)).or_default();
        if facing(asp, a_aspect, 45.0) {
            e[0].push(depth[i]);
        }
        if facing(asp, b_aspect, 45.0) {
            e[1].push(depth[i]);
        }
    }
    let mean = |v: &[f32]| v.iter().map(|&d| d as f64).sum::<f64>() / v.len() as f64;
    let (mut num, mut den) = (0.0, 0.0);
    let mut detail = Vec::new();
    for ((band, class), [va, vb]) in strata {
        let (na, nb) = (va.len(), vb.len());
        if na < min_cells || nb < min_cells {
            continue;
        }
        let (ma, mb) = (mean(&va), mean(&vb));
        let weight = na.min(nb) as f64;
        num += ma * weight;
        den += mb * weight;
        detail.push((band, class, ma / mb, na, nb));
    }
    (if den > 0.0 { num / den } else { f64::NAN }, detail)
}
