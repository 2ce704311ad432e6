//! Kernels of `snowscape-environment` and `snowscape-season` (Cordonnier 2018 §4-5).
//!
//! Bytes per cell are the compulsory traffic of one call (every input read once, every
//! output written once), the floor a perfect kernel would move; the sweeps of the
//! precompute read the height field once per direction on top of it.

use crate::kernel::{Kernel, KernelError};
use snowscape_environment::{EnvironmentMaps, EnvironmentParams, precompute};
use snowscape_season::avalanches::{
    AvalancheParameters, HazardMap, HazardSources, bedrock_slopes_deg,
};
use snowscape_season::melt::{self, MeltParams};
use snowscape_season::powder_diffusion::{self, DiffusionParams, DiffusionScratch};
use snowscape_season::scenario::Scenario;
use snowscape_season::scheduler::EventKind;
use snowscape_season::snowfall::{self, SnowfallParams, SnowfallScratch};
use snowscape_season::stability::{self, StabilityParams, StabilityScratch};
use snowscape_season::wind_transport::{
    self, WindMaps, WindScratch, WindTerms, WindTransportParams,
};
use snowscape_season::winter::Winter;
use snowscape_terrain::{Grid, LayeredTerrain, SnowLayer};
use std::hint::black_box;

/// Days of the benchmarked season (the paper's 100-day winter, §8).
pub const SEASON_DAYS: f64 = 100.0;

/// A terrain with 0.3 m of each snow layer above the lowest third of its altitudes.
fn snowy(terrain: &Grid) -> LayeredTerrain {
    let (lo, hi) = terrain.value_range().unwrap_or((0.0, 0.0));
    let snowline = lo + (hi - lo) / 3.0;
    let mut t = LayeredTerrain::from_bedrock(terrain.clone());
    let bedrock = t.bedrock.clone();
    for layer in SnowLayer::ALL {
        for (d, &z) in t.layer_mut(layer).iter_mut().zip(&bedrock) {
            *d = if z > snowline { 0.3 } else { 0.0 };
        }
    }
    t
}

/// The precompute and each phenomenon step on `terrain`, and a whole 100-day season.
/// - `environment/precompute`: sun, sky, bounce, temperature, wind; 44 B/cell (read the
///   height field, write ten f32 maps);
/// - `season/snowfall` 48 B/cell (read 5 layers + temperature, surface write+read, write 3
///   layers), `season/melt` 36 (temperature, 4 layers read+written), `season/stability` 44
///   (temperature, 4 layers read+written, surface), `season/powder_diffusion` 36 (5 layers
///   read, surface write+read, powder read+written, scale), `season/wind_transport` 72 (4 wind
///   maps, 5 layers, two flux maps written and read, powder and unstable written);
/// - `season/hazard_map`: the natural-release hazard map `λ_i` and its row sums, 20 B/cell
///   (unstable snow and the cached slope window read, `λ` written);
/// - `season/100_days`: the event loop of a 100-day winter without avalanches (environment
///   precomputed once, outside the timing); cells = grid cells × grid-wide events, 45 B per
///   cell-event (the mean of the steps above);
/// - `season/100_days_with_avalanches`: the default winter, natural avalanches included (each
///   run to rest); cells = grid cells × days, no bandwidth model.
pub fn season_kernels(terrain: &Grid) -> Result<Vec<Kernel>, KernelError> {
    let cells = terrain.data().len();
    let base = snowy(terrain);
    let env = EnvironmentParams::default();
    let maps = precompute(&base.bedrock, base.geometry(), base.mask(), &env)?;
    let mut kernels = Vec::new();
    {
        let t = base.clone();
        let env = env.clone();
        kernels.push(Kernel::new(
            "environment/precompute",
            cells,
            44.0,
            move || {
                black_box(precompute(&t.bedrock, t.geometry(), t.mask(), &env)?);
                Ok(())
            },
        ));
    }
    kernels.extend(phenomenon_kernels(&base, &maps)?);
    kernels.extend(season_loop_kernels(terrain)?);
    Ok(kernels)
}

/// One kernel per grid-wide phenomenon step (snowfall, melt, stability, hazard map, powder
/// diffusion, wind transport) on the snowy terrain `base` with its environment `maps`.
fn phenomenon_kernels(
    base: &LayeredTerrain,
    maps: &EnvironmentMaps,
) -> Result<Vec<Kernel>, KernelError> {
    let cells = base.bedrock.len();
    let mut kernels = Vec::new();
    let temperature = maps.temperature.clone();
    {
        let (mut t, temp, mut scratch) = (
            base.clone(),
            temperature.clone(),
            SnowfallScratch::default(),
        );
        kernels.push(Kernel::new("season/snowfall", cells, 48.0, move || {
            snowfall::step(&SnowfallParams::default(), &mut t, &temp, &mut scratch, 0.5)?;
            Ok(())
        }));
    }
    {
        // Melt at a fixed temperature above freezing; refill so every call melts something.
        let (mut t, warm) = (base.clone(), vec![2.0f32; cells]);
        let fresh = base.clone();
        kernels.push(Kernel::new("season/melt", cells, 36.0, move || {
            melt::step(&MeltParams::default(), &mut t, &warm, 0.5)?;
            if t.snow_volume() < 0.5 * fresh.snow_volume() {
                t.clone_from(&fresh);
            }
            Ok(())
        }));
    }
    {
        let (mut t, temp, mut scratch) = (
            base.clone(),
            temperature.clone(),
            StabilityScratch::default(),
        );
        kernels.push(Kernel::new("season/stability", cells, 44.0, move || {
            stability::step(
                &StabilityParams::default(),
                &mut t,
                &temp,
                &mut scratch,
                0.5,
            )?;
            Ok(())
        }));
    }
    {
        // The natural-release hazard map, recomputed after every melt and snowfall event.
        let (t, mut map) = (base.clone(), HazardMap::default());
        let slopes = bedrock_slopes_deg(&t);
        let params = AvalancheParameters::default();
        kernels.push(Kernel::new("season/hazard_map", cells, 20.0, move || {
            let sources = HazardSources {
                skiers: None,
                painted: None,
            };
            black_box(map.compute(&params, &t, &slopes, &sources));
            Ok(())
        }));
    }
    {
        let (mut t, mut scratch) = (base.clone(), DiffusionScratch::default());
        kernels.push(Kernel::new(
            "season/powder_diffusion",
            cells,
            36.0,
            move || {
                powder_diffusion::step(&DiffusionParams::default(), &mut t, &mut scratch, 0.5)?;
                Ok(())
            },
        ));
    }
    {
        let (mut t, mut scratch) = (base.clone(), WindScratch::default());
        let (u, v, s, e) = (
            maps.wind_u.clone(),
            maps.wind_v.clone(),
            maps.wind_shadow.clone(),
            maps.wind_effect_surface.clone(),
        );
        // The wind field's snow-independent terms, once per field as a season computes them.
        let maps_of = |terms| WindMaps {
            u: &u,
            v: &v,
            shadow: &s,
            effect_surface: &e,
            sx: None,
            terms,
            air_temperature: None,
        };
        let terms = WindTerms::new(t.geometry(), t.mask(), &maps_of(None))?;
        // Surface (5 arrays read, 1 written), erosion (surface, wind, shadow, powder and
        // unstable snow read, 2 amounts written), deposit (surface, amounts, a_z read, powder
        // and unstable snow read and written): 22 f32 per cell.
        kernels.push(Kernel::new(
            "season/wind_transport",
            cells,
            88.0,
            move || {
                let w = WindMaps {
                    u: &u,
                    v: &v,
                    shadow: &s,
                    effect_surface: &e,
                    sx: None,
                    terms: Some(&terms),
                    air_temperature: None,
                };
                wind_transport::step(
                    &WindTransportParams::default(),
                    &mut t,
                    &w,
                    &mut scratch,
                    0.5,
                )?;
                Ok(())
            },
        ));
    }
    Ok(kernels)
}

/// The season's event loop over `terrain`: the 100-day winter without avalanches
/// (cells × grid-wide events) and the default winter with its natural avalanches (cell-days).
fn season_loop_kernels(terrain: &Grid) -> Result<Vec<Kernel>, KernelError> {
    let cells = terrain.data().len();
    let mut kernels = Vec::new();
    // The grid event loop alone (no avalanches): cells × grid-wide events.
    let mut calm = Scenario {
        days: SEASON_DAYS,
        ..Scenario::default()
    };
    calm.parameters.avalanche.natural = false;
    let start = Winter::new(calm, LayeredTerrain::from_bedrock(terrain.clone()))?;
    let mut probe = start.clone();
    probe.run_until(SEASON_DAYS)?;
    let events: u64 = probe
        .event_counts()
        .iter()
        .filter(|(k, _)| !matches!(k, EventKind::AvalancheStep | EventKind::SkierStep))
        .map(|(_, n)| n)
        .sum();
    kernels.push(Kernel::new(
        "season/100_days",
        cells * events as usize,
        45.0,
        move || {
            let mut w = start.clone();
            w.run_until(SEASON_DAYS)?;
            black_box(w.budget());
            Ok(())
        },
    ));
    // The default winter with its natural avalanches, each run to rest: cells × days
    // (cell-days; the avalanche cost follows their footprints, not the grid, so no bandwidth
    // model).
    let scenario = Scenario {
        days: SEASON_DAYS,
        ..Scenario::default()
    };
    let start = Winter::new(scenario, LayeredTerrain::from_bedrock(terrain.clone()))?;
    kernels.push(Kernel::new(
        "season/100_days_with_avalanches",
        cells * SEASON_DAYS as usize,
        0.0,
        move || {
            let mut w = start.clone();
            w.run_until(SEASON_DAYS)?;
            black_box(w.budget());
            Ok(())
        },
    ));
    Ok(kernels)
}
