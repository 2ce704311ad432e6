use super::*;
use snowscape_terrain::{Grid, SnowLayer};

/// A plane rising eastwards at `slope_deg`, with the given layer depths everywhere.
fn slope(slope_deg: f64, depths: [f32; 4]) -> LayeredTerrain {
    let geo = GridGeometry::square(6, 5, 10.0).unwrap();
    let g = slope_deg.to_radians().tan();
    let bed = Grid::from_fn(geo, |c, _| 1000.0 + (c as f64 * 10.0 * g) as f32);
    let mut t = LayeredTerrain::from_bedrock(bed);
    for (layer, d) in SnowLayer::ALL.into_iter().zip(depths) {
        t.layer_mut(layer).fill(d);
    }
    t
}

fn share(t: &LayeredTerrain, layer: SnowLayer) -> f64 {
    let l: f64 = t.layer(layer).iter().map(|&v| v as f64).sum();
    let all: f64 = t.total_depth().iter().map(|&v| v as f64).sum();
    l / all
}

fn run(p: &StabilityParams, t: &mut LayeredTerrain, temp: f32, days: f64) -> StabilityReport {
    let temps = vec![temp; t.geometry().len()];
    let mut scratch = StabilityScratch::default();
    step(p, t, &temps, &mut scratch, days).unwrap()
}

#[test]
fn rate_interpolates_between_the_three_temperatures() {
    let p = StabilityParams::default();
    let close = |a: f32, b: f64| (a as f64 - b).abs() < 1e-6;
    assert!(close(p.rate(5.0), -0.2) && close(p.rate(12.0), -0.2));
    assert!(close(p.rate(-5.0), 0.1));
    assert!(close(p.rate(0.0), -0.05));
    assert!(close(p.rate(-12.5), 0.05));
    assert!(close(p.rate(-20.0), 0.0) && close(p.rate(-35.0), 0.0));
}

#[test]
fn cold_flat_snow_stabilises() {
    let p = StabilityParams::default();
    let mut t = slope(0.0, [0.0, 0.5, 0.5, 0.0]);
    let mut last = share(&t, SnowLayer::Unstable);
    for _ in 0..20 {
        let r = run(&p, &mut t, -5.0, 0.5);
        assert!(r.stabilised > 0.0 && r.destabilised == 0.0);
        let now = share(&t, SnowLayer::Unstable);
        assert!(now < last, "{now} >= {last}");
        last = now;
    }
    assert!(last < 0.25, "{last}");
    t.check_invariants().unwrap();
}

#[test]
fn warm_steep_snow_destabilises() {
    let p = StabilityParams::default();
    let mut t = slope(40.0, [0.0, 1.0, 0.0, 0.0]);
    let mut last = share(&t, SnowLayer::Unstable);
    for _ in 0..10 {
        let r = run(&p, &mut t, 6.0, 0.5);
        assert!(r.destabilised > 0.0 && r.stabilised == 0.0);
        let now = share(&t, SnowLayer::Unstable);
        assert!(now > last, "{now} <= {last}");
        last = now;
    }
    assert!(last > 0.4, "{last}");
}

#[test]
fn slope_slows_stabilisation_and_speeds_destabilisation() {
    let p = StabilityParams::default();
    let moved = |deg: f64, temp: f32| {
        let mut t = slope(deg, [0.0, 0.5, 0.5, 0.0]);
        let r = run(&p, &mut t, temp, 0.5);
        r.stabilised + r.destabilised
    };
    assert!(moved(0.0, -5.0) > 3.0 * moved(40.0, -5.0));
    assert!(moved(40.0, 8.0) > 3.0 * moved(0.0, 8.0));
    // The floor keeps a little of each on the unfavoured side.
    assert!(moved(60.0, -5.0) > 0.0 && moved(0.0, 8.0) > 0.0);
}

#[test]
fn powder_ages_into_stable_snow_on_flats_and_unstable_snow_on_steep_slopes() {
    let p = StabilityParams {
        k_compaction: 0.0,
        ..Default::default()
    };
    // At T_freeze the exchange is off, so only ageing acts.
    let mut flat = slope(0.0, [0.0, 0.0, 0.0, 1.0]);
    let r = run(&p, &mut flat, -20.0, 2.0);
    let expect = 1.0 - 1.0 / (1.0 + 0.3);
    assert!((flat.layer(SnowLayer::Powder)[7] as f64 - (1.0 - expect)).abs() < 1e-6);
    assert!(r.aged_to_unstable == 0.0 && r.aged_to_stable > 0.0);
    let mut steep = slope(50.0, [0.0, 0.0, 0.0, 1.0]);
    let r = run(&p, &mut steep, -20.0, 2.0);
    assert!(r.aged_to_stable.abs() < 1e-9 && r.aged_to_unstable > 0.0);
    let before = 1.0;
    for _ in 0..60 {
        run(&p, &mut flat, -20.0, 0.5);
    }
    assert!((flat.layer(SnowLayer::Powder)[7] as f64) < 0.02 * before);
}

#[test]
fn compaction_grows_with_overburden_and_the_volume_budget_closes() {
    let p = StabilityParams::default();
    let compacted_of = |depths: [f32; 4]| {
        let mut t = slope(0.0, depths);
        let before = t.snow_volume();
        let r = run(&p, &mut t, -30.0, 1.0);
        let after = t.snow_volume();
        let budget = before - r.volume_change().removed - after;
        assert!(budget.abs() < 1e-5 * before, "budget off by {budget}");
        assert!((r.densification - 0.4 * r.compacted).abs() < 1e-6 * r.compacted);
        r.compacted / t.layer(SnowLayer::Stable).iter().sum::<f32>() as f64
    };
    let shallow = compacted_of([0.0, 0.5, 0.0, 0.0]);
    let deep = compacted_of([0.0, 0.5, 1.5, 0.0]);
    assert!(shallow > 0.0 && deep > 3.0 * shallow, "{shallow} {deep}");
}

#[test]
fn budget_closes_over_a_mixed_run_and_nodata_stays_bare() {
    let p = StabilityParams::default();
    let geo = GridGeometry::square(9, 7, 5.0).unwrap();
    let mut invalid = vec![false; geo.len()];
    invalid[20] = true;
    let bed = Grid::new(
        geo.clone(),
        (0..geo.len())
            .map(|i| ((i * 7919) % 23) as f32 * 1.5)
            .collect(),
        NodataMask::from_invalid(invalid),
    )
    .unwrap();
    let mut t = LayeredTerrain::from_bedrock(bed);
    for (k, layer) in SnowLayer::ALL.into_iter().enumerate() {
        for i in 0..geo.len() {
            if i != 20 {
                t.layer_mut(layer)[i] = 0.1 + 0.05 * ((i + k) % 5) as f32;
            }
        }
    }
    let temps: Vec<f32> = (0..geo.len()).map(|i| -25.0 + (i % 35) as f32).collect();
    let mut scratch = StabilityScratch::default();
    for _ in 0..10 {
        let before = t.snow_volume();
        let r = step(&p, &mut t, &temps, &mut scratch, 0.5).unwrap();
        let budget = before - r.volume_change().removed - t.snow_volume();
        assert!(budget.abs() < 1e-5 * before, "{budget}");
        t.check_invariants().unwrap();
    }
}

#[test]
fn bad_parameters_are_rejected() {
    let bad = StabilityParams {
        t_cool: 10.0,
        ..Default::default()
    };
    assert!(bad.validate().is_err());
    let bad = StabilityParams {
        compacted_density_ratio: 0.0,
        ..Default::default()
    };
    let e = bad.validate().unwrap_err();
    assert!(e.to_string().contains("compacted_density_ratio = 0"), "{e}");
    assert!(StabilityParams::default().validate().is_ok());
    let json = r#"{"k_warm": 0.3}"#;
    let p: StabilityParams = serde_json::from_str(json).unwrap();
    assert_eq!(p.k_warm, 0.3);
    assert!(serde_json::from_str::<StabilityParams>(r#"{"k_wram": 1}"#).is_err());
}
