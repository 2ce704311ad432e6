//! An avalanche from code: the avaWog release polygons of AvaFrame on its DEM, 1 m of snow
//! released and run to rest by the one run-to-rest path every front end uses; prints the
//! summary and writes the peak flow thickness as a GeoTIFF.
//!
//! `cargo run --release -p snowscape --example avalanche -- [DATA] [OUT]` (defaults: the shared
//! data folder `../shared/data` and `out/example_avalanche`).

use snowscape::avalanche::release_area::release_from_shapefile;
use snowscape::avalanche::{AvalancheError, ReleasedCells};
use snowscape::prelude::*;
use std::path::{Path, PathBuf};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let data = PathBuf::from(args.first().map_or("../shared/data", String::as_str));
    let out = PathBuf::from(args.get(1).map_or("out/example_avalanche", String::as_str));
    let dir = data.join("dem/avaframe_avaWog");
    let (dem_path, release_path) = (dir.join("avaWog.asc"), dir.join("REL/relWog.shp"));
    if !dem_path.is_file() || !release_path.is_file() {
        return Err(format!(
            "{} or {} is missing: this example needs the shared data folder",
            dem_path.display(),
            release_path.display()
        )
        .into());
    }
    let dem = read_terrain(&dem_path, &ReadOptions::default())?;
    let area = release_from_shapefile(&release_path, dem.geometry(), dem.mask())?;
    let cells: Vec<usize> = (0..area.cells.len()).filter(|&i| area.cells[i]).collect();
    let mut terrain = LayeredTerrain::from_bedrock(dem.clone());
    let thickness = area.thickness_field(1.0)?;
    for &i in &cells {
        terrain.layer_mut(SnowLayer::Unstable)[i] = thickness[i] as f32;
    }
    let options = AvalancheRunOptions {
        duration_s: 120.0,
        ..AvalancheRunOptions::default()
    };
    let outcome = AvalancheWorkspace::new().run_to_rest::<AvalancheError>(
        &mut terrain,
        ReleasedCells::new(&cells, None),
        &AvalancheParams::default(),
        &options,
        SnowLayer::Stable,
        |_| Ok(()),
    )?;
    let s = &outcome.summary;
    println!(
        "avaWog: released {:.0} m³ on {} cells; after {:.1} s ({:?}) {:.0} m³ deposited, \
         peak speed {:.1} m/s, footprint {:.0} m², volume closure {:.1e}",
        outcome.released_m3,
        cells.len(),
        s.simulated_s,
        s.stop,
        outcome.deposited_m3,
        s.max_speed_m_s,
        s.footprint_area_m2,
        s.volume_closure_rel
    );
    std::fs::create_dir_all(&out)?;
    let peak = RestOutcome::dense(&outcome.peak_thickness, dem.geometry().len());
    let grid = Grid::new(
        dem.geometry().clone(),
        peak.iter().map(|&v| v as f32).collect(),
        dem.mask().clone(),
    )?;
    let path: &Path = &out.join("peak_thickness.tif");
    write_geotiff(path, &grid)?;
    println!("wrote {}", path.display());
    Ok(())
}
