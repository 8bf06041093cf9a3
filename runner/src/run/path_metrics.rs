//! Each path metric's accumulator: what it keeps of a mode's frames as the path renders, and
//! the value it concludes with. A path metric is one row of the vocabulary
//! (`vocabulary::METRICS`, source `Sequence`), which reads one field of the mode's sequence
//! record, and one accumulator here, which fills it; `measures::ModeState` steps every
//! accumulator with the same frame ([`Step`]) and assembles the record. FLIP and JOD judge the
//! path once it is rendered, from its spool (`measures::flip_along`, `measures::jod_along`):
//! their accumulators take those results.

use aabench_renderer::{DisplayImage, Mode};

use crate::measure::pixels::{self, Decibels, FrameChecks};
use crate::measure::temporal::{
    self, Flow, PairError, change_of_error, mean_of, per_value, squared_difference,
};
use crate::record::{GhostFrame, Ghosting};

/// A mode's frame: its time, display image, sample counts and checks.
pub(super) struct ModeFrame {
    pub seconds: f64,
    pub display: DisplayImage,
    pub counts: Option<Vec<u8>>,
    pub checks: FrameChecks,
}

/// A measured frame of a mode as every accumulator sees it.
pub(super) struct Step<'a> {
    pub mode: Mode,
    /// Whether the scene samples textures (what the mode's sample counts may reach).
    pub textured: bool,
    pub now: &'a ModeFrame,
    pub truth: &'a DisplayImage,
    /// The mode's frame before and the truth's, where this is not the window's first frame.
    pub before: Option<(&'a ModeFrame, &'a DisplayImage)>,
    /// The pair's error along the truth's motion and the flow it followed, where the scene has
    /// a geometry probe.
    pub followed: Option<(&'a PairError, &'a Flow)>,
}

/// What a path metric keeps of each measured frame.
pub(super) trait Accumulate {
    fn add(&mut self, step: &Step);
}

/// The mode's MSE against the truth's frame, per frame: the path's PSNR
/// (`sequence_psnr_vs_truth`).
#[derive(Default)]
pub(super) struct FrameError {
    mse: Vec<f64>,
}

/// The path's PSNR: per frame, and of the frames' mean MSE.
pub(super) struct PathPsnr {
    pub mse: Vec<f64>,
    pub psnr_db: Vec<Decibels>,
    pub mean_psnr_db: Decibels,
}

impl Accumulate for FrameError {
    fn add(&mut self, step: &Step) {
        self.mse.push(pixels::quality(&step.now.display, step.truth, "truth").mse);
    }
}

impl FrameError {
    /// How many frames it measured.
    pub fn frames(&self) -> usize {
        self.mse.len()
    }

    pub fn conclude(self) -> PathPsnr {
        let mean = self.mse.iter().sum::<f64>() / self.mse.len().max(1) as f64;
        let decibels = |mse: f64| Decibels::from_f64(-10.0 * mse.log10());
        PathPsnr {
            psnr_db: self.mse.iter().map(|&e| decibels(e)).collect(),
            mean_psnr_db: decibels(mean),
            mse: self.mse,
        }
    }
}

/// The change of the mode's error along the truth's motion (`flicker`), summed over the
/// frame pairs.
#[derive(Default)]
pub(super) struct Flicker {
    sum: (f64, u64),
}

impl Accumulate for Flicker {
    fn add(&mut self, step: &Step) {
        if let Some((error, _)) = step.followed {
            self.sum = (self.sum.0 + error.flicker.0, self.sum.1 + error.flicker.1);
        }
    }
}

impl Flicker {
    pub fn conclude(self) -> Option<f64> {
        temporal::mean(self.sum)
    }
}

/// What lag costs: the error where the frame before had the surface hidden (`disoccluded_mse`),
/// where it entered from off screen, at moving silhouettes and elsewhere; per frame pair and
/// summed.
#[derive(Default)]
pub(super) struct LagError {
    per_frame: Vec<GhostFrame>,
    sums: PairError,
}

impl Accumulate for LagError {
    fn add(&mut self, step: &Step) {
        let Some((error, flow)) = step.followed else { return };
        self.per_frame.push(GhostFrame {
            disoccluded: flow.disoccluded_share(),
            mse: temporal::mean(error.disoccluded),
            entered: flow.entered_share(),
            mse_entered: temporal::mean(error.entered),
        });
        // Flicker is its own accumulator's.
        self.sums.add(&PairError { flicker: (0.0, 0), ..*error });
    }
}

impl LagError {
    /// The shares and errors over the pairs; `None` where no pair was followed.
    pub fn conclude(self) -> Option<Ghosting> {
        let shares =
            |share: fn(&GhostFrame) -> f64| mean_of(&self.per_frame.iter().map(share).collect::<Vec<_>>());
        Some(Ghosting {
            disoccluded: shares(|g| g.disoccluded)?,
            mse: temporal::mean(self.sums.disoccluded),
            entered: shares(|g| g.entered).unwrap_or(0.0),
            mse_entered: temporal::mean(self.sums.entered),
            mse_edges: temporal::mean(self.sums.edges),
            mse_elsewhere: temporal::mean(self.sums.elsewhere),
            per_frame: self.per_frame,
        })
    }
}

/// Σ (ΔA − ΔT)² over the frame pairs, in squared code steps: the uncompensated change of error
/// (`instability`).
#[derive(Default)]
pub(super) struct Instability {
    sum: u64,
}

impl Accumulate for Instability {
    fn add(&mut self, step: &Step) {
        if let Some((before, truth_before)) = step.before {
            let (now, then) = (&step.now.display.rgba, &before.display.rgba);
            self.sum += change_of_error(now, then, &step.truth.rgba, &truth_before.rgba);
        }
    }
}

impl Instability {
    /// Per value of `last` (the mode's last frame) over `pairs` frame pairs.
    pub fn conclude(self, last: &DisplayImage, pairs: usize) -> f64 {
        per_value(self.sum, last, pairs)
    }
}

/// Σ ΔA² over the frame pairs, in squared code steps: the mode's own change, set against the
/// truth's (`change_ratio`).
#[derive(Default)]
pub(super) struct OwnChange {
    sum: u64,
}

impl Accumulate for OwnChange {
    fn add(&mut self, step: &Step) {
        if let Some((before, _)) = step.before {
            self.sum += squared_difference(&step.now.display, &before.display);
        }
    }
}

impl OwnChange {
    /// Over the truth's own change per value (`None` where the truth does not change).
    pub fn conclude(self, last: &DisplayImage, pairs: usize, truth_change: Option<f64>) -> Option<f64> {
        let own = per_value(self.sum, last, pairs);
        truth_change.filter(|&t| t > 0.0).map(|t| own / t)
    }
}

/// Per frame pair, the share of pixels whose sample count changed (`count_changes`): modes
/// with a sample-count map.
#[derive(Default)]
pub(super) struct CountChanges {
    shares: Vec<f64>,
}

impl Accumulate for CountChanges {
    fn add(&mut self, step: &Step) {
        let Some((before, _)) = step.before else { return };
        if let (Some(now), Some(then)) = (&step.now.counts, &before.counts) {
            let changed = now.iter().zip(then).filter(|(a, b)| a != b).count();
            self.shares.push(changed as f64 / now.len().max(1) as f64);
        }
    }
}

impl CountChanges {
    pub fn conclude(self) -> Option<f64> {
        mean_of(&self.shares)
    }
}

/// Per frame, the share of samples shaded (`sequence_shaded_percent`): modes with a
/// sample-count map.
#[derive(Default)]
pub(super) struct Shading {
    percents: Vec<f64>,
}

impl Accumulate for Shading {
    fn add(&mut self, step: &Step) {
        // Counts outside the window are reported by the frame's checks.
        let counts = step.now.counts.as_deref();
        if let Some(stats) = counts.and_then(|c| pixels::sample_stats(c, step.mode, step.textured).ok()) {
            self.percents.push(stats.shaded_percent);
        }
    }
}

impl Shading {
    pub fn conclude(self) -> Option<f64> {
        mean_of(&self.percents)
    }
}

/// Per frame, mean FLIP against the truth's (`sequence_flip_vs_truth`), from the spool.
#[derive(Default)]
pub(super) struct FlipAlong {
    pub per_frame: Vec<f64>,
}

impl FlipAlong {
    /// Per frame and its mean over the path's `frames`, where it has every one.
    pub fn conclude(self, frames: usize) -> (Vec<f64>, Option<f64>) {
        let mean =
            (self.per_frame.len() == frames).then(|| self.per_frame.iter().sum::<f64>() / frames as f64);
        (self.per_frame, mean)
    }
}

/// ColorVideoVDP of the frames as a video against the truth's (`sequence_jod_vs_truth`), from
/// the spool: its JOD, its worst frame and the path of that frame's distortion map.
#[derive(Default)]
pub(super) struct JodAlong {
    pub jod: Option<f64>,
    pub worst: Option<(u32, Option<String>)>,
}
