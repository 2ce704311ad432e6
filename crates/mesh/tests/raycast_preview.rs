//! Ray casting against brute force on a real mesh, and the CPU preview of the bunny.

mod common;
use snowscape_mesh::preview::{PreviewOptions, SKY, render_preview, write_preview};
use snowscape_mesh::{Ray, Scene, SceneBvh, SnowObject, SourceFrame, read_scene};

fn bunny() -> Scene {
    read_scene(&common::mesh_path("bunny_npm.obj"), &SourceFrame::default())
        .unwrap()
        .0
}

/// The nearest hit by testing every triangle (f64 Möller-Trumbore).
fn brute_force(scene: &Scene, ray: &Ray) -> Option<f64> {
    let mut best: Option<f64> = None;
    let o = ray.origin.map(f64::from);
    let d = ray.direction.map(f64::from);
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    for obj in &scene.objects {
        for t in 0..obj.triangles.len() {
            let [a, b, c] = obj.corners(t).map(|p| p.map(f64::from));
            let (e1, e2) = (sub(b, a), sub(c, a));
            let p = cross(d, e2);
            let det = dot(e1, p);
            if det.abs() < 1e-12 {
                continue;
            }
            let s = sub(o, a);
            let u = dot(s, p) / det;
            let q = cross(s, e1);
            let v = dot(d, q) / det;
            let tt = dot(e2, q) / det;
            if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && tt >= ray.t_min as f64 {
                best = Some(best.map_or(tt, |x: f64| x.min(tt)));
            }
        }
    }
    best
}

#[test]
fn bvh_hits_agree_with_brute_force_on_the_bunny() {
    let scene = bunny();
    let bvh = SceneBvh::new(&scene);
    let b = scene.bounds().unwrap();
    let c = b.centre();
    let mut rays = Vec::new();
    // Rays from a ring around the bunny towards points inside its box, plus vertical ones.
    for i in 0..400 {
        let a = i as f32 * 0.61;
        let h = (i % 17) as f32 / 16.0;
        let origin = [
            c[0] + 20.0 * a.cos(),
            c[1] + 20.0 * a.sin(),
            b.min[2] + h * b.size()[2],
        ];
        let target = [
            b.min[0] + b.size()[0] * ((i * 7 % 13) as f32 / 12.0),
            b.min[1] + b.size()[1] * ((i * 5 % 11) as f32 / 10.0),
            b.min[2] + b.size()[2] * ((i * 3 % 7) as f32 / 6.0),
        ];
        rays.push(Ray::new(origin, [0, 1, 2].map(|k| target[k] - origin[k])));
        rays.push(Ray::new(
            [target[0], target[1], b.max[2] + 1.0],
            [0.0, 0.0, -1.0],
        ));
    }
    let hits = bvh.first_hits(&rays);
    let mut hit_count = 0;
    for (ray, hit) in rays.iter().zip(&hits) {
        let expected = brute_force(&scene, ray);
        match (hit, expected) {
            (Some(h), Some(t)) => {
                hit_count += 1;
                let len = ray.direction.iter().map(|c| c * c).sum::<f32>().sqrt() as f64;
                assert!(
                    (h.t as f64 - t).abs() * len < 1e-3,
                    "{ray:?}: {} vs {t}",
                    h.t
                );
                assert_eq!(h.object, 0);
                assert!((h.triangle as usize) < scene.objects[0].triangles.len());
            }
            (None, None) => {}
            // Grazing rays may differ by an edge; they must be rare.
            (got, want) => panic!("{ray:?}: bvh {got:?}, brute force {want:?}"),
        }
        assert_eq!(hit.is_some(), bvh.hits_anything(ray));
    }
    assert!(
        hit_count > 300,
        "the rays aim at the bunny: {hit_count} hits"
    );
}

#[test]
fn bunny_preview_shows_a_plausible_silhouette() {
    let scene = bunny();
    let opts = PreviewOptions {
        width: 200,
        height: 150,
        ground: false,
        ..Default::default()
    };
    let img = render_preview(&scene, &[], &opts).unwrap();
    let covered = img.pixels().filter(|p| p.0 != SKY).count() as f64 / (200.0 * 150.0);
    // The box fills 90 % of the limiting side; a bunny covers part of its box's outline.
    assert!(
        covered > 0.15 && covered < 0.7,
        "covered fraction {covered}"
    );
    // Shading varies over the body (not a flat silhouette).
    let mut greys: Vec<u8> = img
        .pixels()
        .filter(|p| p.0 != SKY)
        .map(|p| p.0[0])
        .collect();
    greys.sort_unstable();
    assert!(greys[greys.len() * 9 / 10] > greys[greys.len() / 10] + 20);
    // The same bunny drawn as snow is brighter, and the PNG is written atomically.
    let snow = SnowObject::from_object(&scene.objects[0]);
    let white = render_preview(&Scene::default(), std::slice::from_ref(&snow), &opts).unwrap();
    let mean = |im: &image::RgbImage| {
        let v: Vec<f64> = im
            .pixels()
            .filter(|p| p.0 != SKY)
            .map(|p| p.0[0] as f64)
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    assert!(mean(&white) > mean(&img) + 30.0);
    let d = tempfile::tempdir().unwrap();
    let path = d.path().join("preview.png");
    write_preview(&path, &scene, &[snow], &opts).unwrap();
    let back = image::open(&path).unwrap();
    assert_eq!((back.width(), back.height()), (200, 150));
}
