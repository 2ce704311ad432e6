//! The steps of a window in the units of the kernel: the sun's three irradiances, the wind,
//! and the air-side terms that depend on the cell only through its air temperature (the
//! vapour pressure `e_a` and the sky's longwave `L_sky`) as degree-4 polynomials in the
//! cell's normalised lapse offset (parent module's docs).

use super::super::enhanced::{MeltForcing, MeltHour};
use super::constants::{MELTING_POINT_K, STEFAN_BOLTZMANN};
use snowscape_terrain::parallel;

/// Degree of the per-step polynomials, plus one.
pub(super) const TERMS: usize = 5;

/// The terrain's range of lapse offsets, °C: a cell's offset `o` is `mid + half · x` with
/// `x` in [−1, 1].
#[derive(Debug, Clone, Copy)]
pub(super) struct OffsetRange {
    pub(super) mid: f32,
    pub(super) half: f32,
}

impl OffsetRange {
    /// The range of `offsets` (at least ±0.5 °C wide). Minimum and maximum are exact in any
    /// order: the same range for any thread count.
    pub(super) fn of(offsets: &[f32]) -> Self {
        let (lo, hi) = parallel::range(offsets).unwrap_or((0.0, 0.0));
        Self {
            mid: 0.5 * (lo + hi),
            half: (0.5 * (hi - lo)).max(0.5),
        }
    }

    fn offset_at(&self, x: f64) -> f64 {
        self.mid as f64 + self.half as f64 * x
    }
}

/// One step of the window for the kernel (an hour, or consecutive hours with sun or without
/// merged up to the step lengths of [`super::EnergyBalanceParams`]), the same for every cell.
pub(super) struct Step<'a> {
    /// The step's hours' beam factors (/255), each with its direct irradiance per unit of
    /// the beam byte times its share of the step, W/m².
    pub(super) beams: Vec<(&'a [u8], f32)>,
    /// The month's reflected shares (with sun).
    pub(super) reflected_share: Option<&'a [f32]>,
    /// Mean air temperature at sea level, °C.
    pub(super) sea_level_c: f32,
    /// Mean diffuse horizontal irradiance, W/m².
    pub(super) diffuse: f32,
    /// Mean reflected irradiance per unit of reflected share, W/m².
    pub(super) reflected: f32,
    /// Wind speed, m/s (at least [`MIN_WIND_M_S`]).
    pub(super) wind: f32,
    /// `1 / wind²`, s²/m².
    pub(super) inv_wind2: f32,
    /// `e_a`, Pa, as a polynomial in the normalised offset (lowest power first).
    pub(super) vapour: [f32; TERMS],
    /// `L_sky`, W/m², as a polynomial in the normalised offset.
    pub(super) sky: [f32; TERMS],
    /// Length of the step, s.
    pub(super) seconds: f32,
}

/// Lowest wind speed of the turbulent fluxes, m/s (FSM's driver: `Ua = max(Ua, 0.1)`).
pub(super) const MIN_WIND_M_S: f32 = 0.1;

/// Weighted sums of the hours merged into one step.
#[derive(Default)]
struct Merged<'a> {
    weight: f32,
    sun: bool,
    month: usize,
    recorded_longwave: bool,
    beams: Vec<(&'a [u8], f32)>,
    sea_level_c: f32,
    diffuse: f32,
    reflected: f32,
    relative_humidity: f32,
    cloud_cover: f32,
    wind: f32,
    longwave: f32,
}

impl<'a> Merged<'a> {
    fn of(h: &MeltHour<'a>) -> Self {
        let mut m = Self {
            sun: h.beam.is_some(),
            month: h.month,
            recorded_longwave: h.air.longwave_in_w_m2.is_some(),
            ..Self::default()
        };
        m.add(h);
        m
    }

    /// Whether `h` may join this step of at most `sun_hours` (with sun) or `dark_hours`.
    fn takes(&self, h: &MeltHour, (sun_hours, dark_hours): (f32, f32)) -> bool {
        let sun = h.beam.is_some();
        let limit = if sun { sun_hours } else { dark_hours };
        sun == self.sun
            && (!sun || h.month == self.month)
            && h.air.longwave_in_w_m2.is_some() == self.recorded_longwave
            && self.weight + h.weight <= limit + 1e-4
    }

    fn add(&mut self, h: &MeltHour<'a>) {
        let w = h.weight;
        self.weight += w;
        if let Some(b) = h.beam {
            self.beams.push((b, w * h.direct_w_m2 * (1.0 / 255.0)));
        }
        self.sea_level_c += w * h.sea_level_c;
        self.diffuse += w * h.diffuse_w_m2;
        self.reflected += w * h.reflected_w_m2;
        self.relative_humidity += w * h.air.relative_humidity.clamp(0.0, 1.0);
        self.cloud_cover += w * h.air.cloud_cover.clamp(0.0, 1.0);
        self.wind += w * h.air.wind_speed_m_s;
        self.longwave += w * h.air.longwave_in_w_m2.unwrap_or(0.0);
    }
}

impl<'a> Step<'a> {
    /// The steps of the window's hours (those with weight), consecutive hours merged while
    /// they have sun alike (and the same month and kind of longwave) up to `sun_hours`
    /// hours with sun and `dark_hours` without (parent module's docs).
    pub(super) fn of_window(
        f: &MeltForcing<'a>,
        range: &OffsetRange,
        (sun_hours, dark_hours): (f32, f32),
    ) -> Vec<Self> {
        let mut merged: Vec<Merged> = Vec::new();
        for h in f.hours.iter().filter(|h| h.weight > 0.0) {
            match merged.last_mut() {
                Some(m) if m.takes(h, (sun_hours, dark_hours)) => m.add(h),
                _ => merged.push(Merged::of(h)),
            }
        }
        merged.into_iter().map(|m| Self::new(m, f, range)).collect()
    }

    fn new(m: Merged<'a>, f: &MeltForcing<'a>, range: &OffsetRange) -> Self {
        let inv = 1.0 / m.weight;
        let rh = (m.relative_humidity * inv) as f64;
        let cover = (m.cloud_cover * inv) as f64;
        let t_sl = (m.sea_level_c * inv) as f64;
        let vapour = fit(|x| rh * saturation_over_water_pa(t_sl + range.offset_at(x)));
        let sky = if m.recorded_longwave {
            let mut c = [0.0; TERMS];
            c[0] = m.longwave * inv;
            c
        } else {
            fit(|x| {
                let t = t_sl + range.offset_at(x);
                sky_longwave_w_m2(t, rh * saturation_over_water_pa(t), cover)
            })
        };
        let wind = (m.wind * inv).max(MIN_WIND_M_S);
        Self {
            beams: m.beams.into_iter().map(|(b, d)| (b, d * inv)).collect(),
            reflected_share: m.sun.then(|| f.reflected.get(m.month).copied()).flatten(),
            sea_level_c: t_sl as f32,
            diffuse: m.diffuse * inv,
            reflected: m.reflected * inv,
            wind,
            inv_wind2: 1.0 / (wind * wind),
            vapour,
            sky,
            seconds: m.weight * 3600.0,
        }
    }
}

/// Saturation vapour pressure over water, Pa, at `t` °C (Magnus, Sonntag 1990's
/// coefficients: WMO-No. 8 2008, Annex 4.B).
pub(super) fn saturation_over_water_pa(t: f64) -> f64 {
    611.2 * (17.62 * t / (243.12 + t)).exp()
}

/// Saturation vapour pressure over ice, Pa, at `t` °C (as [`saturation_over_water_pa`]).
pub(super) fn saturation_over_ice_pa(t: f64) -> f64 {
    611.2 * (22.46 * t / (272.62 + t)).exp()
}

/// Coldest surface the kernel's saturation polynomial covers, °C.
pub(super) const COLDEST_SURFACE_C: f32 = -60.0;

/// [`saturation_over_ice_pa`] over [−60, 0] °C as a polynomial of degree 6 in
/// `x = (t + 30) / 30` (interpolated at the Chebyshev nodes: within 0.04 Pa and 0.06 Pa/K of
/// the formula and its slope), and its slope's polynomial, Pa/K.
pub(super) fn ice_saturation_polynomials() -> ([f32; 7], [f32; 6]) {
    let half = -0.5 * COLDEST_SURFACE_C as f64;
    let c: [f32; 7] = fit(|x| saturation_over_ice_pa(-half + half * x));
    let slope = std::array::from_fn(|k| c[k + 1] * (k + 1) as f32 / half as f32);
    (c, slope)
}

/// The sky's longwave, W/m², at air temperature `t` °C, vapour pressure `e_a` Pa and cloud
/// cover `n`: Prata 1996's clear sky with Unsworth & Monteith 1975's cloud (module docs).
pub(super) fn sky_longwave_w_m2(t: f64, e_a: f64, n: f64) -> f64 {
    let tk = t + MELTING_POINT_K;
    let w = 46.5 * (e_a / 100.0) / tk;
    let clear = 1.0 - (1.0 + w) * (-(1.2 + 3.0 * w).sqrt()).exp();
    let black = STEFAN_BOLTZMANN * tk.powi(4);
    (1.0 - 0.84 * n) * clear * black + 0.84 * n * black
}

/// The coefficients (lowest power first) of the polynomial of degree `N − 1` through `f` at
/// the `N` Chebyshev nodes of [−1, 1] (Gaussian elimination with partial pivoting, in f64).
pub(super) fn fit<const N: usize>(f: impl Fn(f64) -> f64) -> [f32; N] {
    let mut a = [[0.0f64; N]; N];
    let mut b = [0.0f64; N];
    for (j, row) in a.iter_mut().enumerate() {
        let x = (std::f64::consts::PI * (2 * j + 1) as f64 / (2 * N) as f64).cos();
        let mut p = 1.0;
        for v in row.iter_mut() {
            *v = p;
            p *= x;
        }
        b[j] = f(x);
    }
    for col in 0..N {
        let pivot = (col..N)
            .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
            .unwrap_or(col);
        a.swap(col, pivot);
        b.swap(col, pivot);
        for r in col + 1..N {
            let m = a[r][col] / a[col][col];
            let pivot_row = a[col];
            for (x, p) in a[r][col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= m * p;
            }
            b[r] -= m * b[col];
        }
    }
    let mut c = [0.0f64; N];
    for r in (0..N).rev() {
        let s: f64 = (r + 1..N).map(|k| a[r][k] * c[k]).sum();
        c[r] = (b[r] - s) / a[r][r];
    }
    c.map(|v| v as f32)
}

/// The polynomial `c` (lowest power first) at `x` (Horner).
#[inline(always)]
pub(super) fn polynomial<const N: usize>(c: &[f32; N], x: f32) -> f32 {
    let mut v = c[N - 1];
    for k in (0..N - 1).rev() {
        v = c[k] + x * v;
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fits_follow_the_air_terms_over_the_terrain() {
        // 4000 m of relief (26 °C of lapse offset) on a cold and a warm hour.
        let range = OffsetRange::of(&[0.0, -26.0]);
        for t_sl in [-5.0, 15.0] {
            let v: [f32; TERMS] =
                fit(|x| 0.6 * saturation_over_water_pa(t_sl + range.offset_at(x)));
            let s: [f32; TERMS] = fit(|x| {
                let t = t_sl + range.offset_at(x);
                sky_longwave_w_m2(t, 0.6 * saturation_over_water_pa(t), 0.3)
            });
            for k in 0..=100 {
                let x = -1.0 + 0.02 * k as f64;
                let t = t_sl + range.offset_at(x);
                let e = 0.6 * saturation_over_water_pa(t);
                let fitted = polynomial(&v, x as f32) as f64;
                assert!((fitted / e - 1.0).abs() < 2e-3, "{t}: {fitted} vs {e}");
                let l = sky_longwave_w_m2(t, e, 0.3);
                assert!((polynomial(&s, x as f32) as f64 - l).abs() < 0.05, "{t}");
            }
        }
        // Prata's clear sky at −3 °C and 60 %: an emissivity near 0.7; overcast is black.
        let e = 0.6 * saturation_over_water_pa(-3.0);
        let black = STEFAN_BOLTZMANN * 270.15f64.powi(4);
        let clear = sky_longwave_w_m2(-3.0, e, 0.0) / black;
        assert!((0.65..0.75).contains(&clear), "{clear}");
        let overcast = sky_longwave_w_m2(-3.0, e, 1.0) / black;
        assert!((overcast - (0.16 * clear + 0.84)).abs() < 1e-12);
        // Magnus over ice at 0 and −20 °C (WMO: 611.2 and 103.2 Pa), and the kernel's
        // polynomial of it.
        assert!((saturation_over_ice_pa(0.0) - 611.2).abs() < 1e-9);
        assert!((saturation_over_ice_pa(-20.0) - 103.2).abs() < 0.5);
        let (e, slope) = ice_saturation_polynomials();
        for k in 0..=600 {
            let t = -60.0 + 0.1 * k as f64;
            let x = ((t + 30.0) / 30.0) as f32;
            let exact = saturation_over_ice_pa(t);
            assert!((polynomial(&e, x) as f64 - exact).abs() < 0.05, "{t}");
            let d = exact * 22.46 * 272.62 / (272.62 + t).powi(2);
            assert!((polynomial(&slope, x) as f64 - d).abs() < 0.07, "{t}");
        }
    }
}
