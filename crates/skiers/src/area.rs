//! [`SkiArea`]: the skiers of a terrain, their tracks and maps, and the pure [`step`].
//!
//! **Step.** `step(params, area, terrain, scratch, dt)` moves every skier for `dt` seconds in
//! two phases:
//! 1. *Move* (parallel over skiers): each skier reads the terrain as it was at the start of the
//!    step and writes only its own state and its own event list (refined-track segments, cell
//!    passes).
//! 2. *Apply* (sequential, in skier order): segments are drawn into the track texture, and each
//!    pass triggers (keyed draw), compacts the cell and updates the recent-skier map. Stopped
//!    skiers are removed and their tracks kept.
//!
//! Every random number is keyed by (seed, skier id, per-skier counter), and the apply phase
//! runs in a fixed order, so the result is bit-identical for any rayon thread count.

use crate::effects::{
    Compaction, RecentSkiers, TRIGGER, TriggerCandidate, compact_cell, trigger_probability,
};
use crate::frame::{SnowView, local_to_map, map_to_local};
use crate::skier::{Event, Skier, StepContext, StopReason, Track};
use crate::steering::SteeringRule;
use crate::terminus::{Terminus, TerminusMap};
use crate::texture::TrackTexture;
use crate::{SkiError, SkiParams};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use snowscape_terrain::random::uniform;
use snowscape_terrain::{GridGeometry, LayeredTerrain, SnowLayer};

/// Key purpose of spawn draws.
const SPAWN: u64 = 0x0053_5041_574e;
/// Draws tried per weighted spawn before giving up on a skier.
const SPAWN_TRIES: u64 = 64;

/// The skiers of one terrain: the distance map, the skiers on the slopes, finished tracks, the
/// track texture, the recent-skier map and the clock.
#[derive(Debug, Clone)]
pub struct SkiArea {
    pub(crate) geometry: GridGeometry,
    pub(crate) seed: u64,
    /// Simulation time, s. Tracks and passes are stamped with it; the season may set it.
    pub time_s: f64,
    pub(crate) next_id: u64,
    pub(crate) terminus: TerminusMap,
    pub(crate) skiers: Vec<Skier>,
    pub(crate) finished: Vec<Track>,
    pub(crate) texture: TrackTexture,
    pub(crate) recent: RecentSkiers,
}

/// Buffers reused by [`step`] (one event list per skier).
#[derive(Debug, Clone, Default)]
pub struct SkiScratch {
    events: Vec<Vec<Event>>,
    moved: Vec<f64>,
}

/// A skier that stopped during a step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FinishedSkier {
    /// Skier id.
    pub id: u64,
    /// Why it stopped.
    pub stop: StopReason,
    /// Horizontal length of its refined track, m.
    pub length_m: f64,
}

/// What one call to [`step`] did.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct SkierReport {
    /// Skiers still on the slopes after the step.
    pub active: usize,
    /// Skiers that stopped during the step (removed; their tracks are kept).
    pub finished: Vec<FinishedSkier>,
    /// Cell passes completed (cells left or stopped in).
    pub passes: usize,
    /// Coarse distance travelled by all skiers, m.
    pub distance_m: f64,
    /// Snow packed by the skiers.
    pub compaction: Compaction,
    /// Cells where a skier released unstable snow.
    pub triggers: Vec<TriggerCandidate>,
}

fn check_terrain(geometry: &GridGeometry, terrain: &LayeredTerrain) -> Result<(), SkiError> {
    let g = terrain.geometry();
    if g.width() != geometry.width() || g.height() != geometry.height() {
        return Err(SkiError::GeometryMismatch {
            width: geometry.width(),
            height: geometry.height(),
            terrain_width: g.width(),
            terrain_height: g.height(),
        });
    }
    Ok(())
}

impl SkiArea {
    /// A ski area on `terrain` with the termini `rule` and the random `seed`; computes the
    /// distance map and an empty track texture of `params.texels_per_cell`.
    pub fn new(
        params: &SkiParams,
        terrain: &LayeredTerrain,
        rule: Terminus,
        seed: u64,
    ) -> Result<Self, SkiError> {
        params.validate()?;
        let g = terrain.geometry().clone();
        let terminus = TerminusMap::compute(params, terrain, &rule)?;
        let texture = TrackTexture::new(
            g.width(),
            g.height(),
            g.cell_size_x(),
            g.cell_size_y(),
            params.texels_per_cell,
        )?;
        Ok(Self {
            recent: RecentSkiers::new(g.len()),
            geometry: g,
            seed,
            time_s: 0.0,
            next_id: 0,
            terminus,
            skiers: Vec::new(),
            finished: Vec::new(),
            texture,
        })
    }

    /// Recomputes the distance map with the same termini rule. The map is a snapshot of the
    /// snow cover: skiers always test the live snow before entering a cell, but their route
    /// guide and the spawn weights follow the map, so the season refreshes it when the snow has
    /// changed (after a snowfall or melt event, say).
    pub fn refresh_terminus(
        &mut self,
        params: &SkiParams,
        terrain: &LayeredTerrain,
    ) -> Result<(), SkiError> {
        let rule = self.terminus.rule().clone();
        self.set_terminus(params, terrain, rule)
    }

    /// Recomputes the distance map for another termini rule.
    pub fn set_terminus(
        &mut self,
        params: &SkiParams,
        terrain: &LayeredTerrain,
        rule: Terminus,
    ) -> Result<(), SkiError> {
        check_terrain(&self.geometry, terrain)?;
        self.terminus = TerminusMap::compute(params, terrain, &rule)?;
        Ok(())
    }

    /// The grid geometry.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }
    /// The random seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }
    /// The distance-to-terminus map.
    pub fn terminus(&self) -> &TerminusMap {
        &self.terminus
    }
    /// Skiers on the slopes, in id order.
    pub fn skiers(&self) -> &[Skier] {
        &self.skiers
    }
    /// Tracks of skiers that stopped, in the order they stopped.
    pub fn finished_tracks(&self) -> &[Track] {
        &self.finished
    }
    /// Removes and returns the finished tracks (a long season can write and drop them).
    pub fn take_finished_tracks(&mut self) -> Vec<Track> {
        std::mem::take(&mut self.finished)
    }
    /// Every track, finished ones first, then those of skiers on the slopes.
    pub fn tracks(&self) -> impl Iterator<Item = &Track> {
        self.finished
            .iter()
            .chain(self.skiers.iter().map(|s| s.track()))
    }
    /// The track texture.
    pub fn texture(&self) -> &TrackTexture {
        &self.texture
    }

    /// Fades the track texture under `added_depth` (m of new or drifted snow per cell, see
    /// [`TrackTexture::fade`]), with `params.fade_depth_m`.
    pub fn fade_tracks(&mut self, params: &SkiParams, added_depth: &[f32]) -> Result<(), SkiError> {
        self.texture.fade(added_depth, params.fade_depth_m)
    }

    /// The recent-skier map at the current time (decayed pass counts per cell).
    pub fn recent_skiers(&self, params: &SkiParams) -> Vec<f32> {
        self.recent.map(self.time_s, params.recent_decay_s)
    }

    /// The factor by which recent skiers raise the avalanche probability of cell `i`:
    /// `1 + trigger_recent_gain · r` on unstable snow, 1 elsewhere.
    pub fn release_factor(&self, params: &SkiParams, terrain: &LayeredTerrain, i: usize) -> f64 {
        if terrain.layer(SnowLayer::Unstable)[i] <= 0.0 {
            return 1.0;
        }
        1.0 + params.trigger_recent_gain * self.recent.at(i, self.time_s, params.recent_decay_s)
    }

    /// Puts a new skier at local position `pos` of `cell`, heading down the fall line, and
    /// plans its first move.
    fn place(
        &mut self,
        params: &SkiParams,
        terrain: &LayeredTerrain,
        pos: (f64, f64),
        cell: (usize, usize),
    ) -> u64 {
        let id = self.next_id;
        self.next_id += 1;
        let view = SnowView::new(terrain, params.min_snow_depth_m);
        let (gx, gy) = view.gradient(cell.0, cell.1);
        let g = gx.hypot(gy);
        let heading = if g > 1e-9 {
            (-gx / g, -gy / g)
        } else {
            (1.0, 0.0)
        };
        let mut skier = Skier::new(
            id,
            self.time_s,
            pos,
            cell,
            heading,
            params.amplitude_m,
            view.width,
        );
        let ctx = self.context(params, view, 0.0);
        let i = cell.1 * view.width + cell.0;
        if self.terminus.is_terminus(i) {
            skier.stop_now(StopReason::Terminus, self.time_s);
        } else if !skier.steer(&ctx, false) {
            skier.stop_now(StopReason::Stuck, self.time_s);
        }
        self.skiers.push(skier);
        id
    }

    /// Starts a skier at map point `(x, y)` (CRS units). Errors when the point lies outside the
    /// grid, on nodata, or on a cell without enough snow to ski.
    pub fn spawn_at(
        &mut self,
        params: &SkiParams,
        terrain: &LayeredTerrain,
        x: f64,
        y: f64,
    ) -> Result<u64, SkiError> {
        params.validate()?;
        check_terrain(&self.geometry, terrain)?;
        let (pos, (col, row)) = map_to_local(&self.geometry, "start point", x, y)?;
        let i = row * self.geometry.width() + col;
        if !terrain.mask().is_valid(i) {
            return Err(SkiError::OnNodata {
                what: "start point",
                col,
                row,
            });
        }
        let depth = f64::from(terrain.depth_at(i));
        if depth <= params.min_snow_depth_m && !self.terminus.is_terminus(i) {
            return Err(SkiError::NotEnoughSnow {
                col,
                row,
                depth_m: depth,
                threshold_m: params.min_snow_depth_m,
            });
        }
        Ok(self.place(params, terrain, pos, (col, row)))
    }

    /// Starts up to `count` skiers in cells drawn with probability proportional to their
    /// distance to the terminus (the paper's weighted spawn mask: far from the terminus is the
    /// start of a long run), at a keyed random point of the cell. A drawn cell that has lost its
    /// snow since the map was computed is drawn again (up to 64 times). Returns the new ids.
    pub fn spawn_weighted(
        &mut self,
        params: &SkiParams,
        terrain: &LayeredTerrain,
        count: usize,
    ) -> Result<Vec<u64>, SkiError> {
        params.validate()?;
        check_terrain(&self.geometry, terrain)?;
        let (w, dx, dy) = (
            self.geometry.width(),
            self.geometry.cell_size_x(),
            self.geometry.cell_size_y(),
        );
        let mut ids = Vec::with_capacity(count);
        for _ in 0..count {
            let key = self.next_id;
            let mut placed = None;
            for attempt in 0..SPAWN_TRIES {
                let u = uniform(self.seed ^ SPAWN, key, 3 * attempt);
                let Some(i) = self.terminus.spawn_cell(u) else {
                    break;
                };
                let depth = f64::from(terrain.depth_at(i));
                if terrain.mask().is_valid(i) && depth > params.min_snow_depth_m {
                    let (col, row) = (i % w, i / w);
                    let jx = uniform(self.seed ^ SPAWN, key, 3 * attempt + 1);
                    let jy = uniform(self.seed ^ SPAWN, key, 3 * attempt + 2);
                    let pos = ((col as f64 + jx) * dx, (row as f64 + jy) * dy);
                    placed = Some((pos, (col, row)));
                    break;
                }
            }
            match placed {
                Some((pos, cell)) => ids.push(self.place(params, terrain, pos, cell)),
                None => break,
            }
        }
        Ok(ids)
    }

    fn context<'a>(
        &'a self,
        params: &SkiParams,
        view: SnowView<'a>,
        time0: f64,
    ) -> StepContext<'a> {
        StepContext {
            view,
            map: &self.terminus,
            rule: SteeringRule::new(params),
            seed: self.seed,
            speed: params.speed_m_s,
            turn_distance: params.turn_distance_m,
            target_slope: params.target_slope_rad(),
            amplitude: params.amplitude_m,
            min_frequency: params.min_frequency_per_m,
            vertex_spacing: params.vertex_spacing_m,
            max_run: params.max_run_length_m,
            time0,
        }
    }
}

/// Moves every skier of `area` for `dt` seconds on `terrain`, draws their tracks, packs the
/// snow they cross and reports triggers (see the module docs).
pub fn step(
    params: &SkiParams,
    area: &mut SkiArea,
    terrain: &mut LayeredTerrain,
    scratch: &mut SkiScratch,
    dt: f64,
) -> Result<SkierReport, SkiError> {
    params.validate()?;
    if !(dt.is_finite() && dt >= 0.0) {
        return Err(SkiError::InvalidTimeStep(dt));
    }
    check_terrain(&area.geometry, terrain)?;
    let n = area.skiers.len();
    scratch.events.resize_with(n, Vec::new);
    scratch.moved.resize(n, 0.0);
    let time0 = area.time_s;
    {
        let view = SnowView::new(terrain, params.min_snow_depth_m);
        let mut skiers = std::mem::take(&mut area.skiers);
        let ctx = area.context(params, view, time0);
        skiers
            .par_iter_mut()
            .zip(scratch.events[..n].par_iter_mut())
            .zip(scratch.moved[..n].par_iter_mut())
            .for_each(|((skier, events), moved)| {
                events.clear();
                let before = skier.track().coarse_length_m;
                skier.advance(&ctx, dt, events);
                *moved = skier.track().coarse_length_m - before;
            });
        area.skiers = skiers;
    }
    let mut report = SkierReport::default();
    let area_m2 = area.geometry.cell_area();
    let w = area.geometry.width();
    let width_m = params.track_width_m;
    for (skier, events) in area.skiers.iter().zip(&scratch.events[..n]) {
        let id = skier.id();
        for e in events {
            match *e {
                Event::Segment(a, b) => {
                    area.texture.draw_segment(a, b, width_m);
                }
                Event::Pass {
                    cell,
                    length_m,
                    time_s,
                    pass,
                } => {
                    report.passes += 1;
                    let view = SnowView::new(terrain, params.min_snow_depth_m);
                    let (col, row) = (cell % w, cell / w);
                    let recent = area.recent.at(cell, time_s, params.recent_decay_s);
                    let unstable = f64::from(terrain.layer(SnowLayer::Unstable)[cell]);
                    let slope = view.slope(col, row);
                    let p = trigger_probability(params, unstable, slope, recent, length_m);
                    if p > 0.0 && uniform(area.seed ^ TRIGGER, id, pass) < p {
                        let (cx, cy) = view.centre(col, row);
                        let (x, y) = local_to_map(&area.geometry, cx, cy);
                        report.triggers.push(TriggerCandidate {
                            cell,
                            col,
                            row,
                            x,
                            y,
                            skier: id,
                            time_s,
                            probability: p,
                            unstable_m: unstable,
                            slope_deg: slope.to_degrees(),
                        });
                    }
                    let amount = params.compaction_depth_m * width_m * length_m / area_m2;
                    report.compaction += compact_cell(params, terrain, cell, amount, area_m2);
                    area.recent.record(cell, time_s, params.recent_decay_s);
                }
            }
        }
    }
    report.distance_m = scratch.moved[..n].iter().sum();
    area.time_s = time0 + dt;
    for skier in area.skiers.extract_if(.., |s| s.stopped()) {
        report.finished.push(FinishedSkier {
            id: skier.id(),
            stop: skier.track.stop.unwrap_or(StopReason::Stuck),
            length_m: skier.track.length_m,
        });
        area.finished.push(skier.track);
    }
    report.active = area.skiers.len();
    Ok(report)
}
