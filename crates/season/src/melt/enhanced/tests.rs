//! Unit tests of the enhanced temperature-index melt.
use super::*;
use snowscape_terrain::{Grid, GridGeometry, SnowLayer};

/// Two cells of 1 m of settled snow: cell 0 a sunny south slope, cell 1 a shaded north
/// slope, at an altitude where the day's mean is −2 °C with a +6 °C afternoon.
fn day_of_sun(age_days: f32) -> (MeltReport, LayeredTerrain, SnowpackState, Vec<f32>) {
    let mut t =
        LayeredTerrain::from_bedrock(Grid::filled(GridGeometry::square(2, 1, 1.0).unwrap(), 0.0));
    t.layer_mut(SnowLayer::Stable).fill(1.0);
    let mut pack = SnowpackState::new(2);
    pack.surface_age_days.fill(age_days);
    let south: Vec<u8> = vec![204, 0];
    let hours: Vec<MeltHour> = (0..24)
        .map(|h| {
            let hour = h as f64 + 0.5;
            let t = -2.0 + 8.0 * (std::f64::consts::TAU * (hour - 15.0) / 24.0).cos();
            let day = (7..17).contains(&h);
            MeltHour {
                weight: 1.0,
                sea_level_c: t as f32,
                beam: day.then_some(south.as_slice()),
                direct_w_m2: if day { 800.0 } else { 0.0 },
                diffuse_w_m2: if day { 60.0 } else { 0.0 },
                reflected_w_m2: 0.0,
                month: 0,
                longwave_balance_w_m2: 0.0,
                air: HourAir::default(),
            }
        })
        .collect();
    let zero = [0.0f32; 2];
    let reflected: [&[f32]; 1] = [&zero];
    let forcing = MeltForcing {
        hours: &hours,
        lapse_offset_c: &[0.0, 0.0],
        sky_view_factor: &[0.8, 0.8],
        reflected: &reflected,
        rain_m: &[],
        window_days: 1.0,
    };
    let params = EnhancedMeltParams::default();
    let before: Vec<f32> = (0..2).map(|i| t.depth_at(i)).collect();
    let r = step(&params, &mut t, &mut pack, &forcing).unwrap();
    (r, t, pack, before)
}

#[test]
fn a_sunny_slope_melts_on_a_freezing_day_and_a_shaded_one_does_not() {
    let (r, t, pack, before) = day_of_sun(5.0);
    // The sunny cell lost snow; the shaded one none (its afternoon melt energy went into
    // the night's cold content).
    assert!(t.depth_at(0) < before[0] - 0.01, "south {}", t.depth_at(0));
    assert_eq!(t.depth_at(1), before[1], "north");
    assert_eq!(pack.liquid_water_m[1], 0.0);
    assert!(pack.cold_content_m[1] > 0.0);
    assert!(r.melt_water_m3 > 0.005, "{r:?}");
    // The melt water stays in the pack (5 % holding capacity of 0.3 m w.e.).
    assert!((pack.liquid_water_m[0] as f64 - r.melt_water_m3).abs() < 1e-6);
    assert_eq!(r.runoff_m3, 0.0);
    assert!(t.check_invariants().is_ok());
}

#[test]
fn fresh_snow_reflects_and_melts_less() {
    let (fresh, ..) = day_of_sun(0.0);
    let (old, ..) = day_of_sun(30.0);
    assert!(
        fresh.melt_water_m3 < 0.6 * old.melt_water_m3,
        "{fresh:?} {old:?}"
    );
    let p = EnhancedMeltParams::default();
    assert!((p.albedo(0.0, false) - 0.85).abs() < 1e-6);
    assert!(p.albedo(10.0, true) < p.albedo(10.0, false));
    assert_eq!(p.albedo(1e4, true), 0.4);
}

#[test]
fn liquid_water_refreezes_and_water_is_conserved() {
    let (_, mut t, mut pack, _) = day_of_sun(5.0);
    let liquid = pack.liquid_water_m[0];
    let compacted = t.layer(SnowLayer::Compacted)[0];
    // A cold night: the water refreezes into the compacted layer.
    let hours: Vec<MeltHour> = (0..12).map(|_| dark_hour(1.0, -10.0)).collect();
    let forcing = MeltForcing {
        hours: &hours,
        lapse_offset_c: &[0.0, 0.0],
        sky_view_factor: &[0.8, 0.8],
        reflected: &[],
        rain_m: &[0.002, 0.0],
        window_days: 0.5,
    };
    let r = step(&EnhancedMeltParams::default(), &mut t, &mut pack, &forcing).unwrap();
    let frozen = r.refrozen_water_m3 as f32;
    assert!(frozen > 0.0 && frozen <= liquid + 1e-7, "{r:?}");
    assert!(
        (pack.liquid_water_m[0] - (liquid - frozen + 0.002)).abs() < 1e-6,
        "{:?}",
        pack.liquid_water_m
    );
    let gained = t.layer(SnowLayer::Compacted)[0] - compacted;
    assert!((gained - frozen / 0.5).abs() < 1e-6, "{gained}");
    // A bad map is a typed error.
    let bad = MeltForcing {
        lapse_offset_c: &[0.0],
        ..forcing
    };
    assert!(matches!(
        step(&EnhancedMeltParams::default(), &mut t, &mut pack, &bad),
        Err(PhenomenonError::MapLength { actual: 1, .. })
    ));
}

#[test]
fn the_surface_filled_by_the_melt_is_the_surface_of_the_snow_it_leaves() {
    // A 37 x 5 slope with mixed layers, rain on a few cells and a nodata cell: the surface the
    // melt writes row by row has the bits of a separate pass over the melted terrain, and the
    // melt itself is the plain step's.
    let g = GridGeometry::square(37, 5, 2.0).unwrap();
    let n = g.len();
    let bed: Vec<f32> = (0..n)
        .map(|i| 1500.0 + 0.37 * (i % 37) as f32 + 1.3 * (i / 37) as f32)
        .collect();
    let mut invalid = vec![false; n];
    invalid[40] = true;
    let mask = snowscape_terrain::NodataMask::from_invalid(invalid);
    let mut t = LayeredTerrain::from_bedrock(Grid::new(g, bed, mask).unwrap());
    for (k, layer) in SnowLayer::ALL.into_iter().enumerate() {
        for (i, v) in t.layer_mut(layer).iter_mut().enumerate() {
            *v = if i == 40 {
                0.0
            } else {
                ((i * (k + 3)) % 7) as f32 * 0.013
            };
        }
    }
    let pack = SnowpackState::new(n);
    let hours: Vec<MeltHour> = (0..24)
        .map(|h| MeltHour {
            weight: 1.0,
            sea_level_c: 4.0 + 3.0 * (h as f32 * 0.26).sin(),
            beam: None,
            direct_w_m2: 0.0,
            diffuse_w_m2: 90.0,
            reflected_w_m2: 0.0,
            month: 0,
            longwave_balance_w_m2: 0.0,
            air: HourAir::default(),
        })
        .collect();
    let offset: Vec<f32> = (0..n).map(|i| -0.002 * i as f32).collect();
    let svf = vec![0.9f32; n];
    let rain: Vec<f32> = (0..n)
        .map(|i| if i % 11 == 0 { 0.004 } else { 0.0 })
        .collect();
    let zero = vec![0.0f32; n];
    let reflected: [&[f32]; 1] = [&zero];
    let forcing = MeltForcing {
        hours: &hours,
        lapse_offset_c: &offset,
        sky_view_factor: &svf,
        reflected: &reflected,
        rain_m: &rain,
        window_days: 1.0,
    };
    let params = EnhancedMeltParams::default();
    let (mut plain, mut filled) = (t.clone(), t);
    let (mut pack_a, mut pack_b) = (pack.clone(), pack);
    let a = step(&params, &mut plain, &mut pack_a, &forcing).unwrap();
    let mut surface = vec![f32::NAN; 3];
    let b =
        step_filling_surface(&params, &mut filled, &mut pack_b, &forcing, &mut surface).unwrap();
    assert!(a.melted_snow_m3 > 0.0);
    assert_eq!(a, b);
    assert_eq!(plain, filled);
    let mut fresh = Vec::new();
    crate::phenomenon::fill_surface(&filled, &mut fresh);
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&surface), bits(&fresh));
}

#[test]
fn table_lookups_give_the_bits_of_the_cell_by_cell_lookups() {
    // A day whose hours cross 0 °C and the melt threshold at different lapse offsets.
    let hours: Vec<MeltHour> = (0..24)
        .map(|h| dark_hour(if h == 23 { 0.5 } else { 1.0 }, -6.0 + 0.7 * h as f32))
        .collect();
    let offsets: Vec<f32> = (0..64).map(|k| -9.0 + 0.173 * k as f32).collect();
    let forcing = MeltForcing {
        hours: &hours,
        lapse_offset_c: &offsets,
        sky_view_factor: &[],
        reflected: &[],
        rain_m: &[],
        window_days: 1.0,
    };
    let k = Coefficients::new(&EnhancedMeltParams::default(), &forcing);
    // Ages, curves and offsets on and between the entries, at both ends of the tables and
    // past them, negative zero, NaN and infinities; 83 cells: ten groups of eight and a tail.
    let special = [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        -0.0,
        0.0,
        -3.0,
        1e9,
        3e9,
    ];
    let n = 83;
    let age: Vec<f32> = (0..n)
        .map(|i| {
            if i % 7 == 0 {
                special[(i / 7) % special.len()]
            } else {
                0.05 * i as f32 + 0.013 * (i % 3) as f32 + if i > 70 { 395.0 } else { 0.0 }
            }
        })
        .collect();
    let melting: Vec<f32> = (0..n)
        .map(|i| [0.0, 1.0, 0.5, 0.51, f32::NAN][i % 5])
        .collect();
    let off: Vec<f32> = (0..n)
        .map(|i| {
            if i % 9 == 4 {
                special[(i / 9) % special.len()]
            } else {
                -12.0 + 0.21 * i as f32
            }
        })
        .collect();
    let mut fast = [vec![0.0f32; n], vec![0.0f32; n], vec![0.0f32; n]];
    let mut slow = fast.clone();
    {
        let [a, c, w] = &mut fast;
        k.lookups(&off, (&age, &melting), (a, c, w));
    }
    {
        let [a, c, w] = &mut slow;
        k.lookups_scalar(&off, (&age, &melting), (a, c, w));
    }
    for (f, s) in fast.iter().zip(&slow) {
        for (i, (x, y)) in f.iter().zip(s).enumerate() {
            assert_eq!(x.to_bits(), y.to_bits(), "cell {i}: {x} vs {y}");
        }
    }
}

/// An hour without sun or recorded longwave, `weight` of it in the window, at `sea_level_c`.
fn dark_hour(weight: f32, sea_level_c: f32) -> MeltHour<'static> {
    MeltHour {
        weight,
        sea_level_c,
        beam: None,
        direct_w_m2: 0.0,
        diffuse_w_m2: 0.0,
        reflected_w_m2: 0.0,
        month: 0,
        longwave_balance_w_m2: 0.0,
        air: HourAir::default(),
    }
}
