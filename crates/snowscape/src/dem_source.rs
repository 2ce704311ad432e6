//! A DEM a job is given: a file it reads itself (after its own checks, so that a refused job
//! reads nothing) with the reader's options, or a grid already in memory (the Python
//! package's). The mesh cover stands its mesh on one (`snowscape::cover`), the transport takes
//! one as its scene (`snowscape::transport_job`).

use snowscape_io::{RasterError, ReadOptions, read_terrain};
use snowscape_terrain::Grid;
use std::borrow::Cow;
use std::path::PathBuf;

/// Where a job's DEM comes from.
#[derive(Debug, Clone)]
pub enum DemSource {
    /// A terrain raster, read with [`read_terrain`] (at least 2x2 cells, a surface of valid
    /// cells, altitudes within ±1e5 m).
    File { path: PathBuf, options: ReadOptions },
    /// A grid in memory; `name` names it in reports and errors.
    Grid { name: String, grid: Grid },
}

impl DemSource {
    /// A file read with the default options.
    pub fn file(path: impl Into<PathBuf>) -> Self {
        Self::File {
            path: path.into(),
            options: ReadOptions::default(),
        }
    }

    /// The DEM's name in reports and errors: the file's path, or the grid's name.
    pub fn name(&self) -> String {
        match self {
            Self::File { path, .. } => path.display().to_string(),
            Self::Grid { name, .. } => name.clone(),
        }
    }

    /// The grid: the file read, or the grid given (as it is).
    pub fn read(&self) -> Result<Cow<'_, Grid>, RasterError> {
        match self {
            Self::File { path, options } => read_terrain(path, options).map(Cow::Owned),
            Self::Grid { grid, .. } => Ok(Cow::Borrowed(grid)),
        }
    }
}
