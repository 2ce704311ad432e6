//! # snowscape-io: raster input and output
//!
//! Every output is written through [`atomic::write_atomic`]: to a temporary file in the target
//! folder, flushed and synced, then renamed over the target, so a crash or an error never leaves
//! a half-written file behind.

pub mod atomic;

pub use atomic::{AtomicWriteError, write_atomic, write_bytes_atomic};
