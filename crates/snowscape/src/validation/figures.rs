//! The validation figures, as images (the command encodes and writes them atomically):
//!
//! - [`side_by_side`]: observed and simulated depth on the run's grid, north up, one viridis
//!   scale from 0 to the 99th percentile of both (deeper cells saturate), cells left out of
//!   the comparison in grey, a labelled colour bar on the right.
//! - [`density_scatter`]: observed (x) against simulated (y) depth as a 2-D histogram of
//!   4×4-pixel bins coloured by log(1 + count), on axes from min(0, 0.5th percentile) to the
//!   99.5th percentile of both (points beyond sit on the border), with the 1:1 line in red.

use image::{Rgba, RgbaImage};
use snowscape_render::colour::{to_bytes, viridis};
use snowscape_render::pixel_font::{LINE_HEIGHT, draw_text, text_width};

const WHITE: Rgba<u8> = Rgba([255, 255, 255, 255]);
const BLACK: Rgba<u8> = Rgba([0, 0, 0, 255]);
const GREY: Rgba<u8> = Rgba([128, 128, 128, 255]);
const RED: Rgba<u8> = Rgba([220, 30, 30, 255]);
const MARGIN: u32 = 12;
/// Longest side of a map panel, pixels.
const PANEL_MAX: u32 = 512;
/// Side of the scatter plot's square, pixels.
const PLOT: u32 = 400;
/// Side of a scatter bin, pixels.
const BIN: u32 = 4;

fn rgba(rgb: [f32; 3]) -> Rgba<u8> {
    let [r, g, b] = to_bytes(rgb);
    Rgba([r, g, b, 255])
}

/// The `q` quantile (0..1) of the finite values, by nearest rank; `None` without any.
fn quantile(values: impl Iterator<Item = f64>, q: f64) -> Option<f64> {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[((v.len() - 1) as f64 * q).round() as usize])
}

/// A short label for an axis or colour-bar value.
fn label(v: f64) -> String {
    if v.abs() >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

fn fill(img: &mut RgbaImage, x: u32, y: u32, w: u32, h: u32, c: Rgba<u8>) {
    for py in y..(y + h).min(img.height()) {
        for px in x..(x + w).min(img.width()) {
            img.put_pixel(px, py, c);
        }
    }
}

/// Observed and simulated depth maps side by side (module docs). `observed` and `simulated`
/// hold one value per run cell, row-major, NaN where the cell is not compared.
pub fn side_by_side(width: usize, height: usize, observed: &[f64], simulated: &[f64]) -> RgbaImage {
    let longest = width.max(height) as f64;
    let scale = if longest > PANEL_MAX as f64 {
        PANEL_MAX as f64 / longest
    } else {
        (PANEL_MAX as f64 / longest).floor().max(1.0)
    };
    let pw = ((width as f64 * scale).round() as u32).max(1);
    let ph = ((height as f64 * scale).round() as u32).max(1);
    let top = (quantile(observed.iter().chain(simulated).copied(), 0.99).unwrap_or(1.0)).max(0.01);
    let bar_labels = [label(top), label(top / 2.0), label(0.0), "M".to_string()];
    let label_w = bar_labels.iter().map(|l| text_width(l)).max().unwrap_or(0);
    let title_h = LINE_HEIGHT + 8;
    let bar_x = MARGIN + 2 * (pw + MARGIN);
    let w = bar_x + 16 + 6 + label_w + MARGIN;
    let h = MARGIN + title_h + ph + MARGIN + LINE_HEIGHT;
    let mut img = RgbaImage::from_pixel(w, h, WHITE);
    let y0 = MARGIN + title_h;
    for (k, (name, values)) in [("OBSERVED", observed), ("SIMULATED", simulated)]
        .into_iter()
        .enumerate()
    {
        let x0 = MARGIN + k as u32 * (pw + MARGIN);
        draw_text(&mut img, x0, MARGIN, name, BLACK);
        for py in 0..ph {
            let row = ((py as f64 + 0.5) / scale) as usize;
            for px in 0..pw {
                let col = ((px as f64 + 0.5) / scale) as usize;
                let v = values[row.min(height - 1) * width + col.min(width - 1)];
                let c = if v.is_finite() {
                    rgba(viridis((v / top) as f32))
                } else {
                    GREY
                };
                img.put_pixel(x0 + px, y0 + py, c);
            }
        }
    }
    // The colour bar: `top` at its top edge, 0 at its bottom.
    for py in 0..ph {
        let t = 1.0 - (py as f32 + 0.5) / ph as f32;
        fill(&mut img, bar_x, y0 + py, 16, 1, rgba(viridis(t)));
    }
    let lx = bar_x + 16 + 6;
    draw_text(&mut img, lx, y0, &bar_labels[0], BLACK);
    draw_text(
        &mut img,
        lx,
        y0 + ph / 2 - LINE_HEIGHT / 2,
        &bar_labels[1],
        BLACK,
    );
    draw_text(&mut img, lx, y0 + ph - LINE_HEIGHT, &bar_labels[2], BLACK);
    draw_text(&mut img, lx, MARGIN, &bar_labels[3], BLACK);
    draw_text(
        &mut img,
        MARGIN,
        y0 + ph + 6,
        "DEPTH (M). GREY: NOT COMPARED",
        BLACK,
    );
    img
}

/// Observed against simulated depth as a density scatter with the 1:1 line (module docs).
pub fn density_scatter(observed: &[f64], simulated: &[f64]) -> RgbaImage {
    let all = || observed.iter().chain(simulated).copied();
    let lo = quantile(all(), 0.005).unwrap_or(0.0).min(0.0);
    let mut hi = quantile(all(), 0.995).unwrap_or(1.0);
    if hi <= lo {
        hi = lo + 1.0;
    }
    let bins = PLOT / BIN;
    let mut counts = vec![0u32; (bins * bins) as usize];
    let bin_of = |v: f64| -> u32 {
        let t = ((v - lo) / (hi - lo)).clamp(0.0, 1.0);
        ((t * bins as f64) as u32).min(bins - 1)
    };
    for (&o, &s) in observed.iter().zip(simulated) {
        if o.is_finite() && s.is_finite() {
            counts[(bin_of(s) * bins + bin_of(o)) as usize] += 1;
        }
    }
    let max = counts.iter().copied().max().unwrap_or(0).max(1) as f32;
    let left = MARGIN + text_width(&label(hi)).max(text_width(&label(lo))) + 6;
    let top = MARGIN + LINE_HEIGHT + 8;
    let w = left + PLOT + MARGIN + 8;
    let h = top + PLOT + 6 + 2 * LINE_HEIGHT + 8 + MARGIN;
    let mut img = RgbaImage::from_pixel(w, h, WHITE);
    for by in 0..bins {
        for bx in 0..bins {
            let n = counts[(by * bins + bx) as usize];
            if n == 0 {
                continue;
            }
            let t = (1.0 + n as f32).ln() / (1.0 + max).ln();
            // Simulated grows upwards: bin row 0 is the bottom of the plot.
            let y = top + PLOT - (by + 1) * BIN;
            fill(&mut img, left + bx * BIN, y, BIN, BIN, rgba(viridis(t)));
        }
    }
    for k in 0..PLOT {
        img.put_pixel(left + k, top + PLOT - 1 - k, RED);
    }
    fill(&mut img, left - 1, top, 1, PLOT + 1, BLACK);
    fill(&mut img, left - 1, top + PLOT, PLOT + 1, 1, BLACK);
    let (lo_l, hi_l) = (label(lo), label(hi));
    draw_text(&mut img, MARGIN, top, &hi_l, BLACK);
    draw_text(&mut img, MARGIN, top + PLOT - LINE_HEIGHT, &lo_l, BLACK);
    draw_text(&mut img, left, top + PLOT + 6, &lo_l, BLACK);
    draw_text(
        &mut img,
        left + PLOT - text_width(&hi_l),
        top + PLOT + 6,
        &hi_l,
        BLACK,
    );
    let x_title = "OBSERVED DEPTH (M)";
    draw_text(
        &mut img,
        left + (PLOT - text_width(x_title)) / 2,
        top + PLOT + 6 + LINE_HEIGHT + 6,
        x_title,
        BLACK,
    );
    draw_text(
        &mut img,
        left,
        MARGIN,
        "SIMULATED DEPTH (M)   RED: 1:1",
        BLACK,
    );
    img
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_share_one_scale_and_grey_the_excluded_cells() {
        let obs = vec![0.0, 1.0, f64::NAN, 2.0];
        let sim = vec![0.0, 1.0, 1.5, 2.0];
        let img = side_by_side(2, 2, &obs, &sim);
        // Panels of 256 px (2 cells scaled by 256), side by side.
        let y0 = MARGIN + LINE_HEIGHT + 8;
        assert_eq!(img.height(), y0 + 512 + MARGIN + LINE_HEIGHT);
        let obs_px = |c: u32, r: u32| *img.get_pixel(MARGIN + c * 256 + 128, y0 + r * 256 + 128);
        let sim_px = |c: u32, r: u32| {
            *img.get_pixel(MARGIN + 512 + MARGIN + c * 256 + 128, y0 + r * 256 + 128)
        };
        assert_eq!(obs_px(0, 1), GREY);
        assert_eq!(obs_px(1, 0), sim_px(1, 0));
        assert_eq!(obs_px(1, 1), rgba(viridis(1.0)));
        assert_eq!(sim_px(0, 0), rgba(viridis(0.0)));
    }

    #[test]
    fn scatter_puts_equal_values_on_the_diagonal() {
        let v: Vec<f64> = (0..1000).map(|k| k as f64 / 999.0).collect();
        let img = density_scatter(&v, &v);
        // Off the diagonal stays white; the bins along it are coloured.
        let left = MARGIN + text_width(&label(1.0)) + 6;
        let top = MARGIN + LINE_HEIGHT + 8;
        assert_eq!(*img.get_pixel(left + 300, top + 300), WHITE);
        let p = *img.get_pixel(left + 201, top + PLOT - 203);
        assert_ne!(p, WHITE);
    }
}
