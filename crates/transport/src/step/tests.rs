use super::*;
use crate::params::Phenomena;

/// A wind field with every direction: a vortex-like swirl plus a west wind, so the grid
/// has convergence and divergence lines along both axes.
fn swirl(g: &GridGeometry, strength: f32) -> (Vec<f32>, Vec<f32>) {
    let (w, h) = (g.width() as f32, g.height() as f32);
    let mut u = vec![0.0; g.len()];
    let mut v = vec![0.0; g.len()];
    for r in 0..g.height() {
        for c in 0..g.width() {
            let x = c as f32 / w - 0.5;
            let y = 0.5 - r as f32 / h;
            let i = r * g.width() + c;
            u[i] = strength * (0.6 - 3.0 * y + (7.0 * x).sin());
            v[i] = strength * (3.0 * x + (5.0 * y).cos() - 0.5);
        }
    }
    (u, v)
}

fn varied_snow(g: &GridGeometry) -> SnowState {
    let mut s = SnowState::uniform(g, 0.3, 150.0);
    for (i, m) in s.swe.iter_mut().enumerate() {
        *m *= 0.2 + (i % 13) as f32 / 6.0; // some cells below C_v, some deep
    }
    for (i, r) in s.density.iter_mut().enumerate() {
        *r = 80.0 + (i % 7) as f32 * 40.0;
    }
    s
}

fn snowy_weather() -> Weather {
    Weather {
        precipitation_mm_per_h: 2.0,
        air_temperature_c: -8.0,
        relative_humidity_pct: 40.0,
        ..Default::default()
    }
}

fn run(
    params: &TransportParams,
    weather: &Weather,
    scene: &SceneMaps,
    state: &mut SnowState,
    steps: usize,
    dt: f64,
) -> MassBudget {
    let mut scratch = StepScratch::default();
    let mut total = MassBudget::default();
    for _ in 0..steps {
        let b = step(params, weather, scene, state, &mut scratch, dt).unwrap();
        total.accumulate(&b);
    }
    total
}

#[test]
fn mass_budget_closes_with_every_phenomenon() {
    let g = GridGeometry::square(96, 80, 2.0).unwrap();
    let (u, v) = swirl(&g, 9.0);
    let ratio: Vec<f32> = (0..g.len()).map(|i| 0.5 + (i % 5) as f32 * 0.25).collect();
    let scene = SceneMaps {
        geometry: &g,
        wind_u: &u,
        wind_v: &v,
        precipitation_ratio: Some(&ratio),
    };
    let params = TransportParams {
        saturated_inflow: true,
        ..Default::default()
    };
    let mut state = varied_snow(&g);
    let mut b = run(&params, &snowy_weather(), &scene, &mut state, 12, 300.0);
    // Then a warm spell: melt and densification.
    let warm = Weather {
        from_hour: 1.0,
        air_temperature_c: 4.0,
        precipitation_mm_per_h: 0.0,
        ..snowy_weather()
    };
    b.accumulate(&run(&params, &warm, &scene, &mut state, 12, 300.0));
    assert!(b.transported > 0.0 && b.sublimation_out > 0.0 && b.melt_out > 0.0);
    assert!(b.border_in > 0.0 && b.border_out > 0.0 && b.precipitation_in > 0.0);
    let scale = b.initial_mass + b.precipitation_in + b.transported;
    assert!(
        b.closure_error.abs() < 1e-5 * scale,
        "closure {} of {scale}: {b:?}",
        b.closure_error
    );
    for (m, r) in state.swe.iter().zip(&state.density) {
        assert!(m.is_finite() && *m >= 0.0 && r.is_finite() && *r > 0.0);
    }
}

#[test]
fn calm_snowfall_adds_exactly_rho_w_p_dt_at_fresh_density() {
    let g = GridGeometry::square(20, 10, 1.0).unwrap();
    let zero = vec![0.0f32; g.len()];
    let scene = SceneMaps {
        geometry: &g,
        wind_u: &zero,
        wind_v: &zero,
        precipitation_ratio: None,
    };
    let mut state = SnowState::bare(&g);
    // 3.6 mm/h water equivalent for 1000 s = 1 mm = 1 kg/m² of snow at −5 °C:
    // ρns = 50 + 1.7 (268.15 − 258.16)^1.5 = 103.678 kg/m³ → 9.645 mm of snow.
    let w = Weather {
        precipitation_mm_per_h: 3.6,
        air_temperature_c: -5.0,
        ..Default::default()
    };
    let b = run(
        &TransportParams::default(),
        &w,
        &scene,
        &mut state,
        1,
        1000.0,
    );
    for (m, r) in state.swe.iter().zip(&state.density) {
        assert!((m - 1.0).abs() < 1e-6 && (r - 103.678).abs() < 1e-3);
    }
    assert!((b.precipitation_in - 200.0).abs() < 1e-6); // 200 cells of 1 m²
    assert_eq!(
        (b.transported, b.sublimation_out, b.melt_out),
        (0.0, 0.0, 0.0)
    );
}

#[test]
fn uniform_saturated_drift_only_sublimates_in_the_interior() {
    // Flat ground, deep uniform snow, uniform 12 m/s west wind, saturated inflow: the
    // saltation and suspension fluxes are the same in every cell, so their divergence
    // vanishes and only sublimation changes the interior (Eq. 5.16).
    let g = GridGeometry::square(40, 8, 5.0).unwrap();
    let u = vec![12.0f32; g.len()];
    let v = vec![0.0f32; g.len()];
    let scene = SceneMaps {
        geometry: &g,
        wind_u: &u,
        wind_v: &v,
        precipitation_ratio: None,
    };
    let params = TransportParams {
        saturated_inflow: true,
        ..Default::default()
    };
    let w = Weather {
        relative_humidity_pct: 50.0,
        ..Default::default()
    };
    let mut state = SnowState::uniform(&g, 0.5, 120.0);
    let before = state.swe.clone();
    let mut scratch = StepScratch::default();
    let b = step(&params, &w, &scene, &mut state, &mut scratch, 60.0).unwrap();
    let subl = -scratch.q_subl[3 * 40 + 20] * 60.0;
    assert!(subl > 0.0 && scratch.q_salt[3 * 40 + 20] > 0.0);
    for r in 0..8 {
        for c in 1..40 {
            let i = r * 40 + c;
            let change = before[i] - state.swe[i];
            assert!(
                (change - subl).abs() < 1e-4 * before[i],
                "cell {c},{r}: {change} vs {subl}"
            );
        }
    }
    // The saltation entering at the west border leaves at the east one, with the
    // suspension flux (no suspended snow enters): 8 rows · 60 s · Qsusp / 5 m · 25 m².
    let susp_out = 8.0 * 60.0 * f64::from(scratch.q_susp[20]) / 5.0 * 25.0;
    assert!(susp_out > 0.0);
    let net = b.border_out - b.border_in;
    assert!(
        (net - susp_out).abs() < 1e-4 * b.border_in,
        "{net} vs {susp_out}"
    );
}

#[test]
fn saltation_grows_along_the_fetch_from_a_clean_border() {
    let g = GridGeometry::square(120, 3, 10.0).unwrap();
    let u = vec![10.0f32; g.len()];
    let v = vec![0.0f32; g.len()];
    let scene = SceneMaps {
        geometry: &g,
        wind_u: &u,
        wind_v: &v,
        precipitation_ratio: None,
    };
    let mut state = SnowState::uniform(&g, 0.5, 100.0);
    let mut scratch = StepScratch::default();
    let params = TransportParams::default(); // no inflow
    step(
        &params,
        &Weather::default(),
        &scene,
        &mut state,
        &mut scratch,
        1.0,
    )
    .unwrap();
    let q: Vec<f32> = (0..120).map(|c| scratch.q_salt[120 + c]).collect();
    let q_max = scratch.shear.q_max_per_speed[120] * scratch.shear.speed[120];
    // First cell: (μ Δx / f) Qs_max = 0.1 Qs_max; then monotone growth towards Qs_max.
    assert!((q[0] - 0.1 * q_max).abs() < 1e-6 * q_max);
    assert!(q.windows(2).all(|p| p[1] >= p[0]));
    assert!(q[119] > 0.99 * q_max && q[119] <= q_max * (1.0 + 1e-6));
    // The clean border erodes: the upwind cells lose snow.
    assert!(state.swe[120] < 50.0);
}

#[test]
fn huge_steps_never_make_negative_snow() {
    let g = GridGeometry::square(48, 48, 1.0).unwrap();
    let (u, v) = swirl(&g, 25.0);
    let scene = SceneMaps {
        geometry: &g,
        wind_u: &u,
        wind_v: &v,
        precipitation_ratio: None,
    };
    let warm = Weather {
        air_temperature_c: 15.0,
        relative_humidity_pct: 5.0,
        ..Default::default()
    };
    let mut state = varied_snow(&g);
    let b = run(
        &TransportParams::default(),
        &warm,
        &scene,
        &mut state,
        5,
        86_400.0,
    );
    assert!(state.swe.iter().all(|m| m.is_finite() && *m >= 0.0));
    let scale = b.initial_mass + b.transported;
    assert!(b.closure_error.abs() < 1e-5 * scale, "{b:?}");
}

#[test]
fn switching_phenomena_off_removes_their_terms() {
    let g = GridGeometry::square(64, 32, 2.0).unwrap();
    let (u, v) = swirl(&g, 10.0);
    let scene = SceneMaps {
        geometry: &g,
        wind_u: &u,
        wind_v: &v,
        precipitation_ratio: None,
    };
    let w = Weather {
        air_temperature_c: 3.0,
        ..snowy_weather()
    };
    let off = TransportParams {
        phenomena: Phenomena {
            precipitation: false,
            saltation: false,
            suspension: false,
            sublimation: false,
            melt: false,
            densification: false,
        },
        ..Default::default()
    };
    let mut state = varied_snow(&g);
    let before = state.clone();
    let b = run(&off, &w, &scene, &mut state, 3, 300.0);
    assert_eq!(state, before);
    assert_eq!(
        b.transported + b.sublimation_out + b.melt_out + b.precipitation_in,
        0.0
    );
    // Saltation alone moves snow but keeps the mass, except across the borders.
    let salt_only = TransportParams {
        phenomena: Phenomena {
            saltation: true,
            ..off.phenomena
        },
        ..Default::default()
    };
    let mut state = varied_snow(&g);
    let b = run(&salt_only, &w, &scene, &mut state, 3, 300.0);
    assert!(b.transported > 0.0);
    assert_eq!(
        (b.sublimation_out, b.melt_out, b.precipitation_in),
        (0.0, 0.0, 0.0)
    );
    assert!((b.final_mass - b.initial_mass + b.border_out).abs() < 1e-5 * b.initial_mass);
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let g = GridGeometry::square(150, 70, 3.0).unwrap(); // bands of 64 columns, not a multiple
    let (u, v) = swirl(&g, 11.0);
    let scene = SceneMaps {
        geometry: &g,
        wind_u: &u,
        wind_v: &v,
        precipitation_ratio: None,
    };
    let go = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut state = varied_snow(&g);
            let params = TransportParams {
                saturated_inflow: true,
                ..Default::default()
            };
            let b = run(&params, &snowy_weather(), &scene, &mut state, 4, 300.0);
            (state, b)
        })
    };
    let (s1, b1) = go(1);
    let (s2, b2) = go(2);
    let bits = |s: &SnowState| {
        s.swe
            .iter()
            .chain(&s.density)
            .map(|x| x.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&s1), bits(&s2));
    assert_eq!(b1, b2);
}

/// The fetch rule (Eqs. 5.38-5.39) run cell by cell along one line of cells `line`, whose
/// wind component `comp` is positive towards the end of the line: the plain recurrence the
/// lane sweeps must reproduce.
fn fetch_along_line(
    sweep: &sweep::Sweep,
    shear: &ShearMaps,
    comp: &[f32],
    line: &[usize],
) -> Vec<f32> {
    use crate::physics::saltation::fetch_limited_flux;
    let relax_cell = |i: usize, up: Option<(f32, f32)>| {
        let (q_max, u_star) = (shear.q_max_per_speed[i] * comp[i].abs(), shear.u_star[i]);
        let (q_up, u_up) = match up {
            Some(up) => up,
            None if sweep.saturated_inflow => (q_max, u_star),
            None => (0.0, u_star),
        };
        fetch_limited_flux(q_up, q_max, u_star >= u_up, sweep.relax)
    };
    let mut q = vec![0.0f32; line.len()];
    let mut up = None;
    for (k, &i) in line.iter().enumerate() {
        up = (comp[i] > 0.0).then(|| {
            q[k] = relax_cell(i, up);
            (q[k], shear.u_star[i])
        });
    }
    up = None;
    for (k, &i) in line.iter().enumerate().rev() {
        up = (comp[i] < 0.0).then(|| {
            let flux = relax_cell(i, up);
            q[k] = -flux;
            (flux, shear.u_star[i])
        });
    }
    q
}

#[test]
fn lane_sweeps_match_the_cell_by_cell_recurrence() {
    // 150 columns: y bands of 64 and a partial one; 29 rows: a partial block of x rows.
    let (w, h) = (150, 29);
    let n = w * h;
    let g = GridGeometry::square(w, h, 1.0).unwrap();
    let (mut u, mut v) = swirl(&g, 5.0);
    for i in (0..n).step_by(17) {
        (u[i], v[i]) = (0.0, 0.0); // calm cells end every chain
    }
    let shear = ShearMaps {
        speed: u.iter().zip(&v).map(|(u, v)| u.hypot(*v)).collect(),
        // Shear rising and falling along both axes, some cells without saltation.
        u_star: (0..n)
            .map(|i| 0.2 + ((i * 31) % 13) as f32 * 0.05)
            .collect(),
        u_star_t: vec![0.2; n],
        q_max_per_speed: (0..n)
            .map(|i| {
                if i % 11 == 0 {
                    0.0
                } else {
                    1e-3 * (1 + (i * 17) % 7) as f32
                }
            })
            .collect(),
    };
    for saturated_inflow in [false, true] {
        let sweep = sweep::Sweep {
            relax: 0.3,
            saturated_inflow,
        };
        let block = sweep::X_ROWS * w;
        let mut q_x = vec![f32::NAN; n];
        for (b, q) in q_x.chunks_mut(block).enumerate() {
            let cells = b * block..b * block + q.len();
            let comp = &u[cells.clone()];
            sweep::sweep_rows(&sweep, w, shear.all().cells(cells), comp, q);
        }
        let mut q_y = vec![f32::NAN; n];
        sweep::sweep_y(&sweep, w, shear.all(), &v, &mut q_y);
        let bits = |q: Vec<f32>| q.into_iter().map(f32::to_bits).collect::<Vec<_>>();
        for r in 0..h {
            // Along x, east positive: the row from west to east.
            let line: Vec<usize> = (0..w).map(|c| r * w + c).collect();
            let got = line.iter().map(|&i| q_x[i]).collect();
            assert_eq!(
                bits(got),
                bits(fetch_along_line(&sweep, &shear, &u, &line)),
                "row {r}"
            );
        }
        for c in 0..w {
            // Along y, north positive: the column from south (last row) to north.
            let line: Vec<usize> = (0..h).rev().map(|r| r * w + c).collect();
            let got = line.iter().map(|&i| q_y[i]).collect();
            assert_eq!(
                bits(got),
                bits(fetch_along_line(&sweep, &shear, &v, &line)),
                "column {c}"
            );
        }
    }
}

#[test]
fn bad_inputs_are_typed_errors() {
    let g = GridGeometry::square(4, 4, 1.0).unwrap();
    let short = vec![0.0f32; 15];
    let ok = vec![0.0f32; 16];
    let scene = SceneMaps {
        geometry: &g,
        wind_u: &short,
        wind_v: &ok,
        precipitation_ratio: None,
    };
    let mut state = SnowState::bare(&g);
    let mut scratch = StepScratch::default();
    let p = TransportParams::default();
    let w = Weather::default();
    let err = step(&p, &w, &scene, &mut state, &mut scratch, 1.0).unwrap_err();
    assert!(matches!(
        err,
        TransportError::MapLength { map: "wind_u", .. }
    ));
    let scene = SceneMaps {
        wind_u: &ok,
        ..scene
    };
    let err = step(&p, &w, &scene, &mut state, &mut scratch, f64::NAN).unwrap_err();
    assert!(matches!(err, TransportError::InvalidTimeStep { .. }));
}
