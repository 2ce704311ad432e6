//! Issue 4, item 6: a block released on an inclined plane runs out onto flat ground with pure
//! Coulomb friction; the travel angle of its mass centre (drop over horizontal travel, release
//! to rest) approaches the rest angle θc.
//!
//! Why θc: with horizontal velocity `u`, a point mass obeys `d(u²/2)/dx = g·(tanθ − tanθc)` on
//! the slope and `−g·tanθc` on the flat, so it stops after a horizontal travel of exactly
//! `H / tanθc` (no loss at the slope break in this horizontal formulation). A spreading block
//! deviates from the point mass only through its pressure gradient, which moves mass forwards
//! and backwards about equally, and through the scheme's numerical diffusion.
//!
//! Tolerance: 1°. Measured (2 m cells, 20 m x 20 m x 2 m block, 35° plane 300 m long):
//! θc = 30° → 30.58° (the mass centre stops 7.5 m short of the point mass's 327 m); 1 m cells
//! → 30.41° (examples/validation.rs prints both); θc = 25° → 25.39° without film settling. The
//! residual is the first-order scheme's smearing of the block over the slope break (a few
//! cells); 1° is 12 m of travel at θc = 30°, so the test fails if the friction or the bed
//! gradient is wrong by more than ~3 %.

use snowscape_avalanche::validation::plane_runout;
use snowscape_avalanche::{AvalancheParams, RunOptions, StopReason};

fn check(rest_angle_deg: f64, options: &RunOptions) -> f64 {
    let params = AvalancheParams {
        rest_angle_deg,
        ..AvalancheParams::paper()
    };
    let r = plane_runout(35.0, &params, 2.0, options).unwrap();
    let s = &r.summary;
    eprintln!(
        "35° plane, θc {rest_angle_deg}°: travel angle {:.3}° (drop {:.2} m over {:.2} m), alpha {:.2}°, \
         stop {:?} after {:.1} s, max speed {:.1} m/s",
        s.travel_angle_deg,
        s.centre_drop_m,
        s.centre_travel_m,
        s.alpha_angle_deg,
        s.stop,
        s.simulated_s,
        s.max_speed_m_s
    );
    assert!(s.volume_closure_rel < 1e-9, "{}", s.volume_closure_rel);
    assert!(
        s.border_outflow_m3 < 1e-6 * s.released_volume_m3,
        "the block stays on the grid: {} m³ left",
        s.border_outflow_m3
    );
    // The mass centre leaves the slope (its foot is 280 m below the block's centre) and the
    // snow's farthest point runs out on the flat.
    assert!(s.centre_travel_m > 280.0, "travel {}", s.centre_travel_m);
    assert_eq!(s.runout_point[2], 0.0);
    // The front runs farther than the mass centre.
    assert!(s.alpha_angle_deg < s.travel_angle_deg);
    assert!(
        (s.travel_angle_deg - rest_angle_deg).abs() < 1.0,
        "travel angle {} vs θc {rest_angle_deg}",
        s.travel_angle_deg
    );
    s.travel_angle_deg
}

/// θc = 30° (the paper's), run until every pipe is at rest.
#[test]
fn plane_runout_travel_angle_is_the_rest_angle() {
    let options = RunOptions {
        stop_energy_fraction: 0.0,
        duration_s: 300.0,
        ..RunOptions::default()
    };
    check(30.0, &options);
    let params = AvalancheParams::paper();
    let r = plane_runout(35.0, &params, 2.0, &options).unwrap();
    assert_eq!(r.summary.stop, Some(StopReason::AtRest));
    assert!(r.summary.simulated_s < 120.0);
}

/// θc = 25°: far from the 35° slope, the snow runs longer; stopped by the energy criterion
/// (1 % of the peak kinetic energy: the thin film left on a slope steeper than θc never comes
/// fully to rest under pure Coulomb friction, so the run driver's default criterion ends it).
/// Pure Coulomb: no film settling.
#[test]
fn plane_runout_with_a_lower_rest_angle() {
    let options = RunOptions {
        duration_s: 300.0,
        settle_thickness_m: 0.0,
        ..RunOptions::default()
    };
    let a = check(25.0, &options);
    assert!(a < 28.0);
}

/// With the run driver's default film settling (5 mm), the films the tail leaves on a slope
/// steeper than θc stay there (pure Coulomb friction would let them creep on forever): the
/// mass centre stops a little short, within 2° of θc. Measured: 26.25° for θc = 25°.
#[test]
fn plane_runout_with_film_settling() {
    let params = AvalancheParams {
        rest_angle_deg: 25.0,
        ..AvalancheParams::paper()
    };
    let options = RunOptions {
        duration_s: 300.0,
        ..RunOptions::default()
    };
    let r = plane_runout(35.0, &params, 2.0, &options).unwrap();
    let s = &r.summary;
    assert!(s.volume_closure_rel < 1e-9, "{}", s.volume_closure_rel);
    assert!(
        s.travel_angle_deg > 25.0 && s.travel_angle_deg < 27.0,
        "travel angle {}",
        s.travel_angle_deg
    );
    let unsettled = RunOptions {
        settle_thickness_m: 0.0,
        ..options
    };
    let r0 = plane_runout(35.0, &params, 2.0, &unsettled).unwrap();
    assert!(
        s.travel_angle_deg > r0.summary.travel_angle_deg,
        "settled films hold the centre back: {} vs {}",
        s.travel_angle_deg,
        r0.summary.travel_angle_deg
    );
}

#[test]
fn plane_runout_rejects_bad_inputs() {
    let p = AvalancheParams::paper();
    let o = RunOptions::default();
    let e = plane_runout(95.0, &p, 2.0, &o).unwrap_err();
    assert!(e.to_string().contains("slope_deg"), "{e}");
    let e = plane_runout(35.0, &p, 0.0, &o).unwrap_err();
    assert!(e.to_string().contains("cell_m"), "{e}");
}
