//! Stanford PLY input through ply-rs-bw (ASCII, binary little and big endian): the `vertex`
//! element's `x y z` (any numeric type) and optional `nx ny nz`, and the `face` element's
//! `vertex_indices` (or `vertex_index`) lists. A PLY file is one object, named after the file.
//! A truncated file or a face list of the wrong type is a [`MeshError::Parse`] (with the line
//! for ASCII files).
//!
//! The header's element counts are checked against the limits of [`crate::read`] before the
//! body is parsed (a 100-byte header may announce four billion vertices), naming the header line;
//! each face's corner count is checked as it is converted.

use crate::MeshError;
use crate::read::{MAX_TRIANGLES, MAX_VERTICES, Tally};
use crate::report::RawObject;
use ply_rs_bw::ply::{DefaultElement, Property};
use std::path::Path;

/// The single object of a PLY file, in file coordinates.
pub(crate) fn read_raw(path: &Path) -> Result<Vec<RawObject>, MeshError> {
    let bytes = crate::read::read_bytes(path)?;
    check_header(path, &bytes)?;
    let parser = ply_rs_bw::parser::Parser::<DefaultElement>::new();
    let ply = parser
        .read_ply(&mut std::io::Cursor::new(&bytes))
        .map_err(|e| MeshError::Parse {
            path: path.to_path_buf(),
            format: "PLY",
            line: e.line(),
            // ply-rs quotes the token it could not parse, whatever its length.
            message: snowscape_io::error::clip(
                &e.to_string(),
                snowscape_io::error::MAX_FOREIGN_MESSAGE,
            ),
        })?;
    let bad = |message: String| MeshError::parse(path, "PLY", message);
    let vertices = ply
        .payload
        .get("vertex")
        .ok_or_else(|| bad("no `vertex` element".into()))?;
    let scalar = |v: &DefaultElement, key: &str| v.get(key).and_then(Property::to_f32_lossy);
    let mut positions = Vec::with_capacity(vertices.len());
    for (i, v) in vertices.iter().enumerate() {
        let p = ["x", "y", "z"].map(|k| scalar(v, k));
        match p {
            [Some(x), Some(y), Some(z)] => positions.push([x, y, z]),
            _ => return Err(bad(format!("vertex {i} lacks a numeric x, y or z"))),
        }
    }
    let normals: Option<Vec<[f32; 3]>> = vertices
        .iter()
        .map(|v| match ["nx", "ny", "nz"].map(|k| scalar(v, k)) {
            [Some(x), Some(y), Some(z)] => Some([x, y, z]),
            _ => None,
        })
        .collect();
    let mut faces = Vec::new();
    let mut tally = Tally::default();
    if let Some(elements) = ply.payload.get("face") {
        faces.reserve(elements.len());
        for (i, f) in elements.iter().enumerate() {
            let list = f
                .get("vertex_indices")
                .or_else(|| f.get("vertex_index"))
                .ok_or_else(|| bad(format!("face {i} has no vertex_indices list")))?;
            let face = index_list(list)
                .ok_or_else(|| bad(format!("face {i}: vertex_indices is not an integer list")))?;
            tally.add(path, None, 0, face.len() as u64)?;
            faces.push(face);
        }
    }
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "ply".into());
    Ok(vec![RawObject {
        name,
        positions,
        normals: normals.filter(|n| !n.is_empty()),
        faces,
    }])
}

/// The indices of an integer list property, widened to i64.
fn index_list(p: &Property) -> Option<Vec<i64>> {
    fn widen<T: Copy + Into<i64>>(v: &[T]) -> Vec<i64> {
        v.iter().map(|&x| x.into()).collect()
    }
    Some(match p {
        Property::ListChar(v) => widen(v),
        Property::ListUChar(v) => widen(v),
        Property::ListShort(v) => widen(v),
        Property::ListUShort(v) => widen(v),
        Property::ListInt(v) => widen(v),
        Property::ListUInt(v) => widen(v),
        _ => return None,
    })
}

/// Refuses a header whose `element vertex N` or `element face N` passes the limits of
/// [`crate::read`], naming the header line (a face is at least one triangle).
fn check_header(path: &Path, bytes: &[u8]) -> Result<(), MeshError> {
    let end = bytes
        .windows(10)
        .position(|w| w == b"end_header")
        .unwrap_or(bytes.len().min(1 << 20));
    for (n, line) in bytes[..end].split(|&b| b == b'\n').enumerate() {
        let line = String::from_utf8_lossy(line);
        let words: Vec<&str> = line.split_whitespace().collect();
        let (what, limit) = match words.as_slice() {
            ["element", "vertex", _] => ("vertex count", MAX_VERTICES),
            ["element", "face", _] => ("face count", MAX_TRIANGLES),
            _ => continue,
        };
        let Ok(value) = words[2].parse::<u64>() else {
            continue; // ply-rs names the malformed header line
        };
        if value > limit {
            return Err(MeshError::TooLarge {
                path: path.to_path_buf(),
                line: Some(n + 1),
                what,
                value,
                limit,
            });
        }
    }
    Ok(())
}
