//! Particle/surface intersection (Fearing 2000, Section 3.6): a BVH over the scene's triangles
//! and the current snow surfaces, each triangle tagged with what it is, so that flakes,
//! obstacle tests and avalanche particles can ignore what should not stop them (a site's own
//! triangle, its own group's snow).
//!
//! The paper buckets Z ranges into per-box range trees; a compressed wide BVH built with PLOC
//! by the `obvhs` crate (the BVH behind `snowscape_mesh::SceneBvh`) does the same job faster.
//! It is rebuilt when snow mass is added, the paper's "rebucketing". Intersections are
//! double-sided Möller-Trumbore with edges counted as inside.

use glam::Vec3A;
use obvhs::{BvhBuildParams, cwbvh::CwBvh, triangle::Triangle};
use snowscape_mesh::Scene;
use snowscape_mesh::raycast::intersect;

/// What a triangle of the tracer is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tag {
    /// A triangle of the input scene.
    Scene { object: u32, triangle: u32 },
    /// The top snow surface of site `site` (index into the topology's leaves) of `group`.
    SnowTop { site: u32, group: u32 },
    /// A closing wall of `group`'s snow (Section 3.7), vertical at an edge-group border.
    SnowWall { group: u32 },
}

/// A hit: ray parameter, tag, unit geometric normal (facing against the ray).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub tag: Tag,
    pub normal: [f32; 3],
}

/// A BVH over tagged triangles.
pub struct Tracer {
    bvh: Option<CwBvh>,
    tris: Vec<Triangle>,
    tags: Vec<Tag>,
}

impl Tracer {
    /// The scene's triangles plus extra tagged triangles (snow).
    pub fn new(scene: &Scene, extra: &[([[f32; 3]; 3], Tag)]) -> Self {
        let mut tris = Vec::with_capacity(scene.triangle_count() + extra.len());
        let mut tags = Vec::with_capacity(tris.capacity());
        for (oi, o) in scene.objects.iter().enumerate() {
            for t in 0..o.triangles.len() {
                let [v0, v1, v2] = o.corners(t).map(Vec3A::from);
                if v0.is_finite() && v1.is_finite() && v2.is_finite() {
                    tris.push(Triangle { v0, v1, v2 });
                    tags.push(Tag::Scene {
                        object: oi as u32,
                        triangle: t as u32,
                    });
                }
            }
        }
        for (c, tag) in extra {
            let [v0, v1, v2] = c.map(Vec3A::from);
            if v0.is_finite()
                && v1.is_finite()
                && v2.is_finite()
                && (v1 - v0).cross(v2 - v0).length_squared() > 0.0
            {
                tris.push(Triangle { v0, v1, v2 });
                tags.push(*tag);
            }
        }
        if tris.is_empty() {
            return Self {
                bvh: None,
                tris,
                tags,
            };
        }
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &tris,
            BvhBuildParams::medium_build(),
            &mut std::time::Duration::default(),
        );
        let order = &bvh.primitive_indices;
        let tris = order.iter().map(|&i| tris[i as usize]).collect();
        let tags = order.iter().map(|&i| tags[i as usize]).collect();
        Self {
            bvh: Some(bvh),
            tris,
            tags,
        }
    }

    /// Triangles held.
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    fn ray(from: [f64; 3], to: [f64; 3]) -> Option<obvhs::ray::Ray> {
        let o = Vec3A::new(from[0] as f32, from[1] as f32, from[2] as f32);
        let d = Vec3A::new(
            (to[0] - from[0]) as f32,
            (to[1] - from[1]) as f32,
            (to[2] - from[2]) as f32,
        );
        (o.is_finite() && d.is_finite() && d.length_squared() > 0.0)
            .then(|| obvhs::ray::Ray::new(o, d, 0.0, 1.0))
    }

    /// Whether the segment `from`→`to` meets a triangle that `skip` does not exclude.
    pub fn blocked(&self, from: [f64; 3], to: [f64; 3], skip: impl Fn(Tag) -> bool) -> bool {
        let (Some(bvh), Some(r)) = (&self.bvh, Self::ray(from, to)) else {
            return false;
        };
        !bvh.ray_traverse_miss(r, |r, id| {
            if skip(self.tags[id]) {
                f32::INFINITY
            } else {
                intersect(&self.tris[id], r)
            }
        })
    }

    /// The first triangle on the segment `from`→`to` (t in [0, 1]) that `skip` does not exclude.
    pub fn first_hit(
        &self,
        from: [f64; 3],
        to: [f64; 3],
        skip: impl Fn(Tag) -> bool,
    ) -> Option<Hit> {
        let (Some(bvh), Some(r)) = (&self.bvh, Self::ray(from, to)) else {
            return None;
        };
        let mut hit = obvhs::ray::RayHit::none();
        if !bvh.ray_traverse(r, &mut hit, |r, id| {
            if skip(self.tags[id]) {
                f32::INFINITY
            } else {
                intersect(&self.tris[id], r)
            }
        }) {
            return None;
        }
        let tri = &self.tris[hit.primitive_id as usize];
        let mut n = (tri.v1 - tri.v0).cross(tri.v2 - tri.v0).normalize_or_zero();
        if n.dot(r.direction) > 0.0 {
            n = -n;
        }
        Some(Hit {
            t: hit.t,
            tag: self.tags[hit.primitive_id as usize],
            normal: n.into(),
        })
    }
}
