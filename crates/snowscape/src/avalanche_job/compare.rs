//! The AIMEC-like comparison of a run with a reference peak-thickness raster
//! (`snowscape_avalanche::comparison`, as AvaFrame's ana3AIMEC compares runs along their path):
//! `comparison` in report.json, the profile `comparison_profile.csv` and its plot
//! `comparison.png` (`snowscape avalanche --compare REF [--path LINE.shp]`).

use super::AvalancheJobError;
use crate::outputs::{OutputError, Written, write_png};
use image::{Rgba, RgbaImage};
use snowscape_avalanche::comparison::{PathComparison, compare_along_path, thalweg};
use snowscape_avalanche::validation::read_polyline;
use snowscape_io::{ReadOptions, read_dem, write_bytes_atomic};
use snowscape_render::pixel_font::{LINE_HEIGHT, draw_text};
use snowscape_terrain::{Grid, GridGeometry};
use std::path::{Path, PathBuf};

/// What a comparison names: the reference run's peak thickness, the path along which to
/// compare (default: the run's thalweg) and the corridor's half-width.
#[derive(Debug, Clone, PartialEq)]
pub struct CompareSpec {
    /// Reference peak-thickness raster (e.g. AvaFrame's `*_pft.asc`), matched by map
    /// coordinates.
    pub reference: PathBuf,
    /// A line shapefile of the avalanche path (e.g. AvaFrame's `LINES/path_aimec.shp`).
    pub path: Option<PathBuf>,
    /// Half-width of the corridor around the path, m, in (0, 100 000].
    pub corridor_m: f64,
}

/// Widest corridor half-width, m.
pub const MAX_CORRIDOR_M: f64 = 1e5;

/// The reference raster and the path line, read before the run (a bad file is refused before
/// any output is written).
pub struct CompareInputs {
    pub reference: Grid,
    pub path: Option<Vec<(f64, f64)>>,
}

/// Reads the reference raster and the path line.
pub fn read_inputs(spec: &CompareSpec) -> Result<CompareInputs, AvalancheJobError> {
    let reference = read_dem(&spec.reference, &ReadOptions::default()).map_err(|source| {
        AvalancheJobError::CompareReference {
            path: spec.reference.clone(),
            source: Box::new(source),
        }
    })?;
    let path = spec.path.as_deref().map(read_path).transpose()?;
    Ok(CompareInputs { reference, path })
}

/// Reads the path line: at least 2 vertices.
fn read_path(p: &Path) -> Result<Vec<(f64, f64)>, AvalancheJobError> {
    let line = read_polyline(p).map_err(|source| AvalancheJobError::ComparePath {
        path: p.to_path_buf(),
        source: Box::new(source),
    })?;
    if line.len() < 2 {
        return Err(AvalancheJobError::PathTooShort {
            path: p.to_path_buf(),
            vertices: line.len(),
        });
    }
    Ok(line)
}

/// Compares the run's peak maps with the reference along the path (or the run's thalweg).
pub fn compare(
    inputs: &CompareInputs,
    dem: &Grid,
    peak_thickness: &[f64],
    peak_speed: &[f64],
    threshold_m: f64,
    corridor_m: f64,
) -> PathComparison {
    let g: &GridGeometry = dem.geometry();
    let derived;
    let path = match &inputs.path {
        Some(p) => (p.as_slice(), "given"),
        None => {
            let bed: Vec<f64> = dem.data().iter().map(|&z| z as f64).collect();
            derived = thalweg(g, &bed, peak_thickness, threshold_m, 40);
            (derived.as_slice(), "thalweg of the run")
        }
    };
    compare_along_path(
        g,
        peak_thickness,
        peak_speed,
        &inputs.reference,
        path,
        threshold_m,
        corridor_m,
    )
}

/// Writes the comparison's profile (`comparison_profile.csv`) and its plot (`comparison.png`).
pub fn write(out: &mut Written, c: &PathComparison) -> Result<(), OutputError> {
    let mut csv = String::from("s_m,thickness_m,reference_thickness_m,speed_m_s\n");
    for b in &c.profile {
        csv.push_str(&format!(
            "{},{},{},{}\n",
            b.s_m, b.thickness_m, b.reference_thickness_m, b.speed_m_s
        ));
    }
    write_bytes_atomic(&out.path("comparison_profile.csv"), csv.as_bytes())?;
    write_png(&out.path("comparison.png"), &plot(c))?;
    Ok(())
}

/// Peak thickness of the run (blue) and the reference (red) along the path, with both runout
/// points as vertical lines.
fn plot(c: &PathComparison) -> RgbaImage {
    let (w, h, left, bottom, top) = (900u32, 420u32, 60u32, 40u32, 40u32);
    let mut img = RgbaImage::from_pixel(w, h, Rgba([255, 255, 255, 255]));
    let plot_w = (w - left - 20) as f64;
    let plot_h = (h - bottom - top) as f64;
    let s_max = c.profile.last().map_or(1.0, |b| b.s_m).max(1.0);
    let h_max = c
        .profile
        .iter()
        .map(|b| b.thickness_m.max(b.reference_thickness_m))
        .fold(0.0, f64::max)
        .max(1e-3);
    let px = |s: f64| left as f64 + s / s_max * plot_w;
    let py = |v: f64| top as f64 + plot_h * (1.0 - v / h_max);
    let grey = Rgba([120, 120, 120, 255]);
    for x in left..w - 20 {
        img.put_pixel(x, h - bottom, grey);
    }
    for y in top..=h - bottom {
        img.put_pixel(left, y, grey);
    }
    let mut line = |values: &dyn Fn(usize) -> f64, colour: Rgba<u8>| {
        let mut last: Option<(f64, f64)> = None;
        for (k, b) in c.profile.iter().enumerate() {
            let p = (px(b.s_m), py(values(k)));
            if let Some(q) = last {
                let steps = ((p.0 - q.0).abs().max((p.1 - q.1).abs()).ceil() as usize).max(1);
                for t in 0..=steps {
                    let f = t as f64 / steps as f64;
                    let (x, y) = (q.0 + f * (p.0 - q.0), q.1 + f * (p.1 - q.1));
                    if x >= 0.0 && y >= 0.0 && (x as u32) < w && (y as u32) < h {
                        img.put_pixel(x as u32, y as u32, colour);
                    }
                }
            }
            last = Some(p);
        }
    };
    let (blue, red) = (Rgba([30, 90, 200, 255]), Rgba([200, 40, 40, 255]));
    line(&|k| c.profile[k].reference_thickness_m, red);
    line(&|k| c.profile[k].thickness_m, blue);
    for (s, colour) in [(c.runout_s_m, blue), (c.reference_runout_s_m, red)] {
        let x = px(s) as u32;
        for y in (top..h - bottom).step_by(3) {
            if x < w {
                img.put_pixel(x, y, colour);
            }
        }
    }
    draw_text(
        &mut img,
        left,
        8,
        &format!(
            "peak thickness along the path: run (blue) {:.0} m, reference (red) {:.0} m, iou {:.2}",
            c.runout_s_m, c.reference_runout_s_m, c.jaccard
        ),
        Rgba([0, 0, 0, 255]),
    );
    draw_text(
        &mut img,
        left,
        h - bottom + 8,
        &format!("0 to {s_max:.0} m along the path ({})", c.path_source),
        grey,
    );
    draw_text(
        &mut img,
        4,
        top.saturating_sub(LINE_HEIGHT + 2),
        &format!("{h_max:.1} m"),
        grey,
    );
    img
}
