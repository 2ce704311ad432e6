//! End-to-end tests of `snowscape cover --method diffusion` (von Festenberg & Gumhold 2011)
//! on the real meshes of ../shared/data/meshes (spider legs, teapots with lids and handles;
//! these tests fail when the folder is missing: they exist to check the method on real
//! files), on a mesh standing on a real DEM, and on bad input (exit code 2 naming the value).

mod common;

use common::{report, shared, snowscape, stderr};

#[test]
fn spider_gets_bridged_rounded_snow_and_every_output() {
    let mesh = shared("meshes/spider.obj");
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("spider");
    let o = snowscape(&[
        "cover",
        "--mesh",
        mesh.to_str().unwrap(),
        "--method",
        "diffusion",
        "--growth",
        "3",
        "--out",
        dir.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "snow.glb",
        "snow.obj",
        "snow.mtl",
        "snow_0.png",
        "mask.png",
        "preview.png",
        "report.json",
        "growth/frame_0002.glb",
    ] {
        assert!(dir.join(f).is_file(), "missing {f}");
    }
    let glb = std::fs::read(dir.join("snow.glb")).unwrap();
    assert_eq!(&glb[..4], b"glTF");
    // The JSON chunk: texture coordinates, the embedded mask and an alpha-masked material.
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let doc: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let prim = &doc["meshes"][0]["primitives"][0];
    assert!(prim["attributes"]["TEXCOORD_0"].is_u64(), "{prim}");
    assert_eq!(doc["images"][0]["mimeType"], "image/png");
    assert_eq!(doc["materials"][0]["alphaMode"], "MASK");
    let obj = std::fs::read_to_string(dir.join("snow.obj")).unwrap();
    assert!(obj.contains("\nvt ") && obj.contains("\nvn ") && obj.contains("mtllib snow.mtl"));
    let r = report(&dir);
    assert_eq!(r["method"], "diffusion");
    let h0 = r["parameters"]["depth_m"].as_f64().unwrap();
    let max = r["snow"]["max_height_m"].as_f64().unwrap();
    // Rounded: heights reach above h0 in hollows but never beyond 2 h0 (Eq. 6).
    assert!(
        max > 0.5 * h0 && max <= 2.0 * h0 + 1e-6,
        "max {max}, h0 {h0}"
    );
    // The legs' gaps near the body are bridged.
    assert!(
        r["sites"]["bridge_sites"].as_u64().unwrap() > 50,
        "{}",
        r["sites"]
    );
    assert!(r["snow"]["triangles"].as_u64().unwrap() > 10_000);
    assert!(
        r["snow"]["boundary_loops"].as_u64().unwrap() > 10,
        "every leg has an edge"
    );
    assert!(r["kernel"]["sites_per_s"].as_f64().unwrap() > 0.0);
    assert!(r["growth"]["run"]["steps"].as_u64().unwrap() > 3);
}

#[test]
fn a_turntable_gif_goes_around_the_snowy_mesh() {
    let mesh = shared("meshes/bunny_npm.obj");
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("bunny");
    let o = snowscape(&[
        "cover",
        "--mesh",
        mesh.to_str().unwrap(),
        "--turntable",
        "6",
        "--out",
        dir.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    use image::AnimationDecoder;
    let f = std::io::BufReader::new(std::fs::File::open(dir.join("turntable.gif")).unwrap());
    let frames = image::codecs::gif::GifDecoder::new(f)
        .unwrap()
        .into_frames()
        .collect_frames()
        .unwrap();
    assert_eq!(frames.len(), 6);
    assert_eq!(frames[0].buffer().dimensions(), (480, 360));
    // Seen from another side, the picture changes.
    assert_ne!(frames[0].buffer(), frames[3].buffer());
    assert!(
        report(&dir)["outputs"]
            .as_array()
            .unwrap()
            .iter()
            .any(|f| f == "turntable.gif")
    );
    // A turntable of one frame is refused before anything runs.
    let bad = out.path().join("bad");
    let o = snowscape(&[
        "cover",
        "--mesh",
        mesh.to_str().unwrap(),
        "--turntable",
        "1",
        "--out",
        bad.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--turntable 1"));
    assert!(!bad.exists());
}

#[test]
fn teapots_z_up_with_overhangs() {
    let mesh = shared("meshes/teapot_assimp.obj");
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("teapots");
    let o = snowscape(&[
        "cover",
        "--mesh",
        mesh.to_str().unwrap(),
        "--up",
        "z",
        "--scale",
        "0.01",
        "--overhang",
        "--out",
        dir.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r = report(&dir);
    assert!(r["parameters"]["overhang_m"].as_f64().unwrap() > 0.0);
    assert!(r["sites"]["bridge_sites"].as_u64().unwrap() > 0);
    // Lids on bodies and handles over empty space: several depth layers.
    assert!(r["sites"]["layers"].as_u64().unwrap() >= 2);
    // Metres: the teapots are about 2.6 m across at 1 cm per unit.
    let d = r["parameters"]["diameter_m"].as_f64().unwrap();
    assert!(d > 2.0 && d < 4.0, "{d}");
}

#[test]
fn a_mesh_standing_on_a_dem_is_covered_with_the_ground_around_it() {
    let mesh = shared("meshes/bunny_npm.obj");
    let dem = shared("dem/rme_idaho_50m/dem.asc");
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("bunny");
    let o = snowscape(&[
        "cover",
        "--mesh",
        mesh.to_str().unwrap(),
        "--scale",
        "10",
        "--dem",
        dem.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r = report(&dir);
    let ground = r["input"]["dem"]["ground_m"].as_f64().unwrap();
    assert!((2000.0..2200.0).contains(&ground), "{ground}");
    // The ground around the bunny holds snow too: more sites than the bunny alone.
    assert!(r["sites"]["ground_sites"].as_u64().unwrap() > 20_000);
}

#[test]
fn bad_input_is_refused_with_exit_code_2_naming_the_value() {
    let out = tempfile::tempdir().unwrap();
    let spider = shared("meshes/spider.obj");
    let o = snowscape(&["cover", "--mesh", "/nonexistent/scene.obj", "--out", "x"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("/nonexistent/scene.obj"),
        "{}",
        stderr(&o)
    );
    let dir = out.path().join("r");
    let o = snowscape(&[
        "cover",
        "--mesh",
        spider.to_str().unwrap(),
        "--radius",
        "-0.5",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("-0.5") && stderr(&o).contains("radius"),
        "{}",
        stderr(&o)
    );
    let o = snowscape(&[
        "cover",
        "--mesh",
        spider.to_str().unwrap(),
        "--growth",
        "0",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--growth") && stderr(&o).contains('0'),
        "{}",
        stderr(&o)
    );
    // A degenerate mesh: only zero-area triangles.
    let flat = out.path().join("degenerate.obj");
    std::fs::write(&flat, "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
    let o = snowscape(&[
        "cover",
        "--mesh",
        flat.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("degenerate.obj"), "{}", stderr(&o));
    // A vertical wall (y up: a triangle in the x-y plane of the file stands upright).
    let wall = out.path().join("wall.obj");
    std::fs::write(&wall, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let o = snowscape(&[
        "cover",
        "--mesh",
        wall.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("nothing can hold snow") || stderr(&o).contains("footprint"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn outputs_are_the_same_bytes_whatever_the_thread_count() {
    let mesh = shared("meshes/teapot_assimp.obj");
    let out = tempfile::tempdir().unwrap();
    let run = |threads: &str| {
        let dir = out.path().join(format!("t{threads}"));
        let o = snowscape(&[
            "--threads",
            threads,
            "cover",
            "--mesh",
            mesh.to_str().unwrap(),
            "--up",
            "z",
            "--overhang",
            "--growth",
            "2",
            "--out",
            dir.to_str().unwrap(),
            "-q",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        dir
    };
    let (one, two) = (run("1"), run("2"));
    for f in ["snow.glb", "snow.obj", "mask.png", "growth/frame_0001.glb"] {
        let (a, b) = (
            std::fs::read(one.join(f)).unwrap(),
            std::fs::read(two.join(f)).unwrap(),
        );
        assert!(a == b, "{f} differs between 1 and 2 threads");
    }
}

#[test]
fn a_parameter_file_sets_both_methods_and_a_bad_one_is_refused_before_any_output() {
    let spider = shared("meshes/spider.obj");
    let out = tempfile::tempdir().unwrap();
    let file = out.path().join("cover.toml");
    std::fs::write(
        &file,
        "[diffusion]\nradius_m = 0.9\nbridge_m = 0\n\n[fearing]\ndepth_m = 0.25\npasses = 1\n\
         target_sites = 1500\n[fearing.material]\naor_deg = 40.0\n",
    )
    .unwrap();
    let f = file.to_str().unwrap();
    let dir = out.path().join("d");
    let o = snowscape(&[
        "cover",
        "--mesh",
        spider.to_str().unwrap(),
        "--parameters",
        f,
        "--out",
        dir.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r = report(&dir);
    assert_eq!(
        r["parameters"]["radius_m"].as_f64(),
        Some(0.9),
        "{}",
        r["parameters"]
    );
    assert_eq!(r["parameters"]["bridge_m"].as_f64(), Some(0.0));
    assert_eq!(r["input"]["parameters_file"].as_str(), Some(f));
    // A flag overrides the file.
    let o = snowscape(&[
        "cover",
        "--mesh",
        spider.to_str().unwrap(),
        "--parameters",
        f,
        "--radius",
        "1.1",
        "--out",
        dir.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(report(&dir)["parameters"]["radius_m"].as_f64(), Some(1.1));
    let dir = out.path().join("f");
    let o = snowscape(&[
        "cover",
        "--mesh",
        spider.to_str().unwrap(),
        "--method",
        "fearing",
        "--parameters",
        f,
        "--out",
        dir.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let p = &report(&dir)["params"];
    assert_eq!(p["depth_m"].as_f64(), Some(0.25), "{p}");
    assert_eq!(p["passes"].as_u64(), Some(1));
    assert_eq!(p["material"]["aor_deg"].as_f64(), Some(40.0));
    // Bad files: an unknown key, a value out of range, not TOML; exit 2 naming the file
    // and the key, nothing written.
    for (text, needle) in [
        ("[diffusion]\nradius = 1\n", "radius"),
        ("[fearing]\npasses = 0\n", "passes"),
        ("[fearing.material]\naor_deg = 95\n", "95"),
        ("[diffusion\n", "line 1"),
    ] {
        std::fs::write(&file, text).unwrap();
        let dir = out.path().join("bad");
        let args = [
            "cover",
            "--mesh",
            spider.to_str().unwrap(),
            "--parameters",
            f,
            "--out",
            dir.to_str().unwrap(),
        ];
        let o = snowscape(&args);
        assert_eq!(o.status.code(), Some(2), "{text}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.contains("cover.toml") && e.contains(needle),
            "{text}: {e}"
        );
        assert!(!dir.exists(), "{text}: outputs written");
    }
}
