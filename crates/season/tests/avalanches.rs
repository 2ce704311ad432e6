//! Avalanches inside the season: the hazard map, user and natural triggers, deposits, the
//! budget, and (on the real avaMal terrain) steep slopes cleared with debris at their foot.

use snowscape_season::avalanches::{
    AvalancheParameters, HazardMap, HazardSources, Trigger, hazard, pick_cell,
};
use snowscape_season::scenario::{Scenario, UserAvalanche};
use snowscape_season::winter::Winter;
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, SnowLayer};

/// 60 x 120 cells of 5 m: a 40° slope (rows 0..60) onto flat ground (rows 60..120).
fn slope_onto_flat() -> LayeredTerrain {
    let g = GridGeometry::square(60, 120, 5.0).unwrap();
    let tan = 40f32.to_radians().tan();
    LayeredTerrain::from_bedrock(Grid::from_fn(g, |_, r| {
        1000.0 + tan * 5.0 * (60.0 - r as f32).max(0.0)
    }))
}

fn quiet_scenario(days: f64) -> Scenario {
    let mut s = Scenario {
        days,
        ..Scenario::default()
    };
    s.parameters.environment.sky.directions = 8;
    s.parameters.environment.sun.day_step = 30;
    // A cold winter day: these tests are about dry avalanches (the climatology puts the
    // 1000-1250 m slope near 0-4 °C on 1 December at 45° N, which makes the snow wet).
    s.parameters.climate.temperature_offset_c = -10.0;
    s
}

#[test]
fn slope_window_and_hazard_follow_the_design() {
    let p = AvalancheParameters::default();
    assert_eq!(p.slope_window(20.0), 0.0);
    assert!((p.slope_window(31.5) - 0.5).abs() < 1e-12);
    assert_eq!(p.slope_window(40.0), 1.0);
    assert!((p.slope_window(52.5) - 0.5).abs() < 1e-12);
    assert_eq!(p.slope_window(70.0), 0.0);
    assert_eq!(p.alpha_at(-15.0), 1.0);
    assert!((p.alpha_at(-5.0) - 0.8).abs() < 1e-12);
    assert_eq!(p.alpha_at(3.0), p.wet_alpha);

    let mut t = slope_onto_flat();
    let slopes = snowscape_season::avalanches::bedrock_slopes_deg(&t);
    let mut h = Vec::new();
    assert_eq!(
        hazard(&p, &t, &slopes, None, &mut h),
        0.0,
        "no snow, no hazard"
    );
    t.layer_mut(SnowLayer::Unstable).fill(0.5);
    let total = hazard(&p, &t, &slopes, None, &mut h);
    // Interior slope cells (40°, U = U_ref): f·dx·dy/1 km² each; flat cells: 0.
    let per_cell = p.rate_per_km2_per_day * 25.0 / 1e6;
    assert!(
        (h[30 * 60 + 30] - per_cell).abs() < 1e-15,
        "{}",
        h[30 * 60 + 30]
    );
    assert_eq!(h[100 * 60 + 30], 0.0);
    assert!(total > 50.0 * 55.0 * per_cell && total < 60.0 * 62.0 * per_cell);
    // Skiers raise it.
    let skiers = vec![1.0f32; 60 * 120];
    let with = hazard(&p, &t, &slopes, Some(&skiers), &mut h);
    assert!((with / total - (1.0 + p.skier_gain)).abs() < 1e-9);
    // Sampling follows the hazard: never a zero-hazard cell.
    hazard(&p, &t, &slopes, None, &mut h);
    for k in 0..50 {
        let i = pick_cell(&h, total, k as f64 / 50.0).unwrap();
        assert!(h[i] > 0.0);
    }
    assert_eq!(pick_cell(&h, 0.0, 0.5), None);
}

#[test]
fn the_hazard_map_updated_over_released_cells_keeps_the_bits_of_a_full_computation() {
    let p = AvalancheParameters::default();
    let mut t = slope_onto_flat();
    let n = t.geometry().len();
    for i in 0..n {
        t.layer_mut(SnowLayer::Unstable)[i] =
            (0.6 * snowscape_terrain::random::uniform(4, 0, i as u64)) as f32;
    }
    let slopes = snowscape_season::avalanches::bedrock_slopes_deg(&t);
    let skiers: Vec<f32> = (0..n)
        .map(|i| snowscape_terrain::random::uniform(4, 1, i as u64) as f32)
        .collect();
    let mut kept = HazardMap::default();
    let sources = HazardSources {
        skiers: Some(&skiers),
        painted: None,
    };
    kept.compute(&p, &t, &slopes, &sources);
    for round in 0..5u64 {
        // An avalanche takes the unstable snow of some cells (ascending).
        let cells: Vec<usize> = (0..n)
            .filter(|&i| snowscape_terrain::random::uniform(4, 2 + round, i as u64) < 0.02)
            .collect();
        for &i in &cells {
            t.layer_mut(SnowLayer::Unstable)[i] = 0.0;
        }
        let total = kept.update_cells(&p, &t, &slopes, &sources, &cells);
        let mut fresh = HazardMap::default();
        let full = fresh.compute(&p, &t, &slopes, &sources);
        assert_eq!(total.to_bits(), full.to_bits(), "round {round}");
        assert_eq!(kept, fresh, "round {round}");
        // Draws follow the hazard and agree with the cell-by-cell draw to a neighbour.
        for k in 0..40 {
            let u = k as f64 / 40.0;
            let i = kept.pick(u).unwrap();
            assert!(kept.lambda[i] > 0.0);
            let j = pick_cell(&kept.lambda, full, u).unwrap();
            let between: f64 = kept.lambda[i.min(j)..i.max(j)].iter().sum();
            assert!(between <= 1e-9 * full, "draw {u}: cell {i} vs {j}");
        }
    }
    assert_eq!(kept.pick(0.5).map(|i| kept.lambda[i] > 0.0), Some(true));
    assert_eq!(HazardMap::default().pick(0.5), None);
}

#[test]
fn a_user_avalanche_clears_the_slope_and_piles_at_its_foot() {
    let mut t = slope_onto_flat();
    t.layer_mut(SnowLayer::Unstable).fill(0.8);
    let before_slope: f32 = (5..55).map(|r| t.depth_at(r * 60 + 30)).sum();
    let mut s = quiet_scenario(1.0);
    s.parameters.avalanche.natural = false;
    let g = t.geometry().clone();
    let (x, y) = g.cell_centre(30, 8);
    s.avalanches.push(UserAvalanche { day: 0.0, x, y });
    let mut w = Winter::new(s, t).unwrap();
    let initial = w.terrain.snow_volume();
    w.run_until(0.01).unwrap();
    let recs = w.avalanches();
    assert_eq!(recs.len(), 1, "{recs:?}");
    let r = &recs[0];
    eprintln!("{r:#?}");
    assert_eq!(r.trigger, Trigger::User);
    // The rupture zone (reach 50 m per m of unstable snow: 40 m) swept down the whole slope:
    // a band at least 16 cells wide and 45 rows long.
    assert!(
        r.released_m3 > 0.8 * 25.0 * 16.0 * 45.0,
        "{}",
        r.released_m3
    );
    assert!(
        ((r.deposited_m3 + r.outflow_m3) - r.released_m3 - r.entrained_m3).abs()
            < 1e-4 * r.released_m3,
        "released {} deposited {} outflow {}",
        r.released_m3,
        r.deposited_m3,
        r.outflow_m3
    );
    assert!(r.runout_length_m > 250.0, "runout {}", r.runout_length_m);
    // The slope below the rupture lost snow; the flat at its foot gained stable debris.
    let after_slope: f32 = (5..55).map(|r| w.terrain.depth_at(r * 60 + 30)).sum();
    assert!(
        after_slope < 0.5 * before_slope,
        "{after_slope} vs {before_slope}"
    );
    let foot_stable: f32 = (60..90)
        .map(|r| w.terrain.layer(SnowLayer::Stable)[r * 60 + 30])
        .sum();
    assert!(foot_stable > 5.0, "debris at the foot {foot_stable}");
    // Budget: the store changed only by what left the grid (and the day's melt/snowfall).
    let b = w.budget();
    let store = w.terrain.snow_volume();
    assert!(
        (store - b.expected_store()).abs() < 1e-5 * initial,
        "store {store} expected {} ({b:?})",
        b.expected_store()
    );
    w.terrain.check_invariants().unwrap();
}

/// The editor's painted release probability is a hazard source of the scheduler: with natural
/// releases off, painted cells release during the season's days (trigger `painted`), unpainted
/// ones never; the rate follows the paint; a value out of [0, 1] is refused by name.
#[test]
fn painted_release_probability_starts_avalanches_during_the_days() {
    let mut t = slope_onto_flat();
    t.layer_mut(SnowLayer::Unstable).fill(0.6);
    let mut s = quiet_scenario(3.0);
    s.parameters.avalanche.natural = false;
    let g = t.geometry().clone();
    let mut w = Winter::new(s.clone(), t.clone()).unwrap();
    w.run_until(3.0).unwrap();
    assert!(w.avalanches().is_empty(), "no paint, no natural releases");

    // A painted band across the slope, one release a day per 60 m zone.
    let paint: Vec<f32> = (0..g.len())
        .map(|i| {
            if (10..20).contains(&g.col_row(i).1) {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    let mut w = Winter::new(s.clone(), t.clone()).unwrap();
    w.set_painted_release(Some(&paint), 60.0).unwrap();
    w.run_until(3.0).unwrap();
    let recs = w.avalanches();
    eprintln!("{} painted releases in 3 days", recs.len());
    assert!(!recs.is_empty(), "painted releases happened");
    for r in recs {
        assert_eq!(r.trigger, Trigger::Painted, "{r:?}");
        assert!(
            r.day > 0.0 && r.day <= w.day(),
            "during the days: {}",
            r.day
        );
    }
    // Several distinct days (the scheduler's times), not all at one instant.
    let first = recs.first().unwrap().day;
    assert!(recs.iter().any(|r| r.day != first), "{recs:?}");

    // The same season again: the same avalanches (keyed draws).
    let mut again = Winter::new(s.clone(), t.clone()).unwrap();
    again.set_painted_release(Some(&paint), 60.0).unwrap();
    again.run_until(3.0).unwrap();
    assert_eq!(again.avalanches(), recs);

    let mut bad = paint.clone();
    bad[7] = 1.5;
    let e = w.set_painted_release(Some(&bad), 60.0).unwrap_err();
    assert!(e.to_string().contains("1.5"), "{e}");
    let e = w.set_painted_release(Some(&paint), -1.0).unwrap_err();
    assert!(e.to_string().contains("-1"), "{e}");
    let e = w.set_painted_release(Some(&paint[1..]), 60.0).unwrap_err();
    assert!(e.to_string().contains("cells"), "{e}");
}

#[test]
fn user_avalanche_outside_the_grid_is_named() {
    let w = Winter::new(quiet_scenario(1.0), slope_onto_flat());
    let mut w = w.unwrap();
    let e = w.trigger_avalanche(-1e6, 5.0).unwrap_err().to_string();
    assert!(e.contains("-1000000"), "{e}");
}

#[test]
fn bad_avalanche_parameters_are_named() {
    let mut s = quiet_scenario(10.0);
    s.parameters.avalanche.slope_full_deg = 10.0;
    let e = s.validate("test.toml").unwrap_err().to_string();
    assert!(e.contains("slope_full_deg"), "{e}");
    let mut s = quiet_scenario(10.0);
    s.avalanches.push(UserAvalanche {
        day: f64::NAN,
        x: 0.0,
        y: 0.0,
    });
    let e = s.validate("test.toml").unwrap_err().to_string();
    assert!(e.contains("avalanche[0]"), "{e}");
}

/// Real terrain (AvaFrame's avaMal, 787x567 cells of 5 m, median slope 34°): a 60-day winter
/// with natural avalanches. Avalanches must happen, take their snow from steep slopes and lay
/// it down lower, on gentler ground (the volume-weighted slope and altitude of the deposit
/// below those of the scour), and the season's budget must close with their outflow.
#[test]
fn avamal_avalanches_clear_steep_slopes_and_pile_at_their_foot() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/dem/avaframe_avaMal/avaMal.asc"
    );
    assert!(
        std::path::Path::new(path).exists(),
        "real-DEM test input {path} is missing: this test needs /work/shared/data (AvaFrame avaMal)"
    );
    let dem = snowscape_io::read_dem(std::path::Path::new(path), &Default::default()).unwrap();
    let mut w = Winter::new(quiet_scenario(60.0), LayeredTerrain::from_bedrock(dem)).unwrap();
    w.run_until(60.0).unwrap();
    let recs = w.avalanches();
    assert!(recs.len() >= 3, "only {} avalanches", recs.len());
    let b = w.budget();
    let store = w.terrain.snow_volume();
    assert!(
        (store - b.expected_store()).abs() < 1e-5 * b.snowfall,
        "closure: store {store}, expected {}",
        b.expected_store()
    );
    w.terrain.check_invariants().unwrap();
    let slopes = snowscape_season::avalanches::bedrock_slopes_deg(&w.terrain);
    let maps = w.avalanche_maps();
    let weighted = |m: &[f32], f: &dyn Fn(usize) -> f64| {
        let (num, den) = m.iter().enumerate().fold((0.0, 0.0), |(n, d), (i, &v)| {
            (n + v as f64 * f(i), d + v as f64)
        });
        (num / den, den * 25.0)
    };
    let (scour_slope, scoured) = weighted(&maps.scour, &|i| slopes[i] as f64);
    let (deposit_slope, deposited) = weighted(&maps.deposit, &|i| slopes[i] as f64);
    let (scour_z, _) = weighted(&maps.scour, &|i| w.terrain.bedrock[i] as f64);
    let (deposit_z, _) = weighted(&maps.deposit, &|i| w.terrain.bedrock[i] as f64);
    let released: f64 = recs.iter().map(|r| r.released_m3).sum();
    let entrained: f64 = recs.iter().map(|r| r.entrained_m3).sum();
    eprintln!(
        "{} avalanches, {released:.0} m³ released, {entrained:.0} m³ entrained; scour {scoured:.0} m³ at {scour_slope:.1}°, {scour_z:.0} m; deposit {deposited:.0} m³ at {deposit_slope:.1}°, {deposit_z:.0} m",
        recs.len()
    );
    // The avalanches scoured their tracks: they entrained more than half again of what they
    // released (1.55 times on 2026-12-04).
    assert!(
        entrained > 0.5 * released,
        "entrained {entrained} m³ of {released} m³ released"
    );
    // The scour map holds the released and the entrained snow.
    assert!((scoured - released - entrained).abs() < 1e-3 * (released + entrained));
    assert!(
        (b.avalanche_entrained - entrained).abs() <= 1e-9 * entrained.max(1.0),
        "budget {} vs records {entrained}",
        b.avalanche_entrained
    );
    assert!(scour_slope > 33.0, "scour slope {scour_slope}");
    assert!(
        deposit_slope < scour_slope - 5.0,
        "deposit slope {deposit_slope} vs scour {scour_slope}"
    );
    assert!(
        deposit_z < scour_z - 50.0,
        "deposit {deposit_z} m vs scour {scour_z} m"
    );
}

/// Unstable snow of up to 0.8 m drawn per cell with `seed`.
fn random_unstable(t: &mut LayeredTerrain, seed: u64) {
    for (i, u) in t.layer_mut(SnowLayer::Unstable).iter_mut().enumerate() {
        *u = (0.8 * snowscape_terrain::random::uniform(seed, 0, i as u64)) as f32;
    }
}

/// The hazard of `t` by the fast path (`fast`: no sources) and by the general path (`general`:
/// zero paint), asserted bit for bit (total, every `λ`, every draw); returns the total.
fn hazard_both_ways(
    p: &AvalancheParameters,
    t: &LayeredTerrain,
    (fast, general): (&mut HazardMap, &mut HazardMap),
) -> f64 {
    let slopes = snowscape_season::avalanches::bedrock_slopes_deg(t);
    let zeros = vec![0.0f32; t.geometry().len()];
    let a = fast.compute(p, t, &slopes, &HazardSources::default());
    let b = general.compute(
        p,
        t,
        &slopes,
        &HazardSources {
            skiers: None,
            painted: Some(&zeros),
        },
    );
    assert_eq!(a.to_bits(), b.to_bits());
    let bits = |m: &HazardMap| m.lambda.iter().map(|l| l.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(fast), bits(general));
    // Every draw picks the same cell (the row sums agree too).
    for k in 0..200 {
        let u = (k as f64 + 0.5) / 200.0;
        assert_eq!(fast.pick(u), general.pick(u));
    }
    a
}

#[test]
fn natural_hazard_without_sources_has_the_bits_of_the_general_computation() {
    // The map without skiers, paint or nodata takes a straight loop with the slope window
    // looked up; zero paint sends it through the general cell-by-cell path.
    let p = AvalancheParameters::default();
    let mut t = slope_onto_flat();
    random_unstable(&mut t, 7);
    let (mut fast, mut general) = (HazardMap::default(), HazardMap::default());
    let a = hazard_both_ways(&p, &t, (&mut fast, &mut general));
    assert!(a > 0.0);
    // The cached window follows a change of the window's slopes (the 40° slope now lies where
    // the window falls off).
    let q = AvalancheParameters {
        slope_fall_deg: 38.0,
        ..p.clone()
    };
    assert!(hazard_both_ways(&q, &t, (&mut fast, &mut general)) < a);
    // A height that is not a multiple of the fast path's group of four rows: the last group's
    // rows are summed alone, with the same bits.
    let g = GridGeometry::square(37, 123, 5.0).unwrap();
    let mut t = LayeredTerrain::from_bedrock(Grid::from_fn(g, |c, r| {
        1000.0 + 4.0 * (123.0 - r as f32) + 0.5 * c as f32
    }));
    random_unstable(&mut t, 9);
    assert!(hazard_both_ways(&p, &t, (&mut fast, &mut general)) > 0.0);
}
