//! Unit tests of the energy-balance snowpack.
use super::*;
use crate::melt::{HourAir, MeltHour};
use snowscape_environment::ClearSkyParams;
use snowscape_environment::insolation::clear_sky;
use snowscape_terrain::materials::{
    LATENT_HEAT_FUSION_J_KG as LATENT_HEAT_FUSION, SPECIFIC_HEAT_ICE_J_KG_K as SPECIFIC_HEAT_ICE,
};
use snowscape_terrain::{Grid, GridGeometry, SnowLayer};
use std::f64::consts::TAU;

/// Latitude of the slope tests, ° N (the Sierra Nevada basin of issue 47).
const LATITUDE: f64 = 37.6;
/// 15 March.
const MARCH_15: u32 = 74;
/// Tilt of the slopes, °.
const TILT: f64 = 35.0;

/// Unit vector to the sun (east, north, up) at solar hour `hour` of day `doy` (declination
/// after Cooper 1969; hour angle 15° per hour from solar noon).
fn sun(doy: u32, hour: f64) -> [f64; 3] {
    let decl = 23.44f64.to_radians() * (TAU * (284.0 + doy as f64) / 365.0).sin();
    let (phi, omega) = (LATITUDE.to_radians(), (15.0 * (hour - 12.0)).to_radians());
    [
        -decl.cos() * omega.sin(),
        phi.cos() * decl.sin() - phi.sin() * decl.cos() * omega.cos(),
        phi.sin() * decl.sin() + phi.cos() * decl.cos() * omega.cos(),
    ]
}

/// A day over a planar 35° slope at 3000 m facing south (`south`) or north, the air at −3 °C
/// every hour: the beam factor from the sun's geometry (no horizon), the clear-sky irradiance
/// of the environment crate times `cloud_factor`, the sky view `(1 + cos β)/2`, and
/// snow-covered ground around reflecting 0.8 of the light onto the `1 − V` it fills.
struct SlopeDay {
    beams: Vec<[u8; 1]>,
    reflected_share: [f32; 1],
    sky_view: [f32; 1],
    hours: Vec<(f32, f32, f32, bool)>,
    air: HourAir,
}

impl SlopeDay {
    fn new(south: bool, cloud_factor: f64, air: HourAir) -> Self {
        let tilt = TILT.to_radians();
        let normal = [0.0, if south { -1.0 } else { 1.0 } * tilt.sin(), tilt.cos()];
        let v = (0.5 * (1.0 + tilt.cos())) as f32;
        let (mut beams, mut hours) = (Vec::new(), Vec::new());
        for h in 0..24 {
            let s = sun(MARCH_15, h as f64 + 0.5);
            let (dir, dif) = clear_sky(&ClearSkyParams::default(), MARCH_15, s[2], 3000.0);
            let cos = normal[0] * s[0] + normal[1] * s[1] + normal[2] * s[2];
            beams.push([(255.0 * cos.max(0.0)).round() as u8]);
            hours.push((
                (dir * cloud_factor) as f32,
                (dif * cloud_factor) as f32,
                (dir * s[2].max(0.0) * cloud_factor) as f32,
                s[2] > 0.0,
            ));
        }
        Self {
            beams,
            reflected_share: [0.8 * (1.0 - v)],
            sky_view: [v],
            hours,
            air,
        }
    }

    fn melt_hours(&self) -> Vec<MeltHour<'_>> {
        self.hours
            .iter()
            .zip(&self.beams)
            .map(|(&(direct, diffuse, reflected, up), beam)| MeltHour {
                weight: 1.0,
                sea_level_c: -3.0,
                beam: up.then_some(beam.as_slice()),
                direct_w_m2: direct,
                diffuse_w_m2: diffuse,
                reflected_w_m2: reflected,
                month: 0,
                longwave_balance_w_m2: 0.0,
                air: self.air,
            })
            .collect()
    }
}

/// 1 m of settled snow (0.3 m w.e.) three days old at 3000 m, its cold content that of a
/// pack at the air's −3 °C.
fn slope_pack() -> (LayeredTerrain, SnowpackState) {
    let mut t = LayeredTerrain::from_bedrock(Grid::filled(
        GridGeometry::square(1, 1, 1.0).unwrap(),
        3000.0,
    ));
    t.layer_mut(SnowLayer::Stable).fill(1.0);
    let mut pack = SnowpackState::new(1);
    pack.surface_age_days.fill(3.0);
    let cold = 0.3 * SPECIFIC_HEAT_ICE * 3.0 / LATENT_HEAT_FUSION;
    pack.cold_content_m.fill(cold as f32);
    (t, pack)
}

/// Runs `days` identical days on one slope; returns (snow lost, melt water, sublimated,
/// deposited), m w.e. over the days.
fn run_days(day: &SlopeDay, days: usize) -> [f64; 4] {
    run_days_with(day, days, &EnergyBalanceParams::default())
}

/// [`run_days`] with the parameters `p`.
fn run_days_with(day: &SlopeDay, days: usize, p: &EnergyBalanceParams) -> [f64; 4] {
    let (mut t, mut pack) = slope_pack();
    let hours = day.melt_hours();
    let reflected: [&[f32]; 1] = [&day.reflected_share];
    let forcing = MeltForcing {
        hours: &hours,
        lapse_offset_c: &[0.0],
        sky_view_factor: &day.sky_view,
        reflected: &reflected,
        rain_m: &[],
        window_days: 1.0,
    };
    let shared = EnhancedMeltParams::default();
    let swe = |t: &LayeredTerrain| -> f64 {
        SnowLayer::ALL
            .iter()
            .zip(shared.layer_density_kg_m3)
            .map(|(&l, d)| t.layer(l)[0] as f64 * d / 1000.0)
            .sum()
    };
    let before = swe(&t);
    let mut out = [0.0; 4];
    for _ in 0..days {
        let r = step(p, &shared, &mut t, &mut pack, &forcing).unwrap();
        out[1] += r.melt_water_m3;
        out[2] += r.sublimated_water_m3;
        out[3] += r.deposited_water_m3;
    }
    out[0] = before - swe(&t);
    out
}

#[test]
fn a_sunny_slope_loses_snow_below_freezing_and_a_shaded_one_does_not() {
    let clear = HourAir {
        relative_humidity: 0.6,
        cloud_cover: 0.0,
        wind_speed_m_s: 3.0,
        longwave_in_w_m2: None,
    };
    let south = run_days(&SlopeDay::new(true, 1.0, clear), 3);
    let north = run_days(&SlopeDay::new(false, 1.0, clear), 3);
    eprintln!(
        "clear March days at −3 °C, m w.e. per 3 days (lost, melt, sublimated, deposited): \
         south {south:.5?}, north {north:.5?}"
    );
    // The south slope loses snow to the sun with the air below freezing (here by
    // sublimation: 3.5 mm w.e. in three days; the dry air takes the surface's heat and the
    // nights refill the cold content, so it does not melt); the north slope hardly loses any
    // (0.4 mm: its frost at night against a little sublimation at noon) and melts none.
    assert!(south[0] > 0.002, "south {south:?}");
    assert!(south[1] > 0.0 || south[2] > 0.002, "south {south:?}");
    assert!(north[1] == 0.0, "north melted {north:?}");
    assert!(north[0] < 0.2 * south[0], "north {north:?} south {south:?}");
    // The default steps (two hours at a time with sun, from a predicted surface temperature;
    // up to eight hours without) lose what hourly steps lose within a few per cent.
    let hourly = EnergyBalanceParams {
        sun_step_hours: 1.0,
        dark_step_hours: 1.0,
        ..EnergyBalanceParams::default()
    };
    let south_hourly = run_days_with(&SlopeDay::new(true, 1.0, clear), 3, &hourly);
    let north_hourly = run_days_with(&SlopeDay::new(false, 1.0, clear), 3, &hourly);
    eprintln!("hourly steps: south {south_hourly:.5?}, north {north_hourly:.5?}");
    assert!(
        (south[0] / south_hourly[0] - 1.0).abs() < 0.03,
        "{south_hourly:?}"
    );
    assert!(
        (north[0] / north_hourly[0] - 1.0).abs() < 0.1,
        "{north_hourly:?}"
    );
}

#[test]
fn an_overcast_day_below_freezing_melts_neither_slope() {
    let overcast = HourAir {
        relative_humidity: 0.95,
        cloud_cover: 1.0,
        wind_speed_m_s: 3.0,
        longwave_in_w_m2: None,
    };
    let south = run_days(&SlopeDay::new(true, 0.25, overcast), 3);
    let north = run_days(&SlopeDay::new(false, 0.25, overcast), 3);
    eprintln!(
        "overcast March days at −3 °C, m w.e. per 3 days (lost, melt, sublimated, deposited): \
         south {south:.5?}, north {north:.5?}"
    );
    assert_eq!(south[1], 0.0, "south {south:?}");
    assert_eq!(north[1], 0.0, "north {north:?}");
    assert!(south[0] < 0.001 && north[0] < 0.001, "{south:?} {north:?}");
}

/// A row of cells in varied states under varied hours: every kind of cell (deep, thin, wet,
/// bare, nodata, sunny, shaded) in one window of two days, with rain on some.
struct Mixed {
    terrain: LayeredTerrain,
    pack: SnowpackState,
    offset: Vec<f32>,
    sky_view: Vec<f32>,
    beam: Vec<u8>,
    reflected: Vec<f32>,
    rain: Vec<f32>,
}

impl Mixed {
    fn new(w: usize, h: usize) -> Self {
        let n = w * h;
        let g = GridGeometry::square(w, h, 10.0).unwrap();
        let bed: Vec<f32> = (0..n)
            .map(|i| 1500.0 + 3.7 * (i % w) as f32 + 21.0 * (i / w) as f32)
            .collect();
        let invalid: Vec<bool> = (0..n).map(|i| i % 97 == 5).collect();
        let mask = snowscape_terrain::NodataMask::from_invalid(invalid.clone());
        let mut terrain = LayeredTerrain::from_bedrock(Grid::new(g, bed.clone(), mask).unwrap());
        for (k, layer) in SnowLayer::ALL.into_iter().enumerate() {
            for (i, v) in terrain.layer_mut(layer).iter_mut().enumerate() {
                *v = if invalid[i] || i % 13 == 0 {
                    0.0
                } else {
                    ((i * (k + 3)) % 7) as f32 * 0.05 + if i % 11 == 0 { 0.0 } else { 0.002 }
                };
            }
        }
        let mut pack = SnowpackState::new(n);
        for i in 0..n {
            pack.surface_age_days[i] = (i % 17) as f32 * 1.5;
            pack.cold_content_m[i] = if i % 3 == 0 { 0.0 } else { 0.002 };
            pack.liquid_water_m[i] = if i % 3 == 0 { 0.003 } else { 0.0 };
            pack.melting[i] = if i % 3 == 0 { 1.0 } else { 0.0 };
        }
        Self {
            terrain,
            pack,
            offset: bed.iter().map(|z| -0.0065 * z).collect(),
            sky_view: (0..n).map(|i| 0.7 + 0.3 * ((i % 5) as f32 / 4.0)).collect(),
            beam: (0..n).map(|i| (i * 37 % 256) as u8).collect(),
            reflected: (0..n).map(|i| 0.01 * (i % 7) as f32).collect(),
            rain: (0..n)
                .map(|i| if i % 4 == 0 { 0.006 } else { 0.0 })
                .collect(),
        }
    }

    /// Two days: a warm sunny one (station longwave in its afternoon) and a cold clear one.
    fn hours(&self) -> Vec<MeltHour<'_>> {
        (0..48)
            .map(|h| {
                let hour = (h % 24) as f32 + 0.5;
                let sunny = (7..17).contains(&(h % 24));
                let warm = if h < 24 { 12.0 } else { -2.0 };
                MeltHour {
                    weight: if h == 47 { 0.5 } else { 1.0 },
                    sea_level_c: warm + 5.0 * ((hour - 15.0) * std::f32::consts::TAU / 24.0).cos(),
                    beam: sunny.then_some(self.beam.as_slice()),
                    direct_w_m2: if sunny { 850.0 } else { 0.0 },
                    diffuse_w_m2: if sunny { 90.0 } else { 0.0 },
                    reflected_w_m2: if sunny { 500.0 } else { 0.0 },
                    month: 0,
                    longwave_balance_w_m2: 0.0,
                    air: HourAir {
                        relative_humidity: if h < 24 { 0.8 } else { 0.4 },
                        cloud_cover: 0.2,
                        wind_speed_m_s: 0.5 + (h % 7) as f32,
                        longwave_in_w_m2: (12..18).contains(&h).then_some(290.0),
                    },
                }
            })
            .collect()
    }

    fn step(&mut self) -> MeltReport {
        let hours = self.hours();
        let reflected: [&[f32]; 1] = [&self.reflected];
        let forcing = MeltForcing {
            hours: &hours,
            lapse_offset_c: &self.offset,
            sky_view_factor: &self.sky_view,
            reflected: &reflected,
            rain_m: &self.rain,
            window_days: 47.5 / 24.0,
        };
        let (mut t, mut pack) = (self.terrain.clone(), self.pack.clone());
        let r = step(
            &EnergyBalanceParams::default(),
            &EnhancedMeltParams::default(),
            &mut t,
            &mut pack,
            &forcing,
        )
        .unwrap();
        self.terrain = t;
        self.pack = pack;
        r
    }
}

#[test]
fn the_snow_and_the_water_close_and_every_term_is_at_work() {
    let mut m = Mixed::new(61, 23);
    let a = m.terrain.geometry().cell_area();
    let (snow0, water0) = (m.terrain.snow_volume(), m.pack.liquid_volume(a));
    // (Rain on nodata cells is not the model's.)
    let mask = m.terrain.mask().clone();
    let rain: f64 = (m.rain.iter().enumerate())
        .filter(|&(i, _)| mask.is_valid(i))
        .map(|(_, &r)| r as f64)
        .sum::<f64>()
        * a;
    let r = m.step();
    let (snow1, water1) = (m.terrain.snow_volume(), m.pack.liquid_volume(a));
    eprintln!("{r:?}");
    for v in [
        r.melted_snow_m3,
        r.refrozen_snow_m3,
        r.sublimated_snow_m3,
        r.deposited_snow_m3,
        r.runoff_m3,
        r.rain_on_snow_m3,
    ] {
        assert!(v > 0.0, "{r:?}");
    }
    let snow =
        snow0 - r.melted_snow_m3 - r.sublimated_snow_m3 + r.refrozen_snow_m3 + r.deposited_snow_m3;
    assert!((snow1 - snow).abs() <= 1e-6 * snow0, "{snow1} vs {snow}");
    let water = water0 + rain + r.melt_water_m3 - r.refrozen_water_m3 - r.runoff_m3;
    assert!(
        (water1 - water).abs() <= 1e-6 * (water0 + rain),
        "{water1} vs {water}"
    );
    assert!(m.terrain.check_invariants().is_ok());
    // Nodata cells are untouched.
    assert_eq!(m.pack.cold_content_m[5], 0.002);
}

#[test]
fn the_same_bits_for_any_thread_count() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut m = Mixed::new(67, 29);
            let r = m.step();
            let mut bits: Vec<u32> = SnowLayer::ALL
                .iter()
                .flat_map(|&l| m.terrain.layer(l).to_vec())
                .chain(m.pack.arrays().iter().flat_map(|a| a.to_vec()))
                .map(f32::to_bits)
                .collect();
            bits.extend(
                [r.melted_snow_m3, r.sublimated_water_m3, r.runoff_m3]
                    .iter()
                    .flat_map(|v| {
                        let b = v.to_bits();
                        [b as u32, (b >> 32) as u32]
                    }),
            );
            bits
        })
    };
    let one = run(1);
    assert_eq!(one, run(3));
    assert_eq!(one, run(2));
}

#[test]
fn each_cell_hour_conserves_energy_with_the_surface_at_or_below_zero() {
    use super::kernel::{Cells, Kernel, Pack, RowInputs, air, group_cells, pay, surface};
    use super::steps::{OffsetRange, Step};
    let p = EnergyBalanceParams::default();
    let shared = EnhancedMeltParams::default();
    let albedo = albedo_table(&shared);
    // Eight cells from 500 m to 4000 m, a sunny beam on some.
    let altitude: Vec<f32> = (0..16).map(|i| 500.0 + 250.0 * i as f32).collect();
    let offset: Vec<f32> = altitude.iter().map(|z| -0.0065 * z).collect();
    let sky_view = vec![0.85f32; 16];
    let beam: Vec<u8> = (0..16).map(|i| (i * 17) as u8).collect();
    let reflected_share = vec![0.05f32; 16];
    let reflected: [&[f32]; 1] = [&reflected_share];
    let range = OffsetRange::of(&offset);
    let inputs = RowInputs {
        base: 0,
        altitude: &altitude,
        offset: &offset,
        sky_view: &sky_view,
        rain: None,
        invalid: None,
        albedo: &albedo,
    };
    let (mut checked, mut melting) = (0, 0);
    for sea_level_c in [-25.0f32, -3.0, 5.0, 20.0] {
        for (sun, wind, rh, longwave) in [
            (false, 0.1f32, 0.3f32, None),
            (true, 3.0, 0.6, None),
            (true, 12.0, 0.95, Some(320.0f32)),
        ] {
            let hour = MeltHour {
                weight: 1.0,
                sea_level_c,
                beam: sun.then_some(beam.as_slice()),
                direct_w_m2: if sun { 900.0 } else { 0.0 },
                diffuse_w_m2: if sun { 100.0 } else { 0.0 },
                reflected_w_m2: if sun { 600.0 } else { 0.0 },
                month: 0,
                longwave_balance_w_m2: 0.0,
                air: HourAir {
                    relative_humidity: rh,
                    cloud_cover: 0.4,
                    wind_speed_m_s: wind,
                    longwave_in_w_m2: longwave,
                },
            };
            let hours = [hour];
            let forcing = MeltForcing {
                hours: &hours,
                lapse_offset_c: &offset,
                sky_view_factor: &sky_view,
                reflected: &reflected,
                rain_m: &[],
                window_days: 1.0 / 24.0,
            };
            let k = Kernel::new(&p, &shared, &forcing, &range);
            let h = &Step::of_window(&forcing, &range, (1.0, 1.0))[0];
            for (swe, cold, t0) in [
                (0.002f32, 0.0f32, -1.0f32),
                (0.3, 0.004, -12.0),
                (0.9, 0.0, 0.0),
            ] {
                let layers = [[swe * 2.0; 16], [0.0; 16], [0.0; 16], [0.0; 16]];
                let c: Cells = group_cells(
                    &k,
                    &inputs,
                    0,
                    16,
                    (&layers, [swe; 16], [1.0; 16]),
                    ([4.0; 16], [0.0; 16]),
                );
                let a = air(&k, h, &c, (0, 16));
                let mut pack = Pack {
                    surface_c: [t0; 16],
                    gains: [0.0; 16],
                    compliance: [0.0; 16],
                    swe: [swe; 16],
                    cold: [cold; 16],
                    liquid: [0.0; 16],
                    melted: [0.0; 16],
                    refrozen: [0.0; 16],
                    sublimated: [0.0; 16],
                    deposited: [0.0; 16],
                };
                let f = surface(&k, h, &c, &a, &pack, [t0; 16]);
                for l in 0..16 {
                    assert!(f.surface_c[l] <= 0.0, "{}", f.surface_c[l]);
                    // The terms at the solved surface sum to the energy into the pack.
                    let sum = a.gains[l] - f.emitted[l] + f.sensible[l] + f.latent[l];
                    let scale = a.gains[l].abs()
                        + f.emitted[l].abs()
                        + f.sensible[l].abs()
                        + f.latent[l].abs();
                    assert!(
                        (sum - f.energy[l]).abs() <= 1e-5 * scale,
                        "{sum} vs {} ({scale})",
                        f.energy[l]
                    );
                    melting += usize::from(f.surface_c[l] == 0.0 && f.energy[l] > 0.0);
                    checked += 1;
                }
                // The energy goes into the pack: the cold content it pays (or adds), the melt
                // and the refreezing account for all of it.
                let e = f.energy.map(|q| q * 3600.0 / (334_000.0 * 1000.0));
                let before = pack.cold;
                pay(&mut pack, e);
                for l in 0..16 {
                    let accounted = (before[l] - pack.cold[l]) + pack.melted[l] - pack.refrozen[l];
                    assert!(
                        (accounted - e[l]).abs() <= 1e-6 * (e[l].abs() + before[l]) + 1e-12
                            || pack.swe[l] == 0.0,
                        "{accounted} vs {}",
                        e[l]
                    );
                }
            }
        }
    }
    // Some of those hours melt at a surface held at 0 °C, others are frozen.
    assert!(melting > 0 && melting < checked, "{melting} of {checked}");
}
