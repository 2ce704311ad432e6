//! The cover job of the library (`snowscape::cover::run`) on the real meshes and DEM of the
//! shared data folder (../shared/data beside the checkout; these tests fail when it is
//! missing: they check the job on real files): the files and the typed report of a run into a
//! folder by either method, the snow and report of a run in memory (the Python package's), a
//! mesh standing on a DEM, the typed refusals before any work, and cancelled runs that leave
//! nothing behind.

mod common;

use common::Heard;
use snowscape::control::Unattended;
use snowscape::cover::{
    self, CoverDem, CoverJob, CoverJobError, CoverMethod, CoverOverrides, CoverReport,
};
use snowscape::dem_source::DemSource;
use std::path::{Path, PathBuf};

/// A file of the shared data folder, which must be there.
fn shared(rel: &str) -> PathBuf {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(rel);
    assert!(
        p.exists(),
        "{} is missing: the cover job's tests need the shared data folder beside the checkout",
        p.display()
    );
    p
}

/// The names in `dir` (a file or a folder each), sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The written report.json.
fn written(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap()
}

#[test]
fn a_diffusion_run_into_a_folder_writes_its_files_and_the_typed_report() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("spider");
    let job = CoverJob {
        growth: Some(2),
        turntable: Some(2),
        output: Some(out.clone()),
        ..CoverJob::new(shared("meshes/spider.obj"), CoverMethod::Diffusion)
    };
    let mut heard = Heard::default();
    let o = cover::run(&job, &mut heard).unwrap();
    let CoverReport::Diffusion(r) = &o.report else {
        panic!("a diffusion report")
    };
    assert_eq!((r.command, r.method), ("cover", "diffusion"));
    assert!(r.sites.bridge_sites > 0 && r.snow.triangles > 1000);
    assert_eq!(r.snow.triangles, o.snow.triangles.len());
    assert!(r.growth.as_ref().is_some_and(|g| g.run.steps > 2));
    for name in [
        "snow.glb",
        "snow.obj",
        "snow.mtl",
        "snow_0.png",
        "mask.png",
        "preview.png",
        "turntable.gif",
        "growth/frame_0001.glb",
        "report.json",
    ] {
        assert!(
            r.outputs.iter().any(|f| f == name),
            "{name}: {:?}",
            r.outputs
        );
        assert!(out.join(name).is_file(), "{name}");
    }
    assert_eq!(o.files, r.outputs);
    let keys: Vec<&String> = r.timings_s.keys().collect();
    assert_eq!(keys.first().map(|k| k.as_str()), Some("read"));
    for stage in ["write_glb", "write_obj", "preview", "turntable", "growth"] {
        assert!(r.timings_s.contains_key(stage), "{stage}: {keys:?}");
    }
    // The file is the typed report, key for key; nothing staged is left.
    assert_eq!(written(&out), serde_json::to_value(&o.report).unwrap());
    assert!(!names(&out).iter().any(|n| n.contains("staging")));
    // The stages, in order: reading, the cover, the files, the turntable, the growth.
    assert_eq!(
        heard.status,
        [
            "reading the mesh",
            "covering (diffusion)",
            "writing outputs",
            "turntable",
            "growth"
        ]
    );
    let done: Vec<f64> = heard.progress.iter().map(|p| p.0).collect();
    assert_eq!(done, [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
    assert!(heard.progress.iter().all(|p| p.1 == 5.0));
}

#[test]
fn a_fearing_run_into_a_folder_writes_its_files_and_the_typed_report() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("bunny");
    let overrides = CoverOverrides {
        sites: Some(1500),
        passes: Some(1),
        ..CoverOverrides::default()
    };
    let job = CoverJob {
        scale: 0.1,
        parameters: overrides
            .apply(CoverMethod::Fearing, Default::default())
            .unwrap(),
        output: Some(out.clone()),
        ..CoverJob::new(shared("meshes/bunny_npm.obj"), CoverMethod::Fearing)
    };
    let o = cover::run(&job, &mut Unattended).unwrap();
    let CoverReport::Fearing(r) = &o.report else {
        panic!("a Fearing report")
    };
    assert_eq!(r.cover.method, "fearing");
    assert!(r.cover.flakes_shot > 1000 && r.cover.surface_triangles > 100);
    assert_eq!(r.cover.surface_triangles, o.snow.triangles.len());
    // The default depth is 2 % of the scene's diameter.
    let depth = r.cover.params.as_ref().unwrap().depth_m;
    let expected = cover::default_depth_m(&o.scene).unwrap();
    assert_eq!(depth, expected);
    assert!(r.input.turntable.is_none() && r.input.mesh.metres_per_unit == 0.1);
    for name in [
        "snow.glb",
        "snow.obj",
        "snow.mtl",
        "preview.png",
        "report.json",
    ] {
        assert!(o.files.iter().any(|f| f == name), "{name}: {:?}", o.files);
        assert!(out.join(name).is_file(), "{name}");
    }
    assert_eq!(written(&out), serde_json::to_value(&o.report).unwrap());
}

#[test]
fn a_run_in_memory_and_a_mesh_on_a_dem() {
    // In memory: the snow and the report, no file (the Python package's run).
    let spider = shared("meshes/spider.obj");
    let o = cover::run(
        &CoverJob::new(&spider, CoverMethod::Diffusion),
        &mut Unattended,
    )
    .unwrap();
    let CoverReport::Diffusion(r) = &o.report else {
        panic!("a diffusion report")
    };
    assert!(o.files.is_empty() && r.outputs.is_empty());
    assert!(r.input.dem.is_none());
    assert_eq!(r.snow.vertices, o.snow.positions.len());
    assert!(r.snow.max_height_m > 0.0);
    // The bunny ten times its size on a real DEM: the ground around it is covered too.
    let bunny = shared("meshes/bunny_npm.obj");
    let dem = shared("dem/rme_idaho_50m/dem.asc");
    let job = CoverJob {
        scale: 10.0,
        dem: Some(CoverDem {
            dem: DemSource::file(&dem),
            at: None,
        }),
        ..CoverJob::new(&bunny, CoverMethod::Diffusion)
    };
    let o = cover::run(&job, &mut Unattended).unwrap();
    let CoverReport::Diffusion(r) = &o.report else {
        panic!("a diffusion report")
    };
    let placed = r.input.dem.as_ref().unwrap();
    assert!((2000.0..2200.0).contains(&placed.ground_m), "{placed:?}");
    assert_eq!(placed.terrain.source, dem.display().to_string());
    assert!(r.sites.ground_sites > 20_000, "{:?}", r.sites);
    assert_eq!(o.scene.objects.last().unwrap().name, "terrain");
}

#[test]
fn bad_values_are_refused_typed_before_any_work() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("never");
    let spider = shared("meshes/spider.obj");
    let base = CoverJob {
        output: Some(out.clone()),
        ..CoverJob::new(&spider, CoverMethod::Diffusion)
    };
    let refused = |job: CoverJob| {
        let e = cover::run(&job, &mut Unattended).unwrap_err();
        assert!(e.is_bad_input(), "{e}");
        assert!(!out.exists(), "{e}: the folder was created");
        e
    };
    let e = refused(CoverJob {
        turntable: Some(1),
        ..base.clone()
    });
    assert!(matches!(e, CoverJobError::TurntableFrames(1)), "{e}");
    let e = refused(CoverJob {
        growth: Some(0),
        ..base.clone()
    });
    assert!(matches!(e, CoverJobError::GrowthFrames(0)), "{e}");
    let e = refused(CoverJob {
        scale: -1.0,
        ..base.clone()
    });
    assert!(matches!(e, CoverJobError::Scale(s) if s == -1.0), "{e}");
    let e = refused(CoverJob {
        up: "x".into(),
        ..base.clone()
    });
    assert!(matches!(e, CoverJobError::Up { .. }), "{e}");
    let mut radius = base.clone();
    radius.parameters.diffusion.radius_m = Some(-0.5);
    let e = refused(radius);
    assert!(
        matches!(e, CoverJobError::Diffusion(_)) && e.to_string().contains("-0.5"),
        "{e}"
    );
    let aor = CoverOverrides {
        aor_deg: Some(95.0),
        ..CoverOverrides::default()
    };
    let e = refused(CoverJob {
        method: CoverMethod::Fearing,
        parameters: aor.apply(CoverMethod::Fearing, Default::default()).unwrap(),
        ..base.clone()
    });
    assert!(
        matches!(e, CoverJobError::Fearing(_)) && e.to_string().contains("95"),
        "{e}"
    );
    let e = refused(CoverJob {
        mesh: t.path().join("no_such.obj"),
        ..base.clone()
    });
    assert!(
        matches!(e, CoverJobError::Mesh(_)) && e.to_string().contains("no_such.obj"),
        "{e}"
    );
    // A point off the DEM: refused once the DEM is read, before the folder is opened.
    let e = refused(CoverJob {
        dem: Some(CoverDem {
            dem: DemSource::file(shared("dem/rme_idaho_50m/dem.asc")),
            at: Some([0.0, 0.0]),
        }),
        ..base.clone()
    });
    assert!(matches!(e, CoverJobError::AtOutsideDem { .. }), "{e}");
    // A turntable needs somewhere to go.
    let e = cover::run(
        &CoverJob {
            turntable: Some(4),
            output: None,
            ..base.clone()
        },
        &mut Unattended,
    )
    .unwrap_err();
    assert!(matches!(e, CoverJobError::NeedsOutputFolder(_)), "{e}");
    // An unknown material is refused by the overrides.
    let mud = CoverOverrides {
        material: Some("mud".into()),
        ..CoverOverrides::default()
    };
    let e = mud
        .apply(CoverMethod::Fearing, Default::default())
        .unwrap_err();
    assert!(e.to_string().contains("mud"), "{e}");
}

#[test]
fn a_cancelled_run_stops_between_stages_and_writes_nothing() {
    let t = tempfile::tempdir().unwrap();
    let spider = shared("meshes/spider.obj");
    // Cancelled once the cover has begun: it ends before the files.
    let out = t.path().join("cancelled");
    let job = CoverJob {
        output: Some(out.clone()),
        ..CoverJob::new(&spider, CoverMethod::Diffusion)
    };
    let mut control = Heard {
        cancel_after: Some(2),
        ..Heard::default()
    };
    let e = cover::run(&job, &mut control).unwrap_err();
    assert!(
        matches!(e, CoverJobError::Cancelled { stage } if stage == "writing outputs"),
        "{e}"
    );
    assert!(!e.is_bad_input());
    assert_eq!(control.status, ["reading the mesh", "covering (diffusion)"]);
    // The folder it opened is empty (no output, no staging folder, no manifest).
    assert_eq!(names(&out), Vec::<String>::new());
    // Cancelled after every file was staged: nothing is committed, an earlier run's outputs
    // are left as they were.
    let done = cover::run(&job, &mut Unattended).unwrap();
    let before = std::fs::read(out.join("report.json")).unwrap();
    let mut control = Heard {
        cancel_after: Some(3),
        ..Heard::default()
    };
    let e = cover::run(&job, &mut control).unwrap_err();
    assert!(
        matches!(e, CoverJobError::Cancelled { stage } if stage == "commit"),
        "{e}"
    );
    assert_eq!(std::fs::read(out.join("report.json")).unwrap(), before);
    let mut left = names(&out);
    left.retain(|n| !n.starts_with(".snowscape-outputs"));
    let mut expected = done.files.clone();
    expected.sort();
    assert_eq!(left, expected);
}
