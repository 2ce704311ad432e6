//! The whole precompute: deterministic for any thread count, finite everywhere (nodata
//! included), stored under stable names, and its parameter errors are typed.

mod common;

use common::{rough, terrain};
use snowscape_environment::{
    EnvironmentError, EnvironmentParams, map_names, precompute, store_maps,
};
use snowscape_terrain::{Grid, LayeredTerrain, NodataMask};

fn small_params() -> EnvironmentParams {
    let mut p = EnvironmentParams::default();
    p.sun.num_days = 60;
    p.sun.day_step = 20;
    p.sky.directions = 12;
    p
}

/// Rough terrain with a nodata hole and a nodata border strip (NaN under the mask).
fn holey() -> (Vec<f32>, snowscape_terrain::GridGeometry, NodataMask) {
    let (mut z, g) = terrain(90, 70, 12.0, rough);
    let mut invalid = vec![false; z.len()];
    for r in 0..70 {
        for c in 0..90 {
            let hole = (c as f64 - 40.0).hypot(r as f64 - 30.0) < 8.0;
            if hole || c < 3 {
                invalid[r * 90 + c] = true;
                z[r * 90 + c] = f32::NAN;
            }
        }
    }
    (z, g, NodataMask::from_invalid(invalid))
}

#[test]
fn same_bytes_on_one_and_three_threads_and_no_nan_with_nodata() {
    let (z, g, mask) = holey();
    let p = small_params();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| precompute(&z, &g, &mask, &p).unwrap())
    };
    let a = run(1);
    let b = run(3);
    for ((name, x), (_, y)) in a.named().iter().zip(b.named().iter()) {
        let same = x
            .iter()
            .zip(y.iter())
            .all(|(u, v)| u.to_bits() == v.to_bits());
        assert!(same, "{name} differs between 1 and 3 threads");
        for (i, v) in x.iter().enumerate() {
            assert!(v.is_finite(), "{name}[{i}] = {v}");
            if !mask.is_valid(i) {
                assert_eq!(*v, 0.0, "{name} on nodata cell {i}");
            }
        }
    }
    assert_eq!(a.wind_stats, b.wind_stats);
    // Sanity of magnitudes on valid cells.
    let valid: Vec<usize> = (0..z.len()).filter(|&i| mask.is_valid(i)).collect();
    let k_pi = (p.sky.k_sky * std::f64::consts::PI) as f32;
    assert!(
        valid
            .iter()
            .all(|&i| a.sky[i] > 0.0 && a.sky[i] <= k_pi * (1.0 + 1e-6))
    );
    assert!(valid.iter().all(|&i| a.sky_view_factor[i] <= 1.0 + 1e-6));
    assert!(valid.iter().all(|&i| a.sun[i] >= 0.0 && a.sun[i] < 24.0));
    assert!(valid.iter().any(|&i| a.wind_shadow[i] == 1.0));
}

#[test]
fn maps_are_stored_under_stable_names() {
    let (z, g) = terrain(30, 20, 10.0, rough);
    let all = NodataMask::all_valid();
    let maps = precompute(&z, &g, &all, &small_params()).unwrap();
    let mut t = LayeredTerrain::from_bedrock(Grid::new(g.clone(), z.clone(), all).unwrap());
    store_maps(&maps, &mut t).unwrap();
    for name in [
        "sun",
        "sky",
        "bounce",
        "temperature",
        "wind_u",
        "wind_v",
        "wind_shadow",
    ] {
        assert_eq!(t.maps[name].len(), 600, "{name}");
    }
    assert_eq!(t.maps[map_names::TEMPERATURE], maps.temperature);
    // A terrain of another size is refused with a typed error.
    let other = Grid::filled(
        snowscape_terrain::GridGeometry::square(5, 5, 1.0).unwrap(),
        0.0,
    );
    let mut t = LayeredTerrain::from_bedrock(other);
    assert!(matches!(
        store_maps(&maps, &mut t),
        Err(EnvironmentError::Terrain(_))
    ));
}

#[test]
fn bad_inputs_are_typed_errors() {
    let (mut z, g) = terrain(10, 10, 10.0, rough);
    let all = NodataMask::all_valid();
    let p = EnvironmentParams::default();
    assert!(matches!(
        precompute(&z[..50], &g, &all, &p),
        Err(EnvironmentError::LengthMismatch { actual: 50, .. })
    ));
    z[23] = f32::INFINITY;
    assert!(matches!(
        precompute(&z, &g, &all, &p),
        Err(EnvironmentError::NonFiniteHeight { col: 3, row: 2, .. })
    ));
    let mut p = EnvironmentParams::default();
    p.sky.directions = 2;
    assert!(matches!(
        precompute(&z, &g, &all, &p),
        Err(EnvironmentError::InvalidParameter {
            name: "sky.directions",
            ..
        })
    ));
}
