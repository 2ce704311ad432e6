//! Release polygons from an ESRI shapefile (read by `snowscape-io`: rings, the `.dbf`
//! thickness field, the `.prj` CRS), rasterised onto the grid.

use super::*;
use snowscape_io::vector::{
    ColumnLookup, PolygonRecord, Ring, read_numeric_column, read_polygon_records, read_prj,
};

/// Marks the cells of `geometry` whose centres lie inside `rings` (even-odd rule); returns the
/// number of cell centres inside.
pub(super) fn rasterise(
    rings: &[Ring],
    geometry: &GridGeometry,
    mut mark: impl FnMut(usize),
) -> usize {
    let t = geometry.transform();
    let (w, h) = (geometry.width(), geometry.height());
    let Some(e) = MapExtent::of_points(rings.iter().flatten().copied()) else {
        return 0;
    };
    // Rows whose centre y lies within the polygon's y range.
    let row_of = |y: f64| (t.origin_y - y) / t.pixel_height - 0.5;
    let r0 = row_of(e.y_max).ceil().max(0.0);
    let r1 = row_of(e.y_min).floor().min(h as f64 - 1.0);
    if r1 < r0 {
        return 0;
    }
    let mut count = 0;
    let mut xs: Vec<f64> = Vec::new();
    for row in r0 as usize..=r1 as usize {
        let yc = t.origin_y - (row as f64 + 0.5) * t.pixel_height;
        xs.clear();
        for ring in rings {
            let n = ring.len();
            if n < 3 {
                continue;
            }
            for k in 0..n {
                let (x1, y1) = ring[k];
                let (x2, y2) = ring[(k + 1) % n];
                if (y1 <= yc) != (y2 <= yc) {
                    xs.push(x1 + (yc - y1) * (x2 - x1) / (y2 - y1));
                }
            }
        }
        xs.sort_by(f64::total_cmp);
        for pair in xs.chunks_exact(2) {
            // Columns whose centre x lies in [pair[0], pair[1]).
            let c0 = ((pair[0] - t.origin_x) / t.pixel_width - 0.5)
                .ceil()
                .max(0.0);
            let c1 =
                (((pair[1] - t.origin_x) / t.pixel_width - 0.5).ceil() - 1.0).min(w as f64 - 1.0);
            if c1 < c0 {
                continue;
            }
            for col in c0 as usize..=c1 as usize {
                mark(row * w + col);
                count += 1;
            }
        }
    }
    count
}

/// Per-record release thickness from the `thickness` (or `d0`) field of the `.dbf` beside
/// `shp`, `None` when it has no such field (or there is no `.dbf`); each value a finite
/// number > 0 m.
fn read_thickness(
    shp: &Path,
    records: usize,
    warnings: &mut Vec<String>,
) -> Result<Option<Vec<f64>>, ReleaseAreaError> {
    let column = match read_numeric_column(shp, &["thickness", "d0"], records)? {
        ColumnLookup::NoTable(dbf) => {
            warnings.push(format!(
                "{}: no attribute table {}: release thickness left to the caller",
                shp.display(),
                dbf.display()
            ));
            return Ok(None);
        }
        ColumnLookup::NoField => return Ok(None),
        ColumnLookup::Found(c) => c,
    };
    let mut out = Vec::with_capacity(column.values.len());
    for (k, v) in column.values.iter().enumerate() {
        let bad = |value: String| ReleaseAreaError::BadThickness {
            path: column.path.clone(),
            record: k,
            field: column.field.clone(),
            value,
        };
        let x = v.clone().map_err(bad)?;
        if !(x.is_finite() && x > 0.0) {
            return Err(bad(x.to_string()));
        }
        out.push(x);
    }
    Ok(Some(out))
}

/// Compares the input's CRS with the DEM's: an error when clearly different, a warning when
/// undecidable.
pub(super) fn check_crs(
    path: &Path,
    file_crs: Option<&Crs>,
    dem_crs: Option<&Crs>,
    warnings: &mut Vec<String>,
) -> Result<(), ReleaseAreaError> {
    match (file_crs, dem_crs) {
        (Some(f), Some(d)) => match same_crs(f, d) {
            Some(true) => Ok(()),
            Some(false) => Err(ReleaseAreaError::CrsMismatch {
                path: path.to_path_buf(),
                file_crs: f.to_string(),
                dem_crs: d.to_string(),
            }),
            None => {
                warnings.push(format!(
                    "{}: cannot tell whether its CRS ({f}) is the DEM's ({d}); assuming it is",
                    path.display()
                ));
                Ok(())
            }
        },
        (Some(f), None) => {
            warnings.push(format!(
                "{}: the release area is in {f}, the DEM declares no CRS; assuming they agree",
                path.display()
            ));
            Ok(())
        }
        _ => Ok(()),
    }
}

/// Rasterises the polygons of an ESRI shapefile into the DEM's grid (see the module docs: cell
/// centres inside by the even-odd rule, per-record thickness from a `thickness`/`d0` field, CRS
/// from the `.prj`). Nodata cells of `mask` are never released.
pub fn release_from_shapefile(
    path: &Path,
    geometry: &GridGeometry,
    mask: &NodataMask,
) -> Result<ReleaseMask, ReleaseAreaError> {
    let shapes = read_polygon_records(path)?;
    let mut warnings = Vec::new();
    check_crs(
        path,
        read_prj(path)?.as_ref(),
        geometry.crs(),
        &mut warnings,
    )?;
    let thickness = read_thickness(path, shapes.len(), &mut warnings)?;
    let dem = MapExtent::of_grid(geometry);
    let n = geometry.len();
    let mut cells = vec![false; n];
    let mut th = thickness.as_ref().map(|_| vec![0.0f64; n]);
    let mut polygons = 0;
    for (k, shape) in shapes.iter().enumerate() {
        let rings = match shape {
            PolygonRecord::Null => {
                warnings.push(format!(
                    "{}: record {k} is a null shape, skipped",
                    path.display()
                ));
                continue;
            }
            PolygonRecord::Other(shape_type) => {
                return Err(ReleaseAreaError::NotPolygons {
                    path: path.to_path_buf(),
                    record: k,
                    shape_type: shape_type.clone(),
                });
            }
            PolygonRecord::Polygon(rings) => rings,
        };
        let Some(ext) = MapExtent::of_points(rings.iter().flatten().copied()) else {
            warnings.push(format!(
                "{}: record {k} has no vertex, skipped",
                path.display()
            ));
            continue;
        };
        polygons += 1;
        if !ext.intersects(&dem) {
            return Err(ReleaseAreaError::PolygonOutsideDem {
                path: path.to_path_buf(),
                record: k,
                polygon: ext,
                dem,
            });
        }
        if !dem.contains_extent(&ext) {
            warnings.push(format!(
                "{}: release polygon {k} ({ext}) reaches beyond the DEM ({dem}): clipped",
                path.display()
            ));
        }
        let value = thickness.as_ref().map(|t| t[k]);
        let inside = rasterise(rings, geometry, |i| {
            cells[i] = true;
            if let (Some(t), Some(v)) = (th.as_mut(), value) {
                t[i] = t[i].max(v);
            }
        });
        if inside == 0 {
            let t = geometry.transform();
            return Err(ReleaseAreaError::NoCellInside {
                path: path.to_path_buf(),
                record: k,
                polygon: ext,
                cell_x: t.pixel_width,
                cell_y: t.pixel_height,
            });
        }
    }
    if polygons == 0 {
        return Err(ReleaseAreaError::NoPolygons {
            path: path.to_path_buf(),
            records: shapes.len(),
        });
    }
    finish(path, geometry, mask, cells, th, warnings)
}

/// Drops nodata cells (with a warning), checks something is left.
pub(super) fn finish(
    path: &Path,
    geometry: &GridGeometry,
    mask: &NodataMask,
    cells: Vec<bool>,
    th: Option<Vec<f64>>,
    mut warnings: Vec<String>,
) -> Result<ReleaseMask, ReleaseAreaError> {
    let covered = cells.iter().filter(|&&c| c).count();
    let mut out = ReleaseMask::from_cells(geometry, mask, cells, th)?;
    let kept = out.count();
    if kept == 0 {
        return Err(ReleaseAreaError::EmptyRelease {
            path: path.to_path_buf(),
            covered,
        });
    }
    if kept < covered {
        warnings.push(format!(
            "{}: {} of {covered} covered cells are nodata in the DEM and do not release",
            path.display(),
            covered - kept
        ));
    }
    out.warnings = warnings;
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// Raster masks.
