//! Running a plan: scene after scene, each in its phases (`scene.rs`: load → upload → truth →
//! prepare every mode → timed rounds interleaved across modes (`rounds.rs`) → the sequence along
//! the camera path (`sequence.rs`) → images and metrics (`results.rs`)), the run's record
//! rewritten after each. Timed frames run alone: nothing else is scheduled while one is on the
//! device, and encoding and metrics wait until the scene's frames are done (lavapipe uses every
//! core, so overlapping CPU work would corrupt timings).
//!
//! The run's own machinery sits beside the phases: the GPU worker thread (`worker.rs`), the
//! scene from manifest to upload (`scenes.rs`), the cached ground truth (`truth.rs`), a
//! sequence's frames on disk (`spool.rs`), its worst-flickering region (`flicker.rs`) and the
//! progress line (`progress.rs`).

mod console;
mod context;
pub mod flicker;
mod measures;
mod memory;
mod path_metrics;
pub mod progress;
mod results;
mod rounds;
mod scene;
pub mod scenes;
mod sequence;
pub mod spool;
pub mod truth;
pub mod worker;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::SystemTime;

use aabench_renderer::{AdaptiveSettings, ExtraSamples, RenderSettings};

use crate::manifest::Manifest;
use crate::measure::machine::Machine;
use crate::plan::{RunPlan, SceneEntry, Tier, fallback_name};
use crate::record::{Platform, RUN_SCHEMA, RunRecord, RunSettings, SceneRecord, Status};
use context::SceneRun;
use progress::Progress;
use worker::Worker;

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
        build: Some(crate::record::this_build()),
        // Probed before any frame, while nothing else of the run uses the cores.
        platform: Platform { machine: Some(Machine::measure()), ..Platform::from(&worker.platform) },
        settings: RunSettings {
            modes: plan.modes.iter().map(ToString::to_string).collect(),
            repetitions: plan.repetitions.most(),
            confidence: plan.repetitions.confidence(),
            warmup: plan.warmup,
            frame_timeout_s: plan.frame_timeout.as_secs_f64(),
            interleaving: "round-robin: each repetition renders every mode once, in plan order".into(),
            extra_samples: format!("{:?}", plan.extra_samples).to_lowercase(),
            sequences: plan.sequences,
            quality: plan.quality,
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
            Ok(manifest) => SceneRun::new(&mut worker, plan, manifest, &progress, &cancel).run().await,
            Err(error) => failed_scene(entry, error.to_string()),
        };
        console::report_scene(&progress, &scene);
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
    crate::files::write_json(path, record).map_err(anyhow::Error::msg)
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
        jod_display: None,
        pixels_per_degree: None,
        truth: None,
        sequences: Vec::new(),
        modes: Vec::new(),
        machine: None,
    }
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
