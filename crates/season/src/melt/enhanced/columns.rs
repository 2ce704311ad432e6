//! The per-cell column updates of the enhanced melt (the parent module's documentation:
//! deficit, refreezing, melt from the top down, liquid water, runoff, albedo curve), in lanes
//! of [`LANES`] cells.

/// One row's state, in place.
pub(super) struct RowState<'a> {
    pub(super) layers: [&'a mut [f32]; 4],
    pub(super) age: &'a mut [f32],
    pub(super) cold: &'a mut [f32],
    pub(super) liquid: &'a mut [f32],
    pub(super) melting: &'a mut [f32],
}

/// The scalars of the column updates.
#[derive(Debug, Clone, Copy)]
pub(super) struct Scalars {
    /// f_T, m of water per h per °C.
    pub(super) f_t: f32,
    /// f_R, m of water per h per W/m².
    pub(super) f_r: f32,
    /// The window's recorded longwave balance as melt, m of water (negative: cooling).
    pub(super) longwave_m: f32,
    /// Rain heat: m of melt per m of rain per °C.
    pub(super) rain_heat: f32,
    /// Weighted mean sea-level temperature of the window, °C.
    pub(super) mean_sea_level: f32,
    /// Cold content of 1 m w.e. per °C below 0, m w.e.
    pub(super) cold_per_c: f32,
    /// k_cc, m of water per h per °C.
    pub(super) k_cc: f32,
    /// θ_max.
    pub(super) holding: f32,
    /// Water per metre of each layer's snow, m/m.
    pub(super) water_per_depth: [f32; 4],
    /// Its inverse, m of snow per m of water.
    pub(super) depth_per_water: [f32; 4],
    /// Length of the window, days.
    pub(super) window_days: f32,
}

/// The per-column inputs of one row (all of the row's length).
pub(super) struct Columns<'a> {
    pub(super) off: &'a [f32],
    pub(super) shortwave: &'a [f32],
    pub(super) absorbed: &'a [f32],
    pub(super) cooling: &'a [f32],
    pub(super) warm: &'a [f32],
    pub(super) rain: &'a [f32],
    pub(super) keep: &'a [f32],
}

/// The column updates of one row (module docs: deficit, refreezing, melt from the top
/// down, liquid water, runoff, albedo curve), [`LANES`] cells at a time, lane by lane over
/// fixed-size arrays and without data-dependent branches, so that every operation is one
/// vector instruction (AVX2 where the CPU has it: Rust does not fuse multiply-adds, so both
/// builds give the same bits). Written cell by cell, the compiler vectorised across the four
/// layers of one cell instead and the kernel ran scalar (1024² season: melt and stability
/// 2.5 s, 2.3 s in lanes).
#[multiversion::multiversion(targets("x86_64+avx2"))]
pub(super) fn column_updates<'s>(
    k: &Scalars,
    c: Columns,
    st: RowState,
    sums: &'s mut [Vec<f32>; 6],
) -> &'s [Vec<f32>; 6] {
    let w = c.off.len();
    let [lc, ls, lu, lp] = st.layers;
    let (lc, ls, lu, lp) = (&mut lc[..w], &mut ls[..w], &mut lu[..w], &mut lp[..w]);
    let (age, cold_s, liquid_s, melting) = (
        &mut st.age[..w],
        &mut st.cold[..w],
        &mut st.liquid[..w],
        &mut st.melting[..w],
    );
    let (sw, ab, co, wa, ra, keep) = (
        &c.shortwave[..w],
        &c.absorbed[..w],
        &c.cooling[..w],
        &c.warm[..w],
        &c.rain[..w],
        &c.keep[..w],
    );
    let [s_rd, s_rw, s_md, s_mw, s_rain, s_ro] = sums;
    let (s_rd, s_rw, s_md, s_mw, s_rain, s_ro) = (
        &mut s_rd[..w],
        &mut s_rw[..w],
        &mut s_md[..w],
        &mut s_mw[..w],
        &mut s_rain[..w],
        &mut s_ro[..w],
    );
    let (wpd, dpw) = (k.water_per_depth, k.depth_per_water);
    // The cells in groups of LANES, every operation lane by lane over fixed-size arrays, so
    // that each becomes one vector instruction; the last group is padded with empty cells
    // (kept: 0, nothing written back). Each lane does the scalar operations of one cell in
    // the scalar order, so the results keep their bits.
    let mut c0 = 0;
    while c0 < w {
        let n = LANES.min(w - c0);
        let r = c0..c0 + n;
        let keep_l = load(&keep[r.clone()]);
        let old = [
            load(&lc[r.clone()]),
            load(&ls[r.clone()]),
            load(&lu[r.clone()]),
            load(&lp[r.clone()]),
        ];
        let [mut l0, mut l1, mut l2, mut l3] = old;
        let rain = load(&ra[r.clone()]);
        let off = load(&c.off[r.clone()]);
        let (warm, absorbed, short) = (
            load(&wa[r.clone()]),
            load(&ab[r.clone()]),
            load(&sw[r.clone()]),
        );
        let cooling = load(&co[r.clone()]);
        let old_cold = load(&cold_s[r.clone()]);
        let old_liquid = load(&liquid_s[r.clone()]);
        let old_age = load(&age[r.clone()]);
        let old_melting = load(&melting[r.clone()]);
        let swe = lanes(|l| l0[l] * wpd[0] + l1[l] * wpd[1] + l2[l] * wpd[2] + l3[l] * wpd[3]);
        let t_mean = lanes(|l| k.mean_sea_level + off[l]);
        let energy = lanes(|l| {
            k.f_t * warm[l]
                + k.f_r * absorbed[l] * short[l]
                + k.longwave_m
                + rain[l] * k.rain_heat * t_mean[l].max(0.0)
        });
        // A negative balance (a recorded longwave deficit larger than the gains) cools.
        let deficit = lanes(|l| (-energy[l]).max(0.0));
        let energy = lanes(|l| energy[l].max(0.0));
        // The deficit grows with the cold hours, up to the pack's cold content.
        let cap = lanes(|l| swe[l] * k.cold_per_c * (-t_mean[l]).max(0.0));
        let cold = lanes(|l| {
            old_cold[l].max((old_cold[l] + k.k_cc * cooling[l] + deficit[l]).min(cap[l]))
        });
        // Liquid water refreezes against the deficit, into the compacted layer.
        let refreeze = lanes(|l| old_liquid[l].min(cold[l]));
        let liquid = lanes(|l| old_liquid[l] - refreeze[l]);
        let cold = lanes(|l| cold[l] - refreeze[l]);
        let refrozen_depth = lanes(|l| refreeze[l] * dpw[0]);
        l0 = lanes(|l| l0[l] + refrozen_depth[l]);
        // Melt energy pays the deficit, then melts from the top down.
        let paid = lanes(|l| energy[l].min(cold[l]));
        let cold = lanes(|l| cold[l] - paid[l]);
        let mut water = lanes(|l| energy[l] - paid[l]);
        let (mut melted_water, mut melted_depth) = ([0.0f32; LANES], [0.0f32; LANES]);
        for (layer, j) in [(&mut l3, 3), (&mut l2, 2), (&mut l1, 1), (&mut l0, 0)] {
            let have = lanes(|l| layer[l] * wpd[j]);
            let take = lanes(|l| water[l].min(have[l]));
            let depth = lanes(|l| {
                if take[l] >= have[l] {
                    layer[l]
                } else {
                    take[l] * dpw[j]
                }
            });
            *layer = lanes(|l| layer[l] - depth[l]);
            melted_depth = lanes(|l| melted_depth[l] + depth[l]);
            water = lanes(|l| water[l] - take[l]);
            melted_water = lanes(|l| melted_water[l] + take[l]);
        }
        {
            use crate::phenomenon::flush_negligible as f;
            l0 = lanes(|l| f(l0[l]));
            l1 = lanes(|l| f(l1[l]));
            l2 = lanes(|l| f(l2[l]));
            l3 = lanes(|l| f(l3[l]));
        }
        let liquid = lanes(|l| liquid[l] + (melted_water[l] + rain[l]));
        let left = lanes(|l| l0[l] * wpd[0] + l1[l] * wpd[1] + l2[l] * wpd[2] + l3[l] * wpd[3]);
        let hold = lanes(|l| {
            if left[l] > 0.0 {
                k.holding * left[l]
            } else {
                0.0
            }
        });
        let runoff = lanes(|l| (liquid[l] - hold[l]).max(0.0));
        let liquid = lanes(|l| liquid[l] - runoff[l]);
        let cold = lanes(|l| if left[l] > 0.0 { cold[l] } else { 0.0 });
        // Bare ground has no surface memory; a ripe pack (no cold content left, wet) ages on
        // the melt-season curve.
        let new_age = lanes(|l| {
            if swe[l] > 0.0 {
                old_age[l] + k.window_days
            } else {
                0.0
            }
        });
        let ripe = lanes(|l| {
            if left[l] > 0.0 && cold[l] <= 0.0 && liquid[l] > 0.0 {
                1.0
            } else {
                0.0
            }
        });
        let pick = |new: [f32; LANES], old: [f32; LANES]| {
            lanes(|l| if keep_l[l] > 0.5 { new[l] } else { old[l] })
        };
        store(&mut lc[r.clone()], pick(l0, old[0]));
        store(&mut ls[r.clone()], pick(l1, old[1]));
        store(&mut lu[r.clone()], pick(l2, old[2]));
        store(&mut lp[r.clone()], pick(l3, old[3]));
        store(&mut cold_s[r.clone()], pick(cold, old_cold));
        store(&mut liquid_s[r.clone()], pick(liquid, old_liquid));
        store(&mut age[r.clone()], pick(new_age, old_age));
        store(&mut melting[r.clone()], pick(ripe, old_melting));
        store(
            &mut s_rd[r.clone()],
            lanes(|l| keep_l[l] * refrozen_depth[l]),
        );
        store(&mut s_rw[r.clone()], lanes(|l| keep_l[l] * refreeze[l]));
        store(&mut s_md[r.clone()], lanes(|l| keep_l[l] * melted_depth[l]));
        store(&mut s_mw[r.clone()], lanes(|l| keep_l[l] * melted_water[l]));
        store(
            &mut s_rain[r.clone()],
            lanes(|l| {
                if swe[l] > 0.0 {
                    keep_l[l] * rain[l]
                } else {
                    0.0
                }
            }),
        );
        store(&mut s_ro[r], lanes(|l| keep_l[l] * runoff[l]));
        c0 += LANES;
    }
    sums
}

/// Cells per group of [`column_updates`] (one AVX2 register of f32).
const LANES: usize = 8;

/// `f` of every lane.
#[inline(always)]
fn lanes(f: impl Fn(usize) -> f32) -> [f32; LANES] {
    std::array::from_fn(f)
}

/// Up to [`LANES`] values, the rest 0 (an empty cell). A full group is one fixed-size copy
/// (one vector load): a copy of a slice's length went through a call to `memmove` per load.
#[inline(always)]
fn load(v: &[f32]) -> [f32; LANES] {
    if let Ok(full) = <[f32; LANES]>::try_from(v) {
        return full;
    }
    let mut a = [0.0; LANES];
    a[..v.len()].copy_from_slice(v);
    a
}

/// The first `out.len()` lanes of `a` (a full group in one fixed-size store).
#[inline(always)]
fn store(out: &mut [f32], a: [f32; LANES]) {
    if let Ok(full) = <&mut [f32; LANES]>::try_from(&mut *out) {
        *full = a;
        return;
    }
    let n = out.len();
    out.copy_from_slice(&a[..n]);
}
