//! The error-against-run-time front of a scene: the modes that no other mode beats both in
//! frame time and in nearness to the truth, and for every other mode, the modes that beat it
//! and by how much. This is the answer an engineer reads a run for: which technique is worth
//! its time on this scene.
//!
//! Noise must not decide membership, so frame times are compared by their intervals, not
//! their medians: a mode is faster than another only where its whole interval lies below the
//! other's, and two modes are as fast as each other where each one's median lies inside the
//! other's interval. Intervals that overlap with medians apart decide nothing. Stalled modes
//! simulate another shader's cost, so they are measured among the stalled modes only, and
//! plain modes among the plain ones.

use crate::metrics::Decibels;
use crate::record::{Dominator, FrontPlace, ModeRecord, Status};

/// PSNRs against the truth closer than this are a tie: the images are as near the truth as
/// each other, whatever the last digits say.
pub const PSNR_TIE_DB: f64 = 0.05;

/// What the front reads of a mode: its frame-time median and interval (ms) and its PSNR
/// against the truth (dB, +∞ for an image equal to the truth).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrontPoint {
    pub median: f64,
    pub low: f64,
    pub high: f64,
    pub psnr: f64,
}

impl FrontPoint {
    fn of(mode: &ModeRecord) -> Option<FrontPoint> {
        if mode.status != Status::Ok {
            return None;
        }
        let frame = mode.frame_ms.as_ref()?;
        let psnr = mode.vs_ground_truth.as_ref()?.psnr_db.value();
        (!psnr.is_nan()).then_some(FrontPoint {
            median: frame.median,
            low: frame.ci_low,
            high: frame.ci_high,
            psnr,
        })
    }

    /// Whether `self` dominates `other`: at least as near the truth and faster beyond the
    /// intervals, or nearer the truth by more than a tie and as fast.
    pub fn dominates(&self, other: &FrontPoint) -> bool {
        let gain = psnr_gain(self.psnr, other.psnr);
        let faster = self.high < other.low;
        let inside = |median: f64, of: &FrontPoint| of.low <= median && median <= of.high;
        let as_fast = inside(self.median, other) && inside(other.median, self);
        gain >= -PSNR_TIE_DB && (faster || (as_fast && gain > PSNR_TIE_DB))
    }
}

/// `a − b` in dB, with equal infinities (two images equal to the truth) a tie.
fn psnr_gain(a: f64, b: f64) -> f64 {
    if a == b { 0.0 } else { a - b }
}

/// Sets each mode's `front` among the modes of its scene with the same stall. A mode without
/// a frame time or a PSNR against the truth (failed, or no truth) has no place and takes no
/// part.
pub fn place(modes: &mut [ModeRecord]) {
    let points: Vec<Option<FrontPoint>> = modes.iter().map(FrontPoint::of).collect();
    let places: Vec<Option<FrontPlace>> = (0..modes.len())
        .map(|i| {
            let own = points[i]?;
            let mut dominated_by: Vec<(Dominator, f64)> = (0..modes.len())
                .filter(|&j| j != i && modes[j].stalled == modes[i].stalled)
                .filter_map(|j| {
                    let other = points[j]?;
                    other.dominates(&own).then(|| {
                        let dominator = Dominator {
                            mode: modes[j].mode.clone(),
                            time_ratio: other.median / own.median,
                            psnr_gain_db: Decibels::from_f64(psnr_gain(other.psnr, own.psnr)),
                        };
                        (dominator, other.median)
                    })
                })
                .collect();
            dominated_by.sort_by(|(a, a_time), (b, b_time)| {
                let gain = |d: &Dominator| d.psnr_gain_db.value();
                gain(b).total_cmp(&gain(a)).then(a_time.total_cmp(b_time))
            });
            let dominated_by: Vec<Dominator> = dominated_by.into_iter().map(|(d, _)| d).collect();
            Some(FrontPlace { on_front: dominated_by.is_empty(), dominated_by })
        })
        .collect();
    for (mode, place) in modes.iter_mut().zip(places) {
        mode.front = place;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(median: f64, spread: f64, psnr: f64) -> FrontPoint {
        FrontPoint { median, low: median - spread, high: median + spread, psnr }
    }

    #[test]
    fn faster_and_as_near_dominates_but_overlapping_times_need_a_real_gain() {
        let slow = point(20.0, 1.0, 40.0);
        // Faster beyond the intervals, PSNR tied: dominates.
        assert!(point(10.0, 1.0, 39.97).dominates(&slow));
        // Faster but further from the truth: does not.
        assert!(!point(10.0, 1.0, 39.0).dominates(&slow));
        // As fast (each median inside the other's interval): only a gain beyond the tie
        // dominates, whichever median is lower.
        assert!(!point(19.5, 1.0, 40.04).dominates(&slow));
        assert!(point(20.5, 1.0, 41.0).dominates(&slow));
        // Overlapping intervals with medians apart decide nothing, either way round.
        let wide = point(26.0, 6.0, 41.0);
        assert!(!wide.dominates(&slow) && !slow.dominates(&wide));
        // Nearer the truth but slower beyond the intervals: does not.
        assert!(!point(30.0, 1.0, 50.0).dominates(&slow));
        // Equal to the truth twice over is a tie, not a gain.
        assert!(!point(19.0, 2.0, f64::INFINITY).dominates(&point(20.0, 2.0, f64::INFINITY)));
        assert!(point(10.0, 1.0, f64::INFINITY).dominates(&point(20.0, 1.0, f64::INFINITY)));
    }

    /// An exact image (the `empty` scene's deferred-1x1) dominating an inexact one is an
    /// infinite gain, which JSON writes as "inf" and reads back.
    #[test]
    fn an_infinite_gain_survives_the_record() {
        let place = FrontPlace {
            on_front: false,
            dominated_by: vec![Dominator {
                mode: "deferred-1x1".into(),
                time_ratio: 0.4,
                psnr_gain_db: Decibels::from_f64(psnr_gain(f64::INFINITY, 63.3)),
            }],
        };
        let json = serde_json::to_string(&place).unwrap();
        assert!(json.contains(r#""psnr_gain_db":"inf""#), "{json}");
        assert_eq!(serde_json::from_str::<FrontPlace>(&json).unwrap(), place);
        assert_eq!(place.describe(), "behind deferred-1x1 (+inf dB, 0.40× time)");
    }

    #[test]
    fn a_point_never_dominates_itself() {
        let p = point(10.0, 1.0, 40.0);
        assert!(!p.dominates(&p));
    }
}
