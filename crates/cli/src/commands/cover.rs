//! `snowscape cover --mesh FILE --method diffusion|fearing`: snow on a triangle-mesh scene,
//! alone or standing on a DEM.
//!
//! The front part is shared by both methods: read the mesh (`--up`, `--scale`), optionally
//! place it on a `--dem` (at `--at X,Y`, default the DEM's centre; the terrain around it is
//! covered too), prepare `--out`. Then one function per method: [`cover_diffusion`] (von
//! Festenberg & Gumhold 2011, `snowscape-festenberg`) and [`cover_fearing`] (Fearing 2000).

use crate::cli::GlobalArgs;
use crate::dem_input::DemInputArgs;
use crate::failure::{BAD_INPUT, ExitCodeExt, Failure};
use crate::outputs::{write_png, write_report};
use crate::report::InputSummary;
use crate::stdout::outln;
use anyhow::{Context, anyhow, bail};
use clap::{Args, ValueEnum};
use snowscape::cover::{
    CoverParameters, DemPlacement, DiffusionCoverReport, FearingInputSummary, GrowthSummary,
    MeshInputSummary, Turntable,
};
use snowscape::output_folder::OutputFolder;
use snowscape_festenberg::{CoverParams, FestenbergError, GrowthParams, cover, grow_cover};
use snowscape_mesh::preview::{PreviewOptions, render_turntable, write_preview};
use snowscape_mesh::terrain::{grid_object, map_to_scene, place_scene_on_grid};
use snowscape_mesh::write::{write_glb, write_obj};
use snowscape_mesh::{Scene, SceneObject, SourceFrame, UpAxis, read_scene};
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

/// What the front part read: the scene (mesh, and terrain when on a DEM) and its summary.
pub struct CoverInput {
    pub scene: Scene,
    /// What was read: the mesh, the DEM it stands on, the parameter file.
    pub summary: MeshInputSummary,
    /// The region to cover, scene metres (`None`: the scene's bounds).
    pub extent_m: Option<[f64; 4]>,
    pub read_s: f64,
}

/// Runs `snowscape cover`.
pub fn run(args: &CoverArgs, global: &GlobalArgs) -> Result<(), Failure> {
    let t0 = Instant::now();
    if let Some(n) = args.turntable
        && !(2..=720).contains(&n)
    {
        return Err(anyhow!("--turntable {n}: 2..=720 frames")).bad_input();
    }
    let file = match &args.parameters {
        Some(p) => CoverParameters::read(p).bad_input()?,
        None => CoverParameters::default(),
    };
    let input = read_input(args).bad_input()?;
    let folder = OutputFolder::open(&args.out).bad_input()?;
    folder.check_subfolder("growth").bad_input()?;
    match args.method {
        CoverMethod::Diffusion => {
            cover_diffusion(args, global, &input, file.diffusion, (folder, t0))
        }
        CoverMethod::Fearing => {
            let depth_set = file.fearing_depth_set;
            cover_fearing(args, global, &input, file.fearing, depth_set, (folder, t0))
        }
    }
}

/// The common front part: the mesh in scene metres (z up), standing on the DEM if given.
fn read_input(args: &CoverArgs) -> anyhow::Result<CoverInput> {
    let t0 = Instant::now();
    if !(args.scale.is_finite() && args.scale > 0.0) {
        bail!(
            "--scale must be a positive number of metres per mesh unit, got {}",
            args.scale
        );
    }
    let up: UpAxis = args
        .up
        .parse()
        .with_context(|| format!("--up {:?}", args.up))?;
    let frame = SourceFrame::new(up, args.scale)?;
    let (mut scene, mesh_report) = read_scene(&args.mesh, &frame)?;
    let (mut extent_m, mut dem) = (None, None);
    if let Some(path) = &args.dem {
        let grid = args.dem_input.read(path)?;
        let g = grid.geometry();
        let (x, y) = match &args.at {
            None => (0.5 * g.extent_m().0, 0.5 * g.extent_m().1),
            Some(text) => {
                let (mx, my) = crate::pairs::parse_xy("--at", text)?;
                map_to_scene(g, mx, my).ok_or_else(|| {
                    anyhow!("--at {text:?} lies outside the DEM {}", path.display())
                })?
            }
        };
        // Place the scene as one piece: every object moves by the same offset.
        let (ground, _) = place_scene_on_grid(&mut scene, &grid, x, y)
            .with_context(|| format!("placing {} on {}", args.mesh.display(), path.display()))?;
        let after = scene
            .bounds()
            .ok_or_else(|| anyhow!("the mesh has no triangles"))?;
        // Cover the object and the ground around it: a quarter of its size on each side.
        let margin = 0.25 * after.size()[0].max(after.size()[1]) as f64;
        let e = [
            after.min[0] as f64 - margin,
            after.min[1] as f64 - margin,
            after.max[0] as f64 + margin,
            after.max[1] as f64 + margin,
        ];
        let terrain = crop(grid_object(&grid, "terrain")?, e, margin);
        if terrain.triangles.is_empty() {
            bail!(
                "the DEM {} has no valid cells around the mesh",
                path.display()
            );
        }
        scene.objects.push(terrain);
        extent_m = Some(e);
        dem = Some(DemPlacement {
            terrain: InputSummary::of(&path.display().to_string(), &grid),
            at_scene_m: [x, y],
            ground_m: ground,
        });
    }
    let mut summary = MeshInputSummary::new(&args.mesh, &args.up, args.scale, &mesh_report, &scene);
    summary.dem = dem;
    summary.parameters_file = args.parameters.as_ref().map(|p| p.display().to_string());
    Ok(CoverInput {
        scene,
        summary,
        extent_m,
        read_s: t0.elapsed().as_secs_f64(),
    })
}

/// The triangles of `o` within `margin` of the extent `e`.
fn crop(mut o: SceneObject, e: [f64; 4], margin: f64) -> SceneObject {
    let inside = |p: &[f32; 3]| {
        (p[0] as f64) >= e[0] - margin
            && (p[0] as f64) <= e[2] + margin
            && (p[1] as f64) >= e[1] - margin
            && (p[1] as f64) <= e[3] + margin
    };
    let pos = &o.positions;
    o.triangles
        .retain(|t| t.iter().any(|&i| inside(&pos[i as usize])));
    o
}

/// `turntable.gif` in `dir`: `frames` previews around the scene and its snow, 80 ms apart.
fn write_turntable(
    dir: &std::path::Path,
    scene: &Scene,
    snow: &[snowscape_mesh::SnowObject],
    frames: usize,
) -> anyhow::Result<()> {
    let opts = PreviewOptions {
        width: 480,
        height: 360,
        ..PreviewOptions::default()
    };
    let images: Vec<image::RgbaImage> = render_turntable(scene, snow, &opts, frames)?
        .into_iter()
        .map(|i| image::DynamicImage::ImageRgb8(i).into_rgba8())
        .collect();
    let gif = snowscape_render::encode_gif(&images, 80)?;
    snowscape_io::write_bytes_atomic(&dir.join("turntable.gif"), &gif)?;
    Ok(())
}

/// The exit code of a snow-cover error: the user's input (2) unless it is an output problem.
fn festenberg_failure(e: FestenbergError) -> Failure {
    let code = match &e {
        FestenbergError::Mesh(snowscape_mesh::MeshError::Write(_)) => crate::failure::JOB_FAILED,
        _ => BAD_INPUT,
    };
    Failure {
        code,
        error: e.into(),
    }
}

/// Diffusion-based snow cover (von Festenberg & Gumhold 2011): `snow.glb`, `snow.obj` (+ MTL
/// and mask PNG), `mask.png`, `preview.png`, `growth/` with `--growth`, and `report.json`.
fn cover_diffusion(
    args: &CoverArgs,
    global: &GlobalArgs,
    input: &CoverInput,
    file: CoverParams,
    (folder, t0): (OutputFolder, Instant),
) -> Result<(), Failure> {
    // The file's values, each flag given overriding its own; a DEM fixes the extent.
    let params = CoverParams {
        depth_m: args.depth.or(file.depth_m),
        radius_m: args.radius.or(file.radius_m),
        bridge_m: args.bridge.or(file.bridge_m),
        overhang: args.overhang || file.overhang,
        resolution_m: args.resolution.or(file.resolution_m),
        extent_m: input.extent_m.or(file.extent_m),
        ..file
    };
    if args.growth.is_some_and(|n| n == 0 || n > 10_000) {
        return Err(anyhow!(
            "--growth must be 1..=10000 frames, got {}",
            args.growth.unwrap_or(0)
        ))
        .bad_input();
    }
    let scene = &input.scene;
    let c = cover(scene, &params).map_err(festenberg_failure)?;
    if c.mesh.triangles.is_empty() {
        return Err(anyhow!(
            "no snow settled on {} (every site is an edge at --resolution {} m: try a finer one)",
            args.mesh.display(),
            c.resolved.resolution_m
        ))
        .job_failed();
    }
    let dir = &folder.staging().to_path_buf();
    let mut files = Vec::new();
    let mut timings = vec![("read".to_string(), input.read_s)];
    timings.extend(c.stats.timings.iter().cloned());
    let mut stage = |name: &str, f: &mut dyn FnMut() -> anyhow::Result<()>| {
        let t = Instant::now();
        let r = f();
        timings.push((name.to_string(), t.elapsed().as_secs_f64()));
        r
    };
    let meshes = std::slice::from_ref(&c.mesh);
    stage("write_glb", &mut || {
        Ok(write_glb(&dir.join("snow.glb"), meshes, &scene.frame)?)
    })
    .job_failed()?;
    stage("write_obj", &mut || {
        Ok(write_obj(&dir.join("snow.obj"), meshes, &scene.frame)?)
    })
    .job_failed()?;
    files.extend(["snow.glb", "snow.obj", "snow.mtl", "snow_0.png"].map(String::from));
    if let Some(mask) = &c.mesh.texture {
        write_png(&dir.join("mask.png"), mask).job_failed()?;
        files.push("mask.png".into());
    }
    stage("preview", &mut || {
        Ok(write_preview(
            &dir.join("preview.png"),
            scene,
            meshes,
            &PreviewOptions::default(),
        )?)
    })
    .job_failed()?;
    files.push("preview.png".into());
    if let Some(n) = args.turntable {
        stage("turntable", &mut || write_turntable(dir, scene, meshes, n)).job_failed()?;
        files.push("turntable.gif".into());
    }
    let mut growth_report = None;
    if let Some(frames) = args.growth {
        let t = Instant::now();
        let growth = GrowthParams::for_cover(&c.resolved, frames);
        let gdir = dir.join("growth");
        std::fs::create_dir_all(&gdir)
            .with_context(|| format!("cannot create {}", gdir.display()))
            .job_failed()?;
        let (_, g) = grow_cover(
            scene,
            &params,
            &growth,
            |i, _, mesh| -> anyhow::Result<()> {
                let name = format!("frame_{i:04}.glb");
                if mesh.triangles.is_empty() {
                    return Ok(()); // no snow yet anywhere
                }
                write_glb(&gdir.join(&name), &[mesh], &scene.frame)?;
                files.push(format!("growth/{name}"));
                Ok(())
            },
        )
        .job_failed()?;
        timings.push(("growth".into(), t.elapsed().as_secs_f64()));
        growth_report = Some(GrowthSummary {
            parameters: growth,
            run: g,
        });
    }
    files.push(snowscape::output_folder::REPORT.into());
    let report = DiffusionCoverReport::new(
        input.summary.clone(),
        &c,
        growth_report,
        &timings,
        t0.elapsed().as_secs_f64(),
        files,
    );
    let report = serde_json::to_value(&report)
        .context(snowscape::output_folder::REPORT)
        .job_failed()?;
    write_report(folder, report).job_failed()?;
    if !global.quiet {
        let s = &c.stats;
        outln!(
            "cover (diffusion): {} sites + {} bridge sites, snow {} vertices / {} triangles, \
             max {:.3} m, kernel {:.0} sites/s, {:.2} s -> {}",
            s.ground_sites,
            s.bridge_sites,
            s.vertices,
            s.triangles,
            s.max_height_m,
            s.kernel_sites_per_s(),
            t0.elapsed().as_secs_f64(),
            dir.display()
        );
    }
    Ok(())
}

/// Fearing 2000 snow on meshes (`snowscape-fearing`): `snow.glb`, `snow.obj` (+ MTL),
/// `preview.png` and `report.json`.
fn cover_fearing(
    args: &CoverArgs,
    global: &GlobalArgs,
    input: &CoverInput,
    file: snowscape_fearing::FearingParams,
    depth_set: bool,
    (folder, t0): (OutputFolder, Instant),
) -> Result<(), Failure> {
    use snowscape_fearing::Material;
    let scene = &input.scene;
    // The file's values, each flag given overriding its own.
    let mut params = file;
    if let Some(m) = &args.material {
        params.material = Material::preset(m).bad_input()?;
    }
    if let Some(a) = args.aor {
        params.material.aor_deg = a;
    }
    params.depth_m = match args.depth {
        Some(d) => d,
        None if depth_set => params.depth_m,
        None => snowscape::cover::default_depth_m(scene)
            .ok_or_else(|| anyhow!("the mesh has no triangles"))
            .bad_input()?,
    };
    if let Some(b) = args.budget {
        params.budget_s = b;
    }
    params.flutter_m = args.flutter;
    if let Some(w) = &args.wind {
        let (x, y) = crate::pairs::parse_xy("--wind", w).bad_input()?;
        params.wind_m_s = [x, y];
    }
    if let Some(seed) = args.seed {
        params.seed = seed;
    }
    if let Some(n) = args.sites {
        params.target_sites = n;
    }
    if let Some(p) = args.passes {
        params.passes = p;
    }
    if let Some(w) = args.wind_transport {
        params.wind_transport = w;
    }
    let c = snowscape_fearing::cover(scene, &params).bad_input()?;
    if let Some(n) = args.turntable {
        let meshes = c.meshes();
        write_turntable(folder.staging(), scene, &meshes, n).job_failed()?;
    }
    let summary = FearingInputSummary {
        mesh: input.summary.clone(),
        read_s: input.read_s,
        wall_s: t0.elapsed().as_secs_f64(),
        turntable: args.turntable.map(|frames| Turntable {
            file: "turntable.gif",
            frames,
        }),
    };
    let summary = serde_json::to_value(&summary)
        .context(snowscape::output_folder::REPORT)
        .job_failed()?;
    // Nothing to write (no snow settled) or a file that cannot be written: the job failed.
    let written =
        snowscape::cover::write_fearing_outputs(folder.staging(), scene, &c, Some(summary))
            .job_failed()?;
    let mut files: Vec<String> = written
        .iter()
        .filter_map(|p| p.strip_prefix(folder.staging()).ok())
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    if args.turntable.is_some() {
        files.push("turntable.gif".into());
    }
    folder.commit(&files, None).job_failed()?;
    if !global.quiet {
        let r = &c.report;
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
    Ok(())
}
