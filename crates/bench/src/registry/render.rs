//! Kernels of `snowscape-render`.

use crate::kernel::{Kernel, KernelError};
use snowscape_render::{PreviewOptions, render_preview};
use snowscape_terrain::{Grid, LayeredTerrain, SnowLayer};
use std::hint::black_box;

/// Snow (m of powder) on cells above this share of the altitude range, so the preview colours
/// both rock and snow.
const SNOWLINE_SHARE: f32 = 0.4;

/// `terrain` as a layered terrain with 0.5 m of powder above the snowline.
fn snowy(terrain: &Grid) -> LayeredTerrain {
    let (lo, hi) = terrain.value_range().unwrap_or((0.0, 0.0));
    let snowline = lo + SNOWLINE_SHARE * (hi - lo);
    let mut layered = LayeredTerrain::from_bedrock(terrain.clone());
    let bedrock = layered.bedrock.clone();
    for (depth, &z) in layered
        .layer_mut(SnowLayer::Powder)
        .iter_mut()
        .zip(&bedrock)
    {
        *depth = if z > snowline { 0.5 } else { 0.0 };
    }
    layered
}

/// The rendering kernels on `terrain`:
/// - `render/preview`: the shaded-relief RGBA preview at one pixel per cell; 24 B/cell (read
///   bedrock and four snow layers 20, write RGBA 4).
pub fn render_kernels(terrain: &Grid) -> Result<Vec<Kernel>, KernelError> {
    let layered = snowy(terrain);
    let cells = terrain.data().len();
    let options = PreviewOptions {
        max_size: None,
        ..PreviewOptions::default()
    };
    Ok(vec![Kernel::new(
        "render/preview",
        cells,
        24.0,
        move || {
            black_box(render_preview(&layered, &options)?);
            Ok(())
        },
    )])
}
