//! Snow overhangs (von Festenberg & Gumhold 2011, Section 5.3, Eq. 8): a post-processing
//! offset `g2(r)` added horizontally to the snow mesh's vertices,
//! `|g2(r)| = (1 - r)² (1 - (1 - r)²)`, "in the smoothed direction of r where r points towards
//! the closest boundary". It vanishes at the edge (`r = 0`, the snow still meets the ground
//! there) and away from edges (`r = 1`), and peaks at `1/4` at `r = 1 - 1/√2`: the rim of the
//! snow leans out over the edge like the "wad-like view of fresh snow". The paper leaves the
//! length "up to the designer": here the peak offset is `overhang_m` (so `4·|g2|·overhang_m`).
//!
//! Bridges: the paper also bends bridges inwards "using (8) with r mapped on [-1..1]"; our
//! bridges get that look from their parabolic base and lowered initial height instead
//! ([`crate::bridges`]).

use crate::kernel::KernelField;

/// `|g2(r)|` of Eq. 8 (0 at r = 0 and r = 1, at most 1/4).
#[inline]
pub fn g2(r: f32) -> f32 {
    let q = (1.0 - r.clamp(0.0, 1.0)).powi(2);
    q * (1.0 - q)
}

/// Horizontal offset (x east, y north, metres) of every site's snow vertex; zero where the
/// site holds no snow or has no boundary within the kernel.
pub fn offsets(kernel: &KernelField, overhang_m: f32) -> Vec<[f32; 2]> {
    kernel
        .edge
        .iter()
        .zip(&kernel.towards_edge)
        .zip(&kernel.height)
        .map(|((&r, d), &h)| {
            if h <= 0.0 {
                return [0.0; 2];
            }
            let len = 4.0 * g2(r) * overhang_m;
            [d[0] * len, d[1] * len]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn g2_vanishes_at_both_ends_and_peaks_at_a_quarter() {
        assert_eq!(g2(0.0), 0.0);
        assert_eq!(g2(1.0), 0.0);
        let peak = 1.0 - std::f32::consts::FRAC_1_SQRT_2;
        assert!((g2(peak) - 0.25).abs() < 1e-6);
        assert!(g2(0.1) < 0.25 && g2(0.5) < 0.25);
    }
}
