//! Snowflake motion (Fearing 2000, Section 3.5): flakes are shot upward from a launch site as a
//! polyline random walk. Each step rises `dz` and moves sideways to a random point of a circle
//! of radius fr, fr drawn anew at every step from a normal law; a constant wind bends the path
//! (Section 6: the flake falls downwind, so traced upward it moves upwind by
//! wind · dz / fall speed). With fr = 0 a flake is one straight ray to the sky.
//!
//! A flake that meets any surface on its way is blocked (a "hit"); one that reaches the sky
//! plane is a "miss" and reports where it arrived. Random numbers are keyed by (seed, pass,
//! site, flake), so a flake's path does not depend on who shot before it or on the threads.
//! A [`Ceiling`] grid of the highest surface near each column lets a flake skip ray casts once
//! nothing it could reach within one step rises above it.

use crate::tracer::{Tag, Tracer};
use snowscape_terrain::random::{KeyedRng, hash3};

/// The flutter walk of one pass.
#[derive(Debug, Clone, Copy)]
pub struct Walk {
    /// Mean flutter radius and its standard deviation, metres; radii are clamped to
    /// [0, fr + 3 sd].
    pub fr: f64,
    pub fr_sd: f64,
    /// Rise per step, metres.
    pub dz: f64,
    /// Upwind move per metre of rise (= -wind / fall speed), per axis.
    pub drift: [f64; 2],
    /// Height of the sky plane, metres.
    pub z_sky: f64,
}

impl Walk {
    /// Largest sideways move of one step, metres.
    pub fn reach(&self) -> f64 {
        self.fr + 3.0 * self.fr_sd + self.dz * (self.drift[0].hypot(self.drift[1]))
    }
}

/// The highest surface over each cell of a horizontal grid, taken over the neighbourhood a
/// flake can reach in one step.
pub struct Ceiling {
    x0: f64,
    y0: f64,
    cell: f64,
    nx: usize,
    ny: usize,
    /// Dilated maxima; `-inf` where nothing is.
    top: Vec<f32>,
}

impl Ceiling {
    /// From triangles (scene and snow), over the box `lo`..`hi` (xy), for steps of `reach`.
    pub fn new(
        tris: impl Iterator<Item = [[f32; 3]; 3]>,
        lo: [f64; 2],
        hi: [f64; 2],
        reach: f64,
    ) -> Self {
        let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-6);
        let cell = (span / 256.0).max(reach * 0.5).max(span / 4096.0);
        let nx = (((hi[0] - lo[0]) / cell).ceil() as usize).max(1);
        let ny = (((hi[1] - lo[1]) / cell).ceil() as usize).max(1);
        let mut top = vec![f32::NEG_INFINITY; nx * ny];
        for t in tris {
            let zmax = t[0][2].max(t[1][2]).max(t[2][2]);
            // Plane z = a x + b y + c (when not near vertical): its max over a cell is at a corner.
            let e1 = [t[1][0] - t[0][0], t[1][1] - t[0][1], t[1][2] - t[0][2]].map(f64::from);
            let e2 = [t[2][0] - t[0][0], t[2][1] - t[0][1], t[2][2] - t[0][2]].map(f64::from);
            let n = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            let nl = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let plane = (nl > 0.0 && n[2].abs() > 0.2 * nl).then(|| (-n[0] / n[2], -n[1] / n[2]));
            let bx = |v: f32| {
                ((v as f64 - lo[0]) / cell)
                    .floor()
                    .clamp(0.0, nx as f64 - 1.0) as usize
            };
            let by = |v: f32| {
                ((v as f64 - lo[1]) / cell)
                    .floor()
                    .clamp(0.0, ny as f64 - 1.0) as usize
            };
            let (c0, c1) = (
                bx(t[0][0].min(t[1][0]).min(t[2][0])),
                bx(t[0][0].max(t[1][0]).max(t[2][0])),
            );
            let (r0, r1) = (
                by(t[0][1].min(t[1][1]).min(t[2][1])),
                by(t[0][1].max(t[1][1]).max(t[2][1])),
            );
            for r in r0..=r1 {
                for c in c0..=c1 {
                    let z = match plane {
                        Some((a, b)) => {
                            let (x, y) = (lo[0] + c as f64 * cell, lo[1] + r as f64 * cell);
                            let (px, py) = (x - t[0][0] as f64, y - t[0][1] as f64);
                            let z00 = t[0][2] as f64 + a * px + b * py;
                            let zc = z00 + a.max(0.0) * cell + b.max(0.0) * cell;
                            (zc as f32).min(zmax)
                        }
                        None => zmax,
                    };
                    let v = &mut top[r * nx + c];
                    *v = v.max(z);
                }
            }
        }
        // Dilate by the step reach so one step from a cell stays under its ceiling.
        let k = (reach / cell).ceil() as isize + 1;
        let dil = |src: &[f32], along_x: bool| -> Vec<f32> {
            let mut out = vec![f32::NEG_INFINITY; nx * ny];
            for r in 0..ny as isize {
                for c in 0..nx as isize {
                    let mut m = f32::NEG_INFINITY;
                    for d in -k..=k {
                        let (cc, rr) = if along_x { (c + d, r) } else { (c, r + d) };
                        if cc >= 0 && rr >= 0 && (cc as usize) < nx && (rr as usize) < ny {
                            m = m.max(src[rr as usize * nx + cc as usize]);
                        }
                    }
                    out[r as usize * nx + c as usize] = m;
                }
            }
            out
        };
        let top = dil(&dil(&top, true), false);
        Self {
            x0: lo[0],
            y0: lo[1],
            cell,
            nx,
            ny,
            top,
        }
    }

    /// Whether nothing within one step of (x, y) rises to `z`.
    #[inline]
    pub fn clear(&self, x: f64, y: f64, z: f64) -> bool {
        let c = ((x - self.x0) / self.cell).floor();
        let r = ((y - self.y0) / self.cell).floor();
        if c < 0.0 || r < 0.0 || c >= self.nx as f64 || r >= self.ny as f64 {
            return false;
        }
        z > self.top[r as usize * self.nx + c as usize] as f64
    }
}

/// What one batch of flakes found.
#[derive(Debug, Clone, Default)]
pub struct Batch {
    pub shot: u32,
    /// Where each flake that reached the sky arrived (x, y).
    pub arrivals: Vec<[f64; 2]>,
    /// Ray casts done.
    pub rays: u64,
}

/// One batch of flakes to shoot from a launch site.
#[derive(Debug, Clone, Copy)]
pub struct Volley {
    /// The cover's seed and the accumulation pass (the flakes' random keys).
    pub seed: u64,
    pub pass: u32,
    /// The site (cell id) and where its flakes start.
    pub site: u32,
    pub start: [f64; 3],
    /// The site's own base triangle and snow top, ignored on the first step.
    pub own: [Tag; 2],
    /// Flakes `first..first + count`.
    pub first: u32,
    pub count: u32,
}

/// Shoots flakes `first..first + count` of the volley's site from its start upwards, ignoring the
/// site's own base triangle and snow top (`own`) on the first step.
pub fn shoot(walk: &Walk, tracer: &Tracer, ceiling: &Ceiling, volley: Volley) -> Batch {
    let Volley {
        seed,
        pass,
        site,
        start,
        own,
        first,
        count,
    } = volley;
    let mut b = Batch {
        shot: count,
        ..Default::default()
    };
    // A straight slanted ray leaves its column: the ceiling only vouches for vertical ones.
    let use_ceiling = walk.fr > 0.0 || walk.drift == [0.0, 0.0];
    let key = hash3(seed, 0xf1a4e ^ pass as u64, site as u64);
    for f in first..first + count {
        let mut rng = KeyedRng::new(key, f as u64);
        let mut p = start;
        let mut first_step = true;
        let mut blocked = false;
        while p[2] < walk.z_sky {
            let dz = if walk.fr > 0.0 {
                walk.dz.min(walk.z_sky - p[2]).max(1e-9)
            } else {
                walk.z_sky - p[2]
            };
            let (mut dx, mut dy) = (walk.drift[0] * dz, walk.drift[1] * dz);
            if walk.fr > 0.0 {
                let r = (walk.fr + walk.fr_sd * rng.next_normal())
                    .clamp(0.0, walk.fr + 3.0 * walk.fr_sd);
                let phi = std::f64::consts::TAU * rng.next_f64();
                dx += r * phi.cos();
                dy += r * phi.sin();
            }
            let q = [p[0] + dx, p[1] + dy, p[2] + dz];
            if !(use_ceiling && ceiling.clear(p[0], p[1], p[2])) {
                b.rays += 1;
                let skip = |t: Tag| first_step && (t == own[0] || t == own[1]);
                if tracer.blocked(p, q, skip) {
                    blocked = true;
                    break;
                }
            }
            first_step = false;
            p = q;
        }
        if !blocked {
            b.arrivals.push([p[0], p[1]]);
        }
    }
    b
}
