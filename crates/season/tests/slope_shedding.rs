//! Slope shedding (SnowSlide, Bernhardt & Schulz 2010) on the real avaMal DEM: after 1 m of
//! snow everywhere and one shedding step, rock faces steeper than 60° hold little and the
//! 20-35° slopes keep their cover.

use snowscape_season::slope_shedding::{self, SheddingParams, SheddingScratch};
use snowscape_terrain::{LayeredTerrain, SnowLayer, surface};
use std::time::Instant;

fn avamal() -> LayeredTerrain {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/dem/avaframe_avaMal/avaMal.asc"
    );
    assert!(
        std::path::Path::new(path).exists(),
        "real-DEM test input {path} is missing: this test needs /work/shared/data (AvaFrame avaMal)"
    );
    let dem = snowscape_io::read_dem(std::path::Path::new(path), &Default::default()).unwrap();
    LayeredTerrain::from_bedrock(dem)
}

#[test]
fn avamal_rock_faces_shed_onto_gentler_ground() {
    let mut t = avamal();
    let slopes: Vec<f32> = surface::slopes(&t.bedrock, t.geometry(), t.mask())
        .into_iter()
        .map(f32::to_degrees)
        .collect();
    let valid: Vec<usize> = (0..t.geometry().len())
        .filter(|&i| t.mask().is_valid(i))
        .collect();
    for &i in &valid {
        t.layer_mut(SnowLayer::Powder)[i] = 1.0;
    }
    let before = t.snow_volume();
    let start = Instant::now();
    let r = slope_shedding::step(
        &SheddingParams::default(),
        &mut t,
        &mut SheddingScratch::default(),
        1.0,
    )
    .unwrap();
    let elapsed = start.elapsed();
    t.check_invariants().unwrap();
    let mean = |lo: f32, hi: f32| {
        let cells: Vec<usize> = valid
            .iter()
            .copied()
            .filter(|&i| slopes[i] > lo && slopes[i] <= hi)
            .collect();
        let sum: f64 = cells.iter().map(|&i| t.depth_at(i) as f64).sum();
        (sum / cells.len().max(1) as f64, cells.len())
    };
    let (steep, n_steep) = mean(60.0, 90.0);
    let (mid, n_mid) = mean(20.0, 35.0);
    let (gentle, n_gentle) = mean(0.0, 20.0);
    eprintln!(
        "avaMal {}x{}: {r:?} in {elapsed:.2?}; mean depth > 60°: {steep:.3} m ({n_steep} cells), \
         20-35°: {mid:.3} m ({n_mid}), < 20°: {gentle:.3} m ({n_gentle})",
        t.geometry().width(),
        t.geometry().height()
    );
    assert!(n_steep > 100, "only {n_steep} cells steeper than 60°");
    assert!(
        steep <= 0.3 * mid,
        "faces > 60° hold {steep:.3} m, 20-35° slopes {mid:.3} m"
    );
    assert!(mid >= 1.0 && gentle >= 1.0, "{mid} {gentle}");
    assert_eq!(r.unsettled_cells, 0);
    assert!(
        (before - r.border_outflow_m3 - t.snow_volume()).abs() < 1e-6 * before,
        "budget"
    );
    assert!((r.moved_m3 - r.received_m3 - r.border_outflow_m3).abs() < 1e-6 * r.moved_m3);
}
