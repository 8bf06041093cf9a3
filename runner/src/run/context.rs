//! What a scene's phases share: the scene's run (its plan, manifest, worker and folder) and,
//! per mode, what its stills measured. The phases (`rounds.rs`, `sequence.rs`, `results.rs`)
//! take these from here and give back only their results; `scene.rs` runs them in order.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use aabench_renderer::{FrameImages, FrameTiming};

use crate::manifest::Manifest;
use crate::measure::pixels::FrameChecks;
use crate::plan::RunPlan;
use crate::plan::repetitions::Stop;
use crate::record::{GraphRecord, ModeSequence};
use crate::run::progress::Progress;
use crate::run::worker::Worker;

/// One scene's run: what its phases read and the GPU worker they render on.
pub(super) struct SceneRun<'a> {
    pub worker: &'a mut Worker,
    pub plan: &'a RunPlan,
    pub manifest: &'a Manifest,
    pub progress: &'a Progress,
    /// Set by the first signal: the current frame finishes and what was measured is kept.
    pub cancel: &'a Arc<AtomicBool>,
    /// The scene's resolution in the plan's tier.
    pub resolution: [u32; 2],
    /// The scene's folder in the run's: `<run>/<scene>/`.
    pub dir: PathBuf,
    /// Whether a material samples a texture: where none does, an adaptive mode's full windows
    /// reuse S (see `sample_stats`). Known once the scene is loaded.
    pub textured: bool,
    /// What plays along the path, as the record names it (`walk + wave`). Known once the
    /// scene is loaded.
    pub animation: Option<String>,
    /// ColorVideoVDP on the scene's display model, where quality is measured.
    pub jod: Option<crate::measure::perceptual::Jod>,
}

impl<'a> SceneRun<'a> {
    pub fn new(
        worker: &'a mut Worker,
        plan: &'a RunPlan,
        manifest: &'a Manifest,
        progress: &'a Progress,
        cancel: &'a Arc<AtomicBool>,
    ) -> SceneRun<'a> {
        let resolution = plan.tier.resolution(manifest);
        let dir = plan.run_dir.join(&manifest.name);
        SceneRun {
            worker,
            plan,
            manifest,
            progress,
            cancel,
            resolution,
            dir,
            textured: false,
            animation: None,
            jod: None,
        }
    }

    /// What the phases after the upload need to know of the loaded scene: whether it is
    /// textured, and what plays along its path.
    pub fn note_scene(&mut self, scene: &aabench_renderer::scene::Scene) {
        self.textured = scene.is_textured();
        self.animation = scene.playing.as_ref().map(|playing| playing.short_label.clone());
    }

    /// Whether a signal asked the run to stop.
    pub fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::SeqCst)
    }

    /// Shows what the scene is doing on the progress line.
    pub fn status(&self, what: &str) {
        self.progress.status(&format!("[{}] {what}", self.manifest.name));
    }

    /// Prints a warning about the scene.
    pub fn warn(&self, what: &str) {
        self.progress.line(&format!("[{}] warning: {what}", self.manifest.name));
    }
}

/// What one mode measured during the scene's timed loop.
#[derive(Debug, Default)]
pub(super) struct ModeRun {
    pub(super) graph: Option<GraphRecord>,
    pub(super) timings: Vec<FrameTiming>,
    /// Why it took no more timed rounds; `None` while it takes them, or when they were cut
    /// short (an error, a signal).
    pub(super) stopped: Option<Stop>,
    pub(super) hashes: Vec<String>,
    pub(super) images: Option<FrameImages>,
    pub(super) checks: FrameChecks,
    /// Its sequences, one per scene sequence, where the scene has a camera path.
    pub(super) sequences: Vec<Option<ModeSequence>>,
    pub(super) error: Option<String>,
}
