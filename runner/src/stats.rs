//! Summaries of repeated timings: median with a distribution-free confidence interval from
//! order statistics (no normality assumed: frame times on a shared CPU are skewed).

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

#[cfg(test)]
mod tests {
    use super::*;

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
}
