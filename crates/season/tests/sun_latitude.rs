//! Issue 47: the sun, not the air temperature alone, places the snow. On avaMal (5 m) in the
//! default 100-day winter from 1 December (natural avalanches on, as `snowscape run`), within
//! 200 m elevation bands on slopes steeper than 15°: at 37.6° N (the latitude of the high
//! Sierra) north faces hold at least 1.3 times the snow of south faces at day 100 and at least
//! twice at the end of April, and depth follows altitude less than it did (Spearman ρ of the
//! spring state below 0.8); at the DEM's own 47° N the contrast is at least 1.15 at day 100.

mod support;

use snowscape_season::scenario::Scenario;
use snowscape_season::winter::Winter;
use snowscape_terrain::{Grid, LayeredTerrain};
use support::{band_ratio, facing, shared_dem, slope_aspect};

/// The default winter on avaMal at `latitude`, run to `days`.
fn winter(bedrock: &Grid, latitude: f64, days: f64) -> Winter {
    let s = Scenario {
        days,
        latitude_deg: Some(latitude),
        ..Scenario::default()
    };
    let mut w = Winter::new(s, LayeredTerrain::from_bedrock(bedrock.clone())).unwrap();
    w.run_until(days.min(100.0)).unwrap();
    w
}

/// North over south faces steeper than 15°: the 200 m bands' means with at least 50 cells of
/// each, averaged with the smaller count as weight ([`support::band_ratio`]; the command
/// line's `scripts/aspect_ratio.py` sums the band means instead).
fn north_south(w: &Winter, bedrock: &Grid, classes: &[Option<(f32, f32)>], label: &str) -> f64 {
    let depth = w.terrain.total_depth();
    let (ratio, detail) = band_ratio(
        &depth,
        bedrock,
        classes,
        |s, a| s > 15.0 && facing(a, 0.0, 45.0),
        |s, a| s > 15.0 && facing(a, 180.0, 45.0),
        50,
    );
    eprintln!("{label}: north/south {ratio:.3} {detail:?}");
    ratio
}

/// Spearman rank correlation of depth with altitude over the snow-covered valid cells.
fn depth_altitude_rho(w: &Winter, bedrock: &Grid) -> f64 {
    let depth = w.terrain.total_depth();
    let (d, z): (Vec<f64>, Vec<f64>) = (0..depth.len())
        .filter(|&i| bedrock.mask().is_valid(i) && depth[i] > 0.0)
        .map(|i| (depth[i] as f64, bedrock.data()[i] as f64))
        .unzip();
    let rank = |v: &[f64]| {
        let mut idx: Vec<usize> = (0..v.len()).collect();
        idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
        let mut r = vec![0.0; v.len()];
        for (k, &i) in idx.iter().enumerate() {
            r[i] = k as f64;
        }
        r
    };
    let (rd, rz) = (rank(&d), rank(&z));
    let n = rd.len() as f64;
    let mean = (n - 1.0) / 2.0;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in rd.iter().zip(&rz) {
        sxy += (a - mean) * (b - mean);
        sxx += (a - mean) * (a - mean);
        syy += (b - mean) * (b - mean);
    }
    sxy / (sxx * syy).sqrt()
}

#[test]
fn at_the_sierras_latitude_north_faces_keep_the_snow_south_faces_lose() {
    let mal = shared_dem("avaframe_avaMal/avaMal.asc");
    let classes = slope_aspect(&mal);
    let mut w = winter(&mal, 37.6, 151.0);
    let mid_winter = north_south(&w, &mal, &classes, "37.6° N, day 100");
    assert!(mid_winter >= 1.3, "day 100: north/south {mid_winter} < 1.3");
    w.run_until(151.0).unwrap();
    let spring = north_south(&w, &mal, &classes, "37.6° N, 30 April");
    assert!(spring >= 2.0, "30 April: north/south {spring} < 2");
    let rho = depth_altitude_rho(&w, &mal);
    eprintln!("37.6° N, 30 April: Spearman ρ(depth, altitude) {rho:.3}");
    assert!(rho < 0.8, "ρ(depth, altitude) {rho} ≥ 0.8");
    let b = w.budget();
    let store = w.terrain.snow_volume();
    assert!(
        (store - b.expected_store()).abs() <= 1e-5 * (b.initial_store + b.snowfall + b.refreeze),
        "budget: store {store} expected {} ({b:?})",
        b.expected_store()
    );
}

#[test]
fn at_the_alps_latitude_north_faces_hold_more_snow_in_mid_winter() {
    let mal = shared_dem("avaframe_avaMal/avaMal.asc");
    let classes = slope_aspect(&mal);
    let w = winter(&mal, 47.0, 100.0);
    let ratio = north_south(&w, &mal, &classes, "47° N, day 100");
    assert!(ratio >= 1.15, "day 100: north/south {ratio} < 1.15");
}
