//! `snowscape render FILE --out FILE.png`: a shaded-relief preview of a terrain file.

use crate::cli::{GlobalArgs, RenderArgs, RenderMode, ViewArgs};
use crate::commands::convert::wrote_line;
use crate::failure::{ExitCodeExt, Failure};
use crate::outputs::write_png;
use crate::stdout::outln;
use anyhow::bail;
use snowscape_render::{ColourMode, PreviewOptions, render_dem, render_preview};
use snowscape_terrain::LayeredTerrain;

/// Preview options from the command line (checked: finite angles, a positive size).
pub fn preview_options(view: &ViewArgs, mode: ColourMode) -> anyhow::Result<PreviewOptions> {
    if !view.sun_azimuth.is_finite() {
        bail!(
            "--sun-azimuth must be a finite angle, got {}",
            view.sun_azimuth
        );
    }
    if !(0.0..=90.0).contains(&view.sun_elevation) {
        bail!(
            "--sun-elevation must be within 0..90 degrees, got {}",
            view.sun_elevation
        );
    }
    if !(view.exaggeration.is_finite() && view.exaggeration > 0.0) {
        bail!(
            "--exaggeration must be a positive number, got {}",
            view.exaggeration
        );
    }
    if view.max_size < 16 {
        bail!(
            "--max-size must be at least 16 pixels, got {}",
            view.max_size
        );
    }
    Ok(PreviewOptions {
        sun_azimuth_deg: view.sun_azimuth,
        sun_elevation_deg: view.sun_elevation,
        mode,
        vertical_exaggeration: view.exaggeration,
        max_size: Some(view.max_size),
    })
}

pub fn run(args: &RenderArgs, global: &GlobalArgs) -> Result<(), Failure> {
    if args
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        != Some("png".into())
    {
        return Err(anyhow::anyhow!(
            "--out {} must end in .png",
            args.out.display()
        ))
        .bad_input();
    }
    let grid = args.dem.read(&args.file).bad_input()?;
    let img = match args.mode {
        RenderMode::Relief => {
            let opts = preview_options(&args.view, ColourMode::Snow).bad_input()?;
            render_dem(&grid, &opts).job_failed()?
        }
        RenderMode::Snow => {
            let opts = preview_options(&args.view, ColourMode::Snow).bad_input()?;
            render_preview(&LayeredTerrain::from_bedrock(grid), &opts).job_failed()?
        }
    };
    write_png(&args.out, &img).job_failed()?;
    if !global.quiet {
        let detail = format!("{} x {} px", img.width(), img.height());
        outln!("{}", wrote_line(&args.out, "PNG", &detail));
    }
    Ok(())
}
