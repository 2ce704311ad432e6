//! # snowscape-render: previews, time-lapses and glTF export
//!
//! Everything here returns images ([`image::RgbaImage`]) or byte buffers; writing files is the
//! caller's job (the CLI writes them atomically).
//!
//! - [`render_preview`] / [`render_dem`]: north-up top-down previews of a layered terrain or a
//!   plain DEM, lit by a configurable sun (Lambert, sky light, cast shadows; [`shade`]) and
//!   coloured by a [`ColourMode`] ([`colour`]): snow over hypsometric ground, snow layers,
//!   the stability map of Cordonnier et al. 2018 (Fig. 11), or any named map through viridis.
//!   Big grids are box-averaged down to `max_size` first ([`planes`]).
//! - [`ReliefFrames`]: frames of snow moving on a bare DEM (an avalanche), the relief shaded
//!   once and only the snow's box re-shaded per frame ([`frames`]).
//! - [`encode_png`] and [`encode_gif`] (looping time-lapse, one palette for all frames).
//! - [`terrain_glb`]: a binary glTF 2.0 file with the bedrock and snow-surface meshes
//!   ([`mesh`], [`glb`]).

pub mod colour;
pub mod encode;
pub mod error;
pub mod frames;
pub mod glb;
pub mod legend;
pub mod mesh;
pub mod pixel_font;
pub mod planes;
pub mod preview;
pub mod shade;

pub use encode::{encode_gif, encode_png};
pub use error::RenderError;
pub use frames::ReliefFrames;
pub use glb::{GlbOptions, terrain_glb};
pub use legend::with_legend;
pub use preview::{ColourMode, PreviewOptions, render_dem, render_preview, stability_colour};
