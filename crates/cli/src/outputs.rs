//! Writing a snow-covered terrain to every output format, each file atomically.

use crate::progress::Stages;
use anyhow::{Context, Result};
use image::RgbaImage;
use snowscape_io::{write_bytes_atomic, write_exr, write_geotiff, write_png16, write_splat};
use snowscape_render::{
    ColourMode, GlbOptions, PreviewOptions, encode_gif, encode_png, render_preview, terrain_glb,
};
use snowscape_terrain::{LayeredTerrain, SnowLayer};
use std::path::{Path, PathBuf};

/// Creates the output folder (and parents) and checks it can be written into.
pub fn prepare_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create output folder {}", dir.display()))?;
    let probe = tempfile::Builder::new()
        .prefix(".snowscape-probe")
        .tempfile_in(dir)
        .with_context(|| format!("output folder {} is not writable", dir.display()))?;
    drop(probe);
    Ok(())
}

/// Collects written file names relative to the output folder.
pub struct Written {
    dir: PathBuf,
    pub files: Vec<String>,
}

impl Written {
    pub fn new(dir: &Path) -> Self {
        Self {
            dir: dir.to_path_buf(),
            files: Vec::new(),
        }
    }
    /// Full path of `name` inside the output folder, recorded as written.
    pub fn path(&mut self, name: &str) -> PathBuf {
        self.files.push(name.to_string());
        self.dir.join(name)
    }
}

/// Writes a PNG atomically.
pub fn write_png(path: &Path, img: &RgbaImage) -> Result<()> {
    let bytes = encode_png(img)?;
    write_bytes_atomic(path, &bytes)?;
    Ok(())
}

/// Writes the rasters (GeoTIFF per layer, multi-channel EXR, 16-bit PNG, splat map).
pub fn write_rasters(out: &mut Written, terrain: &LayeredTerrain) -> Result<()> {
    let depth = terrain.to_grid(terrain.total_depth())?;
    write_geotiff(&out.path("depth.tif"), &depth)?;
    write_geotiff(
        &out.path("bedrock.tif"),
        &terrain.to_grid(terrain.bedrock.clone())?,
    )?;
    for layer in SnowLayer::ALL {
        let grid = terrain.to_grid(terrain.layer(layer).to_vec())?;
        write_geotiff(&out.path(&format!("layers_{}.tif", layer.name())), &grid)?;
    }
    let total = depth.data();
    let mut channels: Vec<(&str, &[f32])> = vec![("bedrock", &terrain.bedrock), ("depth", total)];
    for layer in SnowLayer::ALL {
        channels.push((layer.name(), terrain.layer(layer)));
    }
    write_exr(&out.path("layers.exr"), terrain.geometry(), &channels)?;
    write_png16(&out.path("depth.png"), &depth)?;
    out.files.push("depth.png.json".into());
    write_splat(&out.path("splat.png"), terrain)?;
    Ok(())
}

/// Writes the previews: snow (`preview.png`), layer tint (`layers.png`), stability map
/// (`stability.png`, Cordonnier 2018 Fig. 11).
pub fn write_previews(
    out: &mut Written,
    terrain: &LayeredTerrain,
    view: &PreviewOptions,
) -> Result<()> {
    for (name, mode) in [
        ("preview.png", ColourMode::Snow),
        ("layers.png", ColourMode::Layers),
        ("stability.png", ColourMode::Stability),
    ] {
        let opts = PreviewOptions {
            mode,
            ..view.clone()
        };
        let img = render_preview(terrain, &opts)?;
        write_png(&out.path(name), &img)?;
    }
    Ok(())
}

/// Writes `terrain.glb`: terrain and snow surface meshes with normals.
pub fn write_glb(out: &mut Written, terrain: &LayeredTerrain) -> Result<()> {
    let bytes = terrain_glb(terrain, &GlbOptions::default())?;
    write_bytes_atomic(&out.path("terrain.glb"), &bytes)?;
    Ok(())
}

/// Writes `timelapse.gif` from the frames (written as `frames/` while the run went on).
pub fn write_timelapse(out: &mut Written, frames: &[RgbaImage], delay_ms: u32) -> Result<()> {
    if frames.is_empty() {
        return Ok(());
    }
    let gif = encode_gif(frames, delay_ms)?;
    write_bytes_atomic(&out.path("timelapse.gif"), &gif)?;
    Ok(())
}

/// Every output of a snow-covered terrain, each stage timed.
pub fn write_all(
    out: &mut Written,
    terrain: &LayeredTerrain,
    frames: &[RgbaImage],
    view: &PreviewOptions,
    stages: &mut Stages,
) -> Result<()> {
    stages.run("write_rasters", || write_rasters(out, terrain))?;
    stages.run("render_previews", || write_previews(out, terrain, view))?;
    stages.run("write_glb", || write_glb(out, terrain))?;
    stages.run("write_timelapse", || write_timelapse(out, frames, 400))?;
    Ok(())
}
