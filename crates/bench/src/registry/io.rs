//! Kernels of `snowscape-io`.

use crate::kernel::{Kernel, KernelError};
use snowscape_io::{ReadOptions, read_dem, write_geotiff};
use snowscape_terrain::Grid;
use std::hint::black_box;

/// The raster I/O kernels on `terrain`:
/// - `io/geotiff_round_trip`: write a Deflate-compressed f32 GeoTIFF into a temporary directory
///   and read it back; 16 B/cell (write: read the grid 4 + write the file 4; read: read the
///   file 4 + write the grid 4). Compression and the file system dominate, not memory.
pub fn io_kernels(terrain: &Grid) -> Result<Vec<Kernel>, KernelError> {
    let dir = tempfile::tempdir().map_err(|source| KernelError::Io {
        what: "creating the benchmark's temporary directory",
        source,
    })?;
    let path = dir.path().join("bench.tif");
    let grid = terrain.clone();
    let options = ReadOptions {
        max_cells: grid.data().len().max(snowscape_io::DEFAULT_MAX_CELLS),
        ..ReadOptions::default()
    };
    let cells = grid.data().len();
    Ok(vec![Kernel::new(
        "io/geotiff_round_trip",
        cells,
        16.0,
        move || {
            // The closure owns the directory, which is removed when the kernel is dropped.
            let _keep = &dir;
            write_geotiff(&path, &grid)?;
            black_box(read_dem(&path, &options)?);
            Ok(())
        },
    )])
}
