//! One time of one mode of one scene as the gate compares it against the base build, a log
//! value per process of each build, and the rule that decides such values: the process is the
//! unit of evidence, the shift between the builds the Hodges–Lehmann estimate over the
//! processes' values with its Moses interval. Both the per-scene checks ([`super::ab`]) and the
//! checks pooled over the scenes ([`super::pooled`]) are decided here.

use crate::measure::stats::{Shift, Summary};

use super::time::decide;
use super::verdict::{Against, CONFIDENCE, Check, MIN_PROCESSES, Outcome};

/// One time of one mode of one scene, as the gate compares it: a log value per process of each
/// build, in the processes' order (`None` where a process did not time it).
#[derive(Debug, Clone)]
pub(super) struct Series {
    pub scene: String,
    pub mode: String,
    /// The check's metric id (`relative_time`, `pass_time:fxaa`, …).
    pub metric: String,
    /// What is compared, for people: `frame time`, `fxaa pass time over the rest of its frame`.
    pub what: String,
    /// `ms` or `×`: how the detail shows a side's median.
    pub unit: &'static str,
    /// The tolerance, as a log ratio.
    pub bound: f64,
    pub head: Vec<Option<f64>>,
    pub base: Vec<Option<f64>>,
    /// Whether its scene decides it on its own, or only the check pooled over the scenes does
    /// (a pass's time, which one scene's processes cannot judge: see [`super::pooled`]).
    pub alone: bool,
}

impl Series {
    /// The check of this time in its scene: the head's processes against the base's.
    pub(super) fn check(&self) -> Option<Check> {
        let head: Vec<f64> = self.head.iter().flatten().copied().collect();
        let base: Vec<f64> = self.base.iter().flatten().copied().collect();
        let template = Check {
            against: Against::Base,
            unit: "relative".into(),
            ..Check::new(&self.scene, &self.mode, &self.metric, Outcome::Unchanged, String::new())
        };
        decide_processes(&head, &base, self.bound, &self.what, self.unit, template)
    }
}

/// Decides a time from one log value per process of each build: `insufficient` with fewer than
/// [`MIN_PROCESSES`] on a side, else the shift's interval against `bound`.
pub(super) fn decide_processes(
    head: &[f64],
    base: &[f64],
    bound: f64,
    what: &str,
    unit: &str,
    template: Check,
) -> Option<Check> {
    let value = |logs: &[f64]| median(logs.to_vec()).map(f64::exp);
    let values = (value(base)?, value(head)?);
    if head.len() < MIN_PROCESSES || base.len() < MIN_PROCESSES {
        return Some(Check {
            outcome: Outcome::Insufficient,
            baseline: Some(values.0),
            current: Some(values.1),
            detail: format!(
                "{what} against the base build: {} process(es) of the base and {} of the run, fewer than the \
                 {MIN_PROCESSES} on each side a time verdict needs",
                base.len(),
                head.len()
            ),
            ..template
        });
    }
    let shift = Shift::between(head, base, CONFIDENCE)?;
    let extra = format!(", over {} processes of the base and {} of the run", base.len(), head.len());
    let what = format!("{what} against the base build");
    Some(decide(shift, bound, values, unit, &what, &extra).into_check(template))
}

/// The median of `logs`, `None` when there are none.
pub(super) fn median(logs: Vec<f64>) -> Option<f64> {
    Summary::new(logs).map(|s| s.median)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_processes_a_side_reach_the_confidence_three_do_not() {
        let base = [0.0, 0.01, -0.01, 0.005];
        let slower: Vec<f64> = base.iter().map(|x| x + 0.25).collect();
        let shift = Shift::between(&slower, &base, CONFIDENCE).unwrap();
        assert!(shift.level >= CONFIDENCE, "{shift:?}");
        let decided = decide(shift, 0.1f64.ln_1p(), (1.0, 1.28), "×", "t", "");
        assert_eq!(decided.outcome, Outcome::Regressed);
        let few = Shift::between(&slower[..3], &base[..3], CONFIDENCE).unwrap();
        assert!(few.level < CONFIDENCE, "three a side cannot reach 95%: {few:?}");
    }

    /// One head process of six landing 30% slower while the others do not move leaves the
    /// outcome `unchanged`: the Hodges–Lehmann estimate stays within the threshold, so the
    /// stray process is not called a regression.
    #[test]
    fn one_stray_process_makes_a_shift_noisy_not_regressed() {
        let base = [0.0, 0.01, -0.01, 0.005, 0.0, 0.002];
        // One head process landed 30% slower, as bimodal modes do; the others did not move.
        let head = [0.26, 0.01, -0.005, 0.0, 0.004, 0.003];
        let shift = Shift::between(&head, &base, CONFIDENCE).unwrap();
        let decided = decide(shift, 0.1f64.ln_1p(), (1.0, 1.0), "×", "t", "");
        assert_eq!(decided.outcome, Outcome::Unchanged, "{}", decided.detail);
    }
}
