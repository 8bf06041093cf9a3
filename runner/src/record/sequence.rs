//! What a scene's sequences record: the path, what it cost, and each mode's error, FLIP, JOD,
//! flicker and ghosting along it.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

use crate::measure::pixels::Decibels;
use crate::measure::stats::Summary;
use crate::measure::temporal::MeasuredSpeed;

/// What a scene's sequence rendered (`run/sequence.rs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SequenceRecord {
    /// The camera path: `orbit`, `dolly`, `pan`, `static` or `keyframes`.
    pub path: String,
    /// A preset's rate (degrees a second, or for a dolly the share of the distance a second),
    /// and the pixels a frame it moves the image at the tier's resolution (absent for keyframes,
    /// the static path and runs from before).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rate: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pixels_per_frame: Option<f64>,
    /// How fast the truth's covered pixels moved from frame to frame (median, 90th percentile,
    /// maximum): what the content did, where `pixels_per_frame` is the path's nominal speed
    /// (absent in runs from before, and where nothing covered a pixel).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measured_speed: Option<MeasuredSpeed>,
    /// The glTF animation that played along the path (its name, or `animations[i]`), if one did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub animation: Option<String>,
    /// Frames asked for, and frames rendered by every mode still running (fewer when the
    /// sequence stopped: `error` says why).
    pub frames: u32,
    pub frames_done: u32,
    pub time_step_s: f64,
    /// Truth frames rendered in this run (the others came from the cache or, frame 0, from
    /// the still truth), and the seconds they took.
    pub truth_rendered: u32,
    pub truth_render_s: f64,
    /// The truth's own mean squared frame-to-frame change: what every mode's `change_ratio`
    /// is relative to.
    pub truth_change: Option<f64>,
    /// The truth's own mean squared change along its motion (`temporal.rs`): the flicker of a
    /// blank image (black, or any one colour: its error is the truth's negative), the scale
    /// of the modes' `flicker`; not what a good steady image scores, which follows the truth's
    /// detail. Absent in runs from before; `truth_flicker` in runs before it was renamed.
    #[serde(default, alias = "truth_flicker", skip_serializing_if = "Option::is_none")]
    pub blank_flicker: Option<f64>,
    /// Wall seconds of the whole sequence.
    pub seconds: f64,
    pub error: Option<String>,
    /// Of those, the seconds spent on FLIP against the truth's frames (every mode's) and on
    /// cutting and writing the animations of the region (absent in runs from before).
    #[serde(default)]
    pub flip_s: f64,
    /// Seconds ColorVideoVDP took over the modes' frames as videos (absent in runs from
    /// before it).
    #[serde(default)]
    pub jod_s: f64,
    /// Frames along the path before its measured window that every mode and the truth
    /// rendered, unmeasured: TAA's history builds up there, and ColorVideoVDP's temporal
    /// filters read them as the window's past (only the window is pooled). In runs from before
    /// only the modes carrying a history rendered them, and the metric saw the window alone.
    #[serde(default)]
    pub warmup_frames: u32,
    /// Seconds the window starts later than the manifest's start on the keyframes' and the
    /// animation's clocks, so that the warm-up before it moves (absent where 0).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub lead_s: f64,
    /// Warm-up frames that show the same view as the frame before (neither the camera nor the
    /// animation moved): a history built there has seen a still scene (absent where 0).
    #[serde(default, skip_serializing_if = "is_zero_u32")]
    pub warmup_still_frames: u32,
    #[serde(default)]
    pub region_s: f64,
    /// Where the modes flicker most, with its animations; absent where fewer than two frames
    /// were rendered or the frames could not be spooled (`region_error` says why).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<FlickerRegion>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region_error: Option<String>,
}

fn is_zero(value: &f64) -> bool {
    *value == 0.0
}

fn is_zero_u32(value: &u32) -> bool {
    *value == 0
}

impl SequenceRecord {
    /// How fast it moves, by what the content did where measured: `1.8 px a frame (median;
    /// 3.7 nominal)`; on a path without a speed, what moves: `static, animation crossing:
    /// median 5.77, p90 5.86 px a frame over 4.1 % of the frame`; else the nominal `3.7 px a
    /// frame` or the path's name; and the animation that plays (`…, animation crossing`).
    pub fn speed(&self) -> String {
        use crate::manifest::motion::short;
        let path = match &self.animation {
            Some(animation) => format!("{}, animation {animation}", self.path),
            None => self.path.clone(),
        };
        let with_animation = |speed: String| match &self.animation {
            Some(animation) => format!("{speed}, animation {animation}"),
            None => speed,
        };
        match (self.measured_speed, self.pixels_per_frame) {
            (Some(measured), Some(px)) => with_animation(format!(
                "{} px a frame (median; {} nominal)",
                short(measured.median),
                short(px)
            )),
            // A still camera's content moves where an animation moves it: how fast, and how much
            // of the frame.
            (Some(measured), None) => match measured.moving {
                Some(share) => format!(
                    "{path}: median {}, p90 {} px a frame over {} % of the frame",
                    short(measured.median),
                    short(measured.p90),
                    crate::manifest::motion::short(share * 100.0)
                ),
                None => format!("{path}, content up to {} px a frame", short(measured.max)),
            },
            (None, Some(px)) => with_animation(format!("{px} px a frame", px = short(px))),
            (None, None) => path,
        }
    }
}

/// The square of the frame where the modes' error changes most from frame to frame
/// (`flicker.rs`), and its animated PNGs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlickerRegion {
    pub x: u32,
    pub y: u32,
    pub side: u32,
    /// The consecutive frames within which it flickers most: the report's strips.
    pub strip_first: u32,
    pub strip_frames: u32,
    /// Per stream (`truth` and the animated modes' ids), its animation of the region relative to
    /// the run folder: every frame forwards, then back, at the path's time step.
    pub animations: BTreeMap<String, String>,
}

/// One mode's sequence against the truth's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModeSequence {
    /// Per frame, against the truth's frame: MSE and PSNR on display code values in [0, 1].
    pub mse: Vec<f64>,
    pub psnr_db: Vec<Decibels>,
    /// The PSNR of the frames' mean MSE.
    pub mean_psnr_db: Decibels,
    /// Per frame, mean FLIP against the truth's frame, and its mean over the frames (absent in
    /// runs from before).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub flip: Vec<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_flip: Option<f64>,
    /// ColorVideoVDP's score of the frames as a video against the truth's, in JOD, at the
    /// path's frame rate (`perceptual::Jod`); absent in runs from before it and where the
    /// mode failed on the way.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jod: Option<f64>,
    /// The frame whose difference ColorVideoVDP found largest, and its distortion map (1 −
    /// JOD/10 per pixel in FLIP's colour scale, `<scene>/path/<mode>.jod.png`) relative to the
    /// run folder (absent where it could not be written).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jod_worst_frame: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jod_map: Option<String>,
    /// Mean squared change of the error image along the truth's motion, over the pixels seen
    /// in both frames of each pair (`temporal.rs`): what lag and blur cannot pass. Absent in
    /// runs from before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flicker: Option<f64>,
    /// Mean squared frame-to-frame change of the error image without motion compensation
    /// (`run/sequence.rs`); 0 where the mode changes exactly as the truth does. It rewards lag
    /// and blur: kept for the gate, not for ranking.
    pub instability: f64,
    /// The mode's own mean squared frame-to-frame change over the truth's (absent where the
    /// truth does not change).
    pub change_ratio: Option<f64>,
    /// Modes with a sample-count map (adaptive, msaa-4x): the share of pixels whose sample count
    /// changes from one frame to the next, averaged over the frame pairs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub count_changes: Option<f64>,
    /// Modes with a sample-count map: the share of samples shaded (as the still's
    /// `shaded_percent`), averaged over the frames: what the mode costs in motion.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shaded_percent: Option<f64>,
    /// The time of every measured frame, in ms, each frame rendered once with the modes in
    /// turn (in runs from before, every frame but the first): single samples, noisier than the
    /// still's median, but the only time taken in motion, where a `-stable` mode's counts
    /// differ from its still's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame_ms: Option<Summary>,
    /// The mode whose frames these are, where this one rendered no path of its own: a stalled
    /// mode whose still is its unstalled twin's to the bit (the stall changes the time, not the
    /// image). Such a sequence has no `frame_ms`; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frames_of: Option<String>,
    /// What lag costs: the error where the frame before did not see the surface, at moving
    /// silhouettes and elsewhere, by the truth's motion (`temporal.rs`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ghosting: Option<Ghosting>,
    /// The share of the error's energy that a blur of σ 2 px keeps, over the path's frames at
    /// the square where the modes flicker most (`measure::pixels::coarse_share`): near 1 for a
    /// smooth error, near 0 for pixel-scale aliasing. Absent where the square was not cut, and
    /// in runs from before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coarse_share: Option<f64>,
    /// FNV-1a 64 of each frame's display image and sample counts, as `output_hash`.
    pub hashes: Vec<String>,
}

/// A mode's error where lag shows, over the frame pairs of a sequence: on the pixels whose
/// surface point lay off screen or hidden behind another surface in the frame before
/// (disoccluded), on those at or beside a silhouette that moved, and on the others.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Ghosting {
    /// The share of pixels disoccluded (their point hidden behind another surface in the frame
    /// before), averaged over the frame pairs.
    pub disoccluded: f64,
    /// The mode's MSE against the truth on those pixels (display code values in [0, 1]);
    /// absent where no pixel was disoccluded.
    pub mse: Option<f64>,
    /// The share of pixels whose point entered from off the frame before, and the MSE there:
    /// content no history can hold, apart from what lag hides (absent in runs from before,
    /// which counted them as disoccluded).
    #[serde(default)]
    pub entered: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mse_entered: Option<f64>,
    /// The same at moving silhouettes, absent where none moved (absent in runs from before).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mse_edges: Option<f64>,
    /// The same everywhere else, for scale.
    pub mse_elsewhere: Option<f64>,
    /// Frame by frame from the second (each against the frame before): the trail a moving
    /// object leaves grows and shrinks as it crosses (empty in runs from before).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub per_frame: Vec<GhostFrame>,
}

/// One frame's disoccluded share and the mode's MSE on those pixels (absent where none was),
/// and the same of the pixels that entered from off screen.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GhostFrame {
    pub disoccluded: f64,
    pub mse: Option<f64>,
    /// The pixels that entered from off screen, apart (absent in runs from before).
    #[serde(default)]
    pub entered: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mse_entered: Option<f64>,
}
