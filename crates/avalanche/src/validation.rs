//! Validation cases of the avalanche flow, shared by the tests (`tests/validation.rs`,
//! `tests/runout.rs`, `tests/real_paths.rs`) and `examples/validation.rs`, which prints them as
//! one table. Each function runs one case and returns its numbers; the tests hold the
//! tolerances and their justification.
//!
//! - [`dam_break`]: Ritter's dry dam break on a flat frictionless bed.
//! - [`poured_pile`]: a pile poured slowly on one cell stands at the rest angle θc.
//! - [`plane_runout`]: a block released on an inclined plane runs out onto flat ground; for
//!   pure Coulomb friction the mass centre's travel angle `atan(drop / horizontal travel)` tends
//!   to θc (a point mass with horizontal velocity `u` obeys `d(u²/2)/dx = g·(tanθ − tanθc)` on
//!   the slope and `−g·tanθc` on the flat, so it stops after a horizontal travel `H / tanθc`).
//! - [`run_release`]: a release shapefile on a real DEM, run to rest on the one path every
//!   front end shares ([`AvalancheWorkspace::run_to_rest`]); [`read_polyline`] and [`distance_to_polyline`] measure it against a
//!   practitioner's path line, [`footprint_overlap`] against a reference peak-thickness raster
//!   (compared by map coordinates).

use crate::flow::{
    AvalancheError, AvalancheParams, AvalancheScratch, AvalancheState, Border, G, step,
};
use crate::release_area::{ReleaseAreaError, ReleaseMask, release_from_shapefile};
use crate::rest::{AvalancheWorkspace, ReleasedCells, RestOutcome};
use crate::run::{AvalancheRun, RunOptions, RunSummary};
use snowscape_io::{RasterError, ReadOptions};
use snowscape_terrain::operators;
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, NodataMask, SnowLayer};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why a validation case could not run.
#[derive(Debug, Error)]
pub enum ValidationError {
    /// A raster could not be read.
    #[error(transparent)]
    Raster(#[from] RasterError),
    /// A release area could not be made.
    #[error(transparent)]
    Release(#[from] ReleaseAreaError),
    /// The flow failed.
    #[error(transparent)]
    Flow(#[from] AvalancheError),
    /// A path line could not be read or holds no line.
    #[error("path line {path}: {what}")]
    PathLine {
        /// The `.shp` path.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
}

fn flat_state(w: usize, h: usize, dx: f64) -> Result<AvalancheState, AvalancheError> {
    let g = GridGeometry::square(w, h, dx).map_err(|_| AvalancheError::InvalidParameter {
        name: "grid",
        value: dx,
        expected: "a valid grid",
    })?;
    AvalancheState::new(&g, &NodataMask::all_valid(), &vec![0.0; w * h])
}

/// Ritter's dam break compared with the scheme.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DamBreak {
    /// L1 error of the thickness profile over the strip, relative to the exact volume.
    pub l1_rel: f64,
    /// The same over the rarefaction part (x ≤ x0).
    pub l1_rarefaction_rel: f64,
    /// Front position (last cell with h > 1 cm) past the dam, m.
    pub front_m: f64,
    /// Ritter's position of h = 1 cm, m.
    pub front_exact_1cm_m: f64,
    /// Ritter's tip `2·sqrt(g·h0)·t`, m.
    pub front_exact_m: f64,
}

/// Dam break on a flat frictionless bed: 400 x 101 cells of 1 m, h0 = 1 m left of x0 = 200 m,
/// the middle row compared with Ritter's solution at t = 15 s. `params` should be frictionless
/// (`alpha = 0`, `k_viscous = 0`).
pub fn dam_break(params: &AvalancheParams) -> Result<DamBreak, AvalancheError> {
    let (w, hgt) = (400usize, 101usize);
    let mut s = flat_state(w, hgt, 1.0)?;
    let h0 = 1.0;
    let x0 = 200.0;
    let hinit: Vec<f64> = (0..w * hgt)
        .map(|i| if ((i % w) as f64) < x0 { h0 } else { 0.0 })
        .collect();
    s.set_thickness(&hinit)?;
    let mut scratch = AvalancheScratch::default();
    let t = 15.0;
    for _ in 0..15 {
        step(params, &mut s, &mut scratch, 1.0)?;
    }
    let c0 = (G * h0).sqrt();
    let ritter = |x: f64| {
        let xi = (x - x0) / t;
        if xi < -c0 {
            h0
        } else if xi > 2.0 * c0 {
            0.0
        } else {
            (2.0 * c0 - xi).powi(2) / (9.0 * G)
        }
    };
    let row = hgt / 2;
    let (mut err, mut norm, mut err_r, mut norm_r) = (0.0, 0.0, 0.0, 0.0);
    let mut front = x0;
    for c in 0..w {
        let x = c as f64 + 0.5;
        let hn = s.thickness_at(c, row);
        let he = ritter(x);
        err += (hn - he).abs();
        norm += he;
        if x <= x0 {
            err_r += (hn - he).abs();
            norm_r += he;
        }
        if hn > 0.01 {
            front = x;
        }
    }
    Ok(DamBreak {
        l1_rel: err / norm,
        l1_rarefaction_rel: err_r / norm_r,
        front_m: front - x0,
        front_exact_1cm_m: (2.0 * c0 - 3.0 * (0.01 * G).sqrt()) * t,
        front_exact_m: 2.0 * c0 * t,
    })
}

/// A pile poured on flat ground.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pile {
    /// Mean slope of the flank cells (depth between 10 % and 90 % of the maximum), degrees.
    pub mean_flank_deg: f64,
    /// Number of flank cells.
    pub flank_cells: usize,
    /// Largest depth, m.
    pub height_m: f64,
    /// Height of the cone at θc holding the poured volume, m.
    pub cone_height_m: f64,
    /// Largest pipe speed at the end, m/s.
    pub final_speed: f64,
}

/// Mean flank slope (degrees), flank cell count and largest depth of a pile of thickness `hv`
/// on a flat `n x n` grid of 1 m cells.
pub fn flank_angle(hv: &[f64], n: usize) -> (f64, usize, f64) {
    let hmax = hv.iter().cloned().fold(0.0, f64::max);
    let (mut sum, mut count) = (0.0, 0usize);
    for r in 1..n - 1 {
        for c in 1..n - 1 {
            let v = hv[r * n + c];
            if v > 0.1 * hmax && v < 0.9 * hmax {
                let (west, east) = (hv[r * n + c - 1], hv[r * n + c + 1]);
                let (north, south) = (hv[(r - 1) * n + c], hv[(r + 1) * n + c]);
                let gx = operators::centred_difference(Some(west), v, Some(east), 1.0);
                let gy = operators::centred_difference(Some(north), v, Some(south), 1.0);
                sum += operators::slope_angle(gx, gy).to_degrees();
                count += 1;
            }
        }
    }
    (sum / count.max(1) as f64, count, hmax)
}

/// A granular pile poured slowly (0.05 m³ every 0.05 s on one cell of 1 m, 150 m³ in all) on a
/// closed 60 x 60 grid, then left to settle (up to 100 s).
pub fn poured_pile(params: &AvalancheParams) -> Result<Pile, AvalancheError> {
    let n = 60usize;
    let mut s = flat_state(n, n, 1.0)?;
    let params = AvalancheParams {
        border: Border::Closed,
        ..params.clone()
    };
    let mut scratch = AvalancheScratch::default();
    for _ in 0..3000 {
        s.add_thickness(30, 30, 0.05)?;
        step(&params, &mut s, &mut scratch, 0.05)?;
    }
    for _ in 0..100 {
        let rep = step(&params, &mut s, &mut scratch, 1.0)?;
        if rep.max_speed == 0.0 {
            break;
        }
    }
    let (mean, count, hmax) = flank_angle(&s.thickness(), n);
    let v = 3000.0 * 0.05;
    Ok(Pile {
        mean_flank_deg: mean,
        flank_cells: count,
        height_m: hmax,
        cone_height_m: (v / std::f64::consts::PI).cbrt(),
        final_speed: s.max_speed(),
    })
}

/// A block run out from an inclined plane onto flat ground.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneRunout {
    /// Slope of the plane, degrees.
    pub slope_deg: f64,
    /// θc of the run, degrees.
    pub rest_angle_deg: f64,
    /// Cell size, m.
    pub cell_m: f64,
    /// The run's figures (travel angle, drop, travel, stop reason...).
    pub summary: RunSummary,
}

/// A 20 m x 20 m x 2 m block released 20 m below the top of a `slope_deg` plane 300 m long
/// (horizontally), running out onto 400 m of flat ground, 240 m wide; cells of `cell_m`, open
/// borders.
pub fn plane_runout(
    slope_deg: f64,
    params: &AvalancheParams,
    cell_m: f64,
    options: &RunOptions,
) -> Result<PlaneRunout, AvalancheError> {
    if !(slope_deg.is_finite() && slope_deg > 0.0 && slope_deg < 80.0) {
        return Err(AvalancheError::InvalidParameter {
            name: "slope_deg",
            value: slope_deg,
            expected: "in (0, 80)",
        });
    }
    if !(cell_m.is_finite() && cell_m > 0.1 && cell_m <= 10.0) {
        return Err(AvalancheError::InvalidParameter {
            name: "cell_m",
            value: cell_m,
            expected: "in (0.1, 10]",
        });
    }
    let tan = slope_deg.to_radians().tan();
    let (len_slope, len_flat, block, depth) = (300.0, 400.0, 20.0, 2.0);
    let w = (240.0 / cell_m) as usize;
    let h = ((len_slope + len_flat) / cell_m) as usize;
    let mut s = flat_state(w, h, cell_m)?;
    let bed: Vec<f64> = (0..w * h)
        .map(|i| {
            let y = ((i / w) as f64 + 0.5) * cell_m;
            tan * (len_slope - y).max(0.0)
        })
        .collect();
    s = AvalancheState::new(s.geometry(), &NodataMask::all_valid(), &bed)?;
    let mid = w as f64 * cell_m / 2.0;
    let hv: Vec<f64> = (0..w * h)
        .map(|i| {
            let x = ((i % w) as f64 + 0.5) * cell_m;
            let y = ((i / w) as f64 + 0.5) * cell_m;
            if (x - mid).abs() < block / 2.0 && y > 20.0 && y < 20.0 + block {
                depth
            } else {
                0.0
            }
        })
        .collect();
    s.set_thickness(&hv)?;
    let mut run = AvalancheRun::new(s);
    let summary = run.run::<AvalancheError>(params, options, |_| Ok(()))?;
    Ok(PlaneRunout {
        slope_deg,
        rest_angle_deg: params.rest_angle_deg,
        cell_m,
        summary,
    })
}

/// How a release thickness is measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThicknessConvention {
    /// Vertical thickness per horizontal cell (the flow's own convention).
    Vertical,
    /// Measured normal to the slope (AvaFrame com1DFA): the vertical thickness is `d / cosθ`
    /// with θ the bed slope of the cell, so the volume is `d` times the inclined area.
    SlopeNormal,
}

impl ThicknessConvention {
    /// Turns release thicknesses measured this way into the flow's vertical ones, in place,
    /// on the bed `dem` (slope-normal: `d / cosθ`).
    pub fn to_vertical(self, thickness: &mut [f64], dem: &Grid) {
        if self == ThicknessConvention::SlopeNormal {
            let g = dem.geometry();
            let w = g.width();
            for (i, t) in thickness.iter_mut().enumerate() {
                if *t > 0.0 {
                    let slope =
                        snowscape_terrain::surface::slope(dem.data(), g, dem.mask(), i % w, i / w)
                            as f64;
                    *t /= slope.cos();
                }
            }
        }
    }
}

/// A release on a real DEM run to rest.
#[derive(Debug, Clone)]
pub struct RealRun {
    /// The DEM.
    pub dem: Grid,
    /// The release.
    pub release: ReleaseMask,
    /// The run's figures.
    pub summary: RunSummary,
    /// Peak flow thickness per cell, m.
    pub peak_thickness: Vec<f64>,
    /// Flowing thickness at the end, m.
    pub final_thickness: Vec<f64>,
    /// Wall time of the run (release to stop, reading excluded), s.
    pub wall_s: f64,
}

impl RealRun {
    /// Map coordinates of the volume-weighted centre of the final thickness.
    pub fn deposit_centre(&self) -> (f64, f64) {
        let g = self.dem.geometry();
        let w = g.width();
        let (mut sx, mut sy, mut sv) = (0.0, 0.0, 0.0);
        for (i, &h) in self.final_thickness.iter().enumerate() {
            if h > 0.0 {
                let (x, y) = g.cell_centre(i % w, i / w);
                sx += h * x;
                sy += h * y;
                sv += h;
            }
        }
        if sv > 0.0 {
            (sx / sv, sy / sv)
        } else {
            (f64::NAN, f64::NAN)
        }
    }
}

/// Reads `dem`, rasterises the release shapefile into it, releases `default_thickness_m` (or
/// the shapefile's thickness) measured as `convention` says, and runs the flow until
/// `options` stop it.
pub fn run_release(
    dem: &Path,
    release: &Path,
    default_thickness_m: f64,
    convention: ThicknessConvention,
    params: &AvalancheParams,
    options: &RunOptions,
) -> Result<RealRun, ValidationError> {
    let grid = snowscape_io::read_dem(dem, &ReadOptions::default())?;
    let g = grid.geometry().clone();
    let mask = release_from_shapefile(release, &g, grid.mask())?;
    let mut thickness = mask.thickness_field(default_thickness_m)?;
    convention.to_vertical(&mut thickness, &grid);
    // The release as unstable snow on the bare DEM, run to rest on the one path the season,
    // the editor and the command line share.
    let mut terrain = LayeredTerrain::from_bedrock(grid.clone());
    let cells: Vec<usize> = (0..thickness.len())
        .filter(|&i| thickness[i] > 0.0)
        .collect();
    let unstable = terrain.layer_mut(SnowLayer::Unstable);
    for &i in &cells {
        unstable[i] = thickness[i] as f32;
    }
    let t0 = std::time::Instant::now();
    let outcome = AvalancheWorkspace::new().run_to_rest::<AvalancheError>(
        &mut terrain,
        ReleasedCells::new(&cells, None),
        params,
        options,
        SnowLayer::Stable,
        |_| Ok(()),
    )?;
    let wall_s = t0.elapsed().as_secs_f64();
    let n = g.len();
    let summary = outcome.summary.clone();
    Ok(RealRun {
        peak_thickness: RestOutcome::dense(&outcome.peak_thickness, n),
        final_thickness: RestOutcome::dense(&outcome.deposited, n),
        dem: grid,
        release: mask,
        summary,
        wall_s,
    })
}

/// The vertices (map coordinates) of the first line of a Polyline(Z/M) shapefile, all its
/// parts joined in order.
pub fn read_polyline(path: &Path) -> Result<Vec<(f64, f64)>, ValidationError> {
    let err = |what: String| ValidationError::PathLine {
        path: path.to_path_buf(),
        what,
    };
    snowscape_io::vector::read_first_polyline(path).map_err(|e| match e {
        snowscape_io::vector::VectorError::NotALine { what, .. } => err(what),
        other => err(other.to_string()),
    })
}

/// Horizontal distance from `(x, y)` to a polyline, and the distance along the line (from its
/// first vertex) of the nearest point.
pub fn distance_to_polyline(line: &[(f64, f64)], x: f64, y: f64) -> (f64, f64) {
    let mut best = (f64::INFINITY, 0.0);
    let mut along = 0.0;
    for seg in line.windows(2) {
        let ((ax, ay), (bx, by)) = (seg[0], seg[1]);
        let (vx, vy) = (bx - ax, by - ay);
        let len2 = vx * vx + vy * vy;
        let t = if len2 > 0.0 {
            (((x - ax) * vx + (y - ay) * vy) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let d = (x - ax - t * vx).hypot(y - ay - t * vy);
        if d < best.0 {
            best = (d, along + t * len2.sqrt());
        }
        along += len2.sqrt();
    }
    best
}

/// Agreement of two footprints.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Overlap {
    /// Our footprint, m² (on the reference grid).
    pub ours_m2: f64,
    /// The reference footprint, m².
    pub reference_m2: f64,
    /// Both, m².
    pub both_m2: f64,
    /// `both / (ours + reference − both)`.
    pub jaccard: f64,
    /// Share of the reference footprint that ours covers, `both / reference`.
    pub recall: f64,
    /// Share of our footprint inside the reference's, `both / ours`.
    pub precision: f64,
}

/// Compares our peak thickness (on `geometry`) with a reference peak-thickness raster by map
/// coordinates: every valid reference cell is looked up in our grid at its centre (nearest
/// cell); a footprint is where the peak exceeds `threshold_m`.
pub fn footprint_overlap(
    geometry: &GridGeometry,
    peak: &[f64],
    reference: &Grid,
    threshold_m: f64,
) -> Overlap {
    let rg = reference.geometry();
    let w = geometry.width();
    let (mut ours, mut theirs, mut both) = (0usize, 0usize, 0usize);
    for r in 0..rg.height() {
        for c in 0..rg.width() {
            let i = r * rg.width() + c;
            let (x, y) = rg.cell_centre(c, r);
            let o = geometry
                .map_to_cell(x, y)
                .map(|(fc, fr)| {
                    let cc = (fc.round().max(0.0) as usize).min(w - 1);
                    let rr = (fr.round().max(0.0) as usize).min(geometry.height() - 1);
                    peak[rr * w + cc] > threshold_m
                })
                .unwrap_or(false);
            let t = reference.mask().is_valid(i) && reference.data()[i] as f64 > threshold_m;
            ours += o as usize;
            theirs += t as usize;
            both += (o && t) as usize;
        }
    }
    let a = rg.cell_area();
    let union = (ours + theirs - both).max(1) as f64;
    Overlap {
        ours_m2: ours as f64 * a,
        reference_m2: theirs as f64 * a,
        both_m2: both as f64 * a,
        jaccard: both as f64 / union,
        recall: both as f64 / theirs.max(1) as f64,
        precision: both as f64 / ours.max(1) as f64,
    }
}
