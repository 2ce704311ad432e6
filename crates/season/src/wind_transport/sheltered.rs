//! Sx-driven redistribution: scour of wind-exposed cells and deposit on sheltered cells
//! downwind, driven by Winstral et al. 2002's maximum upwind slope `Sx`
//! (`snowscape_environment::max_upwind_slope`, degrees, positive = sheltered). Beyond the
//! paper; it runs after the paper's curvature erosion when [`WindMaps::sx`] is given and
//! [`SxParams::enabled`] is set, and leaves the paper's formulation untouched otherwise.
//!
//! **Scour.** A cell out of the wind shadow whose `Sx` is below `exposed_below_deg` loses
//!
//! ```text
//! e = min(P + U, k_exposed · (exposed_below_deg − Sx) · (|W| / W_ref)^n · δt)
//! ```
//!
//! (powder first, then unstable snow when the paper's `erode_unstable` is set, then stable
//! snow at the share `f_S` of the rest that the wind's excess shear over its threshold leaves
//! when [`SxParams::erode_stable`] is set: [`blowing_snow`]), with `|W|` the cell's wind speed.
//! `n = 3`: saltation transport grows with the cube of the wind speed (Bagnold 1941; Pomeroy &
//! Gray 1990, Water Resour. Res. 26(7)). `Sx` is the sheltering index of
//! `snowscape_environment::sheltering_index`, the short-range (100 m) search plus the
//! long-range (1 km) one: crests exposed to the whole range are scoured hardest, basins in
//! the lee of a range are sheltered even where the slope faces the wind.
//!
//! **Transport and deposit.** The scoured snow is carried downwind by one ordered sweep along
//! the dominant wind (the mean of the wind field, so the sweep follows the direction the `Sx`
//! map was computed for): each cell's load goes to its two downwind neighbours, split by the
//! wind components as in the paper's deposit (`|Ŵx| / (|Ŵx| + |Ŵy|)` to the east/west one),
//! and every cell it crosses keeps the share `1 − exp(−ℓ (1/L + k_deposit · max(0, Sx −
//! sheltered_above_deg)))` of the load reaching it, `ℓ` the mean advance along the wind of one
//! hop (`dx/(|Ŵx| + |Ŵy|)` for square cells) and `L` the settling length on open ground,
//! but for exposed cells (`Sx < exposed_below_deg`), scour zones that keep none unless
//! [`SxParams::deposit_on_exposed`] is set (issue 47: the drift from a whole windward slope
//! otherwise settles on the crest it crosses). So
//! snow settles within about `1 / (k_deposit · shelter)` metres of lee slope, whatever the cell
//! size. It lands as powder, or as unstable snow on slopes steeper than `slab_slope_deg` (the
//! paper's wind slabs). **Sublimation:** before a cell keeps its share, the share
//! `λ ℓ / (1 + λ ℓ)` of the load reaching it sublimates, `λ` (m⁻¹) from the air temperature of
//! the cell and the humidity ([`blowing_snow`]; Liston & Sturm 1998), when the maps carry the
//! air temperature ([`WindMaps::air_temperature`]) and [`DriftSublimationParams::enabled`] is
//! set; it is reported as its own volume ([`super::WindReport::sublimated`]), the season's
//! `wind_sublimation`. **Boundary condition:** the grid's border and the nodata outline are
//! both open: a share leaving the grid or aimed at a nodata cell leaves the terrain as border
//! outflow. (Kept by the sending cell, as before issue 46, the drift piled into walls along
//! the outline: on avaMal the one-cell rim held 2.0 m between 1400 and 1700 m where the cells
//! one step inside held 0.11 m; `tests/nodata_edges.rs`.)
//!
//! **Conservation and determinism.** The scour of every cell is a pure function of the cell
//! as the step found it (the sweep computes a row's just before it reaches the row, whose
//! snow it has not touched yet); the sweep runs row after row in a fixed order, the carries
//! along each row by a scan over fixed segments of it ([`drift_row`]: the cell-by-cell
//! recurrence regrouped, equal to it to f32 round-off), so the result is bit-identical for any
//! thread count, and every depth scoured is deposited once, sublimated or counted as border
//! outflow (each cell keeps what it does not send on), but for loads below
//! [`crate::phenomenon::NEGLIGIBLE_DEPTH_M`] (1e-20 m) and shares below 1e-15, which the sweep
//! sets to 0 ([`drift_row`]: they would decay into subnormal floats).

use super::{Context, WindMaps};
use crate::phenomenon::{
    PhenomenonError, Validity, check_range, flush_below, flush_negligible, row_gradient_norm_in,
};
use serde::{Deserialize, Serialize};
use snowscape_terrain::{LayeredTerrain, parallel};
use std::sync::atomic::{AtomicU32, AtomicUsize, Ordering};

pub mod blowing_snow;
mod drift_row;
pub use blowing_snow::DriftSublimationParams;
use blowing_snow::{KelvinTable, StableErodibility, SublimationTable};
use drift_row::{DriftRow, Exits, NEGLIGIBLE_LOAD, NEGLIGIBLE_SHARE, RowTotals, share_out};

/// Parameters of the Sx-driven redistribution.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct SxParams {
    /// Whether the term runs when an `Sx` map is given. Default true.
    pub enabled: bool,
    /// `Sx` below which a cell is exposed and scoured, degrees. Default −1°: our choice (Sx < 0
    /// is exposed in Winstral et al. 2002; the 1° dead band keeps level ground and round-off
    /// out).
    pub exposed_below_deg: f64,
    /// `Sx` above which a cell is sheltered and collects drifting snow, degrees. Default +1°:
    /// our choice, as above.
    pub sheltered_above_deg: f64,
    /// Scour rate, m of snow per day per degree of exposure at the reference wind speed (>= 0).
    /// Default 0.002: our choice; a windward slope at Sx = −15° loses 14 cm in five days of
    /// reference wind (more where the Venturi speed-up raises the wind). After ten days of
    /// westerly at −5 °C on 0.5 m of powder, avaMal's lee slopes hold 2.8 times the depth of
    /// its windward slopes within 200 m altitude bands at 5 m cells, 7.1 times at 50 m
    /// (2.1 and 5.8 with the 100 m search alone, before issue 47), against 1.14 and 1.05 with
    /// the paper's curvature term alone (tests/sx_redistribution.rs).
    pub k_exposed: f64,
    /// Deposit rate, per metre of downwind travel per degree of shelter (>= 0). Default 0.002:
    /// our choice; on a lee slope at Sx = +15° drifting snow settles within about 36 m, a lee
    /// slope's length on 5-50 m grids.
    pub k_deposit: f64,
    /// Settling length of drifting snow over open (not sheltered) ground, metres (> 0).
    /// Default 200 m: our choice, of the order of the fetch over which saltation and
    /// suspension exchange with the surface; it keeps the drift from crossing whole valleys.
    pub settling_length_m: f64,
    /// Wind speed at which `k_exposed` applies, m/s (> 0). Default 10 m/s: Cordonnier 2018
    /// Table 2's |W|.
    pub reference_speed_m_s: f64,
    /// Exponent `n` of the wind-speed factor (>= 0). Default 3 (cube law, see the module
    /// documentation).
    pub speed_exponent: f64,
    /// Whether stable snow is scoured too, after the powder and the unstable snow, at the
    /// share of the wind's excess shear over its threshold ([`blowing_snow`]; Liston & Sturm
    /// 1998's threshold by density). Default true: the snowfall lays most new snow down as
    /// stable snow, which the wind otherwise never reaches.
    pub erode_stable: bool,
    /// Sublimation of the drifting snow ([`blowing_snow`]; Liston & Sturm 1998).
    pub sublimation: DriftSublimationParams,
    /// Whether exposed cells (`Sx < exposed_below_deg`) keep the open-ground share of the
    /// drifting snow. Default false: exposed ground is a scour zone that holds no drift
    /// (Winstral et al. 2002's scour and drift zones; the wind speeds up over it); true is the
    /// redistribution before issue 47.
    pub deposit_on_exposed: bool,
}

impl Default for SxParams {
    fn default() -> Self {
        Self {
            enabled: true,
            exposed_below_deg: -1.0,
            sheltered_above_deg: 1.0,
            k_exposed: 0.002,
            k_deposit: 0.002,
            settling_length_m: 200.0,
            reference_speed_m_s: 10.0,
            speed_exponent: 3.0,
            erode_stable: true,
            sublimation: DriftSublimationParams::default(),
            deposit_on_exposed: false,
        }
    }
}

const NAME: &str = "wind transport sx_redistribution";

impl SxParams {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), PhenomenonError> {
        check_range(
            NAME,
            "exposed_below_deg",
            self.exposed_below_deg,
            [-90.0, 90.0],
            " °",
        )?;
        check_range(
            NAME,
            "sheltered_above_deg",
            self.sheltered_above_deg,
            [-90.0, 90.0],
            " °",
        )?;
        check_range(NAME, "k_exposed", self.k_exposed, [0.0, 1.0], " 1/day")?;
        check_range(NAME, "k_deposit", self.k_deposit, [0.0, 1.0], " 1/day")?;
        check_range(NAME, "speed_exponent", self.speed_exponent, [0.0, 10.0], "")?;
        check_range(
            NAME,
            "settling_length_m",
            self.settling_length_m,
            [0.0, 1e5],
            " m",
        )?;
        check_range(
            NAME,
            "reference_speed_m_s",
            self.reference_speed_m_s,
            [0.0, 100.0],
            " m/s",
        )?;
        for (name, v) in [
            ("settling_length_m", self.settling_length_m),
            ("reference_speed_m_s", self.reference_speed_m_s),
        ] {
            if v <= 0.0 {
                return Err(PhenomenonError::InvalidParameter {
                    phenomenon: NAME,
                    name,
                    value: v,
                    reason: "must be > 0",
                });
            }
        }
        self.sublimation.validate()
    }
}

/// Volumes of the Sx term, m depth summed over cells.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct SxSums {
    pub eroded: f64,
    pub deposited: f64,
    pub deposited_unstable: f64,
    pub border: f64,
    pub sublimated: f64,
}

/// Buffers of the sweep.
#[derive(Debug, Clone, Default)]
pub(super) struct SxScratch {
    /// Load arriving from the upwind row, per column.
    from_row: Vec<f32>,
    /// The share of the arriving load each cell keeps on open or sheltered ground (before the
    /// slab sign), cached while the `Sx` map and the [`KeepShare`] stay the same (a weather
    /// period): it costs an `exp` per cell.
    keep_share: KeepShareCache,
    /// The sublimation per metre by air temperature ([`blowing_snow`]).
    sublimation: SublimationTable,
}

/// [`SxScratch::keep_share`]: the shares and what they were computed from.
#[derive(Debug, Clone, Default)]
struct KeepShareCache {
    /// `(a, b, sheltered_above_deg, scour-zone limit)` bits of the [`KeepShare`] and the `Sx`
    /// map.
    key: Option<([u64; 4], Vec<f32>)>,
    share: Vec<f32>,
}

impl KeepShareCache {
    /// The shares for `sx` under `keep`, recomputed (row-parallel) if either changed; 0 on
    /// cells whose `Sx` is below `scour_zone` (the exposed cells, unless they take deposits:
    /// `f32::NEG_INFINITY`).
    fn shares(
        &mut self,
        keep: &KeepShare,
        (sheltered, scour_zone): (f32, f32),
        sx: &[f32],
        w: usize,
    ) -> &[f32] {
        let params = [
            keep.a.to_bits(),
            keep.b.to_bits(),
            u64::from(sheltered.to_bits()),
            u64::from(scour_zone.to_bits()),
        ];
        // Rows compared in parallel (a boolean: the same for any thread count).
        let same = self.key.as_ref().is_some_and(|(k, old)| {
            *k == params
                && old.len() == sx.len()
                && parallel::map_rows(w, (old, sx), |_, (old, sx)| {
                    old.iter().zip(sx).all(|(a, b)| a.to_bits() == b.to_bits())
                })
                .into_iter()
                .all(|same| same)
        });
        if !same {
            self.share.resize(sx.len(), 0.0);
            parallel::for_each_row(w, (&mut self.share, sx), |_, (out, sx)| {
                for (o, &s) in out.iter_mut().zip(sx) {
                    *o = if s < scour_zone {
                        0.0
                    } else {
                        keep.at(s - sheltered)
                    };
                }
            });
            self.key = Some((params, sx.to_vec()));
        }
        &self.share
    }
}

/// The share of the arriving load a cell keeps, `1 − exp(−(a + b · x))` for a shelter `x =
/// Sx − sheltered_above_deg` (degrees; `x ≤ 0`, open ground: `1 − exp(−a)`), `a = ℓ / L`,
/// `b = ℓ · k_deposit`.
struct KeepShare {
    open: f32,
    a: f64,
    b: f64,
}

impl KeepShare {
    fn new(a: f64, b: f64) -> Self {
        Self {
            open: (1.0 - (-a).exp()) as f32,
            a,
            b,
        }
    }

    #[inline]
    fn at(&self, x: f32) -> f32 {
        let x = f64::from(x);
        if x > 0.0 {
            (1.0 - (-(self.a + self.b * x)).exp()) as f32
        } else {
            self.open
        }
    }
}

/// Runs the Sx term on the layers (after the paper's passes), sweeping along the `dominant`
/// wind ([`super::WindTerms`]; none in calm air: nothing moves).
pub(super) fn run<V: Validity>(
    ctx: &Context,
    valid: &V,
    params: &SxParams,
    (sx, surface, dominant): (&[f32], &[f32], Option<(f64, f64)>),
    terrain: &mut LayeredTerrain,
    scratch: &mut SxScratch,
    dt_days: f64,
) -> SxSums {
    let Some(wind) = dominant else {
        return SxSums::default();
    };
    let maps = SweepMaps::new(
        (ctx, valid),
        params,
        (sx, surface, wind),
        (&mut scratch.keep_share, &mut scratch.sublimation),
        dt_days,
    );
    sweep(&maps, terrain, &mut scratch.from_row)
}

/// The per-cell terms of the sweep, computed by the sweep for each row before it reaches it
/// from the maps and the row's snow (still as the step found it): the scour and the share
/// kept (a pure function of each cell).
struct CellTerms<'a> {
    sx: &'a [f32],
    keep: KeepShare,
    scour_dt: f32,
    inv_ref: f32,
    expo: f32,
    exposed: f32,
    sheltered: f32,
    /// How readily stable snow erodes, when it does ([`SxParams::erode_stable`]).
    stable: Option<StableErodibility>,
}

/// One row's snow as the step found it: powder, unstable snow (when it erodes) and stable snow.
type RowSnow<'a> = (&'a [f32], Option<&'a [f32]>, &'a [f32]);

/// What sublimates of the load reaching each cell ([`blowing_snow`]).
struct DriftLoss<'a> {
    /// The share `λℓ / (1 + λℓ)` that sublimates per hop, by air temperature (the kelvins of
    /// the `λ` table; `ℓ` the sweep's advance along the wind per hop).
    share: KelvinTable,
    /// Air temperature of every cell, °C.
    temperature: &'a [f32],
}

impl CellTerms<'_> {
    /// Depth scoured from the cells `r` of one row with `snow` on them: into `out`, of the
    /// powder and the unstable snow (when it erodes), `min(P + U, e)` with the demand
    /// `e = k_exposed · (exposed_below_deg − Sx) · (|W| / W_ref)^n · δt`; into `from_stable`,
    /// of the stable snow (when it erodes), `min(S, f_S · (e − P − U))`; 0 in the wind shadow.
    /// Straight loops over the row's slices, so that they vectorise.
    fn scour_row(
        &self,
        wind: &WindMaps,
        r: std::ops::Range<usize>,
        (powder, unstable, stable): RowSnow,
        (out, from_stable): (&mut [f32], &mut [f32]),
    ) {
        let (u, v, shadow, sx) = (
            &wind.u[r.clone()],
            &wind.v[r.clone()],
            &wind.shadow[r.clone()],
            &self.sx[r],
        );
        let w = out.len();
        let (u, v, shadow, sx, powder) = (&u[..w], &v[..w], &shadow[..w], &sx[..w], &powder[..w]);
        // Wind speeds are far from overflow: the plain norm, not the slower `hypot`.
        if self.expo == 3.0 {
            for k in 0..w {
                let speed = (u[k] * u[k] + v[k] * v[k]).sqrt() * self.inv_ref;
                let exposure = (self.exposed - sx[k]).max(0.0);
                out[k] = self.scour_dt * exposure * (speed * speed * speed);
            }
        } else {
            for k in 0..w {
                let speed = (u[k] * u[k] + v[k] * v[k]).sqrt() * self.inv_ref;
                let exposure = (self.exposed - sx[k]).max(0.0);
                out[k] = self.scour_dt * exposure * speed.powf(self.expo);
            }
        }
        // What the loose snow leaves of the demand waits in `from_stable`.
        let rest = &mut from_stable[..w];
        match unstable {
            Some(unstable) => {
                let unstable = &unstable[..w];
                for k in 0..w {
                    let e = out[k].min(powder[k] + unstable[k]).max(0.0);
                    rest[k] = (out[k] - e).max(0.0);
                    out[k] = if shadow[k] > 0.5 { 0.0 } else { e };
                }
            }
            None => {
                for k in 0..w {
                    let e = out[k].min(powder[k]).max(0.0);
                    rest[k] = (out[k] - e).max(0.0);
                    out[k] = if shadow[k] > 0.5 { 0.0 } else { e };
                }
            }
        }
        match self.stable {
            Some(erodibility) => {
                let stable = &stable[..w];
                for k in 0..w {
                    let share = erodibility.share(u[k] * u[k] + v[k] * v[k]);
                    let e = (rest[k] * share).min(stable[k]).max(0.0);
                    rest[k] = if shadow[k] > 0.5 { 0.0 } else { e };
                }
            }
            None => rest.fill(0.0),
        }
    }
}

/// Share of the arriving load each cell of a row keeps (`share`, from [`KeepShareCache`]),
/// negative where the surface `gradient` (tan) exceeds `slab_gradient` (deposits land as
/// unstable snow).
fn keep_row(share: &[f32], gradient: &[f32], slab_gradient: f32, out: &mut [f32]) {
    for ((o, &keep), &g) in out.iter_mut().zip(share).zip(gradient) {
        *o = if g > slab_gradient { -keep } else { keep };
    }
}

/// The ordered sweep downwind: scour, carry, keep, pass on.
///
/// The columns are cut in two halves, upwind and downwind, swept at the same time: the only
/// load that crosses between them is each row's east/west carry at the cut, which the upwind
/// half hands over row by row (the downwind half waits for it). The halves are fixed by the
/// grid and the arithmetic of each cell by its half and row, so the layers are bit-identical
/// for any thread count; the sums are per half, added in a fixed order.
fn sweep<V: Validity>(
    maps: &SweepMaps<V>,
    terrain: &mut LayeredTerrain,
    from_row: &mut Vec<f32>,
) -> SxSums {
    let (w, h) = (maps.ctx.geometry.width(), maps.ctx.geometry.height());
    // Downwind steps: east is +col, north is −row.
    let (dc, dr) = (maps.dc, maps.dr);
    let rows: Vec<usize> = if dr < 0 {
        (0..h).rev().collect()
    } else {
        (0..h).collect()
    };
    from_row.clear();
    from_row.resize(w, 0.0);
    let mid = w / 2;
    let [_, stable, unstable, powder] = &mut terrain.snow;
    // Each row's (stable, unstable, powder) in the west and east halves.
    let (mut west, mut east) = (Vec::with_capacity(h), Vec::with_capacity(h));
    for ((s, u), p) in stable
        .chunks_mut(w)
        .zip(unstable.chunks_mut(w))
        .zip(powder.chunks_mut(w))
    {
        let (sw, se) = s.split_at_mut(mid);
        let ((uw, ue), (pw, pe)) = (u.split_at_mut(mid), p.split_at_mut(mid));
        west.push((sw, uw, pw));
        east.push((se, ue, pe));
    }
    let (from_west, from_east) = from_row.split_at_mut(mid);
    let west = Half {
        first_col: 0,
        rows: west,
        from_row: from_west,
    };
    let east = Half {
        first_col: mid,
        rows: east,
        from_row: from_east,
    };
    let (upwind, downwind) = if dc > 0 { (west, east) } else { (east, west) };
    let handover: Vec<AtomicU32> = (0..h).map(|_| AtomicU32::new(0)).collect();
    let handed = AtomicUsize::new(0);
    let (up, down) = parallel::join(
        || {
            upwind.sweep(
                maps,
                &rows,
                |_| 0.0,
                |k, carry| {
                    handover[k].store(carry.to_bits(), Ordering::Relaxed);
                    handed.store(k + 1, Ordering::Release);
                },
            )
        },
        || {
            downwind.sweep(
                maps,
                &rows,
                |k| {
                    let mut spins = 0u32;
                    while handed.load(Ordering::Acquire) <= k {
                        spins += 1;
                        if spins < 1 << 10 {
                            std::hint::spin_loop();
                        } else {
                            std::thread::yield_now();
                        }
                    }
                    f32::from_bits(handover[k].load(Ordering::Relaxed))
                },
                |_, _| {},
            )
        },
    );
    SxSums {
        eroded: up.eroded + down.eroded,
        deposited: up.deposited + down.deposited,
        deposited_unstable: up.deposited_unstable + down.deposited_unstable,
        border: up.border + down.border,
        sublimated: up.sublimated + down.sublimated,
    }
}

/// What both halves of the sweep read.
struct SweepMaps<'a, V> {
    ctx: &'a Context<'a>,
    valid: &'a V,
    /// The scour's and the kept share's parameters and maps.
    cell: CellTerms<'a>,
    /// The sublimation of the drifting snow, when it runs.
    loss: Option<DriftLoss<'a>>,
    /// The share of the arriving load each cell keeps, before the slab sign
    /// ([`KeepShareCache`]).
    share: &'a [f32],
    /// The snow surface as the step found it (the slab slopes), m.
    surface: &'a [f32],
    fx: f32,
    dc: isize,
    dr: isize,
}

impl<'a, V: Validity> SweepMaps<'a, V> {
    /// What the sweep along the dominant wind `(ex, ey)` reads in a step of `dt_days` (the
    /// kept shares from `shares`, recomputed if the `Sx` map or the parameters changed; the
    /// sublimation per metre from `table`, if the humidity changed).
    fn new(
        (ctx, valid): (&'a Context<'a>, &'a V),
        params: &SxParams,
        (sx, surface, (ex, ey)): (&'a [f32], &'a [f32], (f64, f64)),
        (shares, table): (&'a mut KeepShareCache, &'a mut SublimationTable),
        dt_days: f64,
    ) -> Self {
        let (dx, dy) = (ctx.geometry.cell_size_x(), ctx.geometry.cell_size_y());
        // (A wind within 1e-15 of an axis sweeps along it: see `NEGLIGIBLE_SHARE`.)
        let fx = ex.abs() / (ex.abs() + ey.abs());
        let fx = if fx < f64::from(NEGLIGIBLE_SHARE) {
            0.0
        } else if 1.0 - fx < f64::from(NEGLIGIBLE_SHARE) {
            1.0
        } else {
            fx
        };
        let hop = fx * dx * ex.abs() + (1.0 - fx) * dy * ey.abs();
        let cell = CellTerms {
            sx,
            keep: KeepShare::new(hop / params.settling_length_m, hop * params.k_deposit),
            scour_dt: (params.k_exposed * dt_days) as f32,
            inv_ref: (1.0 / params.reference_speed_m_s) as f32,
            expo: params.speed_exponent as f32,
            exposed: params.exposed_below_deg as f32,
            sheltered: params.sheltered_above_deg as f32,
            stable: params.erode_stable.then(StableErodibility::new),
        };
        let scour_zone = if params.deposit_on_exposed {
            f32::NEG_INFINITY
        } else {
            cell.exposed
        };
        let share = shares.shares(
            &cell.keep,
            (cell.sheltered, scour_zone),
            sx,
            ctx.geometry.width(),
        );
        let air = &params.sublimation;
        let loss = ctx
            .wind
            .air_temperature
            .filter(|_| air.enabled && air.relative_humidity_pct() < 100.0)
            .map(|temperature| DriftLoss {
                share: table
                    .for_air(air.relative_humidity_pct(), params.reference_speed_m_s)
                    .map(|lambda| {
                        let x = f64::from(lambda) * hop;
                        (x / (1.0 + x)) as f32
                    }),
                temperature,
            });
        Self {
            ctx,
            valid,
            cell,
            loss,
            share,
            surface,
            fx: fx as f32,
            dc: if ex >= 0.0 { 1 } else { -1 },
            dr: if ey >= 0.0 { -1 } else { 1 },
        }
    }

    /// The scour (of the loose and of the stable snow), the share kept (negative where
    /// deposits land as unstable snow: surface slope above the slab slope) and the share
    /// sublimated of the cells `cols` of `row`, with `powder`, `unstable` and `stable` snow on
    /// them as the step found them, into `terms`; 0 on nodata.
    fn cell_terms(
        &self,
        row: usize,
        cols: std::ops::Range<usize>,
        (powder, unstable, stable): (&[f32], &[f32], &[f32]),
        terms: &mut RowTerms,
    ) {
        let ctx = self.ctx;
        let n = cols.len();
        let r = row * ctx.geometry.width() + cols.start..row * ctx.geometry.width() + cols.end;
        let (gradient, scour, from_stable, keep, sublimated) = (
            &mut terms.gradient[..n],
            &mut terms.scour[..n],
            &mut terms.from_stable[..n],
            &mut terms.keep[..n],
            &mut terms.sublimated[..n],
        );
        row_gradient_norm_in(
            self.surface,
            ctx.geometry,
            ctx.mask,
            self.valid,
            row,
            cols,
            gradient,
        );
        let erodible = ctx.erode_unstable.then_some(unstable);
        self.cell.scour_row(
            ctx.wind,
            r.clone(),
            (powder, erodible, stable),
            (scour, from_stable),
        );
        keep_row(&self.share[r.clone()], gradient, ctx.slab_gradient, keep);
        match &self.loss {
            Some(loss) => loss.share.read(&loss.temperature[r.clone()], sublimated),
            None => sublimated.fill(0.0),
        }
        for (k, i) in r.enumerate() {
            if !self.valid.at(i) {
                (scour[k], from_stable[k], keep[k], sublimated[k]) = (0.0, 0.0, 0.0, 0.0);
            }
        }
    }
}

/// One half-row's terms ([`SweepMaps::cell_terms`]) and the surface gradient they use.
struct RowTerms {
    gradient: Vec<f32>,
    /// Scour of the powder and the unstable snow.
    scour: Vec<f32>,
    /// Scour of the stable snow.
    from_stable: Vec<f32>,
    keep: Vec<f32>,
    /// Share of the load reaching the cell that sublimates.
    sublimated: Vec<f32>,
}

impl RowTerms {
    fn new(cells: usize) -> Self {
        Self {
            gradient: vec![0.0; cells],
            scour: vec![0.0; cells],
            from_stable: vec![0.0; cells],
            keep: vec![0.0; cells],
            sublimated: vec![0.0; cells],
        }
    }
}

/// A half of the columns: per row its (stable, unstable, powder) and the loads handed down
/// from the row before, indexed from `first_col`.
struct Half<'a> {
    first_col: usize,
    rows: Vec<(&'a mut [f32], &'a mut [f32], &'a mut [f32])>,
    from_row: &'a mut [f32],
}

impl Half<'_> {
    /// Sweeps the half's columns downwind, row by row in `rows` order: each row starts with
    /// the carry `carry_in(k)` from the other half (k the position in `rows`) and ends by
    /// handing its carry to `carry_out`.
    fn sweep<V: Validity>(
        self,
        m: &SweepMaps<V>,
        rows: &[usize],
        carry_in: impl Fn(usize) -> f32,
        carry_out: impl FnMut(usize, f32),
    ) -> SxSums {
        if m.dc > 0 {
            self.sweep_towards::<V, false>(m, rows, carry_in, carry_out)
        } else {
            self.sweep_towards::<V, true>(m, rows, carry_in, carry_out)
        }
    }

    /// [`Half::sweep`] towards lower columns (`WEST`) or higher ones, a row in three passes
    /// ([`drift_row`]): each cell's scour and what reaches it from the row before, the
    /// carries along the row, then each cell's shares.
    fn sweep_towards<V: Validity, const WEST: bool>(
        mut self,
        m: &SweepMaps<V>,
        rows: &[usize],
        carry_in: impl Fn(usize) -> f32,
        mut carry_out: impl FnMut(usize, f32),
    ) -> SxSums {
        let w = m.ctx.geometry.width();
        let n = self.from_row.len();
        let mut sums = SxSums::default();
        if n == 0 {
            for k in 0..rows.len() {
                carry_out(k, 0.0);
            }
            return sums;
        }
        // The column of sweep position p in the half, and the half's cell on the grid's
        // edge downwind, if any.
        let local = |p: usize| if WEST { n - 1 - p } else { p };
        let edge = if WEST {
            (self.first_col == 0).then_some(n - 1)
        } else {
            (self.first_col + n == w).then_some(n - 1)
        };
        let step_x: isize = if WEST { -1 } else { 1 };
        let step_y = m.dr * w as isize;
        let mut buf = DriftRow::new(n);
        let mut totals = RowTotals::new(n);
        let mut terms = RowTerms::new(n);
        for (k, &row) in rows.iter().enumerate() {
            let has_y = k + 1 < rows.len();
            let base = row * w + self.first_col;
            let (stable, unstable, powder) = &mut self.rows[row];
            let (stable, unstable, powder) =
                (&mut stable[..n], &mut unstable[..n], &mut powder[..n]);
            let cols = self.first_col..self.first_col + n;
            m.cell_terms(row, cols, (powder, unstable, stable), &mut terms);
            let (scour, from_stable, keep, sublimated) = (
                &terms.scour[..n],
                &terms.from_stable[..n],
                &terms.keep[..n],
                &terms.sublimated[..n],
            );
            let from_row = &mut self.from_row[..n];
            // Scour (a pure function of the cell, applied before its load: the cell's own
            // layers are not touched before it is reached) and what arrives.
            {
                let (arriving, passed) = (&mut buf.arriving[..n], &mut buf.passed[..n]);
                let eroded = &mut totals.eroded[..n];
                for p in 0..n {
                    let l = local(p);
                    let i = base + l;
                    let loose = scour[l];
                    let from_powder = loose.min(powder[l]);
                    powder[l] -= from_powder;
                    unstable[l] -= (loose - from_powder).min(unstable[l]);
                    stable[l] -= from_stable[l];
                    let e = loose + from_stable[l];
                    eroded[p] = e;
                    let along = Some(p) != edge
                        && m.valid.at(i)
                        && m.valid.at(i.wrapping_add_signed(step_x));
                    arriving[p] = flush_below(from_row[l] + e, NEGLIGIBLE_LOAD);
                    let on = (1.0 - keep[l].abs()) * (1.0 - sublimated[l]);
                    passed[p] = if along {
                        flush_below(on * m.fx, NEGLIGIBLE_SHARE)
                    } else {
                        0.0
                    };
                }
            }
            let out = buf.carries(carry_in(k));
            carry_out(k, out);
            let (carry, arriving) = (&buf.carry[..n + 1], &buf.arriving[..n]);
            let (kept_row, kept_unstable, border_row, sublimated_row) = (
                &mut totals.kept[..n],
                &mut totals.kept_unstable[..n],
                &mut totals.border[..n],
                &mut totals.sublimated[..n],
            );
            for p in 0..n {
                let l = local(p);
                let i = base + l;
                let valid = m.valid.at(i);
                // The nodata outline is an open boundary, as the grid's border: a share aimed
                // at a nodata cell leaves the terrain (border outflow).
                let across = valid && has_y && m.valid.at(i.wrapping_add_signed(step_y));
                let exits = Exits {
                    off_along: valid
                        && (Some(p) == edge || !m.valid.at(i.wrapping_add_signed(step_x))),
                    across,
                    off_across: valid && !across,
                };
                let load = carry[p] + arriving[p];
                let k_share = keep[l];
                let shares = (k_share, sublimated[l], m.fx);
                let [across, kept, border, lost] = share_out(load, shares, carry[p + 1], exits);
                from_row[l] = across;
                let slab = k_share < 0.0;
                unstable[l] = flush_negligible(unstable[l] + if slab { kept } else { 0.0 });
                powder[l] = flush_negligible(powder[l] + if slab { 0.0 } else { kept });
                kept_row[p] = kept;
                kept_unstable[p] = if slab { kept } else { 0.0 };
                border_row[p] = border;
                sublimated_row[p] = lost;
            }
            totals.add_to(&mut sums);
        }
        sums
    }
}

/// Checks the Sx map of `wind`, if any, against the grid.
pub(super) fn check(
    wind: &WindMaps,
    geometry: &snowscape_terrain::GridGeometry,
) -> Result<(), PhenomenonError> {
    match wind.sx {
        Some(sx) => crate::phenomenon::check_map("wind_sx", sx, geometry),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests;
