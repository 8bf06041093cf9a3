//! What a gate could have caught: for each time it decides (a mode's frame against the round's
//! other modes, adaptive against its reference, the absolute frame, each pass), the smallest
//! slowdown that its intervals would have called a regression. A green gate says how green, so a
//! reviewer knows what "no regression" rules out.
//!
//! A time check is regressed when the lower end of its shift's interval (in log time) lies past
//! its bound. A true slowdown `d` moves the whole interval by `d`, so it is caught once
//! `d − (estimate − low) > bound`: the smallest slowdown caught is the bound plus the part of
//! the interval below the estimate. Each check has its own; the summary gives their median over
//! the scenes and modes, and the largest, the least sensitive check's.

use std::collections::BTreeMap;

use super::pooled::ALL_SCENES;
use super::verdict::{Against, Check, Outcome, is_time_metric};
use crate::record::vocabulary::TimeMetric;

/// The smallest slowdown a time check would have caught, as a relative change (0.18: 18 %
/// slower); none for a check without an interval (too few frames).
fn smallest_caught(check: &Check) -> Option<f64> {
    let ([low, _], change, threshold) = (check.interval?, check.change?, check.threshold?);
    let below = (1.0 + change).ln() - (1.0 + low).ln();
    Some(((1.0 + threshold).ln() + below).exp() - 1.0)
}

/// What a group of time checks measures, for people: `frame time over the round's other
/// modes`, `pass shade`.
fn what(metric: &str) -> String {
    match TimeMetric::of(metric) {
        Some(TimeMetric::Relative) => "frame over the round's other modes".into(),
        Some(TimeMetric::VsReference) => "adaptive over its reference".into(),
        Some(TimeMetric::Frame) => "absolute frame".into(),
        Some(TimeMetric::Pass) => format!("pass {}", &metric[TimeMetric::Pass.id().len()..]),
        None => metric.into(),
    }
}

/// One line per time the verdict decided, against the baselines or the base build, per scene or
/// pooled over the scenes: `frame over the round's other modes, against the baselines: +14.2 %
/// (median of 493), +31.0 % at most`; a pooled line's count is of modes.
pub fn lines(checks: &[Check]) -> Vec<String> {
    let mut groups: BTreeMap<(bool, String, bool), Vec<f64>> = BTreeMap::new();
    let timed = checks.iter().filter(|c| is_time_metric(&c.metric) && c.outcome != Outcome::Insufficient);
    for check in timed {
        let Some(smallest) = smallest_caught(check) else { continue };
        let pooled = check.scene == ALL_SCENES;
        let group = (check.against == Against::Base, check.metric.clone(), pooled);
        groups.entry(group).or_default().push(smallest);
    }
    groups
        .into_iter()
        .map(|((base, metric, pooled), mut caught)| {
            caught.sort_by(f64::total_cmp);
            let n = caught.len();
            let median = if n % 2 == 1 { caught[n / 2] } else { (caught[n / 2 - 1] + caught[n / 2]) / 2.0 };
            let against = if base { "the base build" } else { "the baselines" };
            let over = if pooled { " pooled over the scenes" } else { "" };
            format!(
                "{}{over}, against {against}: {:+.1} % (median of {n}), {:+.1} % at most",
                what(&metric),
                median * 100.0,
                caught[n - 1] * 100.0
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn timed(metric: &str, change: f64, interval: [f64; 2], threshold: f64) -> Check {
        Check {
            change: Some(change),
            interval: Some(interval),
            threshold: Some(threshold),
            ..Check::new("s", "fxaa", metric, Outcome::Unchanged, String::new())
        }
    }

    #[test]
    fn the_smallest_slowdown_caught_is_the_bound_plus_the_interval_below_the_estimate() {
        // No shift, an interval 5 % either way in log, a 10 % bound: 15.5 % slower is caught.
        let (down, up) = ((-0.05f64).exp() - 1.0, 0.05f64.exp() - 1.0);
        let check = timed("pass_time:fxaa", 0.0, [down, up], 0.1);
        let caught = smallest_caught(&check).unwrap();
        assert!((caught - (1.1f64.ln() + 0.05).exp() + 1.0).abs() < 1e-12, "{caught}");
        // A wider interval needs a larger slowdown; where the estimate sits does not matter.
        let wide = timed("pass_time:fxaa", 0.3, [0.1, 0.5], 0.1);
        assert!(smallest_caught(&wide).unwrap() > caught);
        let moved = timed("pass_time:fxaa", 0.2, [(1.2 * (-0.05f64).exp()) - 1.0, 0.3], 0.1);
        assert!((smallest_caught(&moved).unwrap() - caught).abs() < 1e-12);
    }

    #[test]
    fn each_time_gets_its_median_and_its_least_sensitive_check() {
        let checks = vec![
            timed("relative_time", 0.0, [-0.1, 0.1], 0.1),
            timed("relative_time", 0.0, [-0.2, 0.2], 0.1),
            timed("relative_time", 0.0, [-0.05, 0.05], 0.1),
            Check { against: Against::Base, ..timed("pass_time:fxaa", 0.0, [-0.1, 0.1], 0.1) },
            // Too few frames: no interval, no line.
            Check::new("s", "taa", "frame_time", Outcome::Insufficient, String::new()),
            Check::new("s", "taa", "psnr_vs_truth", Outcome::Unchanged, String::new()),
        ];
        let lines = lines(&checks);
        assert_eq!(lines.len(), 2, "{lines:?}");
        assert!(
            lines[0].starts_with("frame over the round's other modes, against the baselines: +"),
            "{lines:?}"
        );
        assert!(lines[0].contains("(median of 3)"), "{lines:?}");
        assert!(lines[1].starts_with("pass fxaa, against the base build: +"), "{lines:?}");
        let widest = smallest_caught(&checks[1]).unwrap() * 100.0;
        assert!(lines[0].ends_with(&format!("{widest:+.1} % at most")), "{lines:?}");
    }
}
