//! The season's workspace: the scratch buffers of the steps and the caches rebuilt from the
//! state (the wind's Sx and transport terms, the bedrock slopes, the avalanche hazard map),
//! kept apart from the state a checkpoint holds. As rapier's pipeline holds only buffers, the
//! workspace can be dropped at any time ([`Winter::drop_workspace`]): the next call that
//! steps the season rebuilds it ([`Winter::ensure_workspace`]) and the season continues
//! bit-identical (`tests/resume_skiers.rs`). The hazard map is rebuilt as a resume rebuilds
//! it: computed anew from the snow and marked stale, so the next avalanche start recomputes
//! it.

use super::{SeasonError, Winter};
use crate::avalanches::{self, HazardMap, HazardSources};
use crate::powder_diffusion::DiffusionScratch;
use crate::slope_shedding::SheddingScratch;
use crate::snowfall::SnowfallScratch;
use crate::snowtran_transport::SnowTranScratch;
use crate::stability::StabilityScratch;
use crate::wind_transport::{WindScratch, WindTerms};
use snowscape_skiers::SkiScratch;

/// Scratch buffers and caches of a season (module docs).
#[derive(Debug, Clone, Default)]
pub(super) struct SeasonWorkspace {
    pub snowfall: SnowfallScratch,
    pub stability: StabilityScratch,
    pub diffusion: DiffusionScratch,
    pub wind: WindScratch,
    pub snowtran: SnowTranScratch,
    pub shedding: SheddingScratch,
    pub ski: SkiScratch,
    /// Maximum upwind slope Sx for the current period's wind, degrees (Winstral et al. 2002).
    pub sx: Vec<f32>,
    /// The current wind field's snow-independent transport terms (the paper's wind model).
    pub wind_terms: Option<WindTerms>,
    /// Bedrock slope per cell, degrees (for the avalanche hazard).
    pub slope_deg: Vec<f32>,
    /// Avalanche hazard per cell, 1/day (recomputed when the snow changes).
    pub hazard: HazardMap,
    /// The hazard map may be out of date: an event that can change unstable snow ran since
    /// it was computed (an avalanche start recomputes it).
    pub hazard_stale: bool,
    /// Whether the caches are built (a dropped workspace is not).
    pub built: bool,
}

impl Winter {
    /// Drops the workspace: the steps' scratch buffers and the caches rebuilt from the state
    /// (Sx and the wind terms, the bedrock slopes, the hazard map; until the next step the
    /// hazard reads empty). The next call that steps the season rebuilds them and the season
    /// continues bit-identical.
    pub fn drop_workspace(&mut self) {
        self.workspace = SeasonWorkspace::default();
    }

    /// Rebuilds a dropped workspace's caches (nothing when they are built): the current
    /// period's Sx and wind terms, the bedrock slopes, and the hazard map of the snow, marked
    /// stale as a resume marks it.
    pub(super) fn ensure_workspace(&mut self) -> Result<(), SeasonError> {
        if self.workspace.built {
            return Ok(());
        }
        self.refresh_wind_terms()?;
        self.workspace.slope_deg = avalanches::bedrock_slopes_deg(&self.terrain);
        self.workspace.built = true;
        self.recompute_hazard();
        Ok(())
    }

    /// The hazard map of the snow as it is (with the recent skiers and the paint), marked
    /// stale: the scheduler's Avalanche-Start rate is left as it is, and the next start
    /// recomputes the map.
    pub(super) fn recompute_hazard(&mut self) {
        let skiers = self.recent_skier_map();
        let sources = HazardSources {
            skiers: skiers.as_deref(),
            painted: self.state.painted_release.as_deref(),
        };
        self.workspace.hazard.compute(
            &self.scenario.parameters.avalanche,
            &self.terrain,
            &self.workspace.slope_deg,
            &sources,
        );
        self.workspace.hazard_stale = true;
    }
}
