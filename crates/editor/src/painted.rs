//! What the painted maps do when the season is stepped: avalanches start where the user
//! painted a release probability, and skiers ski the painted skier areas (Cordonnier et al.
//! 2018, Section 3: brushes that paint where events happen; Sections 6.1 and 6.2).
//!
//! Release sites lie on a lattice of about [`SITE_SPACING_M`] (one site per rupture zone); a
//! site with painted probability `p` per day starts an avalanche during a step of `d` days with
//! probability `1 − (1 − p)^d`, drawn from keyed random numbers (seed, step start, cell), so a
//! replay gives the same avalanches. These run to rest inside the season
//! ([`Winter::trigger_avalanche`]) and are counted in its avalanche list and mass budget.
//! Painted skier areas send [`SKIERS_PER_DAY`] skiers a day from cells drawn in proportion to
//! the paint, each run to its terminus on the season's skier path ([`Winter::ski_from`]):
//! counted in its skier statistics and volume budget (compaction), its avalanches started.

use crate::brush::PaintMaps;
use crate::protocol::ErrorCode;
use crate::session::Refusal;
use snowscape_season::winter::{SeasonError, Winter};
use snowscape_terrain::random::uniform;

/// Spacing of the avalanche release sites, m.
pub const SITE_SPACING_M: f64 = 60.0;
/// Skier runs per day from the painted skier areas.
pub const SKIERS_PER_DAY: f64 = 4.0;
/// Most painted avalanches or skier runs per step.
pub const MAX_EVENTS_PER_STEP: usize = 32;
const STREAM_AVALANCHE: u64 = 0xed17_a7a1;
const STREAM_SKIER: u64 = 0xed17_5c1e;

/// Applies the painted maps to the days of `winter` since `from_day`.
pub fn apply_painted(winter: &mut Winter, paint: &PaintMaps, from_day: f64) -> Result<(), Refusal> {
    let days = winter.day() - from_day;
    if days <= 0.0 {
        return Ok(());
    }
    let key = from_day.to_bits();
    let seed = winter.scenario().seed ^ key;
    let g = winter.terrain.geometry().clone();
    let stride = ((SITE_SPACING_M / g.cell_size_x()).round() as usize).max(1);
    let mut fired = 0;
    'sites: for r in (stride / 2..g.height()).step_by(stride) {
        for c in (stride / 2..g.width()).step_by(stride) {
            let i = g.index(c, r);
            let p = paint.avalanche_probability[i] as f64;
            if p <= 0.0 {
                continue;
            }
            let prob = 1.0 - (1.0 - p.min(1.0)).powf(days);
            if uniform(seed, STREAM_AVALANCHE, i as u64) >= prob {
                continue;
            }
            let (x, y) = g.cell_centre(c, r);
            match winter.trigger_avalanche(x, y) {
                Ok(_) | Err(SeasonError::AvalanchePosition { .. }) => {}
                Err(e) => return Err((ErrorCode::Failed, e.to_string())),
            }
            fired += 1;
            if fired >= MAX_EVENTS_PER_STEP {
                break 'sites;
            }
        }
    }
    let total: f64 = paint.ski_area.iter().map(|&v| v as f64).sum();
    let runs = ((days * SKIERS_PER_DAY).round() as usize).min(MAX_EVENTS_PER_STEP);
    if total <= 0.0 || runs == 0 {
        return Ok(());
    }
    for k in 0..runs {
        let u = uniform(seed, STREAM_SKIER, k as u64) * total;
        let mut acc = 0.0;
        let Some(i) = paint.ski_area.iter().position(|&v| {
            acc += v as f64;
            acc > u
        }) else {
            continue;
        };
        ski_once(winter, i)?;
    }
    Ok(())
}

/// One skier from cell `i` to its terminus on the season's own skier-run path
/// ([`Winter::ski_from`]): its compaction in the season's budget, the avalanches it triggers
/// run at once (nothing when the cell holds no skiable snow).
fn ski_once(winter: &mut Winter, i: usize) -> Result<(), Refusal> {
    let g = winter.terrain.geometry().clone();
    let (c, r) = g.col_row(i);
    let (x, y) = g.cell_centre(c, r);
    winter
        .ski_from(x, y)
        .map(|_| ())
        .map_err(|e| (ErrorCode::Failed, e.to_string()))
}
