//! The ablations of Jubert 2018, Figs. 7.6-7.8, on the valley scenario at a reduced
//! resolution: the full run against runs without saltation, without suspension and
//! sublimation, and without melt; prints the depth differences (mean, RMS, largest).
//!
//! `cargo run --release -p snowscape-transport --example ablation [CELLS]` (default 100:
//! 100 × 100 cells of 80 m over the 8 km valley).

use snowscape_transport::scenario::{Scenario, SceneSpec, run};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let cells: usize = std::env::args().nth(1).map_or(Ok(100), |s| s.parse())?;
    let mut s = Scenario::from_toml(include_str!("../scenarios/valley.toml"))?;
    let cell = 8000.0 / cells as f64;
    s.scene = SceneSpec::Procedural {
        size: cells,
        cell_m: cell,
        seed: 4,
        relief_m: 1200.0,
    };
    s.voxel_size_m = cell;
    s.voxel_layers = 40;
    s.wind_iterations = 10;
    s.flakes.count = 200_000;
    let (g, z) = s.build_scene()?.expect("procedural scene");
    let depth = |s: &Scenario| -> Result<Vec<f32>, Box<dyn std::error::Error>> {
        Ok(run(s, &g, &z)?.state.depth())
    };
    let out = run(&s, &g, &z)?;
    println!("budget {:?}", out.budget);
    let wmax = out
        .wind_u
        .iter()
        .zip(&out.wind_v)
        .map(|(u, v)| u.hypot(*v))
        .fold(0.0f32, f32::max);
    println!(
        "max wind {wmax}, flakes landed {} (uniform snowfall fallback: {})",
        out.flakes.landed, out.precipitation_fallback
    );
    let full = out.state.depth();
    let mean_full = full.iter().map(|&d| f64::from(d)).sum::<f64>() / full.len() as f64;
    println!("full run: mean depth {mean_full:.4} m");
    for (name, edit) in [
        ("no saltation (Fig. 7.6)", 0),
        ("no suspension + sublimation (Fig. 7.7)", 1),
        ("no melt (Fig. 7.8)", 2),
    ] {
        let mut t = s.clone();
        match edit {
            0 => t.transport.phenomena.saltation = false,
            1 => {
                t.transport.phenomena.suspension = false;
                t.transport.phenomena.sublimation = false;
            }
            _ => t.transport.phenomena.melt = false,
        }
        let other = depth(&t)?;
        let diffs: Vec<f64> = other
            .iter()
            .zip(&full)
            .map(|(a, b)| f64::from(a - b))
            .collect();
        let n = diffs.len() as f64;
        let mean = diffs.iter().sum::<f64>() / n;
        let rms = (diffs.iter().map(|d| d * d).sum::<f64>() / n).sqrt();
        let max = diffs.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        println!("{name}: depth difference mean {mean:+.4} m, RMS {rms:.4} m, largest {max:.4} m");
    }
    Ok(())
}
