//! Where a calm season's time goes: runs the benchmark's `season/100_days` winter (no natural
//! avalanches) on the benchmark terrain and prints the wall-clock seconds per phenomenon.
//!
//! `cargo run --release -p snowscape-bench --example season_phases -- [size] [paper]`:
//! `size` cells per side (default 1024); `paper` runs the paper's formulation of every
//! phenomenon (Cordonnier melt, snowfall and default winter; no shedding, no Sx) instead of the
//! defaults; `shed` instead times slope shedding alone: 1 m of settled snow shed once, then
//! ten steps each after 2 cm of fresh powder.

use snowscape_bench::registry::{SEASON_DAYS, sample_terrain};
use snowscape_season::climate::DefaultWinter;
use snowscape_season::melt::MeltModel;
use snowscape_season::scenario::Scenario;
use snowscape_season::snowfall::SnowfallModel;
use snowscape_season::winter::Winter;
use snowscape_terrain::LayeredTerrain;
use std::io::Write;
use std::time::Instant;

/// A line on stdout; a closed pipe (`| head`) ends the output quietly instead of panicking.
macro_rules! say {
    ($($arg:tt)*) => {
        if writeln!(std::io::stdout(), $($arg)*).is_err() {
            std::process::exit(0);
        }
    };
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let size: usize = args.get(1).map_or(Ok(1024), |s| s.parse())?;
    let paper = args.get(2).is_some_and(|s| s == "paper");
    let terrain = sample_terrain(size)?;
    if args.get(2).is_some_and(|s| s == "shed") {
        return time_shedding(terrain);
    }
    let mut scenario = Scenario {
        days: SEASON_DAYS,
        ..Scenario::default()
    };
    scenario.parameters.avalanche.natural = false;
    if paper {
        let p = &mut scenario.parameters;
        p.melt.model = MeltModel::Cordonnier;
        p.snowfall.model = SnowfallModel::Cordonnier;
        p.climate.default_winter = DefaultWinter::Cordonnier;
        p.slope_shedding.enabled = false;
        p.wind_transport.sx_redistribution.enabled = false;
    }
    let t = Instant::now();
    let mut winter = Winter::new(scenario, LayeredTerrain::from_bedrock(terrain))?;
    let setup = t.elapsed().as_secs_f64();
    let t = Instant::now();
    winter.run_until(SEASON_DAYS)?;
    let season = t.elapsed().as_secs_f64();
    say!(
        "{size}² {}: setup {setup:.2} s, season {season:.2} s",
        if paper { "paper" } else { "defaults" }
    );
    let mut phases: Vec<_> = winter.wall_seconds.iter().collect();
    phases.sort_by(|a, b| b.1.total_cmp(a.1));
    for (name, s) in phases {
        say!("  {name:<20} {s:8.3} s");
    }
    // A fingerprint of the final snow cover (to check that an optimisation changed no bits).
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for layer in &winter.terrain.snow {
        for v in layer {
            hash = (hash ^ u64::from(v.to_bits())).wrapping_mul(0x0100_0000_01b3);
        }
    }
    say!("  snow cover fingerprint {hash:016x}");
    for (kind, n) in winter.event_counts() {
        say!("  events {kind:?}: {n}");
    }
    Ok(())
}

fn time_shedding(terrain: snowscape_terrain::Grid) -> Result<(), Box<dyn std::error::Error>> {
    use snowscape_season::slope_shedding::{SheddingParams, SheddingScratch, step};
    use snowscape_terrain::SnowLayer;
    let mut t = LayeredTerrain::from_bedrock(terrain);
    t.layer_mut(SnowLayer::Stable).fill(1.0);
    let (p, mut scratch) = (SheddingParams::default(), SheddingScratch::default());
    let clock = Instant::now();
    let first = step(&p, &mut t, &mut scratch, 0.5)?;
    say!(
        "first step {:.3} s: {first:?}",
        clock.elapsed().as_secs_f64()
    );
    let clock = Instant::now();
    let mut last = first;
    for _ in 0..10 {
        t.layer_mut(SnowLayer::Powder)
            .iter_mut()
            .for_each(|d| *d += 0.02);
        last = step(&p, &mut t, &mut scratch, 0.5)?;
    }
    say!(
        "after 2 cm: {:.3} s per step: {last:?}",
        clock.elapsed().as_secs_f64() / 10.0
    );
    Ok(())
}
