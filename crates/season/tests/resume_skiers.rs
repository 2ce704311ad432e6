//! Issue 48 item 1: a season with skiers and painted release rates, stopped mid-season and
//! resumed through its checkpoint file (as `snowscape run --stop-at` / `--resume` do), ends
//! bit-identical to the uninterrupted season, with 1 and 2 threads: the ski area (clock, next
//! skier id, skiers on the slopes, finished tracks, track texture, recent-skier map, distance
//! map) and the paint are in the checkpoint. Dropping the workspace mid-season changes no bit.

use snowscape_season::scenario::Scenario;
use snowscape_season::winter::Winter;
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, SnowLayer};

/// 40 x 64 cells of 5 m: a 35° slope (rows 0..40) onto gentle ground, with 1 m of stable and
/// 0.3 m of unstable snow.
fn snowy_slope() -> LayeredTerrain {
    let g = GridGeometry::square(40, 64, 5.0).unwrap();
    let tan = 35f32.to_radians().tan();
    let mut t = LayeredTerrain::from_bedrock(Grid::from_fn(g, |c, r| {
        1500.0 + tan * 5.0 * (40.0 - r as f32).max(0.0) + 0.4 * (c as f32 - 20.0).abs()
    }));
    t.layer_mut(SnowLayer::Stable).fill(1.0);
    t.layer_mut(SnowLayer::Unstable).fill(0.3);
    t
}

/// Three days with 24 skiers a day (the paper's "once an hour"), each start event stepping
/// the skiers for at most 4 s, so that skiers are still on the slopes between events (and in
/// the checkpoints).
fn scenario() -> Scenario {
    let mut s = Scenario {
        days: 3.0,
        ..Scenario::default()
    };
    s.parameters.environment.sky.directions = 8;
    s.parameters.environment.sun.day_step = 30;
    s.skiers.per_day = 24.0;
    s.skiers.max_run_s = 4.0;
    s
}

/// A painted release probability on the upper slope.
fn paint() -> Vec<f32> {
    (0..40 * 64)
        .map(|i| {
            if (8..24).contains(&(i / 40)) {
                0.2
            } else {
                0.0
            }
        })
        .collect()
}

/// A fresh season with its paint.
fn start() -> Winter {
    let mut w = Winter::new(scenario(), snowy_slope()).unwrap();
    w.set_painted_release(Some(&paint()), 60.0).unwrap();
    w
}

fn checkpoint(w: &Winter) -> Vec<u8> {
    let mut bytes = Vec::new();
    w.write_checkpoint(&mut bytes).unwrap();
    bytes
}

/// The season run to its end in one go.
fn uninterrupted() -> Winter {
    let mut w = start();
    w.run_until(3.0).unwrap();
    w
}

/// The season stopped at each of `stops` and resumed from its checkpoint file (no paint set
/// again: it comes from the checkpoint); with the number of skiers on the slopes at the stops.
fn interrupted(stops: &[f64]) -> (Winter, usize) {
    let d = tempfile::tempdir().unwrap();
    let path = d.path().join("checkpoint.bin");
    let mut w = start();
    let mut on_slopes = 0;
    for &day in stops {
        w.run_until(day).unwrap();
        on_slopes += w.ski_area().map_or(0, |a| a.skiers().len());
        std::fs::write(&path, checkpoint(&w)).unwrap();
        drop(w);
        w = Winter::resume_from_file(scenario(), snowy_slope(), None, &path).unwrap();
    }
    w.run_until(3.0).unwrap();
    (w, on_slopes)
}

fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

/// Everything the two seasons hold and report, compared bit for bit.
fn assert_same(a: &Winter, b: &Winter, what: &str) {
    assert_eq!(a.ski_stats(), b.ski_stats(), "{what}: ski statistics");
    assert_eq!(a.avalanches(), b.avalanches(), "{what}: avalanches");
    let (ta, tb) = (a.ski_area().unwrap(), b.ski_area().unwrap());
    assert_eq!(ta.texture(), tb.texture(), "{what}: track texture");
    assert!(
        ta.tracks().eq(tb.tracks()),
        "{what}: tracks differ ({} and {})",
        ta.tracks().count(),
        tb.tracks().count()
    );
    assert!(a.terrain.snow == b.terrain.snow, "{what}: snow layers");
    assert!(checkpoint(a) == checkpoint(b), "{what}: checkpoints differ");
}

#[test]
fn a_season_with_skiers_and_paint_resumes_bit_identical_with_1_and_2_threads() {
    let whole = in_pool(2, uninterrupted);
    let st = whole.ski_stats();
    assert!(st.runs >= 40 && st.finished > 0, "{st:?}");
    assert!(whole.ski_area().unwrap().texture().allocated_tiles() > 0);
    let painted = whole
        .avalanches()
        .iter()
        .filter(|a| a.trigger == snowscape_season::avalanches::Trigger::Painted)
        .count();
    eprintln!(
        "{st:?}; {painted} painted avalanches of {}",
        whole.avalanches().len()
    );
    for threads in [1, 2] {
        let (resumed, on_slopes) = in_pool(threads, || interrupted(&[0.7, 1.5, 2.2]));
        assert!(on_slopes > 0, "no skier on the slopes at a checkpoint");
        assert_same(&whole, &resumed, &format!("{threads} threads"));
    }
}

#[test]
fn dropping_the_workspace_mid_season_changes_no_bit() {
    let whole = uninterrupted();
    let mut w = start();
    for day in [0.5, 1.2, 2.0, 2.6] {
        w.run_until(day).unwrap();
        w.drop_workspace();
    }
    w.run_until(3.0).unwrap();
    assert_same(&whole, &w, "workspace dropped");
}

#[test]
fn the_editor_restore_keeps_the_ski_area_and_the_paint() {
    // A fork restored to an earlier checkpoint continues as the original did.
    let mut w = start();
    w.run_until(1.0).unwrap();
    let at_one = checkpoint(&w);
    w.run_until(3.0).unwrap();
    let mut fork = start();
    fork.set_painted_release(None, 60.0).unwrap();
    fork.restore_checkpoint(&mut at_one.as_slice()).unwrap();
    fork.run_until(3.0).unwrap();
    assert_same(&w, &fork, "restored");
}
