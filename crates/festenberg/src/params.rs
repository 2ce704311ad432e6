//! Parameters of the diffusion snow cover, with units and the defaults of von Festenberg &
//! Gumhold 2011. Lengths the user leaves unset are resolved from the horizontal scene diameter
//! `D` (the diagonal of the scene's footprint), as the paper gives them:
//! - kernel radius `R` = 5 % of `D` (Section 5.2: "we found R as 5 % of the scene diameter to
//!   be appropriate");
//! - maximum bridge length `bmax` = 3 % of `D` (Section 5.1: "bmax = 3 % of the scene diameter
//!   is realistic");
//! - initial snow height `h0` = 2 % of `D`: the paper gives no figure, but says `bmax` "should
//!   be about half as large as the maximum snow height"; with the clipping of Eq. 6 the
//!   kernel's heights reach up to `2 h0`, so `h0` of 2 % gives a maximum of 4 % ≈ `bmax` / 0.75;
//! - column spacing: the longer horizontal side over 256 columns (Table 1's depth textures are
//!   83 to 300 columns across).

use crate::error::{FestenbergError, invalid};
use serde::{Deserialize, Serialize};

/// Most columns one kernel cylinder may hold (the cost per site is proportional to it).
pub const MAX_KERNEL_COLUMNS: usize = 200_000;

/// Default kernel radius, share of the scene diameter (Section 5.2).
pub const RADIUS_SHARE: f64 = 0.05;
/// Default maximum bridge length, share of the scene diameter (Section 5.1).
pub const BRIDGE_SHARE: f64 = 0.03;
/// Default initial snow height, share of the scene diameter (see the module docs).
pub const DEPTH_SHARE: f64 = 0.02;
/// Default number of columns along the longer horizontal side.
pub const COLUMNS_ALONG: f64 = 256.0;

/// What the user asks for; `None` lengths are resolved from the scene diameter.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CoverParams {
    /// Initial snow height `h0`, metres (Section 5.2).
    pub depth_m: Option<f64>,
    /// Kernel radius `R`, metres (Eq. 5).
    pub radius_m: Option<f64>,
    /// Maximum bridge length `bmax`, metres (Section 5.1); 0 disables bridges.
    pub bridge_m: Option<f64>,
    /// Offset boundary vertices outwards by `g2` (Eq. 8, Section 5.3).
    pub overhang: bool,
    /// Largest overhang offset, metres (the peak of `|g2|` scaled; default `h0`): the paper
    /// leaves the length "up to the designer".
    pub overhang_m: Option<f64>,
    /// Column spacing of the height-span map, metres.
    pub resolution_m: Option<f64>,
    /// Length on the snow of one repeat of the boundary alpha mask, metres (default `h0`):
    /// the paper ties it to "the size of single snowflakes" (Section 6).
    pub mask_scale_m: Option<f64>,
    /// Horizontal extent `[x_min, y_min, x_max, y_max]` of the height-span map, scene
    /// metres; `None`: the scene's bounds with two empty columns around them.
    pub extent_m: Option<[f64; 4]>,
}

/// Every length fixed, metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Resolved {
    /// Horizontal scene diameter `D` the defaults were taken from.
    pub diameter_m: f64,
    pub depth_m: f64,
    pub radius_m: f64,
    pub bridge_m: f64,
    /// `None` without overhangs.
    pub overhang_m: Option<f64>,
    pub resolution_m: f64,
    pub mask_scale_m: f64,
}

impl CoverParams {
    /// Checks the values the user set, before any scene is read: lengths finite and > 0 (a
    /// bridge length >= 0), an extent finite with its minimum below its maximum.
    pub fn validate(&self) -> Result<(), FestenbergError> {
        for (name, v) in [
            ("depth (h0)", self.depth_m),
            ("kernel radius (R)", self.radius_m),
            ("overhang length", self.overhang_m),
            ("resolution", self.resolution_m),
            ("mask scale", self.mask_scale_m),
        ] {
            if let Some(v) = v
                && !(v.is_finite() && v > 0.0)
            {
                return Err(invalid(name, v, "a finite length > 0 m"));
            }
        }
        if let Some(b) = self.bridge_m
            && !(b.is_finite() && b >= 0.0)
        {
            return Err(invalid("bridge length (bmax)", b, "a finite length >= 0 m"));
        }
        if let Some(e) = self.extent_m
            && !(e.iter().all(|v| v.is_finite()) && e[0] < e[2] && e[1] < e[3])
        {
            return Err(FestenbergError::InvalidParameter {
                name: "extent",
                value: format!("{e:?}"),
                expected: "[x_min, y_min, x_max, y_max], finite, min < max",
            });
        }
        Ok(())
    }

    /// Fixes every length for a scene whose footprint is `size_x` by `size_y` metres.
    pub fn resolve(&self, size_x: f64, size_y: f64) -> Result<Resolved, FestenbergError> {
        if !(size_x.is_finite() && size_y.is_finite() && size_x.max(size_y) > 0.0) {
            return Err(FestenbergError::InvalidParameter {
                name: "scene footprint",
                value: format!("{size_x} x {size_y} m"),
                expected: "a scene with a horizontal extent (not a vertical sliver)",
            });
        }
        let d = (size_x * size_x + size_y * size_y).sqrt();
        let positive = |name: &'static str, v: Option<f64>, default: f64| match v {
            Some(v) if !(v.is_finite() && v > 0.0) => {
                Err(invalid(name, v, "a finite length > 0 m"))
            }
            Some(v) => Ok(v),
            None => Ok(default),
        };
        let depth_m = positive("depth (h0)", self.depth_m, DEPTH_SHARE * d)?;
        let radius_m = positive("kernel radius (R)", self.radius_m, RADIUS_SHARE * d)?;
        let resolution_m = positive(
            "resolution",
            self.resolution_m,
            size_x.max(size_y) / COLUMNS_ALONG,
        )?;
        let mask_scale_m = positive("mask scale", self.mask_scale_m, depth_m)?;
        let bridge_m = match self.bridge_m {
            Some(b) if !(b.is_finite() && b >= 0.0) => {
                return Err(invalid("bridge length (bmax)", b, "a finite length >= 0 m"));
            }
            Some(b) => b,
            None => BRIDGE_SHARE * d,
        };
        let overhang_m = if self.overhang {
            Some(positive("overhang length", self.overhang_m, depth_m)?)
        } else {
            None
        };
        let rc = radius_m / resolution_m;
        let columns = (std::f64::consts::PI * rc * rc).ceil();
        if columns > MAX_KERNEL_COLUMNS as f64 {
            return Err(FestenbergError::KernelTooLarge {
                radius_m,
                resolution_m,
                columns: columns as usize,
                max: MAX_KERNEL_COLUMNS,
            });
        }
        Ok(Resolved {
            diameter_m: d,
            depth_m,
            radius_m,
            bridge_m,
            overhang_m,
            resolution_m,
            mask_scale_m,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_follow_the_scene_diameter() {
        let r = CoverParams::default().resolve(3.0, 4.0).unwrap();
        assert!((r.diameter_m - 5.0).abs() < 1e-12);
        assert!((r.radius_m - 0.25).abs() < 1e-12);
        assert!((r.bridge_m - 0.15).abs() < 1e-12);
        assert!((r.depth_m - 0.1).abs() < 1e-12);
        assert!((r.resolution_m - 4.0 / 256.0).abs() < 1e-12);
        assert_eq!(r.overhang_m, None);
    }

    #[test]
    fn bad_values_are_named() {
        let p = CoverParams {
            radius_m: Some(-1.0),
            ..Default::default()
        };
        let e = p.resolve(1.0, 1.0).unwrap_err().to_string();
        assert!(e.contains("-1") && e.contains("radius"), "{e}");
        let p = CoverParams {
            radius_m: Some(10.0),
            resolution_m: Some(0.001),
            ..Default::default()
        };
        assert!(matches!(
            p.resolve(1.0, 1.0),
            Err(FestenbergError::KernelTooLarge { .. })
        ));
        assert!(CoverParams::default().resolve(0.0, 0.0).is_err());
    }
}
