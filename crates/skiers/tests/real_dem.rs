//! Skiers on a real DEM: AvaFrame's avaMal (567×787 cells of 5 m, EPSG:31287) under a
//! synthetic snow cover that thickens with altitude. The test fails loudly if the file is
//! missing.

use snowscape_io::{ReadOptions, read_dem};
use snowscape_skiers::frame::map_extent;
use snowscape_skiers::{
    PngDepth, SkiArea, SkiParams, SkiScratch, StopReason, Terminus, encode_track_png,
    snow_water_equivalent, step, tracks_geojson,
};
use snowscape_terrain::{Crs, LayeredTerrain, SnowLayer};
use std::path::Path;

const DEM: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../../shared/data/dem/avaframe_avaMal/avaMal.asc"
);

fn ava_mal() -> LayeredTerrain {
    let path = Path::new(DEM);
    assert!(
        path.is_file(),
        "real-DEM test input {} is missing: this test needs /work/shared/data (AvaFrame avaMal)",
        path.display()
    );
    let grid = read_dem(path, &ReadOptions::default())
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let mut t = LayeredTerrain::from_bedrock(grid);
    let (lo, hi) = t.to_grid(t.bedrock.clone()).unwrap().value_range().unwrap();
    // Snow line a fifth of the way up; 0.5 m there rising to 2.5 m at the top, a third of it
    // unstable; no snow on nodata.
    let snow_line = lo + 0.2 * (hi - lo);
    for i in 0..t.bedrock.len() {
        if !t.mask().is_valid(i) || t.bedrock[i] < snow_line {
            continue;
        }
        let d = 0.5 + 2.0 * (t.bedrock[i] - snow_line) / (hi - snow_line);
        t.layer_mut(SnowLayer::Stable)[i] = d * 2.0 / 3.0;
        t.layer_mut(SnowLayer::Unstable)[i] = d / 3.0;
    }
    t
}

#[test]
fn skiers_descend_ava_mal_on_snow_and_write_georeferenced_outputs() {
    let params = SkiParams::default();
    let mut t = ava_mal();
    let g = t.geometry().clone();
    assert_eq!((g.width(), g.height(), g.cell_size_x()), (567, 787, 5.0));
    assert_eq!(g.crs(), Some(&Crs::Epsg(31287)));
    let depth0 = t.total_depth();
    let surface0 = t.surface();
    let swe0 = snow_water_equivalent(&params, &t);
    let mut area = SkiArea::new(&params, &t, Terminus::LocalMinima, 2018).unwrap();
    let map = area.terminus().clone();
    assert!(map.spawn_weight_total() > 0.0);
    assert_eq!(area.spawn_weighted(&params, &t, 40).unwrap().len(), 40);
    let mut scratch = SkiScratch::default();
    let mut triggers = 0;
    for _ in 0..3000 {
        if area.skiers().is_empty() {
            break;
        }
        let r = step(&params, &mut area, &mut t, &mut scratch, 1.0).unwrap();
        triggers += r.triggers.len();
    }
    assert!(
        area.skiers().is_empty(),
        "{} skiers still skiing",
        area.skiers().len()
    );
    let tracks = area.finished_tracks();
    let reached = tracks
        .iter()
        .filter(|tr| tr.stop == Some(StopReason::Terminus))
        .count();
    let mut drops = Vec::new();
    for tr in tracks {
        for &c in &tr.cells {
            assert!(
                depth0[c] > params.min_snow_depth_m as f32 || map.is_terminus(c),
                "skier {} in cell {c} with {} m of snow",
                tr.id,
                depth0[c]
            );
        }
        let (a, b) = (tr.cells[0], *tr.cells.last().unwrap());
        drops.push(surface0[a] - surface0[b]);
        assert!(
            map.distance_at(b) < map.distance_at(a),
            "skier {} ended no nearer",
            tr.id
        );
    }
    let mean_drop = drops.iter().sum::<f32>() / drops.len() as f32;
    eprintln!(
        "avaMal: {reached}/40 reached a terminus, mean drop {mean_drop:.0} m, {triggers} triggers, map swept {} times",
        map.sweeps()
    );
    assert!(reached >= 30, "{reached}");
    assert!(drops.iter().all(|&d| d > 0.0));
    assert!(mean_drop > 100.0, "{mean_drop}");
    let swe1 = snow_water_equivalent(&params, &t);
    assert!((swe1 - swe0).abs() < 1e-5 * swe0, "{swe0} -> {swe1}");
    t.check_invariants().unwrap();

    let png = encode_track_png(area.texture(), &g, PngDepth::Sixteen).unwrap();
    let img = image::load_from_memory(&png.png).unwrap();
    assert_eq!((img.width(), img.height()), (567 * 8, 787 * 8));
    let v = tracks_geojson(&area);
    assert_eq!(v["crs"]["properties"]["name"], "EPSG:31287");
    let (x0, x1, y0, y1) = map_extent(&g);
    for f in v["features"].as_array().unwrap() {
        for c in f["geometry"]["coordinates"].as_array().unwrap() {
            let (x, y) = (c[0].as_f64().unwrap(), c[1].as_f64().unwrap());
            assert!(
                (x0..=x1).contains(&x) && (y0..=y1).contains(&y),
                "({x}, {y})"
            );
        }
    }
}
