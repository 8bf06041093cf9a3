//! A scene's sequence: once its stills are timed, every mode renders each frame of the
//! manifest's camera path (`motion.rs`) once, untimed, and is measured against the truth's frame
//! at the same camera. A stalled mode whose still is its unstalled twin's to the bit renders no
//! path of its own: it takes its twin's frames (the stall changes the time, not the image).
//!
//! **Flicker** is measured along the truth's own motion (`temporal.rs`): each pixel followed
//! back to where its surface point lay in the frame before, by the scene's geometry probe
//! rendered at every frame, and the mode's error compared there. An error that travels with the
//! surface does not count; one that crawls, shimmers or stays put while the scene moves does.
//! Beside it, what lag costs: the error on the pixels the frame before did not see
//! (disoccluded), at silhouettes that moved, and elsewhere.
//!
//! **Temporal instability** is kept for the gate: the mean over pixels, channels and
//! consecutive frame pairs of ((A_f − A_{f−1}) − (T_f − T_{f−1}))², with A and T the mode's and
//! the truth's display images (code values scaled to [0, 1]), without motion compensation. It
//! rewards lag and blur: an image that never changes scores the truth's own change.
//! `change_ratio` sets the mode's own mean squared frame-to-frame change against the truth's.
//!
//! Every frame is spooled to disk as it renders (`spool.rs`). Once the last is done, every frame
//! is compared with the truth's by FLIP (`perceptual.rs`), on every core and without disturbing
//! a render's time, and the square where the modes flicker most is cut from them as animations
//! (`flicker.rs`).
//!
//! A temporal mode (TAA) starts the path from a still: its warm-up frames at the first camera.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use aabench_renderer::scene::Camera;
use aabench_renderer::taa::WARMUP_FRAMES;
use aabench_renderer::{DisplayImage, Mode};

use super::rounds::ModeRun;
use super::scene::SceneRun;
use crate::flicker::{self, TRUTH_STREAM, pixel_changes_of_error};
use crate::metrics::{self, Decibels, FrameChecks};
use crate::motion::{MotionSpec, Pace, PathKind};
use crate::record::{GhostFrame, Ghosting, ModeSequence, SequenceRecord, fingerprint};
use crate::spool::Spool;
use crate::temporal::{self, Flow, Geometry, PairError};
use crate::truth;

/// What the sequence is measured along and against: the path and its cameras in this tier, and
/// the still frame's camera, truth and truth key.
#[derive(Debug)]
pub struct Along<'a> {
    pub motion: &'a MotionSpec,
    pub pace: Pace,
    pub cameras: &'a [Camera],
    /// The folder under the scene's that holds the sequence's animations.
    pub folder: &'a str,
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

impl ModeOutcome {
    /// The outcome of a mode that takes the frames of `twin`, whose outcome this is: its
    /// sequence without a time of its own.
    fn of_twin(&self, twin: Mode) -> ModeOutcome {
        let sequence = self.sequence.clone().map(|sequence| ModeSequence {
            frame_ms: None,
            frames_of: Some(twin.to_string()),
            ..sequence
        });
        let error = self.error.as_ref().map(|error| format!("{twin}, whose frames it takes: {error}"));
        ModeOutcome { sequence, checks: self.checks, error }
    }
}

/// A mode as the sequence takes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct PathMode {
    pub mode: Mode,
    /// Whether its stills succeeded: a mode whose stills failed is left out.
    pub ready: bool,
    /// The mode (its index) whose frames are this one's: set for a stalled mode whose still is
    /// its unstalled twin's to the bit, which renders no path of its own.
    pub frames_of: Option<usize>,
}

impl PathMode {
    /// The scene's modes, from what their stills gave.
    pub fn of(modes: &[Mode], runs: &[ModeRun]) -> Vec<PathMode> {
        let hashed = |i: usize| runs[i].error.is_none() && !runs[i].hashes.is_empty();
        let twin = |i: usize| {
            let plain = Mode { stalled: false, ..modes[i] };
            let t = modes.iter().position(|other| *other == plain)?;
            (modes[i].stalled && hashed(i) && hashed(t) && runs[i].hashes == runs[t].hashes).then_some(t)
        };
        (0..modes.len())
            .map(|i| PathMode { mode: modes[i], ready: runs[i].error.is_none(), frames_of: twin(i) })
            .collect()
    }

    /// Whether it renders the path itself.
    fn renders(&self) -> bool {
        self.ready && self.frames_of.is_none()
    }
}

/// A mode's frame: its time, display image, sample counts and checks.
struct ModeFrame {
    seconds: f64,
    display: DisplayImage,
    counts: Option<Vec<u8>>,
    checks: FrameChecks,
}

/// The truth's frame and the frame before, and how the pixels of one follow back into the
/// other.
struct TruthPair<'a> {
    now: &'a DisplayImage,
    then: Option<&'a DisplayImage>,
    flow: Option<&'a Flow>,
}

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
    /// The error along the truth's motion, summed over the frame pairs; per pair, the share of
    /// pixels disoccluded and the error there.
    followed: PairError,
    ghosting: Vec<GhostFrame>,
    checks: FrameChecks,
    error: Option<String>,
}

/// Renders the scene's sequence with the prepared modes on the worker. Returns the scene's
/// record and each mode's outcome.
pub(super) async fn run(
    scene: &mut SceneRun<'_>,
    along: Along<'_>,
    modes: &[PathMode],
) -> (SequenceRecord, Vec<ModeOutcome>) {
    let start = Instant::now();
    let fixed = matches!(along.motion.path, PathKind::Static | PathKind::Keyframes);
    let mut record = SequenceRecord {
        path: along.motion.path.name().to_string(),
        rate: (!fixed).then_some(along.pace.rate),
        pixels_per_frame: along.pace.pixels_per_frame,
        animation: along.motion.animation.as_ref().map(|pick| match (&pick.name, pick.index) {
            (Some(name), _) => name.clone(),
            (None, index) => format!("animations[{}]", index.unwrap_or_default()),
        }),
        frames: along.cameras.len() as u32,
        frames_done: 0,
        time_step_s: along.motion.time_step_s,
        truth_rendered: 0,
        truth_render_s: 0.0,
        truth_change: None,
        truth_flicker: None,
        seconds: 0.0,
        error: None,
        flip_s: 0.0,
        region_s: 0.0,
        region: None,
        region_error: None,
    };
    let mut states: Vec<ModeState> = modes.iter().map(|_| ModeState::default()).collect();
    // Every mode's frames are spooled, to stream `index + 1`; the truth's to stream 0.
    let out_dir = scene.dir.join(along.folder);
    let size = scene.resolution;
    let names = std::iter::once(TRUTH_STREAM.to_string()).chain(modes.iter().map(|m| m.mode.to_string()));
    let mut spool = Spool::create(crate::spool::folder(&out_dir), size, names.collect());
    let mut flicker = vec![0.0; size[0] as usize * size[1] as usize];
    let rendered = render_frames(scene, &along, modes, &mut record, &mut states, (&mut spool, &mut flicker));
    if let Err(error) = rendered.await {
        scene.warn(&format!("the sequence stopped: {error}"));
        record.error = Some(error);
    }
    let done = record.frames_done as usize;
    scene.status("sequence: FLIP and the worst-flickering region");
    // A mode that takes its twin's frames shows in its twin's animation.
    let animated_streams: Vec<usize> =
        (0..modes.len()).filter(|&i| modes[i].frames_of.is_none()).map(|i| i + 1).collect();
    let (delay_s, run_dir) = (along.motion.time_step_s, scene.plan.run_dir.clone());
    let cancel = Arc::clone(scene.cancel);
    let after = tokio::task::spawn_blocking(move || {
        let spool = spool?;
        spool.check()?;
        let start = Instant::now();
        let flips = flip_along(&spool, done, &cancel)?;
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
    let mut outcomes: Vec<ModeOutcome> =
        states.into_iter().map(|state| state.conclude(done, record.truth_change)).collect();
    for (index, path_mode) in modes.iter().enumerate() {
        if let Some(twin) = path_mode.frames_of {
            outcomes[index] = outcomes[twin].of_twin(modes[twin].mode);
        }
    }
    (record, outcomes)
}

/// Renders frame after frame: the truth, then every mode. `record.frames_done` counts the
/// frames that every mode still running rendered.
async fn render_frames(
    scene: &mut SceneRun<'_>,
    along: &Along<'_>,
    modes: &[PathMode],
    record: &mut SequenceRecord,
    states: &mut [ModeState],
    (spool, flicker): (&mut Result<Spool, String>, &mut [f64]),
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
    let mut track = TruthTrack::default();
    prepare_geometry(scene).await?;
    for (frame, &camera) in along.cameras.iter().enumerate() {
        if scene.cancelled() {
            return Err(format!("interrupted after {frame} of {frames} frames"));
        }
        if modes.iter().zip(states.iter()).all(|(mode, state)| !mode.renders() || state.error.is_some()) {
            return Err("no mode is left to render".into());
        }
        let status = |scene: &SceneRun, what: &str| {
            scene.status(&format!("sequence frame {}/{frames}: {what}", frame + 1))
        };
        // The animation's time now and at the frame before (the first frame is a still).
        let times =
            along.motion.animation_time(frame).zip(along.motion.animation_time(frame.saturating_sub(1)));
        set_view(scene, camera, times).await?;
        // The still is the first frame's pose: a later frame of an animation is not.
        let still_pose = frame == 0 || times.is_none();
        let truth = match along.still_truth {
            Some(still) if camera == *along.still_camera && still_pose => still.clone(),
            _ => {
                status(scene, "the truth");
                let view = FrameView { frame, camera: &camera, time: times.map(|(now, _)| now) };
                truth_frame(scene, along.still_key, view, record).await?
            }
        };
        keep(0, &truth);
        status(scene, "the geometry");
        let then = &along.cameras[frame.saturating_sub(1)];
        let geometry = geometry(scene, [&camera, then], frame == 0).await?;
        let (truth_then, geometry_then) = track.previous.as_ref().map(|(t, g)| (t, g)).unzip();
        let flow = geometry_then.map(|then| Flow::between(&geometry, then));
        let pair = TruthPair { now: &truth, then: truth_then, flow: flow.as_ref() };
        for (index, path_mode) in modes.iter().enumerate() {
            let (mode, state) = (&path_mode.mode, &mut states[index]);
            if !path_mode.renders() || state.error.is_some() {
                continue;
            }
            status(scene, &mode.to_string());
            match render(scene, index, mode.m, frame).await {
                Ok(Ok(rendered)) => {
                    keep(index + 1, &rendered.display);
                    state.add(*mode, rendered, &pair, flicker, scene.textured);
                }
                Ok(Err(error)) => state.error = Some(error),
                // The worker is gone or stuck: no later frame can render.
                Err(error) => {
                    state.error = Some(error.clone());
                    return Err(format!("{mode}: {error}"));
                }
            }
        }
        track.advance(truth, geometry, flow.as_ref(), record);
        record.frames_done = frame as u32 + 1;
    }
    Ok(())
}

/// The truth's side of a sequence: its frame and geometry before, and its own changes so far.
#[derive(Default)]
struct TruthTrack {
    previous: Option<(DisplayImage, Geometry)>,
    /// Σ of the squared frame-to-frame change, in squared code steps, over the pairs so far.
    change: u64,
    pairs: usize,
    /// Σ of the squared change along the motion, and its count of values.
    along_motion: (f64, u64),
}

impl TruthTrack {
    /// Takes the next frame's truth and geometry, followed back into the frame before by
    /// `flow`, and records the truth's own changes so far.
    fn advance(
        &mut self,
        truth: DisplayImage,
        geometry: Geometry,
        flow: Option<&Flow>,
        record: &mut SequenceRecord,
    ) {
        if let Some((before, _)) = &self.previous {
            self.change += squared_difference(&truth, before);
            self.pairs += 1;
            record.truth_change = Some(per_value(self.change, &truth, self.pairs));
            if let Some(flow) = flow {
                let (sum, count) = flow.own_change(&truth, before);
                self.along_motion = (self.along_motion.0 + sum, self.along_motion.1 + count);
                record.truth_flicker = temporal::mean(self.along_motion);
            }
        }
        self.previous = Some((truth, geometry));
    }
}

/// Moves the renderer's camera, and poses the scene where an animation plays (at its time now
/// and at the frame before): every frame rendered after sees the scene so.
async fn set_view(scene: &mut SceneRun<'_>, camera: Camera, times: Option<(f64, f64)>) -> Result<(), String> {
    scene
        .worker
        .call(scene.plan.frame_timeout, move |state| {
            let renderer = state.renderer.as_mut().expect("an uploaded scene");
            renderer.set_camera(&camera)?;
            match times {
                Some((now, then)) => renderer.pose(now, then),
                None => Ok(()),
            }
        })
        .await
        .map_err(|e| e.to_string())?
        .map_err(|e| e.to_string())
}

/// Renders prepared mode `index` once at the current camera and reads back its frame `frame`;
/// the path's first as a still, so that a temporal mode starts the path with the history of its
/// warm-up frames at the first camera. The outer error is the worker's (it can render nothing
/// more), the inner the mode's: a frame that shows nothing fails the mode, naming the frame,
/// unless the scene is declared empty.
async fn render(
    scene: &mut SceneRun<'_>,
    index: usize,
    m: u32,
    frame: usize,
) -> Result<Result<ModeFrame, String>, String> {
    let (first, declared_empty) = (frame == 0, scene.manifest.empty);
    let frame_timeout = scene.plan.frame_timeout;
    let timeout = if first { frame_timeout.saturating_mul(WARMUP_FRAMES) } else { frame_timeout };
    let rendered = scene
        .worker
        .call(timeout, move |state| {
            let prepared = state.modes[index].as_ref().expect("prepared mode");
            let timing = if first { prepared.render_still()? } else { prepared.render()? };
            let display = prepared.read_display()?;
            let counts = prepared.read_sample_counts()?;
            let hdr = prepared.read_hdr()?;
            let checks = FrameChecks::of(hdr.as_flattened(), counts.as_deref(), m);
            let blank = metrics::blank_image(hdr.as_flattened(), &display).filter(|_| !declared_empty);
            let seconds = timing.seconds();
            Ok::<_, aabench_renderer::RenderError>((ModeFrame { seconds, display, counts, checks }, blank))
        })
        .await
        .map_err(|error| error.to_string())?;
    Ok(match rendered {
        Ok((_, Some(blank))) => Err(format!("frame {frame}: {blank}")),
        Ok((rendered, None)) => Ok(rendered),
        Err(error) => Err(error.to_string()),
    })
}

/// Prepares the scene's geometry probe on the worker, which the truth's frames follow.
async fn prepare_geometry(scene: &mut SceneRun<'_>) -> Result<(), String> {
    scene
        .worker
        .call(scene.plan.frame_timeout, |state| {
            let renderer = state.renderer.as_mut().expect("an uploaded scene");
            state.geometry = Some(renderer.prepare_geometry()?);
            Ok::<_, aabench_renderer::RenderError>(())
        })
        .await
        .map_err(|e| e.to_string())?
        .map_err(|e| format!("the geometry probe: {e}"))
}

/// Renders the geometry probe at the current camera, `cameras[0]`, and reads it back; the frame
/// before was seen through `cameras[1]`. The `first` frame of the path renders from a reset, so
/// that it has no motion.
async fn geometry(scene: &mut SceneRun<'_>, cameras: [&Camera; 2], first: bool) -> Result<Geometry, String> {
    let [now, then] = cameras.map(|camera| *camera);
    scene
        .worker
        .call(scene.plan.frame_timeout, move |state| {
            let probe = state.geometry.as_ref().expect("a prepared geometry probe");
            if first {
                probe.render_still()?;
            } else {
                probe.render()?;
            }
            let motion = probe.read_motion()?.expect("the probe writes motion");
            let gbuffer = probe.read_gbuffer()?;
            Ok::<_, aabench_renderer::RenderError>(Geometry::from_probe(&gbuffer, &motion, [&now, &then]))
        })
        .await
        .map_err(|e| e.to_string())?
        .map_err(|e| format!("the geometry probe: {e}"))
}

/// A frame of the path: its index, camera and, where an animation plays, its time.
struct FrameView<'a> {
    frame: usize,
    camera: &'a Camera,
    time: Option<f64>,
}

/// The truth at a frame of the path: from the cache, or rendered now and cached. Its key is the
/// still truth's with the frame's camera and animation time added.
async fn truth_frame(
    scene: &mut SceneRun<'_>,
    still_key: &str,
    FrameView { frame, camera, time }: FrameView<'_>,
    record: &mut SequenceRecord,
) -> Result<DisplayImage, String> {
    if still_key.is_empty() {
        return Err("the still truth has no key to derive the frames' from".into());
    }
    let (plan, manifest, resolution) = (scene.plan, scene.manifest, scene.resolution);
    let key = truth::frame_key(still_key, camera, time);
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
    /// Adds a frame: its error against the truth's frame and, from the frame before, its error
    /// along the truth's motion (each pixel's flicker also added to `flicker`), and the change
    /// of its error, of its image and of its sample counts.
    fn add(&mut self, mode: Mode, frame: ModeFrame, truth: &TruthPair, flicker: &mut [f64], textured: bool) {
        self.checks.add(frame.checks);
        // Counts outside the window are reported by the frame's checks.
        if let Some(stats) =
            frame.counts.as_deref().and_then(|counts| metrics::sample_stats(counts, mode, textured).ok())
        {
            self.shaded_percent.push(stats.shaded_percent);
        }
        if self.previous.is_some() {
            self.frame_seconds.push(frame.seconds);
        }
        self.hashes.push(fingerprint(&frame.display, frame.counts.as_deref()));
        self.mse.push(metrics::quality(&frame.display, truth.now, "truth").mse);
        if let (Some(before), Some(truth_before)) = (&self.previous, truth.then) {
            self.error_change += change_of_error(&frame.display, &before.display, truth.now, truth_before);
            self.own_change += squared_difference(&frame.display, &before.display);
            if let (Some(now), Some(then)) = (&frame.counts, &before.counts) {
                let changed = now.iter().zip(then).filter(|(a, b)| a != b).count();
                self.count_changes.push(changed as f64 / now.len().max(1) as f64);
            }
            if let Some(flow) = truth.flow {
                let pair = [&frame.display, truth.now];
                let error = flow.error(pair, [&before.display, truth_before], flicker);
                self.ghosting.push(GhostFrame {
                    disoccluded: flow.disoccluded_share(),
                    mse: temporal::mean(error.disoccluded),
                });
                self.followed.add(&error);
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
            followed,
            ghosting,
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
            frames_of: None,
            flicker: temporal::mean(followed.flicker),
            ghosting: mean(&ghosting.iter().map(|g| g.disoccluded).collect::<Vec<_>>()).map(|disoccluded| {
                Ghosting {
                    disoccluded,
                    mse: temporal::mean(followed.disoccluded),
                    mse_edges: temporal::mean(followed.edges),
                    mse_elsewhere: temporal::mean(followed.elsewhere),
                    per_frame: ghosting,
                }
            }),
            hashes,
        };
        ModeOutcome { sequence: Some(sequence), checks, error: None }
    }
}

/// Per stream of the spool, each of its first `frames` frames' mean FLIP against the truth's
/// frame (stream 0's); empty for the truth's and for a stream that holds fewer frames (its mode
/// failed on the way). Frames identical to another (a stalled mode's and its twin's) are
/// compared once; the comparisons of a frame run on every core.
fn flip_along(spool: &Spool, frames: usize, cancel: &AtomicBool) -> Result<Vec<Vec<f64>>, String> {
    let [width, height] = spool.size();
    let complete: Vec<usize> = (1..spool.streams()).filter(|&s| spool.frames(s) >= frames).collect();
    let mut flips = vec![Vec::with_capacity(frames); spool.streams()];
    let threads = std::thread::available_parallelism().map_or(1, usize::from);
    for frame in 0..frames {
        // A signal stops the comparisons between images, not after the path's last.
        let stopped = || format!("interrupted: FLIP stopped at frame {frame} of {frames}");
        if cancel.load(Ordering::SeqCst) {
            return Err(stopped());
        }
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
                let Some(image) = distinct.get(i).filter(|_| !cancel.load(Ordering::SeqCst)) else {
                    return done;
                };
                done.push((*image, crate::perceptual::flip_rgba8(image, &truth, width, height).mean()));
            }
        };
        let values: std::collections::HashMap<&[u8], f64> = std::thread::scope(|scope| {
            let workers: Vec<_> = (0..threads).map(|_| scope.spawn(compare)).collect();
            workers.into_iter().flat_map(|w| w.join().expect("a FLIP thread panicked")).collect()
        });
        if values.len() < distinct.len() {
            return Err(stopped());
        }
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
/// image from (b, u) to (a, t), in squared code steps.
fn change_of_error(a: &DisplayImage, b: &DisplayImage, t: &DisplayImage, u: &DisplayImage) -> u64 {
    pixel_changes_of_error(&a.rgba, &b.rgba, &t.rgba, &u.rgba).sum()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flip_along_the_path_stops_at_a_signal() {
        let dir = std::env::temp_dir().join(format!("aabench-flip-stop-{}", std::process::id()));
        let mut spool =
            Spool::create(dir.join("spool"), [8, 8], vec!["truth".into(), "mode".into()]).unwrap();
        for value in [10, 200] {
            for stream in [0, 1] {
                spool.append(stream, &DisplayImage::from_rgba8(&[value; 256])).unwrap();
            }
        }
        let flips = flip_along(&spool, 2, &AtomicBool::new(false)).unwrap();
        assert_eq!((flips[1].len(), flips[1][0]), (2, 0.0), "identical frames: FLIP 0 at each");
        let error = flip_along(&spool, 2, &AtomicBool::new(true)).unwrap_err();
        assert!(error.contains("interrupted"), "{error}");
        drop(spool);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_stalled_mode_takes_its_twins_frames_only_where_its_still_is_its_twins() {
        let ids =
            ["taa", "taa-stalled", "fxaa", "fxaa-stalled", "smaa-stalled", "msaa-4x", "msaa-4x-stalled"];
        let modes: Vec<Mode> = ids.iter().map(|id| id.parse().unwrap()).collect();
        let run = |hash: &str, error: Option<&str>| ModeRun {
            hashes: vec![hash.into()],
            error: error.map(Into::into),
            ..ModeRun::default()
        };
        // fxaa's stall changed its image, smaa-stalled has no twin, msaa-4x failed.
        let runs = [
            run("a", None),
            run("a", None),
            run("b", None),
            run("c", None),
            run("d", None),
            run("e", Some("x")),
            run("e", None),
        ];
        let of = PathMode::of(&modes, &runs);
        let frames_of: Vec<Option<usize>> = of.iter().map(|m| m.frames_of).collect();
        assert_eq!(frames_of, [None, Some(0), None, None, None, None, None]);
        let renders: Vec<bool> = of.iter().map(PathMode::renders).collect();
        assert_eq!(renders, [true, false, true, true, true, false, true]);
    }
}
