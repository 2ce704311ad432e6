//! [`SkiParams`]: every knob of the ski tracks, with units and the source of each default.
//!
//! Table 2 of Cordonnier et al. 2018 gives three ski values (read by units, `docs/src/model.md#sources-and-the-reading-of-table-2`):
//! the target slope `st = 30°`, the turn amplitude `a = 5 m` and a frequency `f = 0.01 /m`.
//! Everything else is chosen here; each field says why.

use crate::SkiError;
use serde::{Deserialize, Serialize};

/// Parameters of the ski tracks. Scenario files map onto these fields 1:1.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SkiParams {
    /// Slope the skiers try to follow, `st`, degrees. Default 30 (Table 2).
    pub target_slope_deg: f64,
    /// Width `σ` of the slope preference `f(Δ) = exp(−Δ²/(2σ²))`, degrees. Default 5 (chosen
    /// here: a cell 5° off the target weighs 0.61 of a perfect one, 10° off 0.14, 15° off
    /// 0.011; on the varied-slope test mountain skiers then hold st within 5° on average where
    /// the fall line is 15° steeper, while 10° let them drift 8° off).
    pub slope_tolerance_deg: f64,
    /// Snow depth a cell needs to be skied on (the paper's `threshold`), m. Default 0.3
    /// (chosen here: about 30 cm of snow covers grass and small rocks, the usual minimum for
    /// ski touring).
    pub min_snow_depth_m: f64,
    /// Look-ahead window radius, cells: candidates are the cells within this Chebyshev
    /// distance of the skier's cell (24 cells for 2). Default 2 (the paper's "a few tiles").
    pub lookahead_cells: usize,
    /// Exponent `κ` of the turn weight `w_turn = max(0, cos Δθ)^κ`, where `Δθ` is the angle
    /// between the skier's heading and the candidate. Default 2 (chosen here: a 45° turn
    /// weighs 0.5, a 90° turn or more 0, so skiers never reverse).
    pub turn_exponent: f64,
    /// Weight of a candidate whose distance to the terminus is not smaller than the current
    /// cell's, in [0, 1]. Default 0.05 (chosen here: the paper's `w_d` "discourages skiers from
    /// reaching dead-ends"; a small non-zero weight still lets a skier traverse a bench).
    pub no_progress_weight: f64,
    /// Distance over which the heading turns towards the steering direction by a factor
    /// `1 − 1/e`, m. Default 5 (chosen here: the paper's "smooth transition to the new
    /// steering direction"; about the radius of a ski turn, half a 10 m cell).
    pub turn_distance_m: f64,
    /// Speed of a skier along the coarse path, m/s. Default 5 (chosen here: 18 km/h of
    /// progress down the coarse path, a relaxed touring descent; the turns add length).
    pub speed_m_s: f64,
    /// Amplitude `a` of the sine-wave turns around the coarse path, m. Default 5 (Table 2).
    pub amplitude_m: f64,
    /// Turn frequency on slopes at or below `st`, 1/m. Default 0.01 (Table 2's `f`): the
    /// paper's formula `f = sqrt(sin²s − sin²st)/(4a·sin st)` gives 0 there (a straight run);
    /// Table 2's value reads as the gentle 100 m-wavelength meander kept on such slopes. 0
    /// gives straight runs.
    pub min_frequency_per_m: f64,
    /// Width of a ski track drawn into the texture (and packed by a pass), m. Default 1.0
    /// (chosen here: two skis 20 cm apart plus the trench a turn ploughs in soft snow).
    pub track_width_m: f64,
    /// Texels of the track texture per grid cell along each axis, 1..=64. Default 8 (chosen
    /// here: 1.25 m texels on the paper's 10 m grid draw the 5 m turns 4 texels a side).
    pub texels_per_cell: usize,
    /// Spacing of the vertices kept for a track's GeoJSON line, m. Default 2 (chosen here: at
    /// least 7 vertices per turn wavelength, which is ≥ 14 m for slopes up to 60°).
    pub vertex_spacing_m: f64,
    /// Depth of loose snow a ski pass packs under the track, m. Default 0.2 (chosen here: a
    /// skier sinks 10–30 cm into soft snow). A pass of track length `L` in a cell of area
    /// `dx·dy` compacts the cell-average thickness `compaction_depth · track_width · L/(dx·dy)`.
    pub compaction_depth_m: f64,
    /// Density of unstable snow, kg/m³. Default 300 (chosen here: settled snow; the season's
    /// stability module exchanges stable and unstable snow 1:1, so their densities are equal).
    pub density_unstable_kg_m3: f64,
    /// Density of stable snow, kg/m³. Default 300 (chosen here, as the season's stability
    /// module: settled snow).
    pub density_stable_kg_m3: f64,
    /// Density of compacted snow, kg/m³. Default 500 (Table 2's ρ = 0.5 g/cm³; with 300 for
    /// stable snow this is the season's `compacted_density_ratio` 0.6).
    pub density_compacted_kg_m3: f64,
    /// E-folding time of the "recent skier" map, s. Default 86 400 (chosen here: a day; a
    /// track's load on the weak layer matters while the slope has not re-settled).
    pub recent_decay_s: f64,
    /// Smallest surface slope on which a skier can trigger unstable snow, degrees. Default 30
    /// (Table 2's rest angle θc: snow on gentler slopes cannot slide; also the practitioners'
    /// 30° threshold for slab avalanches).
    pub trigger_min_slope_deg: f64,
    /// Probability that 10 m of track (the paper's cell) across steep ground with
    /// `trigger_unstable_ref_m` of unstable snow triggers it, in [0, 1]. Default 0.05 (chosen
    /// here: crossing a 200 m loaded slope then triggers it with probability
    /// 1 − 0.95²⁰ ≈ 64 %, the paper's storytelling case, "ski-tracks triggering immediate
    /// avalanches when they cross unstable snow layers", made a chance rather than a certainty).
    pub trigger_probability: f64,
    /// Unstable snow depth at which the trigger probability is full, m; below it the
    /// probability scales linearly. Default 0.3 (chosen here: a typical slab thickness).
    pub trigger_unstable_ref_m: f64,
    /// Gain of the recent-skier map on the trigger probability: `p · (1 + gain · r)`, `r` the
    /// decayed count of recent passes through the cell. Default 1 (chosen here: each recent
    /// pass adds the base probability once more, repeated loading of the weak layer).
    pub trigger_recent_gain: f64,
    /// Snow depth that fades a track to `1/e`, m: the texture is multiplied by
    /// `exp(−added/fade_depth)`. Default 0.1 (chosen here: tracks are 10–20 cm deep, so 10 cm of
    /// new or drifted snow blurs them and 30 cm leaves 5 %).
    pub fade_depth_m: f64,
    /// Longest run of one skier along the coarse path, m; a skier who travelled that far
    /// stops. Default 20 000 (chosen here: longer than any alpine descent; it bounds loops on
    /// flats).
    pub max_run_length_m: f64,
}

impl Default for SkiParams {
    fn default() -> Self {
        Self {
            target_slope_deg: 30.0,
            slope_tolerance_deg: 5.0,
            min_snow_depth_m: 0.3,
            lookahead_cells: 2,
            turn_exponent: 2.0,
            no_progress_weight: 0.05,
            turn_distance_m: 5.0,
            speed_m_s: 5.0,
            amplitude_m: 5.0,
            min_frequency_per_m: 0.01,
            track_width_m: 1.0,
            texels_per_cell: 8,
            vertex_spacing_m: 2.0,
            compaction_depth_m: 0.2,
            density_unstable_kg_m3: 300.0,
            density_stable_kg_m3: 300.0,
            density_compacted_kg_m3: 500.0,
            recent_decay_s: 86_400.0,
            trigger_min_slope_deg: 30.0,
            trigger_probability: 0.05,
            trigger_unstable_ref_m: 0.3,
            trigger_recent_gain: 1.0,
            fade_depth_m: 0.1,
            max_run_length_m: 20_000.0,
        }
    }
}

fn bad(name: &'static str, value: f64, expected: &'static str) -> Result<(), SkiError> {
    Err(SkiError::InvalidParameter {
        name,
        value,
        expected,
    })
}

fn positive(name: &'static str, value: f64) -> Result<(), SkiError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        bad(name, value, "finite and > 0")
    }
}

fn non_negative(name: &'static str, value: f64) -> Result<(), SkiError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        bad(name, value, "finite and >= 0")
    }
}

fn unit_interval(name: &'static str, value: f64) -> Result<(), SkiError> {
    if value.is_finite() && (0.0..=1.0).contains(&value) {
        Ok(())
    } else {
        bad(name, value, "in [0, 1]")
    }
}

/// Largest look-ahead radius, cells.
pub const MAX_LOOKAHEAD: usize = 8;
/// Largest texture resolution, texels per cell.
pub const MAX_TEXELS_PER_CELL: usize = 64;

impl SkiParams {
    /// Checks every field; the error names the field and carries its value.
    pub fn validate(&self) -> Result<(), SkiError> {
        if !(self.target_slope_deg.is_finite()
            && self.target_slope_deg > 0.0
            && self.target_slope_deg < 90.0)
        {
            return bad("target_slope_deg", self.target_slope_deg, "in (0, 90)");
        }
        positive("slope_tolerance_deg", self.slope_tolerance_deg)?;
        non_negative("min_snow_depth_m", self.min_snow_depth_m)?;
        if !(1..=MAX_LOOKAHEAD).contains(&self.lookahead_cells) {
            return bad("lookahead_cells", self.lookahead_cells as f64, "in 1..=8");
        }
        non_negative("turn_exponent", self.turn_exponent)?;
        unit_interval("no_progress_weight", self.no_progress_weight)?;
        positive("turn_distance_m", self.turn_distance_m)?;
        positive("speed_m_s", self.speed_m_s)?;
        non_negative("amplitude_m", self.amplitude_m)?;
        non_negative("min_frequency_per_m", self.min_frequency_per_m)?;
        positive("track_width_m", self.track_width_m)?;
        if !(1..=MAX_TEXELS_PER_CELL).contains(&self.texels_per_cell) {
            return bad("texels_per_cell", self.texels_per_cell as f64, "in 1..=64");
        }
        positive("vertex_spacing_m", self.vertex_spacing_m)?;
        non_negative("compaction_depth_m", self.compaction_depth_m)?;
        positive("density_unstable_kg_m3", self.density_unstable_kg_m3)?;
        positive("density_stable_kg_m3", self.density_stable_kg_m3)?;
        positive("density_compacted_kg_m3", self.density_compacted_kg_m3)?;
        if self.density_stable_kg_m3 < self.density_unstable_kg_m3 {
            return bad(
                "density_stable_kg_m3",
                self.density_stable_kg_m3,
                ">= density_unstable_kg_m3 (packing never loosens snow)",
            );
        }
        if self.density_compacted_kg_m3 < self.density_stable_kg_m3 {
            return bad(
                "density_compacted_kg_m3",
                self.density_compacted_kg_m3,
                ">= density_stable_kg_m3 (packing never loosens snow)",
            );
        }
        positive("recent_decay_s", self.recent_decay_s)?;
        if !(self.trigger_min_slope_deg.is_finite()
            && (0.0..90.0).contains(&self.trigger_min_slope_deg))
        {
            return bad(
                "trigger_min_slope_deg",
                self.trigger_min_slope_deg,
                "in [0, 90)",
            );
        }
        unit_interval("trigger_probability", self.trigger_probability)?;
        positive("trigger_unstable_ref_m", self.trigger_unstable_ref_m)?;
        non_negative("trigger_recent_gain", self.trigger_recent_gain)?;
        positive("fade_depth_m", self.fade_depth_m)?;
        positive("max_run_length_m", self.max_run_length_m)?;
        Ok(())
    }

    /// `st` in radians.
    pub fn target_slope_rad(&self) -> f64 {
        self.target_slope_deg.to_radians()
    }
}
