//! Avalanches in the season: when and where they start, and what they leave behind
//! (Cordonnier et al. 2018, §3.2 and §6.1).
//!
//! **When.** Avalanche-Start is a Poisson event (§3.2: "once a week on average for avalanches
//! on a one square kilometre terrain"). Its rate is the sum of a per-cell hazard
//!
//! ```text
//! λ_i = f_av · (dx·dy / 1 km²) · min(U_i / U_ref, 1) · s(θ_i) · (1 + k_ski · K_i)     [1/day]
//! ```
//!
//! with `U_i` the unstable thickness (only unstable snow ruptures, §6.1), `θ_i` the slope of the
//! avalanche bed, `s` a slope window (0 below `slope_min_deg`, rising linearly to 1 at
//! `slope_full_deg`, falling back to 0 at `slope_max_deg`, where snow no longer accumulates:
//! slab avalanches start on 30–45° slopes), and `K_i` the recent-skier map of the ski-track
//! phenomenon (§6.2: skiers on unstable snow raise the probability). A square kilometre of
//! 35–45° slopes loaded with `U_ref` of unstable snow thus averages the paper's one avalanche a
//! week. The hazard is recomputed after every state change of the snow (melt/stability steps,
//! snowfall steps, avalanches).
//!
//! **Where.** The start cell is drawn with probability `λ_i / Σλ` from the keyed random stream
//! of the event; the rupture (§6.1, [`snowscape_avalanche::release_area`]) sets the unstable
//! snow within reach and down-slope of it in motion.
//!
//! **Temporal zoom.** The avalanche then runs to rest inside its start event (§3.1, Fig. 4: "an
//! entire avalanche may take place between two lower frequency events"): the season clock
//! advances by the avalanche's simulated time (records at least 0.1 s apart, at the flow's CFL
//! sub-steps), during which no other event happens. Each avalanche goes through
//! [`AvalancheWorkspace::run_to_rest`] on the season's kept flow state: its cost follows its
//! footprint, and the hazard map ([`HazardMap`]) is updated over its released cells only.
//!
//! **Deposit.** Debris is dense, sintered snow: it becomes *stable* snow (part of the bed of
//! later avalanches; the stability phenomenon compacts it further), volume for volume, so the
//! season's snow budget only loses what flowed off the grid.

use serde::{Deserialize, Serialize};
use snowscape_avalanche::release_area::{ReleaseAreaError, RuptureParams};
use snowscape_avalanche::{
    AvalancheError, AvalancheParams, AvalancheWorkspace, FrictionLaw, ReleasedCells, RunOptions,
};
use snowscape_terrain::parallel::{self, Chunks, PerRow};
use snowscape_terrain::{LayeredTerrain, SnowLayer, surface};
use thiserror::Error;

/// An invalid `[parameters.avalanche]` value.
#[derive(Debug, Error)]
pub enum AvalancheParametersError {
    /// A trigger parameter is out of range.
    #[error("{name} = {value} must be {expected}")]
    Invalid {
        name: &'static str,
        value: f64,
        expected: &'static str,
    },
    /// A flow or run parameter is out of range.
    #[error("flow: {0}")]
    Flow(#[from] AvalancheError),
    /// A rupture parameter is out of range.
    #[error("rupture: {0}")]
    Rupture(#[from] ReleaseAreaError),
}

/// When and how season avalanches happen.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct AvalancheParameters {
    /// Whether avalanches start by themselves. Default true.
    pub natural: bool,
    /// Avalanches per day on 1 km² of fully loaded, 35–45° slopes, 1/day. Default 1/7
    /// (Cordonnier 2018 §3.2: "once a week on average ... on a one square kilometer terrain").
    pub rate_per_km2_per_day: f64,
    /// Unstable thickness at which a cell's hazard saturates, m. Default 0.5 (chosen here:
    /// a typical slab is 0.3–1 m thick).
    pub reference_unstable_m: f64,
    /// Unstable thickness below which a cell cannot rupture, m. Default 0.05 (chosen here).
    pub min_unstable_m: f64,
    /// Slope below which nothing starts, degrees. Default 28 (chosen here: slab avalanches
    /// start on slopes steeper than ~30°).
    pub slope_min_deg: f64,
    /// Slope at which the hazard is full, degrees. Default 35.
    pub slope_full_deg: f64,
    /// Slope above which the hazard falls off, degrees. Default 45 (chosen here: steeper
    /// slopes hold less snow).
    pub slope_fall_deg: f64,
    /// Slope above which nothing starts (snow sloughs off continuously), degrees. Default 60.
    pub slope_max_deg: f64,
    /// Hazard gain per unit of the recent-skier map. Default 20 (chosen here: a skier on a
    /// loaded slope makes a release there far more likely than a natural one, §6.2).
    pub skier_gain: f64,
    /// Set the flow's dry/wet mix α from the snow temperature of the release (§6.1: "α is
    /// proportional to snow temperature"); false keeps `flow.alpha`. Default true. α is the
    /// Coulomb law's (`flow.friction = "coulomb"`, the paper's and the season's default): the
    /// samosAT and Voellmy laws have no dry/wet mix, and with them the release temperature
    /// sets nothing.
    pub alpha_from_temperature: bool,
    /// Release temperature at and below which the snow is dry (α = 1), °C. Default −10
    /// (Table 2's powdery-snow temperature T0powdery).
    pub dry_temperature_c: f64,
    /// Release temperature at and above which the snow is wet (α = `wet_alpha`), °C.
    /// Default 0 (melting).
    pub wet_temperature_c: f64,
    /// α of wet snow. Default 0.6 (chosen here: with Table 2's kv the viscous term alone
    /// cannot stop a flow, so wet snow keeps 60 % of the Coulomb yield, an effective rest
    /// angle of atan(0.6·tan 30°) ≈ 19°: wet avalanches run out farther, on gentler slopes).
    pub wet_alpha: f64,
    /// The rupture at the start cell (reach per metre of unstable snow, ...).
    pub rupture: RuptureParams,
    /// The flow (rest angle, viscosity, dry/wet mix, ...). Default: the paper's Coulomb law
    /// with the shallow-slope gravity ([`AvalancheParams::paper`]), not the `avalanche` job's
    /// samosATSmall default: on the 512² demo the samosAT law with the projected gravity and
    /// curvature ran 3 times the avalanche work (23.9 k → 71.0 k flow events, the season's
    /// avalanche phase 15 → 54 s on the loaded 2-core VM, 2026-12-07), past issue 47's cost
    /// bound. `flow.friction = "samosat"` (with `samos_at`, `slope_gravity = "projected"`)
    /// selects it for a season.
    pub flow: AvalancheParams,
    /// Run length and stop criterion of each avalanche.
    pub run: RunOptions,
}

impl Default for AvalancheParameters {
    fn default() -> Self {
        Self {
            natural: true,
            rate_per_km2_per_day: 1.0 / 7.0,
            reference_unstable_m: 0.5,
            min_unstable_m: 0.05,
            slope_min_deg: 28.0,
            slope_full_deg: 35.0,
            slope_fall_deg: 45.0,
            slope_max_deg: 60.0,
            skier_gain: 20.0,
            alpha_from_temperature: true,
            dry_temperature_c: -10.0,
            wet_temperature_c: 0.0,
            wet_alpha: 0.6,
            rupture: RuptureParams::default(),
            flow: AvalancheParams::paper(),
            run: RunOptions {
                duration_s: 300.0,
                ..RunOptions::default()
            },
        }
    }
}

impl AvalancheParameters {
    /// Checks every field, naming the offending one.
    pub fn validate(&self) -> Result<(), AvalancheParametersError> {
        let check = |name: &'static str, v: f64, ok: bool, expected: &'static str| {
            if v.is_finite() && ok {
                Ok(())
            } else {
                Err(AvalancheParametersError::Invalid {
                    name,
                    value: v,
                    expected,
                })
            }
        };
        let p = self;
        check(
            "rate_per_km2_per_day",
            p.rate_per_km2_per_day,
            (0.0..=100.0).contains(&p.rate_per_km2_per_day),
            "within [0, 100] per km² per day",
        )?;
        check(
            "reference_unstable_m",
            p.reference_unstable_m,
            p.reference_unstable_m > 0.0 && p.reference_unstable_m <= 100.0,
            "within (0, 100] m",
        )?;
        check(
            "min_unstable_m",
            p.min_unstable_m,
            (0.0..=100.0).contains(&p.min_unstable_m),
            "within [0, 100] m",
        )?;
        check(
            "slope_min_deg",
            p.slope_min_deg,
            (0.0..90.0).contains(&p.slope_min_deg),
            "in [0, 90)",
        )?;
        check(
            "slope_full_deg",
            p.slope_full_deg,
            p.slope_full_deg > p.slope_min_deg && p.slope_full_deg <= p.slope_fall_deg,
            "between slope_min_deg and slope_fall_deg",
        )?;
        check(
            "slope_fall_deg",
            p.slope_fall_deg,
            p.slope_fall_deg < p.slope_max_deg,
            "below slope_max_deg",
        )?;
        check(
            "slope_max_deg",
            p.slope_max_deg,
            p.slope_max_deg <= 90.0,
            "<= 90",
        )?;
        check(
            "skier_gain",
            p.skier_gain,
            (0.0..=10_000.0).contains(&p.skier_gain),
            "within [0, 10000]",
        )?;
        check(
            "wet_temperature_c",
            p.wet_temperature_c,
            p.dry_temperature_c.is_finite() && p.wet_temperature_c > p.dry_temperature_c,
            "above dry_temperature_c",
        )?;
        check(
            "wet_alpha",
            p.wet_alpha,
            (0.0..=1.0).contains(&p.wet_alpha),
            "in [0, 1]",
        )?;
        p.rupture.validate()?;
        p.flow.validate()?;
        p.run.validate()?;
        Ok(())
    }

    /// The slope window `s(θ)` of the hazard, for a slope in degrees: 0 below
    /// `slope_min_deg`, linear up to 1 at `slope_full_deg`, 1 up to `slope_fall_deg`, linear
    /// down to 0 at `slope_max_deg`.
    pub fn slope_window(&self, slope_deg: f64) -> f64 {
        if slope_deg <= self.slope_min_deg || slope_deg >= self.slope_max_deg {
            0.0
        } else if slope_deg < self.slope_full_deg {
            (slope_deg - self.slope_min_deg) / (self.slope_full_deg - self.slope_min_deg)
        } else if slope_deg <= self.slope_fall_deg {
            1.0
        } else {
            (self.slope_max_deg - slope_deg) / (self.slope_max_deg - self.slope_fall_deg)
        }
    }

    /// The dry/wet mix α for a release at mean snow temperature `t_c` (°C): 1 at and below
    /// `dry_temperature_c`, `wet_alpha` at and above `wet_temperature_c`, linear between.
    pub fn alpha_at(&self, t_c: f64) -> f64 {
        let x = ((t_c - self.dry_temperature_c)
            / (self.wet_temperature_c - self.dry_temperature_c))
            .clamp(0.0, 1.0);
        1.0 - x * (1.0 - self.wet_alpha)
    }
}

/// Per-cell avalanche hazard `λ_i` (1/day, row-major) into `out`, and its sum (rows summed
/// in order, each row cell by cell: [`HazardMap`]'s total). `slope_deg` is the bedrock slope
/// per cell (cached by the season: snow changes the slope of release areas little); `skiers`
/// the recent-skier map, when skiers run.
pub fn hazard(
    params: &AvalancheParameters,
    terrain: &LayeredTerrain,
    slope_deg: &[f32],
    skiers: Option<&[f32]>,
    out: &mut Vec<f64>,
) -> f64 {
    let mut map = HazardMap {
        lambda: std::mem::take(out),
        ..HazardMap::default()
    };
    let sources = HazardSources {
        skiers,
        painted: None,
    };
    let total = map.compute(params, terrain, slope_deg, &sources);
    *out = map.lambda;
    total
}

/// What raises the hazard besides the snow and the slope, per cell.
#[derive(Debug, Clone, Copy, Default)]
pub struct HazardSources<'a> {
    /// The recent-skier map (skier-triggered releases, weighted by `skier_gain`).
    pub skiers: Option<&'a [f32]>,
    /// Painted release rates, 1/day per cell (the editor's avalanche brush): added to `λ_i`
    /// wherever the cell holds at least `min_unstable_m` of unstable snow, at any slope (a
    /// painted release is the user's choice; the rupture still needs unstable snow).
    pub painted: Option<&'a [f32]>,
}

impl HazardSources<'_> {
    /// Whether nothing but natural releases can raise the hazard.
    fn none_but_natural(&self, params: &AvalancheParameters) -> bool {
        (self.skiers.is_none() || params.skier_gain == 0.0) && self.painted.is_none()
    }
}

/// The hazard `λ_i` of one cell, 1/day.
#[inline]
fn cell_hazard(
    params: &AvalancheParameters,
    terrain: &LayeredTerrain,
    slope_deg: &[f32],
    sources: &HazardSources,
    i: usize,
) -> f64 {
    let u = terrain.layer(SnowLayer::Unstable)[i] as f64;
    if u < params.min_unstable_m || !terrain.mask().is_valid(i) {
        return 0.0;
    }
    let painted = sources.painted.map_or(0.0, |m| f64::from(m[i]));
    let s = params.slope_window(slope_deg[i] as f64);
    if s == 0.0 {
        return painted;
    }
    let natural = if params.natural { 1.0 } else { 0.0 };
    let k = sources.skiers.map_or(0.0, |m| m[i] as f64);
    let per_cell = params.rate_per_km2_per_day * terrain.geometry().cell_area() / 1e6;
    let released = per_cell
        * (u / params.reference_unstable_m).min(1.0)
        * s
        * (natural + params.skier_gain * k);
    released + painted
}

/// The hazard map of a season: `λ_i` per cell, its sum per row and in all. A full
/// [`HazardMap::compute`] after melt or snowfall; after an avalanche only its released cells
/// change (the only cells whose unstable snow it moved: debris is stable snow), and
/// [`HazardMap::update_cells`] recomputes them and their rows' sums, with the same bits as a
/// full computation. A start cell is drawn by walking the row sums, then one row.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HazardMap {
    /// `λ_i`, 1/day, row-major.
    pub lambda: Vec<f64>,
    /// Sum of each row, cell by cell in index order.
    row_sums: Vec<f64>,
    /// Sum of the row sums in row order (the Avalanche-Start rate), 1/day.
    total: f64,
    /// `lambda` and `row_sums` hold only zeros (nothing releases), so a map without sources
    /// need not be cleared again: a season without natural releases computed it after every
    /// melt and snowfall event, writing the whole map each time.
    zeroed: bool,
    /// The slope window `s(θ)` of every cell, for the slopes and the window it was computed
    /// for: the map is recomputed after every melt and snowfall event, the slopes and the
    /// window stay.
    window: SlopeWindowCache,
}

/// The sum of each of the rows of `rows` (`w` cells each, as many rows as `sums`; at most 4),
/// cell by cell in index order, the rows' chains of additions side by side.
fn row_sums_side_by_side(rows: &[f64], w: usize, sums: &mut [f64]) {
    let mut acc = [0.0f64; 4];
    let n = sums.len();
    debug_assert!(n <= 4 && rows.len() == n * w);
    if n == 4 {
        let (r0, rest) = rows.split_at(w);
        let (r1, rest) = rest.split_at(w);
        let (r2, r3) = rest.split_at(w);
        for c in 0..w {
            acc[0] += r0[c];
            acc[1] += r1[c];
            acc[2] += r2[c];
            acc[3] += r3[c];
        }
    } else {
        for (a, row) in acc.iter_mut().zip(rows.chunks(w)) {
            for &l in row {
                *a += l;
            }
        }
    }
    sums.copy_from_slice(&acc[..n]);
}

/// [`HazardMap::window`].
#[derive(Debug, Clone, Default, PartialEq)]
struct SlopeWindowCache {
    /// The window's four slopes (bits) and the slopes (bits) the factors are for.
    key: Option<([u64; 4], Vec<u32>)>,
    factor: Vec<f64>,
}

impl SlopeWindowCache {
    /// `s(θ_i)` of every cell (recomputed, row-parallel, if the slopes or the window changed).
    fn factors(&mut self, params: &AvalancheParameters, slope_deg: &[f32]) -> &[f64] {
        let window = [
            params.slope_min_deg,
            params.slope_full_deg,
            params.slope_fall_deg,
            params.slope_max_deg,
        ]
        .map(f64::to_bits);
        // Blocks of cells compared in parallel (a boolean: the same for any thread count).
        const BLOCK: usize = 1 << 14;
        let same = self.key.as_ref().is_some_and(|(k, slopes)| {
            *k == window
                && slopes.len() == slope_deg.len()
                && parallel::map_rows(BLOCK, (slopes, slope_deg), |_, (slopes, slope_deg)| {
                    slopes.iter().zip(slope_deg).all(|(a, b)| *a == b.to_bits())
                })
                .into_iter()
                .all(|same| same)
        });
        if !same {
            self.factor.resize(slope_deg.len(), 0.0);
            parallel::map_cells(&mut self.factor, slope_deg, |&s| {
                params.slope_window(f64::from(s))
            });
            self.key = Some((window, slope_deg.iter().map(|s| s.to_bits()).collect()));
        }
        &self.factor
    }
}

impl HazardMap {
    /// The Avalanche-Start rate `Σ λ_i`, 1/day.
    pub fn total(&self) -> f64 {
        self.total
    }

    /// Recomputes every cell (rows in parallel; the sums do not depend on the thread count).
    pub fn compute(
        &mut self,
        params: &AvalancheParameters,
        terrain: &LayeredTerrain,
        slope_deg: &[f32],
        sources: &HazardSources,
    ) -> f64 {
        let g = terrain.geometry();
        let (w, h) = (g.width(), g.height());
        let nothing_releases = !params.natural && sources.none_but_natural(params);
        if nothing_releases && self.zeroed && self.lambda.len() == w * h {
            return 0.0;
        }
        self.zeroed = nothing_releases;
        if nothing_releases {
            // Nothing releases: every λ is 0.
            self.lambda.clear();
            self.lambda.resize(w * h, 0.0);
            self.row_sums.clear();
            self.row_sums.resize(h, 0.0);
            self.total = 0.0;
            return 0.0;
        }
        // Every cell and every row sum is written below.
        self.lambda.resize(w * h, 0.0);
        self.row_sums.resize(h, 0.0);
        let unstable = terrain.layer(SnowLayer::Unstable);
        let invalid = terrain.mask().invalid_cells();
        if invalid.is_none() && sources.skiers.is_none() && sources.painted.is_none() {
            // Natural releases on a grid without nodata: `cell_hazard` with its slope window
            // looked up and no sources, the same operations in the same order (no skier: `k`
            // is 0; no paint: `+ 0`), in a straight loop.
            let window = self.window.factors(params, slope_deg);
            let per_cell = params.rate_per_km2_per_day * g.cell_area() / 1e6;
            let natural = if params.natural { 1.0 } else { 0.0 };
            let triggers = natural + params.skier_gain * 0.0;
            let (min, reference) = (params.min_unstable_m, params.reference_unstable_m);
            // Rows by groups of four: each row's sum is one chain of additions in cell order,
            // and four chains side by side run at once.
            const ROWS: usize = 4;
            parallel::for_each_block(
                ROWS * w,
                (
                    &mut self.lambda,
                    Chunks(&mut self.row_sums[..], ROWS),
                    unstable,
                    window,
                ),
                |_, (rows, sums, unstable, window)| {
                    for ((l, &u), &s) in rows.iter_mut().zip(unstable).zip(window) {
                        let u = f64::from(u);
                        *l = if u < min || s == 0.0 {
                            0.0
                        } else {
                            per_cell * (u / reference).min(1.0) * s * triggers
                        };
                    }
                    row_sums_side_by_side(rows, w, sums);
                },
            );
            self.total = self.row_sums.iter().sum();
            return self.total;
        }
        parallel::for_each_row(
            w,
            (&mut self.lambda, PerRow(&mut self.row_sums[..])),
            |r, (row, sum)| {
                *sum = 0.0;
                let o = r * w;
                for (c, l) in row.iter_mut().enumerate() {
                    let i = o + c;
                    // Most cells hold too little unstable snow: a look at it alone.
                    *l = if (unstable[i] as f64) < params.min_unstable_m
                        || invalid.is_some_and(|m| m[i])
                    {
                        0.0
                    } else {
                        cell_hazard(params, terrain, slope_deg, sources, i)
                    };
                    *sum += *l;
                }
            },
        );
        self.total = self.row_sums.iter().sum();
        self.total
    }

    /// Recomputes the cells `cells` (row-major, ascending) and the sums of their rows.
    pub fn update_cells(
        &mut self,
        params: &AvalancheParameters,
        terrain: &LayeredTerrain,
        slope_deg: &[f32],
        sources: &HazardSources,
        cells: &[usize],
    ) -> f64 {
        let w = terrain.geometry().width();
        if self.lambda.len() != terrain.geometry().len() {
            return self.compute(params, terrain, slope_deg, sources);
        }
        if !params.natural && sources.none_but_natural(params) {
            return 0.0;
        }
        self.zeroed = false;
        let mut last_row = usize::MAX;
        for &i in cells {
            self.lambda[i] = cell_hazard(params, terrain, slope_deg, sources, i);
            let r = i / w;
            if r != last_row {
                if last_row != usize::MAX {
                    self.sum_row(last_row, w);
                }
                last_row = r;
            }
        }
        if last_row != usize::MAX {
            self.sum_row(last_row, w);
        }
        self.total = self.row_sums.iter().sum();
        self.total
    }

    fn sum_row(&mut self, r: usize, w: usize) {
        let mut sum = 0.0;
        for &l in &self.lambda[r * w..(r + 1) * w] {
            sum += l;
        }
        self.row_sums[r] = sum;
    }

    /// The cell whose cumulative hazard first exceeds `u · Σλ` (`u` uniform in [0, 1)): the
    /// row by its row sums, then the cell in it; `None` when nothing can release.
    pub fn pick(&self, u: f64) -> Option<usize> {
        if self.total <= 0.0 {
            return None;
        }
        let w = self.lambda.len() / self.row_sums.len().max(1);
        let target = u * self.total;
        let mut acc = 0.0;
        let mut last_row = None;
        for (r, &s) in self.row_sums.iter().enumerate() {
            if s <= 0.0 {
                continue;
            }
            last_row = Some(r);
            if acc + s > target {
                let row = &self.lambda[r * w..(r + 1) * w];
                return pick_cell(row, s, (target - acc) / s).map(|c| r * w + c);
            }
            acc += s;
        }
        // Round-off left the target beyond the last row: its last cell that can release.
        let r = last_row?;
        let row = &self.lambda[r * w..(r + 1) * w];
        row.iter().rposition(|&l| l > 0.0).map(|c| r * w + c)
    }
}

/// Bedrock slope of every cell, degrees.
pub fn bedrock_slopes_deg(terrain: &LayeredTerrain) -> Vec<f32> {
    surface::slopes(&terrain.bedrock, terrain.geometry(), terrain.mask())
        .into_iter()
        .map(f32::to_degrees)
        .collect()
}

/// The cell whose cumulative hazard first exceeds `u · Σλ` (`u` uniform in [0, 1)).
pub fn pick_cell(hazard: &[f64], total: f64, u: f64) -> Option<usize> {
    if total <= 0.0 {
        return None;
    }
    let target = u * total;
    let mut acc = 0.0;
    let mut last = None;
    for (i, &h) in hazard.iter().enumerate() {
        if h > 0.0 {
            acc += h;
            last = Some(i);
            if acc > target {
                return Some(i);
            }
        }
    }
    last
}

/// How an avalanche of the season was triggered.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Trigger {
    /// Drawn from the hazard map.
    Natural,
    /// Started by the user (scenario or library call).
    User,
    /// Started by a skier crossing unstable snow.
    Skier,
    /// Drawn from the painted release rates ([`HazardSources::painted`]: the editor's brush).
    Painted,
}

/// One avalanche of the season, as `report.json` lists it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AvalancheRecord {
    /// Season day of the release.
    pub day: f64,
    /// How it started.
    pub trigger: Trigger,
    /// Rupture cell (column, row) and its map coordinates.
    pub cell: [usize; 2],
    pub map_xy: [f64; 2],
    /// Released volume, m³.
    pub released_m3: f64,
    /// Entrained from the snowpack along the track, m³ (`snowscape_avalanche::entrainment`).
    #[serde(default)]
    pub entrained_m3: f64,
    /// Deposited on the grid, m³.
    pub deposited_m3: f64,
    /// Flowed off the grid, m³.
    pub outflow_m3: f64,
    /// Horizontal distance from the release top to the farthest footprint cell, m.
    pub runout_length_m: f64,
    /// Mass-centre travel angle, degrees.
    pub travel_angle_deg: f64,
    /// Footprint area, m².
    pub footprint_area_m2: f64,
    /// Largest speed, m/s.
    pub max_speed_m_s: f64,
    /// Simulated duration, s.
    pub simulated_s: f64,
    /// Flow records taken (at least `run.record_interval_s`, 0.1 s, apart).
    pub steps: u64,
    /// Mean snow temperature of the released cells, °C (when α follows it: the Coulomb law).
    pub release_temperature_c: Option<f64>,
    /// The dry/wet mix α of the flow (the Coulomb law's; 1 under samosAT and Voellmy).
    pub alpha: f64,
}

/// Snow thickness the avalanches of a season took away (scour) and laid down (deposit), per
/// cell, m.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AvalancheMaps {
    pub scour: Vec<f32>,
    pub deposit: Vec<f32>,
}

/// One release of the season: its cells, when and how it started, and the rupture cell.
#[derive(Debug, Clone, Copy)]
pub struct Release<'a> {
    /// Released cells, row-major, ascending.
    pub cells: &'a [usize],
    /// Season day.
    pub day: f64,
    pub trigger: Trigger,
    /// The rupture cell (row-major index).
    pub cell: usize,
}

/// Releases `cells` (row-major, ascending), runs the avalanche to rest and deposits it as
/// stable snow ([`AvalancheWorkspace::run_to_rest`]: the cost follows the avalanche's
/// footprint). With `alpha_from_temperature` and the Coulomb law, α comes from the mean
/// `temperature` (°C per cell) of the released cells. Returns the record and the cells whose snow the flow
/// entrained (ascending), beside the released ones.
pub fn run_avalanche(
    params: &AvalancheParameters,
    terrain: &mut LayeredTerrain,
    temperature: &[f32],
    release: Release,
    maps: &mut AvalancheMaps,
    workspace: &mut AvalancheWorkspace,
) -> Result<(AvalancheRecord, Vec<usize>), AvalancheError> {
    let Release {
        cells,
        day,
        trigger,
        cell,
    } = release;
    let n = terrain.geometry().len();
    for m in [&mut maps.scour, &mut maps.deposit] {
        if m.len() != n {
            *m = vec![0.0; n];
        }
    }
    let mut flow = params.flow.clone();
    let mut release_t = None;
    if params.alpha_from_temperature && flow.friction == FrictionLaw::Coulomb {
        let valid: Vec<usize> = cells
            .iter()
            .copied()
            .filter(|&i| terrain.mask().is_valid(i))
            .collect();
        if !valid.is_empty() {
            let sum = valid.iter().fold(0.0, |s, &i| s + temperature[i] as f64);
            let t = sum / valid.len() as f64;
            flow.alpha = params.alpha_at(t);
            release_t = Some(t);
        }
    }
    let outcome = workspace.run_to_rest::<AvalancheError>(
        terrain,
        ReleasedCells::new(cells, None),
        &flow,
        &params.run,
        SnowLayer::Stable,
        |_| Ok(()),
    )?;
    for &(i, h) in outcome.released.iter().chain(&outcome.entrained) {
        maps.scour[i as usize] += h;
    }
    for &(i, h) in &outcome.deposited {
        maps.deposit[i as usize] += h;
    }
    let summary = &outcome.summary;
    let g = terrain.geometry();
    let (c, r) = g.col_row(cell);
    let (x, y) = g.cell_centre(c, r);
    let mut entrained: Vec<usize> = outcome.entrained.iter().map(|&(i, _)| i as usize).collect();
    entrained.sort_unstable();
    let record = AvalancheRecord {
        day,
        trigger,
        cell: [c, r],
        map_xy: [x, y],
        released_m3: summary.released_volume_m3,
        entrained_m3: outcome.entrained_m3,
        deposited_m3: outcome.deposited_m3,
        outflow_m3: summary.border_outflow_m3,
        runout_length_m: summary.runout_length_m,
        travel_angle_deg: summary.travel_angle_deg,
        footprint_area_m2: summary.footprint_area_m2,
        max_speed_m_s: summary.max_speed_m_s,
        simulated_s: summary.simulated_s,
        steps: outcome.records,
        release_temperature_c: release_t,
        alpha: flow.dry_weight(),
    };
    Ok((record, entrained))
}
