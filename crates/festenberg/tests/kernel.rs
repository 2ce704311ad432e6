//! The snow diffusion kernel (Section 5.2) and bridges (Section 5.1) on scenes with known
//! answers: a floating plate (snow vanishes at its edges, is h0 far from them), a floor with a
//! low and a high table (capacity never exceeded), two plates with a gap (bridged when
//! shorter than bmax), the fast path against the member-by-member reading, and the
//! independence of the results from the thread count.

mod common;
use common::{cube, quad, scene};
use snowscape_festenberg::kernel::{evaluate, evaluate_reference};
use snowscape_festenberg::{CoverParams, cover, prepare_sites};
use snowscape_mesh::Scene;

fn plate() -> Scene {
    scene(vec![cube("plate", [0.0, 0.0, 0.9], [4.0, 4.0, 1.0])])
}

fn plate_params() -> CoverParams {
    CoverParams {
        depth_m: Some(0.2),
        radius_m: Some(0.5),
        resolution_m: Some(0.05),
        bridge_m: Some(0.0),
        ..Default::default()
    }
}

#[test]
fn snow_vanishes_at_edges_and_is_h0_far_from_them() {
    let c = cover(&plate(), &plate_params()).unwrap();
    let f = &c.field;
    let (mut edge_sites, mut inner_sites) = (0, 0);
    for i in 0..f.len() {
        let [x, y] = f.column_xy(f.column[i] as usize);
        let d = x.min(y).min(4.0 - x).min(4.0 - y); // distance to the plate's edge
        let h = c.kernel.height[i];
        if d < 0.05 {
            // The outermost row of sites is the snow boundary.
            assert_eq!(h, 0.0, "edge site at ({x}, {y})");
            edge_sites += 1;
        } else if d + 0.025 > 0.5 + 1e-6 {
            // No empty column (centres half a column past the edge) within R.
            assert_eq!(h, 0.2, "inner site at ({x}, {y})");
            inner_sites += 1;
        } else {
            assert!(h > 0.0 && h < 0.2, "{h} at ({x}, {y})");
        }
    }
    assert_eq!(edge_sites, 4 * 79);
    assert!(inner_sites > 2000);
    // Rounded: along a line from the edge inwards the height rises monotonically.
    let mut profile: Vec<(f64, f32)> = (0..f.len())
        .filter_map(|i| {
            let [x, y] = f.column_xy(f.column[i] as usize);
            ((y - 2.025).abs() < 1e-6 && x < 1.0).then_some((x, c.kernel.height[i]))
        })
        .collect();
    profile.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert!(profile.windows(2).all(|w| w[1].1 >= w[0].1), "{profile:?}");
    // The mesh meets the plate at its boundary and no vertex is below the plate.
    assert!(c.mesh.positions.iter().all(|p| p[2] >= 1.0 - 1e-6));
    assert!(c.stats.boundary_loops >= 1);
    let uvs = c.mesh.uvs.as_ref().unwrap();
    assert!(uvs.iter().all(|uv| (0.0..=1.0).contains(&uv[1])));
}

#[test]
fn capacity_is_never_exceeded() {
    // A floor with a low table (0.1 m of room, under h0 = 0.2) and a high one (1 m).
    let s = scene(vec![
        quad("floor", [0.0, 0.0, 6.0, 4.0], 0.0),
        cube("low table", [0.5, 0.5, 0.1], [2.5, 3.5, 0.15]),
        cube("high table", [3.5, 0.5, 1.0], [5.5, 3.5, 1.1]),
    ]);
    let p = CoverParams {
        depth_m: Some(0.2),
        radius_m: Some(0.4),
        resolution_m: Some(0.05),
        bridge_m: Some(0.0),
        ..Default::default()
    };
    let c = cover(&s, &p).unwrap();
    let f = &c.field;
    let mut under_tables = 0;
    for i in 0..f.len() {
        assert!(c.kernel.height[i] <= f.capacity[i], "site {i}");
        if f.capacity[i].is_finite() {
            under_tables += 1;
        }
    }
    assert!(under_tables > 1000, "{under_tables}");
    // Under the middle of the high table nothing is visible: no snow.
    for i in 0..f.len() {
        let [x, y] = f.column_xy(f.column[i] as usize);
        if (x - 4.5).abs() < 0.3 && (y - 2.0).abs() < 0.3 && f.z[i] == 0.0 {
            assert_eq!(c.kernel.height[i], 0.0, "({x}, {y})");
        }
    }
    // No snow vertex pierces the surface above its site.
    let (_, _, field) = prepare_sites(&s, &p, false).unwrap();
    for v in &c.mesh.positions {
        let col = ((v[0] as f64 - field.origin[0]) / field.cell_size) as usize;
        let row = field.height - 1 - ((v[1] as f64 - field.origin[1]) / field.cell_size) as usize;
        let sites = field.column_sites(row * field.width + col);
        let below = sites.clone().rfind(|&k| field.z[k] <= v[2] + 1e-5);
        let k = below.expect("a site under every vertex");
        assert!(v[2] <= field.z[k] + field.capacity[k] + 1e-5, "{v:?}");
    }
}

#[test]
fn a_gap_shorter_than_bmax_is_bridged_and_a_longer_one_is_not() {
    for (gap, bridged) in [(0.4f32, true), (1.6, false)] {
        let s = scene(vec![
            cube("west plate", [0.0, 0.0, 0.9], [3.0, 3.0, 1.0]),
            cube("east plate", [3.0 + gap, 0.0, 0.9], [6.0 + gap, 3.0, 1.0]),
        ]);
        let p = CoverParams {
            depth_m: Some(0.2),
            radius_m: Some(0.5),
            resolution_m: Some(0.05),
            bridge_m: Some(0.8),
            ..Default::default()
        };
        let c = cover(&s, &p).unwrap();
        let mid_x = 3.0 + 0.5 * gap;
        let over_gap: Vec<f32> = c
            .mesh
            .positions
            .iter()
            .filter(|v| (v[0] - mid_x).abs() < 0.06 && v[2] > 0.95)
            .map(|v| v[2])
            .collect();
        if bridged {
            assert!(c.stats.bridge_sites > 0);
            assert!(!over_gap.is_empty(), "no snow over the {gap} m gap");
            // Away from the plates' sides the bridge carries snow, under the plates' top + h0.
            assert!(over_gap.iter().any(|&z| z > 1.05) && over_gap.iter().all(|&z| z < 1.4));
        } else {
            assert_eq!(c.stats.bridge_sites, 0);
            assert!(
                over_gap.is_empty(),
                "snow over the {gap} m gap: {over_gap:?}"
            );
        }
    }
}

/// The fast path (columns of one site or none, eight at a time) gives the bits of the
/// member-by-member reading, on a scene with empty columns around it, drops, a box and a table
/// (columns of two sites), for a kernel of a few columns and larger ones.
#[test]
fn the_fast_path_gives_the_member_by_member_bits() {
    let s = scene(vec![
        quad("floor", [0.0, 0.0, 5.0, 4.0], 0.0),
        cube("box", [1.0, 1.0, 0.0], [2.0, 2.5, 0.6]),
        cube("table", [3.0, 0.5, 0.5], [4.5, 3.5, 0.6]),
        cube("shelf", [0.5, 3.0, 0.2], [1.5, 3.5, 0.25]),
    ]);
    for radius in [0.06, 0.35, 1.2] {
        let p = CoverParams {
            depth_m: Some(0.15),
            radius_m: Some(radius),
            resolution_m: Some(0.05),
            bridge_m: Some(0.3),
            ..Default::default()
        };
        let (r, _, field) = prepare_sites(&s, &p, true).unwrap();
        let reference = evaluate_reference(&field, r.radius_m);
        assert!(reference.height.iter().any(|&h| h > 0.0));
        assert!(reference.edge.iter().any(|&e| e < 1.0), "no edge within R");
        assert_eq!(evaluate(&field, r.radius_m), reference, "radius {radius} m");
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let p = CoverParams {
        overhang: true,
        ..plate_params()
    };
    let s = plate();
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| cover(&s, &p).unwrap())
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one.kernel, two.kernel);
    assert_eq!(one.mesh, two.mesh);
}

#[test]
fn the_concave_corner_of_an_l_is_cut_and_the_mesh_is_manifold() {
    let s = scene(vec![
        quad("long arm", [0.0, 0.0, 2.0, 1.0], 1.0),
        quad("short arm", [0.0, 1.0, 1.0, 2.0], 1.0),
    ]);
    let p = CoverParams {
        depth_m: Some(0.05),
        radius_m: Some(0.2),
        resolution_m: Some(0.05),
        bridge_m: Some(0.0),
        ..Default::default()
    };
    let c = cover(&s, &p).unwrap();
    assert!(c.stats.corner_triangles >= 1, "{:?}", c.stats);
    assert!(c.stats.quads > 500);
    let mut edges = std::collections::HashMap::new();
    for t in &c.mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            // Positions, not indices: seam copies share a position.
            let key = |i: u32| c.mesh.positions[i as usize].map(f32::to_bits);
            let (ka, kb) = (key(a), key(b));
            *edges
                .entry(if ka < kb { (ka, kb) } else { (kb, ka) })
                .or_insert(0) += 1;
        }
        // Counter-clockwise from above: the normal points up.
        let [a, b, c3] = t.map(|i| c.mesh.positions[i as usize]);
        let nz = (b[0] - a[0]) * (c3[1] - a[1]) - (b[1] - a[1]) * (c3[0] - a[0]);
        assert!(nz > 0.0, "triangle {t:?} faces down");
    }
    assert!(edges.values().all(|&n| n <= 2), "a non-manifold edge");
    assert_eq!(c.stats.boundary_loops, 1);
}
