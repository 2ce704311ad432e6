//! Release areas: shapefile polygons, raster masks and the rupture at a point (Cordonnier et
//! al. 2018, Section 6.1). Shapefiles and rasters are written into a temporary folder.

use shapefile::dbase::{FieldValue, Record, TableWriterBuilder};
use shapefile::{Point, PointM, PointZ, Polygon, PolygonM, PolygonRing, PolygonZ, Polyline};
use snowscape_avalanche::{
    AvalancheState, RasterRelease, ReleaseAreaError, ReleaseMask, RuptureParams, release_at_point,
    release_from_raster, release_from_shapefile,
};
use snowscape_io::{RasterFormat, ReadOptions, write_raster};
use snowscape_terrain::{
    Crs, GeoTransform, Grid, GridGeometry, LayeredTerrain, NodataMask, SnowLayer,
};
use std::path::{Path, PathBuf};

/// A 40 x 30 grid of 10 m cells whose north-west corner is at map (1000, 2000), EPSG:31287.
fn dem_geometry() -> GridGeometry {
    GridGeometry::from_transform(
        40,
        30,
        GeoTransform {
            origin_x: 1000.0,
            origin_y: 2000.0,
            pixel_width: 10.0,
            pixel_height: 10.0,
        },
        Some(Crs::Epsg(31287)),
    )
    .unwrap()
}

/// Map coordinates of a corner of the cell grid (col, row count from the north-west corner).
fn at(col: f64, row: f64) -> (f64, f64) {
    (1000.0 + 10.0 * col, 2000.0 - 10.0 * row)
}

fn square(c0: f64, r0: f64, c1: f64, r1: f64) -> Vec<Point> {
    [(c0, r0), (c1, r0), (c1, r1), (c0, r1)]
        .iter()
        .map(|&(c, r)| {
            let (x, y) = at(c, r);
            Point::new(x, y)
        })
        .collect()
}

/// Writes `shapes` with an optional numeric attribute per record.
fn write_polygons(path: &Path, shapes: &[Polygon], field: Option<(&str, &[f64])>) {
    let mut builder = TableWriterBuilder::new().add_character_field("Name".try_into().unwrap(), 20);
    if let Some((name, _)) = field {
        builder = builder.add_numeric_field(name.try_into().unwrap(), 11, 3);
    }
    let mut w = shapefile::Writer::from_path(path, builder).unwrap();
    for (k, s) in shapes.iter().enumerate() {
        let mut rec = Record::default();
        rec.insert(
            "Name".into(),
            FieldValue::Character(Some(format!("rel{k}"))),
        );
        if let Some((name, values)) = field {
            rec.insert(name.into(), FieldValue::Numeric(Some(values[k])));
        }
        w.write_shape_and_record(s, &rec).unwrap();
    }
}

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

#[test]
fn polygon_with_hole_and_several_records_with_thickness() {
    let dir = tmp();
    let p = dir.path().join("rel.shp");
    // Record 0: a 10 x 10 cell square (cols 2..12, rows 3..13) with a 4 x 4 hole (6..10, 7..11).
    // Record 1: a 5 x 4 square (cols 20..25, rows 20..24), thicker.
    let outer = square(2.0, 3.0, 12.0, 13.0);
    let hole = square(6.0, 7.0, 10.0, 11.0);
    let shapes = [
        Polygon::with_rings(vec![PolygonRing::Outer(outer), PolygonRing::Inner(hole)]),
        Polygon::new(PolygonRing::Outer(square(20.0, 20.0, 25.0, 24.0))),
    ];
    write_polygons(&p, &shapes, Some(("thickness", &[1.0, 2.5])));
    let g = dem_geometry();
    let m = release_from_shapefile(&p, &g, &NodataMask::all_valid()).unwrap();
    assert_eq!(m.count(), 100 - 16 + 20);
    assert_eq!(m.area_m2(), 104.0 * 100.0);
    let w = g.width();
    assert!(m.cells[3 * w + 2] && m.cells[12 * w + 11]);
    assert!(
        !m.cells[3 * w + 12] && !m.cells[13 * w + 2],
        "edges are exclusive"
    );
    assert!(!m.cells[8 * w + 8], "the hole is not released");
    let th = m.thickness.as_ref().expect("thickness field");
    assert_eq!(th[3 * w + 2], 1.0);
    assert_eq!(th[21 * w + 22], 2.5);
    assert_eq!(th[8 * w + 8], 0.0);
    let field = m.thickness_field(9.0).unwrap();
    assert_eq!(
        field[21 * w + 22],
        2.5,
        "the file's thickness wins over the default"
    );
    assert!((m.volume_m3(9.0).unwrap() - (84.0 * 1.0 + 20.0 * 2.5) * 100.0).abs() < 1e-9);
    // The .prj is absent: no CRS check, no warning about it.
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
}

#[test]
fn polygon_z_and_m_and_the_d0_field() {
    let dir = tmp();
    let g = dem_geometry();
    let pz = dir.path().join("z.shp");
    {
        let pts: Vec<PointZ> = square(0.0, 0.0, 3.0, 2.0)
            .iter()
            .map(|p| PointZ::new(p.x, p.y, 1500.0, 0.0))
            .collect();
        let builder = TableWriterBuilder::new().add_numeric_field("D0".try_into().unwrap(), 8, 2);
        let mut w = shapefile::Writer::from_path(&pz, builder).unwrap();
        let mut rec = Record::default();
        rec.insert("D0".into(), FieldValue::Numeric(Some(0.75)));
        w.write_shape_and_record(&PolygonZ::new(PolygonRing::Outer(pts)), &rec)
            .unwrap();
    }
    let m = release_from_shapefile(&pz, &g, &NodataMask::all_valid()).unwrap();
    assert_eq!(m.count(), 6);
    assert_eq!(m.thickness.unwrap()[0], 0.75);
    let pm = dir.path().join("m.shp");
    {
        let pts: Vec<PointM> = square(5.0, 5.0, 7.0, 7.0)
            .iter()
            .map(|p| PointM::new(p.x, p.y, 3.0))
            .collect();
        let builder = TableWriterBuilder::new().add_character_field("Name".try_into().unwrap(), 8);
        let mut w = shapefile::Writer::from_path(&pm, builder).unwrap();
        let mut rec = Record::default();
        rec.insert("Name".into(), FieldValue::Character(Some("m".into())));
        w.write_shape_and_record(&PolygonM::new(PolygonRing::Outer(pts)), &rec)
            .unwrap();
    }
    let m = release_from_shapefile(&pm, &g, &NodataMask::all_valid()).unwrap();
    assert_eq!(m.count(), 4);
    assert!(
        m.thickness.is_none(),
        "no thickness field: left to the caller"
    );
}

#[test]
fn overlapping_parts_of_one_record_follow_the_even_odd_rule() {
    // Two outer rings of one record that overlap on a 2 x 2 block: even-odd leaves it out.
    let dir = tmp();
    let p = dir.path().join("overlap.shp");
    let shapes = [Polygon::with_rings(vec![
        PolygonRing::Outer(square(0.0, 0.0, 4.0, 4.0)),
        PolygonRing::Outer(square(2.0, 2.0, 6.0, 6.0)),
    ])];
    write_polygons(&p, &shapes, None);
    let g = dem_geometry();
    let m = release_from_shapefile(&p, &g, &NodataMask::all_valid()).unwrap();
    assert_eq!(m.count(), 16 + 16 - 2 * 4);
    assert!(!m.cells[3 * g.width() + 3]);
}

#[test]
fn nodata_cells_never_release() {
    let dir = tmp();
    let p = dir.path().join("rel.shp");
    write_polygons(
        &p,
        &[Polygon::new(PolygonRing::Outer(square(0.0, 0.0, 4.0, 4.0)))],
        None,
    );
    let g = dem_geometry();
    let mut invalid = vec![false; g.len()];
    invalid[0] = true;
    invalid[1] = true;
    let m = release_from_shapefile(&p, &g, &NodataMask::from_invalid(invalid.clone())).unwrap();
    assert_eq!(m.count(), 14);
    assert!(
        m.warnings.iter().any(|w| w.contains("nodata")),
        "{:?}",
        m.warnings
    );
    // All covered cells nodata: a typed error.
    let p2 = dir.path().join("tiny.shp");
    write_polygons(
        &p2,
        &[Polygon::new(PolygonRing::Outer(square(0.0, 0.0, 2.0, 1.0)))],
        None,
    );
    let e = release_from_shapefile(&p2, &g, &NodataMask::from_invalid(invalid)).unwrap_err();
    assert!(
        matches!(e, ReleaseAreaError::EmptyRelease { covered: 2, .. }),
        "{e}"
    );
}

#[test]
fn bad_shapefiles_are_named() {
    let dir = tmp();
    let g = dem_geometry();
    let all = NodataMask::all_valid();
    // Missing file.
    let missing = dir.path().join("nothing.shp");
    let e = release_from_shapefile(&missing, &g, &all).unwrap_err();
    assert!(
        matches!(
            e,
            ReleaseAreaError::Vector(snowscape_io::vector::VectorError::Shapefile { .. })
        ),
        "{e}"
    );
    assert!(e.to_string().contains("nothing.shp"), "{e}");
    // Not a shapefile at all.
    let junk = dir.path().join("junk.shp");
    std::fs::write(&junk, b"this is not a shapefile").unwrap();
    let e = release_from_shapefile(&junk, &g, &all).unwrap_err();
    assert!(e.to_string().contains("junk.shp"), "{e}");
    // A line, not a polygon.
    let line = dir.path().join("line.shp");
    {
        let builder = TableWriterBuilder::new().add_character_field("Name".try_into().unwrap(), 8);
        let mut w = shapefile::Writer::from_path(&line, builder).unwrap();
        let mut rec = Record::default();
        rec.insert("Name".into(), FieldValue::Character(Some("l".into())));
        w.write_shape_and_record(&Polyline::new(square(0.0, 0.0, 3.0, 3.0)), &rec)
            .unwrap();
    }
    let e = release_from_shapefile(&line, &g, &all).unwrap_err();
    assert!(
        matches!(&e, ReleaseAreaError::NotPolygons { record: 0, shape_type, .. } if shape_type == "Polyline"),
        "{e}"
    );
    assert!(e.to_string().contains("line.shp"), "{e}");
    // A polygon entirely outside the DEM: both extents in the message.
    let out = dir.path().join("outside.shp");
    write_polygons(
        &out,
        &[
            Polygon::new(PolygonRing::Outer(square(1.0, 1.0, 3.0, 3.0))),
            Polygon::new(PolygonRing::Outer(square(100.0, 1.0, 103.0, 3.0))),
        ],
        None,
    );
    let e = release_from_shapefile(&out, &g, &all).unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(e, ReleaseAreaError::PolygonOutsideDem { record: 1, .. }),
        "{msg}"
    );
    assert!(
        msg.contains("x 2000.000..2030.000"),
        "polygon extent: {msg}"
    );
    assert!(
        msg.contains("x 1000.000..1400.000, y 1700.000..2000.000"),
        "DEM extent: {msg}"
    );
    // A sliver that covers no cell centre.
    let sliver = dir.path().join("sliver.shp");
    write_polygons(
        &sliver,
        &[Polygon::new(PolygonRing::Outer(square(1.0, 1.0, 1.4, 1.4)))],
        None,
    );
    let e = release_from_shapefile(&sliver, &g, &all).unwrap_err();
    assert!(
        matches!(e, ReleaseAreaError::NoCellInside { record: 0, .. }),
        "{e}"
    );
    // A bad thickness attribute.
    let bad = dir.path().join("bad.shp");
    write_polygons(
        &bad,
        &[Polygon::new(PolygonRing::Outer(square(1.0, 1.0, 3.0, 3.0)))],
        Some(("thickness", &[-1.0])),
    );
    let e = release_from_shapefile(&bad, &g, &all).unwrap_err();
    assert!(
        matches!(&e, ReleaseAreaError::BadThickness { record: 0, value, .. } if value == "-1"),
        "{e}"
    );
}

#[test]
fn partly_outside_polygons_are_clipped_with_a_warning() {
    let dir = tmp();
    let p = dir.path().join("edge.shp");
    write_polygons(
        &p,
        &[Polygon::new(PolygonRing::Outer(square(
            -3.0, -2.0, 2.0, 2.0,
        )))],
        None,
    );
    let m = release_from_shapefile(&p, &dem_geometry(), &NodataMask::all_valid()).unwrap();
    assert_eq!(m.count(), 4);
    assert!(
        m.warnings.iter().any(|w| w.contains("clipped")),
        "{:?}",
        m.warnings
    );
}

fn write_prj(shp: &Path, text: &str) -> PathBuf {
    let prj = shp.with_extension("prj");
    std::fs::write(&prj, text).unwrap();
    prj
}

#[test]
fn prj_crs_is_checked_against_the_dem() {
    let dir = tmp();
    let p = dir.path().join("rel.shp");
    write_polygons(
        &p,
        &[Polygon::new(PolygonRing::Outer(square(1.0, 1.0, 3.0, 3.0)))],
        None,
    );
    let g = dem_geometry();
    let all = NodataMask::all_valid();
    // The ESRI WKT of the real avaWog/avaKot release files: the same CRS as EPSG:31287.
    write_prj(
        &p,
        r#"PROJCS["MGI_Austria_Lambert",GEOGCS["GCS_MGI",DATUM["D_MGI",SPHEROID["Bessel_1841",6377397.155,299.1528128]],PRIMEM["Greenwich",0.0],UNIT["Degree",0.0174532925199433]],PROJECTION["Lambert_Conformal_Conic"],PARAMETER["False_Easting",400000.0],PARAMETER["False_Northing",400000.0],PARAMETER["Central_Meridian",13.3333333333333],PARAMETER["Standard_Parallel_1",49.0],PARAMETER["Standard_Parallel_2",46.0],PARAMETER["Latitude_Of_Origin",47.5],UNIT["Meter",1.0]]"#,
    );
    let m = release_from_shapefile(&p, &g, &all).unwrap();
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
    // UTM 32N: clearly another CRS, both named.
    write_prj(
        &p,
        r#"PROJCS["WGS_1984_UTM_Zone_32N",GEOGCS["GCS_WGS_1984"],UNIT["Meter",1.0]]"#,
    );
    let e = release_from_shapefile(&p, &g, &all).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, ReleaseAreaError::CrsMismatch { .. }), "{msg}");
    assert!(
        msg.contains("EPSG:32632") && msg.contains("EPSG:31287"),
        "{msg}"
    );
    // Geographic degrees against a projected DEM.
    write_prj(
        &p,
        r#"GEOGCS["Some datum",DATUM["x"],UNIT["Degree",0.0174532925199433]]"#,
    );
    let e = release_from_shapefile(&p, &g, &all).unwrap_err();
    assert!(matches!(e, ReleaseAreaError::CrsMismatch { .. }), "{e}");
    // An unknown projected WKT: cannot tell, warn.
    write_prj(&p, r#"PROJCS["My_Local_Grid",GEOGCS["GCS_WGS_1984"]]"#);
    let m = release_from_shapefile(&p, &g, &all).unwrap();
    assert!(
        m.warnings.iter().any(|w| w.contains("cannot tell")),
        "{:?}",
        m.warnings
    );
    // A DEM without CRS: warn that the comparison was not possible.
    let bare = g.clone().with_crs(None);
    write_prj(&p, "EPSG:31287");
    let m = release_from_shapefile(&p, &bare, &all).unwrap();
    assert!(
        m.warnings.iter().any(|w| w.contains("declares no CRS")),
        "{:?}",
        m.warnings
    );
}

fn write_mask_raster(path: &Path, g: &GridGeometry, values: &[f32]) {
    let grid = Grid::new(g.clone(), values.to_vec(), NodataMask::all_valid()).unwrap();
    write_raster(path, &grid, RasterFormat::Asc).unwrap();
}

#[test]
fn raster_masks_in_the_dem_grid() {
    let dir = tmp();
    let g = dem_geometry();
    let all = NodataMask::all_valid();
    let mut v = vec![0.0f32; g.len()];
    v[5] = 1.0;
    v[6] = 2.5;
    v[7] = -9999.0; // the .asc nodata value: not released
    let p = dir.path().join("mask.asc");
    write_mask_raster(&p, &g, &v);
    let opts = ReadOptions::default();
    let m = release_from_raster(&p, &g, &all, &opts, RasterRelease::Mask).unwrap();
    assert_eq!(m.count(), 2);
    assert!(m.cells[5] && m.cells[6] && !m.cells[7]);
    assert!(m.thickness.is_none());
    let t = release_from_raster(&p, &g, &all, &opts, RasterRelease::Thickness).unwrap();
    assert_eq!(t.thickness.as_ref().unwrap()[6], 2.5);
    // Negative thickness: named error.
    v[9] = -0.5;
    write_mask_raster(&p, &g, &v);
    let e = release_from_raster(&p, &g, &all, &opts, RasterRelease::Thickness).unwrap_err();
    assert!(
        matches!(e, ReleaseAreaError::BadRasterValue { col: 9, row: 0, .. }),
        "{e}"
    );
    // All zero: nothing to release.
    let z = dir.path().join("zero.asc");
    write_mask_raster(&z, &g, &vec![0.0; g.len()]);
    let e = release_from_raster(&z, &g, &all, &opts, RasterRelease::Mask).unwrap_err();
    assert!(matches!(e, ReleaseAreaError::EmptyRelease { .. }), "{e}");
}

#[test]
fn raster_masks_in_another_grid_are_refused_naming_both() {
    let dir = tmp();
    let g = dem_geometry();
    let all = NodataMask::all_valid();
    let opts = ReadOptions::default();
    // Another size.
    let small = GridGeometry::from_transform(20, 30, *g.transform(), g.crs().cloned()).unwrap();
    let p = dir.path().join("small.asc");
    write_mask_raster(&p, &small, &vec![1.0; small.len()]);
    let e = release_from_raster(&p, &g, &all, &opts, RasterRelease::Mask).unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(e, ReleaseAreaError::RasterGridMismatch { .. }),
        "{msg}"
    );
    assert!(msg.contains("20x30") && msg.contains("40x30"), "{msg}");
    // Same size, shifted by half a cell.
    let shifted = GridGeometry::from_transform(
        40,
        30,
        GeoTransform {
            origin_x: 1005.0,
            ..*g.transform()
        },
        g.crs().cloned(),
    )
    .unwrap();
    let p = dir.path().join("shifted.asc");
    write_mask_raster(&p, &shifted, &vec![1.0; shifted.len()]);
    let e = release_from_raster(&p, &g, &all, &opts, RasterRelease::Mask).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("1005") && msg.contains("origin (1000"),
        "{msg}"
    );
    // An unreadable file.
    let e = release_from_raster(
        &dir.path().join("none.asc"),
        &g,
        &all,
        &opts,
        RasterRelease::Mask,
    )
    .unwrap_err();
    assert!(matches!(e, ReleaseAreaError::Raster(_)), "{e}");
}

/// A 60 x 120 grid of 5 m cells: a 35° slope facing south (rows 0..80) running out onto flat
/// ground (rows 80..120), with `unstable` m of unstable snow on 0.5 m of stable snow wherever
/// `where_unstable(col, row)` says.
fn snowy_slope(unstable: f32, where_unstable: impl Fn(usize, usize) -> bool) -> LayeredTerrain {
    let (w, h, dx) = (60usize, 120usize, 5.0);
    let g = GridGeometry::square(w, h, dx).unwrap();
    let tan = 35f64.to_radians().tan();
    let bed = Grid::from_fn(g, |_, r| (tan * dx * (80.0 - r as f64).max(0.0)) as f32);
    let mut t = LayeredTerrain::from_bedrock(bed);
    for i in 0..w * h {
        t.layer_mut(SnowLayer::Stable)[i] = 0.5;
        if where_unstable(i % w, i / w) {
            t.layer_mut(SnowLayer::Unstable)[i] = unstable;
        }
    }
    t
}

/// Map coordinates of the centre of cell (col, row) on a local grid.
fn centre(t: &LayeredTerrain, col: usize, row: usize) -> (f64, f64) {
    t.geometry().cell_centre(col, row)
}

#[test]
fn rupture_extends_downslope_not_upslope_beyond_the_reach() {
    let t = snowy_slope(0.4, |_, _| true);
    let params = RuptureParams::default();
    let (x, y) = centre(&t, 30, 30);
    let r = release_at_point(&t, x, y, &params).unwrap();
    assert_eq!(r.cell, (30, 30));
    assert!((r.unstable_m - 0.4).abs() < 1e-6);
    let reach = 50.0 * 0.4;
    assert!((r.reach_m - reach).abs() < 1e-4);
    let w = t.geometry().width();
    let rows: Vec<(usize, usize)> = (0..r.mask.cells.len())
        .filter(|&i| r.mask.cells[i])
        .map(|i| (i % w, i / w))
        .collect();
    let min_row = rows.iter().map(|p| p.1).min().unwrap();
    let max_row = rows.iter().map(|p| p.1).max().unwrap();
    // Upslope (north): never farther than the reach (20 m = 4 cells).
    assert_eq!(min_row, 26, "upslope extent");
    for &(c, rr) in &rows {
        if rr < 30 {
            let d = 5.0 * ((c as f64 - 30.0).hypot(rr as f64 - 30.0));
            assert!(d <= reach + 1e-9, "cell ({c}, {rr}) upslope at {d} m");
        }
        // Across the slope the band keeps the rupture zone's width.
        assert!((26..=34).contains(&c), "cell ({c}, {rr}) outside the band");
    }
    // Downslope: down the fall line to the foot of the slope (row 79), not onto the flat.
    assert_eq!(max_row, 79, "downslope extent");
    assert!(r.downslope_cells > 0 && r.zone_cells > 0);
    assert_eq!(r.zone_cells + r.downslope_cells, r.mask.count());
    assert!(r.mask.thickness.is_none());
    // The released band on every row below the zone is the zone's widest row: 9 cells.
    for row in 40..80 {
        let n = (0..w).filter(|&c| r.mask.cells[row * w + c]).count();
        assert_eq!(n, 9, "row {row}");
    }
}

#[test]
fn rupture_reach_grows_with_the_unstable_thickness() {
    let params = RuptureParams::default();
    let mut zones = Vec::new();
    for u in [0.1f32, 0.2, 0.4] {
        let t = snowy_slope(u, |_, _| true);
        let (x, y) = centre(&t, 30, 30);
        let r = release_at_point(&t, x, y, &params).unwrap();
        zones.push((r.reach_m, r.zone_cells));
    }
    assert!(
        zones[0].1 < zones[1].1 && zones[1].1 < zones[2].1,
        "{zones:?}"
    );
    assert!((zones[2].0 / zones[0].0 - 4.0).abs() < 1e-5, "{zones:?}");
}

#[test]
fn rupture_stops_where_the_unstable_snow_ends() {
    // Unstable snow only on rows 10..50: the downslope reach ends at row 49.
    let t = snowy_slope(0.4, |_, r| (10..50).contains(&r));
    let (x, y) = centre(&t, 30, 20);
    let r = release_at_point(&t, x, y, &RuptureParams::default()).unwrap();
    let w = t.geometry().width();
    let max_row = (0..r.mask.cells.len())
        .filter(|&i| r.mask.cells[i])
        .map(|i| i / w)
        .max()
        .unwrap();
    assert_eq!(max_row, 49);
}

#[test]
fn no_rupture_without_unstable_snow() {
    let params = RuptureParams::default();
    // Snow-free.
    let bare = snowy_slope(0.0, |_, _| false);
    let mut bare = bare.clone();
    bare.layer_mut(SnowLayer::Stable).fill(0.0);
    let (x, y) = centre(&bare, 30, 30);
    let e = release_at_point(&bare, x, y, &params).unwrap_err();
    assert!(
        matches!(e, ReleaseAreaError::NoUnstableSnow { col: 30, row: 30, unstable_m, .. } if unstable_m == 0.0),
        "{e}"
    );
    // Stable snow only: does not release either.
    let stable = snowy_slope(0.0, |_, _| false);
    let e = release_at_point(&stable, x, y, &params).unwrap_err();
    assert!(matches!(e, ReleaseAreaError::NoUnstableSnow { .. }), "{e}");
    assert!(
        e.to_string().contains("stable snow does not release"),
        "{e}"
    );
    // Outside the DEM.
    let e = release_at_point(&stable, -50.0, 10.0, &params).unwrap_err();
    assert!(matches!(e, ReleaseAreaError::PointOutsideDem { .. }), "{e}");
    let e = release_at_point(&stable, f64::NAN, 10.0, &params).unwrap_err();
    assert!(matches!(e, ReleaseAreaError::PointOutsideDem { .. }), "{e}");
    // Bad parameters are named.
    let bad = RuptureParams {
        reach_per_unstable_m: -1.0,
        ..params
    };
    let e = release_at_point(&stable, x, y, &bad).unwrap_err();
    assert!(e.to_string().contains("reach_per_unstable_m"), "{e}");
}

#[test]
fn rupture_on_nodata_is_refused() {
    let g = GridGeometry::square(10, 10, 5.0).unwrap();
    let mut invalid = vec![false; 100];
    invalid[55] = true;
    let bed = Grid::new(g, vec![0.0; 100], NodataMask::from_invalid(invalid)).unwrap();
    let t = LayeredTerrain::from_bedrock(bed);
    let (x, y) = t.geometry().cell_centre(5, 5);
    let e = release_at_point(&t, x, y, &RuptureParams::default()).unwrap_err();
    assert!(
        matches!(e, ReleaseAreaError::PointOnNodata { col: 5, row: 5, .. }),
        "{e}"
    );
}

#[test]
fn rupture_mask_releases_unstable_snow_and_powder_into_the_flow() {
    let mut t = snowy_slope(0.4, |_, _| true);
    t.layer_mut(SnowLayer::Powder).fill(0.1);
    let (x, y) = centre(&t, 30, 30);
    let r = release_at_point(&t, x, y, &RuptureParams::default()).unwrap();
    let mut state = AvalancheState::from_terrain(&t).unwrap();
    let stable_before = t.snow_volume();
    let v = r.mask.release(&mut t, &mut state).unwrap();
    let expected = r.mask.count() as f64 * 25.0 * 0.5;
    assert!((v - expected).abs() < 1e-3 * expected, "{v} vs {expected}");
    assert!((state.flowing_volume() - v).abs() < 1e-9 * v);
    assert!((stable_before - t.snow_volume() - v).abs() < 1e-3 * v);
    for (i, &c) in r.mask.cells.iter().enumerate() {
        let u = t.layer(SnowLayer::Unstable)[i];
        if c {
            assert_eq!(u, 0.0, "cell {i} kept unstable snow");
            assert_eq!(t.layer(SnowLayer::Stable)[i], 0.5, "stable snow stays");
        } else {
            assert_eq!(u, 0.4);
        }
    }
    assert!(state.thickness_at(30, 30) > 0.49);
    assert_eq!(state.thickness_at(30, 25), 0.0, "beyond the reach upslope");
    assert!(state.thickness_at(30, 70) > 0.49, "downslope reach");
}

#[test]
fn per_cell_thickness_releases_from_the_top_of_the_pack() {
    let mut t = snowy_slope(0.4, |_, _| true);
    let g = t.geometry().clone();
    let n = g.len();
    let mut cells = vec![false; n];
    let mut th = vec![0.0; n];
    // 0.3 m (unstable only) in cell (2, 2); 0.7 m (all unstable and 0.3 of stable) in (1, 2).
    let (a, b) = (g.index(2, 2), g.index(1, 2));
    cells[a] = true;
    th[a] = 0.3;
    cells[b] = true;
    th[b] = 0.7;
    let m = ReleaseMask::from_cells(&g, t.mask(), cells, Some(th)).unwrap();
    let mut state = AvalancheState::from_terrain(&t).unwrap();
    let bed_before = state.bed_at(1, 2);
    let v = m.release(&mut t, &mut state).unwrap();
    assert!((v - 25.0 * 1.0).abs() < 1e-5, "{v}");
    assert!((t.layer(SnowLayer::Unstable)[a] - 0.1).abs() < 1e-6);
    assert_eq!(t.layer(SnowLayer::Unstable)[b], 0.0);
    assert!((t.layer(SnowLayer::Stable)[b] - 0.2).abs() < 1e-6);
    assert!((state.thickness_at(2, 2) - 0.3).abs() < 1e-6);
    assert!((state.thickness_at(1, 2) - 0.7).abs() < 1e-6);
    assert!(
        (bed_before - state.bed_at(1, 2) - 0.3).abs() < 1e-6,
        "bed lowered"
    );
    // Wrong lengths are typed errors.
    let e = ReleaseMask::from_cells(&g, t.mask(), vec![true; 3], None).unwrap_err();
    assert!(
        matches!(e, ReleaseAreaError::LengthMismatch { got: 3, .. }),
        "{e}"
    );
    let e = m.thickness_field(f64::NAN).unwrap_err();
    assert!(e.to_string().contains("default release thickness"), "{e}");
}
