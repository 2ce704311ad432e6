//! Behaviour of the Fearing 2000 cover on scenes built in code (the test list).

use snowscape_fearing::{FearingCover, FearingParams, Material, SkyWeight, cover, scenes};
use snowscape_mesh::Scene;

/// Small, fast settings: a few thousand sites.
fn quick(material: Material) -> FearingParams {
    FearingParams {
        target_sites: 4000,
        flakes_per_site: 32,
        budget_s: 600.0,
        ..FearingParams::with_material(material)
    }
}

struct Site {
    object: String,
    p: [f64; 3],
    depth: f64,
    level: u8,
}

fn sites(scene: &Scene, c: &FearingCover) -> Vec<Site> {
    c.topology
        .leaves
        .iter()
        .map(|&id| {
            let cell = &c.sites.cells[id as usize];
            Site {
                object: scene.objects[cell.object as usize].name.clone(),
                p: cell.centroid(),
                depth: cell.depth(),
                level: cell.level,
            }
        })
        .collect()
}

#[test]
fn open_plane_gets_uniform_depth() {
    let scene = scenes::open_plane(6.0);
    let c = cover(&scene, &quick(Material::snow())).unwrap();
    let s = sites(&scene, &c);
    let inner: Vec<f64> = s
        .iter()
        .filter(|s| s.p[0].abs() < 2.0 && s.p[1].abs() < 2.0)
        .map(|s| s.depth)
        .collect();
    assert!(inner.len() > 500, "{}", inner.len());
    for d in &inner {
        assert!(
            (d - 0.3).abs() <= 0.015,
            "depth {d} is not within 5 % of 0.3"
        );
    }
    // The surface is as deep in the middle.
    let mid = c
        .surface
        .mesh
        .positions
        .iter()
        .filter(|p| p[0].abs() < 1.0 && p[1].abs() < 1.0)
        .map(|p| p[2])
        .collect::<Vec<_>>();
    assert!(
        mid.iter().all(|z| (z - 0.3).abs() < 0.015),
        "{:?}",
        mid.iter().copied().fold(0.0f32, f32::max)
    );
}

/// Depth profile of the ground along x (|y| < 1) in bins of 0.1 m from -4 to 4.
fn profile(scene: &Scene, c: &FearingCover) -> Vec<f64> {
    let mut sum = vec![0.0; 80];
    let mut n = vec![0usize; 80];
    for s in sites(scene, c)
        .iter()
        .filter(|s| s.object == "ground" && s.p[1].abs() < 1.0 && s.p[0].abs() < 4.0)
    {
        let b = ((s.p[0] + 4.0) / 0.1) as usize;
        sum[b] += s.depth;
        n[b] += 1;
    }
    sum.iter()
        .zip(&n)
        .map(|(s, &n)| if n > 0 { s / n as f64 } else { f64::NAN })
        .collect()
}

/// Width of the 10 %-90 % rise of the shadow edge on the east side (x > 0), metres.
fn east_edge_width(p: &[f64], open: f64) -> f64 {
    let x = |b: usize| -4.0 + 0.1 * (b as f64 + 0.5);
    let first_above = |f: f64| (40..80).find(|&b| p[b] > f * open).map(x).unwrap();
    let last_below = |f: f64| (40..80).rev().find(|&b| p[b] < f * open).map(x).unwrap();
    let lo = 0.5 * (first_above(0.1) + last_below(0.1));
    let hi = 0.5 * (first_above(0.9) + last_below(0.9));
    hi - lo
}

#[test]
fn ground_under_a_roof_is_bare_without_flutter_and_falls_off_smoothly_with_it() {
    let scene = scenes::roof(10.0, 4.0, 2.0, 0.1);
    // A steep material so that stability barely moves the snow and the falloff is the flakes'.
    let steep = Material {
        aor_deg: 85.0,
        transition_deg: 0.0,
        ..Material::snow()
    };
    let mut widths = Vec::new();
    for fr in [0.0, 0.05, 0.2] {
        let p = FearingParams {
            flutter_m: Some(fr),
            target_sites: 8000,
            ..quick(steep.clone())
        };
        let c = cover(&scene, &p).unwrap();
        let s = sites(&scene, &c);
        let under: Vec<&Site> = s
            .iter()
            .filter(|s| s.object == "ground" && s.p[0].abs() < 1.8 && s.p[1].abs() < 1.8)
            .collect();
        if fr == 0.0 {
            assert!(
                under.iter().all(|s| s.depth == 0.0),
                "ground under the roof got snow with fr = 0"
            );
        } else {
            let centre = under
                .iter()
                .filter(|s| s.p[0].abs() < 0.5 && s.p[1].abs() < 0.5)
                .map(|s| s.depth)
                .fold(0.0, f64::max);
            assert!(
                centre < 0.01,
                "the middle under the roof stays nearly bare: {centre}"
            );
        }
        let prof = profile(&scene, &c);
        let open = 0.3;
        assert!(
            prof[79] > 0.9 * open && prof[0] > 0.9 * open,
            "open ground: {} {}",
            prof[0],
            prof[79]
        );
        let w = east_edge_width(&prof, open);
        if fr > 0.0 {
            // Smooth: no jump between 0.1 m bins larger than a third of the open depth.
            let jump = (40..79)
                .map(|b| (prof[b + 1] - prof[b]).abs())
                .fold(0.0, f64::max);
            assert!(jump < 0.35 * open, "fr {fr}: jump {jump} in {prof:?}");
        }
        widths.push(w);
    }
    assert!(
        widths[1] > widths[0] + 0.05 && widths[2] > widths[1] + 0.1,
        "falloff widths {widths:?} must grow with fr"
    );
}

#[test]
fn snow_on_a_box_top_never_exceeds_the_aor_at_its_edges() {
    // Tall enough that the debris piled around it stays well below its top (a pile that
    // reached it would support the snow over the edge, as it should).
    let scene = scenes::box_on_ground(6.0, 2.0, 2.0);
    let p = FearingParams {
        depth_m: 0.8,
        ..quick(Material::snow())
    };
    let c = cover(&scene, &p).unwrap();
    let (t, cells) = (&c.topology, &c.sites.cells);
    let max_tan = (p.material.aor_deg + 0.5 * p.material.transition_deg)
        .to_radians()
        .tan();
    let tol = p.stability.level_tolerance_m + 1e-9;
    let top = |i: usize| {
        let cell = &cells[t.leaves[i] as usize];
        cell.centroid()[2] + cell.depth()
    };
    let mut edge_sites = 0;
    let mut deep = 0.0f64;
    for i in 0..t.leaves.len() {
        let cell = &cells[t.leaves[i] as usize];
        if scene.objects[cell.object as usize].name != "box" {
            continue;
        }
        deep = deep.max(cell.depth());
        for nb in &t.neighbours[i] {
            let drop = top(i) - top(nb.site as usize);
            assert!(
                drop <= nb.distance * max_tan + tol,
                "slope {} between box sites over {} m; {:?}",
                drop / nb.distance,
                nb.distance,
                c.report
                    .passes
                    .iter()
                    .map(|p| &p.stability)
                    .collect::<Vec<_>>()
            );
        }
        for e in &t.borders[i] {
            edge_sites += 1;
            let mid = [0, 1, 2].map(|k| 0.5 * (e.a[k] + e.b[k]));
            let c0 = cell.centroid();
            let d = (mid[0] - c0[0]).hypot(mid[1] - c0[1]);
            assert!(
                top(i) - mid[2] <= d * max_tan + tol,
                "snow at the box edge stands {} m over a {d} m run; {:?}",
                top(i) - mid[2],
                c.report
                    .passes
                    .iter()
                    .map(|p| &p.stability)
                    .collect::<Vec<_>>()
            );
        }
    }
    assert!(edge_sites > 40, "{edge_sites}");
    assert!(
        deep > 0.6,
        "the middle of the box top keeps its snow: {deep}"
    );
    let r = &c.report;
    assert!(
        r.passes.iter().any(|p| p.stability.edge_transits > 0),
        "snow went over the edges"
    );
}

fn basin_water(depth: f64) -> (Scene, FearingCover) {
    let scene = scenes::basin(6.0, 3.0, 0.2, 0.5, 0.1);
    // Only the sky over the middle of the basin rains (Fig. 13's red patch): 2 m x 2 m of 6 m.
    let mut values = vec![0.0f32; 36];
    for r in 2..4 {
        for c in 2..4 {
            values[r * 6 + c] = 1.0;
        }
    }
    let p = FearingParams {
        depth_m: depth,
        sky_weight: Some(SkyWeight {
            width: 6,
            height: 6,
            values,
        }),
        target_sites: 1000,
        sky_bucket_m: Some(0.25),
        // Overflowing takes long phases: a higher work cap than the default.
        stability: snowscape_fearing::StabilityPhaseParams {
            max_passes: 3000,
            max_tests_per_site: 5000,
            ..Default::default()
        },
        ..quick(Material::water())
    };
    (scene.clone(), cover(&scene, &p).unwrap())
}

fn floor_levels(scene: &Scene, c: &FearingCover) -> (f64, f64) {
    let tops: Vec<f64> = sites(scene, c)
        .iter()
        .filter(|s| s.object == "basin_floor")
        .map(|s| s.p[2] + s.depth)
        .collect();
    let mean = tops.iter().sum::<f64>() / tops.len() as f64;
    let spread = tops.iter().map(|t| (t - mean).abs()).fold(0.0, f64::max);
    (mean, spread)
}

#[test]
fn water_fills_a_basin_flat() {
    // 4 m² x 0.5 m = 2 m³ into a 9 m² basin: level 0.1 + 2/9 m.
    let (scene, c) = basin_water(0.5);
    let (level, spread) = floor_levels(&scene, &c);
    let rained = c.report.mass.allocated_m3;
    assert!((rained - 2.0).abs() < 0.1, "{rained}");
    assert!(
        (level - (0.1 + rained / 9.0)).abs() < 0.005,
        "level {level}"
    );
    assert!(spread < 0.003, "the water surface is flat: spread {spread}");
    assert!(c.report.mass.left_scene_m3 < 1e-9, "nothing overflows");
}

#[test]
fn water_fills_a_basin_to_its_brim_and_overflows() {
    // 4 m² x 1.5 m = 6 m³ for a capacity of 9 m² x 0.4 m = 3.6 m³.
    let (scene, c) = basin_water(1.5);
    let (level, spread) = floor_levels(&scene, &c);
    assert!(
        (level - 0.5).abs() < 0.01,
        "level {level} should be the brim, 0.5"
    );
    assert!(spread < 0.01, "flat: spread {spread}");
    let s = sites(&scene, &c);
    let outside: f64 = s
        .iter()
        .filter(|s| s.object == "ground")
        .map(|s| s.depth)
        .sum();
    let m = &c.report.mass;
    assert!(
        outside > 0.0 || m.left_scene_m3 > 1.0,
        "the overflow went over the walls"
    );
    assert!(m.closure_error_m3.abs() < 1e-9 * m.allocated_m3, "{m:?}");
}

#[test]
fn stability_conserves_mass_except_what_leaves_the_scene() {
    let scene = scenes::box_on_ground(4.0, 2.0, 1.0);
    let c = cover(&scene, &quick(Material::snow())).unwrap();
    let m = &c.report.mass;
    assert!(
        m.left_scene_m3 > 0.0,
        "snow slid off the ground's open edges and is counted"
    );
    assert!(m.closure_error_m3.abs() < 1e-9 * m.allocated_m3, "{m:?}");
    for p in &c.report.passes {
        let s = &p.stability;
        assert!(
            (s.volume_before_m3 - s.left_scene_m3 - s.volume_after_m3).abs()
                < 1e-9 * s.volume_before_m3,
            "{s:?}"
        );
    }
    // The sky over the ground fell on it: almost all the snow was caught.
    assert!(m.allocated_m3 > 0.9 * 0.3 * 16.0, "{m:?}");
}

#[test]
fn same_seed_same_snow_on_one_and_two_threads() {
    let scene = scenes::roof(6.0, 2.0, 1.0, 0.1);
    let p = FearingParams {
        flutter_m: Some(0.1),
        wind_m_s: [0.3, 0.1],
        target_sites: 2000,
        ..quick(Material::snow())
    };
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| cover(&scene, &p).unwrap())
    };
    let (a, b) = (run(1), run(2));
    let vols = |c: &FearingCover| {
        c.topology
            .leaves
            .iter()
            .map(|&i| c.sites.cells[i as usize].volume.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(vols(&a), vols(&b));
    assert_eq!(a.surface.mesh.positions, b.surface.mesh.positions);
    assert_eq!(a.report.flakes_shot, b.report.flakes_shot);
    let other = cover(
        &scene,
        &FearingParams {
            seed: 2,
            ..p.clone()
        },
    )
    .unwrap();
    assert_ne!(vols(&a), vols(&other), "another seed gives other flakes");
}

#[test]
fn wind_moves_the_roof_shadow_downwind() {
    let scene = scenes::roof(12.0, 4.0, 2.0, 0.1);
    let steep = Material {
        aor_deg: 85.0,
        transition_deg: 0.0,
        flutter_m: 0.0,
        ..Material::snow()
    };
    // 1 m/s east against a fall of 1 m/s: the 2 m high shadow moves 2 m east.
    let p = FearingParams {
        wind_m_s: [1.0, 0.0],
        target_sites: 6000,
        ..quick(steep)
    };
    let c = cover(&scene, &p).unwrap();
    let s = sites(&scene, &c);
    let mean = |x0: f64, x1: f64| {
        let v: Vec<f64> = s
            .iter()
            .filter(|s| s.object == "ground" && s.p[1].abs() < 1.0 && s.p[0] > x0 && s.p[0] < x1)
            .map(|s| s.depth)
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    assert!(
        mean(-1.8, -0.2) > 0.25,
        "west part under the roof gets snow: {}",
        mean(-1.8, -0.2)
    );
    assert!(
        mean(2.2, 3.8) < 0.02,
        "ground east of the roof is in its shadow: {}",
        mean(2.2, 3.8)
    );
}

#[test]
fn a_sky_image_writes_with_snow() {
    let scene = scenes::open_plane(6.0);
    // Left half black, right half white.
    let values = (0..64).map(|i| if i % 8 < 4 { 0.0 } else { 1.0 }).collect();
    let p = FearingParams {
        sky_weight: Some(SkyWeight {
            width: 8,
            height: 8,
            values,
        }),
        ..quick(Material::snow())
    };
    let c = cover(&scene, &p).unwrap();
    let s = sites(&scene, &c);
    // (Away from the plane's open edges, where the snow slopes off at its AOR.)
    let inner: Vec<&Site> = s.iter().filter(|s| s.p[1].abs() < 2.5).collect();
    assert!(
        inner
            .iter()
            .filter(|s| s.p[0] < -0.8)
            .all(|s| s.depth < 0.01)
    );
    let right: Vec<f64> = inner
        .iter()
        .filter(|s| s.p[0] > 0.8 && s.p[0] < 2.5)
        .map(|s| s.depth)
        .collect();
    assert!(
        right.iter().all(|d| (d - 0.3).abs() < 0.03),
        "{:?}",
        right.iter().copied().fold(1.0, f64::min)
    );
}

#[test]
fn refinement_gathers_at_the_occlusion_boundary() {
    let scene = scenes::roof(10.0, 4.0, 2.0, 0.1);
    let p = FearingParams {
        flutter_m: Some(0.0),
        target_sites: 3000,
        ..quick(Material::snow())
    };
    let c = cover(&scene, &p).unwrap();
    let acc = &c.report.passes[0].accumulation;
    assert!(acc.splits > 0, "{acc:?}");
    let refined: Vec<Site> = sites(&scene, &c)
        .into_iter()
        .filter(|s| s.object == "ground" && s.level > 0)
        .collect();
    assert!(!refined.is_empty());
    let near = refined
        .iter()
        .filter(|s| (s.p[0].abs().max(s.p[1].abs()) - 2.0).abs() < 0.5)
        .count();
    assert!(
        near as f64 > 0.9 * refined.len() as f64,
        "{near} of {} refined sites near the roof's outline",
        refined.len()
    );
}

#[test]
fn bad_parameters_name_the_value() {
    let scene = scenes::open_plane(2.0);
    let bad = |p: FearingParams, needle: &str| {
        let e = cover(&scene, &p).unwrap_err().to_string();
        assert!(e.contains(needle), "{e}");
    };
    bad(
        FearingParams {
            material: Material {
                aor_deg: 95.0,
                ..Material::snow()
            },
            ..Default::default()
        },
        "95",
    );
    bad(
        FearingParams {
            depth_m: -1.0,
            ..Default::default()
        },
        "-1",
    );
    bad(
        FearingParams {
            flutter_m: Some(f64::NAN),
            ..Default::default()
        },
        "NaN",
    );
    bad(
        FearingParams {
            wind_m_s: [500.0, 0.0],
            ..Default::default()
        },
        "500",
    );
    assert!(
        Material::preset("mud")
            .unwrap_err()
            .to_string()
            .contains("mud")
    );
    let upside_down = Scene {
        objects: vec![snowscape_mesh::SceneObject {
            frame: Default::default(),
            triangles: vec![[0, 2, 1]],
            ..scenes::plane("p", 1.0, 0.0)
        }],
        ..Default::default()
    };
    assert!(
        cover(&upside_down, &FearingParams::default())
            .unwrap_err()
            .to_string()
            .contains("upward-facing")
    );
}

#[test]
fn swept_steep_faces_get_flake_dusting() {
    // A 70° face (steeper than the 50° AOR) over open ground: its snow slides off, but it saw
    // the sky, so it gets a dense dusting; the ground gets a surface.
    let scene = scenes::steep_face(6.0);
    let c = cover(&scene, &quick(Material::snow())).unwrap();
    let d = c.dusting.as_ref().expect("a dusting mesh");
    assert!(d.triangles.len() > 50, "{}", d.triangles.len());
    // The face's sites are in the densest band (v near the bottom of the atlas).
    let dense = d
        .uvs
        .as_ref()
        .unwrap()
        .iter()
        .filter(|uv| uv[1] > 7.0 / 8.0)
        .count();
    assert!(
        dense as f64 > 0.5 * d.positions.len() as f64,
        "{dense} of {}",
        d.positions.len()
    );
    let tex = d.texture.as_ref().unwrap();
    assert!(tex.pixels().any(|p| p.0[3] == 0) && tex.pixels().any(|p| p.0[3] == 255));
    // The files hold the snow, then the dusting (written by snowscape::cover).
    let meshes = c.meshes();
    assert_eq!(meshes.len(), 2);
    assert_eq!(
        (meshes[0].name.as_str(), meshes[1].name.as_str()),
        ("snow", "dusting")
    );
}

#[test]
fn more_flakes_give_a_smoothly_better_answer() {
    // The anytime loop: the same sites with a growing flake budget approach the answer of a
    // large budget (the flutter falloff under a roof), the error shrinking steadily.
    let scene = scenes::roof(8.0, 3.0, 1.5, 0.1);
    let steep = Material {
        aor_deg: 85.0,
        transition_deg: 0.0,
        ..Material::snow()
    };
    let run = |flakes| {
        let p = FearingParams {
            flutter_m: Some(0.1),
            flakes_per_site: flakes,
            max_refinement: 0,
            passes: 1,
            smoothing_iterations: 0,
            target_sites: 3000,
            ..quick(steep.clone())
        };
        let c = cover(&scene, &p).unwrap();
        c.topology
            .leaves
            .iter()
            .map(|&i| c.sites.cells[i as usize].depth())
            .collect::<Vec<f64>>()
    };
    let reference = run(512);
    let errors: Vec<f64> = [8, 32, 128]
        .iter()
        .map(|&f| {
            let d = run(f);
            assert_eq!(d.len(), reference.len());
            (d.iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                / d.len() as f64)
                .sqrt()
        })
        .collect();
    assert!(
        errors[0] > 1.4 * errors[1] && errors[1] > 1.4 * errors[2],
        "errors {errors:?}"
    );
}

#[test]
fn importance_gives_boring_objects_and_far_sites_fewer_flakes() {
    let scene = scenes::roof(10.0, 4.0, 2.0, 0.1);
    let shots = |p: &FearingParams| {
        let c = cover(&scene, p).unwrap();
        let mut by: std::collections::HashMap<String, (f64, usize)> = Default::default();
        let mut near_far = [(0.0, 0usize); 2];
        for &id in &c.topology.leaves {
            let cell = &c.sites.cells[id as usize];
            let e = by
                .entry(scene.objects[cell.object as usize].name.clone())
                .or_default();
            e.0 += cell.shots;
            e.1 += 1;
            if cell.object == 0 {
                let k = usize::from(cell.centroid()[0] > 0.0);
                near_far[k].0 += cell.shots;
                near_far[k].1 += 1;
            }
        }
        let mean = |v: (f64, usize)| v.0 / v.1 as f64;
        (
            mean(by["roof"]),
            mean(by["ground"]),
            mean(near_far[0]),
            mean(near_far[1]),
        )
    };
    let base = FearingParams {
        passes: 1,
        max_refinement: 0,
        target_sites: 3000,
        ..quick(Material::snow())
    };
    let (roof, ground, _, _) = shots(&FearingParams {
        boring_objects: vec!["roof".into()],
        ..base.clone()
    });
    assert!(
        roof < 0.5 * ground,
        "a boring roof gets fewer flakes per site: {roof} vs {ground}"
    );
    let (_, _, west, east) = shots(&FearingParams {
        camera: Some([-8.0, 0.0, 2.0]),
        ..base
    });
    assert!(
        west > 1.2 * east,
        "sites near the camera (west) get more flakes: {west} vs {east}"
    );
}

#[test]
fn wind_in_the_stability_phase_piles_snow_on_the_windward_side() {
    let scene = scenes::box_on_ground(6.0, 1.0, 1.5);
    let strip = |c: &FearingCover, x0: f64, x1: f64| {
        let v: Vec<f64> = sites(&scene, c)
            .iter()
            .filter(|s| s.object == "ground" && s.p[1].abs() < 0.4 && s.p[0] > x0 && s.p[0] < x1)
            .map(|s| s.depth)
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    let p = FearingParams {
        flutter_m: Some(0.0),
        wind_m_s: [4.0, 0.0],
        wind_transport: 0.1,
        passes: 1,
        ..quick(Material::snow())
    };
    let calm = cover(
        &scene,
        &FearingParams {
            wind_transport: 0.0,
            ..p.clone()
        },
    )
    .unwrap();
    let windy = cover(&scene, &p).unwrap();
    assert!(windy.report.passes[0].stability.wind_moved_m3 > 0.0);
    // Snow piles against the box's windward (west) face and leaves the ground's upwind edge.
    let (wall, calm_wall) = (strip(&windy, -0.75, -0.5), strip(&calm, -0.75, -0.5));
    assert!(
        wall > calm_wall * 1.05,
        "against the wall: {wall} (calm {calm_wall})"
    );
    // The ground's snow moves east as a whole.
    let centre_x = |c: &FearingCover| {
        let s = sites(&scene, c);
        let g = s.iter().filter(|s| s.object == "ground");
        g.clone().map(|s| s.p[0] * s.depth).sum::<f64>() / g.map(|s| s.depth).sum::<f64>()
    };
    // (Modestly: what reaches the east border falls off it.)
    assert!(
        centre_x(&windy) > centre_x(&calm) + 0.001,
        "{} vs {}",
        centre_x(&windy),
        centre_x(&calm)
    );
    let m = &windy.report.mass;
    assert!(m.closure_error_m3.abs() < 1e-9 * m.allocated_m3, "{m:?}");
}
