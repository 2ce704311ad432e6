//! # snowscape-mesh: triangle-mesh scenes for the mesh snow methods
//!
//! The shared foundation of Fearing 2000 (snow on meshes by flake shooting and stability) and
//! von Festenberg & Gumhold 2011 (diffusion-based snow cover on a height-span map):
//! - [`read_scene`]: OBJ, PLY and glTF/GLB input into a [`Scene`] (objects in metres, z up),
//!   with the user's up axis and scale ([`SourceFrame`]), checked and reported ([`MeshReport`]);
//! - [`terrain`]: a DEM ([`snowscape_terrain::Grid`]) as a triangle-mesh object, and objects
//!   placed standing on it;
//! - [`SceneBvh`]: ray casting through a compressed wide BVH (obvhs), one ray or a batch on
//!   rayon: first hit, and "is anything above this point";
//! - [`write`](mod@write): snow meshes ([`SnowObject`]) written as GLB or OBJ + MTL + PNG, atomically, in the
//!   input's own axes and units;
//! - [`preview`]: a CPU z-buffer rasteriser for a PNG preview of a scene and its snow.

pub mod error;
pub mod height_span;
pub mod preview;
pub mod raycast;
pub mod read;
pub mod report;
pub mod scene;
pub mod terrain;
pub mod top_view;
pub mod write;

pub use error::MeshError;
pub use height_span::{HeightSpanMap, HeightSpanOptions, SnowSite};
pub use raycast::{Ray, RayHit, SceneBvh};
pub use read::{MeshFormat, read_scene};
pub use report::{MeshReport, ObjectReport};
pub use scene::{Bounds, MeshFrame, Scene, SceneObject, SourceFrame, TriMesh, UpAxis};
pub use write::SnowObject;
