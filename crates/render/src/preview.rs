//! CPU previews: a top-down, north-up image of the terrain, lit by a configurable sun.
//!
//! The snow surface (bedrock + total depth, times the vertical exaggeration) is lit with a
//! Lambert sun term, cast shadows and a sky term (see [`crate::shade`]); each pixel's colour
//! before lighting comes from the [`ColourMode`] (see [`crate::colour`]). Row 0 of the image is
//! the northern edge of the grid; nodata cells (and cells with a non-finite altitude) are
//! transparent. Big grids are box-averaged down to `max_size` first ([`crate::planes`]), and
//! rows are drawn in parallel.

use crate::RenderError;
use crate::colour::{self, Rgb};
use crate::planes::{Planes, Source, check_length};
use crate::shade::{self, HeightField};
use image::RgbaImage;
use rayon::prelude::*;
use snowscape_terrain::{Grid, LayeredTerrain, operators, surface};

/// How a preview is coloured before lighting.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum ColourMode {
    /// White snow blended in by depth over ground tinted by altitude and slope.
    #[default]
    Snow,
    /// Snow tinted by its layer composition (compacted blue-grey, stable white, unstable
    /// orange-red, powder light cyan).
    Layers,
    /// Cordonnier et al. 2018, Fig. 11: unstable and powdery snow purple on top of compacted
    /// and stable snow in blue; no snow black.
    Stability,
    /// One named map of `LayeredTerrain::maps` through a viridis ramp scaled to the map's own
    /// range over valid cells, modulated by the hillshade.
    Map(String),
}

/// Options of [`render_preview`] and [`render_dem`].
#[derive(Debug, Clone, PartialEq)]
pub struct PreviewOptions {
    /// Sun azimuth, degrees clockwise from north (any finite value; taken modulo 360).
    pub sun_azimuth_deg: f64,
    /// Sun elevation above the horizon, degrees, in (0, 90].
    pub sun_elevation_deg: f64,
    /// Colouring.
    pub mode: ColourMode,
    /// Factor applied to altitudes for shading (> 0; 1 = true relief).
    pub vertical_exaggeration: f64,
    /// Longest image side, pixels; bigger grids are box-averaged down. `None` = one pixel per
    /// cell.
    pub max_size: Option<usize>,
}

impl Default for PreviewOptions {
    fn default() -> Self {
        Self {
            sun_azimuth_deg: 315.0,
            sun_elevation_deg: 35.0,
            mode: ColourMode::Snow,
            vertical_exaggeration: 1.0,
            max_size: Some(2048),
        }
    }
}

impl PreviewOptions {
    fn check(&self) -> Result<(), RenderError> {
        let bad = |name, value, expected| RenderError::InvalidOption {
            name,
            value,
            expected,
        };
        if !self.sun_azimuth_deg.is_finite() {
            return Err(bad(
                "sun_azimuth_deg",
                self.sun_azimuth_deg,
                "a finite angle",
            ));
        }
        if !(self.sun_elevation_deg > 0.0 && self.sun_elevation_deg <= 90.0) {
            return Err(bad(
                "sun_elevation_deg",
                self.sun_elevation_deg,
                "an elevation above the horizon, in (0, 90] degrees",
            ));
        }
        if !(self.vertical_exaggeration.is_finite() && self.vertical_exaggeration > 0.0) {
            return Err(bad(
                "vertical_exaggeration",
                self.vertical_exaggeration,
                "a finite positive factor",
            ));
        }
        Ok(())
    }
}

/// Renders a layered terrain as a north-up RGBA preview.
pub fn render_preview(
    terrain: &LayeredTerrain,
    opts: &PreviewOptions,
) -> Result<RgbaImage, RenderError> {
    opts.check()?;
    let g = terrain.geometry();
    check_length("bedrock", &terrain.bedrock, g)?;
    for layer in snowscape_terrain::SnowLayer::ALL {
        check_length(
            &format!("{} snow layer", layer.name()),
            terrain.layer(layer),
            g,
        )?;
    }
    let map = match &opts.mode {
        ColourMode::Map(name) => Some(named_map(terrain, name)?),
        _ => None,
    };
    let source = Source {
        geometry: g,
        mask: terrain.mask(),
        bedrock: &terrain.bedrock,
        snow: Some(std::array::from_fn(|k| terrain.snow[k].as_slice())),
        map,
    };
    draw(&Planes::build(source, opts.max_size)?, opts)
}

/// Renders a plain DEM: hillshade and hypsometric tint, nodata transparent. `opts.mode` is
/// ignored (there is no snow and no map).
pub fn render_dem(dem: &Grid, opts: &PreviewOptions) -> Result<RgbaImage, RenderError> {
    opts.check()?;
    let source = Source {
        geometry: dem.geometry(),
        mask: dem.mask(),
        bedrock: dem.data(),
        snow: None,
        map: None,
    };
    let opts = PreviewOptions {
        mode: ColourMode::Snow,
        ..opts.clone()
    };
    draw(&Planes::build(source, opts.max_size)?, &opts)
}

/// The Fig. 11 stability colour of cell `i` (unlit): black without snow, blue for compacted
/// and stable snow, purple where unstable or powdery snow lies on top. Black for an index
/// outside the terrain or a nodata cell.
pub fn stability_colour(terrain: &LayeredTerrain, i: usize) -> [u8; 3] {
    let inside = i < terrain.geometry().len() && terrain.snow.iter().all(|l| i < l.len());
    if !inside || !terrain.mask().is_valid(i) {
        return colour::to_bytes(colour::STABILITY_BLACK);
    }
    colour::to_bytes(colour::stability_rgb(std::array::from_fn(|k| {
        terrain.snow[k][i]
    })))
}

/// Looks up a named map, checking its length.
fn named_map<'a>(terrain: &'a LayeredTerrain, name: &str) -> Result<&'a [f32], RenderError> {
    let values = terrain
        .maps
        .get(name)
        .ok_or_else(|| RenderError::MissingMap {
            name: name.to_string(),
            available: terrain.maps.keys().cloned().collect(),
        })?;
    check_length(&format!("map {name:?}"), values, terrain.geometry())?;
    Ok(values)
}

/// Minimum and maximum of the finite values of valid cells.
pub(crate) fn finite_range(values: &[f32], planes: &Planes) -> Option<(f32, f32)> {
    let w = planes.geometry.width();
    values
        .par_chunks(w)
        .enumerate()
        .filter_map(|(row, line)| {
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for (col, &v) in line.iter().enumerate() {
                if v.is_finite() && planes.mask.is_valid(row * w + col) {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
            (lo <= hi).then_some((lo, hi))
        })
        .reduce_with(|a, b| (a.0.min(b.0), a.1.max(b.1)))
}

/// Normalises `v` into [0, 1] over `range` (0.5 for a constant range).
#[inline]
pub(crate) fn normalise(v: f32, (lo, hi): (f32, f32)) -> f32 {
    if hi > lo { (v - lo) / (hi - lo) } else { 0.5 }
}

/// Everything the per-pixel colouring needs, precomputed once per image.
struct Scene<'p, 'a> {
    planes: &'p Planes<'a>,
    mode: &'p ColourMode,
    surface: Vec<f32>,
    visibility: Vec<f32>,
    sun: [f32; 3],
    altitude_range: (f32, f32),
    map_range: (f32, f32),
}

fn draw(planes: &Planes, opts: &PreviewOptions) -> Result<RgbaImage, RenderError> {
    let g = &planes.geometry;
    let (w, h) = (g.width(), g.height());
    let (Ok(w32), Ok(h32)) = (u32::try_from(w), u32::try_from(h)) else {
        return Err(RenderError::ImageTooLarge {
            width: w,
            height: h,
            limit: "image sides are limited to 2^32 - 1 pixels",
        });
    };
    let surface = exaggerated_surface(planes, opts.vertical_exaggeration as f32);
    let sun = shade::sun_vector(opts.sun_azimuth_deg, opts.sun_elevation_deg);
    let valid = |i: usize| planes.mask.is_valid(i);
    let visibility = shade::sun_visibility(
        &HeightField {
            z: &surface,
            valid: &valid,
            width: w,
            height: h,
            dx: g.cell_size_x(),
            dy: g.cell_size_y(),
        },
        sun,
    );
    let scene = Scene {
        planes,
        mode: &opts.mode,
        altitude_range: finite_range(&planes.bedrock, planes).unwrap_or((0.0, 0.0)),
        map_range: planes
            .map
            .as_ref()
            .and_then(|m| finite_range(m, planes))
            .unwrap_or((0.0, 0.0)),
        surface,
        visibility,
        sun,
    };
    let mut pixels = vec![0u8; w * h * 4];
    pixels
        .par_chunks_mut(w * 4)
        .enumerate()
        .for_each_init(Vec::new, |normals, (row, line)| {
            row_normals(&scene.surface, planes, row, normals);
            for ((col, px), &normal) in line.chunks_exact_mut(4).enumerate().zip(normals.iter()) {
                px.copy_from_slice(&scene.pixel(row * w + col, normal));
            }
        });
    RgbaImage::from_raw(w32, h32, pixels).ok_or(RenderError::ImageTooLarge {
        width: w,
        height: h,
        limit: "the pixel buffer does not match the image size",
    })
}

/// `(bedrock + total snow depth) · exaggeration` per cell.
fn exaggerated_surface(planes: &Planes, exaggeration: f32) -> Vec<f32> {
    let mut z: Vec<f32> = planes.bedrock.to_vec();
    let w = planes.geometry.width();
    z.par_chunks_mut(w).enumerate().for_each(|(row, line)| {
        let cells = row * w..(row + 1) * w;
        if let Some([c, s, u, p]) = &planes.snow {
            let layers = c[cells.clone()].iter().zip(&s[cells.clone()]);
            let layers = layers.zip(u[cells.clone()].iter().zip(&p[cells]));
            for (v, ((c, s), (u, p))) in line.iter_mut().zip(layers) {
                *v += c + s + u + p;
            }
        }
        if exaggeration != 1.0 {
            line.iter_mut().for_each(|v| *v *= exaggeration);
        }
    });
    z
}

impl Scene<'_, '_> {
    fn layers(&self, i: usize) -> [f32; 4] {
        match &self.planes.snow {
            Some(s) => std::array::from_fn(|k| s[k][i]),
            None => [0.0; 4],
        }
    }

    /// The RGBA pixel of cell `i` whose surface has unit `normal`.
    fn pixel(&self, i: usize, normal: [f32; 3]) -> [u8; 4] {
        if !self.planes.mask.is_valid(i) || !self.surface[i].is_finite() {
            return [0, 0, 0, 0];
        }
        let light = shade::illumination(normal, self.sun, self.visibility[i]);
        let rgb = match self.mode {
            ColourMode::Snow | ColourMode::Layers => {
                let layers = self.layers(i);
                let depth: f32 = layers.iter().sum();
                let ground = colour::ground_colour(
                    normalise(self.planes.bedrock[i], self.altitude_range),
                    normal[2],
                );
                let snow = match self.mode {
                    ColourMode::Layers => colour::layer_tint(layers),
                    _ => colour::SNOW_WHITE,
                };
                lit(colour::mix(ground, snow, colour::snow_cover(depth)), light)
            }
            ColourMode::Stability => softly_lit(colour::stability_rgb(self.layers(i)), light),
            ColourMode::Map(_) => {
                let v = self.planes.map.as_ref().map_or(f32::NAN, |m| m[i]);
                if !v.is_finite() {
                    return [0, 0, 0, 0];
                }
                softly_lit(colour::viridis(normalise(v, self.map_range)), light)
            }
        };
        let [r, g, b] = colour::to_bytes(rgb);
        [r, g, b, 255]
    }
}

/// Unit upward normals (x east, y north, z up) of one row of the surface. Central differences
/// as in `snowscape_terrain::surface::gradient` (which handles rows next to nodata); rows of an
/// all-valid grid take a fast path with the same stencil (`snowscape_terrain::operators`).
pub(crate) fn row_normals(z: &[f32], planes: &Planes, row: usize, out: &mut Vec<[f32; 3]>) {
    let g = &planes.geometry;
    let (w, h) = (g.width(), g.height());
    out.clear();
    let normal = operators::upward_normal::<f32>;
    if planes.mask.has_nodata() || w < 2 {
        out.extend((0..w).map(|col| {
            let (gx, gy) = surface::gradient(z, g, &planes.mask, col, row);
            normal(gx, gy)
        }));
        return;
    }
    let (dx, dy) = (g.cell_size_x() as f32, g.cell_size_y() as f32);
    let line = &z[row * w..(row + 1) * w];
    let north = &z[row.saturating_sub(1) * w..][..w];
    let south = &z[(row + 1).min(h - 1) * w..][..w];
    let rows_apart = ((row + 1).min(h - 1) - row.saturating_sub(1)) as f32;
    let inv_dy = if rows_apart > 0.0 {
        1.0 / (rows_apart * dy)
    } else {
        0.0
    };
    for col in 0..w {
        let (west, east) = (col.saturating_sub(1), (col + 1).min(w - 1));
        let gx = operators::centred_difference(
            (west < col).then(|| line[west]),
            line[col],
            (east > col).then(|| line[east]),
            dx,
        );
        let gy = (north[col] - south[col]) * inv_dy;
        out.push(normal(gx, gy));
    }
}

/// Albedo times light, per channel.
#[inline]
pub(crate) fn lit(albedo: Rgb, light: Rgb) -> Rgb {
    [
        albedo[0] * light[0],
        albedo[1] * light[1],
        albedo[2] * light[2],
    ]
}

/// Albedo modulated by the light's brightness between 45 % and 100 %, so that data colours
/// (stability classes, map values) stay recognisable in the shade.
#[inline]
fn softly_lit(albedo: Rgb, light: Rgb) -> Rgb {
    let brightness = (0.2126 * light[0] + 0.7152 * light[1] + 0.0722 * light[2]).min(1.0);
    let k = 0.45 + 0.55 * brightness;
    [albedo[0] * k, albedo[1] * k, albedo[2] * k]
}
