//! The legend of a terrain preview: what its colours mean, drawn in a corner of the image with
//! the [`crate::pixel_font`], from the same colour functions the preview uses ([`crate::colour`]):
//!
//! - [`ColourMode::Snow`]: the snow cover ramp (bare ground to white at
//!   [`colour::FULL_COVER_DEPTH_M`], in metres of snow) and the ground's altitude ramp with the
//!   terrain's lowest and highest altitudes;
//! - [`ColourMode::Layers`]: the four layer tints and bare ground;
//! - [`ColourMode::Stability`]: the three classes of Cordonnier et al. 2018, Fig. 11;
//! - [`ColourMode::Map`]: the viridis ramp with the map's range.

use crate::ColourMode;
use crate::colour::{self, Rgb};
use crate::pixel_font::{LINE_HEIGHT, draw_text, text_width};
use image::{Rgba, RgbaImage};
use snowscape_terrain::LayeredTerrain;

/// One line of a legend: a swatch (a ramp of colours, or one colour) and its text.
struct Entry {
    swatch: Vec<Rgb>,
    text: String,
}

/// The range of the valid values of `values` under `terrain`'s mask.
fn range(terrain: &LayeredTerrain, values: &[f32]) -> Option<(f32, f32)> {
    let mask = terrain.mask();
    values
        .iter()
        .enumerate()
        .filter(|&(i, v)| mask.is_valid(i) && v.is_finite())
        .map(|(_, &v)| v)
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
}

fn entries(mode: &ColourMode, terrain: &LayeredTerrain) -> Vec<Entry> {
    let ramp = |f: &dyn Fn(f32) -> Rgb| (0..=24).map(|k| f(k as f32 / 24.0)).collect::<Vec<_>>();
    let ground_mid = colour::ground_colour(0.3, 1.0);
    match mode {
        ColourMode::Snow => {
            let (lo, hi) = range(terrain, &terrain.bedrock).unwrap_or((0.0, 0.0));
            vec![
                Entry {
                    swatch: ramp(&|t| {
                        colour::mix(
                            ground_mid,
                            colour::SNOW_WHITE,
                            colour::snow_cover(t * colour::FULL_COVER_DEPTH_M),
                        )
                    }),
                    text: format!(
                        "snow depth 0 - {:.1} m and more",
                        colour::FULL_COVER_DEPTH_M
                    ),
                },
                Entry {
                    swatch: ramp(&|t| colour::ground_colour(t, 1.0)),
                    text: format!("bare ground {lo:.0} - {hi:.0} m"),
                },
                Entry {
                    swatch: vec![colour::CLIFF_ROCK],
                    text: format!("rock, slopes over {:.0} deg", colour::CLIFF_SLOPE_FULL_DEG),
                },
            ]
        }
        ColourMode::Layers => {
            let mut v: Vec<Entry> = ["compacted", "stable", "unstable", "powder"]
                .iter()
                .zip(colour::LAYER_COLOURS)
                .map(|(name, c)| Entry {
                    swatch: vec![c],
                    text: format!("{name} snow"),
                })
                .collect();
            v.push(Entry {
                swatch: vec![ground_mid],
                text: "no snow: ground".into(),
            });
            v
        }
        ColourMode::Stability => vec![
            Entry {
                swatch: vec![colour::STABILITY_BLUE],
                text: "compacted or stable on top".into(),
            },
            Entry {
                swatch: vec![colour::STABILITY_PURPLE],
                text: "unstable or powder on top".into(),
            },
            Entry {
                swatch: vec![colour::STABILITY_BLACK],
                text: "no snow".into(),
            },
        ],
        ColourMode::Map(name) => {
            let values = terrain.maps.get(name.as_str());
            let (lo, hi) = values.and_then(|v| range(terrain, v)).unwrap_or((0.0, 0.0));
            vec![Entry {
                swatch: ramp(&|t| colour::viridis(t)),
                text: format!("{name} {lo:.3} - {hi:.3}"),
            }]
        }
    }
}

/// `image` with the legend of `mode` in its top-left corner (on a dark panel; nothing when the
/// image is too small to hold it).
pub fn with_legend(image: &RgbaImage, mode: &ColourMode, terrain: &LayeredTerrain) -> RgbaImage {
    let mut img = image.clone();
    let list = entries(mode, terrain);
    let (pad, swatch_w, gap) = (6u32, 36u32, 6u32);
    let line = LINE_HEIGHT + 6;
    let text_w = list.iter().map(|e| text_width(&e.text)).max().unwrap_or(0);
    let (w, h) = (
        pad * 2 + swatch_w + gap + text_w,
        pad * 2 + line * list.len() as u32 - 6,
    );
    if w + 8 > img.width() || h + 8 > img.height() {
        return img;
    }
    let (x0, y0) = (4u32, 4u32);
    for y in y0..y0 + h {
        for x in x0..x0 + w {
            let p = img.get_pixel_mut(x, y);
            // A dark, three-quarters opaque panel.
            for c in 0..3 {
                p.0[c] = ((u32::from(p.0[c]) + 3 * 24) / 4) as u8;
            }
            p.0[3] = 255;
        }
    }
    for (k, e) in list.iter().enumerate() {
        let y = y0 + pad + k as u32 * line;
        let n = e.swatch.len() as u32;
        for dx in 0..swatch_w {
            let c = e.swatch[((dx * n) / swatch_w).min(n - 1) as usize];
            let [r, g, b] = colour::to_bytes(c);
            for dy in 0..LINE_HEIGHT {
                img.put_pixel(x0 + pad + dx, y + dy, Rgba([r, g, b, 255]));
            }
        }
        draw_text(
            &mut img,
            x0 + pad + swatch_w + gap,
            y,
            &e.text,
            Rgba([240, 240, 240, 255]),
        );
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_terrain::{Grid, GridGeometry};

    #[test]
    fn every_mode_has_a_legend_drawn_in_the_corner() {
        let g = GridGeometry::square(64, 48, 10.0).unwrap();
        let terrain =
            LayeredTerrain::from_bedrock(Grid::from_fn(g, |c, r| (1000 + 5 * c + r) as f32));
        let img = RgbaImage::from_pixel(400, 300, Rgba([200, 210, 220, 255]));
        for mode in [ColourMode::Snow, ColourMode::Layers, ColourMode::Stability] {
            let list = entries(&mode, &terrain);
            assert!(!list.is_empty());
            let out = with_legend(&img, &mode, &terrain);
            // The panel darkens the corner; the rest is untouched.
            assert!(out.get_pixel(6, 6).0[0] < 100, "{mode:?}");
            assert_eq!(out.get_pixel(399, 299), img.get_pixel(399, 299));
        }
        // The snow legend names the terrain's altitudes.
        let snow = entries(&ColourMode::Snow, &terrain);
        assert!(
            snow.iter().any(|e| e.text.contains("1000 - 1362 m")),
            "{:?}",
            snow.iter().map(|e| &e.text).collect::<Vec<_>>()
        );
        // The layer swatches are the preview's own tints.
        let layers = entries(&ColourMode::Layers, &terrain);
        assert_eq!(layers[2].swatch, vec![colour::LAYER_COLOURS[2]]);
        // Too small an image is left as it is.
        let tiny = RgbaImage::new(40, 20);
        assert_eq!(with_legend(&tiny, &ColourMode::Snow, &terrain), tiny);
    }
}
