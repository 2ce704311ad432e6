//! The growth mode (Eq. 2 with a four-neighbour Laplacian) against the closed-form solution
//! of the 1D rod with zero-height ends (von Festenberg & Gumhold 2011, Fig. 2).
//!
//! The rod is a trough: a floor over x in [0, 1] three columns wide, with walls along both
//! long sides (no flux) and open ends (drops: the snow boundary, h = 0 at x = 0 and x = 1).
//! Every site of the middle row must match `rod_solution` to 1 % of its peak at t = 20 and
//! t = 80 for the three coefficients of Fig. 2.

mod common;
use common::{cube, quad, scene};
use snowscape_festenberg::growth::{GrowthParams, grow, rod_solution};
use snowscape_festenberg::links::links;
use snowscape_festenberg::{CoverParams, FestenbergError, prepare_sites};

#[test]
fn growth_matches_the_rod_solution_of_fig_2() {
    let dx = 0.01f32;
    let floor = quad("floor", [-0.5 * dx, 0.0, 1.0 + 0.5 * dx, 3.0 * dx], 0.0);
    let south = cube(
        "south wall",
        [-0.5 * dx, -dx, 0.0],
        [1.0 + 0.5 * dx, 0.0, 1.0],
    );
    let north = cube(
        "north wall",
        [-0.5 * dx, 3.0 * dx, 0.0],
        [1.0 + 0.5 * dx, 4.0 * dx, 1.0],
    );
    let s = scene(vec![floor, south, north]);
    let d = dx as f64;
    let params = CoverParams {
        depth_m: Some(0.1),
        resolution_m: Some(d),
        // Column centres at x = -dx, 0, dx, ..., 1, 1 + dx; rows at y = -dx/2 .. 3.5 dx.
        extent_m: Some([-1.5 * d, -d, 1.0 + 1.5 * d, 4.0 * d]),
        ..Default::default()
    };
    let (_, _, field) = prepare_sites(&s, &params, false).unwrap();
    let graph = links(&field);
    let middle_y = 1.5 * d;
    let rod: Vec<(usize, f64)> = (0..field.len())
        .filter_map(|i| {
            let [x, y] = field.column_xy(field.column[i] as usize);
            ((y - middle_y).abs() < 1e-6 && field.z[i] == 0.0).then_some((i, x))
        })
        .collect();
    assert_eq!(rod.len(), 101, "a site every dx from 0 to 1");
    let sigma = 0.01;
    for diffusion in [0.001, 0.01, 0.1] {
        let p = GrowthParams {
            diffusion_m2: diffusion,
            snowfall_m: sigma,
            duration: 80.0,
            frames: 4,
            stability: 0.9,
        };
        grow::<FestenbergError>(&field, &graph, &p, |frame, t, h| {
            if frame != 0 && frame != 3 {
                return Ok(());
            }
            let peak = rod_solution(0.5, t, diffusion, sigma);
            let worst = rod
                .iter()
                .map(|&(i, x)| (h[i] as f64 - rod_solution(x, t, diffusion, sigma)).abs())
                .fold(0.0, f64::max);
            assert!(
                worst <= 0.01 * peak,
                "D = {diffusion}, t = {t}: error {worst} vs peak {peak}"
            );
            // The ends are the snow boundary.
            for &(i, x) in &rod {
                if x.abs() < 1e-6 || (x - 1.0).abs() < 1e-6 {
                    assert_eq!(h[i], 0.0);
                }
            }
            Ok(())
        })
        .unwrap();
    }
}

#[test]
fn the_closed_form_is_the_steady_parabola_for_long_times() {
    // t -> infinity: h = σ x (1 - x) / (2D).
    let h = rod_solution(0.3, 1e6, 0.1, 0.01);
    let steady = 0.01 * 0.3 * 0.7 / 0.2;
    assert!((h - steady).abs() < 1e-9 * steady, "{h} vs {steady}");
    // Early on, away from the ends, the snow is σ t.
    let h = rod_solution(0.5, 2.0, 0.001, 0.01);
    assert!((h - 0.02).abs() < 1e-9, "{h}");
}

#[test]
fn growth_frames_do_not_depend_on_the_thread_count() {
    use snowscape_festenberg::grow_cover;
    let s = scene(vec![
        quad("floor", [0.0, 0.0, 3.0, 2.0], 0.0),
        cube("box", [1.0, 0.5, 0.0], [1.6, 1.5, 0.5]),
    ]);
    let params = CoverParams {
        depth_m: Some(0.1),
        resolution_m: Some(0.05),
        ..Default::default()
    };
    let growth = GrowthParams {
        diffusion_m2: 0.02,
        snowfall_m: 0.1,
        duration: 1.0,
        frames: 3,
        stability: 0.9,
    };
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut frames = Vec::new();
                grow_cover::<FestenbergError>(&s, &params, &growth, |_, _, m| {
                    frames.push(m);
                    Ok(())
                })
                .unwrap();
                frames
            })
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one.len(), 3);
    assert!(one[2].triangles.len() > 100);
    // The snow grows frame by frame.
    let top = |m: &snowscape_mesh::SnowObject| m.positions.iter().map(|p| p[2]).fold(0.0, f32::max);
    assert!(top(&one[0]) < top(&one[2]));
    assert_eq!(one, two);
}
