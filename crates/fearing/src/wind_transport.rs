//! Wind in the stability phase (Fearing 2000, Section 6): "we widen our single-site stability
//! test to include neighbours that are within 90° of the downwind direction", with a flux
//! maximum per site spent over a small number of trials, moved by the rules of Section 4.2
//! including the obstacle test.
//!
//! Ours: before the angle-of-repose passes, [`TRIALS`] sweeps (sites from the top down) each
//! move a share `wind_transport · |wind| / TRIALS` of a site's snow (the whole flux maximum being
//! `wind_transport · |wind|` of it, at most all) to its neighbours within 90° of downwind, in
//! proportion to the cosine of their direction from the wind, skipping neighbours behind an
//! obstacle (scene geometry or another group's snow). Snow piles against walls on the windward
//! side and thins in the lee; the stability passes that follow restore the angle of repose.
//! Snow is not blown over border edges. Mass only moves between sites.

use crate::edge_groups::Topology;
use crate::launch_sites::LaunchSites;
use crate::obstacles::own_snow;
use crate::params::FearingParams;
use crate::surface::SnowSurface;
use crate::tracer::{Tag, Tracer};
use snowscape_mesh::Scene;

/// Sweeps per stability phase.
pub const TRIALS: u32 = 4;

/// Blows snow downwind; returns the volume moved, m³.
pub fn blow(scene: &Scene, sites: &mut LaunchSites, topo: &Topology, p: &FearingParams) -> f64 {
    let [wx, wy] = p.wind_m_s;
    let speed = wx.hypot(wy);
    let share = (p.wind_transport * speed).min(1.0) / TRIALS as f64;
    if share <= 0.0 {
        return 0.0;
    }
    let (dx, dy) = (wx / speed, wy / speed);
    let snow = SnowSurface::build(sites, topo, p.min_surface_depth_m);
    let tracer = Tracer::new(scene, &snow.tagged());
    let n = topo.leaves.len();
    let cell = |i: usize| &sites.cells[topo.leaves[i] as usize];
    let centre: Vec<[f64; 3]> = (0..n).map(|i| cell(i).centroid()).collect();
    let area: Vec<f64> = (0..n).map(|i| cell(i).area_xy().max(1e-300)).collect();
    let own: Vec<Tag> = (0..n)
        .map(|i| Tag::Scene {
            object: cell(i).object,
            triangle: cell(i).triangle,
        })
        .collect();
    let mut vol: Vec<f64> = (0..n).map(|i| cell(i).volume).collect();
    let eps = sites.spacing * 1e-3;
    // Downwind neighbours with their weights, behind no obstacle (tested once per phase).
    let targets: Vec<Vec<(usize, f64)>> = (0..n)
        .map(|s| {
            let ts = centre[s][2] + vol[s] / area[s];
            let group = topo.group[s];
            topo.neighbours[s]
                .iter()
                .filter_map(|nb| {
                    let j = nb.site as usize;
                    let cos = ((centre[j][0] - centre[s][0]) * dx
                        + (centre[j][1] - centre[s][1]) * dy)
                        / nb.distance.max(1e-300);
                    if cos <= 0.0 {
                        return None;
                    }
                    let tj = centre[j][2] + vol[j] / area[j];
                    let blocked = tracer.blocked(
                        [centre[s][0], centre[s][1], ts + eps],
                        [centre[j][0], centre[j][1], tj + eps],
                        |t| t == own[s] || t == own[j] || own_snow(t, group),
                    );
                    (!blocked).then_some((j, cos))
                })
                .collect()
        })
        .collect();
    let mut moved = 0.0;
    for _ in 0..TRIALS {
        let mut order: Vec<usize> = (0..n).collect();
        let top = |v: &[f64], i: usize| centre[i][2] + v[i] / area[i];
        order.sort_by(|&a, &b| top(&vol, b).total_cmp(&top(&vol, a)).then(a.cmp(&b)));
        for &s in &order {
            let sum: f64 = targets[s].iter().map(|t| t.1).sum();
            if sum <= 0.0 || vol[s] <= 0.0 {
                continue;
            }
            let amount = vol[s] * share;
            for &(j, w) in &targets[s] {
                let dv = amount * w / sum;
                vol[j] += dv;
                moved += dv;
            }
            vol[s] -= amount;
        }
    }
    for (i, &c) in topo.leaves.iter().enumerate() {
        sites.cells[c as usize].volume = vol[i];
    }
    moved
}
