use super::*;

fn plane(w: usize, h: usize, cell: f64, gx: f64, gy: f64) -> (Vec<f32>, GridGeometry) {
    // z = 1000 + gx·x + gy·y, x east and y north (row 0 north).
    let g = GridGeometry::square(w, h, cell).unwrap();
    let z = (0..w * h)
        .map(|i| {
            let (c, r) = ((i % w) as f64, (i / w) as f64);
            (1000.0 + gx * c * cell - gy * r * cell) as f32
        })
        .collect();
    (z, g)
}

fn sx(z: &[f32], g: &GridGeometry, from: f64, p: &ShelteringParams) -> Vec<f32> {
    max_upwind_slope(z, g, &NodataMask::all_valid(), from, p).unwrap()
}

/// Window mean of `atan(tan α · cos δ)` over the rays: the analytic Sx of a plane rising
/// upwind at `α` along the wind.
fn plane_sx(alpha_deg: f64, p: &ShelteringParams) -> f64 {
    let dirs = p.directions(0.0);
    let t = alpha_deg.to_radians().tan();
    dirs.iter()
        .map(|d| (t * d.to_radians().cos()).atan().to_degrees())
        .sum::<f64>()
        / dirs.len() as f64
}

#[test]
fn level_ground_has_zero_sx() {
    let (z, g) = plane(40, 30, 5.0, 0.0, 0.0);
    let s = sx(&z, &g, 270.0, &ShelteringParams::default());
    assert!(s.iter().all(|&v| v == 0.0), "{:?}", &s[..5]);
}

#[test]
fn a_plane_rising_upwind_shelters_and_one_falling_upwind_exposes_at_any_cell_size() {
    // Rising to the west at 20°; wind from the west; 2 m to 100 m cells, 400 m x 200 m
    // (a 100 m search from the middle stays inside).
    let t = 20f64.to_radians().tan();
    let p = ShelteringParams::default();
    let expect = plane_sx(20.0, &p);
    for cell in [2.0, 5.0, 25.0, 50.0, 100.0] {
        let (w, h) = ((1000.0 / cell) as usize, (600.0 / cell) as usize);
        let (z, g) = plane(w, h, cell, -t, 0.0);
        let s = sx(&z, &g, 270.0, &p);
        let e = sx(&z, &g, 90.0, &p);
        let (r, c) = (h / 2, w / 2);
        // Every ray has its full 100 m from the middle cell.
        let v = s[r * w + c] as f64;
        assert!((v - expect).abs() < 0.02, "{cell} m: {v} vs {expect}");
        // The same plane under an easterly: the terrain falls away upwind, exposed.
        let v = e[r * w + c] as f64;
        assert!((v + expect).abs() < 0.02, "{cell} m: {v} vs {}", -expect);
        // The upwind border has nothing upwind: 0.
        assert_eq!(s[r * w], 0.0);
    }
}

#[test]
fn a_wall_shelters_its_lee_by_its_angle_seen_from_the_cell() {
    // A 20 m high, 10 m thick wall across a level plain; westerly wind, a single ray.
    let g = GridGeometry::square(60, 5, 5.0).unwrap();
    let z: Vec<f32> = (0..300)
        .map(|i| {
            if (20..22).contains(&(i % 60)) {
                120.0
            } else {
                100.0
            }
        })
        .collect();
    let p = ShelteringParams {
        window_half_deg: 0.0,
        ..Default::default()
    };
    let s = sx(&z, &g, 270.0, &p);
    // Cell 30 is 9 cells east of the wall's east cell (col 21): atan(20 / 45 m).
    let want = (20.0f64 / 45.0).atan().to_degrees();
    assert!(
        (s[2 * 60 + 30] as f64 - want).abs() < 1e-3,
        "{}",
        s[2 * 60 + 30]
    );
    // Upwind of the wall the plain sees only level ground... and the wall itself is exposed
    // by its own drop to the west: max over upwind points of atan(−20 / d) at d = 5 m... to 100 m.
    assert_eq!(s[2 * 60 + 10], 0.0);
    let crest = s[2 * 60 + 20] as f64;
    assert!(
        (crest - (-20.0f64 / 100.0).atan().to_degrees()).abs() < 1e-3,
        "{crest}"
    );
    // Beyond dmax (100 m = 20 cells) the wall is out of reach.
    assert_eq!(s[2 * 60 + 45], 0.0);
}

#[test]
fn the_same_terrain_gives_the_same_sx_at_10_m_and_100_m_cells() {
    // A smooth hill 80 m high and ~450 m wide, sampled at two resolutions.
    let hill = |x: f64, y: f64| {
        1000.0 + 80.0 * (-((x - 1500.0).powi(2) + (y - 1500.0).powi(2)) / 4.0e5).exp()
    };
    let make = |cell: f64| {
        let n = (3000.0 / cell) as usize;
        let g = GridGeometry::square(n, n, cell).unwrap();
        let z: Vec<f32> = (0..n * n)
            .map(|i| {
                let (c, r) = ((i % n) as f64 + 0.5, (i / n) as f64 + 0.5);
                hill(c * cell, 3000.0 - r * cell) as f32
            })
            .collect();
        (z, g)
    };
    let p = ShelteringParams {
        dmax_m: 300.0,
        ..Default::default()
    };
    let (z2, g2) = make(10.0);
    let (z100, g100) = make(100.0);
    let s2 = sx(&z2, &g2, 270.0, &p);
    let s100 = sx(&z100, &g100, 270.0, &p);
    // Cell centres of the 100 m grid at (c, r) are 10 m-grid points (10c+5 ± 0.5 ...):
    // compare the 100 m cell with the mean of the 10 x 10 fine cells it covers.
    let (mut worst, mut sum, mut count) = (0.0f64, 0.0, 0.0);
    for r in 5..25 {
        for c in 8..25 {
            let coarse = s100[r * 30 + c] as f64;
            let mut fine = 0.0;
            for rr in 0..10 {
                for cc in 0..10 {
                    fine += s2[(10 * r + rr) * 300 + 10 * c + cc] as f64;
                }
            }
            let d = (coarse - fine / 100.0).abs();
            worst = worst.max(d);
            sum += d;
            count += 1.0;
        }
    }
    // The coarse grid samples each ray every 100 m (three points) where the fine one takes
    // thirty: it misses a little of the maximum, nothing more.
    let mean = sum / count;
    eprintln!("10 m / 100 m difference: mean {mean:.3}°, largest {worst:.3}°");
    assert!(
        worst < 1.5 && mean < 0.4,
        "10 m / 100 m difference: mean {mean}°, largest {worst}°"
    );
}

#[test]
fn a_search_shorter_than_a_cell_takes_one_cell() {
    let t = 10f64.to_radians().tan();
    let (z, g) = plane(20, 10, 50.0, -t, 0.0);
    let p = ShelteringParams {
        dmax_m: 10.0,
        window_half_deg: 0.0,
        ..Default::default()
    };
    assert_eq!(p.steps(&g), 1);
    let s = sx(&z, &g, 270.0, &p);
    assert!((s[5 * 20 + 10] - 10.0).abs() < 1e-3, "{}", s[5 * 20 + 10]);
}

#[test]
fn nodata_is_skipped_not_read_as_ground() {
    // A high wall whose top is nodata: the rays skip it and see only the plain.
    let g = GridGeometry::square(40, 3, 5.0).unwrap();
    let mut z: Vec<f32> = (0..120)
        .map(|i| if i % 40 == 10 { 500.0 } else { 100.0 })
        .collect();
    let p = ShelteringParams {
        window_half_deg: 0.0,
        ..Default::default()
    };
    let seen = sx(&z, &g, 270.0, &p);
    assert!(seen[40 + 15] > 30.0);
    let invalid: Vec<bool> = (0..120).map(|i| i % 40 == 10).collect();
    for (i, v) in z.iter_mut().enumerate() {
        if invalid[i] {
            *v = f32::NAN;
        }
    }
    let mask = NodataMask::from_invalid(invalid);
    let s = max_upwind_slope(&z, &g, &mask, 270.0, &p).unwrap();
    assert_eq!(s[40 + 15], 0.0);
    assert_eq!(s[40 + 10], 0.0);
    assert!(s.iter().all(|v| v.is_finite()));
}

#[test]
fn same_bytes_on_one_and_two_threads() {
    let g = GridGeometry::new(97, 61, 4.0, 6.0).unwrap();
    let z: Vec<f32> = (0..g.len())
        .map(|i| {
            let (c, r) = ((i % 97) as f32, (i / 97) as f32);
            300.0 + 30.0 * (c * 0.21).sin() * (r * 0.13).cos() + 4.0 * (c * r * 0.01).sin()
        })
        .collect();
    let run = |threads: usize, from: f64| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| sx(&z, &g, from, &ShelteringParams::default()))
    };
    for from in [270.0, 33.0, 181.5] {
        let (a, b) = (run(1, from), run(2, from));
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a), bits(&b), "wind from {from}");
        assert!(a.iter().any(|&v| v > 1.0) && a.iter().any(|&v| v < -1.0));
    }
}

#[test]
fn bad_inputs_are_typed_errors() {
    let (z, g) = plane(8, 8, 5.0, 0.0, 0.0);
    let m = NodataMask::all_valid();
    let bad = ShelteringParams {
        dmax_m: 0.0,
        ..Default::default()
    };
    assert!(matches!(
        max_upwind_slope(&z, &g, &m, 270.0, &bad),
        Err(EnvironmentError::InvalidParameter {
            name: "sheltering.dmax_m",
            ..
        })
    ));
    let bad = ShelteringParams {
        window_step_deg: f64::NAN,
        ..Default::default()
    };
    assert!(bad.validate().is_err());
    let p = ShelteringParams::default();
    assert!(max_upwind_slope(&z, &g, &m, f64::INFINITY, &p).is_err());
    assert!(matches!(
        max_upwind_slope(&z[..10], &g, &m, 270.0, &p),
        Err(EnvironmentError::LengthMismatch { .. })
    ));
    assert_eq!(
        p.directions(270.0),
        vec![255.0, 260.0, 265.0, 270.0, 275.0, 280.0, 285.0]
    );
    let json = serde_json::to_string(&p).unwrap();
    assert_eq!(serde_json::from_str::<ShelteringParams>(&json).unwrap(), p);
    assert!(serde_json::from_str::<ShelteringParams>(r#"{"dmax": 3}"#).is_err());
}

#[test]
fn the_search_is_bounded_by_the_grid_not_by_dmax_over_the_cell_size() {
    // 1 cm cells and the default 100 m search once padded the grid by 10 000 cells a side
    // (1.5 GB for 32×32 cells); 1e-320 m cells overflowed the pad and panicked.
    let p = ShelteringParams::default();
    for (cell, n) in [(0.01, 32), (1e-6, 32), (1e-300, 8), (0.5, 4096)] {
        let g = GridGeometry::square(n, n, cell).unwrap();
        let steps = p.steps(&g);
        let diagonal_cells = (2f64.sqrt() * n as f64).ceil() as usize + 1;
        assert!(
            steps <= diagonal_cells.min(MAX_SX_STEPS),
            "{cell} m cells, {n}²: {steps} steps"
        );
    }
    // Where the search fits, nothing changes: 100 m on 5 m cells is 20 steps.
    assert_eq!(p.steps(&GridGeometry::square(64, 64, 5.0).unwrap()), 20);
    // A tiny-cell terrain runs, with a padded copy bounded by its cells.
    let (z, g) = plane(32, 32, 0.01, 0.1, 0.0);
    let s = sx(&z, &g, 270.0, &p);
    assert!(s.iter().all(|v| v.is_finite()));
}
