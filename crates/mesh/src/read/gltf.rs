//! glTF 2.0 input (`.gltf` JSON with external or `data:` buffers, and `.glb`) through the
//! `gltf` crate, without its `import` feature: buffers are resolved here, and every accessor is
//! checked against its buffer before it is read, so a truncated or inconsistent file is a
//! [`MeshError::Parse`] naming the accessor rather than a panic. The vertices and triangles of
//! every node's mesh (a mesh reused by several nodes counts for each) are checked against the
//! limits of [`crate::read`] before any mesh is read.
//!
//! The default scene (or, without one, the first) is walked from its root nodes; each node
//! with a mesh becomes one object named after the node (else the mesh), with the node's world
//! transform applied to positions and its inverse transpose to normals. The triangle
//! primitives of a mesh (modes TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN) are merged into the
//! object; point and line primitives are skipped.

use crate::MeshError;
use crate::read::Tally;
use crate::report::RawObject;
use base64::Engine;
use glam::{Mat3, Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::{Mode, Semantic};
use std::path::Path;

/// Deepest node hierarchy walked (a deeper or cyclic graph is an error).
const MAX_NODE_DEPTH: usize = 256;

/// The objects of a glTF or GLB file, in file coordinates.
pub(crate) fn read_raw(path: &Path) -> Result<Vec<RawObject>, MeshError> {
    let bytes = crate::read::read_bytes(path)?;
    let bad = |message: String| MeshError::parse(path, "glTF", message);
    check_glb_header(&bytes).map_err(bad)?;
    let gltf = parse(&bytes).map_err(bad)?;
    let buffers = load_buffers(path, &gltf)?;
    let doc = &gltf.document;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| bad("no scene".into()))?;
    // The nodes with a mesh, with their world transforms.
    let mut placed = Vec::new();
    let mut stack: Vec<(gltf::Node, Mat4, usize)> =
        scene.nodes().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    // glTF nodes form trees (a node has at most one parent): more visits than nodes is a
    // cycle or a shared child, refused before it can blow up.
    let mut visits = 0usize;
    while let Some((node, parent, depth)) = stack.pop() {
        visits += 1;
        if visits > doc.nodes().len() {
            return Err(bad(format!(
                "node {} is reached twice: the node graph is not a tree",
                node.index()
            )));
        }
        if depth > MAX_NODE_DEPTH {
            return Err(bad(format!(
                "node hierarchy deeper than {MAX_NODE_DEPTH} (a cycle?) at node {}",
                node.index()
            )));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        for child in node.children() {
            stack.push((child, world, depth + 1));
        }
        if let Some(mesh) = node.mesh() {
            placed.push((node, mesh, world));
        }
    }
    // The limits of crate::read over every placed mesh before any is read: a mesh that many
    // nodes reuse counts once for each (a small file could otherwise load millions of
    // triangles before the count passed the limit).
    let mut tally = Tally::default();
    for (_, mesh, _) in &placed {
        for primitive in mesh.primitives() {
            if let Some((vertices, triangles)) = primitive_counts(&primitive) {
                tally.add(path, None, vertices, 0)?;
                tally.add_triangles(path, triangles)?;
            }
        }
    }
    let mut objects = Vec::with_capacity(placed.len());
    for (node, mesh, world) in placed {
        let name = node
            .name()
            .or(mesh.name())
            .map(str::to_string)
            .unwrap_or_else(|| format!("node{}", node.index()));
        objects.push(read_mesh(path, &mesh, &buffers, world, name)?);
    }
    // Walking with a stack reverses sibling order; keep the file's order.
    objects.reverse();
    Ok(objects)
}

/// Parses a glTF or GLB and validates it as `gltf::Gltf::from_slice` does, checking first
/// what that validation takes for granted: it indexes the accessor a primitive's POSITION
/// names without a bounds check, so an index past the accessors panicked (found by the
/// mutation tests, issue 46).
fn parse(bytes: &[u8]) -> Result<gltf::Gltf, String> {
    use gltf::json::validation::{Checked, Validate};
    // serde quotes the values it could not read, whatever their length.
    let foreign = |e: gltf::Error| {
        snowscape_io::error::clip(&e.to_string(), snowscape_io::error::MAX_FOREIGN_MESSAGE)
    };
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(foreign)?;
    let root = gltf.document.as_json();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive
                .attributes
                .get(&Checked::Valid(gltf::json::mesh::Semantic::Positions));
            if let Some(i) = position
                && i.value() >= root.accessors.len()
            {
                return Err(format!(
                    "mesh {m} primitive {p}: POSITION is accessor {}, but the file has {} accessors",
                    i.value(),
                    root.accessors.len()
                ));
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        errors.push((path(), error))
    });
    if errors.is_empty() {
        Ok(gltf)
    } else {
        Err(foreign(gltf::Error::Validation(errors)))
    }
}

/// Checks a GLB header's declared length before the gltf crate subtracts from it.
fn check_glb_header(bytes: &[u8]) -> Result<(), String> {
    if bytes.len() >= 4 && &bytes[..4] == b"glTF" {
        let Some(len) = bytes.get(8..12) else {
            return Err(format!("GLB header truncated ({} bytes)", bytes.len()));
        };
        let len = u32::from_le_bytes([len[0], len[1], len[2], len[3]]) as usize;
        if len < 20 || len > bytes.len() {
            return Err(format!(
                "GLB header declares {len} bytes, the file has {} (truncated?)",
                bytes.len()
            ));
        }
    }
    Ok(())
}

/// The data of every buffer: the GLB's BIN chunk, a `data:` URI, or a file beside `path`.
fn load_buffers(path: &Path, gltf: &gltf::Gltf) -> Result<Vec<Vec<u8>>, MeshError> {
    let bad = |message: String| MeshError::parse(path, "glTF", message);
    let mut out = Vec::new();
    for buffer in gltf.document.buffers() {
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => gltf.blob.clone().ok_or_else(|| {
                bad(format!(
                    "buffer {} refers to a missing BIN chunk",
                    buffer.index()
                ))
            })?,
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let (_, payload) = uri.split_once(";base64,").ok_or_else(|| {
                    bad(format!("buffer {}: data URI is not base64", buffer.index()))
                })?;
                base64::engine::general_purpose::STANDARD
                    .decode(payload)
                    .map_err(|e| bad(format!("buffer {}: {e}", buffer.index())))?
            }
            gltf::buffer::Source::Uri(uri) => {
                let file = buffer_file(path, buffer.index(), uri)?;
                crate::read::read_bytes(&file)?
            }
        };
        if data.len() < buffer.length() {
            return Err(bad(format!(
                "buffer {} holds {} bytes, the file declares {} (truncated?)",
                buffer.index(),
                data.len(),
                buffer.length()
            )));
        }
        out.push(data);
    }
    Ok(out)
}

/// Decodes the `%XX` escapes of a URI path (`%20` is a space, `%2e%2e` is `..`); `None` for
/// a malformed escape or a result that is not UTF-8.
fn percent_decode(uri: &str) -> Option<String> {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = std::str::from_utf8(b.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// The file a relative buffer URI names, which must lie in the glTF file's folder or below
/// it: no scheme, no absolute path, no `..`, and (symbolic links followed) still inside.
fn buffer_file(path: &Path, buffer: usize, uri: &str) -> Result<std::path::PathBuf, MeshError> {
    let outside = |reason| MeshError::BufferOutsideFolder {
        path: path.to_path_buf(),
        buffer,
        uri: uri.to_string(),
        reason,
    };
    let decoded = percent_decode(uri).ok_or_else(|| outside("a malformed %-escape"))?;
    let rel = Path::new(&decoded);
    if decoded.split('/').next().is_some_and(|s| s.contains(':')) {
        return Err(outside("a URI scheme or drive"));
    }
    if decoded.contains('\\') {
        return Err(outside("a backslash"));
    }
    for c in rel.components() {
        match c {
            std::path::Component::Normal(_) | std::path::Component::CurDir => {}
            std::path::Component::ParentDir => return Err(outside("a '..' step")),
            _ => return Err(outside("an absolute path")),
        }
    }
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let file = folder.join(rel);
    // A symbolic link inside the folder may still point out of it.
    if let (Ok(real_folder), Ok(real_file)) = (folder.canonicalize(), file.canonicalize())
        && !real_file.starts_with(&real_folder)
    {
        return Err(outside("a symbolic link leading out of the folder"));
    }
    Ok(file)
}

/// Checks that `accessor` lies inside its buffer view and buffer, with the expected shape.
fn check_accessor(
    accessor: &gltf::Accessor,
    buffers: &[Vec<u8>],
    shapes: &[(DataType, Dimensions)],
) -> Result<(), String> {
    let i = accessor.index();
    if !shapes.contains(&(accessor.data_type(), accessor.dimensions())) {
        return Err(format!(
            "accessor {i} is {:?} {:?}, expected one of {shapes:?}",
            accessor.data_type(),
            accessor.dimensions()
        ));
    }
    if accessor.sparse().is_some() {
        return Err(format!("accessor {i} is sparse (not supported)"));
    }
    let view = accessor
        .view()
        .ok_or_else(|| format!("accessor {i} has no buffer view"))?;
    let size = accessor.size();
    let stride = view.stride().unwrap_or(size);
    if accessor.count() == 0 || stride < size {
        return Err(format!(
            "accessor {i}: count {} and stride {stride} (element size {size})",
            accessor.count()
        ));
    }
    let end = (accessor.count() - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(size))
        .and_then(|x| x.checked_add(accessor.offset()));
    if end.is_none_or(|e| e > view.length()) {
        return Err(format!(
            "accessor {i} of count {} ({size}-byte elements, stride {stride}, offset {}) runs \
             past the end of buffer view {} ({} bytes)",
            accessor.count(),
            accessor.offset(),
            view.index(),
            view.length()
        ));
    }
    let data = buffers.get(view.buffer().index()).map_or(0, Vec::len);
    if view
        .offset()
        .checked_add(view.length())
        .is_none_or(|e| e > data)
    {
        return Err(format!(
            "buffer view {} ({} bytes from offset {}) runs past the end of buffer {} ({data} bytes)",
            view.index(),
            view.length(),
            view.offset(),
            view.buffer().index()
        ));
    }
    Ok(())
}

/// One node's mesh as an object in file coordinates (the node's world transform applied).
fn read_mesh(
    path: &Path,
    mesh: &gltf::Mesh,
    buffers: &[Vec<u8>],
    world: Mat4,
    name: String,
) -> Result<RawObject, MeshError> {
    let bad = |message: String| MeshError::parse(path, "glTF", message);
    let normal_matrix = {
        let m = Mat3::from_mat4(world);
        (m.determinant().abs() > 1e-20).then(|| m.inverse().transpose())
    };
    let mut object = RawObject {
        name,
        normals: normal_matrix.map(|_| Vec::new()),
        ..Default::default()
    };
    let float3 = [(DataType::F32, Dimensions::Vec3)];
    let index_shapes =
        [DataType::U8, DataType::U16, DataType::U32].map(|d| (d, Dimensions::Scalar));
    for primitive in mesh.primitives() {
        let mode = primitive.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            continue;
        }
        let positions = primitive.get(&Semantic::Positions).ok_or_else(|| {
            bad(format!(
                "mesh {} has a primitive without POSITION",
                mesh.index()
            ))
        })?;
        check_accessor(&positions, buffers, &float3).map_err(bad)?;
        let normals = primitive.get(&Semantic::Normals);
        if let Some(n) = &normals {
            check_accessor(n, buffers, &float3).map_err(bad)?;
        }
        if let Some(ix) = primitive.indices() {
            check_accessor(&ix, buffers, &index_shapes).map_err(bad)?;
        }
        let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
        let base = object.positions.len() as i64;
        let first = object.positions.len();
        let read = reader
            .read_positions()
            .ok_or_else(|| bad(format!("mesh {}: unreadable POSITION", mesh.index())))?;
        object
            .positions
            .extend(read.map(|p| world.transform_point3(Vec3::from(p)).to_array()));
        let count = object.positions.len() - first;
        match (normals.is_some(), normal_matrix, object.normals.as_mut()) {
            (true, Some(m), Some(out)) if out.len() == first => {
                if let Some(read) = reader.read_normals() {
                    out.extend(read.map(|n| (m * Vec3::from(n)).normalize_or_zero().to_array()));
                }
                if out.len() != object.positions.len() {
                    object.normals = None;
                }
            }
            _ => object.normals = None,
        }
        let indices: Vec<i64> = match reader.read_indices() {
            Some(ix) => ix.into_u32().map(|i| base + i as i64).collect(),
            None => (0..count as i64).map(|i| base + i).collect(),
        };
        push_faces(&mut object.faces, &indices, mode);
    }
    Ok(object)
}

/// The vertices of a triangle primitive and the triangles its index list (or its vertices,
/// without one) makes in its mode, as the file declares them; `None` for a point or line
/// primitive, or one without POSITION (refused when it is read).
fn primitive_counts(primitive: &gltf::Primitive) -> Option<(u64, u64)> {
    let mode = primitive.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        return None;
    }
    let positions = primitive.get(&Semantic::Positions)?.count() as u64;
    let corners = primitive
        .indices()
        .map_or(positions, |ix| ix.count() as u64);
    let triangles = match mode {
        Mode::Triangles => corners / 3,
        _ => corners.saturating_sub(2),
    };
    Some((positions, triangles))
}

/// Triangles of an index list in a glTF triangle mode (the checker rejects bad indices).
fn push_faces(faces: &mut Vec<Vec<i64>>, ix: &[i64], mode: Mode) {
    match mode {
        Mode::TriangleStrip => {
            for k in 0..ix.len().saturating_sub(2) {
                // Every other triangle of a strip is flipped to keep the winding.
                faces.push(match k % 2 {
                    0 => vec![ix[k], ix[k + 1], ix[k + 2]],
                    _ => vec![ix[k + 1], ix[k], ix[k + 2]],
                });
            }
        }
        Mode::TriangleFan => {
            for k in 1..ix.len().saturating_sub(1) {
                faces.push(vec![ix[0], ix[k], ix[k + 1]]);
            }
        }
        _ => {
            for c in ix.chunks(3) {
                faces.push(c.to_vec());
            }
        }
    }
}
