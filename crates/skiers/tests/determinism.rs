//! Same seed, same bytes, whatever the thread count; another seed, other tracks.

mod common;

use snowscape_skiers::{SkiArea, SkiParams, SkiScratch, Terminus, step, tracks_geojson};

/// Runs 150 skiers (100 at the start, 50 more halfway) for 400 steps of 0.25 s and returns
/// every output as bytes: texture, GeoJSON, snow layers, recent map, trigger list.
fn run(seed: u64) -> Vec<u8> {
    let params = SkiParams::default();
    let mut t = common::georeferenced(&common::varied_mountain(96, 10.0));
    let mut area = SkiArea::new(&params, &t, Terminus::LocalMinima, seed).unwrap();
    area.spawn_weighted(&params, &t, 100).unwrap();
    let mut scratch = SkiScratch::default();
    let mut out = Vec::new();
    for k in 0..400 {
        if k == 200 {
            area.spawn_weighted(&params, &t, 50).unwrap();
        }
        let r = step(&params, &mut area, &mut t, &mut scratch, 0.25).unwrap();
        out.extend(serde_json::to_vec(&r).unwrap());
    }
    let (w, h) = area.texture().size();
    let mut row = vec![0.0f32; w];
    for v in 0..h {
        area.texture().row(v, &mut row);
        out.extend(row.iter().flat_map(|x| x.to_le_bytes()));
    }
    out.extend(serde_json::to_vec(&tracks_geojson(&area)).unwrap());
    for layer in &t.snow {
        out.extend(layer.iter().flat_map(|x| x.to_le_bytes()));
    }
    out.extend(
        area.recent_skiers(&params)
            .iter()
            .flat_map(|x| x.to_le_bytes()),
    );
    out
}

fn in_pool(threads: usize, seed: u64) -> Vec<u8> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| run(seed))
}

#[test]
fn identical_bytes_for_1_2_and_4_threads() {
    let one = in_pool(1, 42);
    assert!(one.len() > 1_000_000);
    assert!(in_pool(2, 42) == one, "2 threads differ from 1");
    assert!(in_pool(4, 42) == one, "4 threads differ from 1");
    assert!(in_pool(2, 43) != one, "another seed gives the same run");
}
