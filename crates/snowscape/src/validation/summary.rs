//! The short text table `snowscape validate` prints: the metrics of the simulation and of
//! both baselines, then the class ratios.

use super::Validation;
use super::classes::{BAND_M, ContrastRatio};
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
        "{name:<20}{}{}{:>9}{:>9}{:>9}{}{}{}{}",
        num(r.simulated, 9, 3),
        num(r.observed, 9, 3),
        r.cells_a,
        r.cells_b,
        r.cells_used,
        num(r.simulated_mean_m[0], 9, 3),
        num(r.simulated_mean_m[1], 9, 3),
        num(r.observed_mean_m[0], 9, 3),
        num(r.observed_mean_m[1], 9, 3),
    );
    // The bands behind the pooled ratio: each band's own ratio, its cell counts and means.
    for b in &r.bands {
        let name = format!("  {:.0}..{:.0} m", b.from_m, b.from_m + BAND_M);
        let used = if b.used {
            (b.cells_a + b.cells_b).to_string()
        } else {
            "-".to_string()
        };
        let _ = writeln!(
            out,
            "{name:<20}{}{}{:>9}{:>9}{used:>9}{}{}{}{}",
            num(b.simulated, 9, 3),
            num(b.observed, 9, 3),
            b.cells_a,
            b.cells_b,
            num(b.simulated_mean_m[0], 9, 3),
            num(b.simulated_mean_m[1], 9, 3),
            num(b.observed_mean_m[0], 9, 3),
            num(b.observed_mean_m[1], 9, 3),
        );
    }
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
        "{:<20}{:>9}{:>9}{:>9}{:>9}{:>9}{:>9}{:>9}{:>9}{:>9}",
        "ratio",
        "sim",
        "obs",
        "cells_a",
        "cells_b",
        "used",
        "sim_a_m",
        "sim_b_m",
        "obs_a_m",
        "obs_b_m"
    );
    let _ = writeln!(
        out,
        "(pooled over {} m bands: sum of w*mean_a over sum of w*mean_b, w = the band's cells \
         of both classes; the band rows give each band's own ratio; wind from {:.0} deg)",
        v.ratios.band_m, v.ratios.wind_from_deg
    );
    ratio_row(&mut out, &v.ratios.north_south);
    ratio_row(&mut out, &v.ratios.steep_moderate);
    ratio_row(&mut out, &v.ratios.lee_windward);
    out
}
