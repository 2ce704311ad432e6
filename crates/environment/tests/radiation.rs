//! Physics of the radiation terms: direct sun, shadows, horizons, sky, bounce.

mod common;

use common::terrain;
use snowscape_environment::solar::{day_samples, declination};
use snowscape_environment::{
    BounceParams, DeclinationModel, SkyParams, SunParams, SunSample, direct_sun, direct_sun_for,
    horizon_angles, indirect_bounce, sky_exposure,
};
use snowscape_terrain::NodataMask;

const TAN30: f64 = 0.577_350_269_189_625_8;

fn slope_params(day: u32, num_days: u32) -> SunParams {
    SunParams {
        latitude_deg: 45.0,
        start_day: day,
        num_days,
        day_step: 1,
        samples_per_hour: 4,
        ..SunParams::default()
    }
}

#[test]
fn south_facing_slope_gets_more_sun_than_north_facing() {
    let all = NodataMask::all_valid();
    // 30° planes: the south-facing one rises to the north, the north-facing one to the south.
    let (south, g) = terrain(48, 48, 10.0, |_, y| y * TAN30);
    let (north, _) = terrain(48, 48, 10.0, |_, y| (480.0 - y) * TAN30);
    let centre = 24 * 48 + 24;
    // Solstice, January, and mid-November to late January.
    for (day, days) in [(355, 1), (1, 28), (320, 75)] {
        let p = slope_params(day, days);
        let s = direct_sun(&south, &g, &all, &p).unwrap()[centre];
        let n = direct_sun(&north, &g, &all, &p).unwrap()[centre];
        assert!(s > 2.0, "day {day}: south-facing gets {s} sun-hours");
        // In winter at 45° N the sun never climbs above 30° in the south (21.6° at the
        // solstice) and never rises north of east-west: a 30° north slope gets no direct sun.
        assert_eq!(n, 0.0, "day {day}");
    }
    // The default season (December to March) reaches March, when the noon sun passes 30°.
    let p = SunParams::default();
    let s = direct_sun(&south, &g, &all, &p).unwrap()[centre];
    let n = direct_sun(&north, &g, &all, &p).unwrap()[centre];
    assert!(n > 0.0 && n < 0.2 * s, "season: south {s}, north {n}");
    // Summer: both get sun, south still more.
    let p = slope_params(172, 1);
    let s = direct_sun(&south, &g, &all, &p).unwrap()[centre];
    let n = direct_sun(&north, &g, &all, &p).unwrap()[centre];
    assert!(n > 3.0 && s > n + 0.2, "summer: south {s}, north {n}");
}

#[test]
fn unshadowed_plane_matches_the_direct_sum() {
    // On a south-facing plane nothing casts a shadow: the sweep must return exactly the
    // Lambert sum k_sun Σ w max(0, n·s) computed independently here.
    let (z, g) = terrain(40, 40, 5.0, |_, y| y * 0.3);
    let samples = day_samples(45.0, 20, 2, DeclinationModel::Spencer);
    let got = direct_sun_for(&z, &g, &NodataMask::all_valid(), &samples, 0.9).unwrap();
    let inv = 1.0 / (1.0f64 + 0.09).sqrt();
    let n = [0.0, -0.3 * inv, inv];
    let expect: f64 = 0.9
        * samples
            .iter()
            .map(|s| {
                let d = s.direction;
                (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]).max(0.0) * s.weight_h
            })
            .sum::<f64>();
    for row in 1..39 {
        for col in 1..39 {
            let v = got[row * 40 + col] as f64;
            assert!(
                (v - expect).abs() < 1e-4 * expect,
                "({col},{row}) {v} vs {expect}"
            );
        }
    }
}

#[test]
fn a_tall_wall_shadows_the_ground_behind_it_at_low_sun() {
    // Flat ground at 0 m, an east-west wall 20 m high on rows 200..203 of 1 m cells.
    let (w, h) = (60, 300);
    let (z, g) = terrain(w, h, 1.0, |_, y| {
        let row = 300.0 - y;
        if (200.0..203.0).contains(&row) {
            20.0
        } else {
            0.0
        }
    });
    let all = NodataMask::all_valid();
    // Sun due south at 10°: the shadow reaches 20 / tan 10° = 113.4 m north of the wall.
    let low = [SunSample::from_angles(10.0, 180.0, 1.0)];
    let sun = direct_sun_for(&z, &g, &all, &low, 1.0).unwrap();
    let lit = 10f32.to_radians().sin();
    for col in 0..w {
        for row in 90..200 {
            assert_eq!(sun[row * w + col], 0.0, "({col},{row}) should be in shadow");
        }
        for row in (0..84).chain(205..h) {
            let v = sun[row * w + col];
            assert!((v - lit).abs() < 1e-5, "({col},{row}) should be lit: {v}");
        }
    }
    // The same wall at a high sun (60°) shadows only 20 / tan 60° = 11.5 m.
    let high = [SunSample::from_angles(60.0, 180.0, 1.0)];
    let sun = direct_sun_for(&z, &g, &all, &high, 1.0).unwrap();
    assert_eq!(sun[195 * w + 30], 0.0);
    assert!(sun[180 * w + 30] > 0.8);
    // An oblique low sun from the south-west still shadows the cells just north-east.
    let oblique = [SunSample::from_angles(10.0, 225.0, 1.0)];
    let sun = direct_sun_for(&z, &g, &all, &oblique, 1.0).unwrap();
    assert_eq!(sun[170 * w + 55], 0.0);
    assert!(sun[170 * w + 5] > 0.1);
}

#[test]
fn flat_open_plane_sees_the_whole_sky() {
    let (z, g) = terrain(50, 30, 7.0, |_, _| 1234.0);
    for n in [8, 16, 32] {
        let p = SkyParams {
            directions: n,
            k_sky: 0.1,
        };
        let m = sky_exposure(&z, &g, &NodataMask::all_valid(), &p).unwrap();
        for i in 0..z.len() {
            assert!(
                (m.sky_view_factor[i] - 1.0).abs() < 1e-6,
                "SVF {}",
                m.sky_view_factor[i]
            );
            assert!(
                (m.sky[i] - 0.1 * std::f32::consts::PI).abs() < 1e-6,
                "sky {}",
                m.sky[i]
            );
        }
    }
}

/// Centre cell of a pit of depth `d` metres and radius (or half-width) `r` cells on 1 m cells.
fn pit(square: bool, d: f64, r: f64) -> (Vec<f32>, snowscape_terrain::GridGeometry, usize) {
    let n = 121;
    let c = 60.5;
    let (z, g) = terrain(n, n, 1.0, |x, y| {
        let (dx, dy) = ((x - c).abs(), (y - c).abs());
        let inside = if square {
            dx.max(dy) <= r
        } else {
            dx.hypot(dy) <= r
        };
        if inside { 0.0 } else { d }
    });
    (z, g, 60 * n + 60)
}

#[test]
fn pit_bottom_sees_the_analytic_horizon() {
    let (d, r) = (20.0, 20.0);
    // Cylinder: horizon atan(d / r) in every direction; the rim cell lies between r and
    // r + 1.5 cells away along a digital line (nearest-cell rasterisation).
    let (z, g, centre) = pit(false, d, r);
    let all = NodataMask::all_valid();
    let (lo, hi) = ((d / (r + 1.5)).atan(), (d / r).atan());
    let n = 16;
    let mut cos2 = 0.0;
    for i in 0..n {
        let az = 360.0 * i as f64 / n as f64;
        let phi = horizon_angles(&z, &g, &all, az).unwrap()[centre] as f64;
        assert!(
            phi >= lo - 1e-4 && phi <= hi + 1e-4,
            "azimuth {az}: {phi} not in [{lo}, {hi}]"
        );
        cos2 += phi.cos().powi(2);
    }
    // Sky exposure = k_sky π/N Σ cos² φ; analytic value k_sky π cos²(atan(d/r)) = k_sky π / 2.
    let p = SkyParams {
        directions: n,
        k_sky: 1.0,
    };
    let m = sky_exposure(&z, &g, &all, &p).unwrap();
    let analytic = std::f64::consts::PI * (d / r).atan().cos().powi(2);
    let tol = std::f64::consts::PI * (lo.cos().powi(2) - hi.cos().powi(2));
    let sky = m.sky[centre] as f64;
    assert!(
        (sky - analytic).abs() <= tol,
        "sky {sky} vs analytic {analytic} ± {tol}"
    );
    assert!((sky - std::f64::consts::PI * cos2 / n as f64).abs() < 1e-5);
    assert!((m.sky_view_factor[centre] as f64 - analytic / std::f64::consts::PI).abs() <= tol);

    // Square pit: the wall is r / max(|sin θ|, |cos θ|) away in direction θ.
    let (z, g, centre) = pit(true, d, r);
    for i in 0..n {
        let az = (360.0 * i as f64 / n as f64).to_radians();
        let dist = r / az.sin().abs().max(az.cos().abs());
        let phi = horizon_angles(&z, &g, &all, az.to_degrees()).unwrap()[centre] as f64;
        let (lo, hi) = ((d / (dist + 1.5)).atan(), (d / dist).atan());
        assert!(
            phi >= lo - 1e-4 && phi <= hi + 1e-4,
            "square, az {az}: {phi} not in [{lo}, {hi}]"
        );
    }
}

#[test]
fn horizon_of_a_slope_is_the_slope_uphill_and_open_downhill() {
    // A uniform 30° south-facing plane: looking north (uphill) the horizon is the plane, 30°;
    // looking south the nearest cells are below: the horizon is −30°.
    let (z, g) = terrain(40, 40, 10.0, |_, y| y * TAN30);
    let all = NodataMask::all_valid();
    let up = horizon_angles(&z, &g, &all, 0.0).unwrap();
    let down = horizon_angles(&z, &g, &all, 180.0).unwrap();
    let c = 20 * 40 + 20;
    assert!((up[c] - 30f32.to_radians()).abs() < 1e-4, "{}", up[c]);
    assert!((down[c] + 30f32.to_radians()).abs() < 1e-4, "{}", down[c]);
    // The paper's sky term measures from the tangent plane: an open plane sees k_sky π;
    // SAGA's SVF measures from the horizontal and tilts: on a plane of slope β it is the
    // classic (1 + cos β)/2.
    let m = sky_exposure(&z, &g, &all, &SkyParams::default()).unwrap();
    assert!((m.sky[c] - 0.1 * std::f32::consts::PI).abs() < 1e-4);
    let plane = (1.0 + 30f32.to_radians().cos()) / 2.0;
    assert!(
        (m.sky_view_factor[c] - plane).abs() < 1e-3,
        "{}",
        m.sky_view_factor[c]
    );
}

#[test]
fn nodata_is_transparent_and_gets_zero() {
    // A wall of nodata between the sun and the ground casts no shadow.
    let (z, g) = terrain(40, 40, 1.0, |_, _| 0.0);
    let mut invalid = vec![false; z.len()];
    for col in 0..40 {
        for row in 20..23 {
            invalid[row * 40 + col] = true;
        }
    }
    let mut z = z;
    for (v, &bad) in z.iter_mut().zip(&invalid) {
        if bad {
            *v = f32::NAN; // whatever lies under nodata must not matter
        }
    }
    let mask = NodataMask::from_invalid(invalid.clone());
    let low = [SunSample::from_angles(5.0, 180.0, 1.0)];
    let sun = direct_sun_for(&z, &g, &mask, &low, 1.0).unwrap();
    for (i, v) in sun.iter().enumerate() {
        assert!(v.is_finite());
        if invalid[i] {
            assert_eq!(*v, 0.0);
        } else {
            assert!(*v > 0.08, "cell {i}: {v}");
        }
    }
    let m = sky_exposure(&z, &g, &mask, &SkyParams::default()).unwrap();
    assert!(
        m.sky
            .iter()
            .chain(&m.sky_view_factor)
            .all(|v| v.is_finite())
    );
    assert_eq!(m.sky[21 * 40 + 5], 0.0);
    assert!((m.sky_view_factor[10 * 40 + 5] - 1.0).abs() < 1e-6);
}

#[test]
fn bounce_lights_the_floor_next_to_a_sunlit_slope_only() {
    // A valley floor at 0 m, with a south-facing 45° slope rising north of row 60 (10 m cells).
    let (z, g) = terrain(60, 100, 10.0, |_, y| (y - 400.0).max(0.0));
    let all = NodataMask::all_valid();
    let sun = direct_sun(&z, &g, &all, &SunParams::default()).unwrap();
    let p = BounceParams::default();
    let bounce = indirect_bounce(&z, &g, &all, &sun, &p).unwrap();
    let w = 60;
    // Floor cells 20 m south of the slope's foot receive light from it...
    let near = bounce[62 * w + 30];
    assert!(near > 0.05, "near {near}");
    // ...more than floor cells 300 m away, which are beyond most samples' reach.
    let far = bounce[95 * w + 30];
    assert!(far < 0.5 * near, "far {far} near {near}");
    // Bounded by the senders: at most k_ind times the brightest sender.
    let max_sun = sun.iter().cloned().fold(0.0, f32::max);
    assert!(
        bounce
            .iter()
            .all(|&b| b >= 0.0 && b <= p.k_ind as f32 * max_sun)
    );
    // A flat plane exchanges nothing (every sender is edge-on).
    let (flat, g) = terrain(30, 30, 10.0, |_, _| 0.0);
    let s = vec![5.0f32; flat.len()];
    let b = indirect_bounce(&flat, &g, &all, &s, &p).unwrap();
    assert!(b.iter().all(|&v| v == 0.0));
}

#[test]
fn declination_formulas_agree_within_one_and_a_half_degrees() {
    for day in (1..=365).step_by(7) {
        let a = declination(day, DeclinationModel::Spencer).to_degrees();
        let b = declination(day, DeclinationModel::Cooper).to_degrees();
        assert!((a - b).abs() < 1.5, "day {day}: {a} vs {b}");
    }
}

#[test]
fn anisotropic_cells_keep_plane_horizons_exact() {
    // 2 m × 5 m cells; a plane rising 0.4 eastwards and 0.2 northwards.
    let g = snowscape_terrain::GridGeometry::new(50, 30, 2.0, 5.0).unwrap();
    let z: Vec<f32> = (0..50 * 30)
        .map(|i| {
            let (c, r) = ((i % 50) as f64, (i / 50) as f64);
            (0.4 * c * 2.0 - 0.2 * r * 5.0) as f32
        })
        .collect();
    let all = NodataMask::all_valid();
    let c = 15 * 50 + 25;
    for az in [0.0f64, 30.0, 75.0, 100.0, 160.0, 200.0, 250.0, 290.0, 340.0] {
        let (se, cn) = az.to_radians().sin_cos();
        let exact = (0.4 * se + 0.2 * cn).atan() as f32;
        let phi = horizon_angles(&z, &g, &all, az).unwrap()[c];
        assert!((phi - exact).abs() < 1e-4, "azimuth {az}: {phi} vs {exact}");
    }
}
