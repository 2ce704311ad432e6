//! Ray casting against a [`Scene`] through a compressed wide BVH (CWBVH, 8-wide, built with
//! PLOC by the `obvhs` crate), the role Fearing 2000 (Section 3) gives to range trees: flakes
//! shot upward from launch sites must know whether, and where, they hit the scene.
//!
//! Triangles are copied in the BVH's leaf order, so a leaf test reads them contiguously, and
//! each keeps its object and triangle index. Intersections are double-sided (Möller-Trumbore);
//! `t` is measured in lengths of the ray's direction (distance in metres for a unit direction).
//! Queries take `&self` and allocate nothing, so batches run on rayon ([`SceneBvh::first_hits`],
//! [`SceneBvh::anything_above_many`]) and results do not depend on the thread count.

use crate::scene::Scene;
use glam::Vec3A;
use obvhs::{BvhBuildParams, cwbvh::CwBvh, triangle::Triangle};
use rayon::prelude::*;

/// Distance along `ray` to `tri` (double-sided Möller-Trumbore), `f32::INFINITY` on a miss.
/// Points on an edge count as inside (`u, v >= 0` also holds for -0.0), so an exactly vertical
/// ray through the shared edge of two triangles hits them, where obvhs's own test, which reads
/// the sign bits, misses both.
#[inline(always)]
pub fn intersect(tri: &Triangle, ray: &obvhs::ray::Ray) -> f32 {
    let e1 = tri.v1 - tri.v0;
    let e2 = tri.v2 - tri.v0;
    let p = ray.direction.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return f32::INFINITY;
    }
    let inv = 1.0 / det;
    let s = ray.origin - tri.v0;
    let u = s.dot(p) * inv;
    let q = s.cross(e1);
    let v = ray.direction.dot(q) * inv;
    let t = e2.dot(q) * inv;
    if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t >= ray.tmin && t <= ray.tmax {
        t
    } else {
        f32::INFINITY
    }
}

/// A ray: points `origin + t * direction` for `t` in `[t_min, t_max]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    pub origin: [f32; 3],
    pub direction: [f32; 3],
    pub t_min: f32,
    pub t_max: f32,
}

impl Ray {
    /// A ray from `origin` along `direction`, `t` in `[0, inf)`.
    pub fn new(origin: [f32; 3], direction: [f32; 3]) -> Self {
        Self {
            origin,
            direction,
            t_min: 0.0,
            t_max: f32::INFINITY,
        }
    }

    /// Straight up (+z) from `point`, ignoring hits closer than `clearance` metres.
    pub fn up(point: [f32; 3], clearance: f32) -> Self {
        Self {
            origin: point,
            direction: [0.0, 0.0, 1.0],
            t_min: clearance,
            t_max: f32::INFINITY,
        }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> [f32; 3] {
        [0, 1, 2].map(|k| self.origin[k] + t * self.direction[k])
    }

    fn to_obvhs(self) -> Option<obvhs::ray::Ray> {
        let (o, d) = (Vec3A::from(self.origin), Vec3A::from(self.direction));
        let usable = o.is_finite()
            && d.is_finite()
            && d.length_squared() > 0.0
            && !self.t_min.is_nan()
            && !self.t_max.is_nan()
            && self.t_min <= self.t_max;
        usable.then(|| obvhs::ray::Ray::new(o, d, self.t_min, self.t_max))
    }
}

/// The first surface a ray meets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Index of the object in [`Scene::objects`].
    pub object: u32,
    /// Index of the triangle in that object's `triangles`.
    pub triangle: u32,
}

/// A BVH over every triangle of a scene.
#[derive(Debug, Clone)]
pub struct SceneBvh {
    /// `None` for a scene without triangles (every ray misses).
    bvh: Option<CwBvh>,
    /// Triangles in BVH leaf order.
    triangles: Vec<Triangle>,
    /// (object, triangle) of each entry of `triangles`.
    ids: Vec<(u32, u32)>,
}

impl SceneBvh {
    /// Builds the BVH of `scene` (triangles with a non-finite corner left out; PLOC with the obvhs "medium" preset: about Embree's build
    /// time with faster traversal).
    pub fn new(scene: &Scene) -> Self {
        let mut triangles = Vec::with_capacity(scene.triangle_count());
        let mut ids = Vec::with_capacity(scene.triangle_count());
        for (oi, object) in scene.objects.iter().enumerate() {
            for t in 0..object.triangles.len() {
                let [v0, v1, v2] = object.corners(t).map(Vec3A::from);
                // A hand-made scene may hold non-finite corners: such a triangle is never hit.
                if !(v0.is_finite() && v1.is_finite() && v2.is_finite()) {
                    continue;
                }
                triangles.push(Triangle { v0, v1, v2 });
                ids.push((oi as u32, t as u32));
            }
        }
        if triangles.is_empty() {
            return Self {
                bvh: None,
                triangles,
                ids,
            };
        }
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &triangles,
            BvhBuildParams::medium_build(),
            &mut std::time::Duration::default(),
        );
        let order = &bvh.primitive_indices;
        let triangles = order.iter().map(|&i| triangles[i as usize]).collect();
        let ids = order.iter().map(|&i| ids[i as usize]).collect();
        Self {
            bvh: Some(bvh),
            triangles,
            ids,
        }
    }

    /// Number of triangles in the BVH.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The nearest hit along `ray` within `[t_min, t_max]`; `None` on a miss, and for a ray
    /// with a non-finite origin or direction, a zero direction or an empty `t` range.
    pub fn first_hit(&self, ray: &Ray) -> Option<RayHit> {
        let bvh = self.bvh.as_ref()?;
        let r = ray.to_obvhs()?;
        let mut hit = obvhs::ray::RayHit::none();
        bvh.ray_traverse(r, &mut hit, |r, id| intersect(&self.triangles[id], r))
            .then(|| {
                let (object, triangle) = self.ids[hit.primitive_id as usize];
                RayHit {
                    t: hit.t,
                    object,
                    triangle,
                }
            })
    }

    /// Whether `ray` meets any surface within `[t_min, t_max]` (stops at the first one found).
    pub fn hits_anything(&self, ray: &Ray) -> bool {
        match (&self.bvh, ray.to_obvhs()) {
            (Some(bvh), Some(r)) => {
                !bvh.ray_traverse_miss(r, |r, id| intersect(&self.triangles[id], r))
            }
            _ => false,
        }
    }

    /// Whether any surface lies straight above `point` (farther than `clearance` metres, so a
    /// point on a surface does not see that surface).
    pub fn anything_above(&self, point: [f32; 3], clearance: f32) -> bool {
        self.hits_anything(&Ray::up(point, clearance))
    }

    /// [`SceneBvh::first_hit`] for every ray, in parallel (order kept).
    pub fn first_hits(&self, rays: &[Ray]) -> Vec<Option<RayHit>> {
        rays.par_iter()
            .with_min_len(256)
            .map(|r| self.first_hit(r))
            .collect()
    }

    /// [`SceneBvh::anything_above`] for every point, in parallel (order kept).
    pub fn anything_above_many(&self, points: &[[f32; 3]], clearance: f32) -> Vec<bool> {
        points
            .par_iter()
            .with_min_len(256)
            .map(|&p| self.anything_above(p, clearance))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SceneObject;

    fn square(name: &str, z: f32, size: f32) -> SceneObject {
        SceneObject {
            frame: Default::default(),
            name: name.into(),
            positions: vec![[0., 0., z], [size, 0., z], [size, size, z], [0., size, z]],
            normals: None,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            uvs: None,
        }
    }

    #[test]
    fn nearest_of_stacked_squares_and_up_queries() {
        let scene = Scene {
            objects: vec![square("floor", 0.0, 10.0), square("roof", 3.0, 5.0)],
            ..Default::default()
        };
        let bvh = SceneBvh::new(&scene);
        assert_eq!(bvh.triangle_count(), 4);
        let down = Ray::new([2.0, 1.0, 10.0], [0.0, 0.0, -1.0]);
        let hit = bvh.first_hit(&down).unwrap();
        assert_eq!(hit.object, 1);
        assert!((hit.t - 7.0).abs() < 1e-5);
        let outside_roof = Ray::new([8.0, 8.0, 10.0], [0.0, 0.0, -1.0]);
        let hit = bvh.first_hit(&outside_roof).unwrap();
        assert_eq!((hit.object, (hit.t - 10.0).abs() < 1e-5), (0, true));
        let up = Ray::up([2.0, 2.0, 0.0], 1e-3);
        assert!(
            bvh.hits_anything(&up),
            "a ray along the shared diagonal of the roof's triangles"
        );
        // A point on the floor under the roof sees it; beside the roof it sees the sky.
        assert!(bvh.anything_above([2.0, 2.0, 0.0], 1e-3));
        assert!(!bvh.anything_above([8.0, 2.0, 0.0], 1e-3));
        // The roof itself is not "above" a point on it.
        assert!(!bvh.anything_above([2.0, 2.0, 3.0], 1e-3));
        let up = bvh.first_hit(&Ray::up([2.0, 2.0, 0.0], 1e-3)).unwrap();
        assert!((up.t - 3.0).abs() < 1e-5 && up.object == 1);
        // Batches give the same answers in the same order.
        let rays = vec![
            down,
            outside_roof,
            Ray::new([20.0, 0.0, 1.0], [0.0, 0.0, -1.0]),
        ];
        let batch = bvh.first_hits(&rays);
        assert_eq!(batch[0], bvh.first_hit(&down));
        assert_eq!(batch[2], None);
        let pts = [[2.0, 2.0, 0.0], [8.0, 2.0, 0.0]];
        assert_eq!(bvh.anything_above_many(&pts, 1e-3), vec![true, false]);
    }

    #[test]
    fn bad_rays_and_empty_scenes_miss() {
        let scene = Scene {
            objects: vec![square("a", 0.0, 1.0)],
            ..Default::default()
        };
        let bvh = SceneBvh::new(&scene);
        for r in [
            Ray::new([f32::NAN, 0.5, 1.0], [0.0, 0.0, -1.0]),
            Ray::new([0.5, 0.5, 1.0], [0.0, 0.0, 0.0]),
            Ray::new([0.5, 0.5, 1.0], [0.0, f32::INFINITY, -1.0]),
        ] {
            assert_eq!(bvh.first_hit(&r), None);
            assert!(!bvh.hits_anything(&r));
        }
        let one = Scene {
            objects: vec![SceneObject {
                frame: Default::default(),
                triangles: vec![[0, 1, 2]],
                ..square("one", 0.0, 1.0)
            }],
            ..Default::default()
        };
        let bvh = SceneBvh::new(&one);
        assert!(
            bvh.first_hit(&Ray::new([0.6, 0.2, 1.0], [0.0, 0.0, -1.0]))
                .is_some()
        );
        let empty = SceneBvh::new(&Scene::default());
        assert_eq!(empty.first_hit(&Ray::new([0.0; 3], [0.0, 0.0, 1.0])), None);
    }
}
