//! A scene's mode records once its frames are done: timing summaries, the cost of adaptive
//! modes, quality against the truth and the compared mode, and the image files, encoded in
//! parallel now that no frame is running.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use aabench_renderer::{DisplayImage, FrameImages, Mode, Technique};

use super::context::{ModeRun, SceneRun};
use crate::files::images;
use crate::measure::perceptual::FlipMap;
use crate::measure::pixels::{self, Quality};
use crate::measure::stats::Summary;
use crate::plan::RunPlan;
use crate::record::{AdaptiveCost, ImageFiles, ModeRecord, PassRecord, SampleCost, Status};
use crate::run::truth::TRUTH_ID;

/// Display differences of this many 8-bit steps reach the top of the difference heatmap.
const DIFFERENCE_FULL_SCALE: f64 = 32.0;

/// How long the image tasks may go on once the run is interrupted. A small scene's metrics and
/// images finish within it; a large still's FLIP, SSIM and JOD (tens of seconds at 4096², in a
/// library that cannot be stopped midway) are given up, so that the run exits while a cancelled
/// CI job's SIGKILL is still seconds away and its record says what was measured.
const GRACE_AFTER_SIGNAL: Duration = Duration::from_millis(500);

/// Builds the mode records from the scene's runs: timing summaries, then quality metrics and
/// image files, one blocking task per mode. Returns them, the CPU seconds that the comparisons
/// with the truth took (MSE, FLIP and SSIM), and whether a signal cut the tasks short: the
/// modes whose task had not finished [`GRACE_AFTER_SIGNAL`] after it are `interrupted`, their
/// timings kept.
pub(super) async fn finish_modes(
    scene: &SceneRun<'_>,
    runs: Vec<ModeRun>,
    truth: Option<DisplayImage>,
    interrupted: bool,
) -> (Vec<ModeRecord>, f64, bool) {
    let modes = &scene.plan.modes;
    let mut records = timing_records(scene, &runs, interrupted);
    if !scene.plan.quality {
        return (records, 0.0, false);
    }
    let images: Arc<Vec<Option<FrameImages>>> = Arc::new(runs.into_iter().map(|r| r.images).collect());
    // The truth's share of SSIM is computed once here, for all of them (a few tens of
    // milliseconds at 1024×768).
    let [width, height] = scene.resolution;
    let jod = scene.jod.clone().expect("a scene that measures quality has its ColorVideoVDP");
    let truth = truth.map(|image| Arc::new(pixels::Truth::new(image, width, height, jod)));
    let tasks: Vec<_> = modes
        .iter()
        .enumerate()
        .map(|(index, &mode)| {
            images[index].as_ref()?;
            let task = ModeTask {
                index,
                mode,
                reference: comparison_reference(modes, &images, mode),
                images: Arc::clone(&images),
                truth: truth.clone(),
                scene_dir: scene.dir.clone(),
                scene_name: scene.manifest.name.clone(),
                textured: scene.textured,
            };
            Some(tokio::task::spawn_blocking(move || task.run()))
        })
        .collect();
    // What was measured is kept when an image cannot be written (a full disk): the mode then
    // fails with the write's error, its metrics and the images that were written recorded.
    let mut perceptual_s = 0.0;
    let mut deadline = None;
    let mut cut_short = false;
    for (record, task) in records.iter_mut().zip(tasks) {
        let Some(task) = task else { continue };
        match finished_in_time(task, scene.cancel, &mut deadline).await {
            Some(Ok(results)) => perceptual_s += results.record_into(record),
            Some(Err(panic)) => fail_mode(record, format!("image task panicked: {panic}")),
            None => {
                cut_short = true;
                record.status = Status::Interrupted;
                record.error = Some(
                    "interrupted while its metrics and images were computed: its timings are kept".into(),
                );
            }
        }
    }
    crate::record::front::place(&mut records);
    (records, perceptual_s, cut_short)
}

/// Waits for an image task, unless a signal came more than [`GRACE_AFTER_SIGNAL`] ago
/// (`deadline`, set on the first wait that sees `cancel`): then `None`, and the task is left to
/// the process's exit (it writes each file atomically, so nothing half-written is left behind
/// under a file's own name).
async fn finished_in_time<T>(
    mut task: tokio::task::JoinHandle<T>,
    cancel: &AtomicBool,
    deadline: &mut Option<Instant>,
) -> Option<Result<T, tokio::task::JoinError>> {
    const POLL: Duration = Duration::from_millis(50);
    loop {
        if deadline.is_none() && cancel.load(Ordering::SeqCst) {
            *deadline = Some(Instant::now() + GRACE_AFTER_SIGNAL);
        }
        if !task.is_finished() && deadline.is_some_and(|d| Instant::now() >= d) {
            return None;
        }
        tokio::select! {
            result = &mut task => return Some(result),
            () = tokio::time::sleep(POLL) => {}
        }
    }
}

/// Each mode's record of its frames' timings (see [`timing_record`]), its frame time over
/// deferred-1x1's and, for adaptive modes, its cost against the reference.
fn timing_records(scene: &SceneRun, runs: &[ModeRun], interrupted: bool) -> Vec<ModeRecord> {
    let (plan, modes) = (scene.plan, &scene.plan.modes);
    let mut records: Vec<ModeRecord> = modes
        .iter()
        .zip(runs)
        .map(|(mode, run)| timing_record(*mode, run, plan, interrupted, scene.manifest.empty))
        .collect();
    let deferred = modes
        .iter()
        .position(|m| *m == Mode::new(Technique::Deferred, 1, false))
        .and_then(|i| records[i].frame_ms.as_ref().map(|s| s.median));
    for ((record, mode), run) in records.iter_mut().zip(modes).zip(runs) {
        record.ratio_to_deferred = match (&record.frame_ms, deferred) {
            (Some(own), Some(base)) if base > 0.0 => Some(own.median / base),
            _ => None,
        };
        record.adaptive = adaptive_cost(modes, runs, *mode, run, scene.textured);
    }
    records
}

/// One mode's comparisons and image files, computed off the async threads.
struct ModeTask {
    index: usize,
    mode: Mode,
    /// The mode it is compared with, where that one ran ([`comparison_reference`]).
    reference: Option<(usize, Mode)>,
    images: Arc<Vec<Option<FrameImages>>>,
    truth: Option<Arc<pixels::Truth>>,
    scene_dir: std::path::PathBuf,
    scene_name: String,
    textured: bool,
}

impl ModeTask {
    fn run(self) -> ModeResults {
        let display = |i: usize| &self.images[i].as_ref().expect("images of a finished mode").display;
        let own = self.images[self.index].as_ref().expect("images of a finished mode");
        let vs_reference =
            self.reference.map(|(i, m)| pixels::quality(&own.display, display(i), &m.to_string()));
        // Thread CPU time: the tasks share the cores, so their wall times overlap.
        let perceptual_start = thread_cpu_seconds();
        let (vs_truth, flip_map) = self
            .truth
            .as_deref()
            .map(|truth| pixels::quality_vs_truth(&own.display, truth, TRUTH_ID))
            .unzip();
        let perceptual_s = thread_cpu_seconds() - perceptual_start;
        let diff_against = match self.reference {
            Some((i, _)) => Some(display(i)),
            None => self.truth.as_deref().map(|truth| &truth.image),
        };
        let samples =
            own.sample_counts.as_ref().map(|counts| pixels::sample_stats(counts, self.mode, self.textured));
        let mut files = ImageFiles::default();
        let written = write_mode_images(
            &self.scene_dir,
            &self.scene_name,
            self.mode,
            own,
            diff_against,
            flip_map.as_ref(),
            &mut files,
        );
        ModeResults { files, samples, vs_reference, vs_truth, written, perceptual_s }
    }
}

/// What a mode's image task computed and wrote.
struct ModeResults {
    files: ImageFiles,
    samples: Option<Result<pixels::SampleStats, String>>,
    vs_reference: Option<Quality>,
    vs_truth: Option<Quality>,
    written: anyhow::Result<()>,
    /// CPU seconds of the comparison with the truth: MSE, FLIP and SSIM.
    perceptual_s: f64,
}

impl ModeResults {
    /// Records what the task measured and wrote into the mode's record, failing the mode where
    /// its samples were out of range or an image could not be written; returns its CPU seconds.
    fn record_into(self, record: &mut ModeRecord) -> f64 {
        record.images = self.files;
        record.vs_reference = self.vs_reference;
        record.vs_ground_truth = self.vs_truth;
        match self.samples.transpose() {
            Ok(samples) => record.samples = samples,
            Err(error) => fail_mode(record, format!("{}: {error}", record.mode)),
        }
        if let Err(error) = self.written {
            fail_mode(record, format!("{error:#}"));
        }
        self.perceptual_s
    }
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
pub(super) fn fail_mode(record: &mut ModeRecord, error: String) {
    record.status = Status::Failed;
    record.error = Some(match record.error.take() {
        Some(first) => format!("{first}; {error}"),
        None => error,
    });
}

/// The image a mode is compared with ([`Mode::compared_with`]), with the same stall if it ran,
/// else the other (their images are identical).
fn comparison_reference(modes: &[Mode], images: &[Option<FrameImages>], mode: Mode) -> Option<(usize, Mode)> {
    let compared = mode.compared_with()?;
    [mode.stalled, !mode.stalled].into_iter().find_map(|stalled| {
        let reference = Mode { stalled, ..compared };
        let index = modes.iter().position(|m| *m == reference)?;
        images[index].as_ref().map(|_| (index, reference))
    })
}

/// The mode's record from its frames: timings, and whether it succeeded. A frame that shows
/// nothing fails its mode unless the scene is `declared_empty`.
fn timing_record(
    mode: Mode,
    run: &ModeRun,
    plan: &RunPlan,
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
    let complete = run.stopped.is_some();
    // A run that times alone reads no still of a jittered mode: its frames alone decide.
    let read_back = run.images.is_some() || (!plan.quality && mode.is_jittered());
    let unstable = run.checks.problem(mode.m);
    let blank = run.images.as_ref().filter(|_| !declared_empty).and_then(pixels::blank_frame);
    let (status, error) = match (&run.error, read_back) {
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
        stopped: run.stopped,
        passes,
        ratio_to_deferred: None,
        deterministic,
        output_hash: run.hashes.last().cloned(),
        images: ImageFiles::default(),
        samples: None,
        vs_reference: None,
        vs_ground_truth: None,
        adaptive: None,
        fronts: Default::default(),
        graph: run.graph.clone(),
        checks: (run.checks.frames > 0).then_some(run.checks),
        sequences: run.sequences.clone(),
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
/// [`AdaptiveCost`]), in a scene with or without textures.
fn adaptive_cost(
    modes: &[Mode],
    runs: &[ModeRun],
    mode: Mode,
    run: &ModeRun,
    textured: bool,
) -> Option<AdaptiveCost> {
    if !matches!(mode.technique, Technique::Adaptive(..)) {
        return None;
    }
    let reference = Mode::new(Technique::Reference, mode.m, mode.stalled);
    let reference_run = &runs[modes.iter().position(|m| *m == reference)?];
    let own = frame_median(run)?;
    let counts = run.images.as_ref()?.sample_counts.as_ref()?;
    let stats = pixels::sample_stats(counts, mode, textured).ok()?;
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
