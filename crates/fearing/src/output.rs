//! Outputs of a cover: `snow.glb` and `snow.obj` (+ `snow.mtl`), the snow mesh alone, in the
//! input's own axes and units so it lies on the input scene; `preview.png`, a CPU render of
//! the scene with its snow; `report.json`. Every file is written atomically.

use crate::{FearingCover, FearingError};
use snowscape_mesh::{Scene, preview};
use std::path::{Path, PathBuf};

/// Writes the outputs into `dir` (created if needed); returns the paths written.
pub fn write_outputs(
    dir: &Path,
    scene: &Scene,
    cover: &FearingCover,
) -> Result<Vec<PathBuf>, FearingError> {
    std::fs::create_dir_all(dir).map_err(|source| snowscape_mesh::MeshError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut written = Vec::new();
    let mesh = cover.surface.to_mesh("snow");
    let meshes = if mesh.triangles.is_empty() {
        Vec::new()
    } else {
        vec![mesh]
    };
    if !meshes.is_empty() {
        let glb = dir.join("snow.glb");
        snowscape_mesh::write::write_glb(&glb, &meshes, &scene.frame)?;
        written.push(glb);
        let obj = dir.join("snow.obj");
        snowscape_mesh::write::write_obj(&obj, &meshes, &scene.frame)?;
        written.push(obj);
        written.push(dir.join("snow.mtl"));
    }
    let png = dir.join("preview.png");
    preview::write_preview(&png, scene, &meshes, &preview::PreviewOptions::default())?;
    written.push(png);
    let json = dir.join("report.json");
    snowscape_io::write_bytes_atomic(
        &json,
        serde_json::to_string_pretty(&cover.report)?.as_bytes(),
    )?;
    written.push(json);
    Ok(written)
}
