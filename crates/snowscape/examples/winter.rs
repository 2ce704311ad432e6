//! A winter from code: reads a DEM (or generates the bundled procedural terrain), runs the
//! default season on it and writes every output of `snowscape run` through the library's
//! output layer.
//!
//! `cargo run --release -p snowscape --example winter -- [DEM|procedural] [DAYS] [OUT]`
//! (defaults: the procedural terrain at 256², 30 days, `out/example_winter`).

use snowscape::outputs::{prepare_dir, write_state};
use snowscape::prelude::*;
use snowscape::render::{ColourMode, PreviewOptions};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let dem = args.first().map_or("procedural", String::as_str);
    let days: f64 = args.get(1).map_or(Ok(30.0), |s| s.parse())?;
    let out = PathBuf::from(args.get(2).map_or("out/example_winter", String::as_str));

    let (bedrock, latitude) = if dem == "procedural" {
        let g = alpine(&AlpineParams {
            size: 256,
            ..AlpineParams::default()
        })?;
        (g, Some(46.5))
    } else {
        // The latitude comes from the DEM's georeferencing (the season says so loudly when it
        // cannot read it).
        (read_terrain(dem.as_ref(), &ReadOptions::default())?, None)
    };
    let scenario = Scenario {
        days,
        seed: 1,
        latitude_deg: latitude,
        ..Scenario::default()
    };
    // Every value is range-checked before any work starts.
    scenario.validate("the example")?;
    scenario.validate_on(bedrock.geometry(), "the example")?;
    let mut winter = Winter::new(scenario, LayeredTerrain::from_bedrock(bedrock))?;
    winter.run_until(days)?;

    let t = &winter.terrain;
    let depth = t.total_depth();
    let valid: Vec<f32> = (0..depth.len())
        .filter(|&i| t.mask().is_valid(i))
        .map(|i| depth[i])
        .collect();
    let mean = valid.iter().map(|&d| f64::from(d)).sum::<f64>() / valid.len().max(1) as f64;
    let budget = winter.budget();
    println!(
        "{dem}: {days} days on {}x{} cells of {} m: mean depth {mean:.3} m, max {:.2} m; \
         {} avalanches; volume budget closes to {:.2e} m³ ({:.0} m³ fell)",
        t.geometry().width(),
        t.geometry().height(),
        t.geometry().cell_size_x(),
        valid.iter().copied().fold(0.0f32, f32::max),
        winter.avalanches().len(),
        t.snow_volume() - budget.expected_store(),
        budget.snowfall,
    );
    prepare_dir(&out)?;
    let view = PreviewOptions {
        mode: ColourMode::Snow,
        ..PreviewOptions::default()
    };
    let files = write_state(&out, t, &view)?;
    println!("wrote {} files into {}", files.len(), out.display());
    Ok(())
}
