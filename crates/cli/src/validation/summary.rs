//! The short text table `snowscape validate` prints: the metrics of the simulation and of
//! both baselines, then the class ratios.

use super::Validation;
use super::classes::ContrastRatio;
use super::stats::Metrics;
use std::fmt::Write;

fn num(v: Option<f64>, width: usize, decimals: usize) -> String {
    match v {
        Some(v) => format!("{v:>width$.decimals$}"),
        None => format!("{:>width$}", "-"),
    }
}

fn metrics_row(out: &mut String, name: &str, m: &Metrics) {
    let c = &m.snow_cover;
    let _ = writeln!(
        out,
        "{name:<20}{}{}{}{}{}{}{}{}",
        num(m.spearman, 9, 3),
        num(m.pearson, 9, 3),
        num(Some(m.rmse_m), 9, 3),
        num(Some(m.bias_m), 9, 3),
        num(c.accuracy, 9, 3),
        num(c.hit_rate, 9, 3),
        num(c.false_alarm_ratio, 9, 3),
        num(c.kappa, 9, 3),
    );
}

fn ratio_row(out: &mut String, r: &ContrastRatio) {
    let name = format!("{}/{}", r.class_a, r.class_b);
    let _ = writeln!(
        out,
        "{name:<20}{}{}{:>9}{:>9}{:>9}",
        num(r.simulated, 9, 3),
        num(r.observed, 9, 3),
        r.cells_a,
        r.cells_b,
        r.cells_used,
    );
}

/// The summary table.
pub fn table(v: &Validation) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{} cells compared ({} sampling; observed mean {:.3} m); snow cover: depth > {} m",
        v.cells_compared,
        v.matching.sampling.name(),
        v.observed_mean_m,
        v.snow_threshold_m
    );
    let _ = writeln!(
        out,
        "{:<20}{:>9}{:>9}{:>9}{:>9}{:>9}{:>9}{:>9}{:>9}",
        "", "spearman", "pearson", "rmse_m", "bias_m", "accuracy", "hit_rate", "far", "kappa"
    );
    metrics_row(&mut out, "simulation", &v.simulation);
    metrics_row(
        &mut out,
        "altitude rank",
        &v.baselines.altitude_rank.metrics,
    );
    metrics_row(
        &mut out,
        "altitude+northness",
        &v.baselines.altitude_northness.metrics,
    );
    let _ = writeln!(
        out,
        "spearman with altitude: simulated {}, observed {}",
        num(v.spearman_with_altitude.simulated, 0, 3),
        num(v.spearman_with_altitude.observed, 0, 3)
    );
    let _ = writeln!(
        out,
        "{:<20}{:>9}{:>9}{:>9}{:>9}{:>9}   (mean over {} m bands; wind from {:.0} deg)",
        "ratio",
        "sim",
        "obs",
        "cells_a",
        "cells_b",
        "used",
        v.ratios.band_m,
        v.ratios.wind_from_deg
    );
    ratio_row(&mut out, &v.ratios.north_south);
    ratio_row(&mut out, &v.ratios.steep_moderate);
    ratio_row(&mut out, &v.ratios.lee_windward);
    out
}
