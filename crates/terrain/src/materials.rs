//! Physical constants and snow materials shared by every phenomenon, so that gravity, the
//! densities of water, ice and the snow layers, and the heats of phase change have one value
//! in the whole model (each with its unit and source).

use crate::SnowLayer;

/// Acceleration of gravity `g`, m/s²: 9.81, the value of Cordonnier et al. 2018 Table 2 (the
/// avalanche flow) and of Fearing 2000's edge transit. Jubert 2018 §5.5.2 writes the standard
/// 9.80665 (3rd CGPM, 1901), 0.03 % less, which the 3D transport used before the model had one
/// value (within 0.1 % of the local gravity anywhere on Earth's mountains, 9.77-9.83).
pub const GRAVITY_M_S2: f64 = 9.81;

/// Density of liquid water `ρw`, kg/m³ (at 0-4 °C; Jubert 2018 Eq. 5.16).
pub const WATER_DENSITY_KG_M3: f64 = 1000.0;

/// Density of ice `ρi`, kg/m³ (Cuffey & Paterson 2010 §2.1; Liston & Sturm 1998: 917).
pub const ICE_DENSITY_KG_M3: f64 = 917.0;

/// Latent heat of fusion of ice `L_f`, J/kg (Cuffey & Paterson 2010 Table 9.1: 3.34e5).
pub const LATENT_HEAT_FUSION_J_KG: f64 = 334_000.0;

/// Latent heat of sublimation of ice `h_s`, J/kg (Jubert 2018 Eq. I.6: 2.838e6).
pub const LATENT_HEAT_SUBLIMATION_J_KG: f64 = 2.838e6;

/// Specific heat of ice, J/(kg K) (Cuffey & Paterson 2010 Table 9.1, at 0 °C: 2097-2102).
pub const SPECIFIC_HEAT_ICE_J_KG_K: f64 = 2102.0;

/// Specific heat of liquid water, J/(kg K) (at 0-20 °C: 4186).
pub const SPECIFIC_HEAT_WATER_J_KG_K: f64 = 4186.0;

/// Default density of each snow layer, kg/m³, in [`SnowLayer::ALL`] order (compacted, stable,
/// unstable, powder). Compacted: Cordonnier et al. 2018 Table 2's ρ = 500 (also the density
/// of flowing snow in the avalanche model); stable: 300 (the 0.6 compaction ratio of the
/// stability phenomenon); unstable 250 and powder 150: our choice within Cuffey & Paterson
/// 2010 Table 2.1 (new snow 50-200, settled snow 200-300).
pub const LAYER_DENSITY_KG_M3: [f64; 4] = [500.0, 300.0, 250.0, 150.0];

// Snow is porous ice: every layer lighter than ice.
const _: () = assert!(LAYER_DENSITY_KG_M3[0] < ICE_DENSITY_KG_M3);

impl SnowLayer {
    /// The layer's default density, kg/m³ ([`LAYER_DENSITY_KG_M3`]).
    pub fn default_density_kg_m3(self) -> f64 {
        LAYER_DENSITY_KG_M3[self.index()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layer_densities_follow_the_layers_and_increase_with_age() {
        assert_eq!(SnowLayer::Compacted.default_density_kg_m3(), 500.0);
        assert_eq!(SnowLayer::Powder.default_density_kg_m3(), 150.0);
        for w in LAYER_DENSITY_KG_M3.windows(2) {
            assert!(
                w[0] > w[1],
                "older layers are denser: {LAYER_DENSITY_KG_M3:?}"
            );
        }
    }
}
