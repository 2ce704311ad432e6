//! Physics of temperature and wind.

mod common;

use common::{rough, terrain};
use snowscape_environment::{
    EnvironmentParams, TemperatureParams, WindParams, precompute, temperature, wind,
};
use snowscape_terrain::NodataMask;

#[test]
fn temperature_lapse_rate_on_a_ramp_matches_kt() {
    // A ramp rising 5 % eastwards from 500 m: every interior cell has
    // the same normal, hence the same exposure, so T differences are kt·ΔA alone.
    let (z, g) = terrain(80, 40, 20.0, |x, _| 500.0 + 0.05 * x);
    let all = NodataMask::all_valid();
    let p = EnvironmentParams::default();
    let maps = precompute(&z, &g, &all, &p).unwrap();
    let (w, interior) = (80, |c: usize, r: usize| {
        (10..70).contains(&c) && (10..30).contains(&r)
    });
    let (mut n, mut sa, mut st, mut saa, mut sat) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for r in 0..40 {
        for c in 0..80 {
            if interior(c, r) {
                let (a, t) = (z[r * w + c] as f64, maps.temperature[r * w + c] as f64);
                n += 1.0;
                sa += a;
                st += t;
                saa += a * a;
                sat += a * t;
            }
        }
    }
    let slope = (n * sat - sa * st) / (n * saa - sa * sa);
    assert!(
        (slope - p.temperature.kt).abs() < 1e-4,
        "lapse rate {slope}"
    );
    // Direct check of the formula on one cell.
    let i = 20 * w + 40;
    let expect = p.temperature.t0_c
        + p.temperature.kt * z[i] as f64
        + p.temperature.ki * maps.irradiance[i] as f64;
    assert!((maps.temperature[i] as f64 - expect).abs() < 1e-4);
    // And the standalone function: 1000 m and 10 h of sun with the defaults: -10 + 4.1 °C.
    let t = temperature(&[1000.0], &[10.0], &all, &TemperatureParams::default()).unwrap();
    assert!((t[0] + 5.9).abs() < 1e-5, "{}", t[0]);
}

/// A north-south ridge 100 m high across a plain at 0 m, 5 m cells, crest at x = 300 m,
/// flanks of slope 0.5; wind from the west.
fn ridge() -> (Vec<f32>, snowscape_terrain::GridGeometry) {
    terrain(160, 40, 5.0, |x, _| {
        (100.0 - 0.5 * (x - 300.0).abs()).max(0.0)
    })
}

#[test]
fn ridge_casts_a_wind_shadow_leeward_only() {
    let (z, g) = ridge();
    // The paper's c (0.7 m/s²): a cap longer than the 10-cell window checked below.
    let p = WindParams {
        direction_deg: 270.0,
        c_m_s2: 0.7,
        ..WindParams::default()
    };
    let m = wind(&z, &g, &NodataMask::all_valid(), &p).unwrap();
    assert!(m.stats.converged, "{:?}", m.stats);
    let w = 160;
    let crest = 60; // x = 302.5 m; the crest lies between columns 59 and 60
    for r in 0..40 {
        // Windward (west) flank and the plain before it: no shadow.
        for c in 0..crest - 1 {
            assert_eq!(m.shadow[r * w + c], 0.0, "windward shadow at ({c},{r})");
            assert_eq!(m.effect_surface[r * w + c], z[r * w + c]);
        }
        // Leeward: the cells just past the crest are in the shadow, and the wind-effect
        // surface stays above the ground down the flank.
        for c in crest + 1..crest + 10 {
            assert_eq!(m.shadow[r * w + c], 1.0, "no lee shadow at ({c},{r})");
            assert!(m.effect_surface[r * w + c] > z[r * w + c] + 1.0);
        }
        // Far downwind on the plain the surface is back on the ground.
        assert_eq!(m.shadow[r * w + 155], 0.0);
    }
    // Turning the wind around moves the shadow to the other side.
    let p = WindParams {
        direction_deg: 90.0,
        ..p
    };
    let m = wind(&z, &g, &NodataMask::all_valid(), &p).unwrap();
    assert_eq!(m.shadow[20 * w + crest + 5], 0.0);
    assert_eq!(m.shadow[20 * w + crest - 6], 1.0);
}

#[test]
fn wind_speeds_up_with_altitude() {
    let all = NodataMask::all_valid();
    // Measured from sea level, as in the paper.
    let p = WindParams {
        venturi_base_m: Some(0.0),
        ..WindParams::default()
    };
    // Flat plateaus: |W| = (1 + kventuri A)|Wd| exactly.
    for a in [0.0f64, 500.0, 2000.0] {
        let (z, g) = terrain(20, 20, 10.0, |_, _| a);
        let m = wind(&z, &g, &all, &p).unwrap();
        let speed = m.u[210].hypot(m.v[210]) as f64;
        let expect = (1.0 + p.k_venturi * a) * p.speed_m_s;
        assert!(
            (speed - expect).abs() < 1e-3 * expect,
            "A = {a}: {speed} vs {expect}"
        );
    }
    // Measured from a base altitude instead of sea level: |Wd| at the base.
    let (z, g) = terrain(20, 20, 10.0, |_, _| 1500.0);
    let based = WindParams {
        venturi_base_m: Some(1000.0),
        ..p.clone()
    };
    let m = wind(&z, &g, &all, &based).unwrap();
    assert!((m.u[210].hypot(m.v[210]) - 15.0).abs() < 1e-3);
    // By default from the terrain's lowest altitude: a flat plateau at any altitude gets |Wd|.
    let m = wind(&z, &g, &all, &WindParams::default()).unwrap();
    assert!((m.u[210].hypot(m.v[210]) - 10.0).abs() < 1e-3);
    // On a uniform ramp (same slope everywhere) the speed grows monotonically with altitude.
    let (z, g) = terrain(60, 10, 10.0, |x, _| 100.0 + 0.1 * x);
    let m = wind(&z, &g, &all, &p).unwrap();
    let speed = |c: usize| m.u[5 * 60 + c].hypot(m.v[5 * 60 + c]);
    for c in 2..57 {
        assert!(speed(c + 1) > speed(c), "column {c}");
    }
}

#[test]
fn red_black_gauss_seidel_converges_and_ignores_thread_count() {
    let (z, g) = terrain(96, 80, 10.0, rough);
    let all = NodataMask::all_valid();
    // From the paper's initial state (no ordered sweeps): pure red-black iterations.
    let p = WindParams {
        direction_deg: 300.0,
        ordered_sweeps: 0,
        max_iterations: 3000,
        tolerance_m: 1e-4,
        c_m_s2: 0.7,
        ..WindParams::default()
    };
    let run = |threads: usize, p: &WindParams| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| wind(&z, &g, &all, p).unwrap())
    };
    let one = run(1, &p);
    let three = run(3, &p);
    let h = &one.stats.residual_history;
    assert!(one.stats.converged && h.len() > 10, "{:?}", one.stats);
    assert!(*h.last().unwrap() < 1e-4);
    assert_eq!(one.effect_surface, three.effect_surface);
    assert_eq!(one.stats, three.stats);
    // The error of the iterate decreases: stop after k iterations and measure the L1
    // distance to the converged surface.
    let n = one.stats.iterations;
    let mut last = f64::INFINITY;
    for k in [1, n / 8, n / 4, n / 2, 3 * n / 4, n - 2] {
        let partial = run(
            2,
            &WindParams {
                max_iterations: k,
                ..p.clone()
            },
        );
        let err: f64 = partial
            .effect_surface
            .iter()
            .zip(&one.effect_surface)
            .map(|(a, b)| (a - b).abs() as f64)
            .sum();
        assert!(err < last, "error after {k} iterations {err} >= {last}");
        last = err;
    }
    assert!(last > 0.0);
    // One sweep in wind order solves the same upwind system: red-black confirms it at once.
    let fast = run(
        3,
        &WindParams {
            ordered_sweeps: 1,
            ..p.clone()
        },
    );
    assert_eq!(fast.stats.iterations, 1, "{:?}", fast.stats);
    for (a, b) in one.effect_surface.iter().zip(&fast.effect_surface) {
        assert!((a - b).abs() < 1e-3, "{a} vs {b}");
    }
    // The rough terrain has real wind shadows.
    assert!(fast.shadow.iter().filter(|&&s| s == 1.0).count() > 200);
}
