//! The error-against-run-time fronts of a scene: for each metric of the vocabulary with a front
//! margin (PSNR against the truth, the paper's; JOD of the still and along each path, the
//! rankings'), which modes no other mode beats both in frame time and in quality, decided with
//! confidence. This is the answer an engineer reads a run for: which technique is worth its
//! time on this scene.
//!
//! A verdict must repeat on a second run, so neither noise in time nor the last digits of a
//! metric decide it. A rival is a mode of the same stall as good as the mode: its value less
//! the mode's is at least minus the metric's margin. Times are compared round by round: every
//! round renders each mode once, so the ratio of two modes' times in one round is free of the
//! machine's drift between rounds, and the median of those ratios comes with the sign test's
//! interval. A rival puts the mode *behind* it when it is faster with confidence (the whole
//! interval below 1); the mode is *on the front* when every rival is slower with confidence;
//! otherwise it is *undecided* against the rivals whose time the rounds do not tell from its
//! own. Along a camera path the frames are the rounds, where both modes timed their path.

use std::collections::BTreeMap;

use crate::measure::pixels::Decibels;
use crate::measure::stats::Summary;
use crate::record::vocabulary::{METRICS, Metric, Source};
use crate::record::{FrontPlace, FrontVerdict, ModeRecord, Rival, Status};

/// The least coverage of a time ratio's interval that decides an order: five rounds' worth
/// (93.75 %). Fewer rounds decide nothing.
pub const TIME_CONFIDENCE: f64 = 0.9;

/// What a front reads of a mode: its value of the front's metric (higher better) and its
/// frame times.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrontPoint<'a> {
    pub mode: &'a str,
    pub stalled: bool,
    /// In the metric's unit; +∞ for PSNR of an image equal to the truth.
    pub level: f64,
    /// Frame times in ms, one a round of the still.
    pub rounds: Option<&'a [f64]>,
    /// Frame times in ms, one a frame of the path, for a path's metric.
    pub path: Option<&'a [f64]>,
}

/// How a rival's time compares with a mode's.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Pace {
    Faster,
    Slower,
    Untold,
}

impl<'a> FrontPoint<'a> {
    /// The point of `mode` on the front of `metric` (along the sequence `index` for a path's),
    /// where it finished with a value of the metric.
    pub fn of(mode: &'a ModeRecord, metric: &Metric, index: usize) -> Option<FrontPoint<'a>> {
        if mode.status != Status::Ok {
            return None;
        }
        let level = metric.value_at(mode, index).filter(|level| !level.is_nan())?;
        let samples = |summary: Option<&'a Summary>| summary.map(|s| s.samples.as_slice());
        let path = match metric.source {
            Source::Sequence => samples(mode.sequence_at(index)?.frame_ms.as_ref()),
            _ => None,
        };
        Some(FrontPoint {
            mode: &mode.mode,
            stalled: mode.stalled,
            level,
            rounds: samples(mode.frame_ms.as_ref()),
            path,
        })
    }

    /// The log ratios of `self`'s frame times to `other`'s, pair by pair: along the path where
    /// both have one, else round by round.
    fn log_ratios(&self, other: &FrontPoint) -> Vec<f64> {
        let (own, theirs) = match (self.path.zip(other.path), self.rounds.zip(other.rounds)) {
            (Some(path), _) => path,
            (None, Some(rounds)) => rounds,
            (None, None) => return Vec::new(),
        };
        own.iter().zip(theirs).map(|(a, b)| (a / b).ln()).collect()
    }

    /// Whether `self` is faster than `other` with confidence, pair by pair (see
    /// `log_ratios`), and saves at least `margin` of the other's time (the median of
    /// their ratios at most 1 − `margin`): statistically and practically
    /// cheaper, as the gate calls a slowdown only past its tolerance.
    pub fn cheaper_by(&self, other: &FrontPoint, margin: f64) -> bool {
        let (pace, ratio) = self.pace(other);
        pace == Pace::Faster && ratio <= 1.0 - margin + 1e-9
    }

    /// Whether `self` is faster or slower than `other` with confidence, and the median of the
    /// ratios of their times.
    fn pace(&self, other: &FrontPoint) -> (Pace, f64) {
        let Some(ratios) = Summary::new(self.log_ratios(other)) else {
            return (Pace::Untold, f64::NAN);
        };
        let sure = ratios.ci_level >= TIME_CONFIDENCE;
        let pace = match () {
            _ if sure && ratios.ci_high < 0.0 => Pace::Faster,
            _ if sure && ratios.ci_low > 0.0 => Pace::Slower,
            _ => Pace::Untold,
        };
        (pace, ratios.median.exp())
    }
}

/// `a − b`, with equal infinities (two images equal to the truth) a tie.
fn gain(a: f64, b: f64) -> f64 {
    if a == b { 0.0 } else { a - b }
}

/// The verdict of every point on the front of a metric with margin `margin`, among the points
/// of the same stall; `None` where there is no point.
pub fn decide(points: &[Option<FrontPoint>], margin: f64) -> Vec<Option<FrontPlace>> {
    points.iter().map(|own| own.map(|own| verdict(&own, points, margin))).collect()
}

fn verdict(own: &FrontPoint, points: &[Option<FrontPoint>], margin: f64) -> FrontPlace {
    let (mut ahead, mut untold) = (Vec::new(), Vec::new());
    for rival in points.iter().flatten() {
        let gain = gain(rival.level, own.level);
        if rival.mode == own.mode || rival.stalled != own.stalled || gain < -margin {
            continue;
        }
        let (pace, time_ratio) = rival.pace(own);
        let entry = Rival { mode: rival.mode.to_string(), time_ratio, gain: Decibels::from_f64(gain) };
        match pace {
            Pace::Faster => ahead.push(entry),
            Pace::Untold => untold.push(entry),
            Pace::Slower => {}
        }
    }
    let (verdict, mut against) = match (ahead.is_empty(), untold.is_empty()) {
        (false, _) => (FrontVerdict::Behind, ahead),
        (true, false) => (FrontVerdict::Undecided, untold),
        (true, true) => (FrontVerdict::Front, Vec::new()),
    };
    against.sort_by(|a, b| {
        b.gain.value().total_cmp(&a.gain.value()).then(a.time_ratio.total_cmp(&b.time_ratio))
    });
    FrontPlace { verdict, against }
}

/// Sets each mode's places on its scene's fronts: one per metric with a front margin, along
/// each of the scene's sequences for a path's metric. A mode without frame times or a value of
/// a front's metric (failed, no truth, no path) has no place on it and takes no part.
pub fn place(modes: &mut [ModeRecord]) {
    let sequences = modes.iter().map(|mode| mode.sequences.len()).max().unwrap_or(0);
    let mut places: Vec<BTreeMap<String, FrontPlace>> = vec![BTreeMap::new(); modes.len()];
    for metric in METRICS.iter() {
        let Some(margin) = metric.front_margin else { continue };
        for index in 0..metric.values_in(sequences) {
            let points: Vec<Option<FrontPoint>> =
                modes.iter().map(|mode| FrontPoint::of(mode, metric, index)).collect();
            for (own, place) in places.iter_mut().zip(decide(&points, margin)) {
                own.extend(place.map(|place| (metric.key(index), place)));
            }
        }
    }
    for (mode, fronts) in modes.iter_mut().zip(places) {
        mode.fronts = fronts;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point with frame times `rounds` (ms).
    fn point<'a>(mode: &'a str, level: f64, rounds: &'a [f64]) -> Option<FrontPoint<'a>> {
        Some(FrontPoint { mode, stalled: false, level, rounds: Some(rounds), path: None })
    }

    fn verdicts(points: &[Option<FrontPoint>], margin: f64) -> Vec<FrontVerdict> {
        decide(points, margin).into_iter().map(|place| place.unwrap().verdict).collect()
    }

    /// Five rounds whose times drift together between rounds by ±20 %, as a busy machine's do.
    fn drifting(ms: f64) -> Vec<f64> {
        [1.0, 1.2, 0.8, 1.1, 0.9].iter().map(|drift| ms * drift).collect()
    }

    #[test]
    fn a_mode_one_percent_faster_and_a_thousandth_worse_makes_no_level_of_its_own() {
        // Faster in every round by 1 %: the slower one, no better beyond the margin, is behind.
        let (slow, fast) = (drifting(50.0), drifting(49.5));
        let places = decide(&[point("slow", 9.001, &slow), point("fast", 9.0, &fast)], 0.1);
        assert_eq!(places[0].as_ref().unwrap().describe("JOD"), "behind fast (-0.00 JOD, 0.99× time)");
        assert_eq!(places[1].as_ref().unwrap().verdict, FrontVerdict::Front);
        // The same 1 % within noise that swaps their order between rounds: neither decided, and
        // neither is a level the other is not.
        let noisy = [50.0, 59.0, 41.0, 56.0, 44.0];
        let places = decide(&[point("slow", 9.001, &slow), point("fast", 9.0, &noisy)], 0.1);
        let undecided = places[0].as_ref().unwrap();
        assert_eq!(undecided.verdict, FrontVerdict::Undecided);
        assert_eq!(undecided.against[0].mode, "fast");
        assert_eq!(places[1].as_ref().unwrap().verdict, FrontVerdict::Undecided);
    }

    #[test]
    fn a_better_mode_beyond_the_margin_is_no_rival_of_a_faster_one() {
        let (cheap, dear) = (drifting(20.0), drifting(60.0));
        // 0.3 JOD better and slower in every round: both on the front.
        let points = [point("cheap", 8.0, &cheap), point("dear", 8.3, &dear)];
        assert_eq!(verdicts(&points, 0.1), [FrontVerdict::Front, FrontVerdict::Front]);
        // Within the margin, the dear one is behind the cheap one.
        let points = [point("cheap", 8.25, &cheap), point("dear", 8.3, &dear)];
        assert_eq!(verdicts(&points, 0.1), [FrontVerdict::Front, FrontVerdict::Behind]);
    }

    #[test]
    fn the_drift_between_rounds_does_not_hide_a_faster_mode() {
        // Intervals of the medians overlap ([40, 60] against [36, 54]), yet the second is 10 %
        // faster in every round.
        let (a, b) = (drifting(50.0), drifting(45.0));
        assert_eq!(
            verdicts(&[point("a", 40.0, &a), point("b", 40.0, &b)], 0.25),
            [FrontVerdict::Behind, FrontVerdict::Front]
        );
    }

    #[test]
    fn fewer_than_five_rounds_decide_nothing_and_a_point_is_not_its_own_rival() {
        let (a, b) = ([50.0, 51.0, 52.0, 50.5], [30.0, 31.0, 30.5, 30.2]);
        assert_eq!(
            verdicts(&[point("a", 40.0, &a), point("b", 40.0, &b)], 0.25),
            [FrontVerdict::Undecided; 2]
        );
        assert_eq!(verdicts(&[point("a", 40.0, &drifting(50.0))], 0.25), [FrontVerdict::Front]);
    }

    #[test]
    fn stalls_are_apart_and_exact_images_tie() {
        let (a, b) = (drifting(50.0), drifting(20.0));
        let mut stalled = point("b-stalled", 40.0, &b).unwrap();
        stalled.stalled = true;
        assert_eq!(verdicts(&[point("a", 40.0, &a), Some(stalled)], 0.25), [FrontVerdict::Front; 2]);
        // Two images equal to the truth are one quality; the faster puts the slower behind.
        let exact = [point("a", f64::INFINITY, &a), point("b", f64::INFINITY, &b)];
        let places = decide(&exact, 0.25);
        assert_eq!(places[0].as_ref().unwrap().describe("dB"), "behind b (+0.00 dB, 0.40× time)");
        // An exact image against an inexact one is an infinite gain.
        let places = decide(&[point("a", 30.0, &a), point("b", f64::INFINITY, &b)], 0.25);
        assert_eq!(places[0].as_ref().unwrap().describe("dB"), "behind b (+inf dB, 0.40× time)");
    }

    #[test]
    fn along_a_path_the_frames_pair_where_both_timed_the_path() {
        let (still_a, still_b) = (drifting(50.0), drifting(55.0));
        let (path_a, path_b) = (drifting(50.0), drifting(40.0));
        let along = |mode, rounds, path| {
            Some(FrontPoint { mode, stalled: false, level: 9.0, rounds: Some(rounds), path })
        };
        let points = [along("a", &still_a, Some(&path_a[..])), along("b", &still_b, Some(&path_b[..]))];
        assert_eq!(verdicts(&points, 0.1), [FrontVerdict::Behind, FrontVerdict::Front], "the path's times");
        let points = [along("a", &still_a, Some(&path_a[..])), along("b", &still_b, None)];
        assert_eq!(verdicts(&points, 0.1), [FrontVerdict::Front, FrontVerdict::Behind], "the still's");
    }
}
