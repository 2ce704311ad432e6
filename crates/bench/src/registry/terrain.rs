//! Kernels of `snowscape-terrain`, with their memory-traffic models (bytes per cell, reads plus
//! writes of the arrays each call streams; neighbour re-reads are assumed to hit the cache).

use crate::kernel::{Kernel, KernelError};
use crate::stencil;
use snowscape_terrain::procedural::{AlpineParams, alpine};
use snowscape_terrain::{Grid, surface};
use std::hint::black_box;

/// The procedural alpine terrain every kernel runs on (seed 1, 10 m cells).
pub fn sample_terrain(size: usize) -> Result<Grid, KernelError> {
    Ok(alpine(&AlpineParams {
        size,
        ..AlpineParams::default()
    })?)
}

/// The terrain kernels on `terrain` (`size`² cells):
/// - `terrain/alpine`: procedural generation; 20 B/cell (landform write 4, cliff pass read 4
///   + write 4, clamp read 4 + write 4); compute-bound, so its fraction stays small.
/// - `terrain/normals`: read heights 4, write three f32 12 = 16 B/cell.
/// - `terrain/slopes`: read 4, write 4 = 8 B/cell.
/// - `terrain/laplacian_reference`: the branch-free 5-point stencil, read 4, write 4 = 8 B/cell.
/// - `terrain/resample_bilinear`: to 3/4 of the side; per output cell, read the source
///   (16/9 cells of 4 B), write 4 B of value and 1 B of nodata flag.
pub fn terrain_kernels(terrain: &Grid, size: usize) -> Result<Vec<Kernel>, KernelError> {
    let cells = terrain.data().len();
    let mut kernels = Vec::new();

    kernels.push(Kernel::new("terrain/alpine", cells, 20.0, move || {
        black_box(sample_terrain(size)?);
        Ok(())
    }));

    let g = terrain.clone();
    kernels.push(Kernel::new("terrain/normals", cells, 16.0, move || {
        black_box(surface::normals(g.data(), g.geometry(), g.mask()));
        Ok(())
    }));

    let g = terrain.clone();
    kernels.push(Kernel::new("terrain/slopes", cells, 8.0, move || {
        black_box(surface::slopes(g.data(), g.geometry(), g.mask()));
        Ok(())
    }));

    let (w, h) = (terrain.geometry().width(), terrain.geometry().height());
    let src = terrain.data().to_vec();
    let mut out = vec![0.0f32; cells];
    kernels.push(Kernel::new(
        "terrain/laplacian_reference",
        cells,
        8.0,
        move || {
            stencil::laplacian(black_box(&src), &mut out, w, h);
            black_box(&out);
            Ok(())
        },
    ));

    let side = (3 * size / 4).max(1);
    let target = terrain.geometry().resampled(side, side)?;
    let source_per_output = cells as f64 / target.len() as f64;
    let g = terrain.clone();
    kernels.push(Kernel::new(
        "terrain/resample_bilinear",
        target.len(),
        4.0 * source_per_output + 5.0,
        move || {
            black_box(g.resample(target.clone()));
            Ok(())
        },
    ));
    Ok(kernels)
}
