//! Gravitational shedding of snow from steep slopes: SnowSlide (Bernhardt & Schulz 2010,
//! "SnowSlide: A simple routine for calculating gravitational snow transport", Geophys. Res.
//! Lett. 37, L11502), as run operationally in FSM2oshd (Quéno et al. 2024, The Cryosphere 18).
//!
//! **Holding depth.** A cell holds at most `D_hold(s)` metres of snow (vertical thickness, like
//! every layer of [`LayeredTerrain`]), a function of a slope `s` in degrees, from one of two
//! published forms, selected by [`SheddingParams::law`]:
//!
//! * [`HoldingLaw::Exponential`] (default): `D_hold = max(d_min, c · exp(−a · s))`, `c = 145 m`,
//!   `a = 0.14 /°`, `d_min = 0.05 m`: the defaults of the OGGM `Snowslide` package (IGE
//!   Grenoble, `snd_max_exponential`, "parameters estimated from Bernhardt & Schulz"). It gives
//!   4.4 m at 25°, 2.2 m at 30°, 1.1 m at 35°, 0.27 m at 45°, 0.13 m at 50° and the 5 cm floor
//!   from 56° up: rock faces hold a few centimetres.
//! * [`HoldingLaw::PowerLaw`]: `D_hold = max(d_min, c · max(s, 10°)^b)`, `c = 3178.4`,
//!   `b = −1.998`, as in the Canadian Hydrological Model's `snow_slide` module (Marsh et al.),
//!   which attributes it to Bernhardt & Schulz 2010 and reads it in metres. It holds 3.5 m at
//!   30° and still 0.89 m at 60°.
//!
//! We could not check either form against the text of Bernhardt & Schulz 2010 itself; both are
//! cited through the implementations above.
//!
//! **Which slope.** Slopes are steepest descents to one of the 8 neighbours, the slope snow
//! would slide down (central differences would call the flat cell at the foot of a cliff
//! steep). A cell's slope is that of its bed, the bedrock plus its compacted snow, unless its
//! snow surface at the start of the step descends more gently (a hollow filled with snow does
//! not shed, whatever the rock beneath it does). A cell that received snow during the step
//! takes the descent of its snow surface to its neighbours' (as seen by the sweep, below), and
//! keeps the depth `d` that equals its holding depth on the slope its surface has when it
//! keeps `d` (a fixed point, found by regula falsi to 0.1 mm): debris spreads into a cone at the foot of a
//! face instead of standing as a one-cell tower on flat ground, which holds 145 m (OGGM
//! Snowslide evaluates every cell on the snow surface), and a hollow filling with debris stops
//! shedding when its surface levels out.
//!
//! **Which cells shed.** A cell sheds its excess `depth − D_hold` when its slope is at least
//! `min_slope_deg` (FSM2oshd's `slope_min` = 30°), or when it received snow during this step
//! (FSM2oshd drops the slope threshold for receiving cells). A receiving cell whose bedrock
//! descends less steeply than [`SheddingParams::entrain_min_slope_deg`] (default 45°) keeps
//! at least the depth it had at the start of the step: it passes on what it cannot hold of
//! what it received, and its own snow stays (FSM2oshd, with `entrain_min_slope_deg = 0`,
//! sheds a receiver's whole excess: every sluff off a face then strips the 30-45° slopes
//! below it, whose release is the avalanche module's job). A receiving cell may also use a
//! reduced holding depth `max(d_min, dynamic_ratio · D_hold)`, FSM2oshd's "dynamic" holding
//! depth of snow already in motion (`dyn_ratio` = 0.09 there); our default is 1 (no
//! reduction): with 0.09 a slide entrains the cover of every 25–35° slope it crosses. The
//! excess is taken from the top of the column down: powder, unstable, stable, then compacted
//! snow. Deposited snow lands in [`SheddingParams::deposit_layer`] (default unstable: loose
//! sluff debris that can load and release on the slope below; the avalanche module lays its
//! denser debris down as stable snow).
//!
//! **Order: one sweep.** Every cell is processed after each of its neighbours whose *bedrock*
//! lies above it (ties, on level ground, broken by a scrambled but fixed order: by index,
//! every debris flow on level ground would run one way), in an order built once by a
//! depth-first climb from each cell and cached in the scratch while the bedrock and the mask
//! are unchanged (the published SnowSlide codes sort by altitude plus snow depth, CHM every
//! step, FSM2oshd once; any order that puts senders before receivers gives the same cascade,
//! and one that stays local in the grid keeps the sweep in cache), so a receiver below is
//! processed after its senders and sheds its own excess in turn: the cascade runs from the
//! crests to the valleys in one pass. A sender sees
//! a neighbour the sweep has not reached with the surface it is expected to keep, its surface
//! at the start of the step less its own excess (its receipts are in transit; judging by them
//! would jam a long face behind its own falling snow), and one it has passed with its current
//! surface. Snow also flows to a passed neighbour whose surface is lower (a drift beside a
//! bare rib, the near side of a debris cone on level ground); such a receiver enters a queue (highest
//! snow surface first) that is drained before the sweep moves on, and so that nothing
//! ping-pongs the sender never ends below it: the amount shed is limited to
//! `min_j (A_i − A_j) / (1 + w_j)` over passed receivers (`w_j` the normalised weights); a
//! round cut by this limit is followed by another without that receiver. A holding depth is
//! evaluated on the surfaces of the moment the cell is processed: a slope that steepens
//! later, as the cells below shed, does not bring the cell back, so a second step can still
//! move a little. A safety budget of 16 revisits per valid cell bounds the work; cells still
//! queued when it runs out are reported as `unsettled_cells`.
//!
//! **Routing (multiple flow directions).** The excess goes to the lower neighbours among the 8
//! in proportion to `tan(β_j)^p = ((A'_i − A_j) / L_j)^p` (Freeman 1991, Computers &
//! Geosciences 17(3), 413-422; `p = 1.1`; `p = 1` is Quinn et al. 1991 without their
//! contour-length factors), with `A_j` the neighbour's snow surface `B + C + S + U + P` as seen
//! and `L_j = dx, dy` or `√(dx² + dy²)`. `A'_i` is the surface the sender will have once its
//! excess is gone, so that snow in transit down a face runs down it instead of spilling
//! sideways onto the neighbours that already shed (which would also cost a revisit each); if
//! no neighbour lies below that, the sender's current surface (a pile on level ground spreads).
//! Past the grid border, and into nodata (the outline of a clipped DEM is its border), east,
//! west, north or south, the bedrock is continued linearly and carries the cell's snow (the
//! drop there is `B_opposite − B_i`, as in powder diffusion's open border); a share sent there
//! leaves the grid and is reported as border outflow. A cell with no lower neighbour keeps its
//! snow. Every share is taken from the sender and added to one receiver (the last share is the
//! rest, so the shares add up to the depth removed): the volume is conserved but for the
//! border outflow.
//!
//! **Parallel strips.** The grid is swept as two strips of rows (its halves, fixed by the
//! grid, not by the threads), each in its own order (the order above, within the strip) on its
//! own thread. A strip sees the row of its neighbour beside it (its halo) as cells its sweep
//! has not reached: with the surface they are expected to keep (at the start of the step less
//! their excess, or as they rest after a phase), whatever they receive (in transit), and no
//! overtaking limit (seen as passed cells, they dammed a face's snow in the row above the
//! boundary). Snow sent there waits until the next phase, when the neighbour takes it in, in
//! strip order, and sweeps again from its receivers, seeing every cell it does not reach as it
//! rests; phases repeat until no snow crosses (at most 1024; what is left then is reported as
//! unsettled). Phases after the first are short: what crosses is the tail of debris flows.
//!
//! **Cost and determinism.** A row-parallel pass finds the cells over their holding depth (a
//! pure function of each cell; a bound from the cached bedrock descent passes over the cells
//! that cannot be steep enough); a step without any returns at once. Each strip's sweep visits
//! only the cells that shed or receive (a bitset of pending positions), setting up a cell's
//! surfaces the first time it looks at it, so that a step costs what its cascade touches
//! rather than the grid; holding depths come from a table in `tan / (1 + tan)` (cached in the
//! scratch) and a receiving cell's fixed point from tables over the steepest rise at each of
//! the three neighbour distances. Strips and phases are fixed by the grid and the snow, and
//! snow crossing between strips is taken in in strip order: the step is bit-identical for any
//! thread count.
//!
//! **Time.** Shedding is a release to rest, not a rate: `dt_days` is validated and otherwise
//! unused; call the step after the snow cover changed (snowfall, wind). A season calls it
//! after a melt-and-state event once [`SheddingParams::interval_days`] (default 1 day) have
//! passed since its last call.

use crate::VolumeChange;
use crate::phenomenon::{
    PhenomenonError, Validity, check_dt, check_finite, check_range, with_validity,
};
use neighbourhood::{
    Around, Neighbour, distance_inv_l, for_each_around, for_each_around_of, neighbours,
    steepest_descent,
};
use serde::{Deserialize, Serialize};
use snowscape_terrain::parallel::{self, PerRow};
use snowscape_terrain::{GridGeometry, LayeredTerrain, SnowLayer};
use std::collections::BinaryHeap;

/// The holding-depth formula (see the module documentation).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum HoldingLaw {
    /// `c · exp(−a · s)` (OGGM Snowslide's form of Bernhardt & Schulz 2010).
    #[default]
    Exponential,
    /// `c · max(s, 10°)^b` (CHM's form of Bernhardt & Schulz 2010).
    PowerLaw,
}

/// Parameters of slope shedding.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct SheddingParams {
    /// Whether a season sheds (after each melt-and-state event). Default true; false keeps
    /// the paper's season, where only avalanches move snow off steep faces.
    pub enabled: bool,
    /// The holding-depth formula. Default: exponential.
    pub law: HoldingLaw,
    /// `c` of the exponential law, metres of snow (> 0). Default 145 m: OGGM Snowslide.
    pub exp_scale_m: f64,
    /// `a` of the exponential law, per degree of slope (>= 0). Default 0.14 /°: OGGM Snowslide.
    pub exp_rate_per_deg: f64,
    /// `c` of the power law, metres of snow at 1° (> 0). Default 3178.4: CHM `snow_slide`.
    pub power_scale_m: f64,
    /// `b` of the power law (finite). Default −1.998: CHM `snow_slide`.
    pub power_exponent: f64,
    /// Floor of the holding depth, metres of snow (>= 0). Default 0.05 m: OGGM Snowslide
    /// (FSM2oshd uses 0.01 m).
    pub min_holding_depth_m: f64,
    /// Slope below which a cell does not shed its own snow, degrees, in [0, 90]. Default 60°:
    /// our choice for seasons, whose avalanches (a 28-60° release window) move the snow of
    /// 30-60° slopes; steeper faces sluff continuously. FSM2oshd's `slope_min` is 30° (DHSVM's
    /// `Avalanche.c` also starts at 30°), for models without avalanches.
    pub min_slope_deg: f64,
    /// Factor on the holding depth of a cell that received snow in this step, in (0, 1].
    /// Default 1 (none): our choice; FSM2oshd uses 0.09 (see the module documentation).
    pub dynamic_ratio: f64,
    /// Slope from which snow sliding onto a cell sets the cell's own snow sliding too,
    /// degrees, in [0, 90]: a receiving cell whose bedrock descends at least this steeply sheds
    /// all of its depth above its holding depth; a gentler one keeps the depth it had at the
    /// start of the step and passes on what it cannot hold of what it received. FSM2oshd
    /// entrains on every receiving cell (0°). Default 45°: our choice, so that sluffs off a
    /// face strip the steep (45-60°) faces they run over, which hold a few decimetres at
    /// most, but not the cover of the 30-45° slopes below, whose release is the avalanche
    /// module's job. With 0°, every sluff stripped those slopes to their holding depth and
    /// piled their snow on the apron beneath: on avaMal (5 m) south-facing 15-30° slopes at
    /// 2400 m held 3.4 m at the end of April, against 1.5 m on north-facing ones.
    pub entrain_min_slope_deg: f64,
    /// Exponent `p` of the flow-direction weights `tan(β)^p` (> 0). Default 1.1: Freeman 1991.
    pub flow_exponent: f64,
    /// Layer the shed snow lands in. Default unstable (see the module documentation).
    pub deposit_layer: SnowLayer,
    /// Shortest time between two shedding steps of a season, days, in [0, 30]: a
    /// melt-and-state event sheds only when at least this long has passed since the last
    /// shedding step (0: after every one). Default 1 day: our choice; what reaches a face
    /// between two steps slides at the next, so shed snow lands up to a day later. A step
    /// costs what its cascade touches, which is set by the faces and the slopes below them
    /// rather than by the amount shed: on the benchmark's 1024² terrain a season's shedding
    /// took 4.5 s after each of its 213 melt-and-state events (twice a day) and 2.3 s
    /// daily, with the same behaviour on avaMal (`tests/realism.rs`).
    pub interval_days: f64,
}

impl Default for SheddingParams {
    fn default() -> Self {
        Self {
            enabled: true,
            law: HoldingLaw::Exponential,
            exp_scale_m: 145.0,
            exp_rate_per_deg: 0.14,
            power_scale_m: 3178.4,
            power_exponent: -1.998,
            min_holding_depth_m: 0.05,
            min_slope_deg: 60.0,
            dynamic_ratio: 1.0,
            entrain_min_slope_deg: 45.0,
            flow_exponent: 1.1,
            deposit_layer: SnowLayer::Unstable,
            interval_days: 1.0,
        }
    }
}

const NAME: &str = "slope shedding";

impl SheddingParams {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), PhenomenonError> {
        let bad = |name, value, reason| {
            Err(PhenomenonError::InvalidParameter {
                phenomenon: NAME,
                name,
                value,
                reason,
            })
        };
        check_range(NAME, "exp_scale_m", self.exp_scale_m, [0.0, 1e4], " m")?;
        check_range(
            NAME,
            "exp_rate_per_deg",
            self.exp_rate_per_deg,
            [0.0, 10.0],
            " 1/°",
        )?;
        check_range(NAME, "power_scale_m", self.power_scale_m, [0.0, 1e6], " m")?;
        check_range(
            NAME,
            "power_exponent",
            self.power_exponent,
            [-10.0, 10.0],
            "",
        )?;
        check_range(
            NAME,
            "min_holding_depth_m",
            self.min_holding_depth_m,
            [0.0, 100.0],
            " m",
        )?;
        check_range(NAME, "min_slope_deg", self.min_slope_deg, [0.0, 90.0], " °")?;
        check_range(
            NAME,
            "entrain_min_slope_deg",
            self.entrain_min_slope_deg,
            [0.0, 90.0],
            " °",
        )?;
        if self.min_slope_deg > 90.0 {
            return bad(
                "min_slope_deg",
                self.min_slope_deg,
                "a slope is at most 90°",
            );
        }
        check_finite(NAME, "dynamic_ratio", self.dynamic_ratio)?;
        if self.dynamic_ratio <= 0.0 || self.dynamic_ratio > 1.0 {
            return bad("dynamic_ratio", self.dynamic_ratio, "must be in (0, 1]");
        }
        check_range(NAME, "flow_exponent", self.flow_exponent, [0.0, 10.0], "")?;
        check_range(
            NAME,
            "interval_days",
            self.interval_days,
            [0.0, 30.0],
            " days",
        )?;
        if self.flow_exponent <= 0.0 {
            return bad("flow_exponent", self.flow_exponent, "must be > 0");
        }
        Ok(())
    }

    /// Holding depth `D_hold`, metres of snow, on a slope of `slope_deg` degrees.
    pub fn holding_depth(&self, slope_deg: f64) -> f64 {
        self.law_depth(slope_deg.max(self.law_min_slope_deg()))
            .max(self.min_holding_depth_m)
    }

    /// The slope below which the law holds its value, degrees (10° for the power law).
    fn law_min_slope_deg(&self) -> f64 {
        match self.law {
            HoldingLaw::Exponential => 0.0,
            HoldingLaw::PowerLaw => 10.0,
        }
    }

    /// The law's formula alone (no floor, no lower slope), m.
    fn law_depth(&self, slope_deg: f64) -> f64 {
        match self.law {
            HoldingLaw::Exponential => {
                self.exp_scale_m * (-self.exp_rate_per_deg * slope_deg).exp()
            }
            HoldingLaw::PowerLaw => self.power_scale_m * slope_deg.powf(self.power_exponent),
        }
    }
}

/// Volumes moved by one shedding step, m³ of snow.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SheddingReport {
    /// Snow shed, summed over every hop of the cascade (a volume shed twice counts twice).
    pub moved_m3: f64,
    /// Snow that landed on cells of the grid (`moved_m3 − border_outflow_m3`).
    pub received_m3: f64,
    /// Snow shed across the grid border.
    pub border_outflow_m3: f64,
    /// Cells that shed snow.
    pub cells_shed: usize,
    /// Visits of cells the sweep had passed, because they received snow after it had.
    pub revisits: usize,
    /// Cells still queued when the visit budget ran out (0 in a settled step).
    pub unsettled_cells: usize,
}

impl SheddingReport {
    /// The step's volume budget: border outflow is the only volume removed.
    pub fn volume_change(&self) -> VolumeChange {
        VolumeChange {
            added: 0.0,
            removed: self.border_outflow_m3,
        }
    }
}

/// Reusable buffers of the shedding step; the strips and their bedrock orders are cached here.
#[derive(Debug, Clone, Default)]
pub struct SheddingScratch {
    /// Bedrock and mask the cached strips were built for.
    key_bedrock: Vec<u32>,
    key_mask: Option<Vec<bool>>,
    /// The strips of rows swept in parallel, each with its order and its cells' state.
    strips: Vec<Strip>,
    /// Steepest descent of the bedrock alone to the valid neighbours (tan; infinite for cells
    /// on the border or beside nodata): with the compacted snow on a cell, a bound on the
    /// slope of its bed that spares the cells far from `min_slope_deg` a full evaluation.
    bedrock_descent: Vec<f32>,
    generation: u32,
    /// The holding table and the parameters it was built for.
    holding: Option<(SheddingParams, HoldingTable)>,
    /// The depths receiving cells keep at each neighbour distance (for the holding table
    /// above), and the `1 / distance` they were built for.
    retained: Option<([u32; 3], [RetainedTable; 3])>,
}

/// Over its holding depth and steep enough to shed its own snow.
const ACTIVE: u8 = 1;
/// Received snow in this step.
const RECEIVED: u8 = 2;
/// In the queue of passed receivers (with an entry keyed by its current surface).
const QUEUED: u8 = 4;
/// Shed snow in this step.
const SHED: u8 = 8;
/// A cell of a neighbouring strip, in a strip's halo.
const HALO: u8 = 16;
/// Waiting for the sweep (its rank's bit is set in the strip's pending bits).
const PENDING: u8 = 32;
/// Its surface changed in this phase (listed in the strip's `dirty`).
const DIRTY: u8 = 64;

/// Depths below this (m) are not shed: f32 round-off of a column, not snow.
const MIN_SHED_M: f32 = 1e-6;

/// Surface differences below this (m) are level: above the f32 round-off of altitudes up to
/// 8 km (5e-4 m).
const LEVEL_M: f32 = 1e-3;

/// Most shedding rounds of one visit of a cell (each limited round drops the receiver that
/// limited it, and a cell has 8 neighbours).
const ROUNDS: usize = 9;

/// One cell's state in the sweep, kept together so that a visit's 3×3 block of cells lies in
/// a few cache lines (as separate arrays it spread over a dozen times as many).
#[derive(Debug, Clone, Copy)]
struct CellState {
    /// Bedrock plus compacted snow, m.
    bed: f32,
    /// Snow surface at the start of the step, less the excess the cell is to shed: what a cell
    /// the sweep has not reached is expected to keep, m.
    surface0: f32,
    /// Snow surface during the sweep, m.
    surface: f32,
    /// Slope of a cell that has not received snow (tan; see the module documentation).
    tan_slope: f32,
    /// Position of the cell in the cached order (`u32::MAX` for nodata); kept between steps.
    rank: u32,
    /// Steepest descent of the cell's bedrock (tan, [`steepest_descent`] on the bedrock, the
    /// border continued): whether snow sliding onto it entrains its own (set with `rank`).
    bedrock_tan: f32,
    /// The step in which `bed`, `surface0`, `surface` and `flags` were set up (equal to the
    /// scratch's `generation`: in this one).
    stamp: u32,
    flags: u8,
    /// Not in the first or last row or column (set with `rank`; kept between steps).
    interior: bool,
}

impl Default for CellState {
    fn default() -> Self {
        Self {
            bed: 0.0,
            surface0: 0.0,
            surface: 0.0,
            tan_slope: 0.0,
            rank: u32::MAX,
            bedrock_tan: 0.0,
            stamp: 0,
            flags: 0,
            interior: false,
        }
    }
}

/// Sets up cell `i` of a strip's window (its bed, surface at the start, surface of the sweep
/// and flags) from its `column` (bedrock, then compacted, stable, unstable and powder snow),
/// unless its stamp says this step (`generation`) already did: the same sums as
/// `LayeredTerrain::surface`.
#[inline(always)]
fn set_up(
    i: usize,
    generation: u32,
    cells: &mut [CellState],
    column: impl FnOnce() -> (f32, [f32; 4]),
) {
    let cell = &mut cells[i];
    if cell.stamp == generation {
        return;
    }
    cell.stamp = generation;
    (cell.bed, cell.surface0) = bed_and_surface(column());
    cell.surface = cell.surface0;
    cell.flags = 0;
}

/// The bed (bedrock and compacted snow) and the snow surface of a [`column`], m: the same sums
/// as `LayeredTerrain::surface`.
#[inline(always)]
fn bed_and_surface((b, [c, st, u, pw]): (f32, [f32; 4])) -> (f32, f32) {
    (b + c, b + (c + st + u + pw))
}

/// The column of a cell: `bedrock[b]` and the four layers at `snow[k]`.
#[inline(always)]
fn column<S: std::ops::Deref<Target = [f32]>>(
    bedrock: &[f32],
    b: usize,
    snow: &[S; 4],
    k: usize,
) -> (f32, [f32; 4]) {
    (bedrock[b], [snow[0][k], snow[1][k], snow[2][k], snow[3][k]])
}

impl SheddingScratch {
    /// Rebuilds the strips if the bedrock or the mask changed.
    fn refresh_strips(&mut self, terrain: &LayeredTerrain) -> Result<(), PhenomenonError> {
        let mask = terrain.mask().invalid_cells();
        // Blocks of cells compared in parallel (a boolean: the same for any thread count).
        const BLOCK: usize = 1 << 14;
        let same = self.key_bedrock.len() == terrain.bedrock.len()
            && self.key_mask.as_deref() == mask
            && parallel::map_rows(
                BLOCK,
                (&self.key_bedrock, &terrain.bedrock),
                |_, (key, bedrock)| key.iter().zip(bedrock).all(|(k, b)| *k == b.to_bits()),
            )
            .into_iter()
            .all(|same| same);
        if same {
            return Ok(());
        }
        let geometry = terrain.geometry();
        // Per cell in one pass: the bound of `bedrock_descent` (infinite beside the border or
        // nodata) and the descent with the border continued ([`steepest_descent`] on the
        // bedrock, the same terms in the same order).
        let nb = neighbours(geometry);
        let bedrock = &terrain.bedrock;
        let descents: Vec<(f32, f32)> = with_validity!(terrain.mask(), |valid| {
            parallel::map_range(bedrock.len(), |i| {
                let (mut bound, mut tan) = (0.0f32, 0.0f32);
                for_each_around(geometry, valid, &nb, i, |n, a| match a {
                    Around::Cell(j) => {
                        let t = (bedrock[i] - bedrock[j]) * n.inv_l;
                        bound = bound.max(t);
                        tan = tan.max(t);
                    }
                    Around::Ghost(o) => {
                        bound = f32::INFINITY;
                        tan = tan.max((bedrock[o] - bedrock[i]) * n.inv_l);
                    }
                });
                (bound, if valid.at(i) { tan } else { 0.0 })
            })
        });
        self.bedrock_descent = descents.iter().map(|d| d.0).collect();
        let bedrock_tan: Vec<f32> = descents.iter().map(|d| d.1).collect();
        // The strips built in parallel, then their results in order (the first error, if any).
        self.strips = with_validity!(terrain.mask(), |valid| {
            parallel::map_rows(1, PerRow(strip_rows(geometry.height())), |_, rows| {
                Strip::new(rows, bedrock, geometry, valid, &bedrock_tan)
            })
            .into_iter()
            .collect::<Result<_, _>>()
        })?;
        self.key_bedrock.resize(terrain.bedrock.len(), 0);
        parallel::map_cells(&mut self.key_bedrock, &terrain.bedrock, |v| v.to_bits());
        self.key_mask = mask.map(<[bool]>::to_vec);
        Ok(())
    }
}

/// The sweep's order: every valid cell after each of its valid neighbours that lies above it,
/// a neighbour being above when its bedrock is higher, or on level ground when its scrambled
/// index is lower (by index, every debris flow on level ground would run one way). A
/// depth-first search climbs from each cell in index order to the cells above it and lists a
/// cell once all of them are listed: a topological order of the neighbours' "above" relation
/// that stays local in the grid, so that the sweep finds the cells it visits one after the
/// other in the same cache lines (a global sort by altitude jumps across the grid and spent
/// most of its time waiting on memory).
fn upslope_first_order<V: Validity>(
    bedrock: &[f32],
    geometry: &GridGeometry,
    valid: &V,
) -> Vec<u32> {
    let n = bedrock.len();
    // Ascending keys are descending altitudes; ties in a scrambled but fixed order, then by
    // index (a total order).
    let key = |i: usize| {
        let scramble = snowscape_terrain::random::mix64(i as u64) as u32;
        (
            (u64::from(!monotone(bedrock[i])) << 32) | u64::from(scramble),
            i,
        )
    };
    let nb = neighbours(geometry);
    let mut listed = vec![false; n];
    let mut order = Vec::with_capacity(n);
    // The search path: a cell and the next of its neighbours to look at.
    let mut path: Vec<(u32, u8)> = Vec::new();
    for start in 0..n {
        if listed[start] || !valid.at(start) {
            continue;
        }
        path.push((start as u32, 0));
        while let Some(top) = path.last_mut() {
            let i = top.0 as usize;
            let mut above = None;
            let mut k = 0u8;
            for_each_around(geometry, valid, &nb, i, |_, a| {
                if above.is_none()
                    && let Around::Cell(j) = a
                {
                    if k >= top.1 && !listed[j] && key(j) < key(i) {
                        above = Some((j, k));
                    }
                    k += 1;
                }
            });
            match above {
                Some((j, k)) => {
                    top.1 = k + 1;
                    path.push((j as u32, 0));
                }
                None => {
                    listed[i] = true;
                    order.push(i as u32);
                    path.pop();
                }
            }
        }
    }
    order
}

/// Sheds the snow above the holding depth of every steep cell, down the slopes, in one sweep
/// per strip of rows (and further phases for what crosses between strips).
pub fn step(
    params: &SheddingParams,
    terrain: &mut LayeredTerrain,
    scratch: &mut SheddingScratch,
    dt_days: f64,
) -> Result<SheddingReport, PhenomenonError> {
    params.validate()?;
    check_dt(dt_days)?;
    let geometry = terrain.geometry().clone();
    let mask = terrain.mask().clone();
    let n = geometry.len();
    if n >= u32::MAX as usize {
        return Err(PhenomenonError::InvalidParameter {
            phenomenon: NAME,
            name: "cells",
            value: n as f64,
            reason: "the sweep indexes cells with 32 bits",
        });
    }
    scratch.refresh_strips(terrain)?;
    let tan_min = params.min_slope_deg.to_radians().tan() as f32;
    if scratch.holding.as_ref().is_none_or(|(p, _)| p != params) {
        scratch.holding = Some((params.clone(), HoldingTable::new(params)));
        scratch.retained = None;
    }
    let holding = match scratch.holding.take() {
        Some((_, table)) => table,
        None => HoldingTable::new(params),
    };
    let active = with_validity!(mask, |valid| over_holding_depth(
        params, &holding, terrain, scratch, &geometry, valid, tan_min
    ));
    if active.is_empty() {
        scratch.holding = Some((params.clone(), holding));
        return Ok(SheddingReport::default());
    }
    // The bed, the surface at the start and the surface of the sweep are set up lazily, the
    // first time the sweep looks at a cell in this step (a cell it has not looked at still has
    // the snow it had at the start): a step costs what its cascade touches, not the grid.
    scratch.generation = scratch.generation.wrapping_add(1);
    if scratch.generation == 0 {
        for strip in &mut scratch.strips {
            strip.cells.iter_mut().for_each(|c| c.stamp = 0);
        }
        scratch.generation = 1;
    }
    let inv_l = distance_inv_l(&geometry);
    let key = inv_l.map(f32::to_bits);
    let retained = match scratch.retained.take() {
        Some((k, tables)) if k == key => tables,
        _ => {
            // Square cells: the east-west and north-south tables are the same.
            let ew = RetainedTable::new(&holding, inv_l[0]);
            let ns = if inv_l[1] == inv_l[0] {
                ew.clone()
            } else {
                RetainedTable::new(&holding, inv_l[1])
            };
            [ew, ns, RetainedTable::new(&holding, inv_l[2])]
        }
    };
    let tables = Tables {
        params,
        holding: &holding,
        retained: &retained,
    };
    let report = with_validity!(mask, |valid| strips::shed_in_phases(
        &tables,
        terrain,
        &mut scratch.strips,
        valid,
        &active,
        scratch.generation
    ));
    scratch.holding = Some((params.clone(), holding));
    scratch.retained = Some((key, retained));
    Ok(report)
}

/// What every strip's sweep reads: the parameters and their tables.
struct Tables<'a> {
    params: &'a SheddingParams,
    holding: &'a HoldingTable,
    retained: &'a [RetainedTable; 3],
}

/// The cells over their holding depth and steep enough to shed their own snow, in index
/// order, each with its slope (tan) and its excess (m): a pure function of each cell,
/// row-parallel. A cell's bed slope is at most its bedrock descent plus its compacted snow over
/// the shortest neighbour distance (the neighbours' compacted snow only lowers it), so cells
/// far from `min_slope_deg` by that bound, and cells holding no more than the floor of the
/// holding depth, are passed over without evaluating their slopes.
fn over_holding_depth<V: Validity>(
    params: &SheddingParams,
    holding: &HoldingTable,
    terrain: &LayeredTerrain,
    scratch: &SheddingScratch,
    geometry: &GridGeometry,
    valid: &V,
    tan_min: f32,
) -> Vec<(u32, f32, f32)> {
    let nb = &neighbours(geometry);
    let w = geometry.width();
    let snow = &terrain.snow;
    let bedrock = &terrain.bedrock;
    let bound = &scratch.bedrock_descent;
    let floor = params.min_holding_depth_m as f32;
    let inv_l_max = nb.iter().fold(0.0f32, |m, n| m.max(n.inv_l));
    // One centimetre of height: more than the f32 round-off of a bed sum at 8 km.
    let margin = 0.01 * inv_l_max;
    let bed = |j: usize| bedrock[j] + snow[0][j];
    let surface = |j: usize| bedrock[j] + (snow[0][j] + snow[1][j] + snow[2][j] + snow[3][j]);
    parallel::map_rows_with(
        w,
        (&bound[..], &snow[0][..]),
        || vec![false; w],
        |candidate, row, (b, c)| {
            // The slope bound first, over the whole row (a loop that vectorises): it reads
            // two arrays and rules out most cells.
            let base = row * w;
            let (b, c) = (&b[..w], &c[..w]);
            for (k, out) in candidate.iter_mut().enumerate() {
                *out = b[k] + c[k] * inv_l_max + margin >= tan_min;
            }
            let mut found = Vec::new();
            for i in (0..w).filter(|&k| candidate[k]).map(|k| base + k) {
                if !valid.at(i) {
                    continue;
                }
                let depth = snow[0][i] + snow[1][i] + snow[2][i] + snow[3][i];
                if depth - floor <= MIN_SHED_M {
                    continue;
                }
                let on_bed = steepest_descent(bed(i), bed, bed, geometry, valid, nb, i);
                if on_bed < tan_min {
                    continue;
                }
                let on_snow = steepest_descent(surface(i), surface, bed, geometry, valid, nb, i);
                let t = on_bed.min(on_snow);
                if t < tan_min {
                    continue;
                }
                let excess = depth - holding.hold(t, false);
                if excess > MIN_SHED_M {
                    found.push((i as u32, t, excess));
                }
            }
            found
        },
    )
    .into_iter()
    .flatten()
    .collect()
}

/// Monotone map of an f32 onto a u32 (larger values, larger keys; a total order).
#[inline]
fn monotone(v: f32) -> u32 {
    let b = v.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// Segments of the [`HoldingTable`].
const TABLE_SEGMENTS: usize = 4096;

/// The holding depth as a function of the tangent of the slope, tabulated at
/// [`TABLE_SEGMENTS`] + 1 points evenly spaced in `u = tan / (1 + tan)` (0 on level ground, 1
/// on a vertical face) and interpolated linearly: the sweep evaluates it many times per cell
/// (root finding), and `atan` and `exp` per evaluation cost more than the rest of the sweep. The
/// table is within 1e-5 relative of [`SheddingParams::holding_depth`] (tested).
#[derive(Debug, Clone)]
struct HoldingTable {
    /// The law without its floor at the table's points, m (the floor is applied after the
    /// interpolation, which would otherwise round its corner).
    depth: Vec<f32>,
    /// Tangent of the law's lowest slope (below it the law holds its value there).
    min_tan: f32,
    /// `dynamic_ratio` and the floor `d_min` (m) of a cell that received snow.
    dynamic_ratio: f32,
    floor: f32,
}

impl HoldingTable {
    fn new(params: &SheddingParams) -> Self {
        let depth = (0..=TABLE_SEGMENTS)
            .map(|k| {
                let u = k as f64 / TABLE_SEGMENTS as f64;
                let degrees = if k == TABLE_SEGMENTS {
                    90.0
                } else {
                    (u / (1.0 - u)).atan().to_degrees()
                };
                // Below the law's lowest slope the lookup never reads the table (the power
                // law is infinite at 0°); the formula itself keeps the segment that straddles
                // that slope smooth.
                params.law_depth(degrees).min(f64::from(f32::MAX)) as f32
            })
            .collect();
        Self {
            depth,
            min_tan: params.law_min_slope_deg().to_radians().tan() as f32,
            dynamic_ratio: params.dynamic_ratio as f32,
            floor: params.min_holding_depth_m as f32,
        }
    }

    /// Holding depth of a cell of slope `tan_slope` (>= 0), metres (reduced by the dynamic
    /// ratio, down to the floor, if it received snow).
    #[inline]
    fn hold(&self, tan_slope: f32, received: bool) -> f32 {
        // NaN and negative slopes are level ground (or the law's lowest slope), an infinite
        // one a vertical face.
        let u = 1.0 - 1.0 / (1.0 + tan_slope.max(self.min_tan));
        let x = u.clamp(0.0, 1.0) * TABLE_SEGMENTS as f32;
        let k = (x as usize).min(TABLE_SEGMENTS - 1);
        let f = x - k as f32;
        let (a, b) = (self.depth[k], self.depth[k + 1]);
        let h = a + f * (b - a);
        if received && self.dynamic_ratio != 1.0 {
            (h.max(self.floor) * self.dynamic_ratio).max(self.floor)
        } else {
            h.max(self.floor)
        }
    }
}

mod cascade;
mod neighbourhood;
mod retained;
mod strips;
use retained::RetainedTable;
use strips::{Strip, set_pending, strip_rows};

#[cfg(test)]
mod tests;
