//! The palette: what colour a cell's ground, snow, snow layers, stability and map values get.
//!
//! Colours are sRGB components in [0, 1] (the values written to the image), before lighting.
//!
//! - Ground (no snow): a hypsometric tint by altitude relative to the terrain's range (green
//!   vegetation low, olive and brown in the middle, grey rock high), darkened towards
//!   [`CLIFF_ROCK`] on slopes between [`CLIFF_SLOPE_START_DEG`] and [`CLIFF_SLOPE_FULL_DEG`].
//! - Snow: [`SNOW_WHITE`] laid over the ground with a coverage that grows with depth and is
//!   complete at [`FULL_COVER_DEPTH_M`] (thin cover lets the ground show through).
//! - Layers: the thickness-weighted mean of the four layer colours
//!   ([`LAYER_COLOURS`]: compacted blue-grey, stable white, unstable orange-red, powder light cyan).
//! - Stability (Cordonnier et al. 2018, Fig. 11): "when present, unstable and powdery snow are
//!   shown in purple on top of compacted and stable snow in blue. Regions with no snow are in
//!   black."
//! - Maps: a viridis ramp ([`VIRIDIS`], 11 stops) over the map's own value range.

/// An sRGB colour, components in [0, 1].
pub type Rgb = [f32; 3];

/// Fresh snow.
pub const SNOW_WHITE: Rgb = [0.97, 0.98, 1.0];
/// Snow depth (metres) at which snow hides the ground completely.
pub const FULL_COVER_DEPTH_M: f32 = 0.3;
/// Dark rock of cliffs.
pub const CLIFF_ROCK: Rgb = [0.30, 0.29, 0.28];
/// Slope (degrees) where ground starts darkening towards cliff rock.
pub const CLIFF_SLOPE_START_DEG: f32 = 35.0;
/// Slope (degrees) at and above which ground is cliff rock.
pub const CLIFF_SLOPE_FULL_DEG: f32 = 55.0;

/// Hypsometric ground tint: (relative altitude in [0, 1], colour), low to high.
pub const GROUND_RAMP: [(f32, Rgb); 5] = [
    (0.0, [0.33, 0.42, 0.22]),  // meadow and forest green
    (0.3, [0.45, 0.44, 0.28]),  // olive
    (0.6, [0.50, 0.44, 0.36]),  // brown scree
    (0.85, [0.56, 0.54, 0.52]), // grey rock
    (1.0, [0.66, 0.65, 0.64]),  // light grey summits
];

/// Layer tints, indexed by `SnowLayer::index`: compacted, stable, unstable, powder.
pub const LAYER_COLOURS: [Rgb; 4] = [
    [0.56, 0.63, 0.74], // compacted: blue-grey
    [0.97, 0.98, 1.0],  // stable: white
    [0.93, 0.42, 0.18], // unstable: orange-red
    [0.70, 0.90, 1.0],  // powder: light cyan
];

/// Fig. 11: compacted and stable snow.
pub const STABILITY_BLUE: Rgb = [0.18, 0.38, 0.85];
/// Fig. 11: unstable and powdery snow, on top.
pub const STABILITY_PURPLE: Rgb = [0.60, 0.20, 0.72];
/// Fig. 11: no snow.
pub const STABILITY_BLACK: Rgb = [0.0, 0.0, 0.0];
/// Thickness (metres) at which a layer counts as fully "present" in the stability map; thinner
/// layers are blended in proportionally so the map has no aliasing at snow edges.
pub const STABILITY_PRESENT_DEPTH_M: f32 = 0.02;

/// Viridis (matplotlib) sampled at 0, 0.1, ..., 1.
pub const VIRIDIS: [Rgb; 11] = [
    [0.267, 0.005, 0.329],
    [0.283, 0.141, 0.458],
    [0.254, 0.265, 0.530],
    [0.207, 0.372, 0.553],
    [0.164, 0.471, 0.558],
    [0.128, 0.567, 0.551],
    [0.135, 0.659, 0.518],
    [0.267, 0.749, 0.441],
    [0.478, 0.821, 0.3182],
    [0.741, 0.873, 0.150],
    [0.993, 0.906, 0.144],
];

/// `a + (b - a) t`, per channel.
#[inline]
pub fn mix(a: Rgb, b: Rgb, t: f32) -> Rgb {
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

/// Hermite smoothstep of `x` between `e0` and `e1`.
#[inline]
fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Piecewise-linear lookup in a ramp of (position, colour) stops sorted by position.
fn ramp_lookup(stops: &[(f32, Rgb)], t: f32) -> Rgb {
    let t = if t.is_finite() { t } else { 0.0 };
    let mut prev = stops[0];
    if t <= prev.0 {
        return prev.1;
    }
    for &stop in &stops[1..] {
        if t <= stop.0 {
            return mix(prev.1, stop.1, (t - prev.0) / (stop.0 - prev.0));
        }
        prev = stop;
    }
    prev.1
}

/// Ground colour at `relative_altitude` (0 = lowest cell, 1 = highest) on a slope given by its
/// cosine (the up component of the unit normal; 1 on flat ground).
pub fn ground_colour(relative_altitude: f32, cos_slope: f32) -> Rgb {
    let tint = ramp_lookup(&GROUND_RAMP, relative_altitude);
    // Smoothstep over the tangent of the slope, tan² = 1/cos² - 1 (no trigonometry per cell).
    let tan2 = |deg: f32| deg.to_radians().tan().powi(2);
    let c2 = (cos_slope * cos_slope).max(1e-12);
    let cliff = smoothstep(
        tan2(CLIFF_SLOPE_START_DEG),
        tan2(CLIFF_SLOPE_FULL_DEG),
        1.0 / c2 - 1.0,
    );
    mix(tint, CLIFF_ROCK, cliff)
}

/// Fraction of the ground hidden by `depth_m` metres of snow: 0 without snow, rising quickly
/// (ease-out) to 1 at [`FULL_COVER_DEPTH_M`].
#[inline]
pub fn snow_cover(depth_m: f32) -> f32 {
    if depth_m.is_nan() || depth_m <= 0.0 {
        return 0.0;
    }
    let t = (depth_m / FULL_COVER_DEPTH_M).min(1.0);
    t * (2.0 - t)
}

/// Thickness-weighted mean of the layer colours; white when every layer is empty.
pub fn layer_tint(layers: [f32; 4]) -> Rgb {
    let total: f32 = layers.iter().map(|v| v.max(0.0)).sum();
    if total <= 0.0 || total.is_nan() {
        return SNOW_WHITE;
    }
    let mut rgb = [0.0f32; 3];
    for (thickness, colour) in layers.iter().zip(LAYER_COLOURS) {
        let w = thickness.max(0.0) / total;
        for k in 0..3 {
            rgb[k] += w * colour[k];
        }
    }
    rgb
}

/// The Fig. 11 stability colour of a cell with these layer thicknesses (compacted, stable,
/// unstable, powder; metres): black without snow, blue for compacted and stable snow, purple
/// where unstable or powdery snow lies on top.
pub fn stability_rgb(layers: [f32; 4]) -> Rgb {
    let [compacted, stable, unstable, powder] = layers.map(|v| v.max(0.0));
    let total = compacted + stable + unstable + powder;
    if total <= 0.0 || total.is_nan() {
        return STABILITY_BLACK;
    }
    let on_top = ((unstable + powder) / STABILITY_PRESENT_DEPTH_M).min(1.0);
    let snow = mix(STABILITY_BLUE, STABILITY_PURPLE, on_top);
    mix(
        STABILITY_BLACK,
        snow,
        (total / STABILITY_PRESENT_DEPTH_M).min(1.0),
    )
}

/// The viridis colour of `t` in [0, 1] (clamped; NaN reads as 0).
pub fn viridis(t: f32) -> Rgb {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (VIRIDIS.len() - 1) as f32;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    mix(VIRIDIS[i], VIRIDIS[i + 1], x - i as f32)
}

/// Rounds a [0, 1] colour to bytes (clamping; NaN becomes 0).
#[inline]
pub fn to_bytes(rgb: Rgb) -> [u8; 3] {
    #[inline(always)]
    fn byte(v: f32) -> u8 {
        // A NaN stays NaN through clamp and casts to 0.
        (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
    }
    [byte(rgb[0]), byte(rgb[1]), byte(rgb[2])]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cover_grows_with_depth_and_saturates() {
        assert_eq!(snow_cover(0.0), 0.0);
        assert_eq!(snow_cover(-1.0), 0.0);
        assert!(snow_cover(0.05) > 0.0 && snow_cover(0.05) < snow_cover(0.1));
        assert_eq!(snow_cover(FULL_COVER_DEPTH_M), 1.0);
        assert_eq!(snow_cover(5.0), 1.0);
    }

    #[test]
    fn ground_gets_greyer_with_altitude_and_darker_on_cliffs() {
        let low = ground_colour(0.0, 1.0);
        let high = ground_colour(1.0, 1.0);
        assert!(low[1] > low[2] + 0.1, "low ground is green: {low:?}");
        assert!(
            (high[0] - high[2]).abs() < 0.05,
            "high ground is grey: {high:?}"
        );
        let cliff = ground_colour(0.5, 70f32.to_radians().cos());
        assert_eq!(
            ground_colour(0.5, 30f32.to_radians().cos()),
            ground_colour(0.5, 1.0)
        );
        assert_eq!(cliff, CLIFF_ROCK);
    }

    #[test]
    fn stability_follows_figure_11() {
        assert_eq!(stability_rgb([0.0; 4]), STABILITY_BLACK);
        assert_eq!(stability_rgb([0.5, 0.5, 0.0, 0.0]), STABILITY_BLUE);
        assert_eq!(stability_rgb([0.5, 0.5, 0.1, 0.0]), STABILITY_PURPLE);
        assert_eq!(stability_rgb([0.0, 0.0, 0.0, 0.3]), STABILITY_PURPLE);
    }

    #[test]
    fn layer_tint_is_weighted_by_thickness() {
        assert_eq!(layer_tint([0.0, 0.0, 1.0, 0.0]), LAYER_COLOURS[2]);
        let half = layer_tint([1.0, 1.0, 0.0, 0.0]);
        let expect = mix(LAYER_COLOURS[0], LAYER_COLOURS[1], 0.5);
        for k in 0..3 {
            assert!((half[k] - expect[k]).abs() < 1e-6);
        }
    }

    #[test]
    fn bytes_round_and_clamp() {
        assert_eq!(to_bytes([0.0, 1.0, 0.5]), [0, 255, 128]);
        assert_eq!(to_bytes([-3.0, 7.0, f32::NAN]), [0, 255, 0]);
    }

    #[test]
    fn viridis_ends_and_clamps() {
        assert_eq!(viridis(0.0), VIRIDIS[0]);
        assert_eq!(viridis(1.0), VIRIDIS[10]);
        assert_eq!(viridis(7.0), VIRIDIS[10]);
        assert_eq!(viridis(f32::NAN), VIRIDIS[0]);
        // Perceptual ramp: brightness rises monotonically.
        let luma = |c: Rgb| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        for k in 0..20 {
            let (a, b) = (k as f32 / 20.0, (k + 1) as f32 / 20.0);
            assert!(luma(viridis(a)) < luma(viridis(b)));
        }
    }
}
