//! The Voellmy and samosAT friction laws against their analytic plane solutions. Voellmy: a uniform layer on a long
//! inclined plane accelerates as `du/dt = g·(tanθ − μ) − g·u²/(ξ·h)` (horizontal-projection
//! form, see [`FrictionLaw::Voellmy`]) and tends to `u∞ = sqrt(ξ·h·(tanθ − μ))`, reaching
//! `u∞·tanh(t/τ)` with `τ = u∞ / (g·(tanθ − μ))`. Far from the layer's ends (which waves reach
//! at ~`sqrt(g·h)` relative to the snow) the simulated speed follows it. The solutions are of
//! the shallow-slope gravity `g` ([`AvalancheParams::paper`]'s), which the runs here take.

use snowscape_avalanche::{
    AvalancheParams, AvalancheScratch, AvalancheState, Border, FrictionLaw, SamosAtParams, step,
};
use snowscape_terrain::{GridGeometry, NodataMask};

const G: f64 = snowscape_avalanche::flow::G;

/// Speed at the layer's centre after `t` s of a `h`-metre layer on a `slope_deg` plane.
fn centre_speed(params: &AvalancheParams, slope_deg: f64, h: f64, t: f64) -> (f64, f64) {
    let (w, rows, dx) = (6, 500, 5.0);
    let g = GridGeometry::square(w, rows, dx).unwrap();
    let tan = slope_deg.to_radians().tan();
    // Row 0 is the top: the bed falls with the row.
    let bed: Vec<f64> = (0..w * rows)
        .map(|i| 3000.0 - tan * dx * (i / w) as f64)
        .collect();
    let mut s = AvalancheState::new(&g, &NodataMask::all_valid(), &bed).unwrap();
    let depth: Vec<f64> = (0..w * rows)
        .map(|i| if (40..340).contains(&(i / w)) { h } else { 0.0 })
        .collect();
    s.set_thickness(&depth).unwrap();
    let mut scratch = AvalancheScratch::default();
    let mut done = 0.0;
    while done < t {
        let dt = (t - done).min(0.5);
        step(params, &mut s, &mut scratch, dt).unwrap();
        done += dt;
    }
    // The uniform part of the layer (no wave from its ends has reached it; its thickness
    // is the centre's, which the layer's first spreading leaves a little above `h`), in the
    // middle column: its median speed and its thickness.
    let hc = s.thickness_at(3, 190);
    let mut speeds: Vec<f64> = (0..rows)
        .filter(|&row| (s.thickness_at(3, row) - hc).abs() < 1e-3 * hc)
        .map(|row| {
            let v = s.velocity_at(3, row);
            (v[0] * v[0] + v[1] * v[1]).sqrt()
        })
        .collect();
    assert!(speeds.len() > 50, "only {} uniform rows left", speeds.len());
    speeds.sort_by(f64::total_cmp);
    (speeds[speeds.len() / 2], hc)
}

fn voellmy(mu: f64, xi: f64) -> AvalancheParams {
    AvalancheParams {
        friction: FrictionLaw::Voellmy,
        voellmy_mu: mu,
        voellmy_xi_m_s2: xi,
        border: Border::Closed,
        ..AvalancheParams::paper()
    }
}

#[test]
fn a_uniform_layer_on_a_plane_follows_the_analytic_voellmy_speed() {
    for (slope, mu, xi, h) in [(35.0f64, 0.6, 1000.0, 1.0), (30.0, 0.4, 2000.0, 0.5)] {
        let drive = slope.to_radians().tan() - mu;
        let tau_of = |h: f64| (xi * h * drive).sqrt() / (G * drive);
        for t in [0.5 * tau_of(h), 3.0 * tau_of(h)] {
            let (got, hc) = centre_speed(&voellmy(mu, xi), slope, h, t);
            let u_inf = (xi * hc * drive).sqrt();
            let want = u_inf * (t / tau_of(hc)).tanh();
            let err = (got - want).abs() / want;
            println!(
                "slope {slope}°, μ {mu}, ξ {xi}, h {hc:.4}: t = {t:.1} s, speed {got:.3} m/s, analytic {want:.3} m/s ({:.2} %)",
                100.0 * err
            );
            assert!(err < 0.02, "speed {got} m/s, analytic {want} m/s");
        }
    }
}

#[test]
fn voellmy_with_more_turbulent_drag_is_slower_and_a_gentle_slope_holds() {
    let fast = centre_speed(&voellmy(0.3, 4000.0), 35.0, 1.0, 20.0).0;
    let slow = centre_speed(&voellmy(0.3, 500.0), 35.0, 1.0, 20.0).0;
    assert!(slow < 0.5 * fast, "ξ 500: {slow} m/s, ξ 4000: {fast} m/s");
    // tanθ < μ: static friction holds the layer.
    let held = centre_speed(&voellmy(0.8, 4000.0), 35.0, 1.0, 5.0).0;
    assert_eq!(held, 0.0);
}

#[test]
fn the_coulomb_law_is_unchanged_by_the_voellmy_fields() {
    let base = AvalancheParams {
        border: Border::Closed,
        ..AvalancheParams::paper()
    };
    let other = AvalancheParams {
        voellmy_mu: 0.9,
        voellmy_xi_m_s2: 50.0,
        ..base.clone()
    };
    assert_eq!(
        centre_speed(&base, 35.0, 1.0, 4.0).0.to_bits(),
        centre_speed(&other, 35.0, 1.0, 4.0).0.to_bits()
    );
}

/// samosAT's steady speed on a plane: the `u` where the drive `g·(tanθ − μ·(1 + Rs0/(Rs0 +
/// u²/(g·h))))` equals the drag `u²/(h·(ln(max(h/R, 1))/κ + B)²)` (bisection).
fn samos_steady_speed(s: &SamosAtParams, tan: f64, h: f64) -> f64 {
    let div = (h / s.roughness_m).max(1.0).ln() / s.kappa + s.b;
    let net = |u: f64| {
        G * (tan - s.mu * (1.0 + s.rs0 / (s.rs0 + u * u / (G * h)))) - u * u / (h * div * div)
    };
    let (mut lo, mut hi) = (0.0, 200.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if net(mid) > 0.0 { lo = mid } else { hi = mid }
    }
    lo
}

#[test]
fn a_uniform_layer_on_a_plane_reaches_the_steady_samosat_speed() {
    for (slope, s, h) in [
        (35.0f64, SamosAtParams::small(), 1.0),
        (30.0, SamosAtParams::standard(), 0.5),
    ] {
        let params = AvalancheParams {
            friction: FrictionLaw::SamosAt,
            samos_at: s,
            border: Border::Closed,
            ..AvalancheParams::paper()
        };
        let (got, hc) = centre_speed(&params, slope, h, 20.0);
        let want = samos_steady_speed(&s, slope.to_radians().tan(), hc);
        let err = (got - want).abs() / want;
        println!(
            "samosAT μ {} on {slope}°, h {hc:.4}: speed {got:.3} m/s after 20 s, steady {want:.3} m/s ({:.2} %)",
            s.mu,
            100.0 * err
        );
        assert!(err < 0.02, "speed {got} m/s, steady {want} m/s");
    }
    // At rest the dry friction is twice μ: a slope with μ < tanθ < 2μ holds.
    let held = AvalancheParams {
        friction: FrictionLaw::SamosAt,
        samos_at: SamosAtParams {
            mu: 0.45,
            ..SamosAtParams::standard()
        },
        border: Border::Closed,
        ..AvalancheParams::paper()
    };
    assert_eq!(centre_speed(&held, 35.0, 1.0, 5.0).0, 0.0);
}
