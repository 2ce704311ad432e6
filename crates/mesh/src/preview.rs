//! CPU preview of a scene and its snow: a z-buffer rasteriser with an orthographic camera
//! fitted to the bounding box, deferred shading under a sun with a shadow map and a blue sky
//! light, on a ground plane, over a sky-blue background. No GPU needed, so `snowscape cover`
//! can always show a result.
//!
//! Materials: the scene in a neutral rock tone, the snow white; the sun light is warm and the
//! sky light blue, so snow in the sun is white and in shadow blue-tinted, and the object stays
//! darker than the snow on it. The ground plane (1.6 times the scene's horizontal size, just
//! below its lowest point) takes the shadows, so an object shows its contact shadow.
//!
//! Camera: looking at the centre of the bounds from azimuth `view_azimuth_deg` (clockwise from
//! north, +y) and `view_elevation_deg` above the horizon; the whole scene (not the ground plane)
//! fits in the image with a 5 % margin. Triangles are two-sided (shaded with the normal facing
//! the camera); snow is drawn after the scene and wins depth ties, so snow lying on a surface
//! shows. Shadows: every triangle is drawn into a depth map seen from the sun (orthographic,
//! twice the image's resolution, at most 4096²), and a pixel is lit by the sun in the share of
//! the 3 × 3 map texels around it that it is not behind (soft edges).

use crate::MeshError;
use crate::scene::{Bounds, Scene};
use crate::write::SnowObject;
use glam::Vec3;
use image::{Rgb, RgbImage};
use std::path::Path;

/// Background colour of a preview.
pub const SKY: [u8; 3] = [150, 180, 215];
/// Albedo of scene surfaces: a neutral rock tone (linear RGB).
pub const SCENE_ROCK: [f32; 3] = [0.42, 0.39, 0.36];
/// Albedo of snow (linear RGB).
pub const SNOW_WHITE: [f32; 3] = [0.93, 0.94, 0.96];
/// Albedo of the ground plane (linear RGB).
pub const GROUND: [f32; 3] = [0.36, 0.38, 0.33];
/// Sun and sky light colours and strengths (linear RGB).
const SUN_LIGHT: [f32; 3] = [1.0, 0.95, 0.88];
const SKY_LIGHT: [f32; 3] = [0.42, 0.52, 0.72];

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
    /// Draw a ground plane under the scene (it takes the contact shadow).
    pub ground: bool,
}

impl Default for PreviewOptions {
    /// 800 x 600, seen from the south-west 30 degrees up, sun from the south-east 45 degrees
    /// up, on a ground plane.
    fn default() -> Self {
        Self {
            width: 800,
            height: 600,
            view_azimuth_deg: 210.0,
            view_elevation_deg: 30.0,
            sun_azimuth_deg: 150.0,
            sun_elevation_deg: 45.0,
            ground: true,
        }
    }
}

/// Unit vector towards azimuth / elevation (degrees; azimuth clockwise from +y).
fn direction(azimuth_deg: f32, elevation_deg: f32) -> Vec3 {
    let (a, e) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
    Vec3::new(a.sin() * e.cos(), a.cos() * e.cos(), e.sin())
}

/// What a pixel shows.
#[derive(Clone, Copy, PartialEq)]
enum Material {
    Scene,
    Snow,
    Ground,
}

impl Material {
    fn albedo(self) -> [f32; 3] {
        match self {
            Material::Scene => SCENE_ROCK,
            Material::Snow => SNOW_WHITE,
            Material::Ground => GROUND,
        }
    }
}

/// The triangles to draw: corners and material.
fn triangles<'a>(
    scene: &'a Scene,
    snow: &'a [SnowObject],
    ground: &'a [[Vec3; 3]],
) -> Result<Vec<([Vec3; 3], Material)>, MeshError> {
    let mut out = Vec::new();
    for object in &scene.objects {
        for t in &object.triangles {
            out.push((
                t.map(|i| Vec3::from(object.positions[i as usize])),
                Material::Scene,
            ));
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
            out.push(([corners[0], corners[1], corners[2]], Material::Snow));
        }
    }
    for t in ground {
        out.push((*t, Material::Ground));
    }
    Ok(out)
}

/// Renders `scene` with `snow` on it.
pub fn render_preview(
    scene: &Scene,
    snow: &[SnowObject],
    opts: &PreviewOptions,
) -> Result<RgbImage, MeshError> {
    render(scene, snow, opts).map(|(image, _)| image)
}

/// `frames` previews of `scene` and `snow` seen from azimuths evenly spaced around the scene,
/// starting at `opts.view_azimuth_deg` (a turntable; the sun stays). The camera is fitted to
/// the scene's horizontal bounding circle, so the scene keeps its size from frame to frame.
pub fn render_turntable(
    scene: &Scene,
    snow: &[SnowObject],
    opts: &PreviewOptions,
    frames: usize,
) -> Result<Vec<RgbImage>, MeshError> {
    if !(2..=720).contains(&frames) {
        return Err(MeshError::InvalidOption {
            name: "turntable frames",
            value: frames.to_string(),
            expected: "2..=720 frames",
        });
    }
    let snow_bounds = snow.iter().filter_map(|m| Bounds::of_points(&m.positions));
    let Some(b) = scene
        .bounds()
        .into_iter()
        .chain(snow_bounds)
        .reduce(Bounds::union)
    else {
        return render_preview(scene, snow, opts).map(|i| vec![i]);
    };
    // The box around the bounding circle of the horizontal extent: any azimuth sees it alike.
    let (c, r) = (
        [0.5 * (b.min[0] + b.max[0]), 0.5 * (b.min[1] + b.max[1])],
        0.5 * (b.max[0] - b.min[0]).hypot(b.max[1] - b.min[1]),
    );
    let circle = Bounds {
        min: [c[0] - r, c[1] - r, b.min[2]],
        max: [c[0] + r, c[1] + r, b.max[2]],
    };
    (0..frames)
        .map(|k| {
            let o = PreviewOptions {
                view_azimuth_deg: opts.view_azimuth_deg + 360.0 * k as f32 / frames as f32,
                ..opts.clone()
            };
            render_framed(scene, snow, &o, Some(&circle)).map(|(img, _)| img)
        })
        .collect()
}

/// [`render_preview`], and what each pixel shows (row-major; `None`: sky).
fn render(
    scene: &Scene,
    snow: &[SnowObject],
    opts: &PreviewOptions,
) -> Result<(RgbImage, Vec<Option<Material>>), MeshError> {
    render_framed(scene, snow, opts, None)
}

/// [`render`] with the camera fitted to `frame` instead of the scene's bounds.
fn render_framed(
    scene: &Scene,
    snow: &[SnowObject],
    opts: &PreviewOptions,
    frame: Option<&Bounds>,
) -> Result<(RgbImage, Vec<Option<Material>>), MeshError> {
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
    // The ground plane: 1.6 times the horizontal size, a hair below the lowest point.
    let ground: Vec<[Vec3; 3]> = if opts.ground {
        let (lo, hi) = (Vec3::from(bounds.min), Vec3::from(bounds.max));
        let c = 0.5 * (lo + hi);
        let r = 0.8 * (hi.x - lo.x).max(hi.y - lo.y).max(1e-3);
        let z = lo.z - 1e-3 * (hi - lo).length().max(1e-3);
        let q =
            [(-r, -r), (r, -r), (r, r), (-r, r)].map(|(dx, dy)| Vec3::new(c.x + dx, c.y + dy, z));
        vec![[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    } else {
        Vec::new()
    };
    let tris = triangles(scene, snow, &ground)?;
    let camera = Camera::fit(
        frame.unwrap_or(&bounds),
        opts.view_azimuth_deg,
        opts.view_elevation_deg,
        opts.width,
        opts.height,
    );
    let sun = direction(opts.sun_azimuth_deg, opts.sun_elevation_deg);
    // The shadow map: the scene and its ground seen from the sun.
    let corners: Vec<[f32; 3]> = ground.iter().flatten().map(|p| p.to_array()).collect();
    let all = Bounds::of_points(&corners).map_or(bounds, |g| g.union(bounds));
    let side = (2 * opts.width.max(opts.height)).min(4096);
    let sun_cam = Camera::fit(
        &all,
        opts.sun_azimuth_deg,
        opts.sun_elevation_deg.clamp(1.0, 90.0),
        side,
        side,
    );
    let mut shadow = Raster::new(side as usize, side as usize);
    for (t, m) in &tris {
        shadow.triangle(&sun_cam, *t, *m, false);
    }
    let mut raster = Raster::new(opts.width as usize, opts.height as usize);
    for (t, m) in &tris {
        raster.triangle(&camera, *t, *m, *m == Material::Snow);
    }
    let texel = 1.0 / sun_cam.scale;
    let mut image = RgbImage::from_pixel(opts.width, opts.height, Rgb(SKY));
    for (i, px) in raster.pixels.iter().enumerate() {
        let Some(px) = px else { continue };
        let mut n = px.normal;
        if n.dot(camera.back) < 0.0 {
            n = -n;
        }
        // The share of the 3 x 3 shadow-map texels around the point that see it from the sun.
        let q = sun_cam.project(px.position);
        let (sx, sy) = (q.x.floor() as i64, q.y.floor() as i64);
        let ndl = n.dot(sun).max(0.0);
        // Slope-scaled bias: surfaces the sun grazes need more (no acne).
        let bias = texel * (1.5 + 6.0 * (1.0 - ndl));
        let mut lit = 0.0f32;
        for dy in -1..=1 {
            for dx in -1..=1 {
                if q.z + bias >= shadow.depth_at(sx + dx, sy + dy) {
                    lit += 1.0 / 9.0;
                }
            }
        }
        let direct = ndl * lit * sun.z.signum().max(0.0);
        let sky = 0.55 + 0.45 * n.z.max(0.0);
        let albedo = px.material.albedo();
        let rgb: [u8; 3] = std::array::from_fn(|k| {
            let linear = albedo[k] * (0.85 * SUN_LIGHT[k] * direct + SKY_LIGHT[k] * sky);
            (255.0 * linear.clamp(0.0, 1.0).powf(1.0 / 2.2)).round() as u8
        });
        image.put_pixel(
            (i % raster.width) as u32,
            (i / raster.width) as u32,
            Rgb(rgb),
        );
    }
    let materials = raster
        .pixels
        .iter()
        .map(|p| p.map(|f| f.material))
        .collect();
    Ok((image, materials))
}

/// Renders and writes a PNG preview atomically.
pub fn write_preview(
    path: &Path,
    scene: &Scene,
    snow: &[SnowObject],
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
    /// Looking from azimuth / elevation (degrees) at the box `b`, which fills 90 % of the
    /// limiting side of a `w` × `h` image.
    fn fit(b: &Bounds, azimuth_deg: f32, elevation_deg: f32, w: u32, h: u32) -> Self {
        let back = direction(azimuth_deg, elevation_deg);
        // Horizontal and perpendicular to the view azimuth (also when looking straight down).
        let a = azimuth_deg.to_radians();
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
        let (w, h) = (w as f32, h as f32);
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

/// What the nearest triangle leaves at a pixel.
#[derive(Clone, Copy)]
struct Fragment {
    position: Vec3,
    normal: Vec3,
    material: Material,
}

struct Raster {
    pixels: Vec<Option<Fragment>>,
    depth: Vec<f32>,
    width: usize,
    height: usize,
}

impl Raster {
    fn new(width: usize, height: usize) -> Self {
        Self {
            pixels: vec![None; width * height],
            depth: vec![f32::NEG_INFINITY; width * height],
            width,
            height,
        }
    }

    /// Depth at a pixel (-inf outside or where nothing was drawn).
    fn depth_at(&self, x: i64, y: i64) -> f32 {
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
            return f32::NEG_INFINITY;
        }
        self.depth[y as usize * self.width + x as usize]
    }

    /// Draws one triangle; `wins_ties` lets it cover equal depths.
    fn triangle(&mut self, cam: &Camera, p: [Vec3; 3], material: Material, wins_ties: bool) {
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        let l2 = n.length_squared();
        if l2.is_nan() || l2 <= 0.0 {
            return;
        }
        let normal = n.normalize();
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
                    self.pixels[i] = Some(Fragment {
                        position: w0 * p[0] + w1 * p[1] + w2 * p[2],
                        normal,
                        material,
                    });
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
            frame: Default::default(),
            name: "q".into(),
            positions: vec![[0., 0., z], [1., 0., z], [1., 1., z], [0., 1., z]],
            normals: None,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            uvs: None,
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
            ground: false,
            ..Default::default()
        };
        let img = render_preview(&scene, &[], &opts).unwrap();
        let lit = img.pixels().filter(|p| p.0 != SKY).count();
        // The square fills 90 % of each side: 81 % of the pixels.
        assert!((lit as f32 / 10_000.0 - 0.81).abs() < 0.03, "{lit}");
        let grey = img.get_pixel(50, 50).0[0];
        let snow = SnowObject::from_object(&quad(0.0));
        let img = render_preview(&scene, &[snow], &opts).unwrap();
        assert!(
            img.get_pixel(50, 50).0[0] > grey,
            "snow is brighter than the grey scene"
        );
        assert!(render_preview(&Scene::default(), &[], &opts).is_err());
        let bad = PreviewOptions { width: 0, ..opts };
        assert!(render_preview(&scene, &[], &bad).is_err());
    }

    /// A box standing on the ground with a snow slab on its top, seen from the south-west.
    fn box_with_snow() -> (Scene, SnowObject) {
        let (lo, hi) = (0.0f32, 1.0f32);
        let p = |x: f32, y: f32, z: f32| [x, y, z];
        let positions = vec![
            p(lo, lo, lo),
            p(hi, lo, lo),
            p(hi, hi, lo),
            p(lo, hi, lo),
            p(lo, lo, hi),
            p(hi, lo, hi),
            p(hi, hi, hi),
            p(lo, hi, hi),
        ];
        let triangles = vec![
            [0, 1, 5],
            [0, 5, 4],
            [1, 2, 6],
            [1, 6, 5],
            [2, 3, 7],
            [2, 7, 6],
            [3, 0, 4],
            [3, 4, 7],
            [4, 5, 6],
            [4, 6, 7],
        ];
        let scene = Scene {
            objects: vec![SceneObject {
                frame: Default::default(),
                name: "box".into(),
                positions,
                normals: None,
                triangles,
                uvs: None,
            }],
            ..Default::default()
        };
        let slab = SceneObject {
            frame: Default::default(),
            name: "snow".into(),
            positions: vec![
                p(lo, lo, 1.05),
                p(hi, lo, 1.05),
                p(hi, hi, 1.05),
                p(lo, hi, 1.05),
            ],
            normals: None,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            uvs: None,
        };
        (scene, SnowObject::from_object(&slab))
    }

    #[test]
    fn snow_is_white_and_bluer_in_shadow_the_object_darker_and_it_casts_a_contact_shadow() {
        let (scene, snow) = box_with_snow();
        let opts = PreviewOptions {
            width: 240,
            height: 180,
            ..Default::default()
        };
        let img = render_preview(&scene, std::slice::from_ref(&snow), &opts).unwrap();
        if let Ok(path) = std::env::var("SNOWSCAPE_PREVIEW_OUT") {
            img.save(path).unwrap();
        }
        // What the rasteriser put at each pixel.
        let (_, what) = render(&scene, std::slice::from_ref(&snow), &opts).unwrap();
        let at = |x: u32, y: u32| what[(y * opts.width + x) as usize];
        let lum =
            |p: &Rgb<u8>| 0.2126 * p.0[0] as f64 + 0.7152 * p.0[1] as f64 + 0.0722 * p.0[2] as f64;
        let mean = |keep: &dyn Fn(u32, u32) -> bool| {
            let v: Vec<f64> = img
                .enumerate_pixels()
                .filter(|(x, y, _)| keep(*x, *y))
                .map(|(_, _, p)| lum(p))
                .collect();
            (v.iter().sum::<f64>() / v.len().max(1) as f64, v.len())
        };
        let on_snow = |x: u32, y: u32| at(x, y) == Some(Material::Snow);
        let on_box = |x: u32, y: u32| at(x, y) == Some(Material::Scene);
        let (snow_lum, ns) = mean(&on_snow);
        let (box_lum, nb) = mean(&on_box);
        assert!(ns > 100 && nb > 100, "{ns} snow and {nb} box pixels");
        assert!(
            snow_lum > box_lum + 60.0,
            "snow {snow_lum} vs object {box_lum}"
        );
        // The ground: a shadow beside the box, away from the sun (sun from the south-east: the
        // shadow falls to the north-west), darker than open ground.
        let ground = |x: u32, y: u32| at(x, y) == Some(Material::Ground);
        let ground_lums: Vec<(f64, [u8; 3])> = img
            .enumerate_pixels()
            .filter(|(x, y, _)| ground(*x, *y))
            .map(|(_, _, p)| (lum(p), p.0))
            .collect();
        let brightest = ground_lums.iter().map(|g| g.0).fold(0.0, f64::max);
        let darkest = ground_lums
            .iter()
            .map(|g| g.0)
            .fold(f64::INFINITY, f64::min);
        assert!(
            darkest < 0.8 * brightest,
            "a contact shadow on the ground: {darkest} vs {brightest}"
        );
        // Shadowed ground is lit by the blue sky only: bluer than sunlit ground.
        let blue = |p: [u8; 3]| p[2] as f64 - p[0] as f64;
        let shade = ground_lums
            .iter()
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap()
            .1;
        let sunny = ground_lums
            .iter()
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap()
            .1;
        assert!(
            blue(shade) > blue(sunny),
            "shadow {shade:?} vs sun {sunny:?}"
        );
    }
}
