//! The transport job of the library (`snowscape::transport_job`) on the real RME DEM and a
//! real mesh of the shared data folder (../shared/data beside the checkout; these tests fail
//! when it is missing: they check the job on real files): the files and the typed report of a
//! run into a folder, the same maps from a grid in memory (the Python package's run), a mesh's
//! top view, the typed refusals before any work, and a cancelled run that writes nothing.

mod common;

use common::Heard;
use snowscape::control::Unattended;
use snowscape::dem_source::DemSource;
use snowscape::io::{ReadOptions, read_terrain};
use snowscape::transport_job::{
    self, Overrides, SceneSummary, TransportJob, TransportJobError, TransportMesh, prepare,
};
use std::path::{Path, PathBuf};

/// A file of the shared data folder, which must be there.
fn shared(rel: &str) -> PathBuf {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(rel);
    assert!(
        p.exists(),
        "{} is missing: the transport job's tests need the shared data folder beside the checkout",
        p.display()
    );
    p
}

/// Two hours of snowfall in the wind on the RME DEM (18 x 19 cells of 50 m), few flakes.
fn short_run(dem: DemSource, output: Option<PathBuf>) -> TransportJob {
    TransportJob {
        dem: Some(dem),
        overrides: Overrides {
            hours: Some(2.0),
            flakes: Some(20_000),
            wind_iterations: Some(4),
            seed: Some(3),
            ..Overrides::default()
        },
        output,
        ..TransportJob::default()
    }
}

/// A typed report as its file reads back (the file is the report written directly: its f32
/// values written shortest, read back as f64).
fn as_json(report: &impl serde::Serialize) -> serde_json::Value {
    serde_json::from_str(&serde_json::to_string_pretty(report).unwrap()).unwrap()
}

#[test]
fn a_run_into_a_folder_writes_its_files_and_the_typed_report_and_in_memory_the_same_maps() {
    let dem = shared("dem/rme_idaho_50m/dem.asc");
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("rme");
    let mut heard = Heard::default();
    let o = transport_job::run(
        &short_run(DemSource::file(&dem), Some(out.clone())),
        &mut heard,
    )
    .unwrap();
    assert_eq!(
        heard.status,
        ["reading the scene", "transport", "writing outputs"]
    );
    let done: Vec<f64> = heard.progress.iter().map(|p| p.0).collect();
    assert_eq!(done, [0.0, 1.0, 2.0, 3.0]);
    let files = [
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
    assert_eq!(o.files, files);
    for f in files {
        assert!(out.join(f).is_file(), "{f}");
    }
    let r = &o.report;
    assert_eq!(r.steps, o.run.steps);
    assert_eq!((r.grid.width, r.grid.height), (18, 19));
    assert_eq!(r.scenario.duration_h, 2.0);
    let b = &r.mass_budget.budget;
    assert!(b.precipitation_in > 0.0 && b.closure_error.abs() <= 1e-4 * b.precipitation_in);
    let SceneSummary::Dem(d) = &o.scene.summary else {
        panic!("a DEM scene")
    };
    assert_eq!(d.dem, dem.display().to_string());
    // The file is the typed report, key for key.
    let written: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(written, as_json(r));

    // The same DEM as a grid in memory, nothing written: the same maps, bit for bit.
    let grid = read_terrain(&dem, &ReadOptions::default()).unwrap();
    let cells = grid.geometry().len();
    let mem = transport_job::run(
        &short_run(
            DemSource::Grid {
                name: "grid".into(),
                grid,
            },
            None,
        ),
        &mut Unattended,
    )
    .unwrap();
    assert!(mem.files.is_empty());
    let (a, b) = (o.maps(), mem.maps());
    let names: Vec<&str> = b.iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names,
        [
            "depth",
            "density",
            "q_salt",
            "q_susp",
            "q_subl",
            "precipitation",
            "wind_u",
            "wind_v"
        ]
    );
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        assert_eq!(y.len(), cells, "{name}");
        let same = x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits());
        assert!(same, "{name} differs between the file and the grid");
    }
    assert_eq!(mem.report.mass_budget.budget, r.mass_budget.budget);
}

#[test]
fn a_mesh_alone_is_seen_from_above() {
    let teapot = shared("meshes/teapot_assimp.obj");
    let job = TransportJob {
        mesh: Some(TransportMesh {
            up: "z".into(),
            resolution_m: Some(2.0),
            ..TransportMesh::new(&teapot)
        }),
        ..TransportJob::default()
    };
    let p = prepare(&job).unwrap();
    let SceneSummary::Mesh(m) = p.summary() else {
        panic!("a mesh scene")
    };
    assert_eq!(m.resolution_m, Some(2.0));
    assert!(m.cells_above_ground > 100 && m.triangles > 1000, "{m:?}");
    // No scenario file: the Table 7.I weather with a wind grid fitted to the scene.
    assert_eq!(p.scenario().name, "table_7_1_weather");
    assert_eq!(p.geometry().cell_size_x(), 2.0);
}

#[test]
fn bad_values_are_refused_typed_before_any_work() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("never");
    let dem = shared("dem/rme_idaho_50m/dem.asc");
    let refused = |job: TransportJob| {
        let e = transport_job::run(&job, &mut Unattended).unwrap_err();
        assert!(e.is_bad_input(), "{e}");
        assert!(!out.exists(), "{e}: the folder was created");
        e
    };
    let base = short_run(DemSource::file(&dem), Some(out.clone()));
    let e = refused(TransportJob {
        dem: None,
        ..base.clone()
    });
    assert!(matches!(e, TransportJobError::NoScene), "{e}");
    let e = refused(TransportJob {
        scenario: Some("glacier".into()),
        ..base.clone()
    });
    assert!(matches!(e, TransportJobError::Unknown(_)), "{e}");
    let mut hours = base.clone();
    hours.overrides.hours = Some(-3.0);
    let e = refused(hours);
    assert!(matches!(e, TransportJobError::Overridden { .. }), "{e}");
    // Too few layers for the relief: the run's own size check, before the folder.
    let mut layers = base.clone();
    layers.overrides.voxel_layers = Some(3);
    let e = refused(layers);
    assert!(
        matches!(e, TransportJobError::Transport(_)) && e.to_string().contains("voxel_layers"),
        "{e}"
    );
    let e = refused(TransportJob {
        dem: Some(DemSource::file(t.path().join("no_such.asc"))),
        ..base.clone()
    });
    assert!(
        matches!(e, TransportJobError::Dem(_)) && e.to_string().contains("no_such.asc"),
        "{e}"
    );
    let e = refused(TransportJob {
        mesh: Some(TransportMesh {
            margin_m: Some(10.0),
            ..TransportMesh::new(shared("meshes/teapot_assimp.obj"))
        }),
        ..base.clone()
    });
    assert!(matches!(e, TransportJobError::MeshGridOnDem), "{e}");
}

#[test]
fn a_cancelled_run_writes_nothing() {
    let dem = shared("dem/rme_idaho_50m/dem.asc");
    let t = tempfile::tempdir().unwrap();
    // Cancelled after the reading: nothing is run, not even the folder is made.
    let out = t.path().join("early");
    let mut control = Heard {
        cancel_after: Some(1),
        ..Heard::default()
    };
    let e = transport_job::run(
        &short_run(DemSource::file(&dem), Some(out.clone())),
        &mut control,
    )
    .unwrap_err();
    assert!(
        matches!(e, TransportJobError::Cancelled { stage } if stage == "transport"),
        "{e}"
    );
    assert!(!e.is_bad_input() && !out.exists());
    // Cancelled after the run, before its files: the folder it opened is left empty.
    let out = t.path().join("late");
    let mut control = Heard {
        cancel_after: Some(2),
        ..Heard::default()
    };
    let e = transport_job::run(
        &short_run(DemSource::file(&dem), Some(out.clone())),
        &mut control,
    )
    .unwrap_err();
    assert!(
        matches!(e, TransportJobError::Cancelled { stage } if stage == "writing outputs"),
        "{e}"
    );
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 0);
}
