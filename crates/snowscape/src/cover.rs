//! Snow on a triangle-mesh scene, alone or standing on a DEM: the job of `snowscape cover`
//! and of the Python package's `snowscape.cover`, so that the same inputs give the same bytes
//! from each front end.
//!
//! The job ([`run`], [`CoverJob`]) checks every value first ([`CoverJob::check`]), reads the
//! mesh (its up axis and scale) and, given a DEM, stands it there with the terrain around it,
//! then covers the scene by one of two methods: the diffusion cover of von Festenberg & Gumhold
//! 2011 (`snowscape::festenberg`: a diffusion kernel on a height-span map, bridges, overhangs,
//! boundary texture coordinates, and its Eq. 2 growth animation) or the flake cover of Fearing
//! 2000 (`snowscape::fearing`: flakes shot from the sky, angle-of-repose stability). With an
//! output folder it writes the snow meshes (GLB, OBJ), a preview, a turntable GIF and the typed
//! `report.json` ([`CoverReport`]; the file names and keys are a contract), staged and committed
//! together through [`crate::output_folder::OutputFolder`].
//!
//! The parameters of both methods come from a TOML file (`snowscape cover --parameters FILE`,
//! the Python package's keywords), like a season's scenario; a front end's flags override the
//! file's values through [`CoverOverrides`]:
//!
//! ```toml
//! [diffusion]          # von Festenberg & Gumhold 2011 (snowscape::festenberg::CoverParams)
//! depth_m = 0.4        # initial snow height h0, m (default: 2 % of the scene's diameter)
//! radius_m = 2.0       # kernel radius R, m (default: 5 %, Section 5.2)
//! overhang = true
//!
//! [fearing]            # Fearing 2000 (snowscape::fearing::FearingParams)
//! depth_m = 0.3
//! passes = 3
//! [fearing.material]   # the material's angle of repose, transition, flutter, fall speed
//! aor_deg = 45.0
//! [fearing.stability]
//! max_passes = 200
//! ```
//!
//! Every key is one of the parameter structs' fields (unknown keys are refused with their
//! name), every value is range-checked before any mesh is read. A cover's reports
//! ([`MeshInputSummary`], [`DiffusionCoverReport`], [`FearingCoverReport`]) are typed here.

use serde::{Deserialize, Serialize};
use snowscape_fearing::{FearingError, FearingParams};
use snowscape_festenberg::{CoverParams, FestenbergError};
use std::path::Path;

mod diffusion;
mod flakes;
mod input;
mod job;
mod outputs;
mod report;
pub use job::{
    CoverDem, CoverJob, CoverJobError, CoverMethod, CoverOutcome, CoverOverrides, CoverReport,
    FearingCoverReport, GROWTH_FRAMES, TURNTABLE_FRAMES, run,
};
pub use outputs::{fearing_no_snow, fearing_report, write_fearing_outputs, write_turntable};
pub use report::{
    DIFFUSION_PAPER, DemPlacement, DiffusionCoverReport, FEARING_PAPER, FearingInputSummary,
    GrowthSummary, KernelWork, MeshInputSummary, SiteCounts, SnowMeshCounts, Turntable,
};

/// Both covers' parameters.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CoverParameters {
    /// The diffusion cover (von Festenberg & Gumhold 2011).
    pub diffusion: CoverParams,
    /// The flake cover (Fearing 2000).
    pub fearing: FearingParams,
    /// Whether the file set `[fearing] depth_m` (the command line's default depth is 2 % of
    /// the scene's diameter, not the struct's fixed default).
    #[serde(skip)]
    pub fearing_depth_set: bool,
}

/// Why a cover parameter file was refused.
#[derive(Debug, thiserror::Error)]
pub enum CoverParameterError {
    #[error("cannot read cover parameters {path}: {source}")]
    Read {
        path: String,
        #[source]
        source: snowscape_io::InputError,
    },
    /// Not TOML, or a key or value the parameters do not have (the message names the line,
    /// the column and the key).
    #[error("cover parameters {source_name}: {message}")]
    Parse {
        source_name: String,
        message: String,
    },
    #[error("cover parameters {source_name}: [diffusion] {source}")]
    Diffusion {
        source_name: String,
        #[source]
        source: Box<FestenbergError>,
    },
    #[error("cover parameters {source_name}: [fearing] {source}")]
    Fearing {
        source_name: String,
        #[source]
        source: FearingError,
    },
}

impl CoverParameters {
    /// Parses and checks a parameter file's text; `source_name` names it in errors.
    pub fn from_toml(text: &str, source_name: &str) -> Result<Self, CoverParameterError> {
        let parse_error = |e: toml::de::Error| CoverParameterError::Parse {
            source_name: source_name.to_string(),
            message: e.to_string(),
        };
        let mut p: Self = toml::from_str(text).map_err(parse_error)?;
        let table: toml::Table = toml::from_str(text).map_err(parse_error)?;
        p.fearing_depth_set = table
            .get("fearing")
            .and_then(|f| f.get("depth_m"))
            .is_some();
        p.validate(source_name)?;
        Ok(p)
    }

    /// The Fearing cover's parameters for `scene`: the file's, with `depth_m` 2 % of the
    /// scene's horizontal diameter unless the file set it (the command line's default and the
    /// Python package's); `None` when the scene has no triangle.
    pub fn fearing_for(&self, scene: &snowscape_mesh::Scene) -> Option<FearingParams> {
        let mut p = self.fearing.clone();
        if !self.fearing_depth_set {
            p.depth_m = default_depth_m(scene)?;
        }
        Some(p)
    }

    /// Reads a parameter file (a regular file of bounded size) and checks it.
    pub fn read(path: &Path) -> Result<Self, CoverParameterError> {
        let name = path.display().to_string();
        let text = snowscape_io::input::read_regular_text(path).map_err(|source| {
            CoverParameterError::Read {
                path: name.clone(),
                source,
            }
        })?;
        Self::from_toml(&text, &name)
    }

    /// Checks both covers' values.
    pub fn validate(&self, source_name: &str) -> Result<(), CoverParameterError> {
        self.diffusion
            .validate()
            .map_err(|source| CoverParameterError::Diffusion {
                source_name: source_name.to_string(),
                source: Box::new(source),
            })?;
        self.fearing
            .validate()
            .map_err(|source| CoverParameterError::Fearing {
                source_name: source_name.to_string(),
                source,
            })
    }
}

/// The default snow depth on a scene: 2 % of its horizontal diameter, m (`None` without
/// triangles).
pub fn default_depth_m(scene: &snowscape_mesh::Scene) -> Option<f64> {
    let b = scene.bounds()?;
    Some(0.02 * (b.size()[0] as f64).hypot(b.size()[1] as f64))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_sets_both_covers_and_keeps_the_other_defaults() {
        let p = CoverParameters::from_toml(
            "[diffusion]\ndepth_m = 0.4\noverhang = true\n\
             [fearing]\npasses = 3\n[fearing.material]\naor_deg = 45.0\n",
            "test",
        )
        .unwrap();
        assert_eq!(p.diffusion.depth_m, Some(0.4));
        assert!(p.diffusion.overhang);
        assert_eq!(p.diffusion.radius_m, None);
        assert_eq!(p.fearing.passes, 3);
        assert_eq!(p.fearing.material.aor_deg, 45.0);
        // The rest of the material is the snow preset's.
        assert_eq!(p.fearing.material.flutter_m, 0.05);
        assert_eq!(p.fearing.seed, FearingParams::default().seed);
        assert!(!p.fearing_depth_set);
        let p = CoverParameters::from_toml("[fearing]\ndepth_m = 0.3\n", "t").unwrap();
        assert!(p.fearing_depth_set);
        assert_eq!(
            CoverParameters::from_toml("", "empty").unwrap(),
            CoverParameters::default()
        );
    }

    #[test]
    fn bad_keys_and_values_are_named() {
        let e = CoverParameters::from_toml("[diffusion]\nradius = 2.0\n", "f.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("f.toml") && e.contains("radius"), "{e}");
        let e = CoverParameters::from_toml("[diffusion]\nradius_m = -2.0\n", "f.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("-2") && e.contains("radius"), "{e}");
        let e = CoverParameters::from_toml("[fearing]\npasses = 0\n", "f.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("passes") && e.contains('0'), "{e}");
        let e = CoverParameters::from_toml("[fearing.material]\naor_deg = nan\n", "f.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("NaN") || e.contains("nan"), "{e}");
        let e = CoverParameters::from_toml(
            "[fearing.sky_weight]\nwidth = 4294967296\nheight = 4294967296\nvalues = []\n",
            "f.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("sky"), "{e}");
        let e = CoverParameters::from_toml("[fearing]\ndepth_m = \"deep\"\n", "f.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("depth_m") && e.contains("line"), "{e}");
    }
}
