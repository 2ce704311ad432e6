//! Tests of the procedural alpine terrain: determinism, geometry, altitude range, slopes,
//! parameter errors.

use super::*;
use crate::surface;

fn params(size: usize, seed: u64) -> AlpineParams {
    AlpineParams {
        size,
        seed,
        ..AlpineParams::default()
    }
}

fn bytes(grid: &Grid) -> Vec<u8> {
    grid.data().iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn in_pool(threads: usize, p: &AlpineParams) -> Grid {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
        .install(|| alpine(p).expect("valid parameters"))
}

#[test]
fn identical_bytes_for_any_thread_count_and_call() {
    let p = params(256, 7);
    let one = bytes(&in_pool(1, &p));
    let three = bytes(&in_pool(3, &p));
    let again = bytes(&alpine(&p).unwrap());
    assert_eq!(one, three);
    assert_eq!(one, again);
}

#[test]
fn different_seeds_give_different_terrain() {
    let a = alpine(&params(128, 1)).unwrap();
    let b = alpine(&params(128, 2)).unwrap();
    let differing = a
        .data()
        .iter()
        .zip(b.data())
        .filter(|(x, y)| (*x - *y).abs() > 1.0)
        .count();
    assert!(
        differing > a.data().len() / 2,
        "only {differing} cells differ"
    );
}

#[test]
fn geometry_follows_size_and_cell_size() {
    let p = AlpineParams {
        size: 200,
        cell_size: 25.0,
        ..AlpineParams::default()
    };
    let g = alpine(&p).unwrap();
    assert_eq!((g.geometry().width(), g.geometry().height()), (200, 200));
    assert_eq!(g.geometry().cell_size_x(), 25.0);
    assert_eq!(g.geometry().cell_size_y(), 25.0);
    assert!(!g.mask().has_nodata());
}

#[test]
fn altitudes_span_the_relief_and_are_finite() {
    // 512 cells of 20 m: 10 km, enough extent for the full relief.
    let p = AlpineParams {
        size: 512,
        cell_size: 20.0,
        ..AlpineParams::default()
    };
    let g = alpine(&p).unwrap();
    g.check_finite("alpine").unwrap();
    let (lo, hi) = g.value_range().unwrap();
    let (base, top) = (p.base_altitude as f32, (p.base_altitude + p.relief) as f32);
    assert!(lo >= base && hi <= top, "{lo}..{hi} outside {base}..{top}");
    assert!(hi - lo > 0.7 * p.relief as f32, "relief only {}", hi - lo);
}

#[test]
fn small_extents_get_proportionally_less_relief() {
    let p = params(128, 3);
    assert!((p.effective_relief() - 0.18 * 1280.0).abs() < 1e-9);
    let (lo, hi) = alpine(&p).unwrap().value_range().unwrap();
    assert!(hi - lo <= p.effective_relief() as f32 + 0.01);
    assert!(lo >= p.base_altitude as f32);
}

/// Share of cells (in %) whose slope in degrees lies in `range`.
fn slope_share(g: &Grid, range: std::ops::Range<f32>) -> f64 {
    let slopes = surface::slopes(g.data(), g.geometry(), g.mask());
    let n = slopes
        .iter()
        .filter(|s| range.contains(&s.to_degrees()))
        .count();
    100.0 * n as f64 / slopes.len() as f64
}

#[test]
fn slopes_include_avalanche_faces_and_flat_floors() {
    for seed in [1, 2] {
        let g = alpine(&params(512, seed)).unwrap();
        let faces = slope_share(&g, 30.0..45.0);
        let flat = slope_share(&g, 0.0..10.0);
        let steep = slope_share(&g, 30.0..90.0);
        assert!(faces > 15.0, "seed {seed}: {faces:.1} % of 30-45° faces");
        assert!(flat > 3.0, "seed {seed}: {flat:.1} % below 10°");
        assert!(steep < 80.0, "seed {seed}: {steep:.1} % above 30°");
    }
}

#[test]
fn cliff_bands_steepen_the_steepest_ground() {
    let with = alpine(&params(256, 5)).unwrap();
    let without = alpine(&AlpineParams {
        cliff_band_height: 0.0,
        ..params(256, 5)
    })
    .unwrap();
    assert!(slope_share(&with, 50.0..90.0) > slope_share(&without, 50.0..90.0));
}

#[test]
fn invalid_parameters_are_errors_with_their_values() {
    let e = alpine(&params(1, 0)).unwrap_err();
    assert!(matches!(e, TerrainError::InvalidSize { width: 1, .. }));
    let e = alpine(&params(20_000, 0)).unwrap_err();
    assert!(matches!(e, TerrainError::InvalidSize { width: 20_000, .. }));
    let e = alpine(&AlpineParams {
        cell_size: 0.0,
        ..params(64, 0)
    })
    .unwrap_err();
    assert!(matches!(e, TerrainError::InvalidCellSize { value, .. } if value == 0.0));
    let e = alpine(&AlpineParams {
        relief: f64::NAN,
        ..params(64, 0)
    })
    .unwrap_err();
    assert!(matches!(e, TerrainError::InvalidParameter { value, .. } if value.is_nan()));
    let e = alpine(&AlpineParams {
        plateau_share: 1.5,
        ..params(64, 0)
    })
    .unwrap_err();
    assert!(matches!(e, TerrainError::InvalidParameter { value, .. } if value == 1.5));
}

#[test]
fn tiny_grids_are_valid() {
    for size in [2, 3, 17] {
        let g = alpine(&params(size, 4)).unwrap();
        g.check_finite("tiny alpine").unwrap();
    }
}
