//! Compaction (mass kept, one class per pass), the recent-skier map, triggers.

mod common;

use snowscape_skiers::{
    SkiArea, SkiParams, SkiScratch, Terminus, compact_cell, snow_water_equivalent, step,
    trigger_probability,
};
use snowscape_terrain::SnowLayer;

#[test]
fn compaction_takes_unstable_first_then_stable_and_keeps_mass() {
    let params = SkiParams::default();
    let mut t = common::terrain(3, 1, 10.0, 1.0, 0.05, |_, _| 0.0);
    t.layer_mut(SnowLayer::Powder).fill(0.2);
    let swe0 = snow_water_equivalent(&params, &t);
    // 0.12 m to pack: 0.05 from unstable (→ 0.05 of stable at equal density), 0.07 from the
    // stable snow as it was (→ 0.07·300/500 = 0.042 of compacted).
    let c = compact_cell(&params, &mut t, 1, 0.12, 100.0);
    assert!((t.layer(SnowLayer::Unstable)[1] - 0.0).abs() < 1e-7);
    assert!((t.layer(SnowLayer::Stable)[1] - (1.0 - 0.07 + 0.05)).abs() < 1e-6);
    assert!((t.layer(SnowLayer::Compacted)[1] - 0.042).abs() < 1e-6);
    assert_eq!(t.layer(SnowLayer::Powder)[1], 0.2, "powder is left alone");
    assert!((c.unstable_to_stable_m3 - 5.0).abs() < 1e-4);
    assert!((c.stable_to_compacted_m3 - 7.0).abs() < 1e-4);
    assert!((c.densification_m3 - 0.07 * 0.4 * 100.0).abs() < 1e-4);
    let swe1 = snow_water_equivalent(&params, &t);
    assert!((swe1 - swe0).abs() < 1e-6 * swe0, "{swe0} -> {swe1}");
    // Thickness lost equals the reported densification.
    let depth_loss = 1.25 - f64::from(t.depth_at(1));
    assert!((depth_loss * 100.0 - c.densification_m3).abs() < 1e-3);
    // Unstable snow left: only unstable moves.
    let mut t2 = common::terrain(1, 1, 10.0, 1.0, 0.5, |_, _| 0.0);
    compact_cell(&params, &mut t2, 0, 0.1, 100.0);
    assert!((t2.layer(SnowLayer::Unstable)[0] - 0.4).abs() < 1e-6);
    assert_eq!(t2.layer(SnowLayer::Compacted)[0], 0.0);
}

#[test]
fn skiing_a_slope_keeps_snow_water_equivalent_and_packs_the_track() {
    let params = SkiParams::default();
    let mut t = common::plane(20, 60, 10.0, 35.0);
    let swe0 = snow_water_equivalent(&params, &t);
    let vol0 = t.snow_volume();
    let mut area = SkiArea::new(
        &params,
        &t,
        Terminus::BelowAltitude(f64::from(t.surface()[59 * 20]) + 1.0),
        3,
    )
    .unwrap();
    area.spawn_weighted(&params, &t, 30).unwrap();
    let mut scratch = SkiScratch::default();
    let mut total = snowscape_skiers::Compaction::default();
    while !area.skiers().is_empty() {
        let r = step(&params, &mut area, &mut t, &mut scratch, 1.0).unwrap();
        total += r.compaction;
    }
    let swe1 = snow_water_equivalent(&params, &t);
    assert!((swe1 - swe0).abs() < 1e-5 * swe0, "SWE {swe0} -> {swe1}");
    assert!(total.unstable_to_stable_m3 > 0.0);
    // Volume lost is the reported densification (unstable→stable keeps volume at equal
    // density, so it all comes from stable→compacted here).
    let lost = vol0 - t.snow_volume();
    assert!(
        (lost - total.densification_m3).abs() < 1e-3 * lost.max(1.0),
        "{lost} {}",
        total.densification_m3
    );
    // Packed snow only under tracks: every cell with less unstable snow was entered.
    let entered: std::collections::HashSet<usize> = area
        .finished_tracks()
        .iter()
        .flat_map(|tr| tr.cells.iter().copied())
        .collect();
    for (i, &u) in t.layer(SnowLayer::Unstable).iter().enumerate() {
        if u < 0.5 {
            assert!(entered.contains(&i), "cell {i} packed without a skier");
        }
    }
    t.check_invariants().unwrap();
}

#[test]
fn trigger_probability_rule() {
    let p = SkiParams::default();
    let steep = 38f64.to_radians();
    assert_eq!(trigger_probability(&p, 0.0, steep, 0.0, 10.0), 0.0);
    assert_eq!(
        trigger_probability(&p, 1.0, 25f64.to_radians(), 5.0, 10.0),
        0.0
    );
    assert_eq!(trigger_probability(&p, 1.0, steep, 0.0, 0.0), 0.0);
    // Per 10 m of track: the parameter itself, scaled by the load, raised by recent passes.
    assert!((trigger_probability(&p, 0.3, steep, 0.0, 10.0) - 0.05).abs() < 1e-12);
    assert!((trigger_probability(&p, 0.15, steep, 0.0, 10.0) - 0.025).abs() < 1e-12);
    assert!((trigger_probability(&p, 0.6, steep, 2.0, 10.0) - 0.15).abs() < 1e-12);
    assert_eq!(trigger_probability(&p, 1.0, steep, 1e6, 3.0), 1.0);
    // Grid independence: two 5 m passes are as risky as one 10 m pass; 20 m is 1 − 0.95².
    let half = trigger_probability(&p, 0.5, steep, 0.0, 5.0);
    assert!((1.0 - (1.0 - half).powi(2) - 0.05).abs() < 1e-12);
    let double = trigger_probability(&p, 0.5, steep, 0.0, 20.0);
    assert!((double - (1.0 - 0.95f64.powi(2))).abs() < 1e-12);
}

#[test]
fn recent_skiers_decay_and_raise_release_factor_and_triggers_happen_on_steep_unstable_snow() {
    let params = SkiParams {
        trigger_probability: 0.2,
        ..SkiParams::default()
    };
    let mut t = common::plane(10, 40, 10.0, 38.0);
    let bottom = f64::from(t.surface()[39 * 10]) + 1.0;
    let mut area = SkiArea::new(&params, &t, Terminus::BelowAltitude(bottom), 9).unwrap();
    for k in 0..5 {
        area.spawn_at(&params, &t, 45.0 + k as f64, 395.0).unwrap();
    }
    let mut scratch = SkiScratch::default();
    let mut triggers = Vec::new();
    while !area.skiers().is_empty() {
        let r = step(&params, &mut area, &mut t, &mut scratch, 1.0).unwrap();
        triggers.extend(r.triggers);
    }
    assert!(
        !triggers.is_empty(),
        "5 skiers down 40 cells of 38° with 0.5 m unstable"
    );
    for tr in &triggers {
        assert!(tr.slope_deg >= 30.0 && tr.unstable_m > 0.0 && tr.probability > 0.0);
        assert!((0.0..=100.0).contains(&tr.x) && (0.0..=400.0).contains(&tr.y));
    }
    let recent = area.recent_skiers(&params);
    let start = 4; // Cell (col 4, row 0) holds all five starts.
    assert!(
        recent[start] > 4.9 && recent[start] <= 5.0,
        "{}",
        recent[start]
    );
    assert!(area.release_factor(&params, &t, start) > 5.0);
    // A day later the count has decayed by e.
    area.time_s += params.recent_decay_s;
    let later = area.recent_skiers(&params);
    assert!((later[start] / recent[start] - (-1.0f32).exp()).abs() < 1e-3);
    // No unstable snow: no raised release.
    t.layer_mut(SnowLayer::Unstable)[start] = 0.0;
    assert_eq!(area.release_factor(&params, &t, start), 1.0);
}
