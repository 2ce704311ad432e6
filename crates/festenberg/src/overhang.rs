//! Snow overhangs (von Festenberg & Gumhold 2011, Section 5.3, Eq. 8): a post-processing
//! offset `g2(r)` added horizontally to the snow mesh's vertices,
//! `|g2(r)| = (1 - r)² (1 - (1 - r)²)`, "in the smoothed direction of r where r points towards
//! the closest boundary". It vanishes at the edge (`r = 0`, the snow still meets the ground
//! there) and away from edges (`r = 1`), and peaks at `1/4` at `r = 1 - 1/√2`: the rim of the
//! snow leans out over the edge like the "wad-like view of fresh snow". The paper leaves the
//! length "up to the designer": here the peak offset is `overhang_m` (so `4·|g2|·overhang_m`).
//!
//! Bridges: "bridges are given a more realistic look by using (8) with r mapped on [-1..1];
//! this makes the snow height bended inwards at bridges". We read it as the offset turned
//! round on bridge sites, scaled by their distance coefficient `d` (0 at a support, 1 in the
//! middle, [`crate::bridges`]): `-4·|g2(r)|·d·overhang_m`, so the rims of a bridge curve in
//! towards its middle (a waisted bridge) instead of leaning out over the gap.

use crate::kernel::KernelField;

/// `|g2(r)|` of Eq. 8 (0 at r = 0 and r = 1, at most 1/4).
#[inline]
pub fn g2(r: f32) -> f32 {
    let q = (1.0 - r.clamp(0.0, 1.0)).powi(2);
    q * (1.0 - q)
}

/// Horizontal offset (x east, y north, metres) of every site's snow vertex; zero where the
/// site holds no snow or has no boundary within the kernel.
/// `bridge` is each site's bridge coefficient (negative on ordinary sites).
pub fn offsets(kernel: &KernelField, bridge: &[f32], overhang_m: f32) -> Vec<[f32; 2]> {
    kernel
        .edge
        .iter()
        .zip(&kernel.towards_edge)
        .zip(&kernel.height)
        .zip(bridge)
        .map(|(((&r, d), &h), &b)| {
            if h <= 0.0 {
                return [0.0; 2];
            }
            let mut len = 4.0 * g2(r) * overhang_m;
            if b >= 0.0 {
                len *= -b;
            }
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

    #[test]
    fn rims_lean_out_and_bridges_curve_in() {
        let r = 1.0 - std::f32::consts::FRAC_1_SQRT_2;
        let k = KernelField {
            height: vec![0.1, 0.1, 0.0, 0.1],
            edge: vec![r, r, r, 1.0],
            towards_edge: vec![[1.0, 0.0]; 4],
            visibility: vec![1.0; 4],
            change: vec![0.0; 4],
            members_visited: 0,
        };
        let o = offsets(&k, &[-1.0, 0.5, -1.0, -1.0], 2.0);
        assert!((o[0][0] - 2.0).abs() < 1e-5, "peak offset: {:?}", o[0]);
        assert!((o[1][0] + 1.0).abs() < 1e-5, "bridge half-way: {:?}", o[1]);
        assert_eq!(o[2], [0.0, 0.0], "no snow, no offset");
        assert_eq!(o[3], [0.0, 0.0], "far from edges");
    }
}
