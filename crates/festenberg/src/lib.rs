//! # snowscape-festenberg: diffusion-based snow cover on meshes
//!
//! von Festenberg & Gumhold 2011, "Diffusion-Based Snow Cover Generation" (Computer Graphics
//! Forum 30(6)), Section 5, on a [`snowscape_mesh::Scene`]:
//! 1. the scene rasterised from above into every depth layer ([`snowscape_mesh::HeightSpanMap`]),
//!    each snow site with its height `z` and capacity `c` ([`sites`]);
//! 2. snow bridges across gaps shorter than `bmax` (Section 5.1, [`bridges`]);
//! 3. the snow diffusion kernel: initial height `h0` capped by capacity, member selection in
//!    the cylinder of radius `R`, Gaussian weights (Eq. 5), clipped differences (Eq. 6), edge
//!    correction `g1` (Eq. 7), visibility, final height (Eq. 3) ([`kernel`]), found through a
//!    spatial grid so the cost is O(sites x kernel);
//! 4. overhangs by the `g2` offset (Eq. 8, Section 5.3, [`overhang`]);
//! 5. the snow mesh: quads of linked neighbours, concave corners cut, quads split by the
//!    smaller largest angle, vertex normals (Section 5.4.1, [`links`], [`surface_mesh`]);
//! 6. texture coordinates `u` along and `v` across the snow boundary by the marching
//!    propagation of Fig. 10 ([`boundary_uv`]) and a procedural boundary alpha mask ([`mask`]);
//! 7. the growth mode: Eq. 2 iterated with a four-neighbour Laplacian ([`growth`]).
//!
//! [`cover`] runs steps 1-6 and returns a [`snowscape_mesh::SnowObject`] ready for the GLB and
//! OBJ writers; [`grow_cover`] runs the growth mode and hands out one mesh per frame. Results
//! are deterministic and do not depend on the thread count.

pub mod boundary_uv;
pub mod bridges;
pub mod error;
pub mod growth;
pub mod kernel;
pub mod links;
pub mod mask;
pub mod overhang;
pub mod params;
pub mod pipeline;
pub mod sites;
pub mod surface_mesh;

pub use error::FestenbergError;
pub use growth::{GrowthParams, GrowthReport};
pub use params::{CoverParams, Resolved};
pub use pipeline::{CoverStats, SnowCover, cover, grow_cover, prepare_sites};
pub use sites::SiteField;
