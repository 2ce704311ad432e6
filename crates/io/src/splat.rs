//! Splat (layer mask) maps: an RGBA8 PNG whose channels give each snow layer's share of the
//! total snow depth, for terrain material blending in game engines and DCC tools.
//!
//! Convention: R = compacted, G = stable, B = unstable, A = powder (the layers of Cordonnier
//! et al. 2018, Section 3, bottom to top). Each channel is `round(255 * layer / total)` where
//! `total` is the sum of the four layers; cells without snow (total <= 0, or not finite) and
//! nodata cells are (0, 0, 0, 0). So the channels of a snowy cell sum to 255 (give or take
//! rounding), and "no snow at all" is told apart by a zero sum. Negative layer values (which
//! the terrain invariants forbid) count as zero. Row 0 of the image is the northern edge.

use crate::error::Result;
use crate::png16::write_png_pixels;
use image::ExtendedColorType;
use snowscape_terrain::{LayeredTerrain, SnowLayer};
use std::path::Path;

/// The four channel values of one cell.
fn shares(depths: [f32; 4]) -> [u8; 4] {
    let d = depths.map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 });
    let total: f32 = d.iter().sum();
    if total.is_finite() && total > 0.0 {
        d.map(|v| (255.0 * v / total).round().clamp(0.0, 255.0) as u8)
    } else {
        [0; 4]
    }
}

/// Writes the splat map of `terrain` as an RGBA8 PNG, atomically (see the module docs for the
/// channel convention).
pub fn write_splat(path: &Path, terrain: &LayeredTerrain) -> Result<()> {
    let g = terrain.geometry();
    let mut pixels = Vec::with_capacity(g.len() * 4);
    for i in 0..g.len() {
        let px = if terrain.mask().is_valid(i) {
            shares(SnowLayer::ALL.map(|l| terrain.layer(l)[i]))
        } else {
            [0; 4]
        };
        pixels.extend_from_slice(&px);
    }
    write_png_pixels(
        path,
        (g.width(), g.height()),
        &pixels,
        ExtendedColorType::Rgba8,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_sum_to_255_and_zero_without_snow() {
        assert_eq!(shares([1.0, 1.0, 0.0, 2.0]), [64, 64, 0, 128]);
        assert_eq!(shares([0.0; 4]), [0; 4]);
        assert_eq!(shares([0.0, 0.0, 0.0, 0.3]), [0, 0, 0, 255]);
        assert_eq!(shares([f32::NAN, -1.0, 0.0, 1.0]), [0, 0, 0, 255]);
        let s = shares([0.1, 0.2, 0.3, 0.4]);
        let sum: u32 = s.iter().map(|&v| u32::from(v)).sum();
        assert!((254..=256).contains(&sum), "{s:?}");
    }
}
