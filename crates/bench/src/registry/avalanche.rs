//! Kernels of `snowscape-avalanche` (Cordonnier 2018 §6.1).
//!
//! Whole avalanches, as users run them (each call releases, runs to rest and deposits through
//! [`AvalancheWorkspace::run_to_rest`], the path of the season, on a terrain restored before
//! each call; cells = the footprint, peak thickness > 1 cm, of a probe run; no bandwidth
//! model, the cost follows the flow; the paper's law, the seasons'):
//! - `avalanche/slope_run_to_rest`: a 1 m release 60 m long across the whole width of a 35°
//!   slope of 5 m cells running out onto flat ground (`size` × `0.3 size` cells; 1000 × 300 at
//!   the size).
//! - `avalanche/avakot_run_to_rest`: the real avaKot DEM (AvaFrame, 5 m) with its release
//!   polygons `REL/relKot.shp` and their thickness, from `../shared/data` (the benchmark
//!   fails when the data is missing).
//!
//! `avalanche/substep` (the paper's model; `_projected`: with Savage-Hutter's projected gravity
//! and the bed's curvature, `_projected_no_curvature` without it; `_default`: the defaults,
//! samosATSmall with the projected gravity and curvature; `_voellmy`, `_samosat`: under those
//! laws): one CFL sub-step of a release of `size/5` square cells (200x200 at
//! 1024², the footprint) sliding down a 35° plane of 2 m cells, two seconds after the
//! release. The state keeps flowing from call to call (a real avalanche's successive
//! sub-steps); cells = the active box after the warm-up. 560 B per active cell: the five passes of a sub-step
//! read and write per cell the thickness, bed, 4 pipe velocities, 6 cell-flow values, 4 new
//! pipe velocities, 4 volumes and an outflow factor (f64), each pass once.

use crate::kernel::{Kernel, KernelError};
use snowscape_avalanche::{
    AvalancheError, AvalancheParams, AvalancheScratch, AvalancheState, AvalancheWorkspace,
    FrictionLaw, FrictionMaps, ReleasedCells, RunOptions, SamosAtParams, SlopeGravity, cfl_dt,
    release_from_shapefile, step,
};
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, NodataMask, SnowLayer};

/// The avalanche flow kernels on a `size`² grid: one sub-step under each friction law (the
/// Voellmy law's cost next to the paper's Coulomb law), and whole runs to rest.
pub fn avalanche_kernels(size: usize) -> Result<Vec<Kernel>, KernelError> {
    // The sub-step kernels keep the paper's model (Coulomb, shallow gravity) but for what
    // each one names, so that their figures compare across versions.
    let paper = AvalancheParams::paper;
    let mut kernels = vec![
        substep_kernel("avalanche/substep", paper(), size)?,
        substep_kernel(
            "avalanche/substep_projected",
            AvalancheParams {
                slope_gravity: SlopeGravity::Projected,
                ..paper()
            },
            size,
        )?,
        substep_kernel(
            "avalanche/substep_projected_no_curvature",
            AvalancheParams {
                slope_gravity: SlopeGravity::Projected,
                curvature: false,
                ..paper()
            },
            size,
        )?,
        substep_kernel(
            "avalanche/substep_default",
            AvalancheParams::default(),
            size,
        )?,
        substep_kernel(
            "avalanche/substep_voellmy",
            AvalancheParams {
                friction: FrictionLaw::Voellmy,
                ..paper()
            },
            size,
        )?,
        substep_kernel_with_maps(
            "avalanche/substep_voellmy_maps",
            AvalancheParams {
                friction: FrictionLaw::Voellmy,
                ..paper()
            },
            size,
            true,
        )?,
        substep_kernel(
            "avalanche/substep_samosat",
            AvalancheParams {
                friction: FrictionLaw::SamosAt,
                samos_at: SamosAtParams::standard(),
                ..paper()
            },
            size,
        )?,
    ];
    kernels.push(run_to_rest_kernel(
        "avalanche/slope_run_to_rest",
        slope_onto_flat(size)?,
    )?);
    kernels.push(run_to_rest_kernel(
        "avalanche/avakot_run_to_rest",
        avakot()?,
    )?);
    Ok(kernels)
}

/// One CFL sub-step per call of a 1 m square release flowing down a 35° plane of 2 m cells.
fn substep_kernel(name: &str, params: AvalancheParams, size: usize) -> Result<Kernel, KernelError> {
    substep_kernel_with_maps(name, params, size, false)
}

/// [`substep_kernel`], with per-cell μ and ξ maps (`maps`: a μ varying ±20 % and a ξ ±50 %
/// around the law's, in stripes across the flow) to measure what reading them costs.
fn substep_kernel_with_maps(
    name: &str,
    params: AvalancheParams,
    size: usize,
    maps: bool,
) -> Result<Kernel, KernelError> {
    let geometry = GridGeometry::square(size, size, 2.0)?;
    let tan = 35f64.to_radians().tan();
    let bed: Vec<f64> = (0..size * size)
        .map(|i| -((i / size) as f64) * 2.0 * tan)
        .collect();
    let mut state = AvalancheState::new(&geometry, &NodataMask::all_valid(), &bed)?;
    // The release starts in the northern part so that it stays on the grid for many calls.
    let side = (size / 5).max(4);
    let (r0, c0) = (size / 10, (size - side) / 2);
    let h: Vec<f64> = (0..size * size)
        .map(|i| {
            let (r, c) = (i / size, i % size);
            if (r0..r0 + side).contains(&r) && (c0..c0 + side).contains(&c) {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    state.set_thickness(&h)?;
    if maps {
        let stripe = |i: usize| ((i % size) / 8 % 5) as f64 / 4.0 - 0.5;
        let mu = (0..size * size)
            .map(|i| params.dry_friction() * (1.0 + 0.4 * stripe(i)))
            .collect();
        let xi = (0..size * size)
            .map(|i| params.voellmy_xi_m_s2 * (1.0 + stripe(i)))
            .collect();
        state.set_friction_maps(&FrictionMaps::new(&geometry, Some(mu), Some(xi))?)?;
    }
    let mut scratch = AvalancheScratch::default();
    let warm = step(&params, &mut state, &mut scratch, 2.0)?;
    let cells = warm.active_cells;
    Ok(Kernel::new(name, cells, 560.0, move || {
        let dt = cfl_dt(&params, &state);
        step(&params, &mut state, &mut scratch, dt)?;
        Ok(())
    }))
}

/// A terrain with unstable snow where it releases, and the released cells.
struct Release {
    terrain: LayeredTerrain,
    cells: Vec<usize>,
}

/// A kernel that runs the release to rest from the same terrain at every call.
fn run_to_rest_kernel(name: &str, release: Release) -> Result<Kernel, KernelError> {
    // The paper's law, the seasons' (`season::avalanches`).
    let (params, options) = (AvalancheParams::paper(), RunOptions::default());
    let run = move |ws: &mut AvalancheWorkspace, t: &mut LayeredTerrain, cells: &[usize]| {
        ws.run_to_rest::<AvalancheError>(
            t,
            ReleasedCells::new(cells, None),
            &params,
            &options,
            SnowLayer::Stable,
            |_| Ok(()),
        )
    };
    let mut workspace = AvalancheWorkspace::new();
    let mut probe = release.terrain.clone();
    let out = run(&mut workspace, &mut probe, &release.cells)?;
    let footprint =
        (out.summary.footprint_area_m2 / release.terrain.geometry().cell_area()).round();
    let mut terrain = release.terrain.clone();
    Ok(Kernel::new(name, footprint as usize, 0.0, move || {
        for (k, layer) in terrain.snow.iter_mut().enumerate() {
            layer.copy_from_slice(&release.terrain.snow[k]);
        }
        run(&mut workspace, &mut terrain, &release.cells)?;
        Ok(())
    }))
}

/// `size` × `0.3 size` cells of 5 m: a 35° slope over the first 40 % of the rows onto flat
/// ground, with 1 m of unstable snow over 12 rows (60 m) below its top.
fn slope_onto_flat(size: usize) -> Result<Release, KernelError> {
    let (w, h) = ((size * 3 / 10).max(8), size.max(16));
    let g = GridGeometry::square(w, h, 5.0)?;
    let tan = 35f32.to_radians().tan();
    let foot = (h * 4 / 10) as f32;
    let bed = Grid::from_fn(g, |_, r| 1000.0 + tan * 5.0 * (foot - r as f32).max(0.0));
    let mut terrain = LayeredTerrain::from_bedrock(bed);
    let rows = 2..(2 + 12).min(h);
    let cells: Vec<usize> = (rows.start * w..rows.end * w).collect();
    for &i in &cells {
        terrain.layer_mut(SnowLayer::Unstable)[i] = 1.0;
    }
    Ok(Release { terrain, cells })
}

/// avaKot from the shared data, its release polygons as unstable snow of their thickness.
fn avakot() -> Result<Release, KernelError> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/dem/avaframe_avaKot");
    let (dem_path, rel_path) = (dir.join("avaKot.asc"), dir.join("REL/relKot.shp"));
    for p in [&dem_path, &rel_path] {
        if !p.exists() {
            return Err(KernelError::MissingData(p.display().to_string()));
        }
    }
    let dem = snowscape_io::read_dem(&dem_path, &snowscape_io::ReadOptions::default())?;
    let area = release_from_shapefile(&rel_path, dem.geometry(), dem.mask())?;
    let thickness = area.thickness_field(1.0)?;
    let mut terrain = LayeredTerrain::from_bedrock(dem);
    let cells: Vec<usize> = (0..area.cells.len()).filter(|&i| area.cells[i]).collect();
    for &i in &cells {
        terrain.layer_mut(SnowLayer::Unstable)[i] = thickness[i] as f32;
    }
    Ok(Release { terrain, cells })
}
