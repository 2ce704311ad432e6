//! The one run-to-rest path: a workspace kept through many avalanches gives the bits of a
//! fresh state built from the whole terrain before each one, closes its volume budget, and
//! loses no snow when a run is stopped.

use snowscape_avalanche::{
    AvalancheError, AvalancheParams, AvalancheRun, AvalancheState, AvalancheWorkspace, Border,
    ReleasedCells, RunOptions, deposit, release,
};
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, NodataMask, SnowLayer, random};

/// Two 38° slopes facing each other across a valley, 4 m cells, with a few nodata cells,
/// unstable snow on the upper slopes and stable snow everywhere (part of the bed).
fn valley() -> LayeredTerrain {
    let (w, h) = (150usize, 90usize);
    let g = GridGeometry::square(w, h, 4.0).unwrap();
    let tan = 38f64.to_radians().tan();
    let invalid: Vec<bool> = (0..w * h)
        .map(|i| random::uniform(5, 0, i as u64) < 0.003)
        .collect();
    let bed: Vec<f32> = (0..w * h)
        .map(|i| {
            let c = (i % w) as f64;
            (tan * 4.0 * (c - 75.0).abs().max(10.0) + 300.0 + 2.0 * (i / w) as f64) as f32
        })
        .collect();
    let grid = Grid::new(g, bed, NodataMask::from_invalid(invalid.clone())).unwrap();
    let mut t = LayeredTerrain::from_bedrock(grid);
    for i in (0..w * h).filter(|&i| !invalid[i]) {
        t.layer_mut(SnowLayer::Stable)[i] = (0.3 + random::uniform(5, 1, i as u64)) as f32;
        let c = i % w;
        if !(25..125).contains(&c) {
            t.layer_mut(SnowLayer::Unstable)[i] = (0.4 * random::uniform(5, 2, i as u64)) as f32;
        }
    }
    t
}

/// The release cells of avalanche `k`: a disc of radius 6 cells on one of the slopes.
fn release_cells(t: &LayeredTerrain, k: usize) -> Vec<usize> {
    let g = t.geometry();
    let (cx, cy) = ([12usize, 138, 18, 130][k % 4], 15 + 17 * (k % 4));
    (0..g.len())
        .filter(|&i| {
            let (c, r) = (i % g.width(), i / g.width());
            let d2 = (c as isize - cx as isize).pow(2) + (r as isize - cy as isize).pow(2);
            d2 <= 36 && t.mask().is_valid(i)
        })
        .collect()
}

/// `cells` of `t` released whole and run to rest through `ws` with the default flow, the debris
/// laid down as stable snow.
fn run_release(
    ws: &mut AvalancheWorkspace,
    t: &mut LayeredTerrain,
    cells: &[usize],
    opts: &RunOptions,
) -> snowscape_avalanche::RestOutcome {
    ws.run_to_rest::<AvalancheError>(
        t,
        ReleasedCells::new(cells, None),
        &AvalancheParams::default(),
        opts,
        SnowLayer::Stable,
        |_| Ok(()),
    )
    .unwrap()
}

/// The path the season took before the workspace: a state built from the whole terrain.
fn fresh_run(t: &mut LayeredTerrain, cells: &[usize], opts: &RunOptions) -> (f64, f64) {
    let mut flags = vec![false; t.geometry().len()];
    for &i in cells {
        flags[i] = true;
    }
    let mut s = AvalancheState::from_terrain(t).unwrap();
    let released = release(t, &mut s, &flags, None).unwrap();
    let mut run = AvalancheRun::new(s);
    run.run_over::<AvalancheError>(&AvalancheParams::default(), opts, t, |_| Ok(()))
        .unwrap();
    let deposited = deposit(t, &mut run.state, SnowLayer::Stable, false).unwrap();
    (released, deposited)
}

#[test]
fn a_kept_workspace_gives_the_bits_of_a_fresh_state_per_avalanche() {
    let opts = RunOptions {
        duration_s: 40.0,
        ..RunOptions::default()
    };
    let (mut a, mut b) = (valley(), valley());
    let mut ws = AvalancheWorkspace::new();
    for k in 0..4 {
        let cells = release_cells(&a, k);
        let out = run_release(&mut ws, &mut a, &cells, &opts);
        let (released, deposited) = fresh_run(&mut b, &cells, &opts);
        assert!(
            out.released_m3 > 100.0,
            "avalanche {k} released {}",
            out.released_m3
        );
        assert_eq!(out.released_m3, released, "avalanche {k}");
        let rel = (out.deposited_m3 - deposited).abs() / deposited;
        assert!(
            rel < 1e-12,
            "avalanche {k}: {} vs {deposited}",
            out.deposited_m3
        );
        for layer in SnowLayer::ALL {
            assert_eq!(a.layer(layer), b.layer(layer), "avalanche {k}, {layer:?}");
        }
        // The budget closes and the sparse lists add up to the volumes.
        let s = &out.summary;
        assert!(
            (out.released_m3 + out.entrained_m3 - out.deposited_m3 - s.border_outflow_m3).abs()
                < 1e-9 * out.released_m3
        );
        let area = a.geometry().cell_area();
        let listed: f64 = out.deposited.iter().map(|&(_, h)| h as f64).sum::<f64>() * area;
        assert!((listed - out.deposited_m3).abs() < 1e-5 * out.deposited_m3);
        let taken: f64 = out.released.iter().map(|&(_, h)| h as f64).sum::<f64>() * area;
        assert!((taken - out.released_m3).abs() < 1e-5 * out.released_m3);
        let entrained: f64 = out.entrained.iter().map(|&(_, h)| h as f64).sum::<f64>() * area;
        assert!((entrained - out.entrained_m3).abs() <= 1e-5 * out.entrained_m3);
        // Each avalanche between the others' changes: the bed the next one reads is new.
        for i in 0..a.geometry().len() {
            if i % 7 == k && a.mask().is_valid(i) {
                a.layer_mut(SnowLayer::Compacted)[i] += 0.05;
                b.layer_mut(SnowLayer::Compacted)[i] += 0.05;
            }
        }
    }
}

#[test]
fn a_stopped_run_lays_its_snow_down_and_loses_none() {
    let mut t = valley();
    let before: f64 = t.snow_volume();
    let cells = release_cells(&t, 0);
    let mut ws = AvalancheWorkspace::new();
    let mut records = 0;
    // (Walls around the grid: no snow leaves it.)
    let closed = AvalancheParams {
        border: Border::Closed,
        ..AvalancheParams::default()
    };
    let err = ws
        .run_to_rest::<Wrapped>(
            &mut t,
            ReleasedCells::new(&cells, None),
            &closed,
            &RunOptions::default(),
            SnowLayer::Stable,
            |_| {
                records += 1;
                if records == 30 {
                    Err(Wrapped("cancelled".into()))
                } else {
                    Ok(())
                }
            },
        )
        .unwrap_err();
    assert_eq!(err.0, "cancelled");
    let after = t.snow_volume();
    assert!(
        (after - before).abs() < 1e-6 * before,
        "{before} -> {after}"
    );
    t.check_invariants().unwrap();
    // The workspace is usable again.
    let cells = release_cells(&t, 1);
    ws.run_to_rest::<AvalancheError>(
        &mut t,
        ReleasedCells::new(&cells, None),
        &AvalancheParams::default(),
        &RunOptions::default(),
        SnowLayer::Stable,
        |_| Ok(()),
    )
    .unwrap();
}

impl From<AvalancheError> for Wrapped {
    fn from(e: AvalancheError) -> Self {
        Wrapped(e.to_string())
    }
}

/// (An error type of a caller's own, as the editor's.)
#[derive(Debug)]
struct Wrapped(String);

#[test]
fn bad_parameters_are_refused_before_any_snow_moves() {
    let mut t = valley();
    let before = t.snow.clone();
    let cells = release_cells(&t, 0);
    let flow = AvalancheParams {
        courant: f64::NAN,
        ..AvalancheParams::default()
    };
    let r = AvalancheWorkspace::new().run_to_rest::<Wrapped>(
        &mut t,
        ReleasedCells::new(&cells, None),
        &flow,
        &RunOptions::default(),
        SnowLayer::Stable,
        |_| Ok(()),
    );
    assert!(r.is_err());
    assert_eq!(t.snow, before);
    let r = AvalancheWorkspace::new().run_to_rest::<Wrapped>(
        &mut t,
        ReleasedCells::new(&[usize::MAX], None),
        &AvalancheParams::default(),
        &RunOptions::default(),
        SnowLayer::Stable,
        |_| Ok(()),
    );
    assert!(r.is_err());
    assert_eq!(t.snow, before);
}

/// A run to rest on one thread (no helper), two (its passes shared with the run's helper
/// thread) and four gives the same bits.
#[test]
fn runs_to_rest_keep_their_bits_with_1_2_and_4_threads() {
    let opts = RunOptions {
        duration_s: 30.0,
        ..RunOptions::default()
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut t = valley();
            let mut ws = AvalancheWorkspace::new();
            let mut volumes = Vec::new();
            for k in 0..3 {
                let cells = release_cells(&t, k);
                let out = run_release(&mut ws, &mut t, &cells, &opts);
                volumes.push((out.released_m3.to_bits(), out.deposited_m3.to_bits()));
            }
            (t, volumes)
        })
    };
    let (t1, v1) = run(1);
    assert!(v1.iter().all(|&(r, _)| f64::from_bits(r) > 100.0));
    for threads in [2, 4] {
        let (t, v) = run(threads);
        assert_eq!(v, v1, "{threads} threads");
        for layer in SnowLayer::ALL {
            assert!(
                t.layer(layer)
                    .iter()
                    .zip(t1.layer(layer))
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{layer:?} with {threads} threads"
            );
        }
    }
}
