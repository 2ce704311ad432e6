//! # snowscape-season: snow-cover evolution through a winter
//!
//! The phenomena of Cordonnier et al. 2018, Section 5, each a module with a pure step
//! `step(params, state, scratch, dt) -> budget` over a [`LayeredTerrain`](snowscape_terrain::LayeredTerrain).
//! Every step reports the snow volume it added, removed or moved, so a run's mass budget is
//! tracked rather than hoped for.
//!
//! Beyond the paper, the default season follows sun, wind and slope on real terrain, each model
//! selectable against the paper's by name: [`melt::enhanced`] (enhanced temperature-index
//! melt with albedo, cold content and refreezing), [`climate`] and [`weather`] (climatology,
//! lapse rate, diurnal cycle, orographic precipitation and phase, hour by hour),
//! [`snowfall::add_precipitation`], [`slope_shedding`] (SnowSlide), the Sx redistribution of
//! [`wind_transport`], and station forcing ([`forcing`]).

pub mod avalanches;
pub mod checkpoint;
pub mod climate;
pub mod forcing;
pub mod melt;
pub mod parameter_catalogue;
pub mod phenomenon;
pub mod powder_diffusion;
pub mod scenario;
pub mod scheduler;
pub mod skiing;
pub mod slope_shedding;
pub mod snowfall;
pub mod snowtran_transport;
pub mod stability;
pub mod weather;
pub mod wind_transport;
pub mod winter;

/// Snow volume a step added to and removed from the terrain, m³ of snow.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VolumeChange {
    /// m³ of snow added (snowfall, deposit from outside).
    pub added: f64,
    /// m³ of snow removed (melt, outflow across the border).
    pub removed: f64,
}

/// Sums per-row partial sums in row order, so totals do not depend on the thread count.
pub(crate) fn ordered_sum(rows: &[f64]) -> f64 {
    rows.iter().sum()
}
