//! CPU preview of a scene and its snow: a z-buffer rasteriser with an orthographic camera
//! fitted to the bounding box, flat Lambert shading (scene grey, snow white) under one sun,
//! over a sky-blue background. No GPU needed, so `snowscape cover` can always show a result.
//!
//! Camera: looking at the centre of the bounds from azimuth `view_azimuth_deg` (clockwise from
//! north, +y) and `view_elevation_deg` above the horizon; the whole box fits in the image with a
//! 5 % margin. Triangles are two-sided (shaded with the normal facing the camera); snow is drawn
//! after the scene and wins depth ties, so snow lying on a surface shows.

use crate::MeshError;
use crate::scene::{Bounds, Scene};
use crate::write::SnowMesh;
use glam::Vec3;
use image::{Rgb, RgbImage};
use std::path::Path;

/// Background colour of a preview.
pub const SKY: [u8; 3] = [150, 180, 215];
/// Albedo of scene surfaces.
pub const SCENE_GREY: f32 = 0.55;
/// Albedo of snow.
pub const SNOW_WHITE: f32 = 0.97;

/// How a preview is drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct PreviewOptions {
    /// Image size in pixels (each 1..=16384).
    pub width: u32,
    pub height: u32,
    /// Direction the camera looks from, degrees clockwise from north (+y).
    pub view_azimuth_deg: f32,
    /// Camera height above the horizon, degrees (0..=90).
    pub view_elevation_deg: f32,
    /// Direction the sun shines from, degrees clockwise from north.
    pub sun_azimuth_deg: f32,
    /// Sun elevation, degrees.
    pub sun_elevation_deg: f32,
}

impl Default for PreviewOptions {
    /// 800 x 600, seen from the south-west 30 degrees up, sun from the south-east 45 degrees up.
    fn default() -> Self {
        Self {
            width: 800,
            height: 600,
            view_azimuth_deg: 210.0,
            view_elevation_deg: 30.0,
            sun_azimuth_deg: 150.0,
            sun_elevation_deg: 45.0,
        }
    }
}

/// Unit vector towards azimuth / elevation (degrees; azimuth clockwise from +y).
fn direction(azimuth_deg: f32, elevation_deg: f32) -> Vec3 {
    let (a, e) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
    Vec3::new(a.sin() * e.cos(), a.cos() * e.cos(), e.sin())
}

/// Renders `scene` with `snow` on it.
pub fn render_preview(
    scene: &Scene,
    snow: &[SnowMesh],
    opts: &PreviewOptions,
) -> Result<RgbImage, MeshError> {
    let bad =
        |name: &'static str, value: String, expected: &'static str| MeshError::InvalidOption {
            name,
            value,
            expected,
        };
    if !(1..=16384).contains(&opts.width) || !(1..=16384).contains(&opts.height) {
        return Err(bad(
            "preview size",
            format!("{}x{}", opts.width, opts.height),
            "1..=16384 pixels each way",
        ));
    }
    if !(0.0..=90.0).contains(&opts.view_elevation_deg) || !opts.view_azimuth_deg.is_finite() {
        return Err(bad(
            "view direction",
            format!("{} / {}", opts.view_azimuth_deg, opts.view_elevation_deg),
            "a finite azimuth and an elevation in 0..=90 degrees",
        ));
    }
    let snow_bounds = snow.iter().filter_map(|m| Bounds::of_points(&m.positions));
    let bounds = scene
        .bounds()
        .into_iter()
        .chain(snow_bounds)
        .reduce(Bounds::union)
        .ok_or_else(|| {
            bad(
                "preview scene",
                "empty".into(),
                "a scene or snow with triangles",
            )
        })?;
    let camera = Camera::fit(&bounds, opts);
    let sun = direction(opts.sun_azimuth_deg, opts.sun_elevation_deg);
    let mut raster = Raster::new(opts.width as usize, opts.height as usize);
    for object in &scene.objects {
        for t in &object.triangles {
            let corners = t.map(|i| Vec3::from(object.positions[i as usize]));
            raster.triangle(&camera, corners, sun, SCENE_GREY, false);
        }
    }
    for mesh in snow {
        for t in &mesh.triangles {
            let Some(corners) = t
                .iter()
                .map(|&i| mesh.positions.get(i as usize).map(|&p| Vec3::from(p)))
                .collect::<Option<Vec<_>>>()
            else {
                return Err(MeshError::InvalidMesh {
                    mesh: mesh.name.clone(),
                    reason: format!(
                        "triangle {t:?} refers past the {} vertices",
                        mesh.positions.len()
                    ),
                });
            };
            raster.triangle(
                &camera,
                [corners[0], corners[1], corners[2]],
                sun,
                SNOW_WHITE,
                true,
            );
        }
    }
    Ok(raster.image)
}

/// Renders and writes a PNG preview atomically.
pub fn write_preview(
    path: &Path,
    scene: &Scene,
    snow: &[SnowMesh],
    opts: &PreviewOptions,
) -> Result<(), MeshError> {
    let img = render_preview(scene, snow, opts)?;
    let rgba = image::DynamicImage::ImageRgb8(img).into_rgba8();
    snowscape_io::write_bytes_atomic(path, &crate::write::png_bytes(&rgba, path)?)?;
    Ok(())
}

/// An orthographic camera: pixel = (p·right - x0)·scale, (y0 - p·up)·scale; depth = p·back.
struct Camera {
    right: Vec3,
    up: Vec3,
    back: Vec3,
    x0: f32,
    y0: f32,
    scale: f32,
}

impl Camera {
    fn fit(b: &Bounds, opts: &PreviewOptions) -> Self {
        let back = direction(opts.view_azimuth_deg, opts.view_elevation_deg);
        // Horizontal and perpendicular to the view azimuth (also when looking straight down).
        let a = opts.view_azimuth_deg.to_radians();
        let right = Vec3::new(-a.cos(), a.sin(), 0.0);
        let up = back.cross(right);
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for i in 0..8 {
            let p = Vec3::new(
                if i & 1 == 0 { b.min[0] } else { b.max[0] },
                if i & 2 == 0 { b.min[1] } else { b.max[1] },
                if i & 4 == 0 { b.min[2] } else { b.max[2] },
            );
            let q = Vec3::new(p.dot(right), p.dot(up), 0.0);
            lo = lo.min(q);
            hi = hi.max(q);
        }
        let (w, h) = (opts.width as f32, opts.height as f32);
        let span = (hi - lo).max(Vec3::splat(1e-6));
        let scale = 0.9 * (w / span.x).min(h / span.y);
        let centre = 0.5 * (lo + hi);
        Self {
            right,
            up,
            back,
            x0: centre.x - 0.5 * w / scale,
            y0: centre.y + 0.5 * h / scale,
            scale,
        }
    }

    /// Pixel x, pixel y, depth (larger is nearer the camera).
    fn project(&self, p: Vec3) -> Vec3 {
        Vec3::new(
            (p.dot(self.right) - self.x0) * self.scale,
            (self.y0 - p.dot(self.up)) * self.scale,
            p.dot(self.back),
        )
    }
}

struct Raster {
    image: RgbImage,
    depth: Vec<f32>,
    width: usize,
    height: usize,
}

impl Raster {
    fn new(width: usize, height: usize) -> Self {
        Self {
            image: RgbImage::from_pixel(width as u32, height as u32, Rgb(SKY)),
            depth: vec![f32::NEG_INFINITY; width * height],
            width,
            height,
        }
    }

    /// Draws one flat-shaded triangle; `wins_ties` lets it cover equal depths.
    fn triangle(&mut self, cam: &Camera, p: [Vec3; 3], sun: Vec3, albedo: f32, wins_ties: bool) {
        let mut n = (p[1] - p[0]).cross(p[2] - p[0]);
        let l2 = n.length_squared();
        if l2.is_nan() || l2 <= 0.0 {
            return;
        }
        if n.dot(cam.back) < 0.0 {
            n = -n;
        }
        let n = n.normalize();
        let shade = albedo * (0.3 + 0.7 * n.dot(sun).max(0.0));
        let grey = (255.0 * shade.clamp(0.0, 1.0)) as u8;
        let [a, b, c] = p.map(|q| cam.project(q));
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if area.abs() < 1e-12 {
            return;
        }
        let x_lo = a.x.min(b.x).min(c.x).floor().max(0.0) as usize;
        let y_lo = a.y.min(b.y).min(c.y).floor().max(0.0) as usize;
        let x_hi = (a.x.max(b.x).max(c.x).ceil().max(0.0) as usize).min(self.width);
        let y_hi = (a.y.max(b.y).max(c.y).ceil().max(0.0) as usize).min(self.height);
        // Depth bias so snow lying exactly on a surface wins.
        let bias = if wins_ties { 1e-4 / cam.scale } else { 0.0 };
        for y in y_lo..y_hi {
            let py = y as f32 + 0.5;
            for x in x_lo..x_hi {
                let px = x as f32 + 0.5;
                let w0 = ((b.x - px) * (c.y - py) - (b.y - py) * (c.x - px)) / area;
                let w1 = ((c.x - px) * (a.y - py) - (c.y - py) * (a.x - px)) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let z = w0 * a.z + w1 * b.z + w2 * c.z + bias;
                let i = y * self.width + x;
                if z > self.depth[i] {
                    self.depth[i] = z;
                    self.image.put_pixel(x as u32, y as u32, Rgb([grey; 3]));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SceneObject;

    fn quad(z: f32) -> SceneObject {
        SceneObject {
            name: "q".into(),
            positions: vec![[0., 0., z], [1., 0., z], [1., 1., z], [0., 1., z]],
            normals: None,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn top_view_of_a_square_fills_the_fitted_frame_and_snow_covers_it() {
        let scene = Scene {
            objects: vec![quad(0.0)],
            ..Default::default()
        };
        let opts = PreviewOptions {
            width: 100,
            height: 100,
            view_elevation_deg: 90.0,
            view_azimuth_deg: 180.0,
            ..Default::default()
        };
        let img = render_preview(&scene, &[], &opts).unwrap();
        let lit = img.pixels().filter(|p| p.0 != SKY).count();
        // The square fills 90 % of each side: 81 % of the pixels.
        assert!((lit as f32 / 10_000.0 - 0.81).abs() < 0.03, "{lit}");
        let grey = img.get_pixel(50, 50).0[0];
        let snow = SnowMesh::from_object(&quad(0.0));
        let img = render_preview(&scene, &[snow], &opts).unwrap();
        assert!(
            img.get_pixel(50, 50).0[0] > grey,
            "snow is brighter than the grey scene"
        );
        assert!(render_preview(&Scene::default(), &[], &opts).is_err());
        let bad = PreviewOptions { width: 0, ..opts };
        assert!(render_preview(&scene, &[], &bad).is_err());
    }
}
