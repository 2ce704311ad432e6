//! Renders the snow of one shared mesh alone and on its scene from a chosen view:
//! `cargo run --release -p snowscape-festenberg --example inspect -- FILE UP AZIMUTH ELEVATION OUT_PREFIX`.

use snowscape_festenberg::{CoverParams, cover};
use snowscape_mesh::preview::{PreviewOptions, write_preview};
use snowscape_mesh::{Scene, SourceFrame, UpAxis, read_scene};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 6 {
        eprintln!("usage: inspect FILE y|z AZIMUTH ELEVATION OUT_PREFIX [--overhang]");
        std::process::exit(2);
    }
    let up: UpAxis = a[2].parse().expect("up axis");
    let (scene, _) =
        read_scene(a[1].as_ref(), &SourceFrame::new(up, 1.0).expect("frame")).expect("mesh reads");
    let params = CoverParams {
        overhang: a.iter().any(|s| s == "--overhang"),
        ..Default::default()
    };
    let c = cover(&scene, &params).expect("cover");
    let opts = PreviewOptions {
        view_azimuth_deg: a[3].parse().expect("azimuth"),
        view_elevation_deg: a[4].parse().expect("elevation"),
        width: 1000,
        height: 800,
        ..Default::default()
    };
    write_preview(
        format!("{}_scene.png", a[5]).as_ref(),
        &scene,
        std::slice::from_ref(&c.mesh),
        &opts,
    )
    .expect("preview");
    let empty = Scene::default();
    write_preview(
        format!("{}_snow.png", a[5]).as_ref(),
        &empty,
        std::slice::from_ref(&c.mesh),
        &opts,
    )
    .expect("preview");
}
