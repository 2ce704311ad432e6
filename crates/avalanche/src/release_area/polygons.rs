//! Release polygons from an ESRI shapefile (with its `.prj` and `.dbf` thickness field),
//! rasterised onto the grid.

use super::*;

/// One record's rings as (x, y) vertex lists.
pub(super) type Rings = Vec<Vec<(f64, f64)>>;

pub(super) fn rings_of(shape: &Shape) -> Option<Rings> {
    fn xy<P>(rings: &[shapefile::PolygonRing<P>], f: impl Fn(&P) -> (f64, f64)) -> Rings {
        rings
            .iter()
            .map(|r| r.points().iter().map(&f).collect())
            .collect()
    }
    match shape {
        Shape::Polygon(p) => Some(xy(p.rings(), |q| (q.x, q.y))),
        Shape::PolygonM(p) => Some(xy(p.rings(), |q| (q.x, q.y))),
        Shape::PolygonZ(p) => Some(xy(p.rings(), |q| (q.x, q.y))),
        _ => None,
    }
}

/// Marks the cells of `geometry` whose centres lie inside `rings` (even-odd rule); returns the
/// number of cell centres inside.
pub(super) fn rasterise(
    rings: &Rings,
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

/// A release thickness attribute (`thickness` or `d0`, any case) of one record.
pub(super) fn thickness_field_name(names: &[String]) -> Option<String> {
    for want in ["thickness", "d0"] {
        if let Some(n) = names.iter().find(|n| n.eq_ignore_ascii_case(want)) {
            return Some(n.clone());
        }
    }
    None
}

pub(super) fn field_number(v: &FieldValue) -> Result<f64, String> {
    match v {
        FieldValue::Numeric(Some(x)) | FieldValue::Double(x) | FieldValue::Currency(x) => Ok(*x),
        FieldValue::Float(Some(x)) => Ok(*x as f64),
        FieldValue::Integer(x) => Ok(*x as f64),
        FieldValue::Character(Some(s)) => s.trim().parse().map_err(|_| format!("{s:?}")),
        FieldValue::Numeric(None) | FieldValue::Float(None) | FieldValue::Character(None) => {
            Err("empty".into())
        }
        other => Err(format!("{other:?}")),
    }
}

/// Per-record release thickness from the `.dbf` beside `shp`, `None` when it has no thickness
/// field (or there is no `.dbf`).
pub(super) fn read_thickness(
    shp: &Path,
    records: usize,
    warnings: &mut Vec<String>,
) -> Result<Option<Vec<f64>>, ReleaseAreaError> {
    let dbf = shp.with_extension("dbf");
    if !dbf.is_file() {
        warnings.push(format!(
            "{}: no attribute table {}: release thickness left to the caller",
            shp.display(),
            dbf.display()
        ));
        return Ok(None);
    }
    let dbf_err = |source| ReleaseAreaError::Dbf {
        path: dbf.clone(),
        source,
    };
    let mut reader = shapefile::dbase::Reader::from_path(&dbf).map_err(dbf_err)?;
    let names: Vec<String> = reader
        .fields()
        .iter()
        .map(|f| f.name().to_string())
        .collect();
    let Some(field) = thickness_field_name(&names) else {
        return Ok(None);
    };
    let rows = reader.read().map_err(dbf_err)?;
    if rows.len() != records {
        return Err(ReleaseAreaError::DbfRecordCount {
            path: dbf,
            records: rows.len(),
            shapes: records,
        });
    }
    let mut out = Vec::with_capacity(rows.len());
    for (k, rec) in rows.iter().enumerate() {
        let bad = |value: String| ReleaseAreaError::BadThickness {
            path: dbf.clone(),
            record: k,
            field: field.clone(),
            value,
        };
        let v = rec.get(&field).ok_or_else(|| bad("missing".into()))?;
        let x = field_number(v).map_err(bad)?;
        if !(x.is_finite() && x > 0.0) {
            return Err(bad(x.to_string()));
        }
        out.push(x);
    }
    Ok(Some(out))
}

/// The CRS of the `.prj` beside `path`, if there is one: its WKT, or the EPSG code at its root.
pub(super) fn read_prj(path: &Path) -> Result<Option<Crs>, ReleaseAreaError> {
    let prj = path.with_extension("prj");
    if !prj.is_file() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&prj).map_err(|source| ReleaseAreaError::Prj {
        path: prj.clone(),
        source,
    })?;
    let t = text.trim().trim_start_matches('\u{feff}');
    if t.is_empty() {
        return Ok(None);
    }
    Ok(Crs::parse(t).map(|c| match &c {
        Crs::Wkt(w) => wkt_facts(w).code.map_or(c.clone(), Crs::Epsg),
        Crs::Epsg(_) => c,
    }))
}

/// Rasterises the polygons of an ESRI shapefile into the DEM's grid (see the module docs: cell
/// centres inside by the even-odd rule, per-record thickness from a `thickness`/`d0` field, CRS
/// from the `.prj`). Nodata cells of `mask` are never released.
pub fn release_from_shapefile(
    path: &Path,
    geometry: &GridGeometry,
    mask: &NodataMask,
) -> Result<ReleaseMask, ReleaseAreaError> {
    let shp_err = |source| ReleaseAreaError::Shapefile {
        path: path.to_path_buf(),
        source,
    };
    let shapes = shapefile::ShapeReader::from_path(path)
        .and_then(|r| r.read())
        .map_err(shp_err)?;
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
        if matches!(shape, Shape::NullShape) {
            warnings.push(format!(
                "{}: record {k} is a null shape, skipped",
                path.display()
            ));
            continue;
        }
        let rings = rings_of(shape).ok_or_else(|| ReleaseAreaError::NotPolygons {
            path: path.to_path_buf(),
            record: k,
            shape_type: shape.shapetype().to_string(),
        })?;
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
        let inside = rasterise(&rings, geometry, |i| {
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
