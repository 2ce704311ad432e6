//! Frames of an animation over one relief: a moving avalanche on a bare DEM.
//!
//! [`ReliefFrames`] shades the relief once (surface, sun visibility, the bare image) and draws
//! each frame by copying the bare image and re-shading only the box of cells holding snow,
//! grown by one cell (their neighbours' normals see the snow). Inside the box a pixel is the
//! one [`crate::render_preview`] draws for the snowy terrain, with one approximation: the sun
//! visibility is the bare relief's (the snow casts no shadows of its own; a flow a few metres
//! thick changes the shadows of a relief hundreds of metres high little). Under a sun at the
//! zenith there are no shadows, and a frame equals `render_preview` to the bit (tested).
//! Grids reduced for the preview (`max_size`) and the stability and map colourings fall back to
//! a full `render_preview` per frame.

use crate::RenderError;
use crate::colour;
use crate::planes::{Planes, reduction_factor};
use crate::preview::{ColourMode, PreviewOptions, finite_range, lit, render_preview, row_normals};
use crate::shade::{self, HeightField};
use image::RgbaImage;
use rayon::prelude::*;
use snowscape_terrain::{Grid, LayeredTerrain, SnowLayer};

/// A relief shaded once, to draw frames of snow on it.
pub struct ReliefFrames<'a> {
    dem: &'a Grid,
    opts: PreviewOptions,
    /// `None` when frames fall back to a full render.
    shaded: Option<Shaded>,
}

struct Shaded {
    /// `bedrock · exaggeration`.
    surface: Vec<f32>,
    visibility: Vec<f32>,
    sun: [f32; 3],
    altitude_range: (f32, f32),
    bare: RgbaImage,
}

impl<'a> ReliefFrames<'a> {
    /// Shades `dem` under `opts`.
    pub fn new(dem: &'a Grid, opts: &PreviewOptions) -> Result<Self, RenderError> {
        let bare = render_preview(&LayeredTerrain::from_bedrock(dem.clone()), opts)?;
        let g = dem.geometry();
        let fast = reduction_factor(g.width(), g.height(), opts.max_size) == 1
            && matches!(opts.mode, ColourMode::Snow | ColourMode::Layers);
        let shaded = fast.then(|| {
            let e = opts.vertical_exaggeration as f32;
            let surface: Vec<f32> = dem
                .data()
                .iter()
                .map(|&b| if e != 1.0 { b * e } else { b })
                .collect();
            let sun = shade::sun_vector(opts.sun_azimuth_deg, opts.sun_elevation_deg);
            let valid = |i: usize| dem.mask().is_valid(i);
            let visibility = shade::sun_visibility(
                &HeightField {
                    z: &surface,
                    valid: &valid,
                    width: g.width(),
                    height: g.height(),
                    dx: g.cell_size_x(),
                    dy: g.cell_size_y(),
                },
                sun,
            );
            let planes = bare_planes(dem);
            Shaded {
                altitude_range: finite_range(dem.data(), &planes).unwrap_or((0.0, 0.0)),
                surface,
                visibility,
                sun,
                bare,
            }
        });
        Ok(Self {
            dem,
            opts: opts.clone(),
            shaded,
        })
    }

    /// A frame with `snow(col, row)` metres of snow in `layer` (0 outside the inclusive box
    /// `(r0, r1, c0, c1)` of grid rows and columns, `None` when there is none).
    pub fn frame(
        &self,
        layer: SnowLayer,
        snow_box: Option<(usize, usize, usize, usize)>,
        snow: impl Fn(usize, usize) -> f32 + Sync,
    ) -> Result<RgbaImage, RenderError> {
        let g = self.dem.geometry();
        let (w, h) = (g.width(), g.height());
        let Some(sh) = &self.shaded else {
            let mut t = LayeredTerrain::from_bedrock(self.dem.clone());
            if let Some((r0, r1, c0, c1)) = snow_box {
                let l = t.layer_mut(layer);
                for r in r0..=r1.min(h - 1) {
                    for c in c0..=c1.min(w - 1) {
                        l[r * w + c] = snow(c, r);
                    }
                }
            }
            return render_preview(&t, &self.opts);
        };
        let mut img = sh.bare.clone();
        let Some((r0, r1, c0, c1)) = snow_box else {
            return Ok(img);
        };
        let (r1, c1) = (r1.min(h - 1), c1.min(w - 1));
        let e = self.opts.vertical_exaggeration as f32;
        let mut surface = sh.surface.clone();
        let bed = self.dem.data();
        for r in r0..=r1 {
            for c in c0..=c1 {
                let i = r * w + c;
                // `render_preview`'s sums: bedrock + (compacted + stable + unstable + powder).
                let z = bed[i] + snow(c, r);
                surface[i] = if e != 1.0 { z * e } else { z };
            }
        }
        let planes = bare_planes(self.dem);
        let (gr0, gr1) = (r0.saturating_sub(1), (r1 + 1).min(h - 1));
        let (gc0, gc1) = (c0.saturating_sub(1), (c1 + 1).min(w - 1));
        let rows: Vec<Vec<[u8; 4]>> = (gr0..=gr1)
            .into_par_iter()
            .map_init(Vec::new, |normals, row| {
                row_normals(&surface, &planes, row, normals);
                (gc0..=gc1)
                    .map(|col| {
                        let inside = (r0..=r1).contains(&row) && (c0..=c1).contains(&col);
                        let depth = if inside { snow(col, row) } else { 0.0 };
                        self.pixel(sh, row * w + col, normals[col], layer, depth)
                    })
                    .collect()
            })
            .collect();
        for (k, line) in rows.iter().enumerate() {
            for (j, px) in line.iter().enumerate() {
                img.put_pixel((gc0 + j) as u32, (gr0 + k) as u32, image::Rgba(*px));
            }
        }
        Ok(img)
    }

    /// The pixel of cell `i` (the Snow and Layers colourings of `render_preview`).
    fn pixel(
        &self,
        sh: &Shaded,
        i: usize,
        normal: [f32; 3],
        layer: SnowLayer,
        depth: f32,
    ) -> [u8; 4] {
        let bed = self.dem.data();
        if !self.dem.mask().is_valid(i) || !(bed[i] + depth).is_finite() {
            return [0, 0, 0, 0];
        }
        let light = shade::illumination(normal, sh.sun, sh.visibility[i]);
        let mut layers = [0.0f32; 4];
        layers[layer.index()] = depth;
        let total: f32 = layers.iter().sum();
        let (lo, hi) = sh.altitude_range;
        let ground = colour::ground_colour(crate::preview::normalise(bed[i], (lo, hi)), normal[2]);
        let tint = match self.opts.mode {
            ColourMode::Layers => colour::layer_tint(layers),
            _ => colour::SNOW_WHITE,
        };
        let [r, g, b] = colour::to_bytes(lit(
            colour::mix(ground, tint, colour::snow_cover(total)),
            light,
        ));
        [r, g, b, 255]
    }
}

/// The bare DEM as preview planes (full resolution, borrowed).
fn bare_planes(dem: &Grid) -> Planes<'_> {
    Planes {
        geometry: dem.geometry().clone(),
        mask: std::borrow::Cow::Borrowed(dem.mask()),
        bedrock: std::borrow::Cow::Borrowed(dem.data()),
        snow: None,
        map: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_terrain::GridGeometry;

    fn hill() -> Grid {
        let g = GridGeometry::square(70, 50, 10.0).unwrap();
        Grid::from_fn(g, |c, r| {
            let (x, y) = (c as f32 - 35.0, r as f32 - 25.0);
            1500.0 + 400.0 * (-(x * x + y * y) / 300.0).exp() + 3.0 * (c as f32 * 0.7).sin()
        })
    }

    fn snow(c: usize, r: usize) -> f32 {
        if (20..40).contains(&c) && (10..30).contains(&r) {
            0.5 + 0.1 * ((c + r) % 7) as f32
        } else {
            0.0
        }
    }

    fn full(dem: &Grid, opts: &PreviewOptions) -> RgbaImage {
        let mut t = LayeredTerrain::from_bedrock(dem.clone());
        let w = dem.geometry().width();
        for (i, v) in t.layer_mut(SnowLayer::Unstable).iter_mut().enumerate() {
            *v = snow(i % w, i / w);
        }
        render_preview(&t, opts).unwrap()
    }

    #[test]
    fn under_a_zenith_sun_a_frame_is_the_full_render() {
        let dem = hill();
        for mode in [ColourMode::Layers, ColourMode::Snow] {
            let opts = PreviewOptions {
                sun_elevation_deg: 90.0,
                vertical_exaggeration: 1.5,
                mode: mode.clone(),
                ..PreviewOptions::default()
            };
            let frames = ReliefFrames::new(&dem, &opts).unwrap();
            assert!(frames.shaded.is_some());
            let f = frames
                .frame(SnowLayer::Unstable, Some((10, 29, 20, 39)), snow)
                .unwrap();
            assert_eq!(f, full(&dem, &opts), "{mode:?}");
            // No snow: the bare relief.
            let bare = frames.frame(SnowLayer::Unstable, None, |_, _| 0.0).unwrap();
            let none = render_preview(&LayeredTerrain::from_bedrock(dem.clone()), &opts).unwrap();
            assert_eq!(bare, none);
        }
    }

    #[test]
    fn under_a_low_sun_only_shadows_cast_by_the_snow_differ() {
        let dem = hill();
        let opts = PreviewOptions {
            mode: ColourMode::Layers,
            ..PreviewOptions::default()
        };
        let frames = ReliefFrames::new(&dem, &opts).unwrap();
        let f = frames
            .frame(SnowLayer::Unstable, Some((10, 29, 20, 39)), snow)
            .unwrap();
        let reference = full(&dem, &opts);
        let differ = f
            .pixels()
            .zip(reference.pixels())
            .filter(|(a, b)| a != b)
            .count();
        assert!(differ < f.pixels().len() / 50, "{differ} pixels differ");
        // A reduced preview falls back to the full render.
        let small = PreviewOptions {
            max_size: Some(20),
            ..opts
        };
        let frames = ReliefFrames::new(&dem, &small).unwrap();
        assert!(frames.shaded.is_none());
        let f = frames
            .frame(SnowLayer::Unstable, Some((0, 49, 0, 69)), snow)
            .unwrap();
        assert_eq!(f, full(&dem, &small));
    }
}
