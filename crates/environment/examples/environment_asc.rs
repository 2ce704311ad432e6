//! Runs the environment precompute on a DEM and writes the maps as ESRI ASCII grids, for
//! comparison with SAGA GIS (`scripts/compare_saga.sh`).
//!
//! ```text
//! cargo run --release -p snowscape-environment --example environment_asc -- DEM OUT_DIR \
//!     [LATITUDE_DEG] [DAY_OF_YEAR] [NUM_DAYS] [DAY_STEP] [SAMPLES_PER_HOUR] [SKY_DIRECTIONS]
//! ```
//!
//! Writes `sun.asc` (direct sun, sun-hours per day, `k_sun = 1`), `svf.asc` (sky view factor,
//! SAGA's definition), `sky.asc`, `bounce.asc`, `temperature.asc`, `wind_shadow.asc`, and
//! `timings.txt` (milliseconds per stage of the full precompute, plus the sun and sky-view
//! computations alone as SAGA's tools do them).

use snowscape_environment::{EnvironmentParams, SkyParams, direct_sun, precompute, sky_exposure};
use snowscape_io::{RasterFormat, ReadOptions, read_dem, write_raster};
use snowscape_terrain::Grid;
use std::path::PathBuf;
use std::time::Instant;

fn arg<T: std::str::FromStr>(args: &[String], i: usize, default: T) -> T {
    args.get(i).and_then(|a| a.parse().ok()).unwrap_or(default)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 {
        eprintln!(
            "usage: environment_asc DEM OUT_DIR [LAT] [DAY] [DAYS] [DAY_STEP] [SAMPLES_PER_HOUR] [DIRECTIONS]"
        );
        std::process::exit(2);
    }
    let out = PathBuf::from(&args[1]);
    std::fs::create_dir_all(&out)?;
    let dem = read_dem(&PathBuf::from(&args[0]), &ReadOptions::default())?;
    let (geometry, mask) = (dem.geometry().clone(), dem.mask().clone());
    let mut p = EnvironmentParams::default();
    p.sun.latitude_deg = arg(&args, 2, 47.0);
    p.sun.start_day = arg(&args, 3, 355);
    p.sun.num_days = arg(&args, 4, 1);
    p.sun.day_step = arg(&args, 5, 1);
    p.sun.samples_per_hour = arg(&args, 6, 2);
    p.sun.k_sun = 1.0;
    p.sky = SkyParams {
        directions: arg(&args, 7, 8),
        ..p.sky
    };

    let t = Instant::now();
    let sun = direct_sun(dem.data(), &geometry, &mask, &p.sun)?;
    let sun_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let sky = sky_exposure(dem.data(), &geometry, &mask, &p.sky)?;
    let sky_ms = t.elapsed().as_secs_f64() * 1e3;
    let maps = precompute(dem.data(), &geometry, &mask, &p)?;

    let write = |name: &str, values: &[f32]| -> Result<(), Box<dyn std::error::Error>> {
        let grid = Grid::new(geometry.clone(), values.to_vec(), mask.clone())?;
        write_raster(&out.join(format!("{name}.asc")), &grid, RasterFormat::Asc)?;
        Ok(())
    };
    write("sun", &sun)?;
    write("svf", &sky.sky_view_factor)?;
    write("sky", &sky.sky)?;
    write("bounce", &maps.bounce)?;
    write("temperature", &maps.temperature)?;
    write("wind_shadow", &maps.wind_shadow)?;
    let tm = maps.timings;
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
    let report = format!(
        "cells {}\nsun_alone_ms {sun_ms:.1}\nsky_alone_ms {sky_ms:.1}\nprecompute_total_ms {:.1}\nprepare_ms {:.1}\nsun_ms {:.1}\nsky_ms {:.1}\nbounce_ms {:.1}\ntemperature_ms {:.1}\nwind_ms {:.1}\n",
        geometry.len(),
        ms(tm.total),
        ms(tm.prepare),
        ms(tm.sun),
        ms(tm.sky),
        ms(tm.bounce),
        ms(tm.temperature),
        ms(tm.wind),
    );
    std::fs::write(out.join("timings.txt"), &report)?;
    print!("{report}");
    Ok(())
}
