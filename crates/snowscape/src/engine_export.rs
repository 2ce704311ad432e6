//! A season's terrain and snow as game engines import them (`snowscape export --engine`): 16-bit
//! heightmaps at the sizes each engine's terrain takes, with the scales to type into its import
//! dialog, and per-texel weight maps of the snow layers and the bare rock that sum to 255.
//!
//! - **Unreal** (Landscape, "Import from File"): 16-bit grayscale PNG heightmaps resampled to
//!   the Landscape sizes Unreal recommends per axis (127, 253, 505, 1009, 2017, 4033, 8129;
//!   larger DEMs are downsampled to 8129), 8-bit grayscale weight maps per layer
//!   (`weight_compacted.png` ... `weight_rock.png`, the Landscape's paint layers), and
//!   `unreal_import.json` with the X/Y/Z scale and the Z location: Unreal reads code `c` as
//!   `(c − 32768) · Zscale/128` cm above the actor, so `Zscale = (zmax − zmin) · 12800/65535`
//!   and `location_z = 100 · zmin + 256 · Zscale` (cm) put code 0 at `zmin` and 65535 at `zmax`.
//!   `--tile N` writes World Partition tiles of N × N samples named `_x{i}_y{j}` (neighbouring
//!   tiles share their edge row and column, as a Landscape's components do).
//! - **Unity** (Terrain, "Import Raw"): 16-bit little-endian RAW heightmaps at 2^n + 1 (33 ..
//!   4097, square; depth 16 bit, byte order Windows), two RGBA splat maps at 2^n
//!   (`splatmap_0.png` = compacted, stable, unstable, powder; `splatmap_1.png` = rock), and
//!   `unity_import.json` with the terrain width, length and height (m) and its position.
//! - **Godot** (the HTerrain add-on by Zylann, "Import" dialog): 2^n + 1 square heightmaps as
//!   16-bit little-endian RAW (with the min and max heights to enter) and 32-bit float EXR
//!   (metres), and one RGBA splat map (`splatmap.png`: rock, compacted + stable, unstable,
//!   powder); `godot_import.json` says what to enter.
//!
//! Both heightmaps (bedrock, and bedrock + snow with `--with-snow`) share one height scale, so
//! the snow surface lies on the bedrock at the same Z. Samples are taken bilinearly at evenly
//! spaced positions from the first to the last cell centre of the run's grid; nodata cells
//! (engines have none) become the lowest valid bedrock, bare (`rock` weight 255). Layer weights:
//! the snow covers a texel in proportion to its depth up to 30 cm (the page's snow shading),
//! shared among the layers by thickness; the rest is rock; rounded so the weights sum to 255.
//!
//! Memory: the run's rasters are read a window of rows at a time ([`TiffRows`]: only the strips
//! or tiles under the window are decoded), so memory follows the output, at most 8129² samples
//! (two f32 heightmaps and five byte weight maps, 0.9 GB at 8129²), whatever the run's size;
//! the outputs are written one tile at a time.

use image::ExtendedColorType;
use serde::Serialize;
use snowscape_io::{ReadOptions, TiffRows, write_atomic, write_bytes_atomic, write_exr};
use snowscape_terrain::{Grid, GridGeometry, SnowLayer};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Landscape sizes Unreal recommends (per axis), quads + 1.
pub const UNREAL_SIZES: [usize; 7] = [127, 253, 505, 1009, 2017, 4033, 8129];

/// The game engines.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Engine {
    Unreal,
    Unity,
    Godot,
}

/// What to export.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportOptions {
    pub engine: Engine,
    /// Tile size in samples (Unreal World Partition tiles); `None`: one file per map.
    pub tile: Option<usize>,
    /// Also write the heightmap of the snow surface (bedrock + snow).
    pub with_snow: bool,
}

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error(transparent)]
    Atomic(#[from] snowscape_io::AtomicWriteError),
    #[error(
        "{path} is not a snowscape run folder: {file} is missing (run `snowscape run` or `demo` first)"
    )]
    NotARun { path: PathBuf, file: &'static str },
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: snowscape_io::RasterError,
    },
    #[error("{what} is {got}x{got_h}, the bedrock {w}x{h}")]
    SizeMismatch {
        what: String,
        got: usize,
        got_h: usize,
        w: usize,
        h: usize,
    },
    #[error("--tile {0}: a tile must be 2 to 8129 samples")]
    BadTile(usize),
    #[error("the bedrock has no valid cell")]
    NoData,
    #[error("cannot write {path}: {message}")]
    Write { path: PathBuf, message: String },
}

/// What was written.
#[derive(Debug, Clone, Serialize)]
pub struct EngineExport {
    pub engine: Engine,
    /// Heightmap samples (width, height).
    pub size: [usize; 2],
    /// Lowest and highest height of the shared scale, m.
    pub z_range_m: [f64; 2],
    /// Distance between samples (x, y), m.
    pub sample_spacing_m: [f64; 2],
    /// The engine's import settings.
    pub import: ImportSettings,
    pub files: Vec<String>,
}

/// What to type into an engine's import dialog for the exported heightmaps.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ImportSettings {
    /// Unreal's Landscape import (scales in cm per sample, the Z scale per 1/512 of the range).
    Unreal {
        dialog: &'static str,
        scale_x: f64,
        scale_y: f64,
        scale_z: f64,
        location_z_cm: f64,
        /// Samples (width, height).
        resolution: [usize; 2],
        /// Samples per tile side, if tiled.
        tile_samples: Option<usize>,
        heightmap_code_to_height_m: String,
    },
    /// Unity's Terrain Import Raw.
    Unity {
        dialog: &'static str,
        heightmap_resolution: usize,
        terrain_width_m: f64,
        terrain_length_m: f64,
        terrain_height_m: f64,
        position_y_m: f64,
        /// The layer of each channel (RGBA) of each splat map.
        splatmaps: BTreeMap<&'static str, Vec<&'static str>>,
        control_texture_resolution: usize,
    },
    /// Godot's HTerrain add-on import.
    Godot {
        add_on: &'static str,
        heightmap: &'static str,
        min_height_m: f64,
        max_height_m: f64,
        resolution: usize,
        cell_size_m: f64,
        /// The layer of each channel (RGBA) of the splat map.
        splatmap: BTreeMap<&'static str, Vec<&'static str>>,
    },
}

/// A run raster opened for windows of rows, with its path (for errors).
struct RunRaster {
    path: PathBuf,
    rows: TiffRows,
}

impl RunRaster {
    fn read_rows(&mut self, rows: std::ops::Range<usize>) -> Result<Grid, ExportError> {
        self.rows
            .read_rows(rows)
            .map_err(|source| ExportError::Read {
                path: self.path.clone(),
                source,
            })
    }
}

/// The run's rasters: bedrock and the four snow layers, read a window of rows at a time.
struct RunRasters {
    bedrock: RunRaster,
    layers: Vec<RunRaster>,
}

fn open_run(dir: &Path) -> Result<RunRasters, ExportError> {
    let open = |file: &'static str| {
        let path = dir.join(file);
        if !path.is_file() {
            return Err(ExportError::NotARun {
                path: dir.to_path_buf(),
                file,
            });
        }
        match TiffRows::open(&path, &ReadOptions::default()) {
            Ok(rows) => Ok(RunRaster { path, rows }),
            Err(source) => Err(ExportError::Read { path, source }),
        }
    };
    let bedrock = open("bedrock.tif")?;
    let mut layers = Vec::new();
    for (l, file) in SnowLayer::ALL.iter().zip([
        "layers_compacted.tif",
        "layers_stable.tif",
        "layers_unstable.tif",
        "layers_powder.tif",
    ]) {
        let r = open(file)?;
        let (a, b) = (r.rows.geometry(), bedrock.rows.geometry());
        if (a.width(), a.height()) != (b.width(), b.height()) {
            return Err(ExportError::SizeMismatch {
                what: l.name().to_string(),
                got: a.width(),
                got_h: a.height(),
                w: b.width(),
                h: b.height(),
            });
        }
        layers.push(r);
    }
    Ok(RunRasters { bedrock, layers })
}

/// Rows of the run's rasters read at a time.
const WINDOW_ROWS: usize = 64;

/// Rows `start..` of the run's rasters.
struct Window {
    start: usize,
    end: usize,
    bedrock: Grid,
    layers: Vec<Grid>,
}

impl RunRasters {
    fn window(&mut self, rows: std::ops::Range<usize>) -> Result<Window, ExportError> {
        Ok(Window {
            start: rows.start,
            end: rows.end,
            bedrock: self.bedrock.read_rows(rows.clone())?,
            layers: self
                .layers
                .iter_mut()
                .map(|l| l.read_rows(rows.clone()))
                .collect::<Result<_, _>>()?,
        })
    }

    /// The lowest valid bedrock cell, m.
    fn lowest_bedrock(&mut self) -> Result<f32, ExportError> {
        let h = self.bedrock.rows.geometry().height();
        let mut lowest: Option<f32> = None;
        for start in (0..h).step_by(4 * WINDOW_ROWS) {
            let rows = self
                .bedrock
                .read_rows(start..(start + 4 * WINDOW_ROWS).min(h))?;
            if let Some((lo, _)) = rows.value_range() {
                lowest = Some(lowest.map_or(lo, |l| l.min(lo)));
            }
        }
        lowest.ok_or(ExportError::NoData)
    }
}

/// The heightmap size of `engine` for a grid of `w` × `h` cells.
pub fn engine_size(engine: Engine, w: usize, h: usize) -> [usize; 2] {
    let unreal = |n: usize| *UNREAL_SIZES.iter().find(|&&s| s >= n).unwrap_or(&8129);
    let pow2 = |n: usize| {
        let mut s = 33;
        while s < n && s < 4097 {
            s = (s - 1) * 2 + 1;
        }
        s
    };
    match engine {
        Engine::Unreal => [unreal(w), unreal(h)],
        Engine::Unity | Engine::Godot => {
            let s = pow2(w.max(h));
            [s, s]
        }
    }
}

/// The resampled maps: heights (bedrock, snow surface) and the five weights (compacted, stable,
/// unstable, powder, rock), row-major, `size` samples.
struct Maps {
    bedrock: Vec<f32>,
    surface: Vec<f32>,
    weights: [Vec<u8>; 5],
}

/// The maps at `size` samples, bilinear at evenly spaced positions from the first to the last
/// cell centre, reading the run's rasters a window of rows at a time (the rows each output row
/// samples: memory follows the output and the window, not the run's grid).
fn resample(run: &mut RunRasters, size: [usize; 2]) -> Result<Maps, ExportError> {
    let g = run.bedrock.rows.geometry().clone();
    let lowest = run.lowest_bedrock()?;
    let [nw, nh] = size;
    let n = nw * nh;
    let (mut bedrock, mut surface) = (vec![0.0f32; n], vec![0.0f32; n]);
    let mut weights: [Vec<u8>; 5] = std::array::from_fn(|_| vec![0u8; n]);
    let at = |k: usize, n: usize, cells: usize| {
        if n <= 1 {
            0.0
        } else {
            k as f64 * (cells - 1) as f64 / (n - 1) as f64
        }
    };
    let h = g.height();
    let mut window: Option<Window> = None;
    for r in 0..nh {
        let row = at(r, nh, h);
        // A sample reads its row and the next (the last row alone at the bottom).
        let first = (row.floor() as usize).min(h - 1);
        let last = (first + 2).min(h);
        if !window
            .as_ref()
            .is_some_and(|w| w.start <= first && last <= w.end)
        {
            window = Some(run.window(first..(first + WINDOW_ROWS).min(h).max(last))?);
        }
        let Some(win) = window.as_ref() else {
            continue;
        };
        // Exact: `row − start` is a multiple of `row`'s last bit, smaller than `row`.
        let wrow = row - win.start as f64;
        for c in 0..nw {
            let col = at(c, nw, g.width());
            let i = r * nw + c;
            let Some(b) = win.bedrock.sample(col, wrow) else {
                bedrock[i] = lowest;
                surface[i] = lowest;
                weights[4][i] = 255;
                continue;
            };
            let t: [f32; 4] =
                std::array::from_fn(|l| win.layers[l].sample(col, wrow).unwrap_or(0.0).max(0.0));
            let depth: f32 = t.iter().sum();
            bedrock[i] = b;
            surface[i] = b + depth;
            let cover = (f64::from(depth) / 0.3).min(1.0);
            let mut share = [0.0f64; 5];
            for l in 0..4 {
                if depth > 0.0 {
                    share[l] = cover * f64::from(t[l]) / f64::from(depth);
                }
            }
            share[4] = 1.0 - cover;
            let q = quantise_255(share);
            for l in 0..5 {
                weights[l][i] = q[l];
            }
        }
    }
    Ok(Maps {
        bedrock,
        surface,
        weights,
    })
}

/// Shares (summing to 1) as bytes summing to exactly 255 (largest remainders).
pub fn quantise_255<const N: usize>(share: [f64; N]) -> [u8; N] {
    let scaled = share.map(|s| s.clamp(0.0, 1.0) * 255.0);
    let mut out = scaled.map(|v| v.floor() as u8);
    let total: u32 = out.iter().map(|&v| u32::from(v)).sum();
    let mut left = 255u32.saturating_sub(total);
    let mut order: Vec<usize> = (0..N).collect();
    order.sort_by(|&a, &b| {
        (scaled[b] - scaled[b].floor()).total_cmp(&(scaled[a] - scaled[a].floor()))
    });
    for &k in order.iter().cycle().take(N * 255) {
        if left == 0 {
            break;
        }
        if out[k] < 255 {
            out[k] += 1;
            left -= 1;
        }
    }
    out
}

/// A tile of the maps: columns `c0..c0 + w`, rows `r0..r0 + h`, named `_x{i}_y{j}`.
struct Tile {
    suffix: String,
    c0: usize,
    r0: usize,
    w: usize,
    h: usize,
}

fn tiles(size: [usize; 2], tile: Option<usize>) -> Vec<Tile> {
    let [w, h] = size;
    let Some(t) = tile else {
        return vec![Tile {
            suffix: String::new(),
            c0: 0,
            r0: 0,
            w,
            h,
        }];
    };
    // Tiles share their edge: tile i starts at i·(t − 1).
    let step = t - 1;
    let count = |n: usize| (n - 1).div_ceil(step).max(1);
    let mut out = Vec::new();
    for j in 0..count(h) {
        for i in 0..count(w) {
            let (c0, r0) = (i * step, j * step);
            out.push(Tile {
                suffix: format!("_x{i}_y{j}"),
                c0,
                r0,
                w: t.min(w - c0),
                h: t.min(h - r0),
            });
        }
    }
    out
}

fn cut<T: Copy>(values: &[T], width: usize, t: &Tile) -> Vec<T> {
    let mut out = Vec::with_capacity(t.w * t.h);
    for r in t.r0..t.r0 + t.h {
        out.extend_from_slice(&values[r * width + t.c0..r * width + t.c0 + t.w]);
    }
    out
}

fn write_png(
    path: &Path,
    (w, h): (usize, usize),
    bytes: &[u8],
    color: ExtendedColorType,
) -> Result<(), ExportError> {
    use image::ImageEncoder;
    let err = |message: String| ExportError::Write {
        path: path.to_path_buf(),
        message,
    };
    write_atomic(path, |out| {
        image::codecs::png::PngEncoder::new(out)
            .write_image(bytes, w as u32, h as u32, color)
            .map_err(|e| err(e.to_string()))
    })
}

/// 16-bit codes of `heights` on the scale `lo..hi` (code 0 at `lo`, 65535 at `hi`).
pub fn codes(heights: &[f32], lo: f64, hi: f64) -> Vec<u16> {
    let span = (hi - lo).max(1e-9);
    heights
        .iter()
        .map(|&z| {
            ((f64::from(z) - lo) / span * 65535.0)
                .round()
                .clamp(0.0, 65535.0) as u16
        })
        .collect()
}

/// Exports the run in `run_dir` for `options.engine` into `out` (created if missing).
pub fn export_run(
    run_dir: &Path,
    out: &Path,
    options: &ExportOptions,
) -> Result<EngineExport, ExportError> {
    if let Some(t) = options.tile
        && !(2..=8129).contains(&t)
    {
        return Err(ExportError::BadTile(t));
    }
    let mut run = open_run(run_dir)?;
    let g: GridGeometry = run.bedrock.rows.geometry().clone();
    let size = engine_size(options.engine, g.width(), g.height());
    let maps = resample(&mut run, size)?;
    std::fs::create_dir_all(out).map_err(|e| ExportError::Write {
        path: out.to_path_buf(),
        message: e.to_string(),
    })?;
    let lo = maps.bedrock.iter().fold(f32::INFINITY, |m, &v| m.min(v)) as f64;
    let hi_b = maps
        .bedrock
        .iter()
        .fold(f32::NEG_INFINITY, |m, &v| m.max(v)) as f64;
    let hi = if options.with_snow {
        maps.surface
            .iter()
            .fold(f32::NEG_INFINITY, |m, &v| m.max(v)) as f64
    } else {
        hi_b
    };
    let extent = [
        (g.width() - 1) as f64 * g.cell_size_x(),
        (g.height() - 1) as f64 * g.cell_size_y(),
    ];
    let spacing = [
        extent[0] / (size[0] - 1).max(1) as f64,
        extent[1] / (size[1] - 1).max(1) as f64,
    ];
    let mut files = Vec::new();
    let mut heightmaps: Vec<(&str, &[f32])> = vec![("bedrock", &maps.bedrock)];
    if options.with_snow {
        heightmaps.push(("snow", &maps.surface));
    }
    let target = Target {
        out,
        maps: &maps,
        heightmaps: &heightmaps,
        size,
        z_range: (lo, hi),
        spacing,
    };
    let import = match options.engine {
        Engine::Unreal => unreal_files(&target, options.tile, &mut files)?,
        Engine::Unity => unity_files(&target, extent, &mut files)?,
        Engine::Godot => godot_files(&target, &mut files)?,
    };
    let report = EngineExport {
        engine: options.engine,
        size,
        z_range_m: [lo, hi],
        sample_spacing_m: spacing,
        import,
        files: files.clone(),
    };
    let name = match options.engine {
        Engine::Unreal => "unreal_import.json",
        Engine::Unity => "unity_import.json",
        Engine::Godot => "godot_import.json",
    };
    let text = serde_json::to_string_pretty(&report).unwrap_or_default();
    write_file(out, name, text.as_bytes(), &mut files)?;
    Ok(EngineExport { files, ..report })
}

/// What every engine's files are made from: the output folder, the resampled maps, the
/// heightmaps to write (bedrock, and snow with `--with-snow`), the engine's sample size, the
/// height range the 16-bit codes span and the sample spacing, m.
struct Target<'a> {
    out: &'a Path,
    maps: &'a Maps,
    heightmaps: &'a [(&'a str, &'a [f32])],
    size: [usize; 2],
    z_range: (f64, f64),
    spacing: [f64; 2],
}

/// The weight maps' names, in the order of `Maps::weights`.
const LAYER_NAMES: [&str; 5] = ["compacted", "stable", "unstable", "powder", "rock"];

/// Writes `bytes` to `name` in `out` atomically and lists it in `files`.
fn write_file(
    out: &Path,
    name: &str,
    bytes: &[u8],
    files: &mut Vec<String>,
) -> Result<(), ExportError> {
    let path = out.join(name);
    write_bytes_atomic(&path, bytes).map_err(|e| ExportError::Write {
        path,
        message: e.to_string(),
    })?;
    files.push(name.to_string());
    Ok(())
}

/// Unreal's files (16-bit PNG heightmaps and 8-bit weight maps, in tiles of `tile` samples
/// when asked) and its import settings.
fn unreal_files(
    target: &Target,
    tile: Option<usize>,
    files: &mut Vec<String>,
) -> Result<ImportSettings, ExportError> {
    let (out, maps, size, (lo, hi), spacing) = (
        target.out,
        target.maps,
        target.size,
        target.z_range,
        target.spacing,
    );
    for t in tiles(size, tile) {
        for (name, h) in target.heightmaps {
            let c = codes(&cut(h, size[0], &t), lo, hi);
            let bytes: Vec<u8> = c.iter().flat_map(|v| v.to_ne_bytes()).collect();
            let file = format!("heightmap_{name}{}.png", t.suffix);
            write_png(&out.join(&file), (t.w, t.h), &bytes, ExtendedColorType::L16)?;
            files.push(file);
        }
        for (l, w) in LAYER_NAMES.iter().zip(&maps.weights) {
            let file = format!("weight_{l}{}.png", t.suffix);
            write_png(
                &out.join(&file),
                (t.w, t.h),
                &cut(w, size[0], &t),
                ExtendedColorType::L8,
            )?;
            files.push(file);
        }
    }
    let z_scale = (hi - lo) * 12800.0 / 65535.0;
    Ok(ImportSettings::Unreal {
        dialog: "Landscape mode > Manage > Import from File (heightmap_bedrock.png, or its tiles); one paint layer per weight map",
        scale_x: spacing[0] * 100.0,
        scale_y: spacing[1] * 100.0,
        scale_z: z_scale,
        location_z_cm: lo * 100.0 + 256.0 * z_scale,
        resolution: size,
        tile_samples: tile,
        heightmap_code_to_height_m: format!("z = {lo} + code / 65535 * {}", hi - lo),
    })
}

/// Unity's files (16-bit RAW heightmaps, two RGBA splat maps) and its import settings;
/// `extent` is the terrain's size, m.
fn unity_files(
    t: &Target,
    extent: [f64; 2],
    files: &mut Vec<String>,
) -> Result<ImportSettings, ExportError> {
    let (out, maps, size, (lo, hi)) = (t.out, t.maps, t.size, t.z_range);
    for (name, h) in t.heightmaps {
        let c = codes(h, lo, hi);
        let bytes: Vec<u8> = c.iter().flat_map(|v| v.to_le_bytes()).collect();
        write_file(out, &format!("heightmap_{name}.raw"), &bytes, files)?;
    }
    let n = size[0] - 1;
    for (k, group) in [[0usize, 1, 2, 3], [4, 5, 5, 5]].iter().enumerate() {
        let splat = splat_rgba(maps, size, n, group);
        let file = format!("splatmap_{k}.png");
        write_png(&out.join(&file), (n, n), &splat, ExtendedColorType::Rgba8)?;
        files.push(file);
    }
    Ok(ImportSettings::Unity {
        dialog: "Terrain > Terrain Settings > Import Raw: depth 16 bit, byte order Windows, flip vertically (row 0 of the file is north)",
        heightmap_resolution: size[0],
        terrain_width_m: extent[0],
        terrain_length_m: extent[1],
        terrain_height_m: hi - lo,
        position_y_m: lo,
        splatmaps: BTreeMap::from([
            (
                "splatmap_0.png",
                vec!["compacted", "stable", "unstable", "powder"],
            ),
            ("splatmap_1.png", vec!["rock"]),
        ]),
        control_texture_resolution: n,
    })
}

/// Godot's files (16-bit RAW and 32-bit EXR heightmaps, one RGBA splat map) and the HTerrain
/// import settings.
fn godot_files(t: &Target, files: &mut Vec<String>) -> Result<ImportSettings, ExportError> {
    let (out, maps, size, (lo, hi), spacing) = (t.out, t.maps, t.size, t.z_range, t.spacing);
    for (name, h) in t.heightmaps {
        let c = codes(h, lo, hi);
        let bytes: Vec<u8> = c.iter().flat_map(|v| v.to_le_bytes()).collect();
        write_file(out, &format!("heightmap_{name}.raw"), &bytes, files)?;
        let geometry =
            GridGeometry::new(size[0], size[1], spacing[0].max(1e-6), spacing[1].max(1e-6))
                .map_err(|e| ExportError::Write {
                    path: out.to_path_buf(),
                    message: e.to_string(),
                })?;
        let file = format!("heightmap_{name}.exr");
        write_exr(&out.join(&file), &geometry, &[("R", h)]).map_err(|e| ExportError::Write {
            path: out.join(&file),
            message: e.to_string(),
        })?;
        files.push(file);
    }
    // R rock, G compacted + stable, B unstable, A powder.
    let splat = splat_rgba(maps, size, size[0], &[4, 6, 2, 3]);
    write_png(
        &out.join("splatmap.png"),
        (size[0], size[1]),
        &splat,
        ExtendedColorType::Rgba8,
    )?;
    files.push("splatmap.png".into());
    Ok(ImportSettings::Godot {
        add_on: "HTerrain (Zylann's Heightmap Terrain, Godot 4): Import dialog",
        heightmap: "heightmap_bedrock.raw (16-bit little endian) with the min and max heights below, or heightmap_bedrock.exr (32-bit float, metres)",
        min_height_m: lo,
        max_height_m: hi,
        resolution: size[0],
        cell_size_m: spacing[0],
        splatmap: BTreeMap::from([(
            "splatmap.png",
            vec!["rock", "compacted + stable", "unstable", "powder"],
        )]),
    })
}

/// RGBA bytes of four weight channels at `n` × `n` texels (nearest sample); channel index 5
/// is 0 and 6 is compacted + stable.
fn splat_rgba(maps: &Maps, size: [usize; 2], n: usize, channels: &[usize; 4]) -> Vec<u8> {
    let mut out = Vec::with_capacity(n * n * 4);
    for r in 0..n {
        let sr = (r * (size[1] - 1)) / (n - 1).max(1);
        for c in 0..n {
            let sc = (c * (size[0] - 1)) / (n - 1).max(1);
            let i = sr * size[0] + sc;
            for &ch in channels {
                out.push(match ch {
                    5 => 0,
                    6 => maps.weights[0][i] + maps.weights[1][i],
                    k => maps.weights[k][i],
                });
            }
        }
    }
    out
}
