//! The diffusion cover of a job (von Festenberg & Gumhold 2011, `snowscape::festenberg`) and
//! its files: `snow.glb`, `snow.obj` (+ `snow.mtl` and the mask `snow_0.png`), `mask.png`,
//! `preview.png`, `turntable.gif` with a turntable, `growth/frame_NNNN.glb` with a growth
//! animation (Eq. 2), and `report.json` ([`DiffusionCoverReport`]; the file names and keys
//! are a contract), staged in the output folder and committed together.

use super::input::CoverInput;
use super::job::{CoverJob, CoverJobError, CoverOutcome, CoverReport};
use super::outputs::write_turntable;
use super::report::{DiffusionCoverReport, GrowthSummary};
use crate::control::Stages;
use crate::output_folder::{OutputFolder, REPORT};
use crate::outputs::{OutputError, write_png};
use snowscape_festenberg::{CoverParams, FestenbergError, GrowthParams, SnowCover, cover};
use snowscape_mesh::preview::{PreviewOptions, write_preview};
use snowscape_mesh::write::{write_glb, write_obj};
use snowscape_mesh::{MeshError, Scene};
use std::path::Path;
use std::time::Instant;

/// Seconds per stage, in the order the stages ran.
type Timings = Vec<(String, f64)>;

/// Runs `f` as the stage `name`, adding its time to `timings`.
fn timed<T>(timings: &mut Timings, name: &str, f: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let r = f();
    timings.push((name.to_string(), t.elapsed().as_secs_f64()));
    r
}

/// The diffusion cover of the input, its files when there is a folder, and its report.
pub(super) fn run(
    job: &CoverJob,
    input: CoverInput,
    folder: Option<OutputFolder>,
    stages: &mut Stages,
    t0: Instant,
) -> Result<CoverOutcome, CoverJobError> {
    // A DEM fixes the extent.
    let params = CoverParams {
        extent_m: input.extent_m.or(job.parameters.diffusion.extent_m),
        ..job.parameters.diffusion.clone()
    };
    let scene = &input.scene;
    let c = cover(scene, &params).map_err(|e| CoverJobError::Diffusion(Box::new(e)))?;
    if c.mesh.triangles.is_empty() {
        return Err(CoverJobError::NoDiffusionSnow {
            mesh: job.mesh.clone(),
            resolution_m: c.resolved.resolution_m,
        });
    }
    let mut timings = vec![("read".to_string(), input.read_s)];
    timings.extend(c.stats.timings.iter().cloned());
    let mut files = Vec::new();
    let mut growth = None;
    if let Some(folder) = &folder {
        let dir = folder.staging();
        stages.begin("writing outputs")?;
        write_files(dir, scene, &c, &mut timings, &mut files).map_err(CoverJobError::Output)?;
        if let Some(n) = job.turntable {
            stages.begin("turntable")?;
            let meshes = std::slice::from_ref(&c.mesh);
            timed(&mut timings, "turntable", || {
                write_turntable(dir, scene, meshes, n)
            })
            .map_err(CoverJobError::Output)?;
            files.push("turntable.gif".into());
        }
        if let (Some(frames), true) = (job.growth, job.grows()) {
            stages.begin("growth")?;
            let t = Instant::now();
            let run = grow(dir, scene, &params, &c, frames, &mut files)?;
            timings.push(("growth".into(), t.elapsed().as_secs_f64()));
            growth = Some(run);
        }
        files.push(REPORT.into());
    }
    let mut report = DiffusionCoverReport::new(
        input.summary,
        &c,
        growth,
        &timings,
        t0.elapsed().as_secs_f64(),
        files,
    );
    stages.finish()?;
    if let Some(folder) = folder {
        report.removed_stale = folder.stale(&report.outputs);
        // Through a JSON value, as report.json has always been written (its f32 values
        // widened to f64).
        let value = serde_json::to_value(&report).map_err(CoverJobError::Report)?;
        let text = serde_json::to_string_pretty(&value).map_err(CoverJobError::Report)?;
        folder
            .commit(&report.outputs, Some(text.as_bytes()))
            .map_err(CoverJobError::Output)?;
    }
    Ok(CoverOutcome {
        scene: input.scene,
        snow: c.mesh,
        dusting: None,
        files: report.outputs.clone(),
        report: CoverReport::Diffusion(report),
    })
}

/// `snow.glb`, `snow.obj` (+ MTL and mask PNG), `mask.png` and `preview.png` into `dir`.
fn write_files(
    dir: &Path,
    scene: &Scene,
    c: &SnowCover,
    timings: &mut Timings,
    files: &mut Vec<String>,
) -> Result<(), OutputError> {
    let meshes = std::slice::from_ref(&c.mesh);
    timed(timings, "write_glb", || {
        write_glb(&dir.join("snow.glb"), meshes, &scene.frame)
    })?;
    timed(timings, "write_obj", || {
        write_obj(&dir.join("snow.obj"), meshes, &scene.frame)
    })?;
    files.extend(["snow.glb", "snow.obj", "snow.mtl", "snow_0.png"].map(String::from));
    if let Some(mask) = &c.mesh.texture {
        write_png(&dir.join("mask.png"), mask)?;
        files.push("mask.png".into());
    }
    timed(timings, "preview", || {
        write_preview(
            &dir.join("preview.png"),
            scene,
            meshes,
            &PreviewOptions::default(),
        )
    })?;
    files.push("preview.png".into());
    Ok(())
}

/// Why a growth animation stopped.
enum GrowthStop {
    Festenberg(FestenbergError),
    Write(MeshError),
}

impl From<FestenbergError> for GrowthStop {
    fn from(e: FestenbergError) -> Self {
        Self::Festenberg(e)
    }
}

/// The growth animation (Eq. 2, no bridges or overhangs): `growth/frame_NNNN.glb` in `dir`,
/// one per frame with snow.
fn grow(
    dir: &Path,
    scene: &Scene,
    params: &CoverParams,
    c: &SnowCover,
    frames: usize,
    files: &mut Vec<String>,
) -> Result<GrowthSummary, CoverJobError> {
    let growth = GrowthParams::for_cover(&c.resolved, frames);
    let gdir = dir.join("growth");
    std::fs::create_dir_all(&gdir).map_err(|source| {
        CoverJobError::Output(OutputError::CreateFolder {
            path: gdir.clone(),
            source,
        })
    })?;
    let (_, run) = snowscape_festenberg::grow_cover(scene, params, &growth, |i, _, mesh| {
        let name = format!("frame_{i:04}.glb");
        if mesh.triangles.is_empty() {
            return Ok(()); // no snow yet anywhere
        }
        write_glb(&gdir.join(&name), &[mesh], &scene.frame).map_err(GrowthStop::Write)?;
        files.push(format!("growth/{name}"));
        Ok(())
    })
    .map_err(|e| match e {
        GrowthStop::Festenberg(e) => CoverJobError::Growth(Box::new(e)),
        GrowthStop::Write(e) => CoverJobError::Output(e.into()),
    })?;
    Ok(GrowthSummary {
        parameters: growth,
        run,
    })
}
