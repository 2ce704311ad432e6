//! The output layer of a snow-covered terrain: every file format a season writes (GeoTIFF per
//! layer, multi-channel EXR, 16-bit PNG, splat map, previews, glTF, time-lapse GIF), each file
//! written atomically (a synced temporary sibling renamed over the name), and the output
//! folder's bookkeeping (unfinished temporary files of an interrupted run, stale outputs of an
//! earlier one, `report.json`). Every front end (the CLI's `run` and `demo`, the editor's
//! export, the Python package) writes through these functions, so the same state gives the
//! same bytes whichever wrote it.

use crate::output_folder::OutputFolder;
use image::RgbaImage;
use snowscape_io::{AtomicWriteError, RasterError};
use snowscape_io::{write_bytes_atomic, write_exr, write_geotiff, write_png16, write_splat};
use snowscape_render::RenderError;
use snowscape_render::{
    ColourMode, GlbOptions, PreviewOptions, encode_gif, encode_png, render_preview, terrain_glb,
    with_legend,
};
use snowscape_terrain::TerrainError;
use snowscape_terrain::{LayeredTerrain, SnowLayer};
use std::path::{Path, PathBuf};

/// Why an output could not be written (nothing half-written is left under its name).
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The output folder cannot be created.
    #[error("cannot create output folder {path}: {source}")]
    CreateFolder {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The output folder exists but cannot be written into.
    #[error("output folder {path} is not writable: {source}")]
    NotWritable {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Write(#[from] AtomicWriteError),
    #[error(transparent)]
    Raster(#[from] RasterError),
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Terrain(#[from] TerrainError),
    /// `report.json` could not be encoded.
    #[error("cannot encode report.json: {0}")]
    Report(#[source] serde_json::Error),
    /// A JSON file could not be encoded.
    #[error("cannot encode {path}: {source}")]
    Json {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
    /// The ski tracks could not be encoded.
    #[error(transparent)]
    Ski(#[from] snowscape_skiers::SkiError),
    /// A mesh file could not be written.
    #[error(transparent)]
    Mesh(#[from] snowscape_mesh::MeshError),
    /// A Fearing cover has nothing to write (no snow settled).
    #[error(transparent)]
    Fearing(#[from] snowscape_fearing::FearingError),
    /// Another job holds the output folder.
    #[error(
        "output folder {path} is in use by another snowscape job; wait for it or choose another --out"
    )]
    Busy { path: PathBuf },
    /// A path in the output folder that a job will not write through or remove.
    #[error("{path} {reason}: refusing to write there")]
    UnsafePath { path: PathBuf, reason: &'static str },
    /// A job listed an output it did not write (a bug, reported rather than committed).
    #[error("output {name} was not written (missing at {path})")]
    NotStaged { path: PathBuf, name: String },
    /// A written output could not be moved into place.
    #[error("cannot move the output into place at {path}: {source}")]
    Commit {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// The result of an output.
pub type Result<T> = std::result::Result<T, OutputError>;

/// Creates the output folder (and parents), checks it can be written into, and removes the
/// temporary files (`.snowscape-*.partial`) that an interrupted write left in it or in its
/// subfolders.
pub fn prepare_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| OutputError::CreateFolder {
        path: dir.to_path_buf(),
        source,
    })?;
    let probe = tempfile::Builder::new()
        .prefix(".snowscape-probe")
        .tempfile_in(dir)
        .map_err(|source| OutputError::NotWritable {
            path: dir.to_path_buf(),
            source,
        })?;
    drop(probe);
    let removed = remove_partial_leftovers(dir);
    if removed > 0 {
        tracing::info!(
            "removed {removed} unfinished temporary file(s) of an earlier run from {}",
            dir.display()
        );
    }
    Ok(())
}

/// Whether `name` is one of the atomic writer's temporary files.
fn is_partial(name: &str) -> bool {
    (name.starts_with(".snowscape-") && name.ends_with(".partial"))
        || name.starts_with(".snowscape-probe")
}

/// Removes temporary files of interrupted writes from `dir` and its direct subfolders;
/// returns how many were removed.
fn remove_partial_leftovers(dir: &Path) -> usize {
    let mut removed = 0;
    let mut folders = vec![dir.to_path_buf()];
    if let Ok(entries) = std::fs::read_dir(dir) {
        folders.extend(
            entries
                .flatten()
                .filter(|e| e.file_type().is_ok_and(|t| t.is_dir()))
                .map(|e| e.path()),
        );
    }
    for folder in folders {
        let Ok(entries) = std::fs::read_dir(&folder) else {
            continue;
        };
        for e in entries.flatten() {
            let is_file = e.file_type().is_ok_and(|t| t.is_file());
            if is_file
                && e.file_name().to_str().is_some_and(is_partial)
                && std::fs::remove_file(e.path()).is_ok()
            {
                removed += 1;
            }
        }
    }
    removed
}

/// Writes `report` (a JSON object with an `outputs` list, the files staged in `folder`) as
/// `report.json` and commits the folder ([`OutputFolder::commit`]): the outputs move into
/// place and the earlier ones this job did not write again (listed as `removed_stale`) are
/// removed.
pub fn write_report(folder: OutputFolder, mut report: serde_json::Value) -> Result<()> {
    let written: Vec<String> = report["outputs"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|s| s.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    let stale = folder.stale(&written);
    if !stale.is_empty() {
        report["removed_stale"] = serde_json::json!(stale);
    }
    let text = serde_json::to_string_pretty(&report).map_err(OutputError::Report)?;
    folder.commit(&written, Some(text.as_bytes()))
}

/// Collects written file names relative to the output folder.
pub struct Written {
    /// The output folder.
    pub dir: PathBuf,
    /// The files written so far, relative to the folder, in order.
    pub files: Vec<String>,
    /// Single-band GeoTIFFs are written Cloud-Optimized (`--cog`; [`snowscape_io::write_cog`]).
    pub cog: bool,
}

impl Written {
    /// Nothing written yet into `dir`.
    pub fn new(dir: &Path) -> Self {
        Self {
            dir: dir.to_path_buf(),
            files: Vec::new(),
            cog: false,
        }
    }

    /// Writes a single-band GeoTIFF `name` of `grid` (Cloud-Optimized when [`Written::cog`]).
    pub fn geotiff(&mut self, name: &str, grid: &snowscape_terrain::Grid) -> Result<()> {
        let path = self.path(name);
        if self.cog {
            snowscape_io::write_cog(&path, grid)?;
        } else {
            write_geotiff(&path, grid)?;
        }
        Ok(())
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
    out.geotiff("depth.tif", &depth)?;
    out.geotiff("bedrock.tif", &terrain.to_grid(terrain.bedrock.clone())?)?;
    for layer in SnowLayer::ALL {
        let grid = terrain.to_grid(terrain.layer(layer).to_vec())?;
        out.geotiff(&format!("layers_{}.tif", layer.name()), &grid)?;
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
        write_png(&out.path(name), &with_legend(&img, &opts.mode, terrain))?;
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

/// Every output of a snow-covered terrain, each stage timed. The four writers are
/// independent (different files) and run at the same time; their files are listed in a fixed
/// order, and the first error (in that order) is returned once all have finished. Returns the
/// seconds of each stage (`write_rasters`, `render_previews`, `write_glb`, `write_timelapse`).
pub fn write_all(
    out: &mut Written,
    terrain: &LayeredTerrain,
    frames: &[RgbaImage],
    view: &PreviewOptions,
) -> Result<Vec<(&'static str, f64)>> {
    let (dir, cog) = (out.dir.clone(), out.cog);
    let timed = |write: &(dyn Fn(&mut Written) -> Result<()> + Sync)| {
        let mut files = Written::new(&dir);
        files.cog = cog;
        let t0 = std::time::Instant::now();
        let result = write(&mut files);
        (files, t0.elapsed().as_secs_f64(), result)
    };
    let ((rasters, previews), (glb, timelapse)) = rayon::join(
        || {
            rayon::join(
                || timed(&|w| write_rasters(w, terrain)),
                || timed(&|w| write_previews(w, terrain, view)),
            )
        },
        || {
            rayon::join(
                || timed(&|w| write_glb(w, terrain)),
                || timed(&|w| write_timelapse(w, frames, 400)),
            )
        },
    );
    let mut first_error = None;
    let mut stages = Vec::new();
    for (name, (files, seconds, result)) in [
        ("write_rasters", rasters),
        ("render_previews", previews),
        ("write_glb", glb),
        ("write_timelapse", timelapse),
    ] {
        stages.push((name, seconds));
        out.files.extend(files.files);
        if let Err(e) = result {
            first_error.get_or_insert(e);
        }
    }
    first_error.map_or(Ok(stages), Err)
}

/// Writes the state outputs of a season (rasters, previews and the glb, as `snowscape run`
/// does, without the time-lapse) into `dir`; returns the files written.
pub fn write_state(
    dir: &Path,
    terrain: &LayeredTerrain,
    view: &PreviewOptions,
) -> Result<Vec<String>> {
    let mut out = Written::new(dir);
    write_rasters(&mut out, terrain)?;
    write_previews(&mut out, terrain, view)?;
    write_glb(&mut out, terrain)?;
    Ok(out.files)
}

/// Writes `texture` (over `geometry`, the terrain grid) as a grayscale PNG at `path`, with its
/// JSON sidecar `<path>.json` and world file `<stem>.pgw`
/// ([`snowscape_skiers::encode_track_png`]), each atomically.
pub fn write_track_png(
    path: &Path,
    texture: &snowscape_skiers::TrackTexture,
    geometry: &snowscape_terrain::GridGeometry,
    depth: snowscape_skiers::PngDepth,
) -> Result<()> {
    let encoded = snowscape_skiers::encode_track_png(texture, geometry, depth)?;
    let mut json_path = path.as_os_str().to_owned();
    json_path.push(".json");
    let json_path = PathBuf::from(json_path);
    let json = serde_json::to_vec_pretty(&encoded.sidecar).map_err(|source| OutputError::Json {
        path: json_path.clone(),
        source,
    })?;
    write_bytes_atomic(path, &encoded.png)?;
    write_bytes_atomic(&json_path, &json)?;
    write_bytes_atomic(&path.with_extension("pgw"), encoded.world_file.as_bytes())?;
    Ok(())
}

/// Writes the tracks of `area` as GeoJSON ([`snowscape_skiers::tracks_geojson`]) at `path`,
/// atomically.
pub fn write_tracks_geojson(path: &Path, area: &snowscape_skiers::SkiArea) -> Result<()> {
    let bytes = serde_json::to_vec(&snowscape_skiers::tracks_geojson(area)).map_err(|source| {
        OutputError::Json {
            path: path.to_path_buf(),
            source,
        }
    })?;
    write_bytes_atomic(path, &bytes)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_skiers::{PngDepth, SkiArea, SkiParams, SkiScratch, Terminus, step};
    use snowscape_terrain::{Grid, GridGeometry};

    /// Twelve skiers for 30 s on a 30° slope under 0.5 m of snow.
    fn skied() -> (SkiArea, LayeredTerrain) {
        let params = SkiParams {
            texels_per_cell: 2,
            ..SkiParams::default()
        };
        let g = GridGeometry::square(24, 48, 10.0).unwrap();
        let tan = 30f64.to_radians().tan();
        let bedrock = Grid::from_fn(g, |c, r| (2000.0 - tan * 10.0 * r as f64 - c as f64) as f32);
        let mut t = LayeredTerrain::from_bedrock(bedrock);
        t.layer_mut(SnowLayer::Stable).fill(0.5);
        let mut area = SkiArea::new(&params, &t, Terminus::LocalMinima, 4).unwrap();
        area.spawn_weighted(&params, &t, 12).unwrap();
        let mut scratch = SkiScratch::default();
        for _ in 0..30 {
            step(&params, &mut area, &mut t, &mut scratch, 1.0).unwrap();
        }
        (area, t)
    }

    #[test]
    fn ski_tracks_are_written_whole_with_their_sidecars() {
        let (area, t) = skied();
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("ski_tracks.png");
        write_track_png(&png, area.texture(), t.geometry(), PngDepth::Sixteen).unwrap();
        write_tracks_geojson(&dir.path().join("ski_tracks.geojson"), &area).unwrap();
        let img = image::open(&png).unwrap();
        let (w, h) = area.texture().size();
        assert_eq!((img.width() as usize, img.height() as usize), (w, h));
        let sidecar: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join("ski_tracks.png.json")).unwrap())
                .unwrap();
        assert_eq!(sidecar["format"], "snowscape-ski-tracks");
        assert_eq!(
            std::fs::read_to_string(dir.path().join("ski_tracks.pgw"))
                .unwrap()
                .lines()
                .count(),
            6
        );
        let geojson: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join("ski_tracks.geojson")).unwrap())
                .unwrap();
        assert_eq!(geojson["features"].as_array().unwrap().len(), 12);
        // The four files and no temporary ones.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 4);
    }

    #[test]
    fn unwritable_ski_tracks_are_typed_errors_and_leave_nothing() {
        let (area, t) = skied();
        let missing = Path::new("/nonexistent-snowscape-outputs/t.png");
        let e =
            write_track_png(missing, area.texture(), t.geometry(), PngDepth::Sixteen).unwrap_err();
        assert!(matches!(e, OutputError::Write(_)), "{e}");
        let e = write_tracks_geojson(&missing.with_extension("geojson"), &area).unwrap_err();
        assert!(matches!(e, OutputError::Write(_)), "{e}");
    }
}
