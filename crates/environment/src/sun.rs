//! Direct sunlight with topographic shadows (Cordonnier et al. 2018, Section 4.1):
//!
//! `I_sun(p) = k_sun · (1/D) Σ_days Σ_h Δt_h · s_h(p) · max(0, n(p)·i_h)`
//!
//! where `i_h` is the unit vector towards the sun at sample `h` ([`crate::solar`]), `n` the
//! terrain normal, `s_h ∈ {0, 1}` the topographic shadowing (1 = the ray towards the sun clears
//! the terrain), `Δt_h` the hours the sample stands for and `D` the number of sampled days.
//! Units: hours per day of sun at normal incidence ("sun-hours"; a flat cell under a sun at
//! 30° elevation for 2 h gets 1 sun-hour), scaled by the dimensionless `k_sun`.
//!
//! Shadows come from one sweep per sun position along the sun's azimuth (`sweep::shadow_pass`):
//! O(cells) per position, no per-cell ray marching. The shadow term of a cell is the linear
//! blend of the two straight rays that bracket it (see `sweep`), so `s_h` takes values in
//! [0, 1] along shadow edges (antialiased over one cell). Nodata cells are transparent (they
//! never cast shadows) and receive 0.

use crate::field::TerrainField;
use crate::solar::{SunSample, day_samples, schedule_days};
use crate::sweep::{LineFrame, shadow_pass};
use crate::{EnvironmentError, SunParams};
use rayon::prelude::*;
use snowscape_terrain::{GridGeometry, NodataMask};

/// The sun positions of the schedule, each weighted by its hours divided by the number of
/// sampled days (so the weights of one day sum to its day length over `D`).
pub fn schedule(params: &SunParams) -> Result<Vec<SunSample>, EnvironmentError> {
    params.validate()?;
    let days = schedule_days(params.start_day, params.num_days, params.day_step);
    let per_day = 1.0 / days.len() as f64;
    Ok(days
        .iter()
        .flat_map(|&d| {
            day_samples(
                params.latitude_deg,
                d,
                params.samples_per_hour,
                params.declination,
            )
        })
        .map(|s| SunSample {
            weight_h: s.weight_h * per_day,
            ..s
        })
        .collect())
}

/// Direct sun exposure over the schedule of `params`, sun-hours per day (see module docs).
pub fn direct_sun(
    surface: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    params: &SunParams,
) -> Result<Vec<f32>, EnvironmentError> {
    let samples = schedule(params)?;
    let field = TerrainField::new(surface, geometry, mask)?;
    Ok(direct_sun_field(&field, &samples, params.k_sun))
}

/// Direct sun exposure for explicit sun positions: `k_sun Σ weight_h · s_h · max(0, n·i_h)`.
pub fn direct_sun_for(
    surface: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    samples: &[SunSample],
    k_sun: f64,
) -> Result<Vec<f32>, EnvironmentError> {
    let field = TerrainField::new(surface, geometry, mask)?;
    Ok(direct_sun_field(&field, samples, k_sun))
}

/// Lambert term of one cell: `max(0, n·i)` (0 for the zero normal of nodata cells).
#[inline(always)]
fn incidence(n: [f32; 3], sun: [f32; 3]) -> f32 {
    (n[0] * sun[0] + n[1] * sun[1] + n[2] * sun[2]).max(0.0)
}

/// `acc += weight · lit · max(0, n·sun)` over a layout, in parallel.
fn accumulate(acc: &mut [f32], lit: &[f32], normal: &[[f32; 3]], sun: [f32; 3], weight: f32) {
    acc.par_chunks_mut(4096)
        .zip(lit.par_chunks(4096))
        .zip(normal.par_chunks(4096))
        .for_each(|((a, l), n)| {
            for ((a, &l), &n) in a.iter_mut().zip(l).zip(n) {
                *a += weight * l * incidence(n, sun);
            }
        });
}

/// The sweep-based exposure on a prepared field.
pub(crate) fn direct_sun_field(
    field: &TerrainField,
    samples: &[SunSample],
    k_sun: f64,
) -> Vec<f32> {
    let mut acc_rows = vec![0.0f32; field.len()];
    let mut acc_cols = vec![0.0f32; field.len()];
    let mut lit = vec![0.0f32; field.len()];
    let mut sheared = Vec::new();
    for sample in samples.iter().filter(|s| s.direction[2] > 0.0) {
        let [e, n, u] = sample.direction;
        let sun = [e as f32, n as f32, u as f32];
        let weight = sample.weight_h as f32;
        let horizontal = (e * e + n * n).sqrt();
        if horizontal < 1e-9 {
            // Sun at the zenith: nothing casts a shadow.
            lit.fill(1.0);
            accumulate(&mut acc_rows, &lit, &field.rows.normal, sun, weight);
            continue;
        }
        let frame = LineFrame::new(field, e, n);
        let layout = field.layout(frame.transposed);
        shadow_pass(&frame, layout, (u / horizontal) as f32, &mut sheared);
        frame.unshear(&sheared, &mut lit, 0.0);
        let acc = if frame.transposed {
            &mut acc_cols
        } else {
            &mut acc_rows
        };
        accumulate(acc, &lit, &layout.normal, sun, weight);
    }
    field.add_transposed(&mut acc_rows, &acc_cols, |a, b| *a += b);
    let k = k_sun as f32;
    acc_rows.iter_mut().for_each(|a| *a *= k);
    acc_rows
}
