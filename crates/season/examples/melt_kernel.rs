//! Times one window of the enhanced temperature-index melt (or, with a second argument
//! `energy_balance`, of the energy balance over 24 hours) on an n² grid of snow
//! (`cargo run --release -p snowscape-season --example melt_kernel -- 1024`): ns per cell.

use snowscape_season::melt::{
    EnergyBalanceParams, EnhancedMeltParams, HourAir, MeltForcing, MeltHour, SnowpackState,
    energy_balance, enhanced,
};
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, SnowLayer};
use std::time::Instant;

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(1024);
    let g = GridGeometry::square(n, n, 10.0).unwrap();
    let mut t = LayeredTerrain::from_bedrock(Grid::from_fn(g, |c, r| 1500.0 + (c + r) as f32));
    t.layer_mut(SnowLayer::Stable).fill(1.0);
    t.layer_mut(SnowLayer::Powder).fill(0.1);
    let cells = n * n;
    let offset: Vec<f32> = t.bedrock.iter().map(|z| -0.0065 * z).collect();
    let svf = vec![0.9f32; cells];
    let beam: Vec<u8> = (0..cells).map(|i| (i * 7 % 256) as u8).collect();
    let refl = vec![0.05f32; cells];
    let reflected: Vec<&[f32]> = vec![&refl];
    let energy_balance = std::env::args().nth(2).as_deref() == Some("energy_balance");
    let (first, last) = if energy_balance { (0, 24) } else { (6, 18) };
    let hours: Vec<MeltHour> = (first..last)
        .map(|h| MeltHour {
            weight: 1.0,
            sea_level_c: 12.0
                + 5.0 * ((h as f32 + 0.5 - 15.0) * std::f32::consts::TAU / 24.0).cos(),
            beam: (8..16).contains(&h).then_some(beam.as_slice()),
            direct_w_m2: 800.0,
            diffuse_w_m2: 60.0,
            reflected_w_m2: 400.0,
            month: 0,
            longwave_balance_w_m2: 0.0,
            air: HourAir::default(),
        })
        .collect();
    let forcing = MeltForcing {
        hours: &hours,
        lapse_offset_c: &offset,
        sky_view_factor: &svf,
        reflected: &reflected,
        rain_m: &[],
        window_days: 0.5,
    };
    let mut pack = SnowpackState::new(cells);
    let p = EnhancedMeltParams::default();
    let reps = 10;
    let start = Instant::now();
    for _ in 0..reps {
        if energy_balance {
            let eb = EnergyBalanceParams::default();
            energy_balance::step(&eb, &p, &mut t, &mut pack, &forcing).unwrap();
        } else {
            enhanced::step(&p, &mut t, &mut pack, &forcing).unwrap();
        }
    }
    let s = start.elapsed().as_secs_f64() / reps as f64;
    println!(
        "{n}²: {:.2} ms per window, {:.2} ns per cell ({} threads)",
        s * 1e3,
        s * 1e9 / cells as f64,
        rayon::current_num_threads()
    );
}
