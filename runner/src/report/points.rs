//! The points of the error-against-run-time plots: one per mode with an error against the
//! truth (MSE, FLIP) or along the camera path (instability) and a frame time.

use super::plots::Point;
use crate::record::{ModeRecord, SceneRecord};
use crate::vocabulary::{self, Metric};

/// The error an error-against-run-time plot draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorMetric {
    /// MSE against the truth ×10⁻⁵; its front is run.json's (by PSNR, with intervals).
    Mse,
    /// Mean FLIP against the truth; its front is drawn by medians: no faster mode of the same
    /// stall has less FLIP.
    Flip,
    /// Temporal instability along the scene's camera path (`run/sequence.rs`); its front is drawn
    /// by medians as FLIP's.
    Instability,
}

impl ErrorMetric {
    pub fn axis(self) -> &'static str {
        match self {
            ErrorMetric::Mse => "MSE against the truth ×1e-5 (log)",
            ErrorMetric::Flip => "mean FLIP against the truth (log)",
            ErrorMetric::Instability => "temporal instability along the camera path (log)",
        }
    }

    /// What a plot of this metric is called, after the scene's name.
    pub fn title(self) -> &'static str {
        match self {
            ErrorMetric::Mse => "error against run time",
            ErrorMetric::Flip => "FLIP against run time",
            ErrorMetric::Instability => "instability against run time",
        }
    }

    /// The x axis: the still's frame time, or for instability the frame time along the path,
    /// where the mode's cost may differ from its still's (a `-stable` mode's counts).
    pub fn time_axis(self) -> &'static str {
        match self {
            ErrorMetric::Instability => "frame time along the path, ms (median and interval; log)",
            ErrorMetric::Mse | ErrorMetric::Flip => "frame time, ms (median and interval; log)",
        }
    }

    /// The frame time a mode is drawn at (see [`Self::time_axis`]); the still's where a run
    /// recorded no times along the path.
    fn time(self, mode: &ModeRecord) -> Option<&crate::stats::Summary> {
        match self {
            ErrorMetric::Instability => {
                mode.sequence.as_ref().and_then(|s| s.frame_ms.as_ref()).or(mode.frame_ms.as_ref())
            }
            ErrorMetric::Mse | ErrorMetric::Flip => mode.frame_ms.as_ref(),
        }
    }

    /// The plots a scene has: instability only where it has a camera path.
    pub fn of_scene(scene: &SceneRecord) -> Vec<ErrorMetric> {
        let mut metrics = vec![ErrorMetric::Mse, ErrorMetric::Flip];
        metrics.extend(scene.sequence.as_ref().map(|_| ErrorMetric::Instability));
        metrics
    }

    /// The metric it plots ([`crate::vocabulary`]) and the scale of its axis.
    fn metric(self) -> (&'static Metric, f64) {
        let (id, scale) = match self {
            ErrorMetric::Mse => ("mse_vs_truth", 1e5),
            ErrorMetric::Flip => ("flip_vs_truth", 1.0),
            ErrorMetric::Instability => ("instability", 1.0),
        };
        (vocabulary::metric(id).expect("a plotted metric is in the vocabulary"), scale)
    }

    fn of(self, mode: &ModeRecord) -> Option<f64> {
        let (metric, scale) = self.metric();
        Some((metric.read)(mode)? * scale)
    }
}

/// The modes with an error against the truth (in `metric`) and a frame time.
pub fn error_points(scene: &SceneRecord, metric: ErrorMetric) -> Vec<Point> {
    let mut points: Vec<Point> = scene
        .modes
        .iter()
        .filter_map(|mode| {
            let frame = metric.time(mode)?;
            let error = metric.of(mode)?;
            let parsed = mode.parsed()?;
            (error > 0.0).then(|| Point {
                label: parsed.short_label(),
                marker: parsed.technique.marker(),
                stalled: mode.stalled,
                time: frame.median,
                time_low: frame.ci_low,
                time_high: frame.ci_high,
                error,
                on_front: mode.front.as_ref().is_some_and(|place| place.on_front),
            })
        })
        .collect();
    if metric != ErrorMetric::Mse {
        let dominated: Vec<bool> = points
            .iter()
            .map(|p| points.iter().any(|q| q.stalled == p.stalled && q.time < p.time && q.error < p.error))
            .collect();
        for (point, dominated) in points.iter_mut().zip(dominated) {
            point.on_front = !dominated;
        }
    }
    points
}
