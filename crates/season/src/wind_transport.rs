//! Wind transport (Cordonnier et al. 2018, Section 5.4 and the race-free update of 7.1).
//!
//! **Erosion.** The wind resistance of the snow surface is
//! `curvW = |W_x| ∂²A/∂x² + |W_y| ∂²A/∂y²` (s⁻¹), zeroed where positive (concave ground
//! shelters its snow) and in the wind shadow (where the wind-effect surface `Wz` floats
//! above the snow surface). A cell loses `min(P + U, −k_erosion · curvW · δt)`: powder
//! first, then unstable snow (Figure 10 scours both). The paper prints `max`; the amount
//! eroded cannot exceed the snow present, so it is a `min` (`docs/src/model.md#wind-transport`).
//!
//! **Deposit.** The eroded snow goes to the two neighbours downwind, split by the wind
//! components: the share `|W_x| / (|W_x| + |W_y|)` to the east or west neighbour (sign of
//! `W_x`), the rest to the north or south one (sign of `W_y`, north positive). It lands as
//! powder, or as unstable snow where the receiving surface is steeper than
//! `slab_slope_deg` ("unstable wind plates", Figure 10). Snow blown across the grid border
//! leaves it and is reported as border outflow; a share aimed at a nodata cell stays put.
//!
//! **Tamping.** "Wind also weakens the stability of snow cover by tamping slopes, thereby
//! forming a thin brittle shell over snow that would otherwise spill downslope ... we
//! increase instability in proportion to positive changes in vertical wind speed." The
//! vertical wind speed is `W_sz = W · ∇Wz` (Section 4.2), so its change along the wind is the
//! vertical acceleration `a_z = W · ∇(W · ∇Wz) ≈ W_x² ∂²Wz/∂x² + 2 W_x W_y ∂²Wz/∂x∂y +
//! W_y² ∂²Wz/∂y²` (m/s², the unit of the paper's `c`). Where `a_z > 0` (where the wind is
//! pushed up: the foot of windward slopes and where a shadow cap lands again on the lee
//! slope) the share `x/(1+x)`, `x = k_tamping · a_z · δt`, of the powder (the snow that
//! "would otherwise spill") becomes unstable snow.
//!
//! **Parallel update.** Scattering to two neighbours races. Pass 1 computes each cell's two
//! outgoing amounts (signed by direction) from the old state; pass 2 has every cell remove
//! its own erosion and *gather* what its four neighbours send it. Each amount is computed
//! once and read by exactly one receiver, so the update is conservative and bit-identical for
//! any thread count, with no colour tiling needed.
//!
//! **Sheltering (beyond the paper).** With an `Sx` map in [`WindMaps::sx`] (Winstral et al.
//! 2002's maximum upwind slope, `snowscape_environment::max_upwind_slope`) and
//! [`WindTransportParams::sx_redistribution`] enabled, a second term scours exposed cells and
//! drifts the snow onto sheltered cells downwind ([`sheltered`]); it works over distances in
//! metres, so lee slopes load at 5 m and at 50 m cells alike, where the paper's curvature term
//! fades with the cell size. Its drifting snow sublimates on the way where the maps carry the
//! air temperature (Liston & Sturm 1998, [`sheltered::blowing_snow`]); the paper's one-hop
//! transport is left lossless. Without a map (`sx: None`) the step is the paper's alone.
//!
//! **Stencils.** Second differences are central in the interior. At the grid border, and
//! next to nodata, they are one-sided (`A_0 − 2A_1 + A_2`, the curvature of the nearest full
//! stencil) when two cells exist on one side, and 0 otherwise; the cross derivative of `Wz`
//! is 0 unless all four diagonal neighbours hold data.

use crate::VolumeChange;
use crate::phenomenon::{
    PhenomenonError, Validity, check_dt, check_map, check_range, fill_surface, with_validity,
};
use serde::{Deserialize, Serialize};
use snowscape_terrain::{GridGeometry, LayeredTerrain, NodataMask};

pub mod sheltered;
mod stencils;
mod terms;
pub use sheltered::{DriftSublimationParams, SxParams};
pub use snowscape_terrain::operators::{one_sided_second_difference, second_difference};
pub use stencils::{
    downwind_split, eroded_depth, erosion_curvature, tamping_share, vertical_wind_change,
};
pub use terms::WindTerms;

/// Which physics moves snow with the wind in a season.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum WindModel {
    /// Cordonnier 2018 Section 5.4: curvature erosion, deposit downwind, wind shadows.
    #[default]
    Cordonnier,
    /// Jubert 2018 Section 5.5 (SnowTran-3D): saltation with the fetch rule, suspension and
    /// sublimation ([`crate::snowtran_transport`], parameters in `[parameters.snowtran]`).
    Snowtran,
}

/// Parameters of wind transport.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct WindTransportParams {
    /// The physics of the wind events (the scenario switch). Default: Cordonnier's.
    pub model: WindModel,
    /// Erosion rate, m of snow per day per s⁻¹ of negative `curvW` (m·s/day). Cordonnier 2018
    /// Table 2 lists k_erosion = 0.1 (units garbled in the text; `k · curvW · δt` must be a
    /// depth, which fixes them). With a 10 m/s wind over a crest of curvature −0.02 /m this
    /// scours 1 cm per half-day event.
    pub k_erosion: f64,
    /// Whether unstable snow is scoured too once the powder is gone (Figure 10). Chosen here:
    /// true.
    pub erode_unstable: bool,
    /// Surface slope above which deposited snow lands as unstable snow ("unstable wind
    /// plates", Figure 10), degrees. Chosen here: 30° (where slab avalanches start).
    pub slab_slope_deg: f64,
    /// Tamping rate: share of the powder turned unstable per day per m/s² of upward vertical
    /// wind acceleration, 1/(day·m·s⁻²). Chosen here: 0.2, so where the wind meets the ground
    /// again at about the paper's `c = 0.7 m/s²`, a week of wind turns half the powder into a
    /// brittle shell.
    pub k_tamping: f64,
    /// The Sx-driven scour and drift (beyond the paper; runs only when [`WindMaps::sx`] is
    /// given).
    pub sx_redistribution: SxParams,
}

impl Default for WindTransportParams {
    fn default() -> Self {
        Self {
            model: WindModel::Cordonnier,
            k_erosion: 0.1,
            erode_unstable: true,
            slab_slope_deg: 30.0,
            k_tamping: 0.2,
            sx_redistribution: SxParams::default(),
        }
    }
}

impl WindTransportParams {
    /// Checks the rates are in [0, 100] (a thousand and five hundred times the defaults) and
    /// the slab slope in [0, 90).
    pub fn validate(&self) -> Result<(), PhenomenonError> {
        const P: &str = "wind transport";
        check_range(P, "k_erosion", self.k_erosion, [0.0, 100.0], "")?;
        check_range(
            P,
            "k_tamping",
            self.k_tamping,
            [0.0, 100.0],
            " 1/(day·m·s⁻²)",
        )?;
        check_range(P, "slab_slope_deg", self.slab_slope_deg, [0.0, 90.0], " °")?;
        if self.slab_slope_deg >= 90.0 {
            return Err(PhenomenonError::InvalidParameter {
                phenomenon: "wind transport",
                name: "slab_slope_deg",
                value: self.slab_slope_deg,
                reason: "a slope angle must be below 90°",
            });
        }
        self.sx_redistribution.validate()
    }
}

/// The precomputed wind field (Section 4.2), one value per cell.
#[derive(Debug, Clone, Copy)]
pub struct WindMaps<'a> {
    /// Wind velocity towards the east, m/s.
    pub u: &'a [f32],
    /// Wind velocity towards the north, m/s.
    pub v: &'a [f32],
    /// Wind shadow: 1 where the wind-effect surface lies above the ground, else 0.
    pub shadow: &'a [f32],
    /// Altitude of the wind-effect surface `Wz`, m.
    pub effect_surface: &'a [f32],
    /// Maximum upwind slope `Sx` for the wind's direction, degrees (Winstral et al. 2002;
    /// `snowscape_environment::max_upwind_slope`). `None`: the paper's transport alone.
    pub sx: Option<&'a [f32]>,
    /// The terms of this wind field that do not depend on the snow ([`WindTerms::new`], once
    /// per wind field). `None`: each step computes them.
    pub terms: Option<&'a WindTerms>,
    /// Air temperature of every cell, °C: the Sx term's drifting snow sublimates at it
    /// ([`sheltered::blowing_snow`]). `None`: no sublimation.
    pub air_temperature: Option<&'a [f32]>,
}

impl WindMaps<'_> {
    fn check(&self, geometry: &GridGeometry) -> Result<(), PhenomenonError> {
        check_map("wind_u", self.u, geometry)?;
        check_map("wind_v", self.v, geometry)?;
        check_map("wind_shadow", self.shadow, geometry)?;
        check_map("wind_effect_surface", self.effect_surface, geometry)?;
        if let Some(terms) = self.terms {
            terms.check(geometry)?;
        }
        if let Some(t) = self.air_temperature {
            check_map("air_temperature", t, geometry)?;
        }
        sheltered::check(self, geometry)
    }
}

/// Volumes moved by one wind-transport step, m³ of snow. `eroded`, `deposited`,
/// `deposited_unstable` and `border_outflow` cover both terms (the paper's and the Sx one).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct WindReport {
    /// Snow scoured from the surface (powder and unstable snow; stable snow too by the Sx
    /// term).
    pub eroded: f64,
    /// Snow deposited inside the grid (`eroded − border_outflow − sublimated`).
    pub deposited: f64,
    /// The part of `deposited` that landed as unstable snow on steep slopes.
    pub deposited_unstable: f64,
    /// Snow blown out of the grid.
    pub border_outflow: f64,
    /// Powder turned into unstable snow by tamping.
    pub tamped: f64,
    /// The part of `eroded` scoured by the Sx term.
    pub sx_eroded: f64,
    /// The part of `deposited` laid down by the Sx term.
    pub sx_deposited: f64,
    /// Drifting snow of the Sx term that sublimated on its way (blowing-snow sublimation).
    pub sublimated: f64,
}

impl WindReport {
    /// The step's volume budget: border outflow and sublimation are the volumes removed.
    pub fn volume_change(&self) -> VolumeChange {
        VolumeChange {
            added: 0.0,
            removed: self.border_outflow + self.sublimated,
        }
    }
}

/// Reusable buffers of the wind-transport step.
#[derive(Debug, Clone, Default)]
pub struct WindScratch {
    surface: Vec<f32>,
    /// The snow surface after the paper's passes, written by the deposit pass for the Sx
    /// term (then swapped with `surface`).
    surface_after: Vec<f32>,
    /// Depth each cell sends east (> 0) or west (< 0), m.
    out_x: Vec<f32>,
    /// Depth each cell sends north (> 0) or south (< 0), m.
    out_y: Vec<f32>,
    /// Buffers of the Sx term.
    sx: sheltered::SxScratch,
    /// The wind's terms, when the maps come without them.
    terms: WindTerms,
}

/// Moves snow with the wind over `dt_days`.
pub fn step(
    params: &WindTransportParams,
    terrain: &mut LayeredTerrain,
    wind: &WindMaps,
    scratch: &mut WindScratch,
    dt_days: f64,
) -> Result<WindReport, PhenomenonError> {
    params.validate()?;
    check_dt(dt_days)?;
    let geometry = terrain.geometry().clone();
    wind.check(&geometry)?;
    let mask = terrain.mask().clone();
    let n = geometry.len();
    fill_surface(terrain, &mut scratch.surface);
    scratch.out_x.resize(n, 0.0);
    scratch.out_y.resize(n, 0.0);
    let ctx = Context::new(&geometry, &mask, wind, params, dt_days);
    // The wind's snow-independent terms: given, or computed here (in the scratch's buffer).
    let mut own_terms = std::mem::take(&mut scratch.terms);
    let terms = match wind.terms {
        Some(t) => t,
        None => {
            with_validity!(mask, |valid| own_terms.compute(&ctx, valid));
            &own_terms
        }
    };
    let sx_params = &params.sx_redistribution;
    let sx_map = wind.sx.filter(|_| sx_params.enabled);
    let (pass1, pass2, sx) = with_validity!(mask, |valid| {
        let p1 = erosion::run(&ctx, valid, terrain, scratch);
        // The Sx term reads the surface the paper's passes leave: the deposit pass writes it.
        let fill = sx_map.is_some();
        let p2 = deposit::run(&ctx, valid, terms, terrain, scratch, fill);
        if fill {
            std::mem::swap(&mut scratch.surface, &mut scratch.surface_after);
        }
        let sx = sx_map.map(|sx| {
            sheltered::run(
                &ctx,
                valid,
                sx_params,
                (sx, &scratch.surface, terms.dominant),
                terrain,
                &mut scratch.sx,
                dt_days,
            )
        });
        (p1, p2, sx.unwrap_or_default())
    });
    scratch.terms = own_terms;
    let area = geometry.cell_area();
    let sum = |rows: &[f64]| rows.iter().sum::<f64>() * area;
    let col = |rows: &[[f64; 3]], k: usize| rows.iter().map(|r| r[k]).sum::<f64>() * area;
    let eroded: Vec<f64> = pass1.iter().map(|r| r[0]).collect();
    let border: Vec<f64> = pass1.iter().map(|r| r[1]).collect();
    Ok(WindReport {
        eroded: sum(&eroded) + sx.eroded * area,
        border_outflow: sum(&border) + sx.border * area,
        deposited: col(&pass2, 0) + sx.deposited * area,
        deposited_unstable: col(&pass2, 1) + sx.deposited_unstable * area,
        tamped: col(&pass2, 2),
        sx_eroded: sx.eroded * area,
        sx_deposited: sx.deposited * area,
        sublimated: sx.sublimated * area,
    })
}

/// What both passes read.
struct Context<'a> {
    geometry: &'a GridGeometry,
    mask: &'a NodataMask,
    wind: &'a WindMaps<'a>,
    inv_dx2: f32,
    inv_dy2: f32,
    inv_4dxdy: f32,
    erosion_dt: f32,
    tamping_dt: f32,
    slab_gradient: f32,
    erode_unstable: bool,
}

impl<'a> Context<'a> {
    fn new(
        geometry: &'a GridGeometry,
        mask: &'a NodataMask,
        wind: &'a WindMaps<'a>,
        params: &WindTransportParams,
        dt_days: f64,
    ) -> Self {
        Self {
            geometry,
            mask,
            wind,
            inv_dx2: (1.0 / (geometry.cell_size_x() * geometry.cell_size_x())) as f32,
            inv_dy2: (1.0 / (geometry.cell_size_y() * geometry.cell_size_y())) as f32,
            inv_4dxdy: (0.25 / (geometry.cell_size_x() * geometry.cell_size_y())) as f32,
            erosion_dt: (params.k_erosion * dt_days) as f32,
            tamping_dt: (params.k_tamping * dt_days) as f32,
            slab_gradient: params.slab_slope_deg.to_radians().tan() as f32,
            erode_unstable: params.erode_unstable,
        }
    }

    /// Value of `field` at `(col + dc, row + dr)` if that cell is inside and holds data.
    #[inline]
    fn at<V: Validity>(
        &self,
        valid: &V,
        field: &[f32],
        col: usize,
        row: usize,
        dc: isize,
        dr: isize,
    ) -> Option<f32> {
        self.geometry
            .neighbour(col, row, dc, dr)
            .filter(|&j| valid.at(j))
            .map(|j| field[j])
    }

    /// `(∂²f/∂x², ∂²f/∂y²)` at any cell, with the border rules of the module docs.
    fn second_differences<V: Validity>(
        &self,
        valid: &V,
        field: &[f32],
        col: usize,
        row: usize,
    ) -> (f32, f32) {
        let f = |dc, dr| self.at(valid, field, col, row, dc, dr);
        let centre = field[row * self.geometry.width() + col];
        let axis = |m2, m1, p1, p2| match (m2, m1, p1, p2) {
            (_, Some(m), Some(p), _) => second_difference(m, centre, p),
            (_, _, Some(p), Some(pp)) => one_sided_second_difference(centre, p, pp),
            (Some(mm), Some(m), _, _) => one_sided_second_difference(centre, m, mm),
            _ => 0.0,
        };
        (
            axis(f(-2, 0), f(-1, 0), f(1, 0), f(2, 0)) * self.inv_dx2,
            axis(f(0, -2), f(0, -1), f(0, 1), f(0, 2)) * self.inv_dy2,
        )
    }

    /// `∂²f/∂x∂y` (y north) at any cell: 0 unless the four diagonal neighbours hold data.
    fn cross_difference<V: Validity>(
        &self,
        valid: &V,
        field: &[f32],
        col: usize,
        row: usize,
    ) -> f32 {
        let f = |dc, dr| self.at(valid, field, col, row, dc, dr);
        match (f(1, -1), f(-1, -1), f(1, 1), f(-1, 1)) {
            (Some(ne), Some(nw), Some(se), Some(sw)) => (ne - nw - se + sw) * self.inv_4dxdy,
            _ => 0.0,
        }
    }
}

mod deposit;
mod erosion;

#[cfg(test)]
mod tests;
