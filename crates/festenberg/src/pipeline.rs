//! The whole diffusion snow cover of a scene (Section 5 end to end): height-span map, bridges,
//! kernel, overhangs, mesh, texture coordinates and mask; and the growth mode's frames.

use crate::boundary_uv::{MASK_ROWS, texture};
use crate::bridges::find_bridges;
use crate::error::FestenbergError;
use crate::growth::{GrowthParams, GrowthReport, grow};
use crate::kernel::{self, KernelField, KernelTable};
use crate::links::{SiteLinks, links};
use crate::mask::boundary_mask;
use crate::overhang;
use crate::params::{CoverParams, Resolved};
use crate::sites::SiteField;
use crate::surface_mesh::{self, SiteMesh};
use serde::Serialize;
use snowscape_mesh::write::vertex_normals;
use snowscape_mesh::{HeightSpanMap, HeightSpanOptions, Scene, SnowObject};
use std::time::Instant;

/// Counts and timings of a snow cover, for reports.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct CoverStats {
    /// Height-span map columns along x and y.
    pub columns: [usize; 2],
    /// Sites of the height-span map (surfaces with free space above).
    pub ground_sites: usize,
    /// Covered surfaces dropped from the map.
    pub covered_dropped: usize,
    /// Depth layers (most sites in one column).
    pub layers: usize,
    /// Bridge sites created (Section 5.1).
    pub bridge_sites: usize,
    /// Columns in one kernel cylinder.
    pub kernel_columns: usize,
    /// Kernel members visited in all.
    pub members_visited: u64,
    /// Sites holding snow (h > 0).
    pub snowy_sites: usize,
    /// Snow volume on the sites (Σ h·dx²), m³.
    pub volume_m3: f64,
    /// Deepest snow, metres.
    pub max_height_m: f32,
    pub vertices: usize,
    pub triangles: usize,
    pub quads: usize,
    pub corner_triangles: usize,
    pub boundary_loops: usize,
    pub uv_propagated: usize,
    pub seam_copies: usize,
    /// Seconds per stage, in order.
    pub timings: Vec<(String, f64)>,
}

impl CoverStats {
    /// Kernel throughput, sites per second.
    pub fn kernel_sites_per_s(&self) -> f64 {
        let s = self.timing("kernel");
        if s > 0.0 {
            (self.ground_sites + self.bridge_sites) as f64 / s
        } else {
            0.0
        }
    }

    /// Seconds of stage `name` (0 if it did not run).
    pub fn timing(&self, name: &str) -> f64 {
        self.timings
            .iter()
            .find(|(n, _)| n == name)
            .map_or(0.0, |t| t.1)
    }
}

/// A computed snow cover.
#[derive(Debug, Clone)]
pub struct SnowCover {
    /// The snow mesh with normals, texture coordinates and the boundary mask.
    pub mesh: SnowObject,
    pub resolved: Resolved,
    pub field: SiteField,
    pub kernel: KernelField,
    pub stats: CoverStats,
}

struct Timer(Vec<(String, f64)>);
impl Timer {
    fn run<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let t0 = Instant::now();
        let out = f();
        self.0.push((name.to_string(), t0.elapsed().as_secs_f64()));
        out
    }
}

/// The resolved parameters, height-span map and sites (with bridges when `bridges`).
pub fn prepare_sites(
    scene: &Scene,
    params: &CoverParams,
    bridges: bool,
) -> Result<(Resolved, HeightSpanMap, SiteField), FestenbergError> {
    let b = scene.bounds().ok_or(FestenbergError::NoSnowSites)?;
    let extent = match params.extent_m {
        Some(e) => e,
        None => [b.min[0], b.min[1], b.max[0], b.max[1]].map(f64::from),
    };
    let r = params.resolve(extent[2] - extent[0], extent[3] - extent[1])?;
    // Two empty columns around a lone object, so its outline is a snow edge (a drop), not
    // the map's border.
    let pad = if params.extent_m.is_some() {
        0.0
    } else {
        2.0 * r.resolution_m
    };
    let opts = HeightSpanOptions {
        cell_size_m: r.resolution_m,
        extent: Some([
            extent[0] - pad,
            extent[1] - pad,
            extent[2] + pad,
            extent[3] + pad,
        ]),
        min_capacity_m: (1e-3 * r.depth_m) as f32,
        two_sided: false,
    };
    let map = HeightSpanMap::build(scene, &opts)?;
    if map.site_count() == 0 {
        return Err(FestenbergError::NoSnowSites);
    }
    let h0 = r.depth_m as f32;
    let bridge_sites = if bridges && r.bridge_m > 0.0 {
        find_bridges(&map, h0, r.bridge_m)
    } else {
        Vec::new()
    };
    let field = SiteField::new(&map, h0, &bridge_sites);
    Ok((r, map, field))
}

/// The snow cover of `scene` (Section 5).
pub fn cover(scene: &Scene, params: &CoverParams) -> Result<SnowCover, FestenbergError> {
    let mut timer = Timer(Vec::new());
    let (r, map, field) = timer.run("height_span_and_bridges", || {
        prepare_sites(scene, params, true)
    })?;
    let kernel = timer.run("kernel", || kernel::evaluate(&field, r.radius_m));
    let links = timer.run("links", || links(&field));
    let offsets = r
        .overhang_m
        .map(|o| overhang::offsets(&kernel, &field.bridge, o as f32));
    let surface = timer.run("mesh", || {
        surface_mesh::build(&field, &links, &kernel.height, offsets.as_deref())
    });
    let SiteMesh {
        mesh: mut snow,
        ground,
        quads,
        corner_triangles,
        ..
    } = surface;
    snow.normals = Some(vertex_normals(&snow.positions, &snow.triangles));
    let uv = timer.run("texture_coordinates", || {
        texture(&mut snow, &ground, r.mask_scale_m as f32)
    });
    let mask = timer.run("mask", || boundary_mask(MASK_ROWS as u32, 1));
    let dx2 = r.resolution_m * r.resolution_m;
    let stats = CoverStats {
        columns: [map.width, map.height],
        ground_sites: map.site_count(),
        covered_dropped: map.covered_dropped,
        layers: map.layer_count(),
        bridge_sites: field.bridge_count(),
        kernel_columns: KernelTable::new(r.radius_m, r.resolution_m).columns,
        members_visited: kernel.members_visited,
        snowy_sites: kernel.height.iter().filter(|&&h| h > 0.0).count(),
        volume_m3: kernel.height.iter().map(|&h| h as f64).sum::<f64>() * dx2,
        max_height_m: kernel.height.iter().copied().fold(0.0, f32::max),
        vertices: snow.positions.len(),
        triangles: snow.triangles.len(),
        quads,
        corner_triangles,
        boundary_loops: uv.loops,
        uv_propagated: uv.propagated,
        seam_copies: uv.seam_copies,
        timings: timer.0,
    };
    let mesh = SnowObject::textured(snow, mask);
    Ok(SnowCover {
        mesh,
        resolved: r,
        field,
        kernel,
        stats,
    })
}

/// A surface mesh as a snow object to write (named `name`, normals computed, no texture).
pub fn plain_mesh(name: &str, surface: SiteMesh) -> SnowObject {
    let mut mesh = surface.mesh;
    mesh.name = name.into();
    mesh.normals = Some(vertex_normals(&mesh.positions, &mesh.triangles));
    SnowObject::new(mesh)
}

/// The growth mode (Eq. 2, no bridges or overhangs) on `scene`: `frame(index, time, mesh)`
/// gets the snow mesh of every frame.
pub fn grow_cover<E: From<FestenbergError>>(
    scene: &Scene,
    params: &CoverParams,
    growth: &GrowthParams,
    mut frame: impl FnMut(usize, f64, SnowObject) -> Result<(), E>,
) -> Result<(Resolved, GrowthReport), E> {
    let (r, _map, field) = prepare_sites(scene, params, false)?;
    let graph: Vec<SiteLinks> = links(&field);
    let report = grow(&field, &graph, growth, |i, t, h| {
        let surface = surface_mesh::build(&field, &graph, h, None);
        frame(i, t, plain_mesh(&format!("snow_{i:04}"), surface))
    })?;
    Ok((r, report))
}
