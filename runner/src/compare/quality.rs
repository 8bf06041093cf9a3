//! Quality against the committed baselines: every gated metric of [`METRICS`] number to number
//! within its tolerance, the shape of the sample-count distribution, and the output hash
//! (failed for the paper's mode, reported for the others: their metrics decide whether a changed image matters).

use super::mode::{ModeContext, show_percent};
use super::verdict::{Check, Outcome};
use crate::manifest::tolerances::{QualityTolerances, Tolerance};
use crate::record::vocabulary::{Gate, METRICS, Metric, Rule, Source};

impl ModeContext<'_> {
    /// The mode's quality checks, metric by metric in the table's order, then the sample
    /// histogram and the output hash. A part of the record the baseline has and the run lacks
    /// fails one check; the sequence is compared only where the run rendered the scene's (a run
    /// without it is one missing check of the scene, `compare_scene`).
    pub(super) fn quality_checks(&self) -> Vec<Check> {
        let tolerance = self.tolerances.quality(self.same_platform);
        let mut checks = Vec::new();
        let mut lacking = Vec::new();
        for metric in &METRICS {
            let Some(gate) = metric.gate else { continue };
            let source = metric.source;
            if (source == Source::Sequence && self.scene.sequence().is_none()) || !self.old.has(source) {
                continue;
            }
            if !source.present(self.mode) {
                if !lacking.contains(&source) {
                    lacking.push(source);
                    let (id, detail) = source.missing();
                    checks.push(self.check(id, Outcome::Failed, gate.rule.unit(), detail.into()));
                }
                continue;
            }
            checks.extend(self.metric_check(metric, gate, &tolerance));
        }
        checks.extend(self.histogram_check(&tolerance));
        checks.extend(self.hash_check());
        checks
    }

    /// One metric where the baseline has it: moved beyond its tolerance or not. A run that
    /// lacks it fails it.
    fn metric_check(&self, metric: &Metric, gate: Gate, tolerance: &QualityTolerances) -> Option<Check> {
        let (now, then) = match (metric.value(self.mode), self.old.value(metric)) {
            (Some(now), Some(then)) => (now, then),
            (None, Some(_)) => {
                let detail = format!("the baseline has {}, the run has none", metric.label);
                return Some(self.check(metric.id, Outcome::Failed, gate.rule.unit(), detail));
            }
            _ => return None,
        };
        let threshold = gate.threshold(tolerance);
        let (change, moved) = match gate.rule {
            Rule::Level { unit } => {
                // Two infinities (identical images both times) are no change.
                let change = if now == then { 0.0 } else { now - then };
                let moved = if change.is_finite() {
                    format!("{change:+.3} {unit}")
                } else {
                    format!("{change} {unit}")
                };
                (change, moved)
            }
            Rule::Relative { perfect } => {
                let change = relative_change((now - perfect).abs(), (then - perfect).abs());
                (change, format!("{} of its error", show_percent(change)))
            }
            Rule::Points => (now - then, format!("{:+.2} points", now - then)),
        };
        let outcome = beyond(change, threshold, gate.rule.higher_is_better());
        let shown_tolerance = match gate.rule {
            Rule::Level { unit } => format!("±{threshold} {unit}"),
            Rule::Relative { .. } => format!("±{:.1}%", threshold * 100.0),
            Rule::Points => format!("±{threshold}"),
        };
        let label = match metric.source.against(self.mode) {
            Some(against) => format!("{} ({against})", metric.label),
            None => metric.label.to_string(),
        };
        let detail = format!(
            "{label} {} → {} ({moved}; tolerance {shown_tolerance})",
            (gate.show)(then),
            (gate.show)(now)
        );
        Some(Check {
            baseline: Some(then).filter(|v| v.is_finite()),
            current: Some(now).filter(|v| v.is_finite()),
            change: Some(change).filter(|v| v.is_finite()),
            threshold: Some(threshold),
            ..self.check(metric.id, outcome, gate.rule.unit(), detail)
        })
    }

    /// How far the distribution of samples per pixel moved: total variation against its
    /// tolerance.
    fn histogram_check(&self, tolerance: &QualityTolerances) -> Option<Check> {
        let (now, then) = (self.mode.samples.as_ref()?, self.old.samples.as_ref()?);
        let distance = total_variation(&now.histogram, &then.histogram);
        let threshold = tolerance.get(Tolerance::Histogram);
        let outcome = if distance > threshold { Outcome::Regressed } else { Outcome::Unchanged };
        let detail = format!(
            "the distribution of samples per pixel moved by {distance:.4} (total variation; tolerance {threshold})"
        );
        Some(Check {
            change: Some(distance),
            threshold: Some(threshold),
            ..self.check("sample_histogram", outcome, "total variation", detail)
        })
    }

    /// A changed output hash: the paper's mode (`adaptive-MxM`, plain or stalled) must render
    /// its blessed bits on their platform, so that a change to the method under study is never
    /// waved through by tolerances (a change that is meant is blessed with `--why`); every other
    /// mode's is reported, and its metrics decide.
    fn hash_check(&self) -> Option<Check> {
        let (now, then) = (self.mode.output_hash.as_ref()?, self.old.output_hash.as_ref()?);
        if now == then {
            return None;
        }
        Some(if self.mode.is_paper() && self.same_platform {
            let detail = format!(
                "the paper's mode renders other bits than its baseline ({then} → {now}): a change to the method \
                 under study fails the gate; if it is meant, bless it with `aabench bless --why`"
            );
            self.check("output_hash", Outcome::Failed, "", detail)
        } else {
            let detail =
                format!("the output changed ({then} → {now}); the metrics decide whether it matters");
            self.check("output_hash", Outcome::Unchanged, "", detail)
        })
    }
}

/// An error's change over its baseline value, as a fraction: 0 when unchanged (two zeros
/// included), infinite from an error of zero.
fn relative_change(now: f64, then: f64) -> f64 {
    match (now, then) {
        (a, b) if a == b => 0.0,
        (_, 0.0) => f64::INFINITY,
        (a, b) => (a - b) / b,
    }
}

/// Improved or regressed when `change` is past `tolerance`; `higher_is_better` says which way
/// is which.
fn beyond(change: f64, tolerance: f64, higher_is_better: bool) -> Outcome {
    let better = if higher_is_better { change } else { -change };
    if better > tolerance {
        Outcome::Improved
    } else if better < -tolerance {
        Outcome::Regressed
    } else {
        Outcome::Unchanged
    }
}

/// Half the L1 distance between two histograms normalized to sum 1 (0: same shape, 1:
/// disjoint). Histograms of different lengths (another M) are disjoint beyond the shorter.
fn total_variation(a: &[u64], b: &[u64]) -> f64 {
    let (sum_a, sum_b) = (a.iter().sum::<u64>().max(1) as f64, b.iter().sum::<u64>().max(1) as f64);
    let length = a.len().max(b.len());
    let at = |h: &[u64], i: usize| h.get(i).copied().unwrap_or(0) as f64;
    (0..length).map(|i| (at(a, i) / sum_a - at(b, i) / sum_b).abs()).sum::<f64>() / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tolerances_decide_direction_and_size() {
        assert_eq!(beyond(0.5, 0.25, true), Outcome::Improved);
        assert_eq!(beyond(-0.5, 0.25, true), Outcome::Regressed);
        assert_eq!(beyond(0.1, 0.25, true), Outcome::Unchanged);
        assert_eq!(beyond(0.5, 0.25, false), Outcome::Regressed, "more MSE is worse");
        assert_eq!(beyond(f64::INFINITY, 0.25, false), Outcome::Regressed);
    }

    #[test]
    fn total_variation_is_half_the_l1_distance_of_the_shapes() {
        assert_eq!(total_variation(&[1, 1], &[2, 2]), 0.0);
        assert_eq!(total_variation(&[1, 0], &[0, 1]), 1.0);
        assert!((total_variation(&[3, 1], &[1, 1]) - 0.25).abs() < 1e-12);
        assert_eq!(total_variation(&[1], &[0, 1]), 1.0);
    }
}
