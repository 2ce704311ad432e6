//! The scene the mesh snow methods work on: named triangle-mesh objects in metres, z up.
//!
//! Every reader converts a file's coordinates into this frame with a [`SourceFrame`] (the
//! file's up axis and its size of one unit in metres), and every writer converts back with the
//! same frame, so a snow mesh lies exactly on the input scene in the user's own tool. Internally
//! x and y are horizontal (for a scene on a DEM: metres east and north of the grid's south-west
//! corner, see [`crate::terrain`]) and z is up: snow falls along -z.

use serde::{Deserialize, Serialize};

/// Which file axis points up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum UpAxis {
    /// y up (glTF, most OBJ and PLY files): file (x, y, z) is scene (x, -z, y).
    #[default]
    Y,
    /// z up (CAD, GIS, Blender's world): file (x, y, z) is scene (x, y, z).
    Z,
}

impl std::str::FromStr for UpAxis {
    type Err = crate::MeshError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "y" | "+y" => Ok(UpAxis::Y),
            "z" | "+z" => Ok(UpAxis::Z),
            _ => Err(crate::MeshError::InvalidOption {
                name: "up axis",
                value: s.to_string(),
                expected: "y or z",
            }),
        }
    }
}

/// The coordinate frame of an input file: its up axis and how many metres one file unit is.
/// Readers map file coordinates into the scene with [`SourceFrame::to_scene`], writers map
/// scene coordinates back with [`SourceFrame::to_file`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SourceFrame {
    /// The file's up axis.
    pub up: UpAxis,
    /// Metres per file unit (1 for files in metres, 0.01 for centimetres); finite and > 0.
    pub metres_per_unit: f64,
}

impl Default for SourceFrame {
    /// y up, metres.
    fn default() -> Self {
        Self {
            up: UpAxis::Y,
            metres_per_unit: 1.0,
        }
    }
}

impl SourceFrame {
    /// A frame, checking that the scale is finite and positive.
    pub fn new(up: UpAxis, metres_per_unit: f64) -> Result<Self, crate::MeshError> {
        if !(metres_per_unit.is_finite() && metres_per_unit > 0.0) {
            return Err(crate::MeshError::InvalidOption {
                name: "scale (metres per file unit)",
                value: metres_per_unit.to_string(),
                expected: "a finite number > 0",
            });
        }
        Ok(Self {
            up,
            metres_per_unit,
        })
    }

    /// Rotates a file direction into the scene frame (no scaling).
    pub fn direction_to_scene(&self, v: [f32; 3]) -> [f32; 3] {
        match self.up {
            UpAxis::Y => [v[0], -v[2], v[1]],
            UpAxis::Z => v,
        }
    }

    /// Rotates a scene direction back into the file frame (no scaling).
    pub fn direction_to_file(&self, v: [f32; 3]) -> [f32; 3] {
        match self.up {
            UpAxis::Y => [v[0], v[2], -v[1]],
            UpAxis::Z => v,
        }
    }

    /// A file position in scene metres.
    pub fn to_scene(&self, p: [f32; 3]) -> [f32; 3] {
        let s = self.metres_per_unit;
        self.direction_to_scene(p).map(|c| (c as f64 * s) as f32)
    }

    /// A scene position in file units and axes.
    pub fn to_file(&self, p: [f32; 3]) -> [f32; 3] {
        let s = self.metres_per_unit;
        self.direction_to_file(p).map(|c| (c as f64 / s) as f32)
    }
}

/// An axis-aligned box, metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Bounds {
    pub min: [f32; 3],
    pub max: [f32; 3],
}

impl Bounds {
    /// The box around `points`, `None` when there are none.
    pub fn of_points<'a>(points: impl IntoIterator<Item = &'a [f32; 3]>) -> Option<Self> {
        let mut it = points.into_iter();
        let first = *it.next()?;
        let mut b = Bounds {
            min: first,
            max: first,
        };
        for p in it {
            b.include(*p);
        }
        Some(b)
    }

    /// Grows the box to hold `p`.
    pub fn include(&mut self, p: [f32; 3]) {
        for (k, c) in p.into_iter().enumerate() {
            self.min[k] = self.min[k].min(c);
            self.max[k] = self.max[k].max(c);
        }
    }

    /// The union of two boxes.
    pub fn union(self, other: Bounds) -> Bounds {
        let mut b = self;
        b.include(other.min);
        b.include(other.max);
        b
    }

    /// Edge lengths along x, y, z.
    pub fn size(&self) -> [f32; 3] {
        [0, 1, 2].map(|k| self.max[k] - self.min[k])
    }

    /// The centre of the box.
    pub fn centre(&self) -> [f32; 3] {
        [0, 1, 2].map(|k| 0.5 * (self.max[k] + self.min[k]))
    }

    /// Length of the diagonal.
    pub fn diagonal(&self) -> f32 {
        let s = self.size();
        (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt()
    }
}

/// The axes and unit of a [`TriMesh`]'s coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum MeshFrame {
    /// The scene frame of the mesh methods (module docs): metres, x and y horizontal (on a
    /// DEM: east and north of the grid's south-west corner), z up. Readers convert into it
    /// with a [`SourceFrame`]; writers convert back.
    #[default]
    Scene,
    /// glTF's frame for a height field (`snowscape-render`'s terrain and snow GLB): metres, x
    /// east, y up, z south, x and z centred on the grid's centre, y above a base altitude
    /// (times an exaggeration).
    Gltf,
}

/// The project's one triangle mesh (after pbrt-v4's `TriangleMesh`): named, with its frame
/// ([`MeshFrame`]), vertex positions, counter-clockwise triangles and optional per-vertex
/// attributes (unit normals, texture coordinates). Every mesh path uses it: a scene object
/// ([`SceneObject`]) is one in the scene frame; the terrain and snow GLB meshes are ones in
/// glTF's; the snow covers build theirs with their own per-vertex records beside it
/// (festenberg's sites and ground points, Fearing's depths and triangle tags); the writers take
/// it with a texture as a [`SnowObject`](crate::write::SnowObject).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TriMesh {
    /// Name from the file (OBJ `o`/`g`, glTF node or mesh name, PLY file stem), or of what
    /// the mesh shows.
    pub name: String,
    /// The axes and unit of `positions` and `normals`.
    pub frame: MeshFrame,
    /// Vertex positions, metres.
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals, one per position, if the file had them or they were computed.
    pub normals: Option<Vec<[f32; 3]>>,
    /// Texture coordinates, one per position, if the mesh has them: glTF convention, u right,
    /// v down from the top left of the image.
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Triangles as indices into `positions`, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
}

/// One named triangle mesh of a scene: a [`TriMesh`] in the scene frame (metres, z up).
pub type SceneObject = TriMesh;

impl TriMesh {
    /// The three corners of triangle `t`.
    #[inline]
    pub fn corners(&self, t: usize) -> [[f32; 3]; 3] {
        self.triangles[t].map(|i| self.positions[i as usize])
    }

    /// Twice the area vector of triangle `t` (cross product of two edges, f64).
    fn area_vector(&self, t: usize) -> [f64; 3] {
        let [a, b, c] = self.corners(t).map(|p| p.map(f64::from));
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        cross(e1, e2)
    }

    /// Area of triangle `t`, square metres.
    pub fn triangle_area(&self, t: usize) -> f32 {
        (0.5 * norm(self.area_vector(t))) as f32
    }

    /// Unit geometric normal of triangle `t` (right-hand rule on its corner order); zero for a
    /// degenerate triangle.
    pub fn triangle_normal(&self, t: usize) -> [f32; 3] {
        let n = self.area_vector(t);
        let l = norm(n);
        if l > 0.0 {
            n.map(|c| (c / l) as f32)
        } else {
            [0.0; 3]
        }
    }

    /// Areas of all triangles, square metres.
    pub fn triangle_areas(&self) -> Vec<f32> {
        (0..self.triangles.len())
            .map(|t| self.triangle_area(t))
            .collect()
    }

    /// Unit normals of all triangles.
    pub fn triangle_normals(&self) -> Vec<[f32; 3]> {
        (0..self.triangles.len())
            .map(|t| self.triangle_normal(t))
            .collect()
    }

    /// Total surface area, square metres.
    pub fn surface_area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| 0.5 * norm(self.area_vector(t)))
            .sum()
    }

    /// The box around the vertices used by triangles (`None` without triangles).
    pub fn bounds(&self) -> Option<Bounds> {
        Bounds::of_points(
            self.triangles
                .iter()
                .flatten()
                .map(|&i| &self.positions[i as usize]),
        )
    }

    /// Moves the object by `d` metres.
    pub fn translate(&mut self, d: [f32; 3]) {
        for p in &mut self.positions {
            for (c, dc) in p.iter_mut().zip(d) {
                *c += dc;
            }
        }
    }
}

/// Named objects in scene metres (z up), with the frame of the file they came from.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Scene {
    pub objects: Vec<SceneObject>,
    /// The frame of the input, used by the writers to convert outputs back.
    pub frame: SourceFrame,
}

impl Scene {
    /// Total triangle count.
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.triangles.len()).sum()
    }

    /// Total vertex count.
    pub fn vertex_count(&self) -> usize {
        self.objects.iter().map(|o| o.positions.len()).sum()
    }

    /// The box around every object (`None` for a scene without triangles).
    pub fn bounds(&self) -> Option<Bounds> {
        self.objects
            .iter()
            .filter_map(SceneObject::bounds)
            .reduce(Bounds::union)
    }

    /// Adds the objects of `other` (their names kept; `other`'s frame is dropped).
    pub fn merge(&mut self, other: Scene) {
        self.objects.extend(other.objects);
    }

    /// The object called `name`, if any.
    pub fn object(&self, name: &str) -> Option<&SceneObject> {
        self.objects.iter().find(|o| o.name == name)
    }
}

pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(crate) fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_round_trip_and_keep_handedness() {
        for up in [UpAxis::Y, UpAxis::Z] {
            let f = SourceFrame::new(up, 0.01).unwrap();
            let p = [100.0, 250.0, -30.0];
            let back = f.to_file(f.to_scene(p));
            for k in 0..3 {
                assert!((back[k] - p[k]).abs() < 1e-3, "{up:?} {back:?}");
            }
        }
        // y up: the file's up (0, 1, 0) is the scene's +z; its +z (towards the viewer) is -y.
        let f = SourceFrame::default();
        assert_eq!(f.direction_to_scene([0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
        assert_eq!(f.direction_to_scene([0.0, 0.0, 1.0]), [0.0, -1.0, 0.0]);
        // A counter-clockwise triangle seen from +y in the file faces +z in the scene.
        let o = SceneObject {
            frame: Default::default(),
            name: "t".into(),
            positions: [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]
                .map(|p| f.to_scene(p))
                .to_vec(),
            normals: None,
            triangles: vec![[0, 1, 2]],
            uvs: None,
        };
        assert_eq!(o.triangle_normal(0), [0.0, 0.0, 1.0]);
        assert!((o.triangle_area(0) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn bad_scales_and_axes_are_errors() {
        assert!(SourceFrame::new(UpAxis::Y, 0.0).is_err());
        assert!(SourceFrame::new(UpAxis::Y, f64::NAN).is_err());
        assert!("x".parse::<UpAxis>().is_err());
        assert_eq!("Z".parse::<UpAxis>().unwrap(), UpAxis::Z);
    }
}
