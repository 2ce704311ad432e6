//! The drift sweep against the cell-by-cell recurrence it regroups.

use super::*;
use crate::phenomenon::with_validity;
use snowscape_terrain::random::uniform;
use snowscape_terrain::{Grid, GridGeometry, NodataMask};

/// The sweep cell after cell in one sequential pass (the recurrence of the module docs, as
/// written before the row scan): what the scan must reproduce to round-off.
fn sequential_sweep(
    valid: &[bool],
    (w, h): (usize, usize),
    (dc, dr, fx): (isize, isize, f32),
    (scour, from_stable, keep, sublimated): (&[f32], &[f32], &[f32], &[f32]),
    [stable, unstable, powder]: [&mut [f32]; 3],
) -> [f64; 5] {
    let rows: Vec<usize> = if dr < 0 {
        (0..h).rev().collect()
    } else {
        (0..h).collect()
    };
    let cols: Vec<usize> = if dc > 0 {
        (0..w).collect()
    } else {
        (0..w).rev().collect()
    };
    let mut from_row = vec![0.0f32; w];
    let [
        mut eroded,
        mut deposited,
        mut unstable_dep,
        mut border,
        mut lost,
    ] = [0.0f64; 5];
    for (k, &row) in rows.iter().enumerate() {
        let mut carry = 0.0f32;
        for &col in &cols {
            let i = row * w + col;
            let from_above = std::mem::take(&mut from_row[col]);
            if !valid[i] {
                carry = 0.0;
                continue;
            }
            let loose = scour[i];
            let from_powder = loose.min(powder[i]);
            powder[i] -= from_powder;
            unstable[i] -= (loose - from_powder).min(unstable[i]);
            stable[i] -= from_stable[i];
            let e = loose + from_stable[i];
            eroded += f64::from(e);
            let load = carry + from_above + e;
            carry = 0.0;
            // The share that sublimates on the way, then the shares of the rest.
            let sublimating = load * sublimated[i];
            lost += f64::from(sublimating);
            let load = load - sublimating;
            let kept = load * keep[i].abs();
            let out = load - kept;
            let to_x = out * fx;
            let to_y = out - to_x;
            let next_col = col as isize + dc;
            if next_col < 0 || next_col >= w as isize {
                border += f64::from(to_x);
            } else if valid[(i as isize + dc) as usize] {
                carry = to_x;
            } else {
                // The nodata outline is an open boundary, as the grid's border.
                border += f64::from(to_x);
            }
            if k + 1 == rows.len() {
                border += f64::from(to_y);
            } else if valid[(i as isize + dr * w as isize) as usize] {
                from_row[col] = to_y;
            } else {
                border += f64::from(to_y);
            }
            deposited += f64::from(kept);
            if keep[i] < 0.0 {
                unstable[i] += kept;
                unstable_dep += f64::from(kept);
            } else {
                powder[i] += kept;
            }
        }
    }
    [eroded, deposited, unstable_dep, border, lost]
}

/// A rough terrain with nodata, random `Sx`, winds and shadows (so that cells are exposed,
/// sheltered, shadowed and on slab slopes), and winds from each quadrant and along each axis,
/// on one and two threads: every layer within 2e-6 m of the sequential recurrence fed with the
/// same per-cell terms, and the sums within 1e-6 of it.
#[test]
fn the_row_scan_gives_the_sequential_recurrence_to_round_off() {
    compare_with_recurrence(53, 37, true);
}

/// The same on grids of one to five columns or rows (halves of 0 to 3 columns, a single row
/// whose shares across all leave the grid).
#[test]
fn the_row_scan_holds_on_grids_a_few_cells_wide() {
    for (w, h) in [(1, 6), (2, 5), (3, 4), (5, 1), (4, 2)] {
        compare_with_recurrence(w, h, false);
    }
}

/// The sweep against [`sequential_sweep`] on a `w` x `h` grid (module test above); `coverage`:
/// also check that the case exercises scour, slab slopes and border outflow.
fn compare_with_recurrence(w: usize, h: usize, coverage: bool) {
    let scene = Scene::new(w, h);
    let wind = scene.wind();
    let params = crate::wind_transport::WindTransportParams::default();
    let mask = scene.terrain.mask().clone();
    let ctx = Context::new(&scene.geo, &mask, &wind, &params, 0.5);
    // A fast scour (it reaches the stable snow) and dry air (a tenth of the load sublimates
    // per 10 m hop at −1 °C).
    let sx_params = SxParams {
        k_exposed: 0.05,
        sublimation: DriftSublimationParams {
            relative_humidity_pct: Some(40.0),
            ..Default::default()
        },
        ..Default::default()
    };
    for (ex, ey) in [
        (1.0f64, 0.3f64),
        (-1.0, 0.5),
        (0.4, -1.0),
        (-0.2, -1.0),
        (1.0, 0.0),
        (0.0, 1.0),
        (-1.0, 0.0),
    ] {
        let case = Case {
            scene: &scene,
            ctx: &ctx,
            mask: &mask,
            sx_params: &sx_params,
            wind: (ex, ey),
        };
        let terms = case.reference_terms();
        let (mut es, mut eu, mut ep) = (
            scene.terrain.snow[1].clone(),
            scene.terrain.snow[2].clone(),
            scene.terrain.snow[3].clone(),
        );
        let sums = sequential_sweep(
            &scene.valid,
            (w, h),
            (terms.dc, terms.dr, terms.fx),
            (
                &terms.scour,
                &terms.from_stable,
                &terms.keep,
                &terms.sublimated,
            ),
            [&mut es, &mut eu, &mut ep],
        );
        if coverage {
            terms.assert_coverage();
        }
        for threads in [1, 2] {
            case.check_sweep(threads, [&es, &eu, &ep], &sums, coverage);
        }
    }
}

/// The scene of [`compare_with_recurrence`]: a rough terrain with nodata and snow in three
/// layers, random `Sx`, winds, air temperatures and shadows (so that cells are exposed,
/// sheltered, shadowed and on slab slopes).
struct Scene {
    geo: GridGeometry,
    valid: Vec<bool>,
    terrain: LayeredTerrain,
    surface: Vec<f32>,
    sx: Vec<f32>,
    u: Vec<f32>,
    v: Vec<f32>,
    air: Vec<f32>,
    shadow: Vec<f32>,
}

impl Scene {
    /// The scene on a `w` x `h` grid.
    fn new(w: usize, h: usize) -> Self {
        let geo = GridGeometry::square(w, h, 10.0).unwrap();
        let n = w * h;
        let invalid: Vec<bool> = (0..n).map(|i| uniform(3, 0, i as u64) < 0.06).collect();
        let valid: Vec<bool> = invalid.iter().map(|b| !b).collect();
        let bed = Grid::new(
            geo.clone(),
            (0..n)
                .map(|i| (1000.0 + 12.0 * uniform(3, 7, i as u64)) as f32)
                .collect(),
            NodataMask::from_invalid(invalid.clone()),
        )
        .unwrap();
        let zero = |v: f64, i: usize| if valid[i] { v as f32 } else { 0.0 };
        let mut terrain = LayeredTerrain::from_bedrock(bed);
        for i in 0..n {
            terrain.snow[1][i] = zero(0.4 * uniform(3, 8, i as u64), i);
            terrain.snow[2][i] = zero(0.3 * uniform(3, 1, i as u64), i);
            terrain.snow[3][i] = zero(0.5 * uniform(3, 2, i as u64), i);
        }
        let surface: Vec<f32> = (0..n)
            .map(|i| terrain.bedrock[i] + terrain.snow.iter().map(|l| l[i]).sum::<f32>())
            .collect();
        let sx: Vec<f32> = (0..n)
            .map(|i| (30.0 * uniform(3, 3, i as u64) - 15.0) as f32)
            .collect();
        let u: Vec<f32> = (0..n)
            .map(|i| (15.0 * uniform(3, 4, i as u64)) as f32)
            .collect();
        let v: Vec<f32> = (0..n)
            .map(|i| (8.0 * uniform(3, 5, i as u64)) as f32)
            .collect();
        // Air from −30 to +3 °C (the table's clamps too).
        let air: Vec<f32> = (0..n)
            .map(|i| (33.0 * uniform(3, 9, i as u64) - 30.0) as f32)
            .collect();
        let shadow: Vec<f32> = (0..n)
            .map(|i| {
                if uniform(3, 6, i as u64) < 0.1 {
                    1.0
                } else {
                    0.0
                }
            })
            .collect();
        Self {
            geo,
            valid,
            terrain,
            surface,
            sx,
            u,
            v,
            air,
            shadow,
        }
    }

    /// The scene's wind field.
    fn wind(&self) -> WindMaps<'_> {
        WindMaps {
            u: &self.u,
            v: &self.v,
            shadow: &self.shadow,
            effect_surface: &self.surface,
            sx: Some(&self.sx),
            terms: None,
            air_temperature: Some(&self.air),
        }
    }
}

/// One case of [`compare_with_recurrence`]: the scene, its context, the parameters and the
/// dominant wind `(ex, ey)`.
struct Case<'a> {
    scene: &'a Scene,
    ctx: &'a Context<'a>,
    mask: &'a NodataMask,
    sx_params: &'a SxParams,
    wind: (f64, f64),
}

/// The per-cell terms the sweep computes, over whole rows, for the reference: scour, erosion
/// of the stable snow, kept share and sublimated share, and the sweep's share across `fx`
/// and steps `dc`, `dr`.
struct ReferenceTerms {
    scour: Vec<f32>,
    from_stable: Vec<f32>,
    keep: Vec<f32>,
    sublimated: Vec<f32>,
    fx: f32,
    dc: isize,
    dr: isize,
}

impl ReferenceTerms {
    /// The case exercises scour (of the stable snow too), slab slopes and sublimation.
    fn assert_coverage(&self) {
        let n = self.scour.len();
        let (scour, from_stable) = (&self.scour, &self.from_stable);
        let (keep, sublimated) = (&self.keep, &self.sublimated);
        assert!(
            keep.iter().any(|&k| k < 0.0)
                && scour.iter().filter(|&&e| e > 0.0).count() > n / 10
                && from_stable.iter().filter(|&&e| e > 0.0).count() > n / 20
                && sublimated.iter().all(|&s| (0.0..0.2).contains(&s))
                && sublimated.iter().filter(|&&s| s > 0.0).count() > n / 2
        );
    }
}

impl Case<'_> {
    /// The per-cell terms of the case's sweep.
    fn reference_terms(&self) -> ReferenceTerms {
        let Scene {
            terrain,
            surface,
            sx,
            ..
        } = self.scene;
        let (w, h) = (self.scene.geo.width(), self.scene.geo.height());
        let n = w * h;
        let (mut scour, mut keep) = (vec![0.0f32; n], vec![0.0f32; n]);
        let (mut from_stable, mut sublimated) = (vec![0.0f32; n], vec![0.0f32; n]);
        let mut cache = KeepShareCache::default();
        let mut table = SublimationTable::default();
        let (fx, dc, dr) = with_validity!(self.mask, |v| {
            let maps = SweepMaps::new(
                (self.ctx, v),
                self.sx_params,
                (sx, surface, self.wind),
                (&mut cache, &mut table),
                0.5,
            );
            let mut terms = RowTerms::new(w);
            for row in 0..h {
                let r = row * w..(row + 1) * w;
                let layers = (
                    &terrain.snow[3][r.clone()],
                    &terrain.snow[2][r.clone()],
                    &terrain.snow[1][r.clone()],
                );
                maps.cell_terms(row, 0..w, layers, &mut terms);
                scour[r.clone()].copy_from_slice(&terms.scour);
                from_stable[r.clone()].copy_from_slice(&terms.from_stable);
                keep[r.clone()].copy_from_slice(&terms.keep);
                sublimated[r].copy_from_slice(&terms.sublimated);
            }
            (maps.fx, maps.dc, maps.dr)
        });
        ReferenceTerms {
            scour,
            from_stable,
            keep,
            sublimated,
            fx,
            dc,
            dr,
        }
    }

    /// The sweep on `threads` threads against the recurrence's layers `[stable, unstable,
    /// powder]` (within 2e-6 m) and sums (within 1e-6 of the depth eroded); `coverage`: also
    /// check that some snow was eroded, deposited on slab slopes, lost at the border and
    /// sublimated.
    fn check_sweep(
        &self,
        threads: usize,
        [es, eu, ep]: [&[f32]; 3],
        sums: &[f64; 5],
        coverage: bool,
    ) {
        let (ex, ey) = self.wind;
        let Scene {
            terrain,
            surface,
            sx,
            ..
        } = self.scene;
        let mut t = terrain.clone();
        let mut scratch = SxScratch::default();
        let got = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                with_validity!(self.mask, |v| run(
                    self.ctx,
                    v,
                    self.sx_params,
                    (sx, surface, Some((ex, ey))),
                    &mut t,
                    &mut scratch,
                    0.5
                ))
            });
        for i in 0..es.len() {
            for (layer, want) in [(1, es[i]), (2, eu[i]), (3, ep[i])] {
                let d = (t.snow[layer][i] - want).abs();
                assert!(
                    d <= 2e-6,
                    "wind ({ex}, {ey}), {threads} threads: layer {layer} at cell {i}: {} against {want}",
                    t.snow[layer][i]
                );
            }
        }
        let got = [
            got.eroded,
            got.deposited,
            got.deposited_unstable,
            got.border,
            got.sublimated,
        ];
        for (g, s) in got.iter().zip(sums) {
            assert!(
                (g - s).abs() <= 1e-6 * sums[0],
                "sums {got:?} against {sums:?}"
            );
        }
        if coverage {
            assert!(
                sums[0] > 1.0 && sums[2] > 0.1 && sums[3] > 0.1 && sums[4] > 0.1,
                "{sums:?}"
            );
        }
        // Every depth scoured is kept, sublimated or border outflow.
        let closure = got[0] - got[1] - got[3] - got[4];
        assert!(closure.abs() <= 1e-5 * got[0], "{got:?}");
    }
}
