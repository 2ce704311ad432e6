//! The season's budgets: snow volume (closes to round-off) and the pack's liquid water.

use serde::{Deserialize, Serialize};

/// The snow budget of a season, m³ of snow (densification changes volume, not mass: it is
/// listed as a sink of volume).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SeasonBudget {
    /// Snow on the terrain at the start.
    pub initial_store: f64,
    /// Added by snowfall.
    pub snowfall: f64,
    /// Removed by melt.
    pub melt: f64,
    /// Volume lost as stable snow compacts into denser compacted snow.
    pub densification: f64,
    /// Powder that diffused out of the grid.
    pub diffusion_outflow: f64,
    /// Snow blown out of the grid.
    pub wind_outflow: f64,
    /// Blowing snow sublimated: the drifting snow of the Sx redistribution (Liston & Sturm
    /// 1998) or of the physical wind transport.
    #[serde(default)]
    pub wind_sublimation: f64,
    /// Avalanche snow that flowed out of the grid.
    pub avalanche_outflow: f64,
    /// Snowpack the avalanches entrained along their tracks and laid down in their debris
    /// (moved inside the grid; not in the closure).
    #[serde(default)]
    pub avalanche_entrained: f64,
    /// Liquid water refrozen into the pack (a source of snow volume).
    #[serde(default)]
    pub refreeze: f64,
    /// Snow lost to vapour at the surface (sublimation; the energy-balance melt).
    #[serde(default)]
    pub sublimation: f64,
    /// Snow gained from vapour at the surface (deposition; the energy-balance melt).
    #[serde(default)]
    pub deposition: f64,
    /// The water equivalent of `sublimation`, m³ of water.
    #[serde(default)]
    pub sublimation_water: f64,
    /// The water equivalent of `deposition`, m³ of water.
    #[serde(default)]
    pub deposition_water: f64,
    /// Snow shed off steep slopes across the grid border.
    #[serde(default)]
    pub shedding_outflow: f64,
    /// Snow the slopes shed and the cells below received (moved inside the grid; not in
    /// the closure).
    #[serde(default)]
    pub shedding_moved: f64,
    /// The liquid water of the pack, m³ of water.
    #[serde(default)]
    pub water: WaterBudget,
}

/// The liquid water of the snowpack, m³ of water: rain and melt in, refreezing and runoff
/// out; `store` is what the pack holds now.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct WaterBudget {
    /// Rain on every valid cell (on snow it joins the pack's water; on bare ground it runs off).
    pub rain: f64,
    /// Water equivalent of the snowfall.
    pub snowfall_water: f64,
    /// Melt water.
    pub melt: f64,
    /// Water refrozen.
    pub refrozen: f64,
    /// Water that left the pack and bare ground.
    pub runoff: f64,
    /// Water held in the pack now.
    pub store: f64,
    /// Rain waiting for the next melt window (counted in `rain`, not yet in `store`).
    pub pending: f64,
}

impl WaterBudget {
    /// `rain + melt − refrozen − runoff − store − pending`: zero when the water closes.
    pub fn closure_error(&self) -> f64 {
        self.rain + self.melt - self.refrozen - self.runoff - self.store - self.pending
    }
}

impl SeasonBudget {
    /// `initial + inputs − outputs`: what the store should hold.
    pub fn expected_store(&self) -> f64 {
        self.initial_store + self.snowfall
            - self.melt
            - self.densification
            - self.diffusion_outflow
            - self.wind_outflow
            - self.wind_sublimation
            - self.avalanche_outflow
            - self.shedding_outflow
            - self.sublimation
            + self.refreeze
            + self.deposition
    }
}
