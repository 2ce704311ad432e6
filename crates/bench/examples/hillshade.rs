//! Renders the procedural alpine terrain as a hillshade PNG and prints its slope statistics:
//! `cargo run --release -p snowscape-bench --example hillshade -- [size] [seed] [cell_size_m] [out.png]`.

use snowscape_terrain::procedural::{AlpineParams, alpine};
use snowscape_terrain::surface;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let size = args.get(1).map_or(Ok(1024), |s| s.parse())?;
    let seed = args.get(2).map_or(Ok(1), |s| s.parse())?;
    let cell_size = args.get(3).map_or(Ok(10.0), |s| s.parse())?;
    let out = args
        .get(4)
        .cloned()
        .unwrap_or_else(|| "/tmp/alpine.png".into());
    let params = AlpineParams {
        size,
        seed,
        cell_size,
        ..AlpineParams::default()
    };
    let params = AlpineParams {
        cliff_band_height: env_or("ALPINE_CLIFF", params.cliff_band_height),
        plateau_share: env_or("ALPINE_PLATEAU", params.plateau_share),
        relief: env_or("ALPINE_RELIEF", params.relief),
        ..params
    };
    let start = Instant::now();
    let grid = alpine(&params)?;
    println!(
        "{size}² generated in {:.3} s",
        start.elapsed().as_secs_f64()
    );
    let (lo, hi) = grid.value_range().unwrap_or((0.0, 0.0));
    println!(
        "altitude {lo:.0}..{hi:.0} m, mean {:.0}",
        grid.mean().unwrap_or(0.0)
    );
    let slopes = surface::slopes(grid.data(), grid.geometry(), grid.mask());
    let share = |lo: f32, hi: f32| {
        let n = slopes
            .iter()
            .filter(|s| (lo..hi).contains(&s.to_degrees()))
            .count();
        100.0 * n as f64 / slopes.len() as f64
    };
    for (lo, hi) in [
        (0., 10.),
        (10., 20.),
        (20., 30.),
        (30., 45.),
        (45., 60.),
        (60., 91.),
    ] {
        println!("slope {lo:>2}..{hi:>2}°: {:5.1} %", share(lo, hi));
    }
    let normals = surface::normals(grid.data(), grid.geometry(), grid.mask());
    let light = [-0.5f32, 0.5, 0.707];
    let pixels: Vec<u8> = normals
        .iter()
        .zip(grid.data())
        .flat_map(|(n, h)| {
            let shade = (n[0] * light[0] + n[1] * light[1] + n[2] * light[2]).max(0.0);
            let t = ((h - lo) / (hi - lo).max(1.0)).clamp(0.0, 1.0);
            let tint = [0.55 + 0.45 * t, 0.6 + 0.4 * t, 0.5 + 0.5 * t];
            tint.map(|c| (255.0 * (0.15 + 0.85 * shade) * c).min(255.0) as u8)
        })
        .collect();
    image::RgbImage::from_raw(size as u32, size as u32, pixels)
        .ok_or("image size")?
        .save(&out)?;
    println!("wrote {out}");
    Ok(())
}

/// A parameter override from the environment.
fn env_or(name: &str, default: f64) -> f64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}
