//! The registry of benchmarked kernels: one function per crate builds that crate's kernels
//! for a grid size. To add a kernel, push one [`Kernel::new`] line in its crate's function (or
//! add a function for a new crate and chain it in [`all_kernels`]).

mod avalanche;
mod io;
mod render;
mod season;
mod snowpack;
mod terrain;
mod transport;

pub use avalanche::avalanche_kernels;
pub use io::io_kernels;
pub use render::render_kernels;
pub use season::{SEASON_DAYS, season_kernels};
pub use snowpack::snowpack_kernels;
pub use terrain::{sample_terrain, terrain_kernels};
pub use transport::transport_kernels;

use crate::kernel::{Kernel, KernelError};

/// Every kernel, at `size`² cells, in report order.
pub fn all_kernels(size: usize) -> Result<Vec<Kernel>, KernelError> {
    kernels_matching(size, None)
}

/// The kernels whose name starts with `only` (all with `None`), at `size`² cells, in report
/// order; only the crates that can hold such a kernel are set up.
pub fn kernels_matching(size: usize, only: Option<&str>) -> Result<Vec<Kernel>, KernelError> {
    // A group holds kernels named `group/...`.
    let wanted = |group: &str| {
        only.is_none_or(|p| {
            p.starts_with(&format!("{group}/")) || format!("{group}/").starts_with(p)
        })
    };
    let terrain = sample_terrain(size)?;
    let mut kernels = Vec::new();
    if wanted("terrain") {
        kernels.extend(terrain_kernels(&terrain, size)?);
    }
    if wanted("io") {
        kernels.extend(io_kernels(&terrain)?);
    }
    if wanted("render") {
        kernels.extend(render_kernels(&terrain)?);
    }
    if wanted("season") {
        kernels.extend(season_kernels(&terrain)?);
    }
    // The snowpack's kernels are season kernels (`season/enhanced_melt`, ...), set up apart.
    if wanted("season") {
        kernels.extend(snowpack_kernels(&terrain)?);
    }
    if wanted("avalanche") {
        kernels.extend(avalanche_kernels(size)?);
    }
    if wanted("transport") {
        kernels.extend(transport_kernels(&terrain, size)?);
    }
    kernels.retain(|k| only.is_none_or(|p| k.name.starts_with(p)));
    Ok(kernels)
}
