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
    let terrain = sample_terrain(size)?;
    let mut kernels = terrain_kernels(&terrain, size)?;
    kernels.extend(io_kernels(&terrain)?);
    kernels.extend(render_kernels(&terrain)?);
    kernels.extend(season_kernels(&terrain)?);
    kernels.extend(snowpack_kernels(&terrain)?);
    kernels.extend(avalanche_kernels(size)?);
    kernels.extend(transport_kernels(&terrain, size)?);
    Ok(kernels)
}
