//! The Section 5 phenomena together: bit-identical results for any thread count, and a
//! volume budget that closes over a short season.

use snowscape_season::phenomenon::PhenomenonError;
use snowscape_season::{VolumeChange, melt, powder_diffusion, snowfall, stability, wind_transport};
use snowscape_terrain::random::uniform;
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, NodataMask, SnowLayer};

/// Bumpy mountain with a nodata hole, and its environment maps.
struct Scene {
    terrain: LayeredTerrain,
    temperature: Vec<f32>,
    u: Vec<f32>,
    v: Vec<f32>,
    shadow: Vec<f32>,
    wz: Vec<f32>,
}

fn scene() -> Scene {
    let (w, h) = (67, 45);
    let geo = GridGeometry::new(w, h, 8.0, 10.0).unwrap();
    let n = geo.len();
    let invalid: Vec<bool> = (0..n)
        .map(|i| {
            let (c, r) = (i % w, i / w);
            (c as i32 - 50).pow(2) + (r as i32 - 10).pow(2) < 20
        })
        .collect();
    let bed: Vec<f32> = (0..n)
        .map(|i| {
            let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
            let ridge = 600.0 * (-((x - 0.45) * 6.0).powi(2)).exp();
            1200.0 + ridge + 40.0 * (y * 9.0).sin() + (uniform(11, 0, i as u64) * 6.0) as f32
        })
        .collect();
    let terrain = LayeredTerrain::from_bedrock(
        Grid::new(geo, bed.clone(), NodataMask::from_invalid(invalid)).unwrap(),
    );
    let temperature = bed.iter().map(|b| 8.0 - 0.01 * (b - 1000.0)).collect();
    let u = (0..n)
        .map(|i| 8.0 + (uniform(11, 1, i as u64) * 4.0) as f32)
        .collect();
    let v = (0..n)
        .map(|i| (uniform(11, 2, i as u64) * 6.0 - 3.0) as f32)
        .collect();
    let shadow = (0..n)
        .map(|i| {
            let x = (i % w) as f32 / w as f32;
            ((0.46..0.6).contains(&x)) as u8 as f32
        })
        .collect();
    let wz = bed
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let x = (i % w) as f32 / w as f32;
            if (0.46..0.6).contains(&x) {
                b + 30.0
            } else {
                *b
            }
        })
        .collect();
    Scene {
        terrain,
        temperature,
        u,
        v,
        shadow,
        wz,
    }
}

/// Volume added and removed by each event, in order.
fn season(s: &mut Scene, events: usize) -> Result<Vec<VolumeChange>, PhenomenonError> {
    let fall = snowfall::SnowfallParams::default();
    let mut fall_scratch = snowfall::SnowfallScratch::default();
    let mut st_scratch = stability::StabilityScratch::default();
    let mut diff_scratch = powder_diffusion::DiffusionScratch::default();
    let mut wind_scratch = wind_transport::WindScratch::default();
    let mut out = Vec::new();
    for k in 0..events {
        let t = &mut s.terrain;
        let change = match k % 5 {
            0 => snowfall::step(&fall, t, &s.temperature, &mut fall_scratch, 1.0)?,
            1 => melt::step(&melt::MeltParams::default(), t, &s.temperature, 0.5)?,
            2 => stability::step(&Default::default(), t, &s.temperature, &mut st_scratch, 0.5)?
                .volume_change(),
            3 => powder_diffusion::step(&Default::default(), t, &mut diff_scratch, 0.5)?
                .volume_change(),
            _ => {
                let maps = wind_transport::WindMaps {
                    u: &s.u,
                    v: &s.v,
                    shadow: &s.shadow,
                    effect_surface: &s.wz,
                    sx: None,
                    terms: None,
                    air_temperature: None,
                };
                wind_transport::step(&Default::default(), t, &maps, &mut wind_scratch, 0.5)?
                    .volume_change()
            }
        };
        t.check_invariants().unwrap();
        out.push(change);
    }
    Ok(out)
}

#[test]
fn results_are_bit_identical_for_1_2_and_4_threads() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut s = scene();
            let budget = season(&mut s, 60).unwrap();
            (s.terrain, budget)
        })
    };
    let (t1, b1) = run(1);
    for threads in [2, 4] {
        let (t, b) = run(threads);
        for layer in SnowLayer::ALL {
            let same = t1
                .layer(layer)
                .iter()
                .zip(t.layer(layer))
                .all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(
                same,
                "{} layer differs with {threads} threads",
                layer.name()
            );
        }
        assert_eq!(b1, b, "budgets differ with {threads} threads");
    }
    assert!(t1.snow_volume() > 0.0);
}

#[test]
fn the_volume_budget_closes_over_a_season() {
    let mut s = scene();
    let start = s.terrain.snow_volume();
    let (mut added, mut removed) = (0.0, 0.0);
    for change in season(&mut s, 100).unwrap() {
        added += change.added;
        removed += change.removed;
    }
    let now = s.terrain.snow_volume();
    let err = (start + added - removed - now).abs();
    assert!(
        err < 1e-5 * added,
        "budget off by {err} m³ of {added} added"
    );
    assert!(removed > 0.0 && now > 0.0);
    // Every layer got some snow (check_invariants after each event kept the nodata hole bare).
    for layer in SnowLayer::ALL {
        assert!(
            s.terrain.layer(layer).iter().any(|&v| v > 0.0),
            "{} empty",
            layer.name()
        );
    }
}
