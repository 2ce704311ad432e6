//! Kernels of the season beyond the paper (issue: snow that follows the sun, the wind and the
//! slope): the hourly sun of the season's months, the enhanced temperature-index melt of one
//! day's window, slope shedding and the maximum upwind slope Sx.
//!
//! Bytes per cell: `environment/hourly_sun` 4 (the height field read; every sweep reads it
//! again, a byte per hour written); `season/enhanced_melt` 45 (4 layers and 4 surface-state
//! maps read and written, lapse offset and sky view read, ~12 beam bytes);
//! `season/slope_shedding` 40 (4 layers read and written, bedrock, order and scratch);
//! `environment/sheltering` 8 (height read, Sx written; each ray re-reads its cells).

use crate::kernel::{Kernel, KernelError};
use snowscape_environment::{
    EnvironmentParams, ShelteringParams, max_upwind_slope, precompute, season_sun,
};
use snowscape_season::melt::{
    EnhancedMeltParams, HourAir, MeltForcing, MeltHour, SnowpackState, enhanced,
};
use snowscape_season::slope_shedding::{self, SheddingParams, SheddingScratch};
use snowscape_terrain::{Grid, LayeredTerrain, SnowLayer};
use std::hint::black_box;
use std::sync::Arc;

/// The four kernels on `terrain`.
pub fn snowpack_kernels(terrain: &Grid) -> Result<Vec<Kernel>, KernelError> {
    let cells = terrain.data().len();
    let t = LayeredTerrain::from_bedrock(terrain.clone());
    let mut env = EnvironmentParams::default();
    env.sun.num_days = 100;
    let maps = precompute(&t.bedrock, t.geometry(), t.mask(), &env)?;
    let svf = maps.sky_view_factor.clone();
    let sun = Arc::new(season_sun(&t.bedrock, t.geometry(), t.mask(), &env, &svf)?);
    let mut kernels = Vec::new();
    {
        let (t, env, svf) = (t.clone(), env.clone(), svf.clone());
        kernels.push(Kernel::new(
            "environment/hourly_sun",
            cells,
            4.0,
            move || {
                black_box(season_sun(&t.bedrock, t.geometry(), t.mask(), &env, &svf)?);
                Ok(())
            },
        ));
    }
    {
        // One day of March sun (the month's hours) over 1 m of settled snow and 10 cm of
        // powder, at sea-level temperatures that melt the lower half of the terrain.
        let mut snow = t.clone();
        snow.layer_mut(SnowLayer::Stable).fill(1.0);
        snow.layer_mut(SnowLayer::Powder).fill(0.1);
        let offset: Arc<Vec<f32>> = Arc::new(snow.bedrock.iter().map(|z| -0.0065 * z).collect());
        let sun = sun.clone();
        let mut pack = SnowpackState::new(cells);
        let fresh = snow.clone();
        kernels.push(Kernel::new(
            "season/enhanced_melt",
            cells,
            45.0,
            move || {
                let month = sun.months.last().expect("a month");
                let hours: Vec<MeltHour> = (0..24u32)
                    .map(|h| MeltHour {
                        weight: 1.0,
                        sea_level_c: 12.0
                            + 5.0 * ((h as f32 + 0.5 - 15.0) * std::f32::consts::TAU / 24.0).cos(),
                        beam: month.hour(h).map(|s| s.beam.as_slice()),
                        direct_w_m2: 800.0,
                        diffuse_w_m2: 60.0,
                        reflected_w_m2: 300.0,
                        month: sun.months.len() - 1,
                        longwave_balance_w_m2: 0.0,
                        air: HourAir::default(),
                    })
                    .collect();
                let reflected: Vec<&[f32]> =
                    sun.months.iter().map(|m| m.reflected.as_slice()).collect();
                let forcing = MeltForcing {
                    hours: &hours,
                    lapse_offset_c: &offset,
                    sky_view_factor: &sun.sky_view_factor,
                    reflected: &reflected,
                    rain_m: &[],
                    window_days: 1.0,
                };
                enhanced::step(
                    &EnhancedMeltParams::default(),
                    &mut snow,
                    &mut pack,
                    &forcing,
                )?;
                if snow.snow_volume() < 0.5 * fresh.snow_volume() {
                    snow.clone_from(&fresh);
                }
                Ok(())
            },
        ));
    }
    {
        let mut snow = t.clone();
        snow.layer_mut(SnowLayer::Stable).fill(1.0);
        let fresh = snow.clone();
        let mut scratch = SheddingScratch::default();
        kernels.push(Kernel::new(
            "season/slope_shedding",
            cells,
            40.0,
            move || {
                snow.clone_from(&fresh);
                slope_shedding::step(&SheddingParams::default(), &mut snow, &mut scratch, 0.5)?;
                Ok(())
            },
        ));
    }
    {
        let t = t.clone();
        kernels.push(Kernel::new(
            "environment/sheltering",
            cells,
            8.0,
            move || {
                black_box(max_upwind_slope(
                    &t.bedrock,
                    t.geometry(),
                    t.mask(),
                    270.0,
                    &ShelteringParams::default(),
                )?);
                Ok(())
            },
        ));
    }
    Ok(kernels)
}
