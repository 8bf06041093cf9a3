//! Statistics of repeated timings, all distribution-free (frame times on a shared CPU are
//! skewed and have outliers): the median with an order-statistic confidence interval, and the
//! shift between two samples with the Mann–Whitney (Moses) interval.

use serde::{Deserialize, Serialize};

/// Every sample of one quantity, and its summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub samples: Vec<f64>,
    pub median: f64,
    pub min: f64,
    pub max: f64,
    /// Interval for the median: [x_(k), x_(n+1−k)] with the widest k whose coverage is at
    /// least 95%, or [min, max] when n is too small for 95% (then `ci_level` says how sure).
    pub ci_low: f64,
    pub ci_high: f64,
    pub ci_level: f64,
}

impl Summary {
    /// Summarizes `samples`; `None` when there are none.
    pub fn new(samples: Vec<f64>) -> Option<Summary> {
        if samples.is_empty() {
            return None;
        }
        let mut sorted = samples.clone();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        let median = if n % 2 == 1 { sorted[n / 2] } else { (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0 };
        let (k, level) = median_interval_rank(n);
        Some(Summary {
            median,
            min: sorted[0],
            max: sorted[n - 1],
            ci_low: sorted[k - 1],
            ci_high: sorted[n - k],
            ci_level: level,
            samples,
        })
    }
}

/// The 1-based rank k of the median's interval [x_(k), x_(n+1−k)] and its coverage
/// 1 − 2·P(B ≤ k−1), B ~ Binomial(n, ½): the largest k with coverage ≥ 95%, else k = 1.
pub fn median_interval_rank(n: usize) -> (usize, f64) {
    let coverage = |k: usize| 1.0 - 2.0 * binomial_half_cdf(n, k - 1);
    let mut best = (1, coverage(1));
    for k in 2..=n.div_ceil(2) {
        let level = coverage(k);
        if level < 0.95 {
            break;
        }
        best = (k, level);
    }
    best
}

/// P(B ≤ j) for B ~ Binomial(n, ½), in f64 (n here is a handful of repetitions).
fn binomial_half_cdf(n: usize, j: usize) -> f64 {
    let mut term = 0.5f64.powi(n as i32); // C(n, 0) / 2^n
    let mut sum = term;
    for i in 1..=j {
        term *= (n + 1 - i) as f64 / i as f64;
        sum += term;
    }
    sum
}

/// The shift of one sample against another: the Hodges–Lehmann estimate (the median of all
/// pairwise differences `current − baseline`) with the distribution-free Moses interval
/// [D₍ₖ₎, D₍ₙₘ₊₁₋ₖ₎] from the Mann–Whitney U distribution. On log times it estimates the
/// log of the ratio "current / baseline": robust like the median, nearly as efficient as the
/// mean on normal noise (95%), which on these machines' noise is worth about a third fewer
/// repetitions than a difference of medians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shift {
    pub estimate: f64,
    pub low: f64,
    pub high: f64,
    /// The interval's coverage: `level` asked for, or less when the samples are too few.
    pub level: f64,
}

impl Shift {
    /// `None` when either sample is empty.
    pub fn between(current: &[f64], baseline: &[f64], level: f64) -> Option<Shift> {
        let (n, m) = (current.len(), baseline.len());
        if n == 0 || m == 0 {
            return None;
        }
        let mut differences: Vec<f64> =
            current.iter().flat_map(|x| baseline.iter().map(move |y| x - y)).collect();
        differences.sort_by(f64::total_cmp);
        let nm = differences.len();
        let estimate = if nm % 2 == 1 {
            differences[nm / 2]
        } else {
            (differences[nm / 2 - 1] + differences[nm / 2]) / 2.0
        };
        // k: the largest rank with P(U ≤ k − 1) ≤ (1 − level) / 2; the coverage is then
        // 1 − 2·P(U ≤ k − 1). Too few samples for `level`: k = 1, with its true coverage.
        let cdf = mann_whitney_cdf(n, m);
        let tail = (1.0 - level) / 2.0;
        let k = (1..=nm.div_ceil(2)).take_while(|&k| cdf[k - 1] <= tail).last().unwrap_or(1);
        Some(Shift {
            estimate,
            low: differences[k - 1],
            high: differences[nm - k],
            level: 1.0 - 2.0 * cdf[k - 1],
        })
    }
}

/// P(U ≤ u) for u = 0…n·m, U the Mann–Whitney statistic of samples of sizes n and m under the
/// null hypothesis. The counts are the coefficients of the Gaussian binomial
/// [n+m choose n]_q = ∏ᵢ₌₁ⁿ (1 − q^(m+i)) / (1 − q^i), built factor by factor; after each one
/// the polynomial is [m+i choose i]_q, whose coefficients are positive.
fn mann_whitney_cdf(n: usize, m: usize) -> Vec<f64> {
    let degree = n * m;
    let mut counts = vec![0.0f64; degree + 1];
    counts[0] = 1.0;
    for i in 1..=n {
        let up = m + i;
        for u in (up..=degree).rev() {
            counts[u] -= counts[u - up];
        }
        for u in i..=degree {
            counts[u] += counts[u - i];
        }
    }
    let total: f64 = counts.iter().sum();
    let mut cumulative = 0.0;
    counts
        .iter()
        .map(|count| {
            cumulative += count;
            (cumulative / total).min(1.0)
        })
        .collect()
}

/// Frame times of one process's modes, round by round: what the in-run time ratios are taken
/// from, in a run's record and in a baseline's.
pub trait Rounds {
    /// Mode `id`'s frame times in milliseconds, one a round.
    fn frames(&self, id: &str) -> Option<&[f64]>;

    /// Round-by-round ratios of `mode`'s frame time to `anchor`'s. Every round renders each
    /// mode once, so round i of both ran moments apart and share the machine's state.
    fn paired_ratios(&self, mode: &str, anchor: &str) -> Option<Vec<f64>> {
        let (own, base) = (self.frames(mode)?, self.frames(anchor)?);
        let ratios: Vec<f64> = own.iter().zip(base).map(|(a, b)| a / b).collect();
        (!ratios.is_empty()).then_some(ratios)
    }

    /// Per round, the log of the geometric mean frame time of `anchors` other than `mode`
    /// itself (a mode is not measured against itself): an anchor that averages the machine's
    /// momentary speed over several modes of the round. Rounds where any of them has no sample
    /// are left out; `None` if no anchor mode or no round remains.
    fn round_anchor(&self, anchors: &[&str], mode: &str) -> Option<Vec<f64>> {
        let samples: Vec<&[f64]> =
            anchors.iter().filter(|id| **id != mode).map(|id| self.frames(id)).collect::<Option<_>>()?;
        let rounds = samples.iter().map(|s| s.len()).min()?;
        let means: Vec<f64> = (0..rounds)
            .map(|i| samples.iter().map(|s| s[i].ln()).sum::<f64>() / samples.len() as f64)
            .collect();
        (!means.is_empty()).then_some(means)
    }
}

/// Spearman's rank correlation of two paired samples, ties ranked by their mean rank; `None`
/// for fewer than three pairs or a sample without spread.
pub fn spearman(a: &[f64], b: &[f64]) -> Option<f64> {
    if a.len() != b.len() || a.len() < 3 {
        return None;
    }
    let (ra, rb) = (ranks(a), ranks(b));
    let mean = (a.len() as f64 + 1.0) / 2.0;
    let (mut covariance, mut var_a, mut var_b) = (0.0, 0.0, 0.0);
    for (x, y) in ra.iter().zip(&rb) {
        covariance += (x - mean) * (y - mean);
        var_a += (x - mean).powi(2);
        var_b += (y - mean).powi(2);
    }
    (var_a > 0.0 && var_b > 0.0).then(|| covariance / (var_a * var_b).sqrt())
}

/// Each value's 1-based rank, ties given their mean rank.
fn ranks(values: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&i, &j| values[i].total_cmp(&values[j]));
    let mut ranks = vec![0.0; values.len()];
    let mut start = 0;
    while start < order.len() {
        // Ties by `total_cmp`, so that a NaN ties with itself and the loop always moves on.
        let first = values[order[start]];
        let tied = order[start..].iter().take_while(|&&i| values[i].total_cmp(&first).is_eq()).count();
        let rank = start as f64 + (tied as f64 + 1.0) / 2.0;
        for &i in &order[start..start + tied] {
            ranks[i] = rank;
        }
        start += tied;
    }
    ranks
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mann_whitney_distribution_matches_small_cases() {
        // n = m = 3: C(6, 3) = 20 orderings, one with U = 0, one with U = 1, two with U = 2.
        let cdf = mann_whitney_cdf(3, 3);
        assert_eq!(cdf.len(), 10);
        assert!((cdf[0] - 1.0 / 20.0).abs() < 1e-15);
        assert!((cdf[1] - 2.0 / 20.0).abs() < 1e-15);
        assert!((cdf[2] - 4.0 / 20.0).abs() < 1e-15);
        assert_eq!(cdf[9], 1.0);
        // Symmetric: P(U ≤ u) = 1 − P(U ≤ nm − u − 1).
        let cdf = mann_whitney_cdf(25, 30);
        for u in 0..cdf.len() - 1 {
            assert!((cdf[u] - (1.0 - cdf[cdf.len() - 2 - u])).abs() < 1e-9, "{u}");
        }
        // Tabulated critical value: n = m = 10, two-sided 5% → U ≤ 23.
        let cdf = mann_whitney_cdf(10, 10);
        assert!(cdf[23] <= 0.025 && cdf[24] > 0.025, "{} {}", cdf[23], cdf[24]);
    }

    #[test]
    fn the_shift_of_a_shifted_sample_is_found_with_an_interval_around_it() {
        let base: Vec<f64> = (0..20).map(|i| f64::from(i % 7) * 0.01).collect();
        let moved: Vec<f64> = base.iter().map(|x| x + 0.25).collect();
        let shift = Shift::between(&moved, &base, 0.95).unwrap();
        assert!((shift.estimate - 0.25).abs() < 1e-12);
        assert!(shift.low < 0.25 && shift.high > 0.25 && shift.low > 0.18, "{shift:?}");
        assert!(shift.level >= 0.95);
        let same = Shift::between(&base, &base, 0.95).unwrap();
        assert!(same.low <= 0.0 && same.high >= 0.0 && same.estimate == 0.0);
        // Three against three cannot reach 95%: the full range, at 90%.
        let few = Shift::between(&[1.0, 2.0, 3.0], &[0.0, 0.5, 1.0], 0.95).unwrap();
        assert_eq!((few.low, few.high), (0.0, 3.0));
        assert!((few.level - 0.9).abs() < 1e-12);
        assert!(Shift::between(&[], &[1.0], 0.95).is_none());
    }

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(Summary::new(vec![3.0, 1.0, 2.0]).unwrap().median, 2.0);
        assert_eq!(Summary::new(vec![4.0, 1.0, 2.0, 3.0]).unwrap().median, 2.5);
        assert!(Summary::new(vec![]).is_none());
    }

    #[test]
    fn small_samples_fall_back_to_the_range_with_its_true_level() {
        let (k, level) = median_interval_rank(5);
        assert_eq!(k, 1);
        assert!((level - (1.0 - 2.0 / 32.0)).abs() < 1e-12);
    }

    #[test]
    fn intervals_match_tabulated_order_statistics() {
        // n = 9: [x_(2), x_(8)] covers 96.1%; n = 20: [x_(6), x_(15)] covers 95.9%.
        let (k, level) = median_interval_rank(9);
        assert_eq!(k, 2);
        assert!((level - 0.9609).abs() < 1e-4);
        let (k, level) = median_interval_rank(20);
        assert_eq!(k, 6);
        assert!((level - 0.9586).abs() < 1e-4);
    }

    #[test]
    fn samples_are_kept_in_their_order() {
        let summary = Summary::new(vec![5.0, 1.0, 9.0, 7.0, 3.0, 2.0, 8.0]).unwrap();
        assert_eq!(summary.samples, vec![5.0, 1.0, 9.0, 7.0, 3.0, 2.0, 8.0]);
        assert_eq!((summary.min, summary.median, summary.max), (1.0, 5.0, 9.0));
        assert_eq!((summary.ci_low, summary.ci_high), (1.0, 9.0));
    }

    #[test]
    fn spearman_is_one_for_the_same_order_minus_one_reversed_and_averages_ties() {
        let a = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(spearman(&a, &[10.0, 20.0, 30.0, 40.0]), Some(1.0));
        assert_eq!(spearman(&a, &[4.0, 3.0, 2.0, 1.0]), Some(-1.0));
        assert_eq!(ranks(&[5.0, 1.0, 5.0, 3.0]), vec![3.5, 1.0, 3.5, 2.0]);
        // The textbook case: d = (0, 0, 1, −1, 0) gives 1 − 6·2 / (5·24) = 0.9.
        let rho = spearman(&[1.0, 2.0, 3.0, 4.0, 5.0], &[1.0, 2.0, 4.0, 3.0, 5.0]).unwrap();
        assert!((rho - 0.9).abs() < 1e-12, "{rho}");
        assert_eq!(spearman(&a, &[1.0; 4]), None, "no spread, no correlation");
        assert_eq!(spearman(&a[..2], &a[..2]), None);
        // Identical images have an infinite PSNR, which ranks like any value; a NaN ends too.
        assert_eq!(spearman(&a, &[1.0, 2.0, 3.0, f64::INFINITY]), Some(1.0));
        assert_eq!(ranks(&[f64::NAN, 1.0, f64::NAN]), vec![2.5, 1.0, 2.5]);
    }
}
