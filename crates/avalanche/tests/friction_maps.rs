//! Per-cell friction (`snowscape_avalanche::friction_maps`): a map of the law's own value
//! changes no bit, the vector and scalar kernels agree on a varying map, a rough (high-μ) band
//! across the track shortens the runout, a low ξ slows the flow, the entrainment reads the map,
//! and bad maps are refused with the value and the cell named.

use snowscape_avalanche::{
    AvalancheError, AvalancheParams, AvalancheScratch, AvalancheState, AvalancheWorkspace,
    FrictionLaw, FrictionMaps, ReleasedCells, RunOptions, SamosAtParams, step,
};
use snowscape_terrain::{GeoTransform, Grid, GridGeometry, LayeredTerrain, NodataMask, SnowLayer};

/// A `w` × `h` grid of `cell` m cells whose north-west corner is at map `(x, y)`.
fn placed(w: usize, h: usize, cell: f64, x: f64, y: f64) -> GridGeometry {
    let t = GeoTransform {
        origin_x: x,
        origin_y: y,
        pixel_width: cell,
        pixel_height: cell,
    };
    GridGeometry::from_transform(w, h, t, None).unwrap()
}

/// The slope's bed as a terrain.
fn terrain_of(g: &GridGeometry, bed: &[f64]) -> LayeredTerrain {
    let data = bed.iter().map(|&b| b as f32).collect();
    LayeredTerrain::from_bedrock(Grid::new(g.clone(), data, NodataMask::all_valid()).unwrap())
}

/// A 35° slope of `rows` 5 m cells running out onto flat ground at row 120, 40 cells wide.
fn slope() -> (GridGeometry, Vec<f64>) {
    let (w, rows, dx) = (40, 260, 5.0);
    let g = GridGeometry::square(w, rows, dx).unwrap();
    let tan = 35f64.to_radians().tan();
    let bed = (0..w * rows)
        .map(|i| {
            let r = (i / w) as f64;
            2000.0 - tan * dx * r.min(120.0)
        })
        .collect();
    (g, bed)
}

/// A 2 m release block near the top of [`slope`].
fn release(g: &GridGeometry) -> Vec<f64> {
    (0..g.len())
        .map(|i| {
            let (c, r) = (i % g.width(), i / g.width());
            if (15..25).contains(&c) && (10..25).contains(&r) {
                2.0
            } else {
                0.0
            }
        })
        .collect()
}

fn voellmy() -> AvalancheParams {
    AvalancheParams {
        friction: FrictionLaw::Voellmy,
        ..AvalancheParams::default()
    }
}

/// Runs `steps` × 1 s of `params` on the slope with `maps`; the final state.
fn run(
    params: &AvalancheParams,
    maps: &FrictionMaps,
    scalar: bool,
    steps: usize,
) -> AvalancheState {
    let (g, bed) = slope();
    let mut s = AvalancheState::new(&g, &NodataMask::all_valid(), &bed).unwrap();
    s.set_thickness(&release(&g)).unwrap();
    s.set_friction_maps(maps).unwrap();
    let mut scratch = AvalancheScratch::default();
    scratch.set_scalar_kernels(scalar);
    for _ in 0..steps {
        step(params, &mut s, &mut scratch, 1.0).unwrap();
    }
    s
}

/// The lowest row holding more than 1 cm of snow.
fn front_row(s: &AvalancheState) -> usize {
    let g = s.geometry();
    (0..g.height())
        .rev()
        .find(|&r| (0..g.width()).any(|c| s.snow_at(c, r) > 0.01))
        .unwrap()
}

#[test]
fn a_map_of_the_laws_own_value_changes_no_bit() {
    let (g, _) = slope();
    let n = g.len();
    let coulomb = AvalancheParams::default();
    let samos = AvalancheParams {
        friction: FrictionLaw::SamosAt,
        samos_at: SamosAtParams::small(),
        ..AvalancheParams::default()
    };
    for (params, xi) in [(coulomb, false), (voellmy(), true), (samos, false)] {
        let maps = FrictionMaps::new(
            &g,
            Some(vec![params.dry_friction(); n]),
            xi.then(|| vec![params.voellmy_xi_m_s2; n]),
        )
        .unwrap();
        for scalar in [false, true] {
            let plain = run(&params, &FrictionMaps::default(), scalar, 20);
            let mapped = run(&params, &maps, scalar, 20);
            assert_eq!(
                plain.thickness(),
                mapped.thickness(),
                "{:?} scalar {scalar}",
                params.friction
            );
        }
    }
}

#[test]
fn vector_and_scalar_kernels_agree_on_a_varying_map() {
    let (g, _) = slope();
    let w = g.width();
    let mu = (0..g.len())
        .map(|i| 0.1 + 0.02 * ((i % w) % 7) as f64 + 0.001 * (i / w) as f64)
        .collect();
    let xi = (0..g.len())
        .map(|i| 500.0 + 300.0 * ((i / w) % 5) as f64)
        .collect();
    let maps = FrictionMaps::new(&g, Some(mu), Some(xi)).unwrap();
    let a = run(&voellmy(), &maps, false, 25);
    let b = run(&voellmy(), &maps, true, 25);
    assert_eq!(a, b);
    assert!(
        front_row(&a) > 30,
        "the flow moved: front at row {}",
        front_row(&a)
    );
}

#[test]
fn a_rough_band_across_the_track_shortens_the_runout() {
    let (g, _) = slope();
    let params = AvalancheParams {
        border: snowscape_avalanche::Border::Closed,
        ..voellmy()
    };
    let open = run(&params, &FrictionMaps::default(), false, 120);
    // A "forest" band of μ = 0.6 from the last 50 m of the slope across the runout zone:
    // on the flat, the dry friction's deceleration μ·g is ~4 times the open one's, so the
    // distance run past the foot of the slope (row 120) should shrink by well over half.
    let mu = (0..g.len())
        .map(|i| {
            if (110..150).contains(&(i / g.width())) {
                0.6
            } else {
                params.voellmy_mu
            }
        })
        .collect();
    let forest = run(
        &params,
        &FrictionMaps::new(&g, Some(mu), None).unwrap(),
        false,
        120,
    );
    let (a, b) = (front_row(&open), front_row(&forest));
    assert!(a > 140, "the open run goes well past the foot: row {a}");
    assert!(
        2 * (b - 120) < a - 120,
        "the band stops the flow: row {b} against {a} (foot at row 120)"
    );
    // Volume is conserved either way (closed border).
    let total = |s: &AvalancheState| -> f64 {
        (0..g.height())
            .flat_map(|r| (0..g.width()).map(move |c| (c, r)))
            .map(|(c, r)| s.snow_at(c, r))
            .sum()
    };
    let released: f64 = release(&g).iter().sum();
    assert!((total(&open) - released).abs() < 1e-6 * released);
    assert!((total(&forest) - released).abs() < 1e-6 * released);
}

#[test]
fn a_low_xi_slows_the_flow() {
    let (g, _) = slope();
    let params = voellmy();
    let peak = |maps: &FrictionMaps| {
        let s = run(&params, maps, false, 8);
        (0..g.len())
            .map(|i| {
                let v = s.velocity_at(i % g.width(), i / g.width());
                v[0].hypot(v[1])
            })
            .fold(0.0f64, f64::max)
    };
    let smooth = peak(&FrictionMaps::default());
    let rough = peak(&FrictionMaps::new(&g, None, Some(vec![200.0; g.len()])).unwrap());
    assert!(
        rough < 0.6 * smooth,
        "ξ = 200: {rough} m/s against {smooth} m/s"
    );
}

#[test]
fn entrainment_reads_the_map() {
    // A uniform 0.3 m powder cover: the erosion rate τ_b·|u|/e_b reads the cell's μ, so a map
    // of the law's μ entrains the very same volume and one of twice the μ another.
    let (g, bed) = slope();
    let entrained = |maps: FrictionMaps| {
        let mut terrain = terrain_of(&g, &bed);
        let rel = release(&g);
        let cells: Vec<usize> = (0..g.len()).filter(|&i| rel[i] > 0.0).collect();
        for (i, &h) in rel.iter().enumerate() {
            if h > 0.0 {
                terrain.layer_mut(SnowLayer::Unstable)[i] = 2.0;
            } else {
                terrain.layer_mut(SnowLayer::Powder)[i] = 0.3;
            }
        }
        let mut ws = AvalancheWorkspace::new();
        ws.set_friction_maps(maps);
        let options = RunOptions {
            duration_s: 30.0,
            ..RunOptions::default()
        };
        ws.run_to_rest::<AvalancheError>(
            &mut terrain,
            ReleasedCells::new(&cells, None),
            &voellmy(),
            &options,
            SnowLayer::Stable,
            |_| Ok(()),
        )
        .unwrap()
        .entrained_m3
    };
    let plain = entrained(FrictionMaps::default());
    let same = entrained(FrictionMaps::new(&g, Some(vec![0.155; g.len()]), None).unwrap());
    let rough = entrained(FrictionMaps::new(&g, Some(vec![0.31; g.len()]), None).unwrap());
    assert!(plain > 0.0);
    assert_eq!(plain, same);
    assert_ne!(plain, rough);
}

#[test]
fn bad_maps_are_refused_naming_the_value() {
    let (g, _) = slope();
    let mut mu = vec![0.2; g.len()];
    mu[45] = f64::NAN;
    match FrictionMaps::new(&g, Some(mu), None) {
        Err(AvalancheError::FrictionMapValue {
            what: "mu map",
            index: 45,
            ..
        }) => {}
        other => panic!("{other:?}"),
    }
    let err = FrictionMaps::new(&g, None, Some(vec![1.0; g.len()])).unwrap_err();
    assert!(
        err.to_string().contains("xi map") && err.to_string().contains("is 1"),
        "{err}"
    );
    assert!(matches!(
        FrictionMaps::new(&g, Some(vec![0.2; 3]), None),
        Err(AvalancheError::LengthMismatch { got: 3, .. })
    ));
    // ξ with a law that has none.
    let xi = Grid::from_fn(g.clone(), |_, _| 1000.0);
    let r = FrictionMaps::from_rasters(
        &g,
        &NodataMask::all_valid(),
        &AvalancheParams::default(),
        None,
        Some(&xi),
    );
    assert!(
        matches!(r, Err(AvalancheError::FrictionMapUnused { .. })),
        "{r:?}"
    );
    // The workspace checks the law against the maps before any snow moves.
    let mut ws = AvalancheWorkspace::new();
    ws.set_friction_maps(FrictionMaps::new(&g, None, Some(vec![1000.0; g.len()])).unwrap());
    let (_, bed) = slope();
    let mut terrain = terrain_of(&g, &bed);
    terrain.layer_mut(SnowLayer::Unstable)[500] = 1.0;
    let before = terrain.clone();
    let r = ws.run_to_rest::<AvalancheError>(
        &mut terrain,
        ReleasedCells::new(&[500], None),
        &AvalancheParams::default(),
        &RunOptions::default(),
        SnowLayer::Stable,
        |_| Ok(()),
    );
    assert!(matches!(r, Err(AvalancheError::FrictionMapUnused { .. })));
    assert_eq!(terrain, before, "nothing released");
}

#[test]
fn rasters_are_matched_by_map_coordinates() {
    let (g, _) = slope();
    // A raster at 10 m covering the right half of the DEM only, with μ rising eastwards.
    let t = g.transform();
    let half = placed(10, 130, 10.0, t.origin_x + 100.0, t.origin_y);
    let raster = Grid::from_fn(half, |c, _| 0.2 + 0.01 * c as f32);
    let (maps, m, x) = FrictionMaps::from_rasters(
        &g,
        &NodataMask::all_valid(),
        &voellmy(),
        Some(&raster),
        None,
    )
    .unwrap();
    assert!(x.is_none());
    let m = m.unwrap();
    assert_eq!(m.raster_cells + m.defaulted_cells, g.len());
    assert_eq!(
        m.defaulted_cells,
        20 * g.height(),
        "the west half keeps the law's μ"
    );
    let mu = maps.mu().unwrap();
    // West half: the scalar; column 21 (centre x = 107.5 m from the origin) samples the
    // raster at column 0.25 → 0.2025 (bilinear).
    assert_eq!(mu[5 * g.width() + 3], 0.155);
    assert!(
        (mu[5 * g.width() + 21] - 0.2025).abs() < 1e-6,
        "{}",
        mu[5 * g.width() + 21]
    );
    // A raster elsewhere on the map.
    let far = Grid::from_fn(placed(4, 4, 10.0, t.origin_x + 1e6, t.origin_y), |_, _| 0.3);
    let r = FrictionMaps::from_rasters(&g, &NodataMask::all_valid(), &voellmy(), Some(&far), None);
    assert!(
        matches!(
            r,
            Err(AvalancheError::FrictionMapOutside { what: "mu map" })
        ),
        "{r:?}"
    );
}
