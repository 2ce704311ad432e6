//! The run driver: stop criteria, peak fields and runout figures.

use snowscape_avalanche::{
    AvalancheError, AvalancheParams, AvalancheRun, AvalancheState, RecordTiming, RunOptions,
    StopReason,
};
use snowscape_terrain::{GridGeometry, NodataMask};

/// A 40° slope (rows 0..60) running out onto flat ground (rows 60..160), 2 m cells, with a
/// 2 m thick block of snow released near the top.
fn slope_runout() -> AvalancheRun {
    let (w, h, dx) = (40usize, 160usize, 2.0);
    let g = GridGeometry::square(w, h, dx).unwrap();
    let tan = 40f64.to_radians().tan();
    let bed: Vec<f64> = (0..w * h)
        .map(|i| {
            let r = (i / w) as f64;
            tan * dx * (60.0 - r).max(0.0)
        })
        .collect();
    let mut s = AvalancheState::new(&g, &NodataMask::all_valid(), &bed).unwrap();
    let hv: Vec<f64> = (0..w * h)
        .map(|i| {
            let (c, r) = (i % w, i / w);
            if (15..25).contains(&c) && (5..15).contains(&r) {
                2.0
            } else {
                0.0
            }
        })
        .collect();
    s.set_thickness(&hv).unwrap();
    AvalancheRun::new(s)
}

#[test]
fn runs_to_rest_with_consistent_peaks_and_figures() {
    let mut run = slope_runout();
    let params = AvalancheParams::default();
    let opts = RunOptions::default();
    let mut records = 0;
    let mut last_time = 0.0;
    let summary = run
        .run::<AvalancheError>(&params, &opts, |r| {
            records += 1;
            assert!(r.kinetic_energy().is_finite());
            // Records at whole sub-steps, at least a record interval apart.
            assert!(
                r.time() - last_time >= 0.1 - 1e-12,
                "{} after {last_time}",
                r.time()
            );
            last_time = r.time();
            Ok(())
        })
        .unwrap();
    eprintln!("{summary:#?}");
    assert!(matches!(
        summary.stop,
        Some(StopReason::AtRest | StopReason::EnergyCriterion)
    ));
    assert!(records as f64 <= (summary.simulated_s / 0.1).round());
    // Records cut at exact intervals: one per 0.1 s, the same physics within the CFL error.
    let exact = RunOptions {
        records: RecordTiming::Exact,
        ..RunOptions::default()
    };
    let mut fixed = slope_runout();
    let mut fixed_records = 0;
    let s2 = fixed
        .run::<AvalancheError>(&params, &exact, |_| {
            fixed_records += 1;
            Ok(())
        })
        .unwrap();
    assert_eq!(fixed_records as f64, (s2.simulated_s / 0.1).round());
    assert!(
        s2.substeps >= summary.substeps,
        "{} vs {}",
        s2.substeps,
        summary.substeps
    );
    assert!((s2.travel_angle_deg - summary.travel_angle_deg).abs() < 0.2);
    assert!((s2.runout_length_m - summary.runout_length_m).abs() < 0.05 * s2.runout_length_m);
    assert!(summary.volume_closure_rel < 1e-9);
    assert_eq!(summary.released_volume_m3, 10.0 * 10.0 * 4.0 * 2.0);
    // Peaks bound the final thickness; the release lies in the footprint.
    let h = run.state.thickness();
    for (i, (&p, &hf)) in run.peak_thickness().iter().zip(&h).enumerate() {
        assert!(p >= hf, "cell {i}: peak {p} < final {hf}");
    }
    let fp = run.footprint(0.01);
    assert!(fp[10 * 40 + 20]);
    assert!(summary.max_thickness_m >= 2.0);
    assert!(
        summary.max_speed_m_s > 5.0,
        "max speed {}",
        summary.max_speed_m_s
    );
    // The snow leaves the slope (foot 110 m south of the release top) and runs out on the flat.
    assert!(
        summary.release_top[1] - summary.runout_point[1] > 110.0,
        "{:?} -> {:?}",
        summary.release_top,
        summary.runout_point
    );
    assert_eq!(summary.runout_point[2], 0.0);
    assert!(summary.runout_length_m > summary.centre_travel_m);
    // The mass centre's travel angle lies between θc-ish and the slope angle.
    assert!(
        summary.travel_angle_deg > 15.0 && summary.travel_angle_deg < 40.0,
        "travel angle {}",
        summary.travel_angle_deg
    );
    assert!(summary.alpha_angle_deg < summary.travel_angle_deg + 10.0);
}

#[test]
fn duration_bounds_the_run() {
    let mut run = slope_runout();
    let opts = RunOptions {
        duration_s: 1.05,
        ..RunOptions::default()
    };
    let s = run
        .run::<AvalancheError>(&AvalancheParams::default(), &opts, |_| Ok(()))
        .unwrap();
    assert_eq!(s.stop, Some(StopReason::Duration));
    assert!((s.simulated_s - 1.05).abs() < 1e-9, "{}", s.simulated_s);
}

#[test]
fn an_empty_release_stops_at_once() {
    let g = GridGeometry::square(8, 8, 1.0).unwrap();
    let s = AvalancheState::new(&g, &NodataMask::all_valid(), &[0.0; 64]).unwrap();
    let run = AvalancheRun::new(s);
    assert_eq!(run.stop_reason(), Some(StopReason::Empty));
}

#[test]
fn bad_options_are_named() {
    let mut run = slope_runout();
    for (opts, name) in [
        (
            RunOptions {
                duration_s: -1.0,
                ..RunOptions::default()
            },
            "duration_s",
        ),
        (
            RunOptions {
                record_interval_s: f64::NAN,
                ..RunOptions::default()
            },
            "record_interval_s",
        ),
        (
            RunOptions {
                stop_energy_fraction: 1.5,
                ..RunOptions::default()
            },
            "stop_energy_fraction",
        ),
    ] {
        let err = run.advance(&AvalancheParams::default(), &opts).unwrap_err();
        assert!(err.to_string().contains(name), "{err}");
    }
}

/// Film settling: only films thinner than the threshold (with thin neighbours) settle, the
/// settled snow counts in the final volume, and a run without settling keeps more cells wet.
#[test]
fn thin_films_settle_and_mass_is_conserved() {
    let params = AvalancheParams::default();
    let threshold = 0.005;
    let mut run = slope_runout();
    let summary = run
        .run::<AvalancheError>(&params, &RunOptions::default(), |r| {
            for (i, &s) in r.state.settled_thickness().iter().enumerate() {
                assert!(s >= 0.0 && s.is_finite(), "cell {i}: settled {s}");
            }
            Ok(())
        })
        .unwrap();
    assert!(
        summary.volume_closure_rel < 1e-9,
        "{}",
        summary.volume_closure_rel
    );
    let settled = run.state.settled_thickness();
    let flowing = run.state.thickness();
    let settled_cells = settled.iter().filter(|&&s| s > 0.0).count();
    assert!(settled_cells > 0, "no film settled");
    // A cell settles at most a few films of less than the threshold each.
    let max_settled = settled.iter().fold(0.0f64, |m, &s| m.max(s));
    assert!(max_settled < 20.0 * threshold, "settled {max_settled} m");
    let total: f64 = run.state.snow_thickness().iter().sum::<f64>() * 4.0;
    let parts: f64 = (settled.iter().sum::<f64>() + flowing.iter().sum::<f64>()) * 4.0;
    assert!((total - parts).abs() < 1e-9 * total);
    let kept = summary.released_volume_m3 - summary.border_outflow_m3;
    assert!((total - kept).abs() < 1e-9 * total, "{total} vs {kept}");

    let mut unsettled = slope_runout();
    let options = RunOptions {
        settle_thickness_m: 0.0,
        ..RunOptions::default()
    };
    unsettled
        .run::<AvalancheError>(&params, &options, |_| Ok(()))
        .unwrap();
    assert!(
        unsettled
            .state
            .settled_thickness()
            .iter()
            .all(|&s| s == 0.0)
    );
    let wet = |v: &[f64]| v.iter().filter(|&&h| h > 0.0).count();
    assert!(
        wet(&flowing) < wet(&unsettled.state.thickness()),
        "settling leaves fewer flowing cells: {} vs {}",
        wet(&flowing),
        wet(&unsettled.state.thickness())
    );
}
