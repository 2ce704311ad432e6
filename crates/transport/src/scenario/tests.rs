use super::*;

const CASTLE: &str = include_str!("../../scenarios/castle.toml");
const VALLEY: &str = include_str!("../../scenarios/valley.toml");

#[test]
fn shipped_scenarios_parse_and_validate() {
    for text in [CASTLE, VALLEY] {
        let s = Scenario::from_toml(text).unwrap();
        s.validate().unwrap();
        assert_eq!(s.duration_h, 36.0);
        assert_eq!(s.weather.len(), 2);
        assert_eq!(s.transport.melt_factor_mm_per_degc_day, 3.2);
    }
    let castle = Scenario::from_toml(CASTLE).unwrap();
    assert!(matches!(castle.scene, SceneSpec::Castle { size_m, .. } if size_m == 850.0));
}

#[test]
fn unknown_keys_name_themselves() {
    let err = Scenario::from_toml("duration_hours = 3.0").unwrap_err();
    assert!(err.to_string().contains("duration_hours"), "{err}");
    let err =
        Scenario::from_toml("[scene]\nkind = \"castle\"\nsize_m = 1.0\ncell = 1.0").unwrap_err();
    assert!(err.to_string().contains("cell"), "{err}");
}

/// A shipped scenario on a coarser `scene`, with voxels of `(size m, layers)`, fewer wind
/// iterations and flakes.
fn coarse(
    text: &str,
    scene: SceneSpec,
    (voxel_size_m, voxel_layers): (f64, usize),
    wind_iterations: usize,
    flakes: usize,
) -> Scenario {
    let mut s = Scenario::from_toml(text).unwrap();
    s.scene = scene;
    s.voxel_size_m = voxel_size_m;
    s.voxel_layers = voxel_layers;
    s.wind_iterations = wind_iterations;
    s.flakes.count = flakes;
    s
}

/// The castle scenario at a coarse resolution, shortened: every stage runs and the mass
/// budget closes.
#[test]
fn a_small_castle_run_closes_its_budget() {
    let scene = SceneSpec::Castle {
        size_m: 850.0,
        cell_m: 10.0,
    };
    let mut s = coarse(CASTLE, scene, (17.0, 12), 4, 40_000);
    s.duration_h = 14.0; // 12 h of snowfall, 2 warm hours
    s.transport.time_step_s = 1800.0;
    let (g, z) = s.build_scene().unwrap().unwrap();
    let out = run(&s, &g, &z).unwrap();
    assert_eq!(out.steps, 28);
    let b = out.budget;
    assert!(b.precipitation_in > 0.0 && b.melt_out > 0.0);
    let scale = b.precipitation_in + b.transported;
    assert!(b.closure_error.abs() < 1e-5 * scale, "{b:?}");
    assert!(out.state.swe.iter().all(|m| m.is_finite() && *m >= 0.0));
    assert!(out.wind_report.mean.relative_divergence < 1e-5);
    assert!(out.flakes.landed > 0 && !out.precipitation_fallback);
    // 7.5 mm/h water equivalent for 12 h is 90 kg/m² on average, less what melted and blew
    // away in the warm hours.
    let area = g.cell_area() * g.len() as f64;
    let mean_swe = b.final_mass / area;
    assert!(mean_swe > 60.0 && mean_swe < 91.0, "{mean_swe}");
}

#[test]
fn fitted_voxels_hold_the_relief_with_air_above_and_low_grids_are_refused() {
    // avaWog-like: 2450 m x 2775 m of 5 m cells, 1250..2550 m.
    let g = GridGeometry::square(490, 555, 5.0).unwrap();
    let (size, layers) = fit_voxels(&g, 1250.0, 2550.0, 5.0, 128);
    assert!((size - 2775.0 / 128.0).abs() < 1e-9, "{size}");
    let top = 1250.0 - size + size * layers as f64;
    assert!(top >= 2550.0 + 1300.0 * 2.0 / 3.0, "top {top}");
    let mut s = Scenario {
        voxel_size_m: size,
        voxel_layers: layers,
        ..Scenario::default()
    };
    check_voxel_height(&s, 1250.0, 2550.0).unwrap();
    // A flat scene still gets 15 voxels of air; fine cells set the smallest voxel.
    let flat = GridGeometry::square(10, 10, 1.0).unwrap();
    assert_eq!(fit_voxels(&flat, 0.0, 0.0, 2.0, 128), (2.0, 16));
    s.voxel_layers = 10;
    let e = check_voxel_height(&s, 1250.0, 2550.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("voxel_layers = 10"), "{e}");
    assert_eq!(shipped_scenario("castle"), Some(CASTLE));
    assert!(shipped_scenario("glacier").is_none());
}

/// The valley of Table 7.I at 80 m cells: against a run without wind transport, the wind
/// erodes the slopes facing it (windward) and deposits on those turned away (lee), as in
/// the thesis's Fig. 7.9 and SnowTran-3D.
#[test]
fn the_valley_wind_erodes_windward_slopes_and_loads_lee_slopes() {
    let n = 100;
    let scene = SceneSpec::Procedural {
        size: n,
        cell_m: 80.0,
        seed: 4,
        relief_m: 1200.0,
    };
    let s = coarse(VALLEY, scene, (80.0, 40), 10, 200_000);
    let (g, z) = s.build_scene().unwrap().unwrap();
    let full = run(&s, &g, &z).unwrap();
    assert!(!full.precipitation_fallback && full.flakes.landed > 50_000);
    let mut still = s.clone();
    still.transport.phenomena.saltation = false;
    still.transport.phenomena.suspension = false;
    still.transport.phenomena.sublimation = false;
    let still = run(&still, &g, &z).unwrap();
    let (a, b) = (full.state.depth(), still.state.depth());
    // The wind blows from the north, towards increasing rows: a slope rising towards the
    // south faces it.
    let (mut windward, mut lee) = (Vec::new(), Vec::new());
    for r in 2..n - 2 {
        for c in 2..n - 2 {
            let i = r * n + c;
            let rise = (z[i + n] - z[i - n]) / (2.0 * 80.0);
            let change = f64::from(a[i] - b[i]);
            if rise > 0.3 {
                windward.push(change);
            } else if rise < -0.3 {
                lee.push(change);
            }
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (w, l) = (mean(&windward), mean(&lee));
    eprintln!(
        "windward {} cells: {w:+.4} m; lee {} cells: {l:+.4} m",
        windward.len(),
        lee.len()
    );
    assert!(windward.len() > 200 && lee.len() > 200);
    assert!(w < 0.0 && l > 0.0, "windward {w}, lee {l}");
}

#[test]
fn a_run_whose_wind_grid_exceeds_the_voxel_cap_is_refused_up_front() {
    // A 16 km scene in 1 m voxels x 32 layers: 8.6 G voxels, refused before the heights are
    // even scanned (they are not finite: the voxel check comes first).
    let mut s = Scenario::from_toml(CASTLE).unwrap();
    s.voxel_size_m = 1.0;
    s.voxel_layers = 32;
    let g = GridGeometry::square(64, 64, 256.0).unwrap();
    let z = vec![f32::NAN; 64 * 64];
    let e = run(&s, &g, &z).unwrap_err();
    assert!(
        matches!(
            e,
            TransportError::TooManyVoxels {
                nx: 16384,
                ny: 16384,
                nz: 32,
                ..
            }
        ),
        "{e:?}"
    );
}
