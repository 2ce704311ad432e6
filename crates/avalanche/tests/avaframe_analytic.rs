//! Issue 20, item 5: the flow against AvaFrame's analytic avalanche tests. First the
//! frictional dam break of Mangeney et al. (2000, "Analytical solution
//! for testing debris avalanche numerical models", Pure Appl. Geophys. 157) against the
//! analytic profiles AvaFrame's `ana1Tests.damBreak` writes
//! (`../shared/data/reference/avaframe_analytic/dambreak_mangeney2000.csv`): a 1 m thick
//! (slope-normal) column behind a dam at x = 0 on a 22° plane with 21° Coulomb friction,
//! released at t = 0 (the similarity solution is at the end of the file).
//!
//! The analytic solution is of the Savage-Hutter equations in slope coordinates: thickness
//! normal to the slope, gravity `g cos θ` across it, x the horizontal projection. The flow
//! here is the pipe model on a horizontal grid with vertical thickness (`h_v = h_n / cos θ`).
//! With [`SlopeGravity::Projected`] (the default, with the bed's curvature: none on these
//! planes) its gravity is Savage-Hutter's projected on
//! the horizontal: sliding at `g cos²θ (tan θ − tan δ)`, waves at `cos²θ sqrt(g h_v)`. The
//! paper's shallow-slope form ([`SlopeGravity::Shallow`], gravity `g`) runs 1/cos²θ (16 % at
//! 22°, 49 % at 35°) faster, and the first-order scheme smears the front. The checks, at
//! t = 10 and 20 s, compare slope-normal thickness by horizontal position: the position of the
//! front (the furthest cell with more than 5 cm) and the L1 profile error relative to the
//! analytic volume. The shallow form, without friction or without momentum advection, fails
//! the tolerances.
//!
//! **The friction law.** Both analytic solutions are of a Coulomb bed friction `tan δ` (their
//! derivations need a friction proportional to the normal load and independent of speed and
//! depth), so the runs here take the default parameters (projected gravity, curvature,
//! momentum advection) with the law set to [`FrictionLaw::Coulomb`] at the solutions' δ: the
//! default samosAT law, whose dry friction depends on `u²/(g h)` and which adds a turbulent
//! drag, has no such solution to meet.
//!
//! Measured (2026-12-04), projected against shallow: front −5.5 %/−6.0 % against
//! +11.0 %/+10.2 % at 10/20 s, L1 profile 4.0 %/4.9 % against 5.2 %/8.3 %; the similarity
//! solution's L1 6.4 % against 30.0 %, centre of mass 20.3 m against 30.4 m (analytic 19.2 m).

use snowscape_avalanche::{
    AvalancheParams, AvalancheScratch, AvalancheState, Border, FrictionLaw, SlopeGravity, step,
};
use snowscape_terrain::{GridGeometry, NodataMask};
use std::path::PathBuf;

const SLOPE_DEG: f64 = 22.0;
const FRICTION_DEG: f64 = 21.0;
const H0_NORMAL_M: f64 = 1.0;
/// The analytic reservoir is infinite (the file's thickness is 1 m at x = −200 m at every
/// time); ours ends at a wall far enough behind that its rarefaction does not reach the
/// compared window by t = 20 s.
const BACK_WALL_M: f64 = -400.0;
/// The compared window starts here (the analytic file's plotting wall).
const WINDOW_START_M: f64 = -120.0;
const DX_M: f64 = 0.5;
const LENGTH_M: f64 = 700.0;
const FRONT_THRESHOLD_M: f64 = 0.05;

fn data(rel: &str) -> PathBuf {
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data")).join(rel);
    assert!(
        p.is_file(),
        "real-data test input {} is missing: these tests need the shared data folder \
         (../shared/data beside the project root, see shared/data/README.md)",
        p.display()
    );
    p
}

/// The analytic profiles: x (m, horizontal) and, per time, the slope-normal thickness (m).
struct Analytic {
    x: Vec<f64>,
    /// (t in s, h at each x)
    h: Vec<(f64, Vec<f64>)>,
}

impl Analytic {
    fn read() -> Self {
        let path = data("reference/avaframe_analytic/dambreak_mangeney2000.csv");
        let text = std::fs::read_to_string(&path).unwrap();
        let mut lines = text.lines().filter(|l| !l.starts_with('#'));
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let h_cols: Vec<(usize, f64)> = header
            .iter()
            .enumerate()
            .filter_map(|(k, name)| {
                let t = name.strip_prefix("h_t")?.parse().ok()?;
                Some((k, t))
            })
            .collect();
        let mut x = Vec::new();
        let mut h: Vec<(f64, Vec<f64>)> = h_cols.iter().map(|&(_, t)| (t, Vec::new())).collect();
        for line in lines.filter(|l| !l.trim().is_empty()) {
            let v: Vec<f64> = line.split(',').map(|s| s.parse().unwrap()).collect();
            x.push(v[0]);
            for (k, &(col, _)) in h_cols.iter().enumerate() {
                h[k].1.push(v[col]);
            }
        }
        assert!(x.len() > 100 && x.windows(2).all(|w| w[1] > w[0]));
        Self { x, h }
    }

    /// The thickness at time `t` and position `x`, linear between the file's points, 0 beyond.
    fn at(&self, t: f64, x: f64) -> f64 {
        let (_, h) = self
            .h
            .iter()
            .find(|(tt, _)| (tt - t).abs() < 1e-9)
            .unwrap_or_else(|| panic!("no analytic profile at t = {t} s"));
        if x <= self.x[0] {
            return h[0];
        }
        match self.x.iter().position(|&xi| xi >= x) {
            None => 0.0,
            Some(k) => {
                let (x0, x1) = (self.x[k - 1], self.x[k]);
                let f = (x - x0) / (x1 - x0);
                h[k - 1] + f * (h[k] - h[k - 1])
            }
        }
    }
}

/// What the comparison at one time gives.
struct Comparison {
    front_m: f64,
    front_exact_m: f64,
    l1_rel: f64,
}

/// Runs the dam break with `params` and compares it with the analytic profiles at `times`.
fn run(params: &AvalancheParams, times: &[f64]) -> Vec<Comparison> {
    let analytic = Analytic::read();
    let (cols, rows) = ((LENGTH_M / DX_M) as usize, 3usize);
    let g = GridGeometry::square(cols, rows, DX_M).unwrap();
    let x_of = |c: usize| BACK_WALL_M + (c as f64 + 0.5) * DX_M;
    let (cos, tan) = (SLOPE_DEG.to_radians().cos(), SLOPE_DEG.to_radians().tan());
    let bed: Vec<f64> = (0..cols * rows).map(|i| -tan * x_of(i % cols)).collect();
    let mut state = AvalancheState::new(&g, &NodataMask::all_valid(), &bed).unwrap();
    let h0: Vec<f64> = (0..cols * rows)
        .map(|i| {
            if x_of(i % cols) < 0.0 {
                H0_NORMAL_M / cos
            } else {
                0.0
            }
        })
        .collect();
    state.set_thickness(&h0).unwrap();
    let mut scratch = AvalancheScratch::default();
    let mut now = 0.0;
    let mut out = Vec::new();
    for &t in times {
        step(params, &mut state, &mut scratch, t - now).unwrap();
        now = t;
        // The middle row, slope-normal thickness.
        let window: Vec<usize> = (0..cols).filter(|&c| x_of(c) >= WINDOW_START_M).collect();
        let h: Vec<f64> = window
            .iter()
            .map(|&c| state.thickness_at(c, 1) * cos)
            .collect();
        let exact: Vec<f64> = window.iter().map(|&c| analytic.at(t, x_of(c))).collect();
        let front = |h: &[f64]| {
            h.iter()
                .rposition(|&v| v > FRONT_THRESHOLD_M)
                .map_or(WINDOW_START_M, |k| x_of(window[k]))
        };
        let volume: f64 = exact.iter().sum::<f64>() * DX_M;
        let l1: f64 = h
            .iter()
            .zip(&exact)
            .map(|(a, b)| (a - b).abs())
            .sum::<f64>()
            * DX_M;
        out.push(Comparison {
            front_m: front(&h),
            front_exact_m: front(&exact),
            l1_rel: l1 / volume,
        });
    }
    out
}

/// The default parameters with the solution's Coulomb friction (see the module documentation).
fn coulomb() -> AvalancheParams {
    let p = AvalancheParams {
        friction: FrictionLaw::Coulomb,
        alpha: 1.0,
        k_viscous: 0.0,
        rest_angle_deg: FRICTION_DEG,
        border: Border::Closed,
        ..AvalancheParams::default()
    };
    assert_eq!(p.slope_gravity, SlopeGravity::Projected);
    assert!(p.curvature && p.momentum_advection);
    p
}

/// Front error at t = 10 and 20 s, relative to the analytic front's distance from the dam.
const FRONT_TOLERANCE: f64 = 0.08;
/// L1 profile error relative to the analytic volume in the window.
const L1_TOLERANCE: f64 = 0.06;

/// Tolerances at t = 10 and 20 s: front within 8 % of the analytic front's distance from the
/// dam, L1 profile error below 6 % of the analytic volume in the window. Measured
/// (2026-12-04): front −5.5 % and −6.0 % (the smeared front's 5 cm contour trails the
/// analytic one), L1 4.0 % and 4.9 %.
#[test]
fn frictional_dam_break_follows_mangeney() {
    let times = [10.0, 20.0];
    for (t, c) in times.iter().zip(run(&coulomb(), &times)) {
        let err = (c.front_m - c.front_exact_m) / c.front_exact_m;
        eprintln!(
            "Mangeney t = {t} s: front {:.1} m vs {:.1} m ({:+.1} %), L1 profile {:.1} %",
            c.front_m,
            c.front_exact_m,
            100.0 * err,
            100.0 * c.l1_rel
        );
        assert!(err.abs() < FRONT_TOLERANCE, "t = {t} s: front error {err}");
        assert!(
            c.l1_rel < L1_TOLERANCE,
            "t = {t} s: L1 profile error {}",
            c.l1_rel
        );
    }
}

/// The paper's shallow-slope form misses the tolerances: its front runs ahead (measured
/// 2026-12-04: +11.0 % and +10.2 %, L1 5.2 % and 8.3 %).
#[test]
fn shallow_slope_dam_break_runs_ahead_of_mangeney() {
    let shallow = AvalancheParams {
        slope_gravity: SlopeGravity::Shallow,
        ..coulomb()
    };
    let times = [10.0, 20.0];
    for (t, c) in times.iter().zip(run(&shallow, &times)) {
        let err = (c.front_m - c.front_exact_m) / c.front_exact_m;
        eprintln!(
            "shallow Mangeney t = {t} s: front {:+.1} %, L1 profile {:.1} %",
            100.0 * err,
            100.0 * c.l1_rel
        );
        assert!(err > FRONT_TOLERANCE, "t = {t} s: front error {err}");
    }
}

/// The test tells the physics apart: frictionless, the front at 20 s runs far past the
/// analytic one; without momentum advection it lags far behind.
#[test]
fn dam_break_without_friction_or_advection_misses_mangeney() {
    let free = AvalancheParams {
        alpha: 0.0,
        ..coulomb()
    };
    let c = &run(&free, &[20.0])[0];
    eprintln!(
        "frictionless: front {:.1} m vs {:.1} m",
        c.front_m, c.front_exact_m
    );
    assert!(c.front_m > 1.15 * c.front_exact_m, "front {}", c.front_m);
    let lagging = AvalancheParams {
        momentum_advection: false,
        ..coulomb()
    };
    let c = &run(&lagging, &[20.0])[0];
    eprintln!(
        "no advection: front {:.1} m vs {:.1} m",
        c.front_m, c.front_exact_m
    );
    assert!(c.front_m < 0.85 * c.front_exact_m, "front {}", c.front_m);
}

/// Issue 20, item 5: AvaFrame's similarity solution (Hutter et al. 1993's parabolic-cap
/// similarity solution of the Savage-Hutter equations, as AvaFrame's `ana1Tests.simiSol`
/// writes it: a cap of L = 80 m and H = 4 m on a 35° plane with 25° friction) at t = 5 s,
/// from its own thickness at t = 0, on the plane DEM
/// (`dem/avaframe_synthetic_avaSimilaritySol`, 401x101 cells of 5 m). Thickness normal to the
/// slope (ours is vertical: × cos 35°), compared cell by cell.
///
/// **What it shows (measured 2026-12-04).** With the projected gravity: L1 error 6.4 % of the
/// analytic volume (48.6 % for a cap that did not move), peak 3.37 m against 3.44 m, centre of
/// mass 20.3 m downslope (horizontal) against the analytic 19.2 m: Savage-Hutter's sliding law
/// projected on the horizontal, `½ g cos²θ (tan θ − tan δ) t²` = 19.3 m. The shallow-slope form
/// gives L1 30.0 %, peak 2.89 m and 30.4 m (its own law `½ g (tan θ − tan δ) t²` = 28.7 m:
/// 1/cos²35° = 1.49 times too far) and fails every tolerance below.
#[test]
fn similarity_solution_shallow_slope_misses() {
    let r = similarity(SlopeGravity::Shallow);
    assert!(r.l1 > SIMILARITY_L1, "shallow L1 {}", r.l1);
    assert!(
        (r.travel - r.travel_exact).abs() > SIMILARITY_TRAVEL * r.travel_exact,
        "shallow travel {} m",
        r.travel
    );
}

/// L1 thickness error of the similarity solution at t = 5 s, relative to its volume.
const SIMILARITY_L1: f64 = 0.09;
/// Centre-of-mass travel error, relative to the analytic travel.
const SIMILARITY_TRAVEL: f64 = 0.08;
/// Peak thickness error, relative.
const SIMILARITY_PEAK: f64 = 0.05;

/// The similarity solution's figures at t = 5 s.
struct Similarity {
    l1: f64,
    peak: f64,
    peak_exact: f64,
    travel: f64,
    travel_exact: f64,
}

/// Runs the similarity solution to t = 5 s with `slope_gravity`.
fn similarity(slope_gravity: SlopeGravity) -> Similarity {
    use snowscape_io::{ReadOptions, read_dem};
    let read = |rel: &str| read_dem(&data(rel), &ReadOptions::default()).unwrap();
    let dem = read("dem/avaframe_synthetic_avaSimilaritySol/DEM_IP_Topo.asc");
    let h_start = read("reference/avaframe_analytic/simisol_h_t00.asc");
    let h_end = read("reference/avaframe_analytic/simisol_h_t05.asc");
    let g = dem.geometry().clone();
    assert_eq!((g.width(), g.height()), (401, 101));
    assert_eq!(h_start.data().len(), g.len());
    let cos = 35f64.to_radians().cos();
    let bed: Vec<f64> = dem.data().iter().map(|&z| f64::from(z)).collect();
    let mut state = AvalancheState::new(&g, &NodataMask::all_valid(), &bed).unwrap();
    let h0: Vec<f64> = h_start.data().iter().map(|&h| f64::from(h) / cos).collect();
    state.set_thickness(&h0).unwrap();
    let params = AvalancheParams {
        friction: FrictionLaw::Coulomb,
        alpha: 1.0,
        k_viscous: 0.0,
        rest_angle_deg: 25.0,
        border: Border::Open,
        slope_gravity,
        ..AvalancheParams::default()
    };
    let mut scratch = AvalancheScratch::default();
    step(&params, &mut state, &mut scratch, 5.0).unwrap();
    let ours: Vec<f64> = state.thickness().iter().map(|h| h * cos).collect();
    let exact: Vec<f64> = h_end.data().iter().map(|&h| f64::from(h)).collect();
    let start: Vec<f64> = h_start.data().iter().map(|&h| f64::from(h)).collect();
    let volume: f64 = exact.iter().sum();
    let l1 = |a: &[f64]| {
        a.iter()
            .zip(&exact)
            .map(|(x, y)| (x - y).abs())
            .sum::<f64>()
            / volume
    };
    let centre = |h: &[f64]| {
        let w = g.width();
        let (m, s) = h.iter().enumerate().fold((0.0, 0.0), |(m, s), (i, &v)| {
            (m + v, s + v * (i % w) as f64 * g.cell_size_x())
        });
        s / m
    };
    let peak = |h: &[f64]| h.iter().copied().fold(0.0, f64::max);
    let (travel, travel_exact) = (
        centre(&ours) - centre(&start),
        centre(&exact) - centre(&start),
    );
    eprintln!(
        "similarity solution t = 5 s ({slope_gravity:?}): L1 {:.1} % (a cap at rest: {:.1} %), peak {:.2} m vs {:.2} m, \
         centre of mass travel {travel:.1} m vs {travel_exact:.1} m",
        100.0 * l1(&ours),
        100.0 * l1(&start),
        peak(&ours),
        peak(&exact)
    );
    let moved: f64 = state.thickness().iter().sum::<f64>();
    let released: f64 = h0.iter().sum();
    assert!(
        (moved - released).abs() < 1e-9 * released,
        "volume {moved} vs {released}"
    );
    Similarity {
        l1: l1(&ours),
        peak: peak(&ours),
        peak_exact: peak(&exact),
        travel,
        travel_exact,
    }
}

/// Tolerances: L1 below 9 %, centre-of-mass travel within 8 % of the analytic, which is
/// Savage-Hutter's projected sliding law (asserted too), peak within 5 %. The default gravity.
#[test]
fn similarity_solution_at_five_seconds() {
    let r = similarity(AvalancheParams::default().slope_gravity);
    let (tan, tan_d) = (35f64.to_radians().tan(), 25f64.to_radians().tan());
    let cos2 = 35f64.to_radians().cos().powi(2);
    let law = 0.5 * snowscape_avalanche::flow::G * cos2 * (tan - tan_d) * 25.0;
    assert!(
        (r.travel_exact - law).abs() < 0.02 * law,
        "analytic travel {} m, Savage-Hutter's sliding law {law} m",
        r.travel_exact
    );
    assert!(r.l1 < SIMILARITY_L1, "L1 {}", r.l1);
    assert!(
        (r.travel - r.travel_exact).abs() < SIMILARITY_TRAVEL * r.travel_exact,
        "centre of mass travel {} m vs {} m",
        r.travel,
        r.travel_exact
    );
    assert!(
        (r.peak - r.peak_exact).abs() < SIMILARITY_PEAK * r.peak_exact,
        "peak {} m vs {} m",
        r.peak,
        r.peak_exact
    );
}
