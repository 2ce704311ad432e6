//! Covers the shared real meshes (../shared/data/meshes) with the default parameters and
//! prints what the kernel did: `cargo run --release -p snowscape-festenberg --example
//! diffusion_shared_meshes [OUT_DIR]` (with OUT_DIR, also writes `<mesh>.glb` and `<mesh>.png` there).

use snowscape_festenberg::{CoverParams, cover};
use snowscape_mesh::preview::{PreviewOptions, write_preview};
use snowscape_mesh::write::write_glb;
use snowscape_mesh::{SourceFrame, UpAxis, read_scene};
use std::path::PathBuf;

fn main() {
    let out = std::env::args().nth(1).map(PathBuf::from);
    let data = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/meshes"
    ));
    for (file, up) in [
        ("spider.obj", UpAxis::Y),
        ("teapot_assimp.obj", UpAxis::Z),
        ("bunny_npm.obj", UpAxis::Y),
    ] {
        let frame = SourceFrame::new(up, 1.0).expect("frame");
        let (scene, _) = read_scene(&data.join(file), &frame).expect("the shared mesh reads");
        let t0 = std::time::Instant::now();
        let c = cover(&scene, &CoverParams::default()).expect("cover");
        let s = &c.stats;
        println!(
            "{file}: {}x{} columns, {} sites + {} bridge sites, {} kernel columns, {} snowy, \
             max {:.3} (h0 {:.3}), {} vertices, {} triangles, {} loops, {:.3} s ({:.0} sites/s)",
            s.columns[0],
            s.columns[1],
            s.ground_sites,
            s.bridge_sites,
            s.kernel_columns,
            s.snowy_sites,
            s.max_height_m,
            c.resolved.depth_m,
            s.vertices,
            s.triangles,
            s.boundary_loops,
            t0.elapsed().as_secs_f64(),
            s.kernel_sites_per_s()
        );
        if let Some(dir) = &out {
            std::fs::create_dir_all(dir).expect("output folder");
            let stem = file.split('.').next().unwrap_or("snow");
            write_glb(
                &dir.join(format!("{stem}.glb")),
                std::slice::from_ref(&c.mesh),
                &scene.frame,
            )
            .expect("glb");
            write_preview(
                &dir.join(format!("{stem}.png")),
                &scene,
                &[c.mesh],
                &PreviewOptions::default(),
            )
            .expect("preview");
        }
    }
}
