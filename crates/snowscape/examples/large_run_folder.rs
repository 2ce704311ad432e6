//! Writes a synthetic run folder of N × N cells (bedrock.tif and the four layers_*.tif that
//! `snowscape export` reads), to measure an export of a grid larger than memory would hold
//! whole: `scripts/export-memory.sh` runs it at 16384² and reports the export's peak memory.
//!
//! `cargo run --release -p snowscape --example large_run_folder -- N DIR`

use snowscape::io::write_geotiff;
use snowscape::terrain::{Grid, GridGeometry};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (Some(n), Some(dir)) = (args.get(1), args.get(2)) else {
        return Err("usage: large_run_folder N DIR".into());
    };
    let n: usize = n.parse()?;
    std::fs::create_dir_all(dir)?;
    let dir = std::path::Path::new(dir);
    let geometry = GridGeometry::square(n, n, 5.0)?;
    // A ridged bedrock, and snow layers that vary north-south.
    let bedrock = Grid::from_fn(geometry.clone(), |c, r| {
        1500.0 + 400.0 * (c as f32 / 900.0).sin() * (r as f32 / 1300.0).cos() + 0.01 * c as f32
    });
    write_geotiff(&dir.join("bedrock.tif"), &bedrock)?;
    drop(bedrock);
    for (k, name) in ["compacted", "stable", "unstable", "powder"]
        .iter()
        .enumerate()
    {
        let layer = Grid::from_fn(geometry.clone(), |_, r| {
            0.2 * (k + 1) as f32 * (1.0 + (r as f32 / (500.0 + 100.0 * k as f32)).sin())
        });
        write_geotiff(&dir.join(format!("layers_{name}.tif")), &layer)?;
    }
    println!("wrote a {n}x{n} run folder in {}", dir.display());
    Ok(())
}
