//! # snowscape-editor: the interactive browser editor
//!
//! Cordonnier et al. 2018, Sections 3, 6 and 8: the user "directly paint[s] height changes into
//! the snow layers", explores the phenomena parameters, edits the season's scenario, and
//! triggers avalanches and skiers that are shown as they run (the temporal zoom of Section
//! 3.1). `snowscape serve` runs this crate: a local web server whose page (`web/`, three.js)
//! shows the terrain and its snow in 3D.
//!
//! - [`session`]: the one shared state (a season, its timeline, undo/redo within a byte
//!   budget, painted maps); free of I/O, so it is tested directly.
//! - [`brush`]: add / remove / smooth / set, per layer or on the total depth, and painting of
//!   the avalanche probability and skier areas; [`painted`]: what those maps do in a step.
//! - [`live`]: avalanches and skiers stepped on the server and streamed frame by frame.
//! - [`job`]: long work (season steps, scenario changes, loads, exports) on a worker, with
//!   progress and cancel.
//! - [`timeline`]: the snapshots the page plays and scrubs, packed (about 20 bytes a cell),
//!   within a memory budget.
//! - [`page_scenario`]: the scenario the page sends, read and checked.
//! - [`protocol`]: the JSON messages, their decoder (byte cap, validation) and the rate cap;
//!   [`wire`]: the binary tile frames (16-bit quantised values, dirty tiles only).
//! - [`project`]: the project folder (save, load, exports; no path leaves it).
//! - [`server`]: axum over WebSocket with the session in an actor thread (exports streamed one
//!   at a time, DEM uploads bounded in bytes and in number); [`access`]: who may talk to it
//!   (Host, Origin and `Sec-Fetch-Site`: no cross-site request is served; the per-session
//!   access token for every request for the data, loopback included); [`assets`]: the page's
//!   files (embedded, or a folder).

pub mod access;
pub mod assets;
pub mod brush;
pub mod history;
pub mod job;
pub mod live;
pub mod page_protocol;
pub mod page_scenario;
pub mod painted;
pub mod project;
pub mod protocol;
pub mod server;
pub mod session;
pub mod timeline;
pub mod wire;

pub use assets::{Assets, BUILD_HINT};
pub use project::{ProjectDir, ProjectError};
pub use server::{ServeConfig, ServeError, Served, serve_blocking, serve_until};
pub use session::{Exporter, Session};
