use super::*;
use crate::wind::sheltering::MAX_SX_STEPS;

/// A ramp rising upwind (west) at gradient `s` from its foot at `foot_m` east of the west
/// border, level ground east of the foot; `cell` m cells, 2 km × 600 m.
fn ramp(cell: f64, s: f64, foot_m: f64) -> (Vec<f32>, GridGeometry) {
    let (w, h) = ((2000.0 / cell) as usize, (600.0 / cell) as usize);
    let g = GridGeometry::square(w, h, cell).unwrap();
    let z = (0..w * h)
        .map(|i| {
            let x = ((i % w) as f64 + 0.5) * cell;
            (1000.0 + s * (foot_m - x).max(0.0)) as f32
        })
        .collect();
    (z, g)
}

/// The analytic Sx of a cell `d_m` east of the ramp's foot for a westerly and a search of
/// `dmax`: along a ray at `δ` from the wind, the terrain at distance `r` rises
/// `s·(r·cos δ − d)` above the cell where `r·cos δ > d`, so the largest rise over distance is
/// at `r = dmax`: `atan(s·(cos δ − d/dmax))`, or 0 (level ground) where that is negative;
/// averaged over the window's rays.
fn ramp_sx(s: f64, d_m: f64, dmax: f64, p: &ShelteringParams) -> f64 {
    let dirs = p.directions(0.0);
    dirs.iter()
        .map(|dd| {
            let rise = s * (dd.to_radians().cos() - d_m / dmax);
            rise.max(0.0).atan().to_degrees()
        })
        .sum::<f64>()
        / dirs.len() as f64
}

#[test]
fn a_ramp_upwind_gives_the_analytic_sx_at_100_m_and_1_km() {
    // A 1 km ramp at 1:2 (26.6°), its foot 1 km from the west border; cells about 50 m and
    // 200 m east of the foot, in the middle row (the ±15° rays, 259 m aside at 1 km, stay
    // inside the 800 m of rows, on the coarse grid too).
    let p = ShelteringParams::default();
    for cell in [5.0, 10.0, 50.0] {
        let (z, g) = ramp(cell, 0.5, 1000.0);
        let m = NodataMask::all_valid();
        let short = max_upwind_slope(&z, &g, &m, 270.0, &p).unwrap();
        let long = long_range_upwind_slope(&z, &g, &m, 270.0, &p).unwrap();
        let w = g.width();
        let row = g.height() / 2;
        for d in [50.0, 200.0] {
            // The cell whose centre is nearest `d` east of the foot, and its distance.
            let col = ((1000.0 + d) / cell - 0.5).round() as usize;
            let d = (col as f64 + 0.5) * cell - 1000.0;
            let i = row * w + col;
            let (want_short, want_long) = (ramp_sx(0.5, d, 100.0, &p), ramp_sx(0.5, d, 1000.0, &p));
            // 100 m: the ramp is within reach 50 m from its foot only. (On 50 m cells a
            // sample between two cell centres reads the foot's kink linearly: 0.3°.)
            let tolerance = if cell > 10.0 { 0.5 } else { 0.05 };
            assert!(
                (f64::from(short[i]) - want_short).abs() < tolerance,
                "{cell} m cells, {d} m: short {} vs {want_short}",
                short[i]
            );
            // 1 km, on the coarse grid of 50 m blocks: the interpolation between block
            // centres costs a few hundredths of a degree.
            assert!(
                (f64::from(long[i]) - want_long).abs() < 0.25,
                "{cell} m cells, {d} m: long {} vs {want_long}",
                long[i]
            );
        }
        let at = |d: f64| row * w + ((1000.0 + d) / cell - 0.5).round() as usize;
        assert_eq!(short[at(200.0)], 0.0);
        assert!(long[at(200.0)] > 10.0, "{}", long[at(200.0)]);
    }
}

#[test]
fn the_sheltering_index_adds_the_weighted_long_range() {
    let (z, g) = ramp(10.0, 0.5, 1000.0);
    let m = NodataMask::all_valid();
    let p = ShelteringParams {
        long_range_weight: 0.5,
        ..Default::default()
    };
    let short = max_upwind_slope(&z, &g, &m, 270.0, &p).unwrap();
    let long = long_range_upwind_slope(&z, &g, &m, 270.0, &p).unwrap();
    let index = sheltering_index(&z, &g, &m, 270.0, &p).unwrap();
    for i in 0..g.len() {
        assert_eq!(index[i], short[i] + 0.5 * long[i]);
    }
    // Off: the short search alone, and the long map all zeros.
    for off in [
        ShelteringParams {
            long_range_dmax_m: 0.0,
            ..Default::default()
        },
        ShelteringParams {
            long_range_weight: 0.0,
            ..Default::default()
        },
    ] {
        assert_eq!(sheltering_index(&z, &g, &m, 270.0, &off).unwrap(), short);
        let zero = long_range_upwind_slope(&z, &g, &m, 270.0, &off).unwrap();
        assert!(zero.iter().all(|&v| v == 0.0));
    }
}

#[test]
fn the_long_search_is_bounded_by_the_cells() {
    // Whatever the cell size, a ray takes at most 1000 / 50 = 20 samples on the coarse grid,
    // never more than MAX_SX_STEPS, and the search reads at most 20 samples per grid cell and
    // ray; on 5 m cells 0.2.
    let p = ShelteringParams::default();
    let bound = (p.long_range_dmax_m / p.long_range_cell_m).floor() as usize;
    for cell in [
        1e-6, 0.01, 0.5, 1.0, 2.0, 3.0, 5.0, 26.0, 30.0, 49.0, 50.0, 100.0, 500.0,
    ] {
        for n in [7usize, 64, 1024] {
            let g = GridGeometry::square(n, (n / 2).max(1), cell).unwrap();
            let plan = LongRangePlan::new(&p, &g).unwrap();
            assert!(
                plan.steps <= bound.min(MAX_SX_STEPS),
                "{cell} m, {n}: {plan:?}"
            );
            assert!(plan.coarse.len() <= g.len());
            assert!(
                plan.samples_per_cell(&g) <= bound as f64,
                "{cell} m, {n}: {} samples per cell",
                plan.samples_per_cell(&g)
            );
        }
    }
    let g5 = GridGeometry::square(1024, 1024, 5.0).unwrap();
    let plan = LongRangePlan::new(&p, &g5).unwrap();
    assert_eq!((plan.factor, plan.steps), (10, 20));
    assert!((plan.samples_per_cell(&g5) - 0.2).abs() < 0.01);
    let g50 = GridGeometry::square(56, 78, 50.0).unwrap();
    let plan = LongRangePlan::new(&p, &g50).unwrap();
    assert_eq!((plan.factor, plan.steps), (1, 20));
    // 20 m cells: blocks of 3 (60 m), 16 samples, 1.8 per cell.
    let g20 = GridGeometry::square(1024, 1024, 20.0).unwrap();
    let plan = LongRangePlan::new(&p, &g20).unwrap();
    assert_eq!((plan.factor, plan.steps), (3, 16));
    assert!(plan.samples_per_cell(&g20) < 1.8);
    // Even a 5 km search on 1 cm cells: the cap.
    let far = ShelteringParams {
        long_range_dmax_m: 5000.0,
        long_range_cell_m: 1e-3,
        ..Default::default()
    };
    let g = GridGeometry::square(4096, 4096, 0.01).unwrap();
    assert_eq!(LongRangePlan::new(&far, &g).unwrap().steps, MAX_SX_STEPS);
}

#[test]
fn same_bytes_on_one_and_two_threads_and_nodata_is_zero() {
    let g = GridGeometry::new(203, 131, 5.0, 6.0).unwrap();
    let invalid: Vec<bool> = (0..g.len())
        .map(|i| {
            let (c, r) = (i % 203, i / 203);
            (c + 2 * r) % 37 == 0 || (c < 30 && r < 40)
        })
        .collect();
    let m = NodataMask::from_invalid(invalid.clone());
    let z: Vec<f32> = (0..g.len())
        .map(|i| {
            let (c, r) = ((i % 203) as f32, (i / 203) as f32);
            2000.0 + 150.0 * (c * 0.031).sin() * (r * 0.023).cos() + 9.0 * (c * r * 0.01).sin()
        })
        .collect();
    let p = ShelteringParams::default();
    let run = |threads: usize, from: f64| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| sheltering_index(&z, &g, &m, from, &p).unwrap())
    };
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for from in [270.0, 33.0, 181.5] {
        let (a, b) = (run(1, from), run(2, from));
        assert_eq!(bits(&a), bits(&b), "wind from {from}");
        for (i, &bad) in invalid.iter().enumerate() {
            if bad {
                assert_eq!(a[i], 0.0);
            } else {
                assert!(a[i].is_finite());
            }
        }
        assert!(a.iter().any(|&v| v > 5.0) && a.iter().any(|&v| v < -5.0));
    }
}

#[test]
fn bad_long_range_parameters_are_named() {
    for (bad, name) in [
        (
            ShelteringParams {
                long_range_dmax_m: 6000.0,
                ..Default::default()
            },
            "sheltering.long_range_dmax_m",
        ),
        (
            ShelteringParams {
                long_range_cell_m: 0.0,
                ..Default::default()
            },
            "sheltering.long_range_cell_m",
        ),
        (
            ShelteringParams {
                long_range_weight: f64::NAN,
                ..Default::default()
            },
            "sheltering.long_range_weight",
        ),
    ] {
        assert!(
            matches!(bad.validate(), Err(EnvironmentError::InvalidParameter { name: n, .. }) if n == name),
            "{name}"
        );
    }
}
