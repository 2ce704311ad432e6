//! `snowscape avalanche --compare REF [--path LINE.shp]`: the AIMEC-like comparison of the run
//! with a reference peak-thickness raster (`snowscape_avalanche::comparison`), written as
//! `comparison` in report.json, `comparison_profile.csv` and the plot `comparison.png`.

use crate::outputs::{Written, write_png};
use anyhow::Context;
use image::{Rgba, RgbaImage};
use snowscape_avalanche::comparison::{PathComparison, compare_along_path, thalweg};
use snowscape_avalanche::validation::read_polyline;
use snowscape_io::{ReadOptions, read_dem, write_bytes_atomic};
use snowscape_render::pixel_font::{LINE_HEIGHT, draw_text};
use snowscape_terrain::{Grid, GridGeometry};
use std::path::Path;

/// What `--compare` and `--path` name, read before the run (a bad file is refused before any
/// output is written).
pub struct CompareInputs {
    pub reference: Grid,
    pub path: Option<Vec<(f64, f64)>>,
}

/// Reads the reference raster and the path line.
pub fn read_inputs(reference: &Path, path: Option<&Path>) -> anyhow::Result<CompareInputs> {
    let grid = read_dem(reference, &ReadOptions::default())
        .with_context(|| format!("--compare {}", reference.display()))?;
    let path = match path {
        Some(p) => {
            let line = read_polyline(p).with_context(|| format!("--path {}", p.display()))?;
            anyhow::ensure!(
                line.len() >= 2,
                "--path {}: the line has {} vertices, it needs at least 2",
                p.display(),
                line.len()
            );
            Some(line)
        }
        None => None,
    };
    Ok(CompareInputs {
        reference: grid,
        path,
    })
}

/// Compares the run's peak maps with the reference along the path (or the run's thalweg) and
/// writes the profile and its plot.
pub fn compare_and_write(
    out: &mut Written,
    inputs: &CompareInputs,
    dem: &Grid,
    peak_thickness: &[f64],
    peak_speed: &[f64],
    threshold_m: f64,
    corridor_m: f64,
) -> anyhow::Result<PathComparison> {
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
    let c = compare_along_path(
        g,
        peak_thickness,
        peak_speed,
        &inputs.reference,
        path,
        threshold_m,
        corridor_m,
    );
    let mut csv = String::from("s_m,thickness_m,reference_thickness_m,speed_m_s\n");
    for b in &c.profile {
        csv.push_str(&format!(
            "{},{},{},{}\n",
            b.s_m, b.thickness_m, b.reference_thickness_m, b.speed_m_s
        ));
    }
    write_bytes_atomic(&out.path("comparison_profile.csv"), csv.as_bytes())?;
    write_png(&out.path("comparison.png"), &plot(&c))?;
    Ok(c)
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
