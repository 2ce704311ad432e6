use super::*;
use snowscape_terrain::random::uniform;
use snowscape_terrain::{Grid, SnowLayer};

/// Owned wind maps for tests.
struct Wind {
    u: Vec<f32>,
    v: Vec<f32>,
    shadow: Vec<f32>,
    z: Vec<f32>,
}

impl Wind {
    fn uniform(t: &LayeredTerrain, u: f32, v: f32) -> Self {
        let n = t.geometry().len();
        Wind {
            u: vec![u; n],
            v: vec![v; n],
            shadow: vec![0.0; n],
            z: t.bedrock.clone(),
        }
    }
    fn maps(&self) -> WindMaps<'_> {
        WindMaps {
            u: &self.u,
            v: &self.v,
            shadow: &self.shadow,
            effect_surface: &self.z,
            sx: None,
            terms: None,
            air_temperature: None,
        }
    }
}

fn run(
    t: &mut LayeredTerrain,
    wind: &Wind,
    params: &WindTransportParams,
    steps: usize,
) -> Vec<WindReport> {
    let mut scratch = WindScratch::default();
    (0..steps)
        .map(|_| {
            let r = step(params, t, &wind.maps(), &mut scratch, 0.5).unwrap();
            t.check_invariants().unwrap();
            r
        })
        .collect()
}

/// A ridge running north-south at column 24 of a 48 x 8 grid of 5 m cells, with 0.5 m of
/// powder everywhere.
fn ridge() -> LayeredTerrain {
    let geo = GridGeometry::square(48, 8, 5.0).unwrap();
    let bed = Grid::from_fn(geo, |c, _| {
        let x = (c as f32 - 24.0) * 5.0;
        1000.0 + 40.0 * (-(x / 30.0).powi(2)).exp()
    });
    let mut t = LayeredTerrain::from_bedrock(bed);
    t.layer_mut(SnowLayer::Powder).fill(0.5);
    t
}

fn depth_at(t: &LayeredTerrain, col: usize) -> f32 {
    t.depth_at(t.geometry().index(col, 4))
}

#[test]
fn a_westerly_wind_builds_a_cornice_just_past_the_crest() {
    let mut t = ridge();
    // Blowing eastwards; the wind-effect surface leaves the ground on the lee side, so the
    // eight cells east of the crest are in the wind shadow.
    let mut wind = Wind::uniform(&t, 10.0, 0.0);
    for r in 0..8 {
        for c in 25..33 {
            wind.shadow[r * 48 + c] = 1.0;
        }
    }
    let reports = run(&mut t, &wind, &WindTransportParams::default(), 40);
    let eroded: f64 = reports.iter().map(|r| r.eroded).sum();
    assert!(eroded > 0.0);
    // The windward side of the crest is scoured...
    for c in 20..=23 {
        assert!(depth_at(&t, c) < 0.4, "col {c}: {}", depth_at(&t, c));
    }
    // ... and the snow piles up just past the crest, in the shadow: the cornice.
    let cornice = depth_at(&t, 25);
    assert!(cornice > 1.5, "{cornice}");
    let deepest = (0..48).max_by(|&a, &b| depth_at(&t, a).total_cmp(&depth_at(&t, b)));
    assert_eq!(deepest, Some(25));
    // Far from the crest (concave or flat ground) nothing moves.
    for c in (0..18).chain(27..48) {
        assert!(
            (depth_at(&t, c) - 0.5).abs() < 1e-5,
            "col {c}: {}",
            depth_at(&t, c)
        );
    }
    for r in &reports {
        assert!((r.eroded - r.deposited).abs() < 1e-6 * r.eroded.max(1.0));
        assert_eq!(r.border_outflow, 0.0);
    }
}

#[test]
fn without_a_shadow_the_snow_is_blown_over_the_crest_and_down_the_lee() {
    let mut t = ridge();
    let wind = Wind::uniform(&t, 10.0, 0.0);
    run(&mut t, &wind, &WindTransportParams::default(), 40);
    // The convex cap is scoured on both sides and the snow travels on down the lee to where
    // the slope turns concave: no cornice at the crest.
    assert!(
        depth_at(&t, 22) < 0.1 && depth_at(&t, 25) < 0.7,
        "{}",
        depth_at(&t, 25)
    );
    let deepest = (0..48)
        .max_by(|&a, &b| depth_at(&t, a).total_cmp(&depth_at(&t, b)))
        .unwrap();
    assert!((26..=29).contains(&deepest), "{deepest}");
}

#[test]
fn deposit_is_split_between_the_two_downwind_neighbours() {
    // One raised cell on a plane: the only convex cell. Wind (3, 4): 3/7 east, 4/7 north.
    let geo = GridGeometry::new(7, 7, 4.0, 5.0).unwrap();
    let bed = Grid::from_fn(
        geo.clone(),
        |c, r| if (c, r) == (3, 3) { 101.0 } else { 100.0 },
    );
    let mut t = LayeredTerrain::from_bedrock(bed);
    t.layer_mut(SnowLayer::Powder).fill(0.5);
    let wind = Wind::uniform(&t, 3.0, 4.0);
    let p = WindTransportParams {
        k_tamping: 0.0,
        ..Default::default()
    };
    let r = run(&mut t, &wind, &p, 1)[0];
    // curvW = 3·(−2/16) + 4·(−2/25) per metre of bump; k·δt = 0.05.
    let e = 0.05 * (3.0 * 2.0 / 16.0 + 4.0 * 2.0 / 25.0);
    let d = |c, r| t.depth_at(geo.index(c, r)) as f64 - 0.5;
    assert!((d(3, 3) + e).abs() < 1e-6, "{} vs {e}", d(3, 3));
    assert!((d(4, 3) - e * 3.0 / 7.0).abs() < 1e-6);
    assert!((d(3, 2) - e * 4.0 / 7.0).abs() < 1e-6);
    let moved: f64 = (0..49).map(|i| (t.depth_at(i) as f64 - 0.5).abs()).sum();
    assert!((moved - 2.0 * e).abs() < 1e-5, "only three cells changed");
    assert!((r.eroded - e * 20.0).abs() < 1e-5 && (r.deposited - r.eroded).abs() < 1e-9);
}

#[test]
fn snow_blown_off_the_grid_is_border_outflow() {
    // A dome whose crest is the east edge, wind blowing east: the edge cells erode.
    let geo = GridGeometry::square(16, 4, 5.0).unwrap();
    let bed = Grid::from_fn(geo, |c, _| 500.0 - 0.05 * ((15 - c) as f32 * 5.0).powi(2));
    let mut t = LayeredTerrain::from_bedrock(bed);
    t.layer_mut(SnowLayer::Powder).fill(0.2);
    t.layer_mut(SnowLayer::Unstable).fill(0.1);
    let wind = Wind::uniform(&t, 8.0, 0.0);
    let before = t.snow_volume();
    let reports = run(&mut t, &wind, &WindTransportParams::default(), 30);
    let out: f64 = reports.iter().map(|r| r.volume_change().removed).sum();
    assert!(out > 0.0);
    assert!((before - out - t.snow_volume()).abs() < 1e-5 * before);
    for r in &reports {
        assert!((r.eroded - r.deposited - r.border_outflow).abs() < 1e-6 * before);
    }
    // The westmost column gets nothing from upwind: once its powder is gone the unstable
    // layer is scoured too.
    assert_eq!(t.depth_at(0), 0.0);
}

#[test]
fn random_fields_conserve_snow_and_nodata_stays_bare() {
    let geo = GridGeometry::new(21, 15, 3.0, 4.0).unwrap();
    let n = geo.len();
    let invalid: Vec<bool> = (0..n).map(|i| uniform(3, 9, i as u64) < 0.08).collect();
    let bed = Grid::new(
        geo.clone(),
        (0..n)
            .map(|i| (uniform(3, 0, i as u64) * 8.0) as f32)
            .collect(),
        snowscape_terrain::NodataMask::from_invalid(invalid.clone()),
    )
    .unwrap();
    let mut t = LayeredTerrain::from_bedrock(bed);
    for i in (0..n).filter(|&i| !invalid[i]) {
        t.layer_mut(SnowLayer::Powder)[i] = (uniform(3, 1, i as u64) * 0.5) as f32;
        t.layer_mut(SnowLayer::Unstable)[i] = (uniform(3, 2, i as u64) * 0.2) as f32;
    }
    let wind = Wind {
        u: (0..n)
            .map(|i| (uniform(3, 3, i as u64) * 20.0 - 10.0) as f32)
            .collect(),
        v: (0..n)
            .map(|i| {
                if i % 5 == 0 {
                    0.0
                } else {
                    (uniform(3, 4, i as u64) * 20.0 - 10.0) as f32
                }
            })
            .collect(),
        shadow: (0..n)
            .map(|i| (uniform(3, 5, i as u64) < 0.2) as u8 as f32)
            .collect(),
        z: (0..n)
            .map(|i| (uniform(3, 6, i as u64) * 8.0) as f32)
            .collect(),
    };
    let mut budget = 0.0;
    let before = t.snow_volume();
    let reports = run(&mut t, &wind, &WindTransportParams::default(), 20);
    for r in &reports {
        assert!((r.eroded - r.deposited - r.border_outflow).abs() < 1e-6 * before);
        budget += r.border_outflow;
    }
    assert!(reports.iter().map(|r| r.eroded).sum::<f64>() > 0.05 * before);
    assert!(reports.iter().map(|r| r.tamped).sum::<f64>() > 0.0);
    assert!((before - budget - t.snow_volume()).abs() < 1e-5 * before);
}

#[test]
fn tamping_turns_powder_unstable_where_the_wind_is_pushed_up() {
    // A valley across the wind: the wind-effect surface is concave along the wind.
    let geo = GridGeometry::square(9, 9, 10.0).unwrap();
    let bed = Grid::from_fn(geo, |c, _| 100.0 + 0.05 * ((c as f32 - 4.0) * 10.0).powi(2));
    let mut t = LayeredTerrain::from_bedrock(bed);
    t.layer_mut(SnowLayer::Powder).fill(0.3);
    let p = WindTransportParams::default();
    let along = run(&mut t.clone(), &Wind::uniform(&t, 5.0, 0.0), &p, 1)[0];
    // a_z = 25 m²/s² · 0.1 /m = 2.5 m/s²; x = 0.2 · 0.5 · 2.5 = 0.25; share 0.2.
    assert!(
        (along.tamped - 0.3 * 0.2 * 8100.0).abs() < 1.0,
        "{}",
        along.tamped
    );
    // Blowing along the valley axis the wind never rises: no tamping, and no erosion either.
    let along_axis = Wind::uniform(&t, 0.0, 5.0);
    let across = run(&mut t, &along_axis, &p, 1)[0];
    assert_eq!((across.tamped, across.eroded), (0.0, 0.0));
}

#[test]
fn deposits_on_steep_lee_slopes_land_as_unstable_wind_slabs() {
    let mut t = ridge();
    // A steeper ridge: the first lee cells slope above 30°.
    let geo = t.geometry().clone();
    t.bedrock = Grid::from_fn(geo, |c, _| {
        let x = (c as f32 - 24.0) * 5.0;
        1000.0 + 120.0 * (-(x / 30.0).powi(2)).exp()
    })
    .into_data();
    let mut wind = Wind::uniform(&t, 10.0, 0.0);
    for r in 0..8 {
        for c in 25..33 {
            wind.shadow[r * 48 + c] = 1.0;
        }
    }
    let r = run(&mut t, &wind, &WindTransportParams::default(), 5);
    let slab: f64 = r.iter().map(|r| r.deposited_unstable).sum();
    let all: f64 = r.iter().map(|r| r.deposited).sum();
    assert!(slab > 0.5 * all && slab < all, "{slab} of {all}");
    // The 52° lee slope just past the crest gets a wind slab; the flat crest gets powder.
    let unstable = t.layer(SnowLayer::Unstable);
    assert!(unstable[4 * 48 + 25] > 0.1, "{}", unstable[4 * 48 + 25]);
    assert_eq!(unstable[4 * 48 + 24], 0.0);
}

#[test]
fn wrong_map_sizes_and_bad_parameters_are_errors() {
    let mut t = ridge();
    let wind = Wind::uniform(&t, 1.0, 0.0);
    let short = vec![0.0f32; 3];
    let maps = WindMaps {
        shadow: &short,
        ..wind.maps()
    };
    let e = step(
        &WindTransportParams::default(),
        &mut t,
        &maps,
        &mut WindScratch::default(),
        0.5,
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("wind_shadow map has 3 values"),
        "{e}"
    );
    let bad = WindTransportParams {
        slab_slope_deg: 95.0,
        ..Default::default()
    };
    assert!(bad.validate().is_err());
}

/// A north-south ridge (crest at column 24 of 48) under a westerly, with its Sx map.
fn ridge_with_sx() -> (LayeredTerrain, Wind, Vec<f32>) {
    let t = ridge();
    let g = t.geometry().clone();
    let sx = snowscape_environment::max_upwind_slope(
        &t.bedrock,
        &g,
        t.mask(),
        270.0,
        &snowscape_environment::ShelteringParams::default(),
    )
    .unwrap();
    let wind = Wind::uniform(&t, 10.0, 0.0);
    (t, wind, sx)
}

#[test]
fn sx_term_scours_the_windward_slope_and_loads_the_lee() {
    let (mut t, wind, sx) = ridge_with_sx();
    // Only the Sx term: no curvature erosion, no tamping.
    let p = WindTransportParams {
        k_erosion: 0.0,
        k_tamping: 0.0,
        ..Default::default()
    };
    let before = t.snow_volume();
    let maps = WindMaps {
        sx: Some(&sx),
        ..wind.maps()
    };
    let mut scratch = WindScratch::default();
    let mut out = 0.0;
    for _ in 0..20 {
        let r = step(&p, &mut t, &maps, &mut scratch, 0.5).unwrap();
        assert!(r.sx_eroded > 0.0 && r.sx_eroded == r.eroded);
        assert!((r.eroded - r.deposited - r.border_outflow).abs() < 1e-6 * before);
        out += r.border_outflow;
        t.check_invariants().unwrap();
    }
    assert!((before - out - t.snow_volume()).abs() < 1e-5 * before);
    // Windward (west) flank exposed and scoured, lee (east) flank sheltered and loaded.
    let windward: f32 = (16..22).map(|c| depth_at(&t, c)).sum::<f32>() / 6.0;
    let lee: f32 = (26..32).map(|c| depth_at(&t, c)).sum::<f32>() / 6.0;
    assert!(sx[4 * 48 + 18] < -1.0 && sx[4 * 48 + 29] > 1.0);
    assert!(
        windward < 0.45 && lee > 0.55,
        "windward {windward}, lee {lee}"
    );
}

#[test]
fn without_an_sx_map_or_disabled_the_step_is_the_papers() {
    let (t, wind, sx) = ridge_with_sx();
    let p = WindTransportParams::default();
    let mut a = t.clone();
    let mut b = t.clone();
    let off = WindTransportParams {
        sx_redistribution: SxParams {
            enabled: false,
            ..Default::default()
        },
        ..Default::default()
    };
    for _ in 0..5 {
        step(&p, &mut a, &wind.maps(), &mut WindScratch::default(), 0.5).unwrap();
        let with = WindMaps {
            sx: Some(&sx),
            ..wind.maps()
        };
        step(&off, &mut b, &with, &mut WindScratch::default(), 0.5).unwrap();
    }
    assert_eq!(a, b);
    let short = vec![0.0f32; 3];
    let bad = WindMaps {
        sx: Some(&short),
        ..wind.maps()
    };
    let e = step(&p, &mut a, &bad, &mut WindScratch::default(), 0.5).unwrap_err();
    assert!(e.to_string().contains("wind_sx map has 3 values"), "{e}");
    let bad = WindTransportParams {
        sx_redistribution: SxParams {
            settling_length_m: 0.0,
            ..Default::default()
        },
        ..Default::default()
    };
    assert!(bad.validate().is_err());
}

#[test]
fn sx_term_is_the_same_on_one_and_two_threads_and_conserves_with_nodata() {
    let geo = GridGeometry::new(41, 33, 5.0, 4.0).unwrap();
    let n = geo.len();
    let invalid: Vec<bool> = (0..n).map(|i| uniform(8, 9, i as u64) < 0.05).collect();
    let bed = Grid::new(
        geo.clone(),
        (0..n)
            .map(|i| {
                let (c, r) = geo.col_row(i);
                (500.0 + 20.0 * (c as f64 * 0.3).sin() * (r as f64 * 0.2).cos()) as f32
            })
            .collect(),
        snowscape_terrain::NodataMask::from_invalid(invalid.clone()),
    )
    .unwrap();
    let mut t = LayeredTerrain::from_bedrock(bed);
    for i in (0..n).filter(|&i| !invalid[i]) {
        t.layer_mut(SnowLayer::Powder)[i] = 0.4;
        t.layer_mut(SnowLayer::Unstable)[i] = 0.1;
    }
    let sx: Vec<f32> = (0..n)
        .map(|i| (uniform(8, 1, i as u64) * 20.0 - 10.0) as f32)
        .collect();
    let wind = Wind {
        u: (0..n).map(|i| 6.0 + (i % 7) as f32).collect(),
        v: (0..n).map(|i| -2.0 - (i % 3) as f32).collect(),
        shadow: vec![0.0; n],
        z: t.bedrock.clone(),
    };
    let p = WindTransportParams {
        k_erosion: 0.0,
        ..Default::default()
    };
    let go = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut t = t.clone();
                let maps = WindMaps {
                    sx: Some(&sx),
                    terms: None,
                    ..wind.maps()
                };
                let mut scratch = WindScratch::default();
                let reports: Vec<WindReport> = (0..10)
                    .map(|_| step(&p, &mut t, &maps, &mut scratch, 0.5).unwrap())
                    .collect();
                (t, reports)
            })
    };
    let (a, ra) = go(1);
    let (b, rb) = go(2);
    assert_eq!(ra, rb);
    for k in 0..4 {
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a.snow[k]), bits(&b.snow[k]));
    }
    a.check_invariants().unwrap();
    let before = t.snow_volume();
    let out: f64 = ra.iter().map(|r| r.border_outflow).sum();
    assert!(ra.iter().map(|r| r.sx_eroded).sum::<f64>() > 0.01 * before);
    assert!(
        out > 0.0,
        "the wind blows snow off the east and south borders"
    );
    assert!((before - out - a.snow_volume()).abs() < 1e-5 * before);
}

/// The wind's snow-independent terms computed once ([`WindTerms::new`]) give the bits of a
/// step that computes them itself, on a bumpy terrain with nodata cells, a varying wind and
/// the Sx term; terms for another grid are refused, naming the map.
#[test]
fn terms_computed_once_give_the_bits_of_terms_computed_per_step() {
    let geo = GridGeometry::square(40, 30, 10.0).unwrap();
    let n = geo.len();
    let invalid: Vec<bool> = (0..n).map(|i| uniform(7, 0, i as u64) < 0.03).collect();
    let bed: Vec<f32> = (0..n)
        .map(|i| {
            let (c, r) = ((i % 40) as f32, (i / 40) as f32);
            1500.0 + 30.0 * (c / 6.0).sin() * (r / 5.0).cos() + 5.0 * uniform(7, 1, i as u64) as f32
        })
        .collect();
    let grid = Grid::new(geo.clone(), bed, NodataMask::from_invalid(invalid)).unwrap();
    let mut t = LayeredTerrain::from_bedrock(grid);
    for i in 0..n {
        t.layer_mut(SnowLayer::Powder)[i] = 0.3 * uniform(7, 2, i as u64) as f32;
        t.layer_mut(SnowLayer::Unstable)[i] = 0.2 * uniform(7, 3, i as u64) as f32;
    }
    let wind = Wind {
        u: (0..n)
            .map(|i| 8.0 + 4.0 * uniform(7, 4, i as u64) as f32)
            .collect(),
        v: (0..n)
            .map(|i| -3.0 + 6.0 * uniform(7, 5, i as u64) as f32)
            .collect(),
        shadow: (0..n)
            .map(|i| (uniform(7, 6, i as u64) < 0.1) as u8 as f32)
            .collect(),
        z: (0..n)
            .map(|i| t.bedrock[i] + 20.0 * uniform(7, 7, i as u64) as f32)
            .collect(),
    };
    let sx = snowscape_environment::max_upwind_slope(
        &t.bedrock,
        &geo,
        t.mask(),
        250.0,
        &snowscape_environment::ShelteringParams::default(),
    )
    .unwrap();
    let maps = WindMaps {
        sx: Some(&sx),
        ..wind.maps()
    };
    let terms = WindTerms::new(&geo, t.mask(), &maps).unwrap();
    assert!(terms.dominant.is_some());
    assert!(terms.vertical_change.iter().any(|&a| a > 0.0));
    let given = WindMaps {
        terms: Some(&terms),
        ..maps
    };
    let p = WindTransportParams::default();
    let (mut a, mut b) = (t.clone(), t.clone());
    let (mut sa, mut sb) = (WindScratch::default(), WindScratch::default());
    for _ in 0..4 {
        let ra = step(&p, &mut a, &maps, &mut sa, 0.5).unwrap();
        let rb = step(&p, &mut b, &given, &mut sb, 0.5).unwrap();
        assert_eq!(ra, rb);
        assert!(ra.tamped > 0.0 && ra.sx_eroded > 0.0);
    }
    assert_eq!(a, b);
    let other = GridGeometry::square(8, 8, 10.0).unwrap();
    let small = Wind::uniform(
        &LayeredTerrain::from_bedrock(Grid::filled(other.clone(), 0.0)),
        5.0,
        0.0,
    );
    let wrong = WindTerms::new(&other, &NodataMask::all_valid(), &small.maps()).unwrap();
    let bad = WindMaps {
        terms: Some(&wrong),
        ..maps
    };
    let e = step(&p, &mut a, &bad, &mut sa, 0.5).unwrap_err();
    assert!(e.to_string().contains("wind terms"), "{e}");
}

#[test]
fn drifting_snow_sublimates_in_dry_wind_only() {
    let (t, _, sx) = ridge_with_sx();
    let air = vec![-5.0f32; t.geometry().len()];
    // Only the Sx term, whose drift sublimates.
    let blow = |wind: &Wind, rh: f64| {
        let mut t = t.clone();
        let mut p = WindTransportParams {
            k_erosion: 0.0,
            k_tamping: 0.0,
            ..Default::default()
        };
        p.sx_redistribution.sublimation.relative_humidity_pct = Some(rh);
        let maps = WindMaps {
            sx: Some(&sx),
            air_temperature: Some(&air),
            ..wind.maps()
        };
        let before = t.snow_volume();
        let mut scratch = WindScratch::default();
        let (mut lost, mut out) = (0.0, 0.0);
        for _ in 0..10 {
            let r = step(&p, &mut t, &maps, &mut scratch, 0.5).unwrap();
            assert_eq!(r.volume_change().removed, r.border_outflow + r.sublimated);
            lost += r.sublimated;
            out += r.border_outflow;
        }
        assert!((before - out - lost - t.snow_volume()).abs() < 1e-5 * before);
        lost
    };
    let dry = blow(&Wind::uniform(&t, 10.0, 0.0), 70.0);
    assert!(dry > 0.0);
    assert!(blow(&Wind::uniform(&t, 10.0, 0.0), 40.0) > dry);
    assert_eq!(blow(&Wind::uniform(&t, 10.0, 0.0), 100.0), 0.0);
    assert_eq!(blow(&Wind::uniform(&t, 0.0, 0.0), 70.0), 0.0);
}
