//! The per-cell formulas of the transport model (Jubert 2018, Section 5.5 and Annex I,
//! after Liston & Sturm 1998, "A snow-transport model for complex terrain", J. Glaciol. 44).
//!
//! Each function evaluates one equation (or a short group of them) for one cell, in SI
//! units and `f64`; the grid kernels call them or tables built from them.

pub mod density;
pub mod melt;
pub mod saltation;
pub mod shear;
pub mod sublimation;
pub mod suspension;

/// Freezing point of water `T_f`, K (Eq. 5.21).
pub const FREEZING_K: f64 = 273.15;
/// Gravitational acceleration `g`, m s⁻²: the model's one value, 9.81 (Section 5.5.2 writes
/// the standard 9.80665, 0.03 % less).
pub const GRAVITY: f64 = snowscape_terrain::materials::GRAVITY_M_S2;
/// von Kármán constant `κ` (Eq. 5.26: ≈ 0.40).
pub const VON_KARMAN: f64 = 0.4;
/// Density of water `ρw`, kg m⁻³ (Eq. 5.16; the shared value).
pub const WATER_DENSITY: f64 = snowscape_terrain::materials::WATER_DENSITY_KG_M3;
/// Density of ice `ρi`, kg m⁻³ (Eq. I.3; Liston & Sturm 1998: 917; the shared value).
pub const ICE_DENSITY: f64 = snowscape_terrain::materials::ICE_DENSITY_KG_M3;
