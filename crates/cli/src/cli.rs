//! Command-line definitions (clap derive).

use crate::dem_input::DemInputArgs;
use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

const EXAMPLES: &str = "\
Examples:
  snowscape demo                                  # procedural terrain, every output in out/demo
  snowscape demo --size 1024 --seed 7 --out out/s7
  snowscape run --dem ../shared/data/dem/avaframe_avaMal/avaMal.asc --out out/mal
  snowscape run --dem dem.tif --scenario winter.toml --days 60 --seed 3
  snowscape run --dem dem.tif --resume out/run     # continue an interrupted run
  snowscape run --dem dem.tif --days 30 --skiers 500  # ski tracks (PNG + GeoJSON) and compaction
  snowscape info ../shared/data/dem/avaframe_avaMal/avaMal.asc
  snowscape render dem.tif --out relief.png --sun-azimuth 300
  snowscape convert dem.asc dem.tif               # any readable format to GeoTIFF/EXR/PNG16/ASC/NPY
  snowscape convert height.png dem.tif --cell-size 2 --height-range 1000,2500
  snowscape avalanche --dem ../shared/data/dem/avaframe_avaWog/avaWog.asc \
      --release ../shared/data/dem/avaframe_avaWog/REL/relWog.shp --out out/wog
  snowscape avalanche --dem dem.tif --release 631250,5220400 --thickness 0.8
  snowscape cover --mesh ../shared/data/meshes/spider.obj --method diffusion --out out/spider
  snowscape cover --mesh teapot.obj --up z --scale 0.01 --dem dem.tif --bridge 0.05 --overhang
  snowscape transport --scenario castle --out out/castle   # Jubert 2018 Table 7.I
  snowscape transport --dem dem.tif --scenario storm.toml --out out/storm
  snowscape serve --size 512 --project proj      # the browser editor on http://127.0.0.1:8080
  snowscape bench --size 1024                     # kernel throughput and memory-bandwidth share
  snowscape validate --run out/mal --observed lidar_depth.tif --mask forest_free.tif

Exit codes: 0 success, 1 the job failed, 2 bad input (usage, file or parameter).";

/// snowscape: snow-covered landscapes from real terrain.
#[derive(Debug, Parser)]
#[command(name = "snowscape", version, about, long_about = None, after_help = EXAMPLES)]
pub struct Cli {
    #[command(flatten)]
    pub global: GlobalArgs,
    #[command(subcommand)]
    pub command: Command,
}

/// Options every command accepts.
#[derive(Debug, Args)]
pub struct GlobalArgs {
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, global = true, value_parser = crate::bounds::threads)]
    pub threads: Option<usize>,
    /// No progress bars and no messages except errors.
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// More log output (-v info, -vv debug); SNOWSCAPE_LOG overrides.
    #[arg(long, short, global = true, action = clap::ArgAction::Count)]
    pub verbose: u8,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a winter on the procedural alpine terrain and write every output.
    Demo(DemoArgs),
    /// Run a winter on a terrain file (a scenario file sets the weather timeline).
    Run(RunArgs),
    /// Describe a terrain file: grid size, cell size, CRS, value range, nodata share.
    Info(InfoArgs),
    /// List the scenario parameters (`[parameters]` keys of a scenario file): help, default,
    /// accepted range and choices, as the CLI, scenario files and the editor check them.
    Parameters(ParametersArgs),
    /// Render a shaded-relief preview of a terrain file to PNG.
    Render(RenderArgs),
    /// Convert a raster between formats (format from the output extension or --to).
    Convert(ConvertArgs),
    /// Measure memory bandwidth and kernel throughput; write bench.json.
    Bench(BenchArgs),
    /// Run one avalanche from a release area or point to rest; write peak maps and a report.
    Avalanche(AvalancheArgs),
    /// Start the interactive browser editor (a local web server; prints its URL).
    Serve(ServeArgs),
    /// Cover a triangle-mesh scene (alone or standing on a DEM) with snow: snow mesh (glb,
    /// OBJ) with boundary texture, preview and report.
    Cover(crate::commands::cover::CoverArgs),
    /// Physical snow transport (Jubert 2018): 3D wind, precipitation map, saltation,
    /// suspension, sublimation and melt over a DEM or a mesh scene.
    Transport(TransportArgs),
    /// Compare a run's snow depth with a measured depth raster (matched by map coordinates):
    /// correlations, errors, snow-cover agreement, terrain-only baselines, class ratios.
    Validate(ValidateArgs),
    /// Export a run's terrain and snow for a game engine: 16-bit heightmaps at the engine's
    /// terrain sizes, layer weight maps summing to 255, the scales to enter on import.
    Export(ExportArgs),
}

/// The engines `snowscape export` writes for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum EngineArg {
    /// Unreal Landscape: 16-bit PNG heightmaps at 127..8129 per axis, weight PNGs, tiles.
    Unreal,
    /// Unity Terrain: 16-bit RAW at 2^n+1, RGBA splat maps.
    Unity,
    /// Godot with the HTerrain add-on: 16-bit RAW and EXR at 2^n+1, an RGBA splat map.
    Godot,
}

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// Run folder written by `snowscape run` or `snowscape demo` (its bedrock.tif and
    /// layers_*.tif are read).
    #[arg(long)]
    pub run: PathBuf,
    /// Target engine.
    #[arg(long, value_enum)]
    pub engine: EngineArg,
    /// Output folder (created if missing).
    #[arg(long, default_value = "out/export")]
    pub out: PathBuf,
    /// Tiles of N x N samples named `_x{i}_y{j}` sharing their edges (Unreal World
    /// Partition), 2..=8129.
    #[arg(long, value_name = "N")]
    pub tile: Option<usize>,
    /// Also write the heightmap of the snow surface (bedrock + snow), on the same height scale.
    #[arg(long)]
    pub with_snow: bool,
}

#[derive(Debug, Args)]
pub struct ValidateArgs {
    /// Run folder written by `snowscape run` or `snowscape demo` (its depth.tif, bedrock.tif
    /// and report.json are read).
    #[arg(long)]
    pub run: PathBuf,
    /// Measured snow depth, metres: GeoTIFF or ESRI ASCII, any cell size and extent (matched
    /// to the run's cells by map coordinates; block-averaged when finer, bilinear otherwise).
    #[arg(long)]
    pub observed: PathBuf,
    /// Mask raster: compare only cells where it is nonzero (nearest cell, by map coordinates).
    #[arg(long)]
    pub mask: Option<PathBuf>,
    /// Output folder (default: RUN/validation).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Depth above which a cell counts as snow-covered, metres.
    #[arg(long, default_value_t = 0.05, allow_negative_numbers = true)]
    pub snow_threshold: f64,
    /// Direction the prevailing wind blows from, degrees clockwise from north, for the
    /// lee/windward ratio (default: the run's report.json, else 270).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub wind_from: Option<f64>,
}

#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Output folder (created if missing).
    #[arg(long, default_value = "out/demo")]
    pub out: PathBuf,
    /// Cells per side of the procedural terrain (128..=8192). The season's memory is checked
    /// first: 2048 needs about 3 GiB, 4096 about 11, 8192 about 43 (see --memory-budget).
    #[arg(long, default_value_t = 512)]
    pub size: usize,
    /// Random seed: the same seed gives the same bytes.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Cell size of the procedural terrain, metres (512 cells of 20 m: a 10 km range with
    /// the generator's full relief).
    #[arg(long, default_value_t = 20.0, value_parser = crate::bounds::metres)]
    pub cell_size: f64,
    /// Length of the winter, days (0, 3650].
    #[arg(long, default_value_t = 100.0, value_parser = crate::bounds::season_days)]
    pub days: f64,
    /// Frames in the time-lapse (snapshots spread evenly over the season), 0..=1000.
    #[arg(long, default_value_t = 10, value_parser = crate::bounds::frames)]
    pub frames: usize,
    /// Latitude of the procedural terrain, degrees north (it has no georeferencing).
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 45.0,
        allow_hyphen_values = true,
        value_parser = crate::bounds::latitude
    )]
    pub latitude: f64,
    /// Write the single-band GeoTIFFs Cloud-Optimized (256x256 tiles, overviews, Deflate with
    /// the floating-point predictor, GDAL's COG layout; wind.tif, two bands, stays plain).
    #[arg(long)]
    pub cog: bool,
    /// The memory the season may take, GiB. Default: what the machine has available (free
    /// memory, a container's limit, `ulimit -v`); a season whose estimate exceeds it is
    /// refused before any work (exit 2).
    #[arg(long, value_name = "GIB", value_parser = crate::bounds::memory_budget)]
    pub memory_budget: Option<u64>,
}

#[derive(Debug, Args)]
pub struct RunArgs {
    /// Terrain raster (.asc, .tif, .png, .raw/.r16, .npy).
    #[arg(long)]
    pub dem: PathBuf,
    /// Scenario file (TOML): dates, latitude, weather timeline, parameters. Default: a
    /// 100-day winter fitted to the terrain's altitudes.
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// Length of the season, days (overrides the scenario), (0, 3650].
    #[arg(long, value_parser = crate::bounds::season_days)]
    pub days: Option<f64>,
    /// Random seed (overrides the scenario).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Output folder (default out/run, or the --resume folder).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Resume an interrupted run from the checkpoint in this folder (same DEM and options).
    #[arg(long)]
    pub resume: Option<PathBuf>,
    /// Stop at this day, write a checkpoint and exit (continue later with --resume): splits
    /// a long season into parts.
    #[arg(long, value_name = "DAY", value_parser = crate::bounds::season_day)]
    pub stop_at: Option<f64>,
    /// Station forcing (CSV: time, air_temperature_c, precipitation_mm, wind_speed_m_s,
    /// wind_from_deg[, shortwave_in_w_m2, relative_humidity]; or a snobal input file): the
    /// season follows the record from its first hour, distributed over the DEM by the lapse
    /// rate and the orographic gradient.
    #[arg(long, value_name = "FILE.csv")]
    pub forcing: Option<PathBuf>,
    /// Altitude of the forcing station, m (overrides the file's `# station_altitude_m`).
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub station_altitude: Option<f64>,
    /// Latitude, degrees north (overrides the scenario and the DEM's georeferencing).
    #[arg(
        long,
        value_name = "DEG",
        allow_hyphen_values = true,
        value_parser = crate::bounds::latitude
    )]
    pub latitude: Option<f64>,
    /// Write the single-band GeoTIFFs Cloud-Optimized (256x256 tiles, overviews, Deflate with
    /// the floating-point predictor, GDAL's COG layout; wind.tif, two bands, stays plain).
    #[arg(long)]
    pub cog: bool,
    /// The memory the season may take, GiB. Default: what the machine has available (free
    /// memory, a container's limit, `ulimit -v`); a season whose estimate exceeds it is
    /// refused before any work (exit 2).
    #[arg(long, value_name = "GIB", value_parser = crate::bounds::memory_budget)]
    pub memory_budget: Option<u64>,
    /// Per-cell dry-friction μ of the season's avalanches, as `snowscape avalanche
    /// --mu-raster` (a raster matched by map coordinates, any cell size, in [0, 2]): replaces
    /// the law's tanθc (the season's Coulomb default), --mu or samosAT μ cell by cell; cells
    /// it does not cover keep the scalar. Give it again with --resume.
    #[arg(long, value_name = "FILE")]
    pub mu_raster: Option<PathBuf>,
    /// Per-cell Voellmy ξ of the season's avalanches, m/s², in [10, 100000] (as --mu-raster;
    /// `[parameters.avalanche.flow] friction = "voellmy"` only).
    #[arg(long, value_name = "FILE")]
    pub xi_raster: Option<PathBuf>,
    #[command(flatten)]
    pub skiers: SkierArgs,
    #[command(flatten)]
    pub dem_input: DemInputArgs,
    #[command(flatten)]
    pub view: ViewArgs,
}

/// Skiers on the slopes of a season (Cordonnier 2018 §6.2): tracks, compaction, triggers.
#[derive(Debug, Args, Clone, Default)]
pub struct SkierArgs {
    /// Number of skier runs over the season (spread evenly: sets the rate to N / days).
    #[arg(long, value_name = "N")]
    pub skiers: Option<u64>,
    /// Skier runs per day (the paper's "once an hour" is 24); overrides --skiers.
    #[arg(long, value_name = "PER_DAY")]
    pub skier_frequency: Option<f64>,
    /// A start point X,Y in map coordinates (repeat for several; used in turn). Without it
    /// skiers start where runs are longest (weighted by distance to the valley).
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub skier_start: Vec<String>,
}

#[derive(Debug, Args)]
pub struct InfoArgs {
    /// Terrain raster (.asc, .tif, .png, .raw/.r16, .npy).
    pub file: PathBuf,
    #[command(flatten)]
    pub dem: DemInputArgs,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct ParametersArgs {
    /// Only the parameters whose dotted path starts with this (e.g. `melt` or
    /// `slope_shedding.min_slope_deg`).
    pub prefix: Option<String>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// How `snowscape avalanche`'s release thickness is measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ThicknessArg {
    Vertical,
    SlopeNormal,
}

/// The friction law of `snowscape avalanche`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FrictionArg {
    Coulomb,
    Voellmy,
    /// AvaFrame com1DFA's samosAT (μ = 0.155).
    #[value(name = "samosat")]
    SamosAt,
    /// AvaFrame com1DFA's samosATSmall (μ = 0.22), for releases below 25,000 m³: the default.
    #[value(name = "samosat-small")]
    SamosAtSmall,
}

/// How gravity acts on a sloping bed in `snowscape avalanche`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SlopeGravityArg {
    /// The paper's shallow-slope form: gravity g whatever the slope.
    Shallow,
    /// Savage-Hutter projected on the horizontal grid (gravity g·cos²θ of the bed).
    Projected,
}

/// Colouring of a rendered preview.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum RenderMode {
    /// Shaded relief with hypsometric tint.
    Relief,
    /// Snow cover, white by depth (the file is taken as bare terrain: no snow).
    Snow,
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Terrain raster to render.
    pub file: PathBuf,
    /// Output PNG.
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub dem: DemInputArgs,
    #[command(flatten)]
    pub view: ViewArgs,
    /// Colouring.
    #[arg(long, value_enum, default_value_t = RenderMode::Relief)]
    pub mode: RenderMode,
}

/// Preview camera and light.
#[derive(Debug, Args, Clone)]
pub struct ViewArgs {
    /// Sun azimuth, degrees clockwise from north.
    #[arg(long, default_value_t = 315.0)]
    pub sun_azimuth: f64,
    /// Sun elevation above the horizon, degrees.
    #[arg(long, default_value_t = 35.0)]
    pub sun_elevation: f64,
    /// Vertical exaggeration of the shading.
    #[arg(long, default_value_t = 1.0)]
    pub exaggeration: f64,
    /// Longest side of the image in pixels (bigger grids are downsampled).
    #[arg(long, default_value_t = 2048, value_parser = crate::bounds::image_side)]
    pub max_size: usize,
}

#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// Input raster.
    pub input: PathBuf,
    /// Output raster (.tif, .exr, .png (16-bit + JSON sidecar), .asc, .npy).
    pub output: PathBuf,
    #[command(flatten)]
    pub dem: DemInputArgs,
    /// Output format, when the extension does not say it.
    #[arg(long)]
    pub to: Option<String>,
    /// Write a Cloud-Optimized GeoTIFF (the output must be .tif; one band).
    #[arg(long)]
    pub cog: bool,
}

#[derive(Debug, Args)]
pub struct AvalancheArgs {
    /// Terrain raster (.asc, .tif, .png, .raw/.r16, .npy): the avalanche bed.
    #[arg(long)]
    pub dem: PathBuf,
    /// Release: a shapefile of polygons (.shp), a raster mask in the DEM's grid (nonzero =
    /// release), or X,Y map coordinates of a rupture point (a uniform unstable cover of
    /// --thickness breaks there and everything down-slope within reach moves).
    #[arg(long, value_name = "FILE|X,Y", allow_hyphen_values = true)]
    pub release: String,
    /// Release thickness, metres, (0, 50] (default: the shapefile's thickness field, else 1 m).
    #[arg(long, value_parser = crate::bounds::release_thickness)]
    pub thickness: Option<f64>,
    /// How the release thickness is measured: slope-normal (the default: as AvaFrame com1DFA
    /// and field measurements give it; the flow then starts with d/cosθ) or vertical (the
    /// flow's own, the paper's).
    #[arg(long, value_enum, default_value_t = ThicknessArg::SlopeNormal)]
    pub thickness_measured: ThicknessArg,
    /// Rest (friction) angle θc of the snow, degrees (default 30, Cordonnier 2018 Table 2;
    /// --friction-model coulomb only).
    #[arg(long)]
    pub friction_angle: Option<f64>,
    /// Viscous coefficient kv, 1/(m·s) (default 5e-4, Cordonnier 2018 Table 2); acts with
    /// weight 1 - dry-fraction (--friction-model coulomb only).
    #[arg(long)]
    pub viscosity: Option<f64>,
    /// Dry/wet mix α in [0, 1]: 1 dry (Coulomb friction only), 0 wet (viscous only)
    /// (--friction-model coulomb only).
    #[arg(long)]
    pub dry_fraction: Option<f64>,
    /// Basal friction law. Default samosat-small: AvaFrame com1DFA's samosAT law (Sampl &
    /// Granig 2009) with its calibration for releases below 25,000 m³ (samosATSmall, μ =
    /// 0.22), the law of AvaFrame's reference run of avaKot, which the defaults meet. Also
    /// samosat (μ = 0.155), voellmy (--mu, --xi; as RAMMS and AvaFrame com1DFA) and coulomb
    /// (the paper's, Cordonnier et al. 2018: --friction-angle, --viscosity, --dry-fraction;
    /// the paper's whole model is `--friction-model coulomb --thickness-measured vertical
    /// --slope-gravity shallow`). --mu overrides the μ of samosat, samosat-small and voellmy.
    #[arg(long, value_enum, default_value_t = FrictionArg::SamosAtSmall)]
    pub friction_model: FrictionArg,
    /// How gravity acts on the sloping bed: projected (the default: Savage & Hutter 1989 on
    /// the horizontal grid, as AvaFrame solves the slope: driving, pressure and dry friction
    /// scaled by the bed's cos²θ, and the bed's curvature in its load; matches AvaFrame's
    /// analytic tests within 6 %) or shallow (the paper's: gravity g whatever the slope).
    #[arg(long, value_enum, default_value_t = SlopeGravityArg::Projected)]
    pub slope_gravity: SlopeGravityArg,
    /// Leave the centrifugal term of the bed's curvature out of the projected gravity (the
    /// flow then loses speed wherever the slope eases).
    #[arg(long)]
    pub no_curvature: bool,
    /// Voellmy dry-friction coefficient μ (default 0.155, AvaFrame com1DFA).
    #[arg(long)]
    pub mu: Option<f64>,
    /// Voellmy turbulence coefficient ξ, m/s² (default 4000, AvaFrame com1DFA).
    #[arg(long)]
    pub xi: Option<f64>,
    /// Per-cell dry-friction coefficient μ (GeoTIFF/ASC/any DEM format, matched by map
    /// coordinates, any cell size): replaces the law's tanθc, --mu or samosAT μ cell by cell,
    /// in [0, 2]; cells it does not cover keep the scalar (counted in report.json).
    #[arg(long, value_name = "FILE")]
    pub mu_raster: Option<std::path::PathBuf>,
    /// Per-cell Voellmy ξ, m/s², in [10, 100000] (as --mu-raster; --friction-model voellmy only).
    #[arg(long, value_name = "FILE")]
    pub xi_raster: Option<std::path::PathBuf>,
    /// Compare with a reference peak-thickness raster (e.g. AvaFrame's `*_pft.asc`, matched
    /// by map coordinates), AIMEC-like along --path: runout difference, true/false
    /// positive/negative areas, profiles (report.json, comparison_profile.csv,
    /// comparison.png).
    #[arg(long, value_name = "REF.asc|tif")]
    pub compare: Option<std::path::PathBuf>,
    /// The avalanche path of --compare (a line shapefile, e.g. AvaFrame's
    /// LINES/path_aimec.shp); default: the thalweg of the run.
    #[arg(long, value_name = "LINE.shp", requires = "compare")]
    pub path: Option<std::path::PathBuf>,
    /// Half-width of the corridor around the path that --compare counts, metres.
    #[arg(long, default_value_t = 300.0, value_parser = crate::bounds::metres)]
    pub corridor: f64,
    /// Loose snow lying on every cell outside the release, metres (laid as powder, fully
    /// entrainable; AvaFrame's entrainment thickness). Default 0: a bare DEM, nothing to
    /// entrain.
    #[arg(long, default_value_t = 0.0, value_parser = crate::bounds::snow_cover)]
    pub snow_cover: f64,
    /// Turn off entrainment of the snow cover by the flow.
    #[arg(long)]
    pub no_entrainment: bool,
    /// Specific erosion energy of entrainment, J/kg, in [1, 1e7] (default 5000: AvaFrame's
    /// entEroEnergy). Larger values entrain less.
    #[arg(long)]
    pub erosion_energy: Option<f64>,
    /// Longest simulated time, seconds (the run stops earlier once the snow is at rest).
    #[arg(long, default_value_t = 600.0, value_parser = crate::bounds::avalanche_seconds)]
    pub duration: f64,
    /// Films thinner than this, metres (a cell and its 8 neighbours), come to rest as deposit
    /// instead of creeping on; 0 keeps every film flowing (pure Coulomb friction).
    #[arg(long, default_value_t = 0.005)]
    pub settle_thickness: f64,
    /// Stop once the kinetic energy falls below this fraction of its peak (AvaFrame's
    /// stopCrit); 0 runs until the snow is at rest or --duration.
    #[arg(long, default_value_t = 0.01)]
    pub stop_energy: f64,
    /// Simulated seconds between playback frames, [0.01, 3600].
    #[arg(long, default_value_t = 1.0, value_parser = crate::bounds::frame_interval)]
    pub frame_interval: f64,
    /// Random seed (recorded; the flow itself is deterministic).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output folder (created if missing).
    #[arg(long, default_value = "out/avalanche")]
    pub out: PathBuf,
    #[command(flatten)]
    pub dem_input: DemInputArgs,
    #[command(flatten)]
    pub view: ViewArgs,
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Grid size (cells per side) of the kernels.
    #[arg(long, default_value_t = 1024)]
    pub size: usize,
    /// Timed repetitions per kernel (the median is reported).
    #[arg(long, default_value_t = 5, value_parser = crate::bounds::repeats)]
    pub repeats: usize,
    /// Where to write the JSON report.
    #[arg(long, default_value = "bench.json")]
    pub out: PathBuf,
    /// Only the kernels whose name starts with this, e.g. `avalanche/` or `season/100_days`.
    #[arg(long, value_name = "PREFIX")]
    pub only: Option<String>,
}

impl Default for ViewArgs {
    fn default() -> Self {
        Self {
            sun_azimuth: 315.0,
            sun_elevation: 35.0,
            exaggeration: 1.0,
            max_size: 2048,
        }
    }
}

#[derive(Debug, Args)]
pub struct ServeArgs {
    /// Terrain raster (default: the procedural alpine terrain of --size and --seed).
    #[arg(long)]
    pub dem: Option<PathBuf>,
    /// Cells per side of the procedural terrain (128..=4096), without --dem.
    #[arg(long, default_value_t = 256)]
    pub size: usize,
    /// Random seed of the procedural terrain and the season.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Cell size of the procedural terrain, metres.
    #[arg(long = "terrain-cell-size", default_value_t = 20.0, value_parser = crate::bounds::metres)]
    pub terrain_cell_size: f64,
    /// Scenario file (TOML); default: a 100-day winter fitted to the terrain.
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// Project folder: the only place the server reads and writes (created if missing).
    #[arg(long, default_value = "snowscape-project")]
    pub project: PathBuf,
    /// Port to listen on (0: any free port).
    #[arg(long, default_value_t = 8080)]
    pub port: u16,
    /// Address to listen on (127.0.0.1: this machine only). Any other address (0.0.0.0, a
    /// network address) makes the editor reachable from the network: it then asks for the
    /// random access token in the URL it prints.
    #[arg(long, default_value = "127.0.0.1")]
    pub bind: std::net::IpAddr,
    /// Folder of the built page (default: embedded in the binary, or web/ beside it).
    #[arg(long)]
    pub web_dir: Option<PathBuf>,
    /// Run live avalanches and skiers as fast as they compute instead of at 25 frames/s.
    #[arg(long)]
    pub no_pace: bool,
    /// Memory the timeline's snapshots may take, MiB: past it the oldest are dropped (never
    /// the first, which a new scenario restarts from).
    #[arg(long, value_name = "MIB", default_value_t = 2048)]
    pub snapshot_memory: u64,
    #[command(flatten)]
    pub dem_input: DemInputArgs,
}

#[derive(Debug, Args)]
pub struct TransportArgs {
    /// Terrain raster (.asc, .tif, .png, .raw/.r16, .npy): the scene, or the ground a
    /// --mesh stands on.
    #[arg(long)]
    pub dem: Option<PathBuf>,
    /// Triangle mesh (.obj, .gltf/.glb, .ply): the scene (on flat ground at its lowest
    /// point), or objects standing on the --dem.
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    /// Scenario: a TOML file (Jubert 2018 Table 6.I parameters and weather timeline) or a
    /// shipped one: castle, valley (Table 7.I). Default: 36 h of the Table 7.I weather on the
    /// input, with a wind grid fitted to it.
    #[arg(long)]
    pub scenario: Option<String>,
    /// Output folder (created if missing).
    #[arg(long, default_value = "out/transport")]
    pub out: PathBuf,
    /// Simulated time, hours (overrides the scenario), (0, 8760].
    #[arg(long, allow_negative_numbers = true, value_parser = crate::bounds::transport_hours)]
    pub hours: Option<f64>,
    /// Flakes of the precipitation map (overrides the scenario), 1..=100000000.
    #[arg(long, value_parser = crate::bounds::flakes)]
    pub flakes: Option<usize>,
    /// Seed of the flakes (overrides the scenario): the same seed gives the same bytes.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Stable Fluids iterations averaged into the mean wind (overrides the scenario).
    #[arg(long, value_parser = crate::bounds::wind_iterations)]
    pub wind_iterations: Option<usize>,
    /// Voxel side of the wind grid, metres (overrides the scenario or the fitted grid).
    #[arg(long, value_parser = crate::bounds::metres)]
    pub voxel_size: Option<f64>,
    /// Voxel layers of the wind grid (overrides the scenario or the fitted grid), 1..=4096.
    #[arg(long, value_parser = crate::bounds::voxel_layers)]
    pub voxel_layers: Option<usize>,
    /// Uniform snowfall instead of the precipitation map (Jubert 2018 Fig. 7.10).
    #[arg(long)]
    pub uniform_precipitation: bool,
    /// Up axis of the mesh file: y (glTF, most OBJ) or z.
    #[arg(long, default_value = "y")]
    pub up: String,
    /// Metres per mesh unit.
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// Cell size of a mesh's top view, metres (mesh alone; default: its longer side / 100).
    #[arg(long)]
    pub resolution: Option<f64>,
    /// Open ground around a mesh alone, metres (default: its longer side).
    #[arg(long)]
    pub margin: Option<f64>,
    /// Where a --mesh stands on the --dem: X,Y map coordinates (default: the DEM's centre).
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub at: Option<String>,
    #[command(flatten)]
    pub dem_input: DemInputArgs,
}
