//! Polygon layers from ESRI shapefiles (read with the `shapefile` crate): the rings of each
//! `.shp` record, a numeric column of the `.dbf` attribute table and the CRS of the `.prj`
//! sidecar, as plain data the model rasterises (the avalanche release areas).

use shapefile::Shape;
use shapefile::dbase::FieldValue;
use snowscape_terrain::Crs;
use snowscape_terrain::crs_facts::wkt_facts;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// A ring as (x, y) vertices, map units.
pub type Ring = Vec<(f64, f64)>;

/// One record of a shapefile.
#[derive(Debug, Clone, PartialEq)]
pub enum PolygonRecord {
    /// A null shape (no geometry).
    Null,
    /// A polygon (Polygon, PolygonZ or PolygonM): its rings, outer and holes alike (the
    /// even-odd rule tells them apart).
    Polygon(Vec<Ring>),
    /// Another shape type, by name (a point, a line...).
    Other(String),
}

/// Why a shapefile, its attribute table or its `.prj` could not be read.
#[derive(Debug, Error)]
pub enum VectorError {
    /// The shapefile (`.shp`/`.shx`) cannot be read.
    #[error("cannot read shapefile {path}: {source}")]
    Shapefile {
        /// The `.shp` path.
        path: PathBuf,
        /// The reader's error.
        #[source]
        source: shapefile::Error,
    },
    /// The attribute table (`.dbf`) cannot be read.
    #[error("cannot read the attribute table {path} of the shapefile: {source}")]
    Dbf {
        /// The `.dbf` path.
        path: PathBuf,
        /// The reader's error.
        #[source]
        source: shapefile::dbase::Error,
    },
    /// The attribute table has another number of records than the shapefile.
    #[error("{path}: {records} attribute records for {shapes} shapes")]
    DbfRecordCount {
        /// The `.dbf` path.
        path: PathBuf,
        /// Records in the `.dbf`.
        records: usize,
        /// Shapes in the `.shp`.
        shapes: usize,
    },
    /// The first record of a shapefile read as a line is not one.
    #[error("{path}: {what}")]
    NotALine {
        /// The `.shp` path.
        path: PathBuf,
        /// What it is instead.
        what: String,
    },
    /// The `.prj` sidecar cannot be read.
    #[error("cannot read the projection file {path}: {source}")]
    Prj {
        /// The `.prj` path.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
}

/// The records of the shapefile at `path`.
pub fn read_polygon_records(path: &Path) -> Result<Vec<PolygonRecord>, VectorError> {
    let shapes = shapefile::ShapeReader::from_path(path)
        .and_then(|r| r.read())
        .map_err(|source| VectorError::Shapefile {
            path: path.to_path_buf(),
            source,
        })?;
    Ok(shapes.iter().map(record_of).collect())
}

/// The vertices (map coordinates) of the first record of a Polyline(Z/M) shapefile, all its
/// parts joined in order (at least two).
pub fn read_first_polyline(path: &Path) -> Result<Vec<(f64, f64)>, VectorError> {
    let not_a_line = |what: String| VectorError::NotALine {
        path: path.to_path_buf(),
        what,
    };
    let shapes = shapefile::read_shapes(path).map_err(|source| VectorError::Shapefile {
        path: path.to_path_buf(),
        source,
    })?;
    let first = shapes
        .first()
        .ok_or_else(|| not_a_line("no record".into()))?;
    let line: Vec<(f64, f64)> = match first {
        Shape::Polyline(l) => l.parts().iter().flatten().map(|q| (q.x, q.y)).collect(),
        Shape::PolylineZ(l) => l.parts().iter().flatten().map(|q| (q.x, q.y)).collect(),
        Shape::PolylineM(l) => l.parts().iter().flatten().map(|q| (q.x, q.y)).collect(),
        other => {
            return Err(not_a_line(format!(
                "record 0 is not a polyline: {}",
                other.shapetype()
            )));
        }
    };
    if line.len() < 2 {
        return Err(not_a_line(format!(
            "{} vertices, a line needs 2",
            line.len()
        )));
    }
    Ok(line)
}

fn record_of(shape: &Shape) -> PolygonRecord {
    fn xy<P>(rings: &[shapefile::PolygonRing<P>], f: impl Fn(&P) -> (f64, f64)) -> Vec<Ring> {
        rings
            .iter()
            .map(|r| r.points().iter().map(&f).collect())
            .collect()
    }
    match shape {
        Shape::NullShape => PolygonRecord::Null,
        Shape::Polygon(p) => PolygonRecord::Polygon(xy(p.rings(), |q| (q.x, q.y))),
        Shape::PolygonM(p) => PolygonRecord::Polygon(xy(p.rings(), |q| (q.x, q.y))),
        Shape::PolygonZ(p) => PolygonRecord::Polygon(xy(p.rings(), |q| (q.x, q.y))),
        other => PolygonRecord::Other(other.shapetype().to_string()),
    }
}

/// A numeric column of an attribute table: its name and each record's value, or the text
/// that is not a number (`"empty"` for a blank).
#[derive(Debug, Clone, PartialEq)]
pub struct NumericColumn {
    /// The `.dbf` path.
    pub path: PathBuf,
    /// The field's name as the table spells it.
    pub field: String,
    /// One entry per record.
    pub values: Vec<Result<f64, String>>,
}

/// What the `.dbf` beside a shapefile holds of a column.
#[derive(Debug, Clone, PartialEq)]
pub enum ColumnLookup {
    /// There is no `.dbf` beside the shapefile (at this path).
    NoTable(PathBuf),
    /// The table has none of the fields asked for.
    NoField,
    /// The column.
    Found(NumericColumn),
}

/// The first field of `names` (compared case-insensitively, in order) in the `.dbf` beside
/// the shapefile `shp`, checked to hold one value per each of its `records` shapes.
pub fn read_numeric_column(
    shp: &Path,
    names: &[&str],
    records: usize,
) -> Result<ColumnLookup, VectorError> {
    let dbf = shp.with_extension("dbf");
    if !dbf.is_file() {
        return Ok(ColumnLookup::NoTable(dbf));
    }
    let dbf_err = |source| VectorError::Dbf {
        path: dbf.clone(),
        source,
    };
    let mut reader = shapefile::dbase::Reader::from_path(&dbf).map_err(dbf_err)?;
    let fields: Vec<String> = reader
        .fields()
        .iter()
        .map(|f| f.name().to_string())
        .collect();
    let Some(field) = names.iter().find_map(|want| {
        fields
            .iter()
            .find(|n| n.eq_ignore_ascii_case(want))
            .cloned()
    }) else {
        return Ok(ColumnLookup::NoField);
    };
    let rows = reader.read().map_err(dbf_err)?;
    if rows.len() != records {
        return Err(VectorError::DbfRecordCount {
            path: dbf,
            records: rows.len(),
            shapes: records,
        });
    }
    let values = rows
        .iter()
        .map(|rec| rec.get(&field).map_or(Err("missing".into()), number))
        .collect();
    Ok(ColumnLookup::Found(NumericColumn {
        path: dbf,
        field,
        values,
    }))
}

/// A field's value as a number, or the text it holds.
fn number(v: &FieldValue) -> Result<f64, String> {
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

/// The CRS of the `.prj` beside `path`, if there is one: its WKT, or the EPSG code at its root
/// (or recognised from its name).
pub fn read_prj(path: &Path) -> Result<Option<Crs>, VectorError> {
    let prj = path.with_extension("prj");
    if !prj.is_file() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&prj).map_err(|source| VectorError::Prj {
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
