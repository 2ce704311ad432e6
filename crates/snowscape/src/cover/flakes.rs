//! Fearing's cover of a job (Fearing 2000, `snowscape::fearing`) and its files: `snow.glb`,
//! `snow.obj` (+ `snow.mtl`, and the dusting's texture), `preview.png`, `turntable.gif` with
//! a turntable, and `report.json` (Fearing's report with what was read as its `input`,
//! [`FearingCoverReport`]), staged in the output folder and committed together.

use super::input::CoverInput;
use super::job::{CoverJob, CoverJobError, CoverOutcome, CoverReport, FearingCoverReport};
use super::outputs::{fearing_no_snow, write_fearing_outputs, write_turntable};
use super::report::{FearingInputSummary, Turntable};
use crate::control::Stages;
use crate::output_folder::OutputFolder;
use std::time::Instant;

/// Fearing's cover of the input, its files when there is a folder, and its report.
pub(super) fn run(
    job: &CoverJob,
    input: CoverInput,
    folder: Option<OutputFolder>,
    stages: &mut Stages,
    t0: Instant,
) -> Result<CoverOutcome, CoverJobError> {
    let scene = &input.scene;
    // The depth, unless set, is 2 % of the scene's diameter.
    let params = job
        .parameters
        .fearing_for(scene)
        .ok_or(CoverJobError::NoTriangles)?;
    let c = snowscape_fearing::cover(scene, &params).map_err(CoverJobError::Fearing)?;
    if let Some(e) = fearing_no_snow(&c) {
        return Err(CoverJobError::NoFearingSnow(e));
    }
    if let (Some(folder), Some(n)) = (&folder, job.turntable) {
        stages.begin("turntable")?;
        write_turntable(folder.staging(), scene, &c.meshes(), n).map_err(CoverJobError::Output)?;
    }
    let report = FearingCoverReport {
        cover: c.report.clone(),
        input: FearingInputSummary {
            mesh: input.summary,
            read_s: input.read_s,
            wall_s: t0.elapsed().as_secs_f64(),
            turntable: job.turntable.map(|frames| Turntable {
                file: "turntable.gif",
                frames,
            }),
        },
    };
    let mut files = Vec::new();
    if let Some(folder) = &folder {
        stages.begin("writing outputs")?;
        let summary = serde_json::to_value(&report.input).map_err(CoverJobError::Report)?;
        let written = write_fearing_outputs(folder.staging(), scene, &c, Some(summary))
            .map_err(CoverJobError::Output)?;
        files = written
            .iter()
            .filter_map(|p| p.strip_prefix(folder.staging()).ok())
            .map(|p| p.to_string_lossy().into_owned())
            .collect();
        if job.turntable.is_some() {
            files.push("turntable.gif".into());
        }
    }
    stages.finish()?;
    if let Some(folder) = folder {
        folder.commit(&files, None).map_err(CoverJobError::Output)?;
    }
    Ok(CoverOutcome {
        snow: c.surface.to_mesh("snow"),
        dusting: c.dusting,
        scene: input.scene,
        report: CoverReport::Fearing(report),
        files,
    })
}
