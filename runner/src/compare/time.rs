//! Time against the committed baselines: ratios measured inside one run (each mode over the
//! round's other unstalled modes, adaptive over its reference) and, on the baseline's own
//! platform, absolute frame times, each decided on the interval of its shift.

use super::mode::{ModeContext, show_percent};
use super::verdict::{CONFIDENCE, Check, MIN_FRAMES, Outcome};
use crate::measure::stats::{Rounds, Shift};
use crate::record::vocabulary::TimeMetric;

impl ModeContext<'_> {
    pub(super) fn time_checks(&self) -> Vec<Check> {
        let mut checks = Vec::new();
        let threshold = self.tolerances.time_ratio;
        let id = self.mode.mode.as_str();
        // The mode's frame samples in each process of the run and each blessed process.
        let (Some(now), Some(then)) = (frames(self.processes, id), frames(self.blessed, id)) else {
            return checks;
        };
        if let (Some(now_anchors), Some(then_anchors)) =
            (anchors(self.processes, self.anchor_modes, id), anchors(self.blessed, self.anchor_modes, id))
        {
            let relative = |samples: &[f64], anchor: &[f64]| -> Vec<f64> {
                samples.iter().zip(anchor).map(|(s, a)| s.ln() - a).collect()
            };
            let relatives = |samples: &[Vec<f64>], anchors: &[Vec<f64>]| -> Vec<Vec<f64>> {
                samples.iter().zip(anchors).map(|(s, a)| relative(s, a)).collect()
            };
            checks.extend(self.time_check(
                TimeMetric::Relative.id(),
                &relatives(&now, &now_anchors).concat(),
                &relatives(&then, &then_anchors),
                threshold,
                "frame time over the geometric mean of the round's other unstalled modes",
                "×",
            ));
        }
        if let Some(cost) = &self.mode.adaptive {
            checks.extend(self.ratio_check(TimeMetric::VsReference.id(), &cost.reference, threshold));
        }
        if self.same_platform {
            let log = |samples: &Vec<f64>| samples.iter().map(|s| s.ln()).collect::<Vec<_>>();
            let now_log: Vec<f64> = now.iter().flat_map(log).collect();
            checks.extend(self.time_check(
                TimeMetric::Frame.id(),
                &now_log,
                &then.iter().map(log).collect::<Vec<_>>(),
                self.tolerances.absolute_time,
                "absolute frame time (wide threshold: processes drift)",
                "ms",
            ));
        }
        checks
    }

    /// The ratio of this mode's frame time to `anchor`'s, round by round, against the
    /// baseline's.
    fn ratio_check(&self, metric: &str, anchor: &str, threshold: f64) -> Option<Check> {
        let (id, log) = (self.mode.mode.as_str(), |ratios: Vec<f64>| ratios.iter().map(|r| r.ln()).collect());
        let now: Vec<Vec<f64>> = self
            .processes
            .iter()
            .map(|record| record.paired_ratios(id, anchor).map(log))
            .collect::<Option<_>>()?;
        let then: Vec<Vec<f64>> = self
            .blessed
            .iter()
            .map(|record| record.paired_ratios(id, anchor).map(log))
            .collect::<Option<_>>()?;
        self.time_check(
            metric,
            &now.concat(),
            &then,
            threshold,
            &format!("frame time over {anchor}'s in the same round"),
            "×",
        )
    }

    /// Decides a time metric from log samples (the baseline's per process): the
    /// Hodges–Lehmann shift with its Moses interval, as relative changes, against the
    /// threshold widened by how far the baseline's own processes disagree ([`process_spread`]).
    /// Fewer than [`MIN_FRAMES`] samples on either side is `insufficient`.
    fn time_check(
        &self,
        metric: &str,
        now: &[f64],
        then_per_process: &[Vec<f64>],
        threshold: f64,
        what: &str,
        unit: &str,
    ) -> Option<Check> {
        let then = then_per_process.concat();
        let values = (median_exp(&then), median_exp(now));
        if now.len() < MIN_FRAMES || then.len() < MIN_FRAMES {
            let value = |v: f64| show_time(v, unit);
            return Some(Check {
                baseline: Some(values.0),
                current: Some(values.1),
                ..self.check(
                    metric,
                    Outcome::Insufficient,
                    "relative",
                    format!(
                        "{what}: {} → {}; {} frames in the run and {} in the baseline, fewer than the {MIN_FRAMES} a time verdict needs",
                        value(values.0),
                        value(values.1),
                        now.len(),
                        then.len()
                    ),
                )
            });
        }
        let shift = Shift::between(now, &then, CONFIDENCE)?;
        // Widened by at most the tolerance itself: a 25% slowdown stays caught under the
        // default 10% however much one blessed process strayed.
        let tolerance = (1.0 + threshold).ln();
        let spread = process_spread(then_per_process).min(tolerance);
        let widening = (spread > 0.0).then(|| {
            format!(
                ": the tolerance {} widened by the baseline processes' own spread, {}",
                show_percent(threshold),
                show_percent(spread.exp() - 1.0)
            )
        });
        let decided =
            decide(shift, tolerance + spread, values, unit, what, widening.as_deref().unwrap_or(""));
        Some(decided.into_check(self.check(metric, Outcome::Unchanged, "relative", String::new())))
    }
}

/// A time shift decided against a bound: its outcome and the numbers that go into a check.
pub(super) struct Decided {
    pub(super) outcome: Outcome,
    pub(super) values: (f64, f64),
    pub(super) change: f64,
    pub(super) interval: [f64; 2],
    pub(super) bound: f64,
    pub(super) detail: String,
}

impl Decided {
    /// `template` with this decision's outcome, numbers and detail.
    pub(super) fn into_check(self, template: Check) -> Check {
        Check {
            outcome: self.outcome,
            baseline: Some(self.values.0),
            current: Some(self.values.1),
            change: Some(self.change),
            interval: Some(self.interval),
            threshold: Some(self.bound.exp() - 1.0),
            detail: self.detail,
            ..template
        }
    }
}

/// Regressed when the whole interval of `shift` (in log) is past `bound`, improved when it is
/// wholly below `-bound`, noisy when only the estimate is past either, else unchanged.
/// `values` are the two sides' medians for the detail, `extra` ends its threshold clause.
pub(super) fn decide(
    shift: Shift,
    bound: f64,
    values: (f64, f64),
    unit: &str,
    what: &str,
    extra: &str,
) -> Decided {
    let outcome = if shift.low > bound {
        Outcome::Regressed
    } else if shift.high < -bound {
        Outcome::Improved
    } else if shift.estimate.abs() > bound {
        Outcome::Noisy
    } else {
        Outcome::Unchanged
    };
    let relative = |log: f64| log.exp() - 1.0;
    let (change, low, high) = (relative(shift.estimate), relative(shift.low), relative(shift.high));
    let detail = format!(
        "{what}: {} → {} ({}, {:.0}% interval {} … {}; thresholds {} and {}{extra})",
        show_time(values.0, unit),
        show_time(values.1, unit),
        show_percent(change),
        shift.level * 100.0,
        show_percent(low),
        show_percent(high),
        show_percent(relative(-bound)),
        show_percent(relative(bound)),
    );
    Decided { outcome, values, change, interval: [low, high], bound, detail }
}

/// A time for people: milliseconds, or a ratio with its unit (`×`).
fn show_time(value: f64, unit: &str) -> String {
    if unit == "ms" { format!("{value:.1} ms") } else { format!("{value:.3}{unit}") }
}

/// How far the baseline's processes disagree with one another: the largest distance (in log)
/// of one process's median from the pooled median; 0 for a baseline of one process. Frames of
/// one process vary less than processes do (a stalled mode's ratio moved 2.31–2.57× across the
/// three blessed processes of one build), and the shift's interval only covers the former: a
/// shift within this spread is no evidence of a change. The caller caps it, so that one
/// disturbed blessed process cannot switch a mode's time gate off.
pub(super) fn process_spread(per_process: &[Vec<f64>]) -> f64 {
    let median = |logs: &[f64]| crate::measure::stats::Summary::new(logs.to_vec()).map(|s| s.median);
    match (per_process.len(), median(&per_process.concat())) {
        (2.., Some(pooled)) => {
            per_process.iter().filter_map(|p| median(p)).map(|m| (m - pooled).abs()).fold(0.0, f64::max)
        }
        _ => 0.0,
    }
}

/// exp of the median of log values: the median ratio.
fn median_exp(logs: &[f64]) -> f64 {
    crate::measure::stats::Summary::new(logs.to_vec()).map_or(f64::NAN, |s| s.median.exp())
}

/// Mode `id`'s frame times in each of `processes`, where every one has them.
fn frames<R: Rounds>(processes: &[R], id: &str) -> Option<Vec<Vec<f64>>> {
    processes.iter().map(|process| process.frames(id).map(<[f64]>::to_vec)).collect()
}

/// Each of `processes`' round anchors for mode `id` (see [`Rounds::round_anchor`]).
fn anchors<R: Rounds>(processes: &[R], modes: &[&str], id: &str) -> Option<Vec<Vec<f64>>> {
    processes.iter().map(|process| process.round_anchor(modes, id)).collect()
}
