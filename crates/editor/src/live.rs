//! Live avalanches and skiers, stepped on the server and streamed to the page: the temporal
//! zoom of Cordonnier et al. 2018, Section 3.1 ("avalanches and ski-tracks ... perceived as
//! dynamic phenomena"), with the flow of Section 6.1 and the skiers of Section 6.2.
//!
//! An avalanche the user triggers ruptures as the season's do ([`release_at_point`], the
//! unstable snow and powder released, α from the release's temperature), advances one record
//! interval at a time ([`AvalancheRun::advance_over`], entraining the snowpack on its track)
//! and deposits as stable snow at rest. After each record the tiles whose quantised flow thickness changed are sent ([`crate::wire`]). Unlike a
//! season avalanche it is not added to the season's avalanche list or mass budget: like a brush
//! stroke, it is a user edit of the snow.

use crate::wire::{self, Quant, TILE};
use serde::{Deserialize, Serialize};
use snowscape_avalanche::{
    AvalancheParams, AvalancheRun, AvalancheState, RunOptions, deposit, release, release_at_point,
};
use snowscape_season::avalanches::AvalancheParameters;
use snowscape_skiers::{SkiArea, SkiScratch};
use snowscape_terrain::{LayeredTerrain, SnowLayer};

/// Simulated seconds between two frames of a live avalanche (the season uses 0.1 s records;
/// 0.04 s gives 25 frames per simulated second).
pub const RECORD_INTERVAL_S: f64 = 0.04;

/// Where a live avalanche stands (sent as [`crate::protocol::ServerMessage::Avalanche`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AvalancheProgress {
    /// `started`, `running` or `ended`.
    pub phase: String,
    /// Rupture cell.
    pub col: usize,
    pub row: usize,
    /// Simulated seconds since the release.
    pub time_s: f64,
    /// Frames sent so far.
    pub records: u64,
    pub released_m3: f64,
    /// Snow in motion, m³.
    pub flowing_m3: f64,
    /// Snowpack entrained along the track so far, m³.
    #[serde(default)]
    pub entrained_m3: f64,
    pub max_speed_m_s: f64,
    /// Deposited snow, m³ (at the end).
    pub deposited_m3: f64,
    /// Why it ended (`at_rest`, `energy_criterion`, `duration`, `empty`).
    pub stop: Option<String>,
}

/// An avalanche in progress.
pub struct LiveAvalanche {
    run: AvalancheRun,
    flow: AvalancheParams,
    options: RunOptions,
    released_cells: Vec<bool>,
    /// Quantised flow thickness last sent.
    sent: Vec<u16>,
    pub progress: AvalancheProgress,
}

/// A list of tiles (column, row).
pub type Tiles = Vec<(usize, usize)>;

/// Tiles holding at least one flagged cell.
pub fn tiles_of_cells(cells: &[bool], width: usize) -> Vec<(usize, usize)> {
    let mut tiles = std::collections::BTreeSet::new();
    for (i, _) in cells.iter().enumerate().filter(|(_, on)| **on) {
        tiles.insert(((i % width) / TILE, (i / width) / TILE));
    }
    tiles.into_iter().collect()
}

impl LiveAvalanche {
    /// Ruptures the snow at cell (`col`, `row`); the released snow leaves the layers at once.
    /// Errors name the position and why nothing released.
    pub fn start(
        terrain: &mut LayeredTerrain,
        temperature: Option<&[f32]>,
        params: &AvalancheParameters,
        col: usize,
        row: usize,
    ) -> Result<Self, String> {
        let g = terrain.geometry().clone();
        if col >= g.width() || row >= g.height() {
            return Err(format!(
                "cell ({col}, {row}) is outside the {}x{} grid",
                g.width(),
                g.height()
            ));
        }
        let (x, y) = g.cell_centre(col, row);
        let rupture =
            release_at_point(terrain, x, y, &params.rupture).map_err(|e| e.to_string())?;
        let cells = rupture.mask.cells;
        let mut flow = params.flow.clone();
        if params.alpha_from_temperature
            && flow.friction == snowscape_avalanche::FrictionLaw::Coulomb
            && let Some(t) = temperature.filter(|t| t.len() == cells.len())
        {
            let (sum, n) = cells
                .iter()
                .zip(t)
                .filter(|(on, _)| **on)
                .fold((0.0, 0usize), |(s, n), (_, &v)| (s + v as f64, n + 1));
            if n > 0 {
                flow.alpha = params.alpha_at(sum / n as f64);
            }
        }
        let mut state = AvalancheState::from_terrain(terrain).map_err(|e| e.to_string())?;
        let released = release(terrain, &mut state, &cells, None).map_err(|e| e.to_string())?;
        let options = RunOptions {
            record_interval_s: RECORD_INTERVAL_S,
            ..params.run.clone()
        };
        options.validate().map_err(|e| e.to_string())?;
        let run = AvalancheRun::new(state);
        Ok(Self {
            run,
            flow,
            options,
            released_cells: cells,
            sent: vec![0; g.len()],
            progress: AvalancheProgress {
                phase: "started".into(),
                col,
                row,
                time_s: 0.0,
                records: 0,
                released_m3: released,
                flowing_m3: released,
                entrained_m3: 0.0,
                max_speed_m_s: 0.0,
                deposited_m3: 0.0,
                stop: None,
            },
        })
    }

    /// Tiles whose snow layers the release changed.
    pub fn release_tiles(&self) -> Vec<(usize, usize)> {
        tiles_of_cells(&self.released_cells, self.run.state.geometry().width())
    }

    /// Whether the flow has stopped.
    pub fn finished(&self) -> bool {
        self.run.stop_reason().is_some()
    }

    /// Advances one record interval; returns the flow thickness (grid-sized, m) and the tiles
    /// whose quantised thickness changed since the last call.
    pub fn advance(&mut self, terrain: &mut LayeredTerrain) -> Result<(Vec<f32>, Tiles), String> {
        self.run
            .advance_over(&self.flow, &self.options, terrain)
            .map_err(|e| e.to_string())?;
        let h: Vec<f32> = self
            .run
            .state
            .thickness()
            .iter()
            .map(|&v| v as f32)
            .collect();
        let w = self.run.state.geometry().width();
        let mut dirty = std::collections::BTreeSet::new();
        for (i, (&v, s)) in h.iter().zip(self.sent.iter_mut()).enumerate() {
            let q = Quant::THICKNESS.quantise(v);
            if q != *s {
                *s = q;
                dirty.insert(((i % w) / TILE, (i / w) / TILE));
            }
        }
        let p = &mut self.progress;
        p.phase = "running".into();
        p.records += 1;
        p.time_s = self.run.time();
        p.flowing_m3 = self.run.state.flowing_volume();
        p.entrained_m3 = self.run.entrained_volume();
        p.max_speed_m_s = p.max_speed_m_s.max(self.run.state.max_speed());
        Ok((h, dirty.into_iter().collect()))
    }

    /// Deposits the snow as stable snow; returns the tiles whose layers changed.
    pub fn finish(&mut self, terrain: &mut LayeredTerrain) -> Result<Vec<(usize, usize)>, String> {
        let footprint = self.run.footprint(0.0);
        let deposited = deposit(terrain, &mut self.run.state, SnowLayer::Stable, false)
            .map_err(|e| e.to_string())?;
        let p = &mut self.progress;
        p.phase = "ended".into();
        p.deposited_m3 = deposited;
        p.flowing_m3 = 0.0;
        p.stop = Some(
            match self.run.stop_reason() {
                Some(r) => format!("{r:?}"),
                None => "stopped".into(),
            }
            .to_lowercase(),
        );
        let mut cells = footprint;
        for (c, r) in cells.iter_mut().zip(&self.released_cells) {
            *c |= *r;
        }
        let w = terrain.geometry().width();
        Ok(tiles_of_cells(&cells, w))
    }
}

/// Live skiers (sent as [`crate::protocol::ServerMessage::Skiers`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SkierProgress {
    /// Positions of the skiers on the slopes, grid cells (col, row; cell centres at integers).
    pub positions: Vec<[f64; 2]>,
    /// The track of the first skier so far, grid cells.
    pub track: Vec<[f64; 2]>,
    /// Skiers still skiing.
    pub active: usize,
    /// Simulated seconds of the current descent.
    pub time_s: f64,
}

/// Cell coordinates of a local position (metres east and south of the north-west corner).
pub fn local_to_cell(terrain: &LayeredTerrain, p: (f64, f64)) -> [f64; 2] {
    let g = terrain.geometry();
    [p.0 / g.cell_size_x() - 0.5, p.1 / g.cell_size_y() - 0.5]
}

/// The skiers' progress message of `area`.
pub fn skier_progress(area: &SkiArea, terrain: &LayeredTerrain, time_s: f64) -> SkierProgress {
    let positions = area
        .skiers()
        .iter()
        .map(|s| local_to_cell(terrain, s.position()))
        .collect();
    let track = area
        .skiers()
        .first()
        .map(|s| {
            s.track()
                .vertices
                .iter()
                .map(|v| local_to_cell(terrain, (v[0], v[1])))
                .collect()
        })
        .unwrap_or_default();
    SkierProgress {
        positions,
        track,
        active: area.skiers().len(),
        time_s,
    }
}

/// The editor's skiers: their area (tracks, distance map) and work buffers.
pub struct LiveSkiers {
    pub area: SkiArea,
    pub scratch: SkiScratch,
    pub time_s: f64,
}

/// Tiles of a `width`x`height` grid within `margin` cells of the given cell positions.
pub fn tiles_near(
    points: &[[f64; 2]],
    width: usize,
    height: usize,
    margin: f64,
) -> Vec<(usize, usize)> {
    let (tw, th) = wire::tile_counts(width, height);
    let mut set = std::collections::BTreeSet::new();
    for p in points {
        for dc in [-margin, 0.0, margin] {
            for dr in [-margin, 0.0, margin] {
                let (c, r) = (p[0] + dc, p[1] + dr);
                if c >= 0.0 && r >= 0.0 {
                    let (tx, ty) = (c as usize / TILE, r as usize / TILE);
                    if tx < tw && ty < th {
                        set.insert((tx, ty));
                    }
                }
            }
        }
    }
    set.into_iter().collect()
}
