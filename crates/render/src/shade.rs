//! Lighting of a height field: the sun direction, Lambert plus sky illumination, and cast
//! shadows found by one sweep along the sun azimuth.
//!
//! Illumination of a cell with unit normal `n` (x east, y north, z up) is
//! `SKY_STRENGTH · (0.5 + 0.5 n_z) · SKY_COLOUR + SUN_STRENGTH · max(0, n·s) · v · SUN_COLOUR`,
//! where `s` is the unit vector towards the sun and `v` in [0, 1] its visibility (0 in a cast
//! shadow). The sky term is a hemispherical ambient light, dimmer on steep walls.

use crate::colour::Rgb;

/// Ambient (sky) light strength.
pub const SKY_STRENGTH: f32 = 0.4;
/// Sky light colour: slightly blue, so shadowed snow reads blue-white as in nature.
pub const SKY_COLOUR: Rgb = [0.86, 0.92, 1.0];
/// Direct sun light strength.
pub const SUN_STRENGTH: f32 = 0.95;
/// Sun light colour: slightly warm.
pub const SUN_COLOUR: Rgb = [1.0, 0.97, 0.92];

/// Unit vector towards the sun (x east, y north, z up) for an azimuth clockwise from north
/// and an elevation above the horizon, both in degrees.
pub fn sun_vector(azimuth_deg: f64, elevation_deg: f64) -> [f32; 3] {
    let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
    [
        (az.sin() * el.cos()) as f32,
        (az.cos() * el.cos()) as f32,
        el.sin() as f32,
    ]
}

/// Light reaching a surface with unit normal `n`, per channel, given the sun visibility.
#[inline]
pub fn illumination(n: [f32; 3], sun: [f32; 3], visibility: f32) -> Rgb {
    let sky = SKY_STRENGTH * (0.5 + 0.5 * n[2]);
    let direct =
        SUN_STRENGTH * (n[0] * sun[0] + n[1] * sun[1] + n[2] * sun[2]).max(0.0) * visibility;
    [
        sky * SKY_COLOUR[0] + direct * SUN_COLOUR[0],
        sky * SKY_COLOUR[1] + direct * SUN_COLOUR[1],
        sky * SKY_COLOUR[2] + direct * SUN_COLOUR[2],
    ]
}

/// The height field seen by the shadow sweep: row-major heights in metres, a validity test,
/// and the metric cell size.
pub struct HeightField<'a> {
    /// Heights (metres), row-major, row 0 north.
    pub z: &'a [f32],
    /// Whether each cell holds data (nodata cells cast no shadow).
    pub valid: &'a dyn Fn(usize) -> bool,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Cell size west-east, metres.
    pub dx: f64,
    /// Cell size north-south, metres.
    pub dy: f64,
}

/// The sweep, in a frame where the sun lies towards lower "lines" and each step back towards
/// the sun moves one line and `offset` positions along the line. Cell `(p, l)` of the frame is
/// grid index `first + l · line_stride + p · pos_stride`.
struct Sweep {
    lines: usize,
    len: usize,
    /// Position shift along a line per step towards the sun.
    offset: f64,
    /// Height the sun ray loses per step away from the sun, metres.
    rise: f32,
    first: isize,
    line_stride: isize,
    pos_stride: isize,
}

fn sweep_frame(field: &HeightField, sun: [f32; 3]) -> Option<Sweep> {
    let horizontal = ((sun[0] * sun[0] + sun[1] * sun[1]) as f64).sqrt();
    if horizontal < 1e-9 || sun[2] <= 0.0 {
        return None;
    }
    let tan_el = sun[2] as f64 / horizontal;
    // Direction towards the sun in cells: +col east, +row south.
    let dc = sun[0] as f64 / field.dx;
    let dr = -(sun[1] as f64) / field.dy;
    let (w, h) = (field.width as isize, field.height as isize);
    Some(if dr.abs() >= dc.abs() {
        // Lines are rows, swept away from the sun; one step towards the sun is one row plus
        // `offset` columns.
        let offset = dc / dr.abs();
        let step = ((offset * field.dx).powi(2) + field.dy.powi(2)).sqrt();
        let north_sun = dr < 0.0;
        Sweep {
            lines: field.height,
            len: field.width,
            offset,
            rise: (step * tan_el) as f32,
            first: if north_sun { 0 } else { (h - 1) * w },
            line_stride: if north_sun { w } else { -w },
            pos_stride: 1,
        }
    } else {
        // Lines are columns; one step towards the sun is one column plus `offset` rows.
        let offset = dr / dc.abs();
        let step = (field.dx.powi(2) + (offset * field.dy).powi(2)).sqrt();
        let west_sun = dc < 0.0;
        Sweep {
            lines: field.width,
            len: field.height,
            offset,
            rise: (step * tan_el) as f32,
            first: if west_sun { 0 } else { w - 1 },
            line_stride: if west_sun { 1 } else { -1 },
            pos_stride: w,
        }
    })
}

/// Occluder heights arriving at every position of a line from the previous line: the previous
/// line's heights at `p + offset` (linear interpolation; `-inf` beyond its ends, since nothing
/// outside the grid casts a shadow), lowered by `rise`.
fn incoming_rays(previous: &[f32], offset: f64, rise: f32, out: &mut [f32]) {
    let n = previous.len() as isize;
    let whole = offset.floor();
    let (shift, frac) = (whole as isize, (offset - whole) as f32);
    for (p, ray) in out.iter_mut().enumerate() {
        let i = p as isize + shift;
        *ray = if i >= 0 && i + 1 < n {
            let (a, b) = (previous[i as usize], previous[i as usize + 1]);
            a + (b - a) * frac - rise
        } else if i == n - 1 && frac == 0.0 {
            previous[i as usize] - rise
        } else {
            f32::NEG_INFINITY
        };
    }
}

/// Sun visibility of every cell in [0, 1]: 0 where terrain between the cell and the sun rises
/// above the sun ray, with a soft edge one step's rise wide (anti-aliasing).
///
/// One sweep in O(cells): lines across the sun direction are processed from the sun side;
/// each cell receives the highest ray `occluder - distance · tan(elevation)` cast by the cells
/// before it (interpolated linearly within the previous line) and passes on the higher of that
/// ray and its own height.
pub fn sun_visibility(field: &HeightField, sun: [f32; 3]) -> Vec<f32> {
    let n = field.width * field.height;
    let mut visibility = vec![1.0f32; n];
    let Some(sweep) = sweep_frame(field, sun) else {
        if sun[2] <= 0.0 {
            visibility.fill(0.0);
        }
        return visibility;
    };
    let mut previous = vec![f32::NEG_INFINITY; sweep.len];
    let mut current = vec![f32::NEG_INFINITY; sweep.len];
    let soft = 1.0 / sweep.rise.max(1e-6);
    for l in 0..sweep.lines {
        if l > 0 {
            incoming_rays(&previous, sweep.offset, sweep.rise, &mut current);
        }
        let start = sweep.first + l as isize * sweep.line_stride;
        for (p, occ) in current.iter_mut().enumerate() {
            let i = (start + p as isize * sweep.pos_stride) as usize;
            let z = field.z[i];
            if !(field.valid)(i) || !z.is_finite() {
                continue; // the ray passes over nodata unchanged
            }
            let excess = *occ - z;
            if excess > 0.0 {
                visibility[i] = (1.0 - excess * soft).max(0.0);
            } else {
                *occ = z;
            }
        }
        std::mem::swap(&mut previous, &mut current);
    }
    visibility
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all_valid(_: usize) -> bool {
        true
    }

    #[test]
    fn sun_vector_points_where_the_azimuth_says() {
        let east = sun_vector(90.0, 0.0);
        assert!((east[0] - 1.0).abs() < 1e-6 && east[1].abs() < 1e-6);
        let south_high = sun_vector(180.0, 60.0);
        assert!(south_high[1] < 0.0 && (south_high[2] - 60f32.to_radians().sin()).abs() < 1e-6);
    }

    #[test]
    fn a_wall_shadows_the_cells_behind_it_for_the_right_length() {
        // 10 m wall across a flat 1 m grid at column 5; sun from the west at 45 degrees:
        // the shadow reaches 10 m (10 cells) east of the wall.
        let (w, h) = (40usize, 6usize);
        let z: Vec<f32> = (0..w * h)
            .map(|i| if i % w == 5 { 10.0 } else { 0.0 })
            .collect();
        let field = HeightField {
            z: &z,
            valid: &all_valid,
            width: w,
            height: h,
            dx: 1.0,
            dy: 1.0,
        };
        let vis = sun_visibility(&field, sun_vector(270.0, 45.0));
        let row = &vis[2 * w..3 * w];
        assert!(row[..6].iter().all(|&v| v == 1.0), "{row:?}");
        assert!(row[6..15].iter().all(|&v| v == 0.0), "{row:?}");
        assert!(row[16..].iter().all(|&v| v == 1.0), "{row:?}");
    }

    #[test]
    fn shadows_follow_a_diagonal_sun_and_rectangular_cells() {
        // A single tall pillar; sun from the north-east. Cells 2 m wide, 1 m tall: the shadow
        // must fall to the south-west, never to the north or east of the pillar.
        let (w, h) = (30usize, 30usize);
        let z: Vec<f32> = (0..w * h)
            .map(|i| if i == 10 * w + 20 { 50.0 } else { 0.0 })
            .collect();
        let field = HeightField {
            z: &z,
            valid: &all_valid,
            width: w,
            height: h,
            dx: 2.0,
            dy: 1.0,
        };
        let vis = sun_visibility(&field, sun_vector(45.0, 30.0));
        let shadowed: Vec<(usize, usize)> = (0..w * h)
            .filter(|&i| vis[i] < 0.5)
            .map(|i| (i % w, i / w))
            .collect();
        assert!(!shadowed.is_empty());
        for &(c, r) in &shadowed {
            assert!(c <= 20 && r >= 10, "shadow at ({c}, {r})");
        }
        // One cell along the exact diagonal direction (2 m west = 1 col, 2 m south = 2 rows).
        assert!(vis[12 * w + 19] < 0.5);
    }

    /// Shadowed by marching a ray towards the sun (quarter-cell steps, bilinear heights).
    fn marched_shadow(
        z: &[f32],
        w: usize,
        h: usize,
        d: (f64, f64),
        sun: [f32; 3],
        i: usize,
    ) -> bool {
        let sample = |c: f64, r: f64| {
            let (c0, r0) = (c.floor() as usize, r.floor() as usize);
            let (c1, r1) = ((c0 + 1).min(w - 1), (r0 + 1).min(h - 1));
            let (fc, fr) = ((c - c0 as f64) as f32, (r - r0 as f64) as f32);
            let top = z[r0 * w + c0] * (1.0 - fc) + z[r0 * w + c1] * fc;
            let bottom = z[r1 * w + c0] * (1.0 - fc) + z[r1 * w + c1] * fc;
            top * (1.0 - fr) + bottom * fr
        };
        let horizontal = (sun[0] as f64).hypot(sun[1] as f64);
        let tan_el = sun[2] as f64 / horizontal;
        let (dc, dr) = (
            sun[0] as f64 / horizontal / d.0,
            -(sun[1] as f64) / horizontal / d.1,
        );
        let (c0, r0) = ((i % w) as f64, (i / w) as f64);
        let step = 0.25 / dc.abs().max(dr.abs());
        let mut t = step;
        loop {
            let (c, r) = (c0 + t * dc, r0 + t * dr);
            if c < 0.0 || r < 0.0 || c > (w - 1) as f64 || r > (h - 1) as f64 {
                return false;
            }
            if sample(c, r) as f64 > z[i] as f64 + t * tan_el + 0.05 {
                return true;
            }
            t += step;
        }
    }

    #[test]
    fn the_sweep_agrees_with_ray_marching() {
        let (w, h, d) = (90usize, 70usize, (3.0, 2.0));
        let z: Vec<f32> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 * 3.0, (i / w) as f32 * 2.0);
                40.0 * (x / 37.0).sin() * (y / 23.0).cos() + 25.0 * ((x + y) / 19.0).sin()
            })
            .collect();
        let field = HeightField {
            z: &z,
            valid: &all_valid,
            width: w,
            height: h,
            dx: d.0,
            dy: d.1,
        };
        for (az, el) in [(123.0, 25.0), (300.0, 15.0), (10.0, 35.0), (250.0, 20.0)] {
            let sun = sun_vector(az, el);
            let vis = sun_visibility(&field, sun);
            let marched: Vec<bool> = (0..w * h)
                .map(|i| marched_shadow(&z, w, h, d, sun, i))
                .collect();
            let share = marched.iter().filter(|&&m| m).count() as f64 / (w * h) as f64;
            assert!(
                (0.05..0.75).contains(&share),
                "azimuth {az}: {share} in shadow"
            );
            // Away from shadow edges (all 8 neighbours alike), the two must agree exactly;
            // on edges the sweep's interpolation may shift the boundary by one cell.
            let (mut interior, mut wrong) = (0, 0);
            for r in 1..h - 1 {
                for c in 1..w - 1 {
                    let i = r * w + c;
                    let edge =
                        (0..9).any(|k| marched[(r + k / 3 - 1) * w + c + k % 3 - 1] != marched[i]);
                    if !edge {
                        interior += 1;
                        wrong += usize::from(marched[i] != (vis[i] < 0.5));
                    }
                }
            }
            assert!(
                wrong * 200 < interior,
                "azimuth {az}: {wrong} of {interior} interior cells differ"
            );
        }
    }

    #[test]
    fn a_flat_plane_is_fully_lit() {
        let z = vec![100.0f32; 64];
        let field = HeightField {
            z: &z,
            valid: &all_valid,
            width: 8,
            height: 8,
            dx: 5.0,
            dy: 5.0,
        };
        for az in [0.0, 33.0, 135.0, 200.0, 315.0] {
            let vis = sun_visibility(&field, sun_vector(az, 10.0));
            assert!(vis.iter().all(|&v| v == 1.0), "azimuth {az}");
        }
    }
}
