//! How many timed rounds each mode of a scene takes: a count (`--repetitions N`), or rounds by
//! confidence until the mode's median is known or its scene's time budget is spent, and why a
//! mode stopped.

use serde::{Deserialize, Serialize};

/// The fewest rounds a mode takes by confidence (where its tier allows as many): two modes'
/// times are compared round by round, the sign test's interval of the median ratio at 90 %
/// (`front::TIME_CONFIDENCE`). With five rounds that interval decides an order only where every
/// round agrees, so one round out of line (a frame that took twice its time) leaves the pair
/// undecided in one run and decided in the next; with nine it decides past one such round.
pub const DECIDING_ROUNDS: u32 = 9;

/// How many timed rounds each mode of a scene takes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Repetitions {
    /// Exactly this many (`--repetitions N`): the gate's processes, a bless of a set size.
    Count(u32),
    /// By confidence, the suite's default: each mode's rounds until the rule is met.
    Confidence(Confidence),
}

/// When a mode that takes its rounds by confidence has enough: a fifteenth round of a mode whose
/// median is known to 1 % buys less than a fifth of one that varies by 30 %.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Confidence {
    /// No mode stops before this many rounds.
    pub floor: u32,
    /// Nor takes more than this many.
    pub most: u32,
    /// A mode stops once its median's interval (≥ 95 %) is at most this share of its median
    /// wide…
    pub width: f64,
    /// …or once its scene's timed frames, every mode's, took this many seconds.
    pub budget_s: f64,
}

/// Why a mode took no more rounds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Stop {
    /// It took the rounds asked for (`--repetitions N`).
    Count,
    /// Its median's interval was within the rule's width.
    Interval,
    /// Its scene's timed frames had taken the rule's budget.
    Budget,
    /// It took the most rounds the rule allows.
    Most,
}

impl Repetitions {
    /// The most rounds a mode may take.
    pub fn most(self) -> u32 {
        match self {
            Repetitions::Count(count) => count,
            Repetitions::Confidence(rule) => rule.most,
        }
    }

    /// Whether a mode whose timed frames so far took `frames_ms` stops here, and why, when its
    /// scene's timed frames took `spent_s` seconds in all.
    pub fn stop(self, frames_ms: &[f64], spent_s: f64) -> Option<Stop> {
        let taken = frames_ms.len() as u32;
        let rule = match self {
            Repetitions::Count(count) => return (taken >= count).then_some(Stop::Count),
            Repetitions::Confidence(rule) if taken >= rule.floor => rule,
            Repetitions::Confidence(_) => return None,
        };
        let summary = crate::measure::stats::Summary::new(frames_ms.to_vec())?;
        if summary.ci_high - summary.ci_low <= rule.width * summary.median {
            Some(Stop::Interval)
        } else if spent_s >= rule.budget_s {
            Some(Stop::Budget)
        } else {
            (taken >= rule.most).then_some(Stop::Most)
        }
    }

    /// The rule, as a run's settings record it (`None` for a count).
    pub fn confidence(self) -> Option<Confidence> {
        match self {
            Repetitions::Count(_) => None,
            Repetitions::Confidence(rule) => Some(rule),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mode_stops_at_its_count_or_once_its_median_is_known_or_its_scene_spent_its_budget() {
        let rule = Repetitions::Confidence(Confidence { floor: 5, most: 15, width: 0.05, budget_s: 5.0 });
        let steady = [10.0, 10.1, 9.9, 10.0, 10.05];
        assert_eq!(rule.stop(&steady[..4], 100.0), None, "below the floor nothing stops it");
        assert_eq!(rule.stop(&steady, 0.0), Some(Stop::Interval), "9.9–10.1 ms is within 5 % of 10");
        let noisy = [10.0, 14.0, 9.0, 12.0, 8.0];
        assert_eq!(rule.stop(&noisy, 4.9), None);
        assert_eq!(rule.stop(&noisy, 5.0), Some(Stop::Budget));
        let alternating: Vec<f64> = (0..15).map(|i| if i % 2 == 0 { 8.0 } else { 12.0 }).collect();
        assert_eq!(rule.stop(&alternating[..14], 1.0), None);
        assert_eq!(rule.stop(&alternating, 1.0), Some(Stop::Most));
        assert_eq!(rule.most(), 15);
        let count = Repetitions::Count(3);
        assert_eq!(
            (count.stop(&[1.0, 2.0], 100.0), count.stop(&[1.0, 2.0, 9.0], 0.0)),
            (None, Some(Stop::Count))
        );
        assert_eq!((count.most(), count.confidence()), (3, None));
    }
}
