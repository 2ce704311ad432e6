//! The finite-difference operators of the workspace: one stencil family, as small named
//! functions in `f32` and `f64` (after Oceananigans' `Operators/`). Every gradient, slope,
//! aspect, normal and terrain curvature of the crates is built from these; a kernel that needs
//! a vectorised or padded form (the avalanche flow, the season's row kernels) writes the same
//! stencil with [`interior_difference`] and states so.
//!
//! **Axes, stated once.** A grid's column index grows east and its row index grows south
//! (row 0 is the northern edge, as in GeoTIFF). Map gradients are `(∂z/∂x, ∂z/∂y)` with x east
//! and **y north** ([`gradient`]); the local frames that follow the rows (the skiers' and the
//! release areas' metres from the north-west corner) use **y south** ([`gradient_south`]).
//! Aspects are azimuths clockwise from north.
//!
//! **The stencil.** A first derivative is the centred difference
//! `(z₊ − z₋) / (2Δ)`; where a neighbour is missing (off the grid, or nodata) it is replaced by
//! the cell itself and the difference becomes one-sided, `(z₊ − z₀) / Δ`; with both missing it
//! is 0 ([`centred_difference`]). Interior cells of a fast path use `(z₊ − z₋) · 1/(2Δ)`
//! ([`interior_difference`]): the same stencil with the division by a precomputed inverse.
//!
//! **Second derivatives.** [`second_difference`] and [`one_sided_second_difference`] (the
//! wind's erosion curvature, Cordonnier 2018 §5.4), [`quadratic_fit_hessian`] (Evans' 3x3 fit:
//! the bed curvature that loads an avalanche's friction) and [`directional_curvature`] (the
//! mean of Liston & Elder's four directional second differences, 2006 Eq. 5.9, that speeds
//! wind over ridges).

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A floating-point type the operators run in (`f32` or `f64`).
pub trait Real:
    Copy
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// Square root.
    fn sqrt(self) -> Self;
    /// Arc tangent.
    fn atan(self) -> Self;
    /// Four-quadrant arc tangent of `self / x`.
    fn atan2(self, x: Self) -> Self;
}

macro_rules! real {
    ($t:ty) => {
        impl Real for $t {
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            #[inline(always)]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline(always)]
            fn atan(self) -> Self {
                <$t>::atan(self)
            }
            #[inline(always)]
            fn atan2(self, x: Self) -> Self {
                <$t>::atan2(self, x)
            }
        }
    };
}
real!(f32);
real!(f64);

/// First derivative along one axis from the neighbours before (`minus`) and after (`plus`) a
/// cell of value `centre`, `spacing` apart: `(plus − minus) / (2·spacing)`, one-sided where a
/// neighbour is `None` (replaced by `centre`), 0 where both are.
#[inline(always)]
pub fn centred_difference<T: Real>(minus: Option<T>, centre: T, plus: Option<T>, spacing: T) -> T {
    let (zm, wm) = minus.map_or((centre, T::ZERO), |z| (z, T::ONE));
    let (zp, wp) = plus.map_or((centre, T::ZERO), |z| (z, T::ONE));
    if wm + wp > T::ZERO {
        (zp - zm) / ((wm + wp) * spacing)
    } else {
        T::ZERO
    }
}

/// The centred difference of an interior cell with both neighbours present, by the inverse
/// of twice the spacing: `(plus − minus) · half_inverse_spacing`. Generic over any type with
/// `−` and `×`, so vector lanes (the avalanche flow's SIMD kernels) use it too.
#[inline(always)]
pub fn interior_difference<T: Sub<Output = T> + Mul<Output = T>>(
    minus: T,
    plus: T,
    half_inverse_spacing: T,
) -> T {
    (plus - minus) * half_inverse_spacing
}

/// The gradient `(∂z/∂x, ∂z/∂y)`, x east and y north, of a field read by `at(dc, dr)` (the
/// value `dc` columns east and `dr` rows south of the cell, `None` where missing), `centre`
/// the cell's own value, cells `dx` by `dy`.
#[inline(always)]
pub fn gradient<T: Real>(
    centre: T,
    at: impl Fn(isize, isize) -> Option<T>,
    dx: T,
    dy: T,
) -> (T, T) {
    let gx = centred_difference(at(-1, 0), centre, at(1, 0), dx);
    let gy = centred_difference(at(0, 1), centre, at(0, -1), dy);
    (gx, gy)
}

/// [`gradient`] in a frame whose y axis points south (along the rows): `(∂z/∂x, ∂z/∂y_south)`.
#[inline(always)]
pub fn gradient_south<T: Real>(
    centre: T,
    at: impl Fn(isize, isize) -> Option<T>,
    dx: T,
    dy: T,
) -> (T, T) {
    // The same stencil with the rows read the other way round.
    gradient(centre, |dc, dr| at(dc, -dr), dx, dy)
}

/// The norm of a gradient, `|∇z|`: the tangent of the slope.
#[inline(always)]
pub fn slope_tangent<T: Real>(gx: T, gy: T) -> T {
    (gx * gx + gy * gy).sqrt()
}

/// The slope angle of a gradient, radians: `atan |∇z|`.
#[inline(always)]
pub fn slope_angle<T: Real>(gx: T, gy: T) -> T {
    slope_tangent(gx, gy).atan()
}

/// The azimuth a slope faces (its aspect: the downhill direction), radians clockwise from
/// north, in [−π, π], of a gradient with y north: `atan2(−∂z/∂x, −∂z/∂y)`. A flat cell has no
/// aspect: it gets 0 or ±π by the signs of its zeros.
#[inline(always)]
pub fn aspect<T: Real>(gx: T, gy: T) -> T {
    (-gx).atan2(-gy)
}

/// The unit upward normal `(nx, ny, nz)` of a gradient (x east, y as the gradient's).
#[inline(always)]
pub fn upward_normal<T: Real>(gx: T, gy: T) -> [T; 3] {
    let inv = T::ONE / (gx * gx + gy * gy + T::ONE).sqrt();
    [-gx * inv, -gy * inv, inv]
}

/// Central second difference `f₋ − 2f₀ + f₊` (divide by the squared spacing).
#[inline(always)]
pub fn second_difference<T: Real>(minus: T, centre: T, plus: T) -> T {
    minus - (T::ONE + T::ONE) * centre + plus
}

/// One-sided second difference at a border cell from itself and the next two cells inwards,
/// `f₀ − 2f₁ + f₂` (the curvature of the nearest full stencil; divide by the squared spacing).
#[inline(always)]
pub fn one_sided_second_difference<T: Real>(own: T, next: T, after: T) -> T {
    own - (T::ONE + T::ONE) * next + after
}

/// The second derivatives `(∂²z/∂x², ∂²z/∂y², ∂²z/∂x∂y)` of Evans' (1979) quadratic fit to a
/// 3x3 window, `rows` north to south and each west to east, with `x` east and `y` south (the
/// rows' direction): `zxx = (Σ west column + Σ east column − 2 Σ middle column)/(3Δx²)`,
/// `zyy` likewise over rows, `zxy = ((se − sw) − (ne − nw))/(4ΔxΔy)`. The inverse factors
/// `1/(3Δx²)`, `1/(3Δy²)` and `1/(4ΔxΔy)` are the caller's (precomputed once). Generic over
/// any type with `+`, `−` and `×`, so vector lanes use it too.
#[inline(always)]
pub fn quadratic_fit_hessian<T>(
    rows: [[T; 3]; 3],
    two: T,
    inv_three_dx2: T,
    inv_three_dy2: T,
    inv_four_dxdy: T,
) -> (T, T, T)
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    let [[nw, n, ne], [w, c, e], [sw, s, se]] = rows;
    let zxx = (((nw + w) + sw) + ((ne + e) + se) - two * ((n + c) + s)) * inv_three_dx2;
    let zyy = (((nw + n) + ne) + ((sw + s) + se) - two * ((w + c) + e)) * inv_three_dy2;
    let zxy = ((se - sw) - (ne - nw)) * inv_four_dxdy;
    (zxx, zyy, zxy)
}

/// Liston & Elder's (2006, Eq. 5.9) terrain curvature of a cell of height `z0`: the mean of
/// the four directional second differences, across the columns, the rows and both
/// diagonals, of the neighbours `k` cells away read by `at(dc, dr)`, each over twice its
/// length (`2η` on the axes, `2√2·η` on the diagonals, `η` the curvature length scale).
#[inline(always)]
pub fn directional_curvature(z0: f64, at: impl Fn(isize, isize) -> f64, k: isize, eta: f64) -> f64 {
    let d = 2.0 * eta;
    let dd = 2.0 * std::f64::consts::SQRT_2 * eta;
    0.25 * ((z0 - 0.5 * (at(-k, 0) + at(k, 0))) / d
        + (z0 - 0.5 * (at(0, k) + at(0, -k))) / d
        + (z0 - 0.5 * (at(-k, k) + at(k, -k))) / dd
        + (z0 - 0.5 * (at(-k, -k) + at(k, k))) / dd)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plane `z = a·x_east + b·y_north` on a 5x4 grid of 2 m by 3 m cells.
    fn plane(c: isize, r: isize) -> f64 {
        0.3 * (c as f64 * 2.0) + 0.7 * (-(r as f64) * 3.0)
    }

    fn on_grid(c: isize, r: isize) -> Option<f64> {
        ((0..5).contains(&c) && (0..4).contains(&r)).then(|| plane(c, r))
    }

    #[test]
    fn a_plane_has_its_gradient_everywhere_borders_included() {
        for r in 0..4 {
            for c in 0..5 {
                let at = |dc, dr| on_grid(c + dc, r + dr);
                let (gx, gy) = gradient(plane(c, r), at, 2.0, 3.0);
                assert!((gx - 0.3).abs() < 1e-12 && (gy - 0.7).abs() < 1e-12);
                let (sx, sy) = gradient_south(plane(c, r), at, 2.0, 3.0);
                assert!((sx - 0.3).abs() < 1e-12 && (sy + 0.7).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn a_cell_without_neighbours_is_flat() {
        assert_eq!(centred_difference(None, 5.0f32, None, 1.0), 0.0);
        assert_eq!(gradient(1.0f64, |_, _| None, 1.0, 1.0), (0.0, 0.0));
    }

    #[test]
    fn the_interior_form_is_the_centred_difference() {
        let (m, p, h) = (1.25f32, 4.5f32, 0.5f32);
        let a = centred_difference(Some(m), 0.0, Some(p), 2.0 * h);
        assert_eq!(a, interior_difference(m, p, 0.5 / (2.0 * h)));
    }

    #[test]
    fn slope_aspect_and_normal_of_a_north_facing_plane() {
        // Height falls to the north (gradient pointing south): the slope faces north.
        let (gx, gy) = (0.0f64, -1.0);
        assert!((slope_angle(gx, gy) - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
        assert!(aspect(gx, gy).abs() < 1e-12);
        // Falling to the east: faces east, azimuth π/2.
        assert!((aspect(-1.0f64, 0.0) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let n = upward_normal(gx, gy);
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        assert!((len - 1.0).abs() < 1e-12 && n[1] > 0.0 && n[2] > 0.0);
    }

    #[test]
    fn second_differences_and_the_fit_of_a_quadratic_are_exact() {
        // z = 3x² − 2y² + 0.5xy on 2 m by 1 m cells (x east, y south).
        let z = |x: f64, y: f64| 3.0 * x * x - 2.0 * y * y + 0.5 * x * y;
        let rows = [-1.0, 0.0, 1.0].map(|r| [-1.0, 0.0, 1.0].map(|c| z(2.0 * c, r)));
        let (zxx, zyy, zxy) = quadratic_fit_hessian(rows, 2.0, 1.0 / 12.0, 1.0 / 3.0, 1.0 / 8.0);
        assert!((zxx - 6.0).abs() < 1e-12 && (zyy + 4.0).abs() < 1e-12);
        assert!((zxy - 0.5).abs() < 1e-12);
        assert_eq!(
            second_difference(z(-2.0, 0.0), z(0.0, 0.0), z(2.0, 0.0)),
            24.0
        );
        assert_eq!(
            one_sided_second_difference(z(0.0, 0.0), z(2.0, 0.0), z(4.0, 0.0)),
            24.0
        );
    }

    #[test]
    fn a_ridge_is_convex_and_a_plane_is_not_curved() {
        let ridge = |dc: isize, _dr: isize| -((dc as f64).abs());
        assert!(directional_curvature(0.0, ridge, 1, 10.0) > 0.0);
        let tilted = |dc: isize, dr: isize| 2.0 * dc as f64 - 0.5 * dr as f64;
        assert!(directional_curvature(0.0, tilted, 1, 10.0).abs() < 1e-12);
    }
}
