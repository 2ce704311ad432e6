//! Parameters of the Fearing 2000 cover, with units and defaults citing the paper, and the
//! material presets (snow, flour, sand, water; Sections 4.1, 6 and 7).
//!
//! The paper leaves most numbers to the user ("We defer the reader to [1] for the actual
//! parameterised importance weighting"); where it gives none, the default is ours and says so.

use crate::error::{FearingError, invalid};
use serde::{Deserialize, Serialize};

/// A granular material: its angle of repose and the width of its transition curve (Section 4.1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Material {
    /// Name of the preset (or "custom").
    pub name: String,
    /// Angle of repose, degrees, in [0, 90). Section 4.1: "near 90° in fresh dendritic snow to
    /// 15° in extreme slush"; 0 for water (Section 6).
    pub aor_deg: f64,
    /// Full width of the transition curve around the AOR, degrees: a site's critical angle is
    /// drawn once from a raised-cosine law on [AOR - w/2, AOR + w/2] (wider gives bumpier
    /// surfaces, Section 4.1). 0 gives a sharp threshold.
    pub transition_deg: f64,
    /// Mean flutter radius fr of this material's flakes, metres (Section 3.5); 0 for water.
    pub flutter_m: f64,
    /// Fall speed, m/s, which turns a wind speed into a path slope (Section 6); ours.
    pub fall_speed_m_s: f64,
}

impl Default for Material {
    /// Fresh snow ([`Material::snow`]).
    fn default() -> Self {
        Self::snow()
    }
}

impl Material {
    /// Fresh snow: AOR 50° (between the paper's 90° dendritic and 15° slush), transition 10°,
    /// fr = 5 cm, falling at 1 m/s (typical of snowflakes).
    pub fn snow() -> Self {
        Self {
            name: "snow".into(),
            aor_deg: 50.0,
            transition_deg: 10.0,
            flutter_m: 0.05,
            fall_speed_m_s: 1.0,
        }
    }
    /// Sifted flour (the paper's validation material, Section 7): AOR 45°, narrow transition,
    /// little flutter.
    pub fn flour() -> Self {
        Self {
            name: "flour".into(),
            aor_deg: 45.0,
            transition_deg: 4.0,
            flutter_m: 0.01,
            fall_speed_m_s: 2.0,
        }
    }
    /// Dry sand: AOR 34°, narrow transition, no flutter.
    pub fn sand() -> Self {
        Self {
            name: "sand".into(),
            aor_deg: 34.0,
            transition_deg: 2.0,
            flutter_m: 0.0,
            fall_speed_m_s: 5.0,
        }
    }
    /// Water (Section 6): AOR = 0 and fr = 0; "fills the first basin, and overflows".
    pub fn water() -> Self {
        Self {
            name: "water".into(),
            aor_deg: 0.0,
            transition_deg: 0.0,
            flutter_m: 0.0,
            fall_speed_m_s: 6.0,
        }
    }
    /// A preset by name (snow, flour, sand, water).
    pub fn preset(name: &str) -> Result<Self, FearingError> {
        match name.trim().to_ascii_lowercase().as_str() {
            "snow" => Ok(Self::snow()),
            "flour" => Ok(Self::flour()),
            "sand" => Ok(Self::sand()),
            "water" => Ok(Self::water()),
            _ => Err(invalid("material", name, "snow, flour, sand or water")),
        }
    }
}

/// Sky weights ("snow writing", Fig. 8): a grid of non-negative multipliers of the sky's mass
/// over the scene's horizontal bounds (row 0 at the north, +y, like an image).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkyWeight {
    pub width: usize,
    pub height: usize,
    /// `width * height` values, row-major, each finite and >= 0.
    pub values: Vec<f32>,
}

impl SkyWeight {
    /// A weight image from a greyscale picture (white = full snowfall, black = none).
    pub fn from_image(img: &image::GrayImage) -> Self {
        Self {
            width: img.width() as usize,
            height: img.height() as usize,
            values: img.pixels().map(|p| p.0[0] as f32 / 255.0).collect(),
        }
    }
    /// The weight at relative position (u, v) in [0, 1]² of the scene's xy bounds (u east, v north).
    pub fn at(&self, u: f64, v: f64) -> f32 {
        if !(0.0..=1.0).contains(&u) || !(0.0..=1.0).contains(&v) {
            return 0.0;
        }
        let c = ((u * self.width as f64) as usize).min(self.width - 1);
        let r = (((1.0 - v) * self.height as f64) as usize).min(self.height - 1);
        self.values[r * self.width + c]
    }
}

/// Stability phase settings (Section 4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StabilityPhaseParams {
    /// Most passes through the unresolved list per stability phase (Section 4.4); the cap in
    /// use is the smaller of this and the number of sites + 16, so it is bounded by the sites
    /// (ours: 100,000, so the sites set it). A phase normally ends earlier, when quiet (see
    /// `quiet_m`); the pass count, never the clock, ends it, so its result is the same on any
    /// machine.
    pub max_passes: u32,
    /// Most site tests per stability phase, per site (the work cap that ends a phase which never
    /// goes quiet, such as snow draining off a steep flank in ever smaller avalanches; ours:
    /// 1000: water in a pit of 9,100 sites goes quiet, flat within 2 mm, after about 510 tests a
    /// site; the bunny's 26 k sites, which do not always go quiet, take about 11 s a phase on
    /// the 2-core machine).
    pub max_tests_per_site: u32,
    /// A pass that moves less than this share of the snow sends every site to a re-check
    /// (Section 4.4: "all avalanches in the last pass moved only a very small amount of snow");
    /// ours: 1e-4.
    pub min_moved_fraction: f64,
    /// Quiet: a full re-check pass in which no avalanche changes a site's snow height by more
    /// than this ends the phase, metres (ours: 0.1 mm; water settles flat to within about a
    /// hundred times this over a pit a few metres wide).
    pub quiet_m: f64,
    /// Height difference below which two sites count as level, metres (keeps water from
    /// trading micro-amounts forever); ours: 0.01 mm.
    pub level_tolerance_m: f64,
    /// Avalanche particles per edge transit (Section 4.3: "usually < 5").
    pub edge_particles: u32,
    /// Speed of avalanche particles leaving an edge, m/s (ours).
    pub edge_speed_m_s: f64,
    /// Share of the speed kept at a bounce off a surface that holds no snow (ours).
    pub restitution: f64,
    /// Rebuild the snow surfaces used by the obstacle tests every this many passes, and no sooner
    /// than a quarter of the sites has been tested since the last rebuild (Section 4.2
    /// reduces the frequency of the obstacle test "from every test, to every pass, to once per
    /// stability phase"); ours: 16.
    pub obstacle_refresh_passes: u32,
}

impl Default for StabilityPhaseParams {
    fn default() -> Self {
        Self {
            max_passes: 100_000,
            min_moved_fraction: 1e-4,
            quiet_m: 1e-4,
            max_tests_per_site: 1000,
            level_tolerance_m: 1e-5,
            edge_particles: 4,
            edge_speed_m_s: 0.5,
            restitution: 0.3,
            obstacle_refresh_passes: 16,
        }
    }
}

/// Everything [`crate::cover`] needs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FearingParams {
    /// Depth of fresh material on open flat ground, metres (the "arbitrary amount of snow" of
    /// Section 3.1); > 0.
    pub depth_m: f64,
    /// AOR, transition, default flutter and fall speed.
    pub material: Material,
    /// Mean flutter radius fr, metres (Section 3.5); `None` takes the material's.
    pub flutter_m: Option<f64>,
    /// Standard deviation of fr as a share of its mean (Section 3.5: "fr is randomly chosen from
    /// a normal distribution"); ours: 0.3.
    pub flutter_sd_fraction: f64,
    /// Height of one flutter step, metres; `None`: 2 fr (and at least 1/400 of the scene's
    /// height). Section 3.5 leaves it to the importance ordering.
    pub step_height_m: Option<f64>,
    /// Constant wind (east, north), m/s (Section 6).
    pub wind_m_s: [f64; 2],
    /// Share of a site's snow the wind carries downwind per stability phase and per m/s
    /// (Section 6's transport in the stability phase; capped at all of it); ours: 0, off.
    pub wind_transport: f64,
    /// Seed of every random number (flakes, transition curve).
    pub seed: u64,
    /// Wall-clock safety net of the whole cover, seconds (ours: 600). The work, not the clock,
    /// ends every stage (the flake budget `flakes_per_site` of each accumulation pass of Section
    /// 3.2's anytime loop; quiet or the pass cap in stability), so a cover is the same bytes on
    /// any machine; a cover still running at this time fails with
    /// [`FearingError::BudgetExceeded`] rather than returning a result cut short by the clock.
    pub budget_s: f64,
    /// Flake budget per pass, the work count that ends accumulation: this many flakes per
    /// launch site on average (ours: 48).
    pub flakes_per_site: u32,
    /// Flakes per batch (Section 3.4: "within the order of 10-15 flakes").
    pub batch_size: u32,
    /// Accumulation passes, each adding depth/passes and followed by stability (Section 3.1,
    /// "we can repeat the accumulation step as often desired").
    pub passes: u32,
    /// Initial launch site spacing, metres; `None`: from `target_sites`.
    pub site_spacing_m: Option<f64>,
    /// Initial launch sites aimed at when `site_spacing_m` is `None` (every upward triangle
    /// still gets at least one, Section 3.3).
    pub target_sites: usize,
    /// Most refinement levels below an initial site (Section 3.2, "Limits").
    pub max_refinement: u32,
    /// Sky-hit disagreement with a neighbour that asks for a refinement site (Section 3.2).
    pub refine_threshold: f64,
    /// Triangles with a unit normal z above this face upwards and get launch sites (Section 3.3
    /// allows [0, 90)°; ours 0.05, about 87°).
    pub min_normal_z: f64,
    /// Sky bucket size, metres; `None`: 4 site spacings.
    pub sky_bucket_m: Option<f64>,
    /// Optional sky weights ("snow writing", Fig. 8).
    pub sky_weight: Option<SkyWeight>,
    /// Optional camera position (scene metres): nearer sites get more flakes (Section 3.2).
    pub camera: Option<[f64; 3]>,
    /// Objects tagged "boring" (Section 3.2, "User"): their sites get a tenth of the importance.
    pub boring_objects: Vec<String>,
    /// Stability phase settings.
    pub stability: StabilityPhaseParams,
    /// Iterations of mass-conserving depth smoothing between neighbours before meshing (the
    /// "simpler documented method" standing in for Section 5's implicit functions); 0 = off.
    pub smoothing_iterations: u32,
    /// Taubin λ|μ smoothing pairs on the finished snow surface's depths ([`crate::SnowSurface::smooth`],
    /// standing in for Section 5's optional implicit-function smoothing); ours: 4; 0 = off.
    pub surface_smoothing: u32,
    /// Thinnest snow drawn as a surface, metres (thinner is flake dusting, Section 3.8).
    pub min_surface_depth_m: f64,
    /// Whether to make the flake-dusting mesh (Section 3.8).
    pub dusting: bool,
}

impl Default for FearingParams {
    fn default() -> Self {
        Self {
            depth_m: 0.3,
            material: Material::snow(),
            flutter_m: None,
            flutter_sd_fraction: 0.3,
            step_height_m: None,
            wind_m_s: [0.0, 0.0],
            wind_transport: 0.0,
            seed: 1,
            budget_s: 600.0,
            flakes_per_site: 48,
            batch_size: 12,
            passes: 2,
            site_spacing_m: None,
            target_sites: 20_000,
            max_refinement: 3,
            refine_threshold: 0.25,
            min_normal_z: 0.05,
            sky_bucket_m: None,
            sky_weight: None,
            camera: None,
            boring_objects: Vec::new(),
            stability: StabilityPhaseParams::default(),
            smoothing_iterations: 2,
            surface_smoothing: 4,
            min_surface_depth_m: 1e-3,
            dusting: true,
        }
    }
}

impl FearingParams {
    /// Defaults with a material preset (its AOR, flutter and fall speed).
    pub fn with_material(material: Material) -> Self {
        Self {
            material,
            ..Self::default()
        }
    }

    /// The flutter radius in use, metres.
    pub fn flutter(&self) -> f64 {
        self.flutter_m.unwrap_or(self.material.flutter_m)
    }

    /// Checks every value, naming the first bad one.
    pub fn validate(&self) -> Result<(), FearingError> {
        let pos = |name, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(invalid(name, v, "a finite number > 0"))
            }
        };
        let non_neg = |name, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(invalid(name, v, "a finite number >= 0"))
            }
        };
        pos("depth (m)", self.depth_m)?;
        let m = &self.material;
        if !(m.aor_deg.is_finite() && (0.0..90.0).contains(&m.aor_deg)) {
            return Err(invalid(
                "angle of repose (degrees)",
                m.aor_deg,
                "0 <= AOR < 90",
            ));
        }
        non_neg("transition width (degrees)", m.transition_deg)?;
        if m.aor_deg + 0.5 * m.transition_deg >= 90.0 {
            return Err(invalid(
                "transition width (degrees)",
                m.transition_deg,
                "AOR + width/2 < 90",
            ));
        }
        pos("fall speed (m/s)", m.fall_speed_m_s)?;
        non_neg("flutter radius (m)", self.flutter())?;
        non_neg("flutter deviation share", self.flutter_sd_fraction)?;
        if let Some(h) = self.step_height_m {
            pos("flutter step height (m)", h)?;
        }
        for w in self.wind_m_s {
            if !w.is_finite() || w.abs() > 100.0 {
                return Err(invalid(
                    "wind (m/s)",
                    format!("{},{}", self.wind_m_s[0], self.wind_m_s[1]),
                    "finite components within ±100 m/s",
                ));
            }
        }
        non_neg("wind transport share", self.wind_transport)?;
        pos("budget (s)", self.budget_s)?;
        if self.flakes_per_site == 0 {
            return Err(invalid("flakes per site", 0, "at least 1"));
        }
        if !(1..=1024).contains(&self.batch_size) {
            return Err(invalid("batch size", self.batch_size, "1..=1024 flakes"));
        }
        if !(1..=64).contains(&self.passes) {
            return Err(invalid("accumulation passes", self.passes, "1..=64"));
        }
        if let Some(s) = self.site_spacing_m {
            pos("site spacing (m)", s)?;
        }
        if !(1..=5_000_000).contains(&self.target_sites) {
            return Err(invalid("target sites", self.target_sites, "1..=5000000"));
        }
        if self.max_refinement > 8 {
            return Err(invalid("refinement levels", self.max_refinement, "0..=8"));
        }
        if !(self.refine_threshold > 0.0 && self.refine_threshold <= 1.0) {
            return Err(invalid(
                "refinement threshold",
                self.refine_threshold,
                "in (0, 1]",
            ));
        }
        if !(self.min_normal_z >= 0.0 && self.min_normal_z < 1.0) {
            return Err(invalid("minimum normal z", self.min_normal_z, "in [0, 1)"));
        }
        if let Some(b) = self.sky_bucket_m {
            pos("sky bucket size (m)", b)?;
        }
        if let Some(w) = &self.sky_weight {
            if w.width == 0
                || w.height == 0
                || w.width.checked_mul(w.height) != Some(w.values.len())
            {
                return Err(FearingError::SkyWeight {
                    what: format!("has {} values for {}x{}", w.values.len(), w.width, w.height),
                });
            }
            if let Some(v) = w.values.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                return Err(FearingError::SkyWeight {
                    what: format!("holds {v}: weights must be finite and >= 0"),
                });
            }
        }
        if let Some(c) = self.camera
            && !c.iter().all(|v| v.is_finite())
        {
            return Err(invalid(
                "camera position",
                format!("{c:?}"),
                "finite coordinates",
            ));
        }
        let s = &self.stability;
        if s.max_passes == 0 {
            return Err(invalid("stability passes", 0, "at least 1"));
        }
        non_neg("stability moved fraction", s.min_moved_fraction)?;
        non_neg("stability quiet height (m)", s.quiet_m)?;
        if s.max_tests_per_site == 0 {
            return Err(invalid("stability tests per site", 0, "at least 1"));
        }
        non_neg("level tolerance (m)", s.level_tolerance_m)?;
        if !(1..=16).contains(&s.edge_particles) {
            return Err(invalid("edge particles", s.edge_particles, "1..=16"));
        }
        non_neg("edge speed (m/s)", s.edge_speed_m_s)?;
        if !(0.0..=1.0).contains(&s.restitution) {
            return Err(invalid("restitution", s.restitution, "in [0, 1]"));
        }
        if s.obstacle_refresh_passes == 0 {
            return Err(invalid("obstacle refresh passes", 0, "at least 1"));
        }
        if self.smoothing_iterations > 1000 {
            return Err(invalid(
                "smoothing iterations",
                self.smoothing_iterations,
                "0..=1000",
            ));
        }
        if self.surface_smoothing > 100 {
            return Err(invalid(
                "surface smoothing passes",
                self.surface_smoothing,
                "0..=100",
            ));
        }
        non_neg("minimum surface depth (m)", self.min_surface_depth_m)?;
        Ok(())
    }
}
