//! Wavefront OBJ input through tobj: `v` positions, `vn` normals, `f` polygons, one object per
//! `o`/`g` (tobj also splits an object where its material changes). Materials are not needed
//! and a missing `.mtl` is ignored.
//!
//! tobj's errors carry no position, so when it rejects a file, `locate_problem` scans the
//! text once more to name the line (and, for an index out of range, the face and the index).
//!
//! Before tobj sees the text, [`prescan`] counts its `v` lines and the corners of its `f` lines
//! in one pass without allocating, and refuses a file beyond the limits of [`crate::read`]
//! (vertices, triangles, corners per face) naming the line. A coordinate beyond
//! [`crate::read::MAX_COORDINATE_M`] once scaled is refused naming its `v` line.

use crate::MeshError;
use crate::read::{MAX_COORDINATE_M, Tally, echo};
use crate::report::RawObject;
use crate::scene::SourceFrame;
use std::path::Path;

/// Counts vertices and face corners line by line, refusing the first line past a limit.
pub(crate) fn prescan(path: &Path, text: &[u8]) -> Result<Tally, MeshError> {
    let mut tally = Tally::default();
    for (n, line) in text.split(|&b| b == b'\n').enumerate() {
        let mut words = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|w| !w.is_empty());
        match words.next() {
            Some(b"v") => tally.add(path, Some(n + 1), 1, 0)?,
            Some(b"f") => tally.add(path, Some(n + 1), 0, words.count() as u64)?,
            _ => {}
        }
    }
    Ok(tally)
}

/// The objects of an OBJ file, in file coordinates.
pub(crate) fn read_raw(path: &Path, frame: &SourceFrame) -> Result<Vec<RawObject>, MeshError> {
    // Read once ourselves: a missing file is an I/O error naming it, and the text is there to
    // locate problems.
    let text = crate::read::read_bytes(path)?;
    prescan(path, &text)?;
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let mut reader = std::io::Cursor::new(&text);
    let loaded = tobj::load_obj_buf(&mut reader, &options, |_| {
        // Materials are not used: an empty library, whatever the file names.
        Ok(Default::default())
    });
    let (models, _materials) = match loaded {
        Ok(m) => m,
        Err(e) => return Err(locate_problem(path, &text, e)),
    };
    // tobj renumbers vertices in order of use: name a bad vertex by its place in the file.
    let non_finite = |v: &[f32]| !v.iter().all(|c| c.is_finite());
    if models.iter().any(|m| non_finite(&m.mesh.positions)) {
        return Err(locate_non_finite(path, &text));
    }
    // The limit in file units (the scale is checked positive and finite by SourceFrame).
    let limit = MAX_COORDINATE_M / frame.metres_per_unit;
    let too_far = |v: &[f32]| v.iter().any(|&c| (c as f64).abs() > limit);
    if models.iter().any(|m| too_far(&m.mesh.positions)) {
        return Err(locate_too_far(path, &text, frame, limit));
    }
    Ok(models
        .into_iter()
        .map(|m| {
            let mesh = m.mesh;
            let positions = triples(&mesh.positions);
            let normals = (!mesh.normals.is_empty()).then(|| triples(&mesh.normals));
            let faces = if mesh.face_arities.is_empty() {
                mesh.indices
                    .chunks(3)
                    .map(|c| c.iter().map(|&i| i as i64).collect())
                    .collect()
            } else {
                let mut start = 0usize;
                mesh.face_arities
                    .iter()
                    .map(|&n| {
                        let end = (start + n as usize).min(mesh.indices.len());
                        let f = mesh.indices[start..end].iter().map(|&i| i as i64).collect();
                        start = end;
                        f
                    })
                    .collect()
            };
            RawObject {
                name: m.name,
                positions,
                normals,
                faces,
            }
        })
        .collect())
}

fn triples(v: &[f32]) -> Vec<[f32; 3]> {
    v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

/// The first `v` line with a NaN or infinite coordinate, as [`MeshError::NonFiniteVertex`]
/// (vertex numbered from 0 in file order, object from the last `o`/`g`).
fn locate_non_finite(path: &Path, text: &[u8]) -> MeshError {
    let text = String::from_utf8_lossy(text);
    let mut object = String::from("unnamed_object");
    let mut vertex = 0usize;
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("o" | "g") => object = echo(&words.collect::<Vec<_>>().join(" ")),
            Some("v") => {
                let mut value = [0.0f32; 3];
                for (c, w) in value.iter_mut().zip(words) {
                    *c = w.parse().unwrap_or(f32::NAN);
                }
                if !value.iter().all(|c| c.is_finite()) {
                    return MeshError::NonFiniteVertex {
                        path: path.to_path_buf(),
                        object: format!("{object} (line {})", n + 1),
                        vertex,
                        value,
                    };
                }
                vertex += 1;
            }
            _ => {}
        }
    }
    MeshError::parse(path, "OBJ", "a non-finite vertex that could not be located")
}

/// The first `v` line with a coordinate beyond `limit` file units, as
/// [`MeshError::CoordinateTooLarge`] (vertex numbered from 0 in file order).
fn locate_too_far(path: &Path, text: &[u8], frame: &SourceFrame, limit: f64) -> MeshError {
    let text = String::from_utf8_lossy(text);
    let mut object = String::from("unnamed_object");
    let mut vertex = 0usize;
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("o" | "g") => object = echo(&words.collect::<Vec<_>>().join(" ")),
            Some("v") => {
                let mut value = [0.0f32; 3];
                for (c, w) in value.iter_mut().zip(words) {
                    *c = w.parse().unwrap_or(0.0);
                }
                if let Some(c) = value.iter().find(|c| (**c as f64).abs() > limit) {
                    return MeshError::CoordinateTooLarge {
                        path: path.to_path_buf(),
                        object,
                        vertex,
                        line: Some(n + 1),
                        value,
                        metres: *c as f64 * frame.metres_per_unit,
                        limit_m: MAX_COORDINATE_M,
                    };
                }
                vertex += 1;
            }
            _ => {}
        }
    }
    MeshError::parse(
        path,
        "OBJ",
        "a vertex beyond the coordinate limit that could not be located",
    )
}

/// Turns a tobj error into a [`MeshError`] naming the line, face and index where possible.
fn locate_problem(path: &Path, text: &[u8], error: tobj::LoadError) -> MeshError {
    let text = String::from_utf8_lossy(text);
    let mut vertices = 0i64;
    let mut faces = 0usize;
    let mut object = String::from("unnamed_object");
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let at = |message: String| MeshError::Parse {
            path: path.to_path_buf(),
            format: "OBJ",
            line: Some(n + 1),
            message,
        };
        match words.next() {
            Some("v") => {
                let coords: Vec<&str> = words.collect();
                if coords.len() < 3 || coords.iter().any(|w| w.parse::<f32>().is_err()) {
                    return at(format!("{error}: vertex {:?}", echo(line.trim())));
                }
                vertices += 1;
            }
            Some(kind @ ("vn" | "vt")) => {
                let needed = if kind == "vn" { 3 } else { 1 };
                let coords: Vec<&str> = words.collect();
                if coords.len() < needed || coords.iter().any(|w| w.parse::<f32>().is_err()) {
                    return at(format!("{error}: {:?}", echo(line.trim())));
                }
            }
            Some("o" | "g") => object = echo(&words.collect::<Vec<_>>().join(" ")),
            Some("f") => {
                let refs: Vec<&str> = words.collect();
                if refs.len() < 3 {
                    return at(format!("{error}: face {faces} has {} corners", refs.len()));
                }
                for r in refs {
                    let Some(Ok(i)) = r.split('/').next().map(str::parse::<i64>) else {
                        return at(format!("{error}: face {faces} corner {:?}", echo(r)));
                    };
                    let resolved = if i < 0 { vertices + i } else { i - 1 };
                    if i == 0 || resolved < 0 || resolved >= vertices {
                        return MeshError::IndexOutOfRange {
                            path: path.to_path_buf(),
                            object,
                            face: faces,
                            index: i,
                            vertex_count: vertices as usize,
                        };
                    }
                }
                faces += 1;
            }
            _ => {}
        }
    }
    MeshError::parse(path, "OBJ", error)
}
