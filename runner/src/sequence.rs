//! A scene's sequence: once its stills are timed, every mode renders each frame of the
//! manifest's camera path (`motion.rs`) once, untimed, and is measured against the truth's frame
//! at the same camera.
//!
//! **Temporal instability** is how much more (or less) a mode's image changes from one frame to
//! the next than the truth's does: with A and T the mode's and the truth's display images (code
//! values scaled to [0, 1]), the mean over pixels, channels and consecutive frame pairs of
//! ((A_f − A_{f−1}) − (T_f − T_{f−1}))², which is the mean squared change of the error image
//! A − T from frame to frame. A mode whose error stays put scores 0 however large the error;
//! aliasing that shimmers or crawls, which flips the error from frame to frame, scores high.
//! No motion compensation is applied: the default paths move the image by a fraction of a pixel
//! per frame, so an error that travels with the geometry changes little between frames, and an
//! exact reprojection of a display image does not exist (disocclusions, sub-pixel detail).
//! `change_ratio` sets the mode's own mean squared frame-to-frame change against the truth's.
//!
//! A temporal mode (TAA) starts the path from a still: its warm-up frames at the first camera.
//! Its **ghosting** is its error on the pixels that its history cannot hold: those whose point
//! lay outside the previous frame, or behind the surfaces seen around where it lay (deeper
//! than each of the four nearest pixels' depths by more than [`HIDDEN_DEPTH`]), found from the
//! mode's own motion vectors and depths.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use aabench_renderer::scene::Camera;
use aabench_renderer::taa::WARMUP_FRAMES;
use aabench_renderer::{DisplayImage, Mode};

use crate::manifest::Manifest;
use crate::metrics::{self, Decibels, FrameChecks};
use crate::motion::MotionSpec;
use crate::plan::RunPlan;
use crate::progress::Progress;
use crate::record::{Ghosting, ModeSequence, SequenceRecord, fingerprint};
use crate::truth;
use crate::worker::Worker;

/// What the sequence is measured along and against: the path and its cameras in this tier, and
/// the still frame's camera, truth and truth key.
#[derive(Debug)]
pub struct Along<'a> {
    pub motion: &'a MotionSpec,
    pub cameras: &'a [Camera],
    pub still_camera: &'a Camera,
    pub still_truth: Option<&'a DisplayImage>,
    pub still_key: &'a str,
}

/// What a mode's sequence gave: its record (absent where it failed or was cut short), the checks
/// of its frames, and its error.
#[derive(Debug)]
pub struct ModeOutcome {
    pub sequence: Option<ModeSequence>,
    pub checks: FrameChecks,
    pub error: Option<String>,
}

/// A mode's frame: its time, display image, sample counts and checks, and a temporal mode's
/// geometry.
struct ModeFrame {
    seconds: f64,
    display: DisplayImage,
    counts: Option<Vec<u8>>,
    checks: FrameChecks,
    geometry: Option<Geometry>,
}

/// Where a temporal mode's pixels were in the frame before, and how deep they are now.
struct Geometry {
    width: usize,
    /// Per pixel: the pixels its point moved since the frame before, and its depth then.
    motion: Vec<[f32; 4]>,
    /// Per pixel, linear view depth at its sample, which lay `jitter` pixels off its centre.
    depth: Vec<f64>,
    jitter: [f64; 2],
}

/// How much deeper than every surface seen around its place in the frame before a point must
/// have been, relatively, to count as hidden then.
pub const HIDDEN_DEPTH: f64 = 0.01;

/// What the sequence keeps of a mode between frames, and its sums so far.
#[derive(Default)]
struct ModeState {
    previous: Option<ModeFrame>,
    mse: Vec<f64>,
    hashes: Vec<String>,
    /// Σ (ΔA − ΔT)² and Σ ΔA², in squared code steps.
    error_change: u64,
    own_change: u64,
    count_changes: Vec<f64>,
    /// Per frame, the share of samples shaded (modes with a sample-count map), and the frame's
    /// time (every frame but the first, which is rendered as a still).
    shaded_percent: Vec<f64>,
    frame_seconds: Vec<f64>,
    /// Squared error in code steps and values, on disoccluded pixels and elsewhere; the share
    /// of pixels disoccluded per frame pair.
    ghosting: [(u64, u64); 2],
    disoccluded: Vec<f64>,
    checks: FrameChecks,
    error: Option<String>,
}

/// Renders the scene's sequence with the prepared modes on the worker: `modes` pairs each with
/// whether its stills succeeded (a mode whose stills failed is left out). Returns the scene's
/// record and each mode's outcome.
pub async fn run(
    worker: &mut Worker,
    plan: &RunPlan,
    manifest: &Manifest,
    along: Along<'_>,
    modes: &[(Mode, bool)],
    progress: &Progress,
    cancel: &Arc<AtomicBool>,
) -> (SequenceRecord, Vec<ModeOutcome>) {
    let start = Instant::now();
    let mut record = SequenceRecord {
        path: along.motion.path.name().to_string(),
        frames: along.cameras.len() as u32,
        frames_done: 0,
        time_step_s: along.motion.time_step_s,
        truth_rendered: 0,
        truth_render_s: 0.0,
        truth_change: None,
        seconds: 0.0,
        error: None,
    };
    let mut states: Vec<ModeState> = modes.iter().map(|_| ModeState::default()).collect();
    let rendered =
        render_frames(worker, plan, manifest, &along, modes, progress, cancel, &mut record, &mut states);
    if let Err(error) = rendered.await {
        progress.line(&format!("[{}] warning: the sequence stopped: {error}", manifest.name));
        record.error = Some(error);
    }
    record.seconds = start.elapsed().as_secs_f64();
    let done = record.frames_done as usize;
    let outcomes = states.into_iter().map(|state| state.conclude(done, record.truth_change)).collect();
    (record, outcomes)
}

/// Renders frame after frame: the truth, then every mode. `record.frames_done` counts the
/// frames that every mode still running rendered.
#[allow(clippy::too_many_arguments)]
async fn render_frames(
    worker: &mut Worker,
    plan: &RunPlan,
    manifest: &Manifest,
    along: &Along<'_>,
    modes: &[(Mode, bool)],
    progress: &Progress,
    cancel: &Arc<AtomicBool>,
    record: &mut SequenceRecord,
    states: &mut [ModeState],
) -> Result<(), String> {
    let frames = along.cameras.len();
    let mut previous_truth: Option<DisplayImage> = None;
    let mut truth_change = 0u64;
    for (frame, &camera) in along.cameras.iter().enumerate() {
        if cancel.load(Ordering::SeqCst) {
            return Err(format!("interrupted after {frame} of {frames} frames"));
        }
        if modes.iter().zip(states.iter()).all(|((_, prepared), state)| !prepared || state.error.is_some()) {
            return Err("no mode is left to render".into());
        }
        let status = |what: &str| {
            progress.status(&format!("[{}] sequence frame {}/{frames}: {what}", manifest.name, frame + 1))
        };
        worker
            .call(plan.frame_timeout, move |state| {
                state.renderer.as_mut().expect("an uploaded scene").set_camera(&camera)
            })
            .await
            .map_err(|e| e.to_string())?
            .map_err(|e| e.to_string())?;
        let truth = match along.still_truth {
            Some(still) if camera == *along.still_camera => still.clone(),
            _ => {
                status("the truth");
                truth_frame(worker, plan, manifest, along.still_key, frame, &camera, record, progress, cancel)
                    .await?
            }
        };
        for (index, (mode, prepared)) in modes.iter().enumerate() {
            let state = &mut states[index];
            if !prepared || state.error.is_some() {
                continue;
            }
            status(&mode.to_string());
            match render(worker, plan, index, mode.m, frame == 0).await {
                Ok(Ok(rendered)) => state.add(*mode, rendered, &truth, previous_truth.as_ref()),
                Ok(Err(error)) => state.error = Some(error),
                // The worker is gone or stuck: no later frame can render.
                Err(error) => {
                    state.error = Some(error.clone());
                    return Err(format!("{mode}: {error}"));
                }
            }
        }
        if let Some(previous) = &previous_truth {
            truth_change += squared_difference(&truth, previous, None);
        }
        previous_truth = Some(truth);
        record.frames_done = frame as u32 + 1;
        if frame > 0 {
            record.truth_change =
                Some(per_value(truth_change, previous_truth.as_ref().expect("set above"), frame));
        }
    }
    Ok(())
}

/// Renders prepared mode `index` once at the current camera and reads back its frame; the
/// `first` frame of the path as a still, so that a temporal mode starts the path with the
/// history of its warm-up frames at the first camera. The outer error is the worker's (it can
/// render nothing more), the inner the mode's.
async fn render(
    worker: &mut Worker,
    plan: &RunPlan,
    index: usize,
    m: u32,
    first: bool,
) -> Result<Result<ModeFrame, String>, String> {
    let timeout = if first { plan.frame_timeout.saturating_mul(WARMUP_FRAMES) } else { plan.frame_timeout };
    let frame = worker
        .call(timeout, move |state| {
            let prepared = state.modes[index].as_ref().expect("prepared mode");
            let timing = if first { prepared.render_still()? } else { prepared.render()? };
            let display = prepared.read_display()?;
            let counts = prepared.read_sample_counts()?;
            let checks = FrameChecks::of(prepared.read_hdr()?.as_flattened(), counts.as_deref(), m);
            let geometry = match prepared.read_motion()? {
                Some(motion) => {
                    let gbuffer = prepared.read_gbuffer()?;
                    let jitter = prepared.last_jitter().unwrap_or_default();
                    Some(Geometry { width: gbuffer.width as usize, motion, depth: gbuffer.depth, jitter })
                }
                None => None,
            };
            let seconds = timing.seconds();
            Ok::<_, aabench_renderer::RenderError>(ModeFrame { seconds, display, counts, checks, geometry })
        })
        .await;
    match frame {
        Ok(frame) => Ok(frame.map_err(|e| e.to_string())),
        Err(error) => Err(error.to_string()),
    }
}

/// The truth at frame `frame` of the path: from the cache, or rendered now and cached. Its key
/// is the still truth's with the frame's camera added.
#[allow(clippy::too_many_arguments)]
async fn truth_frame(
    worker: &mut Worker,
    plan: &RunPlan,
    manifest: &Manifest,
    still_key: &str,
    frame: usize,
    camera: &Camera,
    record: &mut SequenceRecord,
    progress: &Progress,
    cancel: &Arc<AtomicBool>,
) -> Result<DisplayImage, String> {
    if still_key.is_empty() {
        return Err("the still truth has no key to derive the frames' from".into());
    }
    let resolution = plan.tier.resolution(manifest);
    let key = truth::frame_key(still_key, camera);
    let name = format!("{}-frame{frame:03}", manifest.name);
    let cache = truth::cache_file(&plan.truth_cache_dir(manifest), &name, resolution, &key);
    if let Some(display) = truth::load_cached(&cache, resolution, manifest.display_bits()) {
        return Ok(display);
    }
    let start = Instant::now();
    let timeout = plan.frame_timeout.saturating_mul(16);
    let (rendered, not_cached) =
        truth::render_and_store(worker, timeout, &cache, resolution, Arc::clone(cancel))
            .await
            .map_err(|e| format!("the truth of frame {frame}: {e}"))?;
    record.truth_rendered += 1;
    record.truth_render_s += start.elapsed().as_secs_f64();
    if let Some(error) = not_cached {
        progress
            .line(&format!("[{}] warning: the truth of frame {frame} not cached: {error}", manifest.name));
    }
    Ok(rendered.images.display)
}

impl ModeState {
    /// Adds a frame: its error against the truth's frame and, from the frame before, the change
    /// of its error, of its image and of its sample counts.
    fn add(
        &mut self,
        mode: Mode,
        frame: ModeFrame,
        truth: &DisplayImage,
        previous_truth: Option<&DisplayImage>,
    ) {
        self.checks.add(frame.checks);
        // Counts outside the window are reported by the frame's checks.
        if let Some(stats) =
            frame.counts.as_deref().and_then(|counts| metrics::sample_stats(counts, mode).ok())
        {
            self.shaded_percent.push(stats.shaded_percent);
        }
        if self.previous.is_some() {
            self.frame_seconds.push(frame.seconds);
        }
        self.hashes.push(fingerprint(&frame.display, frame.counts.as_deref()));
        self.mse.push(metrics::quality(&frame.display, truth, "truth").mse);
        if let (Some(before), Some(truth_before)) = (&self.previous, previous_truth) {
            self.error_change +=
                squared_difference(&frame.display, &before.display, Some((truth, truth_before)));
            self.own_change += squared_difference(&frame.display, &before.display, None);
            if let (Some(now), Some(then)) = (&frame.counts, &before.counts) {
                let changed = now.iter().zip(then).filter(|(a, b)| a != b).count();
                self.count_changes.push(changed as f64 / now.len().max(1) as f64);
            }
            if let (Some(now), Some(then)) = (&frame.geometry, &before.geometry) {
                let hidden = now.disoccluded(then);
                let share = hidden.iter().filter(|&&h| h).count() as f64 / hidden.len().max(1) as f64;
                self.disoccluded.push(share);
                let pixels = frame.display.rgba.chunks_exact(4).zip(truth.rgba.chunks_exact(4));
                for ((p, t), &hidden) in pixels.zip(&hidden) {
                    let sums = &mut self.ghosting[usize::from(!hidden)];
                    *sums = (sums.0 + pixel_squares(p, t), sums.1 + 3);
                }
            }
        }
        self.previous = Some(frame);
    }

    /// The mode's outcome over the `frames` frames every mode rendered: no record where it
    /// failed, where fewer than two frames were rendered, or where it rendered a frame more
    /// than the others (the sequence stopped in the middle of a frame).
    fn conclude(self, frames: usize, truth_change: Option<f64>) -> ModeOutcome {
        let ModeState {
            previous,
            mse,
            hashes,
            error_change,
            own_change,
            count_changes,
            shaded_percent,
            frame_seconds,
            ghosting,
            disoccluded,
            checks,
            error,
        } = self;
        let Some(last) = previous.filter(|_| error.is_none() && mse.len() == frames && frames > 1) else {
            return ModeOutcome { sequence: None, checks, error };
        };
        let pairs = frames - 1;
        let mean_mse = mse.iter().sum::<f64>() / frames as f64;
        let own = per_value(own_change, &last.display, pairs);
        let sequence = ModeSequence {
            psnr_db: mse.iter().map(|&e| Decibels::from_f64(-10.0 * e.log10())).collect(),
            mean_psnr_db: Decibels::from_f64(-10.0 * mean_mse.log10()),
            mse,
            instability: per_value(error_change, &last.display, pairs),
            change_ratio: truth_change.filter(|&t| t > 0.0).map(|t| own / t),
            count_changes: mean(&count_changes),
            shaded_percent: mean(&shaded_percent),
            frame_ms: crate::stats::Summary::new(frame_seconds.iter().map(|s| s * 1e3).collect()),
            ghosting: (!disoccluded.is_empty()).then(|| {
                let scale = f64::from(last.display.max_code()).powi(2);
                let mse =
                    |(sum, values): (u64, u64)| (values > 0).then(|| sum as f64 / scale / values as f64);
                Ghosting {
                    disoccluded: disoccluded.iter().sum::<f64>() / disoccluded.len() as f64,
                    mse: mse(ghosting[0]),
                    mse_elsewhere: mse(ghosting[1]),
                }
            }),
            hashes,
        };
        ModeOutcome { sequence: Some(sequence), checks, error: None }
    }
}

impl Geometry {
    /// Per pixel, whether the frame before (`then`) could not have seen its point: it lay
    /// outside that frame, or deeper than each of the four samples around where it lay by more
    /// than [`HIDDEN_DEPTH`]. Pixels without geometry (depth 0 then) are never disoccluded.
    fn disoccluded(&self, then: &Geometry) -> Vec<bool> {
        let width = self.width as f64;
        let height = (self.motion.len() / self.width.max(1)) as f64;
        self.motion
            .iter()
            .enumerate()
            .map(|(i, &[dx, dy, depth_then, _])| {
                let depth_then = f64::from(depth_then);
                if depth_then <= 0.0 {
                    return false;
                }
                // The motion is the sample's, which lay `jitter` off the pixel's centre.
                let [sx, sy] = self.jitter;
                let x = (i % self.width) as f64 + 0.5 + sx - f64::from(dx);
                let y = (i / self.width) as f64 + 0.5 + sy - f64::from(dy);
                if !(0.0..width).contains(&x) || !(0.0..height).contains(&y) {
                    return true;
                }
                // The four pixels whose samples surround the point, clamped to the frame.
                let [jx, jy] = then.jitter;
                let (x0, y0) = ((x - 0.5 - jx).floor(), (y - 0.5 - jy).floor());
                let around = [(x0, y0), (x0 + 1.0, y0), (x0, y0 + 1.0), (x0 + 1.0, y0 + 1.0)];
                around.iter().all(|&(ax, ay)| {
                    let ax = ax.clamp(0.0, width - 1.0) as usize;
                    let ay = ay.clamp(0.0, height - 1.0) as usize;
                    depth_then > then.depth[ay * self.width + ax] * (1.0 + HIDDEN_DEPTH)
                })
            })
            .collect()
    }
}

/// The mean of `values`, where there are any.
fn mean(values: &[f64]) -> Option<f64> {
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

/// Σ over pixels and colour channels of (a − b)², or of ((a − b) − (c − d))² with `minus` =
/// (c, d), in squared code steps (exact in integers).
fn squared_difference(
    a: &DisplayImage,
    b: &DisplayImage,
    minus: Option<(&DisplayImage, &DisplayImage)>,
) -> u64 {
    assert_eq!(a.rgba.len(), b.rgba.len(), "images of different sizes");
    // The colour channels of each pixel: alpha is left out.
    fn colour(image: &DisplayImage) -> impl Iterator<Item = [u16; 3]> + '_ {
        image.rgba.chunks_exact(4).map(|p| [p[0], p[1], p[2]])
    }
    let step = |x: u16, y: u16| i64::from(x) - i64::from(y);
    let mut sum = 0u64;
    match minus {
        None => {
            for (p, q) in a.rgba.chunks_exact(4).zip(b.rgba.chunks_exact(4)) {
                sum += pixel_squares(p, q);
            }
        }
        Some((c, d)) => {
            for ((p, q), (r, s)) in colour(a).zip(colour(b)).zip(colour(c).zip(colour(d))) {
                sum += (0..3).map(|i| (step(p[i], q[i]) - step(r[i], s[i])).pow(2) as u64).sum::<u64>();
            }
        }
    }
    sum
}

/// Σ over a pixel's colour channels (RGBA, alpha left out) of (p − q)², in squared code steps.
fn pixel_squares(p: &[u16], q: &[u16]) -> u64 {
    (0..3).map(|c| u64::from(p[c].abs_diff(q[c])).pow(2)).sum()
}

/// A sum of squared code steps over `frames` images like `image`, as a mean over values in
/// [0, 1].
fn per_value(sum: u64, image: &DisplayImage, frames: usize) -> f64 {
    let scale = f64::from(image.max_code());
    let values = (image.rgba.len() / 4 * 3 * frames).max(1) as f64;
    sum as f64 / (scale * scale) / values
}
