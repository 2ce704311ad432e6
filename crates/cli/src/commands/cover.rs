//! `snowscape cover --mesh FILE --method diffusion|fearing`: snow on a triangle-mesh scene,
//! alone or standing on a DEM (at `--at X,Y`, default the DEM's centre; the terrain around it
//! is covered too). The job is the library's ([`snowscape::cover`]: the mesh input, the
//! placement, the diffusion cover of von Festenberg & Gumhold 2011 or Fearing's of 2000, the
//! files and `report.json`); this is its flags, its summary line and its exit codes.

use crate::cli::GlobalArgs;
use crate::dem_input::DemInputArgs;
use crate::failure::{BAD_INPUT, ExitCodeExt, Failure, JOB_FAILED};
use crate::pairs::parse_xy;
use crate::progress::INTERRUPTED;
use crate::stdout::outln;
use anyhow::anyhow;
use clap::{Args, ValueEnum};
use snowscape::control::Unattended;
use snowscape::cover::{
    self, CoverDem, CoverJob, CoverJobError, CoverOverrides, CoverParameters, CoverReport,
};
use snowscape::dem_source::DemSource;
use std::path::PathBuf;
use std::time::Instant;

/// The snow-on-mesh methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CoverMethod {
    /// von Festenberg & Gumhold 2011: diffusion kernel on a height-span map, bridges,
    /// overhangs, boundary texture coordinates.
    Diffusion,
    /// Fearing 2000: flake shooting and angle-of-repose stability.
    Fearing,
}

#[derive(Debug, Args)]
pub struct CoverArgs {
    /// Triangle mesh (.obj, .ply, .gltf/.glb): the scene to cover with snow.
    #[arg(long)]
    pub mesh: PathBuf,
    /// Snow method.
    #[arg(long, value_enum, default_value_t = CoverMethod::Diffusion)]
    pub method: CoverMethod,
    /// Up axis of the mesh file: y (glTF, most OBJ) or z.
    #[arg(long, default_value = "y")]
    pub up: String,
    /// Metres per mesh unit (0.01 for a file in centimetres).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub scale: f64,
    /// Terrain raster the mesh stands on (.asc, .tif, .png, .raw/.r16, .npy).
    #[arg(long)]
    pub dem: Option<PathBuf>,
    /// Where the mesh stands on the --dem: X,Y map coordinates (default: the DEM's centre).
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub at: Option<String>,
    /// Output folder (created if missing).
    #[arg(long, default_value = "out/cover")]
    pub out: PathBuf,
    /// Parameters of both methods from a TOML file (`[diffusion]`: every field of the
    /// diffusion cover; `[fearing]`, `[fearing.material]`, `[fearing.stability]`: of the
    /// Fearing cover); the flags below override it.
    #[arg(long, value_name = "FILE.toml")]
    pub parameters: Option<PathBuf>,
    /// Snow depth on open flat ground, metres (diffusion: the initial height h0; default 2 %
    /// of the scene's horizontal diameter).
    #[arg(long, allow_negative_numbers = true)]
    pub depth: Option<f64>,
    /// Kernel radius R, metres (diffusion; default 5 % of the scene diameter, the paper's).
    #[arg(long, allow_negative_numbers = true)]
    pub radius: Option<f64>,
    /// Longest gap bridged, metres (diffusion: bmax; default 3 % of the scene diameter, the
    /// paper's; 0 disables bridges).
    #[arg(long, allow_negative_numbers = true)]
    pub bridge: Option<f64>,
    /// Let the snow's rim lean out over edges (diffusion: the g2 offset, Eq. 8).
    #[arg(long)]
    pub overhang: bool,
    /// Column spacing of the height-span map, metres (default: the longer side / 256).
    #[arg(long, allow_negative_numbers = true)]
    pub resolution: Option<f64>,
    /// Also write a growth animation of N frames (diffusion: Eq. 2 with a four-neighbour
    /// Laplacian, no bridges or overhangs) as growth/frame_NNNN.glb.
    #[arg(long, value_name = "N", value_parser = crate::bounds::frames)]
    pub growth: Option<usize>,
    /// Also write turntable.gif: N preview frames seen from all around the scene (2..=720).
    #[arg(long, value_name = "N")]
    pub turntable: Option<usize>,
    /// Wall-clock safety net, seconds (fearing; default 600): the work (flakes per site,
    /// stability passes) ends every stage, so a cover is the same bytes on any machine; a cover
    /// still running at this time fails (exit 2) instead of returning a shorter one.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::bounds::wall_seconds)]
    pub budget: Option<f64>,
    /// Mean flake flutter radius fr, metres (fearing; default: the material's, 0.05 for snow,
    /// 0 for water).
    #[arg(long, allow_negative_numbers = true)]
    pub flutter: Option<f64>,
    /// Angle of repose, degrees (fearing; default: the material's, 50 for snow).
    #[arg(long, allow_negative_numbers = true)]
    pub aor: Option<f64>,
    /// Constant wind X,Y (east, north), m/s (fearing).
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub wind: Option<String>,
    /// Material preset (fearing): snow, flour, sand or water (default: the --parameters
    /// file's material, or snow).
    #[arg(long)]
    pub material: Option<String>,
    /// Random seed (fearing; default 1).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Launch sites aimed at (fearing; every upward triangle gets at least one).
    #[arg(long)]
    pub sites: Option<usize>,
    /// Accumulation passes, each followed by stability (fearing).
    #[arg(long)]
    pub passes: Option<u32>,
    /// Share of a site's snow the wind carries downwind per stability phase and per m/s of
    /// --wind (fearing, Section 6; default 0: the wind only bends the flakes).
    #[arg(long, allow_negative_numbers = true)]
    pub wind_transport: Option<f64>,
    #[command(flatten)]
    pub dem_input: DemInputArgs,
}

/// The job the flags describe: the parameter file with the flags over it, the DEM and where
/// the mesh stands on it (the values' ranges are the job's to check).
fn job(args: &CoverArgs) -> anyhow::Result<CoverJob> {
    let method = match args.method {
        CoverMethod::Diffusion => cover::CoverMethod::Diffusion,
        CoverMethod::Fearing => cover::CoverMethod::Fearing,
    };
    let file = match &args.parameters {
        Some(p) => CoverParameters::read(p)?,
        None => CoverParameters::default(),
    };
    // The wind is Fearing's: another method never reads the flag.
    let wind_m_s = match (&args.wind, method) {
        (Some(w), cover::CoverMethod::Fearing) => {
            let (x, y) = parse_xy("--wind", w)?;
            Some([x, y])
        }
        _ => None,
    };
    let overrides = CoverOverrides {
        depth_m: args.depth,
        radius_m: args.radius,
        bridge_m: args.bridge,
        overhang: args.overhang,
        resolution_m: args.resolution,
        material: args.material.clone(),
        aor_deg: args.aor,
        budget_s: args.budget,
        flutter_m: args.flutter,
        wind_m_s,
        seed: args.seed,
        sites: args.sites,
        passes: args.passes,
        wind_transport: args.wind_transport,
    };
    let dem = match &args.dem {
        Some(path) => Some(CoverDem {
            dem: DemSource::File {
                path: path.clone(),
                options: args.dem_input.read_options()?,
            },
            at: match &args.at {
                Some(text) => {
                    let (x, y) = parse_xy("--at", text)?;
                    Some([x, y])
                }
                None => None,
            },
        }),
        None => None,
    };
    Ok(CoverJob {
        mesh: args.mesh.clone(),
        up: args.up.clone(),
        scale: args.scale,
        method,
        parameters: overrides.apply(method, file)?,
        parameters_file: args.parameters.clone(),
        dem,
        growth: args.growth,
        turntable: args.turntable,
        output: Some(args.out.clone()),
    })
}

/// A job's error in the flags' words, with its exit code.
fn failure(e: CoverJobError, args: &CoverArgs) -> Failure {
    let code = if e.is_bad_input() {
        BAD_INPUT
    } else if matches!(e, CoverJobError::Cancelled { .. }) {
        INTERRUPTED
    } else {
        JOB_FAILED
    };
    let error = match e {
        CoverJobError::TurntableFrames(n) => anyhow!("--turntable {n}: 2..=720 frames"),
        CoverJobError::GrowthFrames(n) => {
            anyhow!("--growth must be 1..=10000 frames, got {n}")
        }
        CoverJobError::Scale(s) => {
            anyhow!("--scale must be a positive number of metres per mesh unit, got {s}")
        }
        CoverJobError::Up { up, source } => anyhow!(source).context(format!("--up {up:?}")),
        CoverJobError::AtOutsideDem { dem, .. } => anyhow!(
            "--at {:?} lies outside the DEM {dem}",
            args.at.as_deref().unwrap_or_default()
        ),
        CoverJobError::NoDiffusionSnow { mesh, resolution_m } => anyhow!(
            "no snow settled on {} (every site is an edge at --resolution {resolution_m} m: try a finer one)",
            mesh.display()
        ),
        e => anyhow!(e),
    };
    Failure { code, error }
}

/// Runs `snowscape cover`.
pub fn run(args: &CoverArgs, global: &GlobalArgs) -> Result<(), Failure> {
    let t0 = Instant::now();
    let job = job(args).bad_input()?;
    // The stages are long (a cover, a turntable): Ctrl-C ends the process, as it always has;
    // the next job into the folder removes what was staged.
    let outcome = cover::run(&job, &mut Unattended).map_err(|e| failure(e, args))?;
    if global.quiet {
        return Ok(());
    }
    match &outcome.report {
        CoverReport::Diffusion(r) => outln!(
            "cover (diffusion): {} sites + {} bridge sites, snow {} vertices / {} triangles, \
             max {:.3} m, kernel {:.0} sites/s, {:.2} s -> {}",
            r.sites.ground_sites,
            r.sites.bridge_sites,
            r.snow.vertices,
            r.snow.triangles,
            r.snow.max_height_m,
            r.kernel.sites_per_s,
            t0.elapsed().as_secs_f64(),
            args.out.display()
        ),
        CoverReport::Fearing(f) => {
            let r = &f.cover;
            outln!(
                "cover (fearing): {} sites in {} edge groups, {} flakes ({:.0} flakes/s), snow {} \
                 triangles, max {:.3} m, {:.3} m³ caught, {:.3} m³ left the scene, {:.2} s -> {}",
                r.sites_final,
                r.edge_groups,
                r.flakes_shot,
                r.flakes_per_s,
                r.surface_triangles,
                r.max_depth_m,
                r.mass.allocated_m3,
                r.mass.left_scene_m3,
                t0.elapsed().as_secs_f64(),
                args.out.display()
            );
        }
    }
    Ok(())
}
