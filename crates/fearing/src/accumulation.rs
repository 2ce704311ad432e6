//! Snow accumulation (Fearing 2000, Sections 3.1-3.4): the anytime loop of one pass.
//!
//! The pass builds the tracer over the scene and the snow so far (Section 3.1: added snow
//! blocks later flakes), the flutter walk and the sky buckets. Then, until the flake budget is
//! shot or the time budget runs out, the most important sites (Section 3.2) each shoot a batch
//! of flakes (in parallel; every flake's random numbers are keyed, so the result does not
//! depend on the threads), and whenever every site has shot twice since the last change, sites
//! whose sky occlusion differs enough from a neighbour's split in four and sibling sites that
//! agree on full exposure or full occlusion merge (Section 3.1), up to the refinement limit.
//! At the end the sky buckets turn the flakes into snow volume (Section 3.4). Sites that did not
//! get to shoot in this pass keep their flakes of an earlier pass in the sky.

use crate::edge_groups::Topology;
use crate::flakes::{Batch, Ceiling, Volley, Walk, shoot};
use crate::importance::{Weights, disagreement, importance, top};
use crate::launch_sites::LaunchSites;
use crate::params::FearingParams;
use crate::sky_buckets::{Allocation, SkyGrid, add_arrival};
use crate::surface::SnowSurface;
use crate::tracer::{Tag, Tracer};
use rayon::prelude::*;
use serde::Serialize;
use snowscape_mesh::{Bounds, Scene};
use std::time::Instant;

/// What one accumulation pass did.
#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct AccumulationReport {
    pub flakes: u64,
    pub flakes_to_sky: u64,
    pub rays: u64,
    pub rounds: u32,
    pub sites_start: usize,
    pub sites_end: usize,
    pub splits: usize,
    pub merges: usize,
    /// Whether the time budget ended the pass before its flake budget.
    pub stopped_by_time: bool,
    pub allocation: Allocation,
    pub step_height_m: f64,
    pub sky_bucket_m: f64,
}

/// What the flakes of one pass fly through (Section 3.1): the tracer over the scene and the snow
/// so far, the flutter walk, the ceiling above which a flake sees the sky, and the sky buckets.
struct Snowfall {
    tracer: Tracer,
    walk: Walk,
    ceiling: Ceiling,
    sky: SkyGrid,
}

impl Snowfall {
    /// Builds the pass's tracer, walk, ceiling and sky for `depth` metres of snowfall over
    /// `scene` (whose bounds are `bounds`).
    fn build(
        scene: &Scene,
        bounds: &Bounds,
        sites: &LaunchSites,
        topo: &Topology,
        p: &FearingParams,
        depth: f64,
    ) -> Self {
        let snow = SnowSurface::build(sites, topo, p.min_surface_depth_m);
        let tagged = snow.tagged();
        let tracer = Tracer::new(scene, &tagged);
        let snow_top = snow
            .mesh
            .positions
            .iter()
            .map(|q| q[2])
            .fold(bounds.max[2], f32::max) as f64;
        let height = (snow_top - bounds.min[2] as f64).max(1e-6);
        let fr = p.flutter();
        let dz = p.step_height_m.unwrap_or((2.0 * fr).max(height / 400.0));
        let fall = p.material.fall_speed_m_s;
        let walk = Walk {
            fr,
            fr_sd: fr * p.flutter_sd_fraction,
            dz,
            drift: [-p.wind_m_s[0] / fall, -p.wind_m_s[1] / fall],
            z_sky: snow_top + (sites.spacing * 1e-2).max(1e-4),
        };
        // The sky covers the scene plus the drift and flutter spread over its height.
        let spread = walk.drift[0].hypot(walk.drift[1]) * height
            + 3.0 * (fr + walk.fr_sd) * (height / dz.max(1e-9)).sqrt();
        let lo = [bounds.min[0] as f64 - spread, bounds.min[1] as f64 - spread];
        let hi = [bounds.max[0] as f64 + spread, bounds.max[1] as f64 + spread];
        let wbox = (
            [bounds.min[0] as f64, bounds.min[1] as f64],
            [bounds.max[0] as f64, bounds.max[1] as f64],
        );
        let bucket = p.sky_bucket_m.unwrap_or(4.0 * sites.spacing);
        let sky = SkyGrid::new(lo, hi, bucket, depth, p.sky_weight.as_ref(), wbox);
        let scene_tris = scene
            .objects
            .iter()
            .flat_map(|o| (0..o.triangles.len()).map(move |t| o.corners(t)));
        let ceiling = Ceiling::new(
            scene_tris.chain(tagged.iter().map(|t| t.0)),
            lo,
            hi,
            walk.reach(),
        );
        Snowfall {
            tracer,
            walk,
            ceiling,
            sky,
        }
    }
}

/// The importance weight of each scene object (Section 3.2): 0.1 for the boring ones, else 1.
fn object_weights(scene: &Scene, p: &FearingParams) -> Vec<f64> {
    scene
        .objects
        .iter()
        .map(|o| {
            if p.boring_objects.contains(&o.name) {
                0.1
            } else {
                1.0
            }
        })
        .collect()
}

/// Runs accumulation pass `pass`, adding `depth` metres of snowfall; returns its report.
pub fn accumulate(
    scene: &Scene,
    sites: &mut LaunchSites,
    topo: &mut Topology,
    p: &FearingParams,
    pass: u32,
    depth: f64,
    deadline: Instant,
) -> AccumulationReport {
    let bounds = scene
        .bounds()
        .expect("a scene with launch sites has bounds");
    let fall = Snowfall::build(scene, &bounds, sites, topo, p, depth);
    let tan_aor = p.material.aor_deg.to_radians().tan();
    let size = bounds.diagonal().max(1e-6) as f64;
    let object_weight = object_weights(scene, p);
    let mut rep = AccumulationReport {
        sites_start: topo.leaves.len(),
        step_height_m: fall.walk.dz,
        sky_bucket_m: fall.sky.size,
        ..Default::default()
    };
    let mut refinements = 0;
    loop {
        let n = topo.leaves.len();
        let mean_area = sites.upward_area / n.max(1) as f64;
        let w = Weights {
            mean_area,
            tan_aor,
            camera: p.camera.map(|c| (c, size)),
            object_weight: object_weight.clone(),
        };
        let imp = importance(sites, topo, &w, pass);
        let chosen = top(&imp, (n / 4).max(256).min(n));
        let batches = shoot_batches(&fall, sites, topo, p, pass, mean_area, &chosen);
        record_batches(sites, &fall.sky, pass, batches, &mut rep);
        rep.rounds += 1;
        if fewest_batches(sites, topo, pass) >= 2 && refinements < p.max_refinement {
            refinements += 1;
            let (s, m) = refine(sites, topo, p, pass);
            rep.splits += s;
            rep.merges += m;
            if s + m > 0 {
                *topo = Topology::build(sites);
            }
        }
        let budget = p.flakes_per_site as u64 * topo.leaves.len() as u64;
        if rep.flakes >= budget {
            break;
        }
        if Instant::now() > deadline {
            rep.stopped_by_time = true;
            break;
        }
    }
    rep.sites_end = topo.leaves.len();
    rep.allocation = allocate(sites, topo, &fall.sky);
    rep
}

/// One round's shooting (Section 3.2): each chosen site (an index into the leaves) shoots a
/// batch of flakes from just above its snow, larger for sites larger than `mean_area` (m²), in
/// parallel; returns each site's cell id with its batch, in the order chosen.
fn shoot_batches(
    fall: &Snowfall,
    sites: &LaunchSites,
    topo: &Topology,
    p: &FearingParams,
    pass: u32,
    mean_area: f64,
    chosen: &[u32],
) -> Vec<(u32, Batch)> {
    let cells = &sites.cells;
    chosen
        .par_iter()
        .with_min_len(8)
        .map(|&i| {
            let id = topo.leaves[i as usize];
            let c = &cells[id as usize];
            let count =
                p.batch_size * ((c.area_xy() / mean_area).sqrt().round() as u32).clamp(1, 4);
            let first = if c.pass == pass { c.shots as u32 } else { 0 };
            let centre = c.centroid();
            let start = [
                centre[0],
                centre[1],
                centre[2] + c.depth() + (sites.spacing * 1e-4).max(1e-6),
            ];
            let own = [
                Tag::Scene {
                    object: c.object,
                    triangle: c.triangle,
                },
                Tag::SnowTop {
                    site: i,
                    group: topo.group[i as usize],
                },
            ];
            (
                id,
                shoot(
                    &fall.walk,
                    &fall.tracer,
                    &fall.ceiling,
                    Volley {
                        seed: p.seed,
                        pass,
                        site: id,
                        start,
                        own,
                        first,
                        count,
                    },
                ),
            )
        })
        .collect()
}

/// Adds a round's batches to their sites' tallies and sky arrivals (Section 3.4), starting
/// afresh a site whose tallies belong to an earlier pass; counts the flakes and rays in `rep`.
fn record_batches(
    sites: &mut LaunchSites,
    sky: &SkyGrid,
    pass: u32,
    batches: Vec<(u32, Batch)>,
    rep: &mut AccumulationReport,
) {
    for (id, b) in batches {
        let c = &mut sites.cells[id as usize];
        if c.pass != pass || c.batches == 0 {
            c.pass = pass;
            c.shots = 0.0;
            c.sky_hits = 0.0;
            c.batches = 0;
            c.arrivals.clear();
        }
        c.shots += b.shot as f64;
        c.sky_hits += b.arrivals.len() as f64;
        c.batches += 1;
        for a in &b.arrivals {
            add_arrival(&mut c.arrivals, sky.splat(a[0], a[1]));
        }
        rep.flakes += b.shot as u64;
        rep.flakes_to_sky += b.arrivals.len() as u64;
        rep.rays += b.rays;
    }
}

/// The fewest batches any site has shot in pass `pass` (0 for a site that has not shot in it):
/// refinement waits until every site has shot twice.
fn fewest_batches(sites: &LaunchSites, topo: &Topology, pass: u32) -> u32 {
    topo.leaves
        .iter()
        .map(|&c| {
            if sites.cells[c as usize].pass == pass {
                sites.cells[c as usize].batches
            } else {
                0
            }
        })
        .min()
        .unwrap_or(0)
}

/// Turns the sky arrivals of every site into snow volume; returns the summary.
fn allocate(sites: &mut LaunchSites, topo: &Topology, sky: &SkyGrid) -> Allocation {
    let mut reached = vec![0.0f64; sky.mass.len()];
    for &id in &topo.leaves {
        let c = &sites.cells[id as usize];
        if c.shots > 0.0 {
            let rep = c.area_xy() / c.shots;
            for &(b, w) in &c.arrivals {
                reached[b as usize] += rep * w as f64;
            }
        }
    }
    let rho = sky.densities(&reached);
    let mut allocated = 0.0;
    for &id in &topo.leaves {
        let c = &mut sites.cells[id as usize];
        if c.shots > 0.0 {
            let rep = c.area_xy() / c.shots;
            let v: f64 = c
                .arrivals
                .iter()
                .map(|&(b, w)| rho[b as usize] * rep * w as f64)
                .sum();
            c.volume += v;
            allocated += v;
        }
    }
    sky.summary(&reached, allocated)
}

/// One round of adaptive refinement: split disagreeing sites, merge agreeing siblings.
fn refine(
    sites: &mut LaunchSites,
    topo: &Topology,
    p: &FearingParams,
    pass: u32,
) -> (usize, usize) {
    let n = topo.leaves.len();
    let dis: Vec<f64> = (0..n)
        .map(|i| disagreement(&sites.cells, topo, i))
        .collect();
    let mut split: Vec<(f64, u32)> = (0..n)
        .filter(|&i| {
            let c = &sites.cells[topo.leaves[i] as usize];
            dis[i] > p.refine_threshold && (c.level as u32) < p.max_refinement && c.pass == pass
        })
        .map(|i| (dis[i], topo.leaves[i]))
        .collect();
    split.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    // Limits (Section 3.2): at most n/4 splits a round, and never more than three times the
    // initial sites in all.
    let roots = sites.cells.iter().filter(|c| c.level == 0).count();
    let room = (3 * roots).saturating_sub(n) / 3;
    split.truncate((n / 4).max(64).min(room));
    // Merge: parents whose four leaf children all agree on (nearly) full exposure or occlusion,
    // as do their neighbours.
    let site_of = topo.site_of_cell(sites.cells.len());
    let mut parents: Vec<u32> = topo
        .leaves
        .iter()
        .map(|&c| sites.cells[c as usize].parent)
        .filter(|&q| q != crate::launch_sites::NONE)
        .collect();
    parents.sort_unstable();
    parents.dedup();
    let splitting: std::collections::HashSet<u32> = split.iter().map(|s| s.1).collect();
    let mut merges = Vec::new();
    for q in parents {
        if !sites.can_merge(q) {
            continue;
        }
        let first = sites.cells[q as usize].children;
        let kids: Vec<u32> = (first..first + 4).collect();
        let fr: Vec<f64> = kids
            .iter()
            .map(|&k| sites.cells[k as usize].sky_fraction())
            .collect();
        let extreme = fr.iter().all(|&f| f < 0.02) || fr.iter().all(|&f| f > 0.98);
        let calm = kids.iter().all(|&k| {
            let s = site_of[k as usize];
            s != u32::MAX
                && dis[s as usize] < 0.02
                && sites.cells[k as usize].batches >= 2
                && !splitting.contains(&k)
        });
        if extreme && calm {
            merges.push(q);
        }
    }
    for &(_, id) in &split {
        sites.split(id);
    }
    for &q in &merges {
        sites.merge(q);
    }
    (split.len(), merges.len())
}
