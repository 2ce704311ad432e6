//! Outputs of a cover: `snow.glb` and `snow.obj` (+ `snow.mtl`), the snow mesh alone, in the
//! input's own axes and units so it lies on the input scene; `preview.png`, a CPU render of
//! the scene with its snow; `report.json` (the [`FearingReport`](crate::FearingReport), with
//! whatever the caller adds under `input`). Every file is written atomically.

use crate::{FearingCover, FearingError};
use snowscape_mesh::{Scene, preview};
use std::path::{Path, PathBuf};

/// Writes the outputs into `dir` (created if needed); returns the files written. `input` goes
/// into the report as its `input` member (the CLI puts the mesh summary there).
pub fn write_outputs(
    dir: &Path,
    scene: &Scene,
    cover: &FearingCover,
    input: Option<serde_json::Value>,
) -> Result<Vec<PathBuf>, FearingError> {
    std::fs::create_dir_all(dir).map_err(|source| snowscape_mesh::MeshError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let mesh = cover.surface.to_mesh("snow");
    if mesh.triangles.is_empty() {
        return Err(FearingError::NoSnow {
            sites: cover.topology.leaves.len(),
            min_depth_m: cover
                .report
                .params
                .as_ref()
                .map_or(0.0, |p| p.min_surface_depth_m),
        });
    }
    // The snow surface, then the dusting (its alpha-masked texture travels with it).
    let mut meshes = vec![mesh];
    meshes.extend(cover.dusting.clone());
    let glb = dir.join("snow.glb");
    snowscape_mesh::write::write_glb(&glb, &meshes, &scene.frame)?;
    let obj = dir.join("snow.obj");
    snowscape_mesh::write::write_obj(&obj, &meshes, &scene.frame)?;
    let png = dir.join("preview.png");
    // The preview draws triangles opaque: the dusting would show as solid snow, so it is left out.
    preview::write_preview(
        &png,
        scene,
        &meshes[..1],
        &preview::PreviewOptions::default(),
    )?;
    let json = dir.join("report.json");
    let mut report = serde_json::to_value(&cover.report)?;
    if let (Some(input), Some(obj)) = (input, report.as_object_mut()) {
        obj.insert("input".into(), input);
    }
    snowscape_io::write_bytes_atomic(&json, serde_json::to_string_pretty(&report)?.as_bytes())?;
    let mut files = vec![glb, obj, dir.join("snow.mtl")];
    if meshes.len() > 1 {
        files.push(dir.join("snow_1.png"));
    }
    files.extend([png, json]);
    Ok(files)
}
