//! A scene's sequence: once its stills are timed, every mode renders each frame of the
//! manifest's camera path (`motion/mod.rs`) once, untimed, and is measured against the truth's frame
//! at the same camera (`measures.rs`: the error per frame, flicker along the truth's motion and
//! what lag costs, the uncompensated instability). A stalled mode whose still is its unstalled
//! twin's to the bit renders no path of its own: it takes its twin's frames (the stall changes
//! the time, not the image).
//!
//! Per frame the truth renders (or comes from the cache) with the geometry probe, which follows
//! each pixel back to where its surface point lay in the frame before (`temporal.rs`).
//!
//! Every frame is spooled to disk as it renders (`spool.rs`). Once the last is done, every frame
//! is compared with the truth's by FLIP (`perceptual.rs`), on every core and without disturbing
//! a render's time, and the square where the modes flicker most is cut from them as animations
//! (`flicker.rs`).
//!
//! Every mode and the truth first render the warm-up, the frames of the path before its
//! measured window (`motion::Timeline`): a mode that carries a history (TAA, the `-stable`
//! modes) starts it from a reset there, so that its first measured frame has a history that has
//! been moving, as in a game; and ColorVideoVDP, whose temporal filters read the 250 ms before
//! each frame, sees the path's own frames there rather than the first frame repeated. Only the
//! window is measured: the warm-up is history, spooled for the metric and kept with
//! `--keep-frames`.

use std::sync::Arc;
use std::time::Instant;

use aabench_renderer::scene::Camera;
use aabench_renderer::{DisplayImage, Mode};

use super::context::{ModeRun, SceneRun};
use super::measures::{ModeOutcome, ModeState, TruthPair, TruthTrack, flip_along, jod_along, write_jod_maps};
use super::path_metrics::ModeFrame;
use crate::manifest::motion::{MotionSpec, Pace, PathFrame, PathKind, Timeline};
use crate::measure::pixels::{self, FrameChecks};
use crate::measure::temporal::{Flow, Geometry};
use crate::record::SequenceRecord;
use crate::run::flicker::{self, TRUTH_STREAM};
use crate::run::spool::Spool;
use crate::run::truth;

/// What the sequence is measured along and against: the path and its frames in this tier, and
/// the still frame's camera, truth and truth key.
#[derive(Debug)]
pub struct Along<'a> {
    pub motion: &'a MotionSpec,
    pub pace: Pace,
    pub timeline: &'a Timeline,
    /// Every frame, the warm-up's first: `timeline.warmup` frames, then the measured window's.
    pub frames: &'a [PathFrame],
    /// The folder under the scene's that holds the sequence's animations, and the sequence's
    /// number in the scene (1 the first).
    pub folder: &'a str,
    pub number: usize,
    pub still_camera: &'a Camera,
    pub still_truth: Option<&'a DisplayImage>,
    pub still_key: &'a str,
    /// What plays along the path, as the record names it (`walk`, `walk + wave`).
    pub animation: Option<&'a str>,
}

impl Along<'_> {
    /// The frames of the warm-up.
    fn warmup(&self) -> usize {
        self.timeline.warmup as usize
    }

    /// The frames of the measured window.
    fn measured(&self) -> usize {
        self.frames.len() - self.warmup()
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
    /// The scene's modes, from what their stills gave. A stalled mode takes its twin's frames
    /// where every round of both gave one and the same image: the two may have taken different
    /// numbers of rounds (rounds by confidence), so their hashes are compared as sets.
    pub fn of(modes: &[Mode], runs: &[ModeRun]) -> Vec<PathMode> {
        let hashed = |i: usize| runs[i].error.is_none() && !runs[i].hashes.is_empty();
        let image = |i: usize| -> std::collections::BTreeSet<&String> { runs[i].hashes.iter().collect() };
        let twin = |i: usize| {
            let plain = Mode { stalled: false, ..modes[i] };
            let t = modes.iter().position(|other| *other == plain)?;
            (modes[i].stalled && hashed(i) && hashed(t) && image(i) == image(t)).then_some(t)
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

/// Renders the scene's sequence with the prepared modes on the worker. Returns the scene's
/// record and each mode's outcome.
pub(super) async fn run(
    scene: &mut SceneRun<'_>,
    along: Along<'_>,
    modes: &[PathMode],
) -> (SequenceRecord, Vec<ModeOutcome>) {
    let start = Instant::now();
    let mut record = empty_record(&along);
    if record.warmup_still_frames > 0 && moves(&along, along.warmup()..along.frames.len()) {
        scene.warn(&format!(
            "{} of the {} warm-up frames hold still (the path or the animation has not started): the \
             modes that carry a history start the window from a still scene",
            record.warmup_still_frames,
            along.warmup()
        ));
    }
    let mut states: Vec<ModeState> = modes.iter().map(|_| ModeState::default()).collect();
    // Every mode's frames are spooled, to stream `index + 1`; the truth's to stream 0.
    let out_dir = scene.dir.join(along.folder);
    let size = scene.resolution;
    let names = std::iter::once(TRUTH_STREAM.to_string()).chain(modes.iter().map(|m| m.mode.to_string()));
    let bits = scene.manifest.display_bits();
    let mut spool =
        Spool::create(crate::run::spool::folder(&out_dir), size, bits, along.warmup(), names.collect());
    let mut flicker = vec![0.0; size[0] as usize * size[1] as usize];
    let rendered = render_frames(scene, &along, modes, &mut record, &mut states, (&mut spool, &mut flicker));
    if let Err(error) = rendered.await {
        scene.warn(&format!("the sequence stopped: {error}"));
        record.error = Some(error);
    }
    let done = record.frames_done as usize;
    scene.status("sequence: FLIP, JOD and the worst-flickering region");
    // A mode that takes its twin's frames shows in its twin's animation.
    let animated: Vec<usize> =
        (0..modes.len()).filter(|&i| modes[i].frames_of.is_none()).map(|i| i + 1).collect();
    let measure = AfterRender {
        done,
        delay_s: along.motion.time_step_s,
        dirs: [scene.plan.run_dir.clone(), out_dir],
        // The first sequence's frames in `frames/1/`, the second's in `frames/2/`, ….
        frames_dir: scene.plan.keep_frames.then(|| scene.dir.join("frames").join(along.number.to_string())),
        jod: scene.jod.clone().expect("a scene that renders sequences measures quality"),
        cancel: Arc::clone(scene.cancel),
    };
    let after = tokio::task::spawn_blocking(move || measure.run(spool?, &flicker, &animated));
    match after.await.map_err(|panic| format!("panicked: {panic}")).and_then(|after| after) {
        Ok(after) => after.record_into(scene, &mut record, &mut states),
        Err(error) => {
            scene.warn(&format!("no FLIP or JOD along the path and no flicker region: {error}"));
            // A signal stopped the measures: without FLIP and JOD the path is not measured, and
            // the scene says it was interrupted rather than ok (where the signal stopped the
            // frames already, that is the error the scene keeps).
            if scene.cancelled() && record.error.is_none() {
                record.error = Some(error.clone());
            }
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

/// The sequence's record before its first frame: what it is measured along.
fn empty_record(along: &Along) -> SequenceRecord {
    let fixed = matches!(along.motion.path, PathKind::Static | PathKind::Keyframes);
    SequenceRecord {
        path: along.motion.path.name().to_string(),
        rate: (!fixed).then_some(along.pace.rate),
        pixels_per_frame: along.pace.pixels_per_frame,
        animation: along.animation.map(str::to_string),
        frames: along.measured() as u32,
        frames_done: 0,
        time_step_s: along.motion.time_step_s,
        truth_rendered: 0,
        truth_render_s: 0.0,
        truth_change: None,
        blank_flicker: None,
        seconds: 0.0,
        error: None,
        flip_s: 0.0,
        jod_s: 0.0,
        warmup_frames: 0,
        lead_s: along.timeline.lead_s,
        warmup_still_frames: still_warmup_frames(along),
        measured_speed: None,
        region_s: 0.0,
        region: None,
        region_error: None,
    }
}

/// How many of the warm-up's frames show the same view as the frame before them: neither the
/// camera nor the animation moved (the first counts as moving). A warm-up that holds still
/// builds TAA's history on a still scene.
fn still_warmup_frames(along: &Along) -> u32 {
    (1..along.warmup()).filter(|&index| !moves(along, index..index + 1)).count() as u32
}

/// Whether any of the frames `range` shows another view than the frame before it: the camera
/// or the animation's time moved (an animation may still hold a pose between two times).
fn moves(along: &Along, range: std::ops::Range<usize>) -> bool {
    range.filter(|&index| index > 0).any(|index| {
        let (now, before) = (&along.frames[index], &along.frames[index - 1]);
        now.camera != before.camera || now.time != before.time
    })
}

/// Renders frame after frame, the warm-up's first: the truth, then every mode.
/// `record.frames_done` counts the measured frames that every mode still running rendered.
async fn render_frames(
    scene: &mut SceneRun<'_>,
    along: &Along<'_>,
    modes: &[PathMode],
    record: &mut SequenceRecord,
    states: &mut [ModeState],
    (spool, flicker): (&mut Result<Spool, String>, &mut [f64]),
) -> Result<(), String> {
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
    record.warmup_frames = along.warmup() as u32;
    for (index, path_frame) in along.frames.iter().enumerate() {
        let frame = index as i64 - along.warmup() as i64;
        let name = along.timeline.frame_name(frame);
        if scene.cancelled() {
            return Err(match frame {
                0.. => format!("interrupted after {frame} of {} frames", along.measured()),
                _ => format!("interrupted at {name}"),
            });
        }
        if modes.iter().zip(states.iter()).all(|(mode, state)| !mode.renders() || state.error.is_some()) {
            return Err("no mode is left to render".into());
        }
        // The animation's time now and at the frame before (the first frame's own).
        let before = &along.frames[index.saturating_sub(1)];
        set_view(scene, path_frame.camera, path_frame.time.zip(before.time.or(path_frame.time))).await?;
        let truth = truth_at(scene, along, index, record).await?;
        keep(0, &truth);
        let Ok(frame) = usize::try_from(frame) else {
            warm_up(scene, modes, states, index, &mut keep).await?;
            continue;
        };
        scene.status(&format!("sequence {name}: the geometry"));
        let (camera, then) = (&path_frame.camera, &along.frames[index - 1].camera);
        let geometry = geometry(scene, [camera, then], frame == 0).await?;
        let (truth_then, geometry_then) = track.previous.as_ref().map(|(t, g)| (t, g)).unzip();
        let flow = geometry_then.map(|then| Flow::between(&geometry, then));
        let pair = TruthPair { now: &truth, then: truth_then, flow: flow.as_ref() };
        measure_modes(scene, (modes, states), frame, (&pair, flicker), &mut keep).await?;
        track.advance(truth, geometry, flow.as_ref(), record);
        record.frames_done = frame as u32 + 1;
    }
    Ok(())
}

/// The truth at frame `index` of the path (the warm-up's first is 0): the still truth where the
/// frame shows the still's view (its camera, posed as the window's first frame is), else from
/// the cache or rendered now.
async fn truth_at(
    scene: &mut SceneRun<'_>,
    along: &Along<'_>,
    index: usize,
    record: &mut SequenceRecord,
) -> Result<DisplayImage, String> {
    let (path_frame, first) = (&along.frames[index], &along.frames[along.warmup()]);
    let frame = index as i64 - along.warmup() as i64;
    match along.still_truth {
        Some(still) if path_frame.camera == *along.still_camera && path_frame.time == first.time => {
            Ok(still.clone())
        }
        _ => {
            let name = along.timeline.frame_name(frame);
            scene.status(&format!("sequence {name}: the truth"));
            let view = FrameView { frame, name: &name, camera: &path_frame.camera, time: path_frame.time };
            truth_frame(scene, along.still_key, view, record).await
        }
    }
}

/// Renders window frame `frame` with every mode still running, spools it and measures it
/// against the truth's `pair`, each pixel's flicker added to `flicker`. Errs where the worker
/// can render nothing more.
async fn measure_modes(
    scene: &mut SceneRun<'_>,
    (modes, states): (&[PathMode], &mut [ModeState]),
    frame: usize,
    (pair, flicker): (&TruthPair<'_>, &mut [f64]),
    keep: &mut impl FnMut(usize, &DisplayImage),
) -> Result<(), String> {
    for (index, path_mode) in modes.iter().enumerate() {
        let (mode, state) = (&path_mode.mode, &mut states[index]);
        if !path_mode.renders() || state.error.is_some() {
            continue;
        }
        scene.status(&format!("sequence frame {frame}: {mode}"));
        match render(scene, index, mode.m, frame).await {
            Ok(Ok(rendered)) => {
                keep(index + 1, &rendered.display);
                state.add(*mode, rendered, pair, flicker, scene.textured);
            }
            Ok(Err(error)) => state.error = Some(error),
            // The worker is gone or stuck: no later frame can render.
            Err(error) => {
                state.error = Some(error.clone());
                return Err(format!("{mode}: {error}"));
            }
        }
    }
    Ok(())
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

/// What a sequence measures from its spool once every frame is rendered, off the worker.
struct AfterRender {
    done: usize,
    delay_s: f64,
    /// The run's folder and the sequence's (`<scene>/path/`).
    dirs: [std::path::PathBuf; 2],
    frames_dir: Option<std::path::PathBuf>,
    jod: crate::measure::perceptual::Jod,
    cancel: Arc<std::sync::atomic::AtomicBool>,
}

/// Its results: FLIP and JOD per stream with their seconds, the distortion maps written, the
/// worst-flickering region, and the frames kept on request.
struct Measured {
    flips: Vec<Vec<f64>>,
    flip_s: f64,
    jods: Vec<Option<Arc<crate::measure::perceptual::VideoJod>>>,
    maps: Vec<Option<Result<String, String>>>,
    jod_s: f64,
    region: Result<flicker::Cut, String>,
    region_s: f64,
    kept: Option<Result<(), String>>,
}

impl AfterRender {
    fn run(self, spool: Spool, flicker: &[f64], animated: &[usize]) -> Result<Measured, String> {
        spool.check()?;
        let [run_dir, out_dir] = [self.dirs[0].as_path(), self.dirs[1].as_path()];
        let start = Instant::now();
        let flips = flip_along(&spool, self.done, self.jod.pixels_per_degree(), &self.cancel)?;
        let flip_s = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let jods = jod_along(&spool, self.done, 1.0 / self.delay_s, &self.jod, &self.cancel)?;
        let maps = write_jod_maps(&spool, &jods, [run_dir, out_dir]);
        let jod_s = start.elapsed().as_secs_f64();
        // Frames that cannot be written (a full disk) cost the user their copy, not the
        // measures.
        let kept = self.frames_dir.as_ref().map(|dir| self.keep_frames(&spool, dir));
        let start = Instant::now();
        let region = flicker::region(&spool, flicker, animated, self.done, self.delay_s, [run_dir, out_dir]);
        let region_s = start.elapsed().as_secs_f64();
        Ok(Measured { flips, flip_s, jods, maps, jod_s, region, region_s, kept })
    }
}

/// What `--keep-frames` writes beside a sequence's frames (`sequence.json`), so that anyone can
/// score them again with ColorVideoVDP's reference implementation as aabench did: every frame
/// the metric saw, numbered from the warm-up's first, at `fps` on the display model `display`
/// seen at `pixels_per_degree`, with only the frames from `first_measured_frame` on pooled.
#[derive(Debug, serde::Serialize)]
struct KeptFrames {
    fps: f64,
    first_measured_frame: usize,
    frames: usize,
    display: String,
    pixels_per_degree: f64,
    /// The display's bits per code value: 10-bit frames are 16-bit PNGs whose top 10 bits are
    /// the code values.
    bits: u32,
}

impl AfterRender {
    fn keep_frames(&self, spool: &Spool, dir: &std::path::Path) -> Result<(), String> {
        spool.write_pngs(dir, self.done)?;
        let display = self.jod.display();
        let kept = KeptFrames {
            fps: 1.0 / self.delay_s,
            first_measured_frame: spool.warmup(),
            frames: spool.warmup() + self.done,
            display: display.name.clone(),
            pixels_per_degree: display.pixels_per_degree,
            bits: spool.bits(),
        };
        crate::files::write_json(&dir.join("sequence.json"), &kept)
    }
}

impl Measured {
    /// Hands each mode its FLIP, JOD and coarse share (stream `i + 1` is mode `i`'s) and the
    /// sequence its seconds and region; what could not be written is a warning.
    fn record_into(self, scene: &SceneRun, record: &mut SequenceRecord, states: &mut [ModeState]) {
        if let Some(Err(error)) = self.kept {
            scene.warn(&format!("--keep-frames: {error}"));
        }
        let per_stream = self.flips.into_iter().zip(self.jods).zip(self.maps).skip(1);
        for (state, ((flip, jod), map)) in states.iter_mut().zip(per_stream) {
            if let Some(Err(error)) = &map {
                scene.warn(&format!("no JOD map: {error}"));
            }
            state.flip.per_frame = flip;
            state.jod.jod = jod.as_ref().map(|j| j.jod);
            state.jod.worst = jod.map(|j| (j.worst_frame, map.and_then(Result::ok)));
        }
        (record.flip_s, record.jod_s, record.region_s) = (self.flip_s, self.jod_s, self.region_s);
        match self.region {
            Ok(cut) => {
                for (stream, share) in cut.coarse_shares {
                    states[stream - 1].coarse_share = share;
                }
                record.region = Some(cut.region);
            }
            Err(error) => record.region_error = Some(error),
        }
    }
}

/// Renders warm-up frame `index` (0 the first) with every mode that renders the path, from a
/// reset at the first, and spools each frame: unmeasured, seen only by ColorVideoVDP as the
/// history of the window's frames. A mode whose warm-up fails fails its sequence.
async fn warm_up(
    scene: &mut SceneRun<'_>,
    modes: &[PathMode],
    states: &mut [ModeState],
    index: usize,
    keep: &mut impl FnMut(usize, &DisplayImage),
) -> Result<(), String> {
    for (stream, path_mode) in modes.iter().enumerate() {
        if !path_mode.renders() || states[stream].error.is_some() {
            continue;
        }
        scene.status(&format!("sequence warm-up frame {}: {}", index + 1, path_mode.mode));
        let rendered = scene
            .worker
            .call(scene.plan.frame_timeout, move |state| {
                let prepared = state.modes[stream].as_ref().expect("prepared mode");
                if index == 0 {
                    prepared.reset_history();
                }
                prepared.render()?;
                prepared.read_display()
            })
            .await
            .map_err(|error| error.to_string())?;
        match rendered {
            Ok(display) => keep(stream + 1, &display),
            Err(error) => {
                states[stream].error.get_or_insert(format!("warm-up frame {}: {error}", index + 1));
            }
        }
    }
    Ok(())
}

/// Renders prepared mode `index` once at the current camera, the next frame after the warm-up's
/// and the window's before, and reads back its frame `frame` of the window. The outer error is
/// the worker's (it can render nothing more), the inner the mode's: a frame that shows nothing
/// fails the mode, naming the frame, unless the scene is declared empty.
async fn render(
    scene: &mut SceneRun<'_>,
    index: usize,
    m: u32,
    frame: usize,
) -> Result<Result<ModeFrame, String>, String> {
    let declared_empty = scene.manifest.empty;
    let rendered = scene
        .worker
        .call(scene.plan.frame_timeout, move |state| {
            let prepared = state.modes[index].as_ref().expect("prepared mode");
            let timing = prepared.render()?;
            let display = prepared.read_display()?;
            let counts = prepared.read_sample_counts()?;
            let hdr = prepared.read_hdr()?;
            let checks = FrameChecks::of(hdr.as_flattened(), counts.as_deref(), m);
            let blank = pixels::blank_image(hdr.as_flattened(), &display).filter(|_| !declared_empty);
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

/// A frame of the path: its index in the window (negative in the warm-up) and how messages name
/// it, its camera and, where an animation plays, its time.
struct FrameView<'a> {
    frame: i64,
    name: &'a str,
    camera: &'a Camera,
    time: Option<f64>,
}

/// The truth at a frame of the path: from the cache, or rendered now and cached. Its key is the
/// still truth's with the frame's camera and animation time added.
async fn truth_frame(
    scene: &mut SceneRun<'_>,
    still_key: &str,
    FrameView { frame, name, camera, time }: FrameView<'_>,
    record: &mut SequenceRecord,
) -> Result<DisplayImage, String> {
    if still_key.is_empty() {
        return Err("the still truth has no key to derive the frames' from".into());
    }
    let (plan, manifest, resolution) = (scene.plan, scene.manifest, scene.resolution);
    let key = truth::frame_key(still_key, camera, time);
    // The window's frames as `-frame003`, the warm-up's counted back from it as `-before01`.
    let file = match frame {
        0.. => format!("{}-frame{frame:03}", manifest.name),
        _ => format!("{}-before{:02}", manifest.name, -frame),
    };
    let cache = truth::cache_file(&plan.truth_cache_dir(manifest), &file, resolution, &key);
    if let Some(display) = truth::load_cached(&cache, resolution, manifest.display_bits()) {
        return Ok(display);
    }
    let start = Instant::now();
    let timeout = plan.frame_timeout.saturating_mul(16);
    let (rendered, not_cached) =
        truth::render_and_store(scene.worker, timeout, &cache, resolution, Arc::clone(scene.cancel))
            .await
            .map_err(|e| format!("the truth of {name}: {e}"))?;
    record.truth_rendered += 1;
    record.truth_render_s += start.elapsed().as_secs_f64();
    if let Some(error) = not_cached {
        scene.warn(&format!("the truth of {name} not cached: {error}"));
    }
    Ok(rendered.images.display)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        // taa-stalled took more rounds than taa, of the same image; fxaa's stall changed its
        // image, smaa-stalled has no twin, msaa-4x failed.
        let runs = [
            ModeRun { hashes: vec!["a".into(); 5], ..ModeRun::default() },
            ModeRun { hashes: vec!["a".into(); 12], ..ModeRun::default() },
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
