//! One avalanche on a layered terrain from release to rest, the one path the season, the
//! editor and the command line share: release → run → deposit, with what it did.
//!
//! [`AvalancheWorkspace::run_to_rest`] takes snow from the released cells (all unstable snow
//! and powder, or a thickness from the top of the pack down: [`crate::convert`]), runs the
//! flow until it stops ([`crate::run`]: at rest, the energy criterion, or the duration) and
//! lays every bit of it down into one layer (or leaves it across an open border). The
//! returned [`RestOutcome`] holds the run's figures, the volumes of its budget
//! (`released + entrained = deposited + border outflow` to round-off; the flow entrains the
//! snowpack it runs over, [`crate::entrainment`]) and the thickness taken and laid
//! down per cell, as sparse lists.
//!
//! **Cost.** The workspace keeps one flow state and its buffers through all the avalanches
//! of a terrain. The state reads the bed from the terrain only over the tiles the flow
//! touches, and is returned to rest over those tiles only ([`crate::flow`], *footprint*), so
//! an avalanche costs its footprint, not the grid: a season's avalanches no longer allocate,
//! zero or scan the whole grid.
//!
//! **Nothing lost.** If the run fails (too many sub-steps) or `on_record` stops it (an error
//! from it: cancellation), the snow in flight is laid down where it is before the error is
//! returned, so the terrain keeps its volume.

use crate::convert::{deposit, release_cells};
use crate::flow::{AvalancheError, AvalancheParams, AvalancheState};
use crate::friction_maps::FrictionMaps;
use crate::run::{AvalancheRun, RunBuffers, RunOptions, RunSummary};
use snowscape_terrain::{LayeredTerrain, SnowLayer};

/// What a run releases: `cells` (row-major indices; nodata cells are skipped), with
/// `thickness` `None` all their unstable snow and powder, else up to that many metres from the
/// top of the pack down.
#[derive(Debug, Clone, Copy)]
pub struct ReleasedCells<'a> {
    /// The released cells, row-major indices.
    pub cells: &'a [usize],
    /// Depth released from the top of the pack, m (`None`: the unstable snow and powder).
    pub thickness: Option<f64>,
}

impl<'a> ReleasedCells<'a> {
    /// The release of `cells` to `thickness`.
    pub fn new(cells: &'a [usize], thickness: Option<f64>) -> Self {
        Self { cells, thickness }
    }
}

/// What one avalanche did.
#[derive(Debug, Clone, PartialEq)]
pub struct RestOutcome {
    /// The run's figures (runout, angles, footprint, speeds, stop reason...).
    pub summary: RunSummary,
    /// Volume released from the terrain, m³.
    pub released_m3: f64,
    /// Volume the flow entrained from the snowpack on its way, m³.
    pub entrained_m3: f64,
    /// Volume laid down on the terrain, m³.
    pub deposited_m3: f64,
    /// Thickness taken from each released cell, (row-major index, m), ascending indices.
    pub released: Vec<(u32, f32)>,
    /// Thickness entrained per cell (the flow's scour of the snowpack beyond the release),
    /// (row-major index, m), in the order of the touched tiles.
    pub entrained: Vec<(u32, f32)>,
    /// Thickness laid down per cell, (row-major index, m), cells with a deposit only, in the
    /// order of the touched tiles.
    pub deposited: Vec<(u32, f32)>,
    /// Peak flowing thickness (m) and peak speed (m/s) per cell the run reached, (row-major
    /// index, value), cells with a positive peak only, in the order of the touched tiles: the
    /// run's maps over its footprint.
    pub peak_thickness: Vec<(u32, f64)>,
    pub peak_speed: Vec<(u32, f64)>,
    /// Records taken (calls of `on_record`).
    pub records: u64,
}

impl RestOutcome {
    /// A sparse list as a full grid of `len` cells (0 elsewhere).
    pub fn dense<T: Copy + Into<f64>>(cells: &[(u32, T)], len: usize) -> Vec<f64> {
        let mut out = vec![0.0; len];
        for &(i, v) in cells {
            if let Some(o) = out.get_mut(i as usize) {
                *o = v.into();
            }
        }
        out
    }
}

/// A flow state and its buffers kept from one avalanche to the next on one terrain.
#[derive(Debug, Default)]
pub struct AvalancheWorkspace {
    parts: Option<(AvalancheState, RunBuffers)>,
    /// Grid size and nodata flags the state was built for.
    key: Option<(usize, usize, Option<Vec<bool>>)>,
    /// Per-cell friction of every run (`crate::friction_maps`; empty: the law's scalars).
    friction: FrictionMaps,
    /// Whether the kept state has `friction` set.
    friction_set: bool,
}

/// A clone is an empty workspace with the same friction maps: the kept state is a work buffer (between runs it holds no
/// snow and a stale bed), and rebuilding it on the next run gives the same bits. Cloning a
/// season (the editor's snapshots) thus copies no flow state.
impl Clone for AvalancheWorkspace {
    fn clone(&self) -> Self {
        Self {
            friction: self.friction.clone(),
            ..Self::default()
        }
    }
}

impl AvalancheWorkspace {
    /// An empty workspace (the state is built on the first run).
    pub fn new() -> Self {
        Self::default()
    }

    /// Per-cell μ and ξ for the runs from now on (empty maps: the law's scalars).
    pub fn set_friction_maps(&mut self, maps: FrictionMaps) {
        self.friction = maps;
        self.friction_set = false;
    }

    /// The per-cell friction of the runs.
    pub fn friction_maps(&self) -> &FrictionMaps {
        &self.friction
    }

    /// Releases the cells of `release` of `terrain` (see [`ReleasedCells`]); runs the flow
    /// `flow` to rest under `options`, calling `on_record` after every record interval; lays
    /// the snow down into `deposit_layer`.
    pub fn run_to_rest<E: From<AvalancheError>>(
        &mut self,
        terrain: &mut LayeredTerrain,
        release: ReleasedCells,
        flow: &AvalancheParams,
        options: &RunOptions,
        deposit_layer: SnowLayer,
        mut on_record: impl FnMut(&AvalancheRun) -> Result<(), E>,
    ) -> Result<RestOutcome, E> {
        flow.validate()?;
        options.validate()?;
        self.friction.check_for(terrain.geometry(), flow)?;
        let (mut state, buffers) = self.take_parts(terrain)?;
        let ReleasedCells { cells, thickness } = release;
        let released_m3 = match release_cells(terrain, &mut state, cells, thickness) {
            Ok(v) => v,
            Err(e) => {
                // Nothing moved yet but what was released: lay it back down.
                deposit(terrain, &mut state, deposit_layer, false)?;
                self.parts = Some((state, buffers));
                return Err(e.into());
            }
        };
        let released: Vec<(u32, f32)> = cells
            .iter()
            .filter(|&&i| terrain.mask().is_valid(i))
            .map(|&i| {
                let g = terrain.geometry();
                (
                    i as u32,
                    state.thickness_at(i % g.width(), i / g.width()) as f32,
                )
            })
            .collect();
        let mut run = AvalancheRun::with_buffers(state, buffers);
        let mut records = 0u64;
        // A helper thread for the run's small sub-steps (when the pool has two threads or
        // more); stopped at the end of the run.
        let team = crate::flow::Team::start();
        if let Some(t) = &team {
            run.scratch_mut().set_team(t.handle());
        }
        let result = run.run_over::<E>(flow, options, terrain, |r| {
            records += 1;
            on_record(r)
        });
        run.scratch_mut().set_team(Default::default());
        drop(team);
        let w = terrain.geometry().width();
        let mut entrained = Vec::new();
        let mut deposited = Vec::new();
        let (mut peak_thickness, mut peak_speed) = (Vec::new(), Vec::new());
        for (r0, r1, c0, c1) in run.touched_cells() {
            for r in r0..=r1 {
                for c in c0..=c1 {
                    let i = r * w + c;
                    let h = run.state.snow_at(c, r);
                    if h > 0.0 {
                        deposited.push((i as u32, h as f32));
                    }
                    if run.entrained()[i] > 0.0 {
                        entrained.push((i as u32, run.entrained()[i] as f32));
                    }
                    if run.peak_thickness()[i] > 0.0 {
                        peak_thickness.push((i as u32, run.peak_thickness()[i]));
                    }
                    if run.peak_speed()[i] > 0.0 {
                        peak_speed.push((i as u32, run.peak_speed()[i]));
                    }
                }
            }
        }
        let run_entrained_m3 = run.entrained_volume();
        let deposited_m3 = deposit(terrain, &mut run.state, deposit_layer, false)?;
        self.parts = Some(run.into_parts());
        Ok(RestOutcome {
            summary: result?,
            released_m3,
            entrained_m3: run_entrained_m3,
            deposited_m3,
            released,
            entrained,
            deposited,
            peak_thickness,
            peak_speed,
            records,
        })
    }

    /// The kept state, returned to rest with a stale bed, or a new one if the grid or its
    /// nodata cells changed.
    fn take_parts(
        &mut self,
        terrain: &LayeredTerrain,
    ) -> Result<(AvalancheState, RunBuffers), AvalancheError> {
        let g = terrain.geometry();
        let same = self.key.as_ref().is_some_and(|(w, h, m)| {
            *w == g.width() && *h == g.height() && m.as_deref() == terrain.mask().invalid_cells()
        });
        let (mut state, buffers) = match self.parts.take() {
            Some((mut state, buffers)) if same => {
                state.reset_touched();
                (state, buffers)
            }
            _ => {
                self.key = Some((
                    g.width(),
                    g.height(),
                    terrain.mask().invalid_cells().map(<[bool]>::to_vec),
                ));
                self.friction_set = false;
                (
                    AvalancheState::on_terrain_lazily(terrain)?,
                    RunBuffers::default(),
                )
            }
        };
        if !self.friction_set {
            state.set_friction_maps(&self.friction)?;
            self.friction_set = true;
        }
        Ok((state, buffers))
    }
}
