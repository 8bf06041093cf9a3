//! The points of the error-against-run-time plots: one per mode with an error against the
//! truth (MSE, FLIP) or along the camera path (flicker) and a frame time.

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
    /// Flicker along the scene's sequence `index` (`temporal.rs`); its front is drawn by
    /// medians as FLIP's.
    Flicker(usize),
}

impl ErrorMetric {
    pub fn axis(self) -> &'static str {
        match self {
            ErrorMetric::Mse => "MSE against the truth ×1e-5 (log)",
            ErrorMetric::Flip => "mean FLIP against the truth (log)",
            ErrorMetric::Flicker(_) => "flicker along the camera path (log)",
        }
    }

    /// What a plot of this metric of `scene` is called, after the scene's name.
    pub fn title(self, scene: &SceneRecord) -> String {
        match self {
            ErrorMetric::Mse => "error against run time".into(),
            ErrorMetric::Flip => "FLIP against run time".into(),
            ErrorMetric::Flicker(index) => match scene.sequences.get(index) {
                Some(sequence) => format!("flicker against run time at {}", sequence.speed()),
                None => "flicker against run time".into(),
            },
        }
    }

    /// The x axis: the still's frame time, or for flicker the frame time along the path,
    /// where the mode's cost may differ from its still's (a `-stable` mode's counts).
    pub fn time_axis(self) -> &'static str {
        match self {
            ErrorMetric::Flicker(_) => "frame time along the path, ms (median and interval; log)",
            ErrorMetric::Mse | ErrorMetric::Flip => "frame time, ms (median and interval; log)",
        }
    }

    /// The frame time a mode is drawn at (see [`Self::time_axis`]); the still's where a run
    /// recorded no times along the path.
    fn time(self, mode: &ModeRecord) -> Option<&crate::stats::Summary> {
        match self {
            ErrorMetric::Flicker(index) => {
                mode.sequence_at(index).and_then(|s| s.frame_ms.as_ref()).or(mode.frame_ms.as_ref())
            }
            ErrorMetric::Mse | ErrorMetric::Flip => mode.frame_ms.as_ref(),
        }
    }

    /// The plots a scene has: flicker only where it has a camera path.
    pub fn of_scene(scene: &SceneRecord) -> Vec<ErrorMetric> {
        let mut metrics = vec![ErrorMetric::Mse, ErrorMetric::Flip];
        metrics.extend((0..scene.sequences.len()).map(ErrorMetric::Flicker));
        metrics
    }

    /// The metric it plots ([`crate::vocabulary`]) and the scale of its axis.
    fn metric(self) -> (&'static Metric, f64) {
        let (id, scale) = match self {
            ErrorMetric::Mse => ("mse_vs_truth", 1e5),
            ErrorMetric::Flip => ("flip_vs_truth", 1.0),
            ErrorMetric::Flicker(_) => ("flicker", 1.0),
        };
        (vocabulary::metric(id).expect("a plotted metric is in the vocabulary"), scale)
    }

    fn of(self, mode: &ModeRecord) -> Option<f64> {
        let (metric, scale) = self.metric();
        let index = if let ErrorMetric::Flicker(index) = self { index } else { 0 };
        Some(metric.value_at(mode, index)? * scale)
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
