//! The per-cell step loop of the energy balance (parent module's docs) in groups of
//! [`LANES`] cells: every operation lane by lane over fixed-size arrays without
//! data-dependent branches (vector instructions: AVX-512 or AVX2 where the CPU has them, the
//! same bits as SSE since Rust does not fuse multiply-adds and division and square root are
//! exact), each step over every group of a row with snow before the next step.

use super::super::enhanced::{EnhancedMeltParams, MeltForcing, albedo_from_table};
use super::EnergyBalanceParams;
use super::constants::{
    AIR_HEAT_CAPACITY, DRY_AIR_GAS_CONSTANT, MELTING_POINT_K, PRESSURE_SCALE_HEIGHT,
    SEA_LEVEL_PRESSURE, STEFAN_BOLTZMANN, VAPOUR_GAS_CONSTANT, VON_KARMAN,
};
use super::steps::{COLDEST_SURFACE_C, OffsetRange, Step, ice_saturation_polynomials, polynomial};
use snowscape_terrain::materials::{
    GRAVITY_M_S2, LATENT_HEAT_FUSION_J_KG, LATENT_HEAT_SUBLIMATION_J_KG, SPECIFIC_HEAT_ICE_J_KG_K,
    SPECIFIC_HEAT_WATER_J_KG_K, WATER_DENSITY_KG_M3,
};

/// Cells per group: sixteen, two AVX2 registers (or one AVX-512 register) per operation, so
/// each group carries two independent halves through the pipeline.
const LANES: usize = 16;

type Lanes = [f32; LANES];

/// Shortest conduction length, m (a pack a centimetre deep).
const THINNEST_CONDUCTION_M: f32 = 0.005;

/// The parameters and constants in the units of the kernel.
pub(super) struct Kernel {
    /// ε σ, W m⁻² K⁻⁴.
    eps_sigma: f32,
    /// σ, W m⁻² K⁻⁴.
    sigma: f32,
    /// G, W/m².
    ground: f32,
    /// b of the stability functions.
    stability: f32,
    /// `3 b² C_D` of the unstable function.
    unstable: f32,
    /// z_U / z_0.
    height_ratio: f32,
    /// `c_p C_H / R_d`: times `p / T` it is `ρ c_p C_H`, J m⁻³ K⁻¹.
    heat_per_pressure: f32,
    /// `C_H / R_v`: times `1 / T` it is the vapour conductance per unit wind, kg m⁻³ Pa⁻¹.
    vapour_conductance: f32,
    /// `g z_U² / z_T`, m²/s² (times `ΔT / (T U²)` it is the bulk Richardson number).
    richardson: f32,
    /// k_s, W m⁻¹ K⁻¹.
    conductivity: f32,
    /// Largest conduction length, m.
    conduction_depth: f32,
    /// L_s, J/kg.
    latent_sublimation: f32,
    /// `L_f ρ_w`: energy of 1 m of melt water, J/m².
    fusion_per_m: f32,
    /// `c_i ρ_w`: heat capacity of 1 m w.e. of ice, J m⁻² K⁻¹.
    ice_capacity_per_m: f32,
    /// `c_w / L_f`: melt per m of rain per °C.
    rain_heat: f32,
    /// `1 / ρ_w`, m³/kg.
    water_volume: f32,
    /// Weighted mean sea-level temperature of the window, °C.
    mean_sea_level: f32,
    /// θ_max.
    holding: f32,
    /// Water per metre of each layer's snow, m/m.
    water_per_depth: [f32; 4],
    /// Its inverse.
    depth_per_water: [f32; 4],
    /// Length of the window, days.
    window_days: f32,
    /// The terrain's offsets (the steps' polynomials' variable).
    offsets: OffsetRange,
    /// Saturation vapour pressure over ice and its slope, polynomials in `(T + 30) / 30`.
    ice_saturation: ([f32; 7], [f32; 6]),
}

impl Kernel {
    pub(super) fn new(
        p: &EnergyBalanceParams,
        shared: &EnhancedMeltParams,
        f: &MeltForcing,
        offsets: &OffsetRange,
    ) -> Self {
        let mean_sea_level = f.mean_sea_level_c();
        let (z0, zu, zt) = (
            p.roughness_length_m,
            p.wind_height_m,
            p.temperature_height_m,
        );
        let drag = (VON_KARMAN / (zu / z0).ln()).powi(2);
        let heat = VON_KARMAN.powi(2) / ((zu / z0).ln() * (zt / (0.1 * z0)).ln());
        let b = p.stability_slope;
        Self {
            eps_sigma: (p.emissivity * STEFAN_BOLTZMANN) as f32,
            sigma: STEFAN_BOLTZMANN as f32,
            ground: p.ground_heat_w_m2 as f32,
            stability: b as f32,
            unstable: (3.0 * b * b * drag) as f32,
            height_ratio: (zu / z0) as f32,
            heat_per_pressure: (AIR_HEAT_CAPACITY * heat / DRY_AIR_GAS_CONSTANT) as f32,
            vapour_conductance: (heat / VAPOUR_GAS_CONSTANT) as f32,
            richardson: (GRAVITY_M_S2 * zu * zu / zt) as f32,
            conductivity: p.snow_conductivity_w_m_k as f32,
            conduction_depth: p.conduction_depth_m as f32,
            latent_sublimation: LATENT_HEAT_SUBLIMATION_J_KG as f32,
            fusion_per_m: (LATENT_HEAT_FUSION_J_KG * WATER_DENSITY_KG_M3) as f32,
            ice_capacity_per_m: (SPECIFIC_HEAT_ICE_J_KG_K * WATER_DENSITY_KG_M3) as f32,
            rain_heat: (SPECIFIC_HEAT_WATER_J_KG_K / LATENT_HEAT_FUSION_J_KG) as f32,
            water_volume: (1.0 / WATER_DENSITY_KG_M3) as f32,
            mean_sea_level,
            holding: shared.liquid_holding_capacity as f32,
            water_per_depth: shared
                .layer_density_kg_m3
                .map(|d| (d / WATER_DENSITY_KG_M3) as f32),
            depth_per_water: shared
                .layer_density_kg_m3
                .map(|d| (WATER_DENSITY_KG_M3 / d) as f32),
            window_days: f.window_days,
            offsets: *offsets,
            ice_saturation: ice_saturation_polynomials(),
        }
    }

    /// The window on one row (parent module's docs).
    pub(super) fn row(
        &self,
        steps: &[Step],
        inputs: &RowInputs,
        state: RowState,
        scratch: &mut Scratch,
    ) {
        row_groups(self, steps, inputs, state, scratch);
    }
}

/// What a row reads besides its state.
pub(super) struct RowInputs<'a> {
    /// Index of the row's first cell.
    pub(super) base: usize,
    /// Bedrock altitude, m.
    pub(super) altitude: &'a [f32],
    /// Lapse offset, °C.
    pub(super) offset: &'a [f32],
    /// Sky view factor.
    pub(super) sky_view: &'a [f32],
    /// Rain of the window, m of water (`None`: none).
    pub(super) rain: Option<&'a [f32]>,
    /// Nodata cells (`None`: none).
    pub(super) invalid: Option<&'a [bool]>,
    /// The albedo table of [`super::super::enhanced::albedo_table`].
    pub(super) albedo: &'a [f32],
}

/// One row's state, in place.
pub(super) struct RowState<'a> {
    pub(super) layers: [&'a mut [f32]; 4],
    pub(super) age: &'a mut [f32],
    pub(super) cold: &'a mut [f32],
    pub(super) liquid: &'a mut [f32],
    pub(super) melting: &'a mut [f32],
}

/// Per-row buffers: each group's constants and pack through the window, the groups with
/// snow, and each cell's contributions to the report's sums (parent's `SUMS` order).
pub(super) struct Scratch {
    cells: Vec<Cells>,
    packs: Vec<Pack>,
    snowy: Vec<usize>,
    pub(super) sums: [Vec<f32>; super::SUMS],
}

impl Scratch {
    pub(super) fn new(w: usize) -> Self {
        Self {
            cells: Vec::new(),
            packs: Vec::new(),
            snowy: Vec::new(),
            sums: std::array::from_fn(|_| vec![0.0; w]),
        }
    }
}

/// A group's cells' constants through the window.
#[derive(Clone, Copy, Default)]
pub(super) struct Cells {
    pub(super) offset: Lanes,
    pub(super) x: Lanes,
    pub(super) sky_view: Lanes,
    pub(super) absorbed: Lanes,
    /// `ρ c_p C_H`, J m⁻³ K⁻¹.
    pub(super) heat: Lanes,
    /// `C_H / (R_v T)`, kg m⁻³ Pa⁻¹.
    pub(super) vapour: Lanes,
    /// `g z_U² / (z_T T)`, m² s⁻² K⁻¹.
    pub(super) richardson: Lanes,
    /// `k_s / d`, W m⁻² K⁻¹.
    pub(super) conductance: Lanes,
    /// 1 where the cell has snow (and is valid), else 0.
    pub(super) snow: Lanes,
}

/// A group's pack through the window, m of water equivalent, and the window's sums.
#[derive(Clone, Copy, Default)]
pub(super) struct Pack {
    pub(super) surface_c: Lanes,
    /// The previous step's radiative and ground gains, W/m², and its compliance.
    pub(super) gains: Lanes,
    pub(super) compliance: Lanes,
    pub(super) swe: Lanes,
    pub(super) cold: Lanes,
    pub(super) liquid: Lanes,
    pub(super) melted: Lanes,
    pub(super) refrozen: Lanes,
    pub(super) sublimated: Lanes,
    pub(super) deposited: Lanes,
}

/// A group's state at the start of the window, as read from the row.
struct Start {
    keep: Lanes,
    layers: [Lanes; 4],
    cold: Lanes,
    liquid: Lanes,
    age: Lanes,
    melting: Lanes,
    rain: Lanes,
    swe: Lanes,
}

impl Start {
    #[inline(always)]
    fn read(k: &Kernel, inp: &RowInputs, st: &RowState, c0: usize, n: usize) -> Self {
        let r = c0..c0 + n;
        let keep = lanes(|l| {
            let valid = inp
                .invalid
                .is_none_or(|v| v.get(c0 + l).is_some_and(|&b| !b));
            if l < n && valid { 1.0 } else { 0.0 }
        });
        let layers = [0, 1, 2, 3].map(|j| load(&st.layers[j][r.clone()]));
        let wpd = k.water_per_depth;
        Self {
            keep,
            swe: lanes(|l| {
                layers[0][l] * wpd[0]
                    + layers[1][l] * wpd[1]
                    + layers[2][l] * wpd[2]
                    + layers[3][l] * wpd[3]
            }),
            layers,
            cold: load(&st.cold[r.clone()]),
            liquid: load(&st.liquid[r.clone()]),
            age: load(&st.age[r.clone()]),
            melting: load(&st.melting[r.clone()]),
            rain: inp.rain.map_or([0.0; LANES], |v| load(&v[r])),
        }
    }
}

/// The row in groups of [`LANES`] cells (the last padded with empty cells, which have no
/// snow and are not written back), in three passes: each group's start, then the steps one
/// after the other over every group with snow (the groups' long dependency chains overlap
/// in the pipeline, where a group taken through all its steps at once waited on each), then
/// the layers at the end of the window.
#[multiversion::multiversion(targets("x86_64+avx512f+avx512vl", "x86_64+avx2"))]
fn row_groups(k: &Kernel, steps: &[Step], inp: &RowInputs, st: RowState, sc: &mut Scratch) {
    let w = inp.offset.len();
    let groups = w.div_ceil(LANES);
    let n_of = |g: usize| LANES.min(w - g * LANES);
    sc.cells.clear();
    sc.packs.clear();
    sc.snowy.clear();
    for g in 0..groups {
        let s = Start::read(k, inp, &st, g * LANES, n_of(g));
        let mut pack = Pack {
            swe: s.swe,
            cold: s.cold,
            liquid: lanes(|l| s.liquid[l] + s.rain[l]),
            ..Pack::default()
        };
        let snowy = (0..LANES).any(|l| s.keep[l] > 0.0 && s.swe[l] > 0.0);
        let cells = if snowy {
            let c = group_cells(
                k,
                inp,
                g * LANES,
                n_of(g),
                (&s.layers, s.swe, s.keep),
                (s.age, s.melting),
            );
            // The heat rain brings at the window's mean air temperature.
            let heat = lanes(|l| {
                c.snow[l] * s.rain[l] * k.rain_heat * (k.mean_sea_level + c.offset[l]).max(0.0)
            });
            pay(&mut pack, heat);
            let first = steps.first().map_or(0.0, |h| h.sea_level_c);
            pack.surface_c = lanes(|l| (first + c.offset[l]).min(0.0));
            sc.snowy.push(g);
            c
        } else {
            Cells::default()
        };
        sc.cells.push(cells);
        sc.packs.push(pack);
    }
    for (i, h) in steps.iter().enumerate() {
        for &g in &sc.snowy {
            let at = (inp.base + g * LANES, n_of(g));
            step(k, h, &sc.cells[g], at, &mut sc.packs[g], i == 0);
        }
    }
    for g in 0..groups {
        let (c0, n) = (g * LANES, n_of(g));
        let s = Start::read(k, inp, &st, c0, n);
        let r = c0..c0 + n;
        let pack = &sc.packs[g];
        let end = window_end(k, s.layers, s.liquid, s.rain, pack);
        let keep = s.keep;
        let pick = |new: Lanes, old: Lanes| lanes(|l| if keep[l] > 0.5 { new[l] } else { old[l] });
        for j in 0..4 {
            store(
                &mut st.layers[j][r.clone()],
                pick(end.layers[j], s.layers[j]),
            );
        }
        store(&mut st.cold[r.clone()], pick(end.cold, s.cold));
        store(&mut st.liquid[r.clone()], pick(end.liquid, s.liquid));
        let age = lanes(|l| {
            if s.swe[l] > 0.0 {
                s.age[l] + k.window_days
            } else {
                0.0
            }
        });
        store(&mut st.age[r.clone()], pick(age, s.age));
        store(&mut st.melting[r.clone()], pick(end.ripe, s.melting));
        let has_snow = lanes(|l| if s.swe[l] > 0.0 { keep[l] } else { 0.0 });
        let sums: [Lanes; super::SUMS] = [
            end.melted_depth,
            end.melted_water,
            end.refrozen_depth,
            pack.refrozen,
            lanes(|l| has_snow[l] * s.rain[l]),
            end.runoff,
            end.sublimated_depth,
            end.sublimated_water,
            end.deposited_depth,
            pack.deposited,
        ];
        for (out, v) in sc.sums.iter_mut().zip(sums) {
            store(&mut out[r.clone()], lanes(|l| keep[l] * v[l]));
        }
    }
}

/// The constants of the group of cells from `c0` (`n` of them) through the window.
#[inline(always)]
pub(super) fn group_cells(
    k: &Kernel,
    inp: &RowInputs,
    c0: usize,
    n: usize,
    (layers, swe, keep): (&[Lanes; 4], Lanes, Lanes),
    (age, melting): (Lanes, Lanes),
) -> Cells {
    let r = c0..c0 + n;
    let offset = load(&inp.offset[r.clone()]);
    let altitude = load(&inp.altitude[r.clone()]);
    let sky_view = load(&inp.sky_view[r]);
    let (mid, inv_half) = (k.offsets.mid, 1.0 / k.offsets.half);
    let x = lanes(|l| ((offset[l] - mid) * inv_half).clamp(-1.0, 1.0));
    let inv_t = lanes(|l| 1.0 / (k.mean_sea_level + offset[l] + MELTING_POINT_K as f32));
    let pressure = lanes(|l| {
        SEA_LEVEL_PRESSURE as f32 * exp(altitude[l] * (-1.0 / PRESSURE_SCALE_HEIGHT as f32))
    });
    let depth = lanes(|l| layers[0][l] + layers[1][l] + layers[2][l] + layers[3][l]);
    let length = lanes(|l| (0.5 * depth[l]).clamp(THINNEST_CONDUCTION_M, k.conduction_depth));
    Cells {
        offset,
        x,
        sky_view,
        absorbed: lanes(|l| 1.0 - albedo_from_table(inp.albedo, age[l], melting[l] > 0.5)),
        heat: lanes(|l| k.heat_per_pressure * pressure[l] * inv_t[l]),
        vapour: lanes(|l| k.vapour_conductance * inv_t[l]),
        richardson: lanes(|l| k.richardson * inv_t[l]),
        conductance: lanes(|l| k.conductivity / length[l]),
        snow: lanes(|l| if swe[l] > 0.0 { keep[l] } else { 0.0 }),
    }
}

/// One step of the group (`at`: the index of its first cell and the number of cells):
/// the surface temperature, the energy into the pack and the vapour flux, then the pack.
#[inline(always)]
#[allow(clippy::manual_clamp)]
fn step(k: &Kernel, h: &Step, c: &Cells, at: (usize, usize), pack: &mut Pack, first: bool) {
    let air = air(k, h, c, at);
    // Where to linearise: the previous surface moved by the change of the radiation since
    // the previous step over the balance's stiffness there (a predictor: a surface that lags
    // behind the sun misjudges its fluxes), or twice in a window's first step.
    let start = if first {
        surface(k, h, c, &air, pack, pack.surface_c).surface_c
    } else {
        // min then max (not clamp): a NaN lane reads 0 °C instead of staying NaN.
        lanes(|l| {
            (pack.surface_c[l] + (air.gains[l] - pack.gains[l]) * pack.compliance[l])
                .min(0.0)
                .max(COLDEST_SURFACE_C)
        })
    };
    let flux = surface(k, h, c, &air, pack, start);
    pack.gains = air.gains;
    pack.compliance = flux.compliance;
    pack.surface_c = lanes(|l| {
        if c.snow[l] > 0.0 && pack.swe[l] > 0.0 {
            flux.surface_c[l]
        } else {
            pack.surface_c[l]
        }
    });
    let on_snow = lanes(|l| if pack.swe[l] > 0.0 { c.snow[l] } else { 0.0 });
    let energy = lanes(|l| on_snow[l] * flux.energy[l] * (h.seconds / k.fusion_per_m));
    pay(pack, energy);
    let vapour = lanes(|l| on_snow[l] * flux.vapour[l] * (h.seconds * k.water_volume));
    let sublimated = lanes(|l| vapour[l].max(0.0).min(pack.swe[l]));
    let deposited = lanes(|l| (-vapour[l]).max(0.0));
    pack.swe = lanes(|l| pack.swe[l] - sublimated[l] + deposited[l]);
    pack.sublimated = lanes(|l| pack.sublimated[l] + sublimated[l]);
    pack.deposited = lanes(|l| pack.deposited[l] + deposited[l]);
    pack.liquid = lanes(|l| pack.liquid[l].min(k.holding * pack.swe[l]));
    pack.cold = lanes(|l| if pack.swe[l] > 0.0 { pack.cold[l] } else { 0.0 });
}

/// The air-side terms of step `h` on a group's cells `c` (`at` as [`step`]'s).
#[inline(always)]
pub(super) fn air(k: &Kernel, h: &Step, c: &Cells, at: (usize, usize)) -> Air {
    let (start, n) = at;
    let t_air = lanes(|l| h.sea_level_c + c.offset[l]);
    let mut incoming = lanes(|l| h.diffuse * c.sky_view[l]);
    if let Some(reflected) = h.reflected_share {
        let r = load(&reflected[start..start + n]);
        incoming = lanes(|l| incoming[l] + h.reflected * r[l]);
    }
    for &(beam, direct) in &h.beams {
        let b = load_bytes(&beam[start..start + n]);
        incoming = lanes(|l| incoming[l] + direct * b[l]);
    }
    let shortwave = lanes(|l| c.absorbed[l] * incoming[l]);
    let air_k = lanes(|l| t_air[l] + MELTING_POINT_K as f32);
    let air_emission = lanes(|l| {
        let t2 = air_k[l] * air_k[l];
        k.sigma * (t2 * t2)
    });
    let longwave_in = lanes(|l| {
        let sky = polynomial(&h.sky, c.x[l]);
        c.sky_view[l] * (sky - air_emission[l]) + air_emission[l]
    });
    Air {
        t: t_air,
        vapour: lanes(|l| polynomial(&h.vapour, c.x[l])),
        gains: lanes(|l| shortwave[l] + longwave_in[l] + k.ground),
    }
}

/// The air-side terms of an hour on a group's cells.
pub(super) struct Air {
    /// Air temperature, °C.
    pub(super) t: Lanes,
    /// Vapour pressure, Pa.
    pub(super) vapour: Lanes,
    /// Absorbed shortwave + incoming longwave + ground heat, W/m².
    pub(super) gains: Lanes,
}

/// The solved surface of one hour: its temperature and the terms of the balance at it
/// (the season reads the first three; the others, optimised away there, are the energy
/// conservation test's).
#[cfg_attr(not(test), allow(dead_code))]
pub(super) struct Flux {
    /// Surface temperature, °C.
    pub(super) surface_c: Lanes,
    /// `1 / (−dQ/dT_s + K_eff)`, K m² W⁻¹: how far the surface moves per W/m² of gain.
    pub(super) compliance: Lanes,
    /// Energy into the pack `Q(T_s)`, W/m².
    pub(super) energy: Lanes,
    /// Vapour flux, kg m⁻² s⁻¹ (> 0: sublimation).
    pub(super) vapour: Lanes,
    /// Emitted longwave `ε σ T_s⁴` (linearised about the hour's starting point), W/m².
    pub(super) emitted: Lanes,
    /// Sensible heat `H`, W/m² (> 0: into the surface).
    pub(super) sensible: Lanes,
    /// Latent heat `LE = −L_s E`, W/m².
    pub(super) latent: Lanes,
}

/// The surface temperature of the hour by one Newton step of the balance linearised at `t0`
/// (parent module's docs), with the energy and vapour fluxes at it.
#[inline(always)]
pub(super) fn surface(k: &Kernel, h: &Step, c: &Cells, a: &Air, pack: &Pack, t0: Lanes) -> Flux {
    let t0k = lanes(|l| t0[l] + MELTING_POINT_K as f32);
    let t0k2 = lanes(|l| t0k[l] * t0k[l]);
    let emitted = lanes(|l| k.eps_sigma * (t0k2[l] * t0k2[l]));
    let emitted_slope = lanes(|l| 4.0 * k.eps_sigma * (t0k2[l] * t0k[l]));
    // Saturation over ice (Magnus, as a polynomial) and its slope.
    let x = lanes(|l| (t0[l] + 30.0) * (1.0 / 30.0));
    let saturated = lanes(|l| polynomial(&k.ice_saturation.0, x[l]));
    let saturated_slope = lanes(|l| polynomial(&k.ice_saturation.1, x[l]));
    // Louis et al. 1982's stability correction (FSM's SURF_EXCH).
    let ri = lanes(|l| c.richardson[l] * h.inv_wind2 * (a.t[l] - t0[l]));
    let b = k.stability;
    let root = lanes(|l| {
        if ri[l] > 0.0 {
            1.0 + b * ri[l]
        } else {
            -ri[l] * k.height_ratio
        }
        .sqrt()
    });
    let ratio = lanes(|l| {
        if ri[l] > 0.0 {
            1.0 / (1.0 + 3.0 * b * ri[l] * root[l])
        } else {
            -3.0 * b * ri[l] / (1.0 + k.unstable * root[l])
        }
    });
    let fh = lanes(|l| {
        if ri[l] > 0.0 {
            ratio[l]
        } else {
            1.0 + ratio[l]
        }
    });
    let sensible = lanes(|l| c.heat[l] * h.wind * fh[l]);
    let vapour_k = lanes(|l| c.vapour[l] * h.wind * fh[l]);
    let latent_k = lanes(|l| k.latent_sublimation * vapour_k[l]);
    let q0 = lanes(|l| {
        a.gains[l] - emitted[l] + sensible[l] * (a.t[l] - t0[l])
            - latent_k[l] * (saturated[l] - a.vapour[l])
    });
    let slope = lanes(|l| emitted_slope[l] + sensible[l] + latent_k[l] * saturated_slope[l]);
    // Conduction to the pack in series with its heat capacity over the hour.
    let capacity = lanes(|l| k.ice_capacity_per_m * pack.swe[l]);
    let inv_d = lanes(|l| 1.0 / (capacity[l] + h.seconds * c.conductance[l]));
    let k_eff = lanes(|l| c.conductance[l] * capacity[l] * inv_d[l]);
    let k_tp = lanes(|l| -c.conductance[l] * pack.cold[l] * k.fusion_per_m * inv_d[l]);
    let compliance = lanes(|l| 1.0 / (k_eff[l] + slope[l]));
    // min then max (not clamp): a NaN lane reads 0 °C instead of staying NaN.
    #[allow(clippy::manual_clamp)]
    let surface_c = lanes(|l| {
        ((q0[l] + slope[l] * t0[l] + k_tp[l]) * compliance[l])
            .min(0.0)
            .max(COLDEST_SURFACE_C)
    });
    let step = lanes(|l| surface_c[l] - t0[l]);
    let vapour =
        lanes(|l| vapour_k[l] * (saturated[l] + saturated_slope[l] * step[l] - a.vapour[l]));
    Flux {
        surface_c,
        compliance,
        energy: lanes(|l| q0[l] - slope[l] * step[l]),
        vapour,
        emitted: lanes(|l| emitted[l] + emitted_slope[l] * step[l]),
        sensible: lanes(|l| sensible[l] * (a.t[l] - surface_c[l])),
        latent: lanes(|l| -k.latent_sublimation * vapour[l]),
    }
}

/// Energy `energy` (m of melt water; negative cools) into the pack: it pays the cold content,
/// then melts; liquid water refreezes against what cold content is left.
#[inline(always)]
pub(super) fn pay(pack: &mut Pack, energy: Lanes) {
    let cold = lanes(|l| pack.cold[l] - energy[l]);
    let melt = lanes(|l| (-cold[l]).max(0.0).min(pack.swe[l]));
    let cold = lanes(|l| cold[l].max(0.0));
    let liquid = lanes(|l| pack.liquid[l] + melt[l]);
    let refreeze = lanes(|l| liquid[l].min(cold[l]));
    pack.cold = lanes(|l| cold[l] - refreeze[l]);
    pack.liquid = lanes(|l| liquid[l] - refreeze[l]);
    pack.swe = lanes(|l| pack.swe[l] - melt[l] + refreeze[l]);
    pack.melted = lanes(|l| pack.melted[l] + melt[l]);
    pack.refrozen = lanes(|l| pack.refrozen[l] + refreeze[l]);
}

/// The layers and water at the end of a window, and what changed.
struct WindowEnd {
    layers: [Lanes; 4],
    cold: Lanes,
    liquid: Lanes,
    ripe: Lanes,
    runoff: Lanes,
    melted_depth: Lanes,
    melted_water: Lanes,
    refrozen_depth: Lanes,
    sublimated_depth: Lanes,
    sublimated_water: Lanes,
    deposited_depth: Lanes,
}

/// The window's changes applied to the layers once (parent module's docs): refrozen and
/// deposited ice into the compacted layer, then sublimation and melt from the top down.
#[inline(always)]
fn window_end(
    k: &Kernel,
    old: [Lanes; 4],
    old_liquid: Lanes,
    rain: Lanes,
    pack: &Pack,
) -> WindowEnd {
    let (wpd, dpw) = (k.water_per_depth, k.depth_per_water);
    let mut layers = old;
    let refrozen_depth = lanes(|l| pack.refrozen[l] * dpw[0]);
    let deposited_depth = lanes(|l| pack.deposited[l] * dpw[0]);
    layers[0] = lanes(|l| layers[0][l] + (refrozen_depth[l] + deposited_depth[l]));
    let (sublimated_water, sublimated_depth) =
        take_top_down(&mut layers, pack.sublimated, (wpd, dpw));
    let (melted_water, melted_depth) = take_top_down(&mut layers, pack.melted, (wpd, dpw));
    {
        use crate::phenomenon::flush_negligible as f;
        for layer in &mut layers {
            *layer = lanes(|l| f(layer[l]));
        }
    }
    let left = lanes(|l| {
        layers[0][l] * wpd[0]
            + layers[1][l] * wpd[1]
            + layers[2][l] * wpd[2]
            + layers[3][l] * wpd[3]
    });
    // The water of the window: what was held, the rain, the melt, less what refroze.
    let water = lanes(|l| old_liquid[l] + rain[l] + melted_water[l] - pack.refrozen[l]);
    let hold = lanes(|l| {
        if left[l] > 0.0 {
            k.holding * left[l]
        } else {
            0.0
        }
    });
    let liquid = lanes(|l| pack.liquid[l].min(hold[l]).min(water[l]).max(0.0));
    let cold = lanes(|l| if left[l] > 0.0 { pack.cold[l] } else { 0.0 });
    WindowEnd {
        layers,
        cold,
        liquid,
        ripe: lanes(|l| {
            if left[l] > 0.0 && cold[l] <= 0.0 && liquid[l] > 0.0 {
                1.0
            } else {
                0.0
            }
        }),
        runoff: lanes(|l| water[l] - liquid[l]),
        melted_depth,
        melted_water,
        refrozen_depth,
        sublimated_depth,
        sublimated_water,
        deposited_depth,
    }
}

/// Takes `water` (m w.e.) from the layers, top layer first; returns the water and depth
/// taken (a layer taken whole gives its whole depth, so it ends at exactly 0).
#[inline(always)]
fn take_top_down(
    layers: &mut [Lanes; 4],
    water: Lanes,
    (wpd, dpw): ([f32; 4], [f32; 4]),
) -> (Lanes, Lanes) {
    let mut left = water;
    let (mut taken, mut depth) = ([0.0; LANES], [0.0; LANES]);
    for j in (0..4).rev() {
        let layer = layers[j];
        let have = lanes(|l| layer[l] * wpd[j]);
        let take = lanes(|l| left[l].min(have[l]));
        let d = lanes(|l| {
            if take[l] >= have[l] {
                layer[l]
            } else {
                take[l] * dpw[j]
            }
        });
        layers[j] = lanes(|l| layer[l] - d[l]);
        depth = lanes(|l| depth[l] + d[l]);
        left = lanes(|l| left[l] - take[l]);
        taken = lanes(|l| taken[l] + take[l]);
    }
    (taken, depth)
}

/// `f` of every lane: a plain loop over a fixed-size array, which the compiler unrolls into
/// vector instructions (`std::array::from_fn` was left as a call per use in this kernel).
#[inline(always)]
fn lanes(f: impl Fn(usize) -> f32) -> Lanes {
    let mut a = [0.0; LANES];
    for (l, v) in a.iter_mut().enumerate() {
        *v = f(l);
    }
    a
}

/// Up to [`LANES`] values, the rest 0 (an empty cell).
#[inline(always)]
fn load(v: &[f32]) -> Lanes {
    if let Ok(full) = <Lanes>::try_from(v) {
        return full;
    }
    let mut a = [0.0; LANES];
    a[..v.len()].copy_from_slice(v);
    a
}

/// The first `out.len()` lanes of `a`.
#[inline(always)]
fn store(out: &mut [f32], a: Lanes) {
    if let Ok(full) = <&mut Lanes>::try_from(&mut *out) {
        *full = a;
        return;
    }
    let n = out.len();
    out.copy_from_slice(&a[..n]);
}

/// Up to [`LANES`] bytes as f32, the rest 0.
#[inline(always)]
fn load_bytes(v: &[u8]) -> Lanes {
    let mut a = [0u8; LANES];
    if let Ok(full) = <[u8; LANES]>::try_from(v) {
        a = full;
    } else {
        a[..v.len()].copy_from_slice(v);
    }
    lanes(|l| a[l] as f32)
}

/// `e^x` for x in [−80, 80], relative error below 4·10⁻⁶ (the f32 rounding of `x / ln 2`;
/// 3·10⁻⁷ for |x| < 1): `2^i · e^(f ln 2)` with `i` the
/// nearest integer to `x / ln 2` and the exponential of `|f ln 2| ≤ ln 2 / 2` by its Taylor
/// series to degree 6. Branch-free and without float-to-int conversions (the rounding adds
/// and subtracts 1.5·2^23; `i` is then the low bits of the sum), so it vectorises.
#[inline(always)]
pub(super) fn exp(x: f32) -> f32 {
    const ROUND: f32 = 12_582_912.0;
    let t = (x * std::f32::consts::LOG2_E).clamp(-125.0, 125.0);
    let sum = t + ROUND;
    let y = (t - (sum - ROUND)) * std::f32::consts::LN_2;
    let i = sum.to_bits().wrapping_sub(ROUND.to_bits());
    let p = 1.0
        + y * (1.0
            + y * (0.5
                + y * (1.0 / 6.0 + y * (1.0 / 24.0 + y * (1.0 / 120.0 + y * (1.0 / 720.0))))));
    p * f32::from_bits(i.wrapping_add(127) << 23)
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_vector_exponential_is_accurate() {
        for k in -800..=800 {
            let x = k as f32 * 0.1 + 0.0123;
            let (fast, exact) = (super::exp(x) as f64, (x as f64).exp());
            let tolerance = if x.abs() < 1.0 { 3e-7 } else { 4e-6 };
            assert!(
                (fast / exact - 1.0).abs() < tolerance,
                "{x}: {fast} vs {exact}"
            );
        }
    }
}
