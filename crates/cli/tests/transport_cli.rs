//! End-to-end tests of `snowscape transport` (Jubert 2018): on the real avaWog DEM, on a real
//! mesh alone and standing on the DEM, on the shipped castle scenario, and bad input refused
//! with exit code 2 and nothing written.

mod common;

use common::{report, shared, snowscape, tiff_size};

const OUTPUTS: [&str; 10] = [
    "depth.tif",
    "density.tif",
    "q_salt.tif",
    "q_susp.tif",
    "q_subl.tif",
    "precipitation.tif",
    "wind2d.tif",
    "wind3d.bin",
    "preview.png",
    "report.json",
];

/// The mass budget closes to rounding of the snow that fell.
fn assert_budget_closes(r: &serde_json::Value) {
    let b = &r["mass_budget"];
    let fell = b["precipitation_in"].as_f64().unwrap();
    let closure = b["closure_error"].as_f64().unwrap();
    assert!(fell > 0.0, "{b}");
    assert!(
        closure.abs() <= 1e-4 * fell,
        "closure {closure} of {fell} kg"
    );
}

/// A short run: 2 h of snowfall in the wind, few flakes and wind iterations.
const SHORT: [&str; 8] = [
    "--hours",
    "2",
    "--flakes",
    "30000",
    "--wind-iterations",
    "4",
    "--seed",
    "3",
];

#[test]
fn transport_on_avawog_writes_every_map_georeferenced_like_the_dem() {
    let dem = shared("dem/avaframe_avaWog/avaWog.asc");
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("wog");
    let mut args = vec![
        "transport",
        "--dem",
        dem.to_str().unwrap(),
        "--voxel-size",
        "40",
        "--voxel-layers",
        "50",
        "--out",
        dir.to_str().unwrap(),
        "-q",
    ];
    args.extend(SHORT);
    let o = snowscape(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in OUTPUTS {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    assert_eq!(tiff_size(&dir.join("depth.tif")), (490, 555));
    let r = report(&dir);
    assert_budget_closes(&r);
    assert_eq!(r["input"]["dem"], dem.to_str().unwrap());
    assert!(r["input"]["nodata_cells_filled"].as_u64().is_some());
    let v = &r["voxels"];
    assert_eq!(
        (v["nx"].as_u64(), v["nz"].as_u64()),
        (Some(61), Some(50)),
        "{v}"
    );
    assert!(r["wind"]["residual_divergence_per_s"].as_f64().unwrap() < 1e-2);
    // The DEM's CRS travels to the outputs.
    let bytes = std::fs::read(dir.join("depth.tif")).unwrap();
    let text = String::from_utf8_lossy(&bytes);
    assert!(text.contains("31287") || bytes.windows(2).any(|w| w == 31287u16.to_le_bytes()));
}

#[test]
fn a_mesh_alone_and_a_mesh_on_a_dem_are_rasterised_from_above() {
    let teapot = shared("meshes/teapot_assimp.obj");
    let out = tempfile::tempdir().unwrap();
    let alone = out.path().join("alone");
    let mut args = vec![
        "transport",
        "--mesh",
        teapot.to_str().unwrap(),
        "--up",
        "z",
        "--resolution",
        "2",
        "--out",
        alone.to_str().unwrap(),
        "-q",
    ];
    args.extend(SHORT);
    let o = snowscape(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = report(&alone);
    assert_budget_closes(&r);
    assert_eq!(r["input"]["resolution_m"], 2.0);
    let raised = r["input"]["cells_above_ground"].as_u64().unwrap();
    assert!(raised > 100, "{}", r["input"]);
    assert!(r["input"]["triangles"].as_u64().unwrap() > 1000);

    let dem = shared("dem/rme_idaho_50m/dem.asc");
    let on_dem = out.path().join("on_dem");
    let mut args = vec![
        "transport",
        "--dem",
        dem.to_str().unwrap(),
        "--mesh",
        teapot.to_str().unwrap(),
        "--up",
        "z",
        "--scale",
        "2",
        "--out",
        on_dem.to_str().unwrap(),
        "-q",
    ];
    args.extend(SHORT);
    let o = snowscape(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = report(&on_dem);
    assert_budget_closes(&r);
    assert_eq!(tiff_size(&on_dem.join("depth.tif")), (18, 19));
    // The teapots stand on the DEM: the top view rises above the bare ground somewhere.
    assert!(
        r["input"]["cells_above_ground"].as_u64().unwrap() > 0,
        "{}",
        r["input"]
    );
    assert!(r["input"]["placed_at_m"].is_array());
}

#[test]
fn the_shipped_castle_scenario_runs_by_name() {
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("castle");
    let o = snowscape(&[
        "transport",
        "--scenario",
        "castle",
        "--hours",
        "0.5",
        "--flakes",
        "20000",
        "--wind-iterations",
        "2",
        "--voxel-size",
        "17",
        "--voxel-layers",
        "12",
        "--out",
        dir.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = report(&dir);
    assert_budget_closes(&r);
    assert_eq!(r["scenario"]["name"], "castle");
    assert_eq!(tiff_size(&dir.join("depth.tif")), (850, 850));
}

fn refused(args: &[&str], needle: &str) {
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("never");
    let mut all = args.to_vec();
    all.extend(["--out", dir.to_str().unwrap()]);
    let o = snowscape(&all);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(
        err.contains(needle),
        "{args:?}: expected {needle:?} in {err}"
    );
    assert!(
        !dir.exists() || std::fs::read_dir(&dir).unwrap().next().is_none(),
        "{args:?} wrote outputs"
    );
}

#[test]
fn bad_input_is_refused_naming_the_value() {
    let dem = shared("dem/rme_idaho_50m/dem.asc");
    let dem = dem.to_str().unwrap();
    refused(&["transport"], "no scene");
    refused(&["transport", "--dem", dem, "--hours", "-3"], "--hours");
    refused(
        &["transport", "--dem", "/nonexistent/dem.tif"],
        "/nonexistent/dem.tif",
    );
    refused(&["transport", "--scenario", "glacier"], "glacier");
    refused(
        &["transport", "--dem", dem, "--voxel-layers", "3"],
        "voxel_layers",
    );
    let tmp = tempfile::tempdir().unwrap();
    let bad = tmp.path().join("bad.toml");
    std::fs::write(&bad, "duration_h = 2\n[wind]\nspeed_m_s = \"fast\"\n").unwrap();
    refused(
        &[
            "transport",
            "--dem",
            dem,
            "--scenario",
            bad.to_str().unwrap(),
        ],
        "speed_m_s",
    );
    let nan = tmp.path().join("nan.asc");
    std::fs::write(
        &nan,
        "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\n1 2 3\n4 nan 6\n",
    )
    .unwrap();
    refused(&["transport", "--dem", nan.to_str().unwrap()], "nan.asc");
    let mesh = tmp.path().join("empty.obj");
    std::fs::write(&mesh, "v 0 0 0\nv 0 0 0\nv 0 0 0\nf 1 2 3\n").unwrap();
    refused(
        &["transport", "--mesh", mesh.to_str().unwrap()],
        "empty.obj",
    );
}
