//! The tracks as file contents: GeoJSON in the DEM's CRS, the georeferenced track PNG (the
//! files themselves are written by `snowscape::outputs`, tested there).

mod common;

use snowscape_skiers::frame::map_extent;
use snowscape_skiers::{
    PngDepth, SkiArea, SkiParams, SkiScratch, Terminus, encode_track_png, step, tracks_geojson,
};
use snowscape_terrain::LayeredTerrain;

fn skied_area() -> (SkiParams, SkiArea, LayeredTerrain) {
    let params = SkiParams {
        texels_per_cell: 4,
        ..SkiParams::default()
    };
    let mut t = common::georeferenced(&common::varied_mountain(48, 10.0));
    let mut area = SkiArea::new(&params, &t, Terminus::LocalMinima, 8).unwrap();
    area.spawn_weighted(&params, &t, 12).unwrap();
    let mut scratch = SkiScratch::default();
    for _ in 0..30 {
        step(&params, &mut area, &mut t, &mut scratch, 1.0).unwrap();
    }
    assert!(!area.finished_tracks().is_empty() && !area.skiers().is_empty());
    (params, area, t)
}

#[test]
fn geojson_lines_lie_inside_the_dem_in_its_crs() {
    let (_, area, _) = skied_area();
    // Through its text, as a file holds it.
    let v: serde_json::Value =
        serde_json::from_slice(&serde_json::to_vec(&tracks_geojson(&area)).unwrap()).unwrap();
    assert_eq!(v["type"], "FeatureCollection");
    assert_eq!(v["crs"]["properties"]["name"], "EPSG:31287");
    let features = v["features"].as_array().unwrap();
    assert_eq!(features.len(), 12);
    let (x0, x1, y0, y1) = map_extent(area.geometry());
    assert_eq!((x0, y1), (166_773.0, 353_588.0));
    let mut ids: Vec<u64> = Vec::new();
    let (mut active, mut done) = (0, 0);
    for f in features {
        assert_eq!(f["type"], "Feature");
        assert_eq!(f["geometry"]["type"], "LineString");
        let coords = f["geometry"]["coordinates"].as_array().unwrap();
        assert!(coords.len() >= 2);
        let mut len = 0.0;
        let mut prev: Option<(f64, f64)> = None;
        for c in coords {
            let (x, y) = (c[0].as_f64().unwrap(), c[1].as_f64().unwrap());
            assert!(
                (x0..=x1).contains(&x) && (y0..=y1).contains(&y),
                "({x}, {y}) outside"
            );
            if let Some((px, py)) = prev {
                len += (x - px).hypot(y - py);
            }
            prev = Some((x, y));
        }
        let p = &f["properties"];
        ids.push(p["skier"].as_u64().unwrap());
        let length = p["length_m"].as_f64().unwrap();
        // The polyline is the track decimated to 2 m vertices: a little shorter, never longer.
        assert!(
            len <= length * 1.0001 && len >= 0.9 * length,
            "{len} vs {length}"
        );
        assert!(p["start_time_s"].as_f64().unwrap() >= 0.0);
        if p["active"].as_bool().unwrap() {
            active += 1;
            assert!(p["end_time_s"].is_null());
        } else {
            done += 1;
            assert!(p["stop"].is_string());
        }
    }
    ids.sort();
    assert_eq!(ids, (0..12).collect::<Vec<_>>());
    assert_eq!(active, area.skiers().len());
    assert_eq!(done, area.finished_tracks().len());
}

#[test]
fn geojson_without_epsg_has_no_crs_member() {
    let params = SkiParams::default();
    let t = common::plane(8, 20, 10.0, 30.0);
    let mut area = SkiArea::new(&params, &t, Terminus::LocalMinima, 1).unwrap();
    area.spawn_at(&params, &t, 40.0, 190.0).unwrap();
    let v = snowscape_skiers::tracks_geojson(&area);
    assert!(v.get("crs").is_none());
    assert_eq!(
        v["features"][0]["geometry"]["coordinates"]
            .as_array()
            .unwrap()
            .len(),
        2
    );
}

#[test]
fn track_png_reads_back_with_its_georeferencing() {
    let (_, area, t) = skied_area();
    for depth in [PngDepth::Sixteen, PngDepth::Eight] {
        let encoded = encode_track_png(area.texture(), t.geometry(), depth).unwrap();
        let img = image::load_from_memory(&encoded.png).unwrap();
        assert_eq!((img.width(), img.height()), (192, 192));
        let tex = area.texture();
        let (top, codes): (f32, Vec<u16>) = match depth {
            PngDepth::Sixteen => (65535.0, img.into_luma16().into_raw()),
            PngDepth::Eight => (
                255.0,
                img.into_luma8()
                    .into_raw()
                    .into_iter()
                    .map(u16::from)
                    .collect(),
            ),
        };
        let mut nonzero = 0;
        for v in 0..192 {
            for u in 0..192 {
                let expect = (tex.get(u, v) * top).round() as u16;
                assert_eq!(codes[v * 192 + u], expect, "texel ({u}, {v})");
                nonzero += usize::from(expect > 0);
            }
        }
        assert!(nonzero > 200, "{nonzero}");
        let side = serde_json::to_value(&encoded.sidecar).unwrap();
        assert_eq!(side["format"], "snowscape-ski-tracks");
        assert_eq!(side["width"], 192);
        assert_eq!(side["texels_per_cell"], 4);
        assert_eq!(side["transform"]["pixel_width"], 2.5);
        assert_eq!(side["transform"]["origin_x"], 166_773.0);
        assert_eq!(side["crs_name"], "EPSG:31287");
        let w: Vec<f64> = encoded
            .world_file
            .lines()
            .map(|l| l.parse().unwrap())
            .collect();
        assert_eq!(w, vec![2.5, 0.0, 0.0, -2.5, 166_774.25, 353_586.75]);
    }
}
