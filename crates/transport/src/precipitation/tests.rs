use super::*;
use crate::wind3d::{Wind3dParams, WindSolver};
use snowscape_terrain::GridGeometry;

fn flat_grid(n: usize, nz: usize, cell: f64) -> VoxelGrid {
    let g = GridGeometry::square(n, n, cell).unwrap();
    VoxelGrid::from_heights(&g, &vec![cell as f32; n * n], cell, nz, 0.0).unwrap()
}

fn uniform_wind(grid: &VoxelGrid, u: f32) -> Velocity {
    let mut v = Velocity::zeros(grid.nx, grid.ny, grid.nz);
    v.u.data.iter_mut().for_each(|x| *x = u);
    v
}

#[test]
fn terminal_speed_matches_hand_value() {
    // k = 3 · 1.225 · 0.47 / (4 · 0.002 · 22) = 1.727250 / 0.176 = 9.81392 m⁻¹;
    // v_t = √(9.81 / 9.81392) = 0.999800 m/s.
    let p = FlakeParams::default();
    assert!((p.drag_constant() - 9.813_92).abs() < 1e-4);
    assert!((p.terminal_speed() - 0.999_800).abs() < 1e-5);
}

#[test]
fn open_flat_ground_gets_uniform_snow() {
    let grid = flat_grid(16, 12, 2.0);
    let wind = uniform_wind(&grid, 5.0);
    let params = FlakeParams {
        count: 150_000,
        ..Default::default()
    };
    let map = precipitation_map(&grid, &wind, [5.0, 0.0], &params).unwrap();
    assert!(map.flakes.landed > 20_000, "{}", map.flakes.landed);
    let mean = map.ratio.iter().map(|&r| f64::from(r)).sum::<f64>() / map.ratio.len() as f64;
    assert!((mean - 1.0).abs() < 0.02, "mean {mean}");
    for (i, r) in map.ratio.iter().enumerate() {
        assert!((r - 1.0).abs() < 0.1, "cell {i}: {r}");
    }
}

/// A wind ten to twenty times the fall speed, growing with height like a log law: most
/// flakes enter across the upwind side, yet open flat ground still gets uniform snow, right
/// up to the upwind edge. (Only the flakes entering low land: at 15 m/s aloft a flake
/// drifts 15 m per metre of fall, and the domain is 48 m long.)
#[test]
fn strong_sheared_wind_still_gives_uniform_snow() {
    let grid = flat_grid(24, 20, 2.0);
    let mut wind = Velocity::zeros(grid.nx, grid.ny, grid.nz);
    let (nx, ny) = (wind.u.dims[0], wind.u.dims[1]);
    for (n, u) in wind.u.data.iter_mut().enumerate() {
        let k = n / (nx * ny);
        // Ground voxels are solid (layer 0): the profile starts above them.
        let above = (k as f64 - 0.5).max(0.05) * 2.0;
        *u = (10.0 * (above / 0.1).ln() / (5.0f64 / 0.1).ln()) as f32;
    }
    let params = FlakeParams {
        count: 200_000,
        launch_clearance_m: 30.0,
        ..Default::default()
    };
    let map = precipitation_map(&grid, &wind, [10.0, 0.0], &params).unwrap();
    assert!(
        map.flakes.side_share > 0.8,
        "side share {}",
        map.flakes.side_share
    );
    assert!(map.flakes.landed > 15_000, "{}", map.flakes.landed);
    let cols: Vec<f64> = (0..24)
        .map(|c| (0..24).map(|r| map.counts[r * 24 + c] as f64).sum::<f64>() / 24.0)
        .collect();
    eprintln!("DBG {cols:.1?}");
    for (i, r) in map.ratio.iter().enumerate() {
        assert!((r - 1.0).abs() < 0.1, "cell {i}: {r}");
    }
}

#[test]
fn maps_are_deterministic_across_thread_counts() {
    let grid = flat_grid(12, 8, 2.0);
    let wind = uniform_wind(&grid, 3.0);
    let params = FlakeParams {
        count: 20_000,
        seed: 42,
        ..Default::default()
    };
    let go = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| precipitation_map(&grid, &wind, [3.0, 0.0], &params).unwrap())
    };
    assert_eq!(go(1), go(2));
    let other = FlakeParams {
        seed: 43,
        ..params.clone()
    };
    assert_ne!(
        go(2).counts,
        precipitation_map(&grid, &wind, [3.0, 0.0], &other)
            .unwrap()
            .counts
    );
}

#[test]
fn the_lee_of_a_wall_gets_little_snow() {
    // A north-south wall 8 m high across a west wind of 6 m/s, 2 m voxels.
    let (nx, ny, cell) = (48, 8, 2.0);
    let g = GridGeometry::new(nx, ny, cell, cell).unwrap();
    let z: Vec<f32> = (0..nx * ny)
        .map(|i| if i % nx == 12 { 8.0 } else { 0.0 })
        .collect();
    let grid = VoxelGrid::from_heights(&g, &z, cell, 16, -cell).unwrap();
    let mut solver = WindSolver::new(
        grid.clone(),
        Wind3dParams {
            speed_m_s: 6.0,
            ..Default::default()
        },
    )
    .unwrap();
    for _ in 0..10 {
        solver.iterate();
    }
    let params = FlakeParams {
        count: 200_000,
        ..Default::default()
    };
    let map = precipitation_map(&grid, &solver.mean_velocity(), [6.0, 0.0], &params).unwrap();
    let col_mean = |c0: usize, c1: usize| {
        let mut s = 0.0;
        for r in 0..ny {
            for c in c0..c1 {
                s += f64::from(map.ratio[r * nx + c]);
            }
        }
        s / ((c1 - c0) * ny) as f64
    };
    // The map's mean is 1; the wall's lee (3-7 cells behind it) gets a third of it, about
    // half of what open ground upwind gets, and the snow it misses lands further on.
    let upwind = col_mean(2, 8);
    let lee = col_mean(15, 20);
    let beyond = col_mean(30, 46);
    assert!(lee < 0.4, "lee {lee}");
    assert!(lee < 0.6 * upwind, "lee {lee} vs upwind {upwind}");
    assert!(beyond > 1.0, "beyond {beyond}");
}

#[test]
fn outliers_are_high_spikes_only() {
    let (w, h) = (9, 9);
    let mut r: Vec<f32> = (0..w * h)
        .map(|i| 1.0 + 0.05 * ((i % 3) as f32 - 1.0))
        .collect();
    r[4 * w + 4] = 9.0; // a pile at the foot of a wall
    r[0] = 0.0; // a sheltered cell stays
    let n = replace_outliers(&mut r, w, h);
    assert_eq!(n, 1);
    assert!((r[4 * w + 4] - 1.0).abs() < 0.05);
    assert_eq!(r[0], 0.0);
    // The Gaussian keeps a constant map constant, borders included.
    let g = gaussian_11(&vec![0.7; w * h], w, h, 2.0);
    assert!(g.iter().all(|v| (v - 0.7).abs() < 1e-6));
}
