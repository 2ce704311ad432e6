use super::*;
use crate::wind3d::{WindParams, WindSolver};
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
    // v_t = √(9.80665 / 9.81392) = 0.999630 m/s.
    let p = FlakeParams::default();
    assert!((p.drag_constant() - 9.813_92).abs() < 1e-4);
    assert!((p.terminal_speed() - 0.999_630).abs() < 1e-5);
}

#[test]
fn open_flat_ground_gets_uniform_snow() {
    let grid = flat_grid(16, 12, 2.0);
    let wind = uniform_wind(&grid, 5.0);
    let params = FlakeParams {
        count: 150_000,
        ..Default::default()
    };
    let map = precipitation_map(&grid, &wind, &params).unwrap();
    assert!(map.landed > 20_000, "{}", map.landed);
    let mean = map.ratio.iter().map(|&r| f64::from(r)).sum::<f64>() / map.ratio.len() as f64;
    assert!((mean - 1.0).abs() < 0.02, "mean {mean}");
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
            .install(|| precipitation_map(&grid, &wind, &params).unwrap())
    };
    assert_eq!(go(1), go(2));
    let other = FlakeParams {
        seed: 43,
        ..params.clone()
    };
    assert_ne!(
        go(2).counts,
        precipitation_map(&grid, &wind, &other).unwrap().counts
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
        WindParams {
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
    let map = precipitation_map(&grid, &solver.mean_velocity(), &params).unwrap();
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
