//! Running a plan: per scene, load → prepare every mode → warm up → timed repetitions
//! interleaved across modes → images and metrics. Timed frames run alone: nothing else is
//! scheduled while one is on the device, and encoding and metrics wait until the scene's
//! frames are done (lavapipe uses every core, so overlapping CPU work would corrupt timings).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Instant, SystemTime};

use aabench_renderer::{
    AdaptiveSettings, DisplayImage, ExtraSamples, FrameImages, FrameTiming, Mode, RenderSettings, Technique,
    color,
};

use crate::images;
use crate::inputs::SceneInputs;
use crate::machine::Machine;
use crate::manifest::Manifest;
use crate::metrics::{self, FrameChecks, Quality};
use crate::perceptual::FlipMap;
use crate::plan::{RunPlan, SceneEntry, Tier, fallback_name};
use crate::progress::Progress;
use crate::record::{
    AdaptiveCost, ExposureRecord, GraphRecord, ImageFiles, ModeRecord, ModeSequence, PassRecord, Platform,
    RUN_SCHEMA, RunRecord, RunSettings, SampleCost, SceneRecord, Status, fingerprint,
};
use crate::scenes;
use crate::sequence;
use crate::stats::Summary;
use crate::truth::{self, TRUTH_ID, TRUTH_M, TruthRecord};
use crate::worker::Worker;

/// Display differences of this many 8-bit steps reach the top of the difference heatmap.
const DIFFERENCE_FULL_SCALE: f64 = 32.0;

/// How a run ended.
#[derive(Debug)]
pub struct Outcome {
    pub record: RunRecord,
    pub run_json: PathBuf,
}

/// Runs the plan. `cancel` is set by the first Ctrl-C: the current frame finishes, what was
/// measured is recorded, and the run ends as interrupted.
pub async fn execute(plan: &RunPlan, progress: Progress, cancel: Arc<AtomicBool>) -> anyhow::Result<Outcome> {
    let mut worker = match Worker::start().await {
        Ok(worker) => worker,
        Err(error) => {
            // The run folder `plan` created holds nothing yet.
            let _ = std::fs::remove_dir(&plan.run_dir);
            return Err(error.into());
        }
    };
    let run_json = plan.run_dir.join("run.json");
    let mut record = RunRecord {
        schema: RUN_SCHEMA.into(),
        run_id: plan.run_id.clone(),
        started_at: now(),
        finished_at: None,
        status: Status::Running,
        tier: plan.tier,
        aabench_version: env!("CARGO_PKG_VERSION").into(),
        // Probed before any frame, while nothing else of the run uses the cores.
        platform: Platform { machine: Some(Machine::measure()), ..Platform::from(&worker.platform) },
        settings: RunSettings {
            modes: plan.modes.iter().map(ToString::to_string).collect(),
            repetitions: plan.repetitions,
            warmup: plan.warmup,
            frame_timeout_s: plan.frame_timeout.as_secs_f64(),
            interleaving: "round-robin: each repetition renders every mode once, in plan order".into(),
            extra_samples: format!("{:?}", plan.extra_samples).to_lowercase(),
            sequences: plan.sequences,
        },
        shard: plan.shard,
        merged_from: Vec::new(),
        scenes: Vec::new(),
    };
    progress.line(&format!(
        "aabench {} · {} tier · {} · {}",
        record.run_id,
        plan.tier.name(),
        worker.platform.adapter,
        worker.platform.driver_info
    ));
    write_record(&run_json, &record)?;

    // A failed write (a full disk) does not stop the run: later scenes still render, and each
    // later write tries again; only the last one must succeed.
    let save = |record: &RunRecord| {
        if let Err(error) = write_record(&run_json, record) {
            progress.line(&format!("warning: {error:#}; trying again after the next scene"));
        }
    };
    for entry in &plan.scenes {
        let scene = match entry {
            _ if cancel.load(Ordering::SeqCst) => not_run(entry, "the run was interrupted before it"),
            // After a timeout the stuck frame may still be using every core: later timings
            // would be wrong, so the remaining scenes are recorded as not run.
            Ok(_) if worker.is_stuck() => {
                not_run(entry, "an earlier frame timed out or the GPU worker panicked")
            }
            Ok(manifest) => run_scene(&mut worker, plan, manifest, &progress, Arc::clone(&cancel)).await,
            Err(error) => failed_scene(entry, error.to_string()),
        };
        report_scene(&progress, &scene);
        record.scenes.push(scene);
        save(&record);
    }

    record.finished_at = Some(now());
    record.status = if cancel.load(Ordering::SeqCst) {
        Status::Interrupted
    } else if record.scenes.iter().any(|s| s.status != Status::Ok) {
        Status::Failed
    } else {
        Status::Ok
    };
    write_record(&run_json, &record)?;
    Ok(Outcome { record, run_json })
}

fn now() -> String {
    humantime::format_rfc3339_seconds(SystemTime::now()).to_string()
}

fn write_record(path: &Path, record: &RunRecord) -> anyhow::Result<()> {
    crate::fs::write_json(path, record).map_err(anyhow::Error::msg)
}

fn failed_scene(entry: &SceneEntry, error: String) -> SceneRecord {
    let mut record = match entry {
        Ok(m) => empty_scene(m),
        Err(e) => SceneRecord { name: fallback_name(&e.path), ..empty_scene_at(&e.path) },
    };
    record.status = Status::Failed;
    record.error = Some(error);
    record
}

/// A scene that never started, and why.
fn not_run(entry: &SceneEntry, why: &str) -> SceneRecord {
    SceneRecord { status: Status::NotRun, ..failed_scene(entry, format!("not run: {why}")) }
}

/// A scene record before anything was measured.
fn empty_scene(manifest: &Manifest) -> SceneRecord {
    SceneRecord {
        name: manifest.name.clone(),
        stall_iterations: manifest.stall_iterations,
        gate: manifest.gate,
        ..empty_scene_at(&manifest.path)
    }
}

/// A scene record of a manifest that may not have parsed.
fn empty_scene_at(manifest: &Path) -> SceneRecord {
    SceneRecord {
        name: String::new(),
        manifest: manifest.display().to_string(),
        status: Status::Running,
        error: None,
        resolution: None,
        triangles: None,
        textures: None,
        load_s: None,
        images_s: None,
        perceptual_s: None,
        target_bytes: None,
        texture_bytes: None,
        memory_limit_bytes: None,
        warnings: Vec::new(),
        stall_iterations: 0,
        inputs: None,
        gate: Default::default(),
        exposure: None,
        truth: None,
        sequence: None,
        modes: Vec::new(),
    }
}

/// What one mode measured during the scene's timed loop.
#[derive(Debug, Default)]
struct ModeRun {
    graph: Option<GraphRecord>,
    timings: Vec<FrameTiming>,
    hashes: Vec<String>,
    images: Option<FrameImages>,
    checks: FrameChecks,
    /// Its sequence, where the scene has a camera path.
    sequence: Option<ModeSequence>,
    error: Option<String>,
}

/// What a manifest's scene renders with in `tier`.
pub fn render_settings(manifest: &Manifest, tier: Tier, extra_samples: ExtraSamples) -> RenderSettings {
    let [width, height] = tier.resolution(manifest);
    RenderSettings {
        width,
        height,
        stall_iterations: manifest.stall_iterations,
        adaptive: AdaptiveSettings { extra_samples, ..manifest.adaptive.settings() },
        color: manifest.color_settings(),
    }
}

/// One scene, in its phases: load the file, upload it (and meter its exposure), render the
/// ground truth, prepare every mode, run the timed rounds, free the device, then write images
/// and metrics. A phase that fails ends the scene with its error; the run goes on.
async fn run_scene(
    worker: &mut Worker,
    plan: &RunPlan,
    manifest: &Manifest,
    progress: &Progress,
    cancel: Arc<AtomicBool>,
) -> SceneRecord {
    let mut record = empty_scene(manifest);
    let [width, height] = plan.tier.resolution(manifest);
    record.resolution = Some([width, height]);
    let scene_dir = plan.run_dir.join(&manifest.name);
    if let Err(error) = std::fs::create_dir_all(&scene_dir) {
        return fail(record, format!("{}: {error}", scene_dir.display()));
    }
    let (loaded, inputs) = match load(manifest, progress, &mut record).await {
        Ok(loaded) => loaded,
        Err(error) => return fail(record, error),
    };
    let (still_camera, path) = (loaded.camera, loaded.path.clone());
    match upload(worker, plan, manifest, loaded, progress).await {
        Ok((budget, exposure)) => {
            record.memory_limit_bytes = budget;
            record.exposure = Some(exposure);
        }
        Err(error) => return fail(record, error),
    }

    // The truth renders before any mode is prepared, so its peak memory is its own.
    let (truth_record, truth_image) =
        ground_truth(worker, plan, manifest, &inputs, [width, height], progress, Arc::clone(&cancel)).await;
    record.truth = Some(truth_record);
    if cancel.load(Ordering::SeqCst) {
        free_scene(worker, plan).await;
        record.status = Status::Interrupted;
        record.error = Some("interrupted while its ground truth rendered: no mode ran".into());
        return record;
    }

    let mut runs = match prepare_modes(worker, plan, manifest, progress).await {
        Ok((runs, target_bytes, texture_bytes)) => {
            record.target_bytes = Some(target_bytes);
            record.texture_bytes = Some(texture_bytes);
            runs
        }
        Err(error) => return fail(record, error),
    };
    timed_rounds(worker, plan, manifest, progress, &cancel, &mut runs).await;
    temporal_stills(worker, plan, manifest, progress, &cancel, &mut runs).await;
    if let Some(motion) = manifest.motion.as_ref().filter(|_| plan.sequences)
        && !cancel.load(Ordering::SeqCst)
        && !worker.is_stuck()
    {
        let modes: Vec<(Mode, bool)> =
            plan.modes.iter().zip(&runs).map(|(mode, run)| (*mode, run.error.is_none())).collect();
        let still_key = record.truth.as_ref().map(|truth| truth.key.clone()).unwrap_or_default();
        let along = sequence::Along {
            motion,
            cameras: &path[..plan.tier.sequence_frames(motion) as usize],
            still_camera: &still_camera,
            still_truth: truth_image.as_ref(),
            still_key: &still_key,
        };
        let (sequence, outcomes) =
            sequence::run(worker, plan, manifest, along, &modes, progress, &cancel).await;
        // A sequence frame is a frame of the mode like any other: NaN in it fails the mode.
        for (run, outcome) in runs.iter_mut().zip(outcomes) {
            run.checks.add(outcome.checks);
            run.sequence = outcome.sequence;
            if let Some(error) = outcome.error {
                run.error.get_or_insert(format!("sequence: {error}"));
            }
        }
        record.sequence = Some(sequence);
    }
    // Free the scene's device memory before the CPU work below.
    free_scene(worker, plan).await;

    progress.status(&format!("[{}] writing images and metrics", manifest.name));
    let interrupted = cancel.load(Ordering::SeqCst);
    let started = Instant::now();
    let (modes, perceptual_s) =
        finish_modes(plan, &scene_dir, manifest, runs, truth_image, interrupted).await;
    record.modes = modes;
    record.images_s = Some(started.elapsed().as_secs_f64());
    record.perceptual_s = Some(perceptual_s);
    conclude(record, worker.is_stuck(), interrupted)
}

/// Reads the manifest's glTF file and hashes the scene's inputs, off the async threads; records
/// what the file holds.
async fn load(
    manifest: &Manifest,
    progress: &Progress,
    record: &mut SceneRecord,
) -> Result<(scenes::LoadedScene, SceneInputs), String> {
    progress.status(&format!("[{}] loading {}", manifest.name, manifest.gltf_path().display()));
    let owned = manifest.clone();
    let load = move || -> anyhow::Result<_> { Ok((scenes::load(&owned)?, SceneInputs::of(&owned)?)) };
    let (loaded, inputs) = match tokio::task::spawn_blocking(load).await {
        Ok(Ok(loaded)) => loaded,
        Ok(Err(error)) => return Err(format!("{error:#}")),
        Err(panic) => return Err(format!("loading panicked: {panic}")),
    };
    record.load_s = Some(loaded.seconds);
    record.triangles = Some(loaded.scene.triangle_count());
    record.textures = Some(loaded.scene.textures.len());
    record.inputs = Some(inputs.clone());
    for warning in &loaded.scene.warnings {
        progress.line(&format!("[{}] warning: {warning}", manifest.name));
    }
    record.warnings = loaded.scene.warnings.clone();
    Ok((loaded, inputs))
}

/// Uploads the scene into a new renderer (dropping the previous scene's), sets the memory
/// budget its modes are prepared under, and meters the exposure where the manifest gives none.
/// Returns the budget and the exposure every mode and the truth render at.
async fn upload(
    worker: &mut Worker,
    plan: &RunPlan,
    manifest: &Manifest,
    loaded: scenes::LoadedScene,
    progress: &Progress,
) -> Result<(Option<u64>, ExposureRecord), String> {
    let settings = render_settings(manifest, plan.tier, plan.extra_samples);
    progress.status(&format!("[{}] uploading", manifest.name));
    let memory_limit = plan.memory_limit;
    let metered = manifest.tonemap.exposure.is_none();
    let uploaded = worker
        .call(plan.frame_timeout, move |state| {
            let scenes::LoadedScene { scene, camera, lighting, .. } = loaded;
            state.modes.clear();
            state.renderer = None;
            let mut renderer = aabench_renderer::SceneRenderer::new(
                state.gpu.clone(),
                &scene,
                &camera,
                &lighting,
                settings,
            )?;
            // After the upload, so that the scene's own memory is no longer available.
            let budget = memory_limit.or_else(|| available_memory().map(|bytes| bytes / 10 * 9));
            renderer.set_memory_budget(budget);
            if metered {
                renderer.meter_exposure(color::EXPOSURE_KEY, color::METERED_EXPOSURE_RANGE)?;
            }
            let exposure = ExposureRecord { value: renderer.exposure(), metered };
            state.renderer = Some(renderer);
            Ok::<_, aabench_renderer::RenderError>((budget, exposure))
        })
        .await;
    match uploaded {
        Ok(Ok(uploaded)) => Ok(uploaded),
        // What the device refuses of the file's content (too many textures) names the file.
        Ok(Err(error @ aabench_renderer::RenderError::Limit(_))) => {
            Err(format!("{}: {error}", manifest.gltf_path().display()))
        }
        Ok(Err(error)) => Err(error.to_string()),
        Err(error) => Err(error.to_string()),
    }
}

/// Prepares every mode of the plan; a mode that cannot be prepared fails alone. Returns one
/// run per mode (its graph, or its error), the scene's target bytes and texture bytes.
async fn prepare_modes(
    worker: &mut Worker,
    plan: &RunPlan,
    manifest: &Manifest,
    progress: &Progress,
) -> Result<(Vec<ModeRun>, u64, u64), String> {
    let modes = plan.modes.clone();
    progress.status(&format!("[{}] compiling {} modes", manifest.name, modes.len()));
    let prepared = worker
        .call(plan.frame_timeout.saturating_mul(modes.len() as u32), move |state| {
            let renderer = state.renderer.as_mut().expect("an uploaded scene");
            let mut outcomes = Vec::new();
            for mode in modes {
                match renderer.prepare(mode) {
                    Ok(prepared) => {
                        outcomes.push(Ok(GraphRecord::of(prepared.graph())));
                        state.modes.push(Some(prepared));
                    }
                    Err(error) => {
                        state.modes.push(None);
                        outcomes.push(Err(error.to_string()));
                    }
                }
            }
            (outcomes, renderer.target_bytes(), renderer.texture_bytes())
        })
        .await;
    let (outcomes, target_bytes, texture_bytes) = prepared.map_err(|error| error.to_string())?;
    let runs = outcomes
        .into_iter()
        .map(|outcome| match outcome {
            Ok(graph) => ModeRun { graph: Some(graph), ..Default::default() },
            Err(error) => ModeRun { error: Some(error), ..Default::default() },
        })
        .collect();
    Ok((runs, target_bytes, texture_bytes))
}

/// Warm-up rounds (lavapipe compiles at the first draw), then timed rounds. Each round renders
/// every mode once: A B C … A B C …, so drift over time hits every mode alike. Images are read
/// back after the first timed frame (every later frame is checked to give the same display
/// image), so an interrupted run still has them. A worker that stops (a timeout, a panic)
/// ends the rounds of every mode.
async fn timed_rounds(
    worker: &mut Worker,
    plan: &RunPlan,
    manifest: &Manifest,
    progress: &Progress,
    cancel: &AtomicBool,
    runs: &mut [ModeRun],
) {
    let rounds = plan.warmup + plan.repetitions;
    for round in 0..rounds {
        let timed = round >= plan.warmup;
        let first_timed = round == plan.warmup;
        for (index, mode) in plan.modes.iter().enumerate() {
            if cancel.load(Ordering::SeqCst) {
                return;
            }
            if runs[index].error.is_some() {
                continue;
            }
            let label = if timed {
                format!("rep {}/{}", round - plan.warmup + 1, plan.repetitions)
            } else {
                format!("warm-up {}/{}", round + 1, plan.warmup)
            };
            progress.status(&format!("[{}] {mode} {label}", manifest.name));
            // A jittered mode's frames differ as its history fills: its image is its still's. A
            // `-stable` mode's frames at one camera are its first frame's, so they are hashed.
            let images = first_timed && !mode.is_jittered();
            let hashed = timed && !mode.is_jittered();
            let result = render_frame(worker, plan, index, mode.m, hashed, images).await;
            let run = &mut runs[index];
            match result {
                Ok(Ok(frame)) => {
                    run.checks.add(frame.checks);
                    if timed {
                        run.timings.push(frame.timing);
                        run.hashes.extend(frame.hash);
                    }
                    if frame.images.is_some() {
                        run.images = frame.images;
                    }
                }
                Ok(Err(error)) => run.error = Some(error.to_string()),
                Err(error) => {
                    run.error = Some(format!("{mode}: {error}"));
                    for other in runs.iter_mut().filter(|r| r.error.is_none()) {
                        other.error = Some(format!("not finished: {error}"));
                    }
                    return;
                }
            }
        }
    }
}

/// The stills of jittered modes (TAA), after the timed rounds: each rendered twice from a reset
/// through its warm-up frames ([`aabench_renderer::taa::WARMUP_FRAMES`]), read back and
/// fingerprinted like a timed frame, so that both must agree.
async fn temporal_stills(
    worker: &mut Worker,
    plan: &RunPlan,
    manifest: &Manifest,
    progress: &Progress,
    cancel: &AtomicBool,
    runs: &mut [ModeRun],
) {
    for (index, mode) in plan.modes.iter().enumerate().filter(|(_, mode)| mode.is_jittered()) {
        for attempt in 0..2 {
            if cancel.load(Ordering::SeqCst) || worker.is_stuck() {
                return;
            }
            if runs[index].error.is_some() {
                break;
            }
            progress.status(&format!("[{}] {mode} still {}/2", manifest.name, attempt + 1));
            let m = mode.m;
            let timeout = plan.frame_timeout.saturating_mul(aabench_renderer::taa::WARMUP_FRAMES);
            let still = worker
                .call(timeout, move |state| {
                    let prepared = state.modes[index].as_ref().expect("prepared mode");
                    let timing = prepared.render_still()?;
                    read_frame(prepared, m, timing)
                })
                .await;
            let run = &mut runs[index];
            match still {
                Ok(Ok(frame)) => {
                    run.checks.add(frame.checks);
                    run.hashes.extend(frame.hash);
                    run.images = run.images.take().or(frame.images);
                }
                Ok(Err(error)) => run.error = Some(error.to_string()),
                Err(error) => run.error = Some(format!("{mode}: {error}")),
            }
        }
    }
}

/// What one rendered frame gave: its timing, its fingerprint (timed frames), the checks of its
/// HDR values and sample counts, and its images (the first timed frame).
struct Frame {
    timing: FrameTiming,
    hash: Option<String>,
    checks: FrameChecks,
    images: Option<FrameImages>,
}

/// Renders mode `index` once and reads back what the round needs, between frames, never
/// during one. Every frame is checked; `hashed` frames' display images and sample counts are
/// fingerprinted (every timed frame of a mode without history), and all must agree.
async fn render_frame(
    worker: &mut Worker,
    plan: &RunPlan,
    index: usize,
    m: u32,
    hashed: bool,
    with_images: bool,
) -> Result<Result<Frame, aabench_renderer::RenderError>, crate::worker::WorkerError> {
    worker
        .call(plan.frame_timeout, move |state| {
            let prepared = state.modes[index].as_ref().expect("prepared mode");
            let timing = prepared.render()?;
            if with_images {
                return read_frame(prepared, m, timing);
            }
            let counts = prepared.read_sample_counts()?;
            let checks = FrameChecks::of(prepared.read_hdr()?.as_flattened(), counts.as_deref(), m);
            let hash =
                if hashed { Some(fingerprint(&prepared.read_display()?, counts.as_deref())) } else { None };
            Ok(Frame { timing, hash, checks, images: None })
        })
        .await
}

/// The last frame's images, their fingerprint and checks.
fn read_frame(
    prepared: &aabench_renderer::PreparedMode,
    m: u32,
    timing: FrameTiming,
) -> Result<Frame, aabench_renderer::RenderError> {
    let images = prepared.read_images()?;
    let counts = images.sample_counts.as_deref();
    let hash = Some(fingerprint(&images.display, counts));
    let checks = FrameChecks::of(&images.hdr, counts, m);
    Ok(Frame { timing, hash, checks, images: Some(images) })
}

/// Drops the scene's prepared modes and renderer, freeing its device memory.
async fn free_scene(worker: &mut Worker, plan: &RunPlan) {
    let _ = worker
        .call(plan.frame_timeout, |state| {
            state.modes.clear();
            state.renderer = None;
        })
        .await;
}

/// The scene's status from its modes, its truth and the worker.
fn conclude(mut record: SceneRecord, worker_stuck: bool, interrupted: bool) -> SceneRecord {
    let truth_error = record.truth.as_ref().and_then(|t| t.error.clone());
    if let Some(error) = truth_error {
        record.error = Some(format!("ground truth: {error}"));
    } else if worker_stuck {
        record.error = Some("the GPU worker stopped; see the failed mode".into());
    }
    record.status = if record.error.is_none() && record.modes.iter().all(|m| m.status == Status::Ok) {
        Status::Ok
    } else if interrupted {
        Status::Interrupted
    } else {
        Status::Failed
    };
    record
}

/// The scene's ground truth, from the cache or rendered now (untimed; before any mode is
/// prepared, so the peak memory measured is the truth's own), and written into the run folder.
/// Returns the record and the display image, or the record with its error.
async fn ground_truth(
    worker: &mut Worker,
    plan: &RunPlan,
    manifest: &Manifest,
    inputs: &SceneInputs,
    resolution: [u32; 2],
    progress: &Progress,
    cancel: Arc<AtomicBool>,
) -> (TruthRecord, Option<DisplayImage>) {
    let mut record = TruthRecord {
        id: TRUTH_ID.into(),
        samples_per_pixel: TRUTH_M * TRUTH_M,
        key: String::new(),
        cached: false,
        render_s: None,
        tiles: None,
        peak_rss_bytes: None,
        image: None,
        image_hash: None,
        error: None,
    };
    let fail = |mut record: TruthRecord, error: String| {
        record.error = Some(error);
        (record, None)
    };
    match truth::cache_key(inputs, resolution, &worker.platform) {
        Ok(key) => record.key = key,
        Err(error) => return fail(record, format!("{error:#}")),
    }
    let cache = truth::cache_file(&plan.truth_cache_dir(manifest), &manifest.name, resolution, &record.key);
    let display = match truth::load_cached(&cache, resolution, manifest.display_bits()) {
        Some(display) => {
            record.cached = true;
            display
        }
        None => {
            progress.status(&format!("[{}] rendering the ground truth ({TRUTH_ID}, untimed)", manifest.name));
            let measured = truth::peak_memory::reset();
            let start = Instant::now();
            // A signal stops the truth between tiles, not after the last one.
            let timeout = plan.frame_timeout.saturating_mul(16);
            let (truth, not_cached) =
                match truth::render_and_store(worker, timeout, &cache, resolution, cancel).await {
                    Ok(rendered) => rendered,
                    Err(error) => return fail(record, error),
                };
            record.render_s = Some(start.elapsed().as_secs_f64());
            record.tiles = Some(truth.tiles);
            record.peak_rss_bytes = if measured { truth::peak_memory::read() } else { None };
            if let Some(error) = not_cached {
                progress.line(&format!("[{}] warning: ground truth not cached: {error}", manifest.name));
            }
            truth.images.display
        }
    };
    record.image_hash = Some(fingerprint(&display, None));
    let relative = format!("{}/{TRUTH_ID}.png", manifest.name);
    match images::write_display_png(&plan.run_dir.join(&relative), resolution[0], resolution[1], &display) {
        Ok(()) => record.image = Some(relative),
        Err(error) => return fail(record, format!("{error:#}")),
    }
    (record, Some(display))
}

fn fail(mut record: SceneRecord, error: String) -> SceneRecord {
    record.status = Status::Failed;
    record.error = Some(error);
    record
}

/// Builds the mode records: timing summaries, then quality metrics and image files, encoded in
/// parallel now that no frame is running.
async fn finish_modes(
    plan: &RunPlan,
    scene_dir: &Path,
    manifest: &Manifest,
    runs: Vec<ModeRun>,
    truth: Option<DisplayImage>,
    interrupted: bool,
) -> (Vec<ModeRecord>, f64) {
    let modes = &plan.modes;

    let mut records: Vec<ModeRecord> = modes
        .iter()
        .zip(&runs)
        .map(|(mode, run)| timing_record(*mode, run, plan.repetitions, interrupted, manifest.empty))
        .collect();
    let frame_median = |mode: Mode| -> Option<f64> {
        let i = modes.iter().position(|m| *m == mode)?;
        records[i].frame_ms.as_ref().map(|s| s.median)
    };
    let deferred = frame_median(Mode::new(Technique::Deferred, 1, false));
    let costs: Vec<Option<AdaptiveCost>> =
        modes.iter().zip(&runs).map(|(mode, run)| adaptive_cost(modes, &runs, *mode, run)).collect();
    for (record, cost) in records.iter_mut().zip(costs) {
        record.ratio_to_deferred = match (&record.frame_ms, deferred) {
            (Some(own), Some(base)) if base > 0.0 => Some(own.median / base),
            _ => None,
        };
        record.adaptive = cost;
    }

    // Images and quality, one blocking task per mode. The truth's share of SSIM is computed
    // once here, for all of them (a few tens of milliseconds at 1024×768).
    let images: Arc<Vec<Option<FrameImages>>> = Arc::new(runs.into_iter().map(|r| r.images).collect());
    let [width, height] = plan.tier.resolution(manifest);
    let truth = truth.map(|image| Arc::new(metrics::Truth::new(image, width, height)));
    let mut tasks = Vec::new();
    for (index, mode) in modes.iter().enumerate() {
        if images[index].is_none() {
            tasks.push(None);
            continue;
        }
        let reference = comparison_reference(modes, &images, *mode);
        let images = Arc::clone(&images);
        let (mode, truth, scene_dir, scene_name) =
            (*mode, truth.clone(), scene_dir.to_path_buf(), manifest.name.clone());
        tasks.push(Some(tokio::task::spawn_blocking(move || {
            let own = images[index].as_ref().expect("images of a finished mode");
            let vs = |other: usize, name: &str| {
                metrics::quality(
                    &own.display,
                    &images[other].as_ref().expect("reference images").display,
                    name,
                )
            };
            let vs_reference = reference.map(|(i, m)| vs(i, &m.to_string()));
            // Thread CPU time: the tasks share the cores, so their wall times overlap.
            let perceptual_start = thread_cpu_seconds();
            let (vs_truth, flip_map) = truth
                .as_deref()
                .map(|truth| metrics::quality_vs_truth(&own.display, truth, TRUTH_ID))
                .unzip();
            let perceptual_s = thread_cpu_seconds() - perceptual_start;
            let diff_against = match reference {
                Some((i, _)) => Some(&images[i].as_ref().expect("reference images").display),
                None => truth.as_deref().map(|truth| &truth.image),
            };
            let samples = own.sample_counts.as_ref().map(|counts| metrics::sample_stats(counts, mode));
            let mut files = ImageFiles::default();
            let written = write_mode_images(
                &scene_dir,
                &scene_name,
                mode,
                own,
                diff_against,
                flip_map.as_ref(),
                &mut files,
            );
            ModeResults { files, samples, vs_reference, vs_truth, written, perceptual_s }
        })));
    }
    // What was measured is kept when an image cannot be written (a full disk): the mode then
    // fails with the write's error, its metrics and the images that were written recorded.
    let mut perceptual_s = 0.0;
    for (record, task) in records.iter_mut().zip(tasks) {
        let Some(task) = task else { continue };
        match task.await {
            Ok(results) => {
                record.images = results.files;
                record.vs_reference = results.vs_reference;
                record.vs_ground_truth = results.vs_truth;
                perceptual_s += results.perceptual_s;
                match results.samples.transpose() {
                    Ok(samples) => record.samples = samples,
                    Err(error) => fail_mode(record, format!("{}: {error}", record.mode)),
                }
                if let Err(error) = results.written {
                    fail_mode(record, format!("{error:#}"));
                }
            }
            Err(panic) => fail_mode(record, format!("image task panicked: {panic}")),
        }
    }
    crate::front::place(&mut records);
    (records, perceptual_s)
}

/// What a mode's image task computed and wrote.
struct ModeResults {
    files: ImageFiles,
    samples: Option<Result<metrics::SampleStats, String>>,
    vs_reference: Option<Quality>,
    vs_truth: Option<Quality>,
    written: anyhow::Result<()>,
    /// CPU seconds of the comparison with the truth: MSE, FLIP and SSIM.
    perceptual_s: f64,
}

/// CPU seconds the calling thread has used so far (0 where the clock cannot be read).
fn thread_cpu_seconds() -> f64 {
    let mut time = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: `clock_gettime` writes one `timespec` through a pointer to a live local.
    #[allow(unsafe_code)]
    let status = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut time) };
    if status != 0 {
        return 0.0;
    }
    time.tv_sec as f64 + time.tv_nsec as f64 * 1e-9
}

/// Fails a mode; a second error is added to the first, not written over it.
fn fail_mode(record: &mut ModeRecord, error: String) {
    record.status = Status::Failed;
    record.error = Some(match record.error.take() {
        Some(first) => format!("{first}; {error}"),
        None => error,
    });
}

/// The image a mode is compared with, with the same stall if it ran, else the other (their
/// images are identical): for adaptive modes the reference at the same M; for 4× MSAA the 2×2
/// reference, which shades as many samples everywhere; for FXAA and SMAA the image they
/// post-process, deferred-1x1, which is the 1×1 reference bit for bit; for TAA deferred-1x1,
/// which it blends over frames.
fn comparison_reference(modes: &[Mode], images: &[Option<FrameImages>], mode: Mode) -> Option<(usize, Mode)> {
    let technique = match mode.technique {
        Technique::Adaptive(..) | Technique::Msaa => Technique::Reference,
        Technique::Fxaa | Technique::Smaa | Technique::Taa => Technique::Deferred,
        Technique::Deferred | Technique::Reference => return None,
    };
    [mode.stalled, !mode.stalled].into_iter().find_map(|stalled| {
        let reference = Mode::new(technique, mode.m, stalled);
        let index = modes.iter().position(|m| *m == reference)?;
        images[index].as_ref().map(|_| (index, reference))
    })
}

/// The mode's record from its frames: timings, and whether it succeeded. A frame that shows
/// nothing fails its mode unless the scene is `declared_empty`.
fn timing_record(
    mode: Mode,
    run: &ModeRun,
    repetitions: u32,
    interrupted: bool,
    declared_empty: bool,
) -> ModeRecord {
    let ms = |seconds: f64| seconds * 1e3;
    let frame_ms = Summary::new(run.timings.iter().map(|t| ms(t.seconds())).collect());
    let passes = run.timings.first().map_or_else(Vec::new, |first| {
        (0..first.passes.len())
            .filter_map(|p| {
                let samples = run.timings.iter().map(|t| ms(t.passes[p].seconds)).collect();
                Summary::new(samples)
                    .map(|summary| PassRecord { name: first.passes[p].name.to_string(), ms: summary })
            })
            .collect()
    });
    let deterministic = (!run.hashes.is_empty()).then(|| run.hashes.windows(2).all(|w| w[0] == w[1]));
    let complete = run.timings.len() == repetitions as usize;
    let unstable = run.checks.problem(mode.m);
    let blank = run.images.as_ref().filter(|_| !declared_empty).and_then(metrics::blank_frame);
    let (status, error) = match (&run.error, run.images.is_some()) {
        (Some(error), _) => (Status::Failed, Some(error.clone())),
        // Not a number is never a result: the display passes would hide it, so it fails here.
        (None, _) if unstable.is_some() => (Status::Failed, unstable),
        // Nothing to see is no measurement of anti-aliasing.
        (None, _) if blank.is_some() => (Status::Failed, blank),
        // Same inputs must give the same bits: a difference is a bug, not noise.
        (None, true) if deterministic == Some(false) => {
            (Status::Failed, Some("not deterministic: repetitions produced different images".into()))
        }
        (None, true) if complete => (Status::Ok, None),
        (None, _) if interrupted => (Status::Interrupted, None),
        (None, _) => (Status::Failed, Some("no images were read back".into())),
    };
    ModeRecord {
        mode: mode.to_string(),
        m: mode.m,
        stalled: mode.stalled,
        status,
        error,
        frame_ms,
        passes,
        ratio_to_deferred: None,
        deterministic,
        output_hash: run.hashes.last().cloned(),
        images: ImageFiles::default(),
        samples: None,
        vs_reference: None,
        vs_ground_truth: None,
        adaptive: None,
        front: None,
        graph: run.graph.clone(),
        checks: (run.checks.frames > 0).then_some(run.checks),
        sequence: run.sequence.clone(),
    }
}

fn pass_median(run: &ModeRun, name: &str) -> Option<f64> {
    let samples: Vec<f64> = run
        .timings
        .iter()
        .filter_map(|t| t.passes.iter().find(|p| p.name == name).map(|p| p.seconds * 1e3))
        .collect();
    Summary::new(samples).map(|s| s.median)
}

fn frame_median(run: &ModeRun) -> Option<f64> {
    Summary::new(run.timings.iter().map(|t| t.seconds() * 1e3).collect()).map(|s| s.median)
}

/// Speed-up over the same-M reference with the same stall, and the cost limit (see
/// [`AdaptiveCost`]).
fn adaptive_cost(modes: &[Mode], runs: &[ModeRun], mode: Mode, run: &ModeRun) -> Option<AdaptiveCost> {
    if !matches!(mode.technique, Technique::Adaptive(..)) {
        return None;
    }
    let reference = Mode::new(Technique::Reference, mode.m, mode.stalled);
    let reference_run = &runs[modes.iter().position(|m| *m == reference)?];
    let own = frame_median(run)?;
    let counts = run.images.as_ref()?.sample_counts.as_ref()?;
    let stats = metrics::sample_stats(counts, mode).ok()?;
    // Shading work beyond S, as a fraction of the reference's.
    let pixels = counts.len() as f64;
    let extra_fraction = ((stats.shaded + stats.reshaded) as f64 - pixels) / stats.total as f64;
    // Every frame of the scene pays for its shadow cubes, the reference's too.
    let limit = pass_median(run, "shadow").unwrap_or(0.0)
        + pass_median(run, "gbuffer")?
        + pass_median(run, "shade_first")?
        + pass_median(run, "evaluate")?
        + extra_fraction * pass_median(reference_run, "shade")?;
    let extra_samples = stats.shaded + stats.reshaded - counts.len() as u64;
    let samples = (extra_samples > 0).then(|| -> Option<SampleCost> {
        let extra_sample_ns = pass_median(run, "shade_extra")? * 1e6 / extra_samples as f64;
        let reference_sample_ns = pass_median(reference_run, "shade")? * 1e6 / stats.total as f64;
        Some(SampleCost {
            extra_samples,
            extra_sample_ns,
            reference_sample_ns,
            extra_sample_cost: extra_sample_ns / reference_sample_ns,
            evaluate_share: (pass_median(run, "evaluate")? + pass_median(run, "compact")?) / own,
            gather_share: pass_median(run, "gather")? / own,
        })
    });
    Some(AdaptiveCost {
        reference: reference.to_string(),
        speedup: frame_median(reference_run)? / own,
        limit_ms: limit,
        efficiency: limit / own,
        samples: samples.flatten(),
    })
}

/// Writes a mode's images, recording in `files` each one written (paths relative to the run
/// folder); stops at the first that cannot be written.
fn write_mode_images(
    scene_dir: &Path,
    scene: &str,
    mode: Mode,
    images: &FrameImages,
    diff_against: Option<&DisplayImage>,
    flip_map: Option<&FlipMap>,
    files: &mut ImageFiles,
) -> anyhow::Result<()> {
    let (w, h) = (images.width, images.height);
    let relative = |suffix: &str| Some(format!("{scene}/{mode}{suffix}"));
    let path = |suffix: &str| scene_dir.join(format!("{mode}{suffix}"));
    images::write_display_png(&path(".png"), w, h, &images.display)?;
    files.display = relative(".png");
    images::write_exr(&path(".exr"), w, h, &images.hdr)?;
    files.hdr = relative(".exr");
    if let Some(counts) = &images.sample_counts {
        images::write_png(&path(".samples.png"), w, h, &images::sample_heatmap(counts, mode.m))?;
        files.samples = relative(".samples.png");
    }
    if let Some(other) = diff_against {
        let heatmap = images::difference_heatmap(&images.display, other, DIFFERENCE_FULL_SCALE);
        images::write_png(&path(".diff.png"), w, h, &heatmap)?;
        files.difference = relative(".diff.png");
    }
    if let Some(map) = flip_map {
        images::write_png(&path(".flip.png"), map.width, map.height, &map.magma_rgba())?;
        files.flip = relative(".flip.png");
    }
    Ok(())
}

/// Prints a scene's results as a small table.
fn report_scene(progress: &Progress, scene: &SceneRecord) {
    let resolution = scene.resolution.map_or(String::new(), |[w, h]| format!(" {w}×{h}"));
    match &scene.error {
        Some(error) if scene.modes.is_empty() => {
            progress.line(&format!("[{}] FAILED: {error}", scene.name));
            return;
        }
        _ => progress.line(&format!(
            "[{}]{resolution} {} triangles, ground truth {}",
            scene.name,
            scene.triangles.unwrap_or(0),
            scene.truth.as_ref().map_or("none".into(), truth_summary)
        )),
    }
    progress.line(&format!(
        "  {:<28} {:>10} {:>21} {:>8} {:>9} {:>9} {:>10} {:>10}  {}",
        "mode",
        "median ms",
        "interval ms",
        "×1x1",
        "samples%",
        "PSNR ref",
        "PSNR truth",
        "FLIP truth",
        "front"
    ));
    let db = |q: &Option<Quality>| q.as_ref().map_or("-".into(), |q| format!("{:.2}", q.psnr_db.value()));
    for mode in &scene.modes {
        let Some(frame) = &mode.frame_ms else {
            progress.line(&format!("  {:<28} {}", mode.mode, mode.error.as_deref().unwrap_or("no frames")));
            continue;
        };
        progress.line(&format!(
            "  {:<28} {:>10.1} {:>21} {:>8} {:>9} {:>9} {:>10} {:>10}  {}{}",
            mode.mode,
            frame.median,
            format!("[{:.1}, {:.1}]", frame.ci_low, frame.ci_high),
            mode.ratio_to_deferred.map_or("-".into(), |r| format!("{r:.2}")),
            mode.samples.as_ref().map_or("-".into(), |s| format!("{:.1}", s.shaded_percent)),
            db(&mode.vs_reference),
            db(&mode.vs_ground_truth),
            mode.vs_ground_truth.as_ref().and_then(|q| q.flip).map_or("-".into(), |f| format!("{f:.4}")),
            mode.front.as_ref().map_or("-".into(), |place| place.describe()),
            mode.error.as_ref().map_or(String::new(), |e| format!("  ({e})")),
        ));
    }
}

/// How the truth was obtained, for the printed summary.
fn truth_summary(truth: &TruthRecord) -> String {
    match (&truth.error, truth.cached, truth.render_s) {
        (Some(error), _, _) => format!("FAILED: {error}"),
        (None, true, _) => format!("{} (cached)", truth.id),
        (None, false, Some(seconds)) => format!("{} (rendered in {seconds:.1} s)", truth.id),
        (None, false, None) => truth.id.clone(),
    }
}

/// What the kernel can give this process without swapping, in bytes: `MemAvailable` of
/// /proc/meminfo, or less where the process's memory cgroup allows less.
fn available_memory() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok();
    let host = meminfo.as_deref().and_then(|m| meminfo_field(m, "MemAvailable:")).map(|kib| kib * 1024);
    let membership = std::fs::read_to_string("/proc/self/cgroup").unwrap_or_default();
    host.into_iter().chain(cgroup_headroom(Path::new("/sys/fs/cgroup"), &membership)).min()
}

fn meminfo_field(text: &str, name: &str) -> Option<u64> {
    text.lines().find(|l| l.starts_with(name))?.split_whitespace().nth(1)?.parse().ok()
}

/// What this process's memory cgroups still allow (a container's limit, which MemAvailable
/// does not show): the least, over the process's cgroup and its ancestors, of the limit less
/// the working set (usage without the inactive page cache the kernel reclaims first, as
/// `docker stats` counts it). `root` is the cgroup mount and `membership` the text of
/// /proc/self/cgroup; cgroup v2 where the mount is unified, else v1's memory controller. None
/// where no level sets a limit.
fn cgroup_headroom(root: &Path, membership: &str) -> Option<u64> {
    let unified = root.join("cgroup.controllers").exists();
    let (base, own, files) = if unified {
        let own = membership.lines().find_map(|l| l.strip_prefix("0::"));
        (root.to_path_buf(), own, ["memory.max", "memory.current", "memory.stat", "inactive_file "])
    } else {
        let own = membership.lines().find_map(|l| {
            let (controllers, path) = l.split_once(':')?.1.split_once(':')?;
            controllers.split(',').any(|c| c == "memory").then_some(path)
        });
        let files = ["memory.limit_in_bytes", "memory.usage_in_bytes", "memory.stat", "total_inactive_file "];
        (root.join("memory"), own, files)
    };
    let [limit_file, usage_file, stat_file, inactive_field] = files;
    let headroom = |dir: &Path| {
        let read = |file: &str| std::fs::read_to_string(dir.join(file)).ok();
        // "max" (v2) does not parse: no limit at this level.
        let limit = read(limit_file)?.trim().parse::<u64>().ok()?;
        let usage = read(usage_file)?.trim().parse::<u64>().ok()?;
        let inactive = read(stat_file)
            .and_then(|stat| {
                stat.lines().find_map(|l| l.strip_prefix(inactive_field)?.trim().parse::<u64>().ok())
            })
            .unwrap_or(0);
        Some(limit.saturating_sub(usage.saturating_sub(inactive)))
    };
    // In a cgroup namespace the own path may not exist under the mount: the mount's root is
    // then the process's cgroup.
    let leaf = own.map(|path| base.join(path.trim_start_matches('/'))).filter(|dir| dir.is_dir());
    let levels = leaf.as_deref().unwrap_or(&base).ancestors().take_while(|dir| dir.starts_with(&base));
    levels.filter_map(headroom).min()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cgroup_limit_caps_the_memory_budget_at_the_tightest_level() {
        let root = std::env::temp_dir().join(format!("aabench-cgroup-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let write = |file: &str, text: &str| {
            let path = root.join(file);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, text).unwrap();
        };
        const GIB: u64 = 1 << 30;

        // v1: the process in /ci/job; the job allows 4 GiB (3 used, 1 of it reclaimable
        // cache), its parent 8 GiB with 7.5 used; the root sets no limit that matters.
        let v1 = "4:memory:/ci/job\n1:cpu:/\n";
        write("memory/memory.limit_in_bytes", "9223372036854771712\n");
        write("memory/memory.usage_in_bytes", "0\n");
        assert_eq!(cgroup_headroom(&root, v1), Some(9223372036854771712), "root level only");
        write("memory/ci/job/memory.limit_in_bytes", &format!("{}\n", 4 * GIB));
        write("memory/ci/job/memory.usage_in_bytes", &format!("{}\n", 3 * GIB));
        write("memory/ci/job/memory.stat", &format!("cache 1\ntotal_inactive_file {GIB}\n"));
        assert_eq!(cgroup_headroom(&root, v1), Some(2 * GIB), "the job's own limit");
        write("memory/ci/memory.limit_in_bytes", &format!("{}\n", 8 * GIB));
        write("memory/ci/memory.usage_in_bytes", &format!("{}\n", 15 * GIB / 2));
        assert_eq!(cgroup_headroom(&root, v1), Some(GIB / 2), "the parent is tighter");
        // Usage over the limit leaves nothing, without wrapping.
        write("memory/ci/memory.usage_in_bytes", &format!("{}\n", 9 * GIB));
        assert_eq!(cgroup_headroom(&root, v1), Some(0));

        // v2 (a unified mount): "max" sets no limit; the process's own level does.
        write("cgroup.controllers", "memory\n");
        let v2 = "0::/user.slice/run\n";
        write("memory.max", "max\n");
        assert_eq!(cgroup_headroom(&root, v2), None, "no level sets a limit");
        write("user.slice/run/memory.max", &format!("{GIB}\n"));
        write("user.slice/run/memory.current", &format!("{}\n", GIB / 2));
        write("user.slice/run/memory.stat", "anon 1\ninactive_file 0\n");
        assert_eq!(cgroup_headroom(&root, v2), Some(GIB / 2));
        // In a cgroup namespace the path is "/" and the mount's root is the process's cgroup.
        assert_eq!(cgroup_headroom(&root, "0::/\n"), None);
        std::fs::remove_dir_all(&root).unwrap();
    }
}
