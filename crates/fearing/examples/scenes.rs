//! Covers the scenes built in code and writes their snow meshes (GLB, OBJ):
//! `cargo run --release -p snowscape-fearing --example scenes -- [plane|roof|box|basin|roof_and_basin] [OUT_DIR]`.

use snowscape_fearing::{FearingParams, Material, cover, scenes};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map(String::as_str).unwrap_or("roof_and_basin");
    let out = args
        .get(2)
        .cloned()
        .unwrap_or_else(|| format!("out/fearing_{which}"));
    let (scene, params) = match which {
        "plane" => (scenes::open_plane(10.0), FearingParams::default()),
        "roof" => (scenes::roof(12.0, 4.0, 2.0, 0.1), FearingParams::default()),
        "box" => (
            scenes::box_on_ground(8.0, 2.0, 1.0),
            FearingParams {
                depth_m: 0.6,
                ..Default::default()
            },
        ),
        "basin" => (
            scenes::basin(6.0, 3.0, 0.2, 0.5, 0.1),
            FearingParams {
                depth_m: 0.8,
                ..FearingParams::with_material(Material::water())
            },
        ),
        _ => (scenes::roof_and_basin(), FearingParams::default()),
    };
    let c = cover(&scene, &params).expect("cover");
    let r = &c.report;
    println!(
        "{which}: {} sites ({} initial), {} groups, {} flakes ({:.0}/s), {:.2} s (acc {:.2}, stab {:.2}); mass sky {:.3} alloc {:.3} left {:.3} final {:.3} err {:.2e}; max depth {:.3} mean {:.3}",
        r.sites_final,
        r.sites_initial,
        r.edge_groups,
        r.flakes_shot,
        r.flakes_per_s,
        r.timings.total_s,
        r.timings.accumulation_s,
        r.timings.stability_s,
        r.mass.sky_m3,
        r.mass.allocated_m3,
        r.mass.left_scene_m3,
        r.mass.final_m3,
        r.mass.closure_error_m3,
        r.max_depth_m,
        r.mean_depth_m
    );
    for p in &r.passes {
        println!(
            "  pass: {:?}\n  stab: passes {} tests {} aval {} transits {} moved {:.3} left {:.3}",
            p.accumulation.allocation,
            p.stability.passes,
            p.stability.tests,
            p.stability.avalanches,
            p.stability.edge_transits,
            p.stability.moved_m3,
            p.stability.left_scene_m3
        );
    }
    // The snow meshes (`snowscape cover --method fearing` also writes a preview and a report).
    let out = std::path::Path::new(&out);
    std::fs::create_dir_all(out).expect("output folder");
    let meshes = c.meshes();
    snowscape_mesh::write::write_glb(&out.join("snow.glb"), &meshes, &scene.frame).expect("glb");
    snowscape_mesh::write::write_obj(&out.join("snow.obj"), &meshes, &scene.frame).expect("obj");
}
