//! The statistics of a validation: ranks, correlations, errors, the 2×2 snow-cover table, and
//! the two terrain-only baselines' predictions (quantile mapping, least squares).
//!
//! Sources: Spearman's ρ is Pearson's r of the ranks, ties given their average rank (the
//! "fractional ranking" of Kendall & Gibbons, Rank Correlation Methods, 1990, §3.8). The
//! snow-cover scores are those of the forecast-verification literature (Wilks, Statistical
//! Methods in the Atmospheric Sciences, 3rd ed. 2011, §8.2): accuracy (proportion correct),
//! hit rate (probability of detection), false alarm ratio, critical success index, and
//! Cohen's κ (Cohen 1960, Educ. Psychol. Meas. 20) = (p_o − p_e) / (1 − p_e).
//! Every sum runs in f64 in cell order, so results do not depend on the thread count.

use serde::Serialize;

/// The 1-based ranks of `values`, ties sharing the average of the ranks they span.
pub fn average_ranks(values: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let mut ranks = vec![0.0; values.len()];
    let mut start = 0;
    while start < order.len() {
        let mut end = start + 1;
        while end < order.len() && values[order[end]] == values[order[start]] {
            end += 1;
        }
        // Positions start..end (0-based) hold ranks start+1..=end: their mean.
        let rank = (start + 1 + end) as f64 / 2.0;
        for &i in &order[start..end] {
            ranks[i] = rank;
        }
        start = end;
    }
    ranks
}

/// Arithmetic mean (0 for no values).
pub fn mean(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.iter().sum::<f64>() / values.len() as f64
}

/// Pearson's r; `None` with fewer than two values or a constant series.
pub fn pearson(x: &[f64], y: &[f64]) -> Option<f64> {
    debug_assert_eq!(x.len(), y.len());
    if x.len() < 2 {
        return None;
    }
    let (mx, my) = (mean(x), mean(y));
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        let (dx, dy) = (a - mx, b - my);
        sxy += dx * dy;
        sxx += dx * dx;
        syy += dy * dy;
    }
    (sxx > 0.0 && syy > 0.0).then(|| (sxy / (sxx * syy).sqrt()).clamp(-1.0, 1.0))
}

/// Spearman's ρ (Pearson's r of the average ranks); `None` as for [`pearson`].
pub fn spearman(x: &[f64], y: &[f64]) -> Option<f64> {
    pearson(&average_ranks(x), &average_ranks(y))
}

/// Root-mean-square of `predicted − observed`.
pub fn rmse(predicted: &[f64], observed: &[f64]) -> f64 {
    let n = predicted.len().max(1) as f64;
    let s: f64 = predicted
        .iter()
        .zip(observed)
        .map(|(p, o)| (p - o) * (p - o))
        .sum();
    (s / n).sqrt()
}

/// Mean of `predicted − observed`.
pub fn bias(predicted: &[f64], observed: &[f64]) -> f64 {
    mean(predicted) - mean(observed)
}

/// Snow cover (depth above a threshold) predicted against observed, cell by cell.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CoverAgreement {
    /// Depth above which a cell counts as snow-covered, metres.
    pub threshold_m: f64,
    /// Covered in both.
    pub hits: usize,
    /// Observed covered, predicted bare.
    pub misses: usize,
    /// Predicted covered, observed bare.
    pub false_alarms: usize,
    /// Bare in both.
    pub correct_negatives: usize,
    /// (hits + correct negatives) / cells.
    pub accuracy: Option<f64>,
    /// hits / (hits + misses): the share of observed cover that is predicted.
    pub hit_rate: Option<f64>,
    /// false alarms / (hits + false alarms): the share of predicted cover that is not observed.
    pub false_alarm_ratio: Option<f64>,
    /// Critical success index, hits / (hits + misses + false alarms).
    pub csi: Option<f64>,
    /// Cohen's κ: agreement beyond chance, (p_o − p_e) / (1 − p_e).
    pub kappa: Option<f64>,
}

fn ratio(num: usize, den: usize) -> Option<f64> {
    (den > 0).then(|| num as f64 / den as f64)
}

impl CoverAgreement {
    /// The 2×2 table and its scores from the counts.
    pub fn from_counts(
        threshold_m: f64,
        hits: usize,
        misses: usize,
        false_alarms: usize,
        correct_negatives: usize,
    ) -> Self {
        let (a, b, c, d) = (hits, false_alarms, misses, correct_negatives);
        let n = a + b + c + d;
        let kappa = (n > 0)
            .then(|| {
                let nf = n as f64;
                let po = (a + d) as f64 / nf;
                let pe =
                    ((a + b) as f64 * (a + c) as f64 + (c + d) as f64 * (b + d) as f64) / (nf * nf);
                (pe < 1.0).then(|| (po - pe) / (1.0 - pe))
            })
            .flatten();
        Self {
            threshold_m,
            hits,
            misses,
            false_alarms,
            correct_negatives,
            accuracy: ratio(a + d, n),
            hit_rate: ratio(a, a + c),
            false_alarm_ratio: ratio(b, a + b),
            csi: ratio(a, a + b + c),
            kappa,
        }
    }

    /// Counts cover (depth > `threshold_m`) in `predicted` against `observed`.
    pub fn of(predicted: &[f64], observed: &[f64], threshold_m: f64) -> Self {
        let (mut a, mut b, mut c, mut d) = (0, 0, 0, 0);
        for (&p, &o) in predicted.iter().zip(observed) {
            match (p > threshold_m, o > threshold_m) {
                (true, true) => a += 1,
                (true, false) => b += 1,
                (false, true) => c += 1,
                (false, false) => d += 1,
            }
        }
        Self::from_counts(threshold_m, a, c, b, d)
    }
}

/// How well one prediction of depth matches the observed depth.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Metrics {
    /// Spearman's ρ with the observed depth.
    pub spearman: Option<f64>,
    /// Pearson's r with the observed depth.
    pub pearson: Option<f64>,
    /// Root-mean-square error, metres.
    pub rmse_m: f64,
    /// Mean of predicted − observed, metres.
    pub bias_m: f64,
    /// Mean predicted depth, metres.
    pub mean_m: f64,
    /// Snow-cover agreement.
    pub snow_cover: CoverAgreement,
}

impl Metrics {
    /// Every metric of `predicted` against `observed`; `rank_source` (default: `predicted`)
    /// is what Spearman's ρ ranks.
    pub fn of(
        predicted: &[f64],
        observed: &[f64],
        rank_source: Option<&[f64]>,
        threshold_m: f64,
    ) -> Self {
        Self {
            spearman: spearman(rank_source.unwrap_or(predicted), observed),
            pearson: pearson(predicted, observed),
            rmse_m: rmse(predicted, observed),
            bias_m: bias(predicted, observed),
            mean_m: mean(predicted),
            snow_cover: CoverAgreement::of(predicted, observed, threshold_m),
        }
    }
}

/// Quantile mapping: each cell gets the observed depth whose quantile is the cell's
/// quantile of `predictor`. With the average rank R (1..n) of the cell's predictor, the
/// prediction is the sorted observed values interpolated linearly at 0-based position R − 1,
/// so without ties it is a permutation of the observed values (bias 0, same distribution)
/// ordered like the predictor.
pub fn quantile_map(predictor: &[f64], observed: &[f64]) -> Vec<f64> {
    let mut sorted = observed.to_vec();
    sorted.sort_by(f64::total_cmp);
    let last = sorted.len().saturating_sub(1);
    average_ranks(predictor)
        .into_iter()
        .map(|r| {
            let q = (r - 1.0).clamp(0.0, last as f64);
            let k = q.floor() as usize;
            let f = q - k as f64;
            let hi = sorted[(k + 1).min(last)];
            sorted[k] + f * (hi - sorted[k])
        })
        .collect()
}

/// An ordinary least-squares fit y ≈ intercept + slope_a·a + slope_b·b.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LinearFit {
    pub intercept: f64,
    pub slope_a: f64,
    pub slope_b: f64,
}

impl LinearFit {
    /// Least squares on centred predictors (2×2 normal equations). A predictor without
    /// variance, or two predictors so collinear that the system is singular, is dropped
    /// (its slope set to 0) rather than fitted to noise.
    pub fn fit(a: &[f64], b: &[f64], y: &[f64]) -> Self {
        let (ma, mb, my) = (mean(a), mean(b), mean(y));
        let (mut saa, mut sbb, mut sab, mut say, mut sby) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for ((&ai, &bi), &yi) in a.iter().zip(b).zip(y) {
            let (da, db, dy) = (ai - ma, bi - mb, yi - my);
            saa += da * da;
            sbb += db * db;
            sab += da * db;
            say += da * dy;
            sby += db * dy;
        }
        let det = saa * sbb - sab * sab;
        let (slope_a, slope_b) = if saa > 0.0 && sbb > 0.0 && det > 1e-12 * saa * sbb {
            ((say * sbb - sby * sab) / det, (sby * saa - say * sab) / det)
        } else if saa > 0.0 {
            (say / saa, 0.0)
        } else if sbb > 0.0 {
            (0.0, sby / sbb)
        } else {
            (0.0, 0.0)
        };
        Self {
            intercept: my - slope_a * ma - slope_b * mb,
            slope_a,
            slope_b,
        }
    }

    /// The fitted values.
    pub fn predict(&self, a: &[f64], b: &[f64]) -> Vec<f64> {
        a.iter()
            .zip(b)
            .map(|(ai, bi)| self.intercept + self.slope_a * ai + self.slope_b * bi)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-12
    }

    #[test]
    fn ties_get_average_ranks() {
        assert_eq!(average_ranks(&[3.0, 1.0, 2.0]), vec![3.0, 1.0, 2.0]);
        assert_eq!(
            average_ranks(&[1.0, 2.0, 2.0, 3.0, 2.0]),
            vec![1.0, 3.0, 3.0, 5.0, 3.0]
        );
        assert_eq!(average_ranks(&[5.0, 5.0]), vec![1.5, 1.5]);
        assert!(average_ranks(&[]).is_empty());
    }

    #[test]
    fn spearman_with_ties_by_hand() {
        // Ranks x = [1, 2.5, 2.5, 4], y = [1, 3, 2, 4]; deviations from 2.5:
        // Σdx·dy = 4.5, Σdx² = 4.5, Σdy² = 5, so ρ = 4.5 / √22.5 = √0.9.
        let rho = spearman(&[1.0, 2.0, 2.0, 3.0], &[1.0, 3.0, 2.0, 4.0]).unwrap();
        assert!(close(rho, 0.9f64.sqrt()), "{rho}");
        // Monotone but non-linear: ρ = 1, r < 1.
        let x = [1.0, 2.0, 3.0, 4.0, 5.0];
        let y: Vec<f64> = x.iter().map(|v: &f64| v.powi(3)).collect();
        assert!(close(spearman(&x, &y).unwrap(), 1.0));
        assert!(pearson(&x, &y).unwrap() < 0.99);
        // Reversed order: ρ = -1.
        assert!(close(
            spearman(&x, &[9.0, 7.0, 5.0, 3.0, 1.0]).unwrap(),
            -1.0
        ));
        assert_eq!(spearman(&x, &[1.0; 5]), None);
    }

    #[test]
    fn pearson_by_hand() {
        // Deviations dx = [-2,-1,0,1,2], dy = [-2,0,1,0,1]: Σdx·dy = 6, Σdx² = 10, Σdy² = 6.
        let r = pearson(&[1.0, 2.0, 3.0, 4.0, 5.0], &[2.0, 4.0, 5.0, 4.0, 5.0]).unwrap();
        assert!(close(r, 0.6f64.sqrt()), "{r}");
        assert_eq!(pearson(&[1.0], &[2.0]), None);
        assert_eq!(pearson(&[1.0, 1.0], &[2.0, 3.0]), None);
    }

    #[test]
    fn errors_by_hand() {
        let p = [1.0, 2.0, 4.0];
        let o = [1.0, 1.0, 1.0];
        // Differences 0, 1, 3: RMSE √(10/3), bias 4/3.
        assert!(close(rmse(&p, &o), (10.0f64 / 3.0).sqrt()));
        assert!(close(bias(&p, &o), 4.0 / 3.0));
    }

    #[test]
    fn cover_scores_and_kappa_by_hand() {
        // a = 20 hits, b = 5 false alarms, c = 10 misses, d = 15 correct negatives, n = 50:
        // p_o = 35/50 = 0.7, p_e = (25·30 + 25·20) / 2500 = 0.5, κ = 0.2 / 0.5 = 0.4.
        let t = CoverAgreement::from_counts(0.05, 20, 10, 5, 15);
        assert!(close(t.kappa.unwrap(), 0.4));
        assert!(close(t.accuracy.unwrap(), 0.7));
        assert!(close(t.hit_rate.unwrap(), 20.0 / 30.0));
        assert!(close(t.false_alarm_ratio.unwrap(), 0.2));
        assert!(close(t.csi.unwrap(), 20.0 / 35.0));
        // Counting from depths: strictly above the threshold is cover.
        let t = CoverAgreement::of(&[0.0, 0.06, 0.05, 1.0], &[0.1, 0.0, 0.0, 2.0], 0.05);
        assert_eq!(
            (t.hits, t.misses, t.false_alarms, t.correct_negatives),
            (1, 1, 1, 1)
        );
        // All cells agree and are covered: κ is undefined (p_e = 1), the rest is perfect.
        let t = CoverAgreement::from_counts(0.05, 7, 0, 0, 0);
        assert_eq!(
            (t.kappa, t.accuracy, t.false_alarm_ratio),
            (None, Some(1.0), Some(0.0))
        );
    }

    #[test]
    fn quantile_mapping_orders_the_observed_values_by_the_predictor() {
        let q = quantile_map(&[10.0, 30.0, 20.0, 40.0], &[0.4, 0.1, 0.3, 0.2]);
        assert_eq!(q, vec![0.1, 0.3, 0.2, 0.4]);
        // Tied predictors share the interpolated quantile: ranks 1.5, 1.5, 3, 4.
        let q = quantile_map(&[10.0, 10.0, 20.0, 30.0], &[0.4, 0.1, 0.3, 0.2]);
        for (a, b) in q.iter().zip([0.15, 0.15, 0.3, 0.4]) {
            assert!(close(*a, b), "{q:?}");
        }
    }

    #[test]
    fn least_squares_recovers_a_plane_and_drops_a_constant_predictor() {
        let a = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let b = [0.5, -0.2, 0.9, 0.1, -0.7, 0.3];
        let y: Vec<f64> = a
            .iter()
            .zip(&b)
            .map(|(a, b)| 1.0 + 2.0 * a - 3.0 * b)
            .collect();
        let fit = LinearFit::fit(&a, &b, &y);
        assert!(close(fit.intercept, 1.0) && close(fit.slope_a, 2.0) && close(fit.slope_b, -3.0));
        assert!(close(rmse(&fit.predict(&a, &b), &y), 0.0));
        let fit = LinearFit::fit(&a, &[0.0; 6], &y);
        assert_eq!(fit.slope_b, 0.0);
        assert!(close(fit.intercept + fit.slope_a * 3.5, mean(&y)));
    }
}
