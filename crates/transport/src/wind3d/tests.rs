use super::voxel::{VoxelGrid, castle_heights};
use super::*;
use snowscape_terrain::GridGeometry;

fn flat(nx: usize, ny: usize, nz: usize, cell: f64) -> VoxelGrid {
    let g = GridGeometry::square(nx, ny, cell).unwrap();
    let z = vec![cell as f32; nx * ny]; // one solid ground layer
    VoxelGrid::from_heights(&g, &z, cell, nz, 0.0).unwrap()
}

#[test]
fn uniform_flow_over_a_flat_plate_keeps_its_inflow_speed() {
    let params = Wind3dParams {
        speed_m_s: 8.0,
        from_deg: 250.0, // oblique: enters through the west and south sides
        inflow_roughness_m: 0.0,
        viscosity_m2_s: 0.0,
        ..Default::default()
    };
    let [ux, uy] = params.inflow();
    let mut s = WindSolver::new(flat(20, 16, 8, 2.0), params).unwrap();
    for _ in 0..6 {
        let r = s.iterate();
        assert!(r.relative_divergence < 1e-5, "{r:?}");
    }
    let m = s.mean_velocity();
    for k in 1..8 {
        for j in 0..16 {
            for i in 0..=20 {
                let u = m.u.data[m.u.index(i, j, k)];
                assert!((f64::from(u) - ux).abs() < 1e-3 * 8.0, "u {i},{j},{k}: {u}");
            }
        }
    }
    for k in 1..8 {
        for j in 0..=16 {
            for i in 0..20 {
                let v = m.v.data[m.v.index(i, j, k)];
                assert!((f64::from(v) - uy).abs() < 1e-3 * 8.0, "v {i},{j},{k}: {v}");
            }
        }
    }
    assert!(m.w.data.iter().all(|w| w.abs() < 1e-3));
}

#[test]
fn log_profile_over_a_flat_plate_keeps_its_speed_with_viscosity() {
    let params = Wind3dParams::default(); // 11 m/s from the west at 5 m, z0 = 0.1 m
    let mut s = WindSolver::new(flat(24, 6, 12, 1.0), params).unwrap();
    for _ in 0..10 {
        s.iterate();
    }
    // At 5 m above the ground, across the domain, the wind stays within 2 % of 11 m/s.
    let (u, v) = s.wind_at_height(5.0);
    for (a, b) in u.iter().zip(&v) {
        assert!((a - 11.0).abs() < 0.22 && b.abs() < 0.05, "{a} {b}");
    }
}

/// A north wind over a hill: the west and east sides, parallel to it, are symmetry planes
/// (no air crosses them, where left open the lifted air would leave sideways), and the
/// flow still goes round and over the hill, divergence-free.
#[test]
fn sides_parallel_to_the_wind_are_closed() {
    let (n, cell) = (24, 10.0);
    let g = GridGeometry::square(n, n, cell).unwrap();
    let z: Vec<f32> = (0..n * n)
        .map(|c| {
            let (x, y) = ((c % n) as f32 - 11.5, (c / n) as f32 - 11.5);
            10.0 + 60.0 * (-(x * x + y * y) / 20.0).exp()
        })
        .collect();
    let grid = VoxelGrid::from_heights(&g, &z, cell, 12, 0.0).unwrap();
    let params = Wind3dParams {
        speed_m_s: 10.0,
        from_deg: 0.0,
        ..Default::default()
    };
    assert_eq!(params.inflow()[0], 0.0);
    let mut s = WindSolver::new(grid, params).unwrap();
    for _ in 0..6 {
        s.iterate();
    }
    let report = s.project_mean();
    assert!(report.relative_divergence < 1e-5, "{report:?}");
    let m = s.mean_velocity();
    for k in 0..12 {
        for j in 0..n {
            assert_eq!(m.u.data[m.u.index(0, j, k)], 0.0);
            assert_eq!(m.u.data[m.u.index(n, j, k)], 0.0);
        }
    }
    // The hill deflects the flow sideways inside the domain.
    let side = m.u.data.iter().fold(0.0f32, |a, &u| a.max(u.abs()));
    assert!(side > 0.5, "largest east-west wind {side}");
}

fn castle_solver() -> WindSolver {
    let n = 48;
    let cell = 4.0;
    let g = GridGeometry::square(n, n, cell).unwrap();
    let z = castle_heights(n, cell);
    let vox = VoxelGrid::from_heights(&g, &z, cell, 12, -4.0).unwrap();
    WindSolver::new(vox, Wind3dParams::default()).unwrap()
}

#[test]
fn castle_wind_is_divergence_free_and_never_enters_solids() {
    let mut s = castle_solver();
    for _ in 0..4 {
        let r = s.iterate();
        // Each iteration is projected to the loose `tolerance` (1e-3 of the divergence
        // left by advection) ...
        assert!(r.relative_divergence < 1e-3, "{r:?}");
        assert!(r.solver_iterations < 500);
    }
    assert_eq!(s.max_flow_into_solids(), 0.0);
    // ... and the mean wind to `mean_tolerance` (1e-6).
    let r = s.project_mean();
    assert!(r.relative_divergence < 1e-5, "{r:?}");
    let m = s.mean_velocity();
    let g = s.grid();
    // No mean flow through any face of a solid voxel either.
    for k in 0..g.nz {
        for j in 0..g.ny {
            for i in 0..g.nx {
                if g.is_solid(i, j, k) {
                    assert_eq!(m.u.data[m.u.index(i, j, k)], 0.0);
                    assert_eq!(m.u.data[m.u.index(i + 1, j, k)], 0.0);
                    assert_eq!(m.w.data[m.w.index(i, j, k + 1)], 0.0);
                }
            }
        }
    }
}

#[test]
fn loose_iterations_give_the_mean_wind_of_exact_ones() {
    // The mean wind of iterations projected to 1e-3, projected at the end to 1e-6, matches
    // the mean of iterations each projected to 1e-6: within 0.1 % of the wind speed.
    let run = |tolerance: f64| {
        let mut s = castle_solver();
        s.params.tolerance = tolerance;
        for _ in 0..8 {
            s.iterate();
        }
        s.project_mean();
        s.wind_at_height(3.0)
    };
    let (loose_u, loose_v) = run(1e-3);
    let (exact_u, exact_v) = run(1e-6);
    let worst = loose_u
        .iter()
        .zip(&exact_u)
        .chain(loose_v.iter().zip(&exact_v))
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-3 * 11.0, "largest difference {worst} m/s");
}

#[test]
fn the_lee_of_the_castle_wall_is_sheltered() {
    let mut s = castle_solver();
    for _ in 0..8 {
        s.iterate();
    }
    let (u, _) = s.wind_at_height(3.0);
    let n = 48;
    // Row through the middle, west wind: upwind open ground vs just inside the west wall.
    let row = n / 2 + 4; // away from the gate
    let upwind = u[row * n + 5];
    let lee = u[row * n + 18]; // the west wall is near x = 0.35 · 192 m = 67 m, column 16-17
    assert!(upwind > 8.0, "upwind {upwind}");
    assert!(lee < 0.5 * upwind, "lee {lee} vs upwind {upwind}");
}

#[test]
fn wind_does_not_depend_on_the_thread_count() {
    let go = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut s = castle_solver();
            s.iterate();
            s.iterate();
            s.mean_velocity()
        })
    };
    assert_eq!(go(1), go(2));
}

#[test]
fn mean_wind_file_has_its_header_and_three_fields() {
    let mut s = WindSolver::new(flat(6, 5, 4, 2.0), Wind3dParams::default()).unwrap();
    s.iterate();
    let bytes = s.mean_wind_bytes();
    assert_eq!(&bytes[..8], b"SNOWWIND");
    assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()), 6);
    assert_eq!(bytes.len(), 8 + 12 + 16 + 3 * 4 * 6 * 5 * 4);
}
