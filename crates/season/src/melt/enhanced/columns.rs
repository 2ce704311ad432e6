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

/// One group's snowpack, [`LANES`] cells: the four layers' depths (m of snow, compacted first),
/// cold content and liquid water (m w.e.), surface age (days) and the melt-season flag.
#[derive(Clone, Copy)]
struct Pack {
    layers: [[f32; LANES]; 4],
    cold: [f32; LANES],
    liquid: [f32; LANES],
    age: [f32; LANES],
    melting: [f32; LANES],
}

/// One group's forcing over the window: the temperature offset from sea level (°C), the warm
/// degree hours, absorbed fraction and shortwave, the cold hours and the rain (m of water).
struct Forcing {
    off: [f32; LANES],
    warm: [f32; LANES],
    absorbed: [f32; LANES],
    short: [f32; LANES],
    cooling: [f32; LANES],
    rain: [f32; LANES],
}

/// What one group's update moved: depth (m) and water (m w.e.) refrozen and melted, the runoff
/// (m of water), and the water equivalent before the update (m, for the rain on snow).
struct Moved {
    refrozen_depth: [f32; LANES],
    refreeze: [f32; LANES],
    melted_depth: [f32; LANES],
    melted_water: [f32; LANES],
    runoff: [f32; LANES],
    swe: [f32; LANES],
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
    // The cells in groups of LANES, every operation lane by lane over fixed-size arrays, so
    // that each becomes one vector instruction; the last group is padded with empty cells
    // (kept: 0, nothing written back). Each lane does the scalar operations of one cell in
    // the scalar order, so the results keep their bits.
    let mut c0 = 0;
    while c0 < w {
        let n = LANES.min(w - c0);
        let r = c0..c0 + n;
        let keep_l = load(&keep[r.clone()]);
        let old = Pack {
            layers: [
                load(&lc[r.clone()]),
                load(&ls[r.clone()]),
                load(&lu[r.clone()]),
                load(&lp[r.clone()]),
            ],
            cold: load(&cold_s[r.clone()]),
            liquid: load(&liquid_s[r.clone()]),
            age: load(&age[r.clone()]),
            melting: load(&melting[r.clone()]),
        };
        let forcing = Forcing {
            off: load(&c.off[r.clone()]),
            warm: load(&wa[r.clone()]),
            absorbed: load(&ab[r.clone()]),
            short: load(&sw[r.clone()]),
            cooling: load(&co[r.clone()]),
            rain: load(&ra[r.clone()]),
        };
        let (new, moved) = update_group(k, &forcing, &old);
        let pick = |new: [f32; LANES], old: [f32; LANES]| {
            lanes(|l| if keep_l[l] > 0.5 { new[l] } else { old[l] })
        };
        store(&mut lc[r.clone()], pick(new.layers[0], old.layers[0]));
        store(&mut ls[r.clone()], pick(new.layers[1], old.layers[1]));
        store(&mut lu[r.clone()], pick(new.layers[2], old.layers[2]));
        store(&mut lp[r.clone()], pick(new.layers[3], old.layers[3]));
        store(&mut cold_s[r.clone()], pick(new.cold, old.cold));
        store(&mut liquid_s[r.clone()], pick(new.liquid, old.liquid));
        store(&mut age[r.clone()], pick(new.age, old.age));
        store(&mut melting[r.clone()], pick(new.melting, old.melting));
        let kept = |v: [f32; LANES]| lanes(|l| keep_l[l] * v[l]);
        store(&mut s_rd[r.clone()], kept(moved.refrozen_depth));
        store(&mut s_rw[r.clone()], kept(moved.refreeze));
        store(&mut s_md[r.clone()], kept(moved.melted_depth));
        store(&mut s_mw[r.clone()], kept(moved.melted_water));
        store(
            &mut s_rain[r.clone()],
            lanes(|l| {
                if moved.swe[l] > 0.0 {
                    keep_l[l] * forcing.rain[l]
                } else {
                    0.0
                }
            }),
        );
        store(&mut s_ro[r], kept(moved.runoff));
        c0 += LANES;
    }
    sums
}

/// The update of one group of cells (module docs), lane by lane: the energy balance and the
/// deficit, refreezing, melt from the top down, liquid water and runoff, age and ripeness.
#[inline(always)]
fn update_group(k: &Scalars, f: &Forcing, old: &Pack) -> (Pack, Moved) {
    let (wpd, dpw) = (k.water_per_depth, k.depth_per_water);
    let [mut l0, mut l1, mut l2, mut l3] = old.layers;
    let (rain, off, warm, absorbed, short) = (f.rain, f.off, f.warm, f.absorbed, f.short);
    let (old_cold, old_liquid, old_age) = (old.cold, old.liquid, old.age);
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
    let cold =
        lanes(|l| old_cold[l].max((old_cold[l] + k.k_cc * f.cooling[l] + deficit[l]).min(cap[l])));
    // Liquid water refreezes against the deficit, into the compacted layer.
    let refreeze = lanes(|l| old_liquid[l].min(cold[l]));
    let liquid = lanes(|l| old_liquid[l] - refreeze[l]);
    let cold = lanes(|l| cold[l] - refreeze[l]);
    let refrozen_depth = lanes(|l| refreeze[l] * dpw[0]);
    l0 = lanes(|l| l0[l] + refrozen_depth[l]);
    // Melt energy pays the deficit, then melts from the top down.
    let paid = lanes(|l| energy[l].min(cold[l]));
    let cold = lanes(|l| cold[l] - paid[l]);
    let water = lanes(|l| energy[l] - paid[l]);
    let mut layers = [l0, l1, l2, l3];
    let (melted_water, melted_depth) = melt_top_down(&mut layers, water, wpd, dpw);
    {
        use crate::phenomenon::flush_negligible as f;
        let [m0, m1, m2, m3] = layers;
        l0 = lanes(|l| f(m0[l]));
        l1 = lanes(|l| f(m1[l]));
        l2 = lanes(|l| f(m2[l]));
        l3 = lanes(|l| f(m3[l]));
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
    let new = Pack {
        layers: [l0, l1, l2, l3],
        cold,
        liquid,
        age: new_age,
        melting: ripe,
    };
    let moved = Moved {
        refrozen_depth,
        refreeze,
        melted_depth,
        melted_water,
        runoff,
        swe,
    };
    (new, moved)
}

/// Melt from the top down: `water` (m w.e. per lane) melts the layers from the last (the
/// powder) to the first, each layer wholly once the water reaches its water equivalent.
/// Returns the water and the depth melted.
#[inline(always)]
fn melt_top_down(
    layers: &mut [[f32; LANES]; 4],
    mut water: [f32; LANES],
    wpd: [f32; 4],
    dpw: [f32; 4],
) -> ([f32; LANES], [f32; LANES]) {
    let (mut melted_water, mut melted_depth) = ([0.0f32; LANES], [0.0f32; LANES]);
    for j in [3, 2, 1, 0] {
        let layer = &mut layers[j];
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
    (melted_water, melted_depth)
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
