//! Checking and cleaning what a reader found, and the [`MeshReport`] that says what was done.
//!
//! Rules, the same for every format:
//! - a NaN or infinite vertex coordinate is an error naming the file, object and vertex
//!   ([`MeshError::NonFiniteVertex`]); so is a face index outside the object's vertices
//!   ([`MeshError::IndexOutOfRange`], naming the face and the index);
//! - a degenerate triangle (a repeated corner, or an area below 1e-10 of its longest edge
//!   squared: collinear corners) is dropped and counted; so is a face with fewer than three
//!   corners. Polygons with more than three corners are split into a fan;
//! - a triangle repeating an earlier one's corners in the same cyclic order (on positions welded
//!   by exact equality) is dropped and counted as a duplicate (one linear pass with a hash set);
//! - a coordinate beyond [`crate::read::MAX_COORDINATE_M`] in scene metres is
//!   [`MeshError::CoordinateTooLarge`], and a scene whose extent is more than
//!   [`crate::read::MAX_EXTENT_TO_FEATURE`] times its smallest triangle is
//!   [`MeshError::ExtentTooLarge`] (both name the object and the vertex or triangle);
//! - open edges (used by one triangle) and non-manifold edges (used by three or more) are
//!   counted, not repaired: both snow methods work on open and non-manifold scenes. Edges are
//!   counted on positions welded by exact equality, so a vertex split for UV or normal seams
//!   does not open the mesh;
//! - a file with no usable triangle at all is [`MeshError::EmptyMesh`].

use crate::MeshError;
use crate::scene::{SceneObject, SourceFrame, cross, norm};
use serde::Serialize;
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// What a reader found in one object, in file coordinates, before checks.
#[derive(Debug, Clone, Default)]
pub(crate) struct RawObject {
    pub name: String,
    pub positions: Vec<[f32; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
    /// Faces as vertex indices (any count; signed so that bad files can be reported).
    pub faces: Vec<Vec<i64>>,
}

/// What was found and done in one object.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ObjectReport {
    pub name: String,
    /// Vertices in the file.
    pub vertices: usize,
    /// Faces in the file (polygons count once).
    pub faces: usize,
    /// Triangles kept.
    pub triangles: usize,
    /// Degenerate triangles (and faces of fewer than 3 corners) dropped.
    pub degenerate_dropped: usize,
    /// Triangles repeating an earlier triangle of the object (same corners, same order) dropped.
    pub duplicates_dropped: usize,
    /// Polygons of more than three corners split into triangle fans.
    pub polygons_split: usize,
    /// Edges used by exactly one triangle (holes, open borders).
    pub open_edges: usize,
    /// Edges used by three or more triangles.
    pub non_manifold_edges: usize,
    /// Connected pieces (triangles sharing welded vertices): several teapots in one object
    /// count as several.
    pub components: usize,
    /// Whether the file's normals were dropped (non-finite, or a count not matching positions).
    pub normals_dropped: bool,
}

impl ObjectReport {
    /// Whether the object is a closed 2-manifold (no open and no non-manifold edge).
    pub fn is_closed_manifold(&self) -> bool {
        self.open_edges == 0 && self.non_manifold_edges == 0
    }
}

/// What a reader found in a file: one [`ObjectReport`] per object kept.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Default)]
pub struct MeshReport {
    pub objects: Vec<ObjectReport>,
    /// Objects without any usable triangle, left out of the scene.
    pub empty_objects_dropped: usize,
}

impl MeshReport {
    /// Sum of a per-object count.
    fn total(&self, f: impl Fn(&ObjectReport) -> usize) -> usize {
        self.objects.iter().map(f).sum()
    }
    pub fn vertices(&self) -> usize {
        self.total(|o| o.vertices)
    }
    pub fn faces(&self) -> usize {
        self.total(|o| o.faces)
    }
    pub fn triangles(&self) -> usize {
        self.total(|o| o.triangles)
    }
    pub fn degenerate_dropped(&self) -> usize {
        self.total(|o| o.degenerate_dropped)
    }
    pub fn duplicates_dropped(&self) -> usize {
        self.total(|o| o.duplicates_dropped)
    }
    pub fn open_edges(&self) -> usize {
        self.total(|o| o.open_edges)
    }
    pub fn non_manifold_edges(&self) -> usize {
        self.total(|o| o.non_manifold_edges)
    }
    pub fn components(&self) -> usize {
        self.total(|o| o.components)
    }
}

/// Relative area below which a triangle counts as degenerate: |e1 x e2| < this x (longest edge)^2.
pub const DEGENERATE_RELATIVE_AREA: f64 = 1e-10;

/// Checks `raw`, converts it into the scene frame and reports what was done. `Ok(None)` for an
/// object without usable triangles (counted by the caller).
pub(crate) fn check_object(
    path: &Path,
    raw: RawObject,
    frame: &SourceFrame,
) -> Result<(Option<SceneObject>, ObjectReport), MeshError> {
    let n = raw.positions.len();
    for (vertex, p) in raw.positions.iter().enumerate() {
        let scaled = frame.to_scene(*p);
        if !(p.iter().all(|c| c.is_finite()) && scaled.iter().all(|c| c.is_finite())) {
            return Err(MeshError::NonFiniteVertex {
                path: path.to_path_buf(),
                object: crate::read::echo(&raw.name),
                vertex,
                value: *p,
            });
        }
        if let Some(c) = scaled
            .iter()
            .find(|c| (**c as f64).abs() > crate::read::MAX_COORDINATE_M)
        {
            return Err(MeshError::CoordinateTooLarge {
                path: path.to_path_buf(),
                object: crate::read::echo(&raw.name),
                vertex,
                line: None,
                value: *p,
                metres: *c as f64,
                limit_m: crate::read::MAX_COORDINATE_M,
            });
        }
    }
    let mut report = ObjectReport {
        name: raw.name.clone(),
        vertices: n,
        faces: raw.faces.len(),
        triangles: 0,
        degenerate_dropped: 0,
        duplicates_dropped: 0,
        polygons_split: 0,
        open_edges: 0,
        non_manifold_edges: 0,
        components: 0,
        normals_dropped: false,
    };
    let positions: Vec<[f32; 3]> = raw.positions.iter().map(|p| frame.to_scene(*p)).collect();
    let mut triangles = Vec::with_capacity(raw.faces.len());
    let weld = weld_ids(&positions);
    let mut seen: HashSet<[u32; 3]> = HashSet::with_capacity(raw.faces.len());
    for (face, corners) in raw.faces.iter().enumerate() {
        for &index in corners {
            if index < 0 || index as u64 >= n as u64 {
                return Err(MeshError::IndexOutOfRange {
                    path: path.to_path_buf(),
                    object: crate::read::echo(&raw.name),
                    face,
                    index,
                    vertex_count: n,
                });
            }
        }
        if corners.len() < 3 {
            report.degenerate_dropped += 1;
            continue;
        }
        if corners.len() > 3 {
            report.polygons_split += 1;
        }
        for k in 1..corners.len() - 1 {
            let t = [corners[0], corners[k], corners[k + 1]].map(|i| i as u32);
            if is_degenerate(&positions, t) {
                report.degenerate_dropped += 1;
            } else if !seen.insert(rotated(t.map(|i| weld[i as usize]))) {
                report.duplicates_dropped += 1;
            } else {
                triangles.push(t);
            }
        }
    }
    report.triangles = triangles.len();
    let topology = count_edges(&positions, &triangles);
    report.open_edges = topology.open_edges;
    report.non_manifold_edges = topology.non_manifold_edges;
    report.components = topology.components;
    let normals = raw.normals.and_then(|ns| {
        let ok = ns.len() == n && ns.iter().all(|v| v.iter().all(|c| c.is_finite()));
        report.normals_dropped = !ok;
        ok.then(|| {
            ns.iter()
                .map(|v| normalise(frame.direction_to_scene(*v)))
                .collect()
        })
    });
    if triangles.is_empty() {
        return Ok((None, report));
    }
    Ok((
        Some(SceneObject {
            frame: Default::default(),
            name: raw.name,
            positions,
            normals,
            triangles,
            uvs: None,
        }),
        report,
    ))
}

/// Whether triangle `t` has a repeated corner or (nearly) collinear corners.
pub(crate) fn is_degenerate(positions: &[[f32; 3]], t: [u32; 3]) -> bool {
    if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
        return true;
    }
    let [a, b, c] = t.map(|i| positions[i as usize].map(f64::from));
    let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let (e1, e2, e3) = (sub(b, a), sub(c, a), sub(c, b));
    let longest = norm(e1).max(norm(e2)).max(norm(e3));
    let area2 = norm(cross(e1, e2));
    area2.is_nan() || area2 <= DEGENERATE_RELATIVE_AREA * longest * longest
}

/// `t` rotated so that its smallest index comes first (same cyclic order: same orientation).
fn rotated(t: [u32; 3]) -> [u32; 3] {
    let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
}

/// An id per position, equal for exactly equal positions (+0.0 and -0.0 alike).
fn weld_ids(positions: &[[f32; 3]]) -> Vec<u32> {
    let mut weld: HashMap<[u32; 3], u32> = HashMap::with_capacity(positions.len());
    positions
        .iter()
        .map(|p| {
            let key = p.map(|c| if c == 0.0 { 0 } else { c.to_bits() });
            let next = weld.len() as u32;
            *weld.entry(key).or_insert(next)
        })
        .collect()
}

/// The smallest kept triangle of the scene against its extent: [`MeshError::ExtentTooLarge`]
/// beyond [`crate::read::MAX_EXTENT_TO_FEATURE`].
fn check_extent(path: &Path, scene: &crate::Scene) -> Result<(), MeshError> {
    let Some(b) = scene.bounds() else {
        return Ok(());
    };
    let s = b.size().map(f64::from);
    let extent = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
    let mut smallest: Option<(f64, usize, usize)> = None;
    for (k, o) in scene.objects.iter().enumerate() {
        for t in 0..o.triangles.len() {
            let [a, b, c] = o.corners(t).map(|p| p.map(f64::from));
            let len = |p: [f64; 3], q: [f64; 3]| norm([p[0] - q[0], p[1] - q[1], p[2] - q[2]]);
            let longest = len(a, b).max(len(b, c)).max(len(c, a));
            if smallest.is_none_or(|(l, _, _)| longest < l) {
                smallest = Some((longest, k, t));
            }
        }
    }
    let limit = crate::read::MAX_EXTENT_TO_FEATURE;
    match smallest {
        Some((feature, k, t)) if extent > limit * feature => Err(MeshError::ExtentTooLarge {
            path: path.to_path_buf(),
            object: crate::read::echo(&scene.objects[k].name),
            triangle: t,
            extent_m: extent,
            feature_m: feature,
            ratio: extent / feature,
            limit,
        }),
        _ => Ok(()),
    }
}

/// Edge and piece counts of a triangle set.
pub(crate) struct Topology {
    pub open_edges: usize,
    pub non_manifold_edges: usize,
    pub components: usize,
}

/// Open and non-manifold edges and connected pieces of `triangles`, on positions welded by
/// exact equality.
pub(crate) fn count_edges(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Topology {
    let ids = weld_ids(positions);
    let welded = ids.iter().copied().max().map_or(0, |m| m + 1);
    let mut parent: Vec<u32> = (0..welded).collect();
    fn root(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            let up = parent[parent[i as usize] as usize];
            parent[i as usize] = up;
            i = up;
        }
        i
    }
    let mut edges: HashMap<(u32, u32), u32> = HashMap::with_capacity(triangles.len() * 2);
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (ids[t[k] as usize], ids[t[(k + 1) % 3] as usize]);
            if a != b {
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            parent[ra.max(rb) as usize] = ra.min(rb);
        }
    }
    let mut roots: Vec<u32> = triangles
        .iter()
        .map(|t| root(&mut parent, ids[t[0] as usize]))
        .collect();
    roots.sort_unstable();
    roots.dedup();
    Topology {
        open_edges: edges.values().filter(|&&c| c == 1).count(),
        non_manifold_edges: edges.values().filter(|&&c| c > 2).count(),
        components: roots.len(),
    }
}

fn normalise(v: [f32; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if l > 0.0 { v.map(|c| c / l) } else { v }
}

/// Checks every raw object of a file and gathers the scene and its report.
pub(crate) fn check_objects(
    path: &Path,
    raws: Vec<RawObject>,
    frame: &SourceFrame,
) -> Result<(crate::Scene, MeshReport), MeshError> {
    let mut scene = crate::Scene {
        objects: Vec::new(),
        frame: *frame,
    };
    let mut report = MeshReport::default();
    let raw_count = raws.len();
    for raw in raws {
        let (object, r) = check_object(path, raw, frame)?;
        match object {
            Some(o) => {
                scene.objects.push(o);
                report.objects.push(r);
            }
            None => report.empty_objects_dropped += 1,
        }
    }
    if scene.objects.is_empty() {
        return Err(MeshError::EmptyMesh {
            path: path.to_path_buf(),
            reason: format!("{raw_count} object(s), none with a non-degenerate triangle"),
        });
    }
    check_extent(path, &scene)?;
    Ok((scene, report))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn raw(positions: Vec<[f32; 3]>, faces: Vec<Vec<i64>>) -> RawObject {
        RawObject {
            name: "o".into(),
            positions,
            normals: None,
            faces,
        }
    }

    fn tetrahedron() -> RawObject {
        raw(
            vec![[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]],
            vec![vec![0, 2, 1], vec![0, 1, 3], vec![1, 2, 3], vec![2, 0, 3]],
        )
    }

    #[test]
    fn closed_tetrahedron_has_no_open_edges() {
        let (o, r) = check_object(Path::new("t"), tetrahedron(), &SourceFrame::default()).unwrap();
        assert_eq!(o.unwrap().triangles.len(), 4);
        assert!(r.is_closed_manifold(), "{r:?}");
        assert_eq!(r.components, 1);
        // Two tetrahedra in one object: two pieces.
        let mut two = tetrahedron();
        two.positions.extend(
            tetrahedron()
                .positions
                .iter()
                .map(|p| [p[0] + 5.0, p[1], p[2]]),
        );
        two.faces.extend(
            tetrahedron()
                .faces
                .iter()
                .map(|f| f.iter().map(|i| i + 4).collect()),
        );
        let (_, r) = check_object(Path::new("t"), two, &SourceFrame::default()).unwrap();
        assert_eq!((r.components, r.open_edges), (2, 0));
    }

    #[test]
    fn holes_fins_and_degenerates_are_counted() {
        let mut t = tetrahedron();
        t.faces.pop(); // a hole: 3 open edges
        t.faces.push(vec![0, 1, 1]); // repeated corner
        t.positions.push([2.0, 0.0, 0.0]);
        t.faces.push(vec![0, 1, 4]); // collinear: zero area
        t.faces.push(vec![0, 1]); // not a face
        t.positions.push([0.5, -1.0, 0.5]);
        t.faces.push(vec![0, 1, 5]); // third triangle on edge 0-1: a fin
        let (_, r) = check_object(Path::new("t"), t, &SourceFrame::default()).unwrap();
        assert_eq!(r.degenerate_dropped, 3);
        assert_eq!(r.triangles, 4);
        assert_eq!(r.non_manifold_edges, 1);
        // The hole's three edges, plus the fin's two free edges.
        assert_eq!(r.open_edges, 5);
    }

    #[test]
    fn nan_and_bad_indices_name_the_vertex_and_face() {
        let mut t = tetrahedron();
        t.positions[2][1] = f32::NAN;
        match check_object(Path::new("bad.obj"), t, &SourceFrame::default()) {
            Err(MeshError::NonFiniteVertex {
                vertex: 2, path, ..
            }) => {
                assert_eq!(path, Path::new("bad.obj"))
            }
            other => panic!("{other:?}"),
        }
        let mut t = tetrahedron();
        t.faces[3] = vec![2, 0, 9];
        match check_object(Path::new("bad.obj"), t, &SourceFrame::default()) {
            Err(MeshError::IndexOutOfRange {
                face: 3,
                index: 9,
                vertex_count: 4,
                ..
            }) => {}
            other => panic!("{other:?}"),
        }
        let mut t = tetrahedron();
        t.faces[0] = vec![-1, 0, 1];
        assert!(matches!(
            check_object(Path::new("b"), t, &SourceFrame::default()),
            Err(MeshError::IndexOutOfRange { index: -1, .. })
        ));
    }

    #[test]
    fn only_degenerate_triangles_is_an_empty_mesh() {
        let t = raw(
            vec![[0., 0., 0.], [1., 0., 0.], [2., 0., 0.]],
            vec![vec![0, 1, 2]],
        );
        let e = check_objects(Path::new("flat.obj"), vec![t], &SourceFrame::default());
        assert!(matches!(e, Err(MeshError::EmptyMesh { .. })), "{e:?}");
        let e = check_objects(Path::new("none.obj"), vec![], &SourceFrame::default());
        assert!(matches!(e, Err(MeshError::EmptyMesh { .. })));
    }

    #[test]
    fn quads_become_two_triangles() {
        let q = raw(
            vec![[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
            vec![vec![0, 1, 2, 3]],
        );
        let (o, r) = check_object(Path::new("q"), q, &SourceFrame::default()).unwrap();
        assert_eq!(o.unwrap().triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!((r.polygons_split, r.open_edges), (1, 4));
    }
}
