//! Bad input gives typed errors naming the offending value, never a panic.

mod common;

use snowscape_skiers::{SkiArea, SkiError, SkiParams, SkiScratch, Terminus, step};
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, NodataMask, SnowLayer};

fn area() -> (SkiParams, SkiArea, LayeredTerrain) {
    let params = SkiParams::default();
    let t = common::plane(10, 10, 10.0, 30.0);
    let a = SkiArea::new(&params, &t, Terminus::LocalMinima, 1).unwrap();
    (params, a, t)
}

#[test]
fn start_points_outside_on_nodata_or_without_snow_are_rejected() {
    let (params, mut a, mut t) = area();
    for (x, y) in [
        (-0.1, 50.0),
        (100.0, 50.0),
        (50.0, 100.5),
        (50.0, -1.0),
        (f64::NAN, 5.0),
    ] {
        let e = a.spawn_at(&params, &t, x, y).unwrap_err();
        match e {
            SkiError::OutsideGrid {
                x: ex,
                x_max,
                y_max,
                ..
            } => {
                assert!(ex == x || (ex.is_nan() && x.is_nan()));
                assert_eq!((x_max, y_max), (100.0, 100.0));
            }
            other => panic!("({x}, {y}): {other}"),
        }
    }
    t.layer_mut(SnowLayer::Stable)[5 * 10 + 5] = 0.0;
    t.layer_mut(SnowLayer::Unstable)[5 * 10 + 5] = 0.1;
    let e = a.spawn_at(&params, &t, 55.0, 45.0).unwrap_err();
    assert!(
        matches!(e, SkiError::NotEnoughSnow { col: 5, row: 5, depth_m, .. } if (depth_m - 0.1).abs() < 1e-6),
        "{e}"
    );
    assert!(e.to_string().contains("0.3 m"), "{e}");
    // A nodata cell.
    let g = GridGeometry::square(4, 4, 10.0).unwrap();
    let mut invalid = vec![false; 16];
    invalid[5] = true;
    let grid = Grid::new(g, vec![100.0; 16], NodataMask::from_invalid(invalid)).unwrap();
    let mut nt = LayeredTerrain::from_bedrock(grid);
    for i in 0..16 {
        if i != 5 {
            nt.layer_mut(SnowLayer::Stable)[i] = 1.0;
        }
    }
    let mut na = SkiArea::new(&params, &nt, Terminus::LocalMinima, 1).unwrap();
    let e = na.spawn_at(&params, &nt, 15.0, 25.0).unwrap_err();
    assert!(
        matches!(e, SkiError::OnNodata { col: 1, row: 1, .. }),
        "{e}"
    );
    assert!(a.skiers().is_empty() && na.skiers().is_empty());
}

#[test]
fn every_bad_parameter_is_named() {
    type Mutation = Box<dyn Fn(&mut SkiParams)>;
    let cases: Vec<(&str, Mutation)> = vec![
        (
            "target_slope_deg",
            Box::new(|p| p.target_slope_deg = f64::NAN),
        ),
        ("target_slope_deg", Box::new(|p| p.target_slope_deg = 90.0)),
        (
            "slope_tolerance_deg",
            Box::new(|p| p.slope_tolerance_deg = 0.0),
        ),
        ("min_snow_depth_m", Box::new(|p| p.min_snow_depth_m = -0.1)),
        ("lookahead_cells", Box::new(|p| p.lookahead_cells = 0)),
        ("lookahead_cells", Box::new(|p| p.lookahead_cells = 9)),
        (
            "turn_exponent",
            Box::new(|p| p.turn_exponent = f64::INFINITY),
        ),
        (
            "no_progress_weight",
            Box::new(|p| p.no_progress_weight = 1.5),
        ),
        ("turn_distance_m", Box::new(|p| p.turn_distance_m = 0.0)),
        ("speed_m_s", Box::new(|p| p.speed_m_s = f64::NAN)),
        ("amplitude_m", Box::new(|p| p.amplitude_m = -5.0)),
        (
            "min_frequency_per_m",
            Box::new(|p| p.min_frequency_per_m = f64::NAN),
        ),
        ("track_width_m", Box::new(|p| p.track_width_m = 0.0)),
        ("texels_per_cell", Box::new(|p| p.texels_per_cell = 0)),
        ("texels_per_cell", Box::new(|p| p.texels_per_cell = 65)),
        ("vertex_spacing_m", Box::new(|p| p.vertex_spacing_m = 0.0)),
        (
            "compaction_depth_m",
            Box::new(|p| p.compaction_depth_m = f64::NAN),
        ),
        (
            "density_unstable_kg_m3",
            Box::new(|p| p.density_unstable_kg_m3 = 0.0),
        ),
        (
            "density_stable_kg_m3",
            Box::new(|p| p.density_stable_kg_m3 = 200.0),
        ),
        (
            "density_compacted_kg_m3",
            Box::new(|p| p.density_compacted_kg_m3 = 250.0),
        ),
        ("recent_decay_s", Box::new(|p| p.recent_decay_s = 0.0)),
        (
            "trigger_min_slope_deg",
            Box::new(|p| p.trigger_min_slope_deg = 95.0),
        ),
        (
            "trigger_probability",
            Box::new(|p| p.trigger_probability = f64::NAN),
        ),
        (
            "trigger_unstable_ref_m",
            Box::new(|p| p.trigger_unstable_ref_m = 0.0),
        ),
        (
            "trigger_recent_gain",
            Box::new(|p| p.trigger_recent_gain = -1.0),
        ),
        ("fade_depth_m", Box::new(|p| p.fade_depth_m = f64::NAN)),
        ("max_run_length_m", Box::new(|p| p.max_run_length_m = 0.0)),
    ];
    SkiParams::default().validate().unwrap();
    let (_, mut a, mut t) = area();
    for (name, set) in cases {
        let mut p = SkiParams::default();
        set(&mut p);
        let e = p.validate().unwrap_err();
        assert!(
            matches!(e, SkiError::InvalidParameter { name: n, .. } if n == name),
            "{name}: {e}"
        );
        assert!(e.to_string().contains(name));
        // Every entry point validates.
        assert!(step(&p, &mut a, &mut t, &mut SkiScratch::default(), 0.1).is_err());
        assert!(SkiArea::new(&p, &t, Terminus::LocalMinima, 1).is_err());
        assert!(a.spawn_weighted(&p, &t, 1).is_err());
    }
}

#[test]
fn bad_time_steps_and_mismatched_terrain_are_rejected() {
    let (params, mut a, mut t) = area();
    let mut s = SkiScratch::default();
    for dt in [-1.0, f64::NAN, f64::INFINITY] {
        let e = step(&params, &mut a, &mut t, &mut s, dt).unwrap_err();
        assert!(
            matches!(e, SkiError::InvalidTimeStep(v) if v == dt || v.is_nan()),
            "{e}"
        );
    }
    let mut other = common::plane(10, 12, 10.0, 30.0);
    let e = step(&params, &mut a, &mut other, &mut s, 0.1).unwrap_err();
    assert!(
        matches!(
            e,
            SkiError::GeometryMismatch {
                width: 10,
                height: 10,
                terrain_height: 12,
                ..
            }
        ),
        "{e}"
    );
    assert!(a.spawn_at(&params, &other, 5.0, 5.0).is_err());
    // A zero step moves nothing.
    a.spawn_at(&params, &t, 55.0, 75.0).unwrap();
    let r = step(&params, &mut a, &mut t, &mut s, 0.0).unwrap();
    assert_eq!((r.active, r.passes, r.distance_m), (1, 0, 0.0));
}
