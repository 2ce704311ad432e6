//! Moving snow over edges (Fearing 2000, Section 4.3): snow that leaves an edge group over a
//! border edge is carried by a few (< 5) avalanche particles on projectile paths, tracked
//! downwards through the scene and bouncing off surfaces that hold no snow, until they reach a
//! surface with launch sites; there each gives its load to the nearest launch site. Particles
//! that fall below the scene leave it, and their snow is counted as leaving.

use crate::tracer::{Hit, Tag, Tracer};
use std::collections::HashMap;

/// Gravity, m/s²: the model's one value, 9.81.
pub const G: f64 = snowscape_terrain::materials::GRAVITY_M_S2;

/// Where a particle came to rest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Landing {
    /// On site (topology index).
    Site(u32),
    /// Below the scene: gone.
    Lost,
    /// Still bouncing after the step limit (the caller keeps the snow where it was).
    Stuck,
}

/// A horizontal hash grid of site positions for nearest-site queries.
pub struct SiteGrid {
    cell: f64,
    map: HashMap<(i64, i64), Vec<u32>>,
    points: Vec<[f64; 3]>,
    /// (object, triangle) of each site.
    owner: Vec<(u32, u32)>,
}

impl SiteGrid {
    pub fn new(points: Vec<[f64; 3]>, owner: Vec<(u32, u32)>, cell: f64) -> Self {
        let mut map: HashMap<(i64, i64), Vec<u32>> = HashMap::new();
        for (i, p) in points.iter().enumerate() {
            map.entry(((p[0] / cell).floor() as i64, (p[1] / cell).floor() as i64))
                .or_default()
                .push(i as u32);
        }
        Self {
            cell,
            map,
            points,
            owner,
        }
    }

    /// The site nearest to `p` (3D distance) among those `accept` takes, within `rings` cells.
    pub fn nearest(
        &self,
        p: [f64; 3],
        rings: i64,
        accept: impl Fn(u32, (u32, u32)) -> bool,
    ) -> Option<u32> {
        let (cx, cy) = (
            (p[0] / self.cell).floor() as i64,
            (p[1] / self.cell).floor() as i64,
        );
        let mut best: Option<(f64, u32)> = None;
        for r in 0..=rings {
            for x in cx - r..=cx + r {
                for y in cy - r..=cy + r {
                    if (x - cx).abs() != r && (y - cy).abs() != r {
                        continue;
                    }
                    for &i in self.map.get(&(x, y)).map(|v| v.as_slice()).unwrap_or(&[]) {
                        if !accept(i, self.owner[i as usize]) {
                            continue;
                        }
                        let q = self.points[i as usize];
                        let d =
                            (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2);
                        if best.is_none_or(|(bd, bi)| d < bd || (d == bd && i < bi)) {
                            best = Some((d, i));
                        }
                    }
                }
            }
            // Anything in a farther ring is at least r cells away.
            if let Some((bd, _)) = best
                && bd.sqrt() <= r as f64 * self.cell
            {
                break;
            }
        }
        best.map(|b| b.1)
    }
}

/// What the particle tracer needs to know about the scene.
pub struct Flight<'a> {
    pub tracer: &'a Tracer,
    pub sites: &'a SiteGrid,
    /// Whether a scene triangle (object, triangle) carries launch sites.
    pub has_sites: &'a dyn Fn(u32, u32) -> bool,
    /// Below this height a particle has left the scene.
    pub z_floor: f64,
    /// Longest step of a path, metres.
    pub step: f64,
    pub restitution: f64,
    /// Search radius for the receiving site, in grid cells.
    pub rings: i64,
}

/// Flies a particle from `p` with velocity `v`, ignoring the snow of group `own_group`.
pub fn fly(f: &Flight, mut p: [f64; 3], mut v: [f64; 3], own_group: u32) -> Landing {
    let z_start = p[2];
    let skip = |t: Tag| matches!(t, Tag::SnowTop { group, .. } | Tag::SnowWall { group } if group == own_group);
    let eps = f.step * 1e-3;
    for _ in 0..2000 {
        // Chords whose sagitta (g dt² / 8) stays under a quarter of the step.
        let dt = (2.0 * f.step / G).sqrt();
        let q = [
            p[0] + v[0] * dt,
            p[1] + v[1] * dt,
            p[2] + v[2] * dt - 0.5 * G * dt * dt,
        ];
        match f.tracer.first_hit(p, q, skip) {
            None => {
                p = q;
                v[2] -= G * dt;
                if p[2] < f.z_floor {
                    return Landing::Lost;
                }
            }
            Some(Hit { t, tag, normal }) => {
                let t = t as f64;
                let h = [0, 1, 2].map(|k| p[k] + t * (q[k] - p[k]));
                let n = normal.map(f64::from);
                let lands = match tag {
                    Tag::SnowTop { site, .. } => return Landing::Site(site),
                    Tag::Scene { object, triangle } => {
                        (f.has_sites)(object, triangle) && n[2] > 0.0
                    }
                    Tag::SnowWall { .. } => false,
                };
                if lands {
                    let Tag::Scene { object, triangle } = tag else {
                        unreachable!()
                    };
                    // Snow only falls: the receiving site lies no higher than the start.
                    let low = |i: u32| f.sites.points[i as usize][2] <= z_start;
                    let on_tri = f
                        .sites
                        .nearest(h, f.rings, |i, o| o == (object, triangle) && low(i));
                    let any = || f.sites.nearest(h, f.rings, |i, _| low(i));
                    return on_tri.or_else(any).map_or(Landing::Stuck, Landing::Site);
                }
                // Bounce: reflect about the normal, lose speed, step off the surface.
                v[2] -= G * dt * t;
                let vn = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
                v = [0, 1, 2].map(|k| (v[k] - 2.0 * vn * n[k]) * f.restitution);
                p = [0, 1, 2].map(|k| h[k] + n[k] * eps);
            }
        }
    }
    Landing::Stuck
}
