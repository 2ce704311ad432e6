//! The files of a Fearing cover: `snow.glb` and `snow.obj` (+ `snow.mtl`), the snow mesh alone,
//! in the input's own axes and units so it lies on the input scene; `preview.png`, a CPU render
//! of the scene with its snow; `report.json` (the
//! [`FearingReport`](snowscape_fearing::FearingReport), with whatever the caller adds under
//! `input`). Every file is written atomically. A cover's `turntable.gif` (either method's)
//! is written here too.

use crate::outputs::OutputError;
use snowscape_fearing::{FearingCover, FearingError};
use snowscape_mesh::{Scene, SnowObject, preview};
use std::path::{Path, PathBuf};

/// Writes the outputs into `dir` (created if needed); returns the files written. `input` goes
/// into the report as its `input` member (the CLI puts the mesh summary there).
pub fn write_fearing_outputs(
    dir: &Path,
    scene: &Scene,
    cover: &FearingCover,
    input: Option<serde_json::Value>,
) -> Result<Vec<PathBuf>, OutputError> {
    std::fs::create_dir_all(dir).map_err(|source| OutputError::CreateFolder {
        path: dir.to_path_buf(),
        source,
    })?;
    if let Some(e) = fearing_no_snow(cover) {
        return Err(OutputError::Fearing(e));
    }
    let meshes = cover.meshes();
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
    let json = dir.join(crate::output_folder::REPORT);
    let report = fearing_report(cover, input).map_err(OutputError::Report)?;
    let text = serde_json::to_string_pretty(&report).map_err(OutputError::Report)?;
    snowscape_io::write_bytes_atomic(&json, text.as_bytes())?;
    let mut files = vec![glb, obj, dir.join("snow.mtl")];
    if meshes.len() > 1 {
        files.push(dir.join("snow_1.png"));
    }
    files.extend([png, json]);
    Ok(files)
}

/// [`FearingError::NoSnow`] when no snow settled deep enough for the surface (nothing to
/// write), else `None`.
pub fn fearing_no_snow(cover: &FearingCover) -> Option<FearingError> {
    if !cover.surface.to_mesh("snow").triangles.is_empty() {
        return None;
    }
    Some(FearingError::NoSnow {
        sites: cover.topology.leaves.len(),
        min_depth_m: cover
            .report
            .params
            .as_ref()
            .map_or(0.0, |p| p.min_surface_depth_m),
    })
}

/// `turntable.gif` in `dir`: `frames` previews around the scene and its snow, 80 ms apart.
pub fn write_turntable(
    dir: &Path,
    scene: &Scene,
    snow: &[SnowObject],
    frames: usize,
) -> Result<(), OutputError> {
    let opts = preview::PreviewOptions {
        width: 480,
        height: 360,
        ..preview::PreviewOptions::default()
    };
    let images: Vec<image::RgbaImage> = preview::render_turntable(scene, snow, &opts, frames)?
        .into_iter()
        .map(|i| image::DynamicImage::ImageRgb8(i).into_rgba8())
        .collect();
    let gif = snowscape_render::encode_gif(&images, 80)?;
    snowscape_io::write_bytes_atomic(&dir.join("turntable.gif"), &gif)?;
    Ok(())
}

/// A Fearing cover's report (its [`FearingReport`](snowscape_fearing::FearingReport)) with
/// `input` (what the front end read) as its `input` member: `report.json`, and what the Python
/// package returns.
pub fn fearing_report(
    cover: &FearingCover,
    input: Option<serde_json::Value>,
) -> serde_json::Result<serde_json::Value> {
    let mut report = serde_json::to_value(&cover.report)?;
    if let (Some(input), Some(obj)) = (input, report.as_object_mut()) {
        obj.insert("input".into(), input);
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_fearing::{FearingParams, cover, scenes};

    /// A 70° face over open ground: its snow slides off, but it saw the sky, so its dusting is
    /// written beside the snow (its texture and an object of the OBJ).
    #[test]
    fn the_dusting_is_written_with_the_snow() {
        let scene = scenes::steep_face(6.0);
        let params = FearingParams {
            target_sites: 2000,
            flakes_per_site: 16,
            ..FearingParams::default()
        };
        let c = cover(&scene, &params).unwrap();
        assert_eq!(c.meshes().len(), 2, "the snow and a dusting");
        let out = tempfile::tempdir().unwrap();
        let files = write_fearing_outputs(out.path(), &scene, &c, None).unwrap();
        for name in [
            "snow.glb",
            "snow.obj",
            "snow.mtl",
            "snow_1.png",
            "preview.png",
            "report.json",
        ] {
            assert!(files.contains(&out.path().join(name)), "{name}: {files:?}");
        }
        let obj = std::fs::read_to_string(out.path().join("snow.obj")).unwrap();
        assert!(obj.contains("dusting"), "the OBJ holds the dusting object");
        let report: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.path().join("report.json")).unwrap())
                .unwrap();
        assert_eq!(report["method"], "fearing");
    }
}
