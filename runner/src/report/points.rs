//! The points of the error-against-run-time plots: one per mode with an error against the
//! truth (MSE, FLIP) or along the camera path (flicker) and a frame time.

use super::plots::Point;
use crate::measure::stats::Summary;
use crate::record::vocabulary::{self, Front, METRICS, Metric, Plot, Source};
use crate::record::{ModeRecord, SceneRecord};

/// One error-against-run-time plot of a scene: a metric of the vocabulary that has a
/// [`Plot`], along the scene's sequence `sequence` where it is a sequence's.
#[derive(Debug, Clone, Copy)]
pub struct ErrorPlot {
    metric: &'static Metric,
    plot: Plot,
    sequence: usize,
}

impl ErrorPlot {
    /// The plots a scene has, in the vocabulary's order: a still's metric once, a sequence's
    /// once per speed (none where the scene has no camera path). The first is the still's
    /// error against the truth.
    pub fn of_scene(scene: &SceneRecord) -> Vec<ErrorPlot> {
        let mut plots = Vec::new();
        for metric in &METRICS {
            let Some(plot) = metric.plot else { continue };
            let sequences = if metric.source == Source::Sequence { scene.sequences.len() } else { 1 };
            plots.extend((0..sequences).map(|sequence| ErrorPlot { metric, plot, sequence }));
        }
        plots
    }

    pub fn axis(&self) -> &'static str {
        self.plot.axis
    }

    fn along_path(&self) -> bool {
        self.metric.source == Source::Sequence
    }

    /// What a plot of `scene` is called, after the scene's name.
    pub fn title(&self, scene: &SceneRecord) -> String {
        match scene.sequences.get(self.sequence).filter(|_| self.along_path()) {
            Some(sequence) => format!("{} at {}", self.plot.title, sequence.speed()),
            None => self.plot.title.into(),
        }
    }

    /// The figure's file name after the scene's: `front-flicker`, `front-flicker-2` for the
    /// second speed.
    pub fn file(&self) -> String {
        match self.sequence {
            0 => self.plot.file.into(),
            index => format!("{}-{}", self.plot.file, index + 1),
        }
    }

    /// The x axis: the still's frame time, or for a sequence's metric the frame time along the
    /// path, where the mode's cost may differ from its still's (a `-stable` mode's counts).
    pub fn time_axis(&self) -> &'static str {
        if self.along_path() {
            "frame time along the path, ms (median and interval; log)"
        } else {
            "frame time, ms (median and interval; log)"
        }
    }

    /// The frame time a mode is drawn at (see [`Self::time_axis`]); the still's where a run
    /// recorded no times along the path.
    fn time<'m>(&self, mode: &'m ModeRecord) -> Option<&'m Summary> {
        if self.along_path() {
            mode.sequence_at(self.sequence).and_then(|s| s.frame_ms.as_ref()).or(mode.frame_ms.as_ref())
        } else {
            mode.frame_ms.as_ref()
        }
    }

    fn of(&self, mode: &ModeRecord) -> Option<f64> {
        Some((self.plot.axis_value)(self.metric.value_at(mode, self.sequence)?))
    }
}

/// The key of the front of the metric of id `id` along the plot's sequence `index` (0 for a
/// still's plot, whose recorded front is a still's).
fn metric_key(id: &str, index: usize) -> String {
    vocabulary::metric(id).map_or_else(|| id.to_string(), |metric| metric.key(index))
}

/// The modes with a value of the plot's metric and a frame time.
pub fn error_points(scene: &SceneRecord, plot: ErrorPlot) -> Vec<Point> {
    let mut points: Vec<Point> = scene
        .modes
        .iter()
        .filter_map(|mode| {
            let frame = plot.time(mode)?;
            let error = plot.of(mode)?;
            let parsed = mode.parsed()?;
            (error > 0.0).then(|| Point {
                label: parsed.short_label(),
                marker: super::plots::marker(parsed.technique),
                stalled: mode.stalled,
                time: frame.median,
                time_low: frame.ci_low,
                time_high: frame.ci_high,
                error,
                on_front: match plot.plot.front {
                    Front::Recorded(id) => mode.on_front(&metric_key(id, plot.sequence)),
                    Front::Medians | Front::None => false,
                },
            })
        })
        .collect();
    match plot.plot.front {
        Front::Recorded(_) | Front::None => {}
        Front::Medians => {
            // Every axis is an error, lower better (a JOD is drawn as its distance below 10).
            let dominated: Vec<bool> = points
                .iter()
                .map(|p| {
                    points.iter().any(|q| q.stalled == p.stalled && q.time < p.time && q.error < p.error)
                })
                .collect();
            for (point, dominated) in points.iter_mut().zip(dominated) {
                point.on_front = !dominated;
            }
        }
    }
    points
}
