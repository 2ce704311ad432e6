//! The output layer is the library's ([`snowscape::outputs`]): every front end writes through
//! it. This module adds the command line's view of it: the stage timings on the progress bar.

pub use snowscape::outputs::*;

use crate::progress::Stages;
use image::RgbaImage;
use snowscape_render::PreviewOptions;
use snowscape_terrain::LayeredTerrain;

/// [`snowscape::outputs::write_all`], each stage counted on the progress bar.
pub fn write_all_staged(
    out: &mut Written,
    terrain: &LayeredTerrain,
    frames: &[RgbaImage],
    view: &PreviewOptions,
    stages: &mut Stages,
) -> anyhow::Result<()> {
    for (name, seconds) in write_all(out, terrain, frames, view)? {
        stages.finished(name, seconds);
    }
    Ok(())
}
