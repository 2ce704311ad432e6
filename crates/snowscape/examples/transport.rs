//! 3D snow transport from code: the shipped `castle` scenario (the 850 m castle of the
//! paper's Table 7.I: snowfall at −5 °C in an 11 m/s west wind), shortened to 2 hours and
//! 30 000 flakes; prints the mass budget and writes every map of `snowscape transport`.
//!
//! `cargo run --release -p snowscape --example transport -- [HOURS] [OUT]` (defaults: 2 h,
//! `out/example_transport`).

use snowscape::transport::scenario::{Scenario, run, shipped_scenario};
use snowscape::transport_job::{RunContext, write_outputs};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let hours: f64 = args.first().map_or(Ok(2.0), |s| s.parse())?;
    let out = PathBuf::from(args.get(1).map_or("out/example_transport", String::as_str));
    let mut scenario = Scenario::from_toml(shipped_scenario("castle").ok_or("no castle")?)?;
    scenario.duration_h = hours;
    scenario.flakes.count = 30_000;
    scenario.wind_iterations = 8;
    scenario.validate()?;
    let (geometry, heights) = scenario
        .build_scene()?
        .ok_or("the castle scenario builds its own scene")?;
    let started = std::time::Instant::now();
    let result = run(&scenario, &geometry, &heights)?;
    let b = &result.budget;
    println!(
        "castle, {hours} h on {}x{} cells: {:.0} kg fell, {:.0} kg transported, {:.0} kg \
         sublimated, {:.0} kg left the border; budget closure {:.1e} kg",
        geometry.width(),
        geometry.height(),
        b.precipitation_in,
        b.transported,
        b.sublimation_out,
        b.border_out,
        b.closure_error
    );
    let context = RunContext {
        input: serde_json::json!({ "scenario": "castle (shipped)" }),
        mask: None,
        wall_s: started.elapsed().as_secs_f64(),
    };
    let files = write_outputs(&out, &scenario, &heights, &result, &context)?;
    println!("wrote {} files into {}", files.len(), out.display());
    Ok(())
}
