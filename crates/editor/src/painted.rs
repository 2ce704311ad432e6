//! What the painted maps do when the season is stepped: avalanches start where the user
//! painted a release probability, and skiers ski the painted skier areas (Cordonnier et al.
//! 2018, Section 3: brushes that paint where events happen; Sections 6.1 and 6.2).
//!
//! The painted release probability `p` per day is a hazard source of the season's scheduler
//! ([`Winter::set_painted_release`]): one release zone per [`SITE_SPACING_M`] square releases
//! with probability `p` a day, as a rate spread over its cells and added to the natural hazard,
//! so painted avalanches start during the step's days, at the times the scheduler draws, from
//! the season's keyed random numbers (a replay gives the same avalanches); they run to rest
//! inside the season, counted in its avalanche list (trigger `painted`) and mass budget.
//! Painted skier areas send [`SKIERS_PER_DAY`] skiers a day from cells drawn in proportion to
//! the paint, after the step, each run to its terminus on the season's skier path
//! ([`Winter::ski_from`]): counted in its skier statistics and volume budget (compaction), its
//! avalanches started.

use crate::brush::PaintMaps;
use crate::protocol::ErrorCode;
use crate::session::Refusal;
use snowscape_season::winter::Winter;
use snowscape_terrain::random::uniform;

/// Spacing of the avalanche release sites, m.
pub const SITE_SPACING_M: f64 = 60.0;
/// Skier runs per day from the painted skier areas.
pub const SKIERS_PER_DAY: f64 = 4.0;
/// Most painted skier runs per step.
pub const MAX_EVENTS_PER_STEP: usize = 32;
const STREAM_SKIER: u64 = 0xed17_5c1e;

/// Hands the painted release probability to the season's scheduler (a map of zeros is no
/// painted source).
pub fn set_painted_release(winter: &mut Winter, paint: &PaintMaps) -> Result<(), Refusal> {
    winter
        .set_painted_release(Some(&paint.avalanche_probability), SITE_SPACING_M)
        .map_err(|e| (ErrorCode::InvalidValue, e.to_string()))
}

/// Sends the painted skier areas' skiers of the days of `winter` since `from_day`.
pub fn apply_painted(winter: &mut Winter, paint: &PaintMaps, from_day: f64) -> Result<(), Refusal> {
    let days = winter.day() - from_day;
    if days <= 0.0 {
        return Ok(());
    }
    let seed = winter.scenario().seed ^ from_day.to_bits();
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
