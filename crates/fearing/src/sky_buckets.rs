//! Sky buckets (Fearing 2000, Section 3.4): the sky plane is a grid of constant-size buckets.
//! A flake that reaches the sky spreads its representative area (its site's projected area over
//! the flakes the site shot) bilinearly over the four nearest bucket centres (the filtering of
//! Fig. 7). When the pass ends every bucket b holds mass M_b = depth · B² · weight_b (weight 1,
//! or an image for "snow writing", Fig. 8) and gives its flakes the areal density
//!
//!   ρ_b = M_b / max(R_b, B²),   R_b = Σ representative areas that reached b,
//!
//! so a bucket never gives more than its mass (a dense concentration of flakes, say above a
//! tree, draws the same total as the sky above a sparse flat surface) and otherwise each flake
//! gets exactly the snowfall density: a half-covered bucket at an object's border is not
//! doubled. A site receives Σ_b ρ_b · (its representative area in b). Sky mass that no flake
//! claims fell past the scene's surfaces (or was not sampled) and is counted as leaving.

use crate::params::SkyWeight;
use serde::Serialize;

/// The sky grid of one accumulation pass.
#[derive(Debug, Clone)]
pub struct SkyGrid {
    /// South-west corner of bucket (0, 0), metres.
    pub x0: f64,
    pub y0: f64,
    /// Bucket edge, metres.
    pub size: f64,
    pub nx: usize,
    pub ny: usize,
    /// Mass (snow volume, m³) of each bucket for this pass.
    pub mass: Vec<f64>,
}

/// What a pass's allocation did with the sky's mass.
#[derive(Debug, Clone, Copy, Default, Serialize, PartialEq)]
pub struct Allocation {
    /// Snow volume in the sky over the scene this pass, m³.
    pub sky_volume_m3: f64,
    /// Volume given to launch sites, m³.
    pub allocated_m3: f64,
    /// Volume that no flake claimed: fell past every surface, or was not sampled, m³.
    pub unclaimed_m3: f64,
    /// Buckets, and those that received at least one flake.
    pub buckets: usize,
    pub buckets_reached: usize,
}

impl SkyGrid {
    /// Buckets of `size` metres covering `lo`..`hi` (xy) plus one bucket all round, each with
    /// `depth` metres of snow times its weight. The weight image spans `weight_lo`..`weight_hi`.
    pub fn new(
        lo: [f64; 2],
        hi: [f64; 2],
        size: f64,
        depth: f64,
        weight: Option<&SkyWeight>,
        weight_box: ([f64; 2], [f64; 2]),
    ) -> Self {
        let size = size
            .max(((hi[0] - lo[0]).max(hi[1] - lo[1])) / 2048.0)
            .max(1e-6);
        let x0 = lo[0] - size;
        let y0 = lo[1] - size;
        let nx = (((hi[0] - lo[0]) / size).ceil() as usize + 2).max(2);
        let ny = (((hi[1] - lo[1]) / size).ceil() as usize + 2).max(2);
        let (wl, wh) = weight_box;
        let mut mass = vec![0.0; nx * ny];
        for r in 0..ny {
            for c in 0..nx {
                let (x, y) = (x0 + (c as f64 + 0.5) * size, y0 + (r as f64 + 0.5) * size);
                let w = match weight {
                    Some(w) => w.at(
                        (x - wl[0]) / (wh[0] - wl[0]).max(1e-12),
                        (y - wl[1]) / (wh[1] - wl[1]).max(1e-12),
                    ) as f64,
                    None => 1.0,
                };
                mass[r * nx + c] = depth * size * size * w;
            }
        }
        Self {
            x0,
            y0,
            size,
            nx,
            ny,
            mass,
        }
    }

    /// The bilinear splat of a flake arriving at (x, y): up to four (bucket, weight) pairs
    /// summing to 1 (positions beyond the grid go to its border buckets).
    pub fn splat(&self, x: f64, y: f64) -> [(u32, f32); 4] {
        let fx = ((x - self.x0) / self.size - 0.5).clamp(0.0, self.nx as f64 - 1.0);
        let fy = ((y - self.y0) / self.size - 0.5).clamp(0.0, self.ny as f64 - 1.0);
        let (c, r) = (
            (fx as usize).min(self.nx - 2),
            (fy as usize).min(self.ny - 2),
        );
        let (u, v) = (fx - c as f64, fy - r as f64);
        let b = |cc: usize, rr: usize| (rr * self.nx + cc) as u32;
        [
            (b(c, r), ((1.0 - u) * (1.0 - v)) as f32),
            (b(c + 1, r), (u * (1.0 - v)) as f32),
            (b(c, r + 1), ((1.0 - u) * v) as f32),
            (b(c + 1, r + 1), (u * v) as f32),
        ]
    }

    /// Areal density ρ_b of every bucket from the representative areas that reached it.
    pub fn densities(&self, reached: &[f64]) -> Vec<f64> {
        let cap = self.size * self.size;
        self.mass
            .iter()
            .zip(reached)
            .map(|(&m, &r)| if r > 0.0 { m / r.max(cap) } else { 0.0 })
            .collect()
    }

    /// Summary of an allocation.
    pub fn summary(&self, reached: &[f64], allocated: f64) -> Allocation {
        let sky: f64 = self.mass.iter().sum();
        Allocation {
            sky_volume_m3: sky,
            allocated_m3: allocated,
            unclaimed_m3: (sky - allocated).max(0.0),
            buckets: self.mass.len(),
            buckets_reached: reached.iter().filter(|&&r| r > 0.0).count(),
        }
    }
}

/// Adds one flake's splat to a site's sorted arrival list.
pub fn add_arrival(list: &mut Vec<(u32, f32)>, splat: [(u32, f32); 4]) {
    for (b, w) in splat {
        if w <= 0.0 {
            continue;
        }
        match list.binary_search_by_key(&b, |e| e.0) {
            Ok(i) => list[i].1 += w,
            Err(i) => list.insert(i, (b, w)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splats_sum_to_one_and_densities_cap_at_the_bucket_mass() {
        let g = SkyGrid::new(
            [0.0, 0.0],
            [10.0, 10.0],
            1.0,
            0.5,
            None,
            ([0.0, 0.0], [10.0, 10.0]),
        );
        assert_eq!((g.nx, g.ny), (12, 12));
        let s = g.splat(3.3, 7.9);
        assert!((s.iter().map(|e| e.1).sum::<f32>() - 1.0).abs() < 1e-6);
        let mut reached = vec![0.0; g.nx * g.ny];
        reached[5] = 0.5;
        reached[6] = 2.0;
        let d = g.densities(&reached);
        assert!(
            (d[5] - 0.5).abs() < 1e-12,
            "half-covered bucket keeps the snowfall density"
        );
        assert!(
            (d[6] - 0.25).abs() < 1e-12,
            "over-sampled bucket shares its mass"
        );
        assert_eq!(d[7], 0.0);
        let mut list = Vec::new();
        add_arrival(&mut list, s);
        add_arrival(&mut list, s);
        assert!((list.iter().map(|e| e.1).sum::<f32>() - 2.0).abs() < 1e-6);
        assert!(list.windows(2).all(|w| w[0].0 < w[1].0));
    }
}
