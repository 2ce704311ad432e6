//! The boundary alpha mask (von Festenberg & Gumhold 2011, Section 5.4.2, Figs. 7-8). The
//! paper uses "an alpha mask generated from photographs of real snow boundaries"; we generate
//! one procedurally with the properties the paper asks of it: cyclic in `u` (the image wraps
//! left to right), transparent at `v = 0`, opaque at `v = 1`, "the major snow boundary ...
//! located around v = 1/2", frayed by fractal value noise into flakes and clumps.
//!
//! Image rows run with `v` (row 0 is `v = 0`, glTF's top-left convention); the alpha is
//! `smoothstep` across a boundary at `v = 1/2 + 0.3 (n(u, v) - 1/2)` with fractal noise `n`
//! periodic in `u`, plus isolated flakes below it. RGB is snow white with a faint grain. The
//! noise is a hash of the lattice point and the seed: the same seed gives the same bytes.

use image::{Rgba, RgbaImage};

/// Side of the default mask, pixels.
pub const MASK_SIZE: u32 = 256;

/// The mask image, `size` x `size` pixels.
pub fn boundary_mask(size: u32, seed: u64) -> RgbaImage {
    let s = size.max(8);
    RgbaImage::from_fn(s, s, |x, y| {
        let u = (x as f32 + 0.5) / s as f32;
        let v = (y as f32 + 0.5) / s as f32;
        // The main edge: a frayed line around v = 1/2.
        let n = fbm(u, v, seed, 4, 6);
        let edge = 0.5 + 0.4 * (n - 0.5);
        let mut a = smoothstep(edge - 0.02, edge + 0.02, v);
        // Holes in the snow just inside the edge, closing up further in.
        let holes = fbm(u, v, seed ^ 0x5851_f42d_4c95_7f2d, 16, 4);
        let depth = smoothstep(edge + 0.2, edge, v);
        a *= 1.0 - depth * smoothstep(0.6, 0.66, holes);
        // Loose flakes and clumps in the bare band below the edge.
        let flakes = fbm(u, v, seed ^ 0x9e37_79b9_7f4a_7c15, 16, 4);
        let near = smoothstep(edge - 0.3, edge, v);
        a = a.max(near * smoothstep(0.64, 0.68, flakes));
        let grain = 242.0 + 13.0 * fbm(u, v, seed.wrapping_add(7), 32, 3);
        let c = grain.clamp(0.0, 255.0) as u8;
        Rgba([c, c, 255, (255.0 * a.clamp(0.0, 1.0)).round() as u8])
    })
}

fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Fractal value noise in [0, 1], periodic in `u` with period 1, `octaves` octaves from
/// `base` lattice cells per unit up.
fn fbm(u: f32, v: f32, seed: u64, base: u32, octaves: u32) -> f32 {
    let (mut sum, mut amp, mut total) = (0.0, 1.0, 0.0);
    for o in 0..octaves {
        let cells = base << o;
        sum += amp * value_noise(u * cells as f32, v * cells as f32, cells, seed + o as u64);
        total += amp;
        amp *= 0.5;
    }
    sum / total
}

fn value_noise(x: f32, y: f32, period: u32, seed: u64) -> f32 {
    let (xi, yi) = (x.floor(), y.floor());
    let (fx, fy) = (x - xi, y - yi);
    let (sx, sy) = (fx * fx * (3.0 - 2.0 * fx), fy * fy * (3.0 - 2.0 * fy));
    let at = |dx: i64, dy: i64| {
        let cx = (xi as i64 + dx).rem_euclid(period as i64) as u64;
        let cy = (yi as i64 + dy) as u64;
        (splitmix(seed ^ (cx << 32) ^ cy.wrapping_mul(0x632b_e59b_d9b4_e019)) >> 40) as f32
            / (1u64 << 24) as f32
    };
    let top = at(0, 0) + sx * (at(1, 0) - at(0, 0));
    let bottom = at(0, 1) + sx * (at(1, 1) - at(0, 1));
    top + sy * (bottom - top)
}

fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mask_is_clear_at_v0_opaque_at_v1_and_wraps_in_u() {
        let m = boundary_mask(MASK_SIZE, 1);
        let row_alpha = |y: u32| {
            (0..MASK_SIZE)
                .map(|x| m.get_pixel(x, y).0[3] as f64)
                .sum::<f64>()
                / MASK_SIZE as f64
        };
        assert!(row_alpha(0) < 5.0, "{}", row_alpha(0));
        assert!(row_alpha(MASK_SIZE - 1) > 250.0);
        let mid = row_alpha(MASK_SIZE / 2);
        assert!(mid > 40.0 && mid < 215.0, "{mid}");
        // The first and last columns are neighbours: their alpha differs little.
        let seam: f64 = (0..MASK_SIZE)
            .map(|y| {
                (m.get_pixel(0, y).0[3] as f64 - m.get_pixel(MASK_SIZE - 1, y).0[3] as f64).abs()
            })
            .sum::<f64>()
            / MASK_SIZE as f64;
        assert!(seam < 20.0, "{seam}");
        assert_eq!(m, boundary_mask(MASK_SIZE, 1));
    }
}
