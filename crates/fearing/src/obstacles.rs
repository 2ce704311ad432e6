//! The obstacle tests of the stability phase (Fearing 2000, Sections 4.2 step 2 and 4.3),
//! whose outcomes the phase caches until it rebuilds the snow surfaces.
//!
//! Between a site and a lower neighbour, a segment from snow top to snow top (ignoring the two
//! sites' own triangles and their group's own snow) meets: nothing (the avalanche may go),
//! scene geometry (case i, blocked), another group's closing wall (case ii, blocked), or
//! another group's snow top (case iii: that site receives the snow instead). Over a border
//! edge, a short horizontal probe from the site's snow top to just beyond the edge that meets
//! anything blocks the edge until the snow rises above the obstacle; otherwise the height just
//! beyond the edge (the first surface below the probe, or the edge itself) is what the snow is
//! compared with, and the avalanche particles' landings are traced once.

use crate::edge_groups::BorderEdge;
use crate::edge_transit::{Flight, Landing, fly};
use crate::params::StabilityPhaseParams;
use crate::stability::StabilityReport;
use crate::tracer::{Tag, Tracer};

/// Outcome of an obstacle test between a site and a neighbour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Obs {
    Unknown,
    Clear,
    Geometry,
    Wall,
    /// Another group's snow is in the way: its site (topology index) receives the snow.
    Redirect(u32),
}

/// Outcome of the probe over a border edge, and where its particles land.
#[derive(Debug, Clone, PartialEq)]
pub enum EdgeObs {
    Unknown,
    Blocked,
    Open { height: f64, landings: Vec<Landing> },
}

/// Whether `t` is snow of `group`.
pub fn own_snow(t: Tag, group: u32) -> bool {
    matches!(t, Tag::SnowTop { group: g, .. } | Tag::SnowWall { group: g } if g == group)
}

/// The obstacle test from `from` to `to` (snow tops), ignoring `own` and `group`'s snow.
pub fn between(
    tracer: &Tracer,
    from: [f64; 3],
    to: [f64; 3],
    own: [Tag; 2],
    group: u32,
    rep: &mut StabilityReport,
) -> Obs {
    match tracer.first_hit(from, to, |t| {
        t == own[0] || t == own[1] || own_snow(t, group)
    }) {
        None => Obs::Clear,
        Some(h) => match h.tag {
            Tag::Scene { .. } => {
                rep.blocked_by_geometry += 1;
                Obs::Geometry
            }
            Tag::SnowWall { .. } => {
                rep.blocked_by_snow_wall += 1;
                Obs::Wall
            }
            Tag::SnowTop { site, .. } => {
                rep.redirected += 1;
                Obs::Redirect(site)
            }
        },
    }
}

/// The site whose snow an edge probe starts from.
#[derive(Debug, Clone, Copy)]
pub struct EdgeSite {
    /// Its snow top: centroid x, y and the top's z, m.
    pub centre: [f64; 3],
    /// Its own triangle, which the probe's rays pass through.
    pub own_tri: Tag,
    /// Its group (its own snow, which the rays pass through too).
    pub group: u32,
}

/// The probe over border edge `e` of `site` (sites `spacing` m apart).
pub fn over_edge(
    flight: &Flight,
    site: &EdgeSite,
    e: &BorderEdge,
    spacing: f64,
    sp: &StabilityPhaseParams,
    rep: &mut StabilityReport,
) -> EdgeObs {
    let EdgeSite {
        centre,
        own_tri,
        group,
    } = *site;
    let eps = spacing * 1e-3;
    let mid = [0, 1, 2].map(|q| 0.5 * (e.a[q] + e.b[q]));
    let (dx, dy) = (mid[0] - centre[0], mid[1] - centre[1]);
    let d = dx.hypot(dy);
    let out = if d > 1e-12 {
        [dx / d, dy / d]
    } else {
        [e.b[1] - e.a[1], e.a[0] - e.b[0]]
    };
    let ol = out[0].hypot(out[1]).max(1e-300);
    let out = [out[0] / ol, out[1] / ol];
    let margin = (0.05 * spacing).max(4.0 * eps);
    let probe = [
        mid[0] + out[0] * margin,
        mid[1] + out[1] * margin,
        centre[2] + eps,
    ];
    let skip = |t: Tag| t == own_tri || own_snow(t, group);
    if flight
        .tracer
        .blocked([centre[0], centre[1], centre[2] + eps], probe, skip)
    {
        rep.blocked_edges += 1;
        return EdgeObs::Blocked;
    }
    let below = [probe[0], probe[1], mid[2] - spacing];
    let beyond = flight
        .tracer
        .first_hit(probe, below, skip)
        .map(|h| probe[2] + h.t as f64 * (below[2] - probe[2]));
    let np = sp.edge_particles;
    let landings = (0..np)
        .map(|p| {
            rep.particles += 1;
            let speed = sp.edge_speed_m_s * (0.5 + (p as f64 + 0.5) / np as f64);
            fly(flight, probe, [out[0] * speed, out[1] * speed, 0.0], group)
        })
        .collect();
    EdgeObs::Open {
        height: beyond.map_or(mid[2], |z| z.max(mid[2])),
        landings,
    }
}
