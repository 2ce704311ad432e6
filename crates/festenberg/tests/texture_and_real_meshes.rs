//! Boundary texture coordinates (Section 5.4.2) on a plate with a known boundary, and the
//! whole method on the shared real meshes: bridged, rounded snow on the spider's legs and on
//! the teapots' lids and handles (fails when ../shared/data is missing).

mod common;
use common::{cube, mesh_path, scene};
use snowscape_festenberg::{CoverParams, cover, prepare_sites};
use snowscape_mesh::{SourceFrame, UpAxis, read_scene};

#[test]
fn v_runs_across_the_boundary_and_u_along_it() {
    let s = scene(vec![cube("plate", [0.0, 0.0, 0.9], [4.0, 4.0, 1.0])]);
    let p = CoverParams {
        depth_m: Some(0.2),
        radius_m: Some(0.5),
        resolution_m: Some(0.05),
        bridge_m: Some(0.0),
        ..Default::default()
    };
    let c = cover(&s, &p).unwrap();
    assert_eq!(c.stats.boundary_loops, 1);
    let uvs = c.mesh.uvs.as_ref().unwrap();
    let l = c.resolved.mask_scale_m as f32;
    let mut boundary_v = Vec::new();
    for (q, uv) in c.mesh.positions.iter().zip(uvs) {
        let d = q[0].min(q[1]).min(4.0 - q[0]).min(4.0 - q[1]);
        if d < 0.03 {
            boundary_v.push(uv[1]);
        } else if d > 2.0 * l {
            // Beyond the mask's reach: fully inside (v = 1, on the last texel centre).
            assert!(uv[1] > 0.99, "v {} at distance {d}", uv[1]);
        }
    }
    // Thin snow meets the plate at a shallow angle: v starts low at the boundary...
    let mean = boundary_v.iter().sum::<f32>() / boundary_v.len() as f32;
    assert!(mean < 0.35, "mean boundary v {mean}");
    // ...and grows inwards: a row of vertices from the west edge.
    let mut row: Vec<(f32, f32)> = c
        .mesh
        .positions
        .iter()
        .zip(uvs)
        .filter(|(q, _)| (q[1] - 2.025).abs() < 1e-4 && q[0] < 0.6)
        .map(|(q, uv)| (q[0], uv[1]))
        .collect();
    row.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert!(row.windows(2).all(|w| w[1].1 >= w[0].1 - 1e-4), "{row:?}");
    assert!(row.last().unwrap().1 > row[0].1 + 0.5);
    // u covers a whole number of mask repeats along the loop (16 m / 0.2 m = 80).
    let umax = uvs.iter().map(|uv| uv[0]).fold(f32::MIN, f32::max);
    assert!(umax > 70.0 && umax <= 80.0, "{umax}");
    let mask = c.mesh.texture.as_ref().unwrap();
    assert_eq!(mask.dimensions(), (256, 256));
}

fn read(name: &str, up: UpAxis) -> snowscape_mesh::Scene {
    read_scene(&mesh_path(name), &SourceFrame::new(up, 1.0).unwrap())
        .unwrap()
        .0
}

#[test]
fn spider_legs_carry_thin_rounded_snow_and_are_bridged_near_the_body() {
    let s = read("spider.obj", UpAxis::Y);
    let c = cover(&s, &CoverParams::default()).unwrap();
    let f = &c.field;
    let h0 = c.resolved.depth_m as f32;
    assert!(c.stats.bridge_sites > 50, "{}", c.stats.bridge_sites);
    // Bridge sites hold snow.
    let bridged = (0..f.len())
        .filter(|&i| f.bridge[i] >= 0.0 && c.kernel.height[i] > 0.0)
        .count();
    assert!(bridged > c.stats.bridge_sites / 2, "{bridged}");
    // The legs (objects named Bein*) carry snow, thinner than the abdomen (HLeib01): their
    // edges are close on both sides, so g1 and the kernel round it off.
    let (_, map, ground) = prepare_sites(&s, &CoverParams::default(), false).unwrap();
    let mut object = vec![u32::MAX; f.len()];
    for c in 0..map.width * map.height {
        let sites = map.column(c % map.width, c / map.width);
        for (k, i) in f.column_sites(c).take(sites.len()).enumerate() {
            object[i] = sites[k].object;
        }
    }
    assert_eq!(ground.len(), map.site_count());
    let mean = |pick: &dyn Fn(&str) -> bool| {
        let hs: Vec<f32> = (0..f.len())
            .filter(|&i| object[i] != u32::MAX && pick(&s.objects[object[i] as usize].name))
            .map(|i| c.kernel.height[i])
            .collect();
        let snowy = hs.iter().filter(|&&h| h > 0.0).count() as f64 / hs.len().max(1) as f64;
        (
            hs.iter().sum::<f32>() / hs.len().max(1) as f32,
            snowy,
            hs.len(),
        )
    };
    let (legs, leg_snowy, leg_sites) = mean(&|n| n.starts_with("Bein"));
    let (body, _, body_sites) = mean(&|n| n == "HLeib01");
    assert!(
        leg_sites > 500 && body_sites > 1000,
        "{leg_sites} {body_sites}"
    );
    assert!(leg_snowy > 0.5, "share of leg sites with snow {leg_snowy}");
    assert!(
        legs > 0.0 && legs < 0.6 * body,
        "legs {legs} m, abdomen {body} m"
    );
    let max = c.kernel.height.iter().copied().fold(0.0, f32::max);
    assert!(max <= 2.0 * h0 && max > h0, "{max} vs h0 {h0}");
}

#[test]
fn teapot_lids_and_handles_hold_snow() {
    let s = read("teapot_assimp.obj", UpAxis::Z);
    let c = cover(&s, &CoverParams::default()).unwrap();
    let f = &c.field;
    // The lid knobs are the highest sites: snow lies on them.
    let top = (0..f.len())
        .max_by(|&a, &b| f.z[a].total_cmp(&f.z[b]))
        .unwrap();
    assert!(c.kernel.height[top] > 0.0);
    // The handles are the westmost parts: their sites carry snow.
    let west = s.bounds().unwrap().min[0] as f64;
    let handle: Vec<usize> = (0..f.len())
        .filter(|&i| f.column_xy(f.column[i] as usize)[0] < west + 10.0)
        .collect();
    assert!(!handle.is_empty());
    assert!(handle.iter().any(|&i| c.kernel.height[i] > 0.0));
    assert!(c.stats.layers >= 2 && c.stats.bridge_sites > 0);
}
