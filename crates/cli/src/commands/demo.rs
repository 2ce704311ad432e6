//! `snowscape demo`: the main job on the embedded default terrain, no input file needed.
//!
//! Generates the procedural alpine terrain, lets snow fall on it for `--days` days, and writes
//! every output (GeoTIFF, EXR, 16-bit PNG, splat map, previews, glb, time-lapse, report.json).

use crate::cli::{DemoArgs, GlobalArgs, ViewArgs};
use crate::commands::render::preview_options;
use crate::failure::{ExitCodeExt, Failure};
use crate::outputs::{Written, prepare_dir, write_all};
use crate::progress::Stages;
use crate::report::{InputSummary, MassBudget, Report, timings_object};
use anyhow::anyhow;
use serde_json::json;
use snowscape_io::write_bytes_atomic;
use snowscape_render::{ColourMode, PreviewOptions, render_preview};
use snowscape_season::snowfall::{self, SnowfallParams, SnowfallScratch};
use snowscape_terrain::LayeredTerrain;
use snowscape_terrain::procedural::{AlpineParams, alpine};

/// Air temperature at sea level for the demo's snowfall, °C.
const DEMO_T0: f64 = 2.0;
/// Lapse rate, °C per metre; Cordonnier 2018 Table 2 (kt).
const LAPSE_RATE: f64 = -0.01;

pub fn run(args: &DemoArgs, global: &GlobalArgs) -> Result<(), Failure> {
    if !(128..=8192).contains(&args.size) {
        return Err(anyhow!(
            "--size must be within 128..=8192 cells, got {}",
            args.size
        ))
        .bad_input();
    }
    if !(args.cell_size.is_finite() && args.cell_size > 0.0) {
        return Err(anyhow!(
            "--cell-size must be a positive number of metres, got {}",
            args.cell_size
        ))
        .bad_input();
    }
    prepare_dir(&args.out).bad_input()?;
    let view = preview_options(
        &ViewArgs {
            sun_azimuth: 315.0,
            sun_elevation: 35.0,
            exaggeration: 1.0,
            max_size: 1024,
        },
        ColourMode::Snow,
    )
    .job_failed()?;

    let mut stages = Stages::new(6 + args.days as u64, global.quiet);
    let alpine_params = AlpineParams {
        size: args.size,
        seed: args.seed,
        cell_size: args.cell_size,
        ..AlpineParams::default()
    };
    let bedrock = stages
        .run("terrain", || alpine(&alpine_params))
        .job_failed()?;
    let input = InputSummary::of("procedural alpine terrain", &bedrock);
    let mut terrain = LayeredTerrain::from_bedrock(bedrock);

    let snowfall_params = SnowfallParams::default();
    let temperature: Vec<f32> = terrain
        .bedrock
        .iter()
        .map(|&z| (DEMO_T0 + LAPSE_RATE * z as f64) as f32)
        .collect();
    let initial_store = terrain.snow_volume();
    let mut snowfall_in = 0.0;
    let mut scratch = SnowfallScratch::default();
    let frame_days = snapshot_days(args.days, args.frames);
    let frame_view = PreviewOptions {
        max_size: Some(512),
        ..view.clone()
    };
    let mut frames = Vec::new();
    for day in 1..=args.days {
        let v = stages.run("snowfall", || {
            snowfall::step(
                &snowfall_params,
                &mut terrain,
                &temperature,
                &mut scratch,
                1.0,
            )
        });
        snowfall_in += v.added;
        if frame_days.contains(&day) {
            let frame = stages
                .run("frames", || render_preview(&terrain, &frame_view))
                .job_failed()?;
            frames.push(frame);
        }
    }
    terrain.check_invariants().job_failed()?;

    let mut out = Written::new(&args.out);
    write_all(&mut out, &terrain, &frames, &view, &mut stages).job_failed()?;

    let mut budget = MassBudget {
        initial_store,
        final_store: terrain.snow_volume(),
        ..MassBudget::default()
    };
    budget.inputs.insert("snowfall".into(), snowfall_in);
    out.files.push("report.json".into());
    let report = Report {
        snowscape_version: env!("CARGO_PKG_VERSION"),
        command: "demo".into(),
        input,
        parameters: json!({
            "terrain": {
                "size": alpine_params.size,
                "cell_size_m": alpine_params.cell_size,
                "relief_m": alpine_params.relief,
                "base_altitude_m": alpine_params.base_altitude,
            },
            "days": args.days,
            "sea_level_temperature_c": DEMO_T0,
            "lapse_rate_c_per_m": LAPSE_RATE,
            "snowfall": snowfall_params,
            "preview": { "sun_azimuth_deg": view.sun_azimuth_deg, "sun_elevation_deg": view.sun_elevation_deg },
        }),
        seed: args.seed,
        threads: rayon::current_num_threads(),
        timings: timings_object(&stages.finish()),
        mass_budget: budget.close(),
        outputs: out.files.clone(),
    };
    let text = serde_json::to_vec_pretty(&report).job_failed()?;
    write_bytes_atomic(&args.out.join("report.json"), &text).job_failed()?;
    if !global.quiet {
        println!(
            "demo: {}x{} terrain, {} days of snowfall, {} files in {}",
            args.size,
            args.size,
            args.days,
            report.outputs.len(),
            args.out.display()
        );
    }
    Ok(())
}

/// The days (1-based) at which time-lapse frames are taken: `frames` days spread evenly over
/// the run, always including the last.
fn snapshot_days(days: u32, frames: usize) -> Vec<u32> {
    if days == 0 || frames == 0 {
        return Vec::new();
    }
    let n = (frames as u32).min(days);
    (1..=n).map(|k| (k * days).div_ceil(n)).collect()
}

#[cfg(test)]
mod tests {
    use super::snapshot_days;

    #[test]
    fn snapshots_cover_the_run() {
        assert_eq!(snapshot_days(30, 3), vec![10, 20, 30]);
        assert_eq!(snapshot_days(2, 10), vec![1, 2]);
        assert!(snapshot_days(0, 5).is_empty());
        assert_eq!(*snapshot_days(7, 4).last().unwrap(), 7);
    }
}
