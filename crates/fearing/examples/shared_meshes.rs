//! Covers every shared mesh (and the ~100k-triangle scene of bunnies and teapots) with the
//! default snow and prints sites, flakes, flakes/s and seconds; writes the snow meshes under
//! `out/fearing_meshes/<name>/`. Needs ../shared/data/meshes beside the checkout.
//! `cargo run --release -p snowscape-fearing --example shared_meshes [-- NAME...]`

#[path = "../benches/common/mod.rs"]
mod common;

use snowscape_fearing::{FearingParams, cover};

fn main() {
    let only: Vec<String> = std::env::args().skip(1).collect();
    let mut list: Vec<(String, snowscape_mesh::Scene)> = Vec::new();
    for entry in std::fs::read_dir(common::meshes_dir()).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        list.push((name.clone(), common::mesh(&name, 1.0)));
    }
    list.sort_by(|a, b| a.0.cmp(&b.0));
    list.push(("big_scene".into(), common::big_scene()));
    for (name, scene) in list {
        if !only.is_empty() && !only.contains(&name) {
            continue;
        }
        let b = scene.bounds().unwrap();
        // Snow 5 % of the object's height, flutter 1 % of its size.
        let size = b.size();
        let p = FearingParams {
            depth_m: 0.05 * size[2] as f64,
            flutter_m: Some(0.01 * size[0].max(size[1]) as f64),
            ..Default::default()
        };
        let c = cover(&scene, &p).unwrap();
        let r = &c.report;
        println!(
            "{name}: {} tris ({} up), size {:.2?}, {} sites, {} flakes, {:.0} flakes/s, total {:.2} s (acc {:.2}, stab {:.2}), mass alloc {:.4} left {:.4} err {:.1e}, max depth {:.4}",
            r.triangles,
            r.upward_triangles,
            size,
            r.sites_final,
            r.flakes_shot,
            r.flakes_per_s,
            r.timings.total_s,
            r.timings.accumulation_s,
            r.timings.stability_s,
            r.mass.allocated_m3,
            r.mass.left_scene_m3,
            r.mass.closure_error_m3,
            r.max_depth_m
        );
        let out = std::path::Path::new("out/fearing_meshes").join(&name);
        std::fs::create_dir_all(&out).unwrap();
        let meshes = c.meshes();
        snowscape_mesh::write::write_glb(&out.join("snow.glb"), &meshes, &scene.frame).unwrap();
        snowscape_mesh::write::write_obj(&out.join("snow.obj"), &meshes, &scene.frame).unwrap();
    }
}
