//! # snowscape-editor: the interactive browser editor
//!
//! Cordonnier et al. 2018, Sections 3, 6 and 8: the user "directly paint[s] height changes into
//! the snow layers", explores the phenomena parameters, edits the season's scenario, and
//! triggers avalanches and skiers that are shown as they run (the temporal zoom of Section
//! 3.1). `snowscape serve` runs this crate: a local web server whose page (`web/`, three.js)
//! shows the terrain and its snow in 3D.
//!
//! - [`session`]: the one shared state (a season, its timeline, undo/redo, painted maps);
//!   free of I/O, so it is tested directly.
//! - [`brush`]: add / remove / smooth / set, per layer or on the total depth, and painting of
//!   the avalanche probability and skier areas; [`painted`]: what those maps do in a step.
//! - [`live`]: avalanches and skiers stepped on the server and streamed frame by frame.
//! - [`timeline`]: the snapshots the page plays and scrubs.
//! - [`protocol`]: the JSON messages, their decoder (byte cap, validation) and the rate cap;
//!   [`wire`]: the binary tile frames (16-bit quantised values, dirty tiles only).
//! - [`project`]: the project folder (save, load, exports; no path leaves it).
//! - [`server`]: axum over WebSocket with the session in an actor thread; [`assets`]: the
//!   page's files (embedded, or a folder).

pub mod assets;
pub mod brush;
pub mod live;
pub mod painted;
pub mod project;
pub mod protocol;
pub mod server;
pub mod session;
pub mod timeline;
pub mod wire;

pub use assets::{Assets, BUILD_HINT};
pub use project::{ProjectDir, ProjectError};
pub use server::{ServeConfig, ServeError, serve_blocking};
pub use session::{Exporter, Session};
