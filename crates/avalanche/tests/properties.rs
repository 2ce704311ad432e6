//! Conservation, positivity, determinism, footprint cost, border accounting and conversions.

use proptest::prelude::*;
use snowscape_avalanche::{
    AvalancheParams, AvalancheScratch, AvalancheState, Border, deposit, release, step,
};
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, NodataMask, SnowLayer};

fn hash(i: usize, seed: u64) -> f64 {
    let mut x =
        (i as u64 ^ seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)).wrapping_add(0x632B_E59B_D9B4_E019);
    x ^= x >> 30;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 27;
    x = x.wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^= x >> 31;
    (x >> 11) as f64 / (1u64 << 53) as f64
}

/// A random rough bed and random snow depths on a `w x h` grid.
fn random_state(w: usize, h: usize, seed: u64, dx: f64) -> AvalancheState {
    let g = GridGeometry::new(w, h, dx, dx * 0.8).unwrap();
    let bed: Vec<f64> = (0..w * h)
        .map(|i| 5.0 * hash(i, seed) + 0.3 * (i % w) as f64)
        .collect();
    let mut s = AvalancheState::new(&g, &NodataMask::all_valid(), &bed).unwrap();
    let depth: Vec<f64> = (0..w * h)
        .map(|i| {
            let v = hash(i, seed ^ 0xABCD);
            if v < 0.3 { 0.0 } else { 3.0 * v }
        })
        .collect();
    s.set_thickness(&depth).unwrap();
    s
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    /// Issue 4, item 6: closed box, random bed and depths, any friction mix: volume conserved
    /// to 1e-6 relative (measured ~1e-15), no negative depth, nothing non-finite, at every step.
    #[test]
    fn closed_box_conserves_volume(seed in any::<u64>(), alpha in 0.0f64..=1.0, adv in any::<bool>()) {
        let mut s = random_state(23, 17, seed, 1.5);
        let params = AvalancheParams {
            border: Border::Closed,
            alpha,
            k_viscous: 0.05,
            momentum_advection: adv,
            ..AvalancheParams::default()
        };
        let v0 = s.flowing_volume();
        let mut scratch = AvalancheScratch::default();
        for _ in 0..20 {
            let rep = step(&params, &mut s, &mut scratch, 0.25).unwrap();
            prop_assert_eq!(rep.border_outflow, 0.0);
            let h = s.thickness();
            prop_assert!(h.iter().all(|v| v.is_finite() && *v >= 0.0));
            prop_assert!(rep.max_speed.is_finite());
            let v = s.flowing_volume();
            prop_assert!(((v - v0) / v0).abs() < 1e-6, "volume {} -> {}", v0, v);
        }
    }

    /// Open border: the volume on the grid plus the reported border outflow is conserved.
    #[test]
    fn open_border_outflow_is_counted(seed in any::<u64>()) {
        let mut s = random_state(15, 12, seed, 1.0);
        let params = AvalancheParams { alpha: 0.2, ..AvalancheParams::default() };
        let v0 = s.flowing_volume();
        let mut scratch = AvalancheScratch::default();
        let mut out = 0.0;
        for _ in 0..20 {
            out += step(&params, &mut s, &mut scratch, 0.5).unwrap().border_outflow;
        }
        prop_assert!(out > 0.0);
        let v = s.flowing_volume() + out;
        prop_assert!(((v - v0) / v0).abs() < 1e-9, "volume {} -> {}", v0, v);
    }
}

/// Issue 4, item 6: bit-identical results with rayon pools of 1, 2 and 4 threads.
#[test]
fn deterministic_for_any_thread_count() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut s = random_state(64, 48, 7, 1.0);
            let params = AvalancheParams {
                alpha: 0.7,
                ..AvalancheParams::default()
            };
            let mut scratch = AvalancheScratch::default();
            let mut reports = Vec::new();
            for _ in 0..10 {
                reports.push(step(&params, &mut s, &mut scratch, 0.5).unwrap());
            }
            (s, reports)
        })
    };
    let (s1, r1) = run(1);
    for threads in [2, 4] {
        let (s, r) = run(threads);
        let bits = |st: &AvalancheState| {
            st.thickness()
                .iter()
                .map(|v| v.to_bits())
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&s1), bits(&s), "{threads} threads");
        assert_eq!(s1, s, "{threads} threads (pipes)");
        assert_eq!(r1, r, "{threads} threads (reports)");
    }
}

/// Issue 4, item 6: a small pile on a big grid only costs cells near the pile.
#[test]
fn cost_follows_the_footprint() {
    let n = 512;
    let g = GridGeometry::square(n, n, 1.0).unwrap();
    let mut s = AvalancheState::new(&g, &NodataMask::all_valid(), &vec![0.0; n * n]).unwrap();
    for r in 250..260 {
        for c in 250..260 {
            s.add_thickness(c, r, 3.0).unwrap();
        }
    }
    let mut scratch = AvalancheScratch::default();
    let params = AvalancheParams::default();
    let mut worst = 0;
    for _ in 0..10 {
        let rep = step(&params, &mut s, &mut scratch, 0.5).unwrap();
        worst = worst.max(rep.active_cells);
    }
    let mask = s.moving_mask();
    let wet = mask.iter().filter(|&&m| m).count();
    assert!(wet > 100);
    assert!(worst < 5_000, "active cells {worst} of {}", n * n);
}

fn terrain(w: usize, h: usize) -> LayeredTerrain {
    let g = GridGeometry::square(w, h, 2.0).unwrap();
    let bedrock = Grid::from_fn(g, |c, r| (100.0 - 1.5 * r as f64 + 0.1 * c as f64) as f32);
    let mut t = LayeredTerrain::from_bedrock(bedrock);
    for i in 0..w * h {
        t.layer_mut(SnowLayer::Compacted)[i] = 0.5;
        t.layer_mut(SnowLayer::Stable)[i] = 0.4;
        t.layer_mut(SnowLayer::Unstable)[i] = 0.3;
        t.layer_mut(SnowLayer::Powder)[i] = 0.2;
    }
    t
}

/// Release then deposit: snow volume is conserved through the round trip (to f32 rounding),
/// the released cells lose unstable snow and powder, the bed is bedrock + compacted + stable.
#[test]
fn release_flow_deposit_round_trip() {
    let (w, h) = (30, 40);
    let mut t = terrain(w, h);
    let before = t.snow_volume();
    let mut s = AvalancheState::from_terrain(&t).unwrap();
    let cells: Vec<bool> = (0..w * h)
        .map(|i| (5..10).contains(&(i / w)) && (10..20).contains(&(i % w)))
        .collect();
    let released = release(&mut t, &mut s, &cells, None).unwrap();
    assert!(
        (released - 50.0 * 0.5 * 4.0).abs() < 1e-4,
        "released {released}"
    );
    let i = 7 * w + 15;
    assert_eq!(t.layer(SnowLayer::Unstable)[i], 0.0);
    assert_eq!(t.layer(SnowLayer::Powder)[i], 0.0);
    assert!((s.bed_at(15, 7) - (t.bedrock[i] as f64 + 0.9)).abs() < 1e-5);
    let params = AvalancheParams {
        border: Border::Closed,
        ..AvalancheParams::default()
    };
    let mut scratch = AvalancheScratch::default();
    for _ in 0..30 {
        step(&params, &mut s, &mut scratch, 1.0).unwrap();
    }
    let flowing = s.flowing_volume();
    assert!((flowing - released).abs() < 1e-9 * released);
    let deposited = deposit(&mut t, &mut s, SnowLayer::Stable, false).unwrap();
    assert!((deposited - released).abs() < 1e-9 * released);
    assert_eq!(s.flowing_volume(), 0.0);
    assert!(((t.snow_volume() - before) / before).abs() < 1e-5);
    // A given thickness is taken from the top: powder first, then unstable snow.
    let mut t2 = terrain(w, h);
    let mut s2 = AvalancheState::from_terrain(&t2).unwrap();
    let v = release(&mut t2, &mut s2, &cells, Some(0.25)).unwrap();
    assert!((v - 50.0 * 0.25 * 4.0).abs() < 1e-4);
    assert_eq!(t2.layer(SnowLayer::Powder)[i], 0.0);
    assert!((t2.layer(SnowLayer::Unstable)[i] - 0.25).abs() < 1e-6);
}

/// Parameter and input errors carry the offending values.
#[test]
fn errors_name_the_offending_value() {
    let mut s = random_state(5, 5, 1, 1.0);
    let mut scratch = AvalancheScratch::default();
    let bad = AvalancheParams {
        alpha: 1.5,
        ..AvalancheParams::default()
    };
    let e = step(&bad, &mut s, &mut scratch, 1.0).unwrap_err();
    assert!(e.to_string().contains("alpha = 1.5"), "{e}");
    let e = step(&AvalancheParams::default(), &mut s, &mut scratch, f64::NAN).unwrap_err();
    assert!(e.to_string().contains("NaN"), "{e}");
    assert!(s.set_thickness(&[0.0; 3]).is_err());
}
