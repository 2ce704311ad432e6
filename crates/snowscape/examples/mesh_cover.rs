//! Snow on a mesh from code, both ways: the diffusion cover of von Festenberg & Gumhold 2011
//! (the snow surface as a level set over the object, bridged and rounded) and the flake cover
//! of Fearing 2000 (flakes shot from the sky to launch sites, then a stability pass), on the
//! spider of the shared data folder; writes the diffusion snow as glb and OBJ and the Fearing
//! outputs beside it.
//!
//! `cargo run --release -p snowscape --example mesh_cover -- [MESH] [OUT]` (defaults:
//! `../shared/data/meshes/spider.obj`, `out/example_cover`).

use snowscape::fearing::FearingParams;
use snowscape::festenberg::CoverParams;
use snowscape::mesh::write::{write_glb, write_obj};
use snowscape::mesh::{SourceFrame, UpAxis, read_scene};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mesh = PathBuf::from(
        args.first()
            .map_or("../shared/data/meshes/spider.obj", String::as_str),
    );
    let out = PathBuf::from(args.get(1).map_or("out/example_cover", String::as_str));
    if !mesh.is_file() {
        return Err(format!("{} is missing (the shared data folder)", mesh.display()).into());
    }
    // The file's frame: y up, in metres (every position is converted to the z-up scene).
    let frame = SourceFrame::new(UpAxis::Y, 1.0)?;
    let (scene, report) = read_scene(&mesh, &frame)?;
    println!(
        "{}: {} objects, {} triangles ({} degenerate dropped)",
        mesh.display(),
        report.objects.len(),
        report.triangles(),
        report.degenerate_dropped()
    );

    let diffusion = snowscape::festenberg::cover(&scene, &CoverParams::default())?;
    println!(
        "diffusion: {} snow triangles over {} ground sites, {} bridge sites, resolution {:.3} m",
        diffusion.mesh.triangles.len(),
        diffusion.stats.ground_sites,
        diffusion.stats.bridge_sites,
        diffusion.resolved.resolution_m
    );
    std::fs::create_dir_all(&out)?;
    let meshes = std::slice::from_ref(&diffusion.mesh);
    write_glb(&out.join("diffusion_snow.glb"), meshes, &scene.frame)?;
    write_obj(&out.join("diffusion_snow.obj"), meshes, &scene.frame)?;

    let params = FearingParams {
        target_sites: 2500,
        passes: 2,
        ..FearingParams::default()
    };
    let flakes = snowscape::fearing::cover(&scene, &params)?;
    let r = &flakes.report;
    println!(
        "fearing: {} flakes shot ({:.0}/s), {} sites, mean depth {:.3} m, max {:.3} m",
        r.flakes_shot, r.flakes_per_s, r.sites_final, r.mean_depth_m, r.max_depth_m
    );
    let files =
        snowscape::cover::write_fearing_outputs(&out.join("fearing"), &scene, &flakes, None)?;
    println!("wrote 2 + {} files into {}", files.len(), out.display());
    Ok(())
}
