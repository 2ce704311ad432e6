//! Snow stability (Fearing 2000, Section 4): redistributes accumulated snow into a stable
//! configuration by a series of small, simultaneous avalanches.
//!
//! All sites start in the unresolved list u1, sorted by height (base plus snow) and examined
//! from the top down. The test of one site s (4.2): (1) find the neighbours lower than s whose
//! angle from s (the snow heights over their horizontal distance) exceeds s's critical angle,
//! drawn once per site from the transition curve around the AOR (4.1: a smoothstep law of the
//! given width); (2) test for obstacles between s and each: (i) scene geometry blocks, (ii) a
//! closing wall of another group's snow blocks, (iii) another group's snow top in the way
//! receives the snow instead (its site replaces the neighbour); (3) shift snow evenly from s to
//! every neighbour still in contention until at least one becomes stable; (4) repeat until none
//! is unstable or s is bare. A border edge of s is a neighbour too (4.3): its height is the edge,
//! or whatever lies just beyond it; a short horizontal probe toward it that meets something
//! blocks the edge until the snow rises above the obstacle, else the excess leaves by
//! [`crate::edge_transit`]. Every site affected (s, receivers, higher neighbours of s) goes to
//! u2, which replaces u1 after the pass. Ending a phase (4.4): when u2 is empty, or a pass is
//! quiet (no shift changes a site's height by more than `quiet_m` and it moves less than a small
//! share of the snow), or a pass moves less than that share, every site is re-checked (the
//! paper's re-run "to compensate for speed-accuracy tradeoffs"); the phase ends when that
//! re-check finds nothing to do or is quiet, or at the pass cap or the test cap
//! (`max_tests_per_site` times the sites: both bounded by the number of sites). Work, never the
//! clock, ends a phase: the wall-clock deadline is a safety net whose expiry the caller reports
//! as an error. The snow surfaces used by
//! the obstacle tests are rebuilt every few passes once they have tested a quarter of the sites
//! (the paper's rebucketing "with a considerable lag").

use crate::edge_groups::Topology;
use crate::edge_transit::{Flight, Landing, SiteGrid};
use crate::launch_sites::LaunchSites;
use crate::obstacles::{self, EdgeObs, Obs};
use crate::params::FearingParams;
use crate::surface::SnowSurface;
use crate::tracer::{Tag, Tracer};
use serde::Serialize;
use snowscape_mesh::Scene;
use snowscape_terrain::random::uniform;
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashSet};

/// What one stability phase did.
#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct StabilityReport {
    pub passes: u32,
    /// Whether the wall-clock safety net ended the phase (the cover is then an error).
    pub stopped_by_time: bool,
    /// Whether the phase ended quiet (a full re-check moved no site's snow by more than the
    /// quiet height); false when the pass cap ended it.
    pub quiet: bool,
    /// Site tests, avalanches (snow shifts), edge transits and their particles.
    pub tests: u64,
    pub avalanches: u64,
    pub edge_transits: u64,
    pub particles: u64,
    /// Obstacle outcomes: blocked by geometry, by a snow wall, redirected to another surface.
    pub blocked_by_geometry: u64,
    pub blocked_by_snow_wall: u64,
    pub redirected: u64,
    pub blocked_edges: u64,
    /// Volumes, m³: on the sites before and after, moved, left the scene.
    pub volume_before_m3: f64,
    pub volume_after_m3: f64,
    pub moved_m3: f64,
    pub left_scene_m3: f64,
    /// Moved downwind before the phase (Section 6, [`crate::wind_transport`]).
    pub wind_moved_m3: f64,
}

/// A site's critical angle tan from the transition curve (inverse smoothstep of a keyed uniform).
pub fn critical_tan(p: &FearingParams, cell: u32) -> f64 {
    let m = &p.material;
    let u = uniform(p.seed, 0x57ab, cell as u64);
    let x = 0.5 - ((1.0 - 2.0 * u).asin() / 3.0).sin();
    let deg = m.aor_deg + m.transition_deg * (x - 0.5);
    deg.clamp(0.0, 89.9).to_radians().tan()
}

enum Target {
    Site {
        site: usize,
        allowed: f64,
    },
    Edge {
        slot: usize,
        height: f64,
        allowed: f64,
    },
}

/// Runs one stability phase on the current snow.
pub fn stabilise(
    scene: &Scene,
    sites: &mut LaunchSites,
    topo: &Topology,
    params: &FearingParams,
    deadline: std::time::Instant,
) -> StabilityReport {
    let sp = &params.stability;
    let n = topo.leaves.len();
    let cell = |i: usize| topo.leaves[i] as usize;
    let centroids: Vec<[f64; 3]> = (0..n).map(|i| sites.cells[cell(i)].centroid()).collect();
    let areas: Vec<f64> = (0..n)
        .map(|i| sites.cells[cell(i)].area_xy().max(1e-300))
        .collect();
    let crit: Vec<f64> = (0..n)
        .map(|i| critical_tan(params, topo.leaves[i]))
        .collect();
    let mut vol: Vec<f64> = (0..n).map(|i| sites.cells[cell(i)].volume).collect();
    let owner: Vec<(u32, u32)> = (0..n)
        .map(|i| (sites.cells[cell(i)].object, sites.cells[cell(i)].triangle))
        .collect();
    let site_tris: HashSet<(u32, u32)> = owner.iter().copied().collect();
    let grid = SiteGrid::new(centroids.clone(), owner.clone(), sites.spacing.max(1e-6));
    let bounds = scene
        .bounds()
        .expect("a scene with launch sites has bounds");
    let eps = sites.spacing * 1e-3;
    let total = |v: &[f64]| v.iter().sum::<f64>();
    let mut rep = StabilityReport {
        volume_before_m3: total(&vol),
        ..Default::default()
    };
    let top = |vol: &[f64], i: usize| centroids[i][2] + vol[i] / areas[i];
    let mut obs: Vec<Vec<Obs>> = topo
        .neighbours
        .iter()
        .map(|v| vec![Obs::Unknown; v.len()])
        .collect();
    let mut edges: Vec<Vec<EdgeObs>> = topo
        .borders
        .iter()
        .map(|v| vec![EdgeObs::Unknown; v.len()])
        .collect();

    let mut u1: Vec<usize> = (0..n).collect();
    let mut rechecking = false;
    let mut tracer = None;
    let mut in_u2 = vec![false; n];
    // The pass cap, bounded by the number of sites (every pass that does not end the phase
    // moves snow by more than the quiet height somewhere).
    let max_passes = sp
        .max_passes
        .min(n.saturating_add(16).min(u32::MAX as usize) as u32);
    // The work cap: site tests, bounded by the number of sites.
    let max_tests = (sp.max_tests_per_site as u64)
        .saturating_mul(n as u64)
        .max(1);
    let (mut refreshed_at, mut tests_at_refresh) = (0u32, 0u64);
    while rep.passes < max_passes && rep.tests < max_tests {
        // Rebuild every few passes, and only once those passes have tested a quarter of the
        // sites: the long tail of small passes a phase ends with does not rebuild the whole
        // tracer every few hundred tests.
        let due = rep.passes >= refreshed_at + sp.obstacle_refresh_passes
            && rep.tests >= tests_at_refresh + (n as u64 / 4);
        if due || tracer.is_none() {
            refreshed_at = rep.passes;
            tests_at_refresh = rep.tests;
            sync(sites, topo, &vol);
            let snow = SnowSurface::build(sites, topo, params.min_surface_depth_m);
            tracer = Some(Tracer::new(scene, &snow.tagged()));
            obs.iter_mut().flatten().for_each(|o| *o = Obs::Unknown);
            edges
                .iter_mut()
                .flatten()
                .for_each(|o| *o = EdgeObs::Unknown);
        }
        let tracer = tracer.as_ref().expect("built above");
        let has_sites = |o: u32, t: u32| site_tris.contains(&(o, t));
        let flight = Flight {
            tracer,
            sites: &grid,
            has_sites: &has_sites,
            z_floor: bounds.min[2] as f64 - sites.spacing,
            step: (sites.spacing * 0.5).max(1e-4),
            restitution: sp.restitution,
            rings: 8,
        };
        // The pass examines u1 from the top down; higher neighbours that lose their support
        // re-enter this pass at once (so a drawdown climbs a slope in one pass), receivers wait
        // for the next one.
        let mut heap: BinaryHeap<(u64, Reverse<usize>)> = u1
            .iter()
            .map(|&i| (order_key(top(&vol, i)), Reverse(i)))
            .collect();
        let mut in_heap = vec![false; n];
        for &i in &u1 {
            in_heap[i] = true;
        }
        let cap = 4 * u1.len() + 16;
        let mut work = 0;
        let mut u2 = Vec::new();
        let mut moved = 0.0;
        // The largest change of a site's snow height by one shift in this pass, metres.
        let mut largest_shift = 0.0f64;
        // A receiver is examined later in this pass (it is lower), or in the next one once the
        // pass has done its share of work.
        macro_rules! receive {
            ($j:expr) => {{
                let j = $j;
                if work < cap {
                    if !in_heap[j] {
                        in_heap[j] = true;
                        heap.push((order_key(top(&vol, j)), Reverse(j)));
                    }
                } else {
                    mark(&mut u2, &mut in_u2, j);
                }
            }};
        }
        while let Some((_, Reverse(s))) = heap.pop() {
            if rep.tests >= max_tests {
                break;
            }
            in_heap[s] = false;
            work += 1;
            rep.tests += 1;
            let group = topo.group[s];
            let own_tri = Tag::Scene {
                object: owner[s].0,
                triangle: owner[s].1,
            };
            let mut touched = false;
            // Border edges whose receivers are full for this test.
            let mut full: Vec<usize> = Vec::new();
            for _ in 0..(2 * topo.neighbours[s].len() + 2 * topo.borders[s].len() + 4) {
                if vol[s] <= 0.0 {
                    break;
                }
                let ts = top(&vol, s);
                let mut targets = Vec::new();
                for (k, nb) in topo.neighbours[s].iter().enumerate() {
                    let j = nb.site as usize;
                    let allowed = nb.distance * crit[s] + sp.level_tolerance_m;
                    if ts - top(&vol, j) <= allowed {
                        continue;
                    }
                    if obs[s][k] == Obs::Unknown {
                        let from = [centroids[s][0], centroids[s][1], ts + eps];
                        let to = [centroids[j][0], centroids[j][1], top(&vol, j) + eps];
                        let tri_j = Tag::Scene {
                            object: owner[j].0,
                            triangle: owner[j].1,
                        };
                        obs[s][k] =
                            obstacles::between(tracer, from, to, [own_tri, tri_j], group, &mut rep);
                    }
                    match obs[s][k] {
                        Obs::Clear => targets.push(Target::Site { site: j, allowed }),
                        Obs::Redirect(m) => {
                            let m = m as usize;
                            let d = (centroids[m][0] - centroids[s][0])
                                .hypot(centroids[m][1] - centroids[s][1]);
                            let allowed = d * crit[s] + sp.level_tolerance_m;
                            if ts - top(&vol, m) > allowed
                                && !targets
                                    .iter()
                                    .any(|t| matches!(t, Target::Site { site, .. } if *site == m))
                            {
                                targets.push(Target::Site { site: m, allowed });
                            }
                        }
                        _ => {}
                    }
                }
                for (k, e) in topo.borders[s].iter().enumerate() {
                    let mid = [0, 1, 2].map(|q| 0.5 * (e.a[q] + e.b[q]));
                    let (dx, dy) = (mid[0] - centroids[s][0], mid[1] - centroids[s][1]);
                    let d = dx.hypot(dy);
                    let allowed = d * crit[s] + sp.level_tolerance_m;
                    if ts - mid[2] <= allowed
                        || edges[s][k] == EdgeObs::Blocked
                        || full.contains(&k)
                    {
                        continue;
                    }
                    if edges[s][k] == EdgeObs::Unknown {
                        let centre = [centroids[s][0], centroids[s][1], ts];
                        let site = obstacles::EdgeSite {
                            centre,
                            own_tri,
                            group,
                        };
                        edges[s][k] =
                            obstacles::over_edge(&flight, &site, e, sites.spacing, sp, &mut rep);
                    }
                    if let EdgeObs::Open { height, .. } = edges[s][k]
                        && ts - height > allowed
                    {
                        targets.push(Target::Edge {
                            slot: k,
                            height,
                            allowed,
                        });
                    }
                }
                if targets.is_empty() {
                    break;
                }
                // Even shift: the same volume to each, the least that makes one stable. A
                // neighbour counts as unstable beyond its angle plus the level tolerance and is
                // made stable at the angle itself, so rounding cannot re-trigger it at once.
                let tol = sp.level_tolerance_m;
                let kf = targets.len() as f64;
                let mut dv = vol[s] / kf;
                for t in &targets {
                    let need = match *t {
                        Target::Site { site, allowed } => {
                            (ts - top(&vol, site) - allowed + tol)
                                / (kf / areas[s] + 1.0 / areas[site])
                        }
                        Target::Edge {
                            height, allowed, ..
                        } => (ts - height - allowed + tol) / (kf / areas[s]),
                    };
                    dv = dv.min(need.max(0.0));
                }
                if dv <= 0.0 {
                    break;
                }
                touched = true;
                rep.avalanches += 1;
                for t in &targets {
                    match *t {
                        Target::Site { site, .. } => {
                            vol[s] -= dv;
                            vol[site] += dv;
                            moved += dv;
                            largest_shift = largest_shift.max(dv / areas[s].min(areas[site]));
                            receive!(site);
                        }
                        Target::Edge { slot, .. } => {
                            rep.edge_transits += 1;
                            let EdgeObs::Open { landings, .. } = &edges[s][slot] else {
                                unreachable!()
                            };
                            let share = dv / landings.len() as f64;
                            let mut stuck = false;
                            for l in landings {
                                match *l {
                                    // Never onto snow standing higher than the origin (the
                                    // landing was found on older snow).
                                    Landing::Site(m) if top(&vol, m as usize) >= ts => stuck = true,
                                    Landing::Site(m) => {
                                        // The receiver may fill to halfway up to the origin,
                                        // no more (else the snow would flow back up).
                                        let m = m as usize;
                                        let give = share.min(0.5 * (ts - top(&vol, m)) * areas[m]);
                                        if give < share && !full.contains(&slot) {
                                            full.push(slot);
                                        }
                                        vol[s] -= give;
                                        vol[m] += give;
                                        moved += give;
                                        largest_shift =
                                            largest_shift.max(give / areas[s].min(areas[m]));
                                        receive!(m);
                                    }
                                    Landing::Lost => {
                                        vol[s] -= share;
                                        rep.left_scene_m3 += share;
                                        moved += share;
                                        largest_shift = largest_shift.max(share / areas[s]);
                                    }
                                    Landing::Stuck => stuck = true,
                                }
                            }
                            if stuck {
                                edges[s][slot] = EdgeObs::Blocked;
                            }
                        }
                    }
                }
                vol[s] = vol[s].max(0.0);
            }
            if touched {
                mark(&mut u2, &mut in_u2, s);
                let ts = top(&vol, s);
                for nb in &topo.neighbours[s] {
                    let h = nb.site as usize;
                    // Only a higher neighbour now unstable towards s needs another look; it
                    // gets it in this pass when its excess is a real share of its snow (else
                    // two sites on a chute trade ever smaller amounts), in the next otherwise.
                    let excess = top(&vol, h) - ts - nb.distance * crit[h];
                    if excess > sp.level_tolerance_m && !in_heap[h] {
                        if work < cap && excess > 0.05 * vol[h] / areas[h] {
                            in_heap[h] = true;
                            heap.push((order_key(top(&vol, h)), Reverse(h)));
                        } else {
                            mark(&mut u2, &mut in_u2, h);
                        }
                    }
                }
            }
        }
        rep.passes += 1;
        rep.moved_m3 += moved;
        for &i in &u2 {
            in_u2[i] = false;
        }
        let small = moved <= sp.min_moved_fraction * total(&vol).max(1e-300);
        // Quiet: no shift above the quiet height, and little snow moved in all.
        let quiet = largest_shift <= sp.quiet_m && small;
        if std::time::Instant::now() > deadline {
            // The safety net: the caller turns this into an error, never a cover.
            rep.stopped_by_time = true;
            break;
        }
        // When a pass finds nothing to do, is quiet, or moves only a little, the whole phase is
        // re-run (Section 4.4: it "usually fixes a few missed sites and completes
        // immediately"); a re-check that finds nothing to do or is quiet ends the phase, else
        // passes go on over the sites still touched.
        if u2.is_empty() || quiet {
            if rechecking {
                rep.quiet = true;
                break;
            }
            rechecking = true;
            u1 = (0..n).collect();
        } else if small && !rechecking {
            rechecking = true;
            u1 = (0..n).collect();
        } else {
            rechecking = false;
            u1 = u2;
        }
    }
    sync(sites, topo, &vol);
    rep.volume_after_m3 = total(&vol);
    rep
}

/// A u64 that orders like the f64 height (for the max-heap).
fn order_key(z: f64) -> u64 {
    let b = z.to_bits();
    if b >> 63 == 1 { !b } else { b | (1 << 63) }
}

fn mark(list: &mut Vec<usize>, flag: &mut [bool], i: usize) {
    if !flag[i] {
        flag[i] = true;
        list.push(i);
    }
}

fn sync(sites: &mut LaunchSites, topo: &Topology, vol: &[f64]) {
    for (i, &c) in topo.leaves.iter().enumerate() {
        sites.cells[c as usize].volume = vol[i];
    }
}
