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
use crate::params::{FearingParams, StabilityPhaseParams};
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

/// The sites of one phase as they stand while it runs: centroids, horizontal areas, critical
/// angles (4.1) and the scene triangles that carry them.
struct PhaseSites {
    centroids: Vec<[f64; 3]>,
    areas: Vec<f64>,
    crit: Vec<f64>,
    owner: Vec<(u32, u32)>,
    site_tris: HashSet<(u32, u32)>,
    grid: SiteGrid,
    /// The lift of a ray's ends above the snow tops, m.
    eps: f64,
}

impl PhaseSites {
    /// Gathers the leaves of `topo` from `sites`, drawing each one's critical angle.
    fn gather(sites: &LaunchSites, topo: &Topology, params: &FearingParams) -> Self {
        let n = topo.leaves.len();
        let cell = |i: usize| topo.leaves[i] as usize;
        let centroids: Vec<[f64; 3]> = (0..n).map(|i| sites.cells[cell(i)].centroid()).collect();
        let areas: Vec<f64> = (0..n)
            .map(|i| sites.cells[cell(i)].area_xy().max(1e-300))
            .collect();
        let crit: Vec<f64> = (0..n)
            .map(|i| critical_tan(params, topo.leaves[i]))
            .collect();
        let owner: Vec<(u32, u32)> = (0..n)
            .map(|i| (sites.cells[cell(i)].object, sites.cells[cell(i)].triangle))
            .collect();
        let site_tris: HashSet<(u32, u32)> = owner.iter().copied().collect();
        let grid = SiteGrid::new(centroids.clone(), owner.clone(), sites.spacing.max(1e-6));
        PhaseSites {
            centroids,
            areas,
            crit,
            owner,
            site_tris,
            grid,
            eps: sites.spacing * 1e-3,
        }
    }

    /// The snow top of site `i`: its base plus its snow height, m.
    #[inline]
    fn top(&self, vol: &[f64], i: usize) -> f64 {
        self.centroids[i][2] + vol[i] / self.areas[i]
    }

    /// The scene triangle that carries site `i`, as the tracer tags it.
    fn triangle(&self, i: usize) -> Tag {
        Tag::Scene {
            object: self.owner[i].0,
            triangle: self.owner[i].1,
        }
    }

    /// The horizontal distance between sites `a` and `b`, m.
    fn distance(&self, a: usize, b: usize) -> f64 {
        (self.centroids[b][0] - self.centroids[a][0])
            .hypot(self.centroids[b][1] - self.centroids[a][1])
    }
}

/// The obstacle tests already made (4.2, step 2), per site: toward each neighbour and over each
/// border edge. They hold until the snow surfaces are rebuilt.
struct KnownObstacles {
    neighbours: Vec<Vec<Obs>>,
    edges: Vec<Vec<EdgeObs>>,
}

impl KnownObstacles {
    /// Nothing known yet.
    fn unknown(topo: &Topology) -> Self {
        KnownObstacles {
            neighbours: topo
                .neighbours
                .iter()
                .map(|v| vec![Obs::Unknown; v.len()])
                .collect(),
            edges: topo
                .borders
                .iter()
                .map(|v| vec![EdgeObs::Unknown; v.len()])
                .collect(),
        }
    }

    /// Forgets every test (the snow surfaces they were made against have been rebuilt).
    fn forget(&mut self) {
        self.neighbours
            .iter_mut()
            .flatten()
            .for_each(|o| *o = Obs::Unknown);
        self.edges
            .iter_mut()
            .flatten()
            .for_each(|o| *o = EdgeObs::Unknown);
    }
}

/// What a pass reads and never changes.
struct PassContext<'a> {
    topo: &'a Topology,
    sp: &'a StabilityPhaseParams,
    ps: &'a PhaseSites,
    flight: &'a Flight<'a>,
    /// The launch sites' spacing, m.
    spacing: f64,
    /// The phase's cap on site tests.
    max_tests: u64,
}

/// The work of one pass: the sites still to test in it (a max-heap by snow top), those for the
/// next pass (u2), and what its shifts moved.
struct Pass<'a> {
    heap: BinaryHeap<(u64, Reverse<usize>)>,
    in_heap: Vec<bool>,
    u2: Vec<usize>,
    in_u2: &'a mut [bool],
    /// Site tests so far, and the number after which sites wait for the next pass.
    work: usize,
    cap: usize,
    /// Snow moved, m³.
    moved: f64,
    /// The largest change of a site's snow height by one shift, m.
    largest_shift: f64,
}

impl Pass<'_> {
    /// Queues site `j` in this pass if it is not queued already.
    fn push(&mut self, ps: &PhaseSites, vol: &[f64], j: usize) {
        self.in_heap[j] = true;
        self.heap.push((order_key(ps.top(vol, j)), Reverse(j)));
    }

    /// A receiver is examined later in this pass (it is lower), or in the next one once the
    /// pass has done its share of work.
    fn receive(&mut self, ps: &PhaseSites, vol: &[f64], j: usize) {
        if self.work < self.cap {
            if !self.in_heap[j] {
                self.push(ps, vol, j);
            }
        } else {
            mark(&mut self.u2, self.in_u2, j);
        }
    }

    /// Counts a shift of `dv` m³ between sites of areas `area_a` and `area_b`.
    fn count_shift(&mut self, dv: f64, area_a: f64, area_b: f64) {
        self.moved += dv;
        self.largest_shift = self.largest_shift.max(dv / area_a.min(area_b));
    }
}

fn total(v: &[f64]) -> f64 {
    v.iter().sum::<f64>()
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
    let ps = PhaseSites::gather(sites, topo, params);
    let mut vol: Vec<f64> = (0..n)
        .map(|i| sites.cells[topo.leaves[i] as usize].volume)
        .collect();
    let bounds = scene
        .bounds()
        .expect("a scene with launch sites has bounds");
    let mut rep = StabilityReport {
        volume_before_m3: total(&vol),
        ..Default::default()
    };
    let mut known = KnownObstacles::unknown(topo);

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
            known.forget();
        }
        let tracer = tracer.as_ref().expect("built above");
        let has_sites = |o: u32, t: u32| ps.site_tris.contains(&(o, t));
        let flight = Flight {
            tracer,
            sites: &ps.grid,
            has_sites: &has_sites,
            z_floor: bounds.min[2] as f64 - sites.spacing,
            step: (sites.spacing * 0.5).max(1e-4),
            restitution: sp.restitution,
            rings: 8,
        };
        let ctx = PassContext {
            topo,
            sp,
            ps: &ps,
            flight: &flight,
            spacing: sites.spacing,
            max_tests,
        };
        let (u2, moved, largest_shift) =
            run_pass(&ctx, &u1, &mut vol, &mut known, &mut in_u2, &mut rep);
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

/// One pass (4.2): examines the work list u1 from the top down; higher neighbours that lose
/// their support re-enter this pass at once (so a drawdown climbs a slope in one pass),
/// receivers wait for the next one. Returns the next work list u2, the snow moved (m³) and the
/// largest change of a site's snow height by one shift (m).
fn run_pass(
    ctx: &PassContext,
    u1: &[usize],
    vol: &mut [f64],
    known: &mut KnownObstacles,
    in_u2: &mut [bool],
    rep: &mut StabilityReport,
) -> (Vec<usize>, f64, f64) {
    let ps = ctx.ps;
    let mut pass = Pass {
        heap: u1
            .iter()
            .map(|&i| (order_key(ps.top(vol, i)), Reverse(i)))
            .collect(),
        in_heap: vec![false; vol.len()],
        u2: Vec::new(),
        in_u2,
        work: 0,
        cap: 4 * u1.len() + 16,
        moved: 0.0,
        largest_shift: 0.0,
    };
    for &i in u1 {
        pass.in_heap[i] = true;
    }
    while let Some((_, Reverse(s))) = pass.heap.pop() {
        if rep.tests >= ctx.max_tests {
            break;
        }
        pass.in_heap[s] = false;
        pass.work += 1;
        rep.tests += 1;
        if test_site(ctx, s, vol, known, &mut pass, rep) {
            requeue_after_drawdown(ctx, s, vol, &mut pass);
        }
    }
    (pass.u2, pass.moved, pass.largest_shift)
}

/// The test of site `s` (4.2): finds its unstable neighbours and open border edges and shifts
/// snow evenly to them until none is unstable or `s` is bare. Returns whether snow moved.
fn test_site(
    ctx: &PassContext,
    s: usize,
    vol: &mut [f64],
    known: &mut KnownObstacles,
    pass: &mut Pass,
    rep: &mut StabilityReport,
) -> bool {
    let topo = ctx.topo;
    let mut touched = false;
    // Border edges whose receivers are full for this test.
    let mut full: Vec<usize> = Vec::new();
    for _ in 0..(2 * topo.neighbours[s].len() + 2 * topo.borders[s].len() + 4) {
        if vol[s] <= 0.0 {
            break;
        }
        let ts = ctx.ps.top(vol, s);
        let mut targets = Vec::new();
        unstable_neighbours(ctx, s, ts, vol, known, rep, &mut targets);
        unstable_edges(ctx, s, ts, known, &full, rep, &mut targets);
        if targets.is_empty() {
            break;
        }
        let dv = even_shift(ctx, s, ts, vol, &targets);
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
                    pass.count_shift(dv, ctx.ps.areas[s], ctx.ps.areas[site]);
                    pass.receive(ctx.ps, vol, site);
                }
                Target::Edge { slot, .. } => {
                    rep.edge_transits += 1;
                    pour_over_edge(ctx, s, slot, ts, dv, vol, known, &mut full, pass, rep);
                }
            }
        }
        vol[s] = vol[s].max(0.0);
    }
    touched
}

/// Steps 1 and 2 for the neighbours of `s` (snow top `ts`): those lower than `s` beyond its
/// critical angle and clear of obstacles, or the snow top in the way that receives instead.
fn unstable_neighbours(
    ctx: &PassContext,
    s: usize,
    ts: f64,
    vol: &[f64],
    known: &mut KnownObstacles,
    rep: &mut StabilityReport,
    targets: &mut Vec<Target>,
) {
    let (ps, sp) = (ctx.ps, ctx.sp);
    for (k, nb) in ctx.topo.neighbours[s].iter().enumerate() {
        let j = nb.site as usize;
        let allowed = nb.distance * ps.crit[s] + sp.level_tolerance_m;
        if ts - ps.top(vol, j) <= allowed {
            continue;
        }
        let obs = &mut known.neighbours[s][k];
        if *obs == Obs::Unknown {
            let from = [ps.centroids[s][0], ps.centroids[s][1], ts + ps.eps];
            let to = [
                ps.centroids[j][0],
                ps.centroids[j][1],
                ps.top(vol, j) + ps.eps,
            ];
            let own = [ps.triangle(s), ps.triangle(j)];
            *obs = obstacles::between(ctx.flight.tracer, from, to, own, ctx.topo.group[s], rep);
        }
        match *obs {
            Obs::Clear => targets.push(Target::Site { site: j, allowed }),
            Obs::Redirect(m) => {
                let m = m as usize;
                let allowed = ps.distance(s, m) * ps.crit[s] + sp.level_tolerance_m;
                if ts - ps.top(vol, m) > allowed
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
}

/// Steps 1 and 2 for the border edges of `s` (4.3, snow top `ts`): those lower than `s` beyond
/// its critical angle whose probe finds them open, skipping blocked ones and those whose
/// receivers are `full`.
fn unstable_edges(
    ctx: &PassContext,
    s: usize,
    ts: f64,
    known: &mut KnownObstacles,
    full: &[usize],
    rep: &mut StabilityReport,
    targets: &mut Vec<Target>,
) {
    let (ps, sp) = (ctx.ps, ctx.sp);
    for (k, e) in ctx.topo.borders[s].iter().enumerate() {
        let mid = [0, 1, 2].map(|q| 0.5 * (e.a[q] + e.b[q]));
        let (dx, dy) = (mid[0] - ps.centroids[s][0], mid[1] - ps.centroids[s][1]);
        let d = dx.hypot(dy);
        let allowed = d * ps.crit[s] + sp.level_tolerance_m;
        let edge = &mut known.edges[s][k];
        if ts - mid[2] <= allowed || *edge == EdgeObs::Blocked || full.contains(&k) {
            continue;
        }
        if *edge == EdgeObs::Unknown {
            let site = obstacles::EdgeSite {
                centre: [ps.centroids[s][0], ps.centroids[s][1], ts],
                own_tri: ps.triangle(s),
                group: ctx.topo.group[s],
            };
            *edge = obstacles::over_edge(ctx.flight, &site, e, ctx.spacing, sp, rep);
        }
        if let EdgeObs::Open { height, .. } = *edge
            && ts - height > allowed
        {
            targets.push(Target::Edge {
                slot: k,
                height,
                allowed,
            });
        }
    }
}

/// Step 3's even shift from `s` (snow top `ts`): the same volume to each target, the least that
/// makes one stable, m³. A neighbour counts as unstable beyond its angle plus the level
/// tolerance and is made stable at the angle itself, so rounding cannot re-trigger it at once.
fn even_shift(ctx: &PassContext, s: usize, ts: f64, vol: &[f64], targets: &[Target]) -> f64 {
    let (ps, tol) = (ctx.ps, ctx.sp.level_tolerance_m);
    let kf = targets.len() as f64;
    let mut dv = vol[s] / kf;
    for t in targets {
        let need = match *t {
            Target::Site { site, allowed } => {
                (ts - ps.top(vol, site) - allowed + tol) / (kf / ps.areas[s] + 1.0 / ps.areas[site])
            }
            Target::Edge {
                height, allowed, ..
            } => (ts - height - allowed + tol) / (kf / ps.areas[s]),
        };
        dv = dv.min(need.max(0.0));
    }
    dv
}

/// Sends `dv` m³ from `s` (snow top `ts`) over its open border edge `slot` (4.3), shared evenly
/// among the edge's landings: onto the sites they reach (each filled to halfway up to the
/// origin at most, which marks the edge `full`), out of the scene, or nowhere (which blocks the
/// edge).
#[allow(clippy::too_many_arguments)]
fn pour_over_edge(
    ctx: &PassContext,
    s: usize,
    slot: usize,
    ts: f64,
    dv: f64,
    vol: &mut [f64],
    known: &mut KnownObstacles,
    full: &mut Vec<usize>,
    pass: &mut Pass,
    rep: &mut StabilityReport,
) {
    let ps = ctx.ps;
    let EdgeObs::Open { landings, .. } = &known.edges[s][slot] else {
        unreachable!()
    };
    let share = dv / landings.len() as f64;
    let mut stuck = false;
    for l in landings {
        match *l {
            // Never onto snow standing higher than the origin (the landing was found on older
            // snow).
            Landing::Site(m) if ps.top(vol, m as usize) >= ts => stuck = true,
            Landing::Site(m) => {
                // The receiver may fill to halfway up to the origin, no more (else the snow
                // would flow back up).
                let m = m as usize;
                let give = share.min(0.5 * (ts - ps.top(vol, m)) * ps.areas[m]);
                if give < share && !full.contains(&slot) {
                    full.push(slot);
                }
                vol[s] -= give;
                vol[m] += give;
                pass.count_shift(give, ps.areas[s], ps.areas[m]);
                pass.receive(ps, vol, m);
            }
            Landing::Lost => {
                vol[s] -= share;
                rep.left_scene_m3 += share;
                pass.moved += share;
                pass.largest_shift = pass.largest_shift.max(share / ps.areas[s]);
            }
            Landing::Stuck => stuck = true,
        }
    }
    if stuck {
        known.edges[s][slot] = EdgeObs::Blocked;
    }
}

/// Step 4's follow-up once `s` has shed snow: `s` goes to u2, and a higher neighbour now
/// unstable towards `s` gets another look, in this pass when its excess is a real share of its
/// snow (else two sites on a chute trade ever smaller amounts), in the next otherwise.
fn requeue_after_drawdown(ctx: &PassContext, s: usize, vol: &[f64], pass: &mut Pass) {
    let ps = ctx.ps;
    mark(&mut pass.u2, pass.in_u2, s);
    let ts = ps.top(vol, s);
    for nb in &ctx.topo.neighbours[s] {
        let h = nb.site as usize;
        let excess = ps.top(vol, h) - ts - nb.distance * ps.crit[h];
        if excess > ctx.sp.level_tolerance_m && !pass.in_heap[h] {
            if pass.work < pass.cap && excess > 0.05 * vol[h] / ps.areas[h] {
                pass.push(ps, vol, h);
            } else {
                mark(&mut pass.u2, pass.in_u2, h);
            }
        }
    }
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
