//! The flow's parameters, its errors and the report of a step.

use super::*;

/// What happens at the edges of the terrain: the grid's border and the nodata outline (see
/// the flow module's *Borders*).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Border {
    /// Snow leaves the terrain across the grid's border and into nodata cells (counted in
    /// [`AvalancheReport::border_outflow`]).
    #[default]
    Open,
    /// The border and the nodata cells are walls.
    Closed,
}

/// The basal friction law of the flow.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum FrictionLaw {
    /// The paper's: Coulomb friction `g·tanθc` weighted by α, and a viscous term
    /// `−(1 − α)·kv·h·u` (Cordonnier et al. 2018, §6.1, Table 2).
    Coulomb,
    /// Voellmy-Salm: a dry-friction deceleration `μ·g` and a turbulent drag `g·u²/(ξ·h)`
    /// (Voellmy 1955; Salm 1993; as in RAMMS and AvaFrame com1DFA's `frictModel = Voellmy`).
    /// In this horizontal-projection model the drive is `g·|∇A|`, so on a uniform plane of
    /// slope `tanθ > μ` a layer of thickness `h` tends to `u = sqrt(ξ·h·(tanθ − μ))`.
    Voellmy,
    /// samosAT as AvaFrame com1DFA computes it (`SamosATfric`): a dry friction
    /// `μ·g·(1 + Rs0/(Rs0 + Rs))` with `Rs = u²/(g·h)` (twice μ at rest, μ when fast) and a
    /// turbulent drag `u²/(h·(ln(max(h/R, 1))/κ + B)²)`. AvaFrame's τ0 enters its
    /// configuration but not that function, and is left out here too.
    ///
    /// Named `samosat` as on the command line (`--friction-model samosat`); `samos_at`, its
    /// name in scenario files and reports before, is still read so that they keep loading.
    /// The default ([`AvalancheParams::default`] with AvaFrame's `samosATSmall` coefficients).
    #[default]
    #[serde(rename = "samosat", alias = "samos_at")]
    SamosAt,
}

/// How gravity acts on the flow of the horizontal grid (vertical thickness `h`, horizontal
/// velocity `u`, bed slope θ with `cos²θ = 1/(1 + |∇B|²)`).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum SlopeGravity {
    /// Savage-Hutter's depth-averaged equations (Savage & Hutter 1989, J. Fluid Mech. 199;
    /// Mangeney et al. 2000, Pure Appl. Geophys. 157; in slope coordinates, as AvaFrame com1DFA
    /// solves them) projected on the horizontal grid: the along-slope acceleration
    /// `g sinθ − μ g cosθ − g cosθ ∂h_n/∂s` with `h_n = h cosθ`, `∂s = ∂x/cosθ`, `u = u_s cosθ`
    /// gives the horizontal `−g cos²θ (∇B + cos²θ ∇h)` and a dry friction `μ g cos²θ`, and a
    /// turbulent drag `g u_s²/(ξ h_n)` becomes `g u²/(ξ h cos²θ)`. On a plane: sliding at
    /// `g cos²θ (tanθ − μ)` and waves at `cos²θ sqrt(g h)`.
    ///
    /// With [`AvalancheParams::curvature`] (the default) the flow feels the bed's curvature
    /// as Savage-Hutter on a curved bed does (Gray, Wieland & Hutter 1999, Proc. R. Soc. A 455;
    /// AvaFrame com1DFA's curvature acceleration): (1) the bed's load becomes
    /// `cosθ (g + v·H·v)` (`H` the bed's Hessian, `v` the horizontal velocity: the centrifugal
    /// term, `± u_s²/R` on an arc of radius R; no less than 0, where the flow lifts off), and
    /// the dry friction with it, `μ cos²θ (g + v·H·v)` on the grid (AvaFrame's
    /// `curvAccInFriction`); (2) the reaction turns the flow along the bed: momentum is
    /// advected as the speed along the bed, `u·sqrt(1 + (v̂·∇B)²)`, so that where the slope eases
    /// the horizontal speed picks up the share the slope's tilt held (the horizontal share
    /// `−cos²θ (v·H·v) ∇B` of the reaction; AvaFrame projects its particles' velocity back onto
    /// the bed). Frictionless, the speed along the bed is kept through a bend
    /// (tests/curvature.rs). Without it, the horizontal speed is kept instead: on a 35° plane
    /// running out on flat ground a Coulomb block stops at a travel angle of 32.3° for
    /// θc = 30°. The pressure term keeps `g` (AvaFrame's `curvAccInGradient = 0`).
    #[default]
    Projected,
    /// The paper's shallow-slope form: gravity `g` whatever the slope (`−g ∇A`, friction
    /// `μ g`), exact for θ → 0 and 1/cos²θ too fast on steep slopes (16 % at 22°, 49 % at 35°,
    /// tests/avaframe_analytic.rs).
    Shallow,
}

/// The samosAT law's coefficients (AvaFrame com1DFA, after Sampl & Granig 2009; its
/// `samosATSmall` set, for releases below 25,000 m³, has μ = 0.22, `samosATMedium` μ = 0.17,
/// its standard `samosAT` μ = 0.155, the others equal). The default is the small set
/// ([`SamosAtParams::small`]); a table that names some coefficients takes the others from it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct SamosAtParams {
    /// Dry-friction coefficient μ = tanδ. Default 0.22 (AvaFrame `musamosatsmall`; its
    /// standard `musamosat` is 0.155: [`SamosAtParams::standard`]).
    pub mu: f64,
    /// Reference Froude-type number Rs0. Default 0.222 (AvaFrame `Rs0samosat`).
    pub rs0: f64,
    /// Von Kármán constant κ. Default 0.43 (AvaFrame `kappasamosat`).
    pub kappa: f64,
    /// Roughness length R, m. Default 0.05 (AvaFrame `Rsamosat`).
    pub roughness_m: f64,
    /// Offset B of the logarithmic profile. Default 4.13 (AvaFrame `Bsamosat`).
    pub b: f64,
}

impl Default for SamosAtParams {
    fn default() -> Self {
        Self::small()
    }
}

impl SamosAtParams {
    /// AvaFrame's standard `samosAT` set (μ = 0.155).
    pub fn standard() -> Self {
        Self {
            mu: 0.155,
            rs0: 0.222,
            kappa: 0.43,
            roughness_m: 0.05,
            b: 4.13,
        }
    }

    /// AvaFrame's `samosATSmall` set (μ = 0.22), the one of its avaKot reference run: the
    /// default.
    pub fn small() -> Self {
        Self {
            mu: 0.22,
            ..Self::standard()
        }
    }
}

/// Parameters of the avalanche flow (Cordonnier et al. 2018, Table 2, read as `docs/src/model.md#sources-and-the-reading-of-table-2` says).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct AvalancheParams {
    /// Snow density ρ, kg/m³. Default 500 (Table 2). It cancels out of every acceleration
    /// (`ΔP/ρ = g·ΔA`) and is kept for reports and mass conversions.
    pub density: f64,
    /// Rest angle θc of the snow, degrees: Coulomb friction `g·tanθc`. Default 30 (Table 2).
    pub rest_angle_deg: f64,
    /// Viscous coefficient kv of the term `−kv·h·u`, 1/(m·s). Default 5e-4 (Table 2, which
    /// gives no unit; `docs/src/model.md#sources-and-the-reading-of-table-2` reads /s²).
    pub k_viscous: f64,
    /// Dry/wet mix α ∈ [0, 1]: weight of the Coulomb term, `1 − α` weighs the viscous term.
    /// The paper makes it proportional to snow temperature; here it is an input. Default 1
    /// (chosen here: dry granular snow, the case the rest-angle validation checks).
    pub alpha: f64,
    /// Courant number C of the automatic sub-step, in (0, 1]. Default 0.4 (chosen here: the
    /// explicit pipe update is stable below ~0.5 on the 8-neighbour stencil).
    pub courant: f64,
    /// Include momentum advection `(v·∇)u`. Default true (`docs/src/model.md#flow-model`: needed for Ritter's
    /// front); false gives the paper's hydrostatic pipe model with a depth cross-section.
    pub momentum_advection: bool,
    /// Condition at the grid border and the nodata outline. Default open.
    pub border: Border,
    /// Upper bound on the number of sub-steps in one call to [`step`]. Default 1 000 000.
    pub max_substeps: usize,
    /// Basal friction law. Default `samosat` with AvaFrame's `samosATSmall` coefficients
    /// ([`SamosAtParams::small`]): the law and calibration of AvaFrame com1DFA's reference run
    /// of avaKot, which the default run meets (Jaccard ≥ 0.65, tests/real_paths.rs); the
    /// paper's `coulomb` (Cordonnier et al. 2018) stays by name.
    pub friction: FrictionLaw,
    /// Voellmy dry-friction coefficient μ (with `friction = "voellmy"`). Default 0.155
    /// (AvaFrame com1DFA's `muvoellmy`).
    pub voellmy_mu: f64,
    /// Voellmy turbulence coefficient ξ, m/s² (with `friction = "voellmy"`). Default 4000
    /// (AvaFrame com1DFA's `xsivoellmy`; RAMMS uses 1000–3000 for large avalanches).
    pub voellmy_xi_m_s2: f64,
    /// The samosAT law's coefficients (with `friction = "samosat"`), the table
    /// `[parameters.avalanche.flow.samosat]` (`samos_at`, its name before, is still read).
    /// Default AvaFrame's `samosATSmall` set ([`SamosAtParams::small`], μ = 0.22).
    #[serde(rename = "samosat", alias = "samos_at")]
    pub samos_at: SamosAtParams,
    /// How gravity acts on a sloping bed. Default `projected` (Savage-Hutter on the
    /// horizontal grid, as AvaFrame com1DFA solves the slope): it brings AvaFrame's analytic
    /// tests from a front 11 % ahead and a centre of mass 58 % too far (the paper's
    /// `shallow`) to within 6 % (tests/avaframe_analytic.rs).
    pub slope_gravity: SlopeGravity,
    /// With [`SlopeGravity::Projected`], the bed's curvature: its centrifugal term in the
    /// load and the friction, and momentum carried along the bed (see
    /// [`SlopeGravity::Projected`]). Default true (AvaFrame com1DFA's `curvAccInFriction = 1`
    /// and its reprojection onto the bed; without it the flow loses the share of its speed the
    /// slope's tilt held wherever the slope eases: tests/curvature.rs).
    pub curvature: bool,
    /// Entrainment of the snowpack the flow runs over (`crate::entrainment`: AvaFrame's
    /// erosion rate `τ_b·|u|/e_b`, powder and unstable snow first, then stable snow up to a
    /// depth). On by default; it only acts where the terrain carries snow.
    pub entrainment: crate::entrainment::EntrainmentParams,
}

impl Default for AvalancheParams {
    fn default() -> Self {
        Self {
            density: snowscape_terrain::SnowLayer::Compacted.default_density_kg_m3(),
            rest_angle_deg: 30.0,
            k_viscous: 5e-4,
            alpha: 1.0,
            courant: 0.4,
            momentum_advection: true,
            border: Border::Open,
            max_substeps: 1_000_000,
            friction: FrictionLaw::SamosAt,
            voellmy_mu: 0.155,
            voellmy_xi_m_s2: 4000.0,
            samos_at: SamosAtParams::small(),
            slope_gravity: SlopeGravity::Projected,
            curvature: true,
            entrainment: Default::default(),
        }
    }
}

/// Largest `max_substeps`.
pub const MAX_SUBSTEPS: usize = 10_000_000;

impl AvalancheParams {
    /// The paper's model (Cordonnier et al. 2018): Coulomb friction with θc = 30° and the
    /// shallow-slope gravity, the rest as the defaults.
    pub fn paper() -> Self {
        Self {
            friction: FrictionLaw::Coulomb,
            slope_gravity: SlopeGravity::Shallow,
            ..Self::default()
        }
    }

    /// The dry-friction coefficient of the law: `tanθc` (Coulomb) or μ (Voellmy).
    pub fn dry_friction(&self) -> f64 {
        match self.friction {
            FrictionLaw::Coulomb => self.rest_angle_deg.to_radians().tan(),
            FrictionLaw::Voellmy => self.voellmy_mu,
            FrictionLaw::SamosAt => self.samos_at.mu,
        }
    }

    /// The weight of the dry friction: α (Coulomb), 1 (Voellmy: no viscous mix).
    pub fn dry_weight(&self) -> f64 {
        match self.friction {
            FrictionLaw::Coulomb => self.alpha,
            FrictionLaw::Voellmy | FrictionLaw::SamosAt => 1.0,
        }
    }

    /// Checks every field, naming the offending one.
    pub fn validate(&self) -> Result<(), AvalancheError> {
        let bad = |name: &'static str, value: f64, expected: &'static str| {
            Err(AvalancheError::InvalidParameter {
                name,
                value,
                expected,
            })
        };
        if !(self.density.is_finite() && self.density > 0.0 && self.density <= 1000.0) {
            return bad("density", self.density, "in (0, 1000] kg/m³");
        }
        if !(self.rest_angle_deg.is_finite() && (0.0..90.0).contains(&self.rest_angle_deg)) {
            return bad("rest_angle_deg", self.rest_angle_deg, "in [0, 90)");
        }
        if !(self.k_viscous.is_finite() && (0.0..=100.0).contains(&self.k_viscous)) {
            return bad("k_viscous", self.k_viscous, "in [0, 100] 1/(m·s)");
        }
        if !(0.0..=1.0).contains(&self.alpha) {
            return bad("alpha", self.alpha, "in [0, 1]");
        }
        if !(self.courant > 0.0 && self.courant <= 1.0) {
            return bad("courant", self.courant, "in (0, 1]");
        }
        if !(self.voellmy_mu.is_finite() && (0.0..=2.0).contains(&self.voellmy_mu)) {
            return bad("voellmy_mu", self.voellmy_mu, "in [0, 2]");
        }
        if !(self.voellmy_xi_m_s2.is_finite()
            && self.voellmy_xi_m_s2 >= 10.0
            && self.voellmy_xi_m_s2 <= 1e5)
        {
            return bad(
                "voellmy_xi_m_s2",
                self.voellmy_xi_m_s2,
                "in [10, 100000] m/s²",
            );
        }
        let s = &self.samos_at;
        for (name, v, lo, hi, expected) in [
            ("samosat.mu", s.mu, 0.0, 2.0, "in [0, 2]"),
            ("samosat.rs0", s.rs0, 1e-6, 100.0, "in [1e-6, 100]"),
            ("samosat.kappa", s.kappa, 0.01, 10.0, "in [0.01, 10]"),
            (
                "samosat.roughness_m",
                s.roughness_m,
                1e-4,
                10.0,
                "in [1e-4, 10] m",
            ),
            ("samosat.b", s.b, 0.1, 100.0, "in [0.1, 100]"),
        ] {
            if !(v.is_finite() && v >= lo && v <= hi) {
                return bad(name, v, expected);
            }
        }
        if !(1..=MAX_SUBSTEPS).contains(&self.max_substeps) {
            return bad("max_substeps", self.max_substeps as f64, "in 1..=10000000");
        }
        self.entrainment.validate()
    }
}

/// Errors of the avalanche module, carrying the offending values.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum AvalancheError {
    /// A parameter is out of range.
    #[error("avalanche parameter {name} = {value} must be {expected}")]
    InvalidParameter {
        /// Field name.
        name: &'static str,
        /// Offending value.
        value: f64,
        /// The valid range.
        expected: &'static str,
    },
    /// The time step is negative or not finite.
    #[error("avalanche time step {0} s must be finite and >= 0")]
    InvalidTimeStep(f64),
    /// A per-cell input has the wrong length.
    #[error("{what} has {got} values, the grid has {expected} cells")]
    LengthMismatch {
        /// What was passed.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The number of grid cells.
        expected: usize,
    },
    /// A value that must be finite and non-negative is not.
    #[error("{what} at cell {index} is {value}, must be finite and >= 0")]
    BadValue {
        /// What was passed.
        what: &'static str,
        /// Cell index (row-major, unpadded).
        index: usize,
        /// Offending value.
        value: f64,
    },
    /// The terrain does not have the state's geometry.
    #[error("terrain is {terrain_width}x{terrain_height}, the avalanche state {width}x{height}")]
    GeometryMismatch {
        /// State width.
        width: usize,
        /// State height.
        height: usize,
        /// Terrain width.
        terrain_width: usize,
        /// Terrain height.
        terrain_height: usize,
    },
    /// A state that reads its bed from the terrain was stepped without one.
    #[error("this avalanche state reads its bed from the terrain: step it with `step_on`")]
    BedSourceMissing,
    /// A friction map (or the raster it is sampled from) holds a value out of range.
    #[error("{what} at cell {index} (map x {x}, y {y}) is {value}, must be {expected}")]
    FrictionMapValue {
        /// Which map.
        what: &'static str,
        /// Cell index (row-major).
        index: usize,
        /// Map coordinates of the cell's centre.
        x: f64,
        y: f64,
        /// Offending value.
        value: f64,
        /// The valid range.
        expected: &'static str,
    },
    /// A friction raster covers none of the DEM's valid cells.
    #[error("the {what} raster covers none of the DEM's valid cells (check its georeferencing)")]
    FrictionMapOutside {
        /// Which map.
        what: &'static str,
    },
    /// A friction map the run's law does not read.
    #[error(
        "a {what} was given but the friction law {law:?} has no such coefficient (ξ is Voellmy's)"
    )]
    FrictionMapUnused {
        /// Which map.
        what: &'static str,
        /// The run's law.
        law: FrictionLaw,
    },
    /// The sub-step limit was reached before the step was done.
    #[error("avalanche step stopped after {done} sub-steps with {remaining} s of {dt} s left")]
    TooManySubsteps {
        /// Sub-steps done.
        done: usize,
        /// Time left, s.
        remaining: f64,
        /// Requested step, s.
        dt: f64,
    },
}

/// What one call to [`step`] did.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct AvalancheReport {
    /// Volume that crossed pipes, summed over pipes and sub-steps, m³.
    pub moved_volume: f64,
    /// Volume that left the terrain across an open border (the grid's border or the nodata
    /// outline), m³.
    pub border_outflow: f64,
    /// Largest pipe speed at the end of any sub-step, m/s.
    pub max_speed: f64,
    /// Cells visited in the last sub-step (the active set: tile boxes grown by 3 cells, ghost
    /// ring included).
    pub active_cells: usize,
    /// Grid cells holding flowing snow after the step.
    pub flowing_cells: usize,
    /// Number of sub-steps.
    pub substeps: usize,
    /// Smallest sub-step, s (0 when no sub-step ran).
    pub dt_min: f64,
    /// Largest sub-step, s.
    pub dt_max: f64,
    /// Simulated time the sub-steps covered, s (the step's `dt`, or less when the flow came
    /// to rest; with [`step_at_least`] up to its `max_dt`).
    pub simulated_s: f64,
}
