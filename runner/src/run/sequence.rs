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
//! Every frame is spooled to disk as it renders (`spool.rs`). Once the last is done, every frame
//! is compared with the truth's by FLIP (`perceptual.rs`), on every core and without disturbing
//! a render's time, and the square where the modes flicker most is cut from them as animations
//! (`flicker.rs`).
//!
//! A temporal mode (TAA) starts the path from a still: its warm-up frames at the first camera.
//! Its **ghosting** is its error on the pixels that its history cannot hold: those whose point
//! lay outside the previous frame, or behind the surfaces seen around where it lay (deeper
//! than each of the four nearest pixels' depths by more than [`HIDDEN_DEPTH`]), found from the
//! mode's own motion vectors and depths.

use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::Instant;

use aabench_renderer::scene::Camera;
use aabench_renderer::taa::WARMUP_FRAMES;
use aabench_renderer::{DisplayImage, Mode};

use super::scene::SceneRun;
use crate::flicker::{self, TRUTH_STREAM, pixel_changes_of_error};
use crate::metrics::{self, Decibels, FrameChecks};
use crate::motion::MotionSpec;
use crate::record::{Ghosting, ModeSequence, SequenceRecord, fingerprint};
use crate::spool::Spool;
use crate::truth;

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
pub(super) const HIDDEN_DEPTH: f64 = 0.01;

/// What the sequence keeps of a mode between frames, and its sums so far.
#[derive(Default)]
struct ModeState {
    previous: Option<ModeFrame>,
    mse: Vec<f64>,
    /// Per frame, FLIP against the truth's: filled in once the path is rendered.
    flip: Vec<f64>,
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
pub(super) async fn run(
    scene: &mut SceneRun<'_>,
    along: Along<'_>,
    modes: &[(Mode, bool)],
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
        flip_s: 0.0,
        region_s: 0.0,
        region: None,
        region_error: None,
    };
    let mut states: Vec<ModeState> = modes.iter().map(|_| ModeState::default()).collect();
    // Every mode's frames are spooled, to stream `index + 1`; the truth's to stream 0.
    let out_dir = scene.dir.join("path");
    let size = scene.resolution;
    let names =
        std::iter::once(TRUTH_STREAM.to_string()).chain(modes.iter().map(|(mode, _)| mode.to_string()));
    let mut spool = Spool::create(out_dir.join(".spool"), size, names.collect());
    let mut flicker = vec![0u64; size[0] as usize * size[1] as usize];
    let rendered = render_frames(scene, &along, modes, &mut record, &mut states, (&mut spool, &mut flicker));
    if let Err(error) = rendered.await {
        scene.warn(&format!("the sequence stopped: {error}"));
        record.error = Some(error);
    }
    let done = record.frames_done as usize;
    scene.status("sequence: FLIP and the worst-flickering region");
    let animated_streams: Vec<usize> =
        (0..modes.len()).filter(|&i| animated(modes[i].0, modes)).map(|i| i + 1).collect();
    let (delay_s, run_dir) = (along.motion.time_step_s, scene.plan.run_dir.clone());
    let after = tokio::task::spawn_blocking(move || {
        let spool = spool?;
        let start = Instant::now();
        let flips = flip_along(&spool, done)?;
        let flip_s = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let region =
            flicker::region(&spool, &flicker, &animated_streams, done, delay_s, [&run_dir, &out_dir]);
        Ok::<_, String>((flips, flip_s, region, start.elapsed().as_secs_f64()))
    });
    match after.await.map_err(|panic| format!("panicked: {panic}")).and_then(|after| after) {
        Ok((flips, flip_s, region, region_s)) => {
            for (state, flip) in states.iter_mut().zip(flips.into_iter().skip(1)) {
                state.flip = flip;
            }
            (record.flip_s, record.region_s) = (flip_s, region_s);
            match region {
                Ok(region) => record.region = Some(region),
                Err(error) => record.region_error = Some(error),
            }
        }
        Err(error) => {
            scene.warn(&format!("no FLIP along the path and no flicker region: {error}"));
            record.region_error = Some(error);
        }
    }
    record.seconds = start.elapsed().as_secs_f64();
    let outcomes = states.into_iter().map(|state| state.conclude(done, record.truth_change)).collect();
    (record, outcomes)
}

/// Whether the sequence animates `mode`'s region: every mode but a stalled one whose unstalled
/// twin runs too (stalling changes the time, not the image).
fn animated(mode: Mode, modes: &[(Mode, bool)]) -> bool {
    !mode.stalled || !modes.iter().any(|(other, _)| *other == Mode { stalled: false, ..mode })
}

/// Renders frame after frame: the truth, then every mode. `record.frames_done` counts the
/// frames that every mode still running rendered.
async fn render_frames(
    scene: &mut SceneRun<'_>,
    along: &Along<'_>,
    modes: &[(Mode, bool)],
    record: &mut SequenceRecord,
    states: &mut [ModeState],
    (spool, flicker): (&mut Result<Spool, String>, &mut [u64]),
) -> Result<(), String> {
    let frames = along.cameras.len();
    // A frame that cannot be spooled (a full disk) ends the spooling: the sequence goes on
    // without FLIP and animations, and says why.
    let mut keep = |stream: usize, image: &DisplayImage| {
        if let Ok(kept) = spool
            && let Err(error) = kept.append(stream, image)
        {
            *spool = Err(error);
        }
    };
    let mut previous_truth: Option<DisplayImage> = None;
    let mut truth_change = 0u64;
    for (frame, &camera) in along.cameras.iter().enumerate() {
        if scene.cancelled() {
            return Err(format!("interrupted after {frame} of {frames} frames"));
        }
        if modes.iter().zip(states.iter()).all(|((_, prepared), state)| !prepared || state.error.is_some()) {
            return Err("no mode is left to render".into());
        }
        let status = |scene: &SceneRun, what: &str| {
            scene.status(&format!("sequence frame {}/{frames}: {what}", frame + 1))
        };
        scene
            .worker
            .call(scene.plan.frame_timeout, move |state| {
                state.renderer.as_mut().expect("an uploaded scene").set_camera(&camera)
            })
            .await
            .map_err(|e| e.to_string())?
            .map_err(|e| e.to_string())?;
        let truth = match along.still_truth {
            Some(still) if camera == *along.still_camera => still.clone(),
            _ => {
                status(scene, "the truth");
                truth_frame(scene, along.still_key, frame, &camera, record).await?
            }
        };
        keep(0, &truth);
        for (index, (mode, prepared)) in modes.iter().enumerate() {
            let state = &mut states[index];
            if !prepared || state.error.is_some() {
                continue;
            }
            status(scene, &mode.to_string());
            match render(scene, index, mode.m, frame == 0).await {
                Ok(Ok(rendered)) => {
                    keep(index + 1, &rendered.display);
                    state.add(*mode, rendered, &truth, previous_truth.as_ref(), flicker);
                }
                Ok(Err(error)) => state.error = Some(error),
                // The worker is gone or stuck: no later frame can render.
                Err(error) => {
                    state.error = Some(error.clone());
                    return Err(format!("{mode}: {error}"));
                }
            }
        }
        if let Some(previous) = &previous_truth {
            truth_change += squared_difference(&truth, previous);
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
    scene: &mut SceneRun<'_>,
    index: usize,
    m: u32,
    first: bool,
) -> Result<Result<ModeFrame, String>, String> {
    let frame_timeout = scene.plan.frame_timeout;
    let timeout = if first { frame_timeout.saturating_mul(WARMUP_FRAMES) } else { frame_timeout };
    let frame = scene
        .worker
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
async fn truth_frame(
    scene: &mut SceneRun<'_>,
    still_key: &str,
    frame: usize,
    camera: &Camera,
    record: &mut SequenceRecord,
) -> Result<DisplayImage, String> {
    if still_key.is_empty() {
        return Err("the still truth has no key to derive the frames' from".into());
    }
    let (plan, manifest, resolution) = (scene.plan, scene.manifest, scene.resolution);
    let key = truth::frame_key(still_key, camera);
    let name = format!("{}-frame{frame:03}", manifest.name);
    let cache = truth::cache_file(&plan.truth_cache_dir(manifest), &name, resolution, &key);
    if let Some(display) = truth::load_cached(&cache, resolution, manifest.display_bits()) {
        return Ok(display);
    }
    let start = Instant::now();
    let timeout = plan.frame_timeout.saturating_mul(16);
    let (rendered, not_cached) =
        truth::render_and_store(scene.worker, timeout, &cache, resolution, Arc::clone(scene.cancel))
            .await
            .map_err(|e| format!("the truth of frame {frame}: {e}"))?;
    record.truth_rendered += 1;
    record.truth_render_s += start.elapsed().as_secs_f64();
    if let Some(error) = not_cached {
        scene.warn(&format!("the truth of frame {frame} not cached: {error}"));
    }
    Ok(rendered.images.display)
}

impl ModeState {
    /// Adds a frame: its error against the truth's frame and, from the frame before, the change
    /// of its error (also added per pixel to `flicker`), of its image and of its sample counts.
    fn add(
        &mut self,
        mode: Mode,
        frame: ModeFrame,
        truth: &DisplayImage,
        previous_truth: Option<&DisplayImage>,
        flicker: &mut [u64],
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
                change_of_error(&frame.display, &before.display, truth, truth_before, flicker);
            self.own_change += squared_difference(&frame.display, &before.display);
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
            flip,
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
            mean_flip: (flip.len() == frames).then(|| flip.iter().sum::<f64>() / frames as f64),
            flip,
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

/// Per stream of the spool, each of its first `frames` frames' mean FLIP against the truth's
/// frame (stream 0's); empty for the truth's and for a stream that holds fewer frames (its mode
/// failed on the way). Frames identical to another (a stalled mode's and its twin's) are
/// compared once; the comparisons of a frame run on every core.
fn flip_along(spool: &Spool, frames: usize) -> Result<Vec<Vec<f64>>, String> {
    let [width, height] = spool.size();
    let complete: Vec<usize> = (1..spool.streams()).filter(|&s| spool.frames(s) >= frames).collect();
    let mut flips = vec![Vec::with_capacity(frames); spool.streams()];
    let threads = std::thread::available_parallelism().map_or(1, usize::from);
    for frame in 0..frames {
        let truth = spool.frame(0, frame)?;
        let images = complete.iter().map(|&s| spool.frame(s, frame)).collect::<Result<Vec<_>, _>>()?;
        let mut seen = std::collections::HashSet::new();
        let distinct: Vec<&[u8]> =
            images.iter().map(Vec::as_slice).filter(|image| seen.insert(*image)).collect();
        let next = std::sync::atomic::AtomicUsize::new(0);
        let compare = || {
            let mut done = Vec::new();
            loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(image) = distinct.get(i) else { return done };
                done.push((*image, crate::perceptual::flip_rgba8(image, &truth, width, height).mean()));
            }
        };
        let values: std::collections::HashMap<&[u8], f64> = std::thread::scope(|scope| {
            let workers: Vec<_> = (0..threads).map(|_| scope.spawn(compare)).collect();
            workers.into_iter().flat_map(|w| w.join().expect("a FLIP thread panicked")).collect()
        });
        for (&stream, image) in complete.iter().zip(&images) {
            flips[stream].push(values[image.as_slice()]);
        }
    }
    Ok(flips)
}

/// The mean of `values`, where there are any.
fn mean(values: &[f64]) -> Option<f64> {
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

/// Σ over pixels and colour channels of (a − b)², in squared code steps (exact in integers).
fn squared_difference(a: &DisplayImage, b: &DisplayImage) -> u64 {
    assert_eq!(a.rgba.len(), b.rgba.len(), "images of different sizes");
    a.rgba.chunks_exact(4).zip(b.rgba.chunks_exact(4)).map(|(p, q)| pixel_squares(p, q)).sum()
}

/// Σ over pixels and colour channels of ((a − b) − (t − u))², the squared change of the error
/// image from (b, u) to (a, t), in squared code steps; each pixel's share is also added to
/// `per_pixel`.
fn change_of_error(
    a: &DisplayImage,
    b: &DisplayImage,
    t: &DisplayImage,
    u: &DisplayImage,
    per_pixel: &mut [u64],
) -> u64 {
    let mut sum = 0;
    for (change, out) in pixel_changes_of_error(&a.rgba, &b.rgba, &t.rgba, &u.rgba).zip(per_pixel) {
        *out += change;
        sum += change;
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
