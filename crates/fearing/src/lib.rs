//! # snowscape-fearing: snow on arbitrary meshes after Fearing 2000
//!
//! "Computer Modelling of Fallen Snow" (SIGGRAPH 2000), Sections 3 to 6:
//! - [`launch_sites`] (3.3): upward-facing triangles cut into area-exact cells, one launch
//!   site each, refined and merged adaptively; [`edge_groups`]: neighbours, edge groups, borders;
//! - [`flakes`] (3.5): flakes shot upward as a flutter random walk, bent by wind (6), traced
//!   through the BVH of [`tracer`] (3.6);
//! - [`sky_buckets`] (3.4): the sky's mass shared by representative flake area, optionally
//!   weighted by an image ("snow writing");
//! - [`importance`] (3.2) and [`accumulation`] (3.1): the anytime loop, ended by a flake
//!   budget (a work count: [`FearingParams::flakes_per_site`]);
//! - [`stability`] (4.1, 4.2, 4.4) with [`edge_transit`] (4.3): angle-of-repose avalanches with
//!   obstacle tests and projectile particles over edges; any AOR and material ([`params`]);
//! - [`surface`] (3.7, 5): the snow mesh with closing walls, Taubin-smoothed depths;
//! - [`scenes`]: scenes built in code (plane, roof, box, basin).
//!
//! A cover returns data ([`FearingCover`], its [`FearingCover::meshes`] and report); its files are
//! written by `snowscape::cover::write_fearing_outputs`.
//!
//! Entry point: [`cover`]. A cover is a function of (scene, parameters, seed): the same bytes on
//! any machine and any thread count. Every stage ends on a work count (the flake budget of each
//! accumulation pass; quiet, or a pass cap bounded by the number of sites, in each stability
//! phase). The wall-clock [`FearingParams::budget_s`] is only a safety net: a cover that runs
//! past it fails with [`FearingError::BudgetExceeded`] instead of returning a cover cut short.

pub mod accumulation;
pub mod dusting;
pub mod edge_groups;
pub mod edge_transit;
pub mod error;
pub mod flakes;
pub mod importance;
pub mod launch_sites;
pub mod obstacles;
pub mod params;
pub mod report;
pub mod scenes;
pub mod sky_buckets;
pub mod stability;
pub mod surface;
pub mod tracer;
pub mod wind_transport;

pub use edge_groups::Topology;
pub use error::FearingError;
pub use launch_sites::LaunchSites;
pub use params::{FearingParams, Material, SkyWeight, StabilityPhaseParams};
pub use report::FearingReport;
pub use surface::SnowSurface;

use snowscape_mesh::Scene;
use std::time::{Duration, Instant};

/// The result of a cover: the final sites and their snow, its surface, and the report.
#[derive(Debug, Clone)]
pub struct FearingCover {
    pub sites: LaunchSites,
    pub topology: Topology,
    pub surface: SnowSurface,
    /// Flake dusting of the sites too thin for the surface (Section 3.8), if any.
    pub dusting: Option<snowscape_mesh::SnowObject>,
    pub report: FearingReport,
}

impl FearingCover {
    /// The meshes of the cover, in the order its files hold them: the snow surface (`snow`),
    /// then the dusting of the faces too steep to hold snow, if any (an alpha-masked texture
    /// travels with it).
    pub fn meshes(&self) -> Vec<snowscape_mesh::SnowObject> {
        let mut meshes = vec![self.surface.to_mesh("snow")];
        meshes.extend(self.dusting.clone());
        meshes
    }

    /// Snow depth (m) and base position of every site.
    pub fn site_depths(&self) -> Vec<([f64; 3], f64)> {
        self.topology
            .leaves
            .iter()
            .map(|&c| {
                (
                    self.sites.cells[c as usize].centroid(),
                    self.sites.cells[c as usize].depth(),
                )
            })
            .collect()
    }

    /// Total snow volume on the sites, m³.
    pub fn volume(&self) -> f64 {
        self.topology
            .leaves
            .iter()
            .map(|&c| self.sites.cells[c as usize].volume)
            .sum()
    }
}

/// Covers `scene` with snow (or another material) by Fearing's accumulation and stability.
pub fn cover(scene: &Scene, params: &FearingParams) -> Result<FearingCover, FearingError> {
    params.validate()?;
    for o in &scene.objects {
        if let Some((v, p)) = o
            .positions
            .iter()
            .enumerate()
            .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
        {
            return Err(FearingError::NonFiniteVertex {
                object: o.name.clone(),
                vertex: v,
                value: *p,
            });
        }
    }
    let start = Instant::now();
    let mut sites = LaunchSites::build(
        scene,
        params.min_normal_z,
        params.site_spacing_m,
        params.target_sites,
    );
    if sites.cells.is_empty() {
        return Err(FearingError::NoLaunchSites {
            triangles: scene.triangle_count(),
            min_normal_z: params.min_normal_z,
        });
    }
    let mut topo = Topology::build(&sites);
    let mut report = FearingReport {
        method: "fearing",
        triangles: scene.triangle_count(),
        upward_triangles: sites.upward_triangles,
        site_spacing_m: sites.spacing,
        sites_initial: topo.leaves.len(),
        threads: rayon::current_num_threads(),
        params: Some(params.clone()),
        ..Default::default()
    };
    report.timings.launch_sites_s = start.elapsed().as_secs_f64();
    // The work (flakes per site, stability passes) ends every stage; the wall clock is only a
    // safety net, and running out of it is an error, never a different cover.
    let deadline = start + Duration::from_secs_f64(params.budget_s.min(1e9));
    let over = |stage: String| FearingError::BudgetExceeded {
        budget_s: params.budget_s,
        elapsed_s: start.elapsed().as_secs_f64(),
        stage,
    };
    let passes = params.passes;
    for pass in 0..passes {
        let t = Instant::now();
        let acc = accumulation::accumulate(
            scene,
            &mut sites,
            &mut topo,
            params,
            pass,
            params.depth_m / passes as f64,
            deadline,
        );
        if acc.stopped_by_time {
            return Err(over(format!("accumulation pass {}", pass + 1)));
        }
        surface::smooth_volumes(&mut sites, &topo, params.smoothing_iterations);
        report.timings.accumulation_s += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let blown = wind_transport::blow(scene, &mut sites, &topo, params);
        let mut stab = stability::stabilise(scene, &mut sites, &topo, params, deadline);
        if stab.stopped_by_time {
            return Err(over(format!("stability phase {}", pass + 1)));
        }
        stab.wind_moved_m3 = blown;
        report.timings.stability_s += t.elapsed().as_secs_f64();
        report.flakes_shot += acc.flakes;
        report.flakes_to_sky += acc.flakes_to_sky;
        report.rays += acc.rays;
        report.mass.sky_m3 += acc.allocation.sky_volume_m3;
        report.mass.allocated_m3 += acc.allocation.allocated_m3;
        report.mass.unclaimed_m3 += acc.allocation.unclaimed_m3;
        report.mass.left_scene_m3 += stab.left_scene_m3;
        report.passes.push(report::PassReport {
            accumulation: acc,
            smoothing_iterations: params.smoothing_iterations,
            stability: stab,
        });
    }
    let t = Instant::now();
    let mut surface = SnowSurface::build(&sites, &topo, params.min_surface_depth_m);
    surface.smooth(params.surface_smoothing);
    let dusting = if params.dusting {
        dusting::dusting_mesh(&sites, &topo, params.min_surface_depth_m, params.seed)
    } else {
        None
    };
    report.timings.surface_s = t.elapsed().as_secs_f64();
    report.timings.total_s = start.elapsed().as_secs_f64();
    let mut cover = FearingCover {
        sites,
        topology: topo,
        surface,
        dusting,
        report,
    };
    let vol = cover.volume();
    let max_depth = cover.site_depths().iter().map(|d| d.1).fold(0.0, f64::max);
    let r = &mut cover.report;
    r.sites_final = cover.topology.leaves.len();
    r.edge_groups = cover.topology.group_count;
    r.mass.final_m3 = vol;
    r.mass.closure_error_m3 = r.mass.allocated_m3 - r.mass.left_scene_m3 - vol;
    r.flakes_per_s = r.flakes_shot as f64 / r.timings.accumulation_s.max(1e-9);
    r.surface_vertices = cover.surface.mesh.positions.len();
    r.surface_triangles = cover.surface.mesh.triangles.len();
    r.max_depth_m = max_depth;
    r.mean_depth_m = vol / cover.sites.upward_area.max(1e-300);
    Ok(cover)
}
